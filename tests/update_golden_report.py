"""Regenerate the golden LaTeX reports: ``python tests/update_golden_report.py``.

The only way the files in ``tests/golden/report/`` change. Each case of
:data:`CASES` is a result with small synthetic data logs (written here,
deterministically, with fixed-precision CSV text) and, for the example, a
LuGre file; ``tests/test_report_golden.py`` renders the same cases and
compares the .tex with the golden file, line for line, after
:func:`normalize` (which blanks the package versions, the one part that
legitimately differs between installations). Review ``git diff
tests/golden/report`` before committing.

The helpers here are shared by the report tests.
"""

from __future__ import annotations

import hashlib
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
GOLDEN = REPO / "tests" / "golden" / "report"
EXAMPLE = REPO / "tests" / "data" / "handwritten_result.json"  # known content
INPUTS = ("theta_w", "theta_uw", "omega")
TS = 1e-3


def _profile(t: np.ndarray, kind: str) -> np.ndarray:
    """A smooth velocity profile [rad/s]: steps then a chirp (abstraction), a slow chirp (evaluation)."""
    from scipy import signal

    if kind == "abstraction":
        levels = np.array([2.0, -2.0, 5.0, -5.0])
        cmd = np.where(t < 4.0, levels[np.clip((t // 1.0).astype(int), 0, 3)], 0.0)
        tc = np.maximum(t - 4.0, 0.0)
        cmd = cmd + np.where(t >= 4.0, 10.0 * np.sin(2 * np.pi * (0.2 * tc + 0.3 * tc**2)), 0.0)
    else:
        cmd = 8.0 * np.sin(2 * np.pi * 0.08 * t**2) + 0.5
    # The axis follows the command through a first-order lag (50 rad/s), from rest.
    b, a = signal.bilinear([50.0], [1.0, 50.0], fs=1.0 / TS)
    return signal.lfilter(b, a, cmd)


def log_columns(result, kind: str, n: int = 10_000) -> dict[str, np.ndarray]:  # noqa: ANN001
    """A free-motion log whose target is ``result``'s own compensator plus a small unmodelled part."""
    from edm_sym.engines.simulate import simulate

    t = np.arange(n) * TS
    omega = _profile(t, kind)
    theta_uw = np.cumsum(omega) * TS
    cols = {
        "t": t,
        "theta_w": np.mod(theta_uw, 2 * np.pi),
        "theta_uw": theta_uw,
        "omega": omega,
        "alpha": np.diff(omega, prepend=0.0) / TS,
    }
    cols = {k: np.asarray([float(f"{v:.9g}") for v in c]) for k, c in cols.items()}
    tau = simulate(result, cols).total
    unmodelled = 0.03 * np.sin(2 * np.pi * 3.0 * t) + 0.05 * np.tanh(omega / 3.0)
    cols["tau_ext"] = tau + unmodelled
    return cols


def write_log(path: Path, columns: dict[str, np.ndarray]) -> Path:
    """CSV with 9 significant digits: the same text on every platform."""
    names = list(columns)
    lines = [",".join(names)]
    for row in zip(*(columns[n] for n in names), strict=True):
        lines.append(",".join(f"{float(v):.9g}" for v in row))
    path.write_text("\n".join(lines) + "\n")
    return path


def write_lugre(path: Path, data: Path) -> Path:
    """A LUGRE.json with fixed, plausible parameters (not identified: the report only reads it)."""
    from edm_sym.engines.lugre import LuGreParams, LuGreResult, save_lugre

    params = LuGreParams(v_s=0.05, tau_c=0.9, tau_s=1.1, z0=0.0, sigma0=2.0e3, sigma1=1.0,
                         sigma2=0.006)
    res = LuGreResult(params, "scipy", 0.25, 1000, TS)
    save_lugre(path, res, target="tau_ext", velocity="omega",
               data_sha256=hashlib.sha256(data.read_bytes()).hexdigest(), seed=7)
    return path


def example_result():  # noqa: ANN201
    """The hand-written auger fixture (tests/data/handwritten_result.json): known content."""
    from edm_sym.core.result import load_result

    return load_result(EXAMPLE)


def steps_result():  # noqa: ANN201
    """A 1-row result (Coulomb friction) with two recorded hierarchical steps."""
    from edm_sym.core.matrix import Compensator, make_matrix
    from edm_sym.core.result import EdmResult, StepRecord

    m1 = make_matrix(INPUTS, [("omega", [("sign", 0.0), ("gain", 0.5475)])])
    comp = Compensator(m1, TS, {}, 10.0)
    hist1 = tuple(0.9 * 0.97**k + 0.05 for k in range(60))
    hist2 = tuple(0.2 * 0.95**k + 0.04 for k in range(40))
    steps = (
        StepRecord(1, m1, hist1[-1], hist1, 60, 6000,
                   {"constant": 1.0, "windows": [[0.0, 4.0, 1.0]], "otherwise": 0.0}),
        StepRecord(2, m1, hist2[-1], hist2, 40, 4000,
                   {"constant": 1.0, "threshold": 0.8, "above": 20000.0, "below": 1.0}),
    )
    return EdmResult(comp, "tau_ext", steps, {"seed": 3, "package_version": "0.1.0",
                                              "data_sha256": None}, hist2[-1])


def eight_row_result():  # noqa: ANN201
    """An 8x5 matrix with every kind of stage, nested functions and long expressions."""
    from edm_sym.core.matrix import Compensator, make_matrix
    from edm_sym.core.result import EdmResult

    rows = [
        ("omega", [("sign", 0.0), ("gain", 0.55), ("through", 0.0), ("through", 0.0),
                   ("through", 0.0)]),
        ("omega", [("power_gain", 0.3), ("lpf", 0.7), ("through", 0.0), ("through", 0.0),
                   ("through", 0.0)]),
        ("omega", [("derivative", 0.8), ("notch", 0.6), ("lead", 0.4), ("tanh", 0.3),
                   ("sin_amp", 0.6)]),
        ("theta_w", [("gain", 0.6), ("sin_phase", 0.3), ("tan_amp", 0.52), ("saturation", 0.6),
                     ("asin", 0.0)]),
        ("theta_uw", [("shift", 0.5), ("log", 0.5), ("power", 0.4), ("dead_zone", 0.2),
                      ("atan", 0.4)]),
        ("omega", [("one_way", 0.45), ("acos", 0.0), ("integral", 0.3), ("lag", 0.5),
                   ("hpf", 0.4)]),
        ("omega", [("dead_time", 0.2), ("hysteresis", 0.5), ("gain", 0.55), ("phase", 0.5),
                   ("offset", 0.52)]),
        ("theta_w", [("invert", 0.0), ("tan_phase", 0.55), ("tanh", 0.5), ("power_gain", 0.4),
                     ("lpf", 0.9)]),
    ]
    comp = Compensator(make_matrix(INPUTS, rows), TS, {}, 10.0)
    return EdmResult(comp, "tau_ext", (), {"seed": None, "package_version": "0.1.0",
                                           "data_sha256": None})


@dataclass(frozen=True)
class Case:
    """One golden report: a result, and which logs and LuGre file it is given."""

    name: str
    result: Callable[[], object]
    logs: tuple[str, ...] = ("abstraction", "evaluation")
    lugre: bool = False
    options: dict = field(default_factory=dict)


CASES = (
    Case("auger", example_result, lugre=True),
    Case("steps", steps_result, logs=("abstraction",), options={"prefix": "steps"}),
)


def case_inputs(case: Case, folder: Path) -> tuple[object, dict]:
    """Write the case's logs (and LuGre file) into ``folder``; return the result and the kwargs."""
    folder.mkdir(parents=True, exist_ok=True)
    result = case.result()
    kw: dict = dict(case.options)
    for kind in case.logs:
        path = write_log(folder / f"{case.name}_{kind}.csv", log_columns(result, kind))
        kw["data" if kind == "abstraction" else "eval_data"] = path
    if case.lugre:
        kw["lugre"] = write_lugre(folder / "lugre.json", kw["data"])
    return result, kw


_VERSION_LINE = re.compile(r"^(python|edm\\_sym|numpy|scipy|sympy|control|jinja2|matplotlib)"
                           r" & .* \\\\$", re.M)


def normalize(text: str) -> str:
    """The report text with the package versions blanked (they differ between installations)."""
    return _VERSION_LINE.sub(r"\1 & <version> \\\\", text)


def render_case(case: Case, folder: Path) -> str:
    """Write the case's report (no PDF) into ``folder`` and return its normalized .tex."""
    from edm_sym.outputs.report import write_report

    result, kw = case_inputs(case, folder)
    files = write_report(result, folder, **kw)
    return normalize(files[0].read_text())


def main() -> int:
    """Rewrite every golden report."""
    import tempfile

    GOLDEN.mkdir(parents=True, exist_ok=True)
    for case in CASES:
        with tempfile.TemporaryDirectory() as tmp:
            text = render_case(case, Path(tmp))
        out = GOLDEN / f"{case.name}_report.tex"
        out.write_text(text)
        print(out.relative_to(REPO))
    return 0


if __name__ == "__main__":
    sys.exit(main())

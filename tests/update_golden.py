"""Regenerate the golden files of the code generator: ``python tests/update_golden.py``.

The only way golden files change. It rewrites

* ``tests/golden/<case>/`` for every case in :data:`CASES`, and
* ``generated/auger/``, the committed output of
  ``edm-export examples/auger/result.json --target all --pdf`` (needs latexmk);

``tests/test_codegen_golden.py`` compares fresh renders with both, byte for
byte. Review the diff (``git diff tests/golden generated``) before committing.
"""

from __future__ import annotations

import shutil
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
GOLDEN = REPO / "tests" / "golden"
EXAMPLE = REPO / "examples" / "auger" / "result.json"
#: An earlier release's example, its Coulomb row a relay (the q15 golden: see cg_support).
RELAY_EXAMPLE = REPO / "tests" / "golden" / "relay_auger_result.json"
GENERATED = REPO / "generated" / "auger"


def _kinds_result():  # noqa: ANN202  (imports edm_sym lazily)
    """A hand-written 4x4 matrix with every stage kind and every guard helper."""
    from edm_sym.core.matrix import Compensator, make_matrix
    from edm_sym.core.result import EdmResult

    rows = [
        ("omega", [("notch", 0.6), ("dead_time", 0.2), ("hysteresis", 0.5), ("gain", 0.55)]),
        ("theta_w", [("sin_phase", 0.3), ("tan_amp", 0.7), ("saturation", 0.6), ("asin", 0.0)]),
        ("theta_uw", [("shift", 0.0), ("log", 0.5), ("power", 0.4), ("dead_zone", 0.2)]),
        ("omega", [("one_way", 0.45), ("acos", 0.0), ("integral", 0.3), ("lead", 0.5)]),
    ]
    comp = Compensator(make_matrix(("theta_w", "theta_uw", "omega"), rows), 1e-3, {}, 20.0)
    return EdmResult(comp, "tau_ext", (), {"seed": None, "package_version": "golden",
                                           "data_sha256": None})


@dataclass(frozen=True)
class Case:
    """One golden case: a result file and the exports kept of it."""

    name: str
    result_file: Path
    exports: tuple[tuple[str, dict], ...]
    make: Callable[[], object] | None = None  # writes result_file when it is generated


CASES = (
    # The shipped example's double C and Python are generated/auger/ (checked there).
    Case("auger_float", EXAMPLE, (("c", {"real": "float", "prefix": "edm_comp_f32"}),)),
    # Its fixed-point C and kits (sized and checked on the log the result stores).
    Case("auger_q31", EXAMPLE, (("c", {"real": "q31", "prefix": "edm_comp_q31"}),
                                ("test", {"real": "q31", "prefix": "edm_comp_q31"}))),
    Case("auger_q15", RELAY_EXAMPLE, (("c", {"real": "q15", "prefix": "edm_comp_q15"}),
                                ("test", {"real": "q15", "prefix": "edm_comp_q15"}))),
    Case("kinds", GOLDEN / "kinds" / "result.json", (("c", {}), ("python", {}),
                                                     ("c", {"real": "float",
                                                            "prefix": "kinds_f32"})),
         make=_kinds_result),
)


def render_case(case: Case, out_dir: Path) -> list[Path]:
    """Export ``case`` into ``out_dir``; returns the files written (result file excluded)."""
    import warnings

    from edm_sym import load_result
    from edm_sym.application.exporting import export

    result = load_result(case.result_file)
    written: list[Path] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # golden output does not depend on warnings
        for target, options in case.exports:
            written += export(result, target, out_dir, **options)
    return written


def main() -> int:
    """Rewrite every golden folder and generated/auger; print what was written."""
    from edm_sym.application.exporting import export
    from edm_sym.core.result import load_result, save_result

    for case in CASES:
        folder = GOLDEN / case.name
        if folder.exists():
            for old in folder.iterdir():
                if old != case.result_file:
                    old.unlink()
        if case.make is not None:
            save_result(case.make(), case.result_file)
            print(case.result_file.relative_to(REPO))
        for path in render_case(case, folder):
            print(path.relative_to(REPO))
    if GENERATED.exists():
        shutil.rmtree(GENERATED)
    # As the README's first command, plus --pdf: the compiled report is committed too.
    for path in export(load_result(EXAMPLE), "all", GENERATED, pdf=True):
        print(path.relative_to(REPO))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The observer view of measured logs, on synthetic data and on the EMPS log."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import emps_path

from edm_sym.application.cli import main
from edm_sym.core.data import DataLog, load_data
from edm_sym.engines.observer import (
    MIN_CORNER,
    ObserverOptions,
    fit_reference_model,
    observer_view,
    reference_model,
    relative_error,
)


def synthetic_axis(n: int = 20_000, ts: float = 1e-3) -> tuple[DataLog, np.ndarray]:
    t = np.arange(n) * ts
    q = 0.1 * np.sin(2 * np.pi * 0.5 * t) + 0.05 * np.sin(2 * np.pi * 1.7 * t)
    qd = 0.1 * np.pi * np.cos(np.pi * t) + 0.05 * 2 * np.pi * 1.7 * np.cos(2 * np.pi * 1.7 * t)
    qdd = -0.1 * np.pi**2 * np.sin(np.pi * t) - 0.05 * (2 * np.pi * 1.7) ** 2 * np.sin(2 * np.pi * 1.7 * t)
    true = np.array([95.0, 200.0, 20.0, -3.0])
    force = reference_model(true, qd, qdd)
    log = DataLog({"t": t, "q": q, "u": force / 35.0}, ts, "synthetic", None, {"g": 35.0})
    return log, true


def test_view_recovers_derivatives_and_model() -> None:
    log, true = synthetic_axis()
    view = observer_view(log, ObserverOptions("q", "u", 90.0, "g"))
    c = view.columns
    np.testing.assert_allclose(c["force"], 35.0 * log.columns["u"])
    np.testing.assert_allclose(c["tau_ext"], c["force"] - 90.0 * c["qdd"])
    inner = slice(500, -500)  # away from the filter's end effects
    coef = fit_reference_model(c["qd"][inner], c["qdd"][inner], c["force"][inner])
    np.testing.assert_allclose(coef, true, rtol=0.02)
    res = c["force"][inner] - reference_model(coef, c["qd"][inner], c["qdd"][inner])
    assert relative_error(c["force"][inner], res) < 1.0


def test_bad_options_are_refused(tmp_path: Path, capsys) -> None:
    with pytest.raises(ValueError, match="nominal_inertia"):
        ObserverOptions("q", "u", -1.0)
    log, _ = synthetic_axis(200)
    np.savez(tmp_path / "x.npz", **log.columns)
    assert main(["observe", str(tmp_path / "x.npz"), "--position", "qq", "--force", "u",
                 "--nominal-inertia", "1", "-o", str(tmp_path / "o.csv")]) == 2
    assert "column 'qq'" in capsys.readouterr().err
    assert not (tmp_path / "o.csv").exists()


def test_emps_reference_model_reproduced() -> None:
    """The published inverse-dynamics model fits the observer view of the real log."""
    view = observer_view(load_data(emps_path()), ObserverOptions("qm", "vir", 90.0, "gtau"))
    c = view.columns
    coef = fit_reference_model(c["qd"], c["qdd"], c["force"])
    np.testing.assert_allclose(coef[:3], [95.1089, 203.5034, 20.3935], rtol=0.03)
    err = relative_error(c["force"], c["force"] - reference_model(coef, c["qd"], c["qdd"]))
    print(f"EMPS reference model, refitted: {err:.4f} % (published 4.0834 %)")
    assert 3.5 < err < 5.5


@pytest.mark.parametrize("options,where,problem", [
    # A corner below 1/1000 of Nyquist: numpy's "Singular matrix" at 1e-20 Hz, and below
    # about 3e-5 of Nyquist a filter that diverged in silence.
    (["--cutoff", "1e-20"], "x.npz: cutoff", "expected a corner of at least 0.001 of Nyquist"),
    (["--cutoff", "0.4"], "x.npz: cutoff", "(0.5 Hz: below it"),
    # A force gain that overflows the force was written as inf, with exit 0.
    (["--force-gain", "1e308"], "x.npz: row 1, column 'u'", "found inf"),
    (["--position", "t"], "x.npz: column 't'", "found the log's time column"),
])
def test_an_observer_option_the_log_cannot_take_is_refused(tmp_path: Path, capsys, options,
                                                           where, problem) -> None:
    log, _ = synthetic_axis(2000)
    cols = dict(log.columns)
    cols["u"] = cols["u"] * 100  # |u| > 1, so a gain of 1e308 overflows
    np.savez(tmp_path / "x.npz", **cols)
    args = ["observe", str(tmp_path / "x.npz"), "--position", "q", "--force", "u",
            "--nominal-inertia", "1", "-o", str(tmp_path / "o.csv")]
    position = options.index("--position") if "--position" in options else None
    if position is not None:
        args[args.index("--position") + 1] = options[position + 1]
        options = []
    assert main(args + options) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"{where}: " in err and problem in err, err
    assert not (tmp_path / "o.csv").exists()


def test_the_lowest_corner_still_keeps_the_filters_gain() -> None:
    # A ramp passes the low pass with its slope, away from the ends: 4e-5 off at this
    # corner, 0.3 % at 0.3 of it and 22 % at a tenth, where the filter's coefficients
    # lose its gain.
    n, ts = 100_000, 1e-3
    t = np.arange(n) * ts
    log = DataLog({"t": t, "q": 0.5 * t, "u": np.ones(n)}, ts, "ramp")
    view = observer_view(log, ObserverOptions("q", "u", 1.0, cutoff_hz=MIN_CORNER * 0.5 / ts))
    np.testing.assert_allclose(view.columns["qd"][40_000:-40_000], 0.5, rtol=1e-4)

"""The LuGre baseline on several logs: each simulated from rest, one fit over all of them."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import COMPLIANT, TS, paper_profile

from edm_sym.application.cli import main
from edm_sym.core.data import write_csv
from edm_sym.engines.lugre import identify_lugre, load_lugre, simulate_lugre, weighted_rmse


def _velocities() -> tuple[np.ndarray, np.ndarray]:
    v = paper_profile(TS, 3.0)
    return v[:1200], -0.7 * v[400:1400]  # the second ends and starts away from rest


def test_each_log_starts_from_z0_and_never_from_the_log_before() -> None:
    a, b = _velocities()
    joined = simulate_lugre(COMPLIANT, np.r_[a, b], TS, starts=[len(a)])
    apart = np.r_[simulate_lugre(COMPLIANT, a, TS), simulate_lugre(COMPLIANT, b, TS)]
    np.testing.assert_array_equal(joined, apart)
    # Run through, the second log would start from the first one's last state.
    through = simulate_lugre(COMPLIANT, np.r_[a, b], TS)
    assert np.max(np.abs(through[len(a):len(a) + 5] - apart[len(a):len(a) + 5])) > 1e-6


def test_the_fit_over_several_logs_is_eq8_over_all_their_samples() -> None:
    a, b = _velocities()
    tau = np.r_[simulate_lugre(COMPLIANT, a, TS), simulate_lugre(COMPLIANT, b, TS)]
    result = identify_lugre(tau, np.r_[a, b], TS, seed=0, starts=[len(a)])
    apart = np.r_[simulate_lugre(result.params, a, TS), simulate_lugre(result.params, b, TS)]
    assert result.rmse == pytest.approx(weighted_rmse(tau, apart), rel=1e-9)
    assert result.rmse < 0.02 * np.max(np.abs(tau))


@pytest.mark.parametrize("starts", [[0], [2400], [900, 600]])
def test_bad_starts_are_refused(starts: list[int]) -> None:
    a, b = _velocities()
    with pytest.raises(ValueError, match="starts: expected increasing sample indices"):
        identify_lugre(np.r_[a, b], np.r_[a, b], TS, starts=starts)


def _write(path, v: np.ndarray, ts: float = TS) -> str:  # noqa: ANN001
    write_csv(path, {"t": np.arange(len(v)) * ts, "omega": v,
                     "tau": simulate_lugre(COMPLIANT, v, ts)})
    return str(path)


def test_edm_lugre_fits_several_logs(tmp_path, capsys) -> None:  # noqa: ANN001
    a, b = _velocities()
    files = [_write(tmp_path / "a.csv", a), _write(tmp_path / "b.csv", b)]
    out = tmp_path / "lugre.json"
    assert main(["lugre", *files, "--target", "tau", "--velocity", "omega", "-o", str(out),
                 "--quiet", "--time-limit", "5"]) == 0
    text = capsys.readouterr().out
    assert "on a.csv" in text and "on b.csv" in text
    res = load_lugre(out)
    tau = np.r_[simulate_lugre(COMPLIANT, a, TS), simulate_lugre(COMPLIANT, b, TS)]
    apart = np.r_[simulate_lugre(res.params, a, TS), simulate_lugre(res.params, b, TS)]
    assert json.loads(out.read_text())["fitness"] == pytest.approx(weighted_rmse(tau, apart))


def test_edm_lugre_refuses_logs_of_another_sample_time(tmp_path, capsys) -> None:  # noqa: ANN001
    a, b = _velocities()
    files = [_write(tmp_path / "a.csv", a), _write(tmp_path / "b.csv", b, ts=2 * TS)]
    out = tmp_path / "lugre.json"
    assert main(["lugre", *files, "--target", "tau", "--velocity", "omega", "-o", str(out),
                 "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "b.csv: sample time" in err and "expected" in err
    assert not out.exists()

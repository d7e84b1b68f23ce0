"""Shared fixtures: small hand-written matrices and signals, the friction log; where the EMPS log is.

Helpers several test modules call (log makers, small configs) are in
``helpers.py``; a test module imports them from there, never from another
test module.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from edm_sym.core.matrix import Compensator, make_matrix

TS = 1e-3
N = 20_000


def smooth_signal(n: int = N, ts: float = TS, seed: int = 0, amp: float = 1.0) -> np.ndarray:
    """A smooth, band-limited random signal (sum of a few sines)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * ts
    f = rng.uniform(0.1, 5.0, 6)
    ph = rng.uniform(0, 2 * np.pi, 6)
    w = rng.uniform(0.2, 1.0, 6)
    return amp * (w[:, None] * np.sin(2 * np.pi * f[:, None] * t + ph[:, None])).sum(0) / w.sum()


@pytest.fixture
def signal() -> np.ndarray:
    return smooth_signal()


@pytest.fixture
def coulomb_viscous() -> Compensator:
    """Step 1 of the paper: Coulomb + viscous, on omega."""
    from edm_sym.core.elements import element

    g = element("gain").param.default(TS, 20.0)
    pg = element("power_gain").param.default(TS, 20.0)
    m = make_matrix(
        ["theta_w", "omega"],
        [
            ("omega", [("sign", 0.0), ("gain", g.encode(0.93)), ("through", 0.0)]),
            ("omega", [("power_gain", pg.encode(0.007)), ("through", 0.0), ("through", 0.0)]),
        ],
    )
    return Compensator(m, TS, {}, 20.0)


@pytest.fixture(scope="module")
def friction_data():  # noqa: ANN201
    """The 2 s friction log (:func:`helpers.friction_log`) the GA tests fit, one per module."""
    from helpers import friction_log

    return friction_log(2.0)[0]


@pytest.fixture(scope="module")
def friction_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The 1 s friction log (:func:`helpers.friction_log`) as a CSV file, for ``edm abstract``."""
    from helpers import friction_log

    from edm_sym.core.data import write_csv

    return write_csv(tmp_path_factory.mktemp("d") / "log.csv", friction_log(1.0)[0].columns)


#: The environment variable naming DATA_EMPS.mat, the measured EMPS log (not shipped: its
#: readme says it is for tests and benchmarks, not for the package).
EMPS_ENV = "EDM_EMPS_DATA"
#: Where DATA_EMPS.mat is looked for without the variable: beside the checkout, then the
#: project machines' shared folder.
EMPS_PLACES = (Path(__file__).resolve().parents[1].parent / "shared" / "data" / "emps" / "DATA_EMPS.mat",
               Path("/work/shared/data/emps/DATA_EMPS.mat"))


def emps_path() -> Path:
    """DATA_EMPS.mat for a test that needs it; the test is skipped, saying why, when it is missing.

    The file named by ``$EDM_EMPS_DATA`` when that is set, else the first of
    :data:`EMPS_PLACES` that exists.

    Returns
    -------
    pathlib.Path
    """
    given = os.environ.get(EMPS_ENV)
    if given:
        path = Path(given).expanduser()
        if not path.is_file():
            pytest.skip(f"{EMPS_ENV}={given}: no such file (set it to DATA_EMPS.mat, the EMPS log)")
        return path
    for path in EMPS_PLACES:
        if path.is_file():
            return path
    pytest.skip(f"DATA_EMPS.mat not found in {' or '.join(map(str, EMPS_PLACES))}: set {EMPS_ENV} "
                "to its path (the EMPS log is not shipped)")


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--slow", action="store_true", help="also run tests marked slow")


def pytest_collection_modifyitems(config: pytest.Config, items: list) -> None:
    if config.getoption("--slow"):
        return
    skip = pytest.mark.skip(reason="slow: run with --slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)

"""Shared fixtures: small hand-written matrices and signals."""

from __future__ import annotations

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


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--slow", action="store_true", help="also run tests marked slow")


def pytest_collection_modifyitems(config: pytest.Config, items: list) -> None:
    if config.getoption("--slow"):
        return
    skip = pytest.mark.skip(reason="slow: run with --slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)

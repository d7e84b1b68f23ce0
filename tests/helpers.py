"""Logs and helpers several test modules share (imported by conftest.py and by tests).

A test module imports what it needs from here (``from helpers import
friction_log``), never from another test module.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from conftest import TS
from hypothesis import strategies as st
from scipy import signal

from edm_sym.core.data import DataLog
from edm_sym.core.result import EdmResult
from edm_sym.engines.abstraction import abstract, parse_config
from edm_sym.engines.lugre import LuGreParams, simulate_lugre

# -- the friction log the abstraction tests fit ------------------------------------

#: The friction of :func:`friction_log`: Coulomb level [N m], viscous coefficient [N m s/rad],
#: noise RMS [N m].
COULOMB, VISCOUS, NOISE = 1.0, 0.01, 0.05


def friction_log(duration: float = 5.0, seed: int = 0, noise: float = NOISE
                 ) -> tuple[DataLog, float]:
    """A log made by a known 2-row compensator: Coulomb 1.0 N m + viscous 0.01 N m s/rad.

    The velocity holds steps for the first half and a chirp (as the paper's
    eq. 9) for the second; the target gets Gaussian noise. Returns the log
    and the RMS of the noise actually added (the noise floor).
    """
    n = int(round(duration / TS))
    t = np.arange(n) * TS
    half = duration / 2
    levels = np.array([5, -5, 15, -15, 30, -30, 50, -50, 2, -2.0])
    k = np.minimum((t / (half / len(levels))).astype(int), len(levels) - 1)
    chirp = 20 * np.pi * np.sin(np.pi * (10.0 / (duration - half)) * (t - half) ** 2)
    omega = np.where(t < half, levels[k], chirp)
    alpha = np.gradient(omega, TS)
    e = noise * np.random.default_rng(seed).standard_normal(n)
    tau = COULOMB * np.sign(omega) + VISCOUS * omega + e
    cols = {"t": t, "omega": omega, "alpha": alpha, "tau_ext": tau}
    return DataLog(cols, TS, "friction"), float(np.sqrt(np.mean(e**2)))


# No restarts (the default, said here): 6 generations a step, the schedule these tests reason about.
SMALL = {"ga": {"population": 24, "generations": 6, "continue": "no", "restarts": 0},
         "step": [{"n_rows": 2, "n_elements": 3}, {"n_rows": 3, "n_elements": 3}]}


def run(data: DataLog, doc: dict, **kw) -> EdmResult:
    """``abstract`` on the friction log's omega and alpha with the config ``doc``."""
    return abstract(data, target="tau_ext", inputs=["omega", "alpha"],
                    config=parse_config(doc, "test.toml"), **kw)


# -- LuGre ---------------------------------------------------------------------------

#: A LuGre result's data hash, for hand-made results.
SHA = "0123456789abcdef" * 4
#: LuGre axes of the tests: a stiff one (sigma0 1e6) and a compliant one (sigma0 2e3).
STIFF = LuGreParams(v_s=1.0, tau_c=1.0, tau_s=1.6, z0=0.0, sigma0=1e6, sigma1=30.0, sigma2=0.01)
COMPLIANT = LuGreParams(v_s=2.0, tau_c=0.8, tau_s=1.2, z0=0.0, sigma0=2e3, sigma1=5.0, sigma2=0.015)


def paper_profile(ts: float = TS, duration: float = 20.0) -> np.ndarray:
    """Velocity like the paper's abstraction log (Sec. IV-A).

    0-10 s: velocity steps in both directions at growing levels (through a
    20 ms first-order lag, as a velocity loop would track them); after 10 s
    the chirp of eq. 9, ``20 pi sin(2 pi 0.5 (t - 10)^2)``.
    """
    t = np.arange(int(round(duration / ts))) * ts
    levels = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 50.0, 62.8]
    sequence = [s * a for a in levels for s in (1.0, -1.0)]
    hold = 10.0 / len(sequence)
    t_step = t[t < 10.0]
    steps = np.array(sequence)[np.minimum((t_step / hold).astype(int), len(sequence) - 1)]
    b, a = signal.butter(1, 1.0 / (2.0 * np.pi * 0.02) / (0.5 / ts))
    t_chirp = t[t >= 10.0]
    chirp = 20.0 * np.pi * np.sin(2.0 * np.pi * 0.5 * (t_chirp - 10.0) ** 2)
    return np.concatenate([signal.lfilter(b, a, steps), chirp])


def synthetic(params: LuGreParams, duration: float = 20.0, noise: float = 0.01, seed: int = 1):
    """The velocity of :func:`paper_profile`, LuGre's torque on it, and that torque with noise."""
    v = paper_profile(TS, duration)
    tau = simulate_lugre(params, v, TS)
    rng = np.random.default_rng(seed)
    return v, tau, tau + noise * np.max(np.abs(tau)) * rng.standard_normal(len(tau))


#: Any JSON value, nested a little: what a corrupted file may hold in a place.
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=5),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner, max_size=3),
    max_leaves=6,
)


def write_corrupted(doc: dict, where: tuple, data, tmp_path: Path) -> Path:  # noqa: ANN001
    """Replace (with a drawn JSON value) or delete ``doc[where]``; write it as lugre.json."""
    node = doc
    for key in where[:-1]:
        node = node[key]
    if data.draw(st.booleans()):
        node[where[-1]] = data.draw(JSON_VALUES)
    else:
        del node[where[-1]]
    path = tmp_path / "lugre.json"
    path.write_text(json.dumps(doc))
    return path

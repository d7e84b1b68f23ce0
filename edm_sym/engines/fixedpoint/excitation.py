"""A synthetic excitation inside the recorded input ranges.

It sizes the internal signals of a fixed-point build and makes the
verification kit's vectors when no log is at hand. Each input sweeps its whole
range three ways, one after the other: slow triangles (the static
characteristic), a logarithmic chirp up to 0.45 of the sample rate (the
filters' frequency response) and random levels held for 1 to 200 samples
(steps, the largest transients). The seed is fixed: the same ranges give the
same samples.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

#: The seed of the random levels (fixed, so exports are reproducible).
SEED = 20240917


def _shape(n: int, ts: float, rng: np.random.Generator) -> np.ndarray:
    """A signal of ``n`` samples in [-1, 1]: triangles, then a chirp, then held random levels."""
    n1, n2 = int(0.3 * n), int(0.4 * n)
    n3 = n - n1 - n2
    t1 = np.arange(n1) / max(n1, 1)
    tri = 1.0 - 2.0 * np.abs(((3.0 * t1) % 1.0) * 2.0 - 1.0)
    t2 = np.arange(n2) * ts
    dur = max(n2 * ts, ts)
    f0, f1 = 0.05, 0.45 / ts
    k = np.log(f1 / f0)
    phase = 2 * np.pi * f0 * dur / k * (np.exp(k * t2 / dur) - 1.0)
    chirp = np.sin(phase)
    steps = np.empty(n3)
    i = 0
    while i < n3:
        hold = int(rng.integers(1, 201))
        steps[i:i + hold] = rng.uniform(-1.0, 1.0)
        i += hold
    return np.concatenate([tri, chirp, steps])


def excitation(inputs: Sequence[str], ranges: Mapping[str, tuple[float, float]], ts: float,
               n: int) -> np.ndarray:
    """The synthetic excitation of ``inputs``, shape (len(inputs), n).

    Parameters
    ----------
    inputs : sequence of str
        The model's inputs, in order.
    ranges : mapping of str to (float, float)
        Each input's (min, max); an input without one stays at 0.
    ts : float
        The sample time (the chirp ends at 0.45 of the sample rate).
    n : int
        Number of samples.
    """
    rng = np.random.default_rng(SEED)
    out = np.zeros((len(inputs), n))
    for i, name in enumerate(inputs):
        shape = _shape(n, ts, rng)
        if name not in ranges:
            continue
        lo, hi = ranges[name]
        out[i] = 0.5 * (lo + hi) + 0.5 * (hi - lo) * shape
    return out

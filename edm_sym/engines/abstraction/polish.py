"""Gain fit: a deterministic local search that sets each row's scale by least squares.

The output of a row is proportional to the parameter ``a`` of a gain-like
element (``gain``, ``power_gain``, ``sin_amp``, ``tan_amp``) when every element
after it is linear and homogeneous (gains, filters, delays): scaling ``a``
by c scales the row by c. Given an individual's row outputs (already
simulated and cached), the scales c_j that minimise eq. 8 solve a small
weighted least-squares problem. The gain fit writes ``a_j * c_j`` back into
the chromosome (or turns a ``through`` at such a place into a gain of c_j);
the new individual is then evaluated like any other, and replaces the old
one only when it is really better.

This is the parameter shift of Fig. 7a taken to its optimum along the few
directions where the optimum has a closed form. A row with the right shape
but a wrong scale survives at once, which makes structures (a sign with a
level, a viscous gain) much easier to find; it draws no random numbers.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from edm_sym.core.elements import BY_NAME, REGISTRY, ParamRange
from edm_sym.engines.abstraction.ga import THROUGH, Population

#: Elements whose output is their parameter times a function of the input.
SCALABLE = frozenset(c for c, el in REGISTRY.items() if el.scales_output)
#: Elements with f(c x) = c f(x) for every real c (linear, no offset).
HOMOGENEOUS = frozenset(c for c, el in REGISTRY.items() if el.homogeneous)
GAIN = BY_NAME["gain"].code


def scale_position(codes: Sequence[int], gain_allowed: bool) -> tuple[int, bool] | None:
    """Where a row can be scaled: (element index, True if it is a ``through`` to replace).

    The last gain-like element with only homogeneous elements after it; else,
    when ``gain`` may be used, the last ``through`` with only homogeneous
    elements after it; else None.
    """
    through_at = None
    for i in range(len(codes) - 1, -1, -1):
        c = int(codes[i])
        if c in SCALABLE:
            return i, False
        if c == THROUGH and through_at is None and gain_allowed:
            through_at = i
        if c not in HOMOGENEOUS:
            break
    return (through_at, True) if through_at is not None else None


def gain_fit(
    pop: Population,
    grams: Sequence[tuple[np.ndarray, np.ndarray] | None],
    fitness: np.ndarray,
    n_samples: int,
    ranges: Mapping[str, ParamRange],
    *,
    gain_allowed: bool,
    tol: float = 1e-5,
) -> tuple[np.ndarray, Population]:
    """Candidates with least-squares row scales, for individuals that would gain from them.

    Parameters
    ----------
    pop : Population
        The individuals.
    grams : sequence
        Per individual ``(G, gy)``, the weighted inner products of its rows
        with each other and with the target (see :meth:`Evaluator.evaluate`'s
        ``grams_out``); None: skip it.
    fitness : numpy.ndarray
        Their eq. 8 values.
    n_samples : int
        N, the number of samples (eq. 8 is a mean).
    ranges : mapping
        Parameter ranges (new values are clipped into them).
    gain_allowed : bool
        Whether a ``through`` may become a ``gain``.
    tol : float
        Least relative decrease of the squared fitness the fit must promise.

    Returns
    -------
    idx : numpy.ndarray
        Indices into ``pop`` of the individuals that got a candidate.
    candidates : Population
        The candidates, in the order of ``idx``.
    """
    idx: list[int] = []
    out_in, out_codes, out_ps = [], [], []
    m = pop.codes.shape[1]
    for k, entry in enumerate(grams):
        if entry is None or not np.isfinite(fitness[k]) or fitness[k] == 0.0:
            continue
        places = [scale_position(pop.codes[k, j], gain_allowed) for j in range(m)]
        free = [j for j, pl in enumerate(places) if pl is not None]
        if not free:
            continue
        g_all, gy = entry
        if not (np.all(np.isfinite(g_all)) and np.all(np.isfinite(gy))):
            continue
        # Residual e = y - sum(r): r_i' W e = r_i' W y - sum_j r_i' W r_j.
        g = (gy - g_all.sum(axis=1))[free]
        base = float(fitness[k]) ** 2 * n_samples
        delta = np.linalg.lstsq(g_all[np.ix_(free, free)], g, rcond=1e-10)[0]
        if not float(g @ delta) > tol * base:
            continue
        codes, ps = pop.codes[k].copy(), pop.ps[k].copy()
        for i, j in enumerate(free):
            if abs(float(delta[i])) < 1e-9:
                continue
            c = 1.0 + float(delta[i])
            pos, is_through = places[j]
            if is_through:
                codes[j, pos] = GAIN
                ps[j, pos] = ranges["gain"].encode(c)
                continue
            rng = ranges[REGISTRY[int(codes[j, pos])].name]
            a = rng.decode(float(ps[j, pos])) * c
            if rng.scaling == "log" and not a > 0:
                continue
            ps[j, pos] = rng.encode(a)
        if np.array_equal(codes, pop.codes[k]) and np.array_equal(ps, pop.ps[k]):
            continue
        idx.append(k)
        out_in.append(pop.inputs[k].copy())
        out_codes.append(codes)
        out_ps.append(ps)
    if not idx:
        p, m, n = pop.shape
        return np.zeros(0, dtype=np.intp), Population(
            np.zeros((0, m), np.int64), np.zeros((0, m, n), np.int64), np.zeros((0, m, n)))
    return np.array(idx, dtype=np.intp), Population(
        np.array(out_in), np.array(out_codes), np.array(out_ps))

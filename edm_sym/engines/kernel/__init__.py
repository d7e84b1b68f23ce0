"""The row kernel: rows compiled to a few instructions, run by numba.

The reference simulator (:mod:`edm_sym.engines.simulate`) runs one numpy or
scipy call per element over the whole signal. The genetic algorithm simulates
hundreds of thousands of rows, and there the temporaries, the calls and the
passes over memory cost several times what the generated C needs. This
package compiles a row's realisations into one program of instructions
(:mod:`~edm_sym.engines.kernel.trace`: static elements traced through the
math interface, so elements are still defined once) and runs batches of rows
together (:mod:`~edm_sym.engines.kernel.program`), each instruction one
tight loop over the signal, in place (:mod:`~edm_sym.engines.kernel.loops`),
the first-order filters of several rows overlapped.

The instructions compute what the realisations' numpy steps compute, in the
same order (direct form II transposed as ``scipy.signal.lfilter`` runs it,
numpy's NaN rules for limits and signs), and the transcendental functions
are the C library's (:mod:`edm_sym.core.elements.libm`), as in the reference
simulator, so the kernel agrees with it to rounding (tested to 1e-12; bit for
bit on the machines tried). Several logs laid end to end run in one pass,
every state restarting from rest at each log's first sample
(:func:`~edm_sym.engines.kernel.program.log_bounds`), as the reference
simulator's ``starts`` does.

numba is optional (``pip install edm_sym[fast]``). Without it :data:`NUMBA` is
False and the genetic algorithm runs the reference realisations instead; the
kernel functions then are plain Python (slow, but the same code, which the
tests run on short signals). The compiled code is cached on disk
(``cache=True``): the first import on a machine compiles it once (about
:data:`COMPILE_SECONDS_HINT` s), later processes load it.
"""

from __future__ import annotations

import math

import numpy as np

from edm_sym.engines.kernel.loops import NUMBA, dot_product, numba, score_rows
from edm_sym.engines.kernel.program import (
    Program,
    compile_row,
    compile_steps,
    log_bounds,
    run_program,
    run_rows,
    simulate_rows,
)
from edm_sym.engines.kernel.trace import TraceOps, encode, gene_encoder

__all__ = ["NUMBA", "Program", "TraceOps", "compile_row", "compile_steps", "dot", "encode",
           "gene_encoder", "log_bounds", "numba", "run_program", "run_rows", "score",
           "simulate_rows"]

#: CPU seconds the first compilation took on the development machine (docs only).
COMPILE_SECONDS_HINT = 9


def score(store: np.ndarray, slots: np.ndarray, target: np.ndarray, weights: np.ndarray,
          scratch: np.ndarray | None = None) -> float:
    """Eq. 8 of the individual whose rows are ``store[slots]``.

    Parameters
    ----------
    store : numpy.ndarray
        Shape (S, N) row outputs.
    slots : numpy.ndarray
        int64, the individual's m rows in ``store``.
    target : numpy.ndarray
        Shape (N,).
    weights : numpy.ndarray
        Shape (N,) Lambda, or (1,) for a constant one.
    scratch : numpy.ndarray, optional
        Shape (N,): room for the residual (reused: no allocation per call).

    Returns
    -------
    float
        ``sqrt(sum(Lambda e^2) / N)`` with ``e = target - sum(rows)``, inf when not finite.
    """
    if NUMBA:
        e = scratch if scratch is not None else np.empty(target.shape[0])
        acc = score_rows(store, slots, target, weights, e)
    else:  # numpy: einsum's own loops, not BLAS (the same bits whatever the threads)
        e = target - store[slots].sum(axis=0)
        with np.errstate(over="ignore", invalid="ignore"):
            acc = float(np.einsum("i,i", e, e) * weights[0] if weights.shape[0] == 1
                        else np.einsum("i,i,i", weights, e, e))
    f = math.sqrt(acc / target.shape[0]) if acc >= 0.0 else math.nan
    return f if math.isfinite(f) else math.inf


def dot(a: np.ndarray, b: np.ndarray, weights: np.ndarray) -> float:
    """``sum(Lambda a b)`` (weights of shape (N,) or (1,))."""
    if NUMBA:
        return float(dot_product(a, b, weights))
    with np.errstate(over="ignore", invalid="ignore"):
        return float(np.einsum("i,i", a, b) * weights[0] if weights.shape[0] == 1
                     else np.einsum("i,i,i", weights, a, b))

"""Reference simulator throughput on a 4x5 matrix over 20 000 samples.

Prints element-samples per second of the vectorised simulator and its ratio
to the plain per-sample Python loop over the same matrix (no wall-clock
thresholds: these are figures to read, not tests).

    python benchmarks/bench_simulate.py
"""

from __future__ import annotations

import time

import numpy as np

from edm_sym.core.elements import default_ranges
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.engines.simulate import plain_loop, simulate

TS, N = 1e-3, 20_000


def auger_like_matrix() -> Compensator:
    """A 4x5 matrix in the spirit of the paper's Fig. 21 (mixed static and dynamic)."""
    r = default_ranges(TS, N * TS)
    enc = {k: v.encode for k, v in r.items()}
    m = make_matrix(
        ["theta_w", "theta_uw", "omega"],
        [
            ("omega", [("sign", 0), ("gain", enc["gain"](0.93)), ("through", 0), ("through", 0)]),
            ("omega", [("power_gain", enc["power_gain"](0.007)), ("lpf", 0.9), ("through", 0),
                       ("offset", 0.5)]),
            ("omega", [("derivative", enc["derivative"](1e-3)), ("lpf", enc["lpf"](200.0)),
                       ("gain", 0.55), ("saturation", 0.8)]),
            ("theta_w", [("gain", enc["gain"](4.0)), ("sin_phase", 0.3),
                         ("sin_amp", enc["sin_amp"](0.05)), ("through", 0)]),
            ("omega", [("hpf", 0.3), ("tanh", 0.5), ("notch", 0.6), ("dead_time", 0.05)]),
        ],
    )
    return Compensator(m, TS, {}, N * TS)


def best_of(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    comp = auger_like_matrix()
    t = np.arange(N) * TS
    omega = 20 * np.pi * np.sin(2 * np.pi * 0.1 * t**2)
    theta = np.cumsum(omega) * TS
    data = {"theta_w": np.mod(theta, 2 * np.pi), "theta_uw": theta, "omega": omega}
    n_el = comp.matrix.n_elements * comp.matrix.n_rows
    vec = best_of(lambda: simulate(comp, data), 20)
    loop = best_of(lambda: plain_loop(comp, data), 2)
    print(f"matrix {comp.matrix.shape} ({n_el} elements), {N} samples")
    print(f"vectorised simulator: {vec * 1e3:8.2f} ms  {n_el * N / vec:12.4g} element-samples/s")
    print(f"plain per-sample loop: {loop * 1e3:8.2f} ms  {n_el * N / loop:12.4g} element-samples/s")
    print(f"ratio plain loop / simulator: {loop / vec:.1f}x")


if __name__ == "__main__":
    main()

"""Cost of one compensator sample in generated C, against the reference simulator.

Exports a result (default: the shipped auger example) as double-precision C,
compiles it with -O2 and a timing harness, runs ``<prefix>_step`` over a
20 000-sample log several times and prints nanoseconds per sample; then
times the GA's batched row simulation (the numba row kernel,
:mod:`edm_sym.engines.kernel`, the rows run together into a reused array,
and the GA's own path, every row simulated anew), the reference
simulator (:func:`edm_sym.engines.simulate.simulate`, vectorised over the
log), the plain per-sample Python loop and the generated Python module on
the same log and prints each one's per-sample cost as a ratio to the C.
All times are the best CPU time of several runs (a shared machine's load
shows in wall time, not in CPU time); the C, the row kernel and the GA's
path are timed in turns, so their bests come from the same stretch of time.

Run: ``python benchmarks/bench_c_step.py [RESULT.json] [--cc gcc] [--repeat 20]``.
"""

from __future__ import annotations

import argparse
import importlib.util
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from edm_sym import load_result
from edm_sym.application.exporting import export
from edm_sym.engines import kernel
from edm_sym.engines.simulate import input_array, plain_loop, simulate

REPO = Path(__file__).resolve().parent.parent
N = 20_000
TS = 1e-3

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "edm_comp.h"

/* CPU time of this process: on a shared machine, wall time measures the load. */
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    size_t n = (size_t)strtoul(argv[2], NULL, 10), k;
    int repeat = atoi(argv[3]), r;
    double *u = malloc(n * EDM_COMP_NUM_INPUTS * sizeof *u), best = 1e300, t0, sink = 0.0;
    static edm_comp_state_t s;
    FILE *in = fopen(argv[1], "rb");
    if (argc != 4 || !u || !in || fread(u, sizeof *u, n * EDM_COMP_NUM_INPUTS, in)
            != n * EDM_COMP_NUM_INPUTS) return 2;
    for (r = 0; r < repeat; ++r) {
        edm_comp_init(&s);
        t0 = now();
        for (k = 0; k < n; ++k) sink += edm_comp_step(&s, u + k * EDM_COMP_NUM_INPUTS, NULL);
        t0 = now() - t0;
        if (t0 < best) best = t0;
    }
    printf("%.6g %.17g\n", 1e9 * best / (double)n, sink);
    return 0;
}
"""


def make_log(inputs: tuple[str, ...]) -> dict[str, np.ndarray]:
    """A smooth servo-like log for the given input names (angles from a velocity)."""
    t = np.arange(N) * TS
    omega = 2.0 * np.sin(2 * np.pi * 0.25 * t) + 0.6 * np.sin(2 * np.pi * 1.7 * t + 0.4)
    theta = np.cumsum(omega) * TS
    known = {"omega": omega, "theta_uw": theta, "theta_w": np.mod(theta, 2 * np.pi)}
    rng = np.random.default_rng(0)
    return {name: known.get(name, rng.standard_normal(N)) for name in inputs}


def best_time(fn, repeat: int) -> float:  # noqa: ANN001
    """Shortest CPU time of ``repeat`` calls of ``fn`` (the C harness measures CPU time too)."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def build_c(result, log: dict[str, np.ndarray], d: Path, *, cc: str = "gcc") -> Path:  # noqa: ANN001
    """Export ``result`` as double C into ``d``, compile it with -O2 and the harness; the binary."""
    export(result, "c", d, real="double")
    (d / "harness.c").write_text(HARNESS)
    np.column_stack([log[k] for k in result.inputs]).astype(np.float64).tofile(d / "in.bin")
    subprocess.run([cc, "-std=c99", "-O2", "-o", str(d / "bench"), str(d / "harness.c"),
                    str(d / "edm_comp.c"), "-lm"], check=True, cwd=d)
    return d / "bench"


def run_c(binary: Path, n: int, repeat: int) -> float:
    """Best CPU time of ``repeat`` runs of ``step`` over the log, per sample [ns]."""
    out = subprocess.run([str(binary), str(binary.with_name("in.bin")), str(n), str(repeat)],
                         check=True, capture_output=True, text=True).stdout
    return float(out.split()[0])


def c_ns_per_sample(result, log: dict[str, np.ndarray], *, cc: str = "gcc",  # noqa: ANN001
                    repeat: int = 20) -> float:
    """Export ``result`` as double C, compile it with -O2 and time ``step`` over ``log`` [ns]."""
    with tempfile.TemporaryDirectory() as tmp:
        binary = build_c(result, log, Path(tmp), cc=cc)
        return run_c(binary, len(next(iter(log.values()))), repeat)


def _ga_rows(result, log: dict[str, np.ndarray]):  # noqa: ANN001, ANN202
    """A function simulating the result's rows as the GA does, with nothing cached."""
    from edm_sym.engines.abstraction.rows import simulate_table
    from edm_sym.engines.abstraction.worker import SimContext, Worker, row_table
    comp = result.compensator
    x = np.ascontiguousarray(input_array(comp.matrix.inputs, log))
    rows = comp.matrix.rows
    table = row_table(np.array([r.input for r in rows]),
                      np.array([[g.code for g in r.genes] for r in rows]),
                      np.array([[g.p for g in r.genes] for r in rows]))
    ctx = SimContext(x, comp.sample_time, comp.ranges)
    outs = np.empty((len(rows), x.shape[1]))

    worker = Worker(ctx, ctx.decoder())
    pool = worker.prefix_store()
    simulate_table(worker, table, outs)  # loads the kernel, touches the memory

    def run() -> None:
        worker.stages.clear()  # nothing cached: every row and gene anew
        pool.clear()
        simulate_table(worker, table, outs)

    return run


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print ns per sample and ratios."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("result", nargs="?", default=str(REPO / "examples/auger/result.json"))
    ap.add_argument("--cc", default="gcc")
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args(argv)
    if not shutil.which(args.cc):
        print(f"bench_c_step: {args.cc} is not installed", file=sys.stderr)
        return 1
    result = load_result(args.result)
    log = make_log(result.inputs)
    x = input_array(result.compensator.matrix.inputs, log)
    rows = result.compensator.matrix.rows
    kern_out = np.empty((len(rows), x.shape[-1]))  # reused, as the GA's row stores
    ga_rows = _ga_rows(result, log)
    # The C, the row kernel and the GA's rows in turns, the best of each: a shared
    # machine's load changes within seconds, and all three should meet the same moments.
    rounds = 5
    c_ns = kern_s = rows_s = float("inf")
    with tempfile.TemporaryDirectory() as tmp:
        binary = build_c(result, log, Path(tmp), cc=args.cc)
        for _ in range(rounds):
            c_ns = min(c_ns, run_c(binary, N, max(1, args.repeat // rounds)))
            if kernel.NUMBA:
                kern_s = min(kern_s, best_time(
                    lambda: kernel.simulate_rows(result.compensator, rows, x, kern_out),
                    max(1, args.repeat // rounds)))
            rows_s = min(rows_s, best_time(ga_rows, max(1, args.repeat // rounds)))
    if not kernel.NUMBA:
        kern_s = None
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        export(result, "python", d)
        spec = importlib.util.spec_from_file_location("edm_bench_generated", d / "edm_comp.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        gen_s = best_time(lambda: module.simulate(log), max(1, args.repeat // 10))
    sim_s = best_time(lambda: simulate(result, log), args.repeat)
    loop_s = best_time(lambda: plain_loop(result.compensator, log), max(1, args.repeat // 10))
    print(f"result: {args.result} ({result.matrix.shape}, {N} samples, {args.cc} -O2, double)")
    print(f"{'generated C (edm_comp_step)':36s} {c_ns:10.1f} ns/sample")
    if kern_s is None:
        print("row kernel: numba is not installed (pip install 'edm_sym[fast]')")
    for name, seconds in ((("batched rows (row kernel)", kern_s),) if kern_s else ()) + (
                          ("the GA's rows (kernel, prefix store)", rows_s),
                          ("reference simulator (vectorised)", sim_s),
                          ("plain Python loop (steppers)", loop_s),
                          ("generated Python module", gen_s)):
        ns = 1e9 * seconds / N
        print(f"{name:36s} {ns:10.1f} ns/sample   ratio to C {ns / c_ns:8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

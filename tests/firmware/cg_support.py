"""Shared helpers of the code-generation tests: logs, matrices, harnesses, compilers.

Loaded by path from the tests (``tests/test_codegen*.py``), so it does not
depend on how pytest puts folders on ``sys.path``.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from edm_sym.core.elements import all_elements, default_ranges, element
from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row, make_matrix
from edm_sym.core.result import EdmResult

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
EXAMPLE = REPO / "examples" / "auger" / "result.json"
#: The example an earlier release shipped (seed 1 of the auger config), its Coulomb row a
#: relay: the fixed-point tests of relays and the q15 golden (the shipped example's
#: Coulomb row, a steep tanh, is beyond q15; test_fixedpoint checks the refusal).
RELAY_EXAMPLE = REPO / "tests" / "golden" / "relay_auger_result.json"
#: The example each fixed-point word is tested on: q31 the shipped one, q15 the relay one.
FIXED_EXAMPLES = {"q31": EXAMPLE, "q15": RELAY_EXAMPLE}
#: A hand-written 4x4 result with known content (tests/make_handwritten_result.py).
HANDWRITTEN = REPO / "tests" / "data" / "handwritten_result.json"

TS = 1e-3
N_SAMPLES = 20_000
INPUTS = ("theta_w", "theta_uw", "omega")
#: Columns of the harness's input file: every case's inputs are a prefix of these.
ALL_INPUTS = ("theta_w", "theta_uw", "omega", "alpha")

#: The warnings the generated C must compile cleanly under.
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wdouble-promotion",
          "-Wshadow", "-Werror"]
#: Cortex-M4F with its single-precision FPU, hard-float ABI.
M4 = ["-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard"]


# -- data ---------------------------------------------------------------------
def make_log(n: int = N_SAMPLES, ts: float = TS, seed: int = 0) -> dict[str, np.ndarray]:
    """A smooth, deterministic servo-like log: ``theta_w``, ``theta_uw``, ``omega``, ``alpha`` (+ ``t``)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * ts
    phases = rng.uniform(0, 2 * np.pi, 3)
    omega = (2.0 * np.sin(2 * np.pi * 0.25 * t + phases[0])
             + 0.6 * np.sin(2 * np.pi * 1.7 * t + phases[1])
             + 0.15 * np.sin(2 * np.pi * 9.3 * t + phases[2]))
    alpha = (2.0 * 2 * np.pi * 0.25 * np.cos(2 * np.pi * 0.25 * t + phases[0])
             + 0.6 * 2 * np.pi * 1.7 * np.cos(2 * np.pi * 1.7 * t + phases[1])
             + 0.15 * 2 * np.pi * 9.3 * np.cos(2 * np.pi * 9.3 * t + phases[2]))
    theta_uw = np.cumsum(omega) * ts
    theta_w = np.mod(theta_uw, 2 * np.pi)
    return {"t": t, "theta_w": theta_w, "theta_uw": theta_uw, "omega": omega, "alpha": alpha}


def input_matrix(log: Mapping[str, np.ndarray], inputs: Sequence[str] = ALL_INPUTS) -> np.ndarray:
    """(N, n_inputs) float64 array of the input columns, C order (one sample per row)."""
    return np.ascontiguousarray(np.column_stack([log[k] for k in inputs]), dtype=np.float64)


# -- matrices -----------------------------------------------------------------
def _p(name: str, value: float) -> float:
    return default_ranges(TS, 20.0)[name].encode(value)


#: Per element, its normalised parameter in row 1 and row 2 of its test matrix,
#: where the default (0.7, 0.3) would leave the element idle or near a tan pole.
_P_OVERRIDES = {
    "notch": (0.7, 0.6),  # 0.3 puts the notch at 5 rad/s, too sharp for single precision
    "tan_phase": (0.5, 0.4), "hysteresis": (0.5, 0.3), "saturation": (0.5, 0.3),
    "dead_zone": (0.5, 0.3), "one_way": (0.5, 0.3),
}


def element_compensator(name: str) -> Compensator:
    """A 4x2 matrix exercising element ``name`` between benign neighbours.

    Row 1: omega -> gain 0.5 -> ``name`` -> lpf (about 500 rad/s) -> through;
    row 2: theta_w -> gain 0.2 -> ``name`` -> gain -0.3 -> through. Both keep
    the element's input in a well-conditioned range (no tangent poles), so
    single precision stays close too.
    """
    p1, p2 = _P_OVERRIDES.get(name, (0.7, 0.3))
    rows = [
        ("omega", [("gain", _p("gain", 0.5)), (name, p1), ("lpf", 0.8), ("through", 0.0)]),
        ("theta_w", [("gain", _p("gain", 0.2)), (name, p2), ("gain", _p("gain", -0.3)),
                     ("through", 0.0)]),
    ]
    return Compensator(make_matrix(INPUTS, rows), TS, {}, 20.0)


def random_compensator(rng: np.random.Generator, must_use: int | None = None) -> Compensator:
    """A random valid matrix (1-4 elements per row, 1-4 rows), optionally using code ``must_use``."""
    codes = [e.code for e in all_elements()]
    n, m = int(rng.integers(1, 5)), int(rng.integers(1, 5))
    rows = []
    for _ in range(m):
        genes = tuple(Gene(int(rng.choice(codes)), float(rng.uniform())) for _ in range(n))
        rows.append(Row(int(rng.integers(0, len(INPUTS))), genes))
    if must_use is not None:
        j, i = int(rng.integers(0, m)), int(rng.integers(0, n))
        genes = list(rows[j].genes)
        genes[i] = Gene(element(must_use).code, genes[i].p)
        rows[j] = Row(rows[j].input, tuple(genes))
    return Compensator(ElementMatrix(INPUTS, tuple(rows)), TS, {}, 20.0)


def as_result(comp: Compensator, target: str = "tau_ext") -> EdmResult:
    """Wrap a compensator as a (file-less) result."""
    return EdmResult(comp, target, (), {"seed": None, "package_version": "test",
                                        "data_sha256": None})


# -- tools ----------------------------------------------------------------------
def have(*tools: str) -> bool:
    """True when every tool is on PATH."""
    return all(shutil.which(t) for t in tools)


def run(cmd: Sequence[str], cwd: Path | None = None, timeout: float = 600) -> str:
    """Run a command; raise AssertionError with its output when it fails."""
    proc = subprocess.run(list(map(str, cmd)), cwd=cwd, capture_output=True, text=True,
                          timeout=timeout)
    if proc.returncode != 0:
        raise AssertionError(f"{' '.join(map(str, cmd))} failed ({proc.returncode}):\n"
                             f"{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}")
    return proc.stdout


def compile_objects(cc: str, sources: Sequence[Path], out_dir: Path, flags: Sequence[str] = (),
                    jobs: int | None = None) -> list[Path]:
    """Compile ``sources`` to objects in ``out_dir`` with :data:`STRICT` + ``flags``, in batches."""
    jobs = jobs or max(1, min(8, os.cpu_count() or 1))
    batches = [list(sources[k::jobs]) for k in range(jobs) if sources[k::jobs]]
    procs = []
    for batch in batches:
        cmd = [cc, *STRICT, *flags, "-c", *map(str, batch)]
        procs.append((cmd, subprocess.Popen(cmd, cwd=out_dir, stdout=subprocess.PIPE,
                                            stderr=subprocess.STDOUT, text=True)))
    for cmd, proc in procs:
        out, _ = proc.communicate(timeout=900)
        if proc.returncode != 0:
            raise AssertionError(f"{' '.join(cmd[:3])} ... failed:\n{out[-6000:]}")
    return [out_dir / (Path(s).stem + ".o") for s in sources]


# -- host harness -----------------------------------------------------------------
def host_harness_source(prefixes: Sequence[str]) -> str:
    """A C program running each compensator over a binary log, writing %.17g text.

    ``harness IN.bin N WIDTH OUTDIR``: IN.bin holds N x WIDTH doubles (the
    inputs of every compensator, in order); OUTDIR/<prefix>.txt gets one line
    per sample: each row's output, then the total. A second state stepped with
    ``rows == NULL`` must return bit-identical totals (else exit 3).
    """
    parts = ["#include <stdio.h>", "#include <stdlib.h>", "#include <string.h>"]
    parts += [f'#include "{p}.h"' for p in prefixes]
    for p in prefixes:
        P = p.upper()
        parts.append(f"""
static {p}_state_t {p}_s1, {p}_s2;
static int run_{p}(const double *data, size_t n, size_t width, const char *dir)
{{
    char path[4096];
    {p}_real_t u[{P}_NUM_INPUTS], rows[{P}_NUM_ROWS], total, again;
    size_t k, i;
    int bad = 0;
    FILE *out;
    snprintf(path, sizeof path, "%s/{p}.txt", dir);
    out = fopen(path, "w");
    if (!out) return 2;
    {p}_init(&{p}_s1);
    {p}_init(&{p}_s2);
    for (k = 0; k < n; ++k) {{
        for (i = 0; i < {P}_NUM_INPUTS; ++i) u[i] = ({p}_real_t)data[k * width + i];
        total = {p}_step(&{p}_s1, u, rows);
        again = {p}_step(&{p}_s2, u, NULL);
        if (memcmp(&total, &again, sizeof total) != 0) bad = 1;
        for (i = 0; i < {P}_NUM_ROWS; ++i) fprintf(out, "%.17g ", (double)rows[i]);
        fprintf(out, "%.17g\\n", (double)total);
    }}
    fclose(out);
    return bad ? 3 : 0;
}}""")
    calls = "\n".join(f"    if ((rc = run_{p}(data, n, width, argv[4])) != 0) return rc;"
                      for p in prefixes)
    parts.append(f"""
int main(int argc, char **argv)
{{
    size_t n, width;
    double *data;
    FILE *in;
    int rc;
    if (argc != 5) return 2;
    n = (size_t)strtoul(argv[2], NULL, 10);
    width = (size_t)strtoul(argv[3], NULL, 10);
    data = malloc(n * width * sizeof *data);
    in = fopen(argv[1], "rb");
    if (!data || !in || fread(data, sizeof *data, n * width, in) != n * width) return 2;
    fclose(in);
{calls}
    free(data);
    return 0;
}}
""")
    return "\n".join(parts)


def build_and_run_host(cc: str, gen_dir: Path, prefixes: Sequence[str], x: np.ndarray,
                       opt: str = "-O2") -> dict[str, np.ndarray]:
    """Compile the generated ``<prefix>.c`` files strictly, link the harness, run it.

    Returns prefix -> (N, rows + 1) array: row outputs, then the total.
    """
    objs = compile_objects(cc, [gen_dir / f"{p}.c" for p in prefixes], gen_dir, [opt])
    (gen_dir / "harness.c").write_text(host_harness_source(prefixes))
    exe = gen_dir / f"harness_{cc}"
    run([cc, "-std=c99", opt, "-I", gen_dir, "-o", exe, gen_dir / "harness.c", *objs, "-lm"])
    data = gen_dir / "input.bin"
    x.astype(np.float64).tofile(data)
    out = gen_dir / f"out_{cc}"
    out.mkdir(exist_ok=True)
    run([exe, data, x.shape[0], x.shape[1], out])
    return {p: np.loadtxt(out / f"{p}.txt", ndmin=2) for p in prefixes}


def nm_symbols(nm: str, obj: Path) -> list[tuple[str, str]]:
    """(type letter, name) of every symbol ``nm`` lists for ``obj``."""
    out = []
    for line in run([nm, obj]).splitlines():
        parts = line.split()
        if len(parts) >= 2:
            out.append((parts[-2], parts[-1]))
    return out


def max_abs(a: np.ndarray, b: np.ndarray) -> float:
    """Largest absolute difference (inf when shapes differ or a value is not finite)."""
    if a.shape != b.shape:
        return math.inf
    d = np.abs(a - b)
    return float(np.max(d)) if np.all(np.isfinite(d)) else math.inf

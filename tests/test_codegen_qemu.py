"""The float compensator on a Cortex-M4F: arm-none-eabi-gcc -Os, run under QEMU (mps2-an386).

The harness (tests/firmware/m4_harness.c, start-up and linker script beside
it) reads the log through semihosting file I/O, steps the compensator and
writes every row and the total; they must match the host float build within
1e-4 of the RMS of the compensation torque. The test prints the step
function's code size and stack use, the init function's, the object's .text
and the state's size (the figures docs/codegen.md tables).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

# tests/ is on sys.path (pytest's rootdir-relative import mode): the shared harness.
from firmware import cg_support as cg  # noqa: E402

from edm_sym import load_result
from edm_sym.application.exporting import export
from edm_sym.engines.simulate import simulate

TOOLS = ("arm-none-eabi-gcc", "arm-none-eabi-size", "arm-none-eabi-nm", "qemu-system-arm")
pytestmark = [
    pytest.mark.toolchain,
    pytest.mark.skipif(not cg.have(*TOOLS), reason=f"needs {', '.join(TOOLS)}"),
]
FIRMWARE = cg.HERE
LOG = cg.make_log()


def _kinds():  # noqa: ANN202
    return load_result(cg.REPO / "tests" / "golden" / "kinds" / "result.json")


CASES = {"auger": lambda: load_result(cg.EXAMPLE), "kinds": _kinds}


def build_m4(folder: Path) -> dict[str, int]:
    """Compile edm_comp.c strictly for the M4F, link the harness; return size figures."""
    cc = "arm-none-eabi-gcc"
    cg.run([cc, *cg.M4, "-Os", *cg.STRICT, "-fstack-usage", "-c", "edm_comp.c",
            "-o", "edm_comp.o"], cwd=folder)
    cg.run([cc, *cg.M4, "-Os", "--specs=rdimon.specs", "-T", FIRMWARE / "mps2_an386.ld",
            "-I", folder, "-o", "harness.elf", FIRMWARE / "startup_m4.c",
            FIRMWARE / "m4_harness.c", "edm_comp.o", "-lm"], cwd=folder)
    sizes = {}
    for line in cg.run(["arm-none-eabi-nm", "--size", "edm_comp.o"], cwd=folder).splitlines():
        size, kind, name = line.split()
        sizes[name] = int(size, 16)
        assert kind in "Tt", f"{name}: only code expected, found symbol type {kind}"
    su = (folder / "edm_comp.su").read_text()
    stack = {m.group(1): int(m.group(2)) for m in re.finditer(r":(\w+)\s+(\d+)\s+(\w+)", su)}
    text = int(cg.run(["arm-none-eabi-size", "edm_comp.o"], cwd=folder).splitlines()[1].split()[0])
    # The state's size on the target: an object as large as the state type, measured by nm.
    (folder / "state_size.c").write_text('#include "edm_comp.h"\n'
                                         "char edm_comp_state_size[sizeof(edm_comp_state_t)];\n")
    cg.run([cc, *cg.M4, "-c", "state_size.c", "-o", "state_size.o"], cwd=folder)
    state = int(cg.run(["arm-none-eabi-nm", "--size", "state_size.o"], cwd=folder).split()[0], 16)
    return {"step_bytes": sizes["edm_comp_step"], "init_bytes": sizes["edm_comp_init"],
            "text_bytes": text, "step_stack": stack["edm_comp_step"],
            "init_stack": stack["edm_comp_init"], "state_bytes": state}


@pytest.mark.parametrize("case", list(CASES))
def test_cortex_m4f_under_qemu_matches_host_float(case: str, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture) -> None:
    if not shutil.which("gcc"):
        pytest.skip("gcc is not installed (host float reference)")
    result = CASES[case]()
    export(result, "c", tmp_path, real="float")
    figures = build_m4(tmp_path)
    x = cg.input_matrix(LOG, result.inputs)  # the harness reads NUM_INPUTS columns
    x.astype(np.float32).tofile(tmp_path / "input.bin")
    out = cg.run(["qemu-system-arm", "-M", "mps2-an386", "-nographic", "-semihosting-config",
                  "enable=on,target=native", "-kernel", "harness.elf"], cwd=tmp_path, timeout=300)
    assert f"harness: {cg.N_SAMPLES} samples" in out
    n_cols = result.matrix.n_rows + 1
    m4 = np.fromfile(tmp_path / "output.bin", dtype=np.float32).astype(float).reshape(-1, n_cols)

    host_dir = tmp_path / "host"
    export(result, "c", host_dir, real="float")
    host = cg.build_and_run_host("gcc", host_dir, ["edm_comp"], x)["edm_comp"]
    sim = simulate(result, LOG)
    rms = float(np.sqrt(np.mean(sim.total ** 2)))
    assert m4.shape == host.shape == (cg.N_SAMPLES, n_cols)
    err_host = cg.max_abs(m4, host)
    err_sim = cg.max_abs(m4, np.vstack([sim.rows, sim.total]).T)
    assert err_host <= 1e-4 * rms, f"M4 vs host float: {err_host:.3g} > 1e-4 x {rms:.3g}"
    assert err_sim <= 1e-4 * rms, f"M4 vs simulator: {err_sim:.3g} > 1e-4 x {rms:.3g}"
    with capsys.disabled():
        print(f"\n[cortex-m4f -Os, {case}] edm_comp_step {figures['step_bytes']} B code, "
              f"{figures['step_stack']} B stack; edm_comp_init {figures['init_bytes']} B, "
              f"{figures['init_stack']} B stack; .text {figures['text_bytes']} B; "
              f"state {figures['state_bytes']} B; "
              f"max |M4 - host float| = {err_host:.2e} ({err_host / rms:.1e} RMS), "
              f"|M4 - simulator| = {err_sim:.2e} ({err_sim / rms:.1e} RMS)")

"""The q31 and q15 C on a Cortex-M3 (no FPU) under QEMU (mps2-an385), and no floating point in it.

``arm-none-eabi-gcc -mcpu=cortex-m3 -mfloat-abi=soft -Os`` builds the
compensator strictly; its object must hold no floating-point instruction, call
no soft-float routine (no undefined symbol at all) and hold no .data or .bss.
The verification kit then runs under QEMU through semihosting and must pass.
The test prints the figures docs/codegen.md tables: the step function's code
size and stack, the init function's code, all code, the tables (read-only
data), the state size, and the kit's deviation with and without the
switching rule.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from firmware import cg_support as cg  # noqa: E402

from edm_sym import load_result
from edm_sym.application.exporting import export

TOOLS = ("arm-none-eabi-gcc", "arm-none-eabi-objdump", "arm-none-eabi-nm", "qemu-system-arm")
pytestmark = [
    pytest.mark.toolchain,
    pytest.mark.skipif(not cg.have(*TOOLS), reason=f"needs {', '.join(TOOLS)}"),
]
M3 = ["-mcpu=cortex-m3", "-mthumb", "-mfloat-abi=soft"]
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wshadow", "-Werror"]
#: Floating-point instructions of the ARMv7-M FPU (VFP) and the soft-float library's routines.
FLOAT_INSN = re.compile(r"\tv(add|sub|mul|div|mov|ldr|str|cvt|cmp|abs|neg|sqrt|fma|push|pop)")
SOFT_FLOAT = re.compile(r"__aeabi_[fd]|__(add|sub|mul|div|float|fix|extend|trunc)\w*[sd]f")


@pytest.mark.parametrize("real", ["q31", "q15"])
def test_cortex_m3_runs_the_kit_without_floating_point(real: str, tmp_path: Path,
                                                       capsys: pytest.CaptureFixture) -> None:
    result = load_result(cg.FIXED_EXAMPLES[real])
    export(result, "c", tmp_path, real=real)
    export(result, "test", tmp_path, real=real)
    cc = "arm-none-eabi-gcc"
    cg.run([cc, *M3, "-Os", *STRICT, "-fstack-usage", "-c", "edm_comp.c", "-o", "edm_comp.o"],
           cwd=tmp_path)
    dis = cg.run(["arm-none-eabi-objdump", "-d", "edm_comp.o"], cwd=tmp_path)
    assert not FLOAT_INSN.search(dis), FLOAT_INSN.search(dis).group(0)
    syms = cg.run(["arm-none-eabi-nm", "--size", "-u", "edm_comp.o"], cwd=tmp_path)
    assert not SOFT_FLOAT.search(syms) and not syms.strip(), f"calls: {syms}"
    sizes = {}
    for line in cg.run(["arm-none-eabi-nm", "--size", "edm_comp.o"], cwd=tmp_path).splitlines():
        size, kind, name = line.split()
        sizes[name] = (int(size, 16), kind)
        assert kind in "TtRr", f"{name}: code and read-only tables only, found {kind}"
    cg.run([cc, *M3, "-Os", "-DEDM_COMP_TEST_NO_MAIN", "-c", "edm_comp_test.c", "-o", "kit.o"],
           cwd=tmp_path)
    fw = cg.HERE
    cg.run([cc, *M3, "-Os", "--specs=rdimon.specs", "-T", fw / "mps2_an386.ld", "-I", tmp_path,
            "-o", "kit.elf", fw / "startup_m3.c", fw / "m3_kit_main.c", "kit.o", "edm_comp.o"],
           cwd=tmp_path)
    out = cg.run(["qemu-system-arm", "-M", "mps2-an385", "-nographic", "-semihosting-config",
                  "enable=on,target=native", "-kernel", "kit.elf"], cwd=tmp_path, timeout=300)
    assert "PASS" in out, out
    su = (tmp_path / "edm_comp.su").read_text()
    stack = {m.group(1): int(m.group(2)) for m in re.finditer(r":(\w+)\s+(\d+)\s+(\w+)", su)}
    code = sum(s for s, k in sizes.values() if k in "Tt")
    tables = sum(s for s, k in sizes.values() if k in "Rr")
    state = re.search(r"state (\d+) bytes", out).group(1)
    raw = re.search(r"without the switching rule: max deviation (\d+) LSB", out).group(1)
    with capsys.disabled():
        print(f"\n[cortex-m3 -Os, auger, {real}] edm_comp_step {sizes['edm_comp_step'][0]} B code, "
              f"{stack['edm_comp_step']} B stack; edm_comp_init {sizes['edm_comp_init'][0]} B; "
              f"code {code} B; tables {tables} B; state {state} B; "
              f"{out.strip().splitlines()[-1]} ({raw} without the switching rule)")

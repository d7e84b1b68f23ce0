"""The generated Python module: contract API, standard library only, the simulator's numbers."""

from __future__ import annotations

import ast
import importlib.util
import sys
import warnings
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

# tests/ is on sys.path (pytest's rootdir-relative import mode): the shared harness.
from firmware import cg_support as cg  # noqa: E402

from edm_sym import load_result
from edm_sym.application.exporting import export
from edm_sym.core.elements import all_elements
from edm_sym.engines.simulate import simulate

LOG = cg.make_log()
_count = [0]


def load_module(path: Path) -> ModuleType:
    """Import a generated module from its file under a fresh name."""
    _count[0] += 1
    spec = importlib.util.spec_from_file_location(f"edm_generated_{_count[0]}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def generated(result, tmp_path: Path, prefix: str = "edm_comp") -> ModuleType:  # noqa: ANN001
    (path,) = export(result, "python", tmp_path, prefix=prefix)
    return load_module(path)


def run_rows(module: ModuleType, log: dict, n: int | None = None) -> np.ndarray:
    """(N, rows + 1): step_rows per sample, then step's total from a second instance."""
    comp, comp2 = module.Compensator(), module.Compensator()
    cols = [log[name][:n] for name in module.INPUTS]
    out = []
    for u in zip(*cols, strict=True):
        rows = comp.step_rows(u)
        out.append((*rows, comp2.step(u)))
    return np.array(out)


def reference(comp, log: dict, n: int | None = None) -> np.ndarray:  # noqa: ANN001
    sim = simulate(comp, {k: v[:n] for k, v in log.items()})
    return np.vstack([sim.rows, sim.total]).T


def test_module_has_the_contract_api(tmp_path: Path) -> None:
    result = load_result(cg.EXAMPLE)
    module = generated(result, tmp_path)
    assert module.INPUTS == result.inputs
    assert module.SAMPLE_TIME == result.sample_time == 1e-3
    assert module.NUM_ROWS == result.matrix.n_rows
    assert module.SHA256 == result.sha256
    comp = module.Compensator()
    u = (1.0, 2.0, 0.5, -3.0)[: len(module.INPUTS)]
    first = comp.step(u)
    assert isinstance(first, float)
    assert len(comp.step_rows(u)) == module.NUM_ROWS
    comp.reset()
    assert comp.step(u) == first
    totals = module.simulate({k: LOG[k][:50] for k in module.INPUTS})
    assert isinstance(totals, list) and len(totals) == 50


def test_module_imports_only_the_standard_library(tmp_path: Path) -> None:
    module_path = export(load_result(cg.EXAMPLE), "python", tmp_path)[0]
    tree = ast.parse(module_path.read_text())
    imported = {a.name.split(".")[0] for node in ast.walk(tree)
                if isinstance(node, ast.Import) for a in node.names}
    imported |= {node.module.split(".")[0] for node in ast.walk(tree)
                 if isinstance(node, ast.ImportFrom) and node.module}
    assert imported <= set(sys.stdlib_module_names), imported


def test_example_matches_the_simulator(tmp_path: Path) -> None:
    result = load_result(cg.EXAMPLE)
    got = run_rows(generated(result, tmp_path), LOG)
    assert got.shape == (cg.N_SAMPLES, result.matrix.n_rows + 1)
    assert cg.max_abs(got, reference(result.compensator, LOG)) <= 1e-9
    module = load_module(tmp_path / "edm_comp.py")
    assert np.max(np.abs(np.array(module.simulate(LOG)) - got[:, -1])) == 0.0


@pytest.mark.parametrize("name", [e.name for e in all_elements()])
def test_each_element_matches_the_simulator(name: str, tmp_path: Path) -> None:
    comp = cg.element_compensator(name)
    got = run_rows(generated(cg.as_result(comp), tmp_path, prefix="m"), LOG)
    assert cg.max_abs(got, reference(comp, LOG)) <= 1e-9


def test_random_matrices_match_the_simulator(tmp_path: Path) -> None:
    rng = np.random.default_rng(2024)
    n = 400
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for k in range(30):
            comp = cg.random_compensator(rng, must_use=k)
            got = run_rows(generated(cg.as_result(comp), tmp_path, prefix=f"r{k}"), LOG, n)
            ref = reference(comp, LOG, n)
            scale = np.maximum(1.0, np.abs(ref))
            assert np.all(np.abs(got - ref) <= 1e-9 * scale), f"matrix {k}: {comp.matrix}"


def test_no_state_still_resets(tmp_path: Path) -> None:
    from edm_sym.core.matrix import Compensator, make_matrix

    comp = Compensator(make_matrix(cg.INPUTS, [("omega", [("gain", 0.6)])]), 1e-3, {}, 20.0)
    module = generated(cg.as_result(comp), tmp_path)
    c = module.Compensator()
    c.reset()
    assert c.step((0.0, 0.0, 1.0)) == pytest.approx(2.0)


def test_a_chain_that_amplifies_the_last_bit_of_tanh_still_matches(tmp_path: Path) -> None:
    # numpy's own tanh differs from the C library's in the last bit on about a quarter
    # of the arguments; acos near +-1 made that 1.5e-8 N m (the simulator used numpy's).
    import edm_sym
    from edm_sym.core.elements import default_ranges

    ts, tsum = 1e-3, 20.0
    p = default_ranges(ts, tsum)["tanh"].encode(1.0)
    m = edm_sym.make_matrix(["omega"], [("omega", [("tanh", p), ("acos", 0.0)])])
    comp = edm_sym.Compensator(m, ts, {}, tsum)
    log = {"omega": np.linspace(-20.0, 20.0, 2000)}
    got = run_rows(generated(cg.as_result(comp), tmp_path, prefix="chain"), log)
    assert np.max(np.abs(got - reference(comp, log))) == 0.0

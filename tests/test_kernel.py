"""The numba row kernel against the reference simulator, to 1e-12.

Without numba the kernel's functions are plain Python: these tests then run
the same code, slowly, on the same short signals.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import TS, smooth_signal

from edm_sym.core.elements import REGISTRY, all_elements, default_ranges, libm
from edm_sym.core.elements.base import StaticElement
from edm_sym.core.elements.realisation import REALISATIONS, StaticMap
from edm_sym.core.fitness import fitness
from edm_sym.core.matrix import Compensator
from edm_sym.engines import kernel
from edm_sym.engines.abstraction.ga import Operators
from edm_sym.engines.abstraction.rows import simulate_table
from edm_sym.engines.abstraction.schedule import GaSettings
from edm_sym.engines.abstraction.worker import SimContext, Worker, row_table
from edm_sym.engines.kernel import program
from edm_sym.engines.simulate import simulate_row

N = 2000
RANGES = default_ranges(TS, N * TS)


def _close(got: np.ndarray, want: np.ndarray) -> None:
    """Equal to 1e-12 of the signal's scale, NaN where the reference has NaN."""
    assert got.shape == want.shape
    assert np.array_equal(np.isnan(got), np.isnan(want))
    ok = ~np.isnan(want)
    assert np.array_equal(np.isinf(got[ok]), np.isinf(want[ok]))
    fin = ok & np.isfinite(want)
    scale = max(1.0, float(np.max(np.abs(want[fin]))) if fin.any() else 1.0)
    assert np.max(np.abs(got[fin] - want[fin]), initial=0.0) <= 1e-12 * scale


def _signal(seed: int, amplitude: float = 3.0) -> np.ndarray:
    return amplitude * smooth_signal(N, seed=seed)


@pytest.mark.parametrize("el", all_elements(), ids=lambda e: e.name)
def test_every_element_alone_equals_its_realisation(el) -> None:  # noqa: ANN001
    x = _signal(el.code)
    for p in (0.0, 0.13, 0.5, 0.87, 1.0):
        a = RANGES[el.name].decode(p) if el.param is not None else None
        stage = el.realise(a, TS)
        program, _ = kernel.compile_row([stage])
        _close(kernel.run_program(program, x), stage.run(x.copy()))


@pytest.mark.parametrize("el", all_elements(), ids=lambda e: e.name)
def test_non_finite_inputs_go_through_as_in_numpy(el) -> None:  # noqa: ANN001
    x = _signal(el.code + 50)
    x[[100, 400, 401, 900]] = [np.nan, np.inf, -np.inf, np.nan]
    a = RANGES[el.name].decode(0.4) if el.param is not None else None
    stage = el.realise(a, TS)
    program, _ = kernel.compile_row([stage])
    with np.errstate(all="ignore"):
        _close(kernel.run_program(program, x), stage.run(x.copy()))


def test_every_realisation_type_has_an_encoder() -> None:
    enc = kernel.trace._Encoder()
    for cls in REALISATIONS:
        assert callable(getattr(enc, f"_encode_{cls.__name__}"))


def _random_rows(seed: int, count: int, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # Every registered element, uniformly (no extra weight on ``through``).
    ops = Operators(GaSettings(through_rate=0.0), 3)
    return ops.random_rows(np.random.default_rng(seed), count, n)


@pytest.mark.parametrize("seed", range(6))
def test_random_rows_of_all_elements_equal_the_reference_simulator(seed: int) -> None:
    inputs, codes, ps = _random_rows(seed, 60, 4)
    assert set(np.unique(codes)) <= set(REGISTRY)
    x = np.vstack([_signal(10 * seed + k) for k in range(3)])
    ctx = SimContext(x, TS, RANGES)
    kernel_worker = Worker(ctx, ctx.decoder(), use_kernel=True)
    table = row_table(inputs, codes, ps)
    # Twice: the second time rows start from the prefixes the first one stored.
    for _ in range(2):
        got = simulate_table(kernel_worker, table)
        for r in range(len(table)):
            genes = [(int(c), float(p)) for c, p in zip(codes[r], ps[r], strict=True)]
            y = x[int(inputs[r])]
            with np.errstate(all="ignore"):
                for i, (c, p) in enumerate(genes):
                    el = REGISTRY[c]
                    a = RANGES[el.name].decode(p) if el.param is not None else None
                    if i == 0 and el.from_sin_cos is not None:
                        # The GA's shortcut for a sine reading an input (not the kernel's).
                        y = el.from_sin_cos(np.sin(y), np.cos(y), a)
                        continue
                    y = el.realise(a, TS).run(y)
            _close(got[r], y)
    assert len(kernel_worker.prefix_store()) > 0


def test_the_kernel_worker_equals_simulate_row_on_a_compensator() -> None:
    inputs, codes, ps = _random_rows(99, 8, 4)
    from edm_sym.engines.abstraction.ga import Population

    pop = Population(inputs.reshape(1, 8), codes.reshape(1, 8, 4), ps.reshape(1, 8, 4))
    comp = Compensator(pop.matrix(0, ["u0", "u1", "u2"]), TS, RANGES, N * TS)
    x = np.vstack([_signal(k + 7) for k in range(3)])
    ctx = SimContext(x, TS, RANGES)
    got = simulate_table(Worker(ctx, ctx.decoder(), use_kernel=True),
                         row_table(inputs, codes, ps))
    for j, row in enumerate(comp.matrix.rows):
        with np.errstate(all="ignore"):
            want = simulate_row(comp, row, x[row.input])
        if row.genes[0].element.from_sin_cos is not None:
            # From the input's cached sine and cosine: equal to rounding of the input's scale.
            assert np.allclose(got[j], want, rtol=0, atol=1e-12 * max(1, np.max(np.abs(want))))
            continue
        _close(got[j], want)


def test_stored_prefixes_are_the_outputs_of_the_first_stages() -> None:
    names = ["lpf", "through", "tanh", "hysteresis", "gain"]
    stages = [REGISTRY[next(c for c, e in REGISTRY.items() if e.name == nm)] for nm in names]
    real = [el.realise(RANGES[el.name].decode(0.6) if el.param else None, TS) for el in stages]
    program, stored = kernel.compile_row(real, store=True)
    assert stored == [1, 3, 4]  # ``through`` changes nothing: its prefix is the one before
    x = _signal(3)
    inter = np.empty((program.stores, N))
    out = kernel.run_program(program, x, inter=inter)
    y = x
    prefixes = []
    for r in real:
        y = r.run(y)
        prefixes.append(y)
    for j, count in enumerate(stored):
        _close(inter[j], prefixes[count - 1])
    _close(out, prefixes[-1])


def test_score_is_eq_8_and_dot_the_weighted_inner_product() -> None:
    rng = np.random.default_rng(0)
    store = rng.standard_normal((6, N))
    y = rng.standard_normal(N)
    w = rng.uniform(0, 3, N)
    slots = np.array([4, 0, 2], dtype=np.int64)
    want = fitness(y - store[slots].sum(axis=0), w)
    assert kernel.score(store, slots, y, w) == pytest.approx(want, rel=1e-12)
    assert kernel.score(store, slots, y, np.ones(1)) == pytest.approx(
        fitness(y - store[slots].sum(axis=0)), rel=1e-12)
    assert kernel.dot(store[1], store[3], w) == pytest.approx(float(np.sum(w * store[1] * store[3])),
                                                              rel=1e-12)
    store[2, 17] = np.inf
    assert kernel.score(store, slots, y, w) == np.inf


def test_a_static_element_the_tracer_cannot_follow_is_refused() -> None:
    class Square(StaticElement):
        _abstract = True  # not registered

        @staticmethod
        def f(m, x, a):  # noqa: ANN001, ANN205
            return x * x

    with pytest.raises(TypeError, match="one signal"):
        kernel.compile_row([StaticMap(Square, None)])


@pytest.mark.parametrize("seed", range(3))
def test_simulate_rows_equals_the_reference_simulator(seed: int) -> None:
    from edm_sym.engines.abstraction.ga import Population
    from edm_sym.engines.simulate import simulate_rows

    inputs, codes, ps = _random_rows(100 + seed, 20, 4)
    pop = Population(inputs.reshape(1, 20), codes.reshape(1, 20, 4), ps.reshape(1, 20, 4))
    comp = Compensator(pop.matrix(0, ["u0", "u1", "u2"]), TS, RANGES, N * TS)
    x = np.vstack([_signal(k + 20 * seed) for k in range(3)])
    with np.errstate(all="ignore"):
        want = simulate_rows(comp, comp.matrix.rows, x)
    got = kernel.simulate_rows(comp, comp.matrix.rows, x)
    for j in range(len(want)):
        _close(got[j], want[j])


@pytest.mark.parametrize("el", all_elements(), ids=lambda e: e.name)
def test_the_gene_encoder_gives_the_steps_of_the_realisation(el) -> None:  # noqa: ANN001
    rng = RANGES[el.name] if el.param is not None else None
    make = kernel.gene_encoder(el, TS, rng.decode(0.5) if rng else None)
    for p in (0.0, 0.31, 1.0):
        a = rng.decode(p) if rng else None
        assert make(a) == kernel.encode(el.realise(a, TS))


# -- the numpy steps, bit for bit --------------------------------------------------------

def _special(seed: int) -> np.ndarray:
    """Smooth signals of several scales and the values where guards switch."""
    x = np.concatenate([_signal(seed, a) for a in (1.0, 30.0, 1e3)])
    edges = [0.0, -0.0, np.nan, np.inf, -np.inf, 1.0, -1.0, 1.0000000000000002, 21.999999999999996,
             22.0, -22.0, 19.0, 1e300, -1e300, np.pi / 2, -np.pi / 2, 3 * np.pi / 2, 1e-310,
             np.nextafter(np.pi / 2, 0.0), np.nextafter(np.pi / 2, 4.0), 1e6, -1e6 - 1.0]
    return np.concatenate([x, edges, x[:7]])  # the edges in the middle, a short tail


def _same_bits(got: np.ndarray, want: np.ndarray) -> None:
    """Equal to the bit (signed zeros too), NaN where the reference has NaN."""
    nan = np.isnan(want)
    assert np.array_equal(np.isnan(got), nan)
    assert np.array_equal(got[~nan].view(np.uint64), want[~nan].view(np.uint64))


_STEP_ARGS = {"sym_log": [(0.1,), (1e-3,), (7.0,)],
              "sym_pow": [(0.1,), (0.5,), (1.0,), (1.55,), (2.0,), (3.0,)]}


@pytest.mark.parametrize("name", sorted(program.CALLS))
@pytest.mark.parametrize("in_place", [True, False])
def test_each_numpy_step_gives_the_math_interfaces_bits(name: str, in_place: bool) -> None:
    from edm_sym.core.elements.ops import NUMPY

    for seed in range(3):
        x = _special(seed)
        for args in _STEP_ARGS.get(name, [()]):
            with np.errstate(all="ignore"):
                want = getattr(NUMPY, name)(x.copy(), *args)
                v = x.copy() if in_place else np.full_like(x, 5.0)
                program._call(name, args, v, v if in_place else x.copy(), np.empty_like(x))
            _same_bits(v, want)


def test_a_numpy_step_without_a_kernel_form_runs_the_math_interfaces_own(
        monkeypatch: pytest.MonkeyPatch) -> None:
    x = _special(4)
    el = next(e for e in all_elements() if e.name == "sin_amp")
    stage = el.realise(0.7, TS)
    want = kernel.run_program(kernel.compile_row([stage])[0], x)
    monkeypatch.delitem(program.CALLS, "sin")
    _same_bits(kernel.run_program(kernel.compile_row([stage])[0], x), want)


def test_the_c_librarys_tanh_is_exactly_one_beyond_the_kernels_bound() -> None:
    # The kernel writes +-1 there without calling libm.tanh (program.TANH_ONE).
    rng = np.random.default_rng(0)
    x = np.concatenate([[program.TANH_ONE, np.nextafter(program.TANH_ONE, 30.0), np.inf, 1e308],
                        program.TANH_ONE + rng.uniform(0, 10, 200_000),
                        np.exp(rng.uniform(np.log(program.TANH_ONE), 709.0, 200_000))])
    assert np.all(libm.tanh(x) == 1.0) and np.all(libm.tanh(-x) == -1.0)
    assert all(math.tanh(v) == 1.0 for v in x[::1000])


@pytest.mark.parametrize("el", [e for e in all_elements() if issubclass(e, StaticElement)],
                         ids=lambda e: e.name)
def test_a_static_element_gives_the_reference_bits(el) -> None:  # noqa: ANN001
    # Limits and signs compiled, transcendental functions numpy's: the same numbers.
    x = _special(el.code)
    for p in (0.0, 0.37, 1.0):
        a = RANGES[el.name].decode(p) if el.param is not None else None
        stage = el.realise(a, TS)
        program_, _ = kernel.compile_row([stage])
        with np.errstate(all="ignore"):
            want = stage.run(x.copy())
        _same_bits(kernel.run_program(program_, x), want)


# -- batches -----------------------------------------------------------------------------

_FILTERS = [["lpf", "notch", "gain"], ["notch", "lpf"], ["lpf"], ["hpf", "notch", "tanh"],
            ["lead", "sign", "lag"], ["notch"], ["tan_amp", "lpf"], ["through", "through"],
            ["integral", "atan", "notch"], ["phase"], ["lag", "notch", "log"]]


def _batch(seed: int) -> tuple[list, list[int]]:
    """Rows rich in filters (so groups of both orders form) and random rows of all elements."""
    rng = np.random.default_rng(seed)
    by_name = {e.name: e for e in all_elements()}
    rows = [[by_name[nm] for nm in names] for names in _FILTERS]
    _, codes, _ = _random_rows(seed, 14, 4)
    rows += [[REGISTRY[int(c)] for c in line] for line in codes]
    stages = [[el.realise(RANGES[el.name].decode(rng.random()) if el.param else None, TS)
               for el in row] for row in rows]
    return stages, [int(i) for i in rng.integers(0, 3, len(stages))]


@pytest.mark.parametrize("seed", range(3))
def test_a_batch_gives_each_row_the_numbers_it_gets_alone(seed: int) -> None:
    from edm_sym.engines.kernel.loops import GROUP

    stages, inputs = _batch(seed)
    x = np.vstack([_signal(30 * seed + k) for k in range(3)])
    programs, stored = zip(*(kernel.compile_row(s, store=True) for s in stages), strict=True)
    parts, _ = program._schedule(programs, [range(p.stores) for p in programs], inputs)
    groups = {(int(line[3]), int(line[2])) for part in parts if isinstance(part, np.ndarray)
              for line in part if line[0] == GROUP}
    assert {order for order, _ in groups} == {1, 2} and max(m for _, m in groups) >= 4
    count = len(programs)
    store = np.full((count + 3, N), np.nan)
    dest = np.arange(count, dtype=np.int64)[::-1] + 3  # any rows of the store
    slots = np.cumsum([0, *(p.stores for p in programs)])
    inter = np.full((slots[-1] + 3, N), np.nan)
    inter[slots[-1]:] = x  # as if stored prefixes
    row_slots = [range(slots[r], slots[r + 1]) for r in range(count)]
    # A third of the rows get their input as an array (copied), the others read it in
    # place: a row of the sources or a stored prefix (inter row -1 - k for start k < 0).
    starts = [(x[i].copy(), i, -1 - (slots[-1] + i))[r % 3] for r, i in enumerate(inputs)]
    kernel.run_rows(programs, starts, store, dest, inter, row_slots, sources=x)
    _same_bits(inter[slots[-1]:], x)
    for r, prog in enumerate(programs):
        alone_inter = np.empty((prog.stores, N))
        alone = kernel.run_program(prog, x[inputs[r]], inter=alone_inter)
        _same_bits(store[dest[r]], alone)
        _same_bits(inter[slots[r]:slots[r + 1]], alone_inter)
        y = x[inputs[r]]
        with np.errstate(all="ignore"):
            for stage in stages[r]:
                y = stage.run(y)
        _close(store[dest[r]], y)
    assert [len(s) for s in stored] == [p.stores for p in programs]


def test_a_row_that_changes_nothing_gives_its_input() -> None:
    x = np.vstack([_signal(1), _signal(2)])
    through = REGISTRY[next(c for c, e in REGISTRY.items() if e.name == "through")]
    prog, _ = kernel.compile_row([through.realise(None, TS)] * 3)
    store = np.zeros((3, N))
    kernel.run_rows([prog] * 3, [1, x[0], -2], store, np.array([0, 1, 2]), x[::-1].copy(),
                    sources=x)
    _same_bits(store[0], x[1])
    _same_bits(store[1], x[0])
    _same_bits(store[2], x[0])  # inter row 1


def _table_rows(names: list[list[str]], inputs: list[int]) -> np.ndarray:
    by_name = {e.name: c for c, e in REGISTRY.items()}
    codes = np.array([[by_name[nm] for nm in row] for row in names])
    ps = np.tile([0.3, 0.6, 0.2, 0.8][: codes.shape[1]], (len(names), 1))
    return row_table(np.array(inputs), codes, ps)


@pytest.mark.parametrize("prefix_mb", [64.0, 0.05])
def test_a_row_whose_prefix_a_row_of_its_batch_computes_starts_from_it(
        prefix_mb: float, monkeypatch: pytest.MonkeyPatch) -> None:
    x = np.vstack([_signal(k + 40) for k in range(3)])
    ctx = SimContext(x, TS, RANGES, prefix_bytes=int(prefix_mb * 2**20))
    worker = Worker(ctx, ctx.decoder(), use_kernel=True)
    # Rows 1 and 2 share row 0's first three elements; row 3 is new.
    table = _table_rows([["lpf", "tanh", "notch", "gain"], ["lpf", "tanh", "notch", "sign"],
                         ["lpf", "tanh", "notch", "atan"], ["hpf", "sin_amp", "lag", "offset"]],
                        [1, 1, 1, 2])
    runs: list[list[int]] = []
    real = kernel.run_rows

    def spy(programs, *args, **kw):  # noqa: ANN001, ANN002, ANN003, ANN202
        runs.append([len(p.lines) for p in programs])
        return real(programs, *args, **kw)

    monkeypatch.setattr(kernel, "run_rows", spy)
    got = simulate_table(worker, table)
    if prefix_mb > 1:
        # Rows 0 and 3 together, then 1 and 2 from row 0's prefix: only their last element
        # (sign: one line; atan: a gain and numpy's arctan).
        assert len(runs) == 2 and len(runs[0]) == 2 and runs[1] == [1, 2]
    else:  # a prefix store of a few slots: a row at a time
        assert all(len(r) == 1 for r in runs)
    reference = Worker(ctx, ctx.decoder(), use_kernel=False)
    outs = [np.empty(N) for _ in table]  # outputs given as separate arrays
    assert all(a is b for a, b in zip(simulate_table(reference, table, outs), outs, strict=True))
    for got_row, want in zip(got, outs, strict=True):
        _close(got_row, want)


#: Logs laid end to end: a long one, one shorter than the longest delay, one of a sample.
STARTS = (1200, 1203, 1204)


def _logs_apart(fn, x: np.ndarray) -> np.ndarray:  # noqa: ANN001
    """``fn`` on each log of ``x`` on its own, laid end to end again."""
    edges = [0, *STARTS, x.shape[-1]]
    return np.concatenate([fn(x[..., a:b]) for a, b in zip(edges, edges[1:], strict=False)],
                          axis=-1)


@pytest.mark.parametrize("el", all_elements(), ids=lambda e: e.name)
def test_several_logs_each_run_from_rest_in_the_kernel(el) -> None:  # noqa: ANN001
    # Each log alone and all of them in one pass give the same bits; the reference
    # realisation on each log alone gives them to rounding.
    x = _signal(el.code + 70)
    for p in (0.0, 0.5, 1.0):
        a = RANGES[el.name].decode(p) if el.param is not None else None
        stage = el.realise(a, TS)
        prog, _ = kernel.compile_row([stage])
        got = kernel.run_program(prog, x, starts=STARTS)
        _same_bits(got, _logs_apart(lambda s, p=prog: kernel.run_program(p, s.copy()), x))
        with np.errstate(all="ignore"):
            _close(got, _logs_apart(lambda s, st=stage: st.run(s.copy()), x))


@pytest.mark.parametrize("seed", range(3))
def test_a_batch_over_several_logs_gives_each_log_its_own_numbers(seed: int) -> None:
    # Filters run in groups of four and two, numpy steps between them, stored prefixes:
    # no state crosses from one log into the next.
    stages, inputs = _batch(seed)
    x = np.vstack([_signal(30 * seed + k) for k in range(3)])
    programs = [kernel.compile_row(s, store=True)[0] for s in stages]
    count = len(programs)
    slots = np.cumsum([0, *(p.stores for p in programs)])
    store, inter = np.empty((count, N)), np.empty((slots[-1], N))
    kernel.run_rows(programs, inputs, store, np.arange(count, dtype=np.int64), inter,
                    [range(slots[r], slots[r + 1]) for r in range(count)], sources=x,
                    bounds=kernel.log_bounds(N, STARTS))
    for r, prog in enumerate(programs):
        _same_bits(store[r], _logs_apart(lambda s, p=prog: kernel.run_program(p, s.copy()),
                                         x[inputs[r]]))
        y = _logs_apart(lambda s, st=stages[r]: simulate_row_stages(st, s), x[inputs[r]])
        _close(store[r], y)


def simulate_row_stages(stages, x: np.ndarray) -> np.ndarray:  # noqa: ANN001
    """A row's realisations one after another on ``x`` (from rest)."""
    y = x.copy()
    with np.errstate(all="ignore"):
        for stage in stages:
            y = stage.run(y)
    return y


@pytest.mark.parametrize("seed", range(3))
def test_the_kernel_worker_over_several_logs_equals_the_reference_worker(seed: int) -> None:
    inputs, codes, ps = _random_rows(seed + 20, 60, 4)
    x = np.vstack([_signal(10 * seed + k + 5) for k in range(3)])
    ctx = SimContext(x, TS, RANGES, starts=STARTS)
    table = row_table(inputs, codes, ps)
    fast = Worker(ctx, ctx.decoder(), use_kernel=True)
    reference = Worker(ctx, ctx.decoder(), use_kernel=False)
    for _ in range(2):  # the second time from the prefixes the first one stored
        got = simulate_table(fast, table)
        want = simulate_table(reference, table)
        for r in range(len(table)):
            if REGISTRY[int(codes[r, 0])].from_sin_cos is not None:
                scale = max(1.0, float(np.nanmax(np.abs(want[r]), initial=0.0)))
                assert np.allclose(got[r], want[r], rtol=0, atol=1e-12 * scale, equal_nan=True)
                continue
            _close(got[r], want[r])


def test_log_bounds_refuse_starts_outside_the_signal() -> None:
    assert kernel.log_bounds(10).tolist() == [0, 10]
    assert kernel.log_bounds(10, (4, 7)).tolist() == [0, 4, 7, 10]
    for bad in ((0,), (4, 4), (7, 4), (10,)):
        with pytest.raises(ValueError, match="starts: expected increasing sample indices"):
            kernel.log_bounds(10, bad)

"""Batched evaluation: eq. 8 as the reference simulator gives it, caches, executors, one path."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from conftest import TS, smooth_signal
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import cont2discrete

from edm_sym.core.elements import REGISTRY, LinearElement, all_elements, default_ranges, element
from edm_sym.core.matrix import Compensator
from edm_sym.engines.abstraction import Evaluator
from edm_sym.engines.abstraction.cache import SlotStore
from edm_sym.engines.abstraction.ga import Operators, Population
from edm_sym.engines.abstraction.gain_fit import gain_fit, scale_places
from edm_sym.engines.abstraction.poles import prefix_has_pole, with_tangent
from edm_sym.engines.abstraction.prefixes import plan_prefixes, prefix_keys
from edm_sym.engines.abstraction.rows import simulate_table
from edm_sym.engines.abstraction.schedule import GaSettings
from edm_sym.engines.abstraction.worker import SimContext, Worker, row_table
from edm_sym.engines.simulate import fitness, simulate, simulate_row

N = 3000
NAMES = ["u0", "u1", "u2"]


@pytest.fixture(scope="module")
def signals() -> tuple[np.ndarray, np.ndarray]:
    x = np.vstack([3 * smooth_signal(N, seed=s) for s in range(3)])
    y = np.sign(x[1]) + 0.1 * x[0] + 0.05 * np.random.default_rng(0).standard_normal(N)
    return x, y


def _population(seed: int, p: int = 24, m: int = 3, n: int = 4):  # noqa: ANN202
    ops = Operators(GaSettings(through_rate=0.2), 3)
    return ops.random_population(np.random.default_rng(seed), p, m, n)


def _reference(pop, k: int, x: np.ndarray, y: np.ndarray, lam) -> float:  # noqa: ANN001
    comp = Compensator(pop.matrix(k, NAMES), TS, {}, N * TS)
    total = simulate(comp, dict(zip(NAMES, x, strict=True))).total
    return fitness(y - total, lam)


@pytest.mark.parametrize("weights", ["one", "array"])
def test_fitness_is_eq_8_of_the_reference_simulator(signals, weights: str) -> None:
    x, y = signals
    lam = 1.0 if weights == "one" else np.where(np.arange(N) < N // 2, 3.0, 0.5)
    pop = _population(1)
    with Evaluator(x, y, TS, default_ranges(TS, N * TS), workers=1) as ev:
        ev.set_weights(lam)
        got = ev.evaluate(pop.inputs, pop.codes, pop.ps)
    for k in range(len(pop)):
        want = _reference(pop, k, x, y, lam)
        assert got[k] == pytest.approx(want, rel=1e-9), k


def test_rows_are_simulated_once_then_served_from_the_cache(signals) -> None:
    x, y = signals
    pop = _population(2)
    with Evaluator(x, y, TS, default_ranges(TS, N * TS), workers=1) as ev:
        first = ev.evaluate(pop.inputs, pop.codes, pop.ps)
        simulated = ev.stats.rows_simulated
        assert simulated <= pop.codes.shape[0] * pop.codes.shape[1]
        # A new individual made of rows already seen needs no simulation.
        mixed = pop.take([0])
        mixed.inputs[0, 0], mixed.codes[0, 0], mixed.ps[0, 0] = (
            pop.inputs[5, 1], pop.codes[5, 1], pop.ps[5, 1])
        ev.evaluate(mixed.inputs, mixed.codes, mixed.ps)
        again = ev.evaluate(pop.inputs, pop.codes, pop.ps)
        assert ev.stats.rows_simulated == simulated
        assert np.array_equal(first, again)
        assert ev.stats.hit_rate > 0.4


def test_a_parameter_free_gene_keeps_its_row_key(signals) -> None:
    x, y = signals
    pop = _population(3, p=1, m=1, n=2)
    pop.codes[0, 0] = [19, 0]  # sign, through: p means nothing
    other = pop.take([0])
    other.ps[0, 0] = [0.123, 0.987]
    with Evaluator(x, y, TS, default_ranges(TS, N * TS), workers=1) as ev:
        a = ev.evaluate(pop.inputs, pop.codes, pop.ps)
        b = ev.evaluate(other.inputs, other.codes, other.ps)
        assert a[0] == b[0] and ev.stats.rows_simulated == 1


def test_the_slot_store_evicts_least_recent_rows_but_never_kept_ones() -> None:
    store = SlotStore(3, 4)
    for k, key in enumerate([b"a", b"b", b"c"]):
        store.commit(key, store.allocate(1, ())[0])[:] = k
    store.get(b"a")
    slot = store.allocate(1, keep={b"b"})  # b is kept, a was used lately: c goes
    assert store.get(b"c") is None and store.get(b"b") is not None
    store.commit(b"d", slot[0])
    with pytest.raises(RuntimeError, match="too small"):
        store.allocate(1, keep={b"a", b"b", b"d"})


def _longest_prefixes_one_by_one(store: SlotStore, table: np.ndarray, rows: list[int]
                                 ) -> list[tuple[int, int]]:
    """Each row's longest stored prefix by a lookup per length, longest first (the plain way)."""
    n = (table.shape[1] - 1) // 2
    out = []
    for r in rows:
        for k in range(n - 1, 0, -1):
            slot = store.lookup(prefix_keys(table[r:r + 1], k)[0])
            if slot is not None:
                out.append((k, slot))
                break
        else:
            out.append((0, -1))
    return out


def _new_prefixes_one_by_one(store: SlotStore, table: np.ndarray, rows: list[int],
                             start: list[int], read: set[bytes]) -> dict[tuple[int, int], int]:
    """The slot of each new prefix (row, length), planned row by row (the plain way).

    Row by row, shortest first, each prefix not yet wanted is wanted, as long
    as a row's new ones fit in the budget (half the store, and no slot of a
    prefix read); then the wanted ones get slots in that order.
    """
    n = (table.shape[1] - 1) // 2
    budget = min(store.slots // 2, store.slots - len(read))
    wants: dict[bytes, list[tuple[int, int]]] = {}
    for r, k0 in zip(rows, start, strict=True):
        mine = [(prefix_keys(table[r:r + 1], k)[0], k) for k in range(k0 + 1, n)]
        if len(wants) + len({key for key, _ in mine if key not in wants}) > budget:
            continue
        for key, k in mine:
            wants.setdefault(key, []).append((r, k))
    order = list(wants)
    given = store.place(order, read) if order else []
    return {rk: slot for key, slot in zip(order, given, strict=True) for rk in wants[key]}


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([40, 400]))
def test_batched_lookups_and_prefix_plans_match_one_lookup_at_a_time(seed: int,
                                                                     size: int) -> None:
    # The planning looks up thousands of keys per batch at once (peek, then touch the
    # ones found): it must find the same slots and leave the same least-recent order
    # as one lookup per key, which decides what a later batch evicts.
    rng = np.random.default_rng(seed)
    n = 4
    table = np.zeros((24, 1 + 2 * n))
    table[:, 0] = rng.integers(0, 2, 24)
    table[:, 1:1 + n] = rng.choice([element("lpf").code, element("gain").code], (24, n))
    table[:, 1 + n:] = rng.choice([0.25, 0.5], (24, n))  # few values: prefixes repeat
    # 40 slots: not every row's new prefixes fit (the budget decides row by row); 400: all do.
    stores = [SlotStore(size, 1), SlotStore(size, 1)]
    stored = [key for k in range(1, n) for key in prefix_keys(table[rng.random(24) < 0.5], k)]
    for key in rng.permutation(len(stored)).tolist():
        for store in stores:
            if store.lookup(stored[key]) is None:
                store.commit(stored[key], store.allocate(1, ())[0])
    keys = [stored[k] for k in rng.integers(0, len(stored), 30).tolist()] + [b"none"]
    assert stores[0].lookup_many(keys) == [-1 if (s := stores[1].lookup(k)) is None else s
                                           for k in keys]
    assert list(stores[0]._lru.items()) == list(stores[1]._lru.items())
    simulate = rng.random(24) < 0.7
    plain = _longest_prefixes_one_by_one(stores[1], table, np.flatnonzero(simulate).tolist())
    plan = plan_prefixes(stores[0], table, simulate)
    rows = np.flatnonzero(simulate)
    assert plan.start[rows].tolist() == [k for k, _ in plain]
    assert [plan.slots[r, k] if k else -1 for r, (k, _) in zip(rows, plain, strict=True)] == [
        s for _, s in plain]
    assert not plan.start[~simulate].any()
    # The plan then makes room for the new prefixes: the rows it just read stay.
    read = {prefix_keys(table[r:r + 1], k)[0] for r, (k, _) in zip(rows, plain, strict=True) if k}
    # The new prefixes: the same slots, in the same order, as planned row by row, a
    # prefix two rows share in one slot, and each slot's key recorded.
    new = _new_prefixes_one_by_one(stores[1], table, rows.tolist(), [k for k, _ in plain], read)
    got = {(r, k): int(plan.slots[r, k]) for r in rows.tolist() for k in range(n)
           if k > plan.start[r] and plan.slots[r, k] >= 0}
    assert got == new
    assert plan.new == {slot: prefix_keys(table[r:r + 1], k)[0] for (r, k), slot in new.items()}
    assert list(stores[0]._lru.items()) == list(stores[1]._lru.items())
    assert stores[0]._free == stores[1]._free
    assert all(stores[0].lookup(key) is not None for key in read)


@pytest.mark.parametrize("mode", ["forked pool", "thread executor"])
def test_parallel_evaluation_gives_the_same_bits(signals, mode: str) -> None:
    x, y = signals
    pops = [_population(s, p=32) for s in range(3)]
    ranges = default_ranges(TS, N * TS)
    with Evaluator(x, y, TS, ranges, workers=1) as ev:
        want = [ev.evaluate(p.inputs, p.codes, p.ps) for p in pops]
    if mode == "forked pool":
        ev = Evaluator(x, y, TS, ranges, workers=2, cache_bytes=1)
        ev.start()
        with ev:
            got = [ev.evaluate(p.inputs, p.codes, p.ps) for p in pops]
            assert ev.shared
    else:
        with ThreadPoolExecutor(2) as pool, Evaluator(x, y, TS, ranges, executor=pool,
                                                      workers=2) as ev:
            got = [ev.evaluate(p.inputs, p.codes, p.ps) for p in pops]
    for a, b in zip(want, got, strict=True):
        assert np.array_equal(a, b)


def test_the_rows_of_every_individual_and_the_gram_matrix(signals) -> None:
    x, y = signals
    pop = _population(4, p=6)
    with Evaluator(x, y, TS, default_ranges(TS, N * TS), workers=1) as ev:
        ev.evaluate(pop.inputs, pop.codes, pop.ps)
        rows = ev.evaluation(pop.inputs, pop.codes, pop.ps, rows=True).rows  # all from the memo
        assert len(rows) == 6 and all(r is not None for r in rows)
        keys, outs = rows[2]
        gram, gy = ev.gram(keys, outs)
        a = np.array(outs)
        assert np.allclose(gram, a @ a.T, rtol=1e-12) and np.allclose(gy, a @ y, rtol=1e-12)


# -- one path: the GA runs the simulator's realisations --------------------------

LINEAR = [e for e in all_elements() if issubclass(e, LinearElement)]


@pytest.mark.parametrize("el", [e for e in LINEAR if e.method == "bilinear"], ids=lambda e: e.name)
def test_the_discretisation_equals_scipy_cont2discrete(el) -> None:  # noqa: ANN001
    # scipy's tf -> state space -> bilinear -> tf round trip is the independent oracle.
    ranges = default_ranges(TS, 20.0)
    for p in np.linspace(0, 1, 11):
        a = ranges[el.name].decode(p)
        num, den = el.tf(a)
        b0, a0, _ = cont2discrete((np.array(num, float), np.array(den, float)), TS,
                                  method="bilinear")
        b0, a0 = np.atleast_1d(np.squeeze(b0)), np.atleast_1d(np.squeeze(a0))
        b0, a0 = b0 / a0[0], a0 / a0[0]
        b1, a1 = el.coefficients(a, TS)
        assert len(b1) == len(b0) and len(a1) == len(a0) and a1[0] == 1.0
        scale = max(np.max(np.abs(b0)), 1.0)
        assert np.allclose(b1, b0, rtol=1e-10, atol=1e-12 * scale), (p, b0, b1)
        assert np.allclose(a1, a0, rtol=1e-12, atol=1e-14), (p, a0, a1)


def test_the_backward_difference_of_the_derivative_is_its_closed_form() -> None:
    b, a = element("derivative").coefficients(0.3, TS)
    assert np.allclose(b, [0.3 / TS, -0.3 / TS], rtol=1e-15) and list(a) == [1.0, 0.0]


@pytest.mark.parametrize("el", [e for e in all_elements() if e.from_sin_cos is not None],
                         ids=lambda e: e.name)
def test_from_sin_cos_equals_the_element_to_rounding(el) -> None:  # noqa: ANN001
    x = 4 * smooth_signal(4000, seed=el.code)
    for a in (-2.5, 0.3, 1.7):
        want = el.simulate(x, a, TS)
        got = el.from_sin_cos(np.sin(x), np.cos(x), a)
        assert np.max(np.abs(got - want)) <= 1e-12 * max(float(np.max(np.abs(want))), 1.0)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_ga_rows_equal_the_simulators_rows_bit_for_bit(seed: int) -> None:
    # The GA's reference path (no numba): the simulator's own realisations.
    pop = _population(seed, p=1, m=2, n=4)
    comp = Compensator(pop.matrix(0, NAMES), TS, {}, 20.0)
    x = np.vstack([3 * smooth_signal(1500, seed=seed + k) for k in range(3)])
    worker = Worker(SimContext(x, TS, comp.ranges), SimContext(x, TS, comp.ranges).decoder(),
                    use_kernel=False)
    table = row_table(pop.inputs[0], pop.codes[0], pop.ps[0])
    got = simulate_table(worker, table)
    for j, row in enumerate(comp.matrix.rows):
        if row.genes[0].element.from_sin_cos is not None:
            continue  # computed from cached sines: equal to rounding (the test above)
        assert np.array_equal(got[j], simulate_row(comp, row, x[row.input]), equal_nan=True)


def test_row_table_is_canonical() -> None:
    t = row_table(np.array([1]), np.array([[19, 3]]), np.array([[0.4, 0.6]]))
    assert t.tolist() == [[1.0, 19.0, 3.0, 0.0, 0.6]]


@pytest.mark.parametrize("name", ["sin_phase", "sin_amp"])
def test_a_sine_reading_an_input_uses_cached_sines_to_rounding(signals, name: str) -> None:
    x, y = signals
    pop = _population(0, p=1, m=1, n=2)
    from edm_sym.core.elements import BY_NAME

    pop.codes[0, 0] = [BY_NAME[name].code, BY_NAME["gain"].code]
    pop.ps[0, 0] = [0.37, 0.8]
    with Evaluator(x, y, TS, default_ranges(TS, N * TS), workers=1) as ev:
        rows = ev.evaluation(pop.inputs, pop.codes, pop.ps, rows=True).rows
        got = rows[0][1][0]
    comp = Compensator(pop.matrix(0, NAMES), TS, {}, N * TS)
    want = simulate_row(comp, comp.matrix.rows[0], x[pop.inputs[0, 0]])
    assert np.allclose(got, want, rtol=0, atol=1e-12 * np.max(np.abs(want)))


@pytest.mark.parametrize("cache_mb", [0.5, 4.0])
def test_cache_mb_bounds_the_stores_of_every_process(signals, cache_mb: float) -> None:
    x, y = signals
    cache = int(cache_mb * 2**20)
    row = 8 * N
    with Evaluator(x, y, TS, default_ranges(TS, N * TS), workers=1, cache_bytes=cache,
                   max_batch_rows=24 * 3) as ev:
        for seed in range(6):
            pop = _population(100 + seed)
            ev.evaluate(pop.inputs, pop.codes, pop.ps)
        own, pool = ev._local.own, ev._local.prefix_store()
        # The row store holds at least two batches (72 rows here), else cache_mb.
        assert own.nbytes <= max(cache, (2 * 24 * 3 + 16) * row)
        assert pool.nbytes <= max(cache // 2, 8 * row)
        assert len(own) <= own.slots and len(pool) <= pool.slots
        if cache_mb == 4.0:  # room for all: nothing was simulated twice
            assert ev.stats.rows_simulated <= 6 * 24 * 3


def test_a_prefix_made_in_one_lane_serves_every_lane(signals) -> None:
    # With the forked pool the prefixes are shared like the rows: a row that differs
    # from a simulated one only in its last parameter starts from the same prefix as
    # in one process, whichever lane simulated the first one.
    x, y = signals
    ops = Operators(GaSettings(through_rate=0.0), 3)
    pop = ops.random_population(np.random.default_rng(5), 32, 3, 4)
    shifted = pop.take(np.arange(32))
    shifted.ps[:, :, -1] = (shifted.ps[:, :, -1] + 0.37) % 1.0
    got = {}
    for workers in (1, 2):
        with Evaluator(x, y, TS, default_ranges(TS, N * TS), workers=workers) as ev:
            ev.evaluate(pop.inputs, pop.codes, pop.ps)
            before = (ev.stats.rows_simulated, ev.stats.elements_simulated)
            fit = ev.evaluate(shifted.inputs, shifted.codes, shifted.ps)
            rows = ev.stats.rows_simulated - before[0]
            elements = ev.stats.elements_simulated - before[1]
            # Most rows run their last element only (a few start earlier, before a
            # `through` that stores no prefix).
            assert rows > 32 and rows <= elements < 1.2 * rows
            got[workers] = (fit, rows, elements)
    assert np.array_equal(got[1][0], got[2][0]) and got[1][1:] == got[2][1:]


def test_a_rows_estimated_cost_is_that_of_the_elements_it_runs() -> None:
    from edm_sym.core.elements import BY_NAME
    from edm_sym.engines.abstraction.balance import ROW_COST, element_costs
    from edm_sym.engines.abstraction.cache import SlotStore
    from edm_sym.engines.abstraction.prefixes import plan_prefixes, prefix_key

    code = {name: BY_NAME[name].code for name in ("gain", "tan_phase", "lpf")}
    # Two rows: gain -> lpf -> tan_phase, and gain -> lpf -> gain (its 2-prefix stored).
    table = np.array([[2, code["gain"], code["lpf"], code["tan_phase"], 0.5, 0.5, 0.5],
                      [2, code["gain"], code["lpf"], code["gain"], 0.5, 0.5, 0.7]], dtype=float)
    store = SlotStore(8, 4)
    store.commit(prefix_key(table[1], 3, 2), 0)
    plan = plan_prefixes(store, table, np.array([True, True]), element_costs(table))
    assert plan.start.tolist() == [2, 2]  # both start from the stored prefix
    assert plan.cost.tolist() == pytest.approx([BY_NAME["tan_phase"].cost + ROW_COST,
                                                BY_NAME["gain"].cost + ROW_COST])
    # Counted alike, they would cost the same: a tangent costs over twenty gains.
    assert plan.cost[0] > 5 * plan.cost[1]
    plain = plan_prefixes(SlotStore(8, 4), table, np.array([True, False]))
    assert plain.cost.tolist() == [3, 0]


def test_a_new_prefix_shared_by_the_whole_batch_is_split_between_lanes(signals) -> None:
    # Every individual's first row is new and differs from the others only in its
    # last parameter: one new prefix joins them all. Kept in one group, one lane
    # would do the batch alone; over the cap the lanes each compute the prefix
    # (the same bits into the same slot) and share the rows.
    x, y = signals
    ops = Operators(GaSettings(through_rate=0.0), 3)
    pop = ops.random_population(np.random.default_rng(11), 32, 3, 4)
    pop.inputs[:, 0] = pop.inputs[0, 0]
    pop.codes[:, 0] = pop.codes[0, 0]
    pop.ps[:, 0, :-1] = pop.ps[0, 0, :-1]
    pop.ps[:, 0, -1] = np.linspace(0.05, 0.95, 32)
    got = {}
    for workers in (1, 2):
        with Evaluator(x, y, TS, default_ranges(TS, N * TS), workers=workers) as ev:
            fit = ev.evaluate(pop.inputs, pop.codes, pop.ps)
            got[workers] = (fit, ev.stats.elements_simulated, len(ev.stats.peak_rss))
    assert np.array_equal(got[1][0], got[2][0])
    assert got[2][2] == 2  # both lanes worked
    # The shared prefix ran once per lane: at most its 3 elements more.
    assert got[1][1] < got[2][1] <= got[1][1] + 3


@pytest.mark.parametrize("lanes", ["one", "pool", "threads"])
def test_the_time_lanes_share_is_counted_within_the_evaluation(signals, lanes: str) -> None:
    # bench_ga's "this process alone" is the wall time outside the spans in which
    # other lanes hold pieces; one lane has none.
    x, y = signals
    pop = _population(5, p=32)
    with ThreadPoolExecutor(2) as pool:
        kw = {"one": {"workers": 1}, "pool": {"workers": 2},
              "threads": {"workers": 2, "executor": pool}}[lanes]
        with Evaluator(x, y, TS, default_ranges(TS, N * TS), **kw) as ev:
            ev.evaluate(pop.inputs, pop.codes, pop.ps)
            st = ev.stats
    if lanes == "one":
        assert st.spread_seconds == 0.0 and st.wait_seconds == 0.0 and st.idle_seconds == 0.0
    else:
        assert 0.0 < st.spread_seconds <= st.eval_seconds
        assert 0.0 <= st.wait_seconds <= st.spread_seconds
    if lanes == "pool":
        # Two lanes on one clock: one of them ends first and waits (not more than the span).
        assert 0.0 < st.idle_seconds <= st.spread_seconds
    elif lanes == "threads":
        assert st.idle_seconds == 0.0  # an executor's tasks are not timed on this clock


def test_the_rows_are_made_on_every_lane_with_the_shared_store(signals) -> None:
    # The local search wants the rows back: with the forked pool they are in the
    # shared store, so the batch still runs on both lanes, with the same bits.
    x, y = signals
    pop = _population(7, p=16)
    got = {}
    for workers in (1, 2):
        with Evaluator(x, y, TS, default_ranges(TS, N * TS), workers=workers) as ev:
            res = ev.evaluation(pop.inputs, pop.codes, pop.ps, rows=True)
            fit, rows = res.fitness, res.rows
            got[workers] = (fit, [[np.array(r) for r in outs] for _, outs in rows])
            pids = set(ev.stats.peak_rss)
        assert len(pids) == workers
    assert np.array_equal(got[1][0], got[2][0])
    for a, b in zip(got[1][1], got[2][1], strict=True):
        assert all(np.array_equal(u, v, equal_nan=True) for u, v in zip(a, b, strict=True))


def test_groups_keep_a_new_row_or_prefix_in_one_piece_and_pieces_follow_lane_speeds() -> None:
    from edm_sym.engines.abstraction.balance import Feeder, group_costs, groups, scoring_costs
    from edm_sym.engines.abstraction.prefixes import PrefixPlan

    # Lines 0-5; 1 and 4 are new; line 4's new prefix (slot 7) is also line 5's.
    members = np.array([[0, 1], [2, 4], [3, 5], [0, 1], [2, 3], [0, 2]])
    missing = np.array([False, True, False, False, True, True])
    slots = np.full((6, 3), -1)
    slots[4, 1:] = [7, 8]
    slots[5, 1:] = [7, 9]
    plan = PrefixPlan(np.zeros(6, dtype=np.int64), slots, np.where(missing, 3, 0))
    parts = groups(members, plan, missing)
    assert sorted(parts) == [[0, 3], [1, 2], [4], [5]]
    costs = group_costs(parts, members, plan, scoring_costs(members, np.ones(6, dtype=bool), None))
    score = 2 * 2 * 0.6  # two scored individuals of two rows
    assert costs.tolist() == pytest.approx([3 + score, 6 + score, score / 2, score / 2])
    even = Feeder(parts, costs, [1.0, 1.0])
    assert sorted(i for p in even.pieces for i in p) == list(range(6))
    assert even.pieces[0] == [1, 2] and even.pieces[1] == [0, 3, 4, 5]
    # A lane three times as fast gets the dear groups.
    fast = Feeder(parts, costs, [1.0, 3.0])
    assert fast.loads[1] > 2 * fast.loads[0]
    # Under a cost cap a shared new prefix no longer joins groups: each side computes it.
    per = np.full(6, 1.0)
    capped = groups(members, plan, missing, per, cap=5.0)
    assert sorted(capped) == [[0, 3], [1], [2], [4], [5]]
    # Within the cap it does.
    assert sorted(groups(members, plan, missing, per, cap=10.0)) == [[0, 3], [1, 2], [4], [5]]



_FITTED = ("gain", "power_gain", "sin_amp", "tan_amp", "tan_phase", "through", "lpf", "saturation",
           "sign", "dead_zone", "dead_time", "tanh")


def _fit_population(seed: int, p: int = 40):  # noqa: ANN202
    ops = Operators(GaSettings(through_rate=0.3, elements=_FITTED), 3)
    return ops.random_population(np.random.default_rng(seed), p, 3, 4), ops


@pytest.mark.parametrize("mode", ["this process", "forked pool", "thread executor"])
def test_the_lanes_evaluate_each_gain_fit_candidate_as_the_main_process_would(
        signals, mode: str) -> None:
    # The candidate a lane makes, evaluates and sends back as changed genes is the
    # one gain_fit makes from the scales, with the same eq. 8 bit for bit (poles too).
    x, y = signals
    ranges = default_ranges(TS, N * TS)
    lam = np.where(np.arange(N) < N // 3, 2.0, 1.0)
    pops = [_fit_population(s)[0] for s in range(4)]
    want = []
    with Evaluator(x, y, TS, ranges, workers=1, reject_poles=True) as ref:
        ref.set_weights(lam)
        for pop in pops:
            places = scale_places(pop.codes, gain_allowed=True)
            res = ref.evaluation(pop.inputs, pop.codes, pop.ps, free=places[0] >= 0)
            fit, scales = res.fitness, res.scales
            idx, cand = gain_fit(pop, scales, places, ranges)
            want.append((fit, idx, cand, ref.evaluate(cand.inputs, cand.codes, cand.ps)))
    pool = ThreadPoolExecutor(2) if mode == "thread executor" else None
    workers = 1 if mode == "this process" else 2
    with Evaluator(x, y, TS, ranges, workers=workers, executor=pool, cache_bytes=1,
                   reject_poles=True) as ev:
        ev.set_weights(lam)
        for pop, (fit, idx, cand, cfit) in zip(pops, want, strict=True):
            places = scale_places(pop.codes, gain_allowed=True)
            res = ev.evaluation(pop.inputs, pop.codes, pop.ps, free=places[0] >= 0,
                                gain_allowed=True)
            got, fitted = res.fitness, res.fitted
            assert np.array_equal(got, fit)
            made = [k for k, f in enumerate(fitted) if not np.isnan(f[0])]
            assert made == idx.tolist()
            assert np.isinf(cfit).any() and np.isfinite(cfit).sum() > 10
            for q, k in enumerate(made):
                f, genes = fitted[k]
                assert f == cfit[q] or (np.isinf(f) and np.isinf(cfit[q]))
                codes, ps = pop.codes[k].copy(), pop.ps[k].copy()
                j, i = genes[:, 0].astype(int), genes[:, 1].astype(int)
                codes[j, i], ps[j, i] = genes[:, 2], genes[:, 3]
                assert np.array_equal(codes, cand.codes[q]) and np.array_equal(ps, cand.ps[q])
        if ev.shared:  # every spare slot came back: none lost, none given twice
            assert len(ev.store) + len(set(ev.store._free)) == ev.store.slots
            assert len(ev.store._free) == len(set(ev.store._free))
    if pool is not None:
        pool.shutdown()


def test_a_candidate_that_is_another_individuals_new_row_loses_no_slot(signals) -> None:
    # Each lane's piece is recorded as it comes in: a candidate whose rows are also
    # new rows of the batch (here each candidate is in the batch as an individual
    # too) must neither keep its spare slot nor hide that row from the lane that
    # writes it. Every slot of both stores is then stored or free, once.
    x, y = signals
    ranges = default_ranges(TS, N * TS)
    pops = [_fit_population(s)[0] for s in (11, 12)]
    batches = []
    with Evaluator(x, y, TS, ranges, workers=1) as ref:
        for pop in pops:
            places = scale_places(pop.codes, gain_allowed=True)
            scales = ref.evaluation(pop.inputs, pop.codes, pop.ps, free=places[0] >= 0).scales
            _, cand = gain_fit(pop, scales, places, ranges)
            both = Population.concat([pop, cand])
            batches.append((both, ref.evaluate(both.inputs, both.codes, both.ps)))
    with Evaluator(x, y, TS, ranges, workers=2) as ev:
        assert ev.shared
        for both, want in batches:
            places = scale_places(both.codes, gain_allowed=True)
            got = ev.evaluation(both.inputs, both.codes, both.ps, free=places[0] >= 0,
                                gain_allowed=True).fitness
            assert np.array_equal(got, want)
            for store in (ev.store, ev.prefixes):
                assert len(store) + len(set(store._free)) == store.slots
                assert len(store._free) == len(set(store._free))
        assert len(ev.stats.peak_rss) == 2  # both lanes had pieces


def test_the_gain_fit_never_moves_a_tangent_pole() -> None:
    # Why a lane's candidate needs no pole check of its own: the gain fit scales a
    # row's last gain-like element, after which only homogeneous elements follow, so
    # every tangent sees the same argument as in the individual's row.
    ranges = default_ranges(TS, N * TS)
    pop, _ = _fit_population(7, p=400)
    places = scale_places(pop.codes, gain_allowed=True)
    rng = np.random.default_rng(1)
    checked = 0
    for k in range(len(pop)):
        for j in range(3):
            pos, through = int(places[0][k, j]), bool(places[1][k, j])
            codes = pop.codes[k, j].tolist()
            if pos < 0 or not with_tangent(np.array([codes]))[0]:
                continue
            els = [(REGISTRY[c], ranges[REGISTRY[c].name].decode(float(p))
                    if REGISTRY[c].param is not None else None)
                   for c, p in zip(codes, pop.ps[k, j], strict=True)]
            scaled = list(els)
            c = float(rng.uniform(-5, 5))
            scaled[pos] = ((element("gain"), c) if through
                           else (els[pos][0], els[pos][1] * c))
            for lo, hi in ((-3.0, 3.0), (-40.0, 25.0)):
                assert (prefix_has_pole(lo, hi, els, TS, 2001)
                        == prefix_has_pole(lo, hi, scaled, TS, 2001))
            checked += 1
    assert checked > 20


def test_prefixes_read_by_a_batch_never_leave_its_new_prefixes_without_room() -> None:
    # A small prefix store (a long log, a small cache_mb) full of prefixes the batch
    # reads (rows' starts, the gain-fit candidates' reads): the new prefixes get what
    # is left, here nothing, and the plan does not fail.
    n = 4
    store = SlotStore(8, 10)
    table = np.zeros((8, 1 + 2 * n))
    table[:, 1:1 + n] = element("lpf").code
    table[:, 1 + n:] = np.random.default_rng(0).random((8, n))
    read = prefix_keys(table, 3)
    for key in read:
        store.commit(key, store.allocate(1, ())[0])
    other = table.copy()
    other[:, 1 + n + 1] += 0.5  # parts from the stored rows at element 1: nothing stored to read
    plan = plan_prefixes(store, other, np.ones(8, dtype=bool), keep=set(read))
    assert not plan.new and not plan.start.any()
    assert all(store.lookup(key) is not None for key in read)
    fewer = set(read[:4])  # four slots to spare: one row's three new prefixes fit
    plan = plan_prefixes(store, other, np.ones(8, dtype=bool), keep=fewer)
    assert len(plan.new) == 3 and all(store.lookup(key) is not None for key in fewer)

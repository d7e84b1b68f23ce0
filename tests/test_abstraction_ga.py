"""Genetic operators of Algorithm 1 (Figs. 6, 7) and the gain fit."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from edm_sym.core.elements import BY_NAME, REGISTRY, default_ranges
from edm_sym.core.matrix import make_matrix
from edm_sym.engines.abstraction.ga import THROUGH, Operators, Population, allowed_codes, rank
from edm_sym.engines.abstraction.gain_fit import gain_fit, row_scales, scale_places, scale_position
from edm_sym.engines.abstraction.schedule import GaSettings

P, M, N_EL = 40, 3, 4


def _pop(seed: int = 0, **ga: object) -> tuple[Operators, Population]:
    ops = Operators(GaSettings(**ga), n_inputs=3)
    return ops, ops.random_population(np.random.default_rng(seed), P, M, N_EL)


def _genes(pop: Population, k: int) -> list[tuple]:
    """Individual k as its chromosome, row by row: the input gene, then (code, p) genes."""
    out = []
    for j in range(pop.shape[1]):
        out.append(("in", int(pop.inputs[k, j])))
        out += [(int(c), float(p)) for c, p in zip(pop.codes[k, j], pop.ps[k, j], strict=True)]
    return out


def test_random_individuals_use_only_allowed_elements_and_valid_genes() -> None:
    ops, pop = _pop(elements=("through", "gain", "sign"), through_rate=0.5)
    assert set(np.unique(pop.codes)) <= {BY_NAME[n].code for n in ("through", "gain", "sign")}
    assert pop.inputs.min() >= 0 and pop.inputs.max() < 3
    assert 0 <= pop.ps.min() and pop.ps.max() <= 1
    assert 0.5 < np.mean(pop.codes == THROUGH) < 0.8  # 0.5 + 0.5 / 3


def test_crossover_exchanges_element_code_and_parameter_together() -> None:
    ops, pop = _pop(crossover_rate=1.0)
    kids = pop.take(np.arange(P))
    ops.crossover(np.random.default_rng(1), kids)
    changed = 0
    for a in range(0, P, 2):
        pa, pb, ka, kb = _genes(pop, a), _genes(pop, a + 1), _genes(kids, a), _genes(kids, a + 1)
        for i in range(len(pa)):
            # Each gene of a child is the same gene (code and p) of one of its parents,
            # and the two children hold the two parents' genes between them.
            assert {ka[i], kb[i]} == {pa[i], pb[i]}
        swapped = [i for i in range(len(pa)) if ka[i] != pa[i]]
        if swapped:
            changed += 1
            # Two cut points: one contiguous section comes from the other parent.
            assert all(ka[i] == pb[i] for i in range(swapped[0], swapped[-1] + 1))
    assert changed > P // 4


def test_row_crossover_moves_whole_rows() -> None:
    ops, pop = _pop(crossover_rate=1.0, row_crossover=1.0)
    kids = pop.take(np.arange(P))
    ops.crossover(np.random.default_rng(2), kids)
    for k in range(P):
        for j in range(M):
            row = (kids.inputs[k, j], tuple(kids.codes[k, j]), tuple(kids.ps[k, j]))
            parents = [(pop.inputs[q, j], tuple(pop.codes[q, j]), tuple(pop.ps[q, j]))
                       for q in (k - k % 2, k - k % 2 + 1)]
            assert row in parents


def test_parameter_shift_moves_p_by_small_steps_only() -> None:
    ops, pop = _pop(shift_rate=0.5, shift_min=1e-4, shift_max=0.01)
    kids = pop.take(np.arange(P))
    ops.shift(np.random.default_rng(3), kids)
    assert np.array_equal(kids.codes, pop.codes) and np.array_equal(kids.inputs, pop.inputs)
    d = np.abs(kids.ps - pop.ps)
    moved = d > 0
    assert 0.35 < moved.mean() < 0.65
    assert d.max() <= 0.01 + 1e-15 and d[moved].min() >= 0  # clipped at the bounds only
    assert 0 <= kids.ps.min() and kids.ps.max() <= 1


def test_mutation_rewrites_code_with_a_fresh_p() -> None:
    ops, pop = _pop(mutation_rate=0.3, input_mutation_rate=0.0, through_rate=0.0,
                    elements=("gain", "lpf", "sign", "tanh"))
    kids = pop.take(np.arange(P))
    ops.mutate(np.random.default_rng(4), kids)
    hit = kids.ps != pop.ps
    assert 0.2 < hit.mean() < 0.4
    assert np.array_equal(kids.codes[~hit], pop.codes[~hit])
    assert set(np.unique(kids.codes)) <= set(allowed_codes(("gain", "lpf", "sign", "tanh")))
    assert np.array_equal(kids.inputs, pop.inputs)


def test_input_mutation_changes_input_codes() -> None:
    ops, pop = _pop(mutation_rate=0.0, input_mutation_rate=1.0)
    kids = pop.take(np.arange(P))
    ops.mutate(np.random.default_rng(5), kids)
    assert np.array_equal(kids.codes, pop.codes)
    assert (kids.inputs != pop.inputs).mean() > 0.5  # new draws from 3 inputs


def test_tournament_selection_prefers_the_top_ranks() -> None:
    ops = Operators(GaSettings(tournament=3), 1)
    picks = ops.select(np.random.default_rng(0), 20_000, 10)
    counts = np.bincount(picks, minlength=10) / 20_000
    # P(best of 3 draws from 10 is rank r) = ((10 - r)^3 - (9 - r)^3) / 1000.
    want = [((10 - r) ** 3 - (9 - r) ** 3) / 1000 for r in range(10)]
    assert np.allclose(counts, want, atol=0.01)


def test_ranking_puts_repeated_genomes_after_distinct_ones() -> None:
    fit = np.array([3.0, 1.0, 1.0, 2.0, 1.0])
    keys = [b"a", b"b", b"b", b"c", b"d"]
    assert rank(fit, keys).tolist() == [1, 4, 3, 0, 2]


def test_offspring_are_deterministic_for_a_generator_state() -> None:
    ops, pop = _pop()
    a = ops.offspring(np.random.default_rng(9), pop, 31)
    b = ops.offspring(np.random.default_rng(9), pop, 31)
    assert len(a) == 31
    assert all(np.array_equal(x, y) for x, y in ((a.inputs, b.inputs), (a.codes, b.codes),
                                                  (a.ps, b.ps)))


def test_population_round_trips_through_a_matrix() -> None:
    _, pop = _pop()
    m = pop.matrix(7, ["u", "v", "w"])
    back = Population.from_matrix(m)
    assert np.array_equal(back.codes[0], pop.codes[7]) and np.array_equal(back.ps[0], pop.ps[7])


# -- gain fit ---------------------------------------------------------------------

@pytest.mark.parametrize("names, want", [
    (["sign", "gain", "lpf", "through"], (1, False)),
    (["gain", "sign", "through", "through"], (3, True)),
    (["sign", "tanh", "invert", "hpf"], None),
    (["power_gain", "through", "sin_amp", "dead_zone"], None),
    (["sin_amp", "through", "shift", "through"], (0, False)),
    (["sign", "dead_zone", "through", "shift"], (2, True)),
])
def test_scale_position_finds_a_gain_with_a_linear_tail(names: list, want: tuple | None) -> None:
    codes = [BY_NAME[n].code for n in names]
    assert scale_position(codes, gain_allowed=True) == want
    if want is not None and want[1]:
        assert scale_position(codes, gain_allowed=False) in (None, (0, False))


def _gain_fit(pop, rows, y, fit, n, ranges):  # noqa: ANN001, ANN202
    # What a worker computes (row_scales) and the main process does with it (gain_fit).
    places = scale_places(pop.codes, gain_allowed=True)
    a = np.array(rows)
    scales = [row_scales(a @ a.T, a @ y, places[0][0] >= 0, float(fit[0]), n)]
    return gain_fit(pop, scales, places, ranges)


def test_scale_places_is_scale_position_of_every_row() -> None:
    rng = np.random.default_rng(3)
    codes = rng.choice(sorted(REGISTRY), size=(40, 5, 4))
    codes[rng.random(codes.shape) < 0.4] = BY_NAME["through"].code
    for allowed in (True, False):
        pos, through = scale_places(codes, gain_allowed=allowed)
        for k in range(40):
            for j in range(5):
                want = scale_position(codes[k, j], gain_allowed=allowed)
                got = None if pos[k, j] < 0 else (int(pos[k, j]), bool(through[k, j]))
                assert got == want, (codes[k, j], allowed)


def test_gain_fit_gives_the_least_squares_scale() -> None:
    ts, n = 1e-3, 3000
    omega = 30 * np.sin(np.linspace(0, 12, n))
    y = 0.9 * np.sign(omega) + 0.02 * omega
    ranges = default_ranges(ts, n * ts)
    g, pg = ranges["gain"], ranges["power_gain"]
    m = make_matrix(["omega"], [("omega", [("sign", 0), ("gain", g.encode(3.0))]),
                                ("omega", [("power_gain", pg.encode(0.5)), ("through", 0)])])
    pop = Population.from_matrix(m)
    rows = [np.sign(omega) * 3.0, 0.5 * omega]
    keys = [b"r0", b"r1"]
    resid = y - rows[0] - rows[1]
    fit = np.array([np.sqrt(np.mean(resid**2))])

    del keys
    idx, cand = _gain_fit(pop, rows, y, fit, n, ranges)
    assert idx.tolist() == [0]
    assert g.decode(cand.ps[0, 0, 1]) == pytest.approx(0.9, rel=1e-9)
    assert pg.decode(cand.ps[0, 1, 0]) == pytest.approx(0.02, rel=1e-9)
    assert np.array_equal(cand.codes, pop.codes)


def test_gain_fit_turns_a_through_into_a_gain_and_skips_optimal_rows() -> None:
    n = 500
    x = np.linspace(-1, 1, n)
    ranges = default_ranges(1e-3, 0.5)
    m = make_matrix(["x"], [("x", [("sign", 0), ("through", 0)])])
    pop = Population.from_matrix(m)

    y = 2.5 * np.sign(x)
    fit = np.array([np.sqrt(np.mean((y - np.sign(x)) ** 2))])
    idx, cand = _gain_fit(pop, [np.sign(x)], y, fit, n, ranges)
    assert REGISTRY[int(cand.codes[0, 0, 1])].name == "gain"
    assert ranges["gain"].decode(cand.ps[0, 0, 1]) == pytest.approx(2.5)
    y = np.sign(x) + 1e-3 * np.cos(40 * x)  # already the best scale: no candidate
    fit = np.array([np.sqrt(np.mean((y - np.sign(x)) ** 2))])
    idx, cand = _gain_fit(pop, [np.sign(x)], y, fit, n, ranges)
    assert len(idx) == 0 and len(cand) == 0


def test_the_local_search_runs_every_local_search_generations_without_improvement() -> None:
    from edm_sym.engines.abstraction.ga import Progress

    ga = GaSettings(local_search=3, patience=0, generations=50, continue_mode="no")
    prog, ran = Progress.start(1.0), []
    for gen in range(1, 11):
        prog = prog.after(ga, 0.5 if gen == 1 else prog.ref_best)  # improves once, then stalls
        ran.append(prog.stagnant(ga))
    assert [g for g, r in zip(range(1, 11), ran, strict=True) if r] == [4, 7, 10]
    assert not prog.stagnant(GaSettings(local_search=0))
    assert replace(prog, since_improvement=1, done=True).stagnant(ga)  # a step ending stalled

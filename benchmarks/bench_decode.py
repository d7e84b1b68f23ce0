"""Decoding time: a 4x5 matrix like the paper's Fig. 21 and a deliberately nasty 8x6 one.

Prints the time of :func:`edm_sym.engines.symbolic.decode` (expressions, bounded
simplification, classification and python-control systems) and of its parts,
against their budgets (2 s for 4x5, 5 s for the nasty matrix). No
wall-clock assertions: these are figures to read, not tests.

    python benchmarks/bench_decode.py
"""

from __future__ import annotations

import time

from sympy.core.cache import clear_cache

from edm_sym.core.elements import default_ranges
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.engines.symbolic import build_model, decode
from edm_sym.engines.symbolic.classify import classify_expression
from edm_sym.engines.symbolic.decoding import parameter_signs
from edm_sym.engines.symbolic.lti import row_system, stage_parts
from edm_sym.engines.symbolic.rowexpr import row_expression
from edm_sym.engines.symbolic.simplify import simplify_expression

TS, T_SUM = 1e-3, 20.0
NASTY_CHAIN = ["sin_phase", "tan_amp", "asin", "power", "log", "tan_phase", "acos", "sin_amp"]


def paper_like() -> Compensator:
    """4 elements x 5 rows in the spirit of Fig. 21 / Table II."""
    enc = {k: v.encode for k, v in default_ranges(TS, T_SUM).items()}
    m = make_matrix(
        ["theta_w", "theta_uw", "omega", "alpha"],
        [
            ("omega", [("sign", 0), ("gain", enc["gain"](0.93)), ("through", 0), ("through", 0)]),
            ("omega", [("power_gain", enc["power_gain"](0.2955)), ("through", 0),
                       ("through", 0), ("through", 0)]),
            ("omega", [("derivative", enc["derivative"](7.063e-3)), ("lpf", enc["lpf"](1211.0)),
                       ("gain", enc["gain"](1.001)), ("through", 0)]),
            ("theta_w", [("gain", enc["gain"](4.0)), ("sin_phase", enc["sin_phase"](0.3)),
                         ("gain", enc["gain"](0.0306)), ("through", 0)]),
            ("alpha", [("lpf", enc["lpf"](451.6)), ("gain", enc["gain"](0.0998)),
                       ("tanh", enc["tanh"](2.059)), ("gain", enc["gain"](9.296))]),
        ],
    )
    return Compensator(m, TS, {}, T_SUM)


def nasty() -> Compensator:
    """8 elements x 6 rows of nested sin/tan/asin/power/log/acos (rotated per row)."""
    rows = []
    for j in range(6):
        chain = NASTY_CHAIN[j:] + NASTY_CHAIN[:j]
        rows.append(("omega" if j % 2 else "theta_w",
                     [(name, (0.13 + 0.11 * i + 0.07 * j) % 1.0) for i, name in enumerate(chain)]))
    return Compensator(make_matrix(["theta_w", "omega"], rows), TS, {}, T_SUM)


def _best(f, repeat: int = 3) -> float:
    """Best of ``repeat`` runs, each with sympy's cache cleared first (a cold decode)."""
    best = float("inf")
    for _ in range(repeat):
        clear_cache()
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def parts(comp: Compensator) -> dict[str, float]:
    """Time of each stage of decoding, summed over the rows."""
    model = build_model(comp)
    signs = parameter_signs(model)
    raw = [(row_expression(r, ts=TS), row_expression(r, ts=TS, numeric=True)) for r in model.rows]
    simp = [simplify_expression(n, model.input_symbols, numeric=True) for _, n in raw]
    return {
        "build_model": _best(lambda: build_model(comp)),
        "row expressions": _best(lambda: [(row_expression(r, ts=TS),
                                           row_expression(r, ts=TS, numeric=True))
                                          for r in model.rows]),
        "simplification": _best(lambda: [
            (simplify_expression(e, model.input_symbols, numeric=False, signs=signs),
             simplify_expression(n, model.input_symbols, numeric=True)) for e, n in raw]),
        "classification": _best(lambda: [classify_expression(e, r.input_symbol, "velocity")
                                         for e, r in zip(simp, model.rows, strict=True)]),
        "python-control": _best(lambda: [(stage_parts(r, TS), row_system(r, TS))
                                         for r in model.rows]),
    }


def main() -> None:
    """Print the decode times and their ratio to the budget."""
    for name, comp, budget in (("4x5 paper-like", paper_like(), 2.0),
                               ("8x6 nasty", nasty(), 5.0)):
        t = _best(lambda c=comp: decode(c))
        print(f"{name:16s} decode {t * 1e3:8.1f} ms   budget {budget:.0f} s   "
              f"ratio {t / budget:.3f}")
        for part, tp in parts(comp).items():
            print(f"    {part:18s} {tp * 1e3:8.1f} ms")


if __name__ == "__main__":
    main()

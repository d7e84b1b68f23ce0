"""The C and Python printers: literals, math functions, guards, statements."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from edm_sym.core.elements import StaticElement, all_elements
from edm_sym.core.elements.ops import SCALAR
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.engines.symbolic.functions import DeadZone, GAcos, GAsin, GTan, Sat, SymLog, SymPow
from edm_sym.engines.symbolic.model import X, build_model
from edm_sym.outputs.printing import EdmC99Printer, EdmPythonPrinter

STATIC = [e for e in all_elements() if issubclass(e, StaticElement)]

#: The math functions C99 has in double and in float (``sin`` / ``sinf``).
C_MATH = ("sin", "cos", "tan", "asin", "acos", "atan", "tanh", "log1p", "log", "exp", "pow",
          "fabs", "fmax", "fmin", "sqrt")


def static_exprs(p: float = 0.37) -> list[tuple[str, sp.Expr]]:
    """Every static element's numeric expression (one row per element)."""
    rows = [("x", [(e.name, p)]) for e in STATIC]
    model = build_model(Compensator(make_matrix(["x"], rows), 1e-3, {}, 20.0))
    return [(r.stages[0].element.name, r.stages[0].numeric_expr()) for r in model.rows]


# -- literals -------------------------------------------------------------------
@pytest.mark.parametrize("value", [0.1, 0.95, -1e-5, 1.0, 3.0, 123456.789, 2.0 ** -30, -0.0])
def test_double_literal_reads_back_exactly(value: float) -> None:
    text = EdmC99Printer().literal(value)
    assert float(text) == value
    assert "." in text or "e" in text
    assert len(re.sub(r"[-.]|e.*", "", text).lstrip("0")) <= 17


@pytest.mark.parametrize("value", [0.1, 0.95, -1e-5, 1.0, 123456.789])
def test_float_literal_is_the_nearest_float_with_suffix(value: float) -> None:
    text = EdmC99Printer({"real": "float"}).literal(value)
    assert text.endswith("f")
    assert np.float32(float(text[:-1])) == np.float32(value)
    assert len(re.sub(r"[-.]|e.*|f", "", text).lstrip("0")) <= 9


def test_literals_refuse_non_finite() -> None:
    with pytest.raises(ValueError, match="finite"):
        EdmC99Printer().literal(math.inf)
    with pytest.raises(ValueError, match="finite"):
        EdmPythonPrinter().literal(math.nan)


def test_integers_print_as_reals() -> None:
    assert EdmC99Printer({"real": "float"}).doprint(2 * sp.atan(X)) == "2.0f*atanf(x)"
    assert EdmC99Printer().doprint(sp.Rational(1, 4) * X) in ("0.25*x", "(0.25)*x")


def test_options_are_validated() -> None:
    with pytest.raises(ValueError, match=r"^real: expected one of float, double, found 'half'$"):
        EdmC99Printer({"real": "half"})
    with pytest.raises(ValueError, match=r"^prefix: expected a C identifier, found '9x'$"):
        EdmC99Printer({"prefix": "9x"})


# -- float: no double anywhere ------------------------------------------------------
@pytest.mark.parametrize(("name", "expr"), static_exprs(), ids=[n for n, _ in static_exprs()])
def test_float_printing_never_names_a_double_function(name: str, expr: sp.Expr) -> None:
    pr = EdmC99Printer({"real": "float"})
    code = pr.doprint(expr) + "\n" + "\n".join(pr.helper_definitions())
    for fn in C_MATH:
        assert not re.search(rf"\b{fn}\(", code), f"{name}: double {fn}() in {code!r}"
    for lit in re.findall(r"(?<![\w.])\d+\.\d*(?:e[-+]?\d+)?f?", code):
        assert lit.endswith("f"), f"{name}: double literal {lit} in {code!r}"


def test_double_printing_uses_double_functions() -> None:
    pr = EdmC99Printer()
    assert pr.doprint(sp.sin(X + sp.Float(0.5))) == "sin(x + 0.5)"
    assert pr.doprint(sp.Max(X, sp.Float(-0.25))) == "fmax(-0.25, x)"
    assert EdmC99Printer({"real": "float"}).doprint(sp.tanh(X)) == "tanhf(x)"


# -- the project's functions ---------------------------------------------------------
@pytest.mark.parametrize(("expr", "helper"), [
    (Sat(X, -1, 1), "sat"), (DeadZone(X, 0.5), "dead_zone"), (SymLog(X, 0.5), "sym_log"),
    (SymPow(X, 1.5), "sym_pow"), (GTan(X), "tan"), (GAsin(X), "asin"), (GAcos(X), "acos"),
    (sp.sign(X), "sign"),
])
def test_project_functions_print_as_helpers(expr: sp.Expr, helper: str) -> None:
    c = EdmC99Printer({"prefix": "my"})
    assert c.doprint(expr).startswith(f"my_{helper}(")
    assert helper in c.helpers_used
    defs = c.helper_definitions()
    assert any(d.startswith(f"static inline my_real_t my_{helper}(") for d in defs)
    py = EdmPythonPrinter()
    assert py.doprint(expr).startswith(f"_{helper}(")
    assert any(d.startswith(f"def _{helper}(") for d in py.helper_definitions())


def test_helpers_bring_their_callees_first() -> None:
    defs = EdmC99Printer().helper_definitions(["sym_log", "asin"])
    names = [re.search(r"edm_comp_(\w+)\(", d).group(1) for d in defs]
    assert names == ["sign", "sat", "sym_log", "asin"]
    with pytest.raises(ValueError, match="unknown"):
        EdmC99Printer().helper_definitions(["nope"])


def _python_helpers() -> dict:
    pr = EdmPythonPrinter()
    defs = pr.helper_definitions(["sign", "sat", "dead_zone", "sym_log", "sym_pow", "tan",
                                  "asin", "acos"])
    namespace: dict = {"math": math}
    exec("\n".join(pr.helper_constants(defs) + defs), namespace)  # noqa: S102
    return namespace


PY = _python_helpers()
finite = st.floats(-1e8, 1e8, allow_nan=False)
positive = st.floats(1e-4, 1e2)


@settings(max_examples=300, deadline=None)
@given(x=finite, a=positive, e=st.floats(0.1, 3.0))
def test_python_helpers_are_scalar_ops(x: float, a: float, e: float) -> None:
    assert PY["_sign"](x) == SCALAR.sign(x)
    assert PY["_sat"](x, -a, a) == SCALAR.sat(x, -a, a)
    assert PY["_dead_zone"](x, a) == SCALAR.dead_zone(x, a)
    assert PY["_sym_log"](x, a) == SCALAR.sym_log(x, a)
    assert PY["_sym_pow"](x, e) == SCALAR.sym_pow(x, e)
    assert PY["_tan"](x) == SCALAR.tan(x)
    assert PY["_asin"](x / 1e7) == SCALAR.asin(x / 1e7)
    assert PY["_acos"](x / 1e7) == SCALAR.acos(x / 1e7)


@pytest.mark.parametrize(("name", "expr"), static_exprs(0.81), ids=[n for n, _ in static_exprs()])
def test_printed_python_evaluates_like_the_element(name: str, expr: sp.Expr) -> None:
    pr = EdmPythonPrinter()
    code = pr.doprint(expr)
    f = eval(f"lambda x: {code}", dict(PY))  # noqa: S307
    el = next(e for e in STATIC if e.name == name)
    model = build_model(Compensator(make_matrix(["x"], [("x", [(name, 0.81)])]), 1e-3, {}, 20.0))
    a = model.rows[0].stages[0].value
    for x in np.linspace(-3.0, 3.0, 61):
        assert f(float(x)) == pytest.approx(el.f(SCALAR, float(x), a), rel=1e-15, abs=1e-15)


def test_python_floats_are_shortest_repr() -> None:
    assert EdmPythonPrinter().doprint(sp.Float(0.95, 17) * X) == "0.95*x"


# -- statements ------------------------------------------------------------------
def test_linear_lines_follow_lfilter_order() -> None:
    lines = EdmC99Printer().linear_lines((0.5, 0.25, -0.125), (1.0, -0.5, 0.25), "s->z")
    assert lines[1].strip() == "const edm_comp_real_t y = 0.5 * x + s->z[0];"
    assert lines[2].strip() == "s->z[0] = s->z[1] + x * 0.25 - y * (-0.5);"
    assert lines[3].strip() == "s->z[1] = x * (-0.125) - y * 0.25;"
    with pytest.raises(ValueError):
        EdmC99Printer().linear_lines((1.0,), (1.0,), "z")


def test_python_linear_lines_run_like_lfilter() -> None:
    from scipy import signal

    b, a = (0.2, -0.1, 0.05), (1.0, -0.6, 0.08)
    pr = EdmPythonPrinter()
    body = "\n".join("    " + ln for ln in pr.linear_lines(b, a, "state"))
    ns: dict = {}
    exec(f"def step(x, state):\n{body}\n    return x", ns)  # noqa: S102
    x = np.random.default_rng(3).standard_normal(200)
    state = [0.0, 0.0]
    got = [ns["step"](float(v), state) for v in x]
    assert np.array_equal(got, signal.lfilter(b, a, x))


def test_delay_and_relay_lines() -> None:
    c = EdmC99Printer()
    assert "s->p = (s->p + 1u < 5u) ? s->p + 1u : 0u;" in [
        ln.strip() for ln in c.delay_lines(5, "s->b", "s->p")]
    assert len(c.delay_lines(1, "s->b", None)) == 5
    with pytest.raises(ValueError):
        c.delay_lines(0, "s->b", None)
    assert c.relay_lines(0.5, "s->o[0]")[0] == "if (x >= 0.5) {"

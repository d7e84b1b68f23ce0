"""Nonlinear function elements (paper, Fig. 5).

Every function here is total: the guards in :mod:`edm_sym.core.elements.ops` keep
the output finite for every finite input.
"""

from __future__ import annotations

import math
from typing import Any

from edm_sym.core.elements.base import Param, ParamRange, RelayElement, StaticElement
from edm_sym.core.elements.ops import (
    LOG_QUOTIENT_LIMIT,
    POW_EXPONENT_LIMIT,
    POW_INPUT_LIMIT,
    TAN_LIMIT,
)

LEVEL = Param("level", "unit of the input",
              lambda ts, t_sum: ParamRange(1e-4, 1e2, "log"), "1e-4 .. 100 (log)")
SLOPE = Param("slope at the origin", "1 / unit of the input",
              lambda ts, t_sum: ParamRange(1e-2, 1e4, "log"), "1e-2 .. 1e4 (log)")
AMPLITUDE = Param("amplitude (either sign)", "unit of the output",
                  lambda ts, t_sum: ParamRange(-5.0, 5.0, "linear"), "-5 .. 5 (linear)")


class Saturation(StaticElement):
    name = "saturation"
    code = 15
    title = "Saturation"
    category = "nonlinear"
    formula = "y = min(max(x, -a), a)"
    param = LEVEL

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.sat(x, -a, a)


class OneWay(StaticElement):
    """Passes the input above the level ``a`` and holds ``a`` below it."""

    name = "one_way"
    code = 16
    title = "One way"
    category = "nonlinear"
    formula = "y = max(x, a)   (a = 0: half-wave rectifier)"
    param = Param("lower limit", "unit of the input",
                  lambda ts, t_sum: ParamRange(-5.0, 5.0, "linear"), "-5 .. 5 (linear)")

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.lower_limit(x, a)


class DeadZone(StaticElement):
    name = "dead_zone"
    code = 17
    title = "Dead zone"
    category = "nonlinear"
    formula = "y = x - a (x > a);  0 (|x| <= a);  x + a (x < -a)"
    param = LEVEL

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.dead_zone(x, a)


class Hysteresis(RelayElement):
    name = "hysteresis"
    code = 18
    unit_out = "one"
    title = "Hysteresis"
    category = "nonlinear"
    formula = "relay: y = +1 once x >= a, -1 once x <= -a, else held (starts at 0)"
    param = Param("half width of the hysteresis band", "unit of the input",
                  LEVEL.default, LEVEL.rule)


class Sign(StaticElement):
    name = "sign"
    code = 19
    unit_out = "one"
    title = "Sign function"
    category = "nonlinear"
    formula = "y = sgn(x)   (sgn(0) = 0)"
    switches = True

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.sign(x)


class Logarithm(StaticElement):
    name = "log"
    cost = 3.2
    code = 20
    unit_out = "one"
    title = "Logarithmic function"
    category = "nonlinear"
    formula = "y = sgn(x) ln(1 + |x| / a)"
    guard = ("odd extension: defined for every x (a plain ln x is undefined for x <= 0); "
             "behaves as x / a near 0 and as ln|x| for |x| >> a; |x| / a limited to "
             f"{LOG_QUOTIENT_LIMIT:g} first, so no quotient overflows in float")
    param = Param("scale", "unit of the input", LEVEL.default, LEVEL.rule)

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.sym_log(x, a)


class Power(StaticElement):
    name = "power"
    cost = 4.7
    code = 21
    unit_out = "power"
    title = "Power"
    category = "nonlinear"
    formula = "y = sgn(x) |x|^a"
    guard = (f"odd extension for x < 0 (fractional powers of negatives); |x| limited to "
             f"{POW_INPUT_LIMIT:g} first and any range of the exponent within 0 .. "
             f"{POW_EXPONENT_LIMIT:g}, so no power overflows")
    param = Param("exponent", "1", lambda ts, t_sum: ParamRange(0.1, 3.0, "linear"),
                  "0.1 .. 3 (linear)", limits=(0.0, POW_EXPONENT_LIMIT))

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.sym_pow(x, a)


class SinePhase(StaticElement):
    name = "sin_phase"
    cost = 0.6
    code = 22
    unit_in = "rad"
    unit_out = "one"
    title = "Sine wave (phase)"
    category = "nonlinear"
    formula = "y = sin(x + a)"
    param = Param("phase", "rad", lambda ts, t_sum: ParamRange(-3.141592653589793,
                  3.141592653589793, "linear"), "-pi .. pi (linear)",
                  period=2 * 3.141592653589793)

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.sin(x + a)

    @staticmethod
    def from_sin_cos(s: Any, c: Any, a: float) -> Any:
        """``sin(x + a) = sin x cos a + cos x sin a``, equal to rounding."""
        return s * math.cos(a) + c * math.sin(a)


class SineAmplitude(StaticElement):
    name = "sin_amp"
    cost = 0.25
    code = 23
    unit_in = "rad"
    unit_out = "scaled"
    title = "Sine wave (amp.)"
    category = "nonlinear"
    scales_output = True
    multiplies_output = True
    formula = "y = a sin(x)"
    param = AMPLITUDE

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return a * m.sin(x)

    @staticmethod
    def from_sin_cos(s: Any, c: Any, a: float) -> Any:
        """``a sin(x)`` from ``sin(x)``, bit for bit."""
        return a * s


TAN_GUARD = (f"tan limited to +-{TAN_LIMIT:g}, so its poles give a finite output; where it "
             f"reaches the limit the sign of sin decides, so a pole gives one value in float and "
             f"double alike")


class TangentPhase(StaticElement):
    name = "tan_phase"
    cost = 5.6
    code = 24
    unit_in = "rad"
    unit_out = "one"
    title = "Tangent (phase)"
    category = "nonlinear"
    formula = "y = tan(x + a)"
    guard = TAN_GUARD
    tangent_argument = staticmethod(lambda x, a: x + a)
    param = Param("phase", "rad", lambda ts, t_sum: ParamRange(-1.5707963267948966,
                  1.5707963267948966, "linear"), "-pi/2 .. pi/2 (linear)",
                  period=3.141592653589793)

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.tan(x + a)


class TangentAmplitude(StaticElement):
    name = "tan_amp"
    cost = 5.4
    code = 25
    unit_in = "rad"
    unit_out = "scaled"
    title = "Tangent (amp.)"
    category = "nonlinear"
    scales_output = True
    multiplies_output = True
    formula = "y = a tan(x)"
    guard = TAN_GUARD
    tangent_argument = staticmethod(lambda x, a: x)
    param = AMPLITUDE

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return a * m.tan(x)


class ArcSine(StaticElement):
    name = "asin"
    cost = 1.9
    code = 26
    unit_in = "1"
    unit_out = "one"
    title = "Arc sine"
    category = "nonlinear"
    formula = "y = asin(x)"
    guard = "input limited to [-1, 1] first"

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.asin(x)


class ArcCosine(StaticElement):
    name = "acos"
    cost = 2.4
    code = 27
    unit_in = "1"
    unit_out = "one"
    title = "Arc cosine"
    category = "nonlinear"
    formula = "y = acos(x)"
    guard = "input limited to [-1, 1] first"

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.acos(x)


class ArcTangent(StaticElement):
    name = "atan"
    cost = 2.9
    code = 28
    unit_out = "one"
    title = "Arc tangent"
    category = "nonlinear"
    formula = "y = atan(a x)"
    param = SLOPE

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.atan(a * x)


class HyperbolicTangent(StaticElement):
    name = "tanh"
    cost = 1.5
    code = 29
    unit_out = "one"
    title = "Hyperbolic tangent"
    category = "nonlinear"
    formula = "y = tanh(a x)"
    param = SLOPE

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return m.tanh(a * x)

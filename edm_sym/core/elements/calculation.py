"""Calculation elements (paper, Fig. 4): gains, derivative, integral, filters, delays.

Filters with one corner frequency ``a`` [rad/s] take their default range from
eq. 6 (2 pi / T_sum .. pi / Ts, logarithmic); the phase-lead and phase-lag
compensators keep a fixed 10:1 ratio between their zero and pole, so their
upper corner stays below the Nyquist frequency (pi / (10 Ts)).
"""

from __future__ import annotations

from typing import Any

from edm_sym.core.elements.base import (
    DelayElement,
    LinearElement,
    Param,
    ParamRange,
    StaticElement,
    corner_range,
)

#: Zero-to-pole ratio of the phase-lead and phase-lag compensators.
LEAD_LAG_RATIO = 10

CORNER = Param("corner frequency", "rad/s", corner_range, "2 pi/T_sum .. pi/Ts (log, eq. 6)")
CORNER_LEAD_LAG = Param(
    "lower corner frequency", "rad/s",
    lambda ts, t_sum: corner_range(ts, t_sum, top_divisor=LEAD_LAG_RATIO),
    "2 pi/T_sum .. pi/(10 Ts) (log, eq. 6 with room for the 10:1 ratio)",
)


class Gain(StaticElement):
    name = "gain"
    code = 3
    unit_out = "scaled"
    title = "Gain"
    category = "calculation"
    homogeneous = True
    scales_output = True
    multiplies_output = True
    formula = "y = a x"
    param = Param("gain (either sign)", "output unit per input unit",
                  lambda ts, t_sum: ParamRange(-10.0, 10.0, "linear"), "-10 .. 10 (linear)")

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return a * x


class PowerGain(StaticElement):
    """A positive gain searched over decades: the magnitude of a gain, log-scaled."""

    name = "power_gain"
    code = 4
    unit_out = "scaled"
    title = "Power gain"
    category = "calculation"
    homogeneous = True
    scales_output = True
    multiplies_output = True
    formula = "y = a x,  a = 10^e (searched over decades)"
    param = Param("gain magnitude", "output unit per input unit",
                  lambda ts, t_sum: ParamRange(1e-4, 1e4, "log"), "1e-4 .. 1e4 (log, eq. 5)")

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        return a * x


class Derivative(LinearElement):
    name = "derivative"
    code = 5
    title = "Derivation"
    category = "calculation"
    formula = "y = a s x"
    multiplies_output = True
    method = "backward_diff"
    param = Param("derivative gain", "s",
                  lambda ts, t_sum: ParamRange(1e-6, 1e1, "log"), "1e-6 .. 10 (log)")

    @staticmethod
    def tf(a: Any) -> tuple[list[Any], list[Any]]:
        return [a, 0], [1]


class Integral(LinearElement):
    name = "integral"
    code = 6
    title = "Integral"
    category = "calculation"
    formula = "y = (a / s) x"
    multiplies_output = True
    param = Param("integral gain", "1/s",
                  lambda ts, t_sum: ParamRange(1e-3, 1e3, "log"), "1e-3 .. 1e3 (log)")

    @staticmethod
    def tf(a: Any) -> tuple[list[Any], list[Any]]:
        return [a], [1, 0]


class LowPass(LinearElement):
    name = "lpf"
    code = 7
    title = "Low-pass filter"
    category = "calculation"
    formula = "y = a / (s + a) x"
    param = CORNER

    @staticmethod
    def tf(a: Any) -> tuple[list[Any], list[Any]]:
        return [a], [1, a]


class HighPass(LinearElement):
    name = "hpf"
    code = 8
    title = "High-pass filter"
    category = "calculation"
    formula = "y = s / (s + a) x"
    param = CORNER

    @staticmethod
    def tf(a: Any) -> tuple[list[Any], list[Any]]:
        return [1, 0], [1, a]


class PhaseLead(LinearElement):
    name = "lead"
    code = 9
    title = "Phase-lead compensator"
    category = "calculation"
    formula = "y = (1 + s/a) / (1 + s/(10 a)) x   (unit DC gain, max lead 55 deg at 3.16 a)"
    param = CORNER_LEAD_LAG

    @staticmethod
    def tf(a: Any) -> tuple[list[Any], list[Any]]:
        return [1 / a, 1], [1 / (LEAD_LAG_RATIO * a), 1]


class PhaseLag(LinearElement):
    name = "lag"
    code = 10
    title = "Phase-lag compensator"
    category = "calculation"
    formula = "y = (1 + s/(10 a)) / (1 + s/a) x   (unit DC gain, 0.1 at high frequency)"
    param = CORNER_LEAD_LAG

    @staticmethod
    def tf(a: Any) -> tuple[list[Any], list[Any]]:
        return [1 / (LEAD_LAG_RATIO * a), 1], [1 / a, 1]


class PhaseShift(LinearElement):
    """First-order all-pass: shifts phase (0 to -180 deg) without changing gain."""

    name = "phase"
    code = 11
    title = "Phase compensator"
    category = "calculation"
    formula = "y = (a - s) / (a + s) x   (all-pass, -90 deg at a)"
    param = CORNER

    @staticmethod
    def tf(a: Any) -> tuple[list[Any], list[Any]]:
        return [-1, a], [1, a]


class Notch(LinearElement):
    name = "notch"
    code = 12
    title = "Notch filter"
    category = "calculation"
    formula = "y = (s^2 + a^2) / (s^2 + a s + a^2) x   (damping 0.5)"
    param = CORNER

    @staticmethod
    def tf(a: Any) -> tuple[list[Any], list[Any]]:
        return [1, 0, a * a], [1, a, a * a]


def _round_half_up(v: float) -> int:
    return int(v + 0.5)


class DeadTime(DelayElement):
    name = "dead_time"
    code = 13
    title = "Dead time"
    category = "calculation"
    formula = "y = exp(-a s) x   (realised as z^-N, N = max(1, round(a / Ts)), halves up)"
    param = Param("dead time", "s", lambda ts, t_sum: ParamRange(ts, t_sum, "log"),
                  "Ts .. T_sum (log, eq. 7)")

    @staticmethod
    def samples(a: Any, ts: float) -> int:
        return max(1, _round_half_up(a / ts))


class Shift(DelayElement):
    """Backward shift operator q^-k: a delay of a few whole samples."""

    name = "shift"
    code = 14
    title = "Shift operator"
    category = "calculation"
    formula = "y = z^-k x,  k = max(1, round(a)) samples, halves up"
    param = Param("shift in samples", "samples",
                  lambda ts, t_sum: ParamRange(1.0, 10.0, "linear"), "1 .. 10 (linear)")

    @staticmethod
    def samples(a: Any, ts: float) -> int:
        return max(1, _round_half_up(a))

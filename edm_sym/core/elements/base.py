"""Element base classes: one definition of what each element computes.

An element is a single-input single-output block of the element matrix
(paper, Figs. 3-5). Each concrete element is a class that declares, in one
place, its name and integer code, the meaning, range and scaling of its
parameter ``a``, its continuous-time form, its discrete-time realisation, its
state size and its domain guards; defining the class registers it.

There are four kinds, by how they compute; each is realised in discrete time
by one type of :mod:`edm_sym.core.elements.realisation` (``Element.realise``):

* :class:`StaticElement` -- memoryless ``y = f(x, a)``; ``f`` is written once
  against a small math interface (:mod:`edm_sym.core.elements.ops`) so the same
  definition runs on numpy arrays, on Python floats and on sympy symbols.
* :class:`LinearElement` -- a rational transfer function ``G(s; a)`` whose
  polynomial coefficients are written once (numbers or sympy symbols alike)
  and discretised in one place, :func:`edm_sym.core.discrete.discretize`.
* :class:`DelayElement` -- a pure delay of a whole number of samples.
* :class:`RelayElement` -- the relay with hysteresis (one bit of state).

This module never imports sympy: the symbolic layer passes sympy objects in.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from edm_sym.core.discrete import discretize
from edm_sym.core.elements.realisation import DelayLine, LinearFilter, Realisation, Relay, StaticMap

Scaling = Literal["linear", "log"]


#: The largest magnitude of a parameter range's bound, and 1 / it the smallest low
#: bound of a log range (docs/elements.md): the default ranges of eqs. 6-7 stay
#: within 1e-6 .. 1e6 for any sensible Ts and T_sum; far beyond, products of
#: parameters overflow double precision and the generated C would hold INFINITY.
RANGE_LIMIT = 1e12


@dataclass(frozen=True)
class ParamRange:
    """The range of an element parameter and how ``p`` in [0, 1] maps onto it.

    Parameters
    ----------
    low, high : float
        The parameter values at ``p = 0`` and ``p = 1``.
    scaling : {"linear", "log"}
        ``"linear"`` is the paper's eq. 4, ``a = (high - low) p + low``;
        ``"log"`` is eq. 5, ``a = 10 ** ((log10 high - log10 low) p + log10 low)``
        and needs ``0 < low``.
    """

    low: float
    high: float
    scaling: Scaling = "linear"

    def __post_init__(self) -> None:
        if self.scaling not in ("linear", "log"):
            raise ValueError(f"scaling: expected 'linear' or 'log', found {self.scaling!r}")
        if not (math.isfinite(self.low) and math.isfinite(self.high)):
            raise ValueError(f"range: expected finite bounds, found [{self.low}, {self.high}]")
        if max(abs(self.low), abs(self.high)) > RANGE_LIMIT:
            raise ValueError(f"range: expected bounds within +-{RANGE_LIMIT:g} (a parameter beyond makes "
                             f"the compensator overflow), found [{self.low}, {self.high}]")
        if not self.low < self.high:
            raise ValueError(f"range: expected low < high, found [{self.low}, {self.high}]")
        if self.scaling == "log" and self.low < 1 / RANGE_LIMIT:
            raise ValueError(f"range: a log scaling needs low >= {1 / RANGE_LIMIT:g}, found low = {self.low}")

    def decode(self, p: float) -> float:
        """Map a normalised parameter ``p`` in [0, 1] to the parameter value ``a``."""
        if self.scaling == "log":
            lo, hi = math.log10(self.low), math.log10(self.high)
            return 10.0 ** ((hi - lo) * p + lo)
        return (self.high - self.low) * p + self.low

    def encode(self, a: float) -> float:
        """Map a parameter value ``a`` back to ``p`` (clipped to [0, 1])."""
        if self.scaling == "log":
            lo, hi = math.log10(self.low), math.log10(self.high)
            p = (math.log10(a) - lo) / (hi - lo) if a > 0 else 0.0
        else:
            p = (a - self.low) / (self.high - self.low)
        return min(1.0, max(0.0, p))

    def to_json(self) -> dict[str, Any]:
        """The JSON form stored in result.json."""
        return {"low": self.low, "high": self.high, "scaling": self.scaling}


@dataclass(frozen=True)
class Param:
    """What an element's parameter ``a`` means and its default range.

    Parameters
    ----------
    meaning : str
        One line: what ``a`` is (``"corner frequency"``, ``"dead time"`` ...).
    unit : str
        Its unit, in SI terms, relative to the element's input where needed.
    default : callable
        ``default(ts, t_sum) -> ParamRange``: the default range for a log of
        sample time ``ts`` and length ``t_sum`` seconds (paper, eqs. 6-7).
    rule : str
        The default range as a readable rule, for the documentation.
    period : float or None
        The period of a periodic parameter (a phase), else None: a range at
        least this wide reaches every value, so its bounds limit nothing.
    limits : (float, float) or None
        Bounds no range of ``a`` may pass, a custom one included (a config's
        ``[ranges]``, a result's ``parameter_ranges``): beyond them the element
        is not finite for every finite input. None: only :data:`RANGE_LIMIT`.
    """

    meaning: str
    unit: str
    default: Callable[[float, float], ParamRange]
    rule: str
    period: float | None = None
    limits: tuple[float, float] | None = None

    def check(self, rng: ParamRange) -> None:
        """Refuse a range that passes :attr:`limits` (``ValueError`` naming ``range``)."""
        if self.limits is None:
            return
        lo, hi = self.limits
        if rng.low < lo or rng.high > hi:
            raise ValueError(f"range: expected the {self.meaning} within {lo:g} .. {hi:g} "
                             f"(beyond, the element is not finite for every input), found "
                             f"[{rng.low:g}, {rng.high:g}]")


def corner_range(ts: float, t_sum: float, *, top_divisor: float = 1.0) -> ParamRange:
    """Default range of a corner frequency: eq. 6, 2 pi / T_sum .. pi / Ts (log)."""
    low = 2.0 * math.pi / t_sum
    high = math.pi / (ts * top_divisor)
    return ParamRange(min(low, high / 10.0), high, "log")


REGISTRY: dict[int, type[Element]] = {}
BY_NAME: dict[str, type[Element]] = {}


class Element:
    """Base of all elements. Subclasses register themselves on definition.

    Class attributes to declare
    ---------------------------
    name : str
        Stable identifier used in files (``"lpf"``).
    code : int
        Stable integer code of the chromosome (paper, eq. 2).
    title : str
        Human name (``"Low-pass filter"``).
    category : {"basic", "calculation", "nonlinear"}
        The paper's Fig. 3, 4 or 5.
    param : Param or None
        The parameter, or None for parameter-free elements (their ``p`` is kept
        in the chromosome but ignored).
    formula : str
        The continuous-time form in plain text, for the documentation.
    guard : str
        How inputs outside the mathematical domain are handled ("none" if total).
    """

    name: ClassVar[str]
    code: ClassVar[int]
    title: ClassVar[str]
    category: ClassVar[str]
    param: ClassVar[Param | None] = None
    formula: ClassVar[str]
    guard: ClassVar[str] = "none needed: defined and finite for every finite input"
    kind: ClassVar[str] = "abstract"
    _abstract: ClassVar[bool] = True

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("_abstract", False):
            return
        for attr in ("name", "code", "title", "category", "formula"):
            if attr not in cls.__dict__:
                raise TypeError(f"element class {cls.__name__} does not declare {attr!r}")
        if cls.code in REGISTRY:
            other = REGISTRY[cls.code].__name__
            raise ValueError(f"element code {cls.code} of {cls.__name__} is already used by {other}")
        if cls.name in BY_NAME:
            raise ValueError(f"element name {cls.name!r} of {cls.__name__} is already used")
        if cls.scales_output and not cls.multiplies_output:
            raise TypeError(f"element class {cls.__name__}: an output a f(x) (scales_output) is "
                            "multiplied by a; declare multiplies_output = True")
        REGISTRY[cls.code] = cls
        BY_NAME[cls.name] = cls

    # -- how it computes (the four base classes set these; asked instead of a kind) ---
    #: Memoryless, ``y = f(x, a)``: no state (:class:`StaticElement`).
    is_static: ClassVar[bool] = False
    #: A rational transfer function ``G(s; a)`` (:class:`LinearElement`).
    is_filter: ClassVar[bool] = False
    #: A pure delay of whole samples (:class:`DelayElement`).
    is_delay: ClassVar[bool] = False
    #: The relay with hysteresis (:class:`RelayElement`).
    is_relay: ClassVar[bool] = False

    # -- traits the genetic algorithm, pruning and outputs read (declared here, not in
    # name lists) -----------------------------------------------------------------
    #: The output is the input, whatever ``a`` (``through``: an empty cell of the matrix).
    is_identity: ClassVar[bool] = False
    #: ``a`` multiplies the output (``a f(x)``, ``a s``, ``a / s``): a factor moved
    #: between two such elements of a row (with only homogeneous ones after) leaves it unchanged.
    multiplies_output: ClassVar[bool] = False
    #: For a tangent: ``g(x, a)``, the argument of ``tan`` (a pole where it crosses
    #: pi/2 + k pi); None for an element without poles.
    tangent_argument: ClassVar[Callable[[np.ndarray, float], np.ndarray] | None] = None
    #: The output is the parameter times a function of the input (``a f(x)``),
    #: so a least-squares gain can be folded into ``a``.
    scales_output: ClassVar[bool] = False
    #: ``f(c x) = c f(x)`` for every real c (linear, without offset).
    homogeneous: ClassVar[bool] = False
    #: ``f(sin x, cos x, a)`` giving the output from the input's sine and cosine
    #: (reading an input directly, the GA computes those once per input), or None.
    from_sin_cos: ClassVar[Callable[[np.ndarray, np.ndarray, float], np.ndarray] | None] = None
    #: Rough cost of simulating the element over a signal, about 100 us per 20 000 samples
    #: in the GA's row kernel (measured on the development machine). It only balances the
    #: GA's work among its workers; a kind's default fits most elements of that kind.
    cost: ClassVar[float] = 0.3
    #: The output steps between levels where the input crosses a threshold (a relay, the
    #: sign): a rounding of the input by one LSB can move the step by samples, which a
    #: fixed-point build's measurement allows for (:mod:`edm_sym.engines.fixedpoint.switching`).
    switches: ClassVar[bool] = False

    # -- units (the report traces each parameter's SI unit along its row) ------
    #: How the output's unit follows from the input's: ``"input"`` (the same unit:
    #: filters, delays, offsets, limits), ``"one"`` (dimensionless: sign, relay,
    #: trigonometric, log), ``"power"`` (the input's unit to the power a) or
    #: ``"scaled"`` (set by the parameter: gains and amplitudes, :attr:`scales_output`).
    unit_out: ClassVar[str] = "input"
    #: The unit the input must be in, when the element fixes it (an angle, "rad", for
    #: the sine and tangent; "1" for arcsine and arccosine); None when any will do.
    unit_in: ClassVar[str | None] = None

    # -- numeric -------------------------------------------------------------
    @classmethod
    def realise(cls, a: float | None, ts: float) -> Realisation:
        """The discrete-time realisation for parameter ``a`` and sample time ``ts``."""
        raise NotImplementedError

    @classmethod
    def simulate(cls, x: np.ndarray, a: float | None, ts: float) -> np.ndarray:
        """Run the element over a whole signal (last axis is time), from rest."""
        return cls.realise(a, ts).run(np.asarray(x, dtype=float))

    @classmethod
    def state_size(cls, a: float | None, ts: float) -> int:
        """Number of real state variables of the discrete realisation."""
        return cls.realise(a, ts).state_size

    @classmethod
    def stepper(cls, a: float | None, ts: float) -> Callable[[float], float]:
        """A per-sample function of Python floats (the plain-loop realisation).

        It computes the same thing as :meth:`simulate` one sample at a time;
        the benchmarks compare against it and the tests cross-check the two.
        """
        return cls.realise(a, ts).stepper()

    @classmethod
    def has_param(cls) -> bool:
        """True when the element uses its parameter ``a``."""
        return cls.param is not None


class StaticElement(Element):
    """A memoryless element ``y = f(x, a)``, realised as a :class:`StaticMap`."""

    kind: ClassVar[str] = StaticMap.kind
    is_static: ClassVar[bool] = True
    cost: ClassVar[float] = 0.06
    _abstract: ClassVar[bool] = True

    @staticmethod
    def f(m: Any, x: Any, a: Any) -> Any:
        """The function, written against the math interface ``m`` (see ops)."""
        raise NotImplementedError

    @classmethod
    def realise(cls, a: float | None, ts: float) -> StaticMap:
        return StaticMap(cls, a)


class LinearElement(Element):
    """A linear time-invariant element with a rational transfer function.

    ``tf(a)`` returns numerator and denominator coefficients in descending
    powers of s; they may be numbers or sympy expressions. ``method`` names the
    discretisation (see :func:`edm_sym.core.discrete.discretize`); the realisation
    is a :class:`LinearFilter`.
    """

    kind: ClassVar[str] = LinearFilter.kind
    is_filter: ClassVar[bool] = True
    cost: ClassVar[float] = 0.45
    homogeneous: ClassVar[bool] = True
    method: ClassVar[str] = "bilinear"
    _abstract: ClassVar[bool] = True

    @staticmethod
    def tf(a: Any) -> tuple[Sequence[Any], Sequence[Any]]:
        """Continuous-time transfer function coefficients ``(num, den)`` in s."""
        raise NotImplementedError

    @classmethod
    def coefficients(cls, a: float | None, ts: float) -> tuple[np.ndarray, np.ndarray]:
        """Discrete coefficients ``(b, a)`` in powers of z^-1, ``a[0] == 1``."""
        num, den = cls.tf(a)
        return discretize(num, den, ts, cls.method)

    @classmethod
    def realise(cls, a: float | None, ts: float) -> LinearFilter:
        b, den = cls.coefficients(a, ts)
        return LinearFilter(tuple(b.tolist()), tuple(den.tolist()), cls.method)


class DelayElement(Element):
    """A pure delay of ``samples(a, ts)`` whole samples, realised as a :class:`DelayLine`."""

    kind: ClassVar[str] = DelayLine.kind
    is_delay: ClassVar[bool] = True
    cost: ClassVar[float] = 0.23
    homogeneous: ClassVar[bool] = True
    _abstract: ClassVar[bool] = True

    @staticmethod
    def samples(a: float | None, ts: float) -> int:
        """The delay in samples for parameter ``a``."""
        raise NotImplementedError

    @classmethod
    def realise(cls, a: float | None, ts: float) -> DelayLine:
        return DelayLine(int(cls.samples(a, ts)))


class RelayElement(Element):
    """Relay with hysteresis: switches to +1 at ``x >= a``, to -1 at ``x <= -a``.

    Between the thresholds it holds its last output; it starts at 0, so until
    the input first leaves the band the output is 0. Realised as a :class:`Relay`.
    """

    kind: ClassVar[str] = Relay.kind
    is_relay: ClassVar[bool] = True
    cost: ClassVar[float] = 0.33
    switches: ClassVar[bool] = True
    _abstract: ClassVar[bool] = True

    @classmethod
    def realise(cls, a: float | None, ts: float) -> Relay:
        return Relay(float(a))

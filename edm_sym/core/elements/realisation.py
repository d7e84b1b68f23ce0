"""Realisations: what one element computes in discrete time, one frozen type per stage kind.

``Element.realise(a, ts)`` gives one of these. Each type owns, in one place,

* its state layout (:meth:`Realisation.state_layout` for the generated code,
  :meth:`Realisation.state_labels` for a real state vector);
* its batched numpy step (:meth:`Realisation.run`, the last axis is time),
  which the reference simulator and the genetic algorithm both use;
* its per-sample update on a state vector (:meth:`Realisation.update`, used
  by the python-control row systems) and on Python floats
  (:meth:`Realisation.stepper`, the plain-loop baseline);
* what the printers need (coefficients, delay, threshold), a check that it is
  printable (:meth:`Realisation.validate`) and a line saying how it is
  realised (:meth:`Realisation.describe`).

Consumers dispatch on the type (a printer's ``_stage_<TypeName>`` method, a
table keyed by the class), never on a string. This module never imports sympy.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from scipy import signal

from edm_sym.core.discrete import METHODS
from edm_sym.core.elements import ops as _ops

_QUIET = {"over": "ignore", "invalid": "ignore", "divide": "ignore"}


@dataclass(frozen=True)
class StatePart:
    """One part of a stage's state in the generated code.

    Attributes
    ----------
    suffix : str
        Appended to the stage's name (``r1_e2`` + ``_z``).
    size : int or None
        Number of reals, or None for an index (a ring buffer's position).
    comment : str
        What it holds.
    """

    suffix: str
    size: int | None
    comment: str


def _fmt(v: float) -> str:
    return format(v, ".6g")


class Realisation:
    """Base of the realisation types (each is a frozen dataclass)."""

    #: A readable name of the stage kind (documentation and plans only; never branched on).
    kind: ClassVar[str] = "abstract"
    #: The state vector's entries are ``<prefix>_<letter><i>`` (:meth:`state_labels`).
    state_letter: ClassVar[str] = "x"

    @property
    def state_size(self) -> int:
        """Number of reals in the state vector (:meth:`update`)."""
        return 0

    def state_labels(self, prefix: str) -> list[str]:
        """Names of the state vector's entries, ``prefix`` first."""
        return [f"{prefix}_{self.state_letter}{i}" for i in range(self.state_size)]

    def state_layout(self) -> tuple[StatePart, ...]:
        """The state as the generated code declares it."""
        return ()

    def run(self, x: np.ndarray) -> np.ndarray:
        """The whole signal ``x`` (last axis is time) through the stage, from rest."""
        raise NotImplementedError

    def update(self, v: float, state: Any, nxt: Any, k: int) -> float:
        """One sample: input ``v``, state ``state[k:k + state_size]``; writes ``nxt``; returns y.

        ``state`` and ``nxt`` are sequences of reals (arrays or lists); they
        may be the same object, for an update in place.
        """
        raise NotImplementedError

    def stepper(self) -> Callable[[float], float]:
        """A per-sample function of Python floats with its own state, from rest."""
        state = [0.0] * self.state_size
        update = self.update
        return lambda v: update(v, state, state, 0)

    def validate(self) -> None:
        """Raise ValueError (a message without location) when the stage cannot be printed."""

    def describe(self) -> str | None:
        """How the stage is realised in discrete time, one line (None for a static map)."""
        return None


@dataclass(frozen=True)
class StaticMap(Realisation):
    """A memoryless map ``y = f(x, a)`` of a static element.

    Attributes
    ----------
    element : type
        The :class:`~edm_sym.core.elements.base.StaticElement` (its ``f``).
    a : float or None
        The decoded parameter.
    """

    kind: ClassVar[str] = "static"
    element: type
    a: float | None

    def run(self, x: np.ndarray) -> np.ndarray:
        with np.errstate(**_QUIET):
            y = self.element.f(_ops.NUMPY, x, self.a)
            if not isinstance(y, np.ndarray) or y.shape != np.shape(x) or y.dtype != np.float64:
                y = np.asarray(y, dtype=float) * np.ones_like(x, dtype=float)
        return y

    def update(self, v: float, state: Any, nxt: Any, k: int) -> float:
        return float(self.element.f(_ops.SCALAR, v, self.a))

    def stepper(self) -> Callable[[float], float]:
        f, m, a = self.element.f, _ops.SCALAR, self.a
        return lambda x: float(f(m, x, a))


@dataclass(frozen=True)
class LinearFilter(Realisation):
    """A discrete linear filter in direct form II transposed (the structure of lfilter).

    Attributes
    ----------
    b, a : tuple of float
        Coefficients in ascending powers of z^-1, of one length, ``a[0] == 1``
        (from :func:`edm_sym.core.discrete.discretize`).
    method : str
        The discretisation (a key of :data:`edm_sym.core.discrete.METHODS`).
    """

    kind: ClassVar[str] = "linear"
    state_letter: ClassVar[str] = "z"
    b: tuple[float, ...]
    a: tuple[float, ...]
    method: str

    @property
    def order(self) -> int:
        """The filter order (number of state reals)."""
        return max(len(self.b), len(self.a)) - 1

    @property
    def state_size(self) -> int:
        return self.order

    def state_layout(self) -> tuple[StatePart, ...]:
        return (StatePart("z", self.order, "direct form II transposed state"),)

    def run(self, x: np.ndarray) -> np.ndarray:
        b, a = self.b, self.a
        with np.errstate(**_QUIET):
            if not any(a[1:]) and x.ndim == 1:
                # A pure FIR (a derivative): as lfilter computes it, without its overhead.
                y = b[0] * x
                for k in range(1, len(b)):
                    if b[k] != 0.0:
                        y[k:] += b[k] * x[:-k]
                return y
            return signal.lfilter(b, a, x, axis=-1)

    def update(self, v: float, state: Any, nxt: Any, k: int) -> float:
        # Direct form II transposed, as scipy.signal.lfilter runs it (a[0] == 1).
        b, a = self.b, self.a
        n = len(a) - 1
        y = b[0] * v + (state[k] if n else 0.0)
        for i in range(n - 1):
            nxt[k + i] = b[i + 1] * v + state[k + i + 1] - a[i + 1] * y
        if n:
            nxt[k + n - 1] = b[n] * v - a[n] * y
        return y

    def validate(self) -> None:
        if len(self.b) != len(self.a) or len(self.a) < 2 or self.a[0] != 1.0:
            raise ValueError(f"expected b, a of one length >= 2 with a[0] = 1, "
                             f"found b = {self.b}, a = {self.a}")
        if not all(math.isfinite(c) for c in (*self.b, *self.a)):
            raise ValueError(f"expected finite coefficients, found b = {self.b}, a = {self.a}")

    def describe(self) -> str | None:
        return f"{METHODS[self.method]} (order {len(self.a) - 1})"


@dataclass(frozen=True)
class DelayLine(Realisation):
    """A pure delay of ``samples`` whole samples, the buffer starting at zero.

    The state vector holds the buffer newest first; the generated code keeps
    a ring buffer and, when longer than one, the index of its oldest sample.
    """

    kind: ClassVar[str] = "delay"
    state_letter: ClassVar[str] = "d"
    samples: int

    @property
    def state_size(self) -> int:
        return self.samples

    def state_layout(self) -> tuple[StatePart, ...]:
        n = self.samples
        parts = (StatePart("buf", n, f"ring buffer, {n} samples"),)
        return parts + ((StatePart("pos", None, "its oldest sample"),) if n > 1 else ())

    def run(self, x: np.ndarray) -> np.ndarray:
        k = self.samples
        y = np.zeros_like(x, dtype=float)
        if k < x.shape[-1]:
            y[..., k:] = x[..., : x.shape[-1] - k]
        return y

    def update(self, v: float, state: Any, nxt: Any, k: int) -> float:
        n = self.samples
        if n == 0:
            return v
        y = state[k + n - 1]
        nxt[k + 1:k + n] = state[k:k + n - 1]
        nxt[k] = v
        return float(y)

    def stepper(self) -> Callable[[float], float]:
        # A ring buffer, as the generated code keeps it: O(1) a sample.
        k = self.samples
        buf = [0.0] * k
        pos = [0]

        def step(x: float) -> float:
            if k == 0:
                return x
            y = buf[pos[0]]
            buf[pos[0]] = x
            pos[0] = (pos[0] + 1) % k
            return y

        return step

    def validate(self) -> None:
        if not (isinstance(self.samples, int) and self.samples >= 1):
            raise ValueError(f"expected a delay of >= 1 sample, found {self.samples!r}")

    def describe(self) -> str | None:
        return f"z^-{self.samples}, a ring buffer of {self.samples} sample(s)"


@dataclass(frozen=True)
class Relay(Realisation):
    """Relay with hysteresis: +1 once ``x >= threshold``, -1 once ``x <= -threshold``.

    Between the thresholds it holds its last output; it starts at 0.
    """

    kind: ClassVar[str] = "relay"
    threshold: float

    @property
    def state_size(self) -> int:
        return 1

    def state_labels(self, prefix: str) -> list[str]:
        return [f"{prefix}_relay"]

    def state_layout(self) -> tuple[StatePart, ...]:
        return (StatePart("out", 1, "relay output"),)

    def run(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        a = self.threshold
        event = np.where(x >= a, 1.0, np.where(x <= -a, -1.0, np.nan))
        # Forward-fill the last switching event along time (vectorised hold).
        idx = np.where(np.isnan(event), 0, np.arange(1, x.shape[-1] + 1))
        idx = np.maximum.accumulate(idx, axis=-1)
        padded = np.concatenate([np.zeros(x.shape[:-1] + (1,)), event], axis=-1)
        return np.take_along_axis(padded, idx, axis=-1)

    def update(self, v: float, state: Any, nxt: Any, k: int) -> float:
        a = self.threshold
        y = 1.0 if v >= a else (-1.0 if v <= -a else float(state[k]))
        nxt[k] = y
        return y

    def validate(self) -> None:
        if self.threshold is None or not math.isfinite(self.threshold):
            raise ValueError(f"expected a finite threshold, found {self.threshold!r}")

    def describe(self) -> str | None:
        return (f"relay, +1 once x >= {_fmt(self.threshold)}, "
                f"-1 once x <= {_fmt(-self.threshold)}, starts at 0")


#: Every realisation type (tests are parametrised over these; printers cover each).
REALISATIONS: tuple[type[Realisation], ...] = (StaticMap, LinearFilter, DelayLine, Relay)


def dispatch(owner: Any, prefix: str, realisation: Realisation) -> Callable[..., Any]:
    """``owner``'s method ``<prefix><TypeName>`` for ``realisation`` (sympy's ``_print_<Class>``).

    Raises
    ------
    TypeError
        When ``owner`` has no method for this realisation type.
    """
    for cls in type(realisation).__mro__:
        method = getattr(owner, f"{prefix}{cls.__name__}", None)
        if method is not None:
            return method
    raise TypeError(f"{type(owner).__name__} has no {prefix}{type(realisation).__name__}")

"""A family of plants with known truth: rotary servo axes drawn from documented ranges.

``draw_plant(17)`` is draw 17 of the family: a :class:`PlantPreset` named
``family-17`` whose parameters come from a ``numpy.random.Generator`` seeded by
17 (the same draw always gives the same plant), and its ``truth``: the
physical terms the plant's ``tau_ext`` holds, with their parameters in the
units ``edm describe`` uses on a rotary axis (N m, N m s/rad, kg m^2, rad/s).
A term is present only when it is clearly above the noise: its RMS, through
the observer's low-pass, on the evaluation log is at least
:data:`PRESENCE_SHARE` of the RMS of ``tau_ext``; a drawn term below that is
dropped from the plant. The ranges and the rule are documented in
``docs/plant.md`` ("A family of plants with known truth").

A draw is data wherever a preset name is (``plant:family-17/abstraction@1``,
``edm plant --preset family-17``): :func:`resolve_preset` reads both kinds of
name.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from types import MappingProxyType

import numpy as np

from edm_sym.core.errors import ConfigError
from edm_sym.core.terms import TermKind
from edm_sym.engines.plant.filters import lowpass
from edm_sym.engines.plant.presets import PRESETS, PlantPreset, RippleHarmonic
from edm_sym.engines.plant.servo import PlantLog, simulate_plant

__all__ = [
    "FAMILY_PREFIX",
    "HOLD_MARGIN",
    "PRESENCE_SHARE",
    "STAIRCASE",
    "TRUTH_UNITS",
    "FamilyPlant",
    "draw_plant",
    "family_draw",
    "hump_slope",
    "resolve_preset",
    "term_shares",
    "true_law",
]

#: A preset name ``family-N`` is draw N of the family.
FAMILY_PREFIX = "family-"
_FAMILY_NAME = re.compile(r"family-(0|[1-9][0-9]*)")

#: A term is present when its RMS through Q(s) on the evaluation log is at least
#: this share of the RMS of tau_ext (seed 0).
PRESENCE_SHARE = 0.03
#: The draws' abstraction staircase [rad/s], spaced for the drawn Stribeck
#: velocities (1.5-5 rad/s; docs/plant.md): pi/4, pi/2 and pi below and
#: through the hump (the slowest at about half the slowest v_s, so a hump is
#: seen on its crest, not only on its flank), then 4 pi and 12 pi, where every
#: drawn hump has decayed below 0.2 % of its peak, so two plateaus tell
#: Coulomb from viscous without the hump. The presets keep theirs
#: (:data:`~edm_sym.engines.plant.excitation.STAIRCASE_LEVELS`).
STAIRCASE: tuple[float, ...] = tuple(
    math.pi * k for k in (0.25, 1.0, 4.0, 12.0, 0.5, -0.25, -1.0, -4.0, -12.0, -0.5)
)

#: The units of every truth parameter (rotary axis, as `edm describe` gives them).
TRUTH_UNITS: Mapping[str, Mapping[str, str]] = MappingProxyType({
    TermKind.COULOMB: MappingProxyType({"level": "N m"}),
    TermKind.STRIBECK: MappingProxyType({"peak": "N m", "stiction": "N m",
                                         "stribeck_velocity": "rad/s"}),
    TermKind.VISCOUS: MappingProxyType({"coefficient": "N m s/rad"}),
    TermKind.ACCELERATION: MappingProxyType({"inertia": "kg m^2"}),
    TermKind.SPATIAL: MappingProxyType({"cycles_per_revolution": "1", "amplitude": "N m",
                                        "phase": "rad"}),
})

#: Which log.truth component each kind is, for the presence rule.
_COMPONENT = {TermKind.COULOMB: "coulomb", TermKind.STRIBECK: "stribeck", TermKind.VISCOUS: "viscous",
              TermKind.ACCELERATION: "inertia_mismatch", TermKind.SPATIAL: "ripple"}

#: The drive settings the named presets show to work: (g_dob, K_v, K_i).
_DRIVES = ((500.0, 150.0, 0.0), (800.0, 200.0, 4000.0))
_ENCODERS = (2**20, 2**23)
#: Stribeck ratios (stiction/Coulomb) below this are drawn as 1 (no Stribeck term).
STRIBECK_MIN_RATIO = 1.2
#: The range the Stribeck velocities are drawn from [rad/s] (log-uniform).
STRIBECK_VELOCITIES = (1.5, 5.0)
#: A hump is drawn only as steep as the drive holds: its steepest negative slope
#: (``hump_slope``) at most this share of ``g_dob J_n``. Linearised, a DOB of
#: bandwidth g_dob and nominal inertia J_n leaves the sliding axis the pole
#: ``(k - g_dob J_n) / J`` for a friction slope -k; the share keeps a gain
#: margin of 2 (6 dB) for the sampled loop (docs/plant.md).
HOLD_MARGIN = 0.5


@dataclass(frozen=True)
class FamilyPlant:
    """One draw of the family: the plant and what it holds.

    Parameters
    ----------
    draw : int
        The draw number (the seed of the generator).
    preset : PlantPreset
        The plant, named ``family-<draw>``; ``torque_constant ==
        torque_constant_nominal``.
    truth : mapping of str to mapping of str to float
        The terms present, in the classifier's kind names, each with its
        parameters (units :data:`TRUTH_UNITS`): ``coulomb`` {level},
        ``stribeck`` {peak (= stiction - Coulomb, the excess at rest that
        `edm describe` calls the peak), stiction, stribeck_velocity} when
        stiction >= 1.2 Coulomb, ``viscous`` {coefficient}, ``acceleration``
        {inertia: J - J_n}, ``spatial`` {cycles_per_revolution, amplitude,
        phase}. Never ``offset``.
    shares : mapping of str to float
        Each present term's RMS through Q(s) on the evaluation log (seed 0)
        over the RMS of ``tau_ext``.
    dropped : tuple of str
        Terms drawn but dropped by the presence rule.
    """

    draw: int
    preset: PlantPreset
    truth: Mapping[str, Mapping[str, float]]
    shares: Mapping[str, float]
    dropped: tuple[str, ...] = ()

    @property
    def kinds(self) -> tuple[str, ...]:
        """tuple of str: the kinds of term the plant holds (the keys of ``truth``)."""
        return tuple(self.truth)


def family_draw(name: object) -> int | None:
    """The draw number a ``family-N`` name stands for, else None.

    Parameters
    ----------
    name : object
        A preset name.

    Returns
    -------
    int or None
        ``N`` for ``"family-N"`` (N without leading zeros), None for any other value.
    """
    if isinstance(name, str):
        match = _FAMILY_NAME.fullmatch(name)
        if match:
            return int(match.group(1))
    return None


def resolve_preset(name: str | PlantPreset) -> PlantPreset:
    """A named preset of :data:`PRESETS`, or draw N of the family for ``family-N``.

    Parameters
    ----------
    name : str or PlantPreset
        ``"auger"``, ..., ``"family-17"``, or a preset object (passed through).

    Returns
    -------
    PlantPreset

    Raises
    ------
    ConfigError
        (a ``ValueError``) for any other name.
    """
    if isinstance(name, PlantPreset):
        return name
    draw = family_draw(name)
    if draw is not None:
        return draw_plant(draw).preset
    if isinstance(name, str) and name in PRESETS:
        return PRESETS[name]
    raise ConfigError("preset", f"expected one of {', '.join(sorted(PRESETS))} or "
                                f"{FAMILY_PREFIX}N (N >= 0, a draw of the family), found {name!r}")


def draw_plant(draw: int) -> FamilyPlant:
    """Draw a plant with known truth; the same draw gives the same plant.

    Parameters
    ----------
    draw : int
        Draw number (>= 0), the seed of ``numpy.random.default_rng``.

    Returns
    -------
    FamilyPlant

    Raises
    ------
    ConfigError
        (a ``ValueError``) when ``draw`` is not an integer >= 0.
    """
    if isinstance(draw, bool) or not isinstance(draw, int | np.integer) or draw < 0:
        raise ConfigError("draw", f"expected an integer >= 0, found {draw!r}")
    return _draw(int(draw))


@lru_cache(maxsize=64)
def _draw(draw: int) -> FamilyPlant:
    preset = _drawn_preset(draw)
    dropped: list[str] = []
    # Dropping a term lowers the target's RMS, so the others' shares do not fall
    # much; a second pass settles it.
    for _ in range(4):
        log = simulate_plant(preset, "evaluation", seed=0)
        shares = term_shares(log)
        weak = [kind for kind, share in shares.items() if share < PRESENCE_SHARE]
        if not weak:
            break
        dropped += weak
        preset = _without(preset, weak)
    else:  # pragma: no cover - the ranges keep it from happening
        raise RuntimeError(f"family-{draw}: the presence rule did not settle")
    truth = MappingProxyType({kind: MappingProxyType(params)
                              for kind, params in _truth(preset).items()})
    return FamilyPlant(draw, preset, truth, MappingProxyType(dict(shares)), tuple(dropped))


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(math.exp(rng.uniform(math.log(low), math.log(high))))


def _round(x: float, digits: int = 3) -> float:
    """x to ``digits`` significant digits (readable truths, exactly the plant's values)."""
    return 0.0 if x == 0 else float(f"{x:.{digits - 1}e}")


def hump_slope(excess: float, stribeck_velocity: float) -> float:
    """The steepest negative slope of a Stribeck hump [N m s/rad].

    ``excess * exp(-(v / v_s)^2)`` falls fastest at ``v = v_s / sqrt(2)``,
    by ``excess * sqrt(2 / e) / v_s``.

    Parameters
    ----------
    excess : float
        The hump's excess over Coulomb at rest, ``tau_s - tau_c`` [N m].
    stribeck_velocity : float
        ``v_s`` [rad/s], > 0.

    Returns
    -------
    float
    """
    return excess * math.sqrt(2.0 / math.e) / stribeck_velocity


def _held(stiction: float, coulomb: float, stribeck_velocity: float,
          g_dob: float, inertia_nominal: float) -> bool:
    """Whether the drive holds a sliding axis on the hump (:data:`HOLD_MARGIN`)."""
    return hump_slope(stiction - coulomb, stribeck_velocity) <= HOLD_MARGIN * g_dob * inertia_nominal


def _stiction(coulomb: float, ratio: float) -> float:
    """The stiction level of a drawn ratio, rounded; the Coulomb level (no hump) when
    the ratio, or the rounding, leaves it under :data:`STRIBECK_MIN_RATIO` times it."""
    stiction = _round(coulomb * ratio) if ratio > 1.0 else coulomb
    return stiction if stiction >= STRIBECK_MIN_RATIO * coulomb else coulomb


def _drawn_preset(draw: int) -> PlantPreset:
    """The parameters of draw ``draw`` before the presence rule (ranges: docs/plant.md)."""
    rng = np.random.default_rng(draw)
    coulomb = _round(_log_uniform(rng, 0.15, 1.0))
    ratio = 1.0 if rng.random() < 0.4 else float(rng.uniform(STRIBECK_MIN_RATIO, 2.5))
    stiction = _stiction(coulomb, ratio)
    stribeck_velocity = _round(_log_uniform(rng, *STRIBECK_VELOCITIES))
    viscous = _round(_log_uniform(rng, 0.002, 0.02))
    inertia = _round(_log_uniform(rng, 4e-4, 1.2e-3))
    error = 0.0 if rng.random() < 0.25 else float(rng.choice((-1.0, 1.0)) * rng.uniform(0.08, 0.25))
    inertia_nominal = _round(inertia / (1.0 + error))
    cycles = 0 if rng.random() < 0.3 else int(rng.integers(1, 9))
    amplitude = _round(_log_uniform(rng, 0.05, 0.2))
    phase = _round(float(rng.uniform(0.0, 2.0 * math.pi)))
    torque_constant = _round(float(rng.uniform(0.4, 0.6)))
    current_noise = _round(float(rng.uniform(0.005, 0.03)))
    g_rtob = float(round(rng.uniform(150.0, 300.0)))
    g_dob, velocity_gain, velocity_integral = _DRIVES[int(rng.integers(len(_DRIVES)))]
    encoder_counts = _ENCODERS[int(rng.integers(len(_ENCODERS)))]
    stiffness = _round(_log_uniform(rng, 5e3, 2e4))
    damping_ratio = float(rng.uniform(0.15, 0.3))
    damping = _round(2.0 * damping_ratio * math.sqrt(stiffness * inertia))
    # A hump steeper than the drive holds would stick and slip on the slow
    # plateaus, where no static law can be read: its ratio and v_s are drawn
    # again (a generator of their own, so the other parameters stay).
    for attempt in range(1, 1001):
        if _held(stiction, coulomb, stribeck_velocity, g_dob, inertia_nominal):
            break
        again = np.random.default_rng((draw, attempt))
        stiction = _stiction(coulomb, float(again.uniform(STRIBECK_MIN_RATIO, 2.5)))
        stribeck_velocity = _round(_log_uniform(again, *STRIBECK_VELOCITIES))
    else:  # pragma: no cover - the gentlest hump drawn (1.2, 5 rad/s) is held
        raise RuntimeError(f"family-{draw}: no hump the drive holds in 1000 draws")
    return PlantPreset(
        name=f"{FAMILY_PREFIX}{draw}",
        description=f"draw {draw} of the family of plants with known truth (docs/plant.md)",
        inertia=inertia,
        inertia_nominal=inertia_nominal,
        torque_constant=torque_constant,
        torque_constant_nominal=torque_constant,
        coulomb=coulomb,
        stiction=stiction,
        stribeck_velocity=stribeck_velocity,
        bristle_stiffness=stiffness,
        bristle_damping=damping,
        viscous=viscous,
        ripple=(RippleHarmonic(cycles=cycles, amplitude=amplitude, phase=phase),) if cycles else (),
        g_dob=g_dob,
        g_rtob=g_rtob,
        velocity_gain=velocity_gain,
        velocity_integral=velocity_integral,
        g_velocity=2000.0,
        g_acceleration=1000.0,
        encoder_counts=encoder_counts,
        current_noise=current_noise,
        staircase=STAIRCASE,
    )


def _without(preset: PlantPreset, kinds: Sequence[str]) -> PlantPreset:
    """The plant with the given terms taken out."""
    changes: dict[str, object] = {}
    if TermKind.STRIBECK in kinds:
        changes["stiction"] = preset.coulomb
    if TermKind.COULOMB in kinds:
        changes.update(coulomb=0.0, stiction=0.0, bristle_damping=0.0)
    if TermKind.VISCOUS in kinds:
        changes["viscous"] = 0.0
    if TermKind.ACCELERATION in kinds:
        changes["inertia_nominal"] = preset.inertia
    if TermKind.SPATIAL in kinds:
        changes["ripple"] = ()
    return replace(preset, **changes)


def _truth(p: PlantPreset) -> dict[str, dict[str, float]]:
    """The terms of a family plant (K_tn = K_t, one ripple harmonic at most)."""
    truth: dict[str, dict[str, float]] = {}
    if p.coulomb > 0.0:
        truth[TermKind.COULOMB] = {"level": p.coulomb}
    if p.coulomb > 0.0 and p.stiction >= STRIBECK_MIN_RATIO * p.coulomb:
        truth[TermKind.STRIBECK] = {"peak": _round(p.stiction - p.coulomb, 6),
                                    "stiction": p.stiction,
                                    "stribeck_velocity": p.stribeck_velocity}
    if p.viscous > 0.0:
        truth[TermKind.VISCOUS] = {"coefficient": p.viscous}
    if p.inertia != p.inertia_nominal:
        truth[TermKind.ACCELERATION] = {"inertia": _round(p.inertia - p.inertia_nominal, 6)}
    for h in p.ripple:
        truth[TermKind.SPATIAL] = {"cycles_per_revolution": float(h.cycles),
                                   "amplitude": h.amplitude, "phase": h.phase}
    return truth


def term_shares(log: PlantLog) -> dict[str, float]:
    """Each term's RMS through Q(s) over the RMS of ``tau_ext``, for the terms the plant has.

    Parameters
    ----------
    log : PlantLog
        A simulated log (its ``truth`` holds the components).

    Returns
    -------
    dict of str to float
        Kind (``coulomb``, ``stribeck``, ``viscous``, ``acceleration``,
        ``spatial``) to its share, for the kinds whose parameters are not zero.
    """
    p = log.preset
    has = {TermKind.COULOMB: p.coulomb > 0.0, TermKind.STRIBECK: p.stiction > p.coulomb,
           TermKind.VISCOUS: p.viscous > 0.0, TermKind.ACCELERATION: p.inertia != p.inertia_nominal,
           TermKind.SPATIAL: bool(p.ripple)}
    target = float(np.sqrt(np.mean(log.tau_ext ** 2)))
    out = {}
    for kind, here in has.items():
        if here:
            seen = lowpass(log.truth[_COMPONENT[kind]], p.g_rtob, log.ts)
            out[kind] = float(np.sqrt(np.mean(seen ** 2))) / target
    return out


def true_law(log: PlantLog) -> np.ndarray:
    """The true disturbance as the observer sees it: what ``tau_ext`` is without its noise.

    The truth's ``total`` less its ``current_noise``, aligned as the torque
    balance sees it (one sample later; the acceleration terms averaged over
    the two samples its triangle weighs, docs/plant.md) and passed through
    Q(s). ``tau_ext`` minus this is the sensor noise and encoder rounding:
    its RMS is the error of a model that knew the plant's law exactly.

    Parameters
    ----------
    log : PlantLog
        A simulated log.

    Returns
    -------
    numpy.ndarray
        Same length as ``log.tau_ext`` [N m]; the first two samples are 0.
    """
    accel = log.truth["inertia_mismatch"] + log.truth["torque_constant_mismatch"]
    rest = log.truth["total"] - log.truth["current_noise"] - accel
    aligned = rest[1:-1] + 0.5 * (accel[1:-1] + accel[:-2])
    out = np.zeros_like(log.tau_ext)
    out[2:] = lowpass(aligned, log.preset.g_rtob, log.ts)
    return out

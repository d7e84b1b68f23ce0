"""Servo-axis presets: the physical parameters and drive settings of each plant.

A preset is a frozen, validated dataclass. Custom plants are made with
:func:`dataclasses.replace` on a named preset (every field is re-validated), e.g.
``replace(PRESETS["auger"], coulomb=0.0, stiction=0.0, ripple=())``.

Every parameter is documented, with its unit, in ``docs/plant.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from edm_sym.core.errors import ConfigError
from edm_sym.core.terms import TermKind
from edm_sym.engines.plant.excitation import STAIRCASE_LEVELS

__all__ = ["PRESETS", "PlantPreset", "RippleHarmonic", "get_preset"]


@dataclass(frozen=True)
class RippleHarmonic:
    """One harmonic of the position-dependent torque ripple.

    The ripple torque is ``amplitude * sin(cycles * theta + phase)``; ``cycles``
    is an integer so that the ripple is periodic in the wrapped angle.

    Parameters
    ----------
    cycles : int
        Periods per revolution (>= 1).
    amplitude : float
        Peak torque [N m] (>= 0).
    phase : float
        Phase at theta = 0 [rad].
    """

    cycles: int
    amplitude: float
    phase: float = 0.0

    def __post_init__(self) -> None:
        if isinstance(self.cycles, bool) or not isinstance(self.cycles, int) or self.cycles < 1:
            raise ConfigError(
                "RippleHarmonic.cycles",
                f"expected an integer >= 1 (periods per revolution), found {self.cycles!r}",
            )
        _check_finite("RippleHarmonic.amplitude", self.amplitude, minimum=0.0)
        _check_finite("RippleHarmonic.phase", self.phase)


@dataclass(frozen=True)
class PlantPreset:
    """A rigid servo axis in free motion, its friction and its drive.

    Plant: ``J domega/dt = K_t i - tau_fric - tau_env``, with the friction a LuGre
    bristle model (Coulomb, Stribeck, bristle dynamics) plus viscous friction
    plus a position-dependent ripple. Drive: acceleration control with a
    disturbance observer (DOB), a P or PI velocity loop with acceleration
    feed-forward, and a reaction torque observer (RTOB). The controller only
    knows the nominal values ``inertia_nominal`` and ``torque_constant_nominal``.

    Parameters
    ----------
    name : str
        Preset name.
    description : str
        One line saying what machine the preset stands for.
    inertia : float
        True rigid inertia J [kg m^2].
    inertia_nominal : float
        Nominal inertia J_n used by DOB, RTOB and velocity loop [kg m^2].
    torque_constant : float
        True torque constant K_t [N m/A].
    torque_constant_nominal : float
        Nominal torque constant K_tn [N m/A].
    coulomb : float
        Coulomb friction level tau_c [N m]; 0 together with ``stiction`` = 0
        switches the LuGre part off.
    stiction : float
        Stiction (breakaway) level tau_s [N m]; ``stiction > coulomb`` gives a
        Stribeck dip.
    stribeck_velocity : float
        Stribeck velocity v_s [rad/s].
    bristle_stiffness : float
        LuGre sigma_0 [N m/rad].
    bristle_damping : float
        LuGre sigma_1 [N m s/rad].
    viscous : float
        Viscous friction sigma_2 [N m s/rad].
    ripple : tuple of RippleHarmonic
        Position-dependent torque ripple, periodic in the wrapped angle.
    g_dob : float
        Cut-off of the DOB low-pass [rad/s].
    g_rtob : float
        Cut-off of the RTOB low-pass Q(s) = g/(s + g) [rad/s].
    velocity_gain : float
        Proportional gain K_v of the velocity loop [1/s].
    velocity_integral : float
        Integral gain K_i of the velocity loop [1/s^2]; 0 gives a P loop.
    g_velocity : float
        Cut-off of the low-pass on the logged encoder-difference velocity [rad/s].
    g_acceleration : float
        Cut-off of the low-pass on the logged velocity-difference acceleration [rad/s].
    encoder_counts : int
        Encoder counts per revolution; 0 means an ideal (unquantised) angle.
    current_noise : float
        Standard deviation of the current-sensor noise [A], white per sample.
    staircase : tuple of float, optional
        The ten plateau speeds [rad/s] of this plant's ``"abstraction"``
        staircase; None (the default) uses
        :data:`~edm_sym.engines.plant.excitation.STAIRCASE_LEVELS`.
    """

    name: str
    description: str
    inertia: float
    inertia_nominal: float
    torque_constant: float
    torque_constant_nominal: float
    coulomb: float
    stiction: float
    stribeck_velocity: float
    bristle_stiffness: float
    bristle_damping: float
    viscous: float
    ripple: tuple[RippleHarmonic, ...]
    g_dob: float
    g_rtob: float
    velocity_gain: float
    velocity_integral: float
    g_velocity: float
    g_acceleration: float
    encoder_counts: int
    current_noise: float
    staircase: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        where = f"PlantPreset({self.name!r})"
        for name in (
            "inertia",
            "inertia_nominal",
            "torque_constant",
            "torque_constant_nominal",
            "stribeck_velocity",
            "bristle_stiffness",
            "g_dob",
            "g_rtob",
            "velocity_gain",
            "g_velocity",
            "g_acceleration",
        ):
            _check_finite(f"{where}.{name}", getattr(self, name), minimum=0.0, strict=True)
        for name in ("coulomb", "stiction", "bristle_damping", "viscous", "velocity_integral",
                     "current_noise"):
            _check_finite(f"{where}.{name}", getattr(self, name), minimum=0.0)
        if (self.coulomb == 0.0) != (self.stiction == 0.0):
            # g(v) of eq. (12) must stay positive at every speed, or vanish everywhere.
            raise ConfigError(
                f"{where}.coulomb/stiction",
                "expected both > 0 (LuGre friction) or both 0 (no LuGre friction), "
                f"found coulomb={self.coulomb!r}, stiction={self.stiction!r}",
            )
        if not isinstance(self.ripple, tuple) or not all(
            isinstance(h, RippleHarmonic) for h in self.ripple
        ):
            raise ConfigError(
                f"{where}.ripple",
                f"expected a tuple of RippleHarmonic, found {self.ripple!r}",
            )
        counts = self.encoder_counts
        if isinstance(counts, bool) or not isinstance(counts, int) or counts < 0:
            raise ConfigError(
                f"{where}.encoder_counts",
                f"expected an integer >= 0 (0 = unquantised), found {counts!r}",
            )
        if self.staircase is not None:
            _check_staircase(f"{where}.staircase", self.staircase)

    @property
    def true_terms(self) -> tuple[TermKind, ...]:
        """tuple of TermKind: the physical terms ``tau_ext`` holds, as the classifier names them.

        In free motion the RTOB sees ``(K_tn/K_t)(friction + J alpha) - J_n alpha``
        (docs/plant.md, "Ground truth"), so: ``"coulomb"`` when ``coulomb > 0``,
        ``"viscous"`` when ``viscous > 0``, ``"acceleration"`` when the
        equivalent inertia :attr:`inertia_error` is not zero (beyond rounding), ``"spatial"``
        with a ripple, ``"stribeck"`` when ``stiction > coulomb``; in the order
        of the classifier's kinds. Never ``"offset"``.
        """
        present = {
            TermKind.COULOMB: self.coulomb > 0.0,
            TermKind.VISCOUS: self.viscous > 0.0,
            # Rounding aside: ballscrew's +5 % K_tn and +5 % J_n cancel exactly.
            TermKind.ACCELERATION: abs(self.inertia_error) > 1e-9 * self.inertia,
            TermKind.SPATIAL: bool(self.ripple),
            TermKind.STRIBECK: self.stiction > self.coulomb,
        }
        return tuple(kind for kind, here in present.items() if here)

    @property
    def inertia_error(self) -> float:
        """float: ``(K_tn/K_t) J - J_n`` [kg m^2], the inertia ``tau_ext`` sees times alpha."""
        return self.torque_constant_nominal / self.torque_constant * self.inertia - (
            self.inertia_nominal)

    @property
    def has_lugre(self) -> bool:
        """bool: whether the LuGre (Coulomb/Stribeck/bristle) friction is present."""
        return self.coulomb > 0.0

    def as_dict(self) -> dict[str, object]:
        """Return the parameters as a plain dict (ripple as a list of dicts).

        Returns
        -------
        dict
            Field name to value, in declaration order.
        """
        out: dict[str, object] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "ripple":
                value = [
                    {"cycles": h.cycles, "amplitude": h.amplitude, "phase": h.phase}
                    for h in value
                ]
            out[f.name] = value
        return out


def _check_staircase(where: str, levels: object) -> None:
    n = len(STAIRCASE_LEVELS)
    if not (isinstance(levels, tuple) and len(levels) == n and all(
            not isinstance(v, bool) and isinstance(v, int | float) and math.isfinite(v)
            for v in levels)):
        raise ConfigError(where, f"expected a tuple of {n} finite speeds [rad/s], "
                                 f"found {levels!r}")


def _check_finite(
    where: str, value: object, *, minimum: float | None = None, strict: bool = False
) -> None:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(where, f"expected a finite number, found {value!r}")
    if minimum is not None and (value <= minimum if strict else value < minimum):
        relation = ">" if strict else ">="
        raise ConfigError(where, f"expected a number {relation} {minimum}, found {value!r}")



#: The named plants. See docs/plant.md for the meaning of every number.
PRESETS: dict[str, PlantPreset] = {
    "auger": PlantPreset(
        name="auger",
        description=(
            "auger powder-filling axis of the paper: sealed bearings, screw ripple, "
            "inertia under-estimated by the drive"
        ),
        inertia=1.2e-3,
        inertia_nominal=1.0e-3,
        torque_constant=0.6,
        torque_constant_nominal=0.6,
        coulomb=0.95,
        stiction=1.05,
        stribeck_velocity=0.8,
        bristle_stiffness=1.0e4,
        bristle_damping=1.5,
        viscous=0.005,
        ripple=(
            RippleHarmonic(cycles=1, amplitude=0.06, phase=0.4),
            RippleHarmonic(cycles=4, amplitude=0.03, phase=1.3),
            RippleHarmonic(cycles=9, amplitude=0.02, phase=-0.7),
        ),
        g_dob=500.0,
        g_rtob=150.0,
        velocity_gain=120.0,
        velocity_integral=0.0,
        g_velocity=2000.0,
        g_acceleration=1000.0,
        encoder_counts=2**20,
        current_noise=0.02,
    ),
    "ballscrew": PlantPreset(
        name="ballscrew",
        description=(
            "motor side of a preloaded ball-screw feed axis: strong Stribeck and viscous "
            "friction, ball-pass ripple, over-estimated inertia and torque constant"
        ),
        inertia=4.0e-4,
        inertia_nominal=4.2e-4,
        torque_constant=0.40,
        torque_constant_nominal=0.42,
        coulomb=0.25,
        stiction=0.40,
        stribeck_velocity=2.0,
        bristle_stiffness=5.0e3,
        bristle_damping=0.4,
        viscous=0.02,
        ripple=(
            RippleHarmonic(cycles=2, amplitude=0.010, phase=0.0),
            RippleHarmonic(cycles=5, amplitude=0.015, phase=2.1),
        ),
        g_dob=800.0,
        g_rtob=300.0,
        velocity_gain=200.0,
        velocity_integral=4000.0,
        g_velocity=2000.0,
        g_acceleration=1000.0,
        encoder_counts=2**23,
        current_noise=0.01,
    ),
    "lugre": PlantPreset(
        name="lugre",
        description=(
            "friction that is exactly a LuGre model plus viscous friction: no ripple, "
            "nominal inertia and torque constant exact (a check for LuGre identification)"
        ),
        inertia=8.0e-4,
        inertia_nominal=8.0e-4,
        torque_constant=0.5,
        torque_constant_nominal=0.5,
        coulomb=0.6,
        stiction=0.9,
        stribeck_velocity=1.5,
        bristle_stiffness=2.0e4,
        bristle_damping=2.4,
        viscous=0.01,
        ripple=(),
        g_dob=500.0,
        g_rtob=200.0,
        velocity_gain=150.0,
        velocity_integral=0.0,
        g_velocity=2000.0,
        g_acceleration=1000.0,
        encoder_counts=2**20,
        current_noise=0.02,
    ),
    # -- plants with known truth (docs/plant.md#plants-with-known-truth) ----------
    # Each has one clear mix of disturbances and nothing else, so what `edm describe`
    # names can be checked against PlantPreset.true_terms (tests/test_truth.py).
    "bearing": PlantPreset(
        name="bearing",
        description=(
            "rolling bearings without ripple: Coulomb and viscous friction, no Stribeck "
            "peak, inertia under-estimated by the drive"
        ),
        inertia=1.0e-3,
        inertia_nominal=0.85e-3,
        torque_constant=0.5,
        torque_constant_nominal=0.5,
        coulomb=0.5,
        stiction=0.5,
        stribeck_velocity=1.0,
        bristle_stiffness=1.0e4,
        bristle_damping=1.0,
        viscous=0.015,
        ripple=(),
        g_dob=500.0,
        g_rtob=200.0,
        velocity_gain=150.0,
        velocity_integral=0.0,
        g_velocity=2000.0,
        g_acceleration=1000.0,
        encoder_counts=2**20,
        current_noise=0.02,
    ),
    "stribeck": PlantPreset(
        name="stribeck",
        description=(
            "a dry sliding guide: a strong Stribeck peak (stiction 2.25 x Coulomb, "
            "v_s = 3 rad/s) over Coulomb and viscous friction, exact inertia, no ripple"
        ),
        inertia=6.0e-4,
        inertia_nominal=6.0e-4,
        torque_constant=0.5,
        torque_constant_nominal=0.5,
        coulomb=0.4,
        stiction=0.9,
        stribeck_velocity=3.0,
        bristle_stiffness=1.0e4,
        bristle_damping=1.0,
        viscous=0.01,
        ripple=(),
        g_dob=500.0,
        g_rtob=200.0,
        velocity_gain=150.0,
        velocity_integral=0.0,
        g_velocity=2000.0,
        g_acceleration=1000.0,
        encoder_counts=2**20,
        current_noise=0.02,
    ),
    "inertia": PlantPreset(
        name="inertia",
        description=(
            "a frictionless direct drive on air bearings whose nominal inertia is "
            "20 % low: tau_ext holds the inertia mismatch alone"
        ),
        inertia=1.0e-3,
        inertia_nominal=0.8e-3,
        torque_constant=0.5,
        torque_constant_nominal=0.5,
        coulomb=0.0,
        stiction=0.0,
        stribeck_velocity=1.0,
        bristle_stiffness=1.0e4,
        bristle_damping=0.0,
        viscous=0.0,
        ripple=(),
        g_dob=500.0,
        g_rtob=200.0,
        velocity_gain=150.0,
        velocity_integral=0.0,
        g_velocity=2000.0,
        g_acceleration=1000.0,
        encoder_counts=2**20,
        current_noise=0.02,
    ),
    "ripple3": PlantPreset(
        name="ripple3",
        description=(
            "a three-lobe cam on the axis: Coulomb and viscous friction and a position "
            "ripple of 3 cycles per revolution, exact inertia"
        ),
        inertia=8.0e-4,
        inertia_nominal=8.0e-4,
        torque_constant=0.5,
        torque_constant_nominal=0.5,
        coulomb=0.3,
        stiction=0.3,
        stribeck_velocity=1.0,
        bristle_stiffness=1.0e4,
        bristle_damping=1.0,
        viscous=0.008,
        ripple=(RippleHarmonic(cycles=3, amplitude=0.1, phase=0.5),),
        g_dob=500.0,
        g_rtob=200.0,
        velocity_gain=150.0,
        velocity_integral=0.0,
        g_velocity=2000.0,
        g_acceleration=1000.0,
        encoder_counts=2**20,
        current_noise=0.02,
    ),
}


def get_preset(preset: str | PlantPreset) -> PlantPreset:
    """Resolve a preset name (or pass a preset through).

    Parameters
    ----------
    preset : str or PlantPreset
        A key of :data:`PRESETS`, or a preset object.

    Returns
    -------
    PlantPreset

    Raises
    ------
    ConfigError
        (a ``ValueError``) when the name is not a known preset.
    """
    if isinstance(preset, PlantPreset):
        return preset
    if isinstance(preset, str) and preset in PRESETS:
        return PRESETS[preset]
    raise ConfigError(
        "preset",
        f"expected one of {', '.join(sorted(PRESETS))} or a PlantPreset, found {preset!r}",
    )

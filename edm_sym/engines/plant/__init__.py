"""The data source: a servo axis with DOB, velocity loop and reaction torque observer.

Simulates free-motion logs (``t, theta_w, theta_uw, omega, alpha, tau_ext``,
docs/cli.md#plant-log-columns) of a rigid axis with known friction, for the EDM
abstraction and for checking identified models against the ground truth::

    from edm_sym.engines.plant import PRESETS, EXCITATIONS, simulate_plant
    log = simulate_plant("auger", "abstraction", seed=0)
    log.columns["tau_ext"], log.truth["coulomb"], log.omega_cmd

See ``docs/plant.md`` for the block diagram and every preset parameter.
``family`` draws plants with known truth (``family-N`` wherever a preset name
goes); ``anchor`` is the engineer's least squares that checks such a truth.
"""

from __future__ import annotations

from edm_sym.engines.plant.excitation import EXCITATIONS, excitation_command, get_excitation
from edm_sym.engines.plant.filters import (
    acceleration_from_velocity,
    lowpass,
    lowpass_coefficients,
    velocity_from_angle,
)
from edm_sym.engines.plant.friction import (
    FRICTION_COMPONENTS,
    friction_components,
    ripple_torque,
    stribeck_level,
)
from edm_sym.engines.plant.presets import PRESETS, PlantPreset, RippleHarmonic, get_preset
from edm_sym.engines.plant.servo import (
    COLUMNS,
    TRUTH_KEYS,
    PlantLog,
    default_substeps,
    simulate_axis,
    simulate_plant,
)

__all__ = [
    "COLUMNS",
    "EXCITATIONS",
    "FRICTION_COMPONENTS",
    "PRESETS",
    "TRUTH_KEYS",
    "PlantLog",
    "PlantPreset",
    "RippleHarmonic",
    "acceleration_from_velocity",
    "default_substeps",
    "excitation_command",
    "friction_components",
    "get_excitation",
    "get_preset",
    "lowpass",
    "lowpass_coefficients",
    "ripple_torque",
    "simulate_axis",
    "simulate_plant",
    "stribeck_level",
    "velocity_from_angle",
]

"""The LuGre friction model: the conventional baseline compensator.

The paper's eqs. 10-14: simulation with an exact per-sample bristle update,
the steady-state curve, identification on a free-motion log with the fitness
of eq. 8, and the LUGRE.json file. See ``docs/lugre.md``.
"""

from edm_sym.engines.lugre.fileformat import load_lugre, lugre_schema, parse_lugre, save_lugre
from edm_sym.engines.lugre.ga import LUGRE_GA, identify_ga  # importing it registers "ga"
from edm_sym.engines.lugre.identify import (
    BOTH,
    METHODS,
    LuGreProblem,
    LuGreProgress,
    MethodOutcome,
    identify_lugre,
    register_method,
    search_space,
    shape_bound_flags,
)
from edm_sym.engines.lugre.model import (
    PARAMETER_NAMES,
    LuGreParams,
    simulate_lugre,
    steady_state,
    weighted_rmse,
)
from edm_sym.engines.lugre.result import LuGreProvenance, LuGreResult, MethodScore

__all__ = [
    "BOTH",
    "LUGRE_GA",
    "METHODS",
    "PARAMETER_NAMES",
    "LuGreParams",
    "LuGreProblem",
    "LuGreProgress",
    "LuGreProvenance",
    "LuGreResult",
    "MethodOutcome",
    "MethodScore",
    "identify_ga",
    "identify_lugre",
    "load_lugre",
    "lugre_schema",
    "parse_lugre",
    "register_method",
    "save_lugre",
    "search_space",
    "shape_bound_flags",
    "simulate_lugre",
    "steady_state",
    "weighted_rmse",
]

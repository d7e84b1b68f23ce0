"""Hierarchical abstraction: the genetic algorithm of Algorithm 1, fast.

::

    from edm_sym.engines.abstraction import Parallel, abstract, load_config
    result = abstract(data, target="tau_ext", inputs=["theta_w", "omega", "alpha"],
                      config=load_config("steps.toml"), seed=1, parallel=Parallel(workers=4))

See ``docs/abstraction.md`` for the algorithm, the config format and the
speed design.
"""

from __future__ import annotations

from edm_sym.engines.abstraction.evaluator import Evaluator
from edm_sym.engines.abstraction.fidelity import FidelitySettings
from edm_sym.engines.abstraction.holdout import ValidationSettings
from edm_sym.engines.abstraction.parallel import Parallel
from edm_sym.engines.abstraction.parsimony import ParsimonySettings
from edm_sym.engines.abstraction.run import GenerationInfo, abstract
from edm_sym.engines.abstraction.schedule import (
    AbstractionConfig,
    GaSettings,
    InitialRow,
    StepConfig,
    default_config,
    load_config,
    parse_config,
)
from edm_sym.engines.abstraction.weighting import Weighting

__all__ = [
    "AbstractionConfig",
    "Evaluator",
    "FidelitySettings",
    "GaSettings",
    "GenerationInfo",
    "InitialRow",
    "Parallel",
    "ParsimonySettings",
    "StepConfig",
    "ValidationSettings",
    "Weighting",
    "abstract",
    "default_config",
    "load_config",
    "parse_config",
]

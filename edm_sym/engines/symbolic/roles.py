"""Physical roles of the input signals: :mod:`edm_sym.core.roles`, named here for the decoders.

The roles live in ``core`` so that the commands' closing summary and the
behaviour naming (:mod:`edm_sym.engines.physics`) read them without sympy.
"""

from edm_sym.core.roles import DEFAULT_ROLES, LOG_ROLE_NAMES, ROLES, default_role, input_roles

__all__ = ["DEFAULT_ROLES", "LOG_ROLE_NAMES", "ROLES", "default_role", "input_roles"]

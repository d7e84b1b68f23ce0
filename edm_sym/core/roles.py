"""Physical roles of the input signals, from their names.

A role says what an input measures, so the classifier can give a row's terms
SI units: ``"velocity"`` [rad/s], ``"acceleration"`` [rad/s^2], ``"angle"``
(unwrapped) [rad], ``"angle_wrapped"`` (in [0, 2 pi)) [rad], or None (unknown).

The defaults (:data:`DEFAULT_ROLES`) cover the plant log's columns (``theta_w,
theta_uw, omega, alpha``) and common robotics names. A name is looked up in
lower case, first as it is, then without a trailing number (``omega_2``,
``qd1``). ``decode(result, roles={"x1": "velocity"})`` overrides or adds names.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from edm_sym.core.errors import ConfigError

#: The roles an input may have.
ROLES = ("velocity", "acceleration", "angle", "angle_wrapped")
#: The names of a log's column roles (:data:`edm_sym.core.data.INPUT_ROLES`, the
#: ``--role`` option and result.json's ``logs``) for the roles above; ``input``
#: is a signal without a physical role.
LOG_ROLE_NAMES: dict[str, str | None] = {"position": "angle", "position_wrapped": "angle_wrapped",
                                         "input": None}

#: Default input names of each role (lower case).
DEFAULT_ROLES: dict[str, tuple[str, ...]] = {
    "velocity": ("omega", "omega_m", "w", "vel", "velocity", "speed", "qd", "dq", "q_dot",
                 "dtheta", "theta_dot", "v"),
    "acceleration": ("alpha", "acc", "accel", "acceleration", "qdd", "ddq", "q_ddot",
                     "ddtheta", "theta_ddot"),
    "angle_wrapped": ("theta_w", "q_w", "theta_wrapped", "angle_wrapped", "position_wrapped"),
    "angle": ("theta", "theta_uw", "theta_m", "q", "qm", "q_m", "position", "pos", "angle",
              "phi"),
}

_BY_NAME = {name: role for role, names in DEFAULT_ROLES.items() for name in names}


def default_role(name: str) -> str | None:
    """The default role of an input name, or None when the name is not known.

    Parameters
    ----------
    name : str

    Returns
    -------
    str or None
    """
    key = name.lower()
    if key in _BY_NAME:
        return _BY_NAME[key]
    return _BY_NAME.get(re.sub(r"_?\d+$", "", key))


def input_roles(
    inputs: Iterable[str], overrides: Mapping[str, str | None] | None = None
) -> dict[str, str | None]:
    """The role of each input: the defaults, then ``overrides``.

    Parameters
    ----------
    inputs : iterable of str
        Input names.
    overrides : mapping of str to str or None, optional
        Name -> role (one of :data:`ROLES`, a log role of :data:`LOG_ROLE_NAMES`
        such as ``"position"``, or None for "no role").

    Returns
    -------
    dict of str to str or None

    Raises
    ------
    ConfigError
        For a role that is not one of :data:`ROLES` or a name that is not an input.
    """
    names = list(inputs)
    out = {n: default_role(n) for n in names}
    for name, role in (overrides or {}).items():
        if name not in out:
            raise ConfigError("roles", f"expected an input's name (inputs: {', '.join(names)}), "
                                       f"found {name!r}")
        role = LOG_ROLE_NAMES.get(role, role) if isinstance(role, str) else role
        if role is not None and role not in ROLES:
            raise ConfigError(f"roles[{name!r}]", f"expected one of {', '.join(ROLES)}, "
                              f"{', '.join(LOG_ROLE_NAMES)} or None, found {role!r}")
        out[name] = role
    return out


def motion_signals(inputs: Sequence[np.ndarray], roles: Sequence[str | None],
                   ts: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(velocity, acceleration) from a model's inputs on one contiguous log.

    The velocity input, else the unwrapped angle differentiated; the
    acceleration input, else the velocity differentiated. None without either.
    """
    by_role = {r: np.asarray(x, dtype=float) for x, r in zip(inputs, roles, strict=True)
               if r is not None}
    if "velocity" in by_role:
        v = by_role["velocity"]
    elif "angle" in by_role and by_role["angle"].size > 1:
        v = np.gradient(by_role["angle"], ts)
    else:
        return None
    a = by_role.get("acceleration")
    if a is None:
        if v.size < 2:
            return None
        a = np.gradient(v, ts)
    return v, a

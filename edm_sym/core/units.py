"""SI units of an axis: rotary (rad, N m) or linear (m, N), in one place (docs/data.md#units).

Every output that prints a unit (the classifier's parameters, ``edm describe``,
the report's tables, the C header's comments, the Python module's docstrings)
asks :func:`axis_units` for it, so a linear axis reads N and N s/m everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["AXES", "AxisUnits", "axis_units"]


@dataclass(frozen=True)
class AxisUnits:
    """The SI unit of each quantity on one kind of axis.

    Attributes
    ----------
    axis : str
        ``"rotary"`` or ``"linear"``.
    position, velocity, acceleration : str
        Units of the motion signals.
    force : str
        The target's unit: torque (N m) or force (N).
    viscous : str
        Force per velocity (a viscous coefficient).
    inertia : str
        Force per acceleration (inertia or mass).
    """

    axis: str
    position: str
    velocity: str
    acceleration: str
    force: str
    viscous: str
    inertia: str

    @property
    def effort(self) -> str:
        """What the target is called on this axis: ``"torque"`` (rotary) or ``"force"`` (linear)."""
        return "torque" if self.axis == "rotary" else "force"

    @property
    def motion(self) -> str:
        """What the position is called: ``"angle"`` (rotary) or ``"position"`` (linear)."""
        return "angle" if self.axis == "rotary" else "position"

    def of_role(self, role: str) -> str:
        """The unit of a signal with a role (position, velocity, acceleration, target); "1" otherwise."""
        return {"position": self.position, "velocity": self.velocity,
                "acceleration": self.acceleration, "target": self.force,
                "force": self.force}.get(role, "1")


AXES: dict[str, AxisUnits] = {
    "rotary": AxisUnits("rotary", "rad", "rad/s", "rad/s^2", "N m", "N m s/rad", "kg m^2"),
    "linear": AxisUnits("linear", "m", "m/s", "m/s^2", "N", "N s/m", "kg"),
}


def axis_units(axis: str = "rotary") -> AxisUnits:
    """The units of ``axis`` ("rotary", the default of every file and command, or "linear").

    Raises
    ------
    ValueError
        For another name (callers turn it into their file's or option's message).
    """
    try:
        return AXES[axis]
    except KeyError:
        raise ValueError(f"expected an axis of {' or '.join(AXES)}, found {axis!r}") from None

"""The kinds of physical term a model may be named by (Coulomb, viscous, ...).

One enum for the classifier (``engines.symbolic``), the probes
(``engines.physics``), the simulated plant's ground truth (``engines.plant``)
and the report. Its members are strings: they compare equal to, hash like,
print as and serialise to their value (``"coulomb"``), so JSON files and
messages read as before.
"""

from __future__ import annotations

import enum


class TermKind(str, enum.Enum):
    """A physical law a term may be named by; the value is its name in files and JSON."""

    COULOMB = "coulomb"
    STRIBECK = "stribeck"
    VISCOUS = "viscous"
    ACCELERATION = "acceleration"
    SPATIAL = "spatial"
    OFFSET = "offset"
    UNCLASSIFIED = "unclassified"

    # The value in text, on every Python (3.11 changed format() of mixed-in enums).
    def __str__(self) -> str:
        return self.value

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)

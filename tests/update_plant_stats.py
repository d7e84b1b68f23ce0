"""Regenerate tests/data/plant_stats.json, the pinned statistics of every plant log.

Run by hand only, after a deliberate change of the plant model, and review the diff:

    python tests/update_plant_stats.py

tests/test_plant.py compares against the file and never writes it.
"""

from __future__ import annotations

import json
from pathlib import Path

from edm_sym.engines.plant import EXCITATIONS, PRESETS, simulate_plant

STATS_FILE = Path(__file__).parent / "data" / "plant_stats.json"
SEED = 0


def compute() -> dict[str, object]:
    """Statistics of each preset x excitation log (seed 0, default options).

    Returns
    -------
    dict
        ``{"seed": 0, "logs": {"<preset>/<excitation>": PlantLog.statistics()}}``.
    """
    logs = {}
    for name in sorted(PRESETS):
        for excitation in EXCITATIONS:
            logs[f"{name}/{excitation}"] = simulate_plant(name, excitation, seed=SEED).statistics()
    return {"seed": SEED, "logs": logs}


def main() -> None:
    """Write the statistics file (sorted keys, full float precision)."""
    STATS_FILE.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(compute(), indent=1, sort_keys=True) + "\n"
    tmp = STATS_FILE.with_suffix(".json.tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(STATS_FILE)  # never leave a half-written file behind
    print(f"wrote {STATS_FILE}")


if __name__ == "__main__":
    main()

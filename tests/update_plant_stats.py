"""Pin the plant presets' log statistics: ``python tests/update_plant_stats.py``.

The only way tests/data/plant_stats.json changes; review the diff before committing.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from test_plant import STATS, statistics  # noqa: E402

from edm_sym.fileio import write_atomic  # noqa: E402
from edm_sym.plant import EXCITATIONS, PRESETS, simulate_plant  # noqa: E402


def main() -> int:
    doc = {f"{p}/{e}": statistics(simulate_plant(p, e)) for p in sorted(PRESETS) for e in EXCITATIONS}
    write_atomic(STATS, json.dumps(doc, sort_keys=True, indent=2) + "\n")
    print(STATS)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Where a data log comes from: a file, or the simulated plant.

A data spec is a path (CSV, .npz, .mat: read by :mod:`edm_sym.core.data`) or
``plant:PRESET/EXCITATION[@SEED]``, the log ``edm plant`` would write, simulated
on the fly (docs/data.md); PRESET is a named preset or ``family-N``, draw N of
the family of plants with known truth (docs/plant.md). Resolving the second needs the plant engine, so the
resolver lives here, one layer above the file readers (docs/architecture.md).
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from edm_sym.core import data as _files
from edm_sym.core.data import PLANT_SCHEME, ColumnRoles, DataLog, is_plant_spec, with_roles
from edm_sym.core.errors import DataFormatError
from edm_sym.engines.plant import EXCITATIONS, PRESETS, simulate_plant
from edm_sym.engines.plant.family import FAMILY_PREFIX, family_draw, resolve_preset

__all__ = ["load_data", "plant_log"]


def load_data(
    path: str | Path, *, ts: float | None = None, require: Iterable[str] = (),
    default_ts: float | None = None, columns: ColumnRoles | None = None,
    names: str | Sequence[str] | None = None,
) -> DataLog:
    """Read a log from a file, or simulate the plant log a ``plant:`` spec names.

    Parameters and errors as :func:`edm_sym.core.data.load_data`; ``path`` may
    also be ``"plant:PRESET/EXCITATION[@SEED]"`` (e.g. ``"plant:auger/evaluation"``).
    """
    if is_plant_spec(path):
        log = with_roles(plant_log(str(path)), columns)
        for col in require:
            log.column(col)
        return log
    return _files.load_data(path, ts=ts, require=require, default_ts=default_ts, columns=columns,
                            names=names)


def plant_log(spec: str) -> DataLog:
    """The log of ``edm plant`` that a ``plant:PRESET/EXCITATION[@SEED]`` spec names."""
    body = spec[len(PLANT_SCHEME):]
    body, _, seed_text = body.partition("@")
    preset, _, excitation = body.partition("/")
    if preset not in PRESETS and family_draw(preset) is None:
        raise DataFormatError(f"{spec}: preset", f"expected one of {', '.join(sorted(PRESETS))} "
                              f"or {FAMILY_PREFIX}N (a draw of the family), found {preset!r}")
    if excitation not in EXCITATIONS:
        raise DataFormatError(f"{spec}: excitation",
                              f"expected one of {', '.join(EXCITATIONS)}, found {excitation!r}")
    try:
        if "_" in seed_text:  # int() reads 1_0 as 10
            raise ValueError(seed_text)
        seed = int(seed_text) if seed_text else 0
    except ValueError:
        raise DataFormatError(f"{spec}: seed", f"expected an integer, found {seed_text!r}") from None
    if seed < 0:
        raise DataFormatError(f"{spec}: seed", f"expected an integer >= 0, found {seed}")
    plant = resolve_preset(preset)
    cols = dict(simulate_plant(plant, excitation, seed=seed).columns)
    digest = hashlib.sha256()
    for key, col in cols.items():
        digest.update(key.encode() + np.ascontiguousarray(col, dtype="<f8").tobytes())
    ts = float(cols["t"][1] - cols["t"][0])
    # The observer's bandwidth: what `edm describe` needs to take its lag out of tau_ext.
    return DataLog(cols, ts, spec, digest.hexdigest(),
                   {"observer_bandwidth": float(plant.g_rtob)})

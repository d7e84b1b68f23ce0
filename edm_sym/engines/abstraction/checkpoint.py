"""Checkpoints: the whole state of a run at a generation boundary, as JSON.

A checkpoint holds the finished steps, the current step's population with its
fitness values and counters, and the random generator's state, so a resumed
run draws exactly the numbers the uninterrupted run would have drawn. It is
written atomically at a generation boundary (every few seconds, at each step's
end and when the run stops; never half-written) and holds data only: loading
it evaluates nothing. It carries the sha256 of its own content, so a file
damaged or edited after it was written is refused as a whole when it is
loaded, not met later as a crash in the middle of the resumed run.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from edm_sym.core.errors import ConfigError
from edm_sym.core.fileio import parse_json, write_atomic
from edm_sym.engines.abstraction.ga import Population

FORMAT = "edm-abstraction-checkpoint"
#: 2: with ``sha256``, the digest of the rest of the document.
VERSION = 2


@dataclass
class StepState:
    """The state of the step being run, at a generation boundary."""

    step: int
    generation: int
    blocks: int
    block_start_best: float
    ref_best: float
    since_improvement: int
    done: bool
    population: Population
    fitness: np.ndarray
    history: list[float]
    evaluations: int
    restarts: int = 0


@dataclass
class FinishedStep:
    """A finished step: its best individual and what the result records."""

    step: int
    best: Population
    fitness: float
    history: list[float]
    generations: int
    evaluations: int
    weighting: dict[str, Any]


@dataclass
class RunState:
    """Everything needed to continue a run."""

    fingerprint: str
    rng_state: dict[str, Any]
    finished: list[FinishedStep] = field(default_factory=list)
    current: StepState | None = None


def _pop_json(pop: Population) -> dict[str, Any]:
    return {"inputs": pop.inputs.tolist(), "codes": pop.codes.tolist(), "ps": pop.ps.tolist()}


def _pop_from(doc: dict[str, Any]) -> Population:
    return Population(np.array(doc["inputs"], dtype=np.int64).reshape(np.shape(doc["inputs"])),
                      np.array(doc["codes"], dtype=np.int64).reshape(np.shape(doc["codes"])),
                      np.array(doc["ps"], dtype=float).reshape(np.shape(doc["ps"])))


def dumps(state: RunState) -> str:
    """The checkpoint text (floats written exactly: JSON keeps repr round-trips)."""
    cur = state.current
    doc: dict[str, Any] = {
        "format": FORMAT,
        "version": VERSION,
        "fingerprint": state.fingerprint,
        "rng_state": state.rng_state,
        "finished": [
            {"step": f.step, "best": _pop_json(f.best), "fitness": f.fitness,
             "history": f.history, "generations": f.generations,
             "evaluations": f.evaluations, "weighting": f.weighting}
            for f in state.finished
        ],
        "current": None if cur is None else {
            "step": cur.step, "generation": cur.generation, "blocks": cur.blocks,
            "block_start_best": cur.block_start_best, "ref_best": cur.ref_best,
            "since_improvement": cur.since_improvement, "done": cur.done,
            "population": _pop_json(cur.population), "fitness": cur.fitness.tolist(),
            "history": cur.history, "evaluations": cur.evaluations,
            "restarts": cur.restarts,
        },
    }
    doc["sha256"] = _digest(doc)
    return json.dumps(doc, sort_keys=True) + "\n"


def _digest(doc: dict[str, Any]) -> str:
    """sha256 of the document without its ``sha256`` (JSON, keys sorted: floats round-trip)."""
    body = {k: v for k, v in doc.items() if k != "sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode("utf-8")).hexdigest()


def save_checkpoint(path: str | Path, state: RunState) -> Path:
    """Write ``state`` to ``path`` atomically."""
    return write_atomic(path, dumps(state))


def load_checkpoint(path: str | Path, fingerprint: str) -> RunState:
    """Read a checkpoint written by :func:`save_checkpoint` for the same run.

    Parameters
    ----------
    path : path-like
        The checkpoint file.
    fingerprint : str
        The run's fingerprint (data, target, inputs, config, seed); a
        checkpoint of another run is refused.

    Raises
    ------
    ConfigError
        When the file is unreadable, not a checkpoint, or of another run.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(str(path), f"cannot be read ({exc.strerror})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(str(path), "expected a checkpoint (JSON), found binary data") from None
    # A checkpoint holds the fitness of failed individuals: infinities are written as such.
    doc = parse_json(text, str(path), ConfigError, finite=False)
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise ConfigError(f"{path}: format", f"expected {FORMAT!r} version {VERSION}, found "
                                             "something else")
    if doc.get("version") != VERSION:
        raise ConfigError(f"{path}: version",
                          f"expected {VERSION}, found {doc.get('version')!r} (a checkpoint of "
                          "another edm_sym release: delete it or drop --resume)")
    if doc.get("sha256") != _digest(doc):
        raise ConfigError(f"{path}: sha256", "expected the digest of the checkpoint's content, "
                                             "found another (the file was damaged or edited "
                                             "after it was written; delete it or drop --resume)")
    if doc.get("fingerprint") != fingerprint:
        raise ConfigError(f"{path}: fingerprint",
                          "expected a checkpoint of this run (same data, target, inputs, config "
                          "and seed), found one of another run (delete it or drop --resume)")
    try:
        finished = [FinishedStep(f["step"], _pop_from(f["best"]), float(f["fitness"]),
                                 [float(h) for h in f["history"]], int(f["generations"]),
                                 int(f["evaluations"]), dict(f["weighting"]))
                    for f in doc["finished"]]
        c = doc["current"]
        current = None if c is None else StepState(
            step=int(c["step"]), generation=int(c["generation"]), blocks=int(c["blocks"]),
            block_start_best=float(c["block_start_best"]), ref_best=float(c["ref_best"]),
            since_improvement=int(c["since_improvement"]), done=bool(c["done"]),
            population=_pop_from(c["population"]),
            fitness=np.array(c["fitness"], dtype=float),
            history=[float(h) for h in c["history"]], evaluations=int(c["evaluations"]),
            restarts=int(c.get("restarts", 0)))
        return RunState(doc["fingerprint"], doc["rng_state"], finished, current)
    except (KeyError, TypeError, ValueError) as exc:
        raise ConfigError(str(path), f"expected a complete checkpoint, found a damaged one ({exc})"
                          ) from None

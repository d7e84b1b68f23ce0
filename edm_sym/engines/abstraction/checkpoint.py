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

import glob
import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from edm_sym.core.errors import ConfigError
from edm_sym.core.fileio import json_kind, parse_json, read_utf8, write_atomic
from edm_sym.core.version import __version__
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
    #: With multi-fidelity evaluation: each individual's low-fidelity eq. 8 (``fitness``
    #: is then its eq. 8 on the whole training log, ``inf`` where it was not scored there).
    low: np.ndarray | None = None


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
    #: What the fingerprint is made of, to say what differs in a checkpoint of another run:
    #: ``data`` and ``config`` (digests), ``target``, ``inputs``, ``seed``.
    identity: dict[str, Any] = field(default_factory=dict)


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
        "identity": state.identity,
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
            # Multi-fidelity only: a run of full fidelity writes the checkpoint it always did.
            **({"low": cur.low.tolist()} if cur.low is not None else {}),
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


#: What a checkpoint of another run differs in, by the ``identity`` key.
_DIFFERENCES = {"data": "another data file (or sample time, or held-out share)",
                "config": "another config (or --searches)", "target": "another target",
                "inputs": "another input set", "seed": "another seed"}
_HINT = "delete it, or drop --resume to start afresh; the file is left as it was"


def read_checkpoint(path: str | Path) -> dict[str, Any]:
    """Read a checkpoint's document, refusing another format, version or a damaged file.

    It does not say whether the checkpoint is of the run at hand
    (:func:`load_checkpoint` does); it lets a command refuse a checkpoint
    before any other work, leaving the file as it was.

    Parameters
    ----------
    path : path-like
        The checkpoint file.

    Returns
    -------
    dict
        The document.

    Raises
    ------
    ConfigError
        Naming the file, and both versions for a checkpoint of another format version.
    """
    path = Path(path)
    text = read_utf8(path, ConfigError, where=str(path), expected="a checkpoint (JSON)")
    # A checkpoint holds the fitness of failed individuals: infinities are written as such.
    doc = parse_json(text, str(path), ConfigError, finite=False)
    from edm_sym.core.validation import show_value

    found = doc.get("format") if isinstance(doc, dict) else None
    if found != FORMAT:
        what = (f"format {show_value(found)}" if isinstance(doc, dict) and "format" in doc
                else "a JSON object without one" if isinstance(doc, dict) else json_kind(doc))
        raise ConfigError(f"{path}: format", f"expected {FORMAT!r} (version {VERSION}), found "
                                             f"{what}; {_HINT}")
    if doc.get("version") != VERSION or isinstance(doc.get("version"), bool):
        raise ConfigError(f"{path}: version",
                          f"expected checkpoint format version {VERSION} (edm_sym "
                          f"{__version__}), found version {show_value(doc.get('version'))} "
                          f"(a checkpoint of another edm_sym release); {_HINT}")
    if doc.get("sha256") != _digest(doc):
        raise ConfigError(f"{path}: sha256", "expected the digest of the checkpoint's content, "
                                             "found another (the file was damaged or edited "
                                             f"after it was written); {_HINT}")
    return doc


def _difference(doc: dict[str, Any], identity: dict[str, Any]) -> str:
    """What the run of ``doc`` differs in from the run of ``identity`` (both sides named)."""
    from edm_sym.core.validation import show_value

    theirs = doc.get("identity")
    if not isinstance(theirs, dict) or not identity:
        return "another data file, target, input set, config or seed"
    out = []
    # The training samples differ with the columns: the data is compared for the same columns.
    same_columns = all(theirs.get(k) == identity.get(k) for k in ("target", "inputs"))
    for key, what in _DIFFERENCES.items():
        if theirs.get(key) != identity.get(key) and (key != "data" or same_columns):
            if key in ("data", "config"):
                out.append(what)
            else:
                out.append(f"{what} ({show_value(theirs.get(key))}; this run: "
                           f"{show_value(identity.get(key))})")
    return ", ".join(out) or "another run"


def load_checkpoint(path: str | Path, fingerprint: str,
                    identity: dict[str, Any] | None = None) -> RunState:
    """Read a checkpoint written by :func:`save_checkpoint` for the same run.

    Parameters
    ----------
    path : path-like
        The checkpoint file.
    fingerprint : str
        The run's fingerprint (data, target, inputs, config, seed); a
        checkpoint of another run is refused.
    identity : dict, optional
        What the fingerprint is made of (:attr:`RunState.identity`), to name
        what differs in a checkpoint of another run.

    Raises
    ------
    ConfigError
        When the file is unreadable, not a checkpoint, of another format
        version, or of another run (naming what differs).
    """
    path = Path(path)
    doc = read_checkpoint(path)
    if doc.get("fingerprint") != fingerprint:
        raise ConfigError(f"{path}: fingerprint",
                          "expected a checkpoint of this run (same data, target, inputs, config "
                          f"and seed), found one of {_difference(doc, identity or {})}; {_HINT}")
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
            restarts=int(c.get("restarts", 0)),
            low=np.array(c["low"], dtype=float) if c.get("low") is not None else None)
        return RunState(doc["fingerprint"], doc["rng_state"], finished, current,
                        dict(identity or doc.get("identity") or {}))
    except (KeyError, TypeError, ValueError) as exc:
        raise ConfigError(str(path), f"expected a complete checkpoint, found a damaged one ({exc})"
                          ) from None


def stray_checkpoints(checkpoint: Path | None, count: int) -> list[Path]:
    """Checkpoints beside ``checkpoint`` of a run of another number of searches.

    One search keeps ``checkpoint`` itself; several keep ``<checkpoint>.search<k>``
    (:func:`edm_sym.engines.abstraction.searches.checkpoint_files`).
    """
    if checkpoint is None:
        return []
    checkpoint = Path(checkpoint)
    out = [checkpoint] if count > 1 and checkpoint.exists() else []
    for f in sorted(checkpoint.parent.glob(glob.escape(checkpoint.name) + ".search*")):
        k = f.name[len(checkpoint.name) + len(".search"):]
        if k.isdigit() and (count == 1 or int(k) >= count):
            out.append(f)
    return out


def check_resume(checkpoint: Path | None, files: Sequence[Path | None],
                 runs: Sequence[tuple[str, dict[str, Any]]]) -> None:
    """Refuse, before a resumed run starts, a checkpoint it cannot continue.

    Parameters
    ----------
    checkpoint : pathlib.Path or None
        The run's checkpoint name.
    files : sequence of pathlib.Path or None
        Each search's checkpoint file.
    runs : sequence of (str, dict)
        Each search's fingerprint and identity.

    Raises
    ------
    ConfigError
        Naming the checkpoint: another format version (both named), a damaged
        file, a checkpoint of another run (what differs named), or checkpoints
        of a run of another number of searches. Nothing is written.
    """
    present = [(f, run) for f, run in zip(files, runs, strict=True) if f is not None and f.exists()]
    for f, (fingerprint, identity) in present:
        load_checkpoint(f, fingerprint, identity)
    stray = stray_checkpoints(checkpoint, len(files))
    if stray and not present:
        theirs = "one search" if stray[0] == checkpoint else "several searches"
        ours = "one search" if len(files) == 1 else f"{len(files)} searches"
        raise ConfigError(str(stray[0]), f"expected a checkpoint of this run of {ours} "
                                         f"({Path(files[0]).name}), found one of a run of "
                                         f"{theirs} (another config's searches, or --searches); "
                                         f"{_HINT}")

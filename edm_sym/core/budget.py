"""Up-front estimates of memory and time: work that cannot fit is refused before it starts.

Every command that can be asked for more than a machine has estimates its
work from the sizes alone, before any long work, and refuses it with
:class:`~edm_sym.core.errors.BudgetError` (exit 2) and the figures in the
message (docs/cli.md#sizes-that-cannot-fit):

* the abstraction (``edm abstract``, ``edm pipeline``, ``EDMRegressor``):
  its peak memory (the row store and caches, a generation's rows, the data)
  against the memory this machine has available, and the least CPU time the
  schedule needs against :data:`TIME_LIMIT_SECONDS`, at the fidelity the run
  will have (a run of multi fidelity: its two evaluators);
* the reference simulator (``edm simulate``): its row outputs against the
  available memory;
* reading a log (every command): the file, its text and its columns against
  the available memory, before the values are parsed;
* export: the state a compensator keeps (its delay lines above all) against
  :data:`STATE_LIMIT_BYTES`; above :data:`STATE_WARN_BYTES` a
  :class:`~edm_sym.core.errors.BudgetWarning` gives the figure.

The figures are estimates from sizes, not measurements; the limits leave a
wide margin, so only work that is out of all proportion is refused.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from edm_sym.core.errors import BudgetError, BudgetWarning

#: Element-samples (one element on one sample) the batched GA evaluation simulates per
#: second on one core: measured on the auger log (benchmarks/bench_ga.py prints it),
#: rounded; the time estimates divide by it.
ELEMENT_SAMPLES_PER_SECOND = 2e7

#: The least CPU time a run may need; more is refused (a week).
TIME_LIMIT_SECONDS = 7 * 86400.0

#: Largest state a compensator may keep (the C state struct, the Python module's
#: buffers): 256 MiB. A larger one is refused at export.
STATE_LIMIT_BYTES = 256 * 2**20

#: Above this state (1 MiB, more than the RAM of most microcontrollers) export warns.
STATE_WARN_BYTES = 2**20

#: Bytes of one real of each C type.
REAL_BYTES = {"double": 8, "float": 4, "q31": 8, "q15": 6}  # fixed: a word and a 32-bit feedback word


def format_bytes(n: float) -> str:
    """``n`` bytes for a message: ``"74.5 GiB"``, ``"512 B"``."""
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} B"


def format_seconds(s: float) -> str:
    """A duration for a message: ``"41 days"``, ``"3.2 h"``, ``"12 s"``."""
    for unit, size in (("years", 365 * 86400.0), ("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if s >= size:
            return f"{s / size:.3g} {unit}"
    return f"{s:.3g} s"


def available_memory() -> int | None:
    """Bytes of memory this machine can give a new job, or None when unknown.

    ``MemAvailable`` of ``/proc/meminfo`` (Linux); else the physical memory.
    """
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):  # pragma: no cover (not POSIX)
        return None


@dataclass(frozen=True)
class Estimate:
    """What a piece of work needs, from its sizes.

    Attributes
    ----------
    memory : int
        Peak memory [bytes].
    seconds : float
        The least CPU time [s] (0 when not estimated).
    detail : str
        What the figures are made of, for the message.
    """

    memory: int
    seconds: float = 0.0
    detail: str = ""


@dataclass(frozen=True)
class StepSize:
    """The sizes of one hierarchical step of the abstraction.

    Attributes
    ----------
    population, n_rows, n_elements : int
        Individuals per generation and the matrix size m x n.
    generations : int
        The least number of generations the step runs (without a time limit).
    """

    population: int
    n_rows: int
    n_elements: int
    generations: int


@dataclass(frozen=True)
class MultiFidelitySize:
    """The sizes of a multi-fidelity run's two evaluators (docs/abstraction.md#multi-fidelity-evaluation).

    Attributes
    ----------
    window_samples : int
        Samples of the low-fidelity signal, the windows with their warm-ups (at most
        the training log's).
    promote : int
        The most new individuals of a generation scored on the whole training log.
    full_batch : int
        Rows of the whole log's evaluator's largest batch (a few promoted individuals).
    """

    window_samples: int
    promote: int
    full_batch: int


def _evaluator_memory(cache_bytes: int, batch: int, row: int, workers: int) -> int:
    """One evaluator's peak: its shared row store (twice its largest batch's rows, at least
    its cache), each worker's prefix cache (half its cache) and a batch's row outputs."""
    return max(cache_bytes, (2 * batch + 16) * row) + workers * cache_bytes // 2 + batch * row


def abstraction_estimate(steps: Sequence[StepSize], *, n_samples: int, n_inputs: int,
                         cache_bytes: int, workers: int, time_limit: float | None,
                         multi: MultiFidelitySize | None = None) -> Estimate:
    """Peak memory and least CPU time of an abstraction run.

    Memory: the shared row store (twice the largest generation's rows, at
    least the cache), each worker's prefix cache (half the cache), a
    generation's row outputs, the population's genes and the data. Time:
    every generation simulates each individual's every element on every
    sample (no cache hits), at :data:`ELEMENT_SAMPLES_PER_SECOND`; each step
    runs its initial population and its least generations, or, with a time
    limit, only step 1's initial population is sure to run.

    With ``multi`` (a run of multi fidelity) the run has two evaluators, each
    sized as above: the whole log's, with a quarter of the cache and batches
    of ``multi.full_batch`` rows of ``n_samples``, and the windows', with
    half the cache and a generation's rows of ``multi.window_samples``
    samples; the data is counted once more on the windows. A generation
    simulates every individual on the windows and ``multi.promote`` of them
    (at most the population) on the whole log.

    Parameters
    ----------
    steps : sequence of StepSize
    n_samples : int
        Samples the GA fits (N).
    n_inputs : int
        Input columns.
    cache_bytes : int
        The config's row cache bound.
    workers : int
        Processes evaluating the population.
    time_limit : float, optional
        The run's wall-time limit [s].
    multi : MultiFidelitySize, optional
        The run's multi-fidelity sizes; None: a run of full fidelity.
    """
    n = max(1, int(n_samples))
    batch = max(s.population * s.n_rows for s in steps)
    genes = max(s.population * s.n_rows * (1 + 2 * s.n_elements) for s in steps)
    row = 8 * n
    if multi is None:
        memory = _evaluator_memory(cache_bytes, batch, row, workers)
        per_gen = [s.population * s.n_rows * s.n_elements * n for s in steps]
    else:
        low = max(1, min(n, int(multi.window_samples)))
        memory = (_evaluator_memory(cache_bytes // 4, multi.full_batch, row, workers)
                  + _evaluator_memory(cache_bytes // 2, batch, 8 * low, workers)
                  + (n_inputs + 2) * 8 * low)
        per_gen = [s.n_rows * s.n_elements * (s.population * low
                                              + min(s.population, multi.promote) * n)
                   for s in steps]
    memory += 32 * genes + (n_inputs + 4) * row
    if time_limit is not None:
        element_samples = per_gen[0]
    else:
        element_samples = sum((s.generations + 1) * g for s, g in zip(steps, per_gen, strict=True))
    seconds = element_samples / ELEMENT_SAMPLES_PER_SECOND
    big = max(range(len(steps)), key=lambda k: per_gen[k])
    s = steps[big]
    detail = (f"step[{big}]: population {s.population} x {s.n_rows} rows x {s.n_elements} "
              f"elements x {n} samples a generation")
    if multi is not None:
        detail = (f"step[{big}], multi fidelity: population {s.population} x {s.n_rows} rows x "
                  f"{s.n_elements} elements x {low} samples of windows a generation, "
                  f"{min(s.population, multi.promote)} of them x {n} samples")
    return Estimate(int(memory), seconds, detail)


def simulation_estimate(*, n_samples: int, n_rows: int, n_inputs: int) -> Estimate:
    """Peak memory of the reference simulator on a log: every row's output and the inputs.

    Parameters
    ----------
    n_samples : int
        Samples of the log.
    n_rows : int
        Rows of the matrix.
    n_inputs : int
        Input columns.
    """
    memory = 8 * max(1, int(n_samples)) * (2 * n_rows + n_inputs + 4)
    return Estimate(int(memory), 0.0, f"{n_rows} rows x {n_samples} samples")


def log_estimate(*, file_bytes: int, n_samples: int, n_columns: int) -> Estimate:
    """Peak memory of reading a log and working on it (``edm simulate``, ``edm describe``,
    ``edm-export --data``): the file, its text, and its columns three times over (the
    columns read, the inputs stacked, the outputs made from them).

    Parameters
    ----------
    file_bytes : int
        Size of the file.
    n_samples, n_columns : int
        Rows of data and columns of the log (at most, when estimated from the file).
    """
    memory = 2 * int(file_bytes) + 3 * 8 * max(1, int(n_samples)) * max(1, int(n_columns))
    return Estimate(int(memory), 0.0, f"{n_samples} samples x {n_columns} columns, a "
                                      f"{format_bytes(file_bytes)} file")


#: What to make smaller when a log does not fit.
LOG_HINT = "use a shorter log (split it in time) or a machine with more memory"


def check(estimate: Estimate, where: str, hint: str, *, time_hint: str | None = None,
          memory: int | None = -1) -> None:
    """Refuse work that does not fit: its memory or its least CPU time.

    Parameters
    ----------
    estimate : Estimate
    where : str
        The file and key (or option) whose sizes ask for the work.
    hint : str
        What to make smaller (for memory).
    time_hint : str, optional
        What to make smaller for time (default: ``hint``).
    memory : int, optional
        The memory available [bytes]; default: :func:`available_memory`; None: unknown.

    Raises
    ------
    BudgetError
        With the figures.
    """
    avail = available_memory() if memory == -1 else memory
    if avail is not None and estimate.memory > avail:
        raise BudgetError(where, f"needs about {format_bytes(estimate.memory)} of memory "
                                 f"({estimate.detail}), more than the {format_bytes(avail)} "
                                 f"this machine has available; {hint}")
    if estimate.seconds > TIME_LIMIT_SECONDS:
        raise BudgetError(where, f"needs at least about {format_seconds(estimate.seconds)} of CPU "
                                 f"time ({estimate.detail}), more than the limit of "
                                 f"{format_seconds(TIME_LIMIT_SECONDS)}; {time_hint or hint}")


def state_bytes(sizes: Iterable[int], real: str) -> int:
    """Bytes of a compensator's state: ``sizes`` reals of type ``real`` (and their indices).

    Parameters
    ----------
    sizes : iterable of int
        Each stage's state size in reals (a delay line's length, a filter's order).
    real : {"float", "double", "q31", "q15"}
    """
    return sum(REAL_BYTES[real] * int(k) + (8 if k > 1 else 0) for k in sizes)


def check_state(sizes: Iterable[int], real: str, where: str) -> int:
    """Refuse a state above :data:`STATE_LIMIT_BYTES`, warn above :data:`STATE_WARN_BYTES`.

    Parameters
    ----------
    sizes : iterable of int
        Each stage's state size in reals.
    real : {"float", "double"}
        The real type of the state.
    where : str
        The result file, for the message.

    Returns
    -------
    int
        The state's bytes.

    Raises
    ------
    BudgetError
        When the state exceeds :data:`STATE_LIMIT_BYTES`.
    """
    sizes = list(sizes)
    total = state_bytes(sizes, real)
    largest = max(sizes, default=0)
    detail = f"the longest delay line holds {largest} samples" if largest > 1 else ""
    if total > STATE_LIMIT_BYTES:
        raise BudgetError(where, f"the compensator's state needs {format_bytes(total)} in {real} "
                                 f"({detail}), more than the limit of "
                                 f"{format_bytes(STATE_LIMIT_BYTES)}; shorten the dead time "
                                 f"(its range) or use a longer sample time")
    if total > STATE_WARN_BYTES:
        warnings.warn(BudgetWarning(
            f"{where}: the compensator's state needs {format_bytes(total)} in {real} ({detail}), "
            f"more than the RAM of most microcontrollers"), stacklevel=3)
    return total


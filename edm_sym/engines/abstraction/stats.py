"""The evaluator's counters (for progress lines and benchmarks)."""

from __future__ import annotations

from dataclasses import dataclass, field, fields


@dataclass
class EvalStats:
    """Counters of an evaluator (for progress lines and benchmarks).

    ``elements_simulated`` counts elements run over the signal (a row that
    starts from a stored prefix runs only its other elements),
    ``element_samples`` the rows simulated times their elements and samples.
    ``eval_seconds`` is the wall time spent in :meth:`Evaluator.evaluation`
    (simulation and scoring, in whichever process), ``sim_seconds`` and
    ``task_seconds`` the time the workers spent simulating rows and running
    tasks, summed over workers; ``peak_rss`` the peak resident memory of
    each process that ran a task, by process id.

    How much of a run the lanes share, for judging a speed-up:
    ``spread_seconds`` is the wall time from a batch's first piece sent to
    another lane until its last answer, summed over batches (the time the
    run can use more than one core); ``wait_seconds`` the part of it this
    process spent waiting for those answers once its own piece was done.
    The rest of a run's wall time is this process alone: the GA, the local
    search's single evaluations and the planning of each batch.
    ``idle_seconds`` is the imbalance the cut of each batch left: summed
    over its lanes, the time each lane sat finished while the last one still
    worked (batches whose lanes all share this machine's clock: this process
    and the lanes with shared stores).

    ``scored`` counts the individuals whose eq. 8 was computed (a remembered
    one is not, a gain-fit candidate is), ``full_log`` those of them scored
    on the whole training log: all of them with ``fidelity = "full"``, the
    promoted ones with multi-fidelity evaluation
    (docs/abstraction.md#multi-fidelity-evaluation).
    """

    individuals: int = 0
    row_requests: int = 0
    rows_missed: int = 0
    rows_simulated: int = 0
    elements_simulated: int = 0
    element_samples: int = 0
    sim_seconds: float = 0.0
    task_seconds: float = 0.0
    eval_seconds: float = 0.0
    spread_seconds: float = 0.0
    wait_seconds: float = 0.0
    idle_seconds: float = 0.0
    tasks: int = 0
    peak_rss: dict = field(default_factory=dict)
    scored: int = 0
    full_log: int = 0

    @staticmethod
    def merged(parts: list[EvalStats]) -> EvalStats:
        """The counters of several evaluators of one run added up (peak memory: the
        largest per process)."""
        out = EvalStats()
        for part in parts:
            for f in fields(EvalStats):
                if f.name == "peak_rss":
                    for pid, rss in part.peak_rss.items():
                        out.peak_rss[pid] = max(out.peak_rss.get(pid, 0), rss)
                else:
                    setattr(out, f.name, getattr(out, f.name) + getattr(part, f.name))
        return out

    @property
    def full_log_share(self) -> float:
        """Share of the individuals scored that were scored on the whole training log."""
        return self.full_log / self.scored if self.scored else 0.0

    @property
    def cache_hits(self) -> int:
        """Row requests served without simulating (store, memo or a twin in the batch)."""
        return self.row_requests - self.rows_missed

    @property
    def hit_rate(self) -> float:
        """Share of row requests served without simulating."""
        return self.cache_hits / self.row_requests if self.row_requests else 0.0

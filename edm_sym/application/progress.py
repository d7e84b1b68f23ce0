"""Progress of the long commands, rendered (docs/cli.md#progress-and-summary).

The engines print nothing: the abstraction calls ``callback(GenerationInfo)``
after every generation and the LuGre identification ``progress(LuGreProgress)``
after every evaluation. :class:`ProgressReporter` renders those reports:

* on a terminal, a tqdm bar on stderr (generations, with the step, the best
  fitness and the evaluations per second in its description);
* elsewhere (a log file, CI), one plain line every ``interval`` seconds (and
  at each new step): the step, the generation, the best fitness, the
  evaluations per second and the time left;
* with ``quiet``, nothing.

The time left of the abstraction is an estimate: the generations the run
still needs if its best stopped improving now (the stopping rule decides, see
:attr:`GenerationInfo.generations_left`) at the speed so far, capped by the
time limit.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import IO, Any

__all__ = ["ProgressReporter", "format_seconds"]


def format_seconds(seconds: float) -> str:
    """A duration for people: ``42s``, ``3m05s``, ``1h02m``."""
    s = max(0, int(round(seconds)))
    if s < 60:
        return f"{s}s"
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{s % 3600 // 60:02d}m"


def _is_tty(stream: IO[str]) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class ProgressReporter:
    """Renders engine progress as a bar (terminal), plain lines (elsewhere) or nothing.

    Parameters
    ----------
    prog : str
        The command, which starts every plain line (``edm abstract``).
    quiet : bool, default False
        Show nothing.
    stream : file, optional
        Where to write (default: standard error).
    interval : float, default 5.0
        Seconds between two plain lines.
    unit : str, default ""
        The fitness's unit (the target's, e.g. ``N m``).
    bar : bool, optional
        Force the bar (True) or the lines (False); default: the bar exactly
        when ``stream`` is a terminal.
    clock : callable, optional
        The clock (default :func:`time.monotonic`), for tests.

    Examples
    --------
    >>> reporter = ProgressReporter("edm abstract", stream=sys.stderr)  # doctest: +SKIP
    >>> with reporter:                                                   # doctest: +SKIP
    ...     result = abstract(data, target="tau", inputs=["omega"], callback=reporter.abstraction)
    """

    def __init__(self, prog: str, *, quiet: bool = False, stream: IO[str] | None = None,
                 interval: float = 5.0, unit: str = "", bar: bool | None = None,
                 clock: Callable[[], float] = time.monotonic):
        self.prog = prog
        self.stream = stream if stream is not None else sys.stderr
        self.interval = float(interval)
        self.unit = f" {unit}" if unit else ""
        self.clock = clock
        if quiet:
            self.mode = "off"
        elif bar if bar is not None else _is_tty(self.stream):
            self.mode = "bar"
        else:
            self.mode = "lines"
        self._bar: Any = None
        self._last_line: float | None = None
        self._last_key: object = None
        self._last_by_key: dict[object, float] = {}
        self._generations = 0
        self.lines_written = 0

    # -- the callbacks --------------------------------------------------------
    def abstraction(self, info: Any) -> None:
        """Callback of :func:`edm_sym.engines.abstraction.abstract` (never stops the run)."""
        if self.mode == "off":
            return
        self._generations += 1
        elapsed = info.elapsed
        rate = info.stats.individuals / elapsed if elapsed > 0 else 0.0
        per_gen = elapsed / self._generations
        left = info.generations_left * per_gen
        if info.time_limit is not None:
            left = min(left, max(0.0, info.time_limit - elapsed))
        n_el, n_rows = info.shape
        where = f"step {info.step}/{info.steps} ({n_el}x{n_rows}) gen {info.generation}"
        if info.searches > 1:  # several searches side by side: each reports its own
            where = f"search {info.search + 1}/{info.searches} {where}"
        if self.mode == "bar":
            bar = self._tqdm("gen")
            bar.total = bar.n + 1 + info.generations_left
            bar.set_description_str(f"{where} | best {info.best:.6g}{self.unit} | "
                                    f"{rate:.0f} eval/s", refresh=False)
            bar.update(1)
            return
        self._line((info.search, info.step),
                   f"{where} | best {info.best:.6g}{self.unit} | {rate:.0f} eval/s"
                   f" | time left ~{format_seconds(left)} | elapsed {format_seconds(elapsed)}")

    def lugre(self, info: Any) -> None:
        """``progress`` of :func:`edm_sym.engines.lugre.identify_lugre`."""
        if self.mode == "off":
            return
        elapsed = info.elapsed
        rate = info.evaluations / elapsed if elapsed > 0 else 0.0
        left = None
        if info.budget is not None and rate > 0:
            left = max(0, info.budget - info.evaluations) / rate
        if info.deadline_in is not None:
            left = info.deadline_in if left is None else min(left, info.deadline_in)
        where = f"{info.method} gen {info.generation}"
        if self.mode == "bar":
            bar = self._tqdm("eval", key=info.method)
            if info.budget is not None:
                bar.total = max(info.budget, info.evaluations)
            bar.set_description_str(f"LuGre {where} | best {info.best:.6g}{self.unit}",
                                    refresh=False)
            bar.update(info.evaluations - bar.n)
            return
        left_text = "time left: the stopping rule decides" if left is None \
            else f"time left <= {format_seconds(left)}"
        self._line(info.method, f"LuGre {where} | best {info.best:.6g}{self.unit} | "
                                f"{rate:.0f} eval/s | {left_text} | "
                                f"elapsed {format_seconds(elapsed)}")

    # -- rendering --------------------------------------------------------------
    def _tqdm(self, unit: str, key: object = None) -> Any:
        if self._bar is not None and key != self._last_key:
            self._bar.close()
            self._bar = None
        if self._bar is None:
            from tqdm import tqdm

            self._bar = tqdm(unit=unit, file=self.stream, dynamic_ncols=True, leave=True)
            self._last_key = key
        return self._bar

    def _line(self, key: object, text: str) -> None:
        now = self.clock()
        # A line per key (a step; a search's step) at most every interval: the searches
        # of a run report in turns, each at its own pace.
        last = self._last_by_key.get(key)
        if last is not None and now - last < self.interval:
            return
        self._last_line, self._last_key = now, key
        self._last_by_key[key] = now
        print(f"{self.prog}: {text}", file=self.stream, flush=True)
        self.lines_written += 1

    def close(self) -> None:
        """Close the bar (if any); plain lines need no closing."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> ProgressReporter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

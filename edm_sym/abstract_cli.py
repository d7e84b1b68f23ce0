"""``edm abstract``: the command-line side of the abstraction (docs/cli.md#edm-abstract).

Bad input (config, columns, options) raises :class:`~edm_sym.errors.ConfigError`
or :class:`~edm_sym.errors.DataFormatError`, which ``edm`` prints as one line
with exit status 2. A time limit ends the run with exit 0, Ctrl-C (or
SIGTERM) with exit 1; both write the best result found so far, and the
checkpoint ``<output>.checkpoint`` lets ``--resume`` continue the run to the
result an uninterrupted run gives.
"""

from __future__ import annotations

import argparse
import signal
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from edm_sym.errors import ConfigError

if TYPE_CHECKING:
    from edm_sym.result import EdmResult


def checkpoint_path(output: str | Path) -> Path:
    """The checkpoint next to an output file: ``<output>.checkpoint``."""
    out = Path(output)
    return out.with_name(out.name + ".checkpoint")


def _raise_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def _warn_bounds(result: EdmResult, output: Path) -> None:
    """The closing summary's flags: parameters at their range bounds (docs/describe.md)."""
    from edm_sym.bounds import bound_summary

    lines = bound_summary(result.compensator)
    for line in lines:
        print(f"edm abstract: warning: {line}", file=sys.stderr)
    if lines:
        print(f"edm abstract: see `edm describe {output}` for every row's flags", file=sys.stderr)


def run_cli(args: argparse.Namespace) -> int:
    """Run ``edm abstract`` with parsed arguments.

    Parameters
    ----------
    args : argparse.Namespace
        ``data``, ``target``, ``inputs`` (comma-separated), ``config``,
        ``seed``, ``time_limit``, ``output``, ``ts``, ``resume``, ``quiet``,
        ``workers``.

    Returns
    -------
    int
        0 when done (also at the time limit), 130 when interrupted (the best
        result so far is written anyway, and the checkpoint kept).
    """
    from edm_sym.abstraction.run import abstract
    from edm_sym.abstraction.schedule import default_config, load_config
    from edm_sym.data import load_data
    from edm_sym.result import save_result

    config = load_config(args.config) if args.config else default_config()
    inputs = [name.strip() for name in str(args.inputs).split(",")]
    if not all(inputs):
        raise ConfigError("--inputs", f"expected comma-separated column names, found "
                                      f"{args.inputs!r}")
    if args.workers is not None and args.workers < 1:
        raise ConfigError("--workers", f"expected an integer >= 1, found {args.workers}")
    if args.seed < 0:
        raise ConfigError("--seed", f"expected an integer >= 0, found {args.seed}")
    data = load_data(args.data, ts=args.ts)
    data.column(args.target, role="target column")
    data.stack(inputs)
    output = Path(args.output)
    ckpt = checkpoint_path(output)
    if args.resume and not ckpt.exists():
        print(f"edm abstract: no checkpoint {ckpt}; starting from the beginning",
              file=sys.stderr)
    progress = not args.quiet and sys.stderr.isatty()
    old = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        result = abstract(data, target=args.target, inputs=inputs, config=config,
                          seed=args.seed, time_limit=args.time_limit, progress=progress,
                          checkpoint=ckpt, resume=args.resume, workers=args.workers)
    finally:
        signal.signal(signal.SIGTERM, old)
    save_result(result, output)
    reason = result.provenance.get("stop_reason")
    if reason == "interrupted":
        print(f"edm abstract: interrupted; wrote the best so far to {output} "
              f"(continue with --resume)", file=sys.stderr)
    elif reason == "time_limit":
        print("edm abstract: time limit reached; wrote the best so far", file=sys.stderr)
    print(f"wrote {output}")
    print(f"fitness {result.fitness:.10g}")
    _warn_bounds(result, output)
    return 130 if reason == "interrupted" else 0

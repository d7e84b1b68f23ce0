"""Which template makes which file, and writing them.

:data:`TARGETS` is the fixed table: per export target, the context builder
and the (template, file name pattern) pairs it renders. Every file of a call
is rendered in memory first; only then is the output folder created and each
file written atomically, so a failure leaves no half-written file.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from edm_sym.core.errors import OutputError
from edm_sym.core.fileio import write_atomic
from edm_sym.outputs.render.context import FIXED_REALS, c_context, python_context
from edm_sym.outputs.render.environment import environment
from edm_sym.outputs.render.fixed_context import fixed_c_context, kit_context


@dataclass(frozen=True)
class Output:
    """One generated file: its template and its name pattern (``{prefix}`` is substituted)."""

    template: str
    filename: str


@dataclass(frozen=True)
class Target:
    """An export target: how to build its context and the files it renders.

    Attributes
    ----------
    context : callable
        ``context(model, source, prefix=..., real=...) -> dict``.
    outputs : tuple of Output
    """

    context: Callable[..., dict[str, Any]]
    outputs: tuple[Output, ...]


def _python(model: Any, source: Any, *, prefix: str, real: str) -> dict[str, Any]:
    return python_context(model, source, prefix=prefix)  # Python has one real type


#: The fixed table of code targets; "latex" (the report) is written by the report package.
TARGETS: Mapping[str, Target] = {
    "c": Target(c_context, (Output("c_header.h.j2", "{prefix}.h"),
                            Output("c_source.c.j2", "{prefix}.c"))),
    "python": Target(_python, (Output("python_module.py.j2", "{prefix}.py"),)),
    "test": Target(kit_context, (Output("c_test.c.j2", "{prefix}_test.c"),)),
}

#: The targets whose fixed-point builds (``--real q31``/``q15``) use other templates.
FIXED_TARGETS: Mapping[str, Target] = {
    "c": Target(fixed_c_context, (Output("c_fixed_header.h.j2", "{prefix}.h"),
                                  Output("c_fixed_source.c.j2", "{prefix}.c"))),
}

#: The targets whose context takes the fixed-point options (``build``, ``input_range``).
_OPTIONS = ("test",)

#: What ``--target all`` writes, in this order (targets not in TARGETS yet are skipped).
ALL = ("c", "python", "latex")


def render_target(name: str, model: Any, source: Any, *, prefix: str,
                  real: str, options: Mapping[str, Any] | None = None) -> dict[str, str]:
    """Render every file of target ``name``: file name -> text.

    ``options`` (``build``, ``input_range``) go to the fixed-point and kit contexts.
    """
    fixed = real in FIXED_REALS and name in FIXED_TARGETS
    target = FIXED_TARGETS[name] if fixed else TARGETS[name]
    extra = dict(options or {}) if fixed or name in _OPTIONS else {}
    ctx = target.context(model, source, prefix=prefix, real=real, **extra)
    env = environment()
    return {out.filename.format(prefix=prefix): env.get_template(out.template).render(ctx)
            for out in target.outputs}


def write_files(out_dir: str | Path, files: Mapping[str, str]) -> list[Path]:
    """Create ``out_dir`` and write ``files`` (name -> text) into it atomically.

    Raises
    ------
    OutputError
        When the folder cannot be created or a file cannot be written.
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{out}: cannot create the output folder "
                          f"({exc.strerror or type(exc).__name__})") from None
    written = []
    for name, text in files.items():
        try:
            written.append(write_atomic(out / name, text))
        except OSError as exc:
            raise OutputError(f"{out / name}: cannot write the file "
                              f"({exc.strerror or type(exc).__name__})") from None
    return written

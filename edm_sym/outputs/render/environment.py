"""The one jinja2 environment of edm_sym.

Templates live in the repository's top-level ``templates/`` folder; a wheel
installs that folder as ``edm_sym/templates`` (see ``[tool.setuptools]`` in
pyproject.toml). :func:`template_dir` finds whichever is present.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import jinja2

from edm_sym.core.errors import ToolMissingError

#: A file every complete template folder holds.
_MARKER = "c_source.c.j2"


def template_dir() -> Path:
    """The folder holding the templates: installed inside the package, or the source tree's.

    Raises
    ------
    ToolMissingError
        When neither exists (a broken installation).
    """
    package = Path(__file__).resolve().parents[2]  # .../edm_sym
    for candidate in (package / "templates", package.parent / "templates"):
        if (candidate / _MARKER).is_file():
            return candidate
    raise ToolMissingError(f"the code templates are missing (looked in {package / 'templates'} "
                           f"and {package.parent / 'templates'}); reinstall edm_sym")


@lru_cache(maxsize=1)
def environment() -> jinja2.Environment:
    """The jinja2 environment every template is rendered with.

    Undefined names are errors (StrictUndefined), nothing is escaped (the
    output is code, not HTML), block tags take their own line's newline and
    indentation (trim_blocks, lstrip_blocks), a template's final newline is
    kept, and newlines are ``\\n`` on every platform.
    """
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(template_dir())),
        undefined=jinja2.StrictUndefined,
        autoescape=False,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        newline_sequence="\n",
        auto_reload=False,
    )

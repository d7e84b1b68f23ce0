"""Compiling the report with latexmk, and reading what LaTeX said about it.

:func:`compile_pdf` runs ``latexmk -pdf -interaction=nonstopmode -halt-on-error``
in the report's folder with ``SOURCE_DATE_EPOCH=0`` (the template also omits
the PDF dates and trailer id), parses the log (:class:`LatexLog`: errors,
overfull boxes, undefined references) and removes latexmk's auxiliary files,
keeping the .tex, the figures and the .pdf.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from edm_sym.core.errors import ExternalToolError, ToolMissingError

#: The LaTeX packages the report template loads, each with the Debian package that
#: ships its .sty (checked against ``dpkg -S`` by tests/test_report_pdf.py; ``edm
#: doctor`` lists them as found or missing). ``lmodern`` is only a *Recommends* of
#: TeX Live, so an install with ``--no-install-recommends`` must name it.
LATEX_PACKAGES: dict[str, str] = {
    "adjustbox": "texlive-latex-extra",
    "amsmath": "texlive-latex-base",
    "amssymb": "texlive-base",
    "array": "texlive-latex-base",
    "booktabs": "texlive-latex-recommended",
    "caption": "texlive-latex-recommended",
    "float": "texlive-latex-recommended",
    "fontenc": "texlive-latex-base",
    "fvextra": "texlive-latex-extra",
    "geometry": "texlive-latex-base",
    "graphicx": "texlive-latex-base",
    "hyperref": "texlive-latex-base",
    "lmodern": "lmodern",
    "microtype": "texlive-latex-recommended",
    "placeins": "texlive-latex-extra",
    "tabularx": "texlive-latex-base",
    "tikz": "texlive-pictures",
}

#: Debian packages that give latexmk, pdfLaTeX and every package of LATEX_PACKAGES.
LATEX_APT = ("latexmk", *sorted(set(LATEX_PACKAGES.values())))

#: How to get latexmk and the LaTeX packages the report uses.
INSTALL_HINT = ("install TeX Live with latexmk, e.g. 'sudo apt-get install "
                + " ".join(LATEX_APT) + "' (Debian/Ubuntu) or "
                "'tlmgr install latexmk lm adjustbox fvextra pgf'; 'edm doctor' lists what is missing")

#: Files latexmk and pdflatex leave beside the .tex (suffixes of ``<stem>``).
AUX_SUFFIXES = (".aux", ".log", ".fls", ".fdb_latexmk", ".out", ".toc", ".lof", ".lot",
                ".synctex.gz", ".xdv", ".dvi", ".bbl", ".blg", ".run.xml", ".bcf")

#: Seconds latexmk may take before it is stopped.
TIMEOUT = 300

_OVERFULL = re.compile(r"^Overfull \\[hv]box \((\d+(?:\.\d+)?)pt too (wide|high)\)(.*)$", re.M)
_UNDEFINED = re.compile(r"(?:Reference|Citation) `([^']*)' on page \d+ undefined")


class LatexError(ExternalToolError):
    """LaTeX stopped with an error; the message holds its first error line and the log's path.

    Not an :class:`~edm_sym.core.errors.EdmError`: the input was valid, the work failed (exit 1).
    """


@dataclass(frozen=True)
class LatexLog:
    """What a LaTeX run reported.

    Attributes
    ----------
    errors : tuple of str
        Lines starting with ``!``.
    overfull : tuple of (float, str)
        Overfull boxes: (points too wide/high, the rest of the log line).
    undefined : tuple of str
        Undefined references and citations.
    warnings : tuple of str
        Other ``LaTeX Warning:`` lines.
    """

    errors: tuple[str, ...] = ()
    overfull: tuple[tuple[float, str], ...] = ()
    undefined: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    @property
    def worst_overfull(self) -> float:
        """The widest overfull box in points (0 when there is none)."""
        return max((pt for pt, _ in self.overfull), default=0.0)


_USEPACKAGE = re.compile(r"\\usepackage(?:\[[^\]]*\])?\{([^}]+)\}")


def used_packages(tex: str) -> tuple[str, ...]:
    """The LaTeX packages a template or .tex loads with ``\\usepackage``, sorted.

    Parameters
    ----------
    tex : str
        LaTeX source (``\\usepackage[opts]{a,b}`` gives ``a`` and ``b``).

    Returns
    -------
    tuple of str
    """
    names = {n.strip() for group in _USEPACKAGE.findall(tex) for n in group.split(",")}
    return tuple(sorted(n for n in names if n))


def parse_log(text: str) -> LatexLog:
    """Read errors, overfull boxes and undefined references from a LaTeX log.

    Parameters
    ----------
    text : str
        The ``.log`` file's text.

    Returns
    -------
    LatexLog
    """
    errors = tuple(ln.strip() for ln in text.splitlines() if ln.startswith("!"))
    overfull = tuple((float(m.group(1)), f"{m.group(2)}{m.group(3)}".strip())
                     for m in _OVERFULL.finditer(text))
    undefined = tuple(sorted(set(_UNDEFINED.findall(text))))
    warnings = tuple(ln.strip() for ln in text.splitlines()
                     if "LaTeX Warning:" in ln and "undefined" not in ln)
    return LatexLog(errors, overfull, undefined, warnings)


def latexmk_path() -> str:
    """The latexmk executable.

    Raises
    ------
    ToolMissingError
        When latexmk is not on the PATH (the message says how to install it).
    """
    exe = shutil.which("latexmk")
    if exe is None:
        raise ToolMissingError(f"pdf: latexmk was not found on the PATH; {INSTALL_HINT}")
    return exe


def clean_aux(tex: Path) -> None:
    """Remove latexmk's and pdflatex's auxiliary files of ``tex`` (not the .tex or .pdf)."""
    for suffix in AUX_SUFFIXES:
        f = tex.with_suffix(suffix)
        if f.exists():
            f.unlink()


def compile_pdf(tex: str | Path, *, keep_aux: bool = False) -> tuple[Path, LatexLog]:
    """Compile ``tex`` to PDF with latexmk in its own folder.

    Parameters
    ----------
    tex : path-like
        The report's .tex file.
    keep_aux : bool
        Keep the log and auxiliary files (for debugging).

    Returns
    -------
    pdf : pathlib.Path
    log : LatexLog
        What LaTeX reported on the last run.

    Raises
    ------
    ToolMissingError
        When latexmk is missing.
    LatexError
        When LaTeX stops with an error (the log is kept then).
    """
    tex = Path(tex).resolve()
    exe = latexmk_path()
    env = dict(os.environ, SOURCE_DATE_EPOCH="0", FORCE_SOURCE_DATE="1")
    cmd = [exe, "-pdf", "-interaction=nonstopmode", "-halt-on-error", tex.name]
    try:
        proc = subprocess.run(cmd, cwd=tex.parent, env=env, capture_output=True, text=True,
                              timeout=TIMEOUT, check=False)
    except subprocess.TimeoutExpired:
        raise LatexError(f"{tex.name}: latexmk did not finish within {TIMEOUT} s") from None
    log_file = tex.with_suffix(".log")
    log = parse_log(log_file.read_text(errors="replace")) if log_file.exists() else LatexLog()
    pdf = tex.with_suffix(".pdf")
    if proc.returncode != 0 or not pdf.exists():
        if pdf.exists():  # no half-written PDF is left behind
            pdf.unlink()
        first = log.errors[0] if log.errors else (proc.stderr.strip().splitlines() or ["?"])[-1]
        raise LatexError(f"{tex.name}: LaTeX failed: {first} (see {log_file})")
    if not keep_aux:
        clean_aux(tex)
    return pdf, log

"""``edm doctor``: the optional tools this machine has, and where to get the missing ones.

edm_sym needs only its Python dependencies to abstract, simulate and export.
The optional tools add checks and outputs: a host C compiler builds the
generated C in the tests, arm-none-eabi-gcc with qemu-system-arm runs it on a
Cortex-M4F, latexmk with pdfLaTeX and the report's LaTeX packages turn the
report into a PDF. Each is listed as found or missing with the Debian package
that provides it, so a fresh machine can be set up from one apt line. The
optional Python package numba (the extra ``edm_sym[fast]``) runs the genetic
algorithm's row kernel: it is listed with its version and whether the kernel
is in use or the GA falls back to the reference realisations, with the pip
line that installs it.
"""

from __future__ import annotations

import importlib.metadata
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from edm_sym.outputs.render.environment import template_dir
from edm_sym.outputs.report.pdf import LATEX_PACKAGES, used_packages


@dataclass(frozen=True)
class Check:
    """One optional tool or LaTeX package, found or missing.

    Attributes
    ----------
    kind : str
        ``"tool"``, ``"latex"`` or ``"python"`` (an optional Python package).
    name : str
        The command (``gcc``), the LaTeX package (``lmodern``) or the Python
        package (``numba``).
    apt : str
        The Debian package that provides it (``""`` for a Python package).
    purpose : str
        What edm_sym uses it for.
    location : str or None
        Where it was found; None when it is missing (or does not import).
    version : str or None
        A Python package's installed version (None: not installed, or not a
        Python package).
    pip : str or None
        A Python package's pip requirement that installs it (``edm_sym[fast]``).
    status : str or None
        What its presence changes on this machine now (the row kernel in use,
        or the fallback).
    """

    kind: str
    name: str
    apt: str
    purpose: str
    location: str | None
    version: str | None = None
    pip: str | None = None
    status: str | None = None

    @property
    def found(self) -> bool:
        """Whether the tool or package is on this machine."""
        return self.location is not None


#: Commands edm_sym uses when present: (command, Debian package, purpose).
TOOLS: tuple[tuple[str, str, str], ...] = (
    ("gcc", "gcc", "builds and runs the generated C in the tests"),
    ("clang", "clang", "a second host compiler for the generated C in the tests"),
    ("arm-none-eabi-gcc", "gcc-arm-none-eabi", "builds the generated C for a Cortex-M4F"),
    ("qemu-system-arm", "qemu-system-arm", "runs the Cortex-M4F build in the tests"),
    ("latexmk", "latexmk", "edm-export --pdf: compiles the report"),
    ("pdflatex", "texlive-latex-base", "edm-export --pdf: the LaTeX engine"),
    ("kpsewhich", "texlive-binaries", "finds the report's LaTeX packages"),
    ("pdftotext", "poppler-utils", "reads the report PDF back in the tests"),
)


#: The extra that installs numba, for the row kernel.
FAST_EXTRA = "edm_sym[fast]"


def _distribution_version(name: str) -> str | None:
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return None


def numba_check() -> Check:
    """numba: its version, and whether the GA's row kernel is in use or falls back.

    The kernel is in use when numba imports (:data:`edm_sym.engines.kernel.NUMBA`);
    installed but not importable (a numpy it does not support yet) counts as
    missing, with the import error in the status.

    Returns
    -------
    Check
    """
    from edm_sym.engines import kernel

    version = _distribution_version("numba")
    purpose = "the genetic algorithm's row kernel (about 3x faster row simulation)"
    if kernel.NUMBA:
        return Check("python", "numba", "", purpose, str(Path(kernel.numba.__file__).parent),
                     getattr(kernel.numba, "__version__", version), FAST_EXTRA,
                     "row kernel in use")
    fallback = "row kernel not in use: the GA runs the reference realisations (numpy, slower)"
    if version is not None:
        try:
            import numba  # noqa: F401 (for its error message)
        except ImportError as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            fallback = f"numba {version} is installed but does not import ({reason}); {fallback}"
    return Check("python", "numba", "", purpose, None, version, FAST_EXTRA, fallback)


def _kpsewhich(name: str) -> str | None:
    exe = shutil.which("kpsewhich")
    if exe is None:
        return None
    proc = subprocess.run([exe, f"{name}.sty"], capture_output=True, text=True, check=False,
                          timeout=30)
    path = proc.stdout.strip()
    return path or None


def checks() -> list[Check]:
    """Look for every optional tool and every LaTeX package the report template loads.

    Returns
    -------
    list of Check
        Tools first, then LaTeX packages, then numba, each found or missing.
    """
    out = [Check("tool", cmd, apt, purpose, shutil.which(cmd)) for cmd, apt, purpose in TOOLS]
    template = (template_dir() / "report.tex.j2").read_text()
    for name in used_packages(template):
        # A package missing from the table is a bug of ours; name it rather than guess.
        apt = LATEX_PACKAGES.get(name, "?")
        out.append(Check("latex", name, apt, "the report's LaTeX preamble", _kpsewhich(name)))
    out.append(numba_check())
    return out


def report(results: list[Check]) -> str:
    """The text ``edm doctor`` prints: one line per check, then the install lines.

    A Python package's line gives its version and status; what is missing
    gets a pip line (Python packages), then one apt line (everything else).

    Parameters
    ----------
    results : list of Check

    Returns
    -------
    str
    """
    width = max(len(c.name) for c in results)
    kind = max(len(c.kind) for c in results)
    lines = []
    for c in results:
        state = "found  " if c.found else "missing"
        if c.pip is not None:
            where = (f"{c.version} at {c.location}" if c.found
                     else f"pip install \"{c.pip}\"")
            lines.append(f"{state}  {c.kind:{kind}}  {c.name:{width}}  {where}: {c.purpose}; "
                         f"{c.status}")
            continue
        where = c.location if c.found else f"apt package {c.apt}"
        lines.append(f"{state}  {c.kind:{kind}}  {c.name:{width}}  {where}: {c.purpose}")
    pip = sorted({c.pip for c in results if not c.found and c.pip is not None})
    if pip:
        lines.append("for the missing Python packages: pip install " +
                     " ".join(f'"{p}"' for p in pip))
    missing = sorted({c.apt for c in results if not c.found and c.pip is None})
    if missing:
        count = len([c for c in results if not c.found and c.pip is None])
        lines.append(f"{count} missing; on Debian/Ubuntu: "
                     "sudo apt-get install -y --no-install-recommends " + " ".join(missing))
    elif not pip:
        lines.append("everything found")
    return "\n".join(lines)

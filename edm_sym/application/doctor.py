"""``edm doctor``: the optional tools this machine has, and where to get the missing ones.

edm_sym needs only its Python dependencies to abstract, simulate and export.
The optional tools add checks and outputs: a host C compiler builds the
generated C in the tests, arm-none-eabi-gcc with qemu-system-arm runs it on a
Cortex-M4F, latexmk with pdfLaTeX and the report's LaTeX packages turn the
report into a PDF. Each is listed as found or missing with the Debian package
that provides it, so a fresh machine can be set up from one apt line.
"""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import dataclass

from edm_sym.outputs.render.environment import template_dir
from edm_sym.outputs.report.pdf import LATEX_PACKAGES, used_packages


@dataclass(frozen=True)
class Check:
    """One optional tool or LaTeX package, found or missing.

    Attributes
    ----------
    kind : str
        ``"tool"`` or ``"latex"``.
    name : str
        The command (``gcc``) or the LaTeX package (``lmodern``).
    apt : str
        The Debian package that provides it.
    purpose : str
        What edm_sym uses it for.
    location : str or None
        Where it was found; None when it is missing.
    """

    kind: str
    name: str
    apt: str
    purpose: str
    location: str | None

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
        Tools first, then LaTeX packages, each found or missing.
    """
    out = [Check("tool", cmd, apt, purpose, shutil.which(cmd)) for cmd, apt, purpose in TOOLS]
    template = (template_dir() / "report.tex.j2").read_text()
    for name in used_packages(template):
        # A package missing from the table is a bug of ours; name it rather than guess.
        apt = LATEX_PACKAGES.get(name, "?")
        out.append(Check("latex", name, apt, "the report's LaTeX preamble", _kpsewhich(name)))
    return out


def report(results: list[Check]) -> str:
    """The text ``edm doctor`` prints: one line per check, then the apt line for what is missing.

    Parameters
    ----------
    results : list of Check

    Returns
    -------
    str
    """
    width = max(len(c.name) for c in results)
    lines = []
    for c in results:
        state = "found  " if c.found else "missing"
        where = c.location if c.found else f"apt package {c.apt}"
        lines.append(f"{state}  {c.kind:5}  {c.name:{width}}  {where}: {c.purpose}")
    missing = sorted({c.apt for c in results if not c.found})
    if missing:
        lines.append(f"{len([c for c in results if not c.found])} missing; on Debian/Ubuntu: "
                     "sudo apt-get install -y --no-install-recommends " + " ".join(missing))
    else:
        lines.append("everything found")
    return "\n".join(lines)

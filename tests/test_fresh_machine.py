"""A fresh machine gets every system package the tests and the report need from one apt line.

CI installs with ``--no-install-recommends``, so a LaTeX package that TeX Live
only *recommends* (``lmodern``) is missing there unless the line names it. These
tests map each ``\\usepackage`` of the report template to its .sty
(``kpsewhich``) and to the Debian package that ships it (``dpkg -S``), and check
that package is in the README's apt line or among what that line pulls in
without recommends.
"""

from __future__ import annotations

import importlib.metadata
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from edm_sym.application.cli import main
from edm_sym.application.doctor import TOOLS
from edm_sym.outputs.report.pdf import LATEX_APT, LATEX_PACKAGES, used_packages

ROOT = Path(__file__).resolve().parent.parent


def apt_packages(text: str) -> set[str]:
    """The package names of the first ``apt-get install`` command in ``text`` (continued lines too)."""
    lines = text.splitlines()
    start = next(i for i, ln in enumerate(lines) if "apt-get install" in ln)
    words: list[str] = []
    for ln in lines[start:]:
        words += ln.split()
        if not ln.rstrip().endswith("\\"):
            break
    after = words[words.index("install") + 1:]
    return {w for w in after if re.fullmatch(r"[a-z0-9][a-z0-9.+-]+", w)}


def readme_packages() -> set[str]:
    return apt_packages((ROOT / "README.md").read_text())


def test_ci_installs_what_the_readme_says() -> None:
    ci = apt_packages((ROOT / ".ci" / "run").read_text())
    assert ci == readme_packages()
    assert "--no-install-recommends" in (ROOT / ".ci" / "run").read_text()


def test_every_template_package_has_its_debian_package_in_the_table() -> None:
    template = (ROOT / "templates" / "report.tex.j2").read_text()
    assert set(used_packages(template)) == set(LATEX_PACKAGES)


def test_used_packages_reads_options_and_lists() -> None:
    tex = "\\usepackage[T1]{fontenc}\n\\usepackage{amsmath, amssymb}\n% \\usepackage{x}\n"
    assert used_packages(tex) == ("amsmath", "amssymb", "fontenc", "x")


def _apt_closure(packages: set[str]) -> set[str]:
    """Every package ``apt-get install --no-install-recommends packages`` installs."""
    proc = subprocess.run(
        ["apt-cache", "depends", "--recurse", "--no-recommends", "--no-suggests", "--no-conflicts",
         "--no-breaks", "--no-replaces", "--no-enhances", *sorted(packages)],
        capture_output=True, text=True, check=True, timeout=300)
    return {ln.strip() for ln in proc.stdout.splitlines() if ln and not ln.startswith(" ")}


@pytest.mark.skipif(shutil.which("apt-cache") is None, reason="needs apt-cache (Debian/Ubuntu)")
def test_the_readme_apt_line_brings_every_package_without_recommends() -> None:
    closure = _apt_closure(readme_packages())
    needed = set(LATEX_APT) | {apt for _, apt, _ in TOOLS}
    missing = sorted(needed - closure)
    assert not missing, f"README's apt line does not bring {missing} with --no-install-recommends"


@pytest.mark.skipif(shutil.which("kpsewhich") is None or shutil.which("dpkg") is None,
                    reason="needs TeX Live (kpsewhich) and dpkg")
@pytest.mark.parametrize("sty", sorted(LATEX_PACKAGES))
def test_each_sty_comes_from_the_debian_package_the_table_names(sty: str) -> None:
    path = subprocess.run(["kpsewhich", f"{sty}.sty"], capture_output=True, text=True,
                          check=False).stdout.strip()
    assert path, f"{sty}.sty is not installed here (Debian package {LATEX_PACKAGES[sty]})"
    owner = subprocess.run(["dpkg", "-S", path], capture_output=True, text=True, check=False)
    if owner.returncode != 0:
        pytest.skip(f"{path} belongs to no Debian package (TeX Live installed by hand?)")
    assert owner.stdout.split(":")[0] == LATEX_PACKAGES[sty]


@pytest.mark.skipif(shutil.which("dpkg") is None, reason="needs dpkg")
@pytest.mark.parametrize("cmd,apt", [(cmd, apt) for cmd, apt, _ in TOOLS])
def test_each_tool_comes_from_the_debian_package_doctor_names(cmd: str, apt: str) -> None:
    exe = shutil.which(cmd)
    if exe is None:
        pytest.skip(f"{cmd} is not installed here")
    owner = subprocess.run(["dpkg", "-S", exe], capture_output=True, text=True, check=False)
    if owner.returncode != 0:
        pytest.skip(f"{exe} belongs to no Debian package")
    assert owner.stdout.split(":")[0] == apt


def test_doctor_names_the_package_of_everything_missing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # an empty PATH: nothing is found
    assert main(["doctor"]) == 0
    out = capsys.readouterr().out.splitlines()
    gcc = next(ln for ln in out if re.search(r"\bgcc\b", ln) and "tool" in ln)
    assert gcc.startswith("missing") and "apt package gcc" in gcc
    lm = next(ln for ln in out if re.search(r"\blmodern\b", ln) and "latex" in ln)
    assert lm.startswith("missing") and "apt package lmodern" in lm
    last = out[-1]
    assert "apt-get install" in last
    for apt in {*LATEX_APT, *(apt for _, apt, _ in TOOLS)}:
        assert apt in last.split()


def test_doctor_reports_what_this_machine_has(capsys: pytest.CaptureFixture) -> None:
    assert main(["doctor"]) == 0
    out = capsys.readouterr().out.splitlines()
    for cmd, _, _ in TOOLS:
        line = next(ln for ln in out if re.match(rf"\S+\s+tool\s+{re.escape(cmd)}\s", ln))
        assert line.startswith("found" if shutil.which(cmd) else "missing")


def test_doctor_json_lists_every_check(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                       capsys: pytest.CaptureFixture) -> None:
    import json

    monkeypatch.setenv("PATH", str(tmp_path))
    assert main(["doctor", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert {(d["kind"], d["name"]) for d in doc} == (
        {("tool", cmd) for cmd, _, _ in TOOLS} | {("latex", n) for n in LATEX_PACKAGES}
        | {("python", "numba")})
    assert all(d["found"] is False and d["location"] is None for d in doc if d["kind"] != "python")
    assert {d["name"]: d["apt"] for d in doc if d["kind"] == "latex"} == LATEX_PACKAGES


def _numba_line(out: list[str]) -> str:
    return next(ln for ln in out if re.match(r"\S+\s+python\s+numba\s", ln))


def test_doctor_reports_numba_its_version_and_the_row_kernel(capsys: pytest.CaptureFixture
                                                              ) -> None:
    import json

    from edm_sym.engines import kernel

    assert main(["doctor"]) == 0
    line = _numba_line(capsys.readouterr().out.splitlines())
    assert main(["doctor", "--json"]) == 0
    numba = next(d for d in json.loads(capsys.readouterr().out) if d["kind"] == "python")
    assert numba["pip"] == "edm_sym[fast]" and numba["apt"] == ""
    if kernel.NUMBA:
        assert line.startswith("found") and line.endswith("row kernel in use")
        assert f"{kernel.numba.__version__} at " in line
        assert numba["found"] and numba["version"] == kernel.numba.__version__
    else:
        assert line.startswith("missing") and 'pip install "edm_sym[fast]"' in line
        assert line.endswith("row kernel not in use: the GA runs the reference realisations "
                             "(numpy, slower)")
        assert not numba["found"] and numba["location"] is None


def test_doctor_without_numba_names_the_extra_and_the_fallback(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    from edm_sym.application import doctor
    from edm_sym.engines import kernel

    monkeypatch.setattr(kernel, "NUMBA", False)
    monkeypatch.setattr(doctor, "_distribution_version", lambda name: None)  # not installed
    assert main(["doctor"]) == 0
    out = capsys.readouterr().out.splitlines()
    line = _numba_line(out)
    assert line.startswith("missing") and 'pip install "edm_sym[fast]"' in line
    assert "row kernel not in use" in line and "installed" not in line
    assert 'for the missing Python packages: pip install "edm_sym[fast]"' in out
    assert out[-1] != "everything found"


def test_doctor_reports_a_numba_that_does_not_import_and_the_ga_falls_back() -> None:
    pytest.importorskip("numba")  # installed, then made unimportable in a fresh process
    code = ("import sys; sys.modules['numba'] = None\n"
            "from edm_sym.application.cli import main\n"
            "from edm_sym.engines.abstraction.evaluator import kernel_in_use\n"
            "print('kernel in use:', kernel_in_use())\n"
            "main(['doctor'])\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True, cwd=ROOT, timeout=300)
    out = proc.stdout.splitlines()
    assert out[0] == "kernel in use: False"
    line = _numba_line(out)
    version = importlib.metadata.version("numba")
    assert line.startswith("missing") and 'pip install "edm_sym[fast]"' in line
    assert f"numba {version} is installed but does not import (" in line
    assert "row kernel not in use" in line

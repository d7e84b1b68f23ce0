"""Any input to any command: exit 0 with a valid output, or exit 2, one line, nothing written.

Hypothesis draws the commands' files near valid ones (a log, a result, a
LuGre file, a config, a pipeline file, each either valid, cut short, with a
slice replaced by random text, with a number replaced by an integer of
hundreds or thousands of digits, or - for JSON - with one value replaced) and
odd option values (nan, inf, negative, huge, empty, unknown names), and runs
the commands in-process through ``edm_sym.application.cli.main`` and
``export_main``. Whatever comes in:

* exit 0: the output is valid (it loads with the project's own loader) and
  no input file changed;
* exit 2: stderr is one line, and the folder is as it was (no output, no
  checkpoint, no temporary file);
* nothing else: no exit 1, no traceback, no exception out of ``main``.

The default suite runs a few examples per command (well under a minute);
``pytest --slow`` runs many more.
"""

from __future__ import annotations

import functools
import json
import os
import re
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from edm_sym.application.cli import export_main, main
from edm_sym.core.data import load_data, write_csv
from edm_sym.core.result import load_result
from edm_sym.engines.abstraction.parallel import Parallel
from edm_sym.engines.lugre import load_lugre

REPO = Path(__file__).resolve().parents[1]
RESULT = REPO / "tests" / "data" / "handwritten_result.json"  # inputs theta_w, theta_uw, omega
LUGRE = REPO / "examples" / "auger" / "lugre.json"  # velocity omega, Ts 1 ms

TINY_CONFIG = """cache_mb = 8
[ga]
population = 6
elites = 1
tournament = 2
generations = 2
continue = "no"
patience = 5
local_search = 0
[[step]]
n_rows = 1
n_elements = 2
"""

PIPELINE = """[data]
abstraction = "log.csv"
evaluation = "log.csv"
[abstraction]
config = "tiny.toml"
target = "tau_ext"
inputs = ["omega", "theta_w"]
seed = 1
[lugre]
velocity = "omega"
time_limit = 0.3
[export]
target = "c"
out_dir = "gen"
"""


def _log_text() -> str:
    n, ts = 400, 1e-3
    t = np.arange(n) * ts
    omega = 3.0 * np.sin(2 * np.pi * 2.0 * t) + 0.5
    theta = np.cumsum(omega) * ts
    cols = {"t": t, "theta_w": np.mod(theta, 2 * np.pi), "theta_uw": theta, "omega": omega,
            "alpha": np.gradient(omega, ts), "tau_ext": 0.8 * np.tanh(20 * omega) + 0.01 * omega,
            "gtau": np.full(n, 2.0)}
    with tempfile.TemporaryDirectory() as d:
        return write_csv(Path(d) / "log.csv", cols).read_text()


VALID = {
    "log.csv": _log_text(),
    "result.json": RESULT.read_text(),
    "lugre.json": LUGRE.read_text(),
    "tiny.toml": TINY_CONFIG,
    "pipeline.toml": PIPELINE,
}

JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(min_value=-10**20, max_value=10**20)
    | st.floats() | st.text(max_size=6),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=2),
    max_leaves=6,
)
ODD = ["nan", "inf", "-inf", "-1", "0", "1e400", "1e-300", "abc", "", " 3", "1e9", "٣"]


def _paths(doc: object, prefix: tuple = ()) -> list[tuple]:
    if isinstance(doc, dict):
        return [prefix] + [p for k, v in doc.items() for p in _paths(v, prefix + (k,))]
    if isinstance(doc, list):
        return [prefix] + [p for i, v in enumerate(doc) for p in _paths(v, prefix + (i,))]
    return [prefix]


@st.composite
def variant(draw: st.DrawFn, name: str, text: str | None = None) -> str:
    """The file ``name`` (``text``, default its valid text): valid (half the time), or cut,
    spliced, with a long integer or (JSON) with a value replaced."""
    text = VALID[name] if text is None else text
    kind = draw(st.sampled_from(["valid", "valid", "valid", "cut", "splice", "value", "long"]))
    if kind == "valid":
        return text
    if kind == "long":  # a number replaced by an integer no double holds (or Python reads)
        numbers = list(re.finditer(r"[0-9][0-9.e+-]*", text))
        if numbers:
            m = draw(st.sampled_from(numbers))
            digits = draw(st.sampled_from([310, 4301, 6000]))
            return text[:m.start()] + "7" * digits + text[m.end():]
    if kind == "cut":
        return text[:draw(st.integers(0, len(text)))]
    if kind == "splice" or not name.endswith(".json"):
        i = draw(st.integers(0, len(text)))
        j = min(len(text), i + draw(st.integers(0, 12)))
        return text[:i] + draw(st.text(max_size=12)) + text[j:]
    doc = json.loads(text)
    path = draw(st.sampled_from(_paths(doc)))
    if not path:
        return json.dumps(draw(JSON_VALUES))
    node = doc
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = draw(JSON_VALUES)
    return json.dumps(doc)


@functools.cache
def _checkpoint_text() -> str:
    """The checkpoint of ``edm abstract log.csv --target tau_ext --inputs omega --config
    tiny.toml`` (seed 0) stopped after its first generation."""
    from edm_sym.engines.abstraction import abstract, load_config

    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / "log.csv").write_text(VALID["log.csv"])
        (folder / "tiny.toml").write_text(VALID["tiny.toml"])
        ckpt = folder / "r.json.checkpoint"
        abstract(load_data(folder / "log.csv"), target="tau_ext", inputs=["omega"],
                 config=load_config(folder / "tiny.toml"), seed=0, parallel=Parallel(workers=1),
                 checkpoint=ckpt, callback=lambda info: True)
        return ckpt.read_text()


@st.composite
def checkpoint_variant(draw: st.DrawFn) -> str:
    """A checkpoint: of the drawn run, of another format version or run (sealed), or damaged."""
    from edm_sym.engines.abstraction.checkpoint import _digest

    doc = json.loads(_checkpoint_text())
    kind = draw(st.sampled_from(["valid", "version", "run", "damaged"]))
    if kind == "damaged":
        return draw(variant("r.json.checkpoint", _checkpoint_text()))
    if kind == "version":
        doc["version"] = draw(st.sampled_from([1, 3, "2", None, 2.5]))
    elif kind == "run":
        doc["fingerprint"] = "0" * 64
        doc["identity"]["seed"] = 9
    doc["sha256"] = _digest(doc)
    return json.dumps(doc, sort_keys=True)


def odd(*valid: str) -> st.SearchStrategy[str]:
    """An option value: one of ``valid`` (nine times in ten) or an odd one."""
    return st.integers(0, 9).flatmap(lambda k: st.sampled_from(ODD if k == 9 else list(valid)))


def tiny_budget():  # noqa: ANN201
    """A time budget of 10 s for the abstraction (edm_sym.core.budget), so an edited config
    (a spliced digit makes 2 generations 2000000) is refused up front instead of running for
    hours; the refusal is one of the exits the property accepts."""
    from unittest import mock

    from edm_sym.core import budget

    return mock.patch.object(budget, "TIME_LIMIT_SECONDS", 10.0)


def _in_hypothesis() -> bool:
    from hypothesis.control import currently_in_test_context

    return currently_in_test_context()


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _run(capsys: pytest.CaptureFixture, entry: Callable, args: list[str], files: dict[str, str],
         check: Callable[[Path, str], None], consumed: tuple[str, ...] = ()) -> None:
    """Write ``files`` into a fresh folder, run the command there and check the outcome.

    ``consumed`` names inputs a command that succeeds may replace or remove (a checkpoint).
    """
    capsys.readouterr()
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        for name, text in files.items():
            (folder / name).write_text(text, encoding="utf-8")
        before = _snapshot(folder)
        cwd = os.getcwd()
        os.chdir(folder)
        try:
            rc = entry(args)
        finally:
            os.chdir(cwd)
        out, err = capsys.readouterr()
        after = _snapshot(folder)
        if _in_hypothesis():
            event(f"exit {rc}")
        assert rc in (0, 2), f"exit {rc}: {err}"
        assert "Traceback" not in err, err
        if rc == 2:
            lines = err.strip().splitlines()
            assert len(lines) == 1, f"expected one line, found {len(lines)}:\n{err}"
            assert after == before, f"exit 2 but files changed: {sorted(set(after) ^ set(before))}"
        else:
            for name in before:  # no input harmed
                assert name in consumed or after[name] == before[name], f"{name} changed"
            assert not [n for n in after if n.endswith(".tmp")], sorted(after)
            check(folder, out)


def _examples(default: int, slow: int) -> Callable:
    """Two tests from one property ``body(capsys, data)``: ``default`` examples, ``slow`` with --slow."""
    def wrap(body: Callable) -> tuple[Callable, Callable]:
        def make(n: int) -> Callable:
            def test(capsys: pytest.CaptureFixture, data: st.DataObject) -> None:
                body(capsys, data)

            test.__doc__ = body.__doc__
            return settings(max_examples=n, deadline=None, derandomize=True,
                            suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                   HealthCheck.too_slow])(given(data=st.data())(test))

        return make(default), pytest.mark.slow(make(slow))
    return wrap


# -- edm simulate -----------------------------------------------------------------------------

def _simulate(capsys, model: str, model_text: str, log: str, ts: str | None, resample: bool) -> None:  # noqa: ANN001
    args = ["simulate", model, "log.csv", "-o", "sim.csv"] + (["--ts", ts] if ts is not None else []) \
        + (["--resample"] if resample else [])

    def check(folder: Path, out: str) -> None:
        sim = load_data(folder / "sim.csv")
        assert "tau_cmp" in sim.columns and np.all(np.isfinite(sim.columns["tau_cmp"]))
        assert out.splitlines()[-1].startswith("rmse ")

    _run(capsys, main, args, {model: model_text, "log.csv": log}, check)


def _prop_simulate(capsys, data) -> None:  # noqa: ANN001
    model = data.draw(st.sampled_from(["result.json", "lugre.json"]))
    _simulate(capsys, model, data.draw(variant(model)), data.draw(variant("log.csv")),
              data.draw(st.none() | odd("0.001")), data.draw(st.booleans()))


test_simulate, test_simulate_many = _examples(40, 400)(_prop_simulate)


# -- edm abstract ------------------------------------------------------------------------------

def _prop_abstract(capsys, data) -> None:  # noqa: ANN001
    args = ["abstract", "log.csv", "--target", data.draw(odd("tau_ext", "omega")),
            "--inputs", data.draw(odd("omega", "omega,theta_w", "omega, omega", "nope,omega")),
            "--config", "tiny.toml", "-o", "r.json", "--quiet", "--workers", "1"]
    limits = st.sampled_from(["3", "3", "3", "nan", "inf", "-1", "0", "abc", "", "1e-300"])
    for option, values in (("--seed", odd("0", "7", "4294967296")), ("--time-limit", limits),
                           ("--validation-share", odd("0.2", "0.9", "0.95")),
                           ("--select", odd("best", "knee", "simplest-within=5", "simplest-within=x")),
                           ("--ts", odd("0.001"))):
        if data.draw(st.booleans()):
            args += [option, data.draw(values)]

    files = {"log.csv": data.draw(variant("log.csv")), "tiny.toml": data.draw(variant("tiny.toml"))}
    if data.draw(st.booleans()):  # --resume, with a checkpoint of this run or not quite
        args.append("--resume")
        files["r.json.checkpoint"] = data.draw(checkpoint_variant())

    def check(folder: Path, out: str) -> None:
        res = load_result(folder / "r.json")
        assert res.compensator.matrix.rows
        assert out.startswith("wrote r.json")
        # The checkpoint goes when the run completes; a time limit keeps it for --resume.
        completed = res.provenance["stop_reason"] == "completed"
        assert (folder / "r.json.checkpoint").exists() != completed

    with tiny_budget():
        _run(capsys, main, args, files, check, consumed=("r.json.checkpoint",))


test_abstract, test_abstract_many = _examples(20, 200)(_prop_abstract)


# -- edm lugre -----------------------------------------------------------------------------------

def _prop_lugre(capsys, data) -> None:  # noqa: ANN001
    args = ["lugre", "log.csv", "--target", data.draw(odd("tau_ext")), "--velocity",
            data.draw(odd("omega", "theta_w")), "--time-limit", data.draw(odd("0.2")),
            "--method", data.draw(odd("scipy", "ga")), "-o", "l.json"]
    if data.draw(st.booleans()):
        args += ["--seed", data.draw(odd("3"))]

    def check(folder: Path, out: str) -> None:
        assert load_lugre(folder / "l.json").sample_time > 0
        assert out.splitlines()[-1].startswith("rmse ")

    _run(capsys, main, args, {"log.csv": data.draw(variant("log.csv"))}, check)


test_lugre, test_lugre_many = _examples(15, 150)(_prop_lugre)


# -- edm observe ---------------------------------------------------------------------------------

def _prop_observe(capsys, data) -> None:  # noqa: ANN001
    args = ["observe", "log.csv", "--position", data.draw(odd("theta_uw", "t")),
            "--force", data.draw(odd("tau_ext")), "--nominal-inertia", data.draw(odd("0.01", "0")),
            "--force-gain", data.draw(odd("1", "gtau", "nope", "-2")),
            "--cutoff", data.draw(odd("100", "40", "499", "600")), "-o", "obs.csv"]

    def check(folder: Path, out: str) -> None:
        view = load_data(folder / "obs.csv")
        assert {"t", "q", "qd", "qdd", "force", "tau_ext"} <= set(view.columns)

    _run(capsys, main, args, {"log.csv": data.draw(variant("log.csv"))}, check)


test_observe, test_observe_many = _examples(40, 400)(_prop_observe)


# -- edm describe ----------------------------------------------------------------------------------

def _prop_describe(capsys, data) -> None:  # noqa: ANN001
    as_json = data.draw(st.booleans())
    args = ["describe", "result.json", "--data", "log.csv", "--threshold", data.draw(odd("1", "50"))] \
        + (["--json"] if as_json else [])

    def check(folder: Path, out: str) -> None:
        assert out.strip()
        if as_json:
            assert isinstance(json.loads(out), dict)

    _run(capsys, main, args, {"result.json": data.draw(variant("result.json")),
                              "log.csv": data.draw(variant("log.csv"))}, check)


test_describe, test_describe_many = _examples(6, 60)(_prop_describe)


# -- edm-export --------------------------------------------------------------------------------------

def _prop_export(capsys, data) -> None:  # noqa: ANN001
    target = data.draw(odd("c", "python"))
    args = ["result.json", "--target", target, "-o", "gen",
            "--prefix", data.draw(odd("edm_comp", "ctl", "math", "int", "_", "a b") | st.text(max_size=6)),
            "--real", data.draw(odd("float", "double"))]

    def check(folder: Path, out: str) -> None:
        written = [Path(line) for line in out.splitlines()]
        assert written and all((folder / p).is_file() for p in written)
        for p in written:
            if p.suffix == ".py":
                compile((folder / p).read_text(), str(p), "exec")

    _run(capsys, export_main, args, {"result.json": data.draw(variant("result.json"))}, check)


test_export, test_export_many = _examples(15, 200)(_prop_export)


# -- edm pipeline ----------------------------------------------------------------------------------------

def _prop_pipeline(capsys, data) -> None:  # noqa: ANN001
    def check(folder: Path, out: str) -> None:
        summary = json.loads((folder / "evaluation.json").read_text())
        assert summary["abstraction"]["edm"] >= 0
        assert load_result(folder / "result.json").provenance["stop_reason"] == "completed"
        assert (folder / "gen" / "edm_comp.c").is_file()
        assert not (folder / "result.json.checkpoint").exists()

    with tiny_budget():
        _run(capsys, main, ["pipeline", "pipeline.toml", "--quiet"],
             {"pipeline.toml": data.draw(variant("pipeline.toml")),
              "tiny.toml": data.draw(variant("tiny.toml")), "log.csv": VALID["log.csv"]}, check)


test_pipeline, test_pipeline_many = _examples(10, 80)(_prop_pipeline)


def test_the_valid_files_give_exit_0(capsys) -> None:  # noqa: ANN001
    # The properties would hold vacuously if every draw were refused: the valid files pass.
    for model in ("result.json", "lugre.json"):
        _simulate(capsys, model, VALID[model], VALID["log.csv"], None, False)
    capsys.readouterr()
    with tempfile.TemporaryDirectory() as d:
        for name, text in VALID.items():
            (Path(d) / name).write_text(text)
        cwd = os.getcwd()
        os.chdir(d)
        try:
            assert main(["abstract", "log.csv", "--target", "tau_ext", "--inputs", "omega",
                         "--config", "tiny.toml", "-o", "r.json", "--quiet", "--workers", "1"]) == 0
            assert main(["pipeline", "pipeline.toml", "--quiet"]) == 0
            assert export_main(["result.json", "--target", "python", "-o", "gen"]) == 0
        finally:
            os.chdir(cwd)


# -- an integer no double holds, in every file a command reads ------------------------------------

CHECKPOINT = {"format": "edm-abstraction-checkpoint", "version": 2, "current": {"generation": 1}}


def _long_number(text: str, key: str, digits: int) -> str:
    """``text`` with the number after ``key`` (``"key": 1`` or ``key = 1``) replaced."""
    pattern = rf'((?:"{key}"\s*:|\b{key}\s*=)\s*)-?[0-9][0-9.e+-]*'
    new, count = re.subn(pattern, lambda m: m.group(1) + "-" + "9" * digits, text, count=1)
    assert count == 1, key
    return new


ABSTRACT = ["abstract", "log.csv", "--target", "tau_ext", "--inputs", "omega", "--config",
            "tiny.toml", "-o", "r.json", "--quiet", "--workers", "1"]


@pytest.mark.parametrize("digits", [310, 4301, 100_000])
@pytest.mark.parametrize("entry, args, name, key, shown", [
    (main, ABSTRACT, "tiny.toml", "population", "ga.population"),
    (main, ABSTRACT, "tiny.toml", "cache_mb", "cache_mb"),
    (main, ["pipeline", "pipeline.toml", "--quiet"], "pipeline.toml", "seed", "abstraction.seed"),
    (main, ["describe", "result.json"], "result.json", "record_length", "record_length"),
    (export_main, ["result.json", "--target", "python", "-o", "gen"], "result.json",
     "sample_time", "sample_time"),
    (main, ["simulate", "lugre.json", "log.csv", "-o", "s.csv"], "lugre.json", "evaluations",
     "evaluations"),
    (main, ["abstract", *ABSTRACT[1:], "--resume"], "r.json.checkpoint", "generation",
     "current.generation"),
], ids=["config", "config-top", "pipeline", "result", "export", "lugre", "checkpoint"])
def test_an_integer_no_double_holds_is_refused_naming_the_file_and_key(
    capsys, entry, args, name, key, shown, digits  # noqa: ANN001
) -> None:
    files = dict(VALID) | {"r.json.checkpoint": json.dumps(CHECKPOINT)}
    files[name] = _long_number(files[name], key, digits)
    capsys.readouterr()
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        for file, text in files.items():
            (folder / file).write_text(text, encoding="utf-8")
        before = _snapshot(folder)
        cwd = os.getcwd()
        os.chdir(folder)
        try:
            rc = entry(args)
        finally:
            os.chdir(cwd)
        err = capsys.readouterr().err
        assert _snapshot(folder) == before
    assert rc == 2, err
    assert err.count("\n") == 1 and len(err) < 300, err
    assert f"{name}: {shown}: expected a finite number, found an integer of " in err
    assert ("more than 4300 digits" if digits > 4300 and name.endswith(".toml")
            else f"{digits} digits") in err


def test_pipeline_reuse_refuses_a_checkpoint_of_another_version_before_any_work(capsys) -> None:  # noqa: ANN001
    from edm_sym.engines.abstraction.checkpoint import _digest

    doc = json.loads(_checkpoint_text())
    doc["version"] = 3
    doc["sha256"] = _digest(doc)
    files = dict(VALID) | {"result.json.checkpoint": json.dumps(doc)}
    del files["result.json"], files["lugre.json"]
    capsys.readouterr()
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        for file, text in files.items():
            (folder / file).write_text(text, encoding="utf-8")
        before = _snapshot(folder)
        cwd = os.getcwd()
        os.chdir(folder)
        try:
            rc = main(["pipeline", "pipeline.toml", "--quiet", "--reuse"])
        finally:
            os.chdir(cwd)
        err = capsys.readouterr().err
        assert _snapshot(folder) == before  # no lugre.json either: refused before the LuGre fit
    assert rc == 2 and err.count("\n") == 1, err
    assert "result.json.checkpoint: version: expected checkpoint format version 2" in err
    assert "found version 3" in err


# -- column names: what the first command accepts, every export target prints -------------------

def _with_target(name: str) -> str:
    doc = json.loads(VALID["result.json"])
    doc["target"] = name
    return json.dumps(doc)


def _export_all(capsys, name: str) -> tuple[int, str, Path | None]:  # noqa: ANN001
    """``edm-export result.json --target all`` of a result whose target is ``name``."""
    capsys.readouterr()
    d = tempfile.mkdtemp()
    folder = Path(d)
    (folder / "result.json").write_text(_with_target(name), encoding="utf-8")
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        rc = export_main(["result.json", "--target", "all", "-o", "gen"])
    finally:
        os.chdir(cwd)
    return rc, capsys.readouterr().err, folder


@settings(max_examples=25, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.text(min_size=1, max_size=12) | st.sampled_from(
    ['tau"', '"tau', "a*/b", "%{}#~^&$_", "τ_ext", "tau ext", "x'''y", '""', "  ", "a/*b"]))
def test_every_target_prints_every_name_the_rule_accepts(capsys, name: str) -> None:  # noqa: ANN001
    from edm_sym.core.result import target_name_problem

    rc, err, folder = _export_all(capsys, name)
    problem = target_name_problem(name)
    try:
        if problem is not None:  # refused when read, by the same rule, with the reason
            assert rc == 2 and err.count("\n") == 1, err
            assert f"result.json: target: {problem}" in err
            assert not (folder / "gen").exists()
            return
        assert rc == 0, err
        module = (folder / "gen" / "edm_comp.py").read_text("utf-8")
        scope: dict = {}
        exec(compile(module, "edm_comp.py", "exec"), scope)  # noqa: S102
        assert scope["TARGET"] == name
        header = (folder / "gen" / "edm_comp.h").read_text("utf-8")
        comment = next(line for line in header.splitlines() if "a model of" in line)
        assert "*/" not in comment  # the comment goes on
        assert (folder / "gen" / "edm_comp_report.tex").is_file()
    finally:
        import shutil

        shutil.rmtree(folder)


@pytest.mark.parametrize("name, found", [
    ('tau"""x', "three double quotes in a row"), ("tau\\ext", "a backslash"),
    ("tau\text", "the unprintable character U+0009"),
    ("tau\u2028ext", "the unprintable character U+2028"),
])
@pytest.mark.parametrize("command", ["abstract", "lugre", "pipeline"])
def test_a_name_an_export_cannot_print_is_refused_by_the_first_command(
    capsys, name: str, found: str, command: str  # noqa: ANN001
) -> None:
    header, rest = VALID["log.csv"].split("\n", 1)
    quoted = '"' + name.replace('"', '""') + '"'
    log = header.replace("tau_ext", quoted) + "\n" + rest
    args = {"abstract": ["abstract", "log.csv", "--target", name, "--inputs", "omega",
                         "--config", "tiny.toml", "-o", "r.json", "--quiet", "--workers", "1"],
            "lugre": ["lugre", "log.csv", "--target", name, "--velocity", "omega", "-o", "l.json"],
            "pipeline": ["pipeline", "pipeline.toml", "--quiet"]}[command]
    pipeline = VALID["pipeline.toml"].replace('target = "tau_ext"',
                                              f"target = {json.dumps(name)}")
    files = {"log.csv": log, "tiny.toml": VALID["tiny.toml"], "pipeline.toml": pipeline}
    capsys.readouterr()
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        for file, text in files.items():
            (folder / file).write_text(text, encoding="utf-8")
        assert name in load_data(folder / "log.csv").columns
        before = _snapshot(folder)
        cwd = os.getcwd()
        os.chdir(folder)
        try:
            rc = main(args)
        finally:
            os.chdir(cwd)
        err = capsys.readouterr().err
        assert _snapshot(folder) == before
    assert rc == 2 and err.count("\n") == 1, err
    assert f"found {found}; rename the column" in err


# -- logs too large for the machine ------------------------------------------------------------

@pytest.mark.parametrize("entry, args", [
    (main, ["simulate", "result.json", "log.csv", "-o", "s.csv"]),
    (main, ["describe", "result.json", "--data", "log.csv"]),
    (export_main, ["result.json", "--target", "c", "--data", "log.csv", "-o", "gen"]),
    (export_main, ["result.json", "--target", "python", "--eval-data", "log.csv", "-o", "gen"]),
], ids=["simulate", "describe", "export-data", "export-eval-data"])
@pytest.mark.parametrize("available", [2**10, 2**16], ids=["file", "columns"])
def test_a_log_too_large_for_the_machine_is_refused_up_front_with_the_figure(
    capsys, entry, args, available: int  # noqa: ANN001
) -> None:
    from unittest import mock

    from edm_sym.core import budget

    size = len(VALID["log.csv"].encode())
    assert 2**10 < size < 2**16 < budget.log_estimate(file_bytes=size, n_samples=400,
                                                      n_columns=7).memory
    capsys.readouterr()
    with tempfile.TemporaryDirectory() as d, \
            mock.patch.object(budget, "available_memory", lambda: available):
        folder = Path(d)
        for file in ("result.json", "log.csv"):
            (folder / file).write_text(VALID[file], encoding="utf-8")
        before = _snapshot(folder)
        cwd = os.getcwd()
        os.chdir(folder)
        try:
            rc = entry(args)
        finally:
            os.chdir(cwd)
        out, err = capsys.readouterr()
        assert _snapshot(folder) == before and not out  # nothing written
    assert rc == 2 and err.count("\n") == 1, err
    shown = budget.format_bytes(available)
    detail = "a " if available == 2**10 else "400 samples x 7 columns, a "
    assert "log.csv: needs about " in err and f"of memory ({detail}" in err
    assert f"more than the {shown} this machine has available; use a shorter log" in err


def _peak_rss_kib(argv: list[str], cwd: Path) -> int:
    """Peak resident memory [KiB] of a command run in its own process (it must exit 0)."""
    import subprocess
    import sys

    code = ("import resource, subprocess, sys\n"
            "rc = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL).returncode\n"
            "assert rc == 0, rc\n"
            "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n")
    done = subprocess.run([sys.executable, "-c", code, sys.executable, "-m", "edm_sym", *argv],
                          cwd=cwd, capture_output=True, text=True, check=True)
    return int(done.stdout.split()[-1])


@pytest.mark.slow
def test_simulate_describe_and_export_of_a_two_million_sample_log_fit_in_2_gib(
    tmp_path: Path
) -> None:
    n, ts = 2_000_000, 1e-3
    t = np.arange(n) * ts
    omega = 3.0 * np.sin(2 * np.pi * 0.5 * t) + 0.5
    theta = np.cumsum(omega) * ts
    cols = np.column_stack([t, np.mod(theta, 2 * np.pi), theta, omega, np.gradient(omega, ts),
                            0.8 * np.tanh(20 * omega) + 0.01 * omega])
    np.savetxt(tmp_path / "big.csv", cols, delimiter=",", comments="", fmt="%.10g",
               header="t,theta_w,theta_uw,omega,alpha,tau_ext")
    result = str(REPO / "examples" / "auger" / "result.json")
    for argv in (["simulate", result, "big.csv", "-o", "sim.csv"],
                 ["describe", result, "--data", "big.csv"],
                 ["export", result, "--target", "c", "--data", "big.csv", "-o", "gen"]):
        peak = _peak_rss_kib(argv, tmp_path)
        assert peak < 2 * 2**20, f"{argv[0]}: {peak / 2**20:.2f} GiB"

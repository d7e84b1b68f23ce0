"""Generated code never holds a non-finite literal (INFINITY, NAN, inf, nan).

A literal like that compiles, and the compensator then outputs inf or nan in the
drive. Scanned: every golden and shipped generated file, and the C (double and
float) and Python of random matrices whose parameters sit at their range edges.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from firmware import cg_support as cg  # tests/ is on sys.path (pytest rootdir import mode)

from edm_sym.core.elements import all_elements
from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row
from edm_sym.outputs.render import render

REPO = Path(__file__).resolve().parents[1]
NON_FINITE = re.compile(r"\b(INFINITY|NAN|HUGE_VAL[FL]?|inf|nan|Infinity|NaN)\b|float\(\s*['\"](inf|nan)")


def _code_lines(text: str, suffix: str) -> list[str]:
    """The lines of code, comments and docstrings dropped (they may say 'inf' in prose)."""
    if suffix in (".c", ".h"):
        text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
        text = re.sub(r"//[^\n]*", "", text)
    else:
        text = re.sub(r'""".*?"""', "", text, flags=re.S)
        text = re.sub(r"#[^\n]*", "", text)
    return text.splitlines()


def _non_finite(text: str, suffix: str) -> list[str]:
    return [ln.strip() for ln in _code_lines(text, suffix) if NON_FINITE.search(ln)]


GENERATED = sorted(p for folder in ("tests/golden", "generated")
                   for p in (REPO / folder).rglob("*") if p.suffix in (".c", ".h", ".py"))


def test_there_are_generated_files_to_scan() -> None:
    assert len(GENERATED) >= 6


@pytest.mark.parametrize("path", GENERATED, ids=[str(p.relative_to(REPO)) for p in GENERATED])
def test_goldens_hold_no_non_finite_literal(path: Path) -> None:
    assert not _non_finite(path.read_text(), path.suffix)


def test_the_scan_finds_a_planted_literal() -> None:
    assert _non_finite("double x = INFINITY; /* inf is fine here */", ".c") == ["double x = INFINITY;"]
    assert _non_finite("y = float('nan')  # nan", ".py") == ["y = float('nan')"]
    assert not _non_finite("/* INFINITY */\nint inflate = 1;", ".c")


def test_random_matrices_at_their_range_edges_export_finite_literals() -> None:
    rng = np.random.default_rng(18)
    codes = [e.code for e in all_elements()]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for k in range(40):
            n, m = int(rng.integers(1, 5)), int(rng.integers(1, 5))
            rows = tuple(Row(int(rng.integers(0, len(cg.INPUTS))),
                             tuple(Gene(int(rng.choice(codes)), float(rng.choice([0.0, 1.0, rng.uniform()])))
                                   for _ in range(n))) for _ in range(m))
            comp = Compensator(ElementMatrix(cg.INPUTS, rows), cg.TS, {}, 20.0)
            result = cg.as_result(comp)
            for real in ("double", "float"):
                for name, text in render(result, "c", prefix=f"r{k}", real=real).items():
                    assert not _non_finite(text, Path(name).suffix), f"matrix {k} ({real}): {comp.matrix}"
            for name, text in render(result, "python", prefix=f"r{k}").items():
                assert not _non_finite(text, Path(name).suffix), f"matrix {k}: {comp.matrix}"

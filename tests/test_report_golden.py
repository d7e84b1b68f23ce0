"""The report's .tex is deterministic: fresh renders equal the golden files.

The golden files change only through ``python tests/update_golden_report.py``.
"""

from __future__ import annotations

import difflib
from pathlib import Path

import pytest
import update_golden_report as ugr  # tests/ is on sys.path (pytest rootdir)


@pytest.mark.parametrize("case", ugr.CASES, ids=lambda c: c.name)
def test_report_tex_matches_golden(case: ugr.Case, tmp_path: Path) -> None:
    golden = ugr.GOLDEN / f"{case.name}_report.tex"
    fresh = ugr.render_case(case, tmp_path)
    expected = golden.read_text()
    if fresh != expected:
        diff = "".join(difflib.unified_diff(expected.splitlines(True), fresh.splitlines(True),
                                            str(golden), "fresh", n=1))
        pytest.fail(f"{golden.name} differs (run python tests/update_golden_report.py if the "
                    f"change is intended):\n{diff[:4000]}")


def test_normalize_blanks_only_the_versions() -> None:
    text = "numpy & 2.4.6 \\\\\nseed & 3 \\\\\nedm\\_sym & 0.1.0 \\\\\n"
    assert ugr.normalize(text) == "numpy & <version> \\\\\nseed & 3 \\\\\nedm\\_sym & <version> \\\\\n"


def test_golden_reports_hold_no_dates_or_absolute_paths() -> None:
    for case in ugr.CASES:
        text = (ugr.GOLDEN / f"{case.name}_report.tex").read_text()
        assert "/tmp" not in text and str(ugr.REPO) not in text
        assert "\\today" not in text and "\\date{}" in text

"""The LaTeX model report: what an EDM compensator is, checked physically, reproducible.

``write_report(result, out_dir, ...)`` writes ``<prefix>_report.tex`` with its
figures (``<prefix>_fig_*.pdf``) and, with ``pdf=True``, compiles
``<prefix>_report.pdf`` with latexmk. The parts:

* :mod:`edm_sym.outputs.report.runs` -- the compensator (and the LuGre baseline) on the data logs;
* :mod:`edm_sym.outputs.report.logs` -- each log's contributions and time responses, the fit over all;
* :mod:`edm_sym.outputs.report.blocks` -- a row's simplified expression as a chain of blocks;
* :mod:`edm_sym.outputs.report.diagrams` -- the TikZ pictures' layout and labels;
* :mod:`edm_sym.outputs.report.rows` -- one row's equations, difference equations and physical terms;
* :mod:`edm_sym.outputs.report.context` -- the validated template context;
* :mod:`edm_sym.outputs.report.figures` -- the matplotlib figures;
* :mod:`edm_sym.outputs.report.pdf` -- latexmk, the log, the clean-up.

See ``docs/report.md``.
"""

from __future__ import annotations

from edm_sym.outputs.report.write import write_report

__all__ = ["write_report"]

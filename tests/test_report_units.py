"""The report's parameter units, traced along each row."""

from __future__ import annotations

import re

import pytest

from edm_sym.core.elements import all_elements
from edm_sym.core.matrix import Compensator, make_matrix
from edm_sym.core.result import EdmResult
from edm_sym.engines.symbolic import decode
from edm_sym.outputs.printing.latex import EdmLatexPrinter
from edm_sym.outputs.report.units import format_unit, param_units, parse_unit


def _units(inputs: tuple[str, ...], rows: list, axis: str = "rotary") -> dict:
    comp = Compensator(make_matrix(inputs, rows), 1e-3, {}, 10.0)
    result = EdmResult(comp, "tau", (), {"seed": None, "package_version": "t",
                                         "data_sha256": None}, axis=axis)
    return param_units(decode(result, systems=False))


@pytest.mark.parametrize(("axis", "viscous", "inertia"), [("rotary", "N m s/rad", "kg m^2"),
                                                          ("linear", "N s/m", "kg")])
def test_a_gain_takes_the_unit_from_its_input_to_the_output(axis: str, viscous: str,
                                                           inertia: str) -> None:
    u = _units(("omega", "alpha"), [("omega", [("dead_zone", 0.5), ("gain", 0.7)]),
                                    ("alpha", [("lpf", 0.5), ("gain", 0.7)])], axis)
    vel = "rad/s" if axis == "rotary" else "m/s"
    assert u[0, 0].si == vel  # the dead zone's level is in the input's unit
    assert u[0, 1].si == viscous and u[0, 1].relative == "output unit per input unit"
    assert u[1, 0].si == "rad/s"  # a corner frequency, whatever the axis
    assert u[1, 1].si == inertia


def test_dimensionless_and_angle_signals_in_a_row() -> None:
    u = _units(("omega",), [("omega", [("sign", 0.0), ("gain", 0.7)]),
                            ("omega", [("gain", 0.6), ("sin_amp", 0.7)]),
                            ("omega", [("atan", 0.5), ("gain", 0.7)])])
    assert u[0, 1].si == "N m"  # a sign is dimensionless
    assert u[1, 0].si == "s"  # rad per rad/s: the sine's argument is an angle
    assert u[1, 1].si == "N m"
    assert u[2, 0].si == "s/rad"  # the slope of atan(a x) is 1 / unit of x
    assert u[2, 1].si == "N m"


def test_rows_that_fix_no_unit_say_why() -> None:
    u = _units(("x1", "omega"), [("x1", [("gain", 0.7), ("offset", 0.6)]),
                                 ("omega", [("gain", 0.6), ("gain", 0.7)]),
                                 ("omega", [("gain", 0.6), ("sign", 0.0)]),
                                 ("omega", [("power", 0.6), ("gain", 0.7)])])
    assert u[0, 0].si is None and "x1 has no physical role" in u[0, 0].why
    assert u[0, 1].si == "N m"  # an offset at the row's end is in the output's unit
    assert u[1, 0].si is None and re.search(r"a_\d+ after it scales the output too", u[1, 0].why)
    assert u[1, 1].si is None
    assert u[2, 0].si is None and "feeds sign" in u[2, 0].why
    assert u[3, 0].si == "1"  # the exponent
    assert u[3, 1].si is None and re.search(r"after the power a_\d+,", u[3, 1].why)


def test_unit_text_round_trips_and_prints() -> None:
    for text in ("N m s/rad", "kg m^2", "rad/s^2", "1", "N s/m", "s/rad", "s^2"):
        assert format_unit(parse_unit(text)) == text
    assert parse_unit("N m s/rad") == {"N": 1, "m": 1, "s": 1, "rad": -1}
    assert format_unit(parse_unit("1/(rad s)")) == "1/(s rad)"
    assert EdmLatexPrinter.breakable("a kg m^2 b") == r"a kg m\textsuperscript{2} b"


def test_every_scaling_element_declares_its_output_unit_scaled() -> None:
    for el in all_elements():
        assert el.unit_out in ("input", "one", "power", "scaled"), el.name
        assert (el.unit_out == "scaled") == el.scales_output, el.name


def test_a_linear_axis_report_reads_n_m_s_and_kg_everywhere(tmp_path, monkeypatch) -> None:
    """The report's tables, sentences and figures follow the result's axis."""
    import dataclasses

    import update_golden_report as ugr  # tests/ is on sys.path (pytest rootdir)

    from edm_sym.outputs.report import figures as fg
    from edm_sym.outputs.report import write_report

    labels: list[str] = []
    save = fg._save

    def record(fig, path):  # noqa: ANN001, ANN202
        labels.extend(t for ax in fig.axes for t in (ax.get_xlabel(), ax.get_ylabel()) if t)
        return save(fig, path)

    monkeypatch.setattr(fg, "_save", record)
    linear = dataclasses.replace(ugr.example_result(), axis="linear")
    result, kw = ugr.case_inputs(ugr.Case("lin", lambda: linear, lugre=True), tmp_path)
    tex = write_report(result, tmp_path, **kw)[0].read_text()

    assert r"N\,m" not in tex and "kg m" not in tex and r"kg\,m" not in tex
    assert "angular" not in tex  # roles: "velocity", "position"
    # The prose names the axis's quantity: a force, a reaction force observer.
    assert "torque" not in tex.replace("Reaction Torque Observer", "")  # the paper's title only
    assert "reaction force observer (RFOB)" in tex and "compensation force" in tex
    assert "Forces are in N, positions in m, velocities in m/s." in tex
    assert r"\shortstack[r]{RMS [N]\\ abstraction log}" in tex
    assert r"Row & RMS of the row [N] & RMSE with rows up to it [N] & Drop [N] \\" in tex
    assert re.search(r"fitness \$[-0-9.]+\$~N on its", tex)  # the LuGre paragraph
    assert re.search(r"LuGre \(conventional\) & \$[0-9.]+\$ & \$\\mathrm\{N\}\$ \\\\", tex)
    lugre = tex[tex.index(r"\label{tab:lugre}"):]
    for unit in (r"\mathrm{m/s}", r"\mathrm{N}", r"\mathrm{N/m}", r"\mathrm{N\,s/m}"):
        assert "& $" + unit + "$ \\\\" in lugre, unit
    assert re.search(r"over \$\\pm [0-9.]+\$~m/s", tex)  # the friction characteristic
    assert re.search(r"RMSE on the evaluation log & \$[0-9.]+\$~\$\\mathrm\{N\}\$ \\\\", tex)
    # A corner frequency stays in rad/s and a phase in rad whatever the axis.
    assert r"lpf: corner frequency & $100$" in tex

    assert labels and not [t for t in labels if "N m" in t or "rad/s" in t]
    assert "force [N]" in labels and "residual [N]" in labels and "velocity [m/s]" in labels
    assert "row RMS [N]" in labels and "RMSE [N]" in labels

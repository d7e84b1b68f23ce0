"""Report figures as small, deterministic vector PDFs (matplotlib).

Long logs are decimated (min/max envelope per bin, so spikes stay visible)
before plotting, which keeps each figure a few tens of kB and the whole report
well under 2 MB. PDF metadata carries no creation date, so equal inputs give
equal files.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from edm_sym.core.fitness import rms
from edm_sym.core.units import AxisUnits, axis_units

#: Points per plotted curve after decimation.
MAX_POINTS = 1500
#: Column width of the report in inches (A4 with 2.5 cm margins).
WIDTH = 6.0


def _units(units: AxisUnits | None) -> AxisUnits:
    """The axis's units; rotary when none is given (the default of every file)."""
    return units if units is not None else axis_units("rotary")


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    # Type 3 fonts: subsetting TrueType (type 42) costs about 0.2 s per figure.
    plt.rcParams.update({
        "font.size": 8, "axes.titlesize": 8, "axes.labelsize": 8, "legend.fontsize": 7,
        "xtick.labelsize": 7, "ytick.labelsize": 7, "lines.linewidth": 0.7,
        "pdf.fonttype": 3, "svg.hashsalt": "edm_sym", "axes.grid": True, "grid.alpha": 0.3,
    })
    return plt


def decimate(t: np.ndarray, y: np.ndarray, max_points: int = MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """Min/max envelope decimation to about ``max_points`` points.

    Parameters
    ----------
    t, y : numpy.ndarray
        Time and values, equally long.
    max_points : int
        Upper bound on the returned length.

    Returns
    -------
    t_out, y_out : numpy.ndarray
    """
    n = len(y)
    if n <= max_points:
        return np.asarray(t), np.asarray(y)
    bins = max_points // 2
    edges = np.linspace(0, n, bins + 1).astype(int)
    tt, yy = [], []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        seg = y[lo:hi]
        i, j = lo + int(np.argmin(seg)), lo + int(np.argmax(seg))
        for k in sorted((i, j)):
            tt.append(t[k])
            yy.append(y[k])
    return np.asarray(tt), np.asarray(yy)


def _save(fig, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    fig.savefig(tmp, format="pdf", metadata={"CreationDate": None, "ModDate": None,
                                             "Producer": "edm_sym", "Creator": "edm_sym"})
    tmp.replace(path)
    import matplotlib.pyplot as plt

    plt.close(fig)
    return path


def fitness_history(steps: Sequence[tuple[str, Sequence[float]]], path: Path, *,
                    units: AxisUnits | None = None) -> Path:
    """Best fitness per generation for each hierarchical step (paper, Fig. 17).

    Parameters
    ----------
    steps : sequence of (label, history)
    path : path-like
        The PDF to write.
    units : AxisUnits, optional
        The result's axis (the fitness is in its force unit); rotary by default.
    """
    u = _units(units)
    plt = _pyplot()
    k = max(1, len(steps))
    cols = min(k, 4)
    rows = (k + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(WIDTH, 1.6 * rows + 0.3), squeeze=False)
    for ax in axes.flat[k:]:
        ax.set_visible(False)
    for ax, (label, hist) in zip(axes.flat, steps, strict=False):
        ax.plot(np.arange(1, len(hist) + 1), hist, color="C0")
        ax.set_title(label)
        ax.set_xlabel("generation")
        ax.set_ylabel(f"fitness [{u.force}]")
    fig.tight_layout()
    return _save(fig, path)


def time_series(t: np.ndarray, target: np.ndarray, compensation: np.ndarray, path: Path, *,
                title: str = "", target_label: str = r"$\hat\tau_{ext}$ (target)",
                others: Sequence[tuple[str, np.ndarray]] = (),
                window: tuple[float, float] | None = None, units: AxisUnits | None = None) -> Path:
    """Target, compensation torque (force) and residual over time (paper, Figs. 24-25).

    Parameters
    ----------
    t, target, compensation : numpy.ndarray
        Time [s], the target and the EDM compensation, in the axis's force unit (N m or N).
    path : path-like
        The PDF to write.
    title : str
        Title of the upper panel (left-aligned; keep it short, the legend sits on the right).
    target_label : str
        Legend entry of the target.
    others : sequence of (label, numpy.ndarray)
        Further compensation torques to compare (e.g. the LuGre model's).
    window : (float, float), optional
        Show only ``t0 <= t <= t1`` (an enlarged view).
    units : AxisUnits, optional
        The result's axis; rotary by default.
    """
    u = _units(units)
    plt = _pyplot()
    t = np.asarray(t, dtype=float)
    sel = slice(None)
    if window is not None:
        idx = np.flatnonzero((t >= window[0]) & (t <= window[1]))
        sel = slice(int(idx[0]), int(idx[-1]) + 1) if len(idx) else slice(None)
    tt = t[sel]
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(WIDTH, 3.1), sharex=True)
    # The target is wide and grey underneath, the models thin on top: both stay visible.
    a1.plot(*decimate(tt, np.asarray(target)[sel]), color="0.6", lw=1.4, label=target_label)
    for k, (label, y) in enumerate(others):
        a1.plot(*decimate(tt, np.asarray(y)[sel]), color=f"C{k}", label=label)
    a1.plot(*decimate(tt, np.asarray(compensation)[sel]), color="C3",
            label=r"$\tau_{cmp}$ (EDM)")
    a1.set_ylabel(f"{u.effort} [{u.force}]")
    if title:
        a1.set_title(title, loc="left")
    a1.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=2 + len(others), frameon=False,
              borderaxespad=0.1)
    for k, (label, y) in enumerate(others):
        a2.plot(*decimate(tt, (np.asarray(target) - np.asarray(y))[sel]), color=f"C{k}",
                label=label.split(" ")[0])
    a2.plot(*decimate(tt, (np.asarray(target) - np.asarray(compensation))[sel]), color="C3",
            label="EDM")
    if others:
        a2.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=1 + len(others),
                  frameon=False, borderaxespad=0.1)
    a2.set_ylabel(f"residual [{u.force}]")
    a2.set_xlabel("time [s]")
    a2.set_xlim(float(tt[0]), float(tt[-1]))
    fig.tight_layout()
    return _save(fig, path)


def zoom_window(t: np.ndarray, residual: np.ndarray, fraction: float = 0.1) -> tuple[float, float]:
    """The stretch of ``fraction`` of the log where the residual's RMS is largest.

    The log is cut into ``round(1 / fraction)`` equal pieces; ties go to the
    earliest, so the choice is deterministic.

    Parameters
    ----------
    t, residual : numpy.ndarray
        Time [s] and the residual (target minus compensation).
    fraction : float
        Length of the window relative to the log, in (0, 1].

    Returns
    -------
    (float, float)
        The window's first and last time.
    """
    n = len(t)
    pieces = max(1, round(1.0 / fraction))
    edges = np.linspace(0, n, pieces + 1).astype(int)
    pieces_rms = [rms(residual[lo:hi]) if hi > lo else -1.0
                  for lo, hi in zip(edges[:-1], edges[1:], strict=True)]
    k = int(np.argmax(pieces_rms))
    lo, hi = int(edges[k]), max(int(edges[k + 1]) - 1, int(edges[k]))
    return float(t[lo]), float(t[hi])


def row_outputs(t: np.ndarray, rows: np.ndarray, path: Path, *, labels: Sequence[str]) -> Path:
    """Each row's output over time on a common scale (paper, Fig. 18 a-e)."""
    plt = _pyplot()
    m = len(rows)
    fig, axes = plt.subplots(m, 1, figsize=(WIDTH, 0.9 * m + 0.6), sharex=True, squeeze=False)
    lim = float(np.max(np.abs(rows))) * 1.05 or 1.0
    for ax, y, lab in zip(axes[:, 0], rows, labels, strict=True):
        ax.plot(*decimate(t, y), color="C2")
        ax.set_ylim(-lim, lim)
        ax.set_ylabel(lab, rotation=0, ha="right", va="center")
    axes[-1, 0].set_xlabel("time [s]")
    fig.tight_layout()
    return _save(fig, path)


def contributions(labels: Sequence[str], rms: Sequence[float], cumulative_rmse: Sequence[float],
                  path: Path, *, baseline: float | None = None,
                  units: AxisUnits | None = None) -> Path:
    """RMS of each row and the RMSE as rows are added one by one (paper, Fig. 18 f-j).

    Both are in the force unit of ``units`` (the result's axis; rotary by default).
    """
    u = _units(units)
    plt = _pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(WIDTH, 2.0))
    x = np.arange(len(labels))
    a1.bar(x, rms, color="C2", width=0.6)
    a1.set_xticks(x, labels)
    pad = max(0, 3 - len(labels)) / 2  # a lone bar keeps a bar's width
    a1.set_xlim(-0.6 - pad, len(labels) - 0.4 + pad)
    a1.set_ylabel(f"row RMS [{u.force}]")
    xs = np.arange(len(cumulative_rmse) + (baseline is not None))
    ys = ([baseline] if baseline is not None else []) + list(cumulative_rmse)
    ticks = (["none"] if baseline is not None else []) + [f"+{lab}" for lab in labels]
    a2.plot(xs, ys, marker="o", color="C0")
    a2.set_xticks(xs, ticks)
    a2.set_ylim(bottom=0.0)
    a2.set_ylabel(f"RMSE [{u.force}]")
    fig.tight_layout()
    return _save(fig, path)


def friction_curve(velocity: np.ndarray, rows: Sequence[tuple[str, np.ndarray]], path: Path, *,
                   lugre: np.ndarray | None = None, units: AxisUnits | None = None) -> Path:
    """Steady-state torque (force) against constant velocity: each row and their sum (paper, Fig. 13).

    Parameters
    ----------
    velocity : numpy.ndarray
        The constant velocities, in the axis's velocity unit (rad/s or m/s).
    rows : sequence of (label, numpy.ndarray)
        Each velocity row's settled output, in the axis's force unit.
    path : path-like
        The PDF to write.
    lugre : numpy.ndarray, optional
        The LuGre model's steady state, drawn dashed.
    units : AxisUnits, optional
        The result's axis; rotary by default.
    """
    u = _units(units)
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(WIDTH, 2.3))
    for k, (label, y) in enumerate(rows):
        ax.plot(velocity, y, color=f"C{(k + 2) % 10}", lw=0.8, label=label)
    if len(rows) > 1:
        total = np.sum([y for _, y in rows], axis=0)
        ax.plot(velocity, total, color="C3", lw=1.4, label="sum (EDM)")
    if lugre is not None:
        ax.plot(velocity, lugre, color="C0", lw=1.0, ls="--", label="LuGre")
    ax.set_xlabel(("angular velocity" if u.axis == "rotary" else "velocity")
                  + f" [{u.velocity}]")
    ax.set_ylabel(f"{u.effort} [{u.force}]")
    ax.legend(loc="upper left", ncol=2)
    fig.tight_layout()
    return _save(fig, path)

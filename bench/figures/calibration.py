"""Calibration figures: per axis, the sensor error A_m − A_r against A_r and θ with the LS fit,
the truth (when known) and the ideal sensor; residuals A_m − fit below."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from bench.figures.parameters import true_params
from bench.figures.save import save_figure
from calib.binning import binned_mean
from calib.conventions import AXES, reference_accel

if TYPE_CHECKING:
    from calib.calibration import Calibration
    from calib.io import Ensayo

FIGURE_BINS = 60
"""Bins of the binned means in the calibration figure (equal sample counts)."""
AXIS_LABEL = {"x": "x (A_rx = −g sin θ)", "y": "y (A_ry = −g cos θ)"}

# Drawing order: the data are a light background, the binned mean and its band sit above them,
# the model lines on top (the truth last, dashed, so a fit under it still shows).
Z_SCATTER, Z_IDEAL, Z_BAND, Z_BINNED, Z_FIT, Z_TRUE, Z_TEXT = 1, 2, 3, 4, 5, 6, 7
SCATTER_STYLE = {"ls": "none", "marker": ".", "ms": 1.5, "color": "0.55", "alpha": 0.15,
                 "rasterized": True, "zorder": Z_SCATTER}
"""The samples: light grey dots under everything else."""
FIT_STYLE = {"color": "tab:red", "lw": 2.0, "zorder": Z_FIT}
TRUE_STYLE = {"color": "tab:green", "lw": 2.0, "ls": "--", "zorder": Z_TRUE}
IDEAL_STYLE = {"color": "k", "lw": 1.2, "ls": ":", "zorder": Z_IDEAL}
BINNED_STYLE = {"color": "tab:blue", "lw": 1.5, "zorder": Z_BINNED}
BAND_STYLE = {"color": "tab:blue", "alpha": 0.25, "lw": 0, "zorder": Z_BAND}
VIEW_MARGIN = 1.6
"""The error panels' y range: this factor times the largest model line or binned-mean band
(the per-sample spread ±σ is shown in full in the residual panels below)."""


def _estimates_box(ax, f, axis: str, tp: Mapping | None) -> None:
    """Text box: bias and scale ± one standard deviation — the ``std`` column of
    ``tiltbench calibrate`` (its interval columns are not repeated here) — and the truth."""
    std = dict(zip(f.param_names, f.std, strict=True))
    lines = [f"bias  = {f.param('bias'):.5g} ± {std['bias']:.2g} m/s²",
             f"scale = {f.param('scale'):.5g} ± {std['scale']:.2g}",
             f"(± 1 std, σ² {f.sigma2_source})"]
    if tp:
        lines.append(f"true: bias {tp[f'bias_{axis}']:.5g} m/s², "
                     f"scale {tp[f'scale_{axis}']:.5g}")
    ax.text(0.98, 0.03, "\n".join(lines), transform=ax.transAxes, ha="right",
            va="bottom", fontsize=8, family="monospace", zorder=Z_TEXT,
            bbox={"facecolor": "white", "alpha": 0.9, "edgecolor": "0.7"})


def _binned(ax, xv: np.ndarray, yv: np.ndarray, sigma: float, what: str) -> float:
    """Binned mean of ``yv`` against ``xv`` with its ±2σ/√n band, above the scatter
    (:data:`FIGURE_BINS` bins of equal counts, so n and the band are the same in every bin).
    Returns the band half-width, m/s²."""
    bx, by, _ = binned_mean(xv, yv, FIGURE_BINS)
    half = 2.0 * sigma / np.sqrt(max(1.0, xv.size / FIGURE_BINS))
    ax.fill_between(bx, by - half, by + half, label=f"±2σ/√n = ±{half:.2g} m/s²", **BAND_STYLE)
    ax.plot(bx, by, label=f"binned mean of {what} ({FIGURE_BINS} bins)", **BINNED_STYLE)
    return half


def _residual_panel(rx, xv: np.ndarray, xlabel: str, resid: np.ndarray, sigma: float) -> None:
    """Residuals A_m − fit against ``xv`` with the ±σ lines, the binned mean and its ±2σ/√n
    band drawn over the samples."""
    rx.plot(xv, resid, label="residual A_m − fit", **SCATTER_STYLE)
    for sgn in (-1, 1):
        rx.axhline(sgn * sigma, color="tab:orange", lw=1.2, zorder=Z_IDEAL,
                   label=f"±σ = ±{sigma:.3g} m/s²" if sgn > 0 else None)
    rx.axhline(0.0, color="k", lw=0.8, zorder=Z_IDEAL)
    _binned(rx, xv, resid, sigma, "residual")
    rx.set_xlabel(xlabel)
    rx.set_ylabel("A_m − fit (m/s²)")
    rx.grid(True, alpha=0.3)
    rx.legend(loc="upper right", fontsize=7, ncol=3, markerscale=6)


def _axis_panels(fig, cal: Calibration, ensayo: Ensayo, axis: str,
                 truth: Mapping | None) -> None:
    """Draw the four panels of one axis into ``fig`` (a Figure or SubFigure).

    Top: the sensor error ``A_m − A_r`` (``= scale·A_r + bias`` in the model) against A_r and
    against θ; the LS fit, the truth and the ideal sensor (0) are lines on a scale set by them,
    so a few per cent of scale error and a bias of 0.1 m/s² stand apart. Bottom: residuals.
    """
    k = AXES.index(axis)
    f = cal.fits[axis]
    theta = np.asarray(ensayo.tita, dtype=float)
    a_m = np.asarray(ensayo.datos[:, k], dtype=float)
    a_r = reference_accel(theta, cal.g)[:, k]
    err = a_m - a_r
    b, s = f.param("bias"), f.param("scale")
    resid = a_m - ((1.0 + s) * a_r + b)
    sigma = float(np.sqrt(f.sigma2))
    tp = true_params(truth)
    gs = fig.add_gridspec(3, 2, height_ratios=[0.32, 3, 1.4])
    key = fig.add_subplot(gs[0, :])  # the legend of both error panels, above them
    key.axis("off")
    order = np.argsort(theta, kind="stable")
    for col, (xv, xlabel) in enumerate(((a_r, f"A_r{axis} (m/s²)"), (theta, "θ (rad)"))):
        ax = fig.add_subplot(gs[1, col])
        ax.plot(xv, err, label=f"A_m{axis} − A_r{axis} per sample (N = {ensayo.n})",
                **SCATTER_STYLE)
        half = _binned(ax, xv, err, sigma, "A_m − A_r")
        ar_line = np.array([a_r.min(), a_r.max()]) if col == 0 else a_r[order]
        x_line = ar_line if col == 0 else theta[order]
        fit_line = s * ar_line + b
        ax.axhline(0.0, label="ideal sensor (A_m = A_r): 0", **IDEAL_STYLE)
        ax.plot(x_line, fit_line, label=f"LS fit: {s:+.4f}·A_r {b:+.4f} m/s²", **FIT_STYLE)
        lines = [fit_line]
        if tp:
            tb, ts = tp[f"bias_{axis}"], tp[f"scale_{axis}"]
            true_line = ts * ar_line + tb
            ax.plot(x_line, true_line, label=f"truth: {ts:+.4f}·A_r {tb:+.4f} m/s²",
                    **TRUE_STYLE)
            lines.append(true_line)
        big = max(max(float(np.max(np.abs(v))) for v in lines), 2.0 * half)
        ax.set_ylim(-VIEW_MARGIN * big, VIEW_MARGIN * big)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"sensor error A_m{axis} − A_r{axis} (m/s²)")
        ax.grid(True, alpha=0.3)
        if col == 0:
            key.legend(*ax.get_legend_handles_labels(), loc="center", ncol=3, fontsize=8,
                       markerscale=6, frameon=False)
            _estimates_box(ax, f, axis, tp)
        else:
            ax.text(0.01, 0.02, f"per-sample spread ±σ = ±{sigma:.2g} m/s² runs beyond this "
                    "view (see the residuals below)", transform=ax.transAxes, fontsize=7,
                    color="0.3", zorder=Z_TEXT)
        _residual_panel(fig.add_subplot(gs[2, col], sharex=ax), xv, xlabel, resid, sigma)


def calibration_axis_figure(cal: Calibration, ensayo: Ensayo, axis: str,
                            truth: Mapping | None = None, level: float = 0.95,
                            title: str | None = None) -> Figure:
    """Sensor error of one axis against A_r (left) and θ (right), residuals below.

    Parameters
    ----------
    cal : the calibration.  ensayo : the run (θ rad, A_m m/s²).  axis : "x" or "y".
    truth : ``truth.json`` object (optional): the true error line is drawn dashed.
    level : kept for the callers; the text box gives ± 1 std, as the command line's ``std``.
    """
    del level  # the box states std, the same quantity as `tiltbench calibrate`
    fig = plt.figure(figsize=(12, 7), constrained_layout=True)
    _axis_panels(fig, cal, ensayo, axis, truth)
    fig.suptitle(title or f"Calibration, axis {AXIS_LABEL[axis]}: A_m − A_r = scale·A_r + bias"
                 f" — χ²/dof = {cal.fits[axis].chi2_dof:.3f}")
    return fig


def calibration_figure(cal: Calibration, ensayo: Ensayo, truth: Mapping | None = None,
                       level: float = 0.95) -> Figure:
    """Both axes in one figure (the ``calibrate --plot`` figure): per axis, the sensor error
    A_m − A_r with the fit, truth and ideal lines against A_r and θ, residuals below."""
    del level
    fig = plt.figure(figsize=(12, 13), constrained_layout=True)
    subs = fig.subfigures(2, 1)
    for k, a in enumerate(AXES):
        _axis_panels(subs[k], cal, ensayo, a, truth)
        subs[k].suptitle(f"axis {AXIS_LABEL[a]}: A_m − A_r = scale·A_r + bias — "
                         f"χ²/dof = {cal.fits[a].chi2_dof:.3f}")
    return fig


def save_calibration_plot(path: str | Path, cal: Calibration, ensayo: Ensayo,
                          force: bool = False, truth: Mapping | None = None,
                          level: float = 0.95) -> Path:
    """Write :func:`calibration_figure` as PNG or SVG (by extension), atomically."""
    return save_figure(calibration_figure(cal, ensayo, truth, level), path, force)

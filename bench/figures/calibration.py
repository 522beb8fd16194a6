"""Calibration figures: per axis, A_m and the fit against A_r and θ, residuals ±σ below."""

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
from calib.correct import apply_errors

if TYPE_CHECKING:
    from calib.calibration import Calibration
    from calib.io import Ensayo

FIGURE_BINS = 60
"""Bins of the residual binned mean in the calibration figure (equal sample counts)."""
AXIS_LABEL = {"x": "x (A_rx = −g sin θ)", "y": "y (A_ry = −g cos θ)"}


def _estimates_box(ax, f, axis: str, level: float, tp: Mapping | None) -> None:
    """Text box: bias and scale ± their level-L half-widths (and the true values)."""
    b, s, q = f.param("bias"), f.param("scale"), f.quantile(level)
    lines = [f"bias = {b:.5g} ± {q * f.std[0]:.2g} m/s²",
             f"scale = {s:.5g} ± {q * f.std[1]:.2g}",
             f"({100 * level:g}% intervals, σ² {f.sigma2_source})"]
    if tp:
        lines.append(f"true: bias {tp[f'bias_{axis}']:.5g}, "
                     f"scale {tp[f'scale_{axis}']:.5g}")
    ax.text(0.98, 0.03, "\n".join(lines), transform=ax.transAxes, ha="right",
            va="bottom", fontsize=8, family="monospace",
            bbox={"facecolor": "white", "alpha": 0.85, "edgecolor": "0.7"})


def _residual_panel(rx, xv: np.ndarray, xlabel: str, resid: np.ndarray, sigma: float) -> None:
    """Residuals against ``xv`` with the ±σ band and the binned mean with its ±2σ/√n band
    (:data:`FIGURE_BINS` bins of equal counts, so the band is exact per bin)."""
    rx.plot(xv, resid, ".", ms=1.2, color="tab:blue", alpha=0.3, rasterized=True,
            label="residual A_m − fit")
    rx.axhspan(-sigma, sigma, color="tab:orange", alpha=0.18, label=f"±σ = ±{sigma:.3g}")
    for sgn in (-1, 1):
        rx.axhline(sgn * sigma, color="tab:orange", lw=1)
    bx, by, _ = binned_mean(xv, resid, FIGURE_BINS)
    half = 2.0 * sigma / np.sqrt(max(1.0, xv.size / FIGURE_BINS))  # equal-count bins
    rx.plot(bx, by, color="k", lw=1.3, label=f"binned mean (±2σ/√n: ±{half:.2g})")
    rx.fill_between(bx, -half, half, color="k", alpha=0.12, lw=0)
    rx.axhline(0.0, color="0.3", lw=0.8)
    rx.set_xlabel(xlabel)
    rx.set_ylabel("residual (m/s²)")
    rx.grid(True, alpha=0.3)
    rx.legend(loc="upper right", fontsize=7, ncol=3)


def _axis_panels(fig, cal: Calibration, ensayo: Ensayo, axis: str,
                 truth: Mapping | None, level: float) -> None:
    """Draw the four panels of one axis into ``fig`` (a Figure or SubFigure)."""
    k = AXES.index(axis)
    f = cal.fits[axis]
    theta = np.asarray(ensayo.tita)
    a_m = np.asarray(ensayo.datos[:, k])
    a_r = reference_accel(theta, cal.g)[:, k]
    b, s = f.param("bias"), f.param("scale")
    fit = (1.0 + s) * a_r + b
    resid = a_m - fit
    sigma = float(np.sqrt(f.sigma2))
    tp = true_params(truth)
    gs = fig.add_gridspec(2, 2, height_ratios=[3, 1.4])
    order = np.argsort(theta, kind="stable")
    for col, (xv, xlabel) in enumerate(((a_r, f"A_r{axis} (m/s²)"), (theta, "θ (rad)"))):
        ax = fig.add_subplot(gs[0, col])
        ax.plot(xv, a_m, ".", ms=1.5, color="tab:blue", alpha=0.35, rasterized=True,
                label=f"measured A_m{axis} (N = {ensayo.n})")
        if col == 0:
            xs = np.array([a_r.min(), a_r.max()])
            ax.plot(xs, apply_errors(xs, b, s), color="tab:red", lw=2, label="LS fit")
            ax.plot(xs, xs, color="0.5", lw=1, ls=":", label="ideal sensor A_m = A_r")
            if tp:
                tb, ts = tp[f"bias_{axis}"], tp[f"scale_{axis}"]
                ax.plot(xs, (1 + ts) * xs + tb, color="tab:green", lw=1.5, ls="--",
                        label="true line")
        else:
            ax.plot(theta[order], fit[order], color="tab:red", lw=2, label="LS fit")
            if tp:
                tb, ts = tp[f"bias_{axis}"], tp[f"scale_{axis}"]
                ax.plot(theta[order], (1 + ts) * a_r[order] + tb, color="tab:green", lw=1.5,
                        ls="--", label="true model")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"A_m{axis} (m/s²)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left" if col == 0 else "best", fontsize=8)
        if col == 0:
            _estimates_box(ax, cal.fits[axis], axis, level, tp)
        _residual_panel(fig.add_subplot(gs[1, col], sharex=ax), xv, xlabel, resid, sigma)


def calibration_axis_figure(cal: Calibration, ensayo: Ensayo, axis: str,
                            truth: Mapping | None = None, level: float = 0.95,
                            title: str | None = None) -> Figure:
    """Fit of one axis against A_r (left) and θ (right), residuals with ±σ below.

    Parameters
    ----------
    cal : the calibration.  ensayo : the run (θ rad, A_m m/s²).  axis : "x" or "y".
    truth : ``truth.json`` object (optional): the true line is drawn dashed.
    level : level of the parameter intervals printed in the panel.
    """
    fig = plt.figure(figsize=(12, 7), constrained_layout=True)
    _axis_panels(fig, cal, ensayo, axis, truth, level)
    fig.suptitle(title or f"Calibration, axis {AXIS_LABEL[axis]}: A_m = (1 + scale)·A_r + bias"
                 f" — χ²/dof = {cal.fits[axis].chi2_dof:.3f}")
    return fig


def calibration_figure(cal: Calibration, ensayo: Ensayo, truth: Mapping | None = None,
                       level: float = 0.95) -> Figure:
    """Both axes in one figure (the ``calibrate --plot`` figure): per axis, A_m and the fit
    against A_r and against θ, residuals with the ±σ band below each."""
    fig = plt.figure(figsize=(12, 12), constrained_layout=True)
    subs = fig.subfigures(2, 1)
    for k, a in enumerate(AXES):
        _axis_panels(subs[k], cal, ensayo, a, truth, level)
        subs[k].suptitle(f"axis {AXIS_LABEL[a]} — χ²/dof = {cal.fits[a].chi2_dof:.3f}")
    return fig


def save_calibration_plot(path: str | Path, cal: Calibration, ensayo: Ensayo,
                          force: bool = False, truth: Mapping | None = None,
                          level: float = 0.95) -> Path:
    """Write :func:`calibration_figure` as PNG or SVG (by extension), atomically."""
    return save_figure(calibration_figure(cal, ensayo, truth, level), path, force)

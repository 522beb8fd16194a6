"""Calibration figures: per axis, the sensor error A_m − A_r against A_r and θ with the LS fit,
the truth (when known) and the ideal sensor; residuals A_m − fit below.

Every band and interval of one figure is at the same level L (``level``, 95 % unless given),
said in the legend and the title:

* the fitted line ``scale·A_r + bias`` with its confidence band ``± q·std(line)``,
  ``var(line) = [A_r 1] Cov [A_r 1]ᵀ`` (the fit's covariance,
  :class:`calib.calibration.ls.FitResult`);
* the binned mean with ``± q·σ/√n``, n the samples per bin (equal-count bins) and σ the
  per-sample noise std the fit used;
* the estimates box: ``estimate ± q·std`` (the half-width of the level-L interval; the
  command line prints std itself).

``q`` is the fit's two-sided quantile (:meth:`calib.calibration.ls.FitResult.quantile`: normal when
σ² is given, Student t when estimated). The residual panels also draw ±σ, the per-sample noise: a
spread of the data, not the uncertainty of an estimate.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from bench.figures.fit_quality import fit_quality
from bench.figures.parameters import true_params
from bench.figures.save import save_figure
from calib.conventions import AXES, reference_accel
from calib.stats.binning import binned_mean

if TYPE_CHECKING:
    from calib.calibration.tilt_plane import Calibration
    from calib.files.course import Ensayo

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


def _estimates_box(ax, f, axis: str, tp: Mapping | None, level: float) -> None:
    """Text box: bias and scale ± the half-width of their level-L interval (q·std), and the
    truth."""
    q = f.quantile(level)
    half = dict(zip(f.param_names, q * f.std, strict=True))
    lines = [f"bias  = {f.param('bias'):.5g} ± {half['bias']:.2g} m/s²",
             f"scale = {f.param('scale'):.5g} ± {half['scale']:.2g} (dimensionless)",
             f"(± half-width of the {_pct(level)} interval = {q:.3g} std; σ² {f.sigma2_source})"]
    if tp:
        lines.append(f"true: bias {tp[f'bias_{axis}']:.5g} m/s², "
                     f"scale {tp[f'scale_{axis}']:.5g}")
    ax.text(0.98, 0.03, "\n".join(lines), transform=ax.transAxes, ha="right",
            va="bottom", fontsize=8, family="monospace", zorder=Z_TEXT,
            bbox={"facecolor": "white", "alpha": 0.9, "edgecolor": "0.7"})


def _quality(fit) -> str:
    """χ²/dof of one axis's fit, or that no degree of freedom is left."""
    return fit_quality(fit.chi2_dof, fit.dof)


def _pct(level: float) -> str:
    return f"{100 * level:g} %"


def _binned(ax, xv: np.ndarray, yv: np.ndarray, sigma: float, what: str, q: float,
            level: float) -> float:
    """Binned mean of ``yv`` against ``xv`` with its ±q·σ/√n band (level L), above the
    scatter (:data:`FIGURE_BINS` bins of equal counts, so n and the band are the same in every
    bin). Returns the band half-width, m/s²."""
    bx, by, _ = binned_mean(xv, yv, FIGURE_BINS)
    n = max(1, xv.size // FIGURE_BINS)
    half = q * sigma / np.sqrt(n)
    ax.fill_between(bx, by - half, by + half, label=f"{_pct(level)} band of the binned mean: "
                    f"±{q:.3g}σ/√n = ±{half:.2g} m/s²\n(n = {n} samples per bin, σ the noise "
                    "std)", **BAND_STYLE)
    ax.plot(bx, by, label=f"binned mean of {what} ({FIGURE_BINS} bins)", **BINNED_STYLE)
    return half


def _line_band(f, a_r: np.ndarray, q: float) -> np.ndarray:
    """Half-width q·std of the fitted line ``scale·A_r + bias`` at each ``a_r``, m/s²:
    ``var = [A_r 1] Cov [A_r 1]ᵀ`` with Cov the fit's (scale, bias) covariance."""
    i, j = f.param_names.index("scale"), f.param_names.index("bias")
    c = np.asarray(f.cov, dtype=float)
    var = c[i, i] * a_r ** 2 + 2.0 * c[i, j] * a_r + c[j, j]
    return q * np.sqrt(np.clip(var, 0.0, None))


def _residual_panel(rx, xv: np.ndarray, xlabel: str, resid: np.ndarray, sigma: float,
                    q: float, level: float) -> None:
    """Residuals A_m − fit against ``xv`` with the ±σ lines (per-sample noise), the binned
    mean and its level-L band drawn over the samples."""
    rx.plot(xv, resid, label="residual A_m − fit", **SCATTER_STYLE)
    for sgn in (-1, 1):
        rx.axhline(sgn * sigma, color="tab:orange", lw=1.2, zorder=Z_IDEAL,
                   label=f"per-sample noise ±σ = ±{sigma:.3g} m/s²" if sgn > 0 else None)
    rx.axhline(0.0, color="k", lw=0.8, zorder=Z_IDEAL)
    _binned(rx, xv, resid, sigma, "residual", q, level)
    rx.set_xlabel(xlabel)
    rx.set_ylabel("A_m − fit (m/s²)")
    rx.grid(True, alpha=0.3)
    handles, labels = rx.get_legend_handles_labels()
    labels = [lab.split("\n")[0].replace(" of the binned mean", "") for lab in labels]
    rx.legend(handles, labels, loc="upper right", fontsize=7, ncol=2, markerscale=6)


def _axis_panels(fig, cal: Calibration, ensayo: Ensayo, axis: str,
                 truth: Mapping | None, level: float) -> None:
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
    q = f.quantile(level)
    tp = true_params(truth)
    gs = fig.add_gridspec(3, 2, height_ratios=[0.6, 3, 1.4])
    key = fig.add_subplot(gs[0, :])  # the legend of both error panels, above them
    key.axis("off")
    order = np.argsort(theta, kind="stable")
    for col, (xv, xlabel) in enumerate(((a_r, f"A_r{axis} (m/s²)"), (theta, "θ (rad)"))):
        ax = fig.add_subplot(gs[1, col])
        ax.plot(xv, err, label=f"A_m{axis} − A_r{axis} per sample (N = {ensayo.n})",
                **SCATTER_STYLE)
        half = _binned(ax, xv, err, sigma, "A_m − A_r", q, level)
        ar_line = np.linspace(a_r.min(), a_r.max(), 200) if col == 0 else a_r[order]
        x_line = ar_line if col == 0 else theta[order]
        fit_line = s * ar_line + b
        band = _line_band(f, ar_line, q)
        ax.axhline(0.0, label="ideal sensor (A_m = A_r): 0", **IDEAL_STYLE)
        ax.fill_between(x_line, fit_line - band, fit_line + band, color=FIT_STYLE["color"],
                        alpha=0.35, lw=0, zorder=Z_FIT,
                        label=f"{_pct(level)} confidence band of the LS fit\n"
                              f"(±{q:.3g}·std of the line, ≤ {band.max():.2g} m/s²)")
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
            key.legend(*ax.get_legend_handles_labels(), loc="center", ncol=2, fontsize=8,
                       markerscale=6, frameon=False)
            _estimates_box(ax, f, axis, tp, level)
        else:
            ax.text(0.01, 0.02, f"per-sample spread ±σ = ±{sigma:.2g} m/s² runs beyond this "
                    "view (see the residuals below)", transform=ax.transAxes, fontsize=7,
                    color="0.3", zorder=Z_TEXT)
        _residual_panel(fig.add_subplot(gs[2, col], sharex=ax), xv, xlabel, resid, sigma, q,
                        level)


def calibration_axis_figure(cal: Calibration, ensayo: Ensayo, axis: str,
                            truth: Mapping | None = None, level: float = 0.95,
                            title: str | None = None) -> Figure:
    """Sensor error of one axis against A_r (left) and θ (right), residuals below.

    Parameters
    ----------
    cal : the calibration.  ensayo : the run (θ rad, A_m m/s²).  axis : "x" or "y".
    truth : ``truth.json`` object (optional): the true error line is drawn dashed.
    level : the level of every band and interval drawn (module docstring).
    """
    fig = plt.figure(figsize=(12, 7.5), constrained_layout=True)
    _axis_panels(fig, cal, ensayo, axis, truth, level)
    fig.suptitle(title or f"Calibration, axis {AXIS_LABEL[axis]}: A_m − A_r = scale·A_r + bias"
                 f" — {_quality(cal.fits[axis])}; bands at {_pct(level)}")
    return fig


def calibration_figure(cal: Calibration, ensayo: Ensayo, truth: Mapping | None = None,
                       level: float = 0.95) -> Figure:
    """Both axes in one figure (the ``calibrate --plot`` figure): per axis, the sensor error
    A_m − A_r with the fit, truth and ideal lines against A_r and θ, residuals below; every
    band at ``level``."""
    fig = plt.figure(figsize=(12, 14), constrained_layout=True)
    subs = fig.subfigures(2, 1)
    for k, a in enumerate(AXES):
        _axis_panels(subs[k], cal, ensayo, a, truth, level)
        subs[k].suptitle(f"axis {AXIS_LABEL[a]}: A_m − A_r = scale·A_r + bias — "
                         f"{_quality(cal.fits[a])}; bands at {_pct(level)}")
    return fig


def save_calibration_plot(path: str | Path, cal: Calibration, ensayo: Ensayo,
                          force: bool = False, truth: Mapping | None = None,
                          level: float = 0.95) -> Path:
    """Write :func:`calibration_figure` as PNG or SVG (by extension), atomically."""
    return save_figure(calibration_figure(cal, ensayo, truth, level), path, force)

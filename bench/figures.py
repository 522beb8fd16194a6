"""Figures of a calibration, a vehicle run and the N analysis (matplotlib, Agg backend).

Every figure is built by a ``*_figure`` function returning a :class:`matplotlib.figure.Figure`
and written by :func:`save_figure` as PNG or SVG, chosen by the file extension, atomically
(refusing to overwrite without ``force``). Dense scatter layers are rasterized in SVG so the
files stay small. Metadata carrying dates is dropped so the same data give the same bytes.

Figures (all quantities in SI units, angles in rad):

* :func:`calibration_axis_figure` — per axis: measured A_m and the fitted line against A_r and
  against θ (course reports' figures 3–6), with the true line when the truth is known; under
  each, the residuals with the ±σ band, a binned mean (structure the model misses stands out)
  and the χ²/dof.
* :func:`parameters_figure` — the four estimates with their intervals at the level, next to
  the true values (z-scores).
* :func:`acceleration_figure` — the vehicle's measured, corrected (and true) accelerations.
* trajectory — raw and corrected paths, candidates, the confidence ellipse: drawn by
  :func:`bench.figures_trajectory.trajectory_figure` (the ``trajectory --plot`` figure).
* :func:`uncertainty_growth_figure` — ellipses growing along the corrected path and the
  position standard deviation against time (calibration part and vehicle-noise part).
* :func:`nmin_figure` — Mahalanobis distance of every candidate against the calibration size
  N with the level-L threshold, the data's N, the design N and the a-posteriori range.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402  (backend chosen first)
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from scipy import stats  # noqa: E402

from bench.record import binned_mean  # noqa: E402  (the recordings draw the same means)
from calib.conventions import AXES, reference_accel  # noqa: E402
from calib.io import atomic_write_bytes  # noqa: E402

if TYPE_CHECKING:
    from calib.calibration import Calibration
    from calib.io import Ensayo
    from calib.region import ArrivalRegion
    from calib.trajectory import Trajectory

FORMATS = {".png": "png", ".svg": "svg"}
DPI = 120
FIGURE_BINS = 60
"""Bins of the residual binned mean in the calibration figure (equal sample counts)."""
AXIS_LABEL = {"x": "x (A_rx = −g sin θ)", "y": "y (A_ry = −g cos θ)"}


def save_figure(fig: Figure, path: str | Path, force: bool = False) -> Path:
    """Write ``fig`` as PNG or SVG (by extension) atomically, then close it.

    Raises ``ValueError`` for another extension and ``FileExistsError`` if ``path`` exists
    and not ``force``.
    """
    path = Path(path)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        plt.close(fig)
        raise ValueError(f"{path}: figure format must be .png or .svg")
    if path.exists() and not force:
        plt.close(fig)
        raise FileExistsError(f"{path}: exists; pass --force to overwrite")
    buf = io.BytesIO()
    metadata = {"Date": None} if fmt == "svg" else {"Software": None}
    with plt.rc_context({"svg.hashsalt": "tiltbench"}):  # SVG ids without random salt
        fig.savefig(buf, format=fmt, dpi=DPI, metadata=metadata)
    plt.close(fig)
    return atomic_write_bytes(path, buf.getvalue(), force=force)


def _true_params(truth: Mapping | None) -> dict[str, float] | None:
    if not truth:
        return None
    from bench.validate import true_sensor_params

    return true_sensor_params(truth)


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
    tp = _true_params(truth)
    q = f.quantile(level)
    gs = fig.add_gridspec(2, 2, height_ratios=[3, 1.4])
    order = np.argsort(theta, kind="stable")
    for col, (xv, xlabel) in enumerate(((a_r, f"A_r{axis} (m/s²)"), (theta, "θ (rad)"))):
        ax = fig.add_subplot(gs[0, col])
        ax.plot(xv, a_m, ".", ms=1.5, color="tab:blue", alpha=0.35, rasterized=True,
                label=f"measured A_m{axis} (N = {ensayo.n})")
        if col == 0:
            xs = np.array([a_r.min(), a_r.max()])
            ax.plot(xs, (1 + s) * xs + b, color="tab:red", lw=2, label="LS fit")
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
            lines = [f"bias = {b:.5g} ± {q * f.std[0]:.2g} m/s²",
                     f"scale = {s:.5g} ± {q * f.std[1]:.2g}",
                     f"({100 * level:g}% intervals, σ² {f.sigma2_source})"]
            if tp:
                lines.append(f"true: bias {tp[f'bias_{axis}']:.5g}, "
                             f"scale {tp[f'scale_{axis}']:.5g}")
            ax.text(0.98, 0.03, "\n".join(lines), transform=ax.transAxes, ha="right",
                    va="bottom", fontsize=8, family="monospace",
                    bbox={"facecolor": "white", "alpha": 0.85, "edgecolor": "0.7"})
        rx = fig.add_subplot(gs[1, col], sharex=ax)
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


def parameters_figure(cal: Calibration, truth: Mapping | None = None, level: float = 0.95,
                      title: str | None = None) -> Figure:
    """The four estimates with their level-L intervals (and ±1 std), next to the true values.

    Under each panel: estimate, std and, when the truth is known, the true value and
    ``z = (estimate − true)/std``.
    """
    tp = _true_params(truth)
    fig, axs = plt.subplots(1, 4, figsize=(12, 4.2), constrained_layout=True)
    for i, (a, p) in enumerate((("x", "bias"), ("x", "scale"), ("y", "bias"), ("y", "scale"))):
        f = cal.fits[a]
        j = f.param_names.index(p)
        est, std, q = float(f.params[j]), float(f.std[j]), f.quantile(level)
        ax = axs[i]
        ax.errorbar([0], [est], yerr=[[q * std]], fmt="o", color="tab:blue", capsize=8,
                    label=f"estimate, {100 * level:g}% interval")
        ax.errorbar([0], [est], yerr=[[std]], fmt="none", color="tab:blue", lw=5, alpha=0.35,
                    label="± 1 std")
        lo, hi = est - q * std, est + q * std
        text = f"estimate {est:.6g}\nstd {std:.3g}"
        if tp:
            tv = tp[f"{p}_{a}"]
            ax.axhline(tv, color="tab:green", ls="--", lw=1.5, label="true value")
            lo, hi = min(lo, tv), max(hi, tv)
            text += f"\ntrue {tv:.6g}\nz = {(est - tv) / std:+.2f}"
        pad = 0.15 * (hi - lo)
        ax.set_ylim(lo - pad, hi + pad)
        ax.set_xlim(-1, 1)
        ax.set_xticks([])
        ax.set_xlabel(text, fontsize=8, family="monospace")
        ax.set_title(f"{p}_{a}" + (" (m/s²)" if p == "bias" else " (dimensionless)"))
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(True, axis="y", alpha=0.3)
    handles, labels = axs[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=8)
    fig.suptitle(title or f"Estimates with {100 * level:g}% intervals"
                 + (" against the true values" if tp else ""))
    return fig


def acceleration_figure(traj: Trajectory, true_acc: np.ndarray | None = None,
                        true_t: np.ndarray | None = None, bin_s: float = 1.0,
                        title: str | None = None) -> Figure:
    """Vehicle accelerations against time: measured samples (faint), and ``bin_s``-second
    means of the measured, corrected and (if known) true accelerations — the means show the
    bias and scale correction that the noise hides."""
    fig, axs = plt.subplots(2, 1, figsize=(11, 6.5), sharex=True, constrained_layout=True)
    bins = max(1, int(round((traj.t[-1] - traj.t[0]) / bin_s)))
    for k, a in enumerate(AXES):
        ax = axs[k]
        ax.plot(traj.t, traj.acc_raw[:, k], color="tab:blue", lw=0.4, alpha=0.25,
                label="measured A_m (samples)")
        mx, my, _ = binned_mean(traj.t, traj.acc_raw[:, k], bins)
        ax.plot(mx, my, color="0.35", lw=1.4, label=f"measured, {bin_s:g} s mean")
        cx, cy, _ = binned_mean(traj.t, traj.acc_corrected[:, k], bins)
        ax.plot(cx, cy, color="navy", lw=1.6,
                label=f"corrected (A_m − bias)/(1 + scale), {bin_s:g} s mean")
        if true_acc is not None:
            tt = traj.t if true_t is None else true_t
            ax.plot(tt, true_acc[:, k], color="tab:green", lw=1.5, ls="--", label="true")
        ax.set_ylabel(f"a_{a} (m/s²)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=7, ncol=2)
    axs[-1].set_xlabel("t (s)")
    fig.suptitle(title or "Vehicle accelerations")
    return fig


def uncertainty_growth_figure(traj: Trajectory, region: ArrivalRegion, cal: Calibration,
                              n_ellipses: int = 8, true_path: np.ndarray | None = None,
                              title: str | None = None) -> Figure:
    """Ellipses at the region's level growing along the corrected path; std against time.

    The covariance at each time is the arrival-point model applied to the trajectory
    truncated there (:func:`bench.record.position_cov_along`); the right panel splits the
    standard deviation into the calibration part and the vehicle-noise part.
    """
    from bench.record import position_cov_along
    from calib.region import Ellipse

    m = traj.t.shape[0]
    fig, (ax, sx) = plt.subplots(1, 2, figsize=(13, 5.8), constrained_layout=True,
                                 gridspec_kw={"width_ratios": [1.2, 1]})
    ax.plot(traj.pos_corrected[:, 0], traj.pos_corrected[:, 1], color="tab:blue", lw=1.4,
            label="corrected path")
    if true_path is not None:
        ax.plot(true_path[:, 0], true_path[:, 1], color="tab:green", ls="--", lw=1.2,
                label="true path")
    snaps = np.unique(np.linspace(0, m - 1, n_ellipses + 1).round().astype(int))[1:]
    covs = position_cov_along(traj, cal, region.noise_var, snaps)
    cmap = plt.get_cmap("viridis")
    for i, (k, c) in enumerate(zip(snaps, covs, strict=True)):
        e = Ellipse.from_cov(traj.pos_corrected[k], c, region.level).boundary()
        ax.plot(e[:, 0], e[:, 1], color=cmap(i / max(1, len(snaps) - 1)), lw=1.2,
                label=f"t = {traj.t[k] - traj.t[0]:.0f} s")
    for name, c in region.candidates.items():
        ax.plot(*c, "x", color="tab:red", ms=8, mew=2)
        ax.annotate(name, c, textcoords="offset points", xytext=(5, 5), color="tab:red")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    ax.set_title(f"{100 * region.level:g}% ellipses along the corrected path")
    idx = np.unique(np.linspace(0, m - 1, 150).round().astype(int))
    total = position_cov_along(traj, cal, region.noise_var, idx)
    zero = np.zeros((2, 2))
    cal_only = position_cov_along(traj, cal, zero, idx)
    tt = traj.t[idx] - traj.t[0]
    for k, a in enumerate(AXES):
        color = ("tab:blue", "tab:orange")[k]
        sx.plot(tt, np.sqrt(total[:, k, k]), color=color, lw=2, label=f"{a}: total")
        sx.plot(tt, np.sqrt(cal_only[:, k, k]), color=color, lw=1, ls="--",
                label=f"{a}: calibration part")
        sx.plot(tt, np.sqrt(np.clip(total[:, k, k] - cal_only[:, k, k], 0, None)), color=color,
                lw=1, ls=":", label=f"{a}: vehicle-noise part")
    sx.set_xlabel("t (s)")
    sx.set_ylabel("std of the corrected position (m)")
    sx.grid(True, alpha=0.3)
    sx.legend(fontsize=7)
    sx.set_title("error propagation over time")
    fig.suptitle(title or "Uncertainty of the corrected position along the run")
    return fig


def nmin_figure(region: ArrivalRegion, n_data: int, g: float = 9.8,
                n_range: tuple[float, float] = (1e2, 1e6), title: str | None = None) -> Figure:
    """Mahalanobis distance of each candidate against the calibration size N.

    Uses :class:`calib.nmin.PositionCovModel` (``Σ_P(N) = A/N + B``, θ uniform) built from the
    region; a candidate is inside the level-L region while its distance is below
    ``r = sqrt(χ²₂(L))``. Marks the data's N, the design N (all regions disjoint) and the
    a-posteriori N range with the estimate held fixed; the dashed curves leave out the
    vehicle noise (the course reports' assumption).
    """
    from calib.nmin import PositionCovModel, design_nmin, posterior_nrange
    from calib.region import chi2_2dof

    model = PositionCovModel.from_region(region, g)
    cal_only = PositionCovModel.from_region(region, g, include_noise=False)
    r = float(np.sqrt(chi2_2dof(region.level)))
    ns = np.logspace(np.log10(n_range[0]), np.log10(n_range[1]), 300)
    fig, ax = plt.subplots(figsize=(10, 5.5), constrained_layout=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (name, c) in enumerate(region.candidates.items()):
        d = np.asarray(c, float) - region.estimate
        full = [np.sqrt(d @ np.linalg.solve(model.cov(n), d)) for n in ns]
        part = [np.sqrt(d @ np.linalg.solve(cal_only.cov(n), d)) for n in ns]
        col = colors[i % len(colors)]
        ax.plot(ns, full, color=col, lw=2, label=f"{name}")
        ax.plot(ns, part, color=col, lw=1, ls="--")
    ax.axhline(r, color="k", lw=1.2, label=f"inside below r = √χ²₂({region.level:g}) = {r:.2f}")
    ax.axvline(n_data, color="0.3", ls=":", label=f"data N = {n_data}")
    des = design_nmin(region.candidates, model, region.level)
    if des["n"] is not None and n_range[0] <= des["n"] <= n_range[1]:
        ax.axvline(des["n"], color="tab:purple", ls="-.", label=f"design N = {des['n']}")
    post = posterior_nrange(region.estimate, region.candidates, model, region.level)
    if post["n_min"] is not None:
        hi = post["n_max"] if post["n_max"] is not None else n_range[1]
        ax.axvspan(max(post["n_min"], n_range[0]), min(hi, n_range[1]), color="tab:green",
                   alpha=0.08, label=f"a posteriori: decides {post['letter']} "
                   f"for N ≥ {post['n_min']}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("calibration samples N (θ uniform over [0, 2π))")
    ax.set_ylabel("Mahalanobis distance to the estimate")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(title or "N analysis: Mahalanobis distance of each candidate from the "
                 "estimated arrival\n(solid: calibration + vehicle noise; dashed: calibration "
                 "part only, as the course reports)", fontsize=10)
    return fig


def write_calibration_figures(out: str | Path, cal: Calibration, ensayo: Ensayo,
                              truth: Mapping | None = None, level: float = 0.95,
                              fmt: str = "png", force: bool = False) -> dict[str, Path]:
    """``calibration_x``, ``calibration_y`` and ``parameters`` figures in ``out``."""
    out = Path(out)
    paths = {}
    for a in AXES:
        paths[f"calibration_{a}"] = save_figure(
            calibration_axis_figure(cal, ensayo, a, truth, level),
            out / f"calibration_{a}.{fmt}", force)
    paths["parameters"] = save_figure(parameters_figure(cal, truth, level),
                                      out / f"parameters.{fmt}", force)
    return paths


def write_vehicle_figures(out: str | Path, traj: Trajectory, region: ArrivalRegion,
                          cal: Calibration, n_data: int, true_final: np.ndarray | None = None,
                          true_path: np.ndarray | None = None,
                          true_acc: np.ndarray | None = None, fmt: str = "png",
                          force: bool = False) -> dict[str, Path]:
    """``trajectory`` (helper figure of ``trajectory --plot``), ``acceleration``,
    ``uncertainty_growth`` and ``nmin`` figures in ``out``."""
    from bench.figures_trajectory import trajectory_figure

    out = Path(out)
    paths = {"trajectory": save_figure(trajectory_figure(traj, region, truth=true_final),
                                       out / f"trajectory.{fmt}", force),
             "acceleration": save_figure(acceleration_figure(traj, true_acc),
                                         out / f"acceleration.{fmt}", force),
             "uncertainty_growth": save_figure(
                 uncertainty_growth_figure(traj, region, cal, true_path=true_path),
                 out / f"uncertainty_growth.{fmt}", force),
             "nmin": save_figure(nmin_figure(region, n_data, cal.g), out / f"nmin.{fmt}",
                                 force)}
    return paths


def interval_quantile(level: float) -> float:
    """Two-sided normal quantile ``Φ⁻¹((1 + L)/2)`` (used in captions)."""
    return float(stats.norm.ppf(0.5 + level / 2))


__all__ = ["acceleration_figure", "calibration_axis_figure", "calibration_figure",
           "nmin_figure", "save_calibration_plot",
           "parameters_figure", "save_figure", "uncertainty_growth_figure",
           "write_calibration_figures", "write_vehicle_figures"]

"""Figure of a fused vehicle run: dead reckoning, the position fixes, the Kalman path and the
fused level-L arrival region next to the dead-reckoning one, with the candidates.

A turning run (dead reckoning :class:`calib.vehicle.turning_trajectory.TurningTrajectory`, region
:class:`calib.vehicle.turning_trajectory.TurningRegion`) draws its region the same way, may show the
true path, and gets a second panel: the heading ψ of the filter ±σ, of the dead reckoning and
of the truth when known."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.patches import Polygon

from bench.figures.save import FORMATS, save_figure
from bench.figures.trajectory import BOX_COLOR, REGION_COLOR
from calib.fusion.linear import FusionResult
from calib.vehicle.region import ArrivalRegion, Ellipse
from calib.vehicle.trajectory import Trajectory
from calib.vehicle.turning_trajectory import (
    TurningRegion,
    TurningTrajectory,
    dead_reckoning_path,
    heading_error,
)

FUSED_COLOR = "tab:green"
SMOOTHED_COLOR = "tab:orange"
TRUE_COLOR = "black"


def fusion_figure(traj: Trajectory | TurningTrajectory, region: ArrivalRegion | TurningRegion,
                  fused: FusionResult, fixes: np.ndarray, level: float, decision: str | None,
                  *, candidates: Mapping | None = None, true_path: np.ndarray | None = None,
                  true_heading: tuple[np.ndarray, np.ndarray] | None = None,
                  consistency=None) -> plt.Figure:
    """Dead-reckoned (corrected) path and its level-L region, the fixes (m), the filtered
    path (and the RTS smoothed one when ``fused`` holds it), the fused level-L region of the
    arrival, the candidates, and the true path when ``true_path`` is given.

    Both regions are drawn at the same level, so their sizes compare directly: the fixes
    remove the integrated vehicle noise that dominates dead reckoning.

    A turning run: ``region`` a :class:`~calib.vehicle.turning_trajectory.TurningRegion`, optional
    ``true_path`` (n, 2) m and ``true_heading`` (t s, ψ rad); a heading panel below.
    ``candidates`` default ``region.candidates``.

    The innovation gate's rejected fixes (``fused.fix_used`` False) are circled in red; with
    a ``consistency`` (:class:`calib.fusion.innovation_check.Consistency`) that is not consistent
    the fused region is not drawn and the title says so (no region: the inputs are
    inconsistent)."""
    turning = isinstance(traj, TurningTrajectory)
    if turning and true_heading is not None:
        fig, (ax, axh, axe) = plt.subplots(3, 1, figsize=(8, 11), height_ratios=[3, 1.1, 1.1],
                                           constrained_layout=True)
    elif turning:
        fig, (ax, axh) = plt.subplots(2, 1, figsize=(8, 9), height_ratios=[3, 1.1],
                                      constrained_layout=True)
    else:
        fig, ax = plt.subplots(figsize=(8, 6.5), constrained_layout=True)
    sa = region.ellipse.semi_axes
    ax.add_patch(Polygon(region.ellipse.boundary(), closed=True,
                         facecolor=to_rgba(REGION_COLOR, 0.12), edgecolor=REGION_COLOR,
                         lw=1.2, zorder=1,
                         label=f"{100 * level:g} % region, dead reckoning"
                               + (f" ({sa[0]:.2g} × {sa[1]:.2g} m, decision "
                                  f"{region.decision or 'undecided'})" if turning else "")))
    est = np.asarray(fused.final_position, dtype=float).reshape(2)
    cov = np.asarray(fused.final_position_cov, dtype=float).reshape(2, 2)
    inconsistent = consistency is not None and not consistency.consistent
    if not inconsistent:  # an inconsistent run has no region to draw
        ell = Ellipse.from_cov(est, cov, level)
        ax.add_patch(Polygon(ell.boundary(), closed=True, facecolor=to_rgba(FUSED_COLOR, 0.35),
                             edgecolor=FUSED_COLOR, lw=1.6, zorder=4,
                             label=f"{100 * level:g} % region, fused "
                                   f"({ell.semi_axes[0]:.2g} × {ell.semi_axes[1]:.2g} m)"))
    dr = dead_reckoning_path(traj)
    ax.plot(dr[:, 0], dr[:, 1], color="tab:blue", lw=1.2, zorder=2,
            label="dead reckoning (corrected readings"
                  + (", gyro heading)" if turning else ")"))
    ax.plot(fixes[:, 0], fixes[:, 1], ".", color="0.35", ms=4, zorder=3,
            label=f"position fixes ({fixes.shape[0]})")
    rejected = ~np.asarray(fused.fix_used, dtype=bool).reshape(-1)
    if rejected.shape[0] == fixes.shape[0] and rejected.any():
        ax.plot(fixes[rejected, 0], fixes[rejected, 1], "o", mfc="none", mec="tab:red", ms=9,
                mew=1.5, zorder=4.5, label=f"rejected by the gate ({int(rejected.sum())})")
    path = np.asarray(fused.estimates)[..., :2].reshape(-1, 2)
    ax.plot(path[:, 0], path[:, 1], color=FUSED_COLOR, lw=1.6, zorder=3,
            label="Kalman filter")
    smoothed = np.asarray(fused.smoothed, dtype=float)
    if smoothed.size:  # --smoother: the RTS path, every fix used both ways
        sp = smoothed[..., :2].reshape(-1, 2)
        ax.plot(sp[:, 0], sp[:, 1], color=SMOOTHED_COLOR, lw=1.4, ls="-.", zorder=3.2,
                label="RTS smoother")
    if true_path is not None:
        tp = np.asarray(true_path, dtype=float)
        ax.plot(tp[:, 0], tp[:, 1], "--", color=TRUE_COLOR, lw=1.0, zorder=3.5,
                label="true path (truth.json)")
    cands = region.candidates if candidates is None else candidates
    for k, (name, c) in enumerate(cands.items()):
        ax.plot(*c, "x", color=BOX_COLOR, ms=9, mew=2, zorder=5,
                label="candidate point" if k == 0 else None)
        ax.annotate(name, c, textcoords="offset points", xytext=(6, 6), color=BOX_COLOR,
                    fontsize=12, weight="bold", zorder=5)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    if inconsistent:
        ax.set_title("Fusion with position fixes — INCONSISTENT inputs: no region",
                     color="tab:red")
        ax.text(0.5, 0.02, consistency.verdict(), transform=ax.transAxes, ha="center",
                va="bottom", fontsize=7, color="tab:red", wrap=True)
    else:
        ax.set_title(f"Fusion with position fixes — decision: {decision or 'undecided'}")
    ax.legend(loc="best", fontsize=8)
    if turning:
        _heading_panel(axh, traj, fused, true_heading)
    if turning and true_heading is not None:
        _heading_error_panel(axe, traj, fused, true_heading)
    return fig


def _heading_panel(ax: plt.Axes, traj: TurningTrajectory, fused: FusionResult,
                   true_heading: tuple[np.ndarray, np.ndarray] | None) -> None:
    """Heading ψ (rad) against time (s from the first sample): filtered ±σ, dead reckoning
    (the gyro integrated), truth."""
    t0 = float(traj.t[0])
    t = np.asarray(fused.times, dtype=float) - t0
    psi = np.asarray(fused.estimates, dtype=float)[:, 4]
    sd = np.sqrt(np.clip(np.asarray(fused.covariances, dtype=float)[:, 4, 4], 0.0, None))
    ax.fill_between(t, psi - sd, psi + sd, color=to_rgba(FUSED_COLOR, 0.3), lw=0,
                    label=f"±σ (final σ = {sd[-1]:.2g} rad)")
    ax.plot(t, psi, color=FUSED_COLOR, lw=1.4, label="Kalman filter")
    ax.plot(traj.t - t0, traj.heading, color="tab:blue", lw=1.0,
            label="dead reckoning (gyro integrated)")
    if true_heading is not None:
        ax.plot(np.asarray(true_heading[0], float) - t0, true_heading[1], "--",
                color=TRUE_COLOR, lw=1.0, label="true (truth.json)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("heading ψ (rad)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)


def _heading_error_panel(ax: plt.Axes, traj: TurningTrajectory, fused: FusionResult,
                         true_heading: tuple[np.ndarray, np.ndarray]) -> None:
    """Heading error against the truth's samples (mrad): filtered ±σ, dead reckoning."""
    t0 = float(traj.t[0])
    tt, pt = (np.asarray(v, dtype=float) for v in true_heading)
    keep = (tt >= traj.t[0]) & (tt <= traj.t[-1])
    tt, pt = tt[keep], pt[keep]
    times = np.asarray(fused.times, dtype=float)
    err = 1e3 * heading_error(times, np.asarray(fused.estimates, float)[:, 4], tt, pt)
    sd = 1e3 * np.sqrt(np.interp(tt, times, np.clip(
        np.asarray(fused.covariances, float)[:, 4, 4], 0.0, None)))
    ax.fill_between(tt - t0, -sd, sd, color=to_rgba(FUSED_COLOR, 0.3), lw=0, label="±σ")
    ax.plot(tt - t0, err, ".-", color=FUSED_COLOR, lw=1.0, ms=3, label="Kalman filter")
    ax.plot(tt - t0, 1e3 * heading_error(traj.t, traj.heading, tt, pt), ".-",
            color="tab:blue", lw=1.0, ms=3, label="dead reckoning")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("ψ − ψ true (mrad)")
    ax.set_title("heading error against truth.json (its samples, every second)", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)


def save_fusion_plot(path: str | Path, *args, force: bool = False, **kwargs) -> Path:
    """Write :func:`fusion_figure` as PNG or SVG (by extension), atomically."""
    if FORMATS.get(Path(path).suffix.lower()) is None:  # before drawing anything
        raise ValueError(f"{path}: plot format must be .png or .svg")
    return save_figure(fusion_figure(*args, **kwargs), path, force=force)

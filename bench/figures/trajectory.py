"""Figure of a reconstructed vehicle run: raw and corrected paths, candidates, the level-L
region (ellipse) and the course's 3σ box bound (rectangles)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.patches import Polygon, Rectangle

from bench.figures.save import FORMATS, save_figure
from calib.vehicle.region import ArrivalRegion
from calib.vehicle.trajectory import Trajectory

Z_REGION, Z_PATH, Z_BOX, Z_CANDIDATE, Z_ESTIMATE, Z_TRUE = 1, 2, 3, 4, 5, 6
"""Drawing order: the true arrival last, so it is never hidden under its candidate's cross."""
REGION_COLOR = "tab:purple"
BOX_COLOR = "tab:red"


def course_box_patches(region: ArrivalRegion) -> list[Rectangle]:
    """The course's 3σ box bound around each candidate: the axis-aligned rectangle
    ``c ± (δP_x, δP_y)`` (m) of :func:`calib.vehicle.region.course_box_bound` (a per-axis bound, so
    a box, not an ellipse)."""
    dx, dy = (float(v) for v in region.course_box_bound)
    return [Rectangle((float(c[0]) - dx, float(c[1]) - dy), 2 * dx, 2 * dy, fill=False,
                      edgecolor=BOX_COLOR, lw=1.0, ls="--", zorder=Z_BOX)
            for c in region.candidates.values()]


def trajectory_figure(traj: Trajectory, region: ArrivalRegion, title: str | None = None,
                      truth: np.ndarray | None = None) -> plt.Figure:
    """Raw and corrected trajectories (m), candidates, the level-L region around the estimate
    (a shaded ellipse) and the course's 3σ box bound around each candidate (dashed
    rectangles); the true arrival, when known, drawn on top with its own marker."""
    fig, ax = plt.subplots(figsize=(8, 6.5), constrained_layout=True)
    e = region.ellipse.boundary()
    ax.add_patch(Polygon(e, closed=True, facecolor=to_rgba(REGION_COLOR, 0.18),
                         edgecolor=REGION_COLOR, lw=1.4, zorder=Z_REGION,
                         label=f"{100 * region.level:g} % region of the arrival "
                               "(calibration + vehicle noise)"))
    ax.plot(traj.pos_raw[:, 0], traj.pos_raw[:, 1], color="0.55", ls="--", lw=1.2,
            zorder=Z_PATH, label="uncorrected path (raw readings)")
    ax.plot(traj.pos_corrected[:, 0], traj.pos_corrected[:, 1], color="tab:blue", lw=1.6,
            zorder=Z_PATH, label="corrected path")
    ax.plot(*traj.p0, "ko", ms=5, zorder=Z_ESTIMATE, label="start P0")
    ax.plot(*region.estimate, "o", color="tab:blue", mec="k", ms=7, zorder=Z_ESTIMATE,
            label="estimated arrival")
    dx, dy = region.course_box_bound
    for k, patch in enumerate(course_box_patches(region)):
        if k == 0:
            patch.set_label(f"course 3σ box bound ±{dx:.3g} m (x), ±{dy:.3g} m (y), "
                            "calibration only")
        ax.add_patch(patch)
    for k, (name, c) in enumerate(region.candidates.items()):
        ax.plot(*c, "x", color=BOX_COLOR, ms=9, mew=2, zorder=Z_CANDIDATE,
                label="candidate point" if k == 0 else None)
        ax.annotate(name, c, textcoords="offset points", xytext=(6, 6), color=BOX_COLOR,
                    fontsize=12, weight="bold", zorder=Z_CANDIDATE)
    if truth is not None:
        ax.plot(*np.asarray(truth, float), "*", color="gold", mec="k", mew=1.0, ms=15,
                zorder=Z_TRUE, label="true arrival")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    dec = region.decision or "undecided"
    ax.set_title(title or f"Vehicle trajectory — decision: {dec}")
    ax.legend(loc="best", fontsize=8)
    return fig


def save_trajectory_plot(path: str | Path, traj: Trajectory, region: ArrivalRegion,
                         force: bool = False, **kwargs) -> Path:
    """Write the figure as PNG or SVG (by extension), atomically (see
    :func:`bench.figures.save.save_figure`)."""
    if FORMATS.get(Path(path).suffix.lower()) is None:  # before drawing anything
        raise ValueError(f"{path}: plot format must be .png or .svg")
    return save_figure(trajectory_figure(traj, region, **kwargs), path, force=force)

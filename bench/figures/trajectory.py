"""Figure of a reconstructed vehicle run: raw and corrected paths, candidates, ellipse."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from bench.figures.save import FORMATS, save_figure
from calib.region import ArrivalRegion
from calib.trajectory import Trajectory


def trajectory_figure(traj: Trajectory, region: ArrivalRegion, title: str | None = None,
                      truth: np.ndarray | None = None) -> plt.Figure:
    """Raw and corrected trajectories (m), candidates, the level-L ellipse around the
    estimate and the course's 3σ box-bound ellipses around each candidate."""
    fig, ax = plt.subplots(figsize=(8, 6.5), constrained_layout=True)
    ax.plot(traj.pos_raw[:, 0], traj.pos_raw[:, 1], color="0.55", ls="--", lw=1.2,
            label="uncorrected (raw readings)")
    ax.plot(traj.pos_corrected[:, 0], traj.pos_corrected[:, 1], color="tab:blue", lw=1.6,
            label="corrected")
    ax.plot(*traj.p0, "ko", ms=5, label="start P0")
    ax.plot(*region.estimate, "o", color="tab:blue", ms=6, label="estimated arrival")
    e = region.ellipse.boundary()
    ax.plot(e[:, 0], e[:, 1], color="tab:blue", lw=1.4,
            label=f"{100 * region.level:g}% region (calibration + vehicle noise)")
    box = region.course_box_bound
    s = np.linspace(0, 2 * np.pi, 200)
    first = True
    for name, c in region.candidates.items():
        ax.plot(*c, "x", color="tab:red", ms=9, mew=2)
        ax.annotate(name, c, textcoords="offset points", xytext=(6, 6), color="tab:red",
                    fontsize=12, weight="bold")
        ax.plot(c[0] + box[0] * np.cos(s), c[1] + box[1] * np.sin(s), color="tab:red",
                lw=0.8, ls=":", label="course 3σ box bound (ellipse)" if first else None)
        first = False
    if truth is not None:
        ax.plot(*truth, "*", color="tab:green", ms=12, label="true arrival")
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

"""Figure of a fused vehicle run: dead reckoning, the position fixes, the Kalman path and the
fused level-L arrival region next to the dead-reckoning one, with the candidates."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.patches import Polygon

from bench.figures.save import FORMATS, save_figure
from bench.figures.trajectory import BOX_COLOR, REGION_COLOR
from calib.fusion import FusionResult
from calib.region import ArrivalRegion, Ellipse
from calib.trajectory import Trajectory

FUSED_COLOR = "tab:green"


def fusion_figure(traj: Trajectory, region: ArrivalRegion, fused: FusionResult,
                  fixes: np.ndarray, level: float, decision: str | None) -> plt.Figure:
    """Dead-reckoned (corrected) path and its level-L region, the fixes (m), the filtered
    path and the fused level-L region of the arrival, the candidates.

    Both regions are drawn at the same level, so their sizes compare directly: the fixes
    remove the integrated vehicle noise that dominates dead reckoning."""
    fig, ax = plt.subplots(figsize=(8, 6.5), constrained_layout=True)
    ax.add_patch(Polygon(region.ellipse.boundary(), closed=True,
                         facecolor=to_rgba(REGION_COLOR, 0.12), edgecolor=REGION_COLOR, lw=1.2,
                         zorder=1, label=f"{100 * level:g} % region, dead reckoning"))
    est = np.asarray(fused.final_position, dtype=float).reshape(2)
    cov = np.asarray(fused.final_position_cov, dtype=float).reshape(2, 2)
    ell = Ellipse.from_cov(est, cov, level)
    ax.add_patch(Polygon(ell.boundary(), closed=True, facecolor=to_rgba(FUSED_COLOR, 0.35),
                         edgecolor=FUSED_COLOR, lw=1.6, zorder=4,
                         label=f"{100 * level:g} % region, fused "
                               f"({ell.semi_axes[0]:.2g} × {ell.semi_axes[1]:.2g} m)"))
    ax.plot(traj.pos_corrected[:, 0], traj.pos_corrected[:, 1], color="tab:blue", lw=1.2,
            zorder=2, label="dead reckoning (corrected readings)")
    ax.plot(fixes[:, 0], fixes[:, 1], ".", color="0.35", ms=4, zorder=3,
            label=f"position fixes ({fixes.shape[0]})")
    path = np.asarray(fused.estimates)[..., :2].reshape(-1, 2)
    ax.plot(path[:, 0], path[:, 1], color=FUSED_COLOR, lw=1.6, zorder=3,
            label="Kalman filter")
    for k, (name, c) in enumerate(region.candidates.items()):
        ax.plot(*c, "x", color=BOX_COLOR, ms=9, mew=2, zorder=5,
                label="candidate point" if k == 0 else None)
        ax.annotate(name, c, textcoords="offset points", xytext=(6, 6), color=BOX_COLOR,
                    fontsize=12, weight="bold", zorder=5)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.set_title(f"Fusion with position fixes — decision: {decision or 'undecided'}")
    ax.legend(loc="best", fontsize=8)
    return fig


def save_fusion_plot(path: str | Path, *args, force: bool = False) -> Path:
    """Write :func:`fusion_figure` as PNG or SVG (by extension), atomically."""
    if FORMATS.get(Path(path).suffix.lower()) is None:  # before drawing anything
        raise ValueError(f"{path}: plot format must be .png or .svg")
    return save_figure(fusion_figure(*args), path, force=force)

"""Uncertainty of the corrected position along the run (``uncertainty_growth`` figure)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from calib.conventions import AXES
from calib.vehicle.propagation import position_cov_along
from calib.vehicle.region import Ellipse

if TYPE_CHECKING:
    from calib.calibration.tilt_plane import Calibration
    from calib.vehicle.region import ArrivalRegion
    from calib.vehicle.trajectory import Trajectory


def uncertainty_growth_figure(traj: Trajectory, region: ArrivalRegion, cal: Calibration,
                              n_ellipses: int = 8, true_path: np.ndarray | None = None,
                              title: str | None = None) -> Figure:
    """Ellipses at the region's level growing along the corrected path; std against time.

    The covariance at each time is the arrival-point model applied to the trajectory
    truncated there (:func:`calib.vehicle.propagation.position_cov_along`); the right panel splits
    the standard deviation into the calibration part and the vehicle-noise part.
    """
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

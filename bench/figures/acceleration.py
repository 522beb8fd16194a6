"""Vehicle accelerations against time (``acceleration`` figure)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from calib.binning import binned_mean
from calib.conventions import AXES

if TYPE_CHECKING:
    from calib.trajectory import Trajectory


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

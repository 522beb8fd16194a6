"""Vehicle accelerations against time (``acceleration`` figure)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from calib.conventions import AXES
from calib.stats.binning import binned_mean

if TYPE_CHECKING:
    from calib.vehicle.trajectory import Trajectory


def _bin_half_width(t: np.ndarray, y: np.ndarray, bins: int, q: float) -> np.ndarray:
    """``q·s/√n`` per bin, m/s²: s the sample std within the bin (ddof 1), n its samples —
    the same equal-count groups of consecutive t as :func:`calib.stats.binning.binned_mean`."""
    groups = [g for g in np.array_split(np.argsort(t, kind="stable"), bins) if g.size]
    return np.array([q * np.std(y[g], ddof=1) / np.sqrt(g.size) if g.size > 1 else np.nan
                     for g in groups])


def acceleration_figure(traj: Trajectory, true_acc: np.ndarray | None = None,
                        true_t: np.ndarray | None = None, bin_s: float = 1.0,
                        title: str | None = None, level: float = 0.95) -> Figure:
    """Vehicle accelerations against time: measured samples (faint), and ``bin_s``-second
    means of the measured, corrected and (if known) true accelerations — the means show the
    bias and scale correction that the noise hides.

    The corrected mean carries its level-L band ``± q·s/√n`` (``q = Φ⁻¹((1 + L)/2)``, s the
    within-bin sample std, n the samples per bin): the noise of the mean. It leaves out the
    calibration's own uncertainty (a common shift of every bin, ``std(bias)/(1 + scale)``,
    shown by the calibration figures)."""
    from scipy.stats import norm

    q = float(norm.ppf(0.5 + level / 2))
    fig, axs = plt.subplots(2, 1, figsize=(11, 6.5), sharex=True, constrained_layout=True)
    bins = max(1, int(round((traj.t[-1] - traj.t[0]) / bin_s)))
    for k, a in enumerate(AXES):
        ax = axs[k]
        ax.plot(traj.t, traj.acc_raw[:, k], color="tab:blue", lw=0.4, alpha=0.25,
                label="measured A_m (samples)")
        mx, my, _ = binned_mean(traj.t, traj.acc_raw[:, k], bins)
        ax.plot(mx, my, color="0.35", lw=1.4, label=f"measured, {bin_s:g} s mean")
        cx, cy, _ = binned_mean(traj.t, traj.acc_corrected[:, k], bins)
        half = _bin_half_width(np.asarray(traj.t, float), traj.acc_corrected[:, k], bins, q)
        n = int(round(traj.t.size / bins))
        ax.fill_between(cx, cy - half, cy + half, color="navy", alpha=0.25, lw=0,
                        label=f"{100 * level:g} % band of the corrected mean: ±{q:.3g}·s/√n "
                              f"(n ≈ {n} samples, s the std within {bin_s:g} s)")
        ax.plot(cx, cy, color="navy", lw=1.6,
                label=f"corrected (A_m − bias)/(1 + scale), {bin_s:g} s mean")
        if true_acc is not None:
            tt = traj.t if true_t is None else true_t
            ax.plot(tt, true_acc[:, k], color="tab:green", lw=1.5, ls="--", label="true")
        ax.set_ylabel(f"a_{a} (m/s²)")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=7, ncol=2)
    axs[-1].set_xlabel("t (s)")
    fig.suptitle(title or f"Vehicle accelerations (band at {100 * level:g} %)")
    return fig

"""The gap figure: residuals against θ before and after adding the named effects."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bench.gap.report import GapReport
from calib.binning import binned_mean
from calib.conventions import AXES

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure


def effects_label(report: GapReport) -> str:
    """One line naming the effects added and their parameters (figure title)."""
    if not report.effects:
        return "no effect named"
    return "; ".join(f"{e.name} ({e.axis}): " + ", ".join(f"{k}={v:.4g}"
                                                         for k, v in e.params.items())
                     for e in report.effects)


def gap_figure(report: GapReport) -> Figure:
    """Residuals against θ before and after, per axis, with the ±σ band and binned means.

    Returns a :class:`matplotlib.figure.Figure` (2 × 2: rows x, y; columns before, after).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    theta = report.replay.tita
    fig, axs = plt.subplots(2, 2, figsize=(11, 7), sharex=True, constrained_layout=True)
    for k, ax_name in enumerate(AXES):
        for j, (which, res, gaps) in enumerate((
                ("before", report.residual_before, report.gap_before),
                ("after", report.residual_after, report.gap_after))):
            ax = axs[k, j]
            gm = gaps[ax_name]
            sigma = np.sqrt(report.noise_var[k] if which == "before"
                            else report.after[ax_name].sigma2)
            ax.plot(theta, res[:, k], ".", ms=1.5, color=(0.35, 0.55, 0.85) if j else
                    (0.55, 0.55, 0.55), alpha=0.6, rasterized=True, label="data − simulation")
            cx, cy, _ = binned_mean(theta, res[:, k], 72)
            ax.plot(cx, cy, "-", color=(0.85, 0.2, 0.15), lw=1.5, label="binned mean")
            ax.axhspan(-sigma, sigma, color=(0.95, 0.7, 0.2), alpha=0.25, label="±σ")
            for sign in (-1.0, 1.0):
                ax.axhline(sign * sigma, color=(0.85, 0.55, 0.1), lw=1.0, ls="--", zorder=3)
            ax.axhline(0.0, color="k", lw=0.6)
            ok = "consistent" if gm.consistent(report.family_alpha) else "GAP"
            ax.set_title(f"{ax_name}, {which}: χ²/dof = {gm.chi2_dof:.3f}, max z = "
                         f"{gm.max_signature_z:.1f} ({gm.worst}) — {ok}", fontsize=9)
            ax.set_ylabel(f"residual {ax_name}, m/s²")
            if k == 1:
                ax.set_xlabel("θ (encoder), rad")
            if k == 0 and j == 0:
                ax.legend(loc="upper right", fontsize=7, markerscale=4)
    title = effects_label(report)
    fig.suptitle(f"gap before / after adding: {title}", fontsize=10)
    return fig



def save_gap_figure(report: GapReport, path: str | os.PathLike) -> Path:
    """Draw :func:`gap_figure` and write it to ``path`` (format from the suffix; overwrites)."""
    from bench.figures import save_figure  # matplotlib: imported with the figure, not before

    return save_figure(gap_figure(report), path, force=True)

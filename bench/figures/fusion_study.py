"""Figure of the fusion comparison (:mod:`bench.fusion_study`): RMS error and stated final
std per method and scenario (log scale), and the outage panel — the filter's stated per-axis
std against time with the empirical RMS error of the runs."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from bench.figures.save import FORMATS, save_figure

METHOD_COLORS = {"dead_reckoning": "tab:blue", "fixes": "0.45", "filter": "tab:green",
                 "smoother": "tab:purple"}


def fusion_study_figure(result) -> plt.Figure:
    """Three panels: RMS error along the path (m), stated final-position std (m) — grouped
    bars per scenario, log scale, NEES outside its band marked ✗ — and the outage panel."""
    from bench.fusion_study import METHODS

    scen = result.scenarios
    fig = plt.figure(figsize=(13, 9), constrained_layout=True)
    gs = fig.add_gridspec(2, 2)
    axes = [fig.add_subplot(gs[0, :]), fig.add_subplot(gs[1, 0]), fig.add_subplot(gs[1, 1])]
    x = np.arange(len(scen))
    w = 0.8 / len(METHODS)
    for ax, key, title in ((axes[0], "rms_m", "RMS position error along the path (m)"),
                           (axes[1], "final_std_m", "stated final-position std per axis (m)")):
        for i, m in enumerate(METHODS):
            vals = [getattr(result.row(s, m), key) for s in scen]
            ax.bar(x + (i - 1.5) * w, vals, w, color=METHOD_COLORS[m],
                   label=m.replace("_", " "))
            if key == "final_std_m":
                for j, s in enumerate(scen):
                    if not result.row(s, m).nees_ok:
                        ax.annotate("✗", (x[j] + (i - 1.5) * w, vals[j]), ha="center",
                                    va="bottom", color="red", fontsize=11, weight="bold")
        ax.set_yscale("log")
        ax.set_xticks(x, scen, rotation=30, ha="right", fontsize=8)
        ax.set_title(title)
        ax.grid(True, axis="y", which="both", alpha=0.3)
    axes[0].legend(ncol=4, fontsize=9)
    axes[1].text(0.01, 0.98, "✗ = mean NEES outside its χ² band (inconsistent)",
                 transform=axes[1].transAxes, va="top", fontsize=8, color="red")
    ax = axes[2]
    if result.outage_t.size:
        ax.plot(result.outage_t, result.outage_std, color="tab:green", lw=1.8,
                label="stated std (filter), per axis")
        ax.plot(result.outage_t, 3 * result.outage_std, color="tab:green", lw=1, ls="--",
                label="3 × stated std")
        ax.plot(result.outage_t, result.outage_rms, color="k", lw=1,
                label=f"empirical RMS error per axis ({result.config['runs']} runs)")
        ax.axvspan(result.outage_start, result.outage_t[-1], color="0.85", zorder=0,
                   label="no fixes")
        ax.set_yscale("log")
        ax.legend(fontsize=8, loc="upper left")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("m")
    ax.set_title("outage at the end: the region grows as predicted")
    ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"Fusion comparison on the course geometry ({result.config['runs']} runs per "
                 "scenario)")
    return fig


def save_fusion_study_plot(path: str | Path, result, force: bool = False) -> Path:
    """Write :func:`fusion_study_figure` as PNG or SVG (by extension), atomically."""
    if FORMATS.get(Path(path).suffix.lower()) is None:
        raise ValueError(f"{path}: plot format must be .png or .svg")
    return save_figure(fusion_study_figure(result), path, force=force)

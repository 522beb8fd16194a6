"""Figure of the fusion comparison (:mod:`bench.fusion_study`): RMS error and stated final
std per method and scenario (log scale), the outage panel — the filter's stated per-axis
std against time with the empirical RMS error of the runs — and the filter's mean position
NEES along the path in the nominal and the mis-set scenarios, with the per-epoch Bonferroni
band.

Monte Carlo numbers carry their 95 % interval (the one level of the figure's error bars and
bands, said in the legends): the RMS error of R runs, whose mean square is, per run and axis,
one χ² degree of freedom at least, gets ``[rms·sqrt(k/χ²_k(0.975)), rms·sqrt(k/χ²_k(0.025))]``
with k = 2R (bars) — conservative: averaging along a run only narrows it; the outage panel's
per-axis RMS at each t the same with k = R (band). Stated std come from the filter's P, not
from the runs: no Monte Carlo error. The NEES band is the per-epoch Bonferroni band.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import FormatStrFormatter, NullFormatter

from bench.figures.save import FORMATS, save_figure

MC_LEVEL = 0.95
"""Level of every Monte Carlo interval drawn."""


def rms_interval(rms: np.ndarray, k: int, level: float = MC_LEVEL) -> tuple[np.ndarray,
                                                                            np.ndarray]:
    """Two-sided level-L interval (lo, hi) of an RMS estimated from k independent squared
    Gaussian terms: ``k·rms²/σ² ~ χ²_k`` (module docstring), m."""
    from scipy.stats import chi2

    rms = np.asarray(rms, dtype=float)
    a = 1.0 - level
    return (rms * np.sqrt(k / chi2.ppf(1 - a / 2, k)), rms * np.sqrt(k / chi2.ppf(a / 2, k)))


METHOD_COLORS = {"dead_reckoning": "tab:blue", "fixes": "0.45", "filter": "tab:green",
                 "smoother": "tab:purple"}


def fusion_study_figure(result) -> plt.Figure:
    """Three panels: RMS error along the path (m), stated final-position std (m) — grouped
    bars per scenario, log scale, NEES outside its band marked ✗ — and the outage panel."""
    from bench.fusion_study_result import METHODS

    scen = result.scenarios
    fig = plt.figure(figsize=(13, 13.5), constrained_layout=True)
    gs = fig.add_gridspec(3, 2, height_ratios=[1, 1, 1.1])
    axes = [fig.add_subplot(gs[0, :]), fig.add_subplot(gs[1, 0]), fig.add_subplot(gs[1, 1])]
    path_nees_panel(fig.add_subplot(gs[2, 0]), result, 2)
    path_nees_panel(fig.add_subplot(gs[2, 1]), result, 4)
    x = np.arange(len(scen))
    w = 0.8 / len(METHODS)
    runs = int(result.config["runs"])
    for ax, key, title in ((axes[0], "rms_m", "RMS position error along the path (m), bars: "
                            f"95 % χ² interval of {runs} runs"),
                           (axes[1], "final_std_m", "stated final-position std per axis (m), "
                            "from P: no Monte Carlo error")):
        for i, m in enumerate(METHODS):
            vals = np.array([getattr(result.row(s, m), key) for s in scen])
            err = None
            if key == "rms_m":  # a Monte Carlo estimate: its 95 % interval
                lo, hi = rms_interval(vals, 2 * int(result.config["runs"]))
                err = [vals - lo, hi - vals]
            ax.bar(x + (i - 1.5) * w, vals, w, color=METHOD_COLORS[m],
                   label=m.replace("_", " "), yerr=err, capsize=1.5,
                   error_kw={"elinewidth": 0.8, "ecolor": "0.15"})
            if key == "final_std_m":
                for j, s in enumerate(scen):
                    if not result.row(s, m).nees_ok:
                        ax.annotate("✗", (x[j] + (i - 1.5) * w, vals[j]), ha="center",
                                    va="bottom", color="red", fontsize=11, weight="bold")
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.set_ylabel("m")
        ax.set_xticks(x, scen, rotation=30, ha="right", fontsize=8)
        ax.set_title(title, fontsize=10)
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
        lo, hi = rms_interval(result.outage_rms, runs)
        ax.fill_between(result.outage_t, lo, hi, color="tab:orange", alpha=0.3, lw=0,
                        label=f"95 % χ² interval of the RMS ({runs} runs)")
        ax.plot(result.outage_t, result.outage_rms, color="k", lw=1,
                label=f"empirical RMS error per axis ({runs} runs)")
        ax.axvspan(result.outage_start, result.outage_t[-1], color="0.85", zorder=0,
                   label="no fixes")
        ax.set_yscale("log")
        ax.legend(fontsize=8, loc="upper left")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("position error, per axis (m)")
    ax.set_title("outage at the end: the region grows as predicted", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"Fusion comparison on the course geometry ({result.config['runs']} runs per "
                 "scenario)")
    return fig


MIS_SET = (("p0_factor", "P0", "tab:blue"), ("q_factor", "Q", "tab:orange"),
           ("r_factor", "R", "tab:red"))


def path_nees_panel(ax, result, dof: int = 2) -> None:
    """The filter's mean NEES at every fix epoch against t (log y), position (``dof`` 2) or
    position+velocity (4): the first scenario (nominal) in black, P0, Q, R mis-set ×10
    (dashed) and ÷10 (solid); the nominal's per-epoch Bonferroni band shaded (the mis-set
    scenarios have the same fix epochs and run count, hence the same band), its expected
    value ``dof`` dotted."""
    from calib.stats.consistency import NEES_ALPHA

    scns = result.config["scenarios"]
    names = {p.scenario for p in result.paths if p.method == "filter"}
    if not scns or scns[0]["name"] not in names:
        ax.set_axis_off()
        return

    def curve(p):
        return p.nees if dof == 2 else p.nees4

    nominal = result.path(scns[0]["name"])
    lo, hi = nominal.band if dof == 2 else nominal.band4
    ax.axhspan(lo, hi, color="0.85", zorder=0,
               label=f"per-epoch band ({lo:.2f}–{hi:.2f})")
    ax.axhline(float(dof), color="0.4", lw=0.8, ls=":")
    ax.plot(nominal.t, curve(nominal), color="k", lw=1.8, label="nominal")
    for key, label, color in MIS_SET:
        for s in scns[1:]:
            f = s[key]
            others = [s[k] for k, _, _ in MIS_SET if k != key]
            if f == 1.0 or s["name"] not in names or any(o != 1.0 for o in others) or \
                    s["outage_s"] or s["fix_hz"] != scns[0]["fix_hz"]:
                continue
            p = result.path(s["name"])
            ax.plot(p.t, curve(p), color=color, lw=1.4, ls="--" if f > 1 else "-",
                    label=f"{label} {'×' if f > 1 else '÷'}{max(f, 1 / f):g}")
    ax.set_yscale("log")
    from matplotlib.ticker import FormatStrFormatter, FuncFormatter

    ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.yaxis.set_minor_formatter(FuncFormatter(
        lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "235" else ""))
    ax.tick_params(axis="y", which="minor", labelsize=7)
    ax.set_xlabel("t (s)")
    ax.set_ylabel(f"mean NEES over the runs ({dof} dof)")
    what = "position" if dof == 2 else "position + velocity"
    ax.set_title(f"filter: mean {what} NEES at each fix ({result.config['runs']} runs)",
                 fontsize=11)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7.5, ncol=4, loc="lower center", bbox_to_anchor=(0.5, 1.07),
              frameon=False)
    if dof == 2:
        ax.text(0.01, 0.02, f"band: all epochs of a consistent filter inside with "
                f"probability ≥ 1 − {NEES_ALPHA:g} (Bonferroni)", fontsize=7.5,
                transform=ax.transAxes)


def save_fusion_study_plot(path: str | Path, result, force: bool = False) -> Path:
    """Write :func:`fusion_study_figure` as PNG or SVG (by extension), atomically."""
    if FORMATS.get(Path(path).suffix.lower()) is None:
        raise ValueError(f"{path}: plot format must be .png or .svg")
    return save_figure(fusion_study_figure(result), path, force=force)

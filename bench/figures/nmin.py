"""The N analysis: Mahalanobis distances and P(decision made and right) against the calibration
size N."""

from __future__ import annotations

from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from calib.conventions import G
from calib.stats.proportion import clopper_pearson
from calib.vehicle.nmin import (
    PositionCovModel,
    design_nmin,
    fixed_run_nmin,
    posterior_nrange,
    redrawn_design,
    redrawn_probability,
)
from calib.vehicle.region import chi2_2dof

if TYPE_CHECKING:
    from calib.vehicle.region import ArrivalRegion


def nmin_figure(region: ArrivalRegion, n_data: int, g: float = G,
                n_range: tuple[float, float] = (1e2, 1e6), title: str | None = None,
                fixed_run: dict | None = None, draws: int = 10**5) -> Figure:
    """Mahalanobis distance of each candidate against the calibration size N (top), and
    P(decision made and right) against N (bottom).

    Bottom: the course question (this vehicle run given, :func:`calib.vehicle.nmin.fixed_run_nmin`;
    ``fixed_run`` is its result, computed here with ``draws`` draws when None) and the design
    question with the vehicle noise redrawn (:func:`calib.vehicle.nmin.redrawn_probability`, which
    never exceeds L), the level line and both answers marked.

    Both probability curves are Monte Carlo estimates from ``draws`` draws: each point carries
    its exact (Clopper–Pearson) 95 % binomial interval, the one level of the figure. The
    probability axis is a logit scale, so 0.5, 0.9, 0.99 and 0.999 are equally spaced and no
    part of the curves is cut off.

    Top: uses :class:`calib.vehicle.nmin.PositionCovModel` (``Σ_P(N) = A/N + B``, θ uniform) built
    from the region; a candidate is inside the level-L region while its distance is below
    ``r = sqrt(χ²₂(L))``. Marks the data's N, the design N (all regions disjoint) and the
    a-posteriori N range with the estimate held fixed; the dashed curves leave out the
    vehicle noise (the course reports' assumption).
    """
    model = PositionCovModel.from_region(region, g)
    cal_only = PositionCovModel.from_region(region, g, include_noise=False)
    r = float(np.sqrt(chi2_2dof(region.level)))
    ns = np.logspace(np.log10(n_range[0]), np.log10(n_range[1]), 300)
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(10, 10), constrained_layout=True,
                                  height_ratios=(1.2, 1.0))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    nearest = {}
    for i, (name, c) in enumerate(region.candidates.items()):
        d = np.asarray(c, float) - region.estimate
        full = [np.sqrt(d @ np.linalg.solve(model.cov(n), d)) for n in ns]
        part = [np.sqrt(d @ np.linalg.solve(cal_only.cov(n), d)) for n in ns]
        col = colors[i % len(colors)]
        ax.plot(ns, full, color=col, lw=2, label=f"{name}")
        ax.plot(ns, part, color=col, lw=1, ls="--")
        nearest[name] = (full[0], np.asarray(part), col)
    ax.plot([], [], color="0.3", lw=2,
            label="solid: calibration + vehicle noise (levels off at the noise floor B)")
    ax.plot([], [], color="0.3", lw=1, ls="--",
            label="dashed: calibration only, as the course reports (rises as √N)")
    _explain_rise(ax, ns, nearest, r)
    ax.axhline(r, color="k", lw=1.2, label=f"inside below r = √χ²₂({region.level:g}) = {r:.2f}")
    ax.axvline(n_data, color="0.3", ls=":", label=f"data N = {n_data}")
    des = design_nmin(region.candidates, model, region.level)
    if des["n"] is not None and n_range[0] <= des["n"] <= n_range[1]:
        ax.axvline(des["n"], color="tab:purple", ls="-.", label=f"design N = {des['n']}")
    post = posterior_nrange(region.estimate, region.candidates, model, region.level)
    if post["n_min"] is not None:  # a line at each end of the range, no shading over curves
        span = (f"{post['n_min']} ≤ N ≤ {post['n_max']}" if post["n_max"] is not None
                else f"N ≥ {post['n_min']}")
        for k, end in enumerate((post["n_min"], post["n_max"])):
            if end is not None and n_range[0] <= end <= n_range[1]:
                ax.axvline(end, color="tab:green", ls=(0, (5, 2)), lw=1.2,
                           label=None if k else f"a posteriori: decides {post['letter']} "
                           f"for {span}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("calibration samples N (count; θ uniform over [0, 2π))")
    ax.set_ylabel("Mahalanobis distance d(N) (dimensionless) of a candidate\n"
                  "(rises with N: Σ_P(N) = A/N + B shrinks)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(title or "Distance d(N) = √(Δᵀ Σ_P(N)⁻¹ Δ) of each candidate: it rises with "
                 "N as Σ_P(N) = A/N + B shrinks", fontsize=10)
    _probability_panel(ax2, region, model, n_range, fixed_run, draws)
    return fig


def _probability_panel(ax, region: ArrivalRegion, model: PositionCovModel,
                       n_range: tuple[float, float], fixed_run: dict | None, draws: int
                       ) -> None:
    """P(made and right) against N: fixed run (the course question) and noise redrawn."""
    truth = region.decision or min(region.mahalanobis, key=region.mahalanobis.get)
    fr = fixed_run if fixed_run is not None else fixed_run_nmin(region, truth, draws)
    L = region.level
    _with_interval(ax, fr["grid_n"], fr["grid_p"], int(fr["draws"]), color="tab:blue", lw=2,
                   label=f"this vehicle run given (course question; {fr['draws']} draws)")
    ns = np.geomspace(max(n_range[0], 3), max(n_range[1], 10 * (fr["n"] or 1)), 40)
    w = np.random.default_rng(np.random.SeedSequence(fr["seed"])).standard_normal((draws, 2))
    red = [redrawn_probability(n, model, region.candidates, truth, L, w) for n in ns]
    _with_interval(ax, ns, red, draws, color="tab:purple", lw=1.5, ls="--",
                   label=f"vehicle noise redrawn too (design; never above L; {draws} draws)")
    des = redrawn_design(region.candidates, model, truth, L, draws, fr["seed"])
    ax.axhline(des["p_infinity"], color="tab:purple", lw=0.8, ls=":",
               label=f"redrawn asymptote P_∞ = {des['p_infinity']:.4f}")
    ax.axhline(L, color="k", lw=1.2, label=f"level L = {L:g}")
    if fr["n"] is not None:
        ax.axvline(fr["n"], color="tab:blue", ls="-.",
                   label=f"fixed-run answer N = {fr['n']} (±3σ: {fr['n_band'][0]}–"
                   f"{fr['n_band'][1]})")
    if des["n"] is not None:
        ax.axvline(des["n"], color="tab:purple", ls="-.",
                   label=f"redrawn: reaches L (touches it) at N = {des['n']}")
    ax.errorbar([], [], yerr=[], fmt="none", ecolor="0.3", capsize=2,
                label="bars: exact 95 % binomial interval of each Monte Carlo point")
    ax.set_xscale("log")
    ax.set_xlim(ns[0], ns[-1])
    # logit: the whole curve from its smallest value to P → 1, with room near L; a point
    # with every draw right (P̂ = 1) sits on the top edge, its interval below it
    ax.set_yscale("logit", nonpositive="clip")
    low = min([v for v in (*fr["grid_p"], *red) if v > 0] or [0.5])
    top = 1.0 - min(1e-4, 0.1 * (1.0 - L), 0.5 / draws)
    bottom = max(1e-3, min(0.5, low))
    ax.set_ylim(bottom, top)
    ticks = [t for t in (0.001, 0.01, 0.1, 0.5, 0.9, 0.99, 0.999, 0.9999, 0.99999)
             if bottom <= t <= top]
    ax.set_yticks(ticks, [f"{t:g}" for t in ticks])
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("calibration samples N of a new calibration (count; θ uniform over [0, 2π))")
    ax.set_ylabel(f"P(decision made and right = {truth})\n(dimensionless, logit scale)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("P(decision made and right) against N: reaches L with this run given; cannot "
                 "exceed L redrawn", fontsize=10)


def _with_interval(ax, ns, ps, draws: int, **style) -> None:
    """A Monte Carlo probability curve with the exact 95 % interval of each point as an
    error bar (``draws`` Bernoulli draws per point)."""
    ps = np.asarray(ps, dtype=float)
    ci = np.array([clopper_pearson(int(round(p * draws)), draws) for p in ps])
    ax.errorbar(ns, ps, yerr=[ps - ci[:, 0], ci[:, 1] - ps], marker=".", capsize=2,
                elinewidth=0.8, **style)


def _explain_rise(ax, ns: np.ndarray, curves: dict, r: float) -> None:
    """Annotate the dashed curve of the nearest candidate where it crosses ``r``: with the
    calibration part only (``B = 0``) the distance grows as √N, so with enough samples even
    the candidate nearest the estimate leaves the region — the vehicle noise is what keeps it
    inside (solid curve)."""
    name = min(curves, key=lambda n: curves[n][0])
    part, col = curves[name][1], curves[name][2]
    above = np.nonzero(part > r)[0]
    if above.size == 0 or above[0] == 0:
        return
    i = int(above[0])
    n_cross = float(f"{ns[i]:.2g}")  # two significant digits: the grid is coarse
    ax.annotate(f"{name}, calibration only: d ∝ √N crosses r at N ≈ {n_cross:,.0f} —\n"
                "without the vehicle noise even the nearest candidate would leave the region",
                xy=(ns[i], r), xytext=(0.97, 0.06), textcoords="axes fraction", ha="right",
                fontsize=8, color=col, zorder=6,
                arrowprops={"arrowstyle": "->", "color": col, "lw": 1.0},
                bbox={"facecolor": "white", "alpha": 0.9, "edgecolor": col})

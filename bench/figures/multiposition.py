"""The multi-position calibration figure (``calibrate --method multiposition --plot F``).

Left: the pose means ``[m̄x, m̄y]`` (m/s²) with their error ellipses (the level-``L`` region
of each mean, semi-axes ``k·σ_a/√n_i``, magnified by a stated factor: at the scale of g they
would be invisible), the fitted ellipse ``b + (1 + s)·(−g sin θ, −g cos θ)`` with its centre
(the biases) and the ideal sensor's circle of radius g about 0. Right: each pose's residual
(mean − fitted ellipse) per axis against its estimated angle θ_i (deg), with the same
intervals unmagnified: a model that fits leaves them around 0 within their bars. The
estimates box gives each parameter ± the half-width of its level-``L`` interval: every band,
bar and ± of the figure is at the one level ``L``, with the fit's quantile ``k`` (normal when σ²
was given, Student t on the within-pose dof when it was estimated).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse

from bench.figures.fit_quality import fit_quality
from bench.figures.save import save_figure

if TYPE_CHECKING:
    from calib.calibration.multiposition import MultiPositionFit

ERROR_ELLIPSE_SIZE = 0.03
"""The largest drawn error ellipse's semi-axis, as a fraction of g (sets the magnification)."""


def _magnification(half: np.ndarray, g: float) -> float:
    """A round factor (1, 2, 5 × 10^k) that makes the largest semi-axis ≈
    :data:`ERROR_ELLIPSE_SIZE`·g; 1 when they are already visible."""
    biggest = float(np.max(half))
    if biggest <= 0 or biggest >= ERROR_ELLIPSE_SIZE * g:
        return 1.0
    raw = ERROR_ELLIPSE_SIZE * g / biggest
    exp = np.floor(np.log10(raw))
    for m in (5, 2, 1):
        if m * 10**exp <= raw:
            return float(m * 10**exp)
    return float(10**exp)


def multiposition_figure(fit: MultiPositionFit, level: float = 0.95) -> Figure:
    """The figure of the module docstring for ``fit``; every interval at ``level``."""
    k = fit.quantile(level)
    g = fit.g
    means = fit.poses.means
    half = k * np.sqrt(fit.sigma2[None, :] / fit.poses.n[:, None])  # (P, 2) m/s²
    mag = _magnification(half, g)
    fig, (ax, rx) = plt.subplots(1, 2, figsize=(12, 5.6), gridspec_kw={"width_ratios": [1, 1.3]})

    t = np.linspace(0, 2 * np.pi, 721)
    b, s = fit.bias, fit.scale
    ax.plot(-g * np.sin(t), -g * np.cos(t), color="k", lw=1.0, ls=":",
            label=f"ideal sensor: circle of radius g = {g:g} m/s²")
    ax.plot(b[0] + (1 + s[0]) * (-g * np.sin(t)), b[1] + (1 + s[1]) * (-g * np.cos(t)),
            color="tab:red", lw=1.6, label="fitted ellipse b + (1 + s)·A_r(θ)")
    ax.plot(*b, marker="+", color="tab:red", ms=10, ls="none",
            label=f"centre = biases ({b[0]:.3g}, {b[1]:.3g}) m/s²")
    ax.plot(means[:, 0], means[:, 1], "o", color="tab:blue", ms=4, zorder=5,
            label=f"pose means ({fit.poses.count} poses)")
    for i in range(fit.poses.count):
        ax.add_patch(Ellipse(means[i], 2 * mag * half[i, 0], 2 * mag * half[i, 1],
                             fill=False, color="tab:blue", lw=1.0,
                             label=(f"{100 * level:g}% region of each mean ×{mag:g}"
                                    if i == 0 else None)))
        ax.annotate(str(fit.poses.labels[i]), means[i], textcoords="offset points",
                    xytext=(6, 6), fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("A_mx (m/s²)")
    ax.set_ylabel("A_my (m/s²)")
    ax.set_title("pose means on the fitted ellipse (θ unknown)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="center")

    deg = np.degrees(fit.angles)
    for j, (axis, colour, off) in enumerate((("x", "tab:blue", -0.8), ("y", "tab:orange", 0.8))):
        rx.errorbar(deg + off, fit.residuals[:, j], yerr=half[:, j], fmt="o", ms=4,
                    color=colour, capsize=3,
                    label=f"axis {axis}: mean − fit, ± {100 * level:g}% (k σ/√n)")
    rx.axhline(0.0, color="k", lw=0.8)
    rx.set_xlabel("estimated pose angle θ_i (deg)")
    rx.set_ylabel("residual of the pose mean (m/s²)")
    lof = fit.lack_of_fit
    test = "" if lof is None else (
        f"; lack of fit {lof.statistic} = {lof.value:.3g}, p = {lof.p_value:.2g}")
    rx.set_title(f"residuals per pose: {fit_quality(fit.chi2_dof, fit.dof)}{test}",
                 fontsize=9)
    rx.grid(True, alpha=0.3)
    rx.legend(fontsize=7)
    lines = [f"{n} = {v:.5g} ± {k * sd:.2g} {'m/s²' if n.startswith('bias') else ''}".rstrip()
             for n, v, sd in zip(fit.param_names, fit.params, fit.std, strict=True)]
    rx.text(0.02, 0.03, "\n".join(lines + [f"(± {100 * level:g}% half-width = {k:.3g} std;"
                                           f" σ² {fit.sigma2_source})"]),
            transform=rx.transAxes, fontsize=8, family="monospace", va="bottom",
            bbox={"facecolor": "white", "alpha": 0.9, "edgecolor": "0.7"})
    fig.tight_layout()
    return fig


def save_multiposition_plot(path: str | Path, fit: MultiPositionFit, force: bool = False,
                            level: float = 0.95) -> Path:
    """Write :func:`multiposition_figure` as PNG or SVG (by extension), atomically."""
    return save_figure(multiposition_figure(fit, level), path, force=force)


__all__ = ["multiposition_figure", "save_multiposition_plot"]

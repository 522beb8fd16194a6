"""The 3-axis multi-position calibration figure (``calibrate --plot F`` when the 3-axis fit
is chosen: :func:`calib.calibration.multiposition.fit_multiposition3d`).

Three panels, every interval at one level ``L`` with the fit's quantile ``k`` (normal when σ²
was given, Student t on the within-pose dof when it was estimated):

* **Where the poses point**: each pose's estimated direction ``u_i`` (the sensor's up in its
  x, y, n axes) as azimuth ``atan2(u_y, u_x)`` and elevation ``asin(u_n)`` (deg), with the
  largest empty spherical cap and the smallest eigenvalue of the directions' scatter in the
  title: the geometry that decides how well the six parameters are known.
* **The gravity norm per pose**: ``|(m̄_i − b) ⊘ (1 + s)|`` (m/s²), the pose mean corrected
  with the fitted bias and scale, against the model's ``g`` line. Its bar is
  ``± k·sqrt(Σ_a u_ia² v_ia) / (1 + s_a)``, ``v_ia = σ_a²/n_i + q_a²/12`` (the mean's own
  noise projected on the direction; the parameters' uncertainty is not in it).
* **Residual per pose and axis**: ``m̄_ia − b_a − (1 + s_a)·g·u_ia`` (m/s²) with
  ``± k·sqrt(v_ia)``; a model that fits leaves them around 0 within their bars, and the title
  gives χ²/dof and the lack-of-fit test (or says that no degree of freedom is left).

The lines below the panels give each parameter ± the half-width of its level-``L`` interval.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from bench.figures.fit_quality import fit_quality
from bench.figures.save import save_figure

if TYPE_CHECKING:
    from calib.calibration.multiposition import MultiPosition3DFit

AXIS_COLOURS = (("x", "tab:blue"), ("y", "tab:orange"), ("n", "tab:green"))


def multiposition3d_figure(fit: MultiPosition3DFit, level: float = 0.95) -> Figure:
    """The figure of the module docstring for ``fit``; every interval at ``level``."""
    k = fit.quantile(level)
    P = fit.poses.count
    u = np.asarray(fit.directions)
    var = (fit.sigma2[None, :] / fit.poses.n[:, None]
           + np.asarray(fit.quantization)[None, :] ** 2 / 12)  # (P, 3) (m/s²)²
    b, s = fit.params[0::2], fit.params[1::2]
    fig, (dx, nx, rx) = plt.subplots(1, 3, figsize=(16, 6.2),
                                     gridspec_kw={"width_ratios": [1.1, 1, 1.3]})

    az = np.degrees(np.arctan2(u[:, 1], u[:, 0]))
    el = np.degrees(np.arcsin(np.clip(u[:, 2], -1, 1)))
    dx.scatter(az, el, color="tab:blue", s=22, zorder=3)
    for i in range(P):
        dx.annotate(str(fit.poses.labels[i]), (az[i], el[i]), textcoords="offset points",
                    xytext=(5, 4), fontsize=8)
    dx.set_xlim(-180, 180)
    dx.set_ylim(-90, 90)
    dx.set_xticks(range(-180, 181, 90))
    dx.set_yticks(range(-90, 91, 45))
    dx.set_xlabel("azimuth of the pose's up, atan2(u_y, u_x) (deg)")
    dx.set_ylabel("elevation, asin(u_n) (deg)")
    dx.set_title(f"where the {P} poses point: largest empty cap "
                 f"{np.degrees(fit.largest_cap):.0f}°, min eig {fit.min_eig:.2f} (1/3 at best)",
                 fontsize=9)
    dx.grid(True, alpha=0.3)

    corrected = (fit.poses.means - b) / (1 + s)
    norm = np.linalg.norm(corrected, axis=1)
    half_norm = k * np.sqrt(np.sum(u**2 * var / (1 + s) ** 2, axis=1))
    idx = np.arange(P)
    nx.errorbar(idx, norm, yerr=half_norm, fmt="o", ms=4, color="tab:purple", capsize=3,
                label=f"|(m̄ − b) ⊘ (1 + s)| ± {100 * level:g}% (noise of the mean)")
    nx.axhline(fit.g, color="k", lw=1.0, label=f"model: g = {fit.g:g} m/s²")
    nx.set_xticks(idx, [str(label) for label in fit.poses.labels], fontsize=8)
    nx.set_xlabel("pose")
    nx.set_ylabel("corrected magnitude of the pose mean (m/s²)")
    nx.set_title("each pose reads g once corrected", fontsize=9)
    nx.grid(True, alpha=0.3)
    nx.legend(fontsize=7)

    half = k * np.sqrt(var)
    for j, (axis, colour) in enumerate(AXIS_COLOURS):
        rx.errorbar(idx + (j - 1) * 0.15, fit.residuals[:, j], yerr=half[:, j], fmt="o", ms=4,
                    color=colour, capsize=3,
                    label=f"axis {axis}: mean − fit, ± {100 * level:g}%")
    rx.axhline(0.0, color="k", lw=0.8)
    rx.set_xticks(idx, [str(label) for label in fit.poses.labels], fontsize=8)
    rx.set_xlabel("pose")
    rx.set_ylabel("residual of the pose mean (m/s²)")
    lof = fit.lack_of_fit
    test = "" if lof is None else (
        f"; lack of fit {lof.statistic} = {lof.value:.3g}, p = {lof.p_value:.2g}")
    rx.set_title(f"residuals per pose and axis: {fit_quality(fit.chi2_dof, fit.dof)}{test}",
                 fontsize=9)
    rx.grid(True, alpha=0.3)
    rx.legend(fontsize=7, loc="upper right")
    entries = [f"{n} = {v:.5g} ± {k * sd:.2g}{' m/s²' if n.startswith('bias') else ''}"
               for n, v, sd in zip(fit.param_names, fit.params, fit.std, strict=True)]
    lines = ["      ".join(entries[a:a + 2]) for a in range(0, len(entries), 2)]
    fig.text(0.01, 0.01, "\n".join(lines + [f"(± {100 * level:g}% half-width = {k:.3g} std; "
                                            f"σ² {fit.sigma2_source})"]),
             fontsize=8, family="monospace", va="bottom")
    fig.suptitle("3-axis multi-position calibration (no angle reference): "
                 "m̄ = b + (1 + s)·g·u on the sphere", fontsize=11)
    fig.tight_layout(rect=(0, 0.13, 1, 1))
    return fig


def save_multiposition3d_plot(path: str | Path, fit: MultiPosition3DFit, force: bool = False,
                              level: float = 0.95) -> Path:
    """Write :func:`multiposition3d_figure` as PNG or SVG (by extension), atomically."""
    return save_figure(multiposition3d_figure(fit, level), path, force=force)

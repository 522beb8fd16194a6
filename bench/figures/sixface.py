"""The six-face calibration figure (``calibrate LOG --plot F`` on a 3-axis log held on faces).

One column per sensor axis a. Top: each hold's reading error ``m̄_h,a − g·u_h,a`` (m/s²: what
the axis reads beyond an ideal sensor on that face), grouped by face, with its level-``L``
bar (``k·√(σ̂_B,c² + σ̂_W²/n_h)``, the std the fit used, σ̂_B,c that of the hold's class: the
axis vertical or level) and the fitted model's value on that face
(``b_a + g·(K_a·u) − g·u_a``). Bottom: each hold's residual (mean − model) with the same
bars around 0: a model that fits leaves them inside their bars, a face that repeats badly or a
missing term shows. The title line of each column gives the axis' bias, scale and
misalignments ± the half-width of their level-``L`` intervals: every bar and ± of the figure
is at the one level ``L`` (Student t with the Satterthwaite dof of each parameter, and of each
hold's variance for its bar: :meth:`SixFaceFit.hold_dof`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from scipy import stats

from bench.figures.save import save_figure

if TYPE_CHECKING:
    from calib.calibration.sixface import SixFaceFit

FACE_ORDER = ("+x", "-x", "+y", "-y", "+z", "-z")
FACE_COLORS = dict(zip(FACE_ORDER, plt.get_cmap("tab10").colors[:6], strict=True))


def sixface_figure(fit: SixFaceFit, level: float = 0.95) -> Figure:
    """The figure of the module docstring for ``fit``; every bar and ± at ``level``."""
    order = sorted(range(len(fit.faces)), key=lambda h: (FACE_ORDER.index(fit.faces[h]), h))
    from calib.calibration.sixface import face_vectors

    u = face_vectors(fit.faces)
    g = fit.g
    ci = fit.conf_int(level)
    hold_k = stats.t.ppf(0.5 + level / 2, fit.hold_dof())  # (H, 3)
    fig, axes = plt.subplots(2, 3, figsize=(14.5, 7.0), sharex=True)
    xs = np.arange(len(order))
    for a, name in enumerate("xyz"):
        row = np.concatenate([[fit.params[4 * a]], fit.k_matrix[a]])
        model = row[0] + g * u @ row[1:] - g * u[:, a]
        error = model + fit.residuals[:, a]
        bars = hold_k[:, a] * fit.hold_std[:, a]
        top, bottom = axes[0, a], axes[1, a]
        for x, h in zip(xs, order, strict=True):
            color = FACE_COLORS[fit.faces[h]]
            top.errorbar(x, error[h], yerr=bars[h], fmt="o", color=color, ms=4, capsize=2)
            top.plot(x, model[h], marker="_", color="k", ms=14, mew=1.5)
            bottom.errorbar(x, fit.residuals[h, a], yerr=bars[h], fmt="o", color=color, ms=4,
                            capsize=2)
        bottom.axhline(0.0, color="k", lw=0.8)
        half = (ci[4 * a:4 * a + 4, 1] - ci[4 * a:4 * a + 4, 0]) / 2
        names = [n.split("_", 1)[1] if n.startswith("misalignment") else None
                 for n in fit.param_names[4 * a:4 * a + 4]]
        top.set_title(f"axis {name}: bias {fit.params[4 * a]:.4g} ± {half[0]:.2g} m/s², "
                      f"scale {fit.params[4 * a + 1]:.4g} ± {half[1]:.2g}\n"
                      f"misalignment {names[2]} {1e3 * fit.params[4 * a + 2]:.3g} ± "
                      f"{1e3 * half[2]:.2g} mrad, {names[3]} {1e3 * fit.params[4 * a + 3]:.3g}"
                      f" ± {1e3 * half[3]:.2g} mrad", fontsize=8.5)
        top.set_ylabel(f"m̄{name} − g·u{name} (m/s²)")
        bottom.set_ylabel(f"residual {name} (m/s²)")
        bottom.set_xticks(xs, [fit.faces[h] for h in order], fontsize=8)
        bottom.set_xlabel("hold, by face (the case axis that points up)")
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
    handles = [plt.Line2D([], [], marker="o", ls="", color=c, label=f"face {f}")
               for f, c in FACE_COLORS.items() if f in fit.faces]
    handles.append(plt.Line2D([], [], marker="_", ls="", color="k", ms=14, mew=1.5,
                              label="fitted model"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=8,
               frameon=False)
    fig.suptitle(f"Six-face calibration of {Path(fit.source).name}: {len(fit.faces)} holds, "
                 f"g = {g:.6g} m/s² ({fit.g_source}); bars and ± at {100 * level:g} %\n"
                 + fit.repeatability_line().replace("\n ", ";"), fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.95))
    return fig


def save_sixface_plot(path: str | Path, fit: SixFaceFit, force: bool = False,
                      level: float = 0.95) -> Path:
    """Write :func:`sixface_figure` to ``path`` (PNG/PDF/SVG by suffix), atomically."""
    return save_figure(sixface_figure(fit, level), path, force=force)


__all__ = ["save_sixface_plot", "sixface_figure"]

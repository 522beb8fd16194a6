"""The estimates with their intervals next to the true values (``parameters`` figure)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

if TYPE_CHECKING:
    from calib.calibration.tilt_plane import Calibration


def true_params(truth: Mapping | None) -> dict[str, float] | None:
    """The true sensor parameters (``bias_x``, ``scale_x``, ...) of a ``truth.json`` object,
    or None (no truth, or no sensor parameters in it)."""
    if not truth:
        return None
    from bench.validate import true_sensor_params

    return true_sensor_params(truth)


def parameters_figure(cal: Calibration, truth: Mapping | None = None, level: float = 0.95,
                      title: str | None = None) -> Figure:
    """The four estimates with their level-L intervals (the one level of the figure), next to
    the true values.

    Under each panel, with units: estimate, std and, when the truth is known, the true value
    and ``z = (estimate − true)/std`` (in std).
    """
    tp = true_params(truth)
    fig, axs = plt.subplots(1, 4, figsize=(12, 4.2), constrained_layout=True)
    for i, (a, p) in enumerate((("x", "bias"), ("x", "scale"), ("y", "bias"), ("y", "scale"))):
        f = cal.fits[a]
        j = f.param_names.index(p)
        est, std, q = float(f.params[j]), float(f.std[j]), f.quantile(level)
        ax = axs[i]
        ax.errorbar([0], [est], yerr=[[q * std]], fmt="o", color="tab:blue", capsize=8,
                    label=f"estimate with its {100 * level:g} % interval (±{q:.3g} std)")
        unit = "m/s²" if p == "bias" else "(1)"  # (1): dimensionless, short enough to fit
        lo, hi = est - q * std, est + q * std
        text = f"estimate {est:.6g} {unit}\nstd {std:.3g} {unit}"
        if tp:
            tv = tp[f"{p}_{a}"]
            ax.axhline(tv, color="tab:green", ls="--", lw=1.5, label="true value")
            lo, hi = min(lo, tv), max(hi, tv)
            text += f"\ntrue {tv:.6g} {unit}\nz = {(est - tv) / std:+.2f} (std)"
        pad = 0.15 * (hi - lo)
        ax.set_ylim(lo - pad, hi + pad)
        ax.set_xlim(-1, 1)
        ax.set_xticks([])
        ax.set_xlabel(text, fontsize=8, family="monospace")
        ax.set_title(f"{p}_{a}")
        ax.set_ylabel(f"{p}_{a} ({'m/s²' if p == 'bias' else 'dimensionless'})")
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(True, axis="y", alpha=0.3)
    handles, labels = axs[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=8)
    fig.suptitle(title or f"Estimates with {100 * level:g}% intervals"
                 + (" against the true values" if tp else ""))
    return fig

"""Allan deviation of a static log (``tiltbench noise --plot``): per axis, log–log."""

from __future__ import annotations

from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from bench.figures.save import save_figure
from calib.noise.allan_model import FLICKER_FLOOR

if TYPE_CHECKING:
    from pathlib import Path

    from calib.noise.allan import AxisNoise, NoiseCharacterization

_TERM_STYLE = {  # name → (label, colour)
    "white_noise_density": ("white noise N, slope −½", "tab:blue"),
    "bias_instability": ("bias instability 0.664·B, slope 0", "tab:orange"),
    "rate_random_walk": ("rate random walk K, slope +½", "tab:red"),
}


def _term_line(name: str, value: float, tau: np.ndarray) -> np.ndarray:
    """ADEV asymptote of one term (IEEE Std 952): N/√τ, 0.664·B, K·√(τ/3)."""
    if name == "white_noise_density":
        return value / np.sqrt(tau)
    if name == "bias_instability":
        return np.full_like(tau, FLICKER_FLOOR * value)
    return value * np.sqrt(tau / 3.0)


def _axis_panel(ax, fit: AxisNoise, level: float) -> None:
    tau = fit.taus
    err = np.abs(fit.adev_ci - fit.adev[:, None]).T
    ax.errorbar(tau, fit.adev, yerr=err, fmt="o", color="k", ms=4, capsize=2, lw=1,
                label=f"overlapping ADEV, {level:.1%} interval (χ², EDF)")
    ax.plot(tau, fit.model_adev, color="0.4", lw=1.5, label="fitted model (sum of terms)")
    dense = np.geomspace(tau[0], tau[-1], 200)
    for t in fit.terms:
        label, colour = _TERM_STYLE[t.name]
        if t.resolved:
            ax.plot(dense, _term_line(t.name, t.value, dense), color=colour, ls="--", lw=1.2,
                    label=f"{label}: {t.value:.3g} {t.unit}")
            t0, t1 = t.tau_range
            ax.axvspan(t0, t1, color=colour, alpha=0.07)
        else:
            ax.plot(dense, _term_line(t.name, t.upper_bound, dense), color=colour, ls=":",
                    lw=1.0, label=f"{label}: not resolved, < {t.upper_bound:.3g} {t.unit}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("averaging time τ (s)")
    ax.set_ylabel(f"Allan deviation of a_{fit.axis} (m/s²)")
    note = "" if not fit.lack_of_fit else " — lack of fit"
    ax.set_title(f"axis {fit.axis}: χ² = {fit.chi2:.1f} on {fit.dof} dof, p = {fit.p_fit:.2g}"
                 f"{note}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")


def allan_figure(result: NoiseCharacterization, title: str | None = None) -> Figure:
    """ADEV per axis with χ² error bars at the result's level, the fitted model, each term's
    asymptote (dashed where resolved, its τ range shaded; dotted at the upper bound where
    not) with its slope labelled."""
    fig, axs = plt.subplots(1, len(result.axes), figsize=(6.5 * len(result.axes), 5.2),
                            constrained_layout=True, squeeze=False)
    for ax, fit in zip(axs[0], result.axes, strict=True):
        _axis_panel(ax, fit, result.level)
    fig.suptitle(title or f"Allan deviation: {result.n} samples at {result.sample_rate:g} Hz "
                 f"({result.duration:.4g} s); shaded: τ range each term was read from")
    return fig


def save_allan_plot(path: str | Path, result: NoiseCharacterization, force: bool = False,
                    title: str | None = None) -> Path:
    """Write :func:`allan_figure` (PNG or SVG by extension, atomically)."""
    return save_figure(allan_figure(result, title), path, force=force)  # closes the figure


__all__ = ["allan_figure", "save_allan_plot"]

"""Allan deviation of a static log (``tiltbench noise --plot``): one log–log panel per sensor
kind (accelerometer axes in m/s², gyro axes in rad/s), every axis of that kind in it."""

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

_COLOURS = ("tab:blue", "tab:orange", "tab:green")
_SHORT = {"white_noise_density": "N", "bias_instability": "B", "rate_random_walk": "K",
          "quantization_noise": "Q", "gauss_markov": "GM σ"}


def _term_line(name: str, value: float, tau: np.ndarray) -> np.ndarray:
    """ADEV asymptote of one term (IEEE Std 952): N/√τ, 0.664·B, K·√(τ/3), √3·Q/τ."""
    if name == "white_noise_density":
        return value / np.sqrt(tau)
    if name == "bias_instability":
        return np.full_like(tau, FLICKER_FLOOR * value)
    if name == "quantization_noise":
        return np.sqrt(3.0) * value / tau
    return value * np.sqrt(tau / 3.0)


def _label(fit: AxisNoise) -> str:
    """The axis's legend entry: its resolved terms in datasheet units, the model's p."""
    parts = []
    for t in fit.terms:
        ds = t.datasheet()
        if t.resolved:
            parts.append(f"{_SHORT[t.name]} {ds['value']:.3g} {ds['unit']}")
        elif t.name in _SHORT and t.name != "white_noise_density":
            parts.append(f"{_SHORT[t.name]} < {ds['upper_bound']:.2g} {ds['unit']}")
    ok = "" if fit.fit_ok else " — NO model describes it"
    return f"{fit.axis}: " + ", ".join(parts) + f" (p = {fit.p_fit:.2g}{ok})"


def _axis_curve(ax, fit: AxisNoise, colour: str, level: float) -> None:
    tau = fit.taus
    err = np.abs(fit.adev_ci - fit.adev[:, None]).T
    ax.errorbar(tau, fit.adev, yerr=err, fmt="o", color=colour, ms=3.5, capsize=2, lw=0.9,
                label=_label(fit))
    lo, hi = fit.octaves
    inside = np.zeros(tau.size, bool)
    inside[lo:hi] = True
    ax.plot(tau[inside], fit.model_adev[inside], color=colour, lw=1.6)
    if not inside.all():  # the model is not claimed outside its range
        ax.plot(tau, fit.model_adev, color=colour, lw=0.8, ls=":")
    dense = np.geomspace(tau[lo], tau[hi - 1], 100)
    for t in fit.terms:
        if t.resolved and t.name in ("white_noise_density", "bias_instability",
                                     "rate_random_walk", "quantization_noise"):
            ax.plot(dense, _term_line(t.name, t.value, dense), color=colour, ls="--", lw=0.7,
                    alpha=0.6)


def _kind_panel(ax, fits: list[AxisNoise], level: float) -> None:
    for k, fit in enumerate(fits):
        _axis_curve(ax, fit, _COLOURS[k % len(_COLOURS)], level)
    kind = fits[0].kind
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("averaging time τ (s)")
    ax.set_ylabel(f"Allan deviation ({fits[0].unit})")
    ax.set_title(kind, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6.5, loc="lower left")


def allan_figure(result: NoiseCharacterization, title: str | None = None) -> Figure:
    """One panel per sensor kind: each axis's ADEV with χ² error bars at the result's level,
    its fitted model (solid on the τ range the model describes, dotted outside), the resolved
    terms' asymptotes (dashed), the terms in datasheet units in the legend."""
    kinds: dict[str, list] = {}
    for fit in result.axes:
        kinds.setdefault(fit.kind, []).append(fit)
    fig, axs = plt.subplots(1, len(kinds), figsize=(7.0 * len(kinds), 5.4),
                            constrained_layout=True, squeeze=False)
    for ax, fits in zip(axs[0], kinds.values(), strict=True):
        _kind_panel(ax, fits, result.level)
    fig.suptitle((title or f"Allan deviation: {result.n} samples at {result.sample_rate:g} Hz "
                  f"({result.duration:.4g} s)")
                 + f"\npoints with {result.level:.1%} χ² bars (EDF); solid: the fitted model on "
                 "its τ range, dotted: outside it; dashed: resolved terms' asymptotes"
                 + _shaped_note(result), fontsize=10)
    return fig


def _shaped_note(result: NoiseCharacterization) -> str:
    """A caption line naming the axes whose model includes the export's low-pass filter
    (:mod:`calib.noise.shaping`), or nothing."""
    shaped = [f.axis for f in result.axes if f.export_filter is not None]
    if not shaped:
        return ""
    return (f"\nthe model of {', '.join(shaped)} includes the export's low-pass filter read "
            "from the log (the rise at short τ); the white asymptote is N/√τ without it")


def save_allan_plot(path: str | Path, result: NoiseCharacterization, force: bool = False,
                    title: str | None = None) -> Path:
    """Write :func:`allan_figure` (PNG or SVG by extension, atomically)."""
    return save_figure(allan_figure(result, title), path, force=force)  # closes the figure


__all__ = ["allan_figure", "save_allan_plot"]

"""Power curves of ``tiltbench design``: power against effect size, one panel per effect."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from calib.design import DesignResult, power_from_lambda
from calib.design.experiments import Experiment
from calib.design.signals import coefficients


def design_figure(res: DesignResult) -> Figure:
    """Analytic effects: power vs size (``P(χ²_k(λ₁c²) > crit)``), one curve per experiment,
    the 80 % and 95 % lines and the chosen size; Monte Carlo effects: the power at the chosen
    size with its exact 95 % interval per experiment, or with a grid (``--mc-grid``) the
    powers at the grid sizes with their exact 95 % intervals joined by lines (dashed: the
    isotonic fit), on a log size axis when the grid spans more than ×3."""
    names = list(res.effects)
    cols = 3
    rows = max(1, -(-len(names) // cols))
    fig, axes = plt.subplots(rows, cols, figsize=(5 * cols, 3.6 * rows), squeeze=False,
                             constrained_layout=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, name in zip(axes.ravel(), names, strict=False):
        e = res.effects[name]
        for i, (exp, r) in enumerate(zip(res.experiments, e["per_experiment"], strict=True)):
            col = colors[i % len(colors)]
            label = f"[{i}] {exp['design']} N={exp['n']}"
            if not r["testable"] or r.get("power") is None:
                continue
            if "lambda_unit" in r:
                x = Experiment(exp["design"], exp["n"], exp["rate"])
                top = max(abs(e["size"]), abs(r["size_95"] or 0.0)) * 1.5
                sizes = np.linspace(0.0, top, 200)
                lam = [r["lambda_unit"] * float(np.sum(coefficients(name, s, x, e["axis"]
                                                                    if name != "tilt_offset"
                                                                    else "x") ** 2))
                       for s in sizes]
                ax.plot(sizes, power_from_lambda(np.array(lam), r["df"], r["critical"]),
                        color=col, label=label)
            elif "grid" in r:  # --mc-grid: the powers at the grid sizes, joined
                gr = r["grid"]
                ci = np.array(gr["power_ci95"])
                pw = np.array(gr["powers"])
                ax.errorbar(gr["sizes"], pw, yerr=[pw - ci[:, 0], ci[:, 1] - pw], fmt="o-",
                            color=col, capsize=3, ms=4,
                            label=label + f" (MC, {gr['runs']} runs a point, exact 95 %)")
                ax.plot(gr["sizes"], gr["powers_monotone"], color=col, ls="--", lw=0.8)
            else:
                lo, hi = r["power_ci95"]
                ax.errorbar([e["size"]], [r["power"]],
                            yerr=[[r["power"] - lo], [hi - r["power"]]], fmt="o", color=col,
                            capsize=3, label=label + f" (MC, {r['runs']} runs, exact 95 %)")
        for p in (0.8, 0.95):
            ax.axhline(p, color="0.5", ls=":", lw=1)
        ax.axvline(e["size"], color="k", lw=0.8, ls="--")
        spans = [max(r["grid"]["sizes"]) / min(r["grid"]["sizes"])
                 for r in e["per_experiment"] if "grid" in r]
        if spans and max(spans) > 3.0:  # a wide grid: log size (saturation's stays linear)
            ax.set_xscale("log")
            ax.xaxis.set_minor_formatter(NullFormatter())
            ticks = next(r["grid"]["sizes"] for r in e["per_experiment"] if "grid" in r)
            ax.set_xticks(ticks, [f"{v:.3g}" for v in ticks])
        ax.set_ylim(-0.03, 1.03)
        ax.set_title(f"{name} ({e['axis']}), {e['method']}", fontsize=9)
        ax.set_xlabel(f"size ({e['unit']})")
        ax.set_ylabel("power (probability, dimensionless)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6)
    for ax in axes.ravel()[len(names):]:
        ax.axis("off")
    fig.suptitle("Power of the gap detection vs effect size (dotted: 80 % and 95 %; dashed: "
                 "the size asked)\nlines: analytic power (no Monte Carlo error); points: "
                 "Monte Carlo power with its exact 95 % binomial interval", fontsize=10)
    return fig

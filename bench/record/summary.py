"""The text documents and truth manifest of the recordings (``summary/*``, ``truth/``).

Markdown tables shown by the blueprints' text views: the estimates next to the true values
(:func:`parameters_markdown`) and the arrival decision (:func:`decision_markdown`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from bench.record.stream import json_normal
from calib.conventions import AXES
from calib.vehicle.region import box_k_for_level

if TYPE_CHECKING:
    from calib.vehicle.region import ArrivalRegion


def parameters_markdown(estimates: Mapping | None, truth: Mapping | None,
                        level: float = 0.95) -> str:
    """Markdown table: estimate, std, interval at ``level``, true value, z per parameter.

    Intervals are ``estimate ± q·std`` with ``q = Φ⁻¹((1 + L)/2)``
    (:func:`calib.vehicle.region.box_k_for_level`); ``z = (estimate − true)/std``.
    """
    from bench.validate import true_sensor_params

    tp = true_sensor_params(truth) if truth else None
    q = box_k_for_level(level)
    pct = f"{100 * level:g}%"
    lines = [f"| parameter | estimate | std | {pct} interval | true | z |",
             "|---|---|---|---|---|---|"]
    for a in AXES:
        for p, unit in (("bias", " (m/s²)"), ("scale", "")):
            est = std = None
            if estimates:
                ax = estimates.get("axes", {}).get(a, {})
                est, std = ax.get(p), ax.get(f"{p}_std")
            true = tp.get(f"{p}_{a}") if tp else None
            cells = [f"{p}_{a}{unit}"]
            cells.append("—" if est is None else f"{est:.6g}")
            cells.append("—" if std is None else f"{std:.3g}")
            cells.append("—" if est is None or std is None else
                         f"[{est - q * std:.6g}, {est + q * std:.6g}]")
            cells.append("—" if true is None else f"{true:.6g}")
            cells.append("—" if None in (est, std, true) or not std else
                         f"{(est - true) / std:+.2f}")
            lines.append("| " + " | ".join(cells) + " |")
    note = ("Intervals use normal quantiles (±" + f"{q:.3f}σ); z = (estimate − true)/std.")
    return "\n".join(lines) + "\n\n" + note + "\n"


def truth_manifest(truth: Mapping, seed: int) -> dict:
    """``truth.json`` as :func:`bench.dataset.write_truth` writes it, JSON-normalised."""
    from bench import dataset

    return json_normal(dataset.truth_manifest(dict(truth), seed))


def decision_markdown(region: ArrivalRegion, true_arrival: str | None = None) -> str:
    """Markdown summary of the arrival decision (and the truth, when known)."""
    lines = [f"### Arrival: {region.decision or 'undecided'}", "", region.reason, "",
             f"Estimate ({region.estimate[0]:.2f}, {region.estimate[1]:.2f}) m, std "
             f"({region.std[0]:.2f}, {region.std[1]:.2f}) m; {100 * region.level:g}% ellipse "
             f"semi-axes {region.ellipse.semi_axes[0]:.2f} × {region.ellipse.semi_axes[1]:.2f} m.",
             ""]
    if true_arrival is not None:
        lines += [f"True arrival point (truth.json): **{true_arrival}**", ""]
    lines += ["| candidate | x (m) | y (m) | Mahalanobis | inside |", "|---|---|---|---|---|"]
    for k, c in region.candidates.items():
        lines.append(f"| {k} | {c[0]:.2f} | {c[1]:.2f} | {region.mahalanobis[k]:.3f} | "
                     f"{'yes' if k in region.inside else 'no'} |")
    return "\n".join(lines) + "\n"


def true_arrival(truth: Mapping | None) -> str | None:
    """The true arrival letter from a course truth, if present (searched by key name)."""
    if not truth:
        return None
    stack: list[Any] = [truth]
    while stack:
        d = stack.pop()
        if isinstance(d, Mapping):
            for key in ("answer", "true_arrival", "arrival"):
                v = d.get(key)
                if isinstance(v, str):
                    return v
            stack.extend(d.values())
    return None

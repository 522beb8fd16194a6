"""The result of the discrepancy workflow: :class:`GapReport` (``gap --json``, summary)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from bench.effects import CATALOG, EffectSpec
from bench.gap.replay import Replay
from bench.model import TableEdits
from bench.sensors import SensorErrorModel
from calib.conventions import AXES

if TYPE_CHECKING:  # pragma: no cover
    from calib.gap import GapAnalysis


@dataclass(frozen=True)
class GapReport:
    """Result of :func:`bench.gap.run.run_gap`: the named effects and the gap before / after,
    per axis.

    Attributes
    ----------
    analysis : the ``calib.gap.GapAnalysis`` (detection, estimates, not identifiable).
    effects : the effects added to the bench model, with the parameters used there (sysid
        refinement for physical ones when it converged, else the ``calib`` estimate).
    sysid : effect index → ``mujoco.sysid`` refinement (:func:`bench.gap.sysid.sysid_refine`).
    replay : how the experiment was re-run.  tracking_error : max |θ_sim - θ_data|, rad.
    noise_var : (2,) stated noise variances, (m/s²)².  g : gravity used, m/s².
    timing : "t" (file), "rate" (``--rate``) or "none".
    nominal : axis → (bias, scale) fitted on the nominal simulation.
    after : axis → :class:`bench.gap.prediction.AxisPrediction` of the extended simulation.
    table_after : the physical edits of the extended model.
    sensor_after : the extended sensor model (terms, no noise, fitted bias/scale).
    gap_before, gap_after : axis → ``GapMeasure`` (data vs nominal / extended simulation).
    residual_before, residual_after : (N, 2), m/s² (after: whitened where the extended
        noise model is not white, see :func:`bench.gap.prediction.predict_axis`).
    family_alpha : family-wise level of "consistent with noise".
    files : name → path of the written outputs.
    """

    analysis: GapAnalysis
    effects: tuple[EffectSpec, ...]
    sysid: dict
    replay: Replay
    tracking_error: float
    noise_var: np.ndarray
    g: float
    timing: str
    nominal: dict
    after: dict
    table_after: TableEdits
    sensor_after: SensorErrorModel
    gap_before: dict
    gap_after: dict
    residual_before: np.ndarray
    residual_after: np.ndarray
    family_alpha: float
    files: dict = field(default_factory=dict)

    def consistent(self, which: str = "after") -> dict[str, bool]:
        """Per axis: is the gap (``"before"`` or ``"after"``) consistent with noise alone?"""
        gaps = self.gap_after if which == "after" else self.gap_before
        return {a: bool(gaps[a].consistent(self.family_alpha)) for a in AXES}

    def needs_timing(self) -> list[str]:
        """Catalog effects that need timing and were not tested because the data have none
        (empty when timing is known)."""
        skipped = getattr(self.analysis, "needs_timing", None)
        if skipped is not None:
            return list(skipped)
        if self.timing != "none":
            return []
        return [n for n, e in CATALOG.items() if e.timing == "yes"]

    def to_dict(self) -> dict:
        """The ``tiltbench gap --json`` object (documented keys first; extras allowed)."""
        a = self.analysis.to_dict()
        effects = []
        for i, e in enumerate(a.get("effects", [])):
            d = dict(e)
            d["timing"] = CATALOG[d["name"]].timing if d["name"] in CATALOG else "no"
            if i in self.sysid:
                d["sysid"] = self.sysid[i]
            if i < len(self.effects):
                d["used_in_model"] = dict(self.effects[i].params)
            effects.append(d)
        before = {ax: self.gap_before[ax].to_dict() for ax in AXES}
        after = {ax: self.gap_after[ax].to_dict() for ax in AXES}
        for ax in AXES:
            before[ax]["consistent"] = bool(self.gap_before[ax].consistent(self.family_alpha))
            after[ax]["consistent"] = bool(self.gap_after[ax].consistent(self.family_alpha))
            before[ax]["details"] = self.gap_before[ax].details()
            after[ax]["details"] = self.gap_after[ax].details()
        return {
            "effects": effects,
            "not_identifiable": a.get("not_identifiable", []),
            "gap_before": before,
            "gap_after": after,
            "needs_timing": self.needs_timing(),
            "timing": self.timing,
            "consistent_after": all(self.consistent("after").values()),
            "family_alpha": self.family_alpha,
            "g": self.g,
            "noise_var": [float(v) for v in self.noise_var],
            "replay": {"mode": self.replay.mode, "reason": self.replay.reason,
                       "tracking_error_rad": self.tracking_error},
            "nominal": {ax: {"bias": b, "scale": s} for ax, (b, s) in self.nominal.items()},
            "model_after": {
                "table": {"g": self.table_after.g,
                          "misalignment": list(self.table_after.misalignment),
                          "tilt_offset": self.table_after.tilt_offset,
                          "lever_arm": [list(p) for p in self.table_after.lever_arm],
                          "cutoff": list(self.table_after.cutoff)},
                "sensor": self.sensor_after.to_dict(),
            },
            "analysis": {k: v for k, v in a.items()
                         if k not in ("effects", "not_identifiable")},
            "files": dict(self.files),
        }

    def summary(self) -> str:
        """A readable report (what ``tiltbench gap`` prints without ``--json``)."""
        out = [f"Discrepancy workflow (gap): N = {self.replay.n}, g = {self.g} m/s², "
               f"stated σ² = {self.noise_var[0]:g}, {self.noise_var[1]:g} (m/s²)²",
               f"replay: {self.replay.mode} ({self.replay.reason}); timing: {self.timing}"]
        if self.replay.mode == "sweep":
            out.append(f"  replay tracks the measured encoder to {self.tracking_error:.2g} rad")
        d = self.to_dict()
        if not d["effects"]:
            out.append("effects named: none — nothing is missing from the model")
        else:
            out.append("effects named:")
            for e in d["effects"]:
                params = ", ".join(f"{k} = {v:.6g} ± {e['std'].get(k, float('nan')):.2g}"
                                   for k, v in e["params"].items())
                out.append(f"  {e['name']} ({e['axis']}): {params}; statistic "
                           f"{e['statistic']:.4g}, p = {e['p_value']:.3g}"
                           + ("" if e["timing"] == "no" else f" [timing: {e['timing']}]"))
                if "sysid" in e:
                    s = e["sysid"]
                    sp = ", ".join(f"{k} = {v:.6g} ± {s['std'][k]:.2g}"
                                   for k, v in s["params"].items())
                    out.append(f"      mujoco.sysid re-simulation: {sp}")
        for item in d["not_identifiable"]:
            out.append(f"not identifiable: {', '.join(item['names'])} — {item['reason']}")
        if d["needs_timing"]:
            out.append("not testable without timing (give t in the file or --rate): "
                       + ", ".join(d["needs_timing"])
                       + "; bias_drift / bias_random_walk are reported per sample")
        out.append(f"gap (χ²/dof with the stated noise; max signature z; consistent at "
                   f"family α = {self.family_alpha}):")
        for ax in AXES:
            b, a = self.gap_before[ax], self.gap_after[ax]
            out.append(f"  {ax}: before χ²/dof = {b.chi2_dof:.4f}, max z = "
                       f"{b.max_signature_z:.2f} ({b.worst}) "
                       f"{'consistent' if b.consistent(self.family_alpha) else 'GAP'}"
                       f" | after χ²/dof = {a.chi2_dof:.4f}, max z = {a.max_signature_z:.2f}"
                       f" ({a.worst}) "
                       f"{'consistent' if a.consistent(self.family_alpha) else 'GAP'}")
        for name, path in self.files.items():
            out.append(f"{name}: {path}")
        return "\n".join(out)


"""The result of the discrepancy workflow: :class:`GapReport` (``gap --json``, summary).

What a user reads first is the **verdict** of the estimation side
(``calib.gap.GapAnalysis.verdict``): "explained", "unexplained" (with the signatures that
remain, ``unexplained``) or "nothing_detected" (at the family α of the adequacy battery). The
bench adds, per axis, whether the re-simulated gap shrank and, if not, why (``shrink``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from bench.dataset import MODEL_UNITS
from bench.effects import CATALOG, EffectSpec
from bench.gap.replay import TRACKING_LIMIT, Replay
from bench.model import TableEdits
from bench.sensors import SensorErrorModel
from calib.conventions import AXES
from calib.gap.confusions import design_hint
from calib.gap.practical import gap_worse, worse_signature
from calib.gap.results import POOLED_WORDS, gap_units
from calib.units import effect_units, format_estimate, format_p, format_stat, nest, with_units

if TYPE_CHECKING:  # pragma: no cover
    from calib.gap import GapAnalysis

VERDICTS = ("explained", "unexplained", "nothing_detected")
"""The estimation side's verdicts (``calib.gap.GapAnalysis.verdict``)."""

MOTION_EFFECTS = ("lever_arm",)
"""Effects that change the simulated readings only when the table moves."""

NOISE_EFFECTS = ("noise_level",)
"""Effects that change the noise model, never the simulated readings."""

TABLE_EFFECTS = ("misalignment", "tilt_offset", "lever_arm", "saturation")
"""Effects the bench adds as edits of the MuJoCo table (MjSpec: the sites, the sensor cutoff)
and reads along the replayed motion — the first three refined by re-simulating it with
``mujoco.sysid``: a replay that does not follow θ cannot confirm them. (The sensor terms act
on the replay's specific force before and after alike.)"""


@dataclass(frozen=True)
class GapReport:
    """Result of :func:`bench.gap.run.run_gap`: the verdict, the named effects and the gap
    before / after, per axis.

    Attributes
    ----------
    analysis : the ``calib.gap.GapAnalysis`` (detection, estimates, not identifiable,
        verdict, unexplained signatures, adequacy battery, tentative effects).
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
    gap_before, gap_after : axis → ``GapMeasure`` (data vs nominal / extended simulation;
        after: measured with the extended model's noise, i.e. a named ``noise_level``).
    residual_before, residual_after : (N, 2), m/s² (after: whitened where the extended
        noise model is not white, see :func:`bench.gap.prediction.predict_axis`).
    family_alpha : family-wise level of "consistent with noise".
    chi2_after_stated : axis → χ²/dof after against the **stated** σ² (the reported
        ``gap_after.chi2_dof``; equal to ``gap_after[ax].chi2_dof`` unless ``noise_level``
        is named).
    readings_change : axis → ``{"max_abs", "norm_over_sigma"}``: how much the named effects
        change the simulated mean reading (m/s²; ‖Δ‖/σ_stated over the run).
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
    chi2_after_stated: dict = field(default_factory=dict)
    readings_change: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)

    # ------------------------------------------------------------------ verdict

    @property
    def verdict(self) -> str:
        """"explained", "unexplained" or "nothing_detected": the analysis' verdict, except
        that a verdict other than "unexplained" is never stated beside a re-simulated gap
        after that is not consistent with noise (:meth:`gap_problems`), nor beside an
        addition the re-simulation does not confirm (:meth:`addition_problems`: the gap after
        worse than before, or a replay that left its tracking limit): the report then says
        "unexplained" and lists what failed as the signature (one verdict, never
        contradicting its own numbers)."""
        verdict = str(getattr(self.analysis, "verdict", "nothing_detected"))
        if verdict != "unexplained" and (any(self.gap_problems(a) for a in AXES)
                                         or self.addition_problems()):
            return "unexplained"
        return verdict

    def named_on(self, ax: str) -> list[str]:
        """Names of the effects added to the model on ``ax`` (``gravity_mismatch`` aside)."""
        return sorted({e.name for e in self.effects
                       if ax in e.axes and e.name != "gravity_mismatch"})

    def tracking_failed(self) -> bool:
        """A servo replay whose encoder left the measured one by more than its limit
        (:data:`bench.gap.replay.TRACKING_LIMIT`)."""
        return self.replay.mode == "sweep" and self.tracking_error > TRACKING_LIMIT

    def worse_on(self, ax: str) -> list[str]:
        """Why the re-simulated gap after on ``ax`` is worse than before where effects were
        added there (:func:`calib.gap.practical.gap_worse`); empty when it is not, or when
        nothing was added on ``ax``."""
        if not self.named_on(ax):
            return []
        return gap_worse(self.gap_before[ax], self.gap_after[ax], self.chi2_after(ax))

    def addition_problems(self) -> list[dict]:
        """Why the addition of the named effects is not an explanation as re-simulated, one
        ``unexplained`` entry each (empty: nothing failed; nothing named: nothing to check):

        * ``gap_worse`` — on an axis with effects added, the re-simulated gap after is worse
          than before beyond the spread of each measure under noise alone
          (:func:`calib.gap.practical.gap_worse`: χ²/dof against the stated σ², largest
          signature |z|);
        * ``replay_tracking`` — the servo replay did not follow the measured θ (tracking
          error above :data:`bench.gap.replay.TRACKING_LIMIT`) and an effect of the table is
          named (:data:`TABLE_EFFECTS`): the re-simulation that fits and confirms it is not a
          replay of the measured motion. A sensor term (a walk, a noise level, K2, …) acts
          on the replay's specific force before and after alike, and the gap before/after
          consistency tests (:meth:`gap_problems`) judge its numbers."""
        out: list[dict] = []
        if not self.effects:
            return out
        for ax in AXES:
            problems = self.worse_on(ax)
            if problems:
                out.append(worse_signature(ax, self.named_on(ax), problems,
                                           self.chi2_after(ax) - self.gap_before[ax].chi2_dof))
        named = sorted({e.name for e in self.effects if e.name in TABLE_EFFECTS})
        if self.tracking_failed() and named:
            out.append({"axis": "both", "signature": "replay_tracking",
                        "size": float(self.tracking_error), "unit": "rad",
                        "statistic": float(self.tracking_error / TRACKING_LIMIT),
                        "p_value": None,
                        "description": f"the replay did not follow the measured θ (tracking "
                                       f"error {self.tracking_error:.2g} rad, above its limit "
                                       f"{TRACKING_LIMIT:g} rad): the re-simulation cannot "
                                       "show that the named effects "
                                       f"({', '.join(named)}) explain the gap"})
        return out

    @property
    def unexplained(self) -> list[dict]:
        """The signatures that remain unexplained (verdict "unexplained"), one dict each:
        the analysis' ones, what the re-simulation does not confirm
        (:meth:`addition_problems`), and, when the re-simulated gap after is what fails, one
        per axis (``signature`` "gap_after")."""
        out = [dict(u) for u in getattr(self.analysis, "unexplained", ())]
        have = {(u.get("axis"), u.get("signature")) for u in out}
        analysis_said = str(getattr(self.analysis, "verdict", "")) == "unexplained"
        # a gap after that is not consistent is said once, as "gap_after" (with "worse than
        # before" in its words when it is); a consistent one that is worse, as "gap_worse"
        out += [u for u in self.addition_problems()
                if (u["axis"], u["signature"]) not in have
                and not (u["signature"] == "gap_worse" and not analysis_said
                         and self.gap_problems(u["axis"]))]
        if analysis_said:
            return out
        for ax in AXES:
            problems = self.gap_problems(ax)
            if problems:
                gm = self.gap_after[ax]
                worse = self.worse_on(ax)
                out.append({"axis": ax, "signature": "gap_after", "size": self.chi2_after(ax),
                            "unit": "1", "statistic": float(gm.max_signature_z),
                            "p_value": None,
                            "description": f"the re-simulated gap after on {ax} is not "
                                           "consistent with noise: " + "; ".join(problems)
                                           + ("" if not worse else
                                              f"; and adding {', '.join(self.named_on(ax))} "
                                              "made it worse than before: "
                                              + "; ".join(worse))})
        return out

    @property
    def adequacy(self) -> dict:
        """The adequacy battery run on the final model (``family_alpha``, ``checks``, …)."""
        return dict(getattr(self.analysis, "adequacy", None) or {})

    @property
    def verdict_alpha(self) -> float:
        """α the verdict is stated at: the false-alarm bound of a clean run, the selection's
        family α plus the adequacy battery's (``calib.gap.analyze_gap``)."""
        c = dict(getattr(self.analysis, "criterion", None) or {})
        return (float(c.get("family_alpha", self.family_alpha))
                + float(self.adequacy.get("family_alpha", 0.0)))

    def tentative(self) -> list[bool]:
        """Per named effect (order of ``effects``): named, but the final model fails adequacy
        (or the re-simulated gap after is not consistent with noise)."""
        down = self.verdict == "unexplained"
        return [down or bool(getattr(e, "tentative", False)) for e in self.analysis.effects]

    @property
    def consistency_alpha(self) -> float:
        """Level of each consistency test of the re-simulated gap after: the adequacy
        battery's per-check level (the same Bonferroni as the verdict's checks), else the
        family α."""
        return float(self.adequacy.get("alpha_check", self.family_alpha))

    def verdict_lines(self) -> list[str]:
        """The verdict in words: a headline, then one line per unexplained signature."""
        checks = self.adequacy.get("checks", [])
        passed = sum(bool(c.get("passed")) for c in checks)
        battery = (f"{passed} of {len(checks)} adequacy checks pass" if checks
                   else "adequacy battery not run")
        alpha = f"α = {self.verdict_alpha:g}"
        if self.verdict == "unexplained":
            out = ["verdict: UNEXPLAINED — unexplained structure remains:"]
            out += [f"  {signature_line(u)}" for u in self.unexplained]
            if not self.unexplained:
                out.append("  (no signature listed)")
            return out
        if self.verdict == "explained":
            return [f"verdict: explained — the named effects account for the structure found "
                    f"({battery} at family {alpha})"]
        if self.effects and not checks:  # an analysis that ran no battery has no verdict
            return [f"verdict: not available ({battery}); {len(self.effects)} effect(s) named"]
        return [f"verdict: nothing detected at {alpha} ({battery})"]

    # ------------------------------------------------------------------ gap after

    def chi2_after(self, ax: str) -> float:
        """χ²/dof after, against the stated σ² (see ``chi2_after_stated``)."""
        return float(self.chi2_after_stated.get(ax, self.gap_after[ax].chi2_dof))

    def noise_named(self, ax: str) -> bool:
        """Does the extended model replace the stated σ² of ``ax`` (``noise_level``)?"""
        return any(e.name in NOISE_EFFECTS and ax in e.axes for e in self.effects)

    def after_problems(self, ax: str) -> list[str]:
        """Why the gap after on ``ax`` is not consistent with the stated noise (empty: it is):
        the analysis' unexplained signatures on the axis, then :meth:`gap_problems`."""
        mine = [str(u.get("description", u.get("signature", "?")))
                for u in getattr(self.analysis, "unexplained", ())
                if u.get("axis") in (ax, "both")]
        out = []
        if str(getattr(self.analysis, "verdict", "")) == "unexplained" and mine:
            out.append(f"unexplained structure remains on {ax}: " + "; ".join(mine)
                       + " (see verdict)")
        out += [u["description"] for u in self.addition_problems()
                if u["axis"] in (ax, "both")]
        return out + self.gap_problems(ax, mine)

    def gap_problems(self, ax: str, mine: list[str] | None = None) -> list[str]:
        """The re-simulated gap after on ``ax`` against the stated noise: χ²/dof outside its
        two-sided band, or the largest signature above its threshold, each at
        :attr:`consistency_alpha` (empty: consistent)."""
        gm, alpha = self.gap_after[ax], self.consistency_alpha
        lo, hi = gm.chi2_band(alpha)
        chi2 = self.chi2_after(ax)
        out = []
        if mine is None:
            mine = [u for u in getattr(self.analysis, "unexplained", ())
                    if u.get("axis") in (ax, "both")]
        named_ok = self.noise_named(ax) and not mine and lo <= gm.chi2_dof <= hi
        # a named noise level that passed the adequacy battery (uniform in time and θ,
        # Gaussian) explains the excess over the stated σ²: χ² against it is the yardstick
        if not lo <= chi2 <= hi and not named_ok:
            text = (f"χ²/dof = {chi2:.4g} against the stated σ² = "
                    f"{self.noise_var[AXES.index(ax)]:g} is outside [{lo:.3g}, {hi:.3g}]")
            if self.noise_named(ax):
                text += (f"; the named noise_level σ² = {self.after[ax].sigma2:.4g} gives "
                         f"χ²/dof = {gm.chi2_dof:.4g}")
            out.append(text)
        if gm.max_signature_z > gm.threshold_z(alpha):
            out.append(f"largest signature z = {gm.max_signature_z:.3g} ({gm.worst}) above "
                       f"{gm.threshold_z(alpha):.3g}")
        return out

    def consistent(self, which: str = "after") -> dict[str, bool]:
        """Per axis: is the gap (``"before"`` or ``"after"``) consistent with noise alone?

        After: χ²/dof against the stated σ² inside its band (or, where a noise level is named
        and no signature remains, against the named σ²), the largest signature z below its
        threshold, and no unexplained signature on the axis (:meth:`after_problems` is empty).
        """
        if which == "before":
            return {a: bool(self.gap_before[a].consistent(self.family_alpha)) for a in AXES}
        return {a: not self.after_problems(a) for a in AXES}

    def shrink(self) -> dict[str, dict]:
        """Per axis: did the gap shrink (effects named on the axis and χ²/dof after < before,
        both against the stated σ²) and, if not, why (``reason``)."""
        return {ax: self._shrink_axis(ax) for ax in AXES}

    def _shrink_axis(self, ax: str) -> dict:
        b, a = self.gap_before[ax], self.gap_after[ax]
        before, after = float(b.chi2_dof), self.chi2_after(ax)
        names = self.named_on(ax)
        change = self.readings_change.get(ax, {"max_abs": 0.0, "norm_over_sigma": 0.0})
        out = {"shrunk": bool(names) and after < before, "chi2_dof_before": before,
               "chi2_dof_after": after, "max_signature_z_before": float(b.max_signature_z),
               "max_signature_z_after": float(a.max_signature_z), "effects": names,
               "readings_change": {k: float(v) for k, v in change.items()}}
        out["reason"] = self._shrink_reason(ax, out, names, change)
        return out

    def _shrink_reason(self, ax: str, sh: dict, names: list[str], change: dict) -> str:
        """Why the gap on ``ax`` shrank (χ² before → after) or why it did not."""
        before, after = sh["chi2_dof_before"], sh["chi2_dof_after"]
        listed = ", ".join(names)
        problems = self.after_problems(ax)
        if sh["shrunk"]:
            return f"χ²/dof {before:.4g} → {after:.4g} with {listed} added" + (
                "; the gap after is still not consistent with noise: " + "; ".join(problems)
                if problems else "")
        if not names:
            both = self.gap_before[ax].consistent(self.family_alpha) and not problems
            return f"no effect named on {ax}: the model is unchanged there" + (
                " (its gap is consistent with noise before and after)" if both
                else "; not consistent with noise: " + "; ".join(
                    problems or ["see the gap before"]))
        if self.tracking_failed():
            return (f"the replay could not follow θ: tracking error {self.tracking_error:.2g} "
                    f"rad (limit {TRACKING_LIMIT:g} rad)")
        moving = sorted(set(names) & set(MOTION_EFFECTS))
        if self.replay.mode == "static" and moving:
            return (f"the replay is static ({self.replay.reason}): {', '.join(moving)} "
                    "changes nothing without motion")
        if set(names) <= set(NOISE_EFFECTS):
            return (f"{listed} changes the noise model, not the simulated readings: χ²/dof "
                    f"against the stated σ² stays {after:.4g}; against the named σ² = "
                    f"{self.after[ax].sigma2:.4g} it is {self.gap_after[ax].chi2_dof:.4g}"
                    + (" — unexplained structure remains (see verdict)"
                       if self.verdict == "unexplained"
                       else " (the verdict says whether that excess is explained)"))
        if change["norm_over_sigma"] < 1.0:
            return (f"the named effect(s) on {ax} ({listed}) change the simulated readings by "
                    f"less than the noise (‖Δ‖/σ = {change['norm_over_sigma']:.2g} over the "
                    f"run, largest |Δ| = {change['max_abs']:.2g} m/s²)")
        if self.verdict == "unexplained":
            return "unexplained structure remains (see verdict)"
        return (f"χ²/dof did not fall ({before:.4g} → {after:.4g}) although the named effects "
                f"change the readings by ‖Δ‖/σ = {change['norm_over_sigma']:.3g}: the "
                "extension as re-simulated does not fit these data (see gap_after details)")

    def needs_timing(self) -> list[str]:
        """Catalog effects that need timing and were not tested because the data have none
        (empty when timing is known)."""
        skipped = getattr(self.analysis, "needs_timing", None)
        if skipped is not None:
            return list(skipped)
        if self.timing != "none":
            return []
        return [n for n, e in CATALOG.items() if e.timing == "yes"]

    # ------------------------------------------------------------------ outputs

    def _gap_dicts(self) -> tuple[dict, dict]:
        """``gap_before`` and ``gap_after`` of the JSON object (after: χ²/dof against the
        stated σ², the model's when ``noise_level`` is named, ``consistent`` + ``reason``)."""
        before = {ax: self.gap_before[ax].to_dict() for ax in AXES}
        after = {ax: self.gap_after[ax].to_dict() for ax in AXES}
        for k, ax in enumerate(AXES):
            before[ax]["consistent"] = bool(self.gap_before[ax].consistent(self.family_alpha))
            before[ax]["details"] = self.gap_before[ax].details()
            problems = self.after_problems(ax)
            after[ax]["chi2_dof"] = self.chi2_after(ax)
            after[ax]["noise_var"] = float(self.noise_var[k])
            if self.noise_named(ax):
                after[ax]["chi2_dof_model"] = float(self.gap_after[ax].chi2_dof)
                after[ax]["noise_var_model"] = float(self.after[ax].sigma2)
            after[ax]["consistent"] = not problems
            if problems:
                after[ax]["reason"] = "; ".join(problems)
            after[ax]["details"] = self.gap_after[ax].details()
        return before, after

    def to_dict(self) -> dict:
        """The ``tiltbench gap --json`` object (documented keys first; extras allowed)."""
        a = self.analysis.to_dict()
        effects = []
        tentative = self.tentative()
        for i, e in enumerate(a.get("effects", [])):
            d = dict(e)
            d["tentative"] = bool(d.get("tentative", False)) or (
                i < len(tentative) and tentative[i])
            d["timing"] = CATALOG[d["name"]].timing if d["name"] in CATALOG else "no"
            if i in self.sysid:
                d["sysid"] = self.sysid[i]
            if i < len(self.effects):
                d["used_in_model"] = dict(self.effects[i].params)
            effects.append(d)
        before, after = self._gap_dicts()
        return with_units({
            "verdict": self.verdict,
            "unexplained": self.unexplained,
            "adequacy": self.adequacy,
            "effects": effects,
            "reported": [dict(r) for r in getattr(self.analysis, "reported", ())],
            "not_identifiable": a.get("not_identifiable", []),
            "gap_before": before,
            "gap_after": after,
            "shrink": self.shrink(),
            "needs_timing": self.needs_timing(),
            "timing": self.timing,
            "consistent_after": all(after[ax]["consistent"] for ax in AXES),
            "family_alpha": self.family_alpha,
            "g": self.g,
            "noise_var": [float(v) for v in self.noise_var],
            "replay": {"mode": self.replay.mode, "reason": self.replay.reason,
                       "tracking_error_rad": self.tracking_error,
                       "tracking_limit_rad": TRACKING_LIMIT,
                       "holds": self.replay.holds, "jumps": len(self.replay.jumps)},
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
                         if k not in ("effects", "not_identifiable", "verdict", "unexplained",
                                      "adequacy", "reported", "units")},
            "files": dict(self.files),
        }, report_units())

    def summary(self) -> str:
        """A readable report (what ``tiltbench gap`` prints without ``--json``): the verdict
        first, then the replay, the named effects, the gap before / after and the shrink."""
        d = self.to_dict()
        out = self.verdict_lines()
        out += [f"Discrepancy workflow (gap): N = {self.replay.n}, g = {self.g} m/s², "
                f"stated σ² = {self.noise_var[0]:g}, {self.noise_var[1]:g} (m/s²)²",
                f"replay: {self.replay.mode} ({self.replay.reason}); timing: {self.timing}"]
        if self.replay.mode == "sweep":
            out.append(f"  replay tracks the measured encoder to {self.tracking_error:.2g} rad")
        profile = dict(getattr(self.analysis, "criterion", None) or {}).get("profile") or {}
        out += [f"from the sensor profile: {line}"
                for line in profile.get("terms_from_profile", [])]
        for s in self.adequacy.get("sponges", []):
            out.append(f"{'named' if s['named'] else 'not named'}: {s['reason']}")
        units = effect_units()
        out.append("effects named (estimate ± 1 std):" if d["effects"] else "effects named: none")
        for e in d["effects"]:
            params = ", ".join(
                f"{k} = " + format_estimate(v, e["std"].get(k, float("nan")), units.get(k, ""))
                for k, v in e["params"].items())
            pooled = POOLED_WORDS if e.get("pooled") else ""
            out.append(f"  {effect_name(e)}: {params}; statistic {format_stat(e['statistic'])}"
                       f"{pooled}, {format_p(e['p_value'])}"
                       + ("" if e["timing"] == "no" else f" [timing: {e['timing']}]"))
            if "params" in e.get("sysid", {}):
                s = e["sysid"]
                sp = ", ".join(f"{k} = " + format_estimate(v, s["std"][k], units.get(k, ""))
                               for k, v in s["params"].items())
                out.append(f"      mujoco.sysid re-simulation: {sp}")
        for r in d["reported"]:
            out.append(f"  reported, not named: {r['description']}")
        for item in d["not_identifiable"]:
            hint = f" — {design_hint(item['names'])}" if len(item["names"]) == 2 else ""
            out.append(f"not identifiable: {', '.join(item['names'])} — {item['reason']}{hint}")
        if d["needs_timing"]:
            out.append("not testable without timing (give t in the file or --rate): "
                       + ", ".join(d["needs_timing"])
                       + "; bias_drift / bias_random_walk are reported per sample")
        out.append(f"gap (χ²/dof with the stated noise; max signature z; consistent at "
                   f"family α = {self.family_alpha}):")
        for ax in AXES:
            b, a, da = self.gap_before[ax], self.gap_after[ax], d["gap_after"][ax]
            out.append(f"  {ax}: before χ²/dof = {b.chi2_dof:.4f}, max z = "
                       f"{b.max_signature_z:.2f} ({b.worst}) "
                       f"{'consistent' if d['gap_before'][ax]['consistent'] else 'GAP'}"
                       f" | after χ²/dof = {da['chi2_dof']:.4f}, max z = "
                       f"{a.max_signature_z:.2f} ({a.worst}) "
                       f"{'consistent' if da['consistent'] else 'GAP'}")
            if "reason" in da:
                out.append(f"      after not consistent: {da['reason']}")
        out.append("shrink (gap after vs before, χ²/dof against the stated σ²):")
        for ax in AXES:
            sh = d["shrink"][ax]
            out.append(f"  {ax}: {shrink_word(sh)} — {sh['reason']}")
        for name, path in self.files.items():
            out.append(f"{name}: {path}")
        return "\n".join(out)


def report_units() -> dict[str, str]:
    """The ``units`` of :meth:`GapReport.to_dict` (``gap --json``, ``gap.json``): the
    analysis's (:func:`calib.gap.results.gap_units`) plus the bench's keys (docs/units.md)."""
    calib_units = gap_units()
    eff = effect_units()
    out = dict(calib_units)
    out.update({f"effects.sysid.*.{k}": u for k, u in eff.items()})
    out.update({f"model_after.sensor.*.{k}": u for k, u in eff.items()})
    out.update({
        "effects.sysid.bias.*": "m/s²", "effects.sysid.scale.*": "1",
        "effects.sysid.cost_start": "1", "effects.sysid.cost_end": "1",
        "effects.sysid.iterations": "count", "effects.sysid.n_residuals": "count",
        "gap_before.*.details.dof": "count", "gap_after.*.details.dof": "count",
        "gap_before.*.details.*": "1", "gap_after.*.details.*": "1",
        "gap_before.*.details.signatures.*": "1", "gap_after.*.details.signatures.*": "1",
        "gap_after.*.noise_var": "(m/s²)²", "gap_after.*.noise_var_model": "(m/s²)²",
        "gap_after.*.chi2_dof_model": "1",
        "shrink.*.readings_change.max_abs": "m/s²", "shrink.*.readings_change.*": "1",
        "shrink.*.*": "1",
        "family_alpha": "1", "g": "m/s²", "noise_var": "(m/s²)²",
        "replay.tracking_error_rad": "rad", "replay.tracking_limit_rad": "rad",
        "replay.holds": "count", "replay.jumps": "count",
        "nominal.*.bias": "m/s²", "nominal.*.scale": "1",
        **nest("model_after", MODEL_UNITS),
    })
    out.update(nest("analysis", calib_units))
    return out


def shrink_word(sh: dict) -> str:
    """"shrank", "unchanged" (nothing named on the axis) or "did not shrink"."""
    return "shrank" if sh["shrunk"] else ("did not shrink" if sh["effects"] else "unchanged")


def effect_name(e: dict) -> str:
    """``name (axis)`` of an effect dict of :meth:`GapReport.to_dict`, ``(tentative)`` marked."""
    return f"{e['name']} ({e['axis']})" + (" (tentative)" if e.get("tentative") else "")


def signature_line(u: dict) -> str:
    """One unexplained signature in words: axis, description, then signature name, size with
    unit, statistic and p."""
    parts = [str(u.get("signature", ""))]
    if u.get("size") is not None:
        parts.append(f"size {float(u['size']):.3g} {u.get('unit', '')}".rstrip())
    if u.get("statistic") is not None:
        parts.append(f"statistic {float(u['statistic']):.4g}")
    if u.get("p_value") is not None:
        parts.append(format_p(u["p_value"]))
    details = ", ".join(p for p in parts if p)
    return (f"{u.get('axis', '?')}: {u.get('description', u.get('signature', '?'))}"
            + (f" [{details}]" if details else ""))

"""The whole N analysis of :mod:`calib.vehicle.nmin` on one data set (e.g. the course files) and its
result: the analytic design and a-posteriori N, the course question (fixed run) with its
regeneration check, the redrawn design, the course's subsampling experiment and fresh
synthetic runs. N in samples, positions m, areas m², probabilities fractions.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from calib.calibration.tilt_plane import Calibration, calibrate
from calib.conventions import G
from calib.files.course import Acel, Ensayo
from calib.results import ResultMixin
from calib.stats.proportion import lower_bound
from calib.stats.runs import Mapper
from calib.units import nest, with_units
from calib.vehicle.nmin.case import VehicleCase
from calib.vehicle.nmin.confirm import CONFIRM_N_MAX, ConfirmRow, confirm_fixed_run
from calib.vehicle.nmin.fixed_run import FIXED_RUN_N_MAX, fixed_run_nmin
from calib.vehicle.nmin.redrawn import redrawn_design
from calib.vehicle.nmin.scaling import (
    PositionCovModel,
    course_box_nrange,
    design_nmin,
    posterior_nrange,
)
from calib.vehicle.nmin.subsample import COURSE_STEPS, SubsampleRow, subsample_analysis
from calib.vehicle.nmin.synthetic import McRow, simulate_decisions
from calib.vehicle.region import AREA_COMPARISON_UNITS, arrival_region
from calib.vehicle.trajectory import COURSE_P0, COURSE_V0, Integrator, compute_trajectory


@dataclass(frozen=True, eq=False, kw_only=True)
class NminResult(ResultMixin):
    """Result of the N analysis (see the module docstring for the definitions).

    level : L.  n_data : N of the data.  estimate : (2,) arrival point, m.  decision :
    letter or None.  design*, posterior* : dicts of :func:`design_nmin` /
    :func:`posterior_nrange` / :func:`course_box_nrange` (N in samples, separations
    dimensionless Mahalanobis units).  subsample : :class:`SubsampleRow` s.  monte_carlo :
    :class:`McRow` s.  notes : caveats.  area_comparison : areas m² and ratios.
    ``NminResult.from_dict(r.to_dict()) == r`` (exact).
    """

    _TITLE = "N analysis"
    _UNITS = ("N in samples; positions and box sizes m; areas m²; separations in Mahalanobis "
              "units (dimensionless); level a fraction")

    level: float
    n_data: int
    estimate: np.ndarray
    decision: str | None
    design: dict
    design_calibration_only: dict
    posterior: dict
    posterior_calibration_only: dict
    posterior_course_box: dict
    subsample: tuple = ()
    monte_carlo: tuple = ()
    notes: tuple = field(default_factory=tuple)
    area_comparison: dict = field(default_factory=dict)
    fixed_run: dict = field(default_factory=dict)
    confirmation: tuple = ()
    redrawn: dict = field(default_factory=dict)

    _JSON_UNITS = {  # the units of to_dict(), one home (docs/units.md)
        "level": "1", "n_data": "count", "estimate": "m",
        **{f"{k}.{leaf}": u for k in ("design", "design_calibration_only")
           for leaf, u in (("level", "1"), ("n", "count"), ("required_separation", "1"),
                           ("limiting_separation", "1"), ("*", "1"))},
        **{f"{k}.{leaf}": "count" for k in ("posterior", "posterior_calibration_only",
                                            "posterior_course_box")
           for leaf in ("n_min", "n_max", "crossings.*", "*")},
        "subsample.step": "count", "subsample.n": "count", "subsample.estimate": "m",
        "subsample.std": "m", "subsample.semi_axes": "m", "subsample.course_box": "m",
        "subsample.mahalanobis.*": "1",
        "monte_carlo.n": "count", "monte_carlo.level": "1", "monte_carlo.right_rate": "1",
        "monte_carlo.coverage": "1", "monte_carlo.*": "count",
        **nest("area_comparison", AREA_COMPARISON_UNITS),
        "fixed_run.n": "count", "fixed_run.n_band": "count", "fixed_run.draws": "count",
        "fixed_run.seed": "count", "fixed_run.grid_n": "count", "fixed_run.*": "1",
        "confirmation.n": "count", "confirmation.runs": "count", "confirmation.right": "count",
        "confirmation.wrong": "count", "confirmation.undecided": "count",
        "confirmation.seed": "count", "confirmation.*": "1",
        "redrawn.n": "count", "redrawn.draws": "count", "redrawn.*": "1",
    }

    def to_dict(self) -> dict:
        return with_units({
            "level": self.level, "n_data": self.n_data,
            "estimate": np.asarray(self.estimate).tolist(), "decision": self.decision,
            "design": self.design, "design_calibration_only": self.design_calibration_only,
            "posterior": self.posterior,
            "posterior_calibration_only": self.posterior_calibration_only,
            "posterior_course_box": self.posterior_course_box,
            "subsample": [r.to_dict() for r in self.subsample],
            "monte_carlo": [r.to_dict() for r in self.monte_carlo],
            "notes": list(self.notes), "area_comparison": self.area_comparison,
            "fixed_run": self.fixed_run,
            "confirmation": [r.to_dict() for r in self.confirmation],
            "redrawn": self.redrawn,
        }, self._JSON_UNITS)

    @classmethod
    def from_dict(cls, d: dict) -> NminResult:
        """Rebuild from :meth:`to_dict` (exact, also through JSON).

        Examples
        --------
        >>> from calib.vehicle.nmin import NminResult
        >>> r = NminResult.from_dict({
        ...     "level": 0.95, "n_data": 10, "estimate": [0.0, 0.0], "decision": None,
        ...     "design": {}, "design_calibration_only": {}, "posterior": {},
        ...     "posterior_calibration_only": {}, "posterior_course_box": {}})
        >>> NminResult.from_dict(r.to_dict()) == r
        True
        """
        return cls(
            level=float(d["level"]), n_data=int(d["n_data"]),
            estimate=np.array(d["estimate"], dtype=float), decision=d["decision"],
            design=dict(d["design"]), design_calibration_only=dict(d["design_calibration_only"]),
            posterior=dict(d["posterior"]),
            posterior_calibration_only=dict(d["posterior_calibration_only"]),
            posterior_course_box=dict(d["posterior_course_box"]),
            subsample=tuple(SubsampleRow.from_dict(r) for r in d.get("subsample", ())),
            monte_carlo=tuple(McRow.from_dict(r) for r in d.get("monte_carlo", ())),
            notes=tuple(d.get("notes", ())), area_comparison=dict(d.get("area_comparison", {})),
            fixed_run=dict(d.get("fixed_run", {})),
            confirmation=tuple(ConfirmRow.from_dict(r) for r in d.get("confirmation", ())),
            redrawn=dict(d.get("redrawn", {})),
        )

    def summary(self) -> str:
        L = f"{100 * self.level:g}%"

        def rng_txt(d: dict) -> str:
            if d["n_min"] is None:
                return "never"
            hi = "∞" if d["n_max"] is None else f"{d['n_max']}"
            return f"{d['letter']} for {d['n_min']} ≤ N ≤ {hi}"

        def design_txt(d: dict) -> str:
            if d["n"] is None:
                lim = d["limiting_separation"]
                extra = (f"; with infinite N the closest pair {'/'.join(d['limiting_pair'])} "
                         f"is {lim:.2f} apart, {d['required_separation']:.2f} needed"
                         if lim is not None else "")
                return f"no N suffices (pair {'/'.join(d['binding_pair'])}{extra})"
            return f"N ≥ {d['n']} (binding pair {'/'.join(d['binding_pair'])})"

        out = [
            f"N analysis at {L} (θ uniform over [0, 2π); data: N = {self.n_data}, "
            f"decision {self.decision or 'undecided'})",
        ]
        if self.fixed_run:
            f = self.fixed_run
            out.append(f"  this vehicle run given (the course question): new calibration of "
                       f"N samples, P(decision made and right = {f['truth']}) ≥ {L}:")
            if f["n"] is None:
                out.append(f"    the level {L} cannot be reached with this run: the best "
                           f"reachable is P = {f['best_probability']:.5f} (N ≤ "
                           f"{FIXED_RUN_N_MAX}; N → ∞: P = {f['p_infinity']:g})")
            else:
                lo, hi = f["n_band"]
                out.append(
                    f"    N ≥ {f['n']} (P = {f['probability']:.5f} there, "
                    f"{f['probability_below']:.5f} at N - 1; {f['draws']} draws from the "
                    f"estimator's sampling law, std error {f['std_error']:.1g}: N between "
                    f"{lo} and {hi} at ±3σ; N → ∞: P = {f['p_infinity']:g})")
            for c in self.confirmation:
                out.append(f"    regeneration check: {c.summary()}")
        if self.redrawn:
            r = self.redrawn
            out.append(f"  design, vehicle noise redrawn too (truth {r['truth']}): "
                       f"{r['message']}; asymptote P_∞ = {r['p_infinity']:.5f}")
        out += [
            f"  design, full region (decided and right with prob ≥ {L}): "
            f"{design_txt(self.design)}",
            f"  design, calibration part only (course assumption, no vehicle noise): "
            f"{design_txt(self.design_calibration_only)}",
            f"  a posteriori (this estimate fixed), full region : {rng_txt(self.posterior)}",
            f"  a posteriori, calibration part only            : "
            f"{rng_txt(self.posterior_calibration_only)}",
            f"  a posteriori, course box criterion (3σ)        : "
            f"{rng_txt(self.posterior_course_box)}",
        ]
        if self.area_comparison:
            a = self.area_comparison
            out.append(f"  {L} ellipse area / course box area (same level, N = {self.n_data}): "
                       f"{a['ratio_to_course_box']:.3f}; calibration part alone: "
                       f"{a['calibration_only_ratio_to_course_box']:.3f}")
        if self.subsample:
            out.append("  subsampled course calibration (course report LS, section 3.2.4):")
            out.append(f"  {'step':>5}{'N':>7}{'x (m)':>9}{'y (m)':>9}{'ours':>7}{'inside':>10}"
                       f"{'cal-only':>9}{'box x (m)':>10}{'box y (m)':>10}{'course':>8}"
                       f"{'inside':>10}")
            for r in self.subsample:
                out.append(
                    f"  {r.step:>5}{r.n:>7}{r.estimate[0]:>9.1f}{r.estimate[1]:>9.1f}"
                    f"{r.decision or '-':>7}{','.join(r.inside) or '-':>10}"
                    f"{r.calibration_only_decision or '-':>9}{r.course_box[0]:>10.1f}"
                    f"{r.course_box[1]:>10.1f}{r.course_decision or '-':>8}"
                    f"{','.join(r.course_inside) or '-':>10}")
        if self.monte_carlo:
            out.append("  fresh synthetic runs, vehicle noise redrawn (truth at the decided "
                       "candidate):")
            out.append(f"  {'N':>8}{'runs':>6}{'right':>7}{'wrong':>7}{'undecided':>10}"
                       f"{'truth inside':>14}")
            for m in self.monte_carlo:
                out.append(f"  {m.n:>8}{m.runs:>6}{m.right:>7}{m.wrong:>7}{m.undecided:>10}"
                           f"{m.truth_inside:>14}   supports P(right) ≥ "
                           f"{lower_bound(m.right, m.runs):.4f} at 95 %")
        out.extend(f"  note: {n}" for n in self.notes)
        return "\n".join(out)


NOTES = (
    "no N can guarantee a decision in general: the vehicle-noise part of the arrival "
    "covariance does not shrink with the calibration N, candidates may be arbitrarily close "
    "(or the estimate may fall between two), and at level L the truth is outside its region "
    "with probability 1 - L whatever N is",
    "the fixed-run N answers the course question (this vehicle run given, a new calibration "
    "drawn; plug-in: the full calibration is the truth, the decided candidate the arrival "
    "point); the design N redraws the vehicle noise as well, so there P(made and right) never "
    "exceeds L: it makes the level-L regions pairwise disjoint and only touches L; the "
    "a-posteriori range holds only for this estimate",
    "the course box bound leaves out the vehicle noise and uses worst-case |a|max: it is too "
    "wide in the calibration part and too narrow overall",
)


def analyze_nmin(
    ensayo: Ensayo | None, acel: Acel, candidates: dict[str, np.ndarray], *,
    p0=COURSE_P0, v0=COURSE_V0, noise_var=None, level: float = 0.997, method: str = "ols",
    integrator: Integrator = "trapezoid", g: float = G, steps: Sequence[int] = COURSE_STEPS,
    mc_n: Sequence[int] = (), runs: int = 0, seed: int = 0,
    progress: Callable[[str], None] | None = None, draws: int = 0, confirm_runs: int = 0,
    mapper: Mapper | None = None, count: Callable[[int, int], None] | None = None,
    calibration: Calibration | None = None,
) -> NminResult:
    """The whole N analysis on one data set (e.g. the course files).

    With ``calibration`` (a :class:`calib.Calibration`, e.g. loaded from a calibration file)
    the estimates, σ² and N come from it and ``ensayo`` may be None: every part of the
    analysis but the course's subsampling experiment needs only them (the sampling law and
    the regenerated runs assume θ uniform over a turn, as everywhere here); the subsampling
    re-fits every k-th sample of the ensayo, so it is skipped without one.

    Analytic design and a-posteriori N (module docstring), the course's subsampling
    experiment, and — when ``runs > 0`` — fresh synthetic runs at each N of ``mc_n`` (plus
    the design N when finite and ≤ 10⁶). Synthetic runs use the corrected accelerations of
    the data as the true profile, the calibration estimate as the true sensor errors, and the
    candidates translated so the decided one (or the nearest) is the true arrival point.
    ``progress`` (optional) is called with a short message before each long step.

    Parameters
    ----------
    ensayo : the calibration run (``tita`` (N,) rad, ``datos`` (N, 2) m/s²); None with
        ``calibration``.
    acel : the vehicle run (``t`` (M,) s, ``aerr`` (M, 2) m/s²).
    candidates : name → (2,) candidate arrival point, m.
    p0 : (2,) initial position, m.  v0 : (2,) initial velocity, m/s.
    noise_var : (2,) noise variances, (m/s²)², or None (estimated).
    level : confidence level L.  method : "ols" or "wls".  integrator : "trapezoid" or
        "simpson".  g : gravity, m/s².
    steps : subsampling steps of the course experiment (every k-th sample; () skips it).
    mc_n : calibration sizes N for fresh synthetic runs (vehicle noise redrawn).
    runs : runs per N (0: none).  seed : seed of the draws and of the synthetic runs.
    draws : draws from the calibration's sampling law for the fixed-run N
        (:func:`fixed_run_nmin`; 0: skipped).  confirm_runs : regenerated calibrations at the
        fixed-run answer (:func:`confirm_fixed_run`, when N ≤ ``CONFIRM_N_MAX``; 0: none).
    mapper : runs the regeneration (:mod:`calib.stats.runs`; default in-process).
    count : ``count(done, total)`` chunks of the regeneration done.
    calibration : use this calibration instead of fitting ``ensayo`` (see above).

    Returns
    -------
    NminResult : design and a-posteriori N, subsampling rows, synthetic-run rows.

    Examples
    --------
    >>> import numpy as np
    >>> from calib import Acel, Ensayo, analyze_nmin
    >>> th = np.linspace(0.0, 2 * np.pi, 2000, endpoint=False)
    >>> e = Ensayo(th, np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]))
    >>> a = Acel(np.arange(1001) * 0.01, np.zeros((1001, 2)))
    >>> r = analyze_nmin(e, a, {"A": [10.0, 30.0], "B": [60.0, 30.0]}, noise_var=[0.25, 0.64],
    ...                  steps=())
    >>> r.decision, r.design["n"] is not None
    ('A', True)
    """
    say = progress or (lambda _msg: None)
    if calibration is None:
        if ensayo is None:
            raise ValueError("analyze_nmin needs an ensayo or a calibration")
        cal = calibrate(ensayo, noise_var, method, g)  # type: ignore[arg-type]
    else:
        cal = calibration
        method, g = cal.method, cal.g
    case = VehicleCase(candidates, p0, v0, level, method, integrator, g)
    traj = compute_trajectory(acel, cal, case.p0, case.v0, integrator)
    reg = arrival_region(traj, cal, case.candidates, noise_var, level)
    full = PositionCovModel.from_region(reg, g)
    calonly = PositionCovModel.from_region(reg, g, include_noise=False)
    box1 = reg.course_box_bound * np.sqrt(cal.n)  # box ∝ 1/√N for uniform θ
    rows = []
    if steps and ensayo is not None:
        say(f"subsampling the calibration (steps {list(steps)})")
        rows = subsample_analysis(ensayo, acel, case, steps, noise_var)
    design = design_nmin(case.candidates, full, level)
    truth = reg.decision or min(reg.mahalanobis, key=reg.mahalanobis.get)
    fixed: dict = {}
    confirm = []
    if draws > 0:
        say(f"fixed-run N: {draws} draws from the calibration's sampling law")
        fixed = fixed_run_nmin(reg, truth, draws, seed, g)
        if confirm_runs > 0 and fixed["n"] is not None and fixed["n"] <= CONFIRM_N_MAX:
            say(f"regenerating {confirm_runs} calibrations of N = {fixed['n']} "
                "(vehicle run given)")
            confirm.append(confirm_fixed_run(
                acel, case, truth=truth, n=fixed["n"], runs=confirm_runs, seed=seed,
                bias=cal.bias, scale=cal.scale, noise_var=reg.noise_var,
                predicted=fixed["probability"], mapper=mapper, progress=count))
    redrawn = redrawn_design(case.candidates, full, truth, level, max(draws, 10**5), seed)
    mc = []
    if runs > 0:
        ns = list(mc_n)
        if design["n"] is not None and design["n"] <= 10**6 and design["n"] not in ns:
            ns.append(int(design["n"]))
        moved = case.moved(reg.estimate - case.candidates[truth])
        for i, n in enumerate(ns):
            say(f"synthetic runs {i + 1}/{len(ns)}: {runs} calibrations of N = {int(n)}")
            mc.append(simulate_decisions(moved, acel.t, traj.acc_corrected, truth=truth,
                                         n=int(n), runs=runs, seed=seed + i, bias=cal.bias,
                                         scale=cal.scale, noise_var=reg.noise_var))
    return NminResult(
        level=level, n_data=cal.n, estimate=reg.estimate, decision=reg.decision,
        design=design,
        design_calibration_only=design_nmin(case.candidates, calonly, level),
        posterior=posterior_nrange(reg.estimate, case.candidates, full, level),
        posterior_calibration_only=posterior_nrange(reg.estimate, case.candidates, calonly,
                                                    level),
        posterior_course_box=course_box_nrange(reg.estimate, case.candidates, box1),
        subsample=tuple(rows), monte_carlo=tuple(mc), notes=NOTES,
        area_comparison=reg.area_comparison(), fixed_run=fixed, confirmation=tuple(confirm),
        redrawn=redrawn,
    )


__all__ = ["NOTES", "NminResult", "analyze_nmin"]

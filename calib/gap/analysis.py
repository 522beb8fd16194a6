""":func:`analyze_gap`: select the effects, estimate them, measure the gap before and after."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from calib.calibration.tilt_plane import Calibration, calibrate
from calib.conventions import AXES, G
from calib.effects import Extensions, ModelState, RunData, effect, stated_variances
from calib.effects.catalog import REFINED
from calib.files.course import Ensayo
from calib.gap.adequacy import ADEQUACY_ALPHA, Battery, run_battery
from calib.gap.asymmetry import K2, k2_or_asymmetry
from calib.gap.asymmetry import PAIR as ASYMMETRY
from calib.gap.asymmetry import signature as asymmetry_signature
from calib.gap.confusions import merge_tilt, not_identifiable, prefer_less_assuming
from calib.gap.cubic import K3, named_or_k3
from calib.gap.cubic import signature as cubic_signature
from calib.gap.drive_bias import (
    LEVER,
    WALK,
    lever_or_drive_bias,
    structured_or_drive_bias,
    walk_or_drive_bias,
)
from calib.gap.drive_bias import signature as drive_bias_signature
from calib.gap.drive_noise import LEVEL as NOISE_LEVEL
from calib.gap.drive_noise import level_or_drive_noise
from calib.gap.drive_noise import signature as drive_noise_signature
from calib.gap.drive_state import drive_checks, drive_fits, joint_drive, joint_tone, tone_scans
from calib.gap.estimates import Reporter
from calib.gap.mechanisms import drive_scans, mechanism_checks
from calib.gap.practical import (
    PRACTICAL_FRACTION,
    below_words,
    gap_worse,
    mean_change,
    noise_change,
    quantization_change,
    walk_change,
    worse_signature,
)
from calib.gap.results import EffectEstimate, ExtendedModel, GapAnalysis
from calib.gap.selection import (
    FAMILY_ALPHA,
    JOINT_NOISE,
    candidate_list,
    initial_state,
    joint_noise,
    select,
    try_test,
)
from calib.gap.space import AxisSpace
from calib.gap.sponges import review_sponges
from calib.gap.step_swap import STEP, named_or_step
from calib.gap.step_swap import signature as step_signature
from calib.gap.walk import WALK_CHECKS, WalkReview, review_walk
from calib.noise.sensor_profile import SensorProfile
from calib.stats.diagnostics import GapMeasure, Lattice, detect_lattice, gap_measure


def analyze_gap(ensayo: Ensayo, noise_var, g: float = G, rate: float | None = None,
                family_alpha: float = FAMILY_ALPHA, adequacy_alpha: float = ADEQUACY_ALPHA,
                sensor: SensorProfile | None = None,
                drive_torque: np.ndarray | Callable[[], np.ndarray | None] | None = None,
                on_named: Callable[[list[EffectEstimate], list[dict]], None] | None = None
                ) -> GapAnalysis:
    """Find where the nominal model and a measured calibration run disagree, name the effect.

    Parameters
    ----------
    ensayo : the run: ``tita`` (N,) rad, ``datos`` (N, 2) m/s², optional ``t`` (N,) s;
        samples in time order.
    noise_var : (2,) stated noise variances [σx², σy²], (m/s²)².
    g : gravity, m/s² (course convention ``A_rx = -g sin θ``, ``A_ry = -g cos θ``).
    rate : sample rate, Hz, when ``t`` is missing (``t = k / rate``); without either the
        effects that need timing are skipped (``needs_timing``) and drift / random walk are
        per sample.
    family_alpha : false-alarm probability of the whole selection on a run without any
        effect; the per-step threshold is ``family_alpha / m`` (Bonferroni over the m tests).
    sensor : a sensor profile (``sensor.json``, :func:`calib.noise.sensor_profile.load_profile`):
        its ``rate_random_walk`` per axis states the bias random walk's q (m/s²/√s, the same
        q): the walk's q is searched only inside the term's interval and it is charged no
        parameter; an axis whose term is null has no walk candidate. Needs sample times.
        Which terms came from the profile: ``criterion["profile"]``.
    drive_torque : (N,) the drive's joint torque at the samples, N·m, when the caller has it
        (the bench's inverse dynamics of the replayed θ(t), ``bench.gap.replay``), or a
        callable that returns it (or None) when asked (computed alongside): the
        drive-state checks (:mod:`calib.gap.drive_state`) then test a level and a gain that
        follow it. A quantity derived from the measured encoder, never from a truth.
    on_named : called once, as ``on_named(effects, reported)``, when the selection has named
        its effects (:class:`EffectEstimate` list) and the practical rule has set aside the
        reported ones (dicts, as in ``GapAnalysis.reported``), before the adequacy checks: a
        caller may start work that depends on them alongside (the bench refines the physical
        ones with ``mujoco.sysid``). The checks that follow may still withdraw a named effect,
        so the caller compares with the returned ``effects`` before using such work.

    Returns
    -------
    GapAnalysis

    Notes
    -----
    Criterion (:mod:`calib.gap.selection`), reference distributions
    (:meth:`calib.effects.Extensions.test`), ties and confusions (:mod:`calib.gap.confusions`),
    the adequacy battery and the verdict (:mod:`calib.gap.adequacy`): "unexplained" when a
    check fails (the named effects are then tentative), else "explained" when something is
    named, else "nothing_detected" (at the stated α, never a proof that nothing is missing).
    ``gap_after`` is measured against the stated noise (σ² + lsb²/12), not an estimated one.
    ``calib`` never sees the bench: this works on the measured arrays only.
    """
    for label, a in (("family_alpha", family_alpha), ("adequacy_alpha", adequacy_alpha)):
        if not 0 < a < 1:
            raise ValueError(f"{label} must be in (0, 1), got {a}")
    stated = stated_variances(noise_var)
    run = RunData.build(ensayo.tita, ensayo.datos, g, ensayo.t, rate)
    if drive_torque is not None and not callable(drive_torque):
        drive_torque = _torque(drive_torque, run.n)
    nominal = calibrate(ensayo, stated, "ols", g)
    gains = 1.0 + nominal.scale
    for k, a in enumerate(AXES):  # the extensions act through the sensor's gain
        if not gains[k] > 0:
            std = float(nominal.fits[a].std[1])
            ref = "−g sin θ" if a == "x" else "−g cos θ"
            raise ValueError(
                f"{ensayo.source}: variable 'datos' column {k + 1}: the {a} readings do not "
                f"follow {ref} (fitted gain 1 + scale = {gains[k]:.3g} ± {std:.2g}, expected "
                "≈ 1): the gap workflow needs a sensor that responds to the tilt; is this "
                "the right column/file, or is the θ range too small to tell?")
    ext = Extensions(run, gains)

    lattice = [detect_lattice(run.datos[:, k]) for k in range(2)]
    candidates, needs_timing = candidate_list(run)
    profile = _apply_profile(ext, sensor, candidates)
    sel = select(ext, initial_state(stated, lattice), candidates, family_alpha)
    steps = list(sel.steps)
    state = prefer_less_assuming(ext, sel.state, sel.candidates, steps)
    state = merge_tilt(ext, state, sel.candidates, steps)
    state, sponges = review_sponges(ext, state, lattice, float(np.log(sel.alpha_step)),
                                    joint=joint_noise(state, steps))

    rep = Reporter(ext, state, lattice)
    effects, reported = _practical(ext, rep, state,
                                   _named_effects(ext, rep, state, lattice, steps))
    if on_named is not None:
        on_named(list(effects), list(reported))
    before, after, resid_before, resid_after, fitted = _gaps(ext, rep, state, nominal)
    final = _final_model(ext, rep, state, gains)
    reviews = {k: review_walk(ext, state, k, rep.walk_input(k), rep.innov[k])
               for k in range(2) if state.axes[k].q > 0}
    if callable(drive_torque):  # computed alongside (the bench's replay): asked for now
        drive_torque = _torque(drive_torque(), run.n)
    spaces = [AxisSpace(ext, state, k) for k in range(2)]  # shared by the checks below
    drive = drive_scans(spaces, run)
    tones = tone_scans(ext, state, resid_after)  # both axes' drive_tone scan, made once
    fits = drive_fits(ext, state, drive_torque, spaces)  # the level and gain tests, once
    coarse = [st.lsb > np.sqrt(st.sigma2) for st in state.axes]  # rounding above the noise
    battery = run_battery(ext, state, resid_after, lattice, rep.innov, adequacy_alpha,
                          gaps=_battery_gaps(ext, state, after, resid_after),
                          extra=[c for r in reviews.values() for c in r.checks]
                          + [c for k in range(2) for c in mechanism_checks(
                              ext, state, k, lattice[k].lsb if lattice[k].found else 0.0,
                              space=spaces[k], drive_gains=None if drive is None else drive[k])]
                          + [c for k in range(2) for c in drive_checks(
                              ext, state, k, resid_after[:, k], drive_torque,
                              coarse=coarse[k], fits=None if fits is None else fits[k],
                              scans=tones)]
                          + [c for c in [joint_tone(ext, state, resid_after, coarse=any(coarse),
                                                    scans=tones)]
                             if c is not None]
                          + joint_drive(ext, state, resid_after, drive_torque, coarse=any(coarse),
                                        fits=fits),
                          spaces=spaces)
    reviews = {k: r.with_failed(tuple(c.name for c in battery.failed
                                      if c.axis == r.axis and c.name in WALK_CHECKS))
               for k, r in reviews.items()}
    drifting = [r for r in reviews.values() if not r.earned]
    # a walk that did not earn its place is not named (it stays in the model meanwhile)
    effects = [e for e in effects if not (e.name == "bias_random_walk"
                                          and any(r.axis == e.axis for r in drifting))]
    # a step-like drift is said by its steps: the walk's failed path checks (a jump, a
    # flicker floor, …) are about the walk that is not named and are not repeated (a rival
    # shape that adds beyond the walk, walk_rivals, still is)
    stepped = {r.axis for r in drifting if r.step_shaped}
    unexplained = [r.signature() for r in drifting] + [
        c.signature() for c in battery.failed
        if not (c.axis in stepped and c.name in WALK_CHECKS and c.name != "walk_rivals")]
    effects, said, pairs, terms = _outside_terms(ext, state, effects, battery, resid_after)
    unexplained += said
    unexplained += _never_worse(effects, before, after)
    verdict = ("unexplained" if unexplained else "explained" if effects
               else "nothing_detected")
    if verdict == "unexplained":
        effects = [replace(e, tentative=True) for e in effects]
    criterion = {"rule": "forward likelihood-ratio selection, Bonferroni per-step threshold; "
                         "structured effects first, a random walk only when it beats every "
                         "structured candidate by AIC with its effective dof",
                 "family_alpha": float(family_alpha), "alpha_step": float(sel.alpha_step),
                 "n_tests": int(sel.n_tests), "adequacy_alpha": float(adequacy_alpha)}
    if profile is not None:
        criterion["profile"] = profile
    return GapAnalysis(
        effects=tuple(effects),
        not_identifiable=tuple(not_identifiable(ext, state, sel.candidates, sel.untestable))
        + tuple(_walk_or_cycle(reviews)) + tuple(pairs),
        gap_before=before, gap_after_fit=after, nominal=nominal, final=final,
        residuals_before=resid_before, residuals_after=resid_after, fitted=fitted,
        needs_timing=tuple(needs_timing), criterion=criterion, steps=tuple(steps), g=float(g),
        noise_var=(float(stated[0]), float(stated[1])), verdict=verdict,
        unexplained=tuple(unexplained), reported=tuple(reported),
        adequacy={**_adequacy(battery, drifting, reviews), "sponges": sponges, **terms})


def _outside_terms(ext: Extensions, state: ModelState, effects: list[EffectEstimate],
                   battery: Battery, resid: np.ndarray
                   ) -> tuple[list[EffectEstimate], list[dict], list[dict], dict]:
    """Terms outside the catalog against the named effects: a scale asymmetry in place of a
    named K2 (:mod:`calib.gap.asymmetry`), a K3 in place of the structured effects of an axis
    (:mod:`calib.gap.cubic`; IEEE 1293), one step of the bias in place of them and the drift
    (:mod:`calib.gap.step_swap`), a bias tied to the drive in place of a lever arm, of the
    angle-shaped effects or of a random walk (:mod:`calib.gap.drive_bias`), noise added while
    the table moves in place of a noise level (:mod:`calib.gap.drive_noise`; ``resid`` the
    final model's residuals, (N, 2) m/s²).
    Effects a term leans against are not named (they stay in the model meanwhile). Returns the
    effects still named, the ``unexplained`` entries (the asymmetry's not again where
    ``rival_shapes`` already failed), the ``not_identifiable`` pairs and the ``adequacy``
    entries ``asymmetry``, ``cubic``, ``step``, ``drive_bias`` and ``drive_noise``."""
    effects, asymmetry = _swap_one(effects, K2, lambda k: k2_or_asymmetry(ext, state, k))
    shaped = {c.axis for c in battery.failed if c.name == "rival_shapes"}
    said = [asymmetry_signature(f) for f in asymmetry
            if f["decision"] == "leans" and f["axis"] not in shaped]
    effects, cubic = _swap_set(effects, lambda k, named: named_or_k3(ext, state, k, named))
    said += [cubic_signature(f) for f in cubic if f["decision"] == "leans"]
    effects, steps = _swap_set(effects, lambda k, named: named_or_step(ext, state, k, named))
    said += [step_signature(f) for f in steps if f["decision"] == "leans"]
    effects, drive = _swap_one(effects, LEVER, lambda k: lever_or_drive_bias(ext, state, k))
    effects, shaped_by_drive = _swap_set(
        effects, lambda k, named: structured_or_drive_bias(ext, state, k, named))
    drive += shaped_by_drive
    effects, walk_by_drive = _swap_one(effects, WALK, lambda k: walk_or_drive_bias(ext, state, k))
    drive += walk_by_drive
    said += [drive_bias_signature(f) for f in drive if f["decision"] == "leans"]
    effects, noise = _swap_one(effects, NOISE_LEVEL,
                               lambda k: level_or_drive_noise(ext, state, k, resid[:, k]))
    said += [drive_noise_signature(f) for f in noise if f["decision"] == "leans"]
    pairs = ([{"names": [K2, ASYMMETRY], "axis": f["axis"], "reason": f["reason"]}
              for f in asymmetry]
             + [{"names": [*f["names"], K3], "axis": f["axis"], "reason": f["reason"]}
                for f in cubic]
             + [{"names": [*f["names"], STEP], "axis": f["axis"], "reason": f["reason"]}
                for f in steps]
             + [{"names": [*f["names"], f["bias"]], "axis": f["axis"], "reason": f["reason"]}
                for f in drive]
             + [{"names": [NOISE_LEVEL, f["rival"]], "axis": f["axis"], "reason": f["reason"]}
                for f in noise])
    terms = {key: [{k: v for k, v in f.items() if k != "reason"} for f in found]
             for key, found in (("asymmetry", asymmetry), ("cubic", cubic), ("step", steps),
                                ("drive_bias", drive), ("drive_noise", noise))}
    return effects, said, pairs, terms


def _swap_set(effects: list[EffectEstimate],
              review: Callable[[int, list[str]], dict | None]
              ) -> tuple[list[EffectEstimate], list[dict]]:
    """``review(k, named)`` on each axis k with the names named there (a swap of a set of
    effects: K3, a step of the bias, a bias tied to the drive in place of the angle-shaped
    effects); the effects without those a review leans against, and the reviews found."""
    found = [f for k in range(2)
             if (f := review(k, [e.name for e in effects if e.axis == AXES[k]])) is not None]
    dropped = {(n, f["axis"]) for f in found if f["decision"] == "leans" for n in f["names"]}
    return [e for e in effects if (e.name, e.axis) not in dropped], found


def _swap_one(effects: list[EffectEstimate], name: str, review: Callable[[int], dict | None]
              ) -> tuple[list[EffectEstimate], list[dict]]:
    """``review(k)`` on each axis k where ``name`` is named (a one-effect swap: asymmetry,
    drive bias, drive noise); the effects without ``name`` where its review leans, and the
    reviews found."""
    found = [f for k in range(2) if any(e.name == name and e.axis == AXES[k] for e in effects)
             and (f := review(k)) is not None]
    leaning = {f["axis"] for f in found if f["decision"] == "leans"}
    return [e for e in effects if not (e.name == name and e.axis in leaning)], found


def _practical(ext: Extensions, rep: Reporter, state: ModelState,
               effects: list[EffectEstimate]) -> tuple[list[EffectEstimate], list[dict]]:
    """Split the effects of the final model into those named and those reported, not named:
    below :data:`calib.gap.practical.PRACTICAL_FRACTION` of σ in their change of the fit
    (:mod:`calib.gap.practical`). Reported effects stay in the model."""
    run = ext.run
    named, reported = [], []
    for e in effects:
        k = AXES.index(e.axis) if e.axis in AXES else 0
        st = state.axes[k]
        if e.name == "quantization":
            change = quantization_change(st.lsb, st.sigma2_stated)
        elif e.name == "noise_level":
            change = noise_change(st.sigma2, st.sigma2_stated)
        elif e.name == "bias_random_walk":
            change = walk_change(rep.walk_input(k), st.sigma2_eff, st.q, run.dt_walk)
        else:
            change = mean_change(e.statistic, run.n * (2 if e.axis == "both" else 1))
        if change >= PRACTICAL_FRACTION:
            named.append(e)
            continue
        reported.append({"name": e.name, "axis": e.axis,
                         "params": {key: float(v) for key, v in e.params.items()},
                         "std": {key: float(v) for key, v in e.std.items()},
                         "change": float(change), "unit": "σ",
                         "description": below_words(e.name, e.axis, change, e.params,
                                                    float(np.sqrt(st.sigma2_stated)))})
    return named, reported


def _never_worse(effects: list[EffectEstimate], before: dict[str, GapMeasure],
                 after: dict[str, GapMeasure]) -> list[dict]:
    """A ``gap_worse`` signature per axis where the named effects make the gap after worse
    than before beyond the null spread (:func:`calib.gap.practical.gap_worse`)."""
    out = []
    for a in AXES:
        names = sorted({e.name for e in effects if e.axis in (a, "both")})
        if not names:
            continue
        problems = gap_worse(before[a], after[a])
        if problems:
            out.append(worse_signature(a, names, problems,
                                       after[a].chi2_dof - before[a].chi2_dof))
    return out


def _torque(torque, n: int) -> np.ndarray | None:
    """The drive torque as a checked (n,) array of finite N·m, or None."""
    if torque is None:
        return None
    torque = np.asarray(torque, dtype=float)
    if torque.shape != (n,) or not np.all(np.isfinite(torque)):
        raise ValueError(f"drive_torque must be ({n},) finite N·m, got shape {torque.shape}")
    return torque


def _walk_or_cycle(reviews: dict[int, WalkReview]) -> list[dict]:
    """``not_identifiable`` entries of named walks that this run cannot tell from a slow cycle
    in time (:func:`calib.gap.walk.slow_cycle`), from steps of the bias
    (:func:`calib.gap.walk.step_drift`, decision ``"describes"``, or ``"leans"``: then the
    walk is not named) or from two-level switching (:func:`calib.gap.walk.switching_drift`)."""
    cycles = [{"names": ["bias_random_walk", "slow_cycle"], "axis": r.axis,
               "reason": r.cycle["description"]}
              for r in reviews.values()
              if r.earned and r.cycle is not None and r.cycle["decision"] == "cannot_tell"]
    steps = [{"names": ["bias_random_walk", r.steps["pair"]], "axis": r.axis,
              "reason": r.steps["cannot_tell"]}
             for r in reviews.values() if r.steps is not None and (
                 r.steps["decision"] == "leans" or r.earned and r.steps["decision"] == "describes")]
    return cycles + steps


def _apply_profile(ext: Extensions, sensor: SensorProfile | None,
                   candidates: list[tuple[str, str]]) -> dict | None:
    """Take the walk's q from a sensor profile (``analyze_gap`` docs): set
    ``ext.walk_bounds``, drop the walk candidate of an axis whose term is null, and say
    which terms came from the profile."""
    if sensor is None:
        return None
    terms = tuple(sensor.rate_random_walk or (None, None))
    out: dict = {"rate_random_walk": {}, "terms_from_profile": [], "unit": "m/s²/√s"}
    for k, a in enumerate(AXES):
        term = terms[k] if k < len(terms) else None
        if term is None:
            if ("bias_random_walk", a) in candidates:
                candidates.remove(("bias_random_walk", a))
            out["rate_random_walk"][a] = None
            out["terms_from_profile"].append(
                f"bias_random_walk ({a}): not a candidate — the profile's rate_random_walk "
                "is null (not resolved by its static log)")
            continue
        lo, hi = (float(v) for v in term.interval)
        out["rate_random_walk"][a] = {"value": float(term.value), "interval": [lo, hi],
                                      "level": float(term.level)}
        if ext.run.time_unit != "s":
            out["terms_from_profile"].append(
                f"bias_random_walk ({a}): the profile's q is per √s and this run has no sample"
                " times (t or --rate): the walk stays free")
            continue
        ext.walk_bounds[k] = (max(lo, 0.0), max(hi, lo, 0.0))
        out["terms_from_profile"].append(
            f"bias_random_walk ({a}): q within the profile's {100 * term.level:.3g} % interval "
            f"[{lo:.4g}, {hi:.4g}] m/s²/√s (value {term.value:.4g}), charged 0 parameters")
    return out


def _battery_gaps(ext: Extensions, state: ModelState, after: dict[str, GapMeasure],
                  resid_after: np.ndarray) -> dict[str, GapMeasure]:
    """The gap after as the battery judges it: against the stated noise, except on an axis
    with a named noise level, whose signatures are measured with the named σ² (its χ² is
    the noise level's own business, and the battery checks that excess for uniformity)."""
    run = ext.run
    out = dict(after)
    for k, a in enumerate(AXES):
        st = state.axes[k]
        if st.noise_free:
            out[a] = gap_measure(resid_after[:, k], run.tita, st.sigma2_eff,
                                 model_lsb=st.lsb if st.lsb > 0 else None,
                                 n_params=ext.n_params(state, k), t=run.t,
                                 other_ref=run.a_ref[:, 1 - k], own_ref=run.a_ref[:, k],
                                 readings=run.datos[:, k])
    return out


def _adequacy(battery: Battery, drifting: list[WalkReview], reviews: dict[int, WalkReview]
              ) -> dict:
    """The battery as a dict, plus per axis whether the gap after is consistent with noise:
    every check on the axis passed and no walk on it failed to earn its place — the battery
    holds the gap after's χ² against the stated noise and its signatures (``gap_noise``,
    ``gap_signatures``), so this is the verdict's own judgement, never a second one that
    could contradict it. ``walk``: the review of each named walk (:mod:`calib.gap.walk`)."""
    out = battery.to_dict()
    drift = {r.axis for r in drifting}
    out["consistent"] = {a: bool(battery.axis_passed(a) and a not in drift) for a in AXES}
    out["walk"] = [reviews[k].to_dict() for k in sorted(reviews)]
    return out


def _named_effects(ext: Extensions, rep: Reporter, state: ModelState, lattice: list[Lattice],
                   steps: list[dict]) -> list[EffectEstimate]:
    """Each effect of the final model: estimate ± std, drop-one statistic, interval (a noise
    level named on both axes at once: the pair's pooled test, on each axis' line)."""
    effects = []
    pair = joint_noise(state, steps)
    drops: dict[tuple[str, str], tuple[float, float]] = {}  # the pair's test serves both lines
    for name, axis in state.effects():
        e = effect(name)
        params, std = e.estimate(rep, axis)
        pooled = pair and name == JOINT_NOISE[0]
        if e.lr_tested:
            drop = JOINT_NOISE if pooled else (name, axis)
            if drop not in drops:
                t = try_test(ext, state.without(*drop), *drop)
                drops[drop] = ((t.lr, t.p_value) if t is not None
                               else (float("nan"), float("nan")))
            stat, p = drops[drop]
        else:  # the lattice test of step 0: number of levels, its p-value
            lat = lattice[AXES.index(axis)]
            stat, p = float(lat.levels), float(np.exp(lat.logp))
        interval = e.interval(rep, axis, params)
        effects.append(EffectEstimate(name, axis, params, std, float(stat), float(p), interval,
                                      pooled=pooled))
    return effects


def _gaps(ext: Extensions, rep: Reporter, state: ModelState, nominal: Calibration
          ) -> tuple[dict[str, GapMeasure], dict[str, GapMeasure], np.ndarray, np.ndarray,
                     np.ndarray]:
    """Gap of the nominal and of the extended model per axis, their residuals, the fit."""
    run = ext.run
    resid_before = np.column_stack([nominal.fits[a].residuals for a in AXES])
    resid_after = np.column_stack([rep.residual_after(k) for k in range(2)])
    fitted = np.column_stack([rep.mean(k) for k in range(2)])
    before, after = {}, {}
    for k, a in enumerate(AXES):
        common = dict(t=run.t, other_ref=run.a_ref[:, 1 - k], own_ref=run.a_ref[:, k],
                      readings=run.datos[:, k])
        st = state.axes[k]
        before[a] = gap_measure(resid_before[:, k], run.tita, st.sigma2_stated, n_params=2,
                                **common)
        stated_eff = st.sigma2_stated + st.lsb**2 / 12.0  # the stated noise, not σ̂²
        after[a] = gap_measure(resid_after[:, k], run.tita, stated_eff,
                               model_lsb=st.lsb if st.lsb > 0 else None,
                               n_params=ext.n_params(state, k), **common)
    return before, after, resid_before, resid_after, fitted


def _final_model(ext: Extensions, rep: Reporter, state: ModelState, gains: np.ndarray
                 ) -> ExtendedModel:
    """The extended model: linear parameters with covariance, nonlinear ones ± std."""
    nonlinear = {}
    for k, a in enumerate(AXES):
        for e in REFINED:
            if e.present(state.axes[k]):
                nonlinear[f"{a}.{e.field}"] = e.nonlinear(rep, k)
    return ExtendedModel(tuple(rep.names), rep.params, rep.cov, nonlinear,
                         (state.axes[0].sigma2_eff, state.axes[1].sigma2_eff),
                         (state.axes[0].sigma2, state.axes[1].sigma2), state,
                         (float(gains[0]), float(gains[1])), ext.run.time_unit)

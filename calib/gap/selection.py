"""Forward stepwise selection of the catalog effects, then one backward pass.

Selection criterion (stated once)
---------------------------------
Forward stepwise selection by likelihood-ratio tests with a Bonferroni-controlled family
error rate:

1. Step 0 — quantization: the readings of each axis are tested for a lattice
   (:func:`calib.stats.diagnostics.detect_lattice`); a lattice is named (its lsb adds lsb²/12 to
   the noise variance of every later test).
2. Every step — every remaining candidate (per axis: misalignment, nonlinearity_k2,
   cross_axis, bias_drift, bias_random_walk, saturation, noise_level, and with timing
   lowpass_lag, lever_arm; both axes: tilt_offset, and noise_level on both at once, the two
   axes' χ² pooled) is fitted on top of the current model and
   tested by its likelihood ratio (reference distributions in :meth:`Extensions.test`). The
   candidate with the smallest p-value is added if ``p < α_step = family_alpha / m``, m the
   number of tests at the first step (testable candidates + 2 lattice tests); all nonlinear
   parameters are then re-fitted. Stop when no candidate passes. Under noise alone the run
   names nothing unless some first-step test passes, so ``P(false alarm) ≤ family_alpha``
   (Bonferroni; default :data:`FAMILY_ALPHA` = 0.001, i.e. ≤ 0.1 % of clean runs).
3. Flexible last: ``bias_random_walk`` can follow almost any slow residual, so it is not in
   the pool of step 2. It is considered only when no structured candidate (nor the noise
   level) passes, and it is added only when (a) its own test passes ``α_step`` and (b) it
   explains the residual better than every structured candidate on that axis at its cost:
   ``LR_walk - 2·c_walk > max(0, max_s LR_s - 2·k_s)`` (AIC; k_s the structured candidate's
   parameters). After a walk is added, the structured candidates are tested again on top of
   it (step 2). And the other way round: where structured effects were named on an axis,
   the walk *in their place* is compared with them by the same criterion
   (``nll + 2·p`` against ``nll + 2·c_walk``): on a single sweep a walk's path is smooth in θ
   and several structured effects can share it out, so the cheaper explanation is kept.

   The walk's charge ``c_walk`` (:func:`walk_cost`). Its likelihood is the *marginal* one
   (the path integrated out): its log-determinant term already charges for the path's
   flexibility (the Occam factor), and q counts one parameter. Its effective degrees of
   freedom — the trace of the smoother's hat matrix
   (:func:`calib.gap.flexibility.walk_effective_dof`) — are what the fitted path uses; they
   are reported next to every decision (``steps``). Charging 2·edf *on top of* the marginal
   likelihood counts the flexibility twice: measured on sweeps with a true walk of 8–20σ
   (N = 6001), 3 of 3 walks then lost to sets of two or three structured effects that
   left harmonics behind (``WALK_CHARGE = "edf"`` reproduces it). Structured-first ordering,
   the swap comparison and the adequacy battery's rival shapes
   (:mod:`calib.gap.adequacy`) keep the walk from explaining structured or unknown effects.
4. One backward pass: an effect whose drop-one test no longer passes ``α_step`` is removed.

Noise level on both axes. A stated σ² off by one factor on both axes (a datasheet density
read at the wrong bandwidth) puts each axis' χ² a few σ above its mean; a lone axis must pass
``α_step`` alone, the two pooled (``calib.effects.noise``) reach √2 times the z of either.
The pooled candidate is one more test in m. Where one axis alone carries the excess, its own
test is the stronger and is named first; the pooled one is then not testable (that axis' σ²
is fitted). Named through the pooled test, the pair is kept or dropped together by the
backward pass (:data:`JOINT_NOISE`).

Noise level last. ``noise_level`` competes at every step, so a mere change of σ² is never
taken by a noise-like structured candidate (random walk, low-pass). It cannot take the place of
a real structured effect: an effect that explains ΔRSS gives ``LR = ΔRSS/σ²`` (log p ≈ -LR/2)
while the same ΔRSS as extra variance gives the χ² test ``log p ≈ -(n/2)(ρ - 1 - ln ρ)``,
``ρ = 1 + ΔRSS/(nσ²)``, always less extreme; so noise_level is in effect tested after the
structured effects, on the residuals of the extended model.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from calib.calibration.ls import NotIdentifiableError
from calib.conventions import AXES
from calib.effects import (
    NEEDS_TIMING,
    AxisState,
    Extensions,
    ModelState,
    RunData,
    Trial,
    effect,
)
from calib.gap.flexibility import walk_effective_dof
from calib.stats.diagnostics import Lattice

PER_AXIS_CANDIDATES: tuple[str, ...] = (
    "noise_level", "misalignment", "nonlinearity_k2", "cross_axis", "bias_drift",
    "bias_random_walk", "saturation", "lowpass_lag", "lever_arm")
"""Per-axis extensions tested at every step (``tilt_offset`` is tested for both axes, and
``noise_level`` also on both at once: :data:`JOINT_NOISE`)."""

FLEXIBLE: tuple[str, ...] = ("bias_random_walk",)
"""Flexible candidates: tested only after the structured ones, charged their effective dof."""

WALK_CHARGE = "marginal"
"""How a random walk is charged against structured explanations: "marginal" (its likelihood
integrates the path out; the log-determinant is the Occam charge; q counts 1) or "edf" (2·edf
on top, the AIC of a fitted smoother)."""

MAX_STEPS = 10

FAMILY_ALPHA = 0.001
"""Default family-wise false-alarm probability of the selection on a clean run (with the
battery's :data:`calib.gap.adequacy.ADEQUACY_ALPHA`, 0.35 % nominal in all). Why 0.001: a
tool that names nothing on ≥ 300 clean runs needs a false-alarm rate near 0.1 % (P(none in
300) = e^{−300 p}: 74 % at 0.1 %, 22 % at 0.5 %). At 0.005 + 0.005 the drive part's clean runs
(seeds 0, 2, 3, 4) alarmed in 7 of 1280 (0.55 %; the Bonferroni levels run at about half
their nominal rate), 4 of them by the selection, each at p within 0.4–0.85 of its per-step
level; the catalog effects of those seeds (z 6–12) were named at p at most 0.01 of that
level, so a level five times lower costs them nothing (one degree of freedom at z = 5: power
91 % → 83 %; at z = 6: 99 % → 97 %)."""


def walk_cost(ext: Extensions, st: AxisState, k: int | None = None) -> float:
    """Parameters a random walk on axis k (state ``st``) is charged (:data:`WALK_CHARGE`);
    0 when a sensor profile states its q (``ext.walk_bounds``: measured, not fitted)."""
    if k is not None and k in getattr(ext, "walk_bounds", {}):
        return 0.0
    if WALK_CHARGE == "edf":
        return walk_effective_dof(st.sigma2_eff, st.q, ext.run.dt_walk)
    return 1.0

LATTICE_TESTS = 2
"""Step 0 tests one lattice per axis; they count in the Bonferroni m."""


@dataclass(frozen=True)
class Selection:
    """The outcome of :func:`select`.

    state : the selected model.  candidates : the testable (name, axis) candidates.
    untestable : (name, axis) → why it cannot be tested in this experiment.
    n_tests, alpha_step : the Bonferroni m and per-step α.  steps : the selection trace.
    """

    state: ModelState
    candidates: list[tuple[str, str]]
    untestable: dict[tuple[str, str], str]
    n_tests: int
    alpha_step: float
    steps: tuple[dict, ...]


# --------------------------------------------------------------------- model moves

def _remaining(state: ModelState, candidates: list[tuple[str, str]]) -> list[tuple[str, str]]:
    return [(name, axis) for name, axis in candidates if not state.has(name, axis)]


_MISS = object()


def try_test(ext: Extensions, state: ModelState, name: str, axis: str,
         memo: dict | None = None) -> Trial | None:
    """``ext.test`` or None when the extension is not identifiable here.

    ``memo``: without a tilt offset the two axes' likelihoods are separate, so the test of a
    per-axis extension depends only on that axis' state; a test made before on the same axis
    state is reused with the other axis brought up to date (same LR and p-value)."""
    key = None
    if memo is not None and axis in AXES and not state.tilt:
        k = AXES.index(axis)
        key = (name, axis, state.axes[k])
        hit = memo.get(key, _MISS)
        if hit is None:
            return None
        if hit is not _MISS:
            new = state.with_axis(k, hit.state.axes[k])
            return replace(hit, state=new, nll=ext.nll(new))
    try:
        trial = ext.test(state, name, axis)
    except NotIdentifiableError:
        trial = None
    if key is not None:
        memo[key] = trial
    return trial


# --------------------------------------------------------------------------- steps

def initial_state(noise_var, lattice: list[Lattice]) -> ModelState:
    """Step 0: the nominal model at the stated σ² (checked by
    :func:`calib.effects.stated_variances`), with the lattice of each axis if found."""
    return ModelState.nominal(noise_var, [lat.lsb if lat.found else 0.0 for lat in lattice])


def candidate_list(run: RunData) -> tuple[list[tuple[str, str]], tuple[str, ...]]:
    """(name, axis) candidates for this run (tilt offset third), and the skipped timed ones."""
    needs_timing = () if run.timed else NEEDS_TIMING
    candidates = [(n, a) for n in PER_AXIS_CANDIDATES if n not in needs_timing for a in AXES]
    candidates.insert(2, ("tilt_offset", "both"))
    candidates.append(("noise_level", "both"))
    return candidates, needs_timing


def first_step(ext: Extensions, state: ModelState, candidates: list[tuple[str, str]]
                ) -> tuple[list[Trial], dict[tuple[str, str], str]]:
    """Test every candidate on the nominal model; those that raise are untestable here."""
    untestable: dict[tuple[str, str], str] = {}
    trials = []
    for name, axis in candidates:
        try:
            trials.append(ext.test(state, name, axis))
        except NotIdentifiableError as exc:
            untestable[(name, axis)] = str(exc).split(";")[0]
    return trials, untestable


def _evidence(t: Trial) -> tuple[float, float]:
    """Sort key, strongest first: the log p-value, then the likelihood ratio (very strong
    effects all reach the floor of log p, :data:`calib.stats.diagnostics.LOGP_FLOOR`)."""
    return (t.logp, -t.lr)


def _flexible_choice(ext: Extensions, trials: list[Trial], log_alpha: float
                     ) -> tuple[Trial | None, list[dict]]:
    """The flexible candidate to add, if any: it passes ``α_step`` and beats every structured
    candidate on its axis by AIC with its effective dof (module docstring, step 3)."""
    notes = []
    flexible = sorted((t for t in trials if t.name in FLEXIBLE and t.logp < log_alpha),
                      key=_evidence)
    for t in flexible:
        k = AXES.index(t.axis)
        st = t.state.axes[k]
        edf = walk_effective_dof(st.sigma2_eff, st.q, ext.run.dt_walk)
        crit = t.lr - 2.0 * walk_cost(ext, st, k)
        rivals = [(s.lr - 2.0 * effect(s.name).n_free, s.name) for s in trials
                  if s.name not in FLEXIBLE and s.name != "noise_level"
                  and s.axis in (t.axis, "both")]
        best_rival = max(rivals, default=(0.0, None))
        accepted = crit > max(0.0, best_rival[0])
        notes.append({"flexible": [t.name, t.axis], "lr": t.lr, "edf": edf,
                      "criterion": crit, "best_structured": [best_rival[1], best_rival[0]],
                      "accepted": accepted})
        if accepted:
            return t, notes
    return None, notes


def _forward(ext: Extensions, state: ModelState, trials: list[Trial],
             candidates: list[tuple[str, str]], log_alpha: float, steps: list[dict],
             memo: dict | None = None) -> ModelState:
    """Add the best structured candidate while its p-value passes, else a flexible one that
    pays for its cost; refit the nonlinear parameters after each addition."""
    memo = {} if memo is None else memo
    for _ in range(MAX_STEPS):
        if not trials:
            break
        pool = [t for t in trials if t.name not in FLEXIBLE]
        best = min(pool, key=_evidence) if pool else None
        notes: list[dict] = []
        if best is None or best.logp >= log_alpha:
            best, notes = _flexible_choice(ext, trials, log_alpha)
        step = {"added": [best.name, best.axis] if best is not None else None,
                "candidates": [[t.name, t.axis, t.lr, t.p_value]
                               for t in sorted(trials, key=_evidence)]}
        if notes:
            step["flexible"] = notes
        steps.append(step)
        if best is None:
            break
        state = ext.refine(best.state)
        trials = [t for t in (try_test(ext, state, n, a, memo)
                              for n, a in _remaining(state, candidates)) if t is not None]
    return state


def _flexible_swap(ext: Extensions, state: ModelState, candidates: list[tuple[str, str]],
                   log_alpha: float, steps: list[dict]) -> ModelState:
    """Per axis: the structured effects named there against a walk in their place (AIC, the
    walk charged its effective dof); the walk is kept only when its own test passes."""
    for k, axis in enumerate(AXES):
        st = state.axes[k]
        named = [n for n in st.effects() if n not in ("noise_level", "quantization")]
        if not named or st.q > 0 or ("bias_random_walk", axis) not in candidates:
            continue
        reduced = state
        for n in named:
            reduced = reduced.without(n, axis)
        t = try_test(ext, reduced, "bias_random_walk", axis)
        if t is None or t.logp >= log_alpha:
            continue
        walk = ext.refine(t.state)
        sw = walk.axes[k]
        edf = walk_effective_dof(sw.sigma2_eff, sw.q, ext.run.dt_walk)
        c_named = ext.nll(state) + 2.0 * sum(effect(n).n_free for n in named)
        c_walk = ext.nll(walk) + 2.0 * walk_cost(ext, sw, k)
        note = {"walk_in_place_of": named, "axis": axis, "edf": edf,
                "criterion_named": c_named, "criterion_walk": c_walk,
                "accepted": bool(c_walk < c_named)}
        steps.append({"flexible_swap": note})
        if c_walk < c_named:
            state = walk
    return state


JOINT_NOISE = ("noise_level", "both")
"""The noise level of both axes tested at once (pooled χ², :mod:`calib.effects.noise`)."""


def joint_noise(state: ModelState, steps: list[dict] | tuple[dict, ...]) -> bool:
    """Whether the noise level of both axes was named at once (:data:`JOINT_NOISE`, the
    pooled test) and is in ``state``: then it is tested, kept and reported as a pair."""
    return [*JOINT_NOISE] in (s.get("added") for s in steps) and state.has(*JOINT_NOISE)


def _backward(ext: Extensions, state: ModelState, log_alpha: float, steps: list[dict]
              ) -> ModelState:
    """One backward pass: drop what the later additions made unnecessary. A noise level
    added on both axes at once is tested as it was added (the pooled test), the pair kept
    or dropped together: each axis alone is the weaker test it was added for want of."""
    joint_kept = False
    if joint_noise(state, steps):
        t = try_test(ext, state.without(*JOINT_NOISE), *JOINT_NOISE)
        joint_kept = t is None or t.logp < log_alpha
        if not joint_kept:
            state = ext.refine(state.without(*JOINT_NOISE))
            steps.append({"removed": [*JOINT_NOISE], "p_value": t.p_value})
    for name, axis in state.effects():
        if not effect(name).lr_tested or (joint_kept and name == JOINT_NOISE[0]):
            continue
        t = try_test(ext, state.without(name, axis), name, axis)
        if t is not None and t.logp >= log_alpha:
            state = ext.refine(state.without(name, axis))
            steps.append({"removed": [name, axis], "p_value": t.p_value})
    return state


def select(ext: Extensions, state: ModelState, candidates: list[tuple[str, str]],
           family_alpha: float) -> Selection:
    """Forward selection from ``state`` over ``candidates``, then one backward pass."""
    first, untestable = first_step(ext, state, candidates)
    candidates = [c for c in candidates if c not in untestable]
    n_tests = len(candidates) + LATTICE_TESTS
    alpha_step = family_alpha / n_tests
    log_alpha = float(np.log(alpha_step))
    steps: list[dict] = []
    memo: dict = {}
    if not state.tilt:
        for t in first:
            if t.axis in AXES:
                memo[(t.name, t.axis, state.axes[AXES.index(t.axis)])] = t
    state = _forward(ext, state, first, candidates, log_alpha, steps, memo)
    swapped = _flexible_swap(ext, state, candidates, log_alpha, steps)
    if swapped is not state:  # structured candidates again, on top of the walk
        trials = [t for t in (try_test(ext, swapped, n, a, memo)
                              for n, a in _remaining(swapped, candidates)) if t is not None]
        state = _forward(ext, swapped, trials, candidates, log_alpha, steps, memo)
    state = _backward(ext, state, log_alpha, steps)
    return Selection(state, candidates, untestable, n_tests, alpha_step, tuple(steps))

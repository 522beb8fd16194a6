"""Forward stepwise selection of the catalog effects, then one backward pass.

Selection criterion (stated once)
---------------------------------
Forward stepwise selection by likelihood-ratio tests with a Bonferroni-controlled family
error rate:

1. Step 0 — quantization: the readings of each axis are tested for a lattice
   (:func:`calib.diagnostics.detect_lattice`); a lattice is named (its lsb adds lsb²/12 to
   the noise variance of every later test).
2. Every step — every remaining candidate (per axis: misalignment, nonlinearity_k2,
   cross_axis, bias_drift, bias_random_walk, saturation, noise_level, and with timing
   lowpass_lag, lever_arm; both axes: tilt_offset) is fitted on top of the current model and
   tested by its likelihood ratio (reference distributions in :meth:`Extensions.test`). The
   candidate with the smallest p-value is added if ``p < α_step = family_alpha / m``, m the
   number of tests at the first step (testable candidates + 2 lattice tests); all nonlinear
   parameters are then re-fitted. Stop when no candidate passes. Under noise alone the run
   names nothing unless some first-step test passes, so ``P(false alarm) ≤ family_alpha``
   (Bonferroni; default 0.005, i.e. ≤ 0.5 % of clean runs).
3. One backward pass: an effect whose drop-one test no longer passes ``α_step`` is removed.

Noise level last. ``noise_level`` competes at every step, so a mere change of σ² is never
taken by a noise-like structured candidate (random walk, low-pass). It cannot take the place of
a real structured effect: an effect that explains ΔRSS gives ``LR = ΔRSS/σ²`` (log p ≈ -LR/2)
while the same ΔRSS as extra variance gives the χ² test ``log p ≈ -(n/2)(ρ - 1 - ln ρ)``,
``ρ = 1 + ΔRSS/(nσ²)``, always less extreme; so noise_level is in effect tested after the
structured effects, on the residuals of the extended model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calib.conventions import AXES
from calib.diagnostics import Lattice
from calib.effects import (
    NEEDS_TIMING,
    AxisState,
    Extensions,
    ModelState,
    RunData,
    Trial,
    effect,
)
from calib.ls import NotIdentifiableError

PER_AXIS_CANDIDATES: tuple[str, ...] = (
    "noise_level", "misalignment", "nonlinearity_k2", "cross_axis", "bias_drift",
    "bias_random_walk", "saturation", "lowpass_lag", "lever_arm")
"""Per-axis extensions tested at every step (``tilt_offset`` is tested for both axes)."""

MAX_STEPS = 10

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


def _try(ext: Extensions, state: ModelState, name: str, axis: str) -> Trial | None:
    try:
        return ext.test(state, name, axis)
    except NotIdentifiableError:
        return None


def _drop(state: ModelState, name: str, axis: str, stated: np.ndarray) -> ModelState:
    return state.without(name, axis, stated)


# --------------------------------------------------------------------------- steps

def initial_state(run: RunData, lattice: list[Lattice]) -> ModelState:
    """Step 0: the nominal model at the stated σ², with the lattice of each axis if found."""
    return ModelState(tuple(AxisState(sigma2=float(run.sigma2[k]),
                                      lsb=lattice[k].lsb if lattice[k].found else 0.0)
                            for k in range(2)))


def candidate_list(run: RunData) -> tuple[list[tuple[str, str]], tuple[str, ...]]:
    """(name, axis) candidates for this run (tilt offset third), and the skipped timed ones."""
    needs_timing = () if run.timed else NEEDS_TIMING
    candidates = [(n, a) for n in PER_AXIS_CANDIDATES if n not in needs_timing for a in AXES]
    candidates.insert(2, ("tilt_offset", "both"))
    return candidates, needs_timing


def _first_step(ext: Extensions, state: ModelState, candidates: list[tuple[str, str]]
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


def _forward(ext: Extensions, state: ModelState, trials: list[Trial],
             candidates: list[tuple[str, str]], log_alpha: float, steps: list[dict]
             ) -> ModelState:
    """Add the best candidate while its p-value passes; refit the nonlinear parameters."""
    for _ in range(MAX_STEPS):
        if not trials:
            break
        best = min(trials, key=lambda t: t.logp)
        steps.append({"added": [best.name, best.axis] if best.logp < log_alpha else None,
                      "candidates": [[t.name, t.axis, t.lr, t.p_value]
                                     for t in sorted(trials, key=lambda t: t.logp)]})
        if best.logp >= log_alpha:
            break
        state = ext.refine(best.state)
        trials = [t for t in (_try(ext, state, n, a) for n, a in _remaining(state, candidates))
                  if t is not None]
    return state


def _backward(ext: Extensions, state: ModelState, stated: np.ndarray, log_alpha: float,
              steps: list[dict]) -> ModelState:
    """One backward pass: drop what the later additions made unnecessary."""
    for name, axis in state.effects():
        if not effect(name).lr_tested:
            continue
        t = _try(ext, _drop(state, name, axis, stated), name, axis)
        if t is not None and t.logp >= log_alpha:
            state = ext.refine(_drop(state, name, axis, stated))
            steps.append({"removed": [name, axis], "p_value": t.p_value})
    return state


def select(ext: Extensions, state: ModelState, candidates: list[tuple[str, str]],
           family_alpha: float) -> Selection:
    """Forward selection from ``state`` over ``candidates``, then one backward pass."""
    first, untestable = _first_step(ext, state, candidates)
    candidates = [c for c in candidates if c not in untestable]
    n_tests = len(candidates) + LATTICE_TESTS
    alpha_step = family_alpha / n_tests
    log_alpha = float(np.log(alpha_step))
    steps: list[dict] = []
    state = _forward(ext, state, first, candidates, log_alpha, steps)
    state = _backward(ext, state, ext.run.sigma2, log_alpha, steps)
    return Selection(state, candidates, untestable, n_tests, alpha_step, tuple(steps))

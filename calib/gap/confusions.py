"""Confusions: named effects that another candidate explains as well (``not_identifiable``).

Known confusions: ``gravity_mismatch`` always (absorbed by the scale factors);
``tilt_offset`` vs equal ``misalignment`` of both sensors whenever either is named (identical
on one table; the 1-parameter tilt offset is preferred by the selection when the two δ
agree); ``lowpass_lag`` vs a tilt offset / misalignment and ``bias_drift`` vs
``bias_random_walk`` when the alternative explains the data within a likelihood ratio of 10
(``|Δ(-2 log L)| < 2 ln 10``, AIC-penalised when the parameter counts differ); candidates that
this θ design cannot test (collinear columns).
"""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES, EFFECTS
from calib.effects import CATALOG, Extensions, ModelState, effect
from calib.gap.selection import FLEXIBLE, try_test

AMBIGUITY_LR = 2.0 * float(np.log(10.0))
"""Two explanations whose ``-2 log L`` differ by less than this (likelihood ratio < 10) are
reported as not told apart."""

def design_hint(names: list[str]) -> str:
    """Where to compare experiments that would separate a confused pair (printed after the
    reason in the text report; the JSON ``reason`` is unchanged). A pair with a shape outside
    the catalog has no design to compare: a slow cycle (:func:`calib.gap.walk.slow_cycle`) is
    separated by a run several of its periods long; steps and two-level switching
    (:func:`calib.gap.walk.step_drift`, :func:`calib.gap.walk.switching_drift`) by a longer
    run, as their reason says."""
    if "slow_cycle" in names:
        return "not a catalog pair: a run several periods of the cycle long separates them"
    if not all(n in EFFECTS for n in names):
        return "not a catalog pair: no design of `tiltbench design` compares it"
    return f"compare designs with `tiltbench design --effects {','.join(names)}`"


REASONS: dict[str, str] = {e.name: e.confusion for e in CATALOG if e.confusion}
"""Effect → why it may not be told apart from another (``Effect.confusion``)."""


def assumptions(name: str) -> tuple[bool, bool, int]:
    """How much an explanation assumes, to break ties (smaller assumes less): whether it needs
    sample times, whether it is flexible (a random walk), its number of free parameters."""
    return (EFFECTS[name].timing == "yes", name in FLEXIBLE, effect(name).n_free)


def prefer_less_assuming(ext: Extensions, state: ModelState, candidates: list[tuple[str, str]],
                         steps: list[dict]) -> ModelState:
    """Ties: a named effect that another candidate explains within ``AMBIGUITY_LR`` (AIC
    penalised) is replaced by that candidate when it assumes less (:func:`assumptions`),
    e.g. a one-axis rotation instead of a low-pass lag on a constant-rate sweep. The pair is
    then reported by :func:`not_identifiable`. Each swap is recorded in ``steps``."""
    for name, axis in list(state.effects()):
        if name in ("quantization", "noise_level") or not state.has(name, axis):
            continue
        nll_final = ext.nll(state)
        base = state.without(name, axis)
        named = state.effects()
        alternatives = [(n, a) for n, a in candidates if (n, a) not in named and n != name
                        and n != "noise_level" and n not in FLEXIBLE and a == axis
                        and assumptions(n) < assumptions(name)]
        best = None
        for alt, alt_axis in sorted(alternatives, key=lambda c: assumptions(c[0])):
            t = try_test(ext, base, alt, alt_axis)
            if t is None:
                continue
            penalty = 2.0 * (effect(alt).n_free - effect(name).n_free)
            delta = ext.nll(t.state) + penalty - nll_final
            if delta < AMBIGUITY_LR and (best is None or delta < best[0]):
                best = (delta, alt, alt_axis, t.state)
        if best is not None:
            delta, alt, alt_axis, new = best
            state = ext.refine(new)
            steps.append({"tie": [name, axis], "named_instead": [alt, alt_axis],
                          "delta_m2logL": float(delta),
                          "rule": "within the ambiguity margin the explanation that assumes "
                                  "less is named (no timing, not flexible, fewer parameters)"})
    return state


def merge_tilt(ext: Extensions, state: ModelState, candidates: list[tuple[str, str]],
               steps: list[dict]) -> ModelState:
    """A tilt offset δ_t with a misalignment δ_a of one axis is the same rotation as a
    misalignment δ_t of the other axis when δ_a ≈ -δ_t: one parameter instead of two. When
    that simpler model fits within the ambiguity margin (AIC-penalised), it is named."""
    if not state.tilt:
        return state
    mis = [a for a in AXES if state.has("misalignment", a)]
    if len(mis) != 1:
        return state
    other = AXES[1 - AXES.index(mis[0])]
    if ("misalignment", other) not in candidates:
        return state
    base = state.without("tilt_offset", "both").without("misalignment", mis[0])
    t = try_test(ext, base, "misalignment", other)
    if t is None:
        return state
    delta = ext.nll(t.state) - 2.0 - ext.nll(state)  # one parameter fewer: AIC -2
    if delta < AMBIGUITY_LR:
        steps.append({"tie": ["tilt_offset + misalignment", mis[0]],
                      "named_instead": ["misalignment", other], "delta_m2logL": float(delta),
                      "rule": "one rotation of one sensor rather than a tilt offset and the "
                              "opposite rotation of the other"})
        return ext.refine(t.state)
    return state


def not_identifiable(ext: Extensions, state: ModelState, candidates: list[tuple[str, str]],
                     untestable: dict) -> list[dict]:
    """``not_identifiable`` entries (see the module docstring).

    Swap test: for each named effect, every other candidate is fitted *in its place*; when
    one explains the data within ``AMBIGUITY_LR`` of the final model (``-2 log L`` + 2 per
    extra parameter, AIC) the pair is reported: this experiment cannot tell them apart.
    """
    out: list[dict] = [{"names": ["gravity_mismatch"], "reason": REASONS["gravity_mismatch"]}]
    mis_axes = [a for k, a in enumerate(AXES) if state.axes[k].has("misalignment")]
    seen: set = set()
    if state.tilt or len(mis_axes) == 2:
        out.append({"names": ["tilt_offset", "misalignment"], "reason": REASONS["tilt_offset"]})
        seen.add(("misalignment", "tilt_offset"))  # already said, for every θ design
    nll_final = ext.nll(state)
    named = state.effects()

    def alt_nll(base: ModelState, adds: list[tuple[str, str]]) -> float:
        s = base
        for n, a in adds:
            t = try_test(ext, s, n, a)
            if t is None:
                return np.inf
            s = t.state
        return ext.nll(s)

    def report(pair: tuple[str, str], axis: str, delta: float) -> None:
        key = tuple(sorted(pair))
        if key in seen:
            return
        seen.add(key)
        known = next((REASONS[n] for n in ("bias_drift", "lowpass_lag") if n in pair), None)
        why = known or ("their signatures coincide in this θ design; a wider or denser set of "
                        "angles (a full turn) separates them")
        where = "both axes" if axis == "both" else f"axis {axis}"
        out.append({"names": sorted(pair),
                    "reason": f"{where}: {why} (fitting {pair[1]} in place of {pair[0]} "
                              f"changes -2 log L by {delta:.2f}, less than 2 ln 10)"})

    for name, axis in named:
        if name in ("quantization", "noise_level"):
            continue
        base = state.without(name, axis)
        alternatives = [(n, a) for n, a in candidates if (n, a) not in named and n != name
                        and n != "noise_level" and (a == axis or "both" in (a, axis))]
        for alt, alt_axis in alternatives:
            penalty = 2.0 * (effect(alt).n_free - effect(name).n_free)
            delta = alt_nll(base, [(alt, alt_axis)]) + penalty - nll_final
            if delta < AMBIGUITY_LR:
                report((name, alt), axis, delta)
        if name == "tilt_offset" and ext.run.timed and not any(
                n == "lowpass_lag" for n, _ in named):
            delta = alt_nll(base, [("lowpass_lag", a) for a in AXES]) + 2.0 - nll_final
            if delta < AMBIGUITY_LR:
                report(("tilt_offset", "lowpass_lag"), axis, delta)
    for (name, axis), why in untestable.items():
        out.append({"names": [name], "reason": f"axis {axis}: not testable in this experiment "
                                               f"({why})"})
    return out

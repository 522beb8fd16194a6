"""No sponge names on structured runs: a noise level or a walk beside saturation or quantization.

Saturation and quantization change the *distribution* of the reading, not only its mean: an
output that rails (clipped after its noise) reads exactly the limit, with no spread, and a
coarsely rounded reading has a variance that depends on where the mean falls between two
levels (Sheppard's lsb²/12 is then wrong). The selection's likelihood (Gaussian, constant σ²)
sees both as "less (or more) noise here" and names ``noise_level`` or ``bias_random_walk``
beside them — sponge names for what the structured effect does.

Rule (issue 20, item 4): on an axis where saturation or quantization is named, a noise level
or a walk stays named **only if it still wins after them**: the model without it is refitted,
the readings are standardised by the *exact* moments of the structured effect
(for an output that rails — readings repeated exactly at the smallest or largest value,
:func:`calib.gap.quantization.rails` — the readings away from the rails, whose mean is more
than 4σ inside them, by the stated noise; :func:`calib.gap.quantization.quantized_moments`
for a lattice), and its own test is made again on them at the selection's per-step α:

* ``noise_level``: ``Σz² ~ χ²(n - p)`` two-sided (named on both axes at once by the pooled
  test: the two axes' Σz² pooled, the pair kept or dropped together);
* ``bias_random_walk``: the walk's likelihood ratio on z (q profiled, the differenced local
  level of :mod:`calib.gap.walk`) against ``½χ²₀ + ½χ²₁``.

When it does not pass, it is dropped (the structured effect explains that part) and the
report says why (``adequacy["sponges"]``, one entry per decision, kept or dropped, with the
statistic).
"""

from __future__ import annotations

import numpy as np

from calib import distributions as stats
from calib.calibration.ls import NotIdentifiableError
from calib.conventions import AXES
from calib.effects import Extensions, ModelState
from calib.gap.estimates import Reporter
from calib.gap.quantization import quantized_moments, rails
from calib.gap.selection import JOINT_NOISE
from calib.gap.walk import gls_nll, walk_nll
from calib.stats.diagnostics import Lattice, chi2_two_sided_logp

SPONGES = ("noise_level", "bias_random_walk")
LN2 = float(np.log(2.0))


def standardized(rep: Reporter, k: int) -> tuple[np.ndarray, str, np.ndarray | None]:
    """Readings of axis k standardised by the exact moments of the structured effect of the
    model in ``rep`` (no noise level, no walk): (z, what was used, the indices of the
    readings kept, or None when all are)."""
    st = rep.state.axes[k]
    y = rep.run.datos[:, k]
    rail = rails(y) if np.isfinite(st.limit) else None
    if rail is not None:
        # readings at a rail carry no noise; next to it the reading is a truncated normal:
        # the samples whose mean is within 4σ of a rail are left out, the rest are Gaussian
        mu = rep.unclipped_mean(k)
        s = float(np.sqrt(st.sigma2_eff))
        keep = (mu > rail[0] + 4.0 * s) & (mu < rail[1] - 4.0 * s) & (y > rail[0]) & (y < rail[1])
        return ((y - mu) / s)[keep], (f"the stated noise on the {int(keep.sum())} readings "
                                      "away from the rails (the output clips after its noise)"
                                      ), np.flatnonzero(keep)
    if st.lsb > 0:
        m1, var = quantized_moments(rep.mean(k), st.sigma2, st.lsb)
        return ((y - m1) / np.sqrt(var),
                f"the exact moments of a reading rounded to {st.lsb:.4g}", None)
    mu = rep.mean(k)
    return (y - mu) / np.sqrt(st.sigma2_eff), "the stated noise", None


def _structured(st) -> list[str]:
    """The structured effects of an axis state that change the reading's distribution."""
    return [n for n, on in (("saturation", np.isfinite(st.limit)), ("quantization", st.lsb > 0))
            if on]


def _noise_sum(ext: Extensions, rep: Reporter, reduced: ModelState, k: int
               ) -> tuple[np.ndarray, str, np.ndarray | None, float, int]:
    """Axis k's readings standardised under ``reduced`` (:func:`standardized`: z, how, the
    readings kept) with ``Σz²`` and its degrees of freedom ``n − p`` (at least 1): the
    noise level's statistic, ``χ²(dof)`` under the model."""
    z, how, kept = standardized(rep, k)
    return z, how, kept, float(z @ z), max(z.size - ext.n_params(reduced, k), 1)


def _review_pair(ext: Extensions, state: ModelState, lattice: list[Lattice], log_alpha: float
                 ) -> tuple[ModelState, list[dict]]:
    """The noise level named on both axes at once (the pooled test,
    :func:`calib.gap.selection.joint_noise`) reviewed as it was named: both removed, the
    model refitted, each axis standardised (by its structured effect's moments, or by the
    stated noise on an axis without one) and the two ``Σz²`` pooled, ``χ²(dof_x + dof_y)``
    two-sided at the per-step α; kept or dropped together."""
    reduced = state.without(*JOINT_NOISE)
    beside = sorted({n for st in state.axes for n in _structured(st)})
    try:
        reduced = ext.refine(reduced)
        rep = Reporter(ext, reduced, lattice)
    except NotIdentifiableError as exc:
        return state, [{"name": "noise_level", "axis": a, "beside": beside, "named": True,
                        "statistic": None, "p_value": None,
                        "reason": (f"noise_level on both axes kept beside {' and '.join(beside)}"
                                   f": without it the model is not identifiable here ({exc})")}
                       for a in AXES]
    sums = [_noise_sum(ext, rep, reduced, k)[3:] for k in range(2)]
    stat, dof = sum(s for s, _ in sums), sum(d for _, d in sums)
    logp = chi2_two_sided_logp(stat, dof)
    wins = logp < log_alpha
    reason = (f"noise_level on both axes {'still wins' if wins else 'does not win'} after "
              f"{' and '.join(beside)}: on the readings of both axes standardised (by the "
              f"structured effects' exact moments, else the stated noise), pooled "
              f"Σz²/dof = {stat / dof:.4g} (χ²({dof}), two-sided), p = {np.exp(logp):.3g} "
              f"{'<' if wins else '≥'} the per-step α")
    notes = [{"name": "noise_level", "axis": a, "beside": beside, "named": bool(wins),
              "statistic": stat, "p_value": float(np.exp(logp)), "reason": reason} for a in AXES]
    return (state if wins else reduced), notes


def review_sponges(ext: Extensions, state: ModelState, lattice: list[Lattice],
                   log_alpha: float, joint: bool = False) -> tuple[ModelState, list[dict]]:
    """Apply the rule of the module docstring; returns the model and one note per decision.
    ``joint``: the noise level was named on both axes at once (the pooled test); beside a
    structured effect on either axis it is reviewed as a pair (:func:`_review_pair`)."""
    notes: list[dict] = []
    pair = joint and any(_structured(st) for st in state.axes)
    if pair:
        state, notes = _review_pair(ext, state, lattice, log_alpha)
    for k, axis in enumerate(AXES):
        st = state.axes[k]
        structured = _structured(st)
        sponges = [n for n in SPONGES if st.has(n) and not (pair and n == "noise_level")]
        if not structured or not sponges:
            continue
        reduced = state
        for n in sponges:
            reduced = reduced.without(n, axis)
        try:
            reduced = ext.refine(reduced)
            rep = Reporter(ext, reduced, lattice)
        except NotIdentifiableError as exc:
            # without them the structured effect cannot be fitted on this run: there is no
            # reading to review them on, so they stay as selected, and the report says why
            notes += [{"name": n, "axis": axis, "beside": structured, "named": True,
                       "statistic": None, "p_value": None,  # no test made: JSON null
                       "reason": (f"{n} on {axis} kept beside {' and '.join(structured)}: "
                                  f"without it the model is not identifiable here ({exc})")}
                      for n in sponges]
            continue
        z, how, kept, z2, dof = _noise_sum(ext, rep, reduced, k)
        keep = []
        for n in sponges:
            if n == "noise_level":
                stat = z2
                logp = chi2_two_sided_logp(stat, dof)
                what = f"Σz²/dof = {stat / dof:.4g} (χ²({dof}), two-sided)"
            else:
                dz = np.diff(z)
                a_ref = ext.run.a_ref[:, k]
                dt = np.asarray(ext.run.dt_walk, dtype=float)
                if kept is not None:  # readings left out: the walk steps over them
                    a_ref = a_ref[kept]
                    dt = np.diff(np.concatenate([[0.0], np.cumsum(dt)])[kept])
                base = np.diff(a_ref)[:, None]
                q0 = max(st.q / np.sqrt(st.sigma2_eff), 1e-6)
                lr = max(gls_nll(dz, base, 1.0, 0.0 * dt) - walk_nll(dz, base, 1.0, dt, q0),
                         0.0)
                stat = lr
                logp = float(-LN2 + stats.chi2.logsf(lr, 1)) if lr > 0 else 0.0
                what = f"LR = {lr:.4g} (½χ²₀ + ½χ²₁)"
            wins = logp < log_alpha
            notes.append({"name": n, "axis": axis, "beside": structured, "named": bool(wins),
                          "statistic": float(stat), "p_value": float(np.exp(logp)),
                          "reason": (f"{n} on {axis} {'still wins' if wins else 'does not win'}"
                                     f" after {' and '.join(structured)}: on the readings "
                                     f"standardised by {how}, {what}, p = {np.exp(logp):.3g} "
                                     f"{'<' if wins else '≥'} the per-step α")})
            if wins:
                keep.append(n)
        if len(keep) < len(sponges):
            new = state
            for n in sponges:
                if n not in keep:
                    new = new.without(n, axis)
            state = ext.refine(new)
    return state, notes

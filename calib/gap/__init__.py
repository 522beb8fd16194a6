"""Discrepancy workflow, estimation side: where the nominal model and the data disagree.

Given a measured calibration run (θ, readings, optional times) and the stated noise variances,
:func:`analyze_gap` measures the gap of the nominal model (bias + scale per axis), tests every
effect of ``docs/effects.md`` as an extension of the model (:mod:`calib.effects`), names the
missing effect(s) with their estimates ± std in the catalog's units, and measures the gap that
is left. The bench (:mod:`bench.gap`) re-simulates with the named effects and measures its own
"after" gap with the same yardstick, :func:`calib.stats.diagnostics.gap_measure`.

One job per module:

* :mod:`~calib.gap.results`     — ``EffectEstimate``, ``ExtendedModel``, ``GapAnalysis``.
* :mod:`~calib.gap.analysis`    — :func:`analyze_gap`, the workflow end to end.
* :mod:`~calib.gap.selection`   — the forward / backward stepwise selection (the criterion,
  stated once, is in its docstring).
* :mod:`~calib.gap.confusions`  — the ``not_identifiable`` entries (swap tests).
* :mod:`~calib.gap.estimates`   — the final fit and each effect's estimate ± std.
* :mod:`~calib.gap.random_walk` — the REML profile interval and curvature std of q.
* :mod:`~calib.gap.prediction`  — :func:`predict`, the mean reading of the extended model.
* :mod:`~calib.gap.quantization` — :func:`quantized_moments` of a rounded Gaussian reading.
* :mod:`~calib.gap.practical`   — when an effect may be named (a change of the fit of at least
  1 % of σ; below: reported, not named) and "never worse" (the gap after may not exceed the
  gap before beyond its spread under noise alone).
* :mod:`~calib.gap.drive_state` — the battery's checks conditioned on the drive: the residual
  while moving against while held (level, gain, variance, spectrum).
* :mod:`~calib.gap.steps`       — step-like bias changes (one step, a staircase, two-level
  switching) found and said in words.
* :mod:`~calib.gap.switching`   — faint two-level switching by the likelihood of a two-state
  hidden Markov level (its switches integrated out), set against the walk.

Effects that need timing are skipped without ``t`` or ``rate`` and listed in ``needs_timing``.
"""

from calib.conventions import EFFECT_NAMES
from calib.filters import lowpass
from calib.gap.analysis import analyze_gap
from calib.gap.confusions import AMBIGUITY_LR, REASONS
from calib.gap.prediction import predict
from calib.gap.quantization import quantized_moments
from calib.gap.random_walk import Q_LEVEL, q_curvature_std, q_profile_interval, q_uncertainty
from calib.gap.results import EffectEstimate, ExtendedModel, GapAnalysis
from calib.gap.selection import MAX_STEPS, PER_AXIS_CANDIDATES
from calib.stats.diagnostics import GapMeasure, gap_measure

__all__ = ["analyze_gap", "gap_measure", "predict", "GapAnalysis", "GapMeasure",
           "EffectEstimate", "ExtendedModel", "PER_AXIS_CANDIDATES", "EFFECT_NAMES",
           "lowpass", "quantized_moments", "AMBIGUITY_LR", "REASONS", "MAX_STEPS", "Q_LEVEL",
           "q_curvature_std", "q_profile_interval", "q_uncertainty"]

"""Model extensions of the discrepancy workflow: one per effect of ``docs/effects.md``.

The nominal model of axis a ∈ {x, y} (course; IEEE Std 1293 K0 = bias, K1 = 1 + scale) is
``A_m = bias + (1 + scale)·A_r + v``, v ~ N(0, σ²) white. Every effect of the catalog is an
*extension* of it with its own parameters, in the catalog's units and sign conventions
(``A_rx = -g sin θ``, ``A_ry = -g cos θ``; ``a_p`` = the other axis' reference; ω = dθ/dt,
α = d²θ/dt²)::

    A_m = bias + (1 + s)·[ LPF_τ(clip(A_r, ±L) + δ·sgn·A_p + lever) + k2·r² + k_ip·r·A_p ]
          + rate·(t - t0) + b_walk(t) + v,        then rounded to multiples of lsb

with ``r = LPF_τ(clip(A_r, ±L))``, sgn = +1 (x: ``-g sin(θ+δ) ≈ A_rx + δ A_ry``) or -1 (y:
``-g cos(θ+δ) ≈ A_ry - δ A_rx``), and the lever-arm projection derived from the table geometry
(hinge along +y, site at (pos_x, 0, pos_z) in the table frame, sensitive axis +x for the x
sensor and -z for the y sensor; acceleration of the site ``α ŷ×p - ω² p``)::

    x:  -ω²·pos_x + α·pos_z            y:  +ω²·pos_z + α·pos_x

Which parameter enters how (so each is estimated the right way):

================== ============================ ===============================================
effect              parameter (units)            extension
================== ============================ ===============================================
misalignment        δ (rad)                      column sgn·A_p; exact: ``δ = atan2(c, 1 + s')``
tilt_offset         δ (rad), both axes           one shared column ``sgn·(1 + ŝ_a)·A_p``: sin δ
nonlinearity_k2     k2 (1/(m/s²))                column r², ``k2 = c/(1 + s)``
cross_axis          k_ip (1/(m/s²))              column r·A_p, ``k_ip = c/(1 + s)``
bias_drift          rate (m/s² per s or sample)  column t - t0 (or index k), additive: rate = c
lever_arm           pos_x, pos_z (m)             columns ω², α; divided by (1 + s), signs above
lowpass_lag         τ (s)                        r = LPF_τ(A_r): 1-D profile likelihood in τ
saturation          limit L (m/s²)               r = clip(A_r, ±L): 1-D profile in L
bias_random_walk    q (m/s²/√s or /√sample)      exact Gaussian likelihood (see below), ML in q
noise_level         σ² ((m/s²)²)                 σ² free (profile), χ² interval
quantization        lsb (m/s²)                   lattice of the readings; adds lsb²/12 to σ²
gravity_mismatch    g (m/s²)                     none: absorbed by the scale factors
================== ============================ ===============================================

Likelihood (one code path for every model)
------------------------------------------
The readings are differenced, ``Δy_k = y_k - y_{k-1}``; this removes the bias (an exact
reparametrisation: it is the likelihood restricted with respect to the bias) and makes the
random-walk model banded: ``Δy = ΔH β + q√Δt_k w_k + v_k - v_{k-1}`` has the tridiagonal
covariance ``Σ_Δ = σ² T + q² diag(Δt)`` (T: 2 on the diagonal, -1 beside it). With its
factor ``Σ_Δ = L Lᵀ`` (tridiagonal, O(N)) the model is whitened, ``L⁻¹Δy ≈ L⁻¹ΔH β``, solved
by Householder QR (never a normal matrix), and ``-2 log L = RSS + log det Σ_Δ`` (+ a constant
common to all models). With q = 0 this is exactly ordinary least squares with an intercept
(the engine computes it so: centred columns, no solve); how each form is evaluated and
cached: :mod:`calib.effects.engine`. This is the exact Gaussian likelihood of
the local-level (random-walk bias) model that a Kalman filter with a diffuse initial level
computes (the filter itself gives the innovations and the smoothed bias in :mod:`calib.gap`),
at O(N) per evaluation without a Python loop. q is estimated by restricted ML (REML, see
:meth:`Extensions.nll`). Nested models are compared by the likelihood ratio
``LR = Δ(-2 log L)``.

The low-pass is the bench's own (:func:`calib.filters.lowpass`, one home for both sides):
exact for an input linear between samples,
``y_k = u_k - τc_k + e^{-h/τ}(y_{k-1} - u_{k-1} + τc_k)``, ``c_k = (u_k - u_{k-1})/h``,
starting at rest (``y_0 = u_0``); it acts on the signal (response stage) and the white noise
of the reading stays white.

Layout (one job per module; an effect is one small object, registered once)
---------------------------------------------------------------------------
* :mod:`~calib.effects.base`     — the contract: :class:`Effect`, :func:`register`, ``Trial``,
  the model states ``AxisState``, ``ModelState`` (the stated σ² lives there, checked once by
  :func:`stated_variances`), and the protocols the effects are typed against
  (``Likelihood``: the engine; ``FinalFit``: the final fit).
* :mod:`~calib.effects.linear`   — misalignment, nonlinearity_k2, cross_axis, bias_drift,
  lever_arm (design columns).
* :mod:`~calib.effects.tilt`     — tilt_offset (one column shared by both axes).
* :mod:`~calib.effects.response` — lowpass_lag, saturation (1-D profiles of r).
* :mod:`~calib.effects.noise`    — bias_random_walk, noise_level, quantization.
* :mod:`~calib.effects.gravity`  — gravity_mismatch (never in a model).
* :mod:`~calib.effects.catalog`  — the registry, complete and in catalog order.
* :mod:`~calib.effects.run`      — ``RunData`` (θ, readings, times; no statement of noise).
* :mod:`~calib.effects.engine`   — :class:`Extensions`, generic: it asks the effect objects.

Dependencies point one way (no circle, typing-only ones included): run ← base ← effect
modules ← catalog ← engine.

A new effect: add its row to ``calib.conventions.EFFECTS`` (name, keys, units, timing), write
one :class:`Effect` subclass decorated with ``@register`` in the module of its family (or a
new module imported by :mod:`~calib.effects.catalog`), and, if it needs a parameter the axis
state does not have yet, add that field to :class:`AxisState`.
"""

from calib.conventions import EFFECT_NAMES, NEEDS_TIMING, PER_SAMPLE_UNITS
from calib.effects.base import (
    REGISTRY,
    SIGN_P,
    AxisState,
    Effect,
    FinalFit,
    Likelihood,
    ModelState,
    Trial,
    UntestableError,
    effect,
    register,
    stated_variances,
)
from calib.effects.catalog import CATALOG, LINEAR_COLUMNS, PHYSICAL_COLUMNS
from calib.effects.engine import COND_MAX, Extensions
from calib.effects.run import RunData
from calib.filters import lowpass

__all__ = [
    "EFFECT_NAMES", "NEEDS_TIMING", "PER_SAMPLE_UNITS", "LINEAR_COLUMNS", "PHYSICAL_COLUMNS",
    "SIGN_P", "COND_MAX", "AxisState", "ModelState", "RunData", "Trial", "Extensions",
    "UntestableError", "lowpass", "Effect", "REGISTRY", "CATALOG", "register", "effect",
    "Likelihood", "FinalFit", "stated_variances",
]

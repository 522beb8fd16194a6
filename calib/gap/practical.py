"""Practical significance and "never worse": when an effect may be named, when an addition
may be presented as an explanation.

Practical significance (:data:`PRACTICAL_FRACTION`)
---------------------------------------------------
A test with enough samples finds effects too small to matter: a lattice of 0.001 σ in a log
of raw counts is certain (every reading sits on it) and changes nothing. An effect is
**named** as missing only when it changes the fit by at least ``PRACTICAL_FRACTION`` of the
noise σ; below that it is **reported, not named** ("quantized at q = 0.0006 m/s²
(0.0012 σ), no effect on the fit") and stays in the model (it costs nothing there, and the
numbers are those of the model that has it). The change of the fit, as a fraction of σ:

* an effect on the mean reading (misalignment, tilt offset, K2, cross-axis, drift, lever arm,
  low-pass, saturation) — the rms over the run of the change it makes to the fitted mean,
  the other parameters refitted: ``ρ = sqrt(LR / n)``, LR its drop-one likelihood ratio
  (σ known, so ``LR = ‖Δŷ‖²/σ²`` exactly for a column, to first order for τ and L) and n the
  samples it acts on (2N for the tilt offset, shared by both axes);
* ``quantization`` — the rounding's share of the noise std: ``ρ = sqrt(1 + lsb²/(12σ²)) − 1``
  (Sheppard: it adds lsb²/12 to the variance and nothing to the mean while lsb ≲ 2σ); named
  from lsb ≥ 0.49 σ;
* ``noise_level`` — the change of the noise std, ``ρ = |σ̂/σ_stated − 1|``;
* ``bias_random_walk`` — the rms of the smoothed walk about its mean, over σ.

Why 1 %: it changes χ²/dof of the fit by about ρ² = 1e-4 (a mean effect) or 2ρ = 0.02
(a noise effect) — below how well any stated σ² is known (a σ² estimated from 10⁴ samples is
uncertain by 1.4 %) — and no reading by a visible amount. A structured effect that passes the
selection's per-step test (LR ≳ 13) is always practical on runs shorter than
``13/ρ² ≈ 1.3·10⁵`` samples, so the rule binds on long runs and on the lattice, whose test is
of existence, not size. Not tuned on any data set: the independent set's quantization cases
(lsb = 1–2 σ) and noise levels (χ² excess 6–12 σ on 4001–7001 samples, ≥ 3 % of σ) are far
above it.

Never worse (:data:`NEVER_WORSE_Z`)
-----------------------------------
Adding the named effects must not make the gap worse: per axis with an effect named,
``χ²/dof after − χ²/dof before > NEVER_WORSE_Z·sqrt(2/dof)`` (the spread of χ²/dof under
noise alone) or ``max|z| after − max|z| before > NEVER_WORSE_Z`` (a z's spread is 1) means the
addition does not explain the gap, and the verdict says so ("unexplained" with a
``gap_worse`` signature). Why 3: under a correct model both gaps share the noise, so the
after one is at most as large as the before one up to far less than one spread (it has more
parameters); three spreads is beyond any chance rise (P ≈ 1e-3 even for independent gaps).
"""

from __future__ import annotations

import numpy as np
from scipy import linalg as sla

from calib.stats.diagnostics import GapMeasure

PRACTICAL_FRACTION = 0.01
"""An effect is named only when it changes the fit by at least this fraction of σ (module
docstring: the measure per kind of effect, and why 1 %)."""

NEVER_WORSE_Z = 3.0
"""Spreads (under noise alone) by which the gap after may not exceed the gap before where
effects were added (module docstring)."""


def quantization_change(lsb: float, sigma2: float) -> float:
    """``sqrt(1 + lsb²/(12σ²)) − 1``: the rounding's share of the noise std."""
    if not lsb > 0:
        return 0.0
    return float(np.sqrt(1.0 + lsb * lsb / (12.0 * sigma2)) - 1.0)


def lattice_matters(lsb: float, sigma2: float) -> bool:
    """Whether a lattice of step ``lsb`` (m/s²) changes the fit of noise σ² ((m/s²)²) by at
    least :data:`PRACTICAL_FRACTION` (then ``quantization`` may be named)."""
    return quantization_change(lsb, sigma2) >= PRACTICAL_FRACTION


def mean_change(lr: float, n: int) -> float:
    """``sqrt(LR / n)``: the rms change of the fitted mean over σ of an effect whose
    drop-one likelihood ratio is LR on n samples."""
    if not np.isfinite(lr):
        return float("inf")
    return float(np.sqrt(max(lr, 0.0) / max(n, 1)))


def noise_change(sigma2_fitted: float, sigma2_stated: float) -> float:
    """``|σ̂/σ_stated − 1|``."""
    return float(abs(np.sqrt(sigma2_fitted / sigma2_stated) - 1.0))


def walk_change(e: np.ndarray, sigma2: float, q: float, dt: np.ndarray) -> float:
    """rms of the smoothed walk about its mean, over σ.

    ``e`` (N,) the readings minus the model's mean without the bias (m/s²), a local level
    ``e_k = b_k + v_k``: the smoothed path is ``b̂ = e − σ²·Dᵀ Σ_Δ⁻¹ Δe``, ``Σ_Δ = σ²T +
    diag(q²Δt)`` (D the difference operator, T tridiagonal 2, −1)."""
    e = np.asarray(e, dtype=float)
    if e.size < 3 or not q > 0:
        return 0.0
    r = q * q * np.asarray(dt, dtype=float)
    ab = np.empty((2, r.size))
    ab[0, 0] = 0.0
    ab[0, 1:] = -sigma2
    ab[1] = 2.0 * sigma2 + r
    x = sla.solveh_banded(ab, np.diff(e))
    v = np.zeros(e.size)
    v[:-1] -= x
    v[1:] += x
    b = e - sigma2 * v
    return float(np.std(b) / np.sqrt(sigma2))


def below_words(name: str, axis: str, change: float, params: dict, sigma: float) -> str:
    """The report line of an effect seen but not named (module docstring)."""
    if name == "quantization":
        lsb = float(params.get("lsb", 0.0))
        return (f"quantized at q = {lsb:.4g} m/s² ({lsb / sigma:.2g} σ) on {axis}, no effect "
                f"on the fit (the rounding adds {100 * change:.2g} % to the noise std; "
                f"named from {100 * PRACTICAL_FRACTION:g} %)")
    vals = ", ".join(f"{k} = {float(v):.4g}" for k, v in params.items())
    return (f"{name} on {axis} ({vals}) is significant but changes the fit by only "
            f"{change:.2g} σ rms, below {PRACTICAL_FRACTION:g} σ: no effect on the fit, not "
            "named")


def gap_worse(before: GapMeasure, after: GapMeasure, chi2_after: float | None = None
              ) -> list[str]:
    """Why the gap after is worse than the gap before beyond their spread under noise alone
    (:data:`NEVER_WORSE_Z`); empty when it is not. ``chi2_after``: χ²/dof after against the
    stated noise, when it differs from ``after.chi2_dof``."""
    out = []
    c_b = float(before.chi2_dof)
    c_a = float(after.chi2_dof if chi2_after is None else chi2_after)
    dof = max(int(after.dof or before.dof or 1), 1)
    spread = float(np.sqrt(2.0 / dof))
    if c_a - c_b > NEVER_WORSE_Z * spread:
        out.append(f"χ²/dof rose from {c_b:.4g} to {c_a:.4g}, more than {NEVER_WORSE_Z:g} "
                   f"times its spread under noise alone (√(2/dof) = {spread:.2g})")
    z_b, z_a = float(before.max_signature_z), float(after.max_signature_z)
    if z_a - z_b > NEVER_WORSE_Z:
        out.append(f"the largest signature |z| rose from {z_b:.3g} ({before.worst}) to "
                   f"{z_a:.3g} ({after.worst}), more than {NEVER_WORSE_Z:g} (a z's spread "
                   "under noise alone is 1)")
    return out


def worse_signature(axis: str, names: list[str], problems: list[str], size: float) -> dict:
    """The ``unexplained`` entry of an addition that made the gap worse."""
    return {"axis": axis, "signature": "gap_worse", "size": float(size), "unit": "1",
            "statistic": float(size), "p_value": None,
            "description": f"adding {', '.join(names)} makes the gap on {axis} worse, not "
                           f"better: {'; '.join(problems)} — the addition is not an "
                           "explanation"}

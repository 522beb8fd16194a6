"""Radians or degrees? Told from the readings, never from a range of θ.

Any finite θ in radians is a valid table angle: a run over several turns (0 → 4π), negative
angles, oscillations about 0…2π, an encoder that overshoots 2π (6.2841 rad). A range rule
(|θ| ≤ 2π) refuses those and still lets a degree file of 0 → 5° through. Where the readings
come with the angles (an ensayo: ``tita`` and ``datos``), this module asks instead which
reading of θ the nominal course model fits.

Rule
----
Per axis k ∈ {x, y} the nominal model (course; IEEE Std 1293 K0 = bias, K1 = 1 + scale)::

    datos_k = bias_k + (1 + scale_k) · A_rk(φ),     A_rx = -g sin φ,  A_ry = -g cos φ

is fitted by plain least squares (``numpy.linalg.lstsq`` on ``[1, A_rk - mean(A_rk)]``, no
normal equations) twice: with φ = θ (radians) and with φ = θ·π/180 (degrees), g =
:data:`calib.conventions.G`. ``RSS_k`` is the residual sum of squares, (m/s²)². θ is taken for
degrees — and the reader refuses it — when all three hold:

1. **decidable**: at least :data:`MIN_DISTINCT` = 3 distinct θ values. With one or two poses
   both readings fit the pose means exactly (two parameters per axis): nothing to tell apart.
2. **the degree fit is good on its own terms**: on both axes the degree fit's scale factor is
   a plausible sensor, ``|scale_k| < 0.5`` (:data:`SCALE_LIMIT`), allowing 3 standard errors
   where the axis barely determines it (``|scale_k| - 3 se_k < 0.5``; ``se_k = σ̂_k /
   ‖A_rk - mean A_rk‖``, ``σ̂_k² = RSS_k/(N - 2)``: the QR standard error of the slope).
3. **the degree fit explains the data far better**, by either measure:

   * magnitude: ``RSS_rad ≥ 10 · RSS_deg`` (:data:`RSS_FACTOR`, RSS summed over both axes);
   * evidence: the Gaussian log-likelihood ratio (per-axis variance unknown, the same two
     parameters per axis on both sides, so it equals half the AIC/BIC difference)
     ``Λ = (N/2) · Σ_k ln(RSS_rad,k / RSS_deg,k) ≥ 20`` (:data:`LOG_LR_MIN`: the degree
     reading e²⁰ ≈ 5·10⁸ times more likely).

   The ratio alone misses long, noisy, small-range degree runs: a 0 → 30° sweep at the course
   noise (σ² = 0.25, 0.64) leaves the radian fit only ≈ 3× worse (RSS ratio ≈ 3.3) although
   with N = 2000 samples Λ ≈ 2400 leaves no doubt. Λ alone is weak for a handful of samples
   (0°, 90°, 180°, 270° once each, course noise: ratio ≈ 70 but Λ ≈ 19).

Why this cannot refuse a radian run: the radian fit of radian data is at the noise level, so
no other reading of θ explains the data better (condition 3 fails); and a degree reading of
radian data needs an absurd scale factor (≈ 56 for θ within 0.5 rad, ≈ -1 — explains
nothing — over many turns), so condition 2 fails as well. Ambiguous data are accepted as
radians: a single pose, two poses, a tiny θ range (both readings are then the same straight
line / parabola in θ and fit equally well), readings unrelated to θ. RSS values are floored
at ``N·(10⁻⁹ g)²`` so that noiseless files compare by the model, not by rounding.

Power at the course noise (random start angle, evenly spaced samples, 200 runs each): a
degree file spanning 30° is refused from N ≈ 30 samples, 10° from N ≈ 100–1000, 90° or more
from N ≈ 4–10; one spanning 5° or less with a few hundred samples reads as radians. In 40 000
random radian runs (offsets ±50 rad, spans 10⁻³–200 rad, N = 3–200, sweeps, random and held
positions, noise 10⁻³–3× the course σ) none was refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from calib.conventions import AXES, G

MIN_DISTINCT = 3
"""Fewest distinct θ values with which the two readings can be told apart."""

SCALE_LIMIT = 0.5
"""|scale| of a plausible sensor (dimensionless): the degree fit must stay below it."""

SCALE_SE = 3.0
"""Standard errors of the degree fit's scale allowed beyond :data:`SCALE_LIMIT`."""

RSS_FACTOR = 10.0
"""The degree reading is far better when the radian RSS is at least this many times larger."""

LOG_LR_MIN = 20.0
"""… or when its log-likelihood ratio over the radian reading is at least this (nats)."""

RSS_FLOOR = 1e-9 * G
"""Per-sample residual floor, m/s² (RSS ≥ N·RSS_FLOOR²): rounding is not evidence."""


@dataclass(frozen=True)
class AngleUnits:
    """Both readings of θ fitted to the nominal model; the verdict of the rule (module doc).

    Attributes
    ----------
    n : samples.  distinct : distinct θ values.
    rss_rad, rss_deg : per axis (x, y), residual sum of squares, (m/s²)², of the fit with θ
        as given (radians) and with θ·π/180 (degrees).
    scale_rad, scale_deg : per axis, fitted scale factor (dimensionless; NaN where the
        reading leaves the axis' reference constant).
    scale_deg_se : per axis, standard error of ``scale_deg`` (inf where undetermined).
    """

    n: int
    distinct: int
    rss_rad: tuple[float, float]
    rss_deg: tuple[float, float]
    scale_rad: tuple[float, float]
    scale_deg: tuple[float, float]
    scale_deg_se: tuple[float, float]

    @property
    def rss_rad_total(self) -> float:
        """RSS of the radian reading, both axes, (m/s²)²."""
        return float(sum(self.rss_rad))

    @property
    def rss_deg_total(self) -> float:
        """RSS of the degree reading, both axes, (m/s²)²."""
        return float(sum(self.rss_deg))

    def _floored(self, rss: float) -> float:
        return max(rss, self.n * RSS_FLOOR**2)

    @property
    def rss_ratio(self) -> float:
        """``RSS_rad / RSS_deg`` over both axes (> 1: the degree reading fits better)."""
        return (self._floored(self.rss_rad_total)
                / self._floored(self.rss_deg_total))

    @property
    def log_lr(self) -> float:
        """``Λ = (N/2) Σ_k ln(RSS_rad,k / RSS_deg,k)``, nats (> 0: degrees more likely)."""
        return 0.5 * self.n * sum(
            math.log(self._floored(r) / self._floored(d))
            for r, d in zip(self.rss_rad, self.rss_deg, strict=True))

    @property
    def decidable(self) -> bool:
        """Condition 1: enough distinct θ to tell the readings apart."""
        return self.distinct >= MIN_DISTINCT

    @property
    def degree_fit_plausible(self) -> bool:
        """Condition 2: the degree fit's scale factors are those of a plausible sensor."""
        return all(np.isfinite(s) and abs(s) - SCALE_SE * se < SCALE_LIMIT
                   for s, se in zip(self.scale_deg, self.scale_deg_se, strict=True))

    @property
    def degree_fit_far_better(self) -> bool:
        """Condition 3: RSS ratio ≥ :data:`RSS_FACTOR` or Λ ≥ :data:`LOG_LR_MIN`."""
        return self.rss_ratio >= RSS_FACTOR or self.log_lr >= LOG_LR_MIN

    @property
    def looks_like_degrees(self) -> bool:
        """All three conditions of the rule (module docstring)."""
        return self.decidable and self.degree_fit_plausible and self.degree_fit_far_better

    def summary(self) -> str:
        """One line: both RSS (m/s²)², the degree fit's scale factors, Λ."""
        scales = ", ".join(f"scale_{a} = {s:+.3g}" for a, s in zip(AXES, self.scale_deg,
                                                                    strict=True))
        return (f"residual sum of squares over both axes {self.rss_rad_total:.4g} (m/s²)² "
                f"reading θ as radians vs {self.rss_deg_total:.4g} (m/s²)² reading θ·π/180 "
                f"(ratio {self.rss_ratio:.3g}, log-likelihood ratio {self.log_lr:.3g}; "
                f"degree fit {scales})")


def _fit_axis(ref: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """``y = bias + (1 + scale)·ref`` by lstsq; return (RSS (m/s²)², scale, se(scale)).

    The reference is centred (``[1, ref - mean]``: orthogonal columns, the same fit), so
    ``R[1, 1]`` of its QR is ``‖ref - mean‖`` and the slope's standard error is
    ``σ̂/‖ref - mean‖`` without forming any inverse.
    """
    n = y.shape[0]
    centred = ref - ref.mean()
    norm = float(np.linalg.norm(centred))
    if norm <= 1e-12 * G * math.sqrt(n):  # the reading leaves this axis' reference constant
        r = y - y.mean()
        return float(r @ r), math.nan, math.inf
    H = np.column_stack([np.ones(n), centred])
    p, *_ = np.linalg.lstsq(H, y, rcond=None)
    r = y - H @ p
    rss = float(r @ r)
    se = math.sqrt(rss / (n - 2)) / norm if n > 2 else math.inf
    return rss, float(p[1]) - 1.0, se


def compare_angle_units(tita: np.ndarray, datos: np.ndarray, g: float = G) -> AngleUnits:
    """Fit the nominal model with θ read as radians and as degrees (module docstring).

    Parameters
    ----------
    tita : (N,) table angle, finite, as stored (rad if the file is right).
    datos : (N, 2) readings [A_mx, A_my], m/s², finite.
    g : gravity, m/s² (the readers use :data:`calib.conventions.G`; the scale factor absorbs a
        slightly different local g).

    Returns
    -------
    AngleUnits : both fits and the verdict ``looks_like_degrees``.

    Examples
    --------
    >>> import numpy as np
    >>> th = np.linspace(0.0, 360.0, 361)                  # degrees, by mistake
    >>> datos = np.column_stack([-9.8 * np.sin(np.deg2rad(th)), -9.8 * np.cos(np.deg2rad(th))])
    >>> compare_angle_units(th, datos).looks_like_degrees
    True
    >>> compare_angle_units(np.deg2rad(th) + 4 * np.pi, datos).looks_like_degrees  # 2 turns on
    False
    """
    tita = np.asarray(tita, dtype=float).ravel()
    datos = np.asarray(datos, dtype=float)
    fits = {}
    for unit, phi in (("rad", tita), ("deg", tita * (np.pi / 180.0))):
        ref = np.column_stack([-g * np.sin(phi), -g * np.cos(phi)])
        fits[unit] = [_fit_axis(ref[:, k], datos[:, k]) for k in range(2)]
    return AngleUnits(
        n=int(tita.shape[0]), distinct=int(np.unique(tita).size),
        rss_rad=tuple(f[0] for f in fits["rad"]), rss_deg=tuple(f[0] for f in fits["deg"]),
        scale_rad=tuple(f[1] for f in fits["rad"]), scale_deg=tuple(f[1] for f in fits["deg"]),
        scale_deg_se=tuple(f[2] for f in fits["deg"]))

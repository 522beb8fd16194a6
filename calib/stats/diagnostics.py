"""Residual diagnostics: the yardstick of the discrepancy workflow ("gap").

Every structured signature of a residual series is expressed as a **z-score** whose
distribution under noise alone is N(0, 1) or narrower (a *conservative* z), so one threshold
serves them all. Tests that give a p-value (χ², Ljung-Box, lattice, flat tops) are converted to
the two-sided-equivalent z, ``|z| = Φ⁻¹(1 - p/2)``.

Signatures (residual r, m/s², of one axis; θ the encoder angle, rad; t the time, s)
---------------------------------------------------------------------------------
``chi2``       χ² = Σ r²/σ² against χ²(dof): the noise level (signed: + when too large).
``h1_cos``     marginal regression of r on cos θ (centred): x axis misalignment / tilt
               offset (δ·A_ry = -δ g cos θ).
``h1_sin``     on sin θ: y axis misalignment (-δ·A_rx = δ g sin θ).
``h2_cos``     on cos 2θ: IEEE K2 (``A_rx² = g²(1 - cos 2θ)/2``, ``A_ry² = g²(1 + cos 2θ)/2``).
``h2_sin``     on sin 2θ: cross-axis coupling (``A_rx·A_ry = g² sin 2θ / 2``).
``other_ref``  on the other axis' reference A_p (misalignment, when given).
``trend``      on t - t0 (or the sample index): bias drift.
``whiteness``  Ljung-Box Q over h = min(20, N/10) lags, Q ~ χ²(h): random walk, lags.
``lattice``    the *readings* lie on a lattice {k·lsb}: quantization (needs the readings).
``flat_top``   one-sided score for a clipped reference near the extremes of |A_r|
               (saturation; Davies' bound for a parameter present only under the alternative).
``rate_cos``, ``rate_sin``  on ω cos θ, ω sin θ (ω = dθ/dt): a lag τ gives -τ·dA_r/dt.
``rate_sq``, ``accel``      on ω², α = d²θ/dt²: lever arm (centripetal, tangential).

Marginal regression z's use the residual as if it were white with variance σ²; a residual of
a least-squares fit has covariance σ²(I - P) ≤ σ² I, so those z's are conservative.

The gap of one axis is ``GapMeasure(chi2_dof, max_signature_z)``. ``max_signature_z`` is the
largest |z| among the m signatures computed; its own p-value is Bonferroni-corrected,
``p_max = min(1, m · 2Φ(-max|z|))``, which is a valid p-value under noise alone whatever the
dependence between signatures: ``P(p_max ≤ α) ≤ α``. The threshold at family level α is
``z_α = Φ⁻¹(1 - α/(2m))``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import log_ndtr, ndtri_exp

from calib import distributions as stats
from calib.numerics import equilibrated_cond

LN2 = float(np.log(2.0))
LOGP_FLOOR = -1.0e4
"""log p-values are floored here (z ≈ 141) so every z stays finite and JSON-friendly."""

LATTICE_TOL = 1e-6
"""A reading is on the lattice when it is within this fraction of an lsb of a lattice point."""

LATTICE_MIN_REL = 1e-9
"""Smallest lsb searched, relative to max |reading| (coarser than float64 rounding by ~10⁶)."""


# --------------------------------------------------------------------------- p ↔ z helpers

def z_from_logp(logp: float) -> float:
    """Two-sided-equivalent z of a p-value given as log p: ``Φ⁻¹(1 - p/2)`` (≥ 0)."""
    logp = max(float(logp), LOGP_FLOOR)
    if logp >= 0.0:
        return 0.0
    return float(-ndtri_exp(logp - LN2))


def logp_from_z(z: float) -> float:
    """log of the two-sided p-value of a standard normal z: ``log(2Φ(-|z|))``."""
    return float(min(0.0, LN2 + log_ndtr(-abs(float(z)))))


def chi2_two_sided_logp(chi2: float, dof: int) -> float:
    """log of the two-sided p-value of χ² against χ²(dof): ``log(2 min(F, 1 - F))``."""
    lo = stats.chi2.logcdf(chi2, dof)
    hi = stats.chi2.logsf(chi2, dof)
    return float(min(0.0, LN2 + min(lo, hi)))


def chi2_signed_z(chi2: float, dof: int) -> float:
    """Signed z of χ² against χ²(dof) (two-sided; + when χ² is too large)."""
    z = z_from_logp(chi2_two_sided_logp(chi2, dof))
    return z if chi2 >= dof else -z


# ----------------------------------------------------------------------------- lattice test

@dataclass(frozen=True)
class Lattice:
    """Result of the lattice (quantization) test on one axis' readings.

    found : the readings lie on ``{o + k·lsb}`` within :data:`LATTICE_TOL`·lsb.
    lsb, lsb_std : m/s² (least-squares fit of the distinct values on their lattice indices;
        the std is the rounding-level scatter, tiny for an exact lattice).
    levels : number of distinct readings.  logp : log p-value of that many distinct values
        falling on one lattice if the readings were continuous (``(levels - 2)·log(2·tol)``).
    """

    found: bool
    lsb: float = float("nan")
    lsb_std: float = float("nan")
    levels: int = 0
    logp: float = 0.0

    @property
    def z(self) -> float:
        return z_from_logp(self.logp) if self.found else 0.0


def _fgcd(a: float, b: float, tol: float) -> float:
    """Greatest common divisor of two positive reals, to tolerance ``tol`` (Euclid)."""
    a, b = abs(a), abs(b)
    while b > tol:
        r = abs(a - b * np.round(a / b))
        a, b = b, r
    return a


def detect_lattice(values: np.ndarray) -> Lattice:
    """Test whether readings are quantized: all on a lattice ``o + k·lsb``.

    Parameters
    ----------
    values : (N,) readings of one axis, m/s².

    Notes
    -----
    The distinct values ``u`` (sorted) have gaps that are integer multiples of the lsb; their
    real GCD (Euclid with tolerance ``1e3·eps·max|u|``) is the lsb candidate, then *every*
    distinct value must lie within ``LATTICE_TOL·lsb`` of the lattice. A continuous reading
    passes that check with probability ≈ ``(2·LATTICE_TOL)^(levels - 2)`` (0 in practice).
    The lsb must exceed ``LATTICE_MIN_REL·max|u|`` (float64 rounding is not a quantization).
    Repeated θ (held positions) do not matter: the test looks at readings, and noise makes
    continuous readings distinct.
    """
    u = np.unique(np.asarray(values, dtype=float))
    if u.size < 3:
        return Lattice(False, levels=int(u.size))
    scale = float(np.max(np.abs(u)))
    if scale == 0.0:
        return Lattice(False, levels=int(u.size))
    tol = 1e3 * np.finfo(float).eps * scale
    lsb_min = LATTICE_MIN_REL * scale
    d = np.diff(u)
    # The smallest gaps carry the lsb; a spread of larger ones checks the rest of the range.
    order = np.argsort(d)
    picks = np.concatenate([order[:64], order[:: max(1, order.size // 64)]])
    g = float(d[picks[0]])
    for di in d[picks[1:]]:
        g = _fgcd(g, float(di), tol)
        if g < lsb_min:
            return Lattice(False, levels=int(u.size))
    k = np.round((u - u[0]) / g)
    off = (u - u[0]) - k * g
    if np.max(np.abs(off)) > LATTICE_TOL * g + 8 * tol:
        return Lattice(False, levels=int(u.size))
    kc = k - k.mean()
    lsb = float(kc @ (u - u.mean()) / (kc @ kc))
    res = (u - u.mean()) - lsb * kc
    dof = max(u.size - 2, 1)
    s = float(np.sqrt(res @ res / dof))
    std = max(s / float(np.sqrt(kc @ kc)), np.finfo(float).eps * abs(lsb))
    logp = max((u.size - 2) * np.log(2 * LATTICE_TOL), LOGP_FLOOR)
    return Lattice(True, lsb, std, int(u.size), float(logp))


# ----------------------------------------------------------------------- flat tops (clip)

def hinge_levels(a_ref: np.ndarray, count: int = 28, max_fraction: float = 0.6) -> np.ndarray:
    """Candidate saturation limits L (m/s²) for a reference ``a_ref``: descending order.

    Chosen so that 2, 3, … up to ``max_fraction·N`` samples have ``|a_ref| > L`` (log-spaced
    counts), L half-way between consecutive distinct |a_ref| values.
    """
    s = np.sort(np.abs(np.asarray(a_ref, dtype=float)))[::-1]
    n = s.size
    if n < 3:
        return np.zeros(0)
    # Boundaries between distinct values of |a_ref| (held positions repeat them), with the
    # number of samples beyond each: clipping at a level between s[c-1] and s[c] clips c.
    tol = 1e-9 * max(float(s[0]), 1e-300)
    c_all = np.flatnonzero(s[:-1] - s[1:] > tol) + 1
    c_all = c_all[(c_all >= 1) & (c_all <= max_fraction * n)]
    if c_all.size == 0:
        return np.zeros(0)
    targets = np.geomspace(max(2, c_all[0]), max(c_all[-1], 2), count)
    idx = np.unique(np.clip(np.searchsorted(c_all, targets), 0, c_all.size - 1))
    c = c_all[idx]
    levels = 0.5 * (s[c - 1] + s[c])
    return np.unique(levels[levels > 0])[::-1]


def hinge_columns(a_ref: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """(N, G) columns ``clip(a_ref, ±L) - a_ref`` for each L: the change a limit L makes."""
    a = np.asarray(a_ref, dtype=float)[:, None]
    lv = np.asarray(levels, dtype=float)[None, :]
    h = np.clip(a, -lv, lv)
    h -= a  # in place: one (N, G) array, not two (a long run's G columns are MBs)
    return h


def davies_logp(z: np.ndarray) -> tuple[float, float, float]:
    """One-sided sup test of a standard-normal process over a grid (Davies 1987).

    Parameters
    ----------
    z : (G,) the score process Z(L) on an ordered grid (N(0, 1) at each L under H0).

    Returns
    -------
    (M, V, log p) : ``M = max Z``, ``V = Σ|Z_{j+1} - Z_j|`` (total variation), and the bound
    ``p ≤ Φ(-M) + V·exp(-M²/2)/√(8π)`` — the parameter (the limit) exists only under the
    alternative, so the χ²(1) reference of a regular likelihood-ratio test does not apply.
    """
    z = np.asarray(z, dtype=float)
    if z.size == 0:
        return 0.0, 0.0, 0.0
    m = float(np.max(z))
    v = float(np.sum(np.abs(np.diff(z))))
    terms = [float(log_ndtr(-m))]
    if v > 0:
        terms.append(np.log(v) - 0.5 * m * m - 0.5 * np.log(8 * np.pi))
    return m, v, float(min(0.0, np.logaddexp.reduce(terms)))


@dataclass(frozen=True)
class Hinges:
    """The hinge columns ``(clip(a, ±L) - a) / scale`` (N, G) of a reference ``a`` (N,) for the
    levels ``levels`` (G,), never formed: column L is ``(sgn(a_i)·L - a_i)/scale`` on the
    samples with ``|a_i| > L`` and zero elsewhere, so its products with a vector are sums
    over those samples only — with the samples in descending ``|a|``, the first ``n_L`` of
    them (Σ n_L ≈ 2N for :func:`hinge_levels`' log-spaced counts, against N·G for the
    columns: ≈ 28 at N = 60001). Equal to the formed columns' products to rounding
    (``tests/test_flat_top.py``)."""

    a: np.ndarray
    levels: np.ndarray
    scale: float = 1.0

    def _sorted(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Order of the samples by descending |a|, |a| and sgn(a) in that order."""
        a = np.asarray(self.a, dtype=float)
        order = np.argsort(-np.abs(a), kind="stable")
        return order, np.abs(a)[order], np.sign(a)[order]

    def column(self, j: int) -> np.ndarray:
        """Column j, formed (N,)."""
        return hinge_columns(self.a, np.asarray(self.levels)[j:j + 1])[:, 0] / self.scale

    def products(self, vectors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(‖h_L‖², Vᵀh_L)`` for every level: (G,) and (m, G), of the columns with the
        vectors ``V`` (N, m): ``Σ_{|a|>L} (|a| - L)²/scale²`` and
        ``-Σ_{|a|>L} V·sgn(a)·(|a| - L)/scale``."""
        order, mag, sgn = self._sorted()
        w = np.asarray(vectors, dtype=float).reshape(mag.size, -1)[order] * sgn[:, None]
        levels = np.asarray(self.levels, dtype=float)
        counts = np.searchsorted(-mag, -levels, side="left")  # samples with |a| > L
        raw2 = np.empty(levels.size)
        prods = np.empty((w.shape[1], levels.size))
        for g, (n, lv) in enumerate(zip(counts, levels, strict=True)):
            d = mag[:n] - lv
            raw2[g] = d @ d
            prods[:, g] = -(d @ w[:n])
        return raw2 / self.scale**2, prods / self.scale


def flat_top_score(resid_w: np.ndarray, design_w: np.ndarray | None,
                   hinges_w: np.ndarray | Hinges) -> tuple[float, float]:
    """Score process of a clipped reference on whitened quantities; returns (M, log p).

    Parameters
    ----------
    resid_w : (n,) whitened residual of the current model (unit variance under H0).
    design_w : (n, p) whitened design of the current model (or None): hinge columns are
        projected out of the space it spans (the residual is orthogonal to it). The design may
        be rank-deficient (a tilt offset and the misalignment of the same axis have
        proportional columns on that axis): then the basis of that space is taken from the SVD
        of the equilibrated design with lstsq's rank cut-off (``eps·max(n, p)·s_max``), not
        from a QR whose extra column would be a rounding-error direction.
    hinges_w : (n, G) whitened hinge columns ``clip(A_r, ±L) - A_r`` for the grid of L, or
        the same columns unformed (:class:`Hinges`: a reference not filtered).

    Notes
    -----
    ``Z(L) = ⟨r, h̃_L⟩ / ‖h̃_L‖`` with ``h̃_L`` the hinge column with the design projected out;
    one-sided (a limit pulls the reading towards zero, coefficient 1 + scale > 0). Columns that
    the design already spans (‖h̃‖ < 1e-8 ‖h‖: e.g. two levels of |A_r| only) are skipped.
    """
    resid_w = np.asarray(resid_w, dtype=float)
    q = None
    if design_w is not None and design_w.size:
        q, r = np.linalg.qr(design_w)
        if equilibrated_cond(r) * max(q.shape) * np.finfo(float).eps >= 1.0:
            q = _range_basis(np.asarray(design_w, dtype=float))
    if isinstance(hinges_w, Hinges):
        vectors = resid_w[:, None] if q is None else np.column_stack([resid_w, q])
        raw2, prods = hinges_w.products(vectors)
        num, c = prods[0], prods[1:]
        column = hinges_w.column
    else:
        h = np.asarray(hinges_w, dtype=float)
        raw2 = np.einsum("ij,ij->j", h, h)  # ‖h_L‖², no (n, G) temporary
        num = resid_w @ h
        c = None if q is None else q.T @ h

        def column(j: int) -> np.ndarray:
            return h[:, j]
    norm2 = raw2.copy()
    if q is not None:
        # h̃ = h − Q(Qᵀh) is never formed (a long run's (n, G) copies cost more than the
        # products): ⟨r, h̃⟩ = ⟨r, h⟩ − (Qᵀr)·(Qᵀh) and ‖h̃‖² = ‖h‖² − ‖Qᵀh‖² (Q orthonormal).
        # Where the design spans most of a column the difference loses digits (relative
        # error eps·‖h‖²/‖h̃‖²): those columns are projected out exactly.
        num -= (q.T @ resid_w) @ c
        norm2 -= np.einsum("ij,ij->j", c, c)
        for j in np.flatnonzero(norm2 < 1e-6 * raw2):
            col = column(j) - q @ c[:, j]
            norm2[j] = col @ col
            num[j] = resid_w @ col
    norms = np.sqrt(np.maximum(norm2, 0.0))
    ok = norms > 1e-8 * np.maximum(np.sqrt(raw2), 1e-300)
    if not np.any(ok):
        return 0.0, 0.0
    z = num[ok] / norms[ok]
    m, _, logp = davies_logp(z)
    return m, logp


def _range_basis(d: np.ndarray) -> np.ndarray:
    """Orthonormal basis of the column space of ``d`` (n, p) at lstsq's numerical rank."""
    d = d.reshape(d.shape[0], -1)
    dn = np.linalg.norm(d, axis=0)
    u, sv, _ = np.linalg.svd(d[:, dn > 0] / dn[dn > 0], full_matrices=False)
    if not sv.size:
        return u[:, :0]
    return u[:, sv > sv[0] * max(d.shape) * np.finfo(float).eps]


# ------------------------------------------------------------------------------ whiteness

def ljung_box_logp(r: np.ndarray, lags: int | None = None) -> tuple[float, int, float]:
    """Ljung-Box whiteness test of a series in time order.

    ``Q = n(n+2) Σ_{k=1..h} ρ_k² / (n - k)`` ~ χ²(h) under white noise, ``h = min(20, n/10)``.
    Returns (Q, h, log p) with the upper-tail p-value.
    """
    r = np.asarray(r, dtype=float)
    n = r.size
    h = int(lags if lags is not None else min(20, max(1, n // 10)))
    x = r - r.mean()
    den = float(x @ x)
    if n < 4 or den == 0.0:
        return 0.0, h, 0.0
    rho = np.array([x[k:] @ x[:-k] for k in range(1, h + 1)]) / den
    q = float(n * (n + 2) * np.sum(rho**2 / (n - np.arange(1, h + 1))))
    return q, h, float(stats.chi2.logsf(q, h))


# ------------------------------------------------------------------------ angular rates

def angular_rates(tita: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ω = dθ/dt (rad/s) and α = d²θ/dt² (rad/s²) from the encoder angle, by differences.

    θ is unwrapped first; second-order central differences (``numpy.gradient``, edge order 2)
    on the sample times, which may be non-uniform.
    """
    th = np.unwrap(np.asarray(tita, dtype=float))
    t = np.asarray(t, dtype=float)
    if th.size < 3:
        z = np.zeros_like(th)
        return z, z
    omega = np.gradient(th, t, edge_order=2)
    alpha = np.gradient(omega, t, edge_order=2)
    return omega, alpha


# ---------------------------------------------------------------------------- GapMeasure

@dataclass(frozen=True)
class GapMeasure:
    """The gap of one axis: how far a residual series is from noise alone.

    Attributes
    ----------
    chi2_dof : Σ r²/σ² / dof with the stated (or model) noise variance; ≈ 1 for noise alone.
    max_signature_z : the largest |z| among the structured signatures (module docstring).
    dof : degrees of freedom of χ² (N minus the fitted parameters).
    max_signature_p : Bonferroni-corrected p-value of ``max_signature_z`` over the
        ``n_signatures`` signatures computed (valid under noise alone).
    worst : name of the signature giving ``max_signature_z``.
    signatures : ((name, z), …) every signature computed, signed where a sign means something.
    """

    chi2_dof: float
    max_signature_z: float
    dof: int = 0
    max_signature_p: float = 1.0
    worst: str = ""
    signatures: tuple[tuple[str, float], ...] = ()

    @property
    def n_signatures(self) -> int:
        return len(self.signatures)

    def signature(self, name: str) -> float:
        """z of one signature (KeyError if it was not computed)."""
        return dict(self.signatures)[name]

    def threshold_z(self, alpha: float = 0.005) -> float:
        """``z_α = Φ⁻¹(1 - α/(2m))``: ``max_signature_z`` exceeds it with probability ≤ α
        under noise alone (m = number of signatures)."""
        m = max(self.n_signatures, 1)
        return float(stats.norm.isf(alpha / (2 * m)))

    def chi2_band(self, alpha: float = 0.005) -> tuple[float, float]:
        """Two-sided (1 - α) band of χ²/dof under noise alone: χ²(dof) quantiles / dof."""
        lo, hi = stats.chi2.ppf([alpha / 2, 1 - alpha / 2], self.dof)
        return float(lo / self.dof), float(hi / self.dof)

    def consistent(self, alpha: float = 0.005) -> bool:
        """True when χ²/dof is inside its band and ``max_signature_z`` below its threshold."""
        lo, hi = self.chi2_band(alpha)
        return bool(lo <= self.chi2_dof <= hi and self.max_signature_z <= self.threshold_z(alpha))

    def to_dict(self) -> dict:
        """The documented JSON part: ``{"chi2_dof", "max_signature_z"}``."""
        return {"chi2_dof": float(self.chi2_dof), "max_signature_z": float(self.max_signature_z)}

    def details(self) -> dict:
        """Everything, for reports: dof, corrected p, worst signature and all z's."""
        return {**self.to_dict(), "dof": self.dof, "max_signature_p": self.max_signature_p,
                "worst": self.worst, "signatures": dict(self.signatures)}


def _marginal_z(r: np.ndarray, col: np.ndarray, sigma: float) -> float | None:
    """z of the slope of r on one centred column, with known σ (None if the column is flat)."""
    c = np.asarray(col, dtype=float)
    if np.ptp(c) <= 1e-9 * max(1.0, float(np.max(np.abs(c)))):
        return None  # constant over the run (or rounding noise): no signature to look for
    c = c - c.mean()
    nc = float(np.linalg.norm(c))
    return float((r @ c) / (sigma * nc))


def gap_measure(
    residuals_axis: np.ndarray,
    tita: np.ndarray,
    sigma2: float,
    t: np.ndarray | None = None,
    other_ref: np.ndarray | None = None,
    *,
    own_ref: np.ndarray | None = None,
    readings: np.ndarray | None = None,
    model_lsb: float | None = None,
    n_params: int = 0,
    time_index: bool = True,
) -> GapMeasure:
    """Measure the gap of one axis: χ²/dof and the largest structured-signature z.

    Parameters
    ----------
    residuals_axis : (N,) data - model of one axis, m/s², samples in time order.
    tita : (N,) encoder angle, rad.
    sigma2 : noise variance the residuals should have, (m/s²)² (stated, or the model's).
    t : (N,) sample times, s, or None (then the trend is against the sample index and the
        ω/α signatures are skipped).
    other_ref : (N,) the other axis' reference acceleration A_p, m/s² (optional).
    own_ref : (N,) this axis' reference A_r, m/s² (optional; enables ``flat_top``).
    readings : (N,) this axis' raw readings, m/s² (optional; enables ``lattice``: quantization
        shows in the values, not in the residuals).
    model_lsb : lsb of a quantization the compared model already has (m/s²): a lattice of
        that lsb is then explained (``lattice`` z = 0).
    n_params : number of parameters fitted to make the residuals (dof = N - n_params).
    time_index : with ``t`` None, still test a trend against the sample index (samples in
        time order).

    Returns
    -------
    GapMeasure
    """
    r = np.asarray(residuals_axis, dtype=float)
    tita = np.asarray(tita, dtype=float)
    n = r.size
    if tita.shape != r.shape:
        raise ValueError(f"residuals {r.shape} and tita {tita.shape} must have the same shape")
    if not (np.isfinite(sigma2) and sigma2 > 0):
        raise ValueError(f"sigma2 must be positive, got {sigma2}")
    sigma = float(np.sqrt(sigma2))
    dof = max(n - int(n_params), 1)
    chi2 = float(r @ r / sigma2)

    sig: list[tuple[str, float]] = [("chi2", chi2_signed_z(chi2, dof))]
    sig += _column_signatures(r, tita, sigma, t, other_ref, time_index)
    _, _, lb_logp = ljung_box_logp(r)
    sig.append(("whiteness", z_from_logp(lb_logp)))
    if readings is not None:
        sig.append(("lattice", _lattice_z(readings, model_lsb)))
    if own_ref is not None:
        z = _flat_top_z(r, np.asarray(own_ref, dtype=float), sigma)
        if z is not None:
            sig.append(("flat_top", z))

    worst, z_max, logp_max = _largest(sig)
    return GapMeasure(chi2_dof=chi2 / dof, max_signature_z=z_max, dof=dof,
                      max_signature_p=float(np.exp(logp_max)), worst=worst,
                      signatures=tuple((k, float(v)) for k, v in sig))


def _signature_columns(tita: np.ndarray, t: np.ndarray | None, other_ref: np.ndarray | None,
                       time_index: bool) -> dict[str, np.ndarray]:
    """The structured signatures that are columns: harmonics of θ (1st, 2nd), the other
    axis' reference, a trend (in t, or in the sample index), and with times ω·cos θ, ω·sin θ,
    ω², α."""
    n = tita.size
    cols = {"h1_cos": np.cos(tita), "h1_sin": np.sin(tita),
            "h2_cos": np.cos(2 * tita), "h2_sin": np.sin(2 * tita)}
    if other_ref is not None:
        cols["other_ref"] = np.asarray(other_ref, dtype=float)
    if t is not None:
        cols["trend"] = np.asarray(t, dtype=float) - float(t[0])
    elif time_index:
        cols["trend"] = np.arange(n, dtype=float)
    if t is not None and n >= 3:
        omega, alpha = angular_rates(tita, t)
        cols.update({"rate_cos": omega * np.cos(tita), "rate_sin": omega * np.sin(tita),
                     "rate_sq": omega**2, "accel": alpha})
    return cols


def _column_signatures(r: np.ndarray, tita: np.ndarray, sigma: float, t: np.ndarray | None,
                       other_ref: np.ndarray | None, time_index: bool
                       ) -> list[tuple[str, float]]:
    """(name, z) of the marginal regression of the centred residuals on each column."""
    rc = r - r.mean()
    out = []
    for name, col in _signature_columns(tita, t, other_ref, time_index).items():
        z = _marginal_z(rc, col, sigma)
        if z is not None:
            out.append((name, z))
    return out


def _lattice_z(readings: np.ndarray, model_lsb: float | None) -> float:
    """z of a lattice in the raw readings; 0 when the model's lsb explains it (the lattice
    step is an integer multiple of ``model_lsb``)."""
    lat = detect_lattice(readings)
    explained = (lat.found and model_lsb is not None and model_lsb > 0
                 and abs(lat.lsb / model_lsb - np.round(lat.lsb / model_lsb)) < 1e-6
                 and np.round(lat.lsb / model_lsb) >= 1)
    return 0.0 if explained else lat.z


def _flat_top_z(r: np.ndarray, a: np.ndarray, sigma: float) -> float | None:
    """z of the flat-top (clipping) score test against ``[1, A_r]``, or None when |A_r| has
    no range to clip."""
    levels = hinge_levels(a)
    if not levels.size:
        return None
    n = r.size
    design = np.column_stack([np.ones(n), a]) / sigma
    _, logp = flat_top_score(r / sigma, design, Hinges(a, levels, sigma))
    return z_from_logp(logp)


def _largest(sig: list[tuple[str, float]]) -> tuple[str, float, float]:
    """(name, |z|, log p) of the largest |z|; log p Bonferroni-corrected over the m
    signatures, ``min(0, log m + log p(|z|))``."""
    zs = np.array([abs(z) for _, z in sig])
    i = int(np.argmax(zs))
    logp_max = min(0.0, np.log(len(sig)) + logp_from_z(zs[i]))
    return sig[i][0], float(zs[i]), logp_max

__all__ = [
    "GapMeasure", "Hinges", "Lattice", "gap_measure", "detect_lattice", "hinge_levels",
    "hinge_columns",
    "davies_logp", "flat_top_score", "ljung_box_logp", "angular_rates", "z_from_logp",
    "logp_from_z", "chi2_two_sided_logp", "chi2_signed_z",
]

"""Where the adequacy checks test added columns, and what each check returns.

:class:`AxisSpace`: the whitened system of one axis of the final model (differenced and
whitened with the model's noise σ², lsb, q; unit variance under the model); an added column
block is whitened the same way and projected off the model's columns, and the regression of
the residual on it gives ``ΔRSS ~ χ²(rank)`` under the model (GLS). :class:`Check`: one check
on one axis. The column families used by more than one module: a Fourier peak
(:func:`spectral_peak`, Fisher's g), Legendre polynomials in time, the direction of motion.
Used by the battery (:mod:`calib.gap.adequacy`), the walk review (:mod:`calib.gap.walk`) and
the mechanisms (:mod:`calib.gap.mechanisms`).
"""

from __future__ import annotations

from collections.abc import Callable
from copy import copy
from dataclasses import dataclass
from math import comb

import numpy as np
from scipy import linalg as sla

from calib.effects import SIGN_P, Extensions, ModelState

COLLINEAR_TOL = 1e-6
"""A test column whose part outside the model is below this fraction of its norm is dropped."""


@dataclass(frozen=True)
class Check:
    """One adequacy check on one axis.

    name, axis : the check and the axis ("x", "y").  statistic : its value (χ², g, |z|, …).
    logp : log p-value under the model.
    reference : the reference distribution.
    size, unit : how big the departure is, in the units of the readings.
    description : words a test engineer can act on ("a 3rd harmonic of θ on x, 0.04 m/s²").
    failed : whether the check failed (set by :func:`calib.gap.adequacy.run_battery`).
    """

    name: str
    axis: str
    statistic: float
    logp: float
    reference: str
    size: float
    unit: str
    description: str
    failed: bool = False

    @property
    def p_value(self) -> float:
        return float(np.exp(self.logp))

    def to_dict(self) -> dict:
        return {"name": self.name, "axis": self.axis, "statistic": float(self.statistic),
                "p_value": self.p_value, "reference": self.reference,
                "passed": not self.failed, "size": float(self.size), "unit": self.unit,
                "description": self.description}

    def signature(self) -> dict:
        """The ``unexplained`` entry of a failed check."""
        return {"axis": self.axis, "signature": self.name, "size": float(self.size),
                "unit": self.unit, "statistic": float(self.statistic),
                "p_value": self.p_value, "description": self.description}



class AxisSpace:
    """The whitened system of one axis of the final model, to test added columns.

    ``yw, H`` from :meth:`Extensions.axis_system` (differenced and whitened with the model's
    noise: σ², lsb, q; unit variance under the model), ``rw`` the residual of the model's
    columns. An added column block Z is whitened the same way and projected off H; the
    regression of ``rw`` on it gives ``ΔRSS ~ χ²(rank)`` under the model.
    """

    def __init__(self, ext: Extensions, state: ModelState, k: int) -> None:
        st = state.axes[k]
        self._parts, _ = ext.axis_parts(k, st, state.tilt)
        self.qh, self.rw = _project(ext.whiten(st, self._parts))
        self.ext, self.st = ext, st
        self._cheap: tuple[np.ndarray, np.ndarray] | None = None

    def _scan_system(self) -> tuple[np.ndarray, np.ndarray]:
        """(model basis, residual) in the image the grid scans use, that of
        :meth:`Extensions.white`: with q = 0, L⁻¹Δ is an isometry of centring and dividing by σ
        (the same inner products without the banded solve and the differencing), made on the
        first scan; otherwise the whitened rows themselves."""
        if self.st.q > 0:
            return self.qh, self.rw
        if self._cheap is None:
            self._cheap = _project(self.ext.white(self.st, self._parts))
        return self._cheap

    def without(self, z: np.ndarray) -> AxisSpace:
        """A copy whose residual has the columns of z projected out as well (to look for
        what is left once z is in the model)."""
        z = np.asarray(z, dtype=float).reshape(z.shape[0], -1)
        out = copy(self)
        out.rw = _residual_without(self.qh, self.rw, self.ext.whiten(self.st, z))
        if self.st.q == 0:
            q, r = self._scan_system()
            out._cheap = (q, _residual_without(q, r, self.ext.white(self.st, z)))
        return out

    def step_scan(self) -> np.ndarray | None:
        """ΔRSS of one step of the level, the column ``[k ≥ i]``, at every place i = 1 … N − 1
        (entry i − 1), from sums in the centred image of :meth:`_scan_system` (q = 0): with
        ``S(i)`` the sums from sample i to the end,

            ΔRSS(i) = S_r(i)² / ((N − i)·i/N − ‖S_Q(i)‖²)

        (the step's centred squared norm less its part in the model, whose basis Q and
        residual r are centred: what :meth:`test` gives one place at a time, in O(N·p) for all
        of them). A place whose column lies in the model's span, to :data:`COLLINEAR_TOL` of
        its norm, gets 0. None with a walk (q > 0)."""
        if self.st.q > 0:
            return None
        qh, rw = self._scan_system()
        n = rw.size
        tail_r = np.cumsum(rw[::-1])[::-1][1:]
        tail_q = np.cumsum(qh[::-1], axis=0)[::-1][1:]
        i = np.arange(1, n, dtype=float)
        norm2 = (n - i) * i / n
        den = norm2 - np.einsum("ij,ij->i", tail_q, tail_q)
        out = np.zeros(n - 1)
        ok = den > COLLINEAR_TOL**2 * norm2
        out[ok] = tail_r[ok] ** 2 / den[ok]
        return out

    def scan(self, make, grid) -> np.ndarray:
        """ΔRSS of each column block ``make(g)`` (N, c) of a grid, batched: the blocks are
        whitened together (with q = 0 in the centred image, :meth:`_scan_system`) and each
        projected off the model, each block's QR written from its Gram matrix
        (:func:`_blocks_drss`). A column whose part outside the model and the block's
        earlier columns is below :data:`COLLINEAR_TOL` of its whitened norm is not counted
        (so a block of rank < c gives the ΔRSS of its independent part). Equal to
        :meth:`test` block by block (``tests/test_gap_space.py``); use :meth:`test` on the
        best for its rank and coefficients."""
        grid = list(grid)
        out = np.zeros(len(grid))
        if not grid:
            return out
        qh, rw = self._scan_system()
        chunk = max(1, int(3e6 // (rw.size * 4)))
        for a in range(0, len(grid), chunk):
            part = grid[a:a + chunk]
            first = np.asarray(make(part[0]), dtype=float)
            first = first.reshape(first.shape[0], -1)
            n, c = first.shape
            z = np.empty((n, c * len(part)), order="F")
            z[:, :c] = first
            for j, g in enumerate(part[1:], start=1):
                z[:, j * c:(j + 1) * c] = np.asarray(make(g), dtype=float).reshape(n, c)
            if self.st.q == 0:
                # the centred image without the 1/σ: ΔRSS and the collinearity test are
                # invariant to a common scale of the columns (one pass, no copies)
                z -= z.mean(axis=0)
                zw = z
            else:
                zw = self.ext.white(self.st, z)
            out[a:a + len(part)] = _blocks_drss(zw, qh, rw, c)
        return out

    @staticmethod
    def scan_many(spaces: list[AxisSpace], make, grid) -> list[np.ndarray]:
        """:meth:`scan` of one grid on several spaces of the same run (the two axes): each
        chunk of columns is built once and, where q = 0, centred once (the same numbers as
        one :meth:`scan` per space)."""
        grid = list(grid)
        outs = [np.zeros(len(grid)) for _ in spaces]
        if not grid or not spaces:
            return outs
        systems = [sp._scan_system() for sp in spaces]
        chunk = max(1, int(3e6 // (systems[0][1].size * 4)))
        for a in range(0, len(grid), chunk):
            part = grid[a:a + chunk]
            first = np.asarray(make(part[0]), dtype=float)
            first = first.reshape(first.shape[0], -1)
            n, c = first.shape
            z = np.empty((n, c * len(part)), order="F")
            z[:, :c] = first
            for j, g in enumerate(part[1:], start=1):
                z[:, j * c:(j + 1) * c] = np.asarray(make(g), dtype=float).reshape(n, c)
            centred = None
            for sp, (qh, rw), out in zip(spaces, systems, outs, strict=True):
                if sp.st.q == 0:
                    if centred is None:
                        centred = z - z.mean(axis=0)
                    zw = centred
                else:
                    zw = sp.ext.white(sp.st, z)
                out[a:a + len(part)] = _blocks_drss(zw, qh, rw, c)
        return outs

    def test_each(self, z: np.ndarray) -> tuple[tuple[float, int] | None, np.ndarray,
                                                 np.ndarray]:
        """The columns of z together — (ΔRSS, rank) as :meth:`test` gives them, or None —
        and each column alone: ΔRSS (k,) and coefficient (k,) in its own units, 0 for a
        column in the model's span. Each alone is unique where the joint coefficients of
        columns collinear with the model are not (their split is rounding's choice).

        From inner products only, in the image the scans use (:meth:`_scan_system`; cheap
        with q = 0): ``A = qhᵀ zw``, ``G = zwᵀ zw − AᵀA`` (the projected columns' Gram),
        ``b = zwᵀ rw``; alone ``ΔRSS_j = b_j²/G_jj``, ``coef_j = b_j/G_jj``; together the
        R factor of G column by column (:func:`_gram_drss`: the rule of
        :func:`_blocks_drss`, a column below :data:`COLLINEAR_TOL` of its norm not
        counted)."""
        z = np.asarray(z, dtype=float).reshape(z.shape[0], -1)
        qh, rw = self._scan_system()
        zw = self.ext.white(self.st, z)
        a = qh.T @ zw
        nw = np.einsum("ij,ij->j", zw, zw)
        g = zw.T @ zw - a.T @ a
        b = zw.T @ rw
        d = np.diag(g)
        keep = d > COLLINEAR_TOL**2 * nw
        alone = np.where(keep, b / np.where(keep, d, 1.0), 0.0)
        drss, rank = _gram_drss(g, b, nw)
        return (None if rank == 0 else (drss, rank)), np.where(keep, b * alone, 0.0), alone

    def test(self, z: np.ndarray) -> tuple[float, int, np.ndarray] | None:
        """(ΔRSS, rank, coefficients of the columns of z in their own units) or None.

        The projected columns ``zp`` (those outside the model, to :data:`COLLINEAR_TOL`) by a
        column-pivoted QR, ``zp P = Q R``, its rank where ``|R_jj|`` falls below
        COLLINEAR_TOL of ``|R_11|``; with ``c = Qᵀ rw`` (Householder reflections applied to
        ``rw``, Q never formed: ``scipy.linalg.qr_multiply``) ``ΔRSS = ‖c_{:rank}‖²`` and the
        coefficients of the first ``rank`` pivoted columns ``R_{:rank,:rank}⁻¹ c_{:rank}`` —
        their least-squares solution (the same to rounding as ``lstsq`` on those columns; at
        N = 60001 and 18 columns 12 ms against 45 ms with Q formed and a second
        factorisation)."""
        z = np.asarray(z, dtype=float).reshape(z.shape[0], -1)
        zw = self.ext.whiten(self.st, z)
        zp = zw - self.qh @ (self.qh.T @ zw)
        norms = np.linalg.norm(zw, axis=0)
        keep = np.linalg.norm(zp, axis=0) > COLLINEAR_TOL * np.maximum(norms, 1e-300)
        if not np.any(keep):
            return None
        c, r, piv = sla.qr_multiply(zp[:, keep], self.rw, mode="right", pivoting=True)
        d = np.abs(np.diag(r))
        rank = int(np.sum(d > COLLINEAR_TOL * d[0])) if d.size else 0
        if rank == 0:
            return None
        proj = c[:rank]
        cols = np.flatnonzero(keep)[piv[:rank]]
        coef = np.zeros(z.shape[1])
        coef[cols] = sla.solve_triangular(r[:rank, :rank], proj)
        return float(proj @ proj), rank, coef


def _blocks_drss(zw: np.ndarray, qh: np.ndarray, rw: np.ndarray, c: int) -> np.ndarray:
    """ΔRSS of the blocks of ``c`` whitened columns ``zw`` (N, J·c) for the residual rw
    (orthogonal to the model's basis qh), from inner products only.

    With ``A = qhᵀ zw`` the projected columns ``zp = zw − qh A`` have the Gram matrix
    ``G = zwᵀ zw − Aᵀ A`` and ``zpᵀ rw = zwᵀ rw = b``. Each block's R factor is built from G
    column by column (Cholesky, vectorised over the blocks): ``R_lj = (G_lj − Σ_{m<l} R_ml
    R_mj)/R_ll``, ``R_jj² = G_jj − Σ_{l<j} R_lj²``; then ``x = R⁻ᵀ b`` by forward
    substitution and ``ΔRSS = ‖x‖²`` — what the QR of the projected block gives, without
    forming it. A column whose ``R_jj`` is below :data:`COLLINEAR_TOL` of its whitened norm
    (it lies in the model and the block's earlier columns) is not counted, as in
    :meth:`AxisSpace.test` (the subtractions lose ~1e-15 of ‖zw‖², far below the 1e-12 kept).
    """
    a = qh.T @ zw
    b = (zw.T @ rw).reshape(-1, c)
    nw = np.einsum("ng,ng->g", zw, zw).reshape(-1, c)
    tol2 = COLLINEAR_TOL ** 2 * nw

    def gram(i: int, j: int) -> np.ndarray:
        return (np.einsum("ng,ng->g", zw[:, i::c], zw[:, j::c])
                - np.einsum("pg,pg->g", a[:, i::c], a[:, j::c]))

    r = np.zeros((c, c, b.shape[0]))  # r[l, j]: R_lj of every block
    ok = np.zeros((c, b.shape[0]), dtype=bool)
    x = np.zeros((c, b.shape[0]))
    for j in range(c):
        for m in range(j):
            r[m, j] = np.where(ok[m], (gram(m, j) - np.sum(r[:m, m] * r[:m, j], axis=0))
                               / np.where(ok[m], r[m, m], 1.0), 0.0)
        d2 = (nw[:, j] - np.einsum("pg,pg->g", a[:, j::c], a[:, j::c])
              - np.sum(r[:j, j] ** 2, axis=0))
        ok[j] = d2 > tol2[:, j]
        r[j, j] = np.sqrt(np.where(ok[j], d2, 1.0))
        x[j] = np.where(ok[j], (b[:, j] - np.sum(r[:j, j] * x[:j], axis=0)) / r[j, j], 0.0)
    return np.sum(x * x, axis=0)


def _gram_drss(g: np.ndarray, b: np.ndarray, nw: np.ndarray) -> tuple[float, int]:
    """ΔRSS and rank of columns with projected Gram matrix g (k, k), inner products with the
    residual b (k,) and whitened squared norms nw (k,): the R factor of g column by column,
    a column whose ``R_jj² ≤ COLLINEAR_TOL²·nw_j`` not counted: the rule of
    :func:`_blocks_drss` for one wide block whose Gram matrix is one matrix product (the
    scans' blocks are many and narrow, each Gram entry a vectorised sum over them; for one
    block of 36 columns at N = 60001 this is 11 ms against 270 ms)."""
    k = b.size
    r = np.zeros((k, k))
    x = np.zeros(k)
    ok = np.zeros(k, dtype=bool)
    for j in range(k):
        for m in np.flatnonzero(ok[:j]):
            r[m, j] = (g[m, j] - r[:m, m] @ r[:m, j]) / r[m, m]
        d2 = g[j, j] - r[:j, j] @ r[:j, j]
        if d2 > COLLINEAR_TOL**2 * nw[j]:
            ok[j] = True
            r[j, j] = np.sqrt(d2)
            x[j] = (b[j] - r[:j, j] @ x[:j]) / r[j, j]
    return float(x @ x), int(ok.sum())


def _project(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(orthonormal basis of the model columns ``w[:, 1:]``, residual of ``w[:, 0]`` off it)."""
    q, _ = np.linalg.qr(w[:, 1:])
    return q, w[:, 0] - q @ (q.T @ w[:, 0])


def _residual_without(qh: np.ndarray, rw: np.ndarray, zw: np.ndarray) -> np.ndarray:
    """The residual rw with the part of zw outside the model (qh) projected out as well."""
    zp = zw - qh @ (qh.T @ zw)
    return rw - zp @ np.linalg.lstsq(zp, rw, rcond=None)[0]


ORDER_CHAIN = 32
"""Longest chain of products :func:`order_columns` builds one order's columns by before it
computes them afresh. A grid's orders are not exactly evenly spaced (``arange``): the shared
factor's Δν is off by ~1e-15, a phase error of ~1e-15·|θ| per product, so the columns stay
within ~32·1e-15·max|θ| of cos and sin (3e-12 at 40 rad)."""


def order_columns(theta: np.ndarray) -> Callable[[float], np.ndarray]:
    """``cols(ν)`` = ``[cos νθ, sin νθ]`` (N, 2) for the orders a grid scan asks for.

    ``e^{iνθ}`` is built from the last order's by one complex product with ``e^{iΔν·θ}``
    when that Δν was met before (a grid's step), else computed afresh (the factor of the new
    Δν is then the product of the new phasor and the conjugate of the last). numpy's float64
    cos and sin cost several products each and a drive-order scan asks for a hundred orders
    or more on both axes; by hand because no library evaluates a trigonometric grid so."""
    th = np.asarray(theta, dtype=float)
    factors: dict[float, np.ndarray] = {}
    last: list = [None, None, 0]  # ν, e^{iνθ}, products since the last fresh one

    def cols(v: float) -> np.ndarray:
        v = float(v)
        if last[0] is not None and v == last[0]:
            z = last[1]
        else:
            dv = None if last[0] is None else round(v - last[0], 12)
            f = factors.get(dv) if dv is not None else None
            if f is not None and last[2] < ORDER_CHAIN:
                z, chain = last[1] * f, last[2] + 1
            else:
                z, chain = np.exp(1j * v * th), 0
                if dv is not None and dv not in factors and len(factors) < 8:
                    factors[dv] = z * np.conj(last[1])
            last[:] = [v, z, chain]
        return np.column_stack([z.real, z.imag])

    return cols


def fisher_g_logp(g: float, m: int) -> float:
    """log P(max periodogram ordinate / sum > g) for white Gaussian noise (Fisher 1929)."""
    p = 0.0
    for j in range(1, int(min(m, np.floor(1.0 / g))) + 1):
        term = (-1) ** (j - 1) * comb(m, j) * (1.0 - j * g) ** (m - 1)
        p += term
        if j >= 3:  # alternating, decreasing: three terms are plenty
            break
    return float(np.log(min(max(p, 1e-300), 1.0)))


def spectral_peak(space: AxisSpace, run, min_cycles: float = 0.5,
                  max_cycles: float | None = None
                  ) -> tuple[float, float, int, float, np.ndarray] | None:
    """Largest periodogram ordinate of the whitened residual: (g, log p, m, period, columns).

    Period in the run's time unit (s, or samples), refined between the neighbouring Fourier
    frequencies (a period that is not a whole fraction of the run leaks into two bins);
    columns: cos and sin at that frequency. Frequencies below ``min_cycles`` per run are not
    considered, nor above ``max_cycles`` when given (then m is the number of frequencies
    searched, and g, log p are those of the whole periodogram)."""
    r = space.rw
    n = r.size
    if n < 16:
        return None
    spec = np.abs(np.fft.rfft(r - r.mean())) ** 2
    spec = spec[1:(n - 1) // 2 + 1]  # Fourier frequencies j = 1 … floor((n-1)/2)
    m = spec.size
    total = float(spec.sum())
    j0 = int(np.ceil(min_cycles))
    if m < j0 + 1 or total <= 0:
        return None
    top = m if max_cycles is None else int(min(m, max(np.floor(max_cycles), j0)))
    j = int(np.argmax(spec[j0 - 1:top])) + j0
    g = float(spec[j - 1] / total)
    # j cycles over the N-1 differenced samples: the same frequency in the readings
    span = float(run.tcol[-1] - run.tcol[0]) * (n / max(n - 1, 1))
    tc = run.tcol - run.tcol[0]
    # cos, sin of 2πf·t/span on an evenly spaced grid of f: one complex product per point
    columns = order_columns(2.0 * np.pi * tc / span)

    freqs = np.linspace(max(j - 1.0, min_cycles), j + 1.0, 21)
    best_f = float(freqs[int(np.argmax(space.scan(columns, freqs)))])
    logp = fisher_g_logp(g, m)
    if max_cycles is not None:
        m = top - j0 + 1
    return g, logp, m, span / best_f, columns(best_f)


def legendre_in_time(run, degrees: tuple[int, ...]) -> np.ndarray:
    """(N, len(degrees)) Legendre polynomials ``P_d(x)`` of time mapped onto x ∈ [-1, 1]."""
    tc = run.tcol
    x = 2.0 * (tc - tc[0]) / max(float(tc[-1] - tc[0]), 1e-300) - 1.0
    return np.column_stack([np.polynomial.legendre.Legendre.basis(d)(x) for d in degrees])


def tilt_slope(run, k: int) -> np.ndarray:
    """(N,) ``dA_r/dθ`` of axis k, m/s² per rad: the other axis' reference signed as in a
    rotation by +δ (:data:`calib.effects.SIGN_P`; course signs ``dA_x/dθ = -g cos θ = A_y``,
    ``dA_y/dθ = g sin θ = -A_x``)."""
    return SIGN_P[k] * run.a_ref[:, 1 - k]


def drift_extent(run, coef: np.ndarray) -> float:
    """The largest |change| over the run of a parameter drifting as ``c₁P1(t) + c₂P2(t)``
    (the coefficients of :func:`gain_drift_columns` or :func:`tilt_drift_columns`)."""
    return float(np.max(np.abs(legendre_in_time(run, (1, 2)) @ np.asarray(coef)[:2])))


def gain_drift_words(axis: str, change: float) -> str:
    """A drifting gain in words (the ``gain_drift`` check and the walk's rival)."""
    return (f"the gain on {axis} changes during the run by up to {change:.3g} "
            f"({1e6 * change:.0f} ppm): a scale factor drifting with time or temperature")


def gain_drift_columns(run, k: int) -> np.ndarray:
    """(N, 2) ``A_r·P1(t)``, ``A_r·P2(t)``: a gain (scale factor) of axis k that changes during
    the run (linearly, or bending once) — a temperature coefficient of the scale, not in the
    catalog (whose scale is one number). ``A_r`` the axis' own reference (m/s²), P Legendre of
    time on [-1, 1] (:func:`legendre_in_time`): a coefficient c is a gain change of ±c at the
    ends of the run."""
    return run.a_ref[:, k][:, None] * legendre_in_time(run, (1, 2))


def tilt_drift_columns(run, k: int) -> np.ndarray:
    """(N, 2) ``dA_r/dθ·P1(t)``, ``dA_r/dθ·P2(t)``: a tilt (a rotation of the mount or the
    sensor) that creeps during the run — the catalog's tilt and misalignment are constant.
    ``dA_r/dθ`` from :func:`tilt_slope` (m/s² per rad)."""
    return tilt_slope(run, k)[:, None] * legendre_in_time(run, (1, 2))


def backlash_columns(run, k: int) -> np.ndarray | None:
    """(N, 2) ``d``, ``d·dA_r/dθ`` with d = ±1 the direction of the last motion
    (:func:`motion_direction`), or None when θ does not move both ways: a reading that depends
    on the direction the table last moved, as an offset (hysteresis of the bias) and as an
    angle (backlash of the drive: the table stops ``b`` short of the encoder's θ, so
    ``A_r(θ - d·b) ≈ A_r - d·b·dA_r/dθ``, :func:`tilt_slope`)."""
    d = motion_direction(run.tita)
    if d is None:
        return None
    return np.column_stack([d, d * tilt_slope(run, k)])


def motion_direction(tita: np.ndarray) -> np.ndarray | None:
    """+1 after an upward move, -1 after a downward one (held samples keep the last)."""
    d = np.sign(np.diff(tita, prepend=tita[0]))
    if not (np.any(d > 0) and np.any(d < 0)):
        return None
    idx = np.where(d != 0, np.arange(d.size), 0)
    np.maximum.accumulate(idx, out=idx)
    first = d[np.flatnonzero(d)[0]]
    out = np.where(d[idx] != 0, d[idx], first)
    frac = min(np.mean(out > 0), np.mean(out < 0))
    return out if frac >= 0.05 else None

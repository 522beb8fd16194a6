"""The Kalman machinery both fusion filters share (:mod:`calib.fusion.linear`, the course vehicle;
:mod:`calib.fusion.turning`, the turning one): the calibration as the filters take it, input
checks, P0 and R assembly, the predict/update loop over R runs at once, the nodes it keeps,
the update and the Rauch–Tung–Striebel smoother. A model supplies only its step (the mean, the
step Jacobian F and the process noise Q of one step). Units are the model's (SI).

Predict (the model's step, then)::

    P⁻ = F P Fᵀ + Q

Update at a fix (Joseph form, symmetric for any gain; the gain from a solve with S, never an
inverse)::

    ν = z - H x⁻,   S = H P⁻ Hᵀ + R,   K = P⁻ Hᵀ S⁻¹,
    x⁺ = x⁻ + K ν,  P⁺ = (I - K H) P⁻ (I - K H)ᵀ + K R Kᵀ

Innovation gate (issue 23): a fix whose normalized innovation squared ``NIS = νᵀ S⁻¹ ν``
reaches ``c = χ²_d⁻¹(1 - α)`` (:func:`gate_threshold`) is *rejected*: not used in the update
(``x⁺ = x⁻``, ``P⁺ = P⁻``), its ν and S still recorded. Under a right model NIS ~ χ²(d), so a
good fix is rejected with probability exactly α. ``α = 0``: no gate (c = ∞); ``α = 1``: every
fix rejected (c = 0), the free run: the dead reckoning with each fix's innovation against it.

Rauch–Tung–Striebel smoother, backwards over the stored nodes (``Φ_j`` the product of the
step Jacobians between stored nodes j and j+1; exact on any subset of nodes that includes
every fix, since no information enters between them; with the Jacobians at the filtered
estimates, the extended smoother)::

    C_j = P⁺_j Φ_jᵀ (P⁻_j+1)⁻¹,  xˢ_j = x⁺_j + C_j (xˢ_j+1 - x⁻_j+1),
    Pˢ_j = P⁺_j + C_j (Pˢ_j+1 - P⁻_j+1) C_jᵀ

Why numpy and not filterpy: see :mod:`calib.fusion.linear` (its smoother has no control input, and
it runs one run at a time).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy import stats

CAL_ORDER = ("bias_x", "scale_x", "bias_y", "scale_y")
"""Order of the calibration covariance (:class:`calib.calibration.tilt_plane.Calibration.cov`)."""


def as_runs(a, width: int, name: str) -> tuple[np.ndarray, bool]:
    """``a`` as (R, N, width) floats and whether it had a run axis; refuses NaN/Inf."""
    a = np.asarray(a, dtype=float)
    batched = a.ndim == 3
    if a.ndim == 2:
        a = a[None]
    if a.ndim != 3 or a.shape[-1] != width:
        raise ValueError(f"{name} must be (N, {width}) or (R, N, {width}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} has NaN or Inf: remove or interpolate those samples")
    return a, batched


def cov2(v, name: str) -> np.ndarray:
    """A (2, 2) covariance from a variance, two variances or a (2, 2) matrix."""
    v = np.asarray(v, dtype=float)
    if v.ndim == 0:
        return np.eye(2) * v
    if v.shape == (2,):
        return np.diag(v)
    if v.shape == (2, 2):
        return v
    raise ValueError(f"{name} must be a variance, two variances or a (2, 2) matrix, "
                     f"got shape {v.shape}")

class CalibrationLike(Protocol):
    """What the filters read from a calibration
    (:class:`calib.calibration.tilt_plane.Calibration`)."""

    @property
    def bias(self) -> np.ndarray: ...  # (2,) m/s²
    @property
    def scale(self) -> np.ndarray: ...  # (2,) dimensionless
    @property
    def cov(self) -> np.ndarray: ...  # (4, 4), order CAL_ORDER


@dataclass(frozen=True, eq=False)
class CalibrationPrior:
    """The calibration as the filters use it: ``bias`` (2,) m/s², ``scale`` (2,) and ``cov``
    (4, 4) in the order ``CAL_ORDER``, validated once for both filters."""

    bias: np.ndarray
    scale: np.ndarray
    cov: np.ndarray

    @classmethod
    def of(cls, calibration: CalibrationLike | None = None, *, bias=None, scale=None,
           cal_cov=None) -> CalibrationPrior:
        """From a calibration, or from its three parts (exactly one of the two ways)."""
        if calibration is not None:
            if bias is not None or scale is not None or cal_cov is not None:
                raise ValueError("give calibration or bias/scale/cal_cov, not both")
            bias, scale, cal_cov = calibration.bias, calibration.scale, calibration.cov
        if bias is None or scale is None or cal_cov is None:
            raise ValueError("the filter needs a calibration: calibration=, or bias=, scale= "
                             "and cal_cov=")
        cov = np.asarray(cal_cov, dtype=float)
        if cov.shape != (4, 4):
            raise ValueError(f"cal_cov must be (4, 4) in order {CAL_ORDER}, got {cov.shape}")
        return cls(np.broadcast_to(np.asarray(bias, dtype=float), (2,)),
                   np.broadcast_to(np.asarray(scale, dtype=float), (2,)), cov)

    @property
    def scale_var(self) -> np.ndarray:
        """(2,) the scale factors' variances ``σ_s²``, folded into Q as white terms."""
        return np.diag(self.cov)[[1, 3]]


def check_times(t, min_samples: int) -> np.ndarray:
    """IMU times (N,) s: 1-D, finite, strictly increasing, at least ``min_samples``."""
    t = np.asarray(t, dtype=float)
    if (t.ndim != 1 or t.shape[0] < min_samples or np.any(np.diff(t) <= 0)
            or not np.all(np.isfinite(t))):
        raise ValueError(f"t must be 1-D, finite, strictly increasing, with ≥ {min_samples} "
                         "samples")
    return t


def fix_measurements(pos_gps, m: int, runs: int, sigma_pos: float, vel_gps=None,
                     sigma_vel: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The fixes as measurements ``Z`` (R, M, d) (positions m, then velocities m/s when
    given) and their noise ``R = diag(σ_pos², σ_pos² [, σ_vel², σ_vel²])`` (d, d)."""
    zp, _ = as_runs(pos_gps, 2, "pos_gps")
    if zp.shape[1] != m:
        raise ValueError(f"pos_gps has {zp.shape[1]} fixes for {m} times")
    zs = [np.broadcast_to(zp, (runs, *zp.shape[1:]))]
    r_diag = [float(sigma_pos) ** 2] * 2
    if vel_gps is not None:
        zv, _ = as_runs(vel_gps, 2, "vel_gps")
        zs.append(np.broadcast_to(zv, (runs, *zv.shape[1:])))
        r_diag += [float(sigma_vel) ** 2] * 2
    return np.concatenate(zs, axis=-1), np.diag(r_diag)


@dataclass(frozen=True, eq=False)
class FilterInputs:
    """The checked inputs of a fusion filter (:func:`filter_inputs`), and the run of the
    shared loop on them (:meth:`run`).

    Attributes
    ----------
    t : (N,) IMU times, s.  acc : (R, N, 2) readings, m/s²; ``batched``: the caller gave the
        run axis R (else R = 1, dropped again from the result).
    t_gps : (M,) fix times, s.  Z : (R, M, d) the fixes (positions m, then velocities m/s)
        and Rm : (d, d) their noise (:func:`fix_measurements`).
    cal : the calibration (:class:`CalibrationPrior`).  noise_var : (2,) σ_a², (m/s²)².
    """

    t: np.ndarray
    acc: np.ndarray
    batched: bool
    t_gps: np.ndarray
    Z: np.ndarray
    Rm: np.ndarray
    cal: CalibrationPrior
    noise_var: np.ndarray

    @property
    def runs(self) -> int:
        """R, the runs stepped at once."""
        return int(self.acc.shape[0])

    @property
    def dt(self) -> float:
        """The nominal IMU step, the median step of ``t``, s (the printed Q's)."""
        return float(np.median(np.diff(self.t)))

    def run(self, step, x0: np.ndarray, P0: np.ndarray, fixi: np.ndarray, *,
            nodes: np.ndarray, keep: str, smoother: bool, gate_alpha: float) -> dict:
        """:func:`run_filter` of the model's ``step`` from ``x0``, ``P0`` over the nodes
        ``nodes`` (K,) s with the fix index ``fixi`` (K,) (−1: none), gated at
        :func:`gate_threshold` of ``gate_alpha``; returns the fields of a
        :class:`calib.fusion.linear.FusionResult` this run fills: the stored ``times``,
        ``t_gps``, :func:`filter_outputs`, ``P0``, ``R``, ``noise_var``, ``dt`` and
        ``gate_alpha`` (the model adds ``state_names``, ``Q`` and ``estimate_scale``)."""
        kept, nu, S_all, used = run_filter(step, x0, P0, fixi, self.Z, self.Rm, keep, smoother,
                                           gate=gate_threshold(gate_alpha, self.Z.shape[-1]))
        return {"times": nodes[kept.store], "t_gps": self.t_gps,
                **filter_outputs(kept, nu, S_all, used, self.batched), "P0": P0, "R": self.Rm,
                "noise_var": self.noise_var, "dt": self.dt, "gate_alpha": gate_alpha}


def filter_inputs(t, acc_m, t_gps, pos_gps, *, noise_var, sigma_pos: float,
                  calibration: CalibrationLike | None = None, bias=None, scale=None,
                  cal_cov=None, vel_gps=None, sigma_vel: float | None = None) -> FilterInputs:
    """The checks both filters make on their inputs, in this order: the IMU times
    (:func:`check_times`, at least 2), the readings ``acc_m`` (N, 2) or (R, N, 2) m/s²
    (:func:`as_runs`, one per time), the fixes (:func:`fix_measurements`: ``pos_gps`` m, one
    per fix time ``t_gps`` s, optional ``vel_gps`` m/s), the calibration
    (:meth:`CalibrationPrior.of`) and σ_a² ``noise_var`` (scalar or (2,), (m/s²)²). Each
    filter checks the fix times against its own model afterwards."""
    t = check_times(t, 2)
    acc, batched = as_runs(acc_m, 2, "acc_m")
    if acc.shape[1] != t.shape[0]:
        raise ValueError(f"acc_m has {acc.shape[1]} samples for {t.shape[0]} times")
    t_gps = np.asarray(t_gps, dtype=float).reshape(-1)
    Z, Rm = fix_measurements(pos_gps, t_gps.shape[0], acc.shape[0], sigma_pos, vel_gps,
                             sigma_vel)
    cal = CalibrationPrior.of(calibration, bias=bias, scale=scale, cal_cov=cal_cov)
    sa2 = np.broadcast_to(np.asarray(noise_var, dtype=float), (2,)).copy()
    return FilterInputs(t, acc, batched, t_gps, Z, Rm, cal, sa2)


def initial_cov(n: int, p0_cov, v0_cov, blocks: dict[int, np.ndarray]) -> np.ndarray:
    """P0 (n, n): position (m²) and velocity ((m/s)²) blocks first, then each square block
    of ``blocks`` at its start index (the calibration's, a heading variance, …)."""
    P0 = np.zeros((n, n))
    P0[:2, :2] = cov2(p0_cov, "p0_cov")
    P0[2:4, 2:4] = cov2(v0_cov, "v0_cov")
    for i, b in blocks.items():
        b = np.atleast_2d(np.asarray(b, dtype=float))
        P0[i:i + b.shape[0], i:i + b.shape[0]] = b
    return P0

def gate_threshold(alpha: float, d: int) -> float:
    """The innovation gate ``c = χ²_d⁻¹(1 - α)`` (module docstring): a fix is used when its
    NIS is below c. ``alpha`` in [0, 1] (0: no gate, c = ∞; 1: no fix used, c = 0)."""
    alpha = float(alpha)
    if not 0.0 <= alpha <= 1.0:
        raise ValueError(f"the gate's alpha must be in [0, 1], got {alpha!r}")
    if alpha == 0.0:
        return float("inf")
    return float(stats.chi2.isf(alpha, d)) if alpha < 1.0 else 0.0


def run_filter(step, x0: np.ndarray, P0: np.ndarray, fixi: np.ndarray, Z: np.ndarray,
               Rm: np.ndarray, keep: str, smoother: bool, *, gate: float = float("inf")
               ) -> tuple[NodeStore, np.ndarray, np.ndarray, np.ndarray]:
    """The predict/update loop both filters share, over K nodes for R runs at once.

    ``step(k, x, F, Qk)`` predicts from node k-1 to node k (:class:`LinearStep`, the turning
    filter's step); then ``P⁻ = F P Fᵀ + Qk``; at a node with a fix (``fixi[k] ≥ 0``) the
    Joseph-form update :func:`kalman_update` with ``H = [I_d 0]`` (the fixes measure the
    first d states: positions, then velocities) and ``Rm``, unless the fix's NIS reaches
    ``gate`` (:func:`gate_threshold`): then the prior is kept. Returns the stored nodes
    (:class:`NodeStore`), the innovations (R, M, d), their covariances (R, M, d, d) and which
    fixes were used (R, M) bool.
    """
    Rn, M, d = Z.shape
    n = x0.shape[0]
    H = np.zeros((d, n))
    H[:, :d] = np.eye(d)
    kept = NodeStore(fixi, keep, Rn, n, smoother)
    x = np.broadcast_to(x0, (Rn, n)).copy()
    P = np.broadcast_to(P0, (Rn, n, n)).copy()
    nu = np.empty((Rn, M, d))
    S_all = np.empty((Rn, M, d, d))
    used = np.zeros((Rn, M), dtype=bool)
    F = kept.identity()
    Qk = np.zeros((Rn, n, n))
    for k in range(fixi.shape[0]):
        if k > 0:
            step(k, x, F, Qk)
            P = F @ P @ F.transpose(0, 2, 1) + Qk
            kept.step(F)
        xp, Pp = x.copy(), P.copy()
        m = fixi[k]
        if m >= 0:
            xu, Pu, nu[:, m], S_all[:, m] = kalman_update(x, P, Z[:, m, :], H, Rm)
            nis = np.einsum("ri,ri->r", nu[:, m],
                            np.linalg.solve(S_all[:, m], nu[:, m, :, None])[..., 0])
            ok = nis < gate  # a rejected fix leaves the prior as it is
            used[:, m] = ok
            x = np.where(ok[:, None], xu, x)
            P = np.where(ok[:, None, None], Pu, P)
        kept.keep(k, x, P, xp, Pp)
    return kept, nu, S_all, used


def filter_outputs(kept: NodeStore, nu: np.ndarray, S_all: np.ndarray, used: np.ndarray,
                   batched: bool) -> dict:
    """The per-node fields of a :class:`FusionResult` (filtered, innovations, fixes used,
    smoothed), without the run axis for a single run."""
    xsm, Psm = kept.smoothed()
    out = {"estimates": kept.x_f, "covariances": kept.P_f, "innovations": nu,
           "innovation_covs": S_all, "fix_used": used, "smoothed": xsm,
           "smoothed_covariances": Psm}
    if not batched:
        out = {k: v[0] for k, v in out.items()}
    return {**out, "is_fix": kept.is_fix}


class NodeStore:
    """What a forward pass keeps at its stored nodes, for the result and the RTS smoother.

    ``keep="all"``: every node; ``"fixes"``: the fix nodes and the first and last. Kept per
    stored node j: the filtered ``x⁺_j, P⁺_j``; with ``smoother``, also the prior
    ``x⁻_j, P⁻_j`` and ``Φ_j``, the product of the step Jacobians since the previous stored
    node (module docstring), reset after each stored node.
    """

    def __init__(self, fixi: np.ndarray, keep: str, runs: int, n: int, smoother: bool) -> None:
        if keep == "all":
            store = np.ones(fixi.shape[0], bool)
        elif keep == "fixes":
            store = fixi >= 0
            store[0] = store[-1] = True
        else:
            raise ValueError(f"keep must be 'all' or 'fixes', got {keep!r}")
        self.store, self.smoother, self.runs, self.n = store, smoother, runs, n
        self.is_fix = fixi[store] >= 0
        n_store = int(store.sum())
        n_prior = n_store if smoother else 1  # priors and Φ only for the smoother
        self.x_f, self.P_f = np.empty((runs, n_store, n)), np.empty((runs, n_store, n, n))
        self.x_p, self.P_p = np.empty((runs, n_prior, n)), np.empty((runs, n_prior, n, n))
        self.Phis = np.empty((runs, n_prior, n, n))
        self.Phi = self.identity()
        self.j = 0

    def identity(self) -> np.ndarray:
        """A fresh (R, n, n) stack of identities."""
        return np.broadcast_to(np.eye(self.n), (self.runs, self.n, self.n)).copy()

    def step(self, F: np.ndarray) -> None:
        """Accumulate a step Jacobian into Φ (smoother only)."""
        if self.smoother:
            self.Phi = F @ self.Phi

    def keep(self, k: int, x: np.ndarray, P: np.ndarray, xp: np.ndarray, Pp: np.ndarray
             ) -> None:
        """Node k's posterior (and prior): stored if node k is kept."""
        if not self.store[k]:
            return
        j = self.j
        if self.smoother:
            self.x_p[:, j], self.P_p[:, j], self.Phis[:, j] = xp, Pp, self.Phi
        self.x_f[:, j], self.P_f[:, j] = x, P
        self.Phi = self.identity()
        self.j += 1

    def smoothed(self) -> tuple[np.ndarray, np.ndarray]:
        """The RTS means and covariances at the stored nodes (empty without ``smoother``)."""
        if not self.smoother:
            return np.zeros((self.runs, 0, self.n)), np.zeros((self.runs, 0, self.n, self.n))
        return rts(self.x_f, self.P_f, self.x_p, self.P_p, self.Phis)


def nominal_q(n: int, noise_var: np.ndarray, gain: np.ndarray, dt: float) -> np.ndarray:
    """The Q of one step ``dt`` held at the stated accelerometer noise, printed by the
    reports: per axis i, ``σ_a,i² · gain_i² · g gᵀ`` on (p_i, v_i) with ``g = [dt²/2, dt]``
    (states ordered px, py, vx, vy, …; ``gain = 1/(1 + ŝ)``), zero elsewhere."""
    Q = np.zeros((n, n))
    g = np.array([0.5 * dt * dt, dt])
    for i in range(2):
        Q[np.ix_([i, i + 2], [i, i + 2])] = noise_var[i] * gain[i] ** 2 * np.outer(g, g)
    return Q


def kalman_update(x: np.ndarray, P: np.ndarray, z: np.ndarray, H: np.ndarray,
                  Rm: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Joseph-form update of R runs with a linear measurement (module docstring).

    x : (R, n) prior means, P : (R, n, n) their covariances, z : (R, d) measurements,
    H : (d, n), Rm : (d, d) measurement noise. Returns the posterior ``x⁺`` (R, n), ``P⁺``
    (R, n, n, symmetrised), the innovations ``ν`` (R, d) and their covariances ``S``
    (R, d, d). The gain comes from a solve with S, never an inverse.
    """
    v = z - x @ H.T
    S = H @ P @ H.T + Rm
    PHt = P @ H.T
    Kg = np.linalg.solve(S, PHt.transpose(0, 2, 1)).transpose(0, 2, 1)
    x = x + np.einsum("rij,rj->ri", Kg, v)
    IKH = np.eye(P.shape[-1]) - Kg @ H
    P = IKH @ P @ IKH.transpose(0, 2, 1) + Kg @ Rm @ Kg.transpose(0, 2, 1)
    P = 0.5 * (P + P.transpose(0, 2, 1))
    return x, P, v, S


def _rts_gain(P_f: np.ndarray, Phi: np.ndarray, P_p: np.ndarray) -> np.ndarray:
    """``C = P⁺_j Φᵀ (P⁻_j+1)⁻¹`` for R runs, through a solve with the symmetric prior.

    A prior can be exactly singular: with the initial position and velocity known (P0 = 0
    there, the course's case) the prior one step later has, per axis, only the bias and one
    step's held noise in the three directions (p, v, b): rank 2. The gain is then defined on
    the prior's range, and the pseudo-inverse (symmetric, ``numpy.linalg.pinv``) gives it;
    the mean and covariance updates that use it stay exact, since the smoothed and the
    prior state differ only inside that range.
    """
    rhs = Phi @ P_f
    try:
        return np.linalg.solve(P_p, rhs).transpose(0, 2, 1)
    except np.linalg.LinAlgError:
        return (np.linalg.pinv(P_p, hermitian=True) @ rhs).transpose(0, 2, 1)


def rts(x_f, P_f, x_p, P_p, Phi):
    """Rauch–Tung–Striebel smoother over stored nodes (module docstring).

    Parameters
    ----------
    x_f, P_f : (R, K, n), (R, K, n, n) filtered (posterior) means and covariances.
    x_p, P_p : the predicted (prior) ones at the same nodes.
    Phi : (R, K, n, n), ``Phi[:, j]`` maps node j-1 to node j (``Phi[:, 0]`` unused).

    Returns
    -------
    Smoothed means (R, K, n) and covariances (R, K, n, n).
    """
    xs, Ps = x_f.copy(), P_f.copy()
    for j in range(x_f.shape[1] - 2, -1, -1):
        C = _rts_gain(P_f[:, j], Phi[:, j + 1], P_p[:, j + 1])
        xs[:, j] = x_f[:, j] + np.einsum("rij,rj->ri", C, xs[:, j + 1] - x_p[:, j + 1])
        Pj = P_f[:, j] + C @ (Ps[:, j + 1] - P_p[:, j + 1]) @ C.transpose(0, 2, 1)
        Ps[:, j] = 0.5 * (Pj + Pj.transpose(0, 2, 1))
    return xs, Ps


__all__ = ["CAL_ORDER", "CalibrationLike", "CalibrationPrior", "NodeStore", "as_runs",
           "check_times", "cov2", "filter_outputs", "fix_measurements", "gate_threshold",
           "initial_cov", "kalman_update", "nominal_q", "rts", "run_filter"]

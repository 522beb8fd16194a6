"""Linear Kalman fusion of the corrected accelerometers with position fixes (issue 13, part 3).

Course vehicle: it moves in the horizontal plane without rotating, so the x and y
accelerometers read ``d²x/dt²`` and ``d²y/dt²`` (world axes, m/s²), as in
:mod:`calib.vehicle.trajectory`. Positions m, velocities m/s, biases m/s², scale factors 1, time s.

Model
-----
State ``x = [px, py, vx, vy, bx, by]`` (and ``[sx, sy]`` with ``estimate_scale=True``).
Each reading ``A_m,k`` is held over its step ``[t_k, t_k+1)`` (zero-order hold, the same hold
for its noise), the corrected acceleration is (course model,
:func:`calib.calibration.correct.correct`)::

    a_k = (A_m,k - b - v_k) / (1 + s),        v_k ~ N(0, σ_a²) per axis, white

and over a step of length h the double integrator is discretised exactly::

    p⁺ = p + v h + a h²/2,     v⁺ = v + a h,     b⁺ = b,     s⁺ = s

* ``estimate_scale=False`` (default): s is fixed at the calibration estimate ŝ; the map is
  linear in the state (``F`` constant, input ``G A_m/(1+ŝ)``). The scale uncertainty
  ``σ_s²`` is folded into Q as a white term ``σ_s² â_k²/(1+ŝ)²`` (``∂a/∂s = -a/(1+s)``); it
  is a constant in truth, so this is an approximation, good while ``σ_s·|a|·T²/2`` over the
  longest gap between fixes stays far below the fix σ (mm against m on the course).
* ``estimate_scale=True``: s is a state, the step is linearised about the current estimate
  (``∂a/∂b = -1/(1+ŝ)``, ``∂a/∂s = -â/(1+ŝ)``): an extended filter with a linear
  measurement.

Process noise per step and axis, exact for the held noise sample (``g = [h²/2, h]``)::

    Q_pv = σ_a²/(1+ŝ)² · g gᵀ      (+ the folded scale term, same shape)

P0 is block-diagonal: the initial position and velocity covariances and the calibration
covariance (bias block, and scale block when estimated, with their cross terms); the
bias–scale cross terms are dropped when the scale is not estimated. R is ``σ_pos² I`` (and
``σ_vel² I`` for velocity fixes). Nothing is tuned: Q from the accelerometer's stated
variance, P0 from the stated initial uncertainty and the calibration, R from the receiver.

Fixes come at their own times ``t_gps`` (asynchronous): the timeline is the union of the IMU
times and the fix times; a fix inside ``(t_k, t_k+1)`` splits that step in two with the same
held reading (the two parts are given independent noise: an approximation of order
``σ_a² h⁴``, 1e-8 m² at 50 Hz). The update at a fix (Joseph form) and the Rauch–Tung–Striebel
smoother over the stored nodes are those of :mod:`calib.fusion.kalman`, which runs this model's step
(:class:`LinearStep`) in the loop both filters share.

Why numpy and not filterpy
--------------------------
filterpy 2.0.0 (PyPI) has ``KalmanFilter`` and ``rts_smoother``, but (1) its smoother
predicts ``x_k+1|k = F x_k`` without the control input (``rts_smoother`` in
``filterpy/kalman/kalman_filter.py``), while this model is driven by the accelerations
(``B u`` every step), so its smoothed means would be wrong; (2) it runs one run at a time, a
Python call per step: 6000 steps × 500 Monte Carlo runs is 3·10⁶ predict calls (minutes),
where this module steps all runs at once as (R, n, n) arrays (a Monte Carlo of 500 runs of
3000 steps takes about a second).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from calib.fusion.kalman import (
    CAL_ORDER,
    CalibrationLike,
    CalibrationPrior,
    FilterInputs,
    filter_inputs,
    initial_cov,
    kalman_update,
    nominal_q,
    rts,
)
from calib.results import ResultMixin, readonly

STATE_NAMES = ("px", "py", "vx", "vy", "bx", "by")
SCALE_NAMES = ("sx", "sy")


@dataclass(frozen=True, eq=False, kw_only=True)
class FusionResult(ResultMixin):
    """Kalman filter (and smoother) estimates of one run or of R runs at once.

    Attributes (a leading run axis R when the inputs had one)
    ----------
    state_names : names of the n state components (``STATE_NAMES`` [+ ``SCALE_NAMES``]).
    times : (K,) s, the stored nodes (all: IMU times merged with fix times; or the start,
        every fix and the end).
    estimates : (K, n) filtered state (after the update at a fix), m, m/s, m/s², 1.
    covariances : (K, n, n) their covariances.
    is_fix : (K,) bool, node carries a fix.
    t_gps : (M,) s.  innovations : (M, d) ν, m (and m/s).  innovation_covs : (M, d, d) S.
    smoothed, smoothed_covariances : RTS estimates at the nodes, or empty when not asked.
    P0 : (n, n) initial covariance.  Q : (n, n) process noise of one nominal IMU step
        (median step, without the data-dependent scale term).  R : (d, d) fix noise.
    noise_var : (2,) accelerometer white-noise variance σ_a², (m/s²)².
    estimate_scale : bool.  dt : nominal IMU step, s.
    fix_used : (M,) bool, the fix passed the innovation gate and was used in the update
        (:func:`calib.fusion.kalman.gate_threshold`); all True without a gate.
    gate_alpha : the gate's α (0: no gate): a right fix is rejected with probability α.
    """

    # only alike (bench.validate.Validation): a result's title, units and fields, not logic
    _TITLE = "Kalman fusion"
    _UNITS = ("t s; px, py m; vx, vy m/s; bx, by m/s²; sx, sy 1; covariances in the products "
              "of those units; innovations m (position) and m/s (velocity)")

    state_names: tuple[str, ...]
    times: np.ndarray
    estimates: np.ndarray
    covariances: np.ndarray
    is_fix: np.ndarray
    t_gps: np.ndarray
    innovations: np.ndarray
    innovation_covs: np.ndarray
    smoothed: np.ndarray
    smoothed_covariances: np.ndarray
    P0: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    noise_var: np.ndarray
    estimate_scale: bool
    dt: float
    fix_used: np.ndarray | None = None
    gate_alpha: float = 0.0

    def __post_init__(self) -> None:
        if self.fix_used is None:
            object.__setattr__(self, "fix_used",
                               np.ones(np.shape(self.innovations)[:-1], dtype=bool))
        object.__setattr__(self, "fix_used", readonly(self.fix_used, bool))
        object.__setattr__(self, "gate_alpha", float(self.gate_alpha))
        object.__setattr__(self, "state_names", tuple(self.state_names))
        for name in ("times", "estimates", "covariances", "t_gps", "innovations",
                     "innovation_covs", "smoothed", "smoothed_covariances", "P0", "Q", "R",
                     "noise_var"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "is_fix", readonly(self.is_fix, bool))
        object.__setattr__(self, "dt", float(self.dt))
        object.__setattr__(self, "estimate_scale", bool(self.estimate_scale))

    @property
    def n_runs(self) -> int:
        """R, or 0 for a single run (no run axis)."""
        return self.estimates.shape[0] if self.estimates.ndim == 3 else 0

    @property
    def final_position(self) -> np.ndarray:
        """(2,) or (R, 2) filtered position at the last node, m."""
        return self.estimates[..., -1, :2].copy()

    @property
    def final_position_cov(self) -> np.ndarray:
        """(2, 2) or (R, 2, 2) its covariance, m²."""
        return self.covariances[..., -1, :2, :2].copy()

    @property
    def n_rejected(self) -> np.ndarray | int:
        """Fixes the gate rejected (an int, or (R,) for R runs)."""
        r = np.sum(~self.fix_used, axis=-1)
        return int(r) if np.ndim(r) == 0 else r

    def nis(self) -> np.ndarray:
        """(M,) or (R, M) normalized innovation squared ``νᵀ S⁻¹ ν`` (χ²(d) if consistent)."""
        sol = np.linalg.solve(self.innovation_covs, self.innovations[..., None])[..., 0]
        return np.einsum("...i,...i->...", self.innovations, sol)

    def nees(self, truth: np.ndarray, smoothed: bool = False) -> np.ndarray:
        """(K,) or (R, K) ``eᵀ P⁻¹ e`` against the true states ``truth`` (same shape)."""
        x = self.smoothed if smoothed else self.estimates
        P = self.smoothed_covariances if smoothed else self.covariances
        e = np.asarray(truth, dtype=float) - x
        return np.einsum("...i,...i->...", e, np.linalg.solve(P, e[..., None])[..., 0])

    def to_dict(self) -> dict:
        d = {name: getattr(self, name).tolist() for name in (
            "times", "estimates", "covariances", "is_fix", "t_gps", "innovations",
            "innovation_covs", "smoothed", "smoothed_covariances", "P0", "Q", "R",
            "noise_var", "fix_used")}
        d.update(state_names=list(self.state_names), estimate_scale=self.estimate_scale,
                 dt=self.dt, gate_alpha=self.gate_alpha,
                 fixes_rejected=np.asarray(self.n_rejected).tolist(),
                 final_position=self.final_position.tolist(),
                 final_position_cov=self.final_position_cov.tolist())
        d["units"] = {
            "times": "s", "t_gps": "s", "dt": "s",
            "estimates": "[m, m, m/s, m/s, m/s², m/s², 1, 1]",
            "smoothed": "[m, m, m/s, m/s, m/s², m/s², 1, 1]",
            "covariances": "products of the state units", "smoothed_covariances":
            "products of the state units", "P0": "products of the state units",
            "Q": "products of the state units", "R": "[m², m², (m/s)², (m/s)²]",
            "innovations": "[m, m, m/s, m/s]", "innovation_covs": "[m², m², (m/s)², (m/s)²]",
            "noise_var": "(m/s²)²", "final_position": "m", "final_position_cov": "m²",
            "gate_alpha": "1", "fixes_rejected": "count",
        }
        return d

    @classmethod
    def from_dict(cls, d: dict) -> FusionResult:
        """Rebuild from :meth:`to_dict` (exact, also through JSON, which keeps no shape for
        the empty smoothed or innovation arrays: they get theirs back here)."""
        kw = {f.name: d[f.name] for f in fields(cls) if f.name in d}
        est = np.asarray(kw["estimates"], dtype=float)
        runs, n, dm = est.shape[:-2], est.shape[-1], np.shape(kw["R"])[0]
        for name, shape in (("smoothed", (0, n)), ("smoothed_covariances", (0, n, n)),
                            ("innovations", (0, dm)), ("innovation_covs", (0, dm, dm)),
                            ("fix_used", (0,))):
            if name in kw and not np.size(kw[name]):
                kw[name] = np.zeros((*runs, *shape), dtype=bool if name == "fix_used" else float)
        return cls(**kw)

    def summary(self) -> str:
        def mat(name: str, m: np.ndarray, unit: str) -> list[str]:
            rows = ["  " + " ".join(f"{v:11.4g}" for v in row) for row in m]
            return [f"{name} ({unit}; order {', '.join(self.state_names)}):"
                    if m.shape[0] == len(self.state_names) else f"{name} ({unit}):", *rows]
        nis = self.nis()
        d = self.innovations.shape[-1]
        lines = [
            f"Kalman fusion: {self.times.shape[-1]} nodes over "
            f"{self.times[-1] - self.times[0]:g} s, IMU step {self.dt:g} s, "
            f"{self.t_gps.shape[0]} fixes ({'position+velocity' if d == 4 else 'position'}), "
            f"scale {'estimated' if self.estimate_scale else 'fixed (folded into Q)'}"
            + (f", {self.n_runs} runs" if self.n_runs else ""),
            "  accelerometer noise σ_a² = ["
            + ", ".join(f"{v:.4g}" for v in self.noise_var) + "] (m/s²)²",
        ]
        lines += mat("P0", self.P0, "SI, products of state units")
        lines += mat("Q per IMU step", self.Q, "SI, products of state units")
        lines += mat("R", self.R, "m² / (m/s)²")
        fp = self.final_position.reshape(-1, 2)[0]
        fs = np.sqrt(np.diag(self.final_position_cov.reshape(-1, 2, 2)[0]))
        lines.append(f"  final position ({fp[0]:.3f}, {fp[1]:.3f}) m, std "
                     f"({fs[0]:.3f}, {fs[1]:.3f}) m")
        used = np.asarray(self.fix_used, dtype=bool)
        if nis.size:  # the mean of the fixes used: a rejected one is the gate's business
            gate = (f"gate at α = {self.gate_alpha:g}: {int(np.sum(~used))} of {used.size} "
                    "fixes rejected" if self.gate_alpha > 0 else "no innovation gate")
            lines.append(f"  mean NIS {float(np.mean(nis[used])):.3f} (expected {d}); {gate}"
                         if used.any() else f"  no fix used; {gate}")
        return "\n".join(lines)


def _timeline(t: np.ndarray, t_gps: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Merged nodes (K,), the IMU sample held from each node (K,), the fix index (K,) or -1."""
    tol = 1e-9 * max(1.0, float(np.max(np.abs(t))))
    k_imu = np.clip(np.searchsorted(t, t_gps, side="right") - 1, 0, t.shape[0] - 1)
    on_grid = np.abs(t[k_imu] - t_gps) <= tol
    extra = t_gps[~on_grid]
    nodes = np.concatenate([t, extra])
    order = np.argsort(nodes, kind="stable")
    nodes = nodes[order]
    hold = np.concatenate([np.arange(t.shape[0]), k_imu[~on_grid]])[order]
    fix = np.full(nodes.shape[0], -1)
    pos_imu = np.argsort(order)  # node position of each original entry
    m_idx = np.arange(t_gps.shape[0])
    fix[pos_imu[k_imu[on_grid]]] = m_idx[on_grid]
    fix[pos_imu[t.shape[0] + np.arange(extra.shape[0])]] = m_idx[~on_grid]
    return nodes, hold, fix


def fuse(t, acc_m, t_gps, pos_gps, *, noise_var, sigma_pos, p0, v0, p0_cov, v0_cov,
         calibration: CalibrationLike | None = None, bias=None, scale=None, cal_cov=None,
         vel_gps=None, sigma_vel=None, estimate_scale=False, smoother=False,
         keep="all", gate_alpha: float = 0.0) -> FusionResult:
    """Kalman filter (and RTS smoother) of accelerometer readings with position fixes.

    Parameters
    ----------
    t : (N,) IMU times, s, strictly increasing.
    acc_m : (N, 2) measured accelerations ``A_m`` (uncorrected), m/s²; or (R, N, 2) for R
        runs on the same times (Monte Carlo).
    t_gps : (M,) fix times, s, strictly increasing, within ``[t_0, t_N-1]``.
    pos_gps : (M, 2) or (R, M, 2) position fixes, m.
    calibration : the calibration (a :class:`calib.calibration.tilt_plane.Calibration`, or anything
    with
        ``bias`` (2,) m/s², ``scale`` (2,) dimensionless and ``cov`` (4, 4) in the order
        ``[bias_x, scale_x, bias_y, scale_y]``); or give those three as ``bias``, ``scale``
        and ``cal_cov``.
    noise_var : σ_a², variance of each reading's white noise, (2,) (m/s²)² or a scalar.
    sigma_pos : σ of each position fix coordinate, m.
    p0 : (2,) m, v0 : (2,) m/s initial estimate; p0_cov, v0_cov : their covariances (scalar,
        (2,) or (2, 2)), m², (m/s)².
    vel_gps : optional (M, 2) or (R, M, 2) velocity fixes, m/s, with sigma_vel, m/s.
    estimate_scale : add ``[sx, sy]`` to the state (linearised step), else fix at ``scale``.
    smoother : also run the RTS smoother over the stored nodes.
    keep : "all" stores every node (IMU times merged with fix times); "fixes" stores the
        start, the fixes and the end only (Monte Carlo: the smoother is exact on them too).
    gate_alpha : the innovation gate's α (:func:`calib.fusion.kalman.gate_threshold`): a fix with
        ``NIS ≥ χ²_d⁻¹(1 - α)`` is not used; 0 (default): every fix used; 1: none (the free
        run, dead reckoning with the innovations against it).

    Returns
    -------
    FusionResult

    Examples
    --------
    A vehicle at rest for 10 s (100 Hz readings of zero), a fix every second at the origin
    (σ = 3 m), a calibration known to 0.01 m/s² in bias:

    >>> import numpy as np
    >>> t = np.arange(1001) * 0.01
    >>> res = fuse(t, np.zeros((t.size, 2)), np.arange(11.0), np.zeros((11, 2)),
    ...            bias=[0, 0], scale=[0, 0], cal_cov=np.diag([1e-4, 1e-6, 1e-4, 1e-6]),
    ...            noise_var=[0.25, 0.64], sigma_pos=3.0, p0=[0, 0], v0=[0, 0],
    ...            p0_cov=0.0, v0_cov=0.0)
    >>> np.round(res.final_position, 6).tolist()
    [0.0, 0.0]
    >>> bool(np.all(np.sqrt(np.diag(res.final_position_cov)) < 3.0))  # below one fix's σ
    True
    """
    inp = filter_inputs(t, acc_m, t_gps, pos_gps, noise_var=noise_var, sigma_pos=sigma_pos,
                        calibration=calibration, bias=bias, scale=scale, cal_cov=cal_cov,
                        vel_gps=vel_gps, sigma_vel=sigma_vel)
    t, t_gps, cal = inp.t, inp.t_gps, inp.cal
    if np.any(np.diff(t_gps) <= 0) or (t_gps.size and (t_gps[0] < t[0] or t_gps[-1] > t[-1])):
        raise ValueError("t_gps must be strictly increasing and inside [t[0], t[-1]]")

    n = 8 if estimate_scale else 6
    # P0: position, velocity, then the calibration blocks (bias [0, 2], scale [1, 3]).
    cal_idx = [0, 2, 1, 3] if estimate_scale else [0, 2]
    P0 = initial_cov(n, p0_cov, v0_cov, {4: cal.cov[np.ix_(cal_idx, cal_idx)]})
    x0 = np.concatenate([p0, v0, cal.bias] + ([cal.scale] if estimate_scale else []))

    nodes, hold, fixi = _timeline(t, t_gps)
    step = LinearStep(nodes, hold, inp, estimate_scale)
    names = STATE_NAMES + (SCALE_NAMES if estimate_scale else ())
    return FusionResult(state_names=names,
                        **inp.run(step, x0, P0, fixi, nodes=nodes, keep=keep, smoother=smoother,
                                  gate_alpha=gate_alpha),
                        Q=nominal_q(n, inp.noise_var, 1.0 / (1.0 + cal.scale), inp.dt),
                        estimate_scale=estimate_scale)


class LinearStep:
    """The course vehicle's step (module docstring): ``step(k, x, F, Qk)`` moves the means
    ``x`` (R, n) from node k-1 to node k in place and fills the step Jacobian ``F`` and the
    process noise ``Qk`` (R, n, n) (entries it does not write stay as
    :func:`calib.fusion.kalman.run_filter` set them: identity, zeros)."""

    def __init__(self, nodes: np.ndarray, hold: np.ndarray, inputs: FilterInputs,
                 estimate_scale: bool) -> None:
        self.nodes, self.hold, self.acc, self.scale = nodes, hold, inputs.acc, inputs.cal.scale
        self.sa2, self.estimate_scale = inputs.noise_var, estimate_scale
        self.ss2 = np.zeros(2) if estimate_scale else inputs.cal.scale_var

    def __call__(self, k: int, x: np.ndarray, F: np.ndarray, Qk: np.ndarray) -> None:
        ax = np.arange(2)
        h = self.nodes[k] - self.nodes[k - 1]
        A = self.acc[:, self.hold[k - 1], :]
        s_hat = x[:, 6:8] if self.estimate_scale else self.scale
        c = 1.0 / (1.0 + s_hat)  # (R, 2) or (2,)
        a = (A - x[:, 4:6]) * c
        # Jacobian of the step (exact for b; linearised for s).
        F[:, ax, ax + 2] = h
        F[:, ax, ax + 4] = -0.5 * h * h * c
        F[:, ax + 2, ax + 4] = -h * c
        if self.estimate_scale:
            F[:, ax, ax + 6] = -0.5 * h * h * a * c
            F[:, ax + 2, ax + 6] = -h * a * c
        q = (self.sa2 + self.ss2 * a * a) * c * c  # (R, 2): (σ_a² + σ_s² â²)/(1+ŝ)²
        g1, g2 = 0.5 * h * h, h
        Qk[:, ax, ax] = q * g1 * g1
        Qk[:, ax, ax + 2] = Qk[:, ax + 2, ax] = q * g1 * g2
        Qk[:, ax + 2, ax + 2] = q * g2 * g2
        x[:, 0:2] += x[:, 2:4] * h + a * g1
        x[:, 2:4] += a * h




__all__ = ["CAL_ORDER", "CalibrationPrior", "FusionResult", "LinearStep", "SCALE_NAMES",
           "STATE_NAMES", "fuse", "kalman_update", "rts"]

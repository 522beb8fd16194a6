"""The discrepancy workflow on the bench: re-simulate a measured run, add the missing effects.

``run_gap`` takes a measured calibration run (course format, optional ``t``) and

1. asks the estimation side (:func:`calib.gap.analyze_gap`) which catalog effects the data
   show — detection, selection and estimates live there, never here;
2. re-runs **the same experiment on the bench** (:class:`Replay`) with the fitted nominal
   parameters (bias, scale) and measures the gap: per axis χ²/dof of data − simulation with
   the stated noise, and the largest structured-signature z (:func:`calib.gap.gap_measure`);
3. adds the named effects to the bench — physical ones as ``MjSpec`` edits of a copy of the
   model (written to ``model_after.xml``), the others as sensor terms without noise —,
   refines the physical parameters by re-simulation with ``mujoco.sysid`` (cross-checked
   against the linear least-squares estimate of ``calib``), re-simulates and measures the gap
   again; after a correct extension it is consistent with noise alone;
4. writes a figure (PNG + SVG), a rerun recording and a Markdown report.

Replay of the experiment
------------------------
* **static** (no timing, or held positions): every distinct θ is a static pose
  (:func:`bench.tilt.static_readings`), exactly what a static bench run produces.
* **sweep** (sample times ``t`` from the file or ``--rate``, θ moving continuously): the
  measured encoder angle is replayed through the table's position servo. A cubic spline of
  θ(t) gives ω and α; inverse dynamics (``mj_inverse``) gives the joint torque that produces
  that motion and the servo command that delivers it (``u = (τ - b0 - b1·θ - b2·ω) / gain``,
  the actuator's affine law), so the simulated table follows the measured encoder instead of
  lagging behind it (commanding the servo with the measured angle itself would add the servo
  lag, ≈ 0.014 rad at 20 s/rev, a spurious tilt offset). The physics runs at the model
  timestep; the sensors are read at the measured sample times. The largest encoder
  difference between replay and data is reported (``replay.tracking_error``).

Noise model of the "after" gap: the extended model's noise variance (``noise_level`` if
named, else the stated one); with ``quantization`` the mean and variance of the rounded
reading are those of ``Q(μ + v)``, v ~ N(0, σ²); with ``bias_random_walk`` the residuals are
whitened by a Kalman filter (state: the walking bias) and its normalized innovations are
measured.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import mujoco
import mujoco.rollout
import numpy as np
from scipy.interpolate import CubicSpline

from bench.effects import CATALOG, EffectSpec, apply_to_model
from bench.model import (
    ACC_SENSORS,
    ENCODER,
    TableEdits,
    edit_tilt_table,
    full_state,
    load_spec,
    sensor_slice,
    tilt_table,
)
from bench.sensors import AxisErrors, SensorContext, SensorErrorModel
from bench.tilt import static_readings
from calib.conventions import AXES
from calib.gap import quantized_moments

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from calib.gap import GapAnalysis
    from calib.io import Ensayo

PathLike = str | os.PathLike

ReplayMode = Literal["static", "sweep"]

MAX_SWEEP_STEP = 0.5
"""rad: a larger jump between consecutive samples means held positions, not a sweep."""

HELD_FRACTION = 0.01
"""A run whose consecutive samples repeat θ more often than this is treated as static."""

MAX_REPLAY_STEPS = 2_000_000
"""Longest servo replay (physics steps, ≈ 2000 s at 1 kHz); longer runs use static poses,
which give the same readings for sites on the hinge axis (only a lever arm differs)."""

SYSID_EFFECTS = ("misalignment", "tilt_offset", "lever_arm")
"""Physical effects whose parameters are refined by re-simulation with ``mujoco.sysid``."""

FD_STEP = 1e-4
"""Finite-difference step of the sysid Jacobian (rad or m, relative above 1). Smaller steps
fall inside MuJoCo's compile-time "same frame" tolerance: a site rotated or moved by less
than ~1e-6 from its body frame is compiled as the body frame, so its reading does not move."""


def _progress(msg: str, quiet: bool) -> None:
    if not quiet:
        print(f"[gap] {msg}", file=sys.stderr, flush=True)


# --------------------------------------------------------------------------- replay

@dataclass(frozen=True)
class Replay:
    """A measured experiment as the bench re-runs it.

    Attributes
    ----------
    mode : "static" (distinct poses) or "sweep" (servo replay of θ(t)).
    tita : (N,) measured encoder angle, rad.  t : (N,) sample times, s, or None.
    reason : why this mode was chosen (for the report).
    control : sweep: (S,) servo command at the physics steps ``t[0] + j·dt``, rad.
    qvel0 : sweep: initial joint velocity, rad/s (spline derivative at t[0]).
    rows, weights : sweep: sample k is ``(1 - w_k)·step[rows_k] + w_k·step[rows_k + 1]``.
    """

    mode: ReplayMode
    tita: np.ndarray
    t: np.ndarray | None
    reason: str
    control: np.ndarray | None = None
    qvel0: float = 0.0
    rows: np.ndarray | None = None
    weights: np.ndarray | None = None

    @property
    def n(self) -> int:
        return int(self.tita.shape[0])

    @property
    def nstep(self) -> int:
        return 0 if self.control is None else int(self.control.shape[0])


def timing(ensayo_t: np.ndarray | None, n: int, rate: float | None) -> np.ndarray | None:
    """Sample times: the file's ``t`` or ``k / rate`` (samples in time order), else None."""
    if ensayo_t is not None:
        return np.asarray(ensayo_t, dtype=float)
    if rate is not None:
        if not np.isfinite(rate) or rate <= 0:
            raise ValueError(f"--rate must be a positive sample rate in Hz, got {rate}")
        return np.arange(n, dtype=float) / float(rate)
    return None


def _servo_command(model: mujoco.MjModel, theta: np.ndarray, omega: np.ndarray,
                   alpha: np.ndarray) -> np.ndarray:
    """Servo command giving joint motion (θ, ω, α): inverse dynamics + the actuator law."""
    data = mujoco.MjData(model)
    gain = float(model.actuator_gainprm[0, 0])
    b0, b1, b2 = (float(v) for v in model.actuator_biasprm[0, :3])
    tau = np.empty_like(theta)
    for j in range(theta.size):  # mj_inverse ≈ 3 µs per step
        data.qpos[0], data.qvel[0], data.qacc[0] = theta[j], omega[j], alpha[j]
        mujoco.mj_inverse(model, data)
        tau[j] = data.qfrc_inverse[0]
    return (tau - b0 - b1 * theta - b2 * omega) / gain


def make_replay(tita: np.ndarray, t: np.ndarray | None) -> Replay:
    """Decide how to re-run the measured experiment and prepare the servo replay.

    Static when there is no timing, when θ is held (more than :data:`HELD_FRACTION` of the
    consecutive samples repeat θ) or jumps (> :data:`MAX_SWEEP_STEP` rad between samples);
    otherwise a servo replay of θ(t) (see the module docstring).
    """
    tita = np.asarray(tita, dtype=float)
    if t is None:
        return Replay("static", tita, None, "no sample times: static poses")
    t = np.asarray(t, dtype=float)
    step = np.abs(np.diff(tita))
    if step.size == 0 or np.mean(step < 1e-12) > HELD_FRACTION:
        return Replay("static", tita, t, "θ held at discrete positions: static poses")
    if step.max() > MAX_SWEEP_STEP:
        return Replay("static", tita, t, f"θ jumps by up to {step.max():.3g} rad between "
                      "samples: static poses")
    model, _ = tilt_table()
    dt = float(model.opt.timestep)
    if (t[-1] - t[0]) / dt > MAX_REPLAY_STEPS:
        return Replay("static", tita, t, f"run of {t[-1] - t[0]:.4g} s exceeds the servo "
                      f"replay limit ({MAX_REPLAY_STEPS} steps): static poses")
    pos = (t - t[0]) / dt
    rows = np.floor(pos + 1e-7).astype(int)
    weights = np.clip(pos - rows, 0.0, 1.0)
    weights[weights < 1e-7] = 0.0
    nstep = int(rows[-1]) + 2
    step_t = t[0] + dt * np.arange(nstep)
    spline = CubicSpline(t, tita)
    ts = np.minimum(step_t, t[-1])
    control = _servo_command(model, spline(ts), spline(ts, 1), spline(ts, 2))
    return Replay("sweep", tita, t, "sample times and continuous θ: servo replay of the "
                  "measured encoder angle", control=control, qvel0=float(spline(t[0], 1)),
                  rows=rows, weights=weights)


def _accel_columns(model: mujoco.MjModel) -> list[int]:
    """sensordata columns of the sensitive axes (site +x) of the x and y accelerometers."""
    return [sensor_slice(model, ACC_SENSORS[a]).start for a in AXES]


def initial_state(model: mujoco.MjModel, replay: Replay) -> np.ndarray:
    """Full-physics state at the first sample of a sweep replay (θ0, ω0)."""
    data = mujoco.MjData(model)
    data.qpos[0] = replay.tita[0]
    data.qvel[0] = replay.qvel0
    return full_state(model, data)


def sample_rows(replay: Replay, per_step: np.ndarray) -> np.ndarray:
    """Per-step values (S, ...) at the measured sample times (linear between steps)."""
    lo = per_step[replay.rows]
    hi = per_step[np.minimum(replay.rows + 1, per_step.shape[0] - 1)]
    w = replay.weights.reshape((-1,) + (1,) * (per_step.ndim - 1))
    return np.where(w == 0.0, lo, (1.0 - w) * lo + w * hi)


def simulate(replay: Replay, table: TableEdits | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
    """Bench readings of the replayed experiment: true specific force (N, 2), encoder (N,)."""
    if replay.mode == "static":
        return static_readings(replay.tita, table)
    model, _ = tilt_table(table)
    data = mujoco.MjData(model)
    state0 = initial_state(model, replay)
    _, sd = mujoco.rollout.rollout(model, data, state0[None, :],
                                   replay.control.reshape(1, -1, 1), nstep=replay.nstep)
    rows = sample_rows(replay, sd[0])
    enc = sensor_slice(model, ENCODER).start
    return rows[:, _accel_columns(model)], rows[:, enc]


# ------------------------------------------------------------------ extended sensor model

def response(a_phys: np.ndarray, t: np.ndarray | None, sensor: SensorErrorModel,
             k: int) -> np.ndarray:
    """Deterministic response-stage signal of axis ``k`` (before scale and bias), m/s².

    Applies the axis' response terms (``lowpass_lag``, ``nonlinearity_k2``, ``cross_axis``) to
    the bench's true specific force; no noise.
    """
    err = sensor.axis(AXES[k])
    ctx = SensorContext(a_phys, t, k)
    a = np.array(a_phys[:, k], dtype=float)
    rng = np.random.default_rng(0)  # response terms are deterministic; never drawn from
    for term in err.terms:
        if term.stage == "response":
            a = term.apply(a, ctx, rng)
    return a


def additive_output(n: int, t: np.ndarray | None, sensor: SensorErrorModel, k: int
                    ) -> np.ndarray:
    """Deterministic additive output terms of axis ``k`` (``bias_drift``), m/s² (N,)."""
    out = np.zeros(n)
    ctx = SensorContext(np.zeros((n, 2)), t, k)
    for term in sensor.axis(AXES[k]).terms:
        if term.name == "bias_drift":
            out = term.apply(out, ctx, np.random.default_rng(0))
    return out


def _term(sensor: SensorErrorModel, k: int, name: str) -> Any:
    """The term ``name`` of axis ``k`` (None if absent)."""
    return next((t for t in sensor.axis(AXES[k]).terms if t.name == name), None)


def fit_bias_scale(y: np.ndarray, x: np.ndarray) -> tuple[float, float, np.ndarray]:
    """Least squares ``y ≈ bias + (1 + scale)·x``; returns (bias, scale, residual y - fit)."""
    xc = x - x.mean()
    sxx = float(xc @ xc)
    gain = float(xc @ (y - y.mean()) / sxx) if sxx > 0 else 1.0
    bias = float(y.mean() - gain * x.mean())
    return bias, gain - 1.0, y - (bias + gain * x)


def kalman_innovations(r: np.ndarray, t: np.ndarray | None, sigma2: float, q: float,
                       per_second: bool) -> np.ndarray:
    """Normalized innovations of ``r_k = b_k + v_k``, ``b`` a random walk (q), v ~ N(0, σ²).

    The walk starts from a diffuse prior (variance 1e6·σ²), so the first innovation carries no
    information about the model; under the model the innovations ``e_k / √S_k`` are i.i.d.
    N(0, 1). Returned scaled by σ, so they read as residuals with the stated variance.
    """
    n = r.shape[0]
    dt = np.diff(t) if (per_second and t is not None) else np.ones(max(n - 1, 0))
    qk = np.concatenate([[0.0], q * q * dt])
    b, p = 0.0, 1e6 * sigma2
    out = np.empty(n)
    for k in range(n):
        p = p + qk[k]
        s = p + sigma2
        e = r[k] - b
        out[k] = e / np.sqrt(s)
        gain = p / s
        b = b + gain * e
        p = (1.0 - gain) * p
    return out * np.sqrt(sigma2)


@dataclass(frozen=True)
class AxisPrediction:
    """The extended model's prediction of one axis, and the residual to measure.

    bias, scale : refitted nominal parameters.  mean : (N,) predicted mean reading, m/s².
    residual : (N,) data − mean, whitened where the model's noise is not white (random walk:
    Kalman innovations; quantization: scaled by σ/√Var), m/s².  sigma2 : the noise variance
    the residual is to be measured with, (m/s²)².
    """

    bias: float
    scale: float
    mean: np.ndarray
    residual: np.ndarray
    sigma2: float


def predict_axis(y: np.ndarray, a_phys: np.ndarray, t: np.ndarray | None,
                 sensor: SensorErrorModel, k: int, sigma2: float) -> AxisPrediction:
    """Fit bias and scale of axis ``k`` on the extended simulation and build the residual.

    Model: ``y = Q(bias + (1 + scale)·resp(a_phys) + drift + walk + v)`` with the axis'
    terms in ``sensor`` (zero noise); ``sigma2`` is the axis' white-noise variance.
    """
    n = y.shape[0]
    x = response(a_phys, t, sensor, k)
    drift = additive_output(n, t, sensor, k)
    bias, scale, _ = fit_bias_scale(y - drift, x)
    mean = bias + (1.0 + scale) * x + drift
    var = np.full(n, sigma2)
    quant = _term(sensor, k, "quantization")
    if quant is not None:
        mean, var = quantized_moments(mean, sigma2, quant.lsb)
    r = y - mean
    walk = _term(sensor, k, "bias_random_walk")
    if walk is not None:
        per_second = walk.q is not None
        q = walk.q if per_second else walk.q_per_sample
        r = kalman_innovations(r, t, float(np.mean(var)), q, per_second)
        var = np.full(n, float(np.mean(var)))
    scale_to = float(np.mean(var))
    if np.any(var != scale_to):
        r = r * np.sqrt(scale_to / np.maximum(var, 1e-300))
    return AxisPrediction(bias, scale, mean, r, scale_to)


# ------------------------------------------------------------------- mujoco.sysid refine

def _param_name(effect: EffectSpec) -> str:
    return f"{effect.name}_{effect.axis}"


def _table_with(table: TableEdits, effects: Sequence[EffectSpec], values: dict[str, np.ndarray]
                ) -> TableEdits:
    """``table`` with the physical parameters of ``effects`` set from ``values``."""
    mis, lever = list(table.misalignment), [tuple(p) for p in table.lever_arm]
    offset = table.tilt_offset
    for e in effects:
        v = np.atleast_1d(values[_param_name(e)]).astype(float)
        if e.name == "tilt_offset":
            offset = float(v[0])
        for a in e.axes if e.name != "tilt_offset" else ():
            k = AXES.index(a)
            if e.name == "misalignment":
                mis[k] = float(v[0])
            elif e.name == "lever_arm":
                lever[k] = (float(v[0]), float(v[1]))
    return replace(table, misalignment=tuple(mis), tilt_offset=offset, lever_arm=tuple(lever))


def _nominal_vector(e: EffectSpec) -> np.ndarray:
    if e.name == "lever_arm":
        return np.array([e.params.get("pos_x", 0.0), e.params.get("pos_z", 0.0)])
    return np.array([e.params["delta"]])


def _effect_params(e: EffectSpec, v: np.ndarray) -> dict[str, float]:
    if e.name == "lever_arm":
        return {"pos_x": float(v[0]), "pos_z": float(v[1])}
    return {"delta": float(v[0])}


def _static_rollout(*, models: Sequence[mujoco.MjModel], datas: Sequence[mujoco.MjData],
                    control_signal: Sequence[Any], initial_states: Sequence[np.ndarray],
                    param_dicts: Any = None, rollout_signal_mapping: Any = None,
                    rollout_state_mapping: Any = None, ctrl_mapping: Any = None) -> list:
    """``mujoco.sysid`` custom rollout for static poses: one batched ``nstep = 1`` rollout.

    The "control" of a static run is its list of distinct poses (θ, rad); each pose starts at
    rest with the servo target on it (no torque), so the sensors are the ``mj_forward``
    reading at that pose — what :func:`bench.tilt.static_readings` does.
    """
    import mujoco.sysid as sysid

    out = []
    for model, ctrl, s0 in zip(models, control_signal, initial_states, strict=True):
        poses = np.asarray(ctrl.data[:, 0], dtype=float)
        state0 = np.tile(np.asarray(s0, dtype=float), (poses.size, 1))
        state0[:, 1] = poses  # mjSTATE_FULLPHYSICS: [time, qpos, ...]
        state, sd = mujoco.rollout.rollout(model, list(datas), state0, poses.reshape(-1, 1, 1),
                                           nstep=1)
        state = state[:, 0, :].copy()
        state[:, 0] = ctrl.times  # poses are not in time: index them by pose number
        out.append(sysid.SystemTrajectory(
            model=model, control=ctrl,
            sensordata=sysid.TimeSeries(ctrl.times, sd[:, 0, :], rollout_signal_mapping),
            initial_state=np.asarray(s0, dtype=float),
            state=sysid.TimeSeries(ctrl.times, state, rollout_state_mapping)))
    return out


def sysid_refine(effects: Sequence[EffectSpec], replay: Replay, datos: np.ndarray,
                 sigma2: np.ndarray, table: TableEdits, sensor: SensorErrorModel,
                 max_iters: int = 50, xtol: float = 1e-3) -> dict[int, dict]:
    """Refine the physical effects by re-simulation with ``mujoco.sysid``.

    Parameters
    ----------
    effects : the extension (catalog effects with starting values, e.g. from ``calib``).
    replay : the re-run experiment.  datos : (N, 2) measured readings, m/s².
    sigma2 : (2,) noise variances of the residual weights, (m/s²)².
    table, sensor : the extended model (physical edits, sensor terms) the fit starts from.

    Returns
    -------
    dict
        effect index → ``{"params", "std", "ci95_halfwidth", "bias", "scale", "iterations",
        "cost_start", "cost_end", "method"}`` for every effect in :data:`SYSID_EFFECTS`.

    Notes
    -----
    One ``mujoco.sysid`` problem: a ``Parameter`` per physical effect (δ of a misalignment or
    tilt offset, rad; (pos_x, pos_z) of a lever arm, m); the model is rebuilt for each
    candidate by editing a copy of the spec with :func:`bench.model.edit_tilt_table` (the
    ``build_model`` hook); rollouts are ``sysid_rollout`` (sweep: the servo replay) or a
    batched static-pose rollout (``custom_rollout``); the residual (``modify_residual``) is
    ``(data - bias - (1 + scale)·resp(a_sim) - drift) / σ`` on the affected axes, with bias
    and scale solved linearly for every candidate (variable projection), so the optimizer
    (``sysid.optimize``, Gauss-Newton with finite-difference Jacobians) sees only the
    physical parameters. Intervals: ``sysid.calculate_intervals`` at the optimum.
    """
    import mujoco.sysid as sysid
    from absl import logging as absl_logging

    targets = [(i, e) for i, e in enumerate(effects) if e.name in SYSID_EFFECTS]
    if not targets:
        return {}
    target_effects = [e for _, e in targets]
    axes_k = sorted({AXES.index(a) for e in target_effects for a in e.axes})
    params = sysid.ParameterDict()
    for e in target_effects:
        v = _nominal_vector(e)
        bound = 2.0 if e.name == "lever_arm" else 0.5  # m / rad: far outside any bench
        params.add(sysid.Parameter(_param_name(e), v, np.full_like(v, -bound),
                                   np.full_like(v, bound)))

    spec0 = load_spec()
    edit_tilt_table(spec0, replace(table, misalignment=(0.0, 0.0), tilt_offset=0.0,
                                   lever_arm=((0.0, 0.0), (0.0, 0.0))))
    pristine = load_spec()

    def build_model(p: Any, spec: mujoco.MjSpec) -> mujoco.MjModel:
        s = pristine.copy()
        edit_tilt_table(s, _table_with(table, target_effects,
                                       {k: p[k].value for k in p.keys()}))
        return s.compile()

    model0 = spec0.compile()
    cols = _accel_columns(model0)
    sigma = np.sqrt(np.asarray(sigma2, dtype=float))
    drifts = {k: additive_output(replay.n, replay.t, sensor, k) for k in axes_k}
    nsd = model0.nsensordata
    measured_full = np.zeros((replay.n, nsd))
    measured_full[:, cols] = datos
    mapping = sysid.TimeSeries.compute_all_sensor_mapping(model0)
    s0 = full_state(model0, mujoco.MjData(model0))
    if replay.mode == "static":
        poses, inverse = np.unique(replay.tita, return_inverse=True)
        control = sysid.TimeSeries(np.arange(poses.size, dtype=float), poses.reshape(-1, 1))
        meas = sysid.TimeSeries(np.arange(replay.n, dtype=float), measured_full, mapping)
        custom = _static_rollout

        def at_samples(pred: np.ndarray) -> np.ndarray:
            return pred[inverse]
    else:
        dt = float(model0.opt.timestep)
        u = np.append(replay.control, replay.control[-1])  # sysid drops the last control
        control = sysid.TimeSeries(replay.t[0] + dt * np.arange(u.size), u.reshape(-1, 1))
        meas = sysid.TimeSeries(np.asarray(replay.t, dtype=float), measured_full, mapping)
        s0 = initial_state(model0, replay)
        custom = None

        def at_samples(pred: np.ndarray) -> np.ndarray:
            return sample_rows(replay, pred)

    projections: dict[int, tuple[float, float]] = {}

    def modify_residual(p: Any, pred_ts: Any, meas_ts: Any, model: mujoco.MjModel,
                        return_pred_all: bool = False, **_: Any) -> tuple:
        a_sim = at_samples(np.asarray(pred_ts.data))[:, cols]
        res = []
        pred_full = np.zeros_like(measured_full)
        for k in axes_k:
            x = response(a_sim, replay.t, sensor, k)
            bias, scale, r = fit_bias_scale(datos[:, k] - drifts[k], x)
            projections[k] = (bias, scale)
            pred_full[:, cols[k]] = datos[:, k] - r
            res.append(r / sigma[k])
        return (np.concatenate(res), sysid.TimeSeries(meas_ts.times, pred_full, mapping),
                meas_ts)

    seq = sysid.ModelSequences("tilt_table", pristine.copy(), "replay", s0, control, meas)
    residual_fn = sysid.build_residual_fn(models_sequences=[seq], build_model=build_model,
                                          modify_residual=modify_residual,
                                          custom_rollout=custom, resample_true=False,
                                          n_threads=2)

    def cost(x: np.ndarray) -> float:
        r = np.concatenate(residual_fn(x, params.copy())[0])
        return float(r @ r)

    old = absl_logging.get_verbosity()
    absl_logging.set_verbosity(absl_logging.ERROR)
    try:
        x0 = params.as_vector()
        cost_start = cost(x0)
        log = io.StringIO()  # the backend prints its iterations; keep stdout clean
        with contextlib.redirect_stdout(log):
            opt, result = sysid.optimize(params, residual_fn, optimizer="mujoco", verbose=False,
                                         max_iters=max_iters, xtol=xtol, eps=FD_STEP)
        xs = opt.as_vector()
        r_star = residual_fn(xs, opt)[0]
        jac = _jacobian(residual_fn, opt, xs)
        cov, half = sysid.calculate_intervals(r_star, jac, alpha=0.05)
    finally:
        absl_logging.set_verbosity(old)
    r_all = np.concatenate(r_star)
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    out: dict[int, dict] = {}
    at = 0
    for i, e in targets:
        size = _nominal_vector(e).size
        sl = slice(at, at + size)
        at += size
        names = list(_effect_params(e, xs[sl]))
        out[i] = {
            "method": "mujoco.sysid: re-simulation (Gauss-Newton, finite differences), "
                      "bias/scale projected out",
            "params": _effect_params(e, xs[sl]),
            "std": dict(zip(names, (float(s) for s in std[sl]), strict=True)),
            "ci95_halfwidth": dict(zip(names, (float(h) for h in half[sl]), strict=True)),
            "bias": {AXES[k]: projections[k][0] for k in axes_k},
            "scale": {AXES[k]: projections[k][1] for k in axes_k},
            "cost_start": cost_start, "cost_end": float(r_all @ r_all),
            "n_residuals": int(r_all.size),
            "iterations": int(len(result.extras.get("objective", []))) or None,
        }
    return out


def _jacobian(residual_fn: Callable, params: Any, x: np.ndarray) -> np.ndarray:
    """Central-difference Jacobian of the sysid residual at ``x`` (one batched rollout)."""
    h = FD_STEP * np.maximum(1.0, np.abs(x))
    cols = np.concatenate([x[:, None] + np.diag(h), x[:, None] - np.diag(h)], axis=1)
    r = residual_fn(cols, params.copy())[0]
    r = np.concatenate(r, axis=0) if isinstance(r, list) else r
    n = x.size
    return (r[:, :n] - r[:, n:]) / (2.0 * h)


# ---------------------------------------------------------------------------- workflow

def _effect_spec(est: Any) -> EffectSpec:
    """Catalog :class:`EffectSpec` of a ``calib.gap`` effect estimate (name, axis, params)."""
    return EffectSpec(str(est.name), str(est.axis), {k: float(v) for k, v in
                                                     dict(est.params).items()})


def _axis_count(effects: Sequence[EffectSpec], k: int) -> int:
    """Number of effect parameters fitted on axis ``k`` (for the χ² degrees of freedom)."""
    return sum(len(e.params) for e in effects if AXES[k] in e.axes
               and e.name != "gravity_mismatch")


@dataclass(frozen=True)
class GapReport:
    """Result of :func:`run_gap`: the named effects and the gap before / after, per axis.

    Attributes
    ----------
    analysis : the ``calib.gap.GapAnalysis`` (detection, estimates, not identifiable).
    effects : the effects added to the bench model, with the parameters used there (sysid
        refinement for physical ones when it converged, else the ``calib`` estimate).
    sysid : effect index → ``mujoco.sysid`` refinement (:func:`sysid_refine`).
    replay : how the experiment was re-run.  tracking_error : max |θ_sim - θ_data|, rad.
    noise_var : (2,) stated noise variances, (m/s²)².  g : gravity used, m/s².
    timing : "t" (file), "rate" (``--rate``) or "none".
    nominal : axis → (bias, scale) fitted on the nominal simulation.
    after : axis → :class:`AxisPrediction` of the extended simulation.
    table_after : the physical edits of the extended model.
    sensor_after : the extended sensor model (terms, no noise, fitted bias/scale).
    gap_before, gap_after : axis → ``GapMeasure`` (data vs nominal / extended simulation).
    residual_before, residual_after : (N, 2), m/s² (after: whitened where the extended
        noise model is not white, see :func:`predict_axis`).
    family_alpha : family-wise level of "consistent with noise".
    files : name → path of the written outputs.
    """

    analysis: GapAnalysis
    effects: tuple[EffectSpec, ...]
    sysid: dict
    replay: Replay
    tracking_error: float
    noise_var: np.ndarray
    g: float
    timing: str
    nominal: dict
    after: dict
    table_after: TableEdits
    sensor_after: SensorErrorModel
    gap_before: dict
    gap_after: dict
    residual_before: np.ndarray
    residual_after: np.ndarray
    family_alpha: float
    files: dict = field(default_factory=dict)

    def consistent(self, which: str = "after") -> dict[str, bool]:
        """Per axis: is the gap (``"before"`` or ``"after"``) consistent with noise alone?"""
        gaps = self.gap_after if which == "after" else self.gap_before
        return {a: bool(gaps[a].consistent(self.family_alpha)) for a in AXES}

    def needs_timing(self) -> list[str]:
        """Catalog effects that need timing and were not tested because the data have none
        (empty when timing is known)."""
        skipped = getattr(self.analysis, "needs_timing", None)
        if skipped is not None:
            return list(skipped)
        if self.timing != "none":
            return []
        return [n for n, e in CATALOG.items() if e.timing == "yes"]

    def to_dict(self) -> dict:
        """The ``tiltbench gap --json`` object (documented keys first; extras allowed)."""
        a = self.analysis.to_dict()
        effects = []
        for i, e in enumerate(a.get("effects", [])):
            d = dict(e)
            d["timing"] = CATALOG[d["name"]].timing if d["name"] in CATALOG else "no"
            if i in self.sysid:
                d["sysid"] = self.sysid[i]
            if i < len(self.effects):
                d["used_in_model"] = dict(self.effects[i].params)
            effects.append(d)
        before = {ax: self.gap_before[ax].to_dict() for ax in AXES}
        after = {ax: self.gap_after[ax].to_dict() for ax in AXES}
        for ax in AXES:
            before[ax]["consistent"] = bool(self.gap_before[ax].consistent(self.family_alpha))
            after[ax]["consistent"] = bool(self.gap_after[ax].consistent(self.family_alpha))
            before[ax]["details"] = self.gap_before[ax].details()
            after[ax]["details"] = self.gap_after[ax].details()
        return {
            "effects": effects,
            "not_identifiable": a.get("not_identifiable", []),
            "gap_before": before,
            "gap_after": after,
            "needs_timing": self.needs_timing(),
            "timing": self.timing,
            "consistent_after": all(self.consistent("after").values()),
            "family_alpha": self.family_alpha,
            "g": self.g,
            "noise_var": [float(v) for v in self.noise_var],
            "replay": {"mode": self.replay.mode, "reason": self.replay.reason,
                       "tracking_error_rad": self.tracking_error},
            "nominal": {ax: {"bias": b, "scale": s} for ax, (b, s) in self.nominal.items()},
            "model_after": {
                "table": {"g": self.table_after.g,
                          "misalignment": list(self.table_after.misalignment),
                          "tilt_offset": self.table_after.tilt_offset,
                          "lever_arm": [list(p) for p in self.table_after.lever_arm],
                          "cutoff": list(self.table_after.cutoff)},
                "sensor": self.sensor_after.to_dict(),
            },
            "analysis": {k: v for k, v in a.items()
                         if k not in ("effects", "not_identifiable")},
            "files": dict(self.files),
        }

    def summary(self) -> str:
        """A readable report (what ``tiltbench gap`` prints without ``--json``)."""
        out = [f"Discrepancy workflow (gap): N = {self.replay.n}, g = {self.g} m/s², "
               f"stated σ² = {self.noise_var[0]:g}, {self.noise_var[1]:g} (m/s²)²",
               f"replay: {self.replay.mode} ({self.replay.reason}); timing: {self.timing}"]
        if self.replay.mode == "sweep":
            out.append(f"  replay tracks the measured encoder to {self.tracking_error:.2g} rad")
        d = self.to_dict()
        if not d["effects"]:
            out.append("effects named: none — nothing is missing from the model")
        else:
            out.append("effects named:")
            for e in d["effects"]:
                params = ", ".join(f"{k} = {v:.6g} ± {e['std'].get(k, float('nan')):.2g}"
                                   for k, v in e["params"].items())
                out.append(f"  {e['name']} ({e['axis']}): {params}; statistic "
                           f"{e['statistic']:.4g}, p = {e['p_value']:.3g}"
                           + ("" if e["timing"] == "no" else f" [timing: {e['timing']}]"))
                if "sysid" in e:
                    s = e["sysid"]
                    sp = ", ".join(f"{k} = {v:.6g} ± {s['std'][k]:.2g}"
                                   for k, v in s["params"].items())
                    out.append(f"      mujoco.sysid re-simulation: {sp}")
        for item in d["not_identifiable"]:
            out.append(f"not identifiable: {', '.join(item['names'])} — {item['reason']}")
        if d["needs_timing"]:
            out.append("not testable without timing (give t in the file or --rate): "
                       + ", ".join(d["needs_timing"])
                       + "; bias_drift / bias_random_walk are reported per sample")
        out.append(f"gap (χ²/dof with the stated noise; max signature z; consistent at "
                   f"family α = {self.family_alpha}):")
        for ax in AXES:
            b, a = self.gap_before[ax], self.gap_after[ax]
            out.append(f"  {ax}: before χ²/dof = {b.chi2_dof:.4f}, max z = "
                       f"{b.max_signature_z:.2f} ({b.worst}) "
                       f"{'consistent' if b.consistent(self.family_alpha) else 'GAP'}"
                       f" | after χ²/dof = {a.chi2_dof:.4f}, max z = {a.max_signature_z:.2f}"
                       f" ({a.worst}) "
                       f"{'consistent' if a.consistent(self.family_alpha) else 'GAP'}")
        for name, path in self.files.items():
            out.append(f"{name}: {path}")
        return "\n".join(out)


def run_gap(ensayo: Ensayo, noise_var: Sequence[float] | np.ndarray, g: float = 9.8,
            rate: float | None = None, report_dir: PathLike | None = None,
            rrd: PathLike | None = None, force: bool = False, *,
            family_alpha: float = 0.005, progress: bool = False) -> GapReport:
    """Run the discrepancy workflow on a measured calibration run.

    Parameters
    ----------
    ensayo : :class:`calib.io.Ensayo` (θ rad, readings m/s², optional t s; time order).
    noise_var : (2,) stated noise variances [σx², σy²], (m/s²)².
    g : gravity, m/s².  rate : sample rate, Hz, of a run without ``t`` (samples in time order).
    report_dir : write ``gap.json``, ``gap.md``, ``gap.png``, ``gap.svg`` and
        ``model_after.xml`` there (refuses to overwrite unless ``force``).
    rrd : write a rerun recording there.
    family_alpha : family-wise level of the detection and of "consistent with noise".
    progress : print progress on stderr.

    Returns
    -------
    GapReport
    """
    from calib.diagnostics import gap_measure
    from calib.gap import analyze_gap

    quiet = not progress
    noise_var = np.asarray(noise_var, dtype=float).reshape(-1)
    if noise_var.shape != (2,) or np.any(~np.isfinite(noise_var)) or np.any(noise_var <= 0):
        raise ValueError(f"noise_var must be two positive variances (x, y), got {noise_var}")
    if report_dir is not None and not force:
        _check_outputs(report_dir, rrd)
    elif rrd is not None and not force and _exists(rrd):
        raise FileExistsError(f"{rrd}: exists; pass --force to overwrite")
    t = timing(ensayo.t, ensayo.n, rate)
    timing_src = "t" if ensayo.t is not None else ("rate" if rate is not None else "none")
    datos = np.asarray(ensayo.datos, dtype=float)
    tita = np.asarray(ensayo.tita, dtype=float)

    clock = time.perf_counter()
    _progress(f"analysing {ensayo.n} samples (calib.gap)…", quiet)
    analysis = analyze_gap(ensayo, noise_var, g=g, rate=rate, family_alpha=family_alpha)
    _progress(f"analysis done in {time.perf_counter() - clock:.1f} s", quiet)

    clock = time.perf_counter()
    replay = make_replay(tita, t)
    base = TableEdits(g=g)
    a_nom, enc = simulate(replay, base)
    tracking = float(np.max(np.abs(enc - tita))) if replay.mode == "sweep" else 0.0
    nominal, res_before, gap_before = {}, np.empty_like(datos), {}
    for k, ax in enumerate(AXES):
        bias, scale, r = fit_bias_scale(datos[:, k], a_nom[:, k])
        nominal[ax] = (bias, scale)
        res_before[:, k] = r
        gap_before[ax] = gap_measure(r, tita, float(noise_var[k]), t,
                                     other_ref=a_nom[:, 1 - k], own_ref=a_nom[:, k],
                                     readings=datos[:, k], n_params=2)
    _progress(f"nominal re-simulation ({replay.mode}) in {time.perf_counter() - clock:.1f} s",
              quiet)

    effects = [_effect_spec(e) for e in analysis.effects]
    sensor0 = SensorErrorModel.from_pairs((0.0, 0.0), (0.0, 0.0), (0.0, 0.0))
    table_after, sensor_after = apply_to_model(
        [e for e in effects if e.name != "gravity_mismatch"], base, sensor0)
    sysid_out: dict[int, dict] = {}
    if any(e.name in SYSID_EFFECTS for e in effects):
        clock = time.perf_counter()
        _progress("refining physical effects by re-simulation (mujoco.sysid)…", quiet)
        sigma2 = np.array([sensor_after.axis(a).noise_var or noise_var[k]
                           for k, a in enumerate(AXES)])
        try:
            sysid_out = sysid_refine(effects, replay, datos, sigma2, table_after, sensor_after)
        except Exception as exc:  # the LS estimate stays usable; say why sysid did not run
            sysid_out = {i: {"error": f"{type(exc).__name__}: {exc}"}
                         for i, e in enumerate(effects) if e.name in SYSID_EFFECTS}
        used = list(effects)
        for i, s in sysid_out.items():
            if "params" in s and _sysid_usable(s):
                used[i] = EffectSpec(effects[i].name, effects[i].axis, s["params"])
        effects = used
        table_after, sensor_after = apply_to_model(
            [e for e in effects if e.name != "gravity_mismatch"], base, sensor0)
        _progress(f"sysid done in {time.perf_counter() - clock:.1f} s", quiet)

    clock = time.perf_counter()
    a_ext, _ = simulate(replay, table_after) if effects else (a_nom, enc)
    after, res_after, gap_after = {}, np.empty_like(datos), {}
    axes_after = {}
    for k, ax in enumerate(AXES):
        sigma2_k = sensor_after.axis(ax).noise_var or float(noise_var[k])
        pred = predict_axis(datos[:, k], a_ext, t, sensor_after, k, sigma2_k)
        after[ax] = pred
        res_after[:, k] = pred.residual
        quant = _term(sensor_after, k, "quantization")
        gap_after[ax] = gap_measure(pred.residual, tita, pred.sigma2, t,
                                    other_ref=a_nom[:, 1 - k], own_ref=a_nom[:, k],
                                    readings=datos[:, k],
                                    model_lsb=None if quant is None else quant.lsb,
                                    n_params=2 + _axis_count(effects, k))
        axes_after[ax] = AxisErrors(pred.bias, pred.scale, sigma2_k,
                                    sensor_after.axis(ax).terms)
    sensor_after = SensorErrorModel(axes_after["x"], axes_after["y"])
    _progress(f"extended re-simulation in {time.perf_counter() - clock:.1f} s", quiet)

    report = GapReport(analysis=analysis, effects=tuple(effects), sysid=sysid_out,
                       replay=replay, tracking_error=tracking, noise_var=noise_var, g=float(g),
                       timing=timing_src, nominal=nominal, after=after,
                       table_after=table_after, sensor_after=sensor_after,
                       gap_before=gap_before, gap_after=gap_after,
                       residual_before=res_before, residual_after=res_after,
                       family_alpha=float(family_alpha))
    files: dict[str, str] = {}
    if report_dir is not None or rrd is not None:
        clock = time.perf_counter()
        _progress("writing the report…", quiet)
        if report_dir is not None:
            files.update(write_report(report, report_dir, force=force))
        if rrd is not None:
            files["rrd"] = str(write_recording(report, rrd, force=force))
        _progress(f"report written in {time.perf_counter() - clock:.1f} s", quiet)
    return replace(report, files=files)


def _sysid_usable(s: dict) -> bool:
    """A sysid refinement is used when it lowered the cost and has finite intervals."""
    std = list(s.get("std", {}).values())
    return bool(std) and all(np.isfinite(std)) and s["cost_end"] <= s["cost_start"] + 1e-9


REPORT_FILES = ("gap.json", "gap.md", "gap.png", "gap.svg", "model_after.xml")


def _exists(path: PathLike) -> bool:
    return Path(path).exists()


def _check_outputs(report_dir: PathLike, rrd: PathLike | None) -> None:
    clash = [str(Path(report_dir) / n) for n in REPORT_FILES if (Path(report_dir) / n).exists()]
    if rrd is not None and Path(rrd).exists():
        clash.append(str(rrd))
    if clash:
        raise FileExistsError(f"{', '.join(clash)}: exist(s); pass --force to overwrite")


# ----------------------------------------------------------------------------- outputs

def _effects_label(report: GapReport) -> str:
    if not report.effects:
        return "no effect named"
    return "; ".join(f"{e.name} ({e.axis}): " + ", ".join(f"{k}={v:.4g}"
                                                         for k, v in e.params.items())
                     for e in report.effects)


def gap_figure(report: GapReport) -> Figure:
    """Residuals against θ before and after, per axis, with the ±σ band and binned means.

    Returns a :class:`matplotlib.figure.Figure` (2 × 2: rows x, y; columns before, after).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bench.record import binned_mean

    theta = report.replay.tita
    fig, axs = plt.subplots(2, 2, figsize=(11, 7), sharex=True, constrained_layout=True)
    for k, ax_name in enumerate(AXES):
        for j, (which, res, gaps) in enumerate((
                ("before", report.residual_before, report.gap_before),
                ("after", report.residual_after, report.gap_after))):
            ax = axs[k, j]
            gm = gaps[ax_name]
            sigma = np.sqrt(report.noise_var[k] if which == "before"
                            else report.after[ax_name].sigma2)
            ax.plot(theta, res[:, k], ".", ms=1.5, color=(0.35, 0.55, 0.85) if j else
                    (0.55, 0.55, 0.55), alpha=0.6, rasterized=True, label="data − simulation")
            cx, cy, _ = binned_mean(theta, res[:, k], 72)
            ax.plot(cx, cy, "-", color=(0.85, 0.2, 0.15), lw=1.5, label="binned mean")
            ax.axhspan(-sigma, sigma, color=(0.95, 0.7, 0.2), alpha=0.25, label="±σ")
            for sign in (-1.0, 1.0):
                ax.axhline(sign * sigma, color=(0.85, 0.55, 0.1), lw=1.0, ls="--", zorder=3)
            ax.axhline(0.0, color="k", lw=0.6)
            ok = "consistent" if gm.consistent(report.family_alpha) else "GAP"
            ax.set_title(f"{ax_name}, {which}: χ²/dof = {gm.chi2_dof:.3f}, max z = "
                         f"{gm.max_signature_z:.1f} ({gm.worst}) — {ok}", fontsize=9)
            ax.set_ylabel(f"residual {ax_name}, m/s²")
            if k == 1:
                ax.set_xlabel("θ (encoder), rad")
            if k == 0 and j == 0:
                ax.legend(loc="upper right", fontsize=7, markerscale=4)
    title = _effects_label(report)
    fig.suptitle(f"gap before / after adding: {title}", fontsize=10)
    return fig


def gap_markdown(report: GapReport) -> str:
    """The Markdown report (``gap.md``)."""
    d = report.to_dict()
    lines = ["# Discrepancy workflow (gap)", "",
             f"- samples: {report.replay.n}; g = {report.g} m/s²; stated σ² = "
             f"{report.noise_var[0]:g}, {report.noise_var[1]:g} (m/s²)²",
             f"- timing: {report.timing}; replay: **{report.replay.mode}** — "
             f"{report.replay.reason}"]
    if report.replay.mode == "sweep":
        lines.append(f"- the replay follows the measured encoder to "
                     f"{report.tracking_error:.2g} rad")
    lines += ["", "## Effects named", ""]
    if not d["effects"]:
        lines.append("None: the nominal model (bias, scale) explains the data within the "
                     "noise.")
    else:
        lines += ["| effect | axis | estimate ± std (calib LS) | mujoco.sysid ± std | "
                  "statistic | p | timing |", "|---|---|---|---|---|---|---|"]
        for e in d["effects"]:
            est = "; ".join(f"{k} = {v:.6g} ± {e['std'].get(k, float('nan')):.2g}"
                            for k, v in e["params"].items())
            s = e.get("sysid", {})
            sy = ("; ".join(f"{k} = {v:.6g} ± {s['std'][k]:.2g}"
                            for k, v in s["params"].items()) if "params" in s
                  else s.get("error", "—"))
            lines.append(f"| `{e['name']}` | {e['axis']} | {est} | {sy} | "
                         f"{e['statistic']:.4g} | {e['p_value']:.3g} | {e['timing']} |")
    if d["not_identifiable"]:
        lines += ["", "## Not identifiable", ""]
        lines += [f"- {', '.join(i['names'])}: {i['reason']}" for i in d["not_identifiable"]]
    if d["needs_timing"]:
        lines += ["", "## Needs timing", "",
                  "Not testable without sample times (`t` in the file or `--rate`): "
                  + ", ".join(f"`{n}`" for n in d["needs_timing"])
                  + ". `bias_drift` and `bias_random_walk` are reported per sample."]
    lines += ["", f"## Gap (family α = {report.family_alpha})", "",
              "| axis | χ²/dof before | max z before | χ²/dof after | max z after | "
              "after consistent with noise |", "|---|---|---|---|---|---|"]
    for ax in AXES:
        b, a = report.gap_before[ax], report.gap_after[ax]
        lines.append(f"| {ax} | {b.chi2_dof:.4f} | {b.max_signature_z:.2f} ({b.worst}) | "
                     f"{a.chi2_dof:.4f} | {a.max_signature_z:.2f} ({a.worst}) | "
                     f"{'yes' if a.consistent(report.family_alpha) else 'no'} |")
    lines += ["", "![residuals before and after](gap.png)", "",
              "The edited model is `model_after.xml` (MjSpec edit of models/tilt_table.xml); "
              "sensor terms and fitted bias/scale are in `gap.json` (`model_after`)."]
    return "\n".join(lines) + "\n"


def write_model_after(report: GapReport, path: PathLike, force: bool = False) -> Path:
    """Write the extended model (``MjSpec`` edit of a copy of the tilt table) as MJCF."""
    from calib.io import atomic_write_text

    spec = load_spec()
    edit_tilt_table(spec, report.table_after)
    spec.compile()
    return atomic_write_text(path, spec.to_xml(), force=force)


def write_report(report: GapReport, out_dir: PathLike, force: bool = False) -> dict[str, str]:
    """Write ``gap.json``, ``gap.md``, ``gap.png``, ``gap.svg``, ``model_after.xml``."""
    from bench.dataset import write_json
    from bench.figures import save_figure

    out = Path(out_dir)
    if not force:
        _check_outputs(out, None)
    out.mkdir(parents=True, exist_ok=True)
    files = {"json": str(out / "gap.json"), "markdown": str(out / "gap.md"),
             "png": str(out / "gap.png"), "svg": str(out / "gap.svg"),
             "model_after": str(out / "model_after.xml")}
    write_model_after(report, files["model_after"], force=True)
    save_figure(gap_figure(report), files["png"], force=True)
    save_figure(gap_figure(report), files["svg"], force=True)
    from calib.io import atomic_write_text

    atomic_write_text(files["markdown"], gap_markdown(report), force=True)
    write_json(files["json"], replace(report, files=files).to_dict(), force=True)
    return files


def _recording_blueprint() -> Any:
    """Layout of the gap recording: per axis the residual before (top) and after (bottom)
    adding the named effects, each with its ±σ band and binned mean over the whole θ range,
    and the effects text. ``gap_report/**`` (the JSON tree) is left out of every view."""
    import rerun.blueprint as rrb

    from bench.record import THETA_TIMELINE, full_time_axis, time_panel

    def view(ax: str, which: str) -> Any:
        return rrb.TimeSeriesView(
            origin=f"gap/{ax}", name=f"{ax}: residual {which}, ±σ, binned mean vs θ (µrad), m/s²",
            contents=[f"+ gap/{ax}/residual_{which}", f"+ gap/{ax}/band_{which}/**",
                      f"+ gap/{ax}/mean_{which}"], axis_x=full_time_axis())

    grid = rrb.Horizontal(*(rrb.Vertical(view(ax, "before"), view(ax, "after"))
                            for ax in AXES))
    return rrb.Blueprint(
        rrb.Horizontal(grid, rrb.TextDocumentView(origin="gap/effects", name="effects"),
                       column_shares=[3, 1]),
        time_panel(THETA_TIMELINE), collapse_panels=True)


def _recording_markdown(report: GapReport) -> str:
    """``gap.md`` without its image line (a path relative to the report, broken in a viewer)."""
    import re

    lines = [ln for ln in gap_markdown(report).split("\n") if not ln.startswith("![")]
    return re.sub(r"\n{3,}", "\n\n", "\n".join(lines))


def write_recording(report: GapReport, path: PathLike, force: bool = False) -> Path:
    """Rerun recording: ``gap/{x,y}/residual_before``, ``…/residual_after`` (timelines
    ``sample`` and ``theta_urad``), ``gap/{x,y}/band_{before,after}/{plus,minus}`` (±σ),
    ``gap/{x,y}/mean_{before,after}`` (binned means), ``gap/effects`` (Markdown text) and the
    ``gap --json`` object as a tree under ``gap_report``, with a blueprint (2 × 2 grid)."""
    import rerun as rr

    from bench.record import COLORS, binned_mean, log_series, log_tree, open_recording

    theta = report.replay.tita
    n = theta.size
    index = {"sample": np.arange(n, dtype=np.int64),
             "theta_urad": np.round(theta * 1e6).astype(np.int64)}
    # ±σ bands span the θ range (the first and last samples of an up-then-down sweep share θ)
    ends = {tl: v[[int(np.argmin(theta)), int(np.argmax(theta))]] for tl, v in index.items()}
    with open_recording(path, force=force, blueprint=_recording_blueprint(),
                        name="tiltbench gap") as rec:
        for k, ax in enumerate(AXES):
            for which, res, s2 in (("before", report.residual_before, report.noise_var[k]),
                                   ("after", report.residual_after,
                                    report.after[ax].sigma2)):
                log_series(rec, f"gap/{ax}/residual_{which}", res[:, k], index,
                           style="points", color=COLORS[which], name=f"residual {which}",
                           size=1.0 if n < 10_000 else 0.5)
                for part, sign in (("plus", 1.0), ("minus", -1.0)):
                    log_series(rec, f"gap/{ax}/band_{which}/{part}",
                               np.full(2, sign * np.sqrt(s2)), ends, color=COLORS["band"],
                               name=f"{sign:+.0f}σ {which}")
                th, mean, at = binned_mean(theta, res[:, k], bins=min(100, max(1, n // 80)))
                log_series(rec, f"gap/{ax}/mean_{which}", mean,
                           {"sample": at, "theta_urad": np.round(th * 1e6).astype(np.int64)},
                           color=COLORS["mean"], name=f"binned mean {which}")
        rec.log("gap/effects", rr.TextDocument(_recording_markdown(report),
                                               media_type=rr.MediaType.MARKDOWN), static=True)
        log_tree(rec, "gap_report", report.to_dict())
    return Path(path)

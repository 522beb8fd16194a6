"""Refine the physical effects with ``mujoco.sysid`` on the replayed experiment.

One ``mujoco.sysid`` problem per run (:func:`sysid_refine`), built in steps: the parameters
(:func:`_parameters`), the experiment as sysid sees it (:func:`_experiment`: model, control,
measurements, rollout), the variable-projection residual (:class:`_Projection`), the
optimization with its intervals (:func:`_optimize`) and the per-effect result
(:func:`_results`).

**Rollout.** The physical effects move or turn massless sensor sites: the table moves the
same for every candidate. So the motion is simulated once (:func:`bench.gap.replay.
record_motion`) and each candidate model is read along it by the kinematic readout
(:func:`bench.gap.readout.readout`, ≈ 1 ms for 60 000 samples) instead of re-simulating the
run for every optimizer step (≈ 2 s each at 60 000 samples). At the optimum MuJoCo reads the
fitted model along the same motion (one batched rollout) and the two must agree within
:data:`bench.gap.readout.READOUT_TOL`, the model must move as recorded; otherwise (or for a
sensor the readout does not cover) the fit is redone by re-simulation
(:func:`_replay_rollout`), and the entry's ``method`` and ``check`` say so.

``mujoco.sysid`` (the extra ``mujoco[sysid]``) is imported on first use through
:func:`_sysid`, without its HTML report (≈ 0.2 s instead of ≈ 0.6 s), so importing
:mod:`bench.gap` stays cheap.
"""

from __future__ import annotations

import contextlib
import io
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import mujoco
import mujoco.rollout
import numpy as np

from bench.effects import EffectSpec
from bench.gap.prediction import additive_output, fit_bias_scale, response
from bench.gap.readout import (
    READOUT_TOL,
    AccelField,
    ReadoutUnsupportedError,
    readout,
    readout_error,
    record_field,
)
from bench.gap.replay import (
    MOTION_TOL,
    Replay,
    accel_columns,
    initial_state,
    replay_sensordata,
)
from bench.model import TableEdits, edit_tilt_table, load_spec
from bench.sensors import SensorErrorModel
from calib.conventions import AXES

SYSID_EFFECTS = ("misalignment", "tilt_offset", "lever_arm")
"""Physical effects whose parameters are refined by re-simulation with ``mujoco.sysid``."""

FD_STEP = 1e-4
"""Finite-difference step of the sysid Jacobian (rad or m, relative above 1). Smaller steps
fall inside MuJoCo's compile-time "same frame" tolerance: a site rotated or moved by less
than ~1e-6 from its body frame is compiled as the body frame, so its reading does not move."""

METHOD = ("mujoco.sysid: kinematic readout of the simulated motion, confirmed by MuJoCo "
          "(Gauss-Newton, finite differences), bias/scale projected out")
METHOD_RESIM = ("mujoco.sysid: re-simulation (Gauss-Newton, finite differences), "
                "bias/scale projected out")


SYSID_REPORT = "mujoco.sysid.report.defaults"
"""``mujoco.sysid``'s HTML report (plotly, matplotlib, jinja2): left out of its import."""


def _sysid() -> Any:
    """``mujoco.sysid``, imported on first use (optional extra, slow to import), without its
    HTML report.

    The package's ``__init__`` imports the report last, inside ``try: … except
    ModuleNotFoundError: pass`` (an optional part of the package), and with plotly,
    matplotlib and jinja2 it is ≈ 0.4 s of the ≈ 0.6 s import (GIL-bound, on the gap run's
    main thread); the refinement never writes a report. A ``None`` entry in ``sys.modules``
    makes that one import raise ``ModuleNotFoundError`` (the import system's way to block a
    module), which the package's own ``except`` takes; the entry is removed right after, so
    ``import mujoco.sysid.report.defaults`` still works later. Should a release no longer
    catch it, the package is imported whole.
    """
    if "mujoco.sysid" in sys.modules:
        return sys.modules["mujoco.sysid"]
    blocked = SYSID_REPORT not in sys.modules
    if blocked:
        sys.modules[SYSID_REPORT] = None
    try:
        import mujoco.sysid
    except ModuleNotFoundError as exc:
        if not blocked or exc.name != SYSID_REPORT:
            raise
        del sys.modules[SYSID_REPORT]
        blocked = False
        import mujoco.sysid
    finally:
        if blocked and sys.modules.get(SYSID_REPORT, 0) is None:
            del sys.modules[SYSID_REPORT]
    return mujoco.sysid


def preload_sysid() -> None:
    """Import ``mujoco.sysid`` ahead of its first use (the gap run does it once the analysis
    has named a physical effect, while the nominal re-simulation still runs on its thread:
    the refinement then does not wait for the import)."""
    _sysid()


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


def _split(target_effects: Sequence[EffectSpec], xs: np.ndarray) -> dict[str, np.ndarray]:
    """Parameter name → its slice of the sysid vector ``xs`` (effects in order)."""
    out, at = {}, 0
    for e in target_effects:
        size = _nominal_vector(e).size
        out[_param_name(e)] = xs[at:at + size]
        at += size
    return out


def _effect_params(e: EffectSpec, v: np.ndarray) -> dict[str, float]:
    if e.name == "lever_arm":
        return {"pos_x": float(v[0]), "pos_z": float(v[1])}
    return {"delta": float(v[0])}



def _replay_rollout(replay: Replay) -> Callable:
    """``mujoco.sysid`` custom rollout of the replayed experiment, read at the samples.

    For every candidate model the sensors at the measured samples come from
    :func:`bench.gap.replay.replay_sensordata` — the same static poses / servo replay pieces
    as :func:`bench.gap.replay.simulate` — so the "control" sysid carries is only the
    measured θ per sample.
    """

    def rollout(*, models: Sequence[mujoco.MjModel], datas: Sequence[mujoco.MjData],
                control_signal: Sequence[Any], initial_states: Sequence[np.ndarray],
                param_dicts: Any = None, rollout_signal_mapping: Any = None,
                rollout_state_mapping: Any = None, ctrl_mapping: Any = None) -> list:
        sysid = _sysid()
        sd, state = replay_sensordata(models, replay)
        out = []
        for i, (model, ctrl, s0) in enumerate(zip(models, control_signal, initial_states,
                                                  strict=True)):
            state[i, :, 0] = ctrl.times  # mjSTATE_FULLPHYSICS: [time, qpos, ...]
            out.append(sysid.SystemTrajectory(
                model=model, control=ctrl,
                sensordata=sysid.TimeSeries(ctrl.times, sd[i], rollout_signal_mapping),
                initial_state=np.asarray(s0, dtype=float),
                state=sysid.TimeSeries(ctrl.times, state[i], rollout_state_mapping)))
        return out

    return rollout


def _readout_rollout(field: AccelField) -> Callable:
    """``mujoco.sysid`` custom rollout: each candidate read along the recorded motion by the
    kinematic readout (:func:`bench.gap.readout.readout`); the state is the recorded one."""

    def rollout(*, models: Sequence[mujoco.MjModel], datas: Sequence[mujoco.MjData],
                control_signal: Sequence[Any], initial_states: Sequence[np.ndarray],
                param_dicts: Any = None, rollout_signal_mapping: Any = None,
                rollout_state_mapping: Any = None, ctrl_mapping: Any = None) -> list:
        sysid = _sysid()
        out = []
        for model, ctrl, s0 in zip(models, control_signal, initial_states, strict=True):
            state = field.state.copy()
            state[:, 0] = ctrl.times  # mjSTATE_FULLPHYSICS: [time, qpos, ...]
            out.append(sysid.SystemTrajectory(
                model=model, control=ctrl,
                sensordata=sysid.TimeSeries(ctrl.times, readout(field, model),
                                            rollout_signal_mapping),
                initial_state=np.asarray(s0, dtype=float),
                state=sysid.TimeSeries(ctrl.times, state, rollout_state_mapping)))
        return out

    return rollout


def sysid_refine(effects: Sequence[EffectSpec], replay: Replay, datos: np.ndarray,
                 sigma2: np.ndarray, table: TableEdits, sensor: SensorErrorModel,
                 max_iters: int = 50, xtol: float = 1e-3, *, accel: AccelField | None = None
                 ) -> dict[int, dict]:
    """Refine the physical effects with ``mujoco.sysid`` on the replayed experiment.

    Parameters
    ----------
    effects : the extension (catalog effects with starting values, e.g. from ``calib``).
    replay : the re-run experiment.  datos : (N, 2) measured readings, m/s².
    sigma2 : (2,) noise variances of the residual weights, (m/s²)².
    table, sensor : the extended model (physical edits, sensor terms) the fit starts from.
    accel : the recorded motion's :class:`bench.gap.readout.AccelField` (of ``table``'s
        physics); None: recorded here (one simulation of the replay).

    Returns
    -------
    dict
        effect index → ``{"params", "std", "ci95_halfwidth", "bias", "scale", "iterations",
        "cost_start", "cost_end", "method", "check"}`` for every effect in
        :data:`SYSID_EFFECTS`.

    Notes
    -----
    One ``mujoco.sysid`` problem: a ``Parameter`` per physical effect (δ of a misalignment or
    tilt offset, rad; (pos_x, pos_z) of a lever arm, m); the model is rebuilt for each
    candidate by editing a copy of the spec with :func:`bench.model.edit_tilt_table` (the
    ``build_model`` hook); the rollout (``custom_rollout``) reads each candidate along the
    recorded motion (:func:`_readout_rollout`; module docstring: confirmed by MuJoCo at the
    optimum, else redone by re-simulation, :func:`_replay_rollout`); the residual
    (``modify_residual``) is ``(data - bias - (1 + scale)·resp(a_sim) - drift) / σ`` on the
    affected axes, with bias and scale solved linearly for every candidate (variable
    projection), so the optimizer (``sysid.optimize``, Gauss-Newton with finite-difference
    Jacobians) sees only the physical parameters. Intervals: ``sysid.calculate_intervals``
    at the optimum.
    """
    targets = [(i, e) for i, e in enumerate(effects) if e.name in SYSID_EFFECTS]
    if not targets:
        return {}
    target_effects = [e for _, e in targets]
    axes_k = sorted({AXES.index(a) for e in target_effects for a in e.axes})
    pristine = load_spec()

    def table_at(x: dict[str, np.ndarray]) -> TableEdits:
        return _table_with(table, target_effects, x)

    def build_model(p: Any, spec: mujoco.MjSpec) -> mujoco.MjModel:
        s = pristine.copy()
        edit_tilt_table(s, table_at({k: p[k].value for k in p.keys()}))
        return s.compile()

    def solve(rollout: Callable) -> tuple[_Fit, _Projection]:
        params = _parameters(target_effects)
        exp = _experiment(replay, datos, table)
        projection = _Projection(exp, replay, datos, sensor, axes_k, sigma2)
        sysid = _sysid()
        seq = sysid.ModelSequences("tilt_table", pristine.copy(), "replay", exp.state0,
                                   exp.control, exp.measured)
        residual_fn = sysid.build_residual_fn(models_sequences=[seq], build_model=build_model,
                                              modify_residual=projection.modify_residual,
                                              custom_rollout=rollout, resample_true=False,
                                              n_threads=1)
        return _optimize(params, residual_fn, max_iters, xtol), projection

    if accel is None:
        accel = record_field(replay, table)
    try:
        fit, projection = solve(_readout_rollout(accel))
        ok, check = confirm_readout(accel, table_at(_split(target_effects, fit.xs)))
    except ReadoutUnsupportedError as exc:
        ok, check = False, f"kinematic readout not applicable ({exc})"
    if ok:
        return _results(targets, fit, projection, METHOD, check)
    fit, projection = solve(_replay_rollout(replay))
    return _results(targets, fit, projection, METHOD_RESIM,
                    f"{check}: refitted by re-simulation")


def confirm_readout(accel: AccelField, table: TableEdits) -> tuple[bool, str]:
    """Does MuJoCo read the table ``table`` along the recorded motion as the kinematic
    readout does?

    One batched rollout (:meth:`bench.gap.readout.AccelField.mujoco_read`): the model must
    move as recorded (every recorded step reproduced within
    :data:`bench.gap.replay.MOTION_TOL`) and its accelerometers must agree with
    :func:`bench.gap.readout.readout` within :data:`bench.gap.readout.READOUT_TOL`. Returns
    (agreed, a sentence with the numbers).
    """
    model, sd, step_error = accel.mujoco_read(table)
    diff = readout_error(accel, model, sd)
    ok = step_error <= MOTION_TOL and diff <= READOUT_TOL
    text = (f"kinematic readout vs MuJoCo's sensors at the optimum: largest difference "
            f"{diff:.1e} m/s² (limit {READOUT_TOL:g} m/s²)")
    if step_error > MOTION_TOL:
        text += f"; the fitted model does not move as recorded (state off by {step_error:.1e})"
    return ok, text


def _parameters(target_effects: Sequence[EffectSpec]) -> Any:
    """One bounded ``sysid.Parameter`` per physical effect, started at its estimate."""
    sysid = _sysid()
    params = sysid.ParameterDict()
    for e in target_effects:
        v = _nominal_vector(e)
        bound = 2.0 if e.name == "lever_arm" else 0.5  # m / rad: far outside any bench
        params.add(sysid.Parameter(_param_name(e), v, np.full_like(v, -bound),
                                   np.full_like(v, bound)))
    return params


@dataclass(frozen=True)
class _Experiment:
    """The replayed experiment as ``mujoco.sysid`` sees it.

    cols : sensordata columns of the x, y accelerometers.  mapping : sensor mapping.
    measured_full : (N, nsensordata) data in sensordata layout (accelerometer columns set).
    state0 : initial full-physics state.  control, measured : ``sysid.TimeSeries`` (control:
    the measured θ per sample).
    """

    cols: list[int]
    mapping: Any
    measured_full: np.ndarray
    state0: np.ndarray
    control: Any
    measured: Any


def _experiment(replay: Replay, datos: np.ndarray, table: TableEdits) -> _Experiment:
    """Control, measurements and rollout of the replay (static poses or servo replay)."""
    sysid = _sysid()
    spec0 = load_spec()
    edit_tilt_table(spec0, replace(table, misalignment=(0.0, 0.0), tilt_offset=0.0,
                                   lever_arm=((0.0, 0.0), (0.0, 0.0))))
    model0 = spec0.compile()
    cols = accel_columns(model0)
    measured_full = np.zeros((replay.n, model0.nsensordata))
    measured_full[:, cols] = datos
    mapping = sysid.TimeSeries.compute_all_sensor_mapping(model0)
    index = np.arange(replay.n, dtype=float)  # samples by number (a static run has no t)
    return _Experiment(
        cols, mapping, measured_full, initial_state(model0, float(replay.tita[0])),
        sysid.TimeSeries(index, replay.tita.reshape(-1, 1)),
        sysid.TimeSeries(index, measured_full, mapping))


@dataclass
class _Projection:
    """The ``modify_residual`` hook: bias and scale projected out (variable projection).

    For every candidate the residual on the affected axes is
    ``(data - bias - (1 + scale)·resp(a_sim) - drift) / σ`` with bias and scale solved
    linearly (:func:`bench.gap.prediction.fit_bias_scale`); ``projections`` keeps the last
    candidate's (bias, scale) per axis.
    """

    exp: _Experiment
    replay: Replay
    datos: np.ndarray
    sensor: SensorErrorModel
    axes_k: list[int]
    sigma2: np.ndarray
    projections: dict[int, tuple[float, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.sigma = np.sqrt(np.asarray(self.sigma2, dtype=float))
        self.drifts = {k: additive_output(self.replay.n, self.replay.t, self.sensor, k)
                       for k in self.axes_k}

    def modify_residual(self, p: Any, pred_ts: Any, meas_ts: Any, model: mujoco.MjModel,
                        return_pred_all: bool = False, **_: Any) -> tuple:
        exp = self.exp
        a_sim = np.asarray(pred_ts.data)[:, exp.cols]
        res = []
        pred_full = np.zeros_like(exp.measured_full)
        for k in self.axes_k:
            x = response(a_sim, self.replay.t, self.sensor, k)
            bias, scale, r = fit_bias_scale(self.datos[:, k] - self.drifts[k], x)
            self.projections[k] = (bias, scale)
            pred_full[:, exp.cols[k]] = self.datos[:, k] - r
            res.append(r / self.sigma[k])
        return (np.concatenate(res),
                _sysid().TimeSeries(meas_ts.times, pred_full, exp.mapping), meas_ts)


@dataclass(frozen=True)
class _Fit:
    """Optimum ``xs`` with std and 95 % half-widths, costs and iteration count."""

    xs: np.ndarray
    std: np.ndarray
    half: np.ndarray
    cost_start: float
    cost_end: float
    n_residuals: int
    iterations: int | None


def _optimize(params: Any, residual_fn: Callable, max_iters: int, xtol: float) -> _Fit:
    """Gauss-Newton (``sysid.optimize``) from the estimates, then intervals at the optimum."""
    from absl import logging as absl_logging  # comes with mujoco.sysid

    sysid = _sysid()

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
    return _Fit(xs, np.sqrt(np.maximum(np.diag(cov), 0.0)), np.asarray(half), cost_start,
                float(r_all @ r_all), int(r_all.size),
                int(len(result.extras.get("objective", []))) or None)


def _results(targets: Sequence[tuple[int, EffectSpec]], fit: _Fit, projection: _Projection,
             method: str, check: str) -> dict[int, dict]:
    """Effect index → its refined parameters, std, half-widths and the fit's bookkeeping."""
    proj, axes_k = projection.projections, projection.axes_k
    out: dict[int, dict] = {}
    at = 0
    for i, e in targets:
        size = _nominal_vector(e).size
        sl = slice(at, at + size)
        at += size
        names = list(_effect_params(e, fit.xs[sl]))
        out[i] = {
            "method": method,
            "check": check,
            "params": _effect_params(e, fit.xs[sl]),
            "std": dict(zip(names, (float(s) for s in fit.std[sl]), strict=True)),
            "ci95_halfwidth": dict(zip(names, (float(h) for h in fit.half[sl]), strict=True)),
            "bias": {AXES[k]: proj[k][0] for k in axes_k},
            "scale": {AXES[k]: proj[k][1] for k in axes_k},
            "cost_start": fit.cost_start, "cost_end": fit.cost_end,
            "n_residuals": fit.n_residuals,
            "iterations": fit.iterations,
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


def sysid_usable(s: dict) -> bool:
    """A sysid refinement is used when it lowered the cost and has finite intervals."""
    std = list(s.get("std", {}).values())
    return bool(std) and all(np.isfinite(std)) and s["cost_end"] <= s["cost_start"] + 1e-9


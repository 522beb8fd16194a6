"""Calibration runs ("ensayos") on the MuJoCo tilt table.

Two modes:

* **static** — the table is commanded to each θ, held (``qvel = 0``, ``ctrl = θ``: the position
  servo exerts no torque since the centre of mass is on the hinge) and sampled. Each distinct
  pose is evaluated once by MuJoCo (``mujoco.rollout`` with ``nstep = 1`` over a batch of poses);
  samples held at one pose share that physics evaluation and differ only by sensor noise.
* **sweep** — continuous rotation following a commanded angle profile ``θ_cmd(t)`` through the
  position servo, simulated in one ``mujoco.rollout`` call and sampled every ``1/rate`` s. The
  readings carry whatever dynamics MuJoCo produces (servo lag, start-up transient, lever-arm
  accelerations if the sites are moved off the axis); θ is the simulated encoder angle
  (``jointpos`` sensor), never the commanded one.

MuJoCo's accelerometers give the true specific force along each site's +x axis; with the
model's site frames this is ``[-g sin θ, -g cos θ]`` (course convention). The sensor error model
(:mod:`bench.sensors`) turns it into readings.
"""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass, field
from typing import Literal

import mujoco
import mujoco.rollout
import numpy as np

from bench.model import (
    ENCODER,
    TABLE_ACC_SENSORS,
    TILT_JOINT,
    TableEdits,
    full_state,
    sensor_slice,
    tilt_table,
)
from bench.sensors import SensorErrorModel
from calib.files.course import Ensayo

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class ThetaDesign:
    """Static θ schedule (rad).

    kind "range": ``count`` angles ``linspace(start, stop, count)`` (course: 0..2π, 20001).
    kind "list": the explicit ``values`` (one sample each, in order).
    kind "positions": ``positions`` distinct angles evenly spread over [start, stop]
    (``stop`` excluded when it closes a full turn), ``per_position`` samples held at each.
    """

    kind: Literal["range", "list", "positions"] = "range"
    start: float = 0.0
    stop: float = TWO_PI
    count: int = 20001
    values: tuple[float, ...] = ()
    positions: int = 0
    per_position: int = 0

    def angles(self) -> np.ndarray:
        if self.kind == "range":
            if self.count < 3:
                raise ValueError(f"theta count must be >= 3, got {self.count}")
            return np.linspace(self.start, self.stop, self.count)
        if self.kind == "list":
            if len(self.values) < 3:
                raise ValueError("an explicit θ list needs at least 3 values")
            return np.asarray(self.values, dtype=float)
        if self.kind == "positions":
            if self.positions < 1 or self.per_position < 1:
                raise ValueError("positions and per-position samples must be >= 1")
            full = np.isclose(abs(self.stop - self.start), TWO_PI)
            pos = np.linspace(self.start, self.stop, self.positions, endpoint=not full)
            return np.repeat(pos, self.per_position)
        raise ValueError(f"unknown θ design kind {self.kind!r}")


@dataclass(frozen=True)
class SweepProfile:
    """Commanded angle profile of a sweep, θ_cmd(t) for t in [0, duration] (rad, s).

    kind "constant": constant rate from ``start`` to ``stop``.
    kind "accel": rate growing linearly from 0, ``θ = start + (stop - start)(t/T)²``.
    kind "updown": start → stop → start, ``cycles`` times (triangle wave).
    kind "sine": oscillation ``mid - amp·cos(2π·cycles·t/T)`` between start and stop.
    ``rate``: sample rate, Hz (1/rate must be a multiple of the model timestep).
    """

    kind: Literal["constant", "accel", "updown", "sine"] = "constant"
    start: float = 0.0
    stop: float = TWO_PI
    duration: float = 20.0
    rate: float = 100.0
    cycles: float = 1.0

    def command(self, t: np.ndarray) -> np.ndarray:
        u = np.clip(np.asarray(t, float) / self.duration, 0.0, 1.0)
        span = self.stop - self.start
        if self.kind == "constant":
            return self.start + span * u
        if self.kind == "accel":
            return self.start + span * u**2
        if self.kind == "updown":
            phase = (u * self.cycles) % 1.0
            return self.start + span * (1.0 - np.abs(2.0 * phase - 1.0))
        if self.kind == "sine":
            return self.start + 0.5 * span * (1.0 - np.cos(TWO_PI * self.cycles * u))
        raise ValueError(f"unknown sweep kind {self.kind!r}")


@dataclass(frozen=True)
class CalibrationConfig:
    """Everything that defines a calibration run (besides the seed)."""

    mode: Literal["static", "sweep"] = "static"
    theta: ThetaDesign = field(default_factory=ThetaDesign)
    sweep: SweepProfile = field(default_factory=SweepProfile)
    sensor: SensorErrorModel = field(default_factory=SensorErrorModel)
    table: TableEdits = field(default_factory=TableEdits)
    twin: dict | None = None
    """The measured sensor this run simulates (``generate --sensor``,
    :func:`bench.sensor_twin.twin_truth`), recorded in the truth; None otherwise."""

    @property
    def g(self) -> float:
        return self.table.g

    def to_dict(self) -> dict:
        d = {"mode": self.mode, "g": self.g, "sensor": self.sensor.to_dict(),
             "table": asdict(self.table)}
        d["theta_design" if self.mode == "static" else "sweep"] = asdict(
            self.theta if self.mode == "static" else self.sweep)
        if self.twin is not None:  # only then: other runs keep their bytes
            d["sensor_profile"] = self.twin
        return d


@dataclass(frozen=True)
class CalibrationRun:
    """A generated calibration run with its truth.

    tita : (N,) encoder angle, rad (what a student gets).  datos : (N, 2) readings, m/s².
    t : (N,) sample times (sweeps) or None (static).
    a_true : (N, 2) MuJoCo's true specific force on the sensitive axes, before sensor errors.
    config, seed : what made it.
    """

    tita: np.ndarray
    datos: np.ndarray
    t: np.ndarray | None
    a_true: np.ndarray
    config: CalibrationConfig
    seed: int

    def ensayo(self) -> Ensayo:
        return Ensayo(self.tita, self.datos, self.t, source=f"bench seed {self.seed}")

    def truth(self) -> dict:
        d = {"kind": "calibration", "n": int(self.tita.shape[0]), **self.config.to_dict()}
        d["model"] = "models/tilt_table.xml"
        d["theta_summary"] = {"min": float(self.tita.min()), "max": float(self.tita.max()),
                              "distinct": int(np.unique(self.tita).size)}
        return d


def _accel_columns(model: mujoco.MjModel) -> tuple[int, int, int]:
    """sensordata columns of the x and y sensitive axes (site +x) and of the encoder."""
    sx = sensor_slice(model, TABLE_ACC_SENSORS["x"]).start
    sy = sensor_slice(model, TABLE_ACC_SENSORS["y"]).start
    return sx, sy, sensor_slice(model, ENCODER).start


def _tilt_qposadr(model: mujoco.MjModel) -> int:
    """Index of the tilt hinge's angle in ``qpos`` (looked up by name)."""
    return int(model.joint(TILT_JOINT).qposadr[0])


def static_readings(theta: np.ndarray, table: TableEdits | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """True specific force (N, 2) and encoder angle (N,) at static poses θ (rad).

    Each distinct θ is simulated once (one batched ``mujoco.rollout`` with ``nstep = 1``, which
    returns the sensors at the initial state, i.e. the ``mj_forward`` reading).
    """
    theta = np.asarray(theta, dtype=float)
    model, _ = tilt_table(table)
    data = mujoco.MjData(model)
    poses, inverse = np.unique(theta, return_inverse=True)
    base = full_state(model, data)
    # mjSTATE_FULLPHYSICS layout: [time, qpos (nq), qvel (nv), act, ...]
    qpos_at = 1 + _tilt_qposadr(model)
    state0 = np.tile(base, (poses.size, 1))
    state0[:, qpos_at] = poses
    control = poses.reshape(-1, 1, 1)  # servo target = pose: no torque, no motion
    # Poses are independent: split the batch over the cores (rollout runs one thread per
    # MjData). Each pose is computed the same way whatever the split: same bytes.
    n_threads = max(1, min(os.cpu_count() or 1, poses.size // 1000))
    datas = data if n_threads == 1 else [data] + [mujoco.MjData(model)
                                                  for _ in range(n_threads - 1)]
    _, sensordata = mujoco.rollout.rollout(model, datas, state0, control, nstep=1)
    sx, sy, enc = _accel_columns(model)
    a = sensordata[:, 0, [sx, sy]]
    return a[inverse], sensordata[inverse, 0, enc]


def sweep_readings(sweep: SweepProfile, table: TableEdits | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Simulate a sweep; return sample times (N,), true specific force (N, 2), encoder (N,).

    The table starts at rest at θ_cmd(0); the servo target follows θ_cmd at every physics
    step. Samples are the sensors at step ``k · stride`` (state at that time).
    """
    model, _ = tilt_table(table)
    data = mujoco.MjData(model)
    dt = model.opt.timestep
    if not (np.isfinite(sweep.rate) and sweep.rate > 0):
        raise ValueError(f"sample rate must be positive and finite, got {sweep.rate} Hz")
    stride = 1.0 / (sweep.rate * dt)
    if stride < 0.5 or abs(stride - round(stride)) > 1e-9:
        raise ValueError(f"sample period 1/{sweep.rate} Hz must be a multiple of the model "
                         f"timestep {dt} s")
    stride = int(round(stride))
    if not (np.isfinite(sweep.duration) and sweep.duration > 0):
        raise ValueError(f"sweep duration must be positive and finite, got {sweep.duration}")
    if not (np.isfinite(sweep.cycles) and sweep.cycles > 0):
        raise ValueError(f"sweep cycles must be positive and finite, got {sweep.cycles}")
    n_samples = int(np.floor(sweep.duration * sweep.rate + 1e-9)) + 1
    nstep = (n_samples - 1) * stride + 1
    t_step = np.arange(nstep) * dt
    cmd = sweep.command(t_step)
    data.qpos[_tilt_qposadr(model)] = cmd[0]
    state0 = full_state(model, data)
    _, sensordata = mujoco.rollout.rollout(model, data, state0[None, :],
                                           cmd.reshape(1, nstep, 1), nstep=nstep)
    sx, sy, enc = _accel_columns(model)
    rows = sensordata[0, ::stride]
    a, theta = rows[:, [sx, sy]], rows[:, enc]
    # A run that never moves (θ ≡ θ_cmd(0): zero cycles, a sub-sample duration, start = stop)
    # or a simulation that diverged is not a calibration run: say so instead of writing it.
    if not (np.isfinite(a).all() and np.isfinite(theta).all()):
        raise ValueError("the sweep's simulation diverged (non-finite readings); lower the "
                         "sweep speed (range / duration) or the cycles")
    if n_samples < 3 or np.ptp(theta) == 0.0:
        raise ValueError(f"the sweep never moves (θ stays at {theta[0]:g} rad over "
                         f"{n_samples} samples); give a longer duration, start ≠ stop and "
                         "cycles > 0")
    return t_step[::stride], a, theta


def generate_calibration(config: CalibrationConfig, seed: int) -> CalibrationRun:
    """Generate a calibration run: MuJoCo true readings + seeded sensor errors."""
    rng = np.random.default_rng(np.random.SeedSequence(int(seed)))
    if config.mode == "static":
        a_true, tita = static_readings(config.theta.angles(), config.table)
        t = None
    elif config.mode == "sweep":
        t, a_true, tita = sweep_readings(config.sweep, config.table)
    else:
        raise ValueError(f"mode must be 'static' or 'sweep', got {config.mode!r}")
    datos = config.sensor.apply(a_true, rng, t)
    return CalibrationRun(tita=tita, datos=datos, t=t, a_true=a_true, config=config,
                          seed=int(seed))


def write_calibration(run: CalibrationRun, out, force: bool = False) -> dict[str, str]:
    """Write ``ensayo.mat`` (tita, datos, and t for sweeps) and ``truth.json`` into ``out``."""
    from bench.dataset import prepare_out_dir, save_mat, write_truth

    out = prepare_out_dir(out, ["ensayo.mat", "truth.json"], force)
    variables = {"tita": run.tita, "datos": run.datos}
    if run.t is not None:
        variables["t"] = run.t
    paths = {"ensayo": save_mat(out / "ensayo.mat", variables, force=True),
             "truth": write_truth(out / "truth.json", run.truth(), run.seed, force=True)}
    return {k: str(v) for k, v in paths.items()}

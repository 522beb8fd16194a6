"""Vehicle runs on the MuJoCo planar vehicle (``models/vehicle.xml``).

The vehicle slides in the horizontal x-y plane (world axes, no rotation — the course's
assumption) driven by two force motors. A commanded acceleration profile ``a_cmd(t)`` (m/s²,
piecewise constant :class:`Segment` s) is turned into motor forces ``F = m · a_cmd`` with ``m``
read from the compiled model, held constant over each physics step (zero-order hold) and
simulated in one ``mujoco.rollout`` call (RK4, timestep = sample period). The **true
trajectory is MuJoCo's state** (``qpos``, ``qvel`` of the slide joints), sampled at
``t_k = k / rate``, ``k = 0 … M-1`` (course: 6000 samples, ``t = 0, 0.01, …, 59.99`` s).

Readings: MuJoCo's accelerometers give the specific force in each site frame; each site's
local +x is the sensitive axis (x site along world +x, y site along world +y), so the true
readings are ``[d²x/dt², d²y/dt²]``. The seeded sensor error model (:mod:`bench.sensors`,
``A_m = (1 + scale)·A_r + bias + v``) makes them measured readings, through the single
function :func:`apply_sensor_errors`.

Signs: positive acceleration along +x / +y increases x / y. Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import mujoco.rollout
import numpy as np

from bench.model import (
    VEHICLE_ACC_SENSORS,
    VEHICLE_BODY,
    VEHICLE_DRIVES,
    VEHICLE_SLIDE_JOINTS,
    VEHICLE_XML,
    full_state,
    load_spec,
    sensor_slice,
)
from bench.sensors import SensorErrorModel
from calib.conventions import AXES, G
from calib.io import Acel
from calib.trajectory import COURSE_P0, COURSE_V0, integrate_twice

SENSITIVE_COMPONENT = 0
"""Component of each accelerometer (site frame) along its sensitive axis: local +x."""

COURSE_SENSOR = SensorErrorModel.from_pairs((0.08, -0.02), (-0.03, 0.01), (0.25, 0.64))
"""Course-like true sensor errors (bias m/s², scale, noise variance (m/s²)²)."""


@dataclass(frozen=True)
class Segment:
    """A piece of the commanded acceleration profile.

    duration : s (a multiple of the sample period).  accel : (ax, ay), m/s², world axes.
    """

    duration: float
    accel: tuple[float, float]

    def to_dict(self) -> dict:
        return {"duration": float(self.duration), "accel": [float(a) for a in self.accel]}


COURSE_PROFILE: tuple[Segment, ...] = (
    Segment(20.0, (0.5, 0.0)), Segment(20.0, (0.0, -0.2)), Segment(20.0, (-0.5, 0.0)))
"""Profile like the course run (read off the corrected ``acel.mat``: three 20 s segments)."""


@dataclass(frozen=True)
class VehicleConfig:
    """Everything that defines a vehicle run (besides the seed).

    duration : s; samples at ``t_k = k/rate`` for ``k < duration·rate`` (60 s → 6000 samples,
        last at 59.99 s, as ``acel.mat``).
    rate : sample rate = physics rate, Hz.
    p0 : initial position, m.  v0 : initial velocity, m/s.
    profile : commanded acceleration segments, applied from t = 0 in order; zero after the
        last one.
    sensor : true sensor errors of the two accelerometers.
    g : gravity, m/s² (the horizontal readings do not depend on it).
    """

    duration: float = 60.0
    rate: float = 100.0
    p0: tuple[float, float] = COURSE_P0
    v0: tuple[float, float] = COURSE_V0
    profile: tuple[Segment, ...] = COURSE_PROFILE
    sensor: SensorErrorModel = field(default_factory=lambda: COURSE_SENSOR)
    g: float = G

    @property
    def n_samples(self) -> int:
        m = self.duration * self.rate
        if self.rate <= 0 or self.duration <= 0 or abs(m - round(m)) > 1e-9 * max(m, 1.0):
            raise ValueError(f"duration·rate must be a positive integer, got {self.duration} s "
                             f"× {self.rate} Hz")
        if round(m) < 3:
            raise ValueError("a vehicle run needs at least 3 samples")
        return int(round(m))

    @property
    def t(self) -> np.ndarray:
        """(M,) sample times, s."""
        return np.arange(self.n_samples) / self.rate

    def command(self) -> np.ndarray:
        """(M, 2) commanded acceleration at each sample (held over the following step), m/s².

        Segment boundaries must fall on the sample grid (else ValueError): the zero-order
        hold then reproduces the profile exactly.
        """
        m = self.n_samples
        cmd = np.zeros((m, 2))
        start = 0
        for seg in self.profile:
            steps = seg.duration * self.rate
            if seg.duration < 0 or abs(steps - round(steps)) > 1e-9 * max(steps, 1.0):
                raise ValueError(f"segment duration {seg.duration} s is not a whole number of "
                                 f"samples at {self.rate} Hz")
            stop = min(start + int(round(steps)), m)
            cmd[start:stop] = np.asarray(seg.accel, dtype=float)
            start = stop
        return cmd

    def to_dict(self) -> dict:
        return {"duration": self.duration, "rate": self.rate, "n_samples": self.n_samples,
                "p0": list(map(float, self.p0)), "v0": list(map(float, self.v0)),
                "profile": [s.to_dict() for s in self.profile],
                "sensor": self.sensor.to_dict(), "g": self.g}


def vehicle_model(rate: float = 100.0, g: float = G) -> tuple[mujoco.MjModel, mujoco.MjSpec]:
    """Compile ``models/vehicle.xml`` with timestep ``1/rate`` and gravity ``(0, 0, -g)``."""
    spec = load_spec(VEHICLE_XML)
    spec.option.timestep = 1.0 / float(rate)
    spec.option.gravity = [0.0, 0.0, -float(g)]
    return spec.compile(), spec


def vehicle_mass(model: mujoco.MjModel) -> float:
    """Mass moved by the slide joints, kg (the vehicle's subtree)."""
    return float(model.body_subtreemass[model.body(VEHICLE_BODY).id])


@dataclass(frozen=True)
class VehicleTruth:
    """MuJoCo's true run.

    t : (M,) s.  pos, vel : (M, 2) slide-joint state at ``t_k``, m, m/s.
    acc : (M, 2) true specific force on the sensitive axes at ``t_k`` (accelerometers), m/s².
    acc_cmd : (M, 2) commanded acceleration, m/s².  mass : kg.
    """

    t: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    acc: np.ndarray
    acc_cmd: np.ndarray
    mass: float

    def __post_init__(self) -> None:
        for name in ("t", "pos", "vel", "acc", "acc_cmd"):
            arr = np.array(getattr(self, name), dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def final_position(self) -> np.ndarray:
        """(2,) true arrival point at the last sample time, m."""
        return self.pos[-1].copy()

    @property
    def final_velocity(self) -> np.ndarray:
        return self.vel[-1].copy()

    def summary_dict(self, every: float = 1.0) -> dict:
        """Trajectory summary for truth.json: final state and the position every ``every`` s."""
        dt = float(self.t[1] - self.t[0])
        stride = max(1, int(round(every / dt)))
        idx = np.arange(0, self.t.shape[0], stride)
        return {"final_position": self.final_position.tolist(),
                "final_velocity": self.final_velocity.tolist(),
                "t_final": float(self.t[-1]), "mass": self.mass,
                "samples": {"t": self.t[idx].tolist(), "pos": self.pos[idx].tolist(),
                            "vel": self.vel[idx].tolist()}}


def simulate_vehicle(config: VehicleConfig | None = None) -> VehicleTruth:
    """Simulate the commanded run with ``mujoco.rollout`` (one call, no Python step loop).

    ``ctrl = m · a_cmd`` (N) on the two motors; the rollout's ``sensordata[k]`` is evaluated at
    the state before step k (time ``t_k``), ``state[k]`` is the state after it (``t_{k+1}``).
    """
    config = config or VehicleConfig()
    model, _ = vehicle_model(config.rate, config.g)
    data = mujoco.MjData(model)
    m = config.n_samples
    qadr = {a: int(model.joint(VEHICLE_SLIDE_JOINTS[a]).qposadr[0]) for a in AXES}
    vadr = {a: int(model.joint(VEHICLE_SLIDE_JOINTS[a]).dofadr[0]) for a in AXES}
    for k, a in enumerate(AXES):
        data.qpos[qadr[a]] = config.p0[k]
        data.qvel[vadr[a]] = config.v0[k]
    state0 = full_state(model, data)
    mass = vehicle_mass(model)
    cmd = config.command()
    control = np.zeros((1, m, model.nu))
    for k, a in enumerate(AXES):
        control[0, :, model.actuator(VEHICLE_DRIVES[a]).id] = mass * cmd[:, k]
    state, sensordata = mujoco.rollout.rollout(model, data, state0[None, :], control, nstep=m)
    # mjSTATE_FULLPHYSICS layout: [time, qpos (nq), qvel (nv), ...]
    qpos = np.vstack([state0[1:1 + model.nq], state[0, :m - 1, 1:1 + model.nq]])
    qvel = np.vstack([state0[1 + model.nq:1 + model.nq + model.nv],
                      state[0, :m - 1, 1 + model.nq:1 + model.nq + model.nv]])
    cols = [sensor_slice(model, VEHICLE_ACC_SENSORS[a]).start + SENSITIVE_COMPONENT for a in AXES]
    return VehicleTruth(
        t=config.t, pos=qpos[:, [qadr[a] for a in AXES]], vel=qvel[:, [vadr[a] for a in AXES]],
        acc=sensordata[0][:, cols], acc_cmd=cmd, mass=mass)


def apply_sensor_errors(acc_true: np.ndarray, sensor: SensorErrorModel,
                        rng: np.random.Generator, t: np.ndarray | None = None) -> np.ndarray:
    """Measured readings ``A_m = (1 + scale)·A_r + bias + v`` (+ any extra error terms).

    The one place where the vehicle run meets the sensor error model
    (:meth:`bench.sensors.SensorErrorModel.apply`); swap the model here.
    """
    return sensor.apply(acc_true, rng, t)


@dataclass(frozen=True)
class VehicleRun:
    """A generated vehicle run: what a student gets (``t``, ``aerr``) and the truth."""

    t: np.ndarray
    aerr: np.ndarray
    truth: VehicleTruth
    config: VehicleConfig
    seed: int

    def acel(self) -> Acel:
        return Acel(self.t, self.aerr, source=f"bench vehicle seed {self.seed}")

    def raw_final_position(self) -> np.ndarray:
        """Final position integrated from the uncorrected readings (trapezoid), m."""
        pos, _ = integrate_twice(self.t, self.aerr, self.config.p0, self.config.v0)
        return pos[-1]

    def truth_dict(self) -> dict:
        return {"kind": "vehicle", "model": "models/vehicle.xml", **self.config.to_dict(),
                "trajectory": self.truth.summary_dict(),
                "raw_final_position": self.raw_final_position().tolist()}


def make_vehicle_run(config: VehicleConfig | None = None, seed: int = 0,
                     rng: np.random.Generator | None = None) -> VehicleRun:
    """Simulate the run and apply the seeded sensor errors (no files).

    ``rng`` defaults to ``default_rng(SeedSequence(seed))``; a course set passes its own
    independent stream.
    """
    config = config or VehicleConfig()
    truth = simulate_vehicle(config)
    rng = rng if rng is not None else np.random.default_rng(np.random.SeedSequence(int(seed)))
    aerr = apply_sensor_errors(truth.acc, config.sensor, rng, truth.t)
    return VehicleRun(t=truth.t, aerr=aerr, truth=truth, config=config, seed=int(seed))


VEHICLE_FILES = ("acel.mat", "datos.txt", "truth.json")


def write_vehicle(run: VehicleRun, out: str | Path, force: bool = False,
                  gps=None) -> dict[str, str]:
    """Write ``acel.mat`` {t, Aerr}, ``datos.txt`` and ``truth.json`` into ``out``; with
    ``gps`` (:class:`bench.gnss.GnssFixes` of this run) also ``gps.mat`` and the receiver
    under ``truth.json``'s ``gps`` key."""
    from bench.dataset import prepare_out_dir, save_mat, write_datos, write_truth

    names = list(VEHICLE_FILES) + ([] if gps is None else ["gps.mat"])
    out = prepare_out_dir(out, names, force)
    nv = [run.config.sensor.x.noise_var, run.config.sensor.y.noise_var]
    truth = run.truth_dict() if gps is None else {**run.truth_dict(), "gps": gps.truth_dict()}
    paths = {
        "acel": save_mat(out / "acel.mat", {"t": run.t, "Aerr": run.aerr}, force=True),
        "datos": write_datos(out / "datos.txt", run.config.p0, run.config.v0, nv, force=True),
        "truth": write_truth(out / "truth.json", truth, run.seed, force=True),
    }
    if gps is not None:
        from bench.dataset import write_gps

        paths["gps"] = write_gps(out / "gps.mat", gps, force=True)
    return {k: str(v) for k, v in paths.items()}


def generate_vehicle(out: str | Path, seed: int = 0, force: bool = False,
                     config: VehicleConfig | None = None) -> VehicleRun:
    """Generate a vehicle run and write it (``tiltbench generate vehicle``)."""
    run = make_vehicle_run(config, seed)
    write_vehicle(run, out, force)
    return run


__all__ = [
    "COURSE_PROFILE", "COURSE_SENSOR", "Segment", "VehicleConfig", "VehicleRun", "VehicleTruth",
    "apply_sensor_errors", "generate_vehicle", "make_vehicle_run", "simulate_vehicle",
    "vehicle_mass", "vehicle_model", "write_vehicle",
]

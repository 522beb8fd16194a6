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

Turning vehicle (``VehicleConfig(turning=True)``, issue 13 part 2). :func:`vehicle_model`
adds, through ``mujoco.MjSpec`` (``models/vehicle.xml`` is not edited), a free hinge
``yaw`` about world +z after the two slides (so the slides keep their world axes), a torque
motor ``drive_yaw`` on it and a MuJoCo ``gyro`` sensor on ``acc_x_site``. The yaw profile
is piecewise-constant angular acceleration :class:`YawSegment` s ``α_cmd(t)`` (rad/s²),
commanded as torque ``τ = I_zz · α_cmd`` (``I_zz`` the yaw diagonal of MuJoCo's mass matrix);
the heading ``ψ(t)`` (rad, counter-clockwise from world +x about +z) and the yaw rate
``ω = dψ/dt`` (rad/s) are MuJoCo's hinge state. The accelerometer sites turn with the body,
so the readings are the specific force in the BODY frame::

    [A_x, A_y]_body = R(ψ)ᵀ [d²x/dt², d²y/dt²]_world,   R(ψ) = [[cos ψ, -sin ψ], [sin ψ, cos ψ]]

The translational command stays in world axes (force motors on the slides, as the course
vehicle: a hovercraft-like body that slides and spins), held over each step, so
``R(ψ_k) A_body,k`` is the world acceleration over ``[t_k, t_k+1)`` exactly. The gyro reads
the body rate about the site's z axis (= world +z): ``ω_k``. Its measurement is
``ω_m = ω + v_g`` with white ``v_g ~ N(0, σ_g²)`` (``gyro_sigma``, rad/s; no gyro bias) from
its own seed stream (:func:`gyro_rng`, spawn key :data:`GYRO_STREAM`), so the accelerometer
readings and fixes of a seed do not change with the option. The default (``turning=False``)
builds and simulates exactly the non-rotating model (same bytes).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import mujoco.rollout
import numpy as np

from bench.model import (
    VEHICLE_ACC_SENSORS,
    VEHICLE_ACC_SITES,
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
from calib.files.course import Acel
from calib.vehicle.trajectory import COURSE_P0, COURSE_V0, integrate_twice

YAW_JOINT = "yaw"
YAW_DRIVE = "drive_yaw"
GYRO_SENSOR = "gyro"
GYRO_AXIS_COMPONENT = 2
"""Component of the gyro (site frame) along world +z: the yaw rate."""
GYRO_STREAM = 7
"""Spawn key of the gyro's noise stream (the GNSS receiver uses its own key)."""
GYRO_SIGMA = 0.005
"""Default white gyro noise σ_g, rad/s."""

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


@dataclass(frozen=True)
class YawSegment:
    """A piece of the commanded yaw profile (turning vehicle).

    duration : s (a multiple of the sample period).  alpha : yaw angular acceleration, rad/s²
    (positive: counter-clockwise seen from +z).
    """

    duration: float
    alpha: float

    def to_dict(self) -> dict:
        return {"duration": float(self.duration), "alpha": float(self.alpha)}


TURN_PROFILE: tuple[YawSegment, ...] = (
    YawSegment(5.0, 0.02), YawSegment(20.0, 0.0), YawSegment(5.0, -0.02),
    YawSegment(10.0, -0.03), YawSegment(10.0, 0.03))
"""Default yaw profile (ψ(0) = 0, ω(0) = 0): ω rises to 0.1 rad/s, ψ reaches 2.5 rad (143°)
at 30 s, then ω falls to -0.3 rad/s and back to 0; ψ ends at -0.5 rad at 50 s and stays."""

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
    turning : free yaw hinge driven by ``yaw_profile`` (angular acceleration segments,
        rad/s², zero after the last one); body-frame readings and a gyro with white noise
        σ ``gyro_sigma`` (rad/s). False: the course's non-rotating vehicle (then
        ``yaw_profile`` and ``gyro_sigma`` are unused and not written).
    """

    duration: float = 60.0
    rate: float = 100.0
    p0: tuple[float, float] = COURSE_P0
    v0: tuple[float, float] = COURSE_V0
    profile: tuple[Segment, ...] = COURSE_PROFILE
    sensor: SensorErrorModel = field(default_factory=lambda: COURSE_SENSOR)
    g: float = G
    turning: bool = False
    yaw_profile: tuple[YawSegment, ...] = TURN_PROFILE
    gyro_sigma: float = GYRO_SIGMA

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
        return self._hold([(seg.duration, seg.accel) for seg in self.profile], 2)

    def yaw_command(self) -> np.ndarray:
        """(M,) commanded yaw angular acceleration at each sample (held), rad/s²."""
        return self._hold([(seg.duration, (seg.alpha,)) for seg in self.yaw_profile], 1)[:, 0]

    def _hold(self, segments, width: int) -> np.ndarray:
        m = self.n_samples
        cmd = np.zeros((m, width))
        start = 0
        for duration, value in segments:
            steps = duration * self.rate
            if duration < 0 or abs(steps - round(steps)) > 1e-9 * max(steps, 1.0):
                raise ValueError(f"segment duration {duration} s is not a whole number of "
                                 f"samples at {self.rate} Hz")
            stop = min(start + int(round(steps)), m)
            cmd[start:stop] = np.asarray(value, dtype=float)
            start = stop
        return cmd

    def to_dict(self) -> dict:
        return {"duration": self.duration, "rate": self.rate, "n_samples": self.n_samples,
                "p0": list(map(float, self.p0)), "v0": list(map(float, self.v0)),
                "profile": [s.to_dict() for s in self.profile],
                "sensor": self.sensor.to_dict(), "g": self.g,
                **({} if not self.turning else {
                    "turning": True, "yaw_profile": [s.to_dict() for s in self.yaw_profile],
                    "gyro_sigma": float(self.gyro_sigma), "gyro_seed_spawn_key": GYRO_STREAM})}


def vehicle_model(rate: float = 100.0, g: float = G,
                  turning: bool = False) -> tuple[mujoco.MjModel, mujoco.MjSpec]:
    """Compile ``models/vehicle.xml`` with timestep ``1/rate`` and gravity ``(0, 0, -g)``;
    ``turning`` adds the yaw hinge, its torque motor and the gyro (module docstring)."""
    spec = load_spec(VEHICLE_XML)
    spec.option.timestep = 1.0 / float(rate)
    spec.option.gravity = [0.0, 0.0, -float(g)]
    if turning:
        add_yaw(spec)
    return spec.compile(), spec


def add_yaw(spec: mujoco.MjSpec) -> mujoco.MjSpec:
    """Edit a vehicle spec in place: hinge ``yaw`` about +z (after the slides, so they keep
    their world axes), torque motor ``drive_yaw`` (N·m, gear 1, unlimited) and a ``gyro`` on
    ``acc_x_site`` (rad/s, site frame; its z component is the yaw rate)."""
    spec.body(VEHICLE_BODY).add_joint(name=YAW_JOINT, type=mujoco.mjtJoint.mjJNT_HINGE,
                                      axis=[0.0, 0.0, 1.0])
    spec.add_actuator(name=YAW_DRIVE, target=YAW_JOINT, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    spec.add_sensor(name=GYRO_SENSOR, type=mujoco.mjtSensor.mjSENS_GYRO,
                    objtype=mujoco.mjtObj.mjOBJ_SITE, objname=VEHICLE_ACC_SITES["x"])
    return spec


def yaw_inertia(model: mujoco.MjModel) -> float:
    """Diagonal of MuJoCo's mass matrix on the yaw hinge, kg·m² (at qpos0)."""
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    dof = int(model.joint(YAW_JOINT).dofadr[0])
    return float(full[dof, dof])


def vehicle_mass(model: mujoco.MjModel) -> float:
    """Mass moved by the slide joints, kg (the vehicle's subtree)."""
    return float(model.body_subtreemass[model.body(VEHICLE_BODY).id])


@dataclass(frozen=True)
class VehicleTruth:
    """MuJoCo's true run.

    t : (M,) s.  pos, vel : (M, 2) slide-joint state at ``t_k``, m, m/s.
    acc : (M, 2) true specific force on the sensitive axes at ``t_k`` (accelerometers), m/s²
        (body frame when turning; world axes otherwise, where the two coincide).
    acc_cmd : (M, 2) commanded acceleration, m/s² (world axes).  mass : kg.
    heading : (M,) ψ, rad, and yaw_rate : (M,) the true gyro reading ω = dψ/dt, rad/s, at
        ``t_k`` (turning vehicle); None otherwise.
    """

    t: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    acc: np.ndarray
    acc_cmd: np.ndarray
    mass: float
    heading: np.ndarray | None = None
    yaw_rate: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("t", "pos", "vel", "acc", "acc_cmd", "heading", "yaw_rate"):
            if getattr(self, name) is None:
                continue
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
        out = {"final_position": self.final_position.tolist(),
               "final_velocity": self.final_velocity.tolist(),
               "t_final": float(self.t[-1]), "mass": self.mass,
               "samples": {"t": self.t[idx].tolist(), "pos": self.pos[idx].tolist(),
                           "vel": self.vel[idx].tolist()}}
        if self.heading is not None:
            out["final_heading"] = float(self.heading[-1])
            out["samples"]["heading"] = self.heading[idx].tolist()
            out["samples"]["yaw_rate"] = self.yaw_rate[idx].tolist()
        return out


def simulate_vehicle(config: VehicleConfig | None = None) -> VehicleTruth:
    """Simulate the commanded run with ``mujoco.rollout`` (one call, no Python step loop).

    ``ctrl = m · a_cmd`` (N) on the two motors; the rollout's ``sensordata[k]`` is evaluated at
    the state before step k (time ``t_k``), ``state[k]`` is the state after it (``t_{k+1}``).
    """
    config = config or VehicleConfig()
    model, _ = vehicle_model(config.rate, config.g, config.turning)
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
    if config.turning:
        control[0, :, model.actuator(YAW_DRIVE).id] = yaw_inertia(model) * config.yaw_command()
    state, sensordata = mujoco.rollout.rollout(model, data, state0[None, :], control, nstep=m)
    # mjSTATE_FULLPHYSICS layout: [time, qpos (nq), qvel (nv), ...]
    qpos = np.vstack([state0[1:1 + model.nq], state[0, :m - 1, 1:1 + model.nq]])
    qvel = np.vstack([state0[1 + model.nq:1 + model.nq + model.nv],
                      state[0, :m - 1, 1 + model.nq:1 + model.nq + model.nv]])
    cols = [sensor_slice(model, VEHICLE_ACC_SENSORS[a]).start + SENSITIVE_COMPONENT for a in AXES]
    yaw = {}
    if config.turning:
        j = model.joint(YAW_JOINT)
        yaw = {"heading": qpos[:, int(j.qposadr[0])],
               "yaw_rate": sensordata[0][:, sensor_slice(model, GYRO_SENSOR).start
                                         + GYRO_AXIS_COMPONENT]}
    return VehicleTruth(
        t=config.t, pos=qpos[:, [qadr[a] for a in AXES]], vel=qvel[:, [vadr[a] for a in AXES]],
        acc=sensordata[0][:, cols], acc_cmd=cmd, mass=mass, **yaw)


def apply_sensor_errors(acc_true: np.ndarray, sensor: SensorErrorModel,
                        rng: np.random.Generator, t: np.ndarray | None = None) -> np.ndarray:
    """Measured readings ``A_m = (1 + scale)·A_r + bias + v`` (+ any extra error terms).

    The one place where the vehicle run meets the sensor error model
    (:meth:`bench.sensors.SensorErrorModel.apply`); swap the model here.
    """
    return sensor.apply(acc_true, rng, t)


def gyro_rng(seed: int) -> np.random.Generator:
    """The gyro's noise stream of ``seed`` (spawn key :data:`GYRO_STREAM`)."""
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(GYRO_STREAM,)))


def measure_gyro(yaw_rate: np.ndarray, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """Measured yaw rate ``ω_m = ω + v_g``, ``v_g ~ N(0, σ_g²)`` white, rad/s."""
    return np.asarray(yaw_rate, dtype=float) + rng.normal(0.0, float(sigma),
                                                          np.shape(yaw_rate))


@dataclass(frozen=True)
class VehicleRun:
    """A generated vehicle run: what a student gets (``t``, ``aerr`` and, turning, ``gyro``
    rad/s) and the truth."""

    t: np.ndarray
    aerr: np.ndarray
    truth: VehicleTruth
    config: VehicleConfig
    seed: int
    gyro: np.ndarray | None = None

    def acel(self) -> Acel:
        return Acel(self.t, self.aerr, source=f"bench vehicle seed {self.seed}", gyro=self.gyro)

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
    gyro = (None if truth.yaw_rate is None
            else measure_gyro(truth.yaw_rate, config.gyro_sigma, gyro_rng(seed)))
    return VehicleRun(t=truth.t, aerr=aerr, truth=truth, config=config, seed=int(seed),
                      gyro=gyro)


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
        "acel": save_mat(out / "acel.mat", {"t": run.t, "Aerr": run.aerr,
                                            **({} if run.gyro is None else {"gyro": run.gyro})},
                         force=True),
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
    "COURSE_PROFILE", "COURSE_SENSOR", "GYRO_SIGMA", "GYRO_STREAM", "Segment", "TURN_PROFILE",
    "VehicleConfig", "VehicleRun", "VehicleTruth", "YawSegment", "add_yaw",
    "apply_sensor_errors", "generate_vehicle", "gyro_rng", "make_vehicle_run", "measure_gyro",
    "simulate_vehicle", "vehicle_mass", "vehicle_model", "write_vehicle", "yaw_inertia",
]

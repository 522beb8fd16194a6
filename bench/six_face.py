"""The MuJoCo twin of the six-face test: a 3-axis accelerometer in a case, held on its faces.

The experiment people run on a real IMU — lay the case on each face, hold it still, tumble it
to the next face — run on ``models/six_face_fixture.xml``: three nested hinges driven by
position servos turn the case; MuJoCo's 3-axis accelerometer (and gyro) on the site ``imu``
(site frame = the case axes) give the true specific force ``a_c`` (m/s²) and rate ``ω_c``
(rad/s) in case axes at every sample, the holds *and* the tumbles between them.

Run (one continuous simulation, chained ``mujoco.rollout`` calls, one per segment)::

    hold 0 (hold_seconds) → tumble (TUMBLE_SECONDS, minimum-jerk command)
    + settle (SETTLE_SECONDS, command at the next face) → hold 1 → …

The holds visit ``faces`` in order, the list repeated ``holds_per_face`` times, so that the
re-holds of a face are separate placements (that is how hold-to-hold repeatability shows).

Placement wobble (the between-hold component). Each hold's case sits tilted: its three joint
targets are offset by ``δ_h ~ N(0, σ_p² I₃)`` (σ_p = ``wobble_std``, rad). At every face one of
the three hinges turns the case about the vertical (no effect on the readings) and the other
two tilt it about two orthogonal horizontal axes with unit gain, so the case's up direction
leaves the face normal by a tilt of std σ_p about each horizontal axis (to first order). An
axis lying horizontal then reads ``g·ε`` off its face value from hold to hold; the axis along
gravity only ``g(1 − cos ε) ≈ g ε²/2`` (second order: E = g σ_p², a scale shift of −σ_p²).

Sensor model (IEEE Std 1293 linear terms, the convention of
:mod:`calib.calibration.sixface`)::

    m = b + K · a_c + v (+ output-stage terms),   K = (I + S)(I + M)

``b`` (3,) bias, m/s² (K0; positive shifts the reading up); ``S = diag(s)`` scale errors
(dimensionless; positive: the axis reads too much); ``M`` the misalignment (rad, small
angles, zero diagonal): ``m_ab`` leans sensitive axis a toward case axis b, so axis a reads
``+m_ab·g`` (times 1 + s_a) with case axis b up. ``v`` white noise of variance ``noise_var``
per axis, then the output-stage terms of :mod:`bench.terms` (bias instability, bias random
walk, quantization: the terms of a ``sensor.json`` profile), one
:class:`bench.sensors.AxisErrors` per axis. The gyro gets white noise ``gyro_sigma`` (rad/s).

Random draws: ``SeedSequence(seed).spawn(3)`` → the wobble (H × 3 normals), the
accelerometer (axis x, y, z in turn: white noise, then its terms in order), the gyro (N × 3).
The same seed and configuration give the same bytes.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mujoco
import mujoco.rollout
import numpy as np

from bench.model import (
    FIXTURE_ENCODERS,
    FIXTURE_JOINTS,
    FIXTURE_SERVOS,
    IMU_ACCEL,
    IMU_GYRO,
    full_state,
    sensor_slice,
    six_face_fixture,
)
from bench.sensors import AxisErrors
from bench.terms import SensorContext
from calib.calibration.sixface import AXES_3, face_vectors
from calib.conventions import G

FACES: tuple[str, ...] = ("+x", "-x", "+y", "-y", "+z", "-z")
"""The six faces: the case axis that points up, with its sign (face ``+z``: z reads +g)."""
FACE_ANGLES: dict[str, tuple[float, float, float]] = {
    "+z": (0.0, 0.0, 0.0), "-z": (math.pi, 0.0, 0.0),
    "+y": (math.pi / 2, 0.0, 0.0), "-y": (-math.pi / 2, 0.0, 0.0),
    "+x": (math.pi / 2, 0.0, math.pi / 2), "-x": (math.pi / 2, 0.0, -math.pi / 2),
}
"""Hinge angles (α, β, γ) rad of ``tumble_x``, ``tumble_y``, ``tumble_z`` that put each face
up (models/six_face_fixture.xml: u = Rz(−γ)·Ry(−β)·Rx(−α)·e_z)."""
MISALIGNMENT_NAMES: tuple[str, ...] = ("xy", "xz", "yx", "yz", "zx", "zy")
"""Order of the six misalignment angles m_ab (that of :mod:`calib.calibration.sixface`)."""
TUMBLE_SECONDS = 1.5
"""Length of the commanded minimum-jerk tumble between two holds, s."""
SETTLE_SECONDS = 0.5
"""The servo settles at the next face for this long before the hold counts, s (the case is
then still to ~1e-9 rad; the rows are moving rows of the log all the same)."""
MIN_HOLD_SECONDS = 2.0
"""Shortest hold, s: the pose detector (:mod:`calib.logs.poses`) ignores holds under 1 s and
trims half a 0.5 s window at each edge."""
MAX_TILT = 0.1
"""Largest placement wobble σ_p and misalignment angle, rad (5.7°): beyond, a hold is no
longer a small-angle placement on a face."""
TRUTH_FORMAT = "tiltbench-six-face-truth"
TRUTH_FORMAT_VERSION = 1
LOG_NAME = "log.csv"
TRUTH_NAME = "truth.json"
LOG_HEADER = ("t (s),acc_x (m/s^2),acc_y (m/s^2),acc_z (m/s^2),"
              "gyro_x (rad/s),gyro_y (rad/s),gyro_z (rad/s)")
"""The CSV header: units stated in brackets (:mod:`calib.logs.csvlog` recognizes them)."""

TRUTH_UNITS: dict[str, str] = {
    "g": "m/s²", "rate": "Hz", "hold_seconds": "s", "tumble_seconds": "s",
    "settle_seconds": "s", "holds_per_face": "count", "n": "count", "seed": "—",
    "sensor.bias": "m/s²", "sensor.scale": "1", "sensor.misalignment": "rad",
    "sensor.k_matrix": "1", "sensor.noise_std": "m/s²", "sensor.noise_var": "(m/s²)²",
    "sensor.gyro_sigma": "rad/s", "sensor.axes.*.noise_var": "(m/s²)²",
    "sensor.axes.*.terms.b": "m/s²", "sensor.axes.*.terms.q_per_sample": "m/s²/√sample",
    "sensor.axes.*.terms.lsb": "m/s²",
    "params.values": "bias m/s², scale 1, misalignment rad",
    "between_hold.tilt_std": "rad", "between_hold.sigma_between_pooled": "m/s²",
    "between_hold.sigma_between": "m/s²",
    "holds.start": "sample", "holds.stop": "sample", "holds.t_start": "s", "holds.t_stop": "s",
    "holds.joint_offsets": "rad", "holds.tilt": "rad", "holds.up": "1",
    "holds.mean_specific_force": "m/s²",
    "sensor_profile.sample_rate": "Hz", "sensor_profile.run_rate": "Hz",
    "sensor_profile.white_noise_density": "(m/s²)/√Hz",
    "sensor_profile.bias_instability": "m/s²", "sensor_profile.rate_random_walk": "m/s²/√s",
    "sensor_profile.quantization_step": "m/s²",
}
"""Units of ``truth.json`` (docs/six-face-twin.md)."""


def check_faces(faces: tuple[str, ...] | list[str]) -> tuple[str, ...]:
    """The faces as a tuple; ValueError naming an unknown one (faces are :data:`FACES`)."""
    faces = tuple(faces)
    if not faces:
        raise ValueError("no faces given; faces are " + ", ".join(FACES))
    for f in faces:
        if f not in FACE_ANGLES:
            raise ValueError(f"unknown face {f!r}; faces are {', '.join(FACES)} (the case axis "
                             "that points up, with its sign)")
    return faces


def check_identifiable(faces: tuple[str, ...], g: float = G, source: str = "<faces>") -> None:
    """Refuse faces that cannot identify every parameter of the six-face fit: the
    :class:`calib.calibration.ls.NotIdentifiableError` (a ValueError) that
    :func:`calib.calibration.sixface.fit_six_face` raises on holds on these faces, with its
    message (the parameters left free and the faces that would fix them)."""
    from calib.calibration.multiposition import Poses
    from calib.calibration.sixface import fit_six_face, on_faces

    h = len(check_faces(faces))
    poses = Poses(np.arange(h), np.full(h, 2), g * face_vectors(tuple(faces)), np.ones((h, 3)))
    if not on_faces(poses):
        fit_six_face(poses, g=g, source=source)  # raises, naming what the faces leave free
        raise ValueError(f"{source}: these faces do not make a six-face test")


def twin_axes(profile: Any, rate: float) -> tuple[tuple[AxisErrors, AxisErrors, AxisErrors],
                                                  dict[str, str]]:
    """The noise of the three axes from a sensor profile (``sensor.json`` read by
    :func:`calib.noise.sensor_profile.load_profile`) at ``rate`` Hz, through
    :func:`bench.sensor_twin.twin_axis`: white noise (per-sample σ = N·√rate), bias
    instability, random walk, quantization. The profile's calibration is not used (bias, scale
    and misalignment are the run's). A profile holds the tilt plane's x and y (what
    ``tiltbench noise`` writes); z takes the terms of the noisier of the two (larger
    white-noise density). Returns the three :class:`AxisErrors` and the profile axis each
    came from."""
    from bench.sensor_twin import twin_axis

    plane = ("x", "y")
    dens = []
    for name in plane:
        term = profile.white_noise_density[profile.axes.index(name)]
        dens.append(-1.0 if term is None else float(term.value))
    source = (*plane, plane[int(np.argmax(dens))])
    axes = tuple(twin_axis(profile, plane.index(name), rate) for name in source)
    return axes, dict(zip(AXES_3, source, strict=True))  # type: ignore[return-value]


# ---------------------------------------------------------------- the sensor
@dataclass(frozen=True)
class ThreeAxisSensor:
    """True errors of a 3-axis accelerometer (and the white noise of its gyro).

    Attributes
    ----------
    bias : (3,) m/s², per case axis x, y, z (K0); positive shifts the reading up.
    scale : (3,) dimensionless scale errors s (K1 − 1); positive: the axis reads too much.
    misalignment : (6,) rad, m_xy, m_xz, m_yx, m_yz, m_zx, m_zy (:data:`MISALIGNMENT_NAMES`):
        sensitive axis a leans toward case axis b by the small angle m_ab.
    axes : per axis, the white noise ``noise_var`` ((m/s²)²) and output-stage
        :mod:`bench.terms` (bias instability, random walk, quantization) as
        :class:`bench.sensors.AxisErrors`; their own bias and scale stay 0 (here they are
        ``bias`` and K).
    gyro_sigma : white noise std of each gyro axis, rad/s.

    Notes
    -----
    ``m = b + K·a_c + v``, ``K = (I + S)(I + M)`` (module docstring; the six-face fit's
    convention, :mod:`calib.calibration.sixface`).
    """

    bias: tuple[float, float, float] = (0.0, 0.0, 0.0)
    scale: tuple[float, float, float] = (0.0, 0.0, 0.0)
    misalignment: tuple[float, ...] = (0.0,) * 6
    axes: tuple[AxisErrors, AxisErrors, AxisErrors] = (AxisErrors(), AxisErrors(),
                                                       AxisErrors())
    gyro_sigma: float = 0.0

    def __post_init__(self) -> None:
        for name, size in (("bias", 3), ("scale", 3), ("misalignment", 6)):
            values = tuple(float(v) for v in getattr(self, name))
            if len(values) != size or not all(math.isfinite(v) for v in values):
                raise ValueError(f"sensor {name} must be {size} finite numbers, got {values}")
            object.__setattr__(self, name, values)
        if any(s <= -1 for s in self.scale):
            raise ValueError(f"scale must be > -1 on every axis (1 + scale is the gain), got "
                             f"{self.scale}")
        if any(abs(m) > MAX_TILT for m in self.misalignment):
            raise ValueError(f"misalignment angles must be small, |m_ab| <= {MAX_TILT} rad, "
                             f"got {self.misalignment}")
        if len(self.axes) != 3:
            raise ValueError("axes: give the noise of three axes x, y, z")
        for name, err in zip(AXES_3, self.axes, strict=True):
            if err.bias != 0 or err.scale != 0:
                raise ValueError(f"axis {name}: its bias and scale belong in the sensor's "
                                 "bias / scale (K), not in its AxisErrors")
            if any(t.stage != "output" for t in err.terms):
                raise ValueError(f"axis {name}: only output-stage terms (bias instability, "
                                 "random walk, quantization) apply to the 3-axis sensor")
        if not (math.isfinite(self.gyro_sigma) and self.gyro_sigma >= 0):
            raise ValueError(f"gyro_sigma must be a finite number >= 0 rad/s, got "
                             f"{self.gyro_sigma}")

    def misalignment_matrix(self) -> np.ndarray:
        """(3, 3) M, rad: ``M[a, b] = m_ab``, zero diagonal."""
        m = np.zeros((3, 3))
        for (a, b), v in zip(MISALIGNMENT_NAMES, self.misalignment, strict=True):
            m[AXES_3.index(a), AXES_3.index(b)] = v
        return m

    def k_matrix(self) -> np.ndarray:
        """(3, 3) ``K = (I + S)(I + M)``, dimensionless (rows: sensor axes; columns: case
        axes)."""
        return (np.eye(3) + np.diag(self.scale)) @ (np.eye(3) + self.misalignment_matrix())

    def params(self) -> tuple[tuple[str, ...], np.ndarray]:
        """The truth in the six-face fit's parametrization: 12 names (per axis a: ``bias_a``,
        ``scale_a``, then ``misalignment_ab`` for the two other axes in order) and values (m/s²,
        1, rad)."""
        names, values = [], []
        m = self.misalignment_matrix()
        for k, a in enumerate(AXES_3):
            others = [j for j in range(3) if j != k]
            names += [f"bias_{a}", f"scale_{a}", *(f"misalignment_{a}{AXES_3[j]}"
                                                   for j in others)]
            values += [self.bias[k], self.scale[k], *(m[k, j] for j in others)]
        return tuple(names), np.array(values)

    def apply(self, a_case: np.ndarray, rng: np.random.Generator,
              t: np.ndarray | None = None) -> np.ndarray:
        """Readings (N, 3), m/s², from the true specific force ``a_case`` (N, 3) in case axes.

        Per axis a: ``b_a + K_a·a_c``, then white noise, then the output-stage terms
        (draws in the order x, y, z)."""
        a_case = np.asarray(a_case, dtype=float)
        if a_case.ndim != 2 or a_case.shape[1] != 3:
            raise ValueError(f"a_case must be (N, 3), got {a_case.shape}")
        ideal = a_case @ self.k_matrix().T + np.asarray(self.bias)
        out = np.empty_like(ideal)
        for k, err in enumerate(self.axes):
            a = ideal[:, k].copy()
            if err.noise_var > 0:
                a = a + math.sqrt(err.noise_var) * rng.standard_normal(a.shape[0])
            ctx = SensorContext(a_case, t, k)
            for term in err.terms:
                a = term.apply(a, ctx, rng)
            out[:, k] = a
        return out

    def gyro(self, w_case: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Gyro readings (N, 3), rad/s: the true rate ``w_case`` (N, 3) plus white noise."""
        w_case = np.asarray(w_case, dtype=float)
        if self.gyro_sigma == 0:
            return w_case.copy()
        return w_case + self.gyro_sigma * rng.standard_normal(w_case.shape)

    def to_dict(self) -> dict[str, Any]:
        noise_var = [err.noise_var for err in self.axes]
        return {"bias": list(self.bias), "scale": list(self.scale),
                "misalignment": self.misalignment_matrix().tolist(),
                "misalignment_order": [f"m_{n}" for n in MISALIGNMENT_NAMES],
                "k_matrix": self.k_matrix().tolist(),
                "k_convention": "K = (I + S)(I + M); reading m = b + K a_case + v",
                "noise_var": noise_var, "noise_std": [math.sqrt(v) for v in noise_var],
                "axes": {a: err.to_dict() for a, err in zip(AXES_3, self.axes, strict=True)},
                "gyro_sigma": self.gyro_sigma}


# ---------------------------------------------------------------- the run
@dataclass(frozen=True)
class SixFaceConfig:
    """Everything that defines a six-face run (besides the seed).

    Attributes
    ----------
    faces : the faces in hold order (:data:`FACES` names; repeats allowed).
    holds_per_face : the face list is held this many times over (re-holds: repeatability).
    hold_seconds : length of each hold, s (>= :data:`MIN_HOLD_SECONDS`).
    rate : sample rate, Hz (1/rate a whole number of model timesteps).
    g : gravity, m/s² (MjSpec edit of the model).
    sensor : the true sensor errors.
    wobble_std : σ_p, rad: each hold's placement tilt (module docstring).
    twin : the ``sensor.json`` profile the noise came from (its record), or None.
    """

    faces: tuple[str, ...] = FACES
    holds_per_face: int = 2
    hold_seconds: float = 5.0
    rate: float = 100.0
    g: float = G
    sensor: ThreeAxisSensor = field(default_factory=ThreeAxisSensor)
    wobble_std: float = 0.0
    twin: dict | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "faces", check_faces(self.faces))
        if int(self.holds_per_face) != self.holds_per_face or self.holds_per_face < 1:
            raise ValueError(f"holds per face must be an integer >= 1, got "
                             f"{self.holds_per_face}")
        for name in ("hold_seconds", "rate", "g"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a positive finite number, got {v}")
        if self.hold_seconds < MIN_HOLD_SECONDS:
            raise ValueError(f"holds must last at least {MIN_HOLD_SECONDS:g} s (the pose "
                             f"detector ignores holds under 1 s and trims their edges), got "
                             f"{self.hold_seconds:g} s")
        if not (math.isfinite(self.wobble_std) and 0 <= self.wobble_std <= MAX_TILT):
            raise ValueError(f"the placement wobble must be in [0, {MAX_TILT}] rad, got "
                             f"{self.wobble_std}")

    def schedule(self) -> tuple[str, ...]:
        """The face of every hold, in order: ``faces`` repeated ``holds_per_face`` times."""
        return self.faces * int(self.holds_per_face)

    def to_dict(self) -> dict[str, Any]:
        d = {"faces": list(self.faces), "holds_per_face": int(self.holds_per_face),
             "hold_seconds": float(self.hold_seconds), "rate": float(self.rate),
             "g": float(self.g), "tumble_seconds": TUMBLE_SECONDS,
             "settle_seconds": SETTLE_SECONDS, "sensor": self.sensor.to_dict()}
        if self.twin is not None:
            d["sensor_profile"] = self.twin
        return d


def sample_stride(rate: float, timestep: float) -> int:
    """Physics steps per sample at ``rate`` Hz; ValueError unless 1/rate is a whole number of
    model timesteps."""
    stride = 1.0 / (rate * timestep)
    if stride < 0.5 or abs(stride - round(stride)) > 1e-9:
        raise ValueError(f"sample period 1/{rate:g} Hz must be a whole number of model "
                         f"timesteps ({timestep:g} s), e.g. {1 / timestep:g}, "
                         f"{1 / (2 * timestep):g}, {1 / (10 * timestep):g} Hz")
    return int(round(stride))


def segment_samples(config: SixFaceConfig) -> tuple[int, int]:
    """Samples per hold and per tumble (tumble + settle) at the run's rate."""
    n_hold = int(math.floor(config.hold_seconds * config.rate + 1e-9))
    n_move = int(math.floor((TUMBLE_SECONDS + SETTLE_SECONDS) * config.rate + 1e-9))
    return n_hold, max(n_move, 1)


def run_samples(config: SixFaceConfig) -> int:
    """Rows of the log: every hold and every tumble between two holds."""
    n_hold, n_move = segment_samples(config)
    h = len(config.schedule())
    return h * n_hold + (h - 1) * n_move


def _columns(model: mujoco.MjModel) -> tuple[slice, slice, list[int]]:
    """``sensordata`` columns of the accelerometer, the gyro and the three encoders."""
    enc = [sensor_slice(model, name).start for name in FIXTURE_ENCODERS]
    return sensor_slice(model, IMU_ACCEL), sensor_slice(model, IMU_GYRO), enc


def _pose(model: mujoco.MjModel, data: mujoco.MjData, angles: np.ndarray) -> None:
    """Set ``data`` to rest at hinge angles ``angles`` (3,) rad with the servos aimed there."""
    mujoco.mj_resetData(model, data)
    for name, servo, q in zip(FIXTURE_JOINTS, FIXTURE_SERVOS, angles, strict=True):
        data.qpos[int(model.joint(name).qposadr[0])] = q
        data.ctrl[int(model.actuator(servo).id)] = q
    mujoco.mj_forward(model, data)


def face_readings(faces: tuple[str, ...] | list[str], g: float = G) -> np.ndarray:
    """True specific force (H, 3), m/s², in case axes, of the case resting on each face (no
    sensor errors): MuJoCo's accelerometer after ``mj_forward`` at the face's hinge angles
    (:data:`FACE_ANGLES`), ``qvel = 0``, servos aimed at the pose (no torque). Face ``+z``
    reads ``(0, 0, +g)``."""
    model, _ = six_face_fixture(g)
    data = mujoco.MjData(model)
    acc, _, _ = _columns(model)
    out = np.empty((len(faces), 3))
    for h, f in enumerate(check_faces(tuple(faces))):
        _pose(model, data, np.array(FACE_ANGLES[f]))
        out[h] = data.sensordata[acc]
    return out


def _min_jerk(n: int) -> np.ndarray:
    """(n,) the minimum-jerk blend 10τ³ − 15τ⁴ + 6τ⁵ at τ = k/n, k = 0 … n − 1."""
    tau = np.arange(n) / n
    return tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)


@dataclass(frozen=True)
class FixtureMotion:
    """What MuJoCo gives for a run: per sample, t (N,) s, the true specific force ``acc``
    (N, 3) m/s² and rate ``gyro`` (N, 3) rad/s in case axes, the encoder angles ``joints``
    (N, 3) rad, and ``hold`` (N,) int, the hold each sample belongs to (-1: tumbling)."""

    t: np.ndarray
    acc: np.ndarray
    gyro: np.ndarray
    joints: np.ndarray
    hold: np.ndarray


def simulate_fixture(targets: np.ndarray, n_hold: int, n_move: int, rate: float,
                     g: float = G) -> FixtureMotion:
    """Simulate the fixture: rest at ``targets[0]``, hold each target for ``n_hold`` samples,
    tumble to the next in ``n_move`` samples (a minimum-jerk servo command over
    :data:`TUMBLE_SECONDS`, then the command held).

    Parameters
    ----------
    targets : (H, 3) hinge angles (α, β, γ) rad of each hold.
    n_hold, n_move : samples per hold and per tumble.
    rate : sample rate, Hz (1/rate a whole number of timesteps).
    g : gravity, m/s².

    Returns
    -------
    FixtureMotion

    Notes
    -----
    One ``mujoco.rollout`` per segment, each starting from the state the previous one ended
    in: a continuous simulation whose memory is one segment's. A sample is the sensors at the
    state before that step's integration (the rollout's ``sensordata`` rows every stride).
    """
    targets = np.asarray(targets, dtype=float)
    model, _ = six_face_fixture(g)
    data = mujoco.MjData(model)
    stride = sample_stride(rate, model.opt.timestep)
    acc_cols, gyro_cols, enc_cols = _columns(model)
    ctrl_cols = [int(model.actuator(s).id) for s in FIXTURE_SERVOS]
    _pose(model, data, targets[0])
    state = full_state(model, data)
    tumble_steps = int(round(TUMBLE_SECONDS / model.opt.timestep))
    rows, holds = [], []
    for h in range(targets.shape[0]):
        segments = [(n_hold, h, None)]
        if h + 1 < targets.shape[0]:
            segments.append((n_move, -1, h + 1))
        for n, label, nxt in segments:
            nstep = n * stride
            command = np.empty((nstep, model.nu))
            if nxt is None:
                command[:, ctrl_cols] = targets[h]
            else:
                blend = np.ones(nstep)
                k = min(tumble_steps, nstep)
                blend[:k] = _min_jerk(tumble_steps)[:k]
                command[:, ctrl_cols] = targets[h] + blend[:, None] * (targets[nxt] - targets[h])
            states, sensordata = mujoco.rollout.rollout(model, data, state[None, :],
                                                        command[None], nstep=nstep)
            rows.append(sensordata[0, ::stride])
            holds.append(np.full(n, label, dtype=int))
            state = states[0, -1]
    sd = np.concatenate(rows)
    if not np.all(np.isfinite(sd)):
        raise ValueError("the fixture's simulation diverged (non-finite readings)")
    t = np.arange(sd.shape[0]) / float(rate)
    return FixtureMotion(t=t, acc=sd[:, acc_cols], gyro=sd[:, gyro_cols], joints=sd[:, enc_cols],
                         hold=np.concatenate(holds))


@dataclass(frozen=True)
class SixFaceRun:
    """A simulated six-face test of a 3-axis sensor with its truth.

    Attributes
    ----------
    t : (N,) s.  acc : (N, 3) readings, m/s², case axes.  gyro : (N, 3) readings, rad/s.
    motion : what MuJoCo gave (:class:`FixtureMotion`: the true specific force and rate, the
        hinge angles, the hold of each sample).
    offsets : (H, 3) rad, each hold's placement offsets of the three hinges.
    schedule : the face of each hold.
    config, seed : what made it.
    """

    t: np.ndarray
    acc: np.ndarray
    gyro: np.ndarray
    motion: FixtureMotion
    offsets: np.ndarray
    schedule: tuple[str, ...]
    config: SixFaceConfig
    seed: int

    def hold_truth(self) -> list[dict[str, Any]]:
        """Per hold: face, sample range, times, hinge offsets, the mean true specific force,
        the true up direction u_h and its tilt from the face normal (rad)."""
        out = []
        u_face = face_vectors(self.schedule)
        for h, face in enumerate(self.schedule):
            idx = np.flatnonzero(self.motion.hold == h)
            mean = self.motion.acc[idx].mean(axis=0)
            up = mean / np.linalg.norm(mean)
            tilt = float(np.arccos(np.clip(up @ u_face[h], -1.0, 1.0)))
            out.append({"face": face, "start": int(idx[0]), "stop": int(idx[-1]) + 1,
                        "t_start": float(self.t[idx[0]]), "t_stop": float(self.t[idx[-1]]),
                        "joint_offsets": self.offsets[h].tolist(),
                        "mean_specific_force": mean.tolist(), "up": up.tolist(),
                        "tilt": tilt})
        return out

    def truth(self) -> dict[str, Any]:
        """The ``truth.json`` object (without versions and units: :func:`truth_manifest`)."""
        cfg = self.config
        names, values = cfg.sensor.params()
        u = face_vectors(self.schedule)
        horizontal = np.mean(np.abs(u) < 0.5, axis=0)  # share of holds with axis a level
        return {
            "format": TRUTH_FORMAT, "format_version": TRUTH_FORMAT_VERSION,
            "kind": "six_face", "model": "models/six_face_fixture.xml", "log": LOG_NAME,
            "n": int(self.t.size), **cfg.to_dict(), "schedule": list(self.schedule),
            "params": {"param_names": list(names), "values": values.tolist(),
                       "convention": "calib.calibration.sixface: m_h,a = b_a + g K_a u_h, "
                                     "K = (I + S)(I + M), m_ab = K_ab / K_aa"},
            "between_hold": {
                "tilt_std": float(cfg.wobble_std),
                "model": "each hold's three hinge targets offset by N(0, tilt_std²): a tilt "
                         "of std tilt_std about each horizontal axis, one offset a turn "
                         "about the vertical",
                "sigma_between": [[cfg.g * cfg.wobble_std**2, cfg.g * cfg.wobble_std]] * 3,
                "sigma_between_pooled": (cfg.g * cfg.wobble_std
                                         * np.sqrt(horizontal)).tolist(),
                "sigma_between_note": "sigma_between: per axis, what the six-face fit's σ_B "
                                      "of its two classes estimates, to first order: axis "
                                      "vertical (faces ±a) g·tilt_std² (the std of "
                                      "g·(1 − cos ε) ≈ g·ε²/2), axis level g·tilt_std; "
                                      "sigma_between_pooled: one σ_B pooled over all holds, "
                                      "g·tilt_std·√(share of holds with the axis level)",
            },
            "holds": self.hold_truth(),
        }


def generate_six_face(config: SixFaceConfig, seed: int) -> SixFaceRun:
    """Simulate the six-face test of ``config`` (module docstring); same seed, same numbers."""
    wobble_ss, acc_ss, gyro_ss = np.random.SeedSequence(int(seed)).spawn(3)
    schedule = config.schedule()
    offsets = config.wobble_std * np.random.default_rng(wobble_ss).standard_normal(
        (len(schedule), 3))
    targets = np.array([FACE_ANGLES[f] for f in schedule]) + offsets
    n_hold, n_move = segment_samples(config)
    motion = simulate_fixture(targets, n_hold, n_move, config.rate, config.g)
    acc = config.sensor.apply(motion.acc, np.random.default_rng(acc_ss), motion.t)
    gyro = config.sensor.gyro(motion.gyro, np.random.default_rng(gyro_ss))
    return SixFaceRun(t=motion.t, acc=acc, gyro=gyro, motion=motion, offsets=offsets,
                      schedule=schedule, config=config, seed=int(seed))


def log_text(run: SixFaceRun) -> str:
    """The measured-log style CSV: :data:`LOG_HEADER`, then t (µs resolution), the three
    accelerations (1e-7 m/s²) and the three rates (1e-7 rad/s) of every sample, holds and
    tumbles alike."""
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack([run.t, run.acc, run.gyro]),
               fmt=["%.6f"] + ["%.7f"] * 6, delimiter=",", header=LOG_HEADER, comments="")
    return buf.getvalue()


def truth_manifest(run: SixFaceRun) -> dict[str, Any]:
    """``truth.json``: :meth:`SixFaceRun.truth` with the seed, the package and MuJoCo
    versions (:func:`bench.dataset.versions`) and the units (:data:`TRUTH_UNITS`)."""
    from bench.dataset import versions
    from calib.units import with_units

    manifest = run.truth()
    manifest["seed"] = int(run.seed)
    manifest["versions"] = versions()
    return with_units(manifest, TRUTH_UNITS)


def write_six_face(run: SixFaceRun, out: str | Path, force: bool = False) -> dict[str, str]:
    """Write ``log.csv`` and ``truth.json`` into ``out`` atomically; refuses (before writing
    anything) when either exists, unless ``force``."""
    from bench.dataset import prepare_out_dir, write_json
    from calib.files.atomic import write_text

    out = prepare_out_dir(out, [LOG_NAME, TRUTH_NAME], force)
    paths = {"log": write_text(out / LOG_NAME, log_text(run), force=True),
             "truth": write_json(out / TRUTH_NAME, truth_manifest(run), force=True)}
    return {k: str(v) for k, v in paths.items()}


__all__ = ["FACES", "FACE_ANGLES", "LOG_HEADER", "LOG_NAME", "MAX_TILT",
           "MIN_HOLD_SECONDS", "MISALIGNMENT_NAMES", "SETTLE_SECONDS", "TRUTH_FORMAT",
           "TRUTH_FORMAT_VERSION", "TRUTH_NAME", "TRUTH_UNITS", "TUMBLE_SECONDS",
           "FixtureMotion", "SixFaceConfig", "SixFaceRun", "ThreeAxisSensor", "check_faces",
           "check_identifiable", "twin_axes",
           "face_readings", "generate_six_face", "log_text", "run_samples",
           "sample_stride", "segment_samples", "simulate_fixture", "truth_manifest",
           "write_six_face"]

"""Re-run a measured experiment on the bench: static poses or a servo replay of θ(t).

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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import mujoco
import mujoco.rollout
import numpy as np
from scipy.interpolate import CubicSpline

from bench.model import ACC_SENSORS, ENCODER, TableEdits, full_state, sensor_slice, tilt_table
from bench.tilt import static_readings
from calib.conventions import AXES

ReplayMode = Literal["static", "sweep"]

MAX_SWEEP_STEP = 0.5
"""rad: a larger jump between consecutive samples means held positions, not a sweep."""

HELD_FRACTION = 0.01
"""A run whose consecutive samples repeat θ more often than this is treated as static."""

MAX_REPLAY_STEPS = 2_000_000
"""Longest servo replay (physics steps, ≈ 2000 s at 1 kHz); longer runs use static poses,
which give the same readings for sites on the hinge axis (only a lever arm differs)."""


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


def accel_columns(model: mujoco.MjModel) -> list[int]:
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
    return rows[:, accel_columns(model)], rows[:, enc]


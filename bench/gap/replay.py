"""Re-run a measured experiment on the bench: static poses or a servo replay of θ(t).

The rule (``docs/gap.md``):

* **static** — no timing (no ``t``, no ``--rate``), or θ never moves, or θ only changes by
  *jumps* (below) between held positions: every distinct θ is a static pose
  (:func:`bench.tilt.static_readings`), exactly what a static bench run produces.
* **sweep** — timing and θ moving anywhere, stops included: the measured encoder angle is
  replayed through the table's position servo. A shape-preserving interpolant of θ(t)
  (:func:`profile`: a cubic spline per moving stretch, held stretches exactly flat, zero
  slope where a stretch meets a hold) is sampled at the physics steps; the step states are
  those of MuJoCo's integrator passing through it (:func:`step_motion`: semi-implicit Euler,
  ``v_{j+1} = v_j + h·a_j``, ``q_{j+1} = q_j + h·v_{j+1}``, so ``v_j = (q_j − q_{j−1})/h`` and
  ``a_j = (v_{j+1} − v_j)/h``), and MuJoCo's discrete-time inverse dynamics
  (``mj_inverse`` with ``mjENBL_INVDISCRETE``) gives the joint torque of each step and the
  servo command that delivers it (``u = (τ - b0 - b1·θ - b2·ω) / gain``, the actuator's
  affine law). The simulated table then passes through the interpolant at every step to
  rounding (≈ 1e-15 rad), where the torque of the interpolant's own ω and α at the steps
  (not the integrator's differences) left it up to ≈ 1e-3 rad behind on a fast reversal;
  commanding the servo with the measured angle itself would add the servo lag, ≈ 0.014 rad
  at 20 s/rev, a spurious tilt offset. The sensors are read at the measured sample times
  (:func:`record_motion`): only the steps the samples read are stepped, each by MuJoCo from
  its state, and where each lands is checked against the next state of the interpolant
  (``Motion.miss``; a whole-run rollout of the same commands passes through the same states,
  ``tests/test_gap_bench.py``). The largest encoder difference between replay and data is
  reported (``replay.tracking_error``).

**Jumps.** A step between two consecutive samples that no tilt table can make — a mean rate
above :data:`MAX_TABLE_RATE` or a finite-difference acceleration at either end above
:data:`MAX_TABLE_ACCEL` — is a move that was not sampled (e.g. held positions logged with
``--rate``). It is replayed as an instantaneous move: the replay is split there into pieces
(:class:`Piece`); each piece starts from the measured θ with the interpolant's rate (at rest
when it starts on a hold), and a piece whose θ is constant is a static pose.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import mujoco
import mujoco.rollout
import numpy as np
from scipy.interpolate import CubicSpline

from bench.model import (
    ACC_SENSORS,
    ENCODER,
    TILT_JOINT,
    TableEdits,
    full_state,
    sensor_slice,
    tilt_table,
)
from bench.tilt import static_readings
from calib.conventions import AXES

ReplayMode = Literal["static", "sweep"]

MAX_TABLE_RATE = 50.0
"""rad/s (≈ 8 rev/s): a larger mean rate between two samples is a jump, not a sampled move.
The bench's own fastest generated sweeps reach ≈ 11 rad/s (``sine``, 5 s, 3 cycles)."""

MAX_TABLE_ACCEL = 1000.0
"""rad/s²: a larger finite-difference acceleration at either end of a step is a jump. The
tilt table (I = 0.09 kg·m², servo kp = 200 N·m/rad) would need 90 N·m, a servo error of
0.45 rad; the bench's fastest generated sweeps reach ≈ 40 rad/s². A move between two held
samples 10 ms apart needs ≥ 4·Δθ/Δt² (bang-bang): 0.39 rad (16 positions) is 1.6e4 rad/s²."""

TRACKING_LIMIT = 1e-3
"""rad: a replay whose encoder differs from the measured one by more did not follow θ (the
report says so); the servo replay passes through the interpolant at every step (≈ 1e-15
rad), so only a table MuJoCo cannot move as commanded (a clamp, a limit) reaches it."""

MISS_TOL = 1e-9
"""rad: largest difference between where MuJoCo's step lands and the interpolant's next state
(position, and velocity times the step) for the steps read alone to stand for the whole
rollout (:func:`record_motion`); rounding gives ≈ 1e-15. Above it the run is rolled out."""

MAX_REPLAY_STEPS = 2_000_000
"""Longest servo replay (physics steps, ≈ 2000 s at 1 kHz); longer runs use static poses,
which give the same readings for sites on the hinge axis (only a lever arm differs)."""


def _step_union(*steps: np.ndarray) -> np.ndarray:
    """The sorted distinct non-negative step numbers among ``steps`` (integer arrays).

    A mark per step, not ``np.unique``: numpy 2.4 finds distinct integers with a hash table
    and then sorts them, 0.12 s for the 3·10⁵ steps of a 60001-sample sweep, against 1.3 ms
    for these marks (the steps are at most the run's, a few 10⁵)."""
    if not any(s.size for s in steps):
        return np.zeros(0, dtype=int)
    mark = np.zeros(max(int(s.max()) for s in steps if s.size) + 1, dtype=bool)
    for s in steps:
        mark[s[s >= 0]] = True
    return np.flatnonzero(mark)


@dataclass(frozen=True)
class Piece:
    """Samples ``[first, stop)`` replayed continuously (a run without jumps is one piece).

    nstep : physics steps of the piece, at ``t[first] + j·dt`` (0: θ is constant there, a
        static pose). dt : the physics timestep, s.
    qvel0 : joint velocity of the first step, rad/s: the interpolant's rate half a step
        before ``t[first]`` (semi-implicit Euler's velocities sit half a step back).
    rows, weights : sample ``first + i`` is ``(1 - w_i)·step[rows_i] + w_i·step[rows_i + 1]``.
    """

    first: int
    stop: int
    nstep: int = 0
    dt: float = 0.0
    qvel0: float = 0.0
    rows: np.ndarray | None = None
    weights: np.ndarray | None = None

    @property
    def static(self) -> bool:
        return self.nstep == 0

    def read_steps(self) -> np.ndarray:
        """The steps the samples read, sorted: ``rows``, and ``rows + 1`` where a sample falls
        between two steps."""
        return _step_union(self.rows, np.minimum(self.rows + 1, self.nstep - 1)[
            self.weights > 0])


@dataclass(frozen=True)
class Replay:
    """A measured experiment as the bench re-runs it.

    Attributes
    ----------
    mode : "static" (distinct poses) or "sweep" (servo replay of θ(t)).
    tita : (N,) measured encoder angle, rad.  t : (N,) sample times, s, or None.
    reason : why this mode was chosen (for the report).
    pieces : sweep: the stretches between jumps (:class:`Piece`), in sample order.
    holds : number of held stretches (≥ 2 consecutive equal θ) kept still.
    jumps : sample indices k whose step to k + 1 is a jump (instantaneous move).
    """

    mode: ReplayMode
    tita: np.ndarray
    t: np.ndarray | None
    reason: str
    pieces: tuple[Piece, ...] = ()
    holds: int = 0
    jumps: tuple[int, ...] = ()

    @property
    def n(self) -> int:
        return int(self.tita.shape[0])

    @property
    def nstep(self) -> int:
        return sum(p.nstep for p in self.pieces)


def timing(ensayo_t: np.ndarray | None, n: int, rate: float | None) -> np.ndarray | None:
    """Sample times: the file's ``t`` or ``k / rate`` (samples in time order), else None."""
    if ensayo_t is not None:
        return np.asarray(ensayo_t, dtype=float)
    if rate is not None:
        if not np.isfinite(rate) or rate <= 0:
            raise ValueError(f"--rate must be a positive sample rate in Hz, got {rate}")
        return np.arange(n, dtype=float) / float(rate)
    return None


INVERSE_CHECK_TOL = 1e-9
"""Largest disagreement, relative to the largest torque, between the closed-form inverse
dynamics of :func:`inverse_dynamics` and ``mj_inverse`` at its check states; above it the
per-step ``mj_inverse`` loop is used."""


def _inverse_loop(model: mujoco.MjModel, theta: np.ndarray, omega: np.ndarray,
                  alpha: np.ndarray, discrete: bool = False) -> np.ndarray:
    """Joint torque of motion (θ, ω, α) by ``mj_inverse`` at every entry (≈ 3 µs each);
    ``discrete``: the inverse of the integrator's step (``mjENBL_INVDISCRETE``: the torque
    whose step changes the velocity by ``α·dt``), else of the continuous-time dynamics."""
    data = mujoco.MjData(model)
    q = int(model.joint(TILT_JOINT).qposadr[0])
    v = int(model.joint(TILT_JOINT).dofadr[0])
    tau = np.empty_like(theta)
    flags = int(model.opt.enableflags)
    if discrete:
        model.opt.enableflags = flags | int(mujoco.mjtEnableBit.mjENBL_INVDISCRETE)
    try:
        for j in range(theta.size):
            data.qpos[q], data.qvel[v], data.qacc[v] = theta[j], omega[j], alpha[j]
            mujoco.mj_inverse(model, data)
            tau[j] = data.qfrc_inverse[v]
    finally:
        model.opt.enableflags = flags
    return tau


def _hinge_basis(theta: np.ndarray, omega: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    return np.column_stack([alpha, omega, theta, np.sin(theta), np.cos(theta),
                            np.ones_like(theta)])


def hinge_inverse_fit(model: mujoco.MjModel, theta: np.ndarray, omega: np.ndarray,
                      alpha: np.ndarray, discrete: bool = False) -> np.ndarray | None:
    """Coefficients (6,) of the closed-form inverse dynamics of :func:`inverse_dynamics` over
    the run's (θ, ω, α), or None when the model is not of that form (checked on
    ``mj_inverse``; ``discrete`` as in :func:`_inverse_loop`)."""
    if model.nv != 1 or theta.size <= 48:
        return None
    rng = np.random.default_rng(0)  # probe states only; any draw gives the same coefficients
    pick = rng.choice(theta.size, 48, replace=False)
    w_max = max(1.0, float(np.max(np.abs(omega))))
    a_max = max(1.0, float(np.max(np.abs(alpha))))
    th = theta[pick]
    om, al = rng.uniform(-w_max, w_max, 48), rng.uniform(-a_max, a_max, 48)
    tau = _inverse_loop(model, th, om, al, discrete)
    basis = _hinge_basis(th, om, al)
    coef = np.linalg.lstsq(basis[:24], tau[:24], rcond=None)[0]
    miss = np.max(np.abs(basis[24:] @ coef - tau[24:]))
    if not miss <= INVERSE_CHECK_TOL * max(1.0, float(np.max(np.abs(tau)))):
        return None
    return coef


def inverse_dynamics(model: mujoco.MjModel, theta: np.ndarray, omega: np.ndarray,
                     alpha: np.ndarray, discrete: bool = False) -> np.ndarray:
    """Joint torque τ (N·m) giving the hinge motion (θ rad, ω rad/s, α rad/s²), per entry;
    ``discrete``: the torque of one integrator step (MuJoCo's ``mjENBL_INVDISCRETE``: where
    the Euler step takes the joint damping implicitly it adds ``dt·D`` to M below; the tilt
    table turns that off, ``eulerdamp="disable"``, so both agree on it).

    ``mj_inverse`` (``qfrc_inverse``) called once per physics step is exact but a Python
    loop: ≈ 3 µs a step, 2 s for a 10-minute run at 1 kHz. MuJoCo has no batched inverse
    dynamics, so this uses the closed form it computes for a model whose only degree of
    freedom is one hinge about a fixed axis:

        τ = M·α + D·ω + K·θ + a·sin θ + b·cos θ + c

    M the inertia about the axis plus armature (constant: the body turns about that very
    axis, so no Coriolis term either), D the joint damping, K the stiffness, a and b the
    gravity torque of a centre of mass off the axis, c the spring reference (Featherstone,
    *Rigid Body Dynamics Algorithms*, 2008, §3.2). The six coefficients are fitted by
    least squares to ``mj_inverse`` at 24 states drawn over the run's (θ, ω, α) and checked
    at 24 others (:func:`hinge_inverse_fit`); if a check state disagrees by more than
    :data:`INVERSE_CHECK_TOL` of the largest torque (another joint, friction loss, a
    limit…), the per-step loop is used.
    """
    theta, omega, alpha = (np.asarray(x, dtype=float) for x in (theta, omega, alpha))
    coef = hinge_inverse_fit(model, theta, omega, alpha, discrete)
    if coef is None:
        return _inverse_loop(model, theta, omega, alpha, discrete)
    return _hinge_basis(theta, omega, alpha) @ coef


def servo_command(model: mujoco.MjModel, theta: np.ndarray, omega: np.ndarray,
                  alpha: np.ndarray, discrete: bool = True) -> np.ndarray:
    """Servo command of the steps from states (θ, ω) whose velocity changes by ``α·dt``:
    discrete-time inverse dynamics (:func:`inverse_dynamics`) + the actuator law
    (``discrete=False``: the continuous-time torque of (θ, ω, α), which a step does not
    follow exactly)."""
    gain = float(model.actuator_gainprm[0, 0])
    b0, b1, b2 = (float(v) for v in model.actuator_biasprm[0, :3])
    tau = inverse_dynamics(model, theta, omega, alpha, discrete=discrete)
    return (tau - b0 - b1 * theta - b2 * omega) / gain


def sample_torque(replay: Replay) -> np.ndarray | None:
    """The drive's joint torque at the samples of a servo replay, N·m (None for a static
    replay): inverse dynamics (:func:`inverse_dynamics`) of the replayed profile — θ, ω, α
    of :func:`profile` at the sample times of each moving piece, (θ, 0, 0) on a static pose.
    What the drive must deliver to move the table as measured; the analysis tests a level and
    a gain that follow it (:mod:`calib.gap.drive_state`)."""
    if replay.mode != "sweep" or replay.t is None or not replay.pieces:
        return None
    model, _ = tilt_table()
    tita, t = replay.tita, replay.t
    theta, omega, alpha = tita.copy(), np.zeros(replay.n), np.zeros(replay.n)
    for p in replay.pieces:
        if p.static:
            continue
        sl = slice(p.first, p.stop)
        theta[sl], omega[sl], alpha[sl] = profile(t[sl], tita[sl], t[sl])
    return inverse_dynamics(model, theta, omega, alpha)


def find_jumps(tita: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Indices k whose step θ_k → θ_{k+1} no table can make (a move that was not sampled).

    A jump has a mean rate ``|Δθ_k| / Δt_k`` above :data:`MAX_TABLE_RATE`, or a
    finite-difference acceleration ``|ω_{k+1/2} - ω_{k∓1/2}| / Δt`` at either end above
    :data:`MAX_TABLE_ACCEL` (ω_{k+1/2} = Δθ_k/Δt_k; Δt the mean of the two intervals).
    """
    dth, dt = np.diff(tita), np.diff(t)
    if dth.size == 0:
        return np.zeros(0, dtype=int)
    w = dth / dt
    fast = np.abs(w) > MAX_TABLE_RATE
    if dth.size > 1:
        acc = np.abs(np.diff(w)) / (0.5 * (dt[1:] + dt[:-1]))  # at sample j = i + 1
        for i in np.flatnonzero(acc > MAX_TABLE_ACCEL):  # steps i and i + 1 meet there:
            fast[i + int(abs(w[i + 1]) > abs(w[i]))] = True  # the faster one is the jump
    return np.flatnonzero(fast & (dth != 0.0))


def profile(t: np.ndarray, tita: np.ndarray, ts: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """θ, ω, α at times ``ts`` (sorted, from ``t[0]``) from samples without jumps; past
    ``t[-1]`` the last stretch goes on (its cubic, or its hold).

    Shape-preserving where the table stops: held stretches (consecutive equal θ) are exactly
    flat (ω = α = 0); each moving stretch between holds is a cubic spline with zero slope at
    an end that meets a hold (the table is at rest there) and not-a-knot at the ends of the
    run. A run without holds is one not-a-knot cubic spline. (A single cubic spline through
    a stop overshoots: it rings on both sides of the hold.)
    """
    theta, omega, alpha = (np.full(ts.shape, tita[0]), np.zeros(ts.shape), np.zeros(ts.shape))
    if tita.size < 2:
        return theta, omega, alpha
    flat = np.diff(tita) == 0.0
    idx = np.clip(np.searchsorted(t, ts, side="right") - 1, 0, t.size - 2)
    theta[:] = tita[idx]  # held intervals: the hold's value (exactly flat)
    moving = np.flatnonzero(~flat)
    if moving.size == 0:
        return theta, omega, alpha
    breaks = np.flatnonzero(np.diff(moving) > 1)
    for a, b in zip(np.r_[moving[0], moving[breaks + 1]], np.r_[moving[breaks], moving[-1]],
                    strict=True):
        # samples a … b + 1 move; a hold before a / after b + 1 pins the slope to 0
        bc0 = (1, 0.0) if a > 0 else "not-a-knot"
        bc1 = (1, 0.0) if b + 1 < t.size - 1 else "not-a-knot"
        spline = CubicSpline(t[a:b + 2], tita[a:b + 2], bc_type=(bc0, bc1))
        sel = slice(np.searchsorted(idx, a, "left"), np.searchsorted(idx, b, "right"))
        theta[sel], omega[sel], alpha[sel] = (spline(ts[sel], d) for d in range(3))
    return theta, omega, alpha


def _piece(dt: float, tita: np.ndarray, t: np.ndarray, first: int, stop: int) -> Piece:
    """Servo replay of samples ``[first, stop)`` (a static pose if θ is constant there)."""
    th, tt = tita[first:stop], t[first:stop]
    if np.all(th == th[0]):
        return Piece(first, stop)
    pos = (tt - tt[0]) / dt
    rows = np.floor(pos + 1e-7).astype(int)
    weights = np.clip(pos - rows, 0.0, 1.0)
    weights[weights < 1e-7] = 0.0
    _, omega, alpha = profile(tt, th, tt[:1])
    return Piece(first, stop, int(rows[-1]) + 2, dt, float(omega[0] - 0.5 * dt * alpha[0]),
                 rows, weights)


@dataclass(frozen=True)
class StepMotion:
    """The replayed motion at some physics steps ``j`` of a piece (semi-implicit Euler through
    the interpolant θ(t) sampled at the steps, ``q_j``).

    q, v : (S,) state of step j: ``q_j`` rad, ``v_j = (q_j − q_{j−1})/dt`` rad/s (``v_0`` the
        piece's ``qvel0``). a : (S,) ``(v_{j+1} − v_j)/dt``, rad/s², the acceleration the step
        must make. q_next, v_next : (S,) the state after the step.
    """

    steps: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    q_next: np.ndarray
    v_next: np.ndarray


def step_motion(replay: Replay, piece: Piece, steps: np.ndarray) -> StepMotion:
    """The states of steps ``steps`` (sorted) of a moving piece (:class:`StepMotion`).

    The interpolant (:func:`profile`) at ``t[first] + j·dt`` is ``q_j`` (the last one or two
    steps lie past the last sample: its last cubic goes on there, or its hold). MuJoCo's
    Euler step ``v_{j+1} = v_j + dt·a_j``, ``q_{j+1} = q_j + dt·v_{j+1}`` passes through every
    ``q_j`` when ``v_j`` and ``a_j`` are the differences above (``a_j`` is then the second
    central difference of θ, which is θ''(t_j) exactly inside a cubic piece).
    """
    steps = np.asarray(steps, dtype=int)
    dt, sl = piece.dt, slice(piece.first, piece.stop)
    tt, th = replay.t[sl], replay.tita[sl]
    need = _step_union(steps - 1, steps, steps + 1)
    theta = profile(tt, th, tt[0] + dt * need)[0]

    def at(j: np.ndarray) -> np.ndarray:
        return theta[np.searchsorted(need, j)]

    q, q_next = at(steps), at(steps + 1)
    v, v_next = (q - at(np.maximum(steps - 1, 0))) / dt, (q_next - q) / dt
    v[steps == 0] = piece.qvel0
    return StepMotion(steps, q, v, (v_next - v) / dt, q_next, v_next)


def _hinge_columns(model: mujoco.MjModel) -> tuple[int, int]:
    """The hinge's angle and rate columns in a full-physics state (``mjSTATE_FULLPHYSICS``
    layout: ``[time, qpos (nq), qvel (nv), act, …]``)."""
    return (1 + int(model.joint(TILT_JOINT).qposadr[0]),
            1 + model.nq + int(model.joint(TILT_JOINT).dofadr[0]))


def step_states(model: mujoco.MjModel, time: np.ndarray | float, q: np.ndarray,
                v: np.ndarray | float) -> np.ndarray:
    """Full-physics states (S, nstate) at time ``time`` s, angle ``q`` rad, rate ``v`` rad/s,
    everything else at rest."""
    out = np.tile(initial_state(model, 0.0), (q.size, 1))
    qcol, vcol = _hinge_columns(model)
    out[:, 0], out[:, qcol], out[:, vcol] = time, q, v
    return out


def piece_command(model: mujoco.MjModel, replay: Replay, piece: Piece) -> np.ndarray:
    """Servo command (nstep,) of every step of a moving piece (:func:`step_motion`)."""
    m = step_motion(replay, piece, np.arange(piece.nstep))
    return servo_command(model, m.q, m.v, m.a)


def make_replay(tita: np.ndarray, t: np.ndarray | None) -> Replay:
    """Decide how to re-run the measured experiment and prepare the servo replay.

    Static when there is no timing, when θ never moves, or when θ only changes by jumps
    between held positions (:func:`find_jumps`); otherwise a servo replay of θ(t), holds
    included (module docstring).
    """
    tita = np.asarray(tita, dtype=float)
    if t is None:
        return Replay("static", tita, None, "no sample times: static poses")
    t = np.asarray(t, dtype=float)
    if np.all(tita == tita[0]):
        return Replay("static", tita, t, "θ never moves: static poses")
    jumps = find_jumps(tita, t)
    bounds = np.r_[0, jumps + 1, tita.size]
    spans = [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
    flat = np.diff(tita) == 0.0
    holds = int(np.sum(flat[1:] & ~flat[:-1]) + (flat[0] if flat.size else 0))
    jump_text = ""
    if jumps.size:
        dth, dtt = np.abs(np.diff(tita))[jumps], np.diff(t)[jumps]
        jump_text = (f"{jumps.size} jump(s) between samples (up to {dth.max():.3g} rad in "
                     f"{dtt[np.argmax(dth)]:.3g} s; limits {MAX_TABLE_RATE:g} rad/s, "
                     f"{MAX_TABLE_ACCEL:g} rad/s²: moves that were not sampled)")
    if all(np.all(tita[a:b] == tita[a]) for a, b in spans):
        return Replay("static", tita, t, f"θ held at {np.unique(tita).size} positions, "
                      f"{jump_text}: static poses", holds=holds,
                      jumps=tuple(int(j) for j in jumps))
    dt = float(tilt_table()[0].opt.timestep)
    if (t[-1] - t[0]) / dt > MAX_REPLAY_STEPS:
        return Replay("static", tita, t, f"run of {t[-1] - t[0]:.4g} s exceeds the servo "
                      f"replay limit ({MAX_REPLAY_STEPS} steps): static poses", holds=holds,
                      jumps=tuple(int(j) for j in jumps))
    pieces = tuple(_piece(dt, tita, t, a, b) for a, b in spans)
    reason = "sample times and θ moving: servo replay of the measured encoder angle"
    if holds:
        reason += f"; {holds} hold(s) kept still"
    if jumps.size:
        reason += f"; {jump_text} replayed as instantaneous moves"
    return Replay("sweep", tita, t, reason, pieces, holds, tuple(int(j) for j in jumps))


def accel_columns(model: mujoco.MjModel) -> list[int]:
    """sensordata columns of the sensitive axes (site +x) of the x and y accelerometers."""
    return [sensor_slice(model, ACC_SENSORS[a]).start for a in AXES]


def initial_state(model: mujoco.MjModel, theta: float, omega: float = 0.0) -> np.ndarray:
    """Full-physics state at rest (or turning at ``omega``, rad/s) at ``theta``, rad."""
    data = mujoco.MjData(model)
    data.qpos[int(model.joint(TILT_JOINT).qposadr[0])] = theta
    data.qvel[int(model.joint(TILT_JOINT).dofadr[0])] = omega
    return full_state(model, data)


def sample_rows(piece: Piece, per_step: np.ndarray) -> np.ndarray:
    """Per-step values (S, ...) of a piece at its measured sample times (linear between
    steps)."""
    lo = per_step[piece.rows]
    hi = per_step[np.minimum(piece.rows + 1, per_step.shape[0] - 1)]
    w = piece.weights.reshape((-1,) + (1,) * (per_step.ndim - 1))
    return np.where(w == 0.0, lo, (1.0 - w) * lo + w * hi)


def replay_sensordata(models: Sequence[mujoco.MjModel], replay: Replay, threads: int = 2
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Sensordata (M, N, nsensordata) and state (M, N, nstate) of each of the M ``models``
    (same size signature, e.g. candidates of one model) at the measured samples.

    Static poses (a static replay, or the constant pieces of a sweep) are one batched
    ``nstep = 1`` rollout at rest with the servo target on the pose (no torque: the
    ``mj_forward`` reading); each moving piece is one rollout per model of its servo command
    from (θ_first, ω0). The models of a rollout are split over ``threads`` threads.
    """
    m0, n, nm = models[0], replay.n, len(models)
    datas = [mujoco.MjData(m0) for _ in range(max(1, min(threads, nm)))]
    nstate = mujoco.mj_stateSize(m0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    sd_out, st_out = np.empty((nm, n, m0.nsensordata)), np.empty((nm, n, nstate))
    pieces = replay.pieces or (Piece(0, n),)
    static_at = np.concatenate([np.arange(p.first, p.stop) for p in pieces if p.static]
                               + [np.zeros(0, dtype=int)])
    if static_at.size:
        poses, inverse = np.unique(replay.tita[static_at], return_inverse=True)
        state0 = step_states(m0, 0.0, np.tile(poses, nm), 0.0)
        batch = [m for m in models for _ in poses]
        st, sd = mujoco.rollout.rollout(batch, datas, state0,
                                        np.tile(poses, nm).reshape(-1, 1, 1), nstep=1)
        sd_out[:, static_at] = sd[:, 0].reshape(nm, poses.size, -1)[:, inverse]
        st_out[:, static_at] = st[:, 0].reshape(nm, poses.size, -1)[:, inverse]
    for p in pieces:
        if p.static:
            continue
        _, _, st, sd = piece_rollout(models, datas, replay, p)
        for i in range(nm):
            sd_out[i, p.first:p.stop] = sample_rows(p, sd[i])
            st_out[i, p.first:p.stop] = sample_rows(p, st[i])
    return sd_out, st_out


def motion_model(table: TableEdits | None = None) -> mujoco.MjModel:
    """The tilt table compiled for moving only: sensors off, and collision and constraint
    solving off when the model has nothing they could act on (no colliding geom pair, no
    limit, equality, tendon or friction loss). The integrated states are those of the full
    model bit for bit (checked by the tests) at about half the cost of a step."""
    model, _ = tilt_table(table)
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_SENSOR) | idle_stages(model)
    return model


def idle_stages(model: mujoco.MjModel) -> int:
    """MuJoCo's disable flags of the stages that have nothing to act on in ``model``:
    collision when no geom pair can collide, and then constraint solving when there is no
    limit, equality, tendon or friction loss either. Setting them leaves every state and
    sensor value as it was, bit for bit (``tests/test_gap_bench.py``), at a lower cost."""
    off = mujoco.mjtDisableBit
    flags = 0
    if model.npair == 0 and (not np.any(model.geom_contype) or not np.any(model.geom_conaffinity)):
        flags |= int(off.mjDSBL_CONTACT)
        if (model.neq == 0 and model.ntendon == 0 and not np.any(model.jnt_limited)
                and not np.any(model.dof_frictionloss)):
            flags |= int(off.mjDSBL_CONSTRAINT)
    return flags


MOTION_TOL = 1e-12
"""Largest difference (rad, rad/s) between the state a model reaches in a recorded step and
the recorded one for that model to count as moving as recorded (same physics gives 0)."""


@dataclass(frozen=True)
class Motion:
    """The replayed table motion, simulated once: the physics steps the samples read.

    The catalog's physical effects move or turn the accelerometer sites, which have no
    mass: they change what the sensors read, never how the table moves. So the replay is
    simulated once (:func:`record_motion`) and any edited model is read at the recorded
    steps (:func:`motion_sensordata`: one batched ``nstep = 1`` rollout from the state before
    each step), which gives the same sensordata, bit for bit, as re-simulating the whole run
    with that model (a rollout returns, for step j, the sensors computed in that step's
    ``mj_forward``, i.e. at the state before it).

    Attributes
    ----------
    state : (B, nstate) full-physics state before each recorded step.
    control : (B,) servo command of that step, rad (a static pose: the pose itself).
    after : (B, nstate) state after the step, as MuJoCo's step of the nominal table lands.
    lo, hi, weight : (N,) sample i reads ``(1 - w_i)·step[lo_i] + w_i·step[hi_i]``.
    miss : rad, the largest difference between where a recorded step lands and the
        interpolant's next state (position, and velocity times the step; :data:`MISS_TOL`).
    """

    state: np.ndarray
    control: np.ndarray
    after: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    weight: np.ndarray
    miss: float = 0.0

    @property
    def n(self) -> int:
        return int(self.lo.shape[0])

    def at_samples(self, x: np.ndarray) -> np.ndarray:
        """Rows (B, …) of the recorded steps at the N samples: ``(1 - w)·x[lo] + w·x[hi]``."""
        w = self.weight[:, None]
        lo, hi = x[self.lo], x[self.hi]
        return np.where(w == 0.0, lo, (1.0 - w) * lo + w * hi)


def _static_steps(model: mujoco.MjModel, poses: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """State before (at rest on each pose, servo target on it) and after one step, and the
    step's sensordata."""
    state0 = step_states(model, 0.0, poses, 0.0)
    st, sd = mujoco.rollout.rollout(model, mujoco.MjData(model), state0,
                                    poses.reshape(-1, 1, 1), nstep=1)
    return state0, st[:, 0], sd[:, 0]


def piece_rollout(models: Sequence[mujoco.MjModel], datas: Sequence[mujoco.MjData],
                  replay: Replay, piece: Piece
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A moving piece rolled out whole on each of ``models`` (same size signature) from
    (θ_first, ``qvel0``) with the servo commands of :func:`piece_command` (those of the
    first model): start state (nstate,), commands (nstep,), states (M, nstep, nstate) and
    sensordata (M, nstep, nsensordata) after each step."""
    state0 = initial_state(models[0], replay.tita[piece.first], piece.qvel0)
    control = piece_command(models[0], replay, piece)
    st, sd = mujoco.rollout.rollout(list(models), list(datas), state0[None, :],
                                    control.reshape(1, -1, 1), nstep=piece.nstep)
    return state0, control, st, sd


def _rolled_steps(model: mujoco.MjModel, replay: Replay, piece: Piece, steps: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """State before and after, and command, of steps ``steps`` of a whole-piece rollout."""
    state0, control, st, _ = piece_rollout([model], [mujoco.MjData(model)], replay, piece)
    st = st[0]
    prior = np.vstack([state0[None, :], st[:-1]])  # the state step j starts from
    return prior[steps], st[steps], control[steps]


def record_motion(replay: Replay, table: TableEdits | None = None, threads: int = 2
                  ) -> Motion:
    """Simulate the replayed motion once (:func:`motion_model` of ``table``'s physics):
    :func:`record_motion_read` without a model to read."""
    return record_motion_read(replay, table, threads)[0]


def record_motion_read(replay: Replay, table: TableEdits | None = None, threads: int = 2,
                       read: mujoco.MjModel | None = None
                       ) -> tuple[Motion, np.ndarray | None]:
    """Simulate the replayed motion once (:func:`motion_model` of ``table``'s physics), and
    read ``read`` along it in the same rollouts.

    ``read``: a model of ``table``'s physics with its sensors on (sites and sensors added,
    no mass moved: the bench's probe model): the rollouts then step it instead of
    :func:`motion_model` — the same states bit for bit, with the sensors and collision
    stages its steps compute — and its sensordata before each recorded step (B, nsensordata)
    is returned beside the motion: what :func:`motion_sensordata` of ``read`` along the
    motion computes, from the same calls, without a second rollout. None without ``read``,
    and when a piece was rolled out whole (its steps then come from a long rollout, which
    :func:`motion_sensordata` reads again step by step).

    Static poses (a static replay, or the constant pieces of a sweep) are one step at rest
    each. Of a moving piece only the steps the samples read are simulated (and the step
    after, where a sample falls between two): each from its state of :func:`step_motion`
    with its servo command, in one batched ``nstep = 1`` rollout over ``threads``. That is
    the whole-piece rollout of the same commands at those steps, since that rollout passes
    through the same states; each step's landing is checked against the next state
    (``Motion.miss``), and a piece whose steps miss it by more than :data:`MISS_TOL` (a
    table MuJoCo cannot move as commanded) is rolled out whole instead.
    """
    model = motion_model(table)
    stepped = model if read is None else read
    qcol, vcol = _hinge_columns(model)
    n = replay.n
    lo, hi, weight = np.zeros(n, dtype=int), np.zeros(n, dtype=int), np.zeros(n)
    states, controls, afters, reads = [], [], [], []
    whole = False
    pieces = replay.pieces or (Piece(0, n),)
    at = 0
    static_at = np.concatenate([np.arange(p.first, p.stop) for p in pieces if p.static]
                               + [np.zeros(0, dtype=int)])
    if static_at.size:
        poses, inverse = np.unique(replay.tita[static_at], return_inverse=True)
        before, after, sd = _static_steps(stepped, poses)
        states.append(before)
        afters.append(after)
        reads.append(sd)
        controls.append(poses)
        lo[static_at] = hi[static_at] = inverse
        at = poses.size
    moving = [p for p in pieces if not p.static]
    plans = []
    for p in moving:
        m = step_motion(replay, p, p.read_steps())
        plans.append((m, step_states(model, m.steps * p.dt, m.q, m.v),
                      servo_command(model, m.q, m.v, m.a)))
    miss = 0.0
    if moving:
        state0 = np.vstack([plan[1] for plan in plans])
        control = np.concatenate([plan[2] for plan in plans])
        datas = [mujoco.MjData(stepped)
                 for _ in range(max(1, min(threads, len(control) // 1000)))]
        landed, landed_sd = mujoco.rollout.rollout(stepped, datas, state0,
                                                   control.reshape(-1, 1, 1), nstep=1)
        landed, landed_sd = landed[:, 0], landed_sd[:, 0]
        bounds = np.cumsum([0] + [plan[0].steps.size for plan in plans])
    for k, (p, (m, before, command)) in enumerate(zip(moving, plans, strict=True)):
        after = landed[bounds[k]:bounds[k + 1]]
        off = float(max(np.max(np.abs(after[:, qcol] - m.q_next)),
                        p.dt * np.max(np.abs(after[:, vcol] - m.v_next))))
        if not off <= MISS_TOL:
            before, after, command = _rolled_steps(model, replay, p, m.steps)
            whole = True  # these steps come from a long rollout of the motion model
        miss = max(miss, off)
        states.append(before)
        afters.append(after)
        controls.append(command)
        reads.append(landed_sd[bounds[k]:bounds[k + 1]])
        steps, sl = m.steps, slice(p.first, p.stop)
        lo[sl] = at + np.searchsorted(steps, p.rows)
        between = p.weights > 0
        hi[sl] = lo[sl]
        hi[np.arange(p.first, p.stop)[between]] = at + np.searchsorted(
            steps, np.minimum(p.rows + 1, p.nstep - 1)[between])
        weight[sl] = p.weights
        at += steps.size
    motion = Motion(np.vstack(states), np.concatenate(controls), np.vstack(afters), lo, hi,
                    weight, miss)
    return motion, (None if read is None or whole else np.vstack(reads))


def motion_sensordata(motion: Motion, model: mujoco.MjModel, threads: int = 2
                      ) -> tuple[np.ndarray, np.ndarray, float]:
    """``model`` read along the recorded motion: sensordata (N, nsensordata), state (N,
    nstate) at the samples, and the largest difference between the state ``model`` reaches
    in each recorded step and the recorded one (0 when ``model`` moves as recorded; the
    sensordata are only those of a re-simulation when it is ~0).

    One batched ``nstep = 1`` rollout over the recorded steps, split over ``threads``.
    """
    nb = motion.state.shape[0]
    datas = [mujoco.MjData(model) for _ in range(max(1, min(threads, nb // 1000)))]
    st, sd = mujoco.rollout.rollout(model, datas, motion.state,
                                    motion.control.reshape(-1, 1, 1), nstep=1)
    st, sd = st[:, 0], sd[:, 0]
    step_error = float(np.max(np.abs(st - motion.after))) if nb else 0.0
    return motion.at_samples(sd), motion.at_samples(st), step_error


def simulate(replay: Replay, table: TableEdits | None = None
             ) -> tuple[np.ndarray, np.ndarray]:
    """Bench readings of the replayed experiment: true specific force (N, 2), encoder (N,)."""
    if replay.mode == "static":
        return static_readings(replay.tita, table)
    model, _ = tilt_table(table)
    sd = replay_sensordata([model], replay)[0][0]
    return sd[:, accel_columns(model)], sd[:, sensor_slice(model, ENCODER).start]

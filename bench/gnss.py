"""A GNSS receiver on the MuJoCo vehicle: position (and velocity) fixes from the simulated state.

The receiver samples the **same** MuJoCo run that produces the accelerometer readings
(:class:`bench.vehicle.VehicleTruth`: ``t``, ``pos``, ``vel`` of the slide joints). Model:

* **epochs** ``τ_k = t_0 + k / rate_hz``, ``k = 0, 1, …`` while ``τ_k ≤ t_last`` (the last
  IMU sample), on the receiver's own clock (1 Hz: whole seconds);
* **latency** ``L``: the fix at ``τ_k`` reports the state at ``τ_k − L``
  (``pos_gps(τ_k) = p(τ_k − L) + e_k``); epochs with ``τ_k − L < t_0`` have no state yet
  and give no fix;
* **noise** white, Gaussian, independent per axis and epoch: ``e_k ~ N(0, σ_p² I₂)`` (m),
  velocity ``w_k ~ N(0, σ_v² I₂)`` (m/s) when velocity fixes are asked for;
* **outages**: closed intervals ``[a, b]`` (s, receiver time) with no fix.

Fix epochs and their state times must fall on the IMU sample grid (``1/rate_hz`` and ``L``
whole numbers of IMU periods: 1 Hz or 10 Hz fixes on 100 Hz or 50 Hz samples, latency 0.2 s):
the fix then reports MuJoCo's state itself, not an interpolation of it.

Random stream: the noise comes from its own child of the user's seed,
``SeedSequence(seed, spawn_key=(GNSS_STREAM,))`` (:func:`gnss_rng`), independent of the
streams of the vehicle and course files (those use the root and children 0–2), so asking for
fixes changes no other file. The noise of every epoch is drawn before latency and outages
remove epochs (positions first, then velocities): epoch ``k`` gets the same error whatever the
outages, the latency or whether velocity fixes are written.

Units SI: s, m, m/s, Hz.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

GNSS_STREAM = 13
"""Spawn key of the receiver's noise stream under the user's seed (issue 13; the course uses
children 0–2, the demo's coverage runs 7)."""

GPS_FILE = "gps.mat"

GRID_TOL = 1e-6
"""Largest distance of a fix's state time from the IMU grid, in IMU periods."""


@dataclass(frozen=True)
class Receiver:
    """A GNSS receiver (thesis defaults: 1 Hz fixes, σ = 3 m per axis, velocity σ = 0.1 m/s).

    rate_hz : fix rate, Hz (> 0; ``imu_rate / rate_hz`` a whole number).
    pos_sigma_m : position noise std per axis, m (>= 0; 0 gives the exact state).
    vel_sigma_mps : velocity noise std per axis, m/s (>= 0), or None: no velocity fixes.
    latency_s : the fix at ``t`` reports the state at ``t − latency_s``, s (>= 0).
    outages : closed intervals ``(start, end)`` of receiver time without fixes, s
        (``start <= end``, finite; any list-like of pairs, stored as a tuple of tuples).
    """

    rate_hz: float = 1.0
    pos_sigma_m: float = 3.0
    vel_sigma_mps: float | None = None
    latency_s: float = 0.0
    outages: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        def finite(name: str, value, lo: float, strict: bool = False) -> float:
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"Receiver.{name} must be a number, got {value!r}") from None
            if not math.isfinite(v) or v < lo or (strict and v == lo):
                rel = ">" if strict else ">="
                raise ValueError(f"Receiver.{name} must be finite and {rel} {lo:g}, got {value!r}")
            return v

        object.__setattr__(self, "rate_hz", finite("rate_hz", self.rate_hz, 0.0, strict=True))
        object.__setattr__(self, "pos_sigma_m", finite("pos_sigma_m", self.pos_sigma_m, 0.0))
        if self.vel_sigma_mps is not None:
            object.__setattr__(self, "vel_sigma_mps",
                               finite("vel_sigma_mps", self.vel_sigma_mps, 0.0))
        object.__setattr__(self, "latency_s", finite("latency_s", self.latency_s, 0.0))
        outs = []
        for item in self.outages:
            try:
                a, b = (float(x) for x in item)
            except (TypeError, ValueError):
                raise ValueError(f"Receiver.outages: each outage is a pair (start, end) in s, "
                                 f"got {item!r}") from None
            if not (math.isfinite(a) and math.isfinite(b)) or a > b:
                raise ValueError(f"Receiver.outages: an outage needs finite start <= end (s), "
                                 f"got {item!r}")
            outs.append((a, b))
        object.__setattr__(self, "outages", tuple(outs))

    @property
    def has_velocity(self) -> bool:
        return self.vel_sigma_mps is not None

    def in_outage(self, t: np.ndarray) -> np.ndarray:
        """(M,) bool: receiver times inside any outage (closed intervals)."""
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape, dtype=bool)
        for a, b in self.outages:
            out |= (t >= a) & (t <= b)
        return out

    def to_dict(self) -> dict:
        """The receiver's parameters for ``truth.json`` (units: :data:`GPS_UNITS`)."""
        return {"rate_hz": self.rate_hz, "pos_sigma_m": self.pos_sigma_m,
                "vel_sigma_mps": self.vel_sigma_mps, "latency_s": self.latency_s,
                "outages": [list(o) for o in self.outages]}


GPS_UNITS: dict[str, str] = {
    "gps.rate_hz": "Hz", "gps.pos_sigma_m": "m", "gps.vel_sigma_mps": "m/s",
    "gps.latency_s": "s", "gps.outages": "s", "gps.n_fixes": "count",
    "gps.t_first": "s", "gps.t_last": "s", "gps.seed_spawn_key": "—",
}
"""Units of the ``gps`` object of ``truth.json`` (:meth:`GnssFixes.truth_dict`)."""


@dataclass(frozen=True)
class GnssFixes:
    """The receiver's output and the receiver that made it.

    t_gps : (M,) fix times (receiver clock), s.  pos : (M, 2) position fixes, m.
    vel : (M, 2) velocity fixes, m/s, or None (no velocity fixes asked for).
    """

    receiver: Receiver
    t_gps: np.ndarray
    pos: np.ndarray
    vel: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("t_gps", "pos", "vel"):
            value = getattr(self, name)
            if value is None:
                continue
            arr = np.array(value, dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def n(self) -> int:
        return int(self.t_gps.shape[0])

    def mat_variables(self) -> dict[str, np.ndarray]:
        """``gps.mat`` variables: ``t_gps`` M×1 (s), ``pos`` M×2 (m), ``vel`` M×2 (m/s) if any."""
        out = {"t_gps": self.t_gps, "pos": self.pos}
        if self.vel is not None:
            out["vel"] = self.vel
        return out

    def truth_dict(self) -> dict:
        """The ``gps`` object of ``truth.json``: the receiver, the fix count and span."""
        return {**self.receiver.to_dict(), "n_fixes": self.n,
                "t_first": float(self.t_gps[0]), "t_last": float(self.t_gps[-1]),
                "seed_spawn_key": GNSS_STREAM, "file": GPS_FILE}


def gnss_rng(seed: int) -> np.random.Generator:
    """The receiver's noise stream of ``seed`` (module docstring)."""
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(GNSS_STREAM,)))


def fix_epochs(receiver: Receiver, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All epochs ``τ_k`` within the run, the IMU index of the state each reports, and which
    give a fix.

    Returns ``(tau, idx, keep)``: ``idx[k]`` indexes ``t`` at ``τ_k − latency`` (-1 before
    the run); ``keep[k]`` is False before the run and inside an outage. ValueError if a fix's
    state time is off the IMU sample grid ``t`` or if no fix remains — checkable before the
    run is simulated (only ``t`` is needed).
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.shape[0] < 2:
        raise ValueError("the truth needs at least 2 sample times")
    t0, dt = float(t[0]), float(t[1] - t[0])
    span = float(t[-1] - t0)
    n_epochs = int(math.floor(span * receiver.rate_hz + GRID_TOL)) + 1
    tau = t0 + np.arange(n_epochs) / receiver.rate_hz
    steps = (tau - receiver.latency_s - t0) / dt
    idx = np.rint(steps).astype(np.int64)
    if np.any(np.abs(steps - idx) > GRID_TOL):
        raise ValueError(
            f"fixes at {receiver.rate_hz:g} Hz with latency {receiver.latency_s:g} s do not fall "
            f"on the IMU sample grid ({1 / dt:g} Hz): the IMU rate must be a whole multiple of "
            "the fix rate and the latency a whole number of IMU periods")
    idx = np.where(idx < 0, -1, np.minimum(idx, t.shape[0] - 1))
    keep = (idx >= 0) & ~receiver.in_outage(tau)
    if not np.any(keep):
        raise ValueError(f"the receiver gives no fix: latency {receiver.latency_s:g} s and "
                         f"outages {[list(o) for o in receiver.outages]} s leave no epoch "
                         f"within the run ({t0:g} … {t[-1]:g} s)")
    return tau, idx, keep


def simulate_fixes(receiver: Receiver, t: np.ndarray, pos: np.ndarray, vel: np.ndarray,
                   rng: np.random.Generator) -> GnssFixes:
    """Fixes of ``receiver`` on the simulated truth (module docstring for the model).

    Parameters
    ----------
    receiver : the receiver model.
    t : (N,) IMU sample times, s, uniformly spaced (``VehicleTruth.t``).
    pos, vel : (N, 2) MuJoCo's position (m) and velocity (m/s) at ``t``
        (``VehicleTruth.pos``, ``.vel``).
    rng : the noise stream (:func:`gnss_rng` of the run's seed).

    Returns
    -------
    GnssFixes with ``t_gps`` (M,), ``pos`` (M, 2) = ``pos[t_gps − latency] + e``, ``vel`` (M, 2)
    or None. ValueError if no fix remains (latency past the run, outages covering it).

    Notes
    -----
    The noise of all epochs is drawn first (``standard_normal((K, 2))`` for positions, then
    for velocities if asked), so removing epochs (latency, outages) changes no other fix.
    """
    t = np.asarray(t, dtype=float)
    pos = np.asarray(pos, dtype=float)
    vel = np.asarray(vel, dtype=float)
    if pos.shape != (t.shape[0], 2) or vel.shape != (t.shape[0], 2):
        raise ValueError(f"pos and vel must be (N, 2) with N = {t.shape[0]}, got {pos.shape} "
                         f"and {vel.shape}")
    tau, idx, keep = fix_epochs(receiver, t)
    e_pos = rng.standard_normal((tau.shape[0], 2)) * receiver.pos_sigma_m
    e_vel = (rng.standard_normal((tau.shape[0], 2)) * receiver.vel_sigma_mps
             if receiver.has_velocity else None)
    k = idx[keep]
    return GnssFixes(receiver, tau[keep], pos[k] + e_pos[keep],
                     None if e_vel is None else vel[k] + e_vel[keep])


def fixes_for_seed(receiver: Receiver, truth, seed: int) -> GnssFixes:
    """Fixes on a :class:`bench.vehicle.VehicleTruth` with the noise stream of ``seed``."""
    return simulate_fixes(receiver, truth.t, truth.pos, truth.vel, gnss_rng(seed))


__all__ = ["GNSS_STREAM", "GPS_FILE", "GPS_UNITS", "GnssFixes", "Receiver", "fix_epochs",
           "fixes_for_seed", "gnss_rng", "simulate_fixes"]

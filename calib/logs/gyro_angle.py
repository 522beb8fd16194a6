"""The table angle θ(t) from a gyro about the tilt axis, anchored to the held poses' angles
(``--theta-source gyro``, docs/real-data.md).

A board turned by hand between held poses has a known angle only while held (``--poses``);
a gyro about the tilt axis measures the turns themselves. The angle is

    θ(t) = θ₀ + ∫_{t₀}^{t} (ω(s) − b̂_ω) ds              rad

integrated by the trapezoid rule on the log's own sample times (``scipy.integrate
.cumulative_trapezoid``), with ``b̂_ω`` the gyro's mean over all held samples (its bias while
still, rad/s) and ``θ₀`` chosen so that the first hold's mean angle is its stated angle.

Closure. Integrating from one hold to the next, the mean angle over hold k+1 should differ
from hold k's by the stated difference, modulo a whole turn (stated angles are orientations:
180° and −180° are the same pose; the gyro says which way the board went, and θ stays
continuous — a turn over and back over reads 0, −180°, −360°). The closure error of hold
k+1 is

    e_{k+1} = (θ̄_{k+1} − θ̄_k) − (θ*_{k+1} − θ*_k) − 360°·m,   m the nearest whole turn

(θ̄ the integrated mean over a hold, θ* the stated angle). It collects the bias's change
since it was estimated, the gyro's scale error and any turn out of the tilt plane. Each
|e| must stay within :data:`CLOSURE_BOUND_DEG`; beyond it the gyro is not measuring this
turn (wrong axis, or the poses' angles or their unit are wrong) and the log is refused.

Correction. With two or more holds the errors are removed: the correction is constant over
each hold (its mean then equals its stated angle exactly) and linear in time across the
motion between consecutive holds — the assumption being that the error builds up at a
steady rate while moving (a bias step or scale error does). With one hold there is nothing
to close: θ is the anchored integral.

Sign. With holds 180° apart only, a gyro of the wrong sign closes as well as the right one.
The accelerometer decides: while turning the nominal model ``A_r = [−g sin θ, −g cos θ]``
(course signs) must fit the readings better with θ than with its mirror ``2θ₀ − θ``; when
the mirror's mean square misfit is below half of θ's, the log is refused (check ``--axes``:
the tilt axis is ``â × b̂``, and the gyro column).

This is written here rather than taken from a library because no library anchors an
integrated rate to stated poses; the integral itself is scipy's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from calib.input_rules import DataError
from calib.results import ResultMixin, readonly

CLOSURE_BOUND_DEG = 5.0
"""Largest closure error between consecutive holds, deg, before the log is refused."""
MIRROR_RATIO = 0.5
"""Refuse when the mirrored angle's mean square misfit is below this fraction of θ's."""


@dataclass(frozen=True, eq=False)
class GyroAngle(ResultMixin):
    """θ(t) from the gyro (module docstring).

    Attributes
    ----------
    theta : (N,) rad, the angle of every sample (moving ones too).
    bias : rad/s, b̂_ω, the gyro's mean over the held samples.
    hold_bias : (H,) rad/s, the gyro's mean over each hold (its spread shows how far the
        bias moved).
    holds : (H, 2) int, each hold's sample range ``[start, stop)`` in time order.
    hold_pose : (H,) int, the pose label of each hold.
    stated_rad : (H,) rad, each hold's angle as reached (the stated angle plus whole turns).
    closure_deg : (H,) deg, closure error of each hold against the one before (0 for the
        first, the anchor).
    hold_std_deg : (H,) deg, std of θ over each hold after the correction.
    correction : how the closure errors were removed (a sentence).
    mirror_misfit : (2,) (m/s²)², mean square of ``A − A_r(θ)`` and ``A − A_r(2θ₀ − θ)``
        over the moving samples (NaN when none move).
    gyro_from : the gyro column used (for messages).
    """

    theta: np.ndarray
    bias: float
    hold_bias: np.ndarray
    holds: np.ndarray
    hold_pose: np.ndarray
    stated_rad: np.ndarray
    closure_deg: np.ndarray
    hold_std_deg: np.ndarray
    correction: str
    mirror_misfit: np.ndarray
    gyro_from: str = "gyro"

    _TITLE = "θ from the gyro"
    _UNITS = {"theta": "rad", "bias": "rad/s", "hold_bias": "rad/s", "stated_rad": "rad",
              "closure_deg": "deg", "hold_std_deg": "deg", "mirror_misfit": "(m/s²)²",
              "bound_deg": "deg"}

    def __post_init__(self) -> None:
        for name in ("theta", "hold_bias", "stated_rad", "closure_deg", "hold_std_deg",
                     "mirror_misfit"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "holds", readonly(self.holds, int))
        object.__setattr__(self, "hold_pose", readonly(self.hold_pose, int))

    @property
    def max_closure_deg(self) -> float:
        return float(np.max(np.abs(self.closure_deg))) if self.closure_deg.size else 0.0

    def summary(self) -> str:
        """One line: what was integrated, the bias, the closure errors and their fix."""
        errs = ", ".join(f"{e:+.2f}" for e in self.closure_deg[1:]) or "none (one hold)"
        return (f"from the gyro ({self.gyro_from}): θ = θ₀ + ∫(ω − b̂)dt over all "
                f"{self.theta.size} samples, b̂ = {self.bias:.6f} rad/s (holds "
                f"{np.min(self.hold_bias):.6f} to {np.max(self.hold_bias):.6f}); closure "
                f"errors {errs} deg (bound {CLOSURE_BOUND_DEG:g}°); {self.correction}")

    def to_dict(self, with_theta: bool = True) -> dict:
        """JSON-able; ``with_theta=False`` leaves the per-sample angle out (provenance)."""
        d = {"bias": self.bias, "hold_bias": self.hold_bias.tolist(),
             "holds": self.holds.tolist(), "hold_pose": self.hold_pose.tolist(),
             "stated_rad": self.stated_rad.tolist(), "closure_deg": self.closure_deg.tolist(),
             "hold_std_deg": self.hold_std_deg.tolist(), "correction": self.correction,
             "mirror_misfit": self.mirror_misfit.tolist(), "gyro_from": self.gyro_from,
             "bound_deg": CLOSURE_BOUND_DEG, "units": dict(self._UNITS)}
        if with_theta:
            d["theta"] = self.theta.tolist()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> GyroAngle:
        return cls(theta=np.asarray(d["theta"]), bias=d["bias"],
                   hold_bias=np.asarray(d["hold_bias"]), holds=np.asarray(d["holds"]),
                   hold_pose=np.asarray(d["hold_pose"]),
                   stated_rad=np.asarray(d["stated_rad"]),
                   closure_deg=np.asarray(d["closure_deg"]),
                   hold_std_deg=np.asarray(d["hold_std_deg"]), correction=d["correction"],
                   mirror_misfit=np.asarray(d["mirror_misfit"], dtype=float),
                   gyro_from=d["gyro_from"])


def hold_runs(pose: np.ndarray) -> list[tuple[int, int, int]]:
    """Contiguous runs of one pose label ≥ 0: ``(start, stop, label)`` in time order (a label
    that comes back, or a pose merged across a bump, gives several runs)."""
    runs: list[tuple[int, int, int]] = []
    p = np.asarray(pose, dtype=int)
    i = 0
    while i < p.size:
        if p[i] < 0:
            i += 1
            continue
        j = i
        while j < p.size and p[j] == p[i]:
            j += 1
        runs.append((i, j, int(p[i])))
        i = j
    return runs


def theta_from_gyro(t: np.ndarray, gyro: np.ndarray, pose: np.ndarray,
                    angles_rad: np.ndarray, acc: np.ndarray | None = None, g: float = 9.8,
                    where: str = "<log>", gyro_from: str = "gyro") -> GyroAngle:
    """θ(t) of every sample from the gyro about the tilt axis (module docstring).

    Parameters
    ----------
    t : (N,) s, strictly increasing.
    gyro : (N,) rad/s, rate about the tilt axis (dθ/dt with the course signs).
    pose : (N,) int, pose label per sample, -1 moving.
    angles_rad : (P,) rad, the stated angle of each pose label.
    acc : (N, 2) m/s², the tilt-plane readings, for the sign check (skipped when None).
    g : m/s², for the sign check's nominal model.
    where, gyro_from : the file and the gyro column, for messages.

    Raises
    ------
    DataError : no times, no hold, a closure error beyond :data:`CLOSURE_BOUND_DEG`, or a
        gyro turning against the accelerometer.
    """
    from scipy.integrate import cumulative_trapezoid

    if t is None:
        raise DataError(f"{where}: --theta-source gyro integrates the gyro over time but the "
                        "log has no sample times (--columns t=…)")
    t = np.asarray(t, dtype=float)
    w = np.asarray(gyro, dtype=float)
    pose = np.asarray(pose, dtype=int)
    runs = hold_runs(pose)
    if not runs:
        raise DataError(f"{where}: --theta-source gyro needs at least one held pose to anchor "
                        "the angle; none was found")
    held = pose >= 0
    bias = float(np.mean(w[held]))
    integral = cumulative_trapezoid(w - bias, t, initial=0.0)
    means = np.array([integral[a:b].mean() for a, b, _ in runs])
    stated = np.asarray(angles_rad, dtype=float)[[k for _, _, k in runs]]
    # targets: the stated angles as reached, continuous with the integral (whole turns added)
    target = np.empty(len(runs))
    closure = np.zeros(len(runs))
    target[0] = stated[0]
    for k in range(1, len(runs)):
        step = means[k] - means[k - 1]
        want = stated[k] - stated[k - 1]
        turns = round((step - want) / (2 * math.pi))
        target[k] = target[k - 1] + want + 2 * math.pi * turns
        closure[k] = step - (target[k] - target[k - 1])
    closure_deg = np.degrees(closure)
    bad = np.flatnonzero(np.abs(closure_deg) > CLOSURE_BOUND_DEG)
    if bad.size:
        k = int(bad[0])
        a, b, label = runs[k]
        raise DataError(
            f"{where}: --theta-source gyro: integrating the gyro ({gyro_from}) from hold "
            f"{k - 1} to hold {k} (pose {label}, t = {t[a]:.3f} s) turns "
            f"{math.degrees(means[k] - means[k - 1]):+.1f}° but the poses' angles differ by "
            f"{math.degrees(stated[k] - stated[k - 1]):+.1f}° (closure error "
            f"{closure_deg[k]:+.1f}°, bound {CLOSURE_BOUND_DEG:g}°): the gyro is not the "
            "rate about the tilt axis — check --axes (the tilt axis is a × b), the gyro "
            "column (--columns gyro=…), --gyro-unit, and the --poses angles and --angle-unit")
    err = means - target  # cumulative error of each hold, 0 at the anchor
    if len(runs) >= 2:
        knots_t, knots_e = [], []
        for (a, b, _), e in zip(runs, err, strict=True):
            knots_t += [t[a], t[b - 1]]
            knots_e += [e, e]
        correction = np.interp(t, knots_t, knots_e)
        how = ("closure errors removed: constant over each hold, linear in time across the "
               "motion between consecutive holds")
    else:
        correction = np.full(t.size, err[0])
        how = "no correction (one hold: nothing to close)"
    theta = integral - correction
    hold_std = np.array([math.degrees(float(np.std(theta[a:b]))) for a, b, _ in runs])
    hold_bias = np.array([float(np.mean(w[a:b])) for a, b, _ in runs])
    misfit = np.array([math.nan, math.nan])
    moving = ~held
    if acc is not None and moving.any():
        acc = np.asarray(acc, dtype=float)
        mirror = 2 * target[0] - theta

        def ms(th: np.ndarray) -> float:
            r = acc[moving] - np.column_stack([-g * np.sin(th[moving]),
                                               -g * np.cos(th[moving])])
            return float(np.mean(np.sum(r * r, axis=1)))

        misfit = np.array([ms(theta), ms(mirror)])
        if misfit[1] < MIRROR_RATIO * misfit[0]:
            raise DataError(
                f"{where}: --theta-source gyro: the gyro ({gyro_from}) turns against the "
                "accelerometer — while moving the readings fit the mirrored angle far better "
                f"(mean square misfit {misfit[1]:.3g} vs {misfit[0]:.3g} (m/s²)²): its sign is "
                "wrong; check --axes (the tilt axis is a × b and the gyro rate is taken about "
                "it) and the gyro column")
    return GyroAngle(theta=theta, bias=bias, hold_bias=hold_bias,
                     holds=np.array([[a, b] for a, b, _ in runs], dtype=int).reshape(-1, 2),
                     hold_pose=np.array([k for _, _, k in runs], dtype=int),
                     stated_rad=target, closure_deg=closure_deg, hold_std_deg=hold_std,
                     correction=how, mirror_misfit=misfit, gyro_from=gyro_from)


__all__ = ["CLOSURE_BOUND_DEG", "MIRROR_RATIO", "GyroAngle", "hold_runs", "theta_from_gyro"]

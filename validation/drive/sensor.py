"""The sensor chain of the drive part, and the yardstick that sizes every effect.

Signs and model (DESIGN.md "Conventions", docs/effects.md): the table turns by θ about its
hinge; at rest the specific force on the two sensitive directions is
``A_rx = −g sin θ``, ``A_ry = −g cos θ`` (m/s², x column first). The sensors sit on the hinge
axis (no lever arm). Per axis a (index i, the other in-plane axis p), in this order::

    φ      = θ + tilt_offset + misalignment_a                  angle of the sensitive axis (rad)
    a_i    = clip(−g·[sin φ, cos φ]_i, ±limit)                 true specific force (saturation)
    a_p    = −g·[sin φ, cos φ]_p                               the other in-plane axis' force
    r      = a_i + k2·a_i² + k_ip·a_i·a_p                      IEEE 1293 response (K2, K_ip)
    μ      = LPF_τ( bias + (1 + scale)·r·(1 + ε·M + κ·α) )     gain while moving / with α
           + rate·clock + q·W(clock)                           drift, random walk
           + b·M + c_ω·|ω| + c_α·|α| + A·M·sin(2πf·t + ϕ)      drive-state biases
           + h·S(t)                                            step-like biases
    y      = μ + σ_true·w + s_a·M·w'                           white noise, noise while moving
    out    = lsb·round(y / lsb)  (or integer counts in a CSV log: round(y / 9.80665 · S))

M = 1 while the table moves (inside a move segment), 0 while it holds; ω, α the table's exact
rate and acceleration (rad/s, rad/s²); t the true sample time (s); ``clock`` t with timing,
the sample index without (the catalog's per-sample units). LPF_τ is the first-order low-pass
τ·dy/dt + y = u of docs/effects.md (unit DC gain, on the deterministic output; the white noise
is not filtered). S(t) is 0/1 for a single step, the number of steps passed for a staircase,
and a two-level switching (0 or 1, flipped at Poisson times) for telegraph noise.

Drive-state and step-like mechanisms are not catalog effects (``tiltbench gap`` is expected to
say "unexplained"). The yardstick (:func:`z_mean`) is the size of a change Δ of the mean
reading in noise σ once bias and scale are refitted — ``‖P⊥Δ‖/σ``, P⊥ the projection off
span{1, A_r} — optionally with every parametric catalog signature (:func:`catalog_columns`)
projected out too: the size no catalog effect can take.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .motion import Motion

G = 9.8
"""Gravity of the nominal model, m/s² (the project's default, ``tiltbench gap --g``)."""
G_UNIT = 9.80665
"""The unit g (standard gravity), m/s²: counts are ``y / G_UNIT · sensitivity``."""
AXES = ("x", "y")

CATALOG = ("noise_level", "misalignment", "tilt_offset", "nonlinearity_k2", "cross_axis",
           "bias_drift", "bias_random_walk", "quantization", "saturation", "lowpass_lag",
           "lever_arm", "gravity_mismatch")
"""The JSON names of docs/effects.md."""

DRIVE_KINDS = ("move_noise", "move_vibration", "move_gain", "move_bias", "speed_bias",
               "accel_bias", "accel_gain")
STEP_KINDS = ("telegraph", "bias_step", "staircase")


@dataclass(frozen=True)
class Draws:
    """Every random number of one case, drawn before any size is chosen: white noise, the
    extra noise while moving and the walk's steps, each (N, 2) standard normal."""

    noise: np.ndarray
    extra: np.ndarray
    walk: np.ndarray

    @classmethod
    def draw(cls, rng: np.random.Generator, n: int) -> Draws:
        return cls(rng.standard_normal((n, 2)), rng.standard_normal((n, 2)),
                   rng.standard_normal((n, 2)))


def axis(bias: float, scale: float, sigma2: float) -> dict:
    """One axis without effects: bias (m/s²), scale (1), sigma2 (true noise, (m/s²)²)."""
    return {"bias": bias, "scale": scale, "sigma2": sigma2, "misalignment": 0.0, "k2": 0.0,
            "k_ip": 0.0, "drift": 0.0, "q": 0.0, "tau": None, "limit": None, "lsb": None}


def reference(theta: np.ndarray, g: float = G) -> np.ndarray:
    """(N, 2): ``[−g sin θ, −g cos θ]`` (course signs)."""
    return np.column_stack([-g * np.sin(theta), -g * np.cos(theta)])


def lowpass(u: np.ndarray, t: np.ndarray, tau: float) -> np.ndarray:
    """τ·dy/dt + y = u with y(0) = u(0), exact for u piecewise linear between the samples
    (any spacing). Over a step h with e = exp(−h/τ) and slope m = (u₁ − u₀)/h:
    y₁ = u₁ − τm + e·(y₀ − u₀ + τm)."""
    h = np.diff(t)
    e = np.exp(-h / tau)
    m = np.diff(u) / h
    if np.allclose(h, h[0], rtol=1e-9, atol=0.0):
        # the same recursion as a linear filter, c = τ(1 − e)/h:
        # y₁ = e·y₀ + (1 − c)·u₁ + (c − e)·u₀; state c·u₀ makes y₀ = u₀
        from scipy.signal import lfilter  # here: scipy.signal is slow to import

        c = tau * (1.0 - e[0]) / h[0]
        return lfilter([1.0 - c, c - e[0]], [1.0, -e[0]], u, zi=[c * u[0]])[0]
    y = np.empty_like(u)
    y[0] = u[0]
    for k in range(u.size - 1):
        y[k + 1] = u[k + 1] - tau * m[k] + e[k] * (y[k] - u[k] + tau * m[k])
    return y


def walk(clock: np.ndarray, w: np.ndarray) -> np.ndarray:
    """W_0 = 0, W_k = W_{k−1} + √Δclock_k · w_k (unit intensity per √s, or per √sample)."""
    dt = np.diff(clock, prepend=clock[0])
    return np.cumsum(np.sqrt(dt) * w)


def switching(time: np.ndarray, switch_times, start: int) -> np.ndarray:
    """Two-level state (0/1) that starts at ``start`` and flips at each of ``switch_times``."""
    flips = np.searchsorted(np.sort(np.asarray(switch_times, dtype=float)), time, side="right")
    return ((start + flips) % 2).astype(float)


def _applies(m: dict, ax: str) -> bool:
    return m.get("axis", "both") in (ax, "both")


def _gain_factor(mo: Motion, mechs: list[dict], ax: str) -> np.ndarray:
    f = np.ones(mo.n)
    for m in mechs:
        if not _applies(m, ax):
            continue
        if m["kind"] == "move_gain":
            f = f + m["eps"] * mo.moving
        elif m["kind"] == "accel_gain":
            f = f + m["kappa"] * mo.alpha
    return f


def _bias_terms(mo: Motion, mechs: list[dict], ax: str) -> np.ndarray:
    out = np.zeros(mo.n)
    t = mo.time
    for m in mechs:
        if not _applies(m, ax):
            continue
        k = m["kind"]
        if k == "move_bias":
            out += m["b"] * mo.moving
        elif k == "speed_bias":
            out += m["c"] * np.abs(mo.omega)
        elif k == "accel_bias":
            out += m["c"] * np.abs(mo.alpha)
        elif k == "move_vibration":
            out += m["amp"] * mo.moving * np.sin(2 * np.pi * m["freq"] * t + m["phase"])
        elif k == "telegraph":
            out += m["h"] * switching(t, m["switch_times"], m["start"])
        elif k == "bias_step":
            out += m["h"] * (t >= m["at"])
        elif k == "staircase":
            out += m["h"] * np.searchsorted(np.sort(m["at"]), t, side="right")
    return out


def mean_output(mo: Motion, spec: dict) -> np.ndarray:
    """μ of the module docstring, (N, 2) m/s² (no white noise, no output stage)."""
    g = spec.get("g", G)
    mechs = spec.get("mechanisms", [])
    out = np.empty((mo.n, 2))
    for i, ax in enumerate(AXES):
        p = spec["axes"][ax]
        both = reference(mo.theta + spec.get("tilt_offset", 0.0) + p["misalignment"], g)
        a_i, a_p = both[:, i], both[:, 1 - i]
        if p["limit"] is not None:
            a_i = np.clip(a_i, -p["limit"], p["limit"])
        r = a_i + p["k2"] * a_i**2 + p["k_ip"] * a_i * a_p
        mu = p["bias"] + (1.0 + p["scale"]) * r * _gain_factor(mo, mechs, ax)
        if p["tau"] is not None:
            mu = lowpass(mu, mo.time, p["tau"])
        mu = mu + p["drift"] * mo.clock + _bias_terms(mo, mechs, ax)
        if p["q"]:
            mu = mu + p["q"] * walk(mo.clock, spec["draws"].walk[:, i])
        out[:, i] = mu
    return out


def readings(mo: Motion, spec: dict) -> np.ndarray:
    """The readings (N, 2) m/s²: μ, the white noise, the noise while moving, then rounding
    to ``lsb`` where an axis has one (integer counts are made by the CSV writer)."""
    d: Draws = spec["draws"]
    y = mean_output(mo, spec)
    for i, ax in enumerate(AXES):
        p = spec["axes"][ax]
        y[:, i] += np.sqrt(p["sigma2"]) * d.noise[:, i]
        for m in spec.get("mechanisms", []):
            if m["kind"] == "move_noise" and _applies(m, ax):
                y[:, i] += m["s"][ax] * mo.moving * d.extra[:, i]
        if p["lsb"]:
            y[:, i] = p["lsb"] * np.round(y[:, i] / p["lsb"])
    return y


# --- the yardstick ----------------------------------------------------------------------------

CATALOG_COLUMNS = {"misalignment": 0, "tilt_offset": 0, "nonlinearity_k2": 1, "cross_axis": 2,
                   "bias_drift": 3, "lowpass_lag": 4, "lever_arm": (5, 6)}
"""Effect → its column(s) of :func:`catalog_columns` (to leave an effect's own out)."""


def catalog_columns(mo: Motion, ax: str, exclude: str = "") -> np.ndarray:
    """Linearised signatures of the catalog's parametric effects on one axis, (N, k), from
    docs/effects.md: a rotation (misalignment, tilt offset: dA_r/dθ), K2 (A_r²), cross-axis
    (A_r·A_p), drift (clock) and, on a timed moving run, the lag (ω·dA_r/dθ, i.e. −dA_r/dt
    per τ) and the lever arm (ω², α)."""
    ref = reference(mo.theta)
    i = AXES.index(ax)
    a_i, a_p = ref[:, i], ref[:, 1 - i]
    dadth = a_p if i == 0 else -a_p       # d(−g sin θ)/dθ = −g cos θ; d(−g cos θ)/dθ = g sin θ
    cols = [dadth, a_i**2, a_i * a_p, mo.clock]
    if mo.timing != "none" and mo.moving.any():
        cols += [mo.omega * dadth, mo.omega**2, mo.alpha]
    own = CATALOG_COLUMNS.get(exclude, ())
    own = own if isinstance(own, tuple) else (own,)
    return np.column_stack([c for k, c in enumerate(cols) if k not in own])


def residual(delta: np.ndarray, a_ref: np.ndarray, extra: np.ndarray | None) -> np.ndarray:
    """P⊥Δ: Δ less its least-squares fit on [1, A_r, extra]."""
    h = np.column_stack([np.ones_like(a_ref), a_ref] + ([] if extra is None else [extra]))
    h = h / np.maximum(np.linalg.norm(h, axis=0), 1e-300)
    coef, *_ = np.linalg.lstsq(h, delta, rcond=None)
    return delta - h @ coef


def z_mean(mo: Motion, base: dict, spec: dict, beyond_catalog: bool = False,
           exclude: str = "") -> float:
    """Size of ``spec``'s change of the mean over ``base``, in noise σ, both axes pooled:
    √Σ_a ‖P⊥Δ_a‖²/σ²_a with the stated σ² of ``base``; ``beyond_catalog`` also projects out
    :func:`catalog_columns` (module docstring) but the columns of the effect ``exclude``
    (a catalog effect's size beyond the *other* catalog effects: can the design tell them
    apart?)."""
    d = mean_output(mo, spec) - mean_output(mo, base)
    ref = reference(mo.theta, base.get("g", G))
    z2 = 0.0
    for i, ax in enumerate(AXES):
        if not np.any(d[:, i]):
            continue
        extra = catalog_columns(mo, ax, exclude) if beyond_catalog else None
        r = residual(d[:, i], ref[:, i], extra)
        z2 += float(r @ r) / base["axes"][ax]["sigma2"]
    return float(np.sqrt(z2))


__all__ = ["AXES", "CATALOG", "CATALOG_COLUMNS", "DRIVE_KINDS", "Draws", "G", "G_UNIT",
           "STEP_KINDS", "axis", "catalog_columns", "lowpass", "mean_output", "readings",
           "reference", "residual", "switching", "walk", "z_mean"]

"""The sensor chain of the independent set: catalog effects from their physical definitions
(``docs/effects.md``) and mechanisms outside the catalog.

A run's readings, per axis a (index i; the in-plane perpendicular input a_p), in this order::

    φ      = θ + tilt_offset + misalignment_a                     angle of the sensitive axis
    a_i    = clip(static_i(φ, g) + lever_i(ω, α), ±limit)          true specific force (m/s²)
    a_p    = static_p(φ, g)                                        perpendicular input
    r      = a_i + k2·a_i² + k_ip·a_i·a_p (+ response mechanisms)  IEEE 1293 response
    μ      = LPF_τ( bias + (1 + scale)·r )                          first-order lag, unit DC gain
           + rate·clock + q·walk + (bias-level mechanisms)          additive at the bias level
    y      = μ + √σ²_true·w (+ noise mechanisms),  w ~ N(0, 1)
    out    = output stage(y): rounding to lsb, rail clipping, a stuck stretch

``clock`` is t (s) with timing, the sample index without (``rate`` is then per sample, ``q``
per √sample: the catalog's ``rate_per_sample`` / ``q_per_sample``). Every random path is
drawn once per case (:class:`Draws`), before any size is chosen, so the same draws serve the
run with and without an effect and the size of an effect can be set on its mean signature
(:func:`effect_z`).

Mechanisms outside the catalog (``kind``, params with units):

==========================  ======================================================  ==========
kind                        model (added to μ unless stated)                        stage
==========================  ======================================================  ==========
settling_transient          Σ_stops dir·amp·exp(−(t − t_s)/tau_s), amp m/s², s     bias
direction_hysteresis        h·(sign of the last motion), h m/s²                     bias
dead_zone                   r − clip(a_i, −d, d) (no output within ±d m/s²)         response
fractional_harmonic         amp·sin(nu·θ + phase), nu not an integer                bias
bias_jump                   jump·[sample ≥ at·N], jump m/s²                         bias
flicker                     amp·f_k, f 1/f noise of unit std (FFT-shaped)           bias
ringing                     Σ_stops dir·amp·e^(−ζ2πf(t−t_s))·sin(2πf√(1−ζ²)(t−t_s)) bias
drive_vibration             amp·(|ω|/max|ω|)·sin(teeth·θ + phase)                   bias
thermal_cycle               amp·sin(2π t/period + phase), period s                  bias
scale_asymmetry             r + kappa·max(a_i, 0) (gain differs for ±input)         response
cubic_k3                    r + k3·a_i³, k3 1/(m/s²)² (IEEE 1293 K3/K1)             response
speed_noise                 extra white noise, std amp·|ω|/max|ω| m/s²              noise
impulsive_spikes            a fraction ``frac`` of samples jumps by ±size·σ          noise
asymmetric_clip             out clipped to [lo, hi] m/s² (rails, hi ≠ −lo)          output
frozen_output               out[k0 : k0+length] = out[k0] on both axes (stuck bus)  output
==========================  ======================================================  ==========
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .designs import Motion
from .physics import G, lever_force, residual, signature_z, static_force

AXES = ("x", "y")

CATALOG = ("noise_level", "misalignment", "tilt_offset", "nonlinearity_k2", "cross_axis",
           "bias_drift", "bias_random_walk", "quantization", "saturation", "lowpass_lag",
           "lever_arm", "gravity_mismatch")
"""The effect names of docs/effects.md (JSON vocabulary)."""


@dataclass(frozen=True)
class Draws:
    """Every random number of one case, drawn before anything is sized (N, 2) each."""

    noise: np.ndarray
    walk: np.ndarray
    flicker: np.ndarray
    extra: np.ndarray
    uniform: np.ndarray

    @classmethod
    def draw(cls, rng: np.random.Generator, n: int) -> Draws:
        return cls(noise=rng.standard_normal((n, 2)), walk=rng.standard_normal((n, 2)),
                   flicker=_flicker(rng.standard_normal((n, 2))),
                   extra=rng.standard_normal((n, 2)), uniform=rng.uniform(size=(n, 2)))


def _flicker(white: np.ndarray) -> np.ndarray:
    """1/f ("flicker") noise of unit standard deviation per column: white noise whose Fourier
    amplitudes are divided by √f (power ∝ 1/f), the mean removed."""
    n = white.shape[0]
    spec = np.fft.rfft(white, axis=0)
    f = np.fft.rfftfreq(n)
    spec[0] = 0.0
    spec[1:] /= np.sqrt(f[1:, None])
    out = np.fft.irfft(spec, n=n, axis=0)
    return out / out.std(axis=0)


def neutral_axis(bias: float, scale: float, sigma2: float) -> dict:
    """Axis parameters without any effect: bias m/s², scale 1, sigma2 (m/s²)² (true noise)."""
    return {"bias": bias, "scale": scale, "sigma2": sigma2, "misalignment": 0.0, "k2": 0.0,
            "k_ip": 0.0, "lever": None, "limit": None, "tau": None, "drift": 0.0, "q": 0.0,
            "lsb": None}


def lowpass(u: np.ndarray, t: np.ndarray, tau: float) -> np.ndarray:
    """τ·dy/dt + y = u, y(0) = u(0), exact for u linear between samples (any spacing).

    y_{k+1} = e·y_k + (1 − e)·u_k + (u_{k+1} − u_k)·(1 − τ(1 − e)/h), e = exp(−h/τ),
    h = t_{k+1} − t_k. Written out because scipy.signal.lsim wants equal steps and the
    designs here include non-uniform sampling.
    """
    h = np.diff(t)
    e = np.exp(-h / tau)
    c = 1.0 - tau * (1.0 - e) / h
    y = np.empty_like(u)
    y[0] = u[0]
    for k in range(u.size - 1):
        y[k + 1] = e[k] * y[k] + (1.0 - e[k]) * u[k] + (u[k + 1] - u[k]) * c[k]
    return y


def _walk(motion: Motion, w: np.ndarray) -> np.ndarray:
    """b_0 = 0, b_k = b_{k−1} + √Δt_k·w_k (unit intensity; Δt in s, or 1 per sample)."""
    dt = np.diff(motion.clock, prepend=motion.clock[0])
    return np.cumsum(np.sqrt(dt) * w)


def _after_stops(motion: Motion, shape) -> np.ndarray:
    t = motion.clock
    out = np.zeros(motion.n)
    for ts, d in zip(motion.stop_times, motion.stop_dirs, strict=True):
        m = t >= ts
        out[m] += d * shape(t[m] - ts)
    return out


def _bias_mechanism(m: dict, motion: Motion, draws: Draws, i: int) -> np.ndarray:
    k = m["kind"]
    t = motion.clock
    if k == "settling_transient":
        return _after_stops(motion, lambda s: m["amp"] * np.exp(-s / m["tau_s"]))
    if k == "direction_hysteresis":
        return m["h"] * motion.last_dir
    if k == "fractional_harmonic":
        return m["amp"] * np.sin(m["nu"] * motion.theta + m["phase"])
    if k == "bias_jump":
        return m["jump"] * (np.arange(motion.n) >= int(m["at"] * motion.n))
    if k == "flicker":
        return m["amp"] * draws.flicker[:, i]
    if k == "ringing":
        wn = 2 * np.pi * m["freq"]
        wd = wn * np.sqrt(1 - m["zeta"] ** 2)
        return _after_stops(motion, lambda s: m["amp"] * np.exp(-m["zeta"] * wn * s)
                            * np.sin(wd * s))
    if k == "drive_vibration":
        speed = np.abs(motion.omega) / np.abs(motion.omega).max()
        return m["amp"] * speed * np.sin(m["teeth"] * motion.theta + m["phase"])
    if k == "thermal_cycle":
        return m["amp"] * np.sin(2 * np.pi * t / m["period"] + m["phase"])
    return np.zeros(motion.n)


def _response_mechanism(m: dict, a_i: np.ndarray) -> np.ndarray:
    k = m["kind"]
    if k == "dead_zone":
        return -np.clip(a_i, -m["d"], m["d"])
    if k == "scale_asymmetry":
        return m["kappa"] * np.maximum(a_i, 0.0)
    if k == "cubic_k3":
        return m["k3"] * a_i**3
    return np.zeros_like(a_i)


def _applies(m: dict, axis: str) -> bool:
    return m.get("axis", "both") in (axis, "both")


def mean_readings(motion: Motion, spec: dict, draws: Draws) -> np.ndarray:
    """μ of the module docstring, (N, 2) m/s²: everything but the white noise and the output
    stage."""
    g = spec.get("g", G)
    out = np.empty((motion.n, 2))
    for i, ax in enumerate(AXES):
        p = spec["axes"][ax]
        phi = motion.theta + spec.get("tilt_offset", 0.0) + p["misalignment"]
        both = static_force(phi, g)
        a_i, a_p = both[:, i], both[:, 1 - i]
        if p["lever"] is not None:
            a_i = a_i + lever_force(motion.omega, motion.alpha, *p["lever"], axis=i)
        if p["limit"] is not None:
            a_i = np.clip(a_i, -p["limit"], p["limit"])
        r = a_i + p["k2"] * a_i**2 + p["k_ip"] * a_i * a_p
        for m in spec.get("mechanisms", []):
            if _applies(m, ax):
                r = r + _response_mechanism(m, a_i)
        mu = p["bias"] + (1.0 + p["scale"]) * r
        if p["tau"] is not None:
            mu = lowpass(mu, motion.t, p["tau"])
        mu = mu + p["drift"] * motion.clock
        if p["q"]:
            mu = mu + p["q"] * _walk(motion, draws.walk[:, i])
        for m in spec.get("mechanisms", []):
            if _applies(m, ax):
                mu = mu + _bias_mechanism(m, motion, draws, i)
        out[:, i] = mu
    return out


def readings(motion: Motion, spec: dict, draws: Draws) -> np.ndarray:
    """The measured readings ``datos`` (N, 2) m/s²: μ, the noise, then the output stage."""
    y = mean_readings(motion, spec, draws)
    sig = np.sqrt([spec["axes"][ax]["sigma2"] for ax in AXES])
    y = y + draws.noise * sig
    mechs = spec.get("mechanisms", [])
    for i, ax in enumerate(AXES):
        for m in mechs:
            if not _applies(m, ax):
                continue
            if m["kind"] == "speed_noise":
                speed = np.abs(motion.omega) / np.abs(motion.omega).max()
                y[:, i] += m["amp"] * speed * draws.extra[:, i]
            elif m["kind"] == "impulsive_spikes":
                hit = draws.uniform[:, i] < m["frac"]
                y[hit, i] += np.sign(draws.extra[hit, i]) * m["size"] * sig[i]
        lsb = spec["axes"][ax]["lsb"]
        if lsb:
            y[:, i] = np.round(y[:, i] / lsb) * lsb
        for m in mechs:
            if m["kind"] == "asymmetric_clip" and _applies(m, ax):
                y[:, i] = np.clip(y[:, i], m["lo"], m["hi"])
    for m in mechs:
        if m["kind"] == "frozen_output":
            k0 = int(m["at"] * motion.n)
            y[k0:k0 + m["length"]] = y[k0]
    return y


def effect_z(motion: Motion, base: dict, spec: dict, draws: Draws,
             rivals: dict[str, np.ndarray] | None = None, band: int = 0) -> float:
    """Size of ``spec``'s effect over ``base`` in noise σ, both axes pooled:
    z = √(Σ_a z_a²), z_a = :func:`~.physics.signature_z` of the change of μ on axis a with
    the stated σ² of ``base``; ``rivals`` (axis → (N, k)) are projected out too.

    ``band`` K > 0 measures a broadband change instead (1/f noise, whose energy is spread over
    all frequencies, so that ‖P⊥Δ‖ overstates what any test can see): the residual's
    periodogram I_k = |R_k|²/N summed over the K lowest non-zero frequencies, in units of its
    standard deviation under white noise (each I_k ~ σ²·Exp(1): sum mean Kσ², sd √K σ²),
    z_a = Σ I_k / (√K σ²) — the excess a low-band χ² test sees.
    """
    d = mean_readings(motion, spec, draws) - mean_readings(motion, base, draws)
    ref = static_force(motion.theta, base.get("g", G))
    z2 = 0.0
    for i, ax in enumerate(AXES):
        if not np.any(d[:, i] != 0):
            continue
        riv = None if rivals is None else rivals.get(ax)
        s2 = base["axes"][ax]["sigma2"]
        if band:
            r = residual(d[:, i], ref[:, i], riv)
            za = float(np.sum(np.abs(np.fft.rfft(r)[1:band + 1]) ** 2) / r.size
                       / (np.sqrt(band) * s2))
        else:
            za = signature_z(d[:, i], ref[:, i], s2, riv)
        z2 += za**2
    return float(np.sqrt(z2))


def catalog_columns(motion: Motion) -> dict[str, np.ndarray]:
    """Per axis, every linear catalog signature stacked (N, k): what the catalog's parametric
    effects could take of a mechanism. A mechanism outside the catalog is sized on what is
    left after them (the detector then has something no catalog effect explains)."""
    return {ax: np.column_stack(list(rival_columns(motion, ax, "").values())) for ax in AXES}


def rival_columns(motion: Motion, axis: str, exclude: str) -> dict[str, np.ndarray]:
    """Linearised signatures of the catalog's parametric effects on one axis (N,) or (N, 2),
    from docs/effects.md: misalignment δ·a_p-like first harmonic, k2·a_i², k_ip·a_i·a_p,
    drift (clock), and with rates the lag (−dA_r/dt) and the lever arm (ω², α). Used to say
    how far a case's effect stands from the nearest other effect (truth ``z_vs_nearest``)."""
    ref = static_force(motion.theta)
    i = AXES.index(axis)
    a_i, a_p = ref[:, i], ref[:, 1 - i]
    # d a_i/dθ: x: −g cos θ = a_p; y: +g sin θ = −a_p
    dadth = a_p if i == 0 else -a_p
    cols = {"misalignment": dadth, "nonlinearity_k2": a_i**2, "cross_axis": a_i * a_p,
            "bias_drift": motion.clock}
    if motion.moving and motion.t is not None:
        cols["lowpass_lag"] = dadth * motion.omega
        cols["lever_arm"] = np.column_stack([motion.omega**2, motion.alpha])
    cols.pop(exclude, None)
    if exclude == "tilt_offset":
        cols.pop("misalignment", None)
    return cols


def z_vs_nearest(motion: Motion, base: dict, spec: dict, draws: Draws, name: str,
                 axes: tuple[str, ...]) -> tuple[float, str]:
    """The effect's z once the closest single rival signature is also projected out, and the
    rival's name (a small value warns that a case cannot be told apart on its design)."""
    worst, who = np.inf, ""
    for ax in axes:
        for rname, col in rival_columns(motion, ax, name).items():
            z = effect_z(motion, base, spec, draws, rivals={ax: col})
            if z < worst:
                worst, who = z, rname
    return float(worst), who


__all__ = ["AXES", "CATALOG", "Draws", "catalog_columns", "effect_z", "lowpass",
           "mean_readings", "neutral_axis", "readings", "rival_columns", "z_vs_nearest"]

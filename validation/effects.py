"""The sensor chain of the validation set, written from the physics and IEEE Std 1293.

Nothing here comes from ``bench`` or ``calib``: the equations are those of
``docs/effects.md`` (parameter names, keys and units) and of the IEEE Std 1293 model,
written again. Per axis a ∈ {x, y} (k = 0, 1), in this order:

1. **true specific force** (:func:`true_force`): ``[-g sin θ_true, -g cos θ_true]`` with
   ``θ_true = θ_enc + tilt_offset`` at the sensor's clock time (a clock drift reads the table
   at ``t - d(t)``); on the MuJoCo sweep, the simulated sensors (lever arm: the off-axis site).
2. **mounting** (:func:`rotate`): the sensitive axes turned by ``+δ`` about the hinge
   (+y): ``a_x = cos δ·f_x + sin δ·f_y`` (= -g sin(θ+δ)), ``a_y = cos δ·f_y - sin δ·f_x``
   (= -g cos(θ+δ)); ``a_i`` is the own axis, ``a_p`` the other in-plane one.
3. **saturation**: ``clip(a_i, -L, L)`` — the true specific force clipped (``limit`` L).
4. **response** (IEEE 1293 K2, K_ip): ``r = a + k2·a² + k_ip·a·a_p`` (+ outside the catalog:
   ``k3·a³``, scale asymmetry ``asym·|a|``).
5. **low-pass** (:func:`lowpass`): ``τ·dy/dt + y = r`` (``tau``), at rest before the run.
6. **output** (IEEE K0, K1): ``bias + (1 + scale)·y`` + drift ``rate·(t - t0)`` (per sample
   without timing) + bias-level terms outside the catalog (periodic, step, hysteresis, θ
   harmonic).
7. **random terms**: random walk ``b_k = b_{k-1} + q·sqrt(Δt)·w_k`` (``b_0 = 0``), white noise
   ``N(0, sigma2)``, outside the catalog flicker (1/f) noise and rare spikes.
8. **output stage**: rounding to multiples of ``lsb`` (quantization, undithered).

Signs: a positive δ (misalignment, tilt offset) reads the table as if turned by +δ; a positive
k2 raises the reading by ``k2·a²``; a positive ``rate`` makes the reading grow.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy import interpolate, signal

from validation import sweep

G: float = 9.80665
"""Standard gravity, m/s²."""

AXES: tuple[str, str] = ("x", "y")


def reference(theta: np.ndarray, g: float = G) -> np.ndarray:
    """(N, 2) true specific force of the tilt table at rest, ``[-g sin θ, -g cos θ]``, m/s²."""
    theta = np.asarray(theta, dtype=float)
    return np.column_stack([-g * np.sin(theta), -g * np.cos(theta)])


def rotate(force: np.ndarray, delta: float) -> np.ndarray:
    """Specific force along sensitive axes turned by ``+δ`` (rad) about the hinge (+y).

    ``force`` (N, 2) is along the nominal axes (x = table +x, y = table -z). Exact for any
    in-plane force: on ``reference(θ)`` it gives ``reference(θ + δ)``.
    """
    c, s = np.cos(delta), np.sin(delta)
    return np.column_stack([c * force[:, 0] + s * force[:, 1], c * force[:, 1] - s * force[:, 0]])


def lowpass(u: np.ndarray, t: np.ndarray, tau: float) -> np.ndarray:
    """First-order low-pass ``τ·dy/dt + y = u``, exact for ``u`` linear between samples.

    With ``h = t_k - t_{k-1}``, ``e = exp(-h/τ)`` and ``m = (u_k - u_{k-1})/h`` the solution over
    one step is ``y(t) = u(t) - τm + (y_{k-1} - u_{k-1} + τm)·exp(-(t - t_{k-1})/τ)``, so

        y_k = e·y_{k-1} + (1 - c + e·c)·u_k + (c - e - e·c)·u_{k-1},   c = τ/h.

    The sensor is at rest before the run: ``y_0 = u_0`` (unit DC gain: filter ``u - u_0`` from
    zero and add ``u_0`` back). Uniform steps use ``scipy.signal.lfilter``, others a loop.
    """
    u = np.asarray(u, dtype=float)
    if tau <= 0.0 or u.size < 2:
        return u.copy()
    t = np.asarray(t, dtype=float)
    h = np.diff(t)
    v = u - u[0]
    if np.allclose(h, h[0], rtol=1e-9, atol=0.0):
        e, c = np.exp(-h[0] / tau), tau / h[0]
        b = [1.0 - c + e * c, c - e - e * c]
        return u[0] + signal.lfilter(b, [1.0, -e], v)
    y = np.zeros_like(v)
    for k in range(1, v.size):
        e, c = np.exp(-h[k - 1] / tau), tau / h[k - 1]
        y[k] = e * y[k - 1] + (1.0 - c + e * c) * v[k] + (c - e - e * c) * v[k - 1]
    return u[0] + y


def quantize(x: np.ndarray, lsb: float) -> np.ndarray:
    """Round to the nearest multiple of ``lsb`` (m/s²); ``lsb = 0`` leaves ``x`` as is."""
    return x if lsb <= 0.0 else lsb * np.round(x / lsb)


def direction(omega: np.ndarray) -> np.ndarray:
    """Direction of motion ±1 with memory: the sign of ω, kept through holds (|ω| < 1e-9);
    before the first motion, the first direction taken."""
    s = np.sign(np.where(np.abs(omega) > 1e-9, omega, 0.0))
    idx = np.where(s != 0, np.arange(s.size), 0)
    np.maximum.accumulate(idx, out=idx)
    out = s[idx]
    nz = np.flatnonzero(s)
    out[out == 0] = s[nz[0]] if nz.size else 1.0
    return out


def walk(w: np.ndarray, dt: np.ndarray, q: float) -> np.ndarray:
    """Random walk ``b_0 = 0``, ``b_k = b_{k-1} + q·sqrt(Δt_k)·w_k`` (``w`` (N,) standard)."""
    return np.concatenate([[0.0], np.cumsum(q * np.sqrt(dt) * w[1:])])


def flicker(normals: np.ndarray, h: float, n: int) -> np.ndarray:
    """Gaussian series with spectral density ``h/ω`` (ω = 2πj/N, 1/f), ``normals`` (N//2+1, 2).

    The DFT coefficients are ``X_j = sqrt(N f_j / 2)·(a_j + i b_j)`` (real ``sqrt(N f)·a`` at
    Nyquist, 0 at DC), so the periodogram ``|X_j|²/N`` has mean ``f_j``.
    """
    j = np.arange(n // 2 + 1)
    w = 2.0 * np.pi * np.maximum(j, 1) / n
    f = np.where(j == 0, 0.0, h / w)
    coef = np.sqrt(n * f / 2.0) * (normals[:, 0] + 1j * normals[:, 1])
    if n % 2 == 0:
        coef[-1] = np.sqrt(n * f[-1]) * normals[-1, 0]
    return np.fft.irfft(coef, n=n)


@dataclass(frozen=True)
class AxisSpec:
    """True error parameters of one axis (catalog keys and units of ``docs/effects.md``).

    bias m/s², scale 1, delta (misalignment) rad, k2 and k_ip 1/(m/s²), limit (saturation)
    m/s², tau (low-pass) s, rate (drift) m/s²/s (per sample untimed), q (random walk)
    m/s²/√s (per √sample untimed), lsb m/s², sigma2 (true noise variance, None = stated).
    Outside the catalog: k3 1/(m/s²)², asym 1, harmonic (amplitude m/s², order, phase rad) of
    θ, periodic (amplitude m/s², period s, phase rad) in time, step (amplitude m/s², sample
    index), hysteresis m/s² (+ while θ increases, - while it decreases), flicker h
    ((m/s²)²·rad per sample: density h/ω), spikes (scale of the drawn spikes, 0 = none).
    Mechanisms (issue 20, outside the catalog): transient (amplitude m/s², centre s, width s)
    a Gaussian bump of the bias in time; two_tone (amplitude m/s², period 1 s, period 2 s,
    phase rad) two sinusoids in time (the second at 0.7 × the amplitude); box (amplitude
    m/s², first sample, last sample) the bias jumps up and back down; zero_g (amplitude m/s²,
    width m/s²) a dip ``-A·exp(-(a/w)²/2)`` of the reading near 0 g; ringing (amplitude m/s²,
    frequency Hz, damping ratio) a damped oscillation after each stop of the table, signed by
    the direction of the move that stopped; drive (amplitude m/s², order ν, phase rad) a
    vibration ``A·sin(νθ + φ)`` tied to the drive angle at a non-integer order; frozen (first
    sample, length) the output repeats one reading exactly for that many samples.
    """

    bias: float = 0.0
    scale: float = 0.0
    delta: float = 0.0
    k2: float = 0.0
    k_ip: float = 0.0
    limit: float = np.inf
    tau: float = 0.0
    rate: float = 0.0
    q: float = 0.0
    lsb: float = 0.0
    sigma2: float | None = None
    k3: float = 0.0
    asym: float = 0.0
    harmonic: tuple[float, int, float] = (0.0, 3, 0.0)
    periodic: tuple[float, float, float] = (0.0, 30.0, 0.0)
    step: tuple[float, int] = (0.0, 0)
    hysteresis: float = 0.0
    flicker: float = 0.0
    spikes: float = 0.0
    transient: tuple[float, float, float] = (0.0, 0.0, 1.0)
    two_tone: tuple[float, float, float, float] = (0.0, 30.0, 11.0, 0.0)
    box: tuple[float, int, int] = (0.0, 0, 0)
    zero_g: tuple[float, float] = (0.0, 1.0)
    ringing: tuple[float, float, float] = (0.0, 3.0, 0.05)
    drive: tuple[float, float, float] = (0.0, 2.5, 0.0)
    frozen: tuple[int, int] = (0, 0)


@dataclass(frozen=True)
class Spec:
    """True errors of a run: per axis (:class:`AxisSpec`) and shared.

    tilt_offset : rad, table angle = encoder + δ (both axes).
    clock_drift : s/s, the readings lag the encoder by ``d(t) = clock_drift·(t - t0)``.
    lever : ((pos_x, pos_z) of the x sensor, (pos_x, pos_z) of the y sensor), m, table frame
        (MuJoCo sweep only).
    """

    x: AxisSpec = field(default_factory=AxisSpec)
    y: AxisSpec = field(default_factory=AxisSpec)
    tilt_offset: float = 0.0
    clock_drift: float = 0.0
    lever: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 0.0), (0.0, 0.0))

    def axis(self, k: int) -> AxisSpec:
        return (self.x, self.y)[k]

    def with_axis(self, k: int, **changes) -> Spec:
        return replace(self, **{AXES[k]: replace(self.axis(k), **changes)})


@dataclass(frozen=True)
class Run:
    """A θ design with what the physics needs: ``tita`` (N,) rad, ``t`` (N,) s or None,
    ``omega``/``alpha`` (N,) rad/s, rad/s² (timed runs; central differences, or the simulated
    joint on the MuJoCo sweep), ``design`` name and whether it is the MuJoCo sweep."""

    design: str
    tita: np.ndarray
    t: np.ndarray | None
    omega: np.ndarray | None
    alpha: np.ndarray | None
    mujoco: bool = False

    @classmethod
    def build(cls, design: str, tita, t) -> Run:
        tita = np.asarray(tita, dtype=float)
        if design == "mujoco_sweep":
            sim = sweep.simulate(tita.size)
            return cls(design, tita, np.asarray(t, float), np.array(sim.omega),
                       np.array(sim.alpha), True)
        if t is None:
            return cls(design, tita, None, None, None)
        t = np.asarray(t, dtype=float)
        omega = np.gradient(tita, t)
        return cls(design, tita, t, omega, np.gradient(omega, t))

    @property
    def n(self) -> int:
        return int(self.tita.size)

    @property
    def tcol(self) -> np.ndarray:
        """Time since the first sample, s; the sample index without timing."""
        return np.arange(self.n, dtype=float) if self.t is None else self.t - self.t[0]

    @property
    def dt(self) -> np.ndarray:
        """(N-1,) sample intervals, s (1 per sample without timing)."""
        return np.ones(self.n - 1) if self.t is None else np.diff(self.t)


def true_force(run: Run, spec: Spec) -> np.ndarray:
    """(N, 2) true specific force along the nominal axes, m/s² (step 1 of the module doc)."""
    if run.mujoco:
        if spec.clock_drift:
            raise ValueError("a clock drift is not defined on the MuJoCo sweep here")
        sim = sweep.simulate(run.n, spec.lever)
        force = np.column_stack([
            sim.arm_force[:, k] if any(spec.lever[k]) else sim.force[:, k] for k in range(2)])
        return rotate(force, spec.tilt_offset) if spec.tilt_offset else force
    if any(any(p) for p in spec.lever):
        raise ValueError("a lever arm needs the MuJoCo sweep (a physical effect)")
    theta = run.tita
    if spec.clock_drift:
        if run.t is None:
            raise ValueError("a clock drift needs sample times")
        spline = interpolate.CubicSpline(run.t, run.tita)
        theta = spline(run.t - spec.clock_drift * (run.t - run.t[0]))
    return reference(theta + spec.tilt_offset)


def mean_reading(run: Run, spec: Spec, axes=(0, 1)) -> np.ndarray:
    """(N, 2) noise-free reading (steps 1-6; the columns not in ``axes`` are left zero)."""
    force = true_force(run, spec)
    out = np.zeros((run.n, 2))
    tcol = run.tcol
    for k in axes:
        p = spec.axis(k)
        rot = rotate(force, p.delta) if p.delta else force
        a, a_p = rot[:, k], rot[:, 1 - k]
        a = np.clip(a, -p.limit, p.limit)
        r = a + p.k2 * a * a + p.k_ip * a * a_p + p.k3 * a**3 + p.asym * np.abs(a)
        if p.tau > 0.0:
            if run.t is None:
                raise ValueError("a low-pass lag needs sample times")
            r = lowpass(r, run.t, p.tau)
        y = p.bias + (1.0 + p.scale) * r + p.rate * tcol
        amp, order, phase = p.harmonic
        if amp:
            y = y + amp * np.cos(order * run.tita + phase)
        amp, period, phase = p.periodic
        if amp:
            y = y + amp * np.sin(2.0 * np.pi * tcol / period + phase)
        amp, at = p.step
        if amp:
            y = y + amp * (np.arange(run.n) >= at)
        if p.hysteresis:
            y = y + p.hysteresis * direction(run.omega)
        y = y + _mechanisms(run, p, a)
        out[:, k] = y
    return out


def stops(run: Run, still: float = 1e-6) -> np.ndarray:
    """Sample indices where the table comes to rest after moving (|ω| falls below
    ``still`` rad/s), with the sign of the move that stopped: (m, 2) [index, ±1]."""
    if run.omega is None:
        return np.zeros((0, 2), dtype=int)
    moving = np.abs(run.omega) > still
    at = np.flatnonzero(moving[:-1] & ~moving[1:]) + 1
    return np.column_stack([at, np.sign(run.omega[at - 1]).astype(int)])


def _mechanisms(run: Run, p: AxisSpec, a: np.ndarray) -> np.ndarray:
    """The deterministic mechanisms outside the catalog (AxisSpec docstring), m/s²."""
    tcol = run.tcol
    out = np.zeros(run.n)
    amp, centre, width = p.transient
    if amp:
        out += amp * np.exp(-0.5 * ((tcol - centre) / width) ** 2)
    amp, p1, p2, phase = p.two_tone
    if amp:
        out += amp * (np.sin(2.0 * np.pi * tcol / p1 + phase)
                      + 0.7 * np.sin(2.0 * np.pi * tcol / p2 + 2.0 * phase + 1.0))
    amp, i1, i2 = p.box
    if amp:
        idx = np.arange(run.n)
        out += amp * ((idx >= i1) & (idx < i2))
    amp, width = p.zero_g
    if amp:
        out -= amp * np.exp(-0.5 * (a / width) ** 2)
    amp, freq, zeta = p.ringing
    if amp:
        w = 2.0 * np.pi * freq
        wd = w * np.sqrt(1.0 - zeta**2)
        for i, sign in stops(run):
            tau = tcol[i:] - tcol[i]
            out[i:] += sign * amp * np.exp(-zeta * w * tau) * np.sin(wd * tau)
    amp, order, phase = p.drive
    if amp:
        out += amp * np.sin(order * run.tita + phase)
    return out


@dataclass(frozen=True)
class Draws:
    """Standard random numbers of one case, drawn once in a fixed order so that scaling a
    parameter never changes the realisation: ``noise``, ``walk`` (N, 2) N(0, 1); ``flicker``
    (N//2+1, 2, 2) N(0, 1); ``spike_at`` (2, m) sample indices and ``spike_sigma`` (2, m) signed
    amplitudes in σ (8-15, ≈ 0.3 % of the samples, at least 3)."""

    noise: np.ndarray
    walk: np.ndarray
    flicker: np.ndarray
    spike_at: np.ndarray
    spike_sigma: np.ndarray

    @classmethod
    def draw(cls, rng: np.random.Generator, n: int) -> Draws:
        noise = rng.standard_normal((n, 2))
        walk_w = rng.standard_normal((n, 2))
        flick = rng.standard_normal((n // 2 + 1, 2, 2))
        m = max(3, int(round(0.003 * n)))
        at = np.stack([np.sort(rng.choice(np.arange(n // 50, n - n // 50), m, replace=False))
                       for _ in range(2)])
        amp = rng.uniform(8.0, 15.0, (2, m)) * rng.choice([-1.0, 1.0], (2, m))
        return cls(noise, walk_w, flick, at, amp)

    def spikes(self, k: int, n: int, sigma: float) -> np.ndarray:
        """(N,) the spike signal of axis k for noise std σ."""
        s = np.zeros(n)
        s[self.spike_at[k]] = self.spike_sigma[k] * sigma
        return s


def readings(run: Run, spec: Spec, draws: Draws, noise_var) -> np.ndarray:
    """(N, 2) readings ``datos``, m/s² (steps 1-8); ``noise_var`` the stated σ² of each axis
    (the white-noise variance unless ``AxisSpec.sigma2`` gives the true one)."""
    out = mean_reading(run, spec)
    for k in range(2):
        p = spec.axis(k)
        stated_sd = float(np.sqrt(noise_var[k]))
        sd = stated_sd if p.sigma2 is None else float(np.sqrt(p.sigma2))
        out[:, k] += sd * draws.noise[:, k]
        if p.q:
            out[:, k] += walk(draws.walk[:, k], run.dt, p.q)
        if p.flicker:
            out[:, k] += flicker(draws.flicker[:, k, :], p.flicker, run.n)
        if p.spikes:
            out[:, k] += p.spikes * draws.spikes(k, run.n, stated_sd)
        start, length = p.frozen
        if length:  # the output stage holds one reading (a stuck register / dropped updates)
            out[start:start + length, k] = out[start, k]
        out[:, k] = quantize(out[:, k], p.lsb)
    return out

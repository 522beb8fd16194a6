"""Motion-conditioned checks: is the residual different while the table moves?

A disturbance or a gain change tied to the drive — the motor's field or current picked up by
the sensor, a vibration of the drive, a cable that pulls while the table turns, a gain that
changes with the speed, the acceleration or the drive torque — is present while the table
moves and gone while it holds. The catalog has none of these; the selection never looks at
the drive state. So the final model's residuals are compared between the **moving** and the
**held** stretches of a run, by six checks of the adequacy battery per axis and four on
both axes at once (the tone, :func:`joint_tone`; the level, the gain and the excess,
:func:`joint_drive`) (:mod:`calib.gap.adequacy`, each at the battery's Bonferroni level; a
failure makes the verdict "unexplained" with the words "present while moving …", where — the
moving stretches and their share of the run — and how big, in m/s²).

Held samples are those in a run of at least :data:`calib.gap.mechanisms.MIN_HOLD` equal
consecutive encoder angles; the rest move (:func:`drive_state`). The checks run when both
states have at least :data:`MIN_STATE` samples (a stop-and-go run, dwells between moves; not
a constant sweep, nor poses joined by jumps, where one state is missing).

With ``z`` the final model's standardised residuals (unit variance under the model; the
random-walk filter's innovations on a walk axis), ``m`` the moving indicator (1 moving,
0 held), ``A_r`` the axis' reference (m/s²), and with sample times ω, α (rad/s, rad/s²) and
the drive torque τ (N·m, the bench's inverse dynamics of the replayed θ(t), when given),
each normalised by its largest magnitude (``|ω|ₙ = |ω|/max|ω|``):

========================  ==================================================================
check                     statistic and reference distribution under the model
========================  ==================================================================
``drive_level``           columns ``m`` (and ``τₙ``, ``|τ|ₙ``) added to the model in its
                          whitened space (:class:`calib.gap.space.AxisSpace`, GLS):
                          ``ΔRSS ~ χ²(k)``. A level while moving (or one that follows the
                          drive torque).
``drive_gain``            columns ``A_r·m``, and with timing ``A_r·|ω|ₙ``, ``A_r·αₙ``,
                          ``A_r·τₙ``: ``ΔRSS ~ χ²(k)``. A gain (scale factor) that changes
                          while moving, with the speed, the acceleration or the torque.
``drive_variance``        ``F = s²_moving / s²_held`` of z (each about its own mean):
                          ``F(n_m − 1, n_h − 1)``, two-sided. Noise that changes while
                          moving.
``drive_excess``          ``Σ_moving z²`` against the model's variance, one-sided: under
                          the model each z² has mean 1 (a little less after the fit) and
                          variance κ = 2 for Gaussian noise, so the sum is compared with
                          ``c·χ²(ν)``, ``c = κ/2``, ``ν = 2 n_m/κ`` (Satterthwaite: its mean
                          and variance), κ = max(2, var(z²) over the run) so that heavier
                          tails than Gaussian widen it and a chance-small estimate never
                          narrows it; left out on a walk axis. Noise that the drive adds
                          (never removes) while moving: where the held stretches are short,
                          ``drive_variance`` must estimate their variance too and loses most
                          of its power (for an excess of z standard deviations of the moving
                          χ², F's statistic is about z/√2 when n_h ≈ n_m).
``drive_spectrum``        autocorrelations ``r_j`` (j = 1 … h) of z within the moving
                          stretches against those within the held ones (pairs never cross a
                          stretch): ``Σ_j (r_j^m − r_j^h)² / (1/P_j^m + 1/P_j^h) ~ χ²(h)``,
                          ``P_j`` the pairs at lag j (each r_j ≈ N(0, 1/P_j) for white noise,
                          independent across lags). A vibration while moving.
``drive_tone``            the periodogram of z on the moving samples alone (held ones set
                          to 0): at frequencies a quarter of a Fourier bin apart
                          (:data:`TONE_OVERSAMPLE`; zero-padded DFT) the pair
                          ``(Σ_M z cos ωk, Σ_M z sin ωk)`` with its exact covariance under
                          the model, ``C(f) = [[Σ_M cos², Σ_M cos·sin], [·, Σ_M sin²]]``
                          (from the mask's DFT at 2f), gives ``S(f) = uᵀC⁻¹u ~ χ²(2)``;
                          the largest over the m frequencies of at least one cycle per
                          median moving stretch, ``P ≤ m·e^{−S/2}`` (Bonferroni). A tone
                          while moving — a vibration of the drive — which ``drive_spectrum``
                          (ten lags) and ``drive_variance`` (the whole noise) dilute: a tone
                          of amplitude A over n_m moving samples gives ``S ≈ n_m·A²/(2σ²)``.
                          On both axes at once (:func:`joint_tone`, axis ``both``):
                          ``S_x(f) + S_y(f) ~ χ²(4)``, ``P ≤ m·e^{−S/2}(1 + S/2)``.
========================  ==================================================================

Why by hand: these are tests of this bench's drive states; no library conditions a
regression, a variance ratio or an autocorrelation on the held stretches of an encoder.
"""

from __future__ import annotations

import numpy as np
from scipy import special
from scipy.fft import next_fast_len

from calib.conventions import AXES
from calib.effects import Extensions, ModelState
from calib.gap.mechanisms import MIN_HOLD
from calib.gap.space import AxisSpace, Check

MIN_STATE = 50
"""Fewest samples in each drive state (moving, held) for the checks to run."""

SPECTRUM_LAGS = 10
"""Lags h of ``drive_spectrum`` (each needs at least :data:`MIN_PAIRS` pairs per state)."""

TONE_CONDITION = 0.2
"""A frequency of ``drive_tone`` is scanned only where the moving mask leaves its cos and sin
columns apart: ``det C(f) ≥ TONE_CONDITION·(n_m/2)²`` (near 0, the Nyquist frequency and a
mask period's half, cos and sin sampled on the mask are nearly one column)."""

TONE_OVERSAMPLE = 4
"""``drive_tone`` scans frequencies 1/4 of a Fourier bin apart or closer (the moving samples'
DFT zero-padded to at least 4 N, :func:`_scan_size`): a tone between two Fourier frequencies of
the run loses up to 60 % of its statistic on the run's own grid (sinc² of half a bin), 5 % at
a quarter bin. The Bonferroni count is the number of frequencies scanned, about 4 per bin
(conservative: neighbours are correlated)."""

MIN_PAIRS = 30
"""Fewest lagged pairs within the stretches of a state for a lag to be used."""

NORM_FLOOR = 1e-9
"""A drive column whose largest magnitude is below this is left out (no such state)."""


def drive_state(tita: np.ndarray) -> np.ndarray | None:
    """(N,) True where the table moves: not in a run of at least ``MIN_HOLD`` equal
    consecutive angles; None when either state has fewer than :data:`MIN_STATE` samples."""
    th = np.asarray(tita, dtype=float)
    n = th.size
    if n < 2 * MIN_STATE:
        return None
    same = np.diff(th) == 0.0
    edges = np.diff(np.concatenate([[0], same.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    held = np.zeros(n, dtype=bool)
    for a, b in zip(starts, ends, strict=True):  # same[a:b] true: samples a … b equal
        if b - a + 1 >= MIN_HOLD:
            held[a:b + 1] = True
    moving = ~held
    if min(int(moving.sum()), int(held.sum())) < MIN_STATE:
        return None
    return moving


def stretches(mask: np.ndarray) -> list[tuple[int, int]]:
    """(first, stop) of each maximal run of True in ``mask``."""
    edges = np.diff(np.concatenate([[0], np.asarray(mask, dtype=np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist(),
                    strict=True))


def where_moving(run, moving: np.ndarray) -> str:
    """Where the moving stretches are, in words: how many, their share of the run, the first
    few spans (s, or samples without timing)."""
    parts = stretches(moving)
    tc = run.tcol
    if run.time_unit == "s":
        span = float(tc[-1] - tc[0]) or 1.0
        dt = np.diff(tc, append=tc[-1])
        share = float(np.sum(dt[moving]) / span)
        spans = [f"{tc[a]:.3g}–{tc[min(b, run.n - 1)]:.3g} s" for a, b in parts[:3]]
    else:
        share = float(np.mean(moving))
        spans = [f"samples {a}–{b - 1}" for a, b in parts[:3]]
    more = ", …" if len(parts) > 3 else ""
    return (f"during the {len(parts)} moving stretches ({100 * share:.0f} % of the run: "
            f"{', '.join(spans)}{more})")


def _normalised(x: np.ndarray | None) -> np.ndarray | None:
    if x is None:
        return None
    x = np.asarray(x, dtype=float)
    top = float(np.max(np.abs(x))) if x.size else 0.0
    return None if not top > NORM_FLOOR else x / top


def _chi2_logsf(stat: float, dof: float) -> float:
    """log P(χ²(dof) > stat) (the regularised upper incomplete gamma; any dof > 0)."""
    return float(np.log(max(special.gammaincc(0.5 * dof, 0.5 * max(stat, 0.0)), 1e-300)))


Fit = tuple[np.ndarray, tuple[float, int, np.ndarray] | None]
"""A drive check's columns (N, c) and their test in the axis' space (:meth:`AxisSpace.test`:
ΔRSS, rank, coefficients), None when the columns lie in the model's span."""


def _level_columns(moving: np.ndarray, torque: np.ndarray | None) -> np.ndarray:
    """``drive_level``'s columns ``[m, τₙ, |τ|ₙ]`` (the torque's only when given)."""
    cols = [moving.astype(float)]
    tn = _normalised(torque)
    if tn is not None:
        cols += [tn, np.abs(tn)]
    return np.column_stack(cols)


def _gain_columns(run, k: int, moving: np.ndarray, torque: np.ndarray | None) -> np.ndarray:
    """``drive_gain``'s columns ``A_r·m`` and, with timing, ``A_r·|ω|ₙ``, ``A_r·αₙ``,
    ``A_r·τₙ``."""
    a = run.a_ref[:, k]
    cols = [a * moving]
    if run.omega is not None:
        for x in (_normalised(np.abs(run.omega)), _normalised(run.alpha),
                  _normalised(torque)):
            if x is not None:
                cols.append(a * x)
    return np.column_stack(cols)


def drive_fits(ext: Extensions, state: ModelState, torque: np.ndarray | None = None,
               spaces: list[AxisSpace] | None = None) -> list[dict[str, Fit]] | None:
    """Per axis, the ``drive_level`` and ``drive_gain`` columns of ``state`` and their tests
    (``{"level": Fit, "gain": Fit}``), made once for :func:`drive_checks` (each axis) and
    :func:`joint_drive` (both at once); None when the run has no moving and held stretches.
    ``torque`` as :func:`drive_checks`' (used with sample times only); ``spaces`` the two
    axes' :class:`AxisSpace` of ``state``, when already built."""
    moving = drive_state(ext.run.tita)
    if moving is None:
        return None
    spaces = [AxisSpace(ext, state, k) for k in range(2)] if spaces is None else spaces
    return [_axis_fits(space, ext.run, k, moving, torque) for k, space in enumerate(spaces)]


def _axis_fits(space: AxisSpace, run, k: int, moving: np.ndarray,
               torque: np.ndarray | None) -> dict[str, Fit]:
    """Axis k's ``drive_level`` and ``drive_gain`` columns and their tests in ``space``."""
    tq = None if torque is None or run.t is None else np.asarray(torque, dtype=float)
    zl, zg = _level_columns(moving, tq), _gain_columns(run, k, moving, tq)
    return {"level": (zl, space.test(zl)), "gain": (zg, space.test(zg))}


def _level(fitted: Fit, moving: np.ndarray, axis: str, where: str) -> Check | None:
    z, fit = fitted
    if fit is None:
        return None
    stat, dof, coef = fit
    size, mean_m = _level_size(z, coef, moving)
    follows = (" (it follows the drive torque)" if z.shape[1] == 3
               and abs(coef[1]) + abs(coef[2]) > abs(coef[0]) else "")
    return Check("drive_level", axis, stat, _chi2_logsf(stat, dof), f"chi2({dof})", size,
                 "m/s²",
                 f"present while moving on {axis}: a disturbance of the reading {where}, "
                 f"{mean_m:+.3g} m/s² on average against the held stretches, up to "
                 f"{size:.3g} m/s²{follows} — the drive's field or current, a cable or a "
                 "mount that pulls while the table turns")


def _level_size(z: np.ndarray, coef: np.ndarray, moving: np.ndarray) -> tuple[float, float]:
    """The fitted shift's largest magnitude while moving and its mean moving − held, m/s²."""
    shift = z @ coef
    size = float(np.max(np.abs(shift[moving])) if np.any(moving) else 0.0)
    return size, float(np.mean(shift[moving]) - np.mean(shift[~moving]))


def _gain(fitted: Fit, run, k: int, axis: str, where: str) -> Check | None:
    z, fit = fitted
    if fit is None:
        return None
    stat, dof, coef = fit
    size = float(np.max(np.abs(z @ coef)))
    gain = float(coef[0])
    top = float(np.max(np.abs(run.a_ref[:, k]))) or 1.0
    return Check("drive_gain", axis, stat, _chi2_logsf(stat, dof), f"chi2({dof})", size,
                 "m/s²",
                 f"present while moving on {axis}: the gain changes {where} — by "
                 f"{100 * gain:+.3g} % while moving ({gain * top:+.3g} m/s² at "
                 f"{top:.3g} m/s²), up to {size:.3g} m/s² with the speed, the acceleration "
                 "or the drive torque")


def _variance(z: np.ndarray, moving: np.ndarray, scale: float, axis: str, where: str
              ) -> Check | None:
    zm, zh = z[moving], z[~moving]
    if zm.size < MIN_STATE or zh.size < MIN_STATE:
        return None
    vm, vh = float(np.var(zm, ddof=1)), float(np.var(zh, ddof=1))
    if not (vm > 0 and vh > 0):
        return None
    f = vm / vh
    d1, d2 = zm.size - 1, zh.size - 1
    # P(F ≤ f) = I_x(d1/2, d2/2), x = d1·f/(d1·f + d2)
    x = d1 * f / (d1 * f + d2)
    lower = float(special.betainc(0.5 * d1, 0.5 * d2, x))
    upper = float(special.betainc(0.5 * d2, 0.5 * d1, 1.0 - x))
    logp = float(min(0.0, np.log(2.0) + np.log(max(min(lower, upper), 1e-300))))
    sm, sh = np.sqrt(vm) * scale, np.sqrt(vh) * scale
    return Check("drive_variance", axis, f, logp, f"F({d1}, {d2}), two-sided",
                 float(abs(sm - sh)), "m/s²",
                 f"present while moving on {axis}: the noise changes {where} — std "
                 f"{sm:.3g} m/s² while moving against {sh:.3g} m/s² held (a vibration or "
                 "electrical noise of the drive)")


def _excess_law(z: np.ndarray, moving: np.ndarray) -> tuple[float, float, float] | None:
    """``drive_excess``'s ``Σ_moving z²`` and its reference ``c·χ²(ν)``: (sum, c, ν) with
    ``c = κ/2``, ``ν = 2 n_m/κ``, ``κ = max(2, var(z²))``; None with too few moving samples."""
    zm = z[moving]
    if zm.size < MIN_STATE:
        return None
    kappa = max(2.0, float(np.var(z * z)))
    return float(zm @ zm), 0.5 * kappa, 2.0 * zm.size / kappa


def _excess(z: np.ndarray, moving: np.ndarray, scale: float, axis: str, where: str
            ) -> Check | None:
    """``drive_excess`` (module docstring): Σ_moving z² against the model's variance, upper
    tail of ``c·χ²(ν)`` with ``c = κ/2``, ``ν = 2 n_m/κ``, ``κ = max(2, var(z²))``."""
    law = _excess_law(z, moving)
    if law is None:
        return None
    stat, c, nu = law
    logp = _chi2_logsf(stat / c, nu)
    ratio = stat / int(moving.sum())
    added = scale * float(np.sqrt(max(ratio - 1.0, 0.0)))
    return Check("drive_excess", axis, stat, logp, f"{c:.3g}·chi2({nu:.4g}), upper tail",
                 added, "m/s²",
                 f"present while moving on {axis}: the noise is larger {where} — std "
                 f"{scale * np.sqrt(ratio):.3g} m/s² while moving against the model's "
                 f"{scale:.3g} m/s² (an added noise of std {added:.3g} m/s²: a vibration or "
                 "electrical noise of the drive)")


def _lagged(z: np.ndarray, parts: list[tuple[int, int]], lags: int
            ) -> tuple[np.ndarray, np.ndarray]:
    """Autocorrelations r_j (j = 1 … lags) of z within the stretches ``parts`` (each about
    the state's mean, over the state's variance) and the pairs P_j behind each."""
    idx = np.concatenate([np.arange(a, b) for a, b in parts])
    mu = float(np.mean(z[idx]))
    var = float(np.var(z[idx]))
    num = np.zeros(lags)
    pairs = np.zeros(lags)
    for a, b in parts:
        x = z[a:b] - mu
        for j in range(1, min(lags, b - a - 1) + 1):
            num[j - 1] += float(x[j:] @ x[:-j])
            pairs[j - 1] += b - a - j
    r = np.where(pairs > 0, num / np.maximum(pairs, 1.0) / max(var, 1e-300), 0.0)
    return r, pairs


def _spectrum(z: np.ndarray, run, moving: np.ndarray, scale: float, axis: str, where: str
              ) -> Check | None:
    mov, held = stretches(moving), stretches(~moving)
    rm, pm = _lagged(z, mov, SPECTRUM_LAGS)
    rh, ph = _lagged(z, held, SPECTRUM_LAGS)
    use = (pm >= MIN_PAIRS) & (ph >= MIN_PAIRS)
    if not np.any(use):
        return None
    d = (rm - rh)[use]
    stat = float(np.sum(d * d / (1.0 / pm[use] + 1.0 / ph[use])))
    dof = int(np.sum(use))
    lags = np.arange(1, SPECTRUM_LAGS + 1)[use]
    # the moving stretches' spectrum from their autocorrelations: S(f) = 1 + 2 Σ r_j cos(2πfj)
    f = np.linspace(0.0, 0.5, 201)
    spec = 1.0 + 2.0 * np.cos(2.0 * np.pi * f[:, None] * lags[None, :]) @ rm[use]
    peak = float(f[int(np.argmax(spec))])
    # a tone of amplitude A in the moving stretches' noise s_m: |r_j| ≤ (A²/2)/s_m²
    s_m = float(np.std(z[moving])) * scale
    amp = float(np.sqrt(2.0 * float(np.max(np.abs(rm[use]))))) * s_m
    if run.time_unit == "s":
        h = float(np.median(np.diff(run.tcol)))
        at = f"{peak / h:.3g} Hz" if peak > 0 else "the lowest frequencies"
    else:
        at = f"{peak:.3g} cycles per sample" if peak > 0 else "the lowest frequencies"
    return Check("drive_spectrum", axis, stat, _chi2_logsf(stat, dof),
                 f"chi2({dof}) of the lag-1…{int(lags[-1])} autocorrelation differences",
                 amp, "m/s²",
                 f"present while moving on {axis}: the residual's spectrum changes {where} — "
                 f"lag-1 autocorrelation {rm[0]:+.2f} while moving against {rh[0]:+.2f} held, "
                 f"the moving spectrum peaking at {at}, about {amp:.2g} m/s² (a vibration of "
                 "the drive)")


def _scan_size(n: int) -> int:
    """Length of the zero-padded DFT of ``drive_tone``: at least :data:`TONE_OVERSAMPLE`·N,
    rounded up to a length the FFT factors fast (a prime-rich 4N is ten times slower)."""
    return next_fast_len(TONE_OVERSAMPLE * n)


def _tone_scan(zs: list[np.ndarray], moving: np.ndarray
               ) -> tuple[np.ndarray, list[np.ndarray]] | None:
    """``(j, [S, …])``: the frequencies scanned (``j / size`` cycles per sample, size
    :func:`_scan_size`) and, for each of ``zs``, the tone statistic ``S(f) = uᵀC⁻¹u ~ χ²(2)``
    of its moving samples at each (module docstring); the mask's terms C(f) are the same for
    every z. None when no frequency is scanned (C too close to singular everywhere)."""
    n, nm = moving.size, int(moving.sum())
    size = _scan_size(n)
    mask = np.fft.fft(moving.astype(float), size)  # Σ_M e^{−iωk}, ω = 2πj/size: 2ω is 2j
    parts = stretches(moving)
    lowest = int(np.ceil(size / max(float(np.median([b - a for a, b in parts])), 1.0)))
    j = np.arange(max(lowest, 1), (size - 1) // 2 + 1)
    if j.size == 0:
        return None
    w2 = mask[(2 * j) % size]
    cc, ss = 0.5 * (nm + w2.real), 0.5 * (nm - w2.real)
    cs = -0.5 * w2.imag  # Σ cos·sin = ½ Σ sin 2ωk
    det = cc * ss - cs * cs
    ok = det >= TONE_CONDITION * (0.5 * nm) ** 2
    if not np.any(ok):
        return None
    j, cc, ss, cs, det = j[ok], cc[ok], ss[ok], cs[ok], det[ok]
    stats = []
    for z in zs:
        x = np.where(moving, z - float(np.mean(z[moving])), 0.0)
        spec = np.fft.rfft(x, size)[j]  # Σ_M x e^{−iωk}
        a, b = spec.real, -spec.imag  # Σ x cos ωk, Σ x sin ωk
        stats.append((ss * a * a - 2.0 * cs * a * b + cc * b * b) / det)
    return j, stats


def tone_scans(ext: Extensions, state: ModelState, residuals: np.ndarray
               ) -> tuple[np.ndarray, list[np.ndarray]] | None:
    """The ``drive_tone`` scan of both axes' standardised residuals (N, 2) of ``state`` at
    once (:func:`_tone_scan`), for :func:`drive_checks` and :func:`joint_tone`; None when the
    run has no moving and held stretches of :data:`MIN_STATE` samples or nothing to scan."""
    moving = drive_state(ext.run.tita)
    if moving is None:
        return None
    zs = [np.asarray(residuals[:, k], dtype=float) / np.sqrt(state.axes[k].sigma2_eff)
          for k in range(2)]
    return _tone_scan(zs, moving)


def _tone_words(z: np.ndarray, run, moving: np.ndarray, j: int, scale: float) -> tuple[str, float]:
    """The frequency of scan index ``j`` in words, and z's amplitude there on the held
    samples × ``scale`` (m/s²)."""
    size = _scan_size(z.size)
    kk = np.flatnonzero(~moving)
    om = 2.0 * np.pi * j / size
    zh = z[kk] - float(np.mean(z[kk]))
    amp_h = float(2.0 * np.hypot(zh @ np.cos(om * kk), zh @ np.sin(om * kk)) / kk.size) * scale
    if run.time_unit == "s":
        return f"{j / size / float(np.median(np.diff(run.tcol))):.4g} Hz", amp_h
    return f"{j / size:.4g} cycles per sample", amp_h


def _tone(z: np.ndarray, run, moving: np.ndarray, scale: float, axis: str, where: str,
          scan: tuple[np.ndarray, np.ndarray] | None) -> Check | None:
    """``drive_tone`` of one axis from its scan ``(j, S)`` (:func:`_tone_scan`)."""
    if scan is None:
        return None
    j, stat_all = scan
    nm = int(moving.sum())
    i = int(np.argmax(stat_all))
    stat, m = float(stat_all[i]), int(j.size)
    logp = float(min(0.0, np.log(m) - 0.5 * stat))
    amp = float(np.sqrt(max(2.0 * (stat - 2.0) / nm, 0.0))) * scale
    at, amp_h = _tone_words(z, run, moving, int(j[i]), scale)
    return Check("drive_tone", axis, stat, logp, f"max χ²(2) over {m} frequencies", amp,
                 "m/s²",
                 f"present while moving on {axis}: a tone of {at}, about {amp:.2g} m/s² "
                 f"{where}, against {amp_h:.2g} m/s² at that frequency held (a vibration of "
                 "the drive)")


def joint_tone(ext: Extensions, state: ModelState, residuals: np.ndarray,
               coarse: bool = False,
               scans: tuple[np.ndarray, list[np.ndarray]] | None = None) -> Check | None:
    """``drive_tone`` on both axes at once: a vibration of the drive shakes the whole sensor
    block, so both axes see the same frequency (in different amounts). With z_x, z_y the two
    axes' standardised residuals (independent under the model), ``S_x(f) + S_y(f) ~ χ²(4)``
    at each frequency scanned, and the largest over the m frequencies has
    ``P ≤ m·P(χ²(4) > S) = m·e^{−S/2}(1 + S/2)`` (Bonferroni). A tone of amplitudes A_x, A_y
    gives ``S ≈ n_m·(A_x²/σ_x² + A_y²/σ_y²)/2 + 4``: on both axes it is found where each
    axis alone stays within its level. ``scans``: :func:`tone_scans` of ``state``, when
    already made. None when either axis is coarse (rounding above the noise) or the run has no
    moving and held stretches."""
    run = ext.run
    moving = drive_state(run.tita)
    scans = tone_scans(ext, state, residuals) if scans is None else scans
    if coarse or moving is None or scans is None:
        return None
    j, (sx, sy) = scans
    total = sx + sy
    i = int(np.argmax(total))
    stat, m, nm = float(total[i]), int(j.size), int(moving.sum())
    logp = float(min(0.0, np.log(m) - 0.5 * stat + np.log1p(0.5 * stat)))
    scales = [float(np.sqrt(state.axes[k].sigma2_eff)) for k in range(2)]
    amps = [float(np.sqrt(max(2.0 * (sc[i] - 2.0) / nm, 0.0))) * s
            for sc, s in zip((sx, sy), scales, strict=True)]
    at, _ = _tone_words(np.asarray(residuals[:, 0], dtype=float) / scales[0], run, moving,
                        int(j[i]), scales[0])
    return Check("drive_tone", "both", stat, logp,
                 f"max χ²(4) over {m} frequencies, both axes", max(amps), "m/s²",
                 f"present while moving on both axes: a tone of {at}, about {amps[0]:.2g} m/s² "
                 f"on x and {amps[1]:.2g} m/s² on y {where_moving(run, moving)} (a vibration "
                 "of the drive)")


def _shares(fits: list[tuple[float, int, np.ndarray]]) -> str:
    """Each axis' part of a joint χ², in words: where the departure is."""
    return (f"χ² {fits[0][0]:.3g} of {fits[0][1]} dof on x, {fits[1][0]:.3g} of {fits[1][1]} "
            "on y")


def joint_drive(ext: Extensions, state: ModelState, residuals: np.ndarray,
                torque: np.ndarray | None = None, coarse: bool = False,
                fits: list[dict[str, Fit]] | None = None) -> list[Check]:
    """``drive_level``, ``drive_gain`` and ``drive_excess`` on both axes at once (axis
    ``both``): the drive's field, current or vibration reaches the whole sensor block, so a
    disturbance, a gain change or added noise while moving shows on both axes (in different
    amounts), each of which may stay within its own level.

    Each axis' statistic is the one of :func:`drive_checks` (its own columns, coefficients
    free per axis); under the model the two axes' residuals are independent (each axis is
    fitted on its own; a tilt offset shares one column, a weak dependence neglected here as
    in :func:`joint_tone`), so

    * ``drive_level``, ``drive_gain``: ``S_x + S_y ~ χ²(k_x + k_y)``;
    * ``drive_excess``: ``Σ_M z_x² + Σ_M z_y²``, the sum of ``c_x·χ²(ν_x)`` and
      ``c_y·χ²(ν_y)``, is compared with ``c·χ²(ν)`` of the same mean and variance
      (Satterthwaite): ``μ = c_xν_x + c_yν_y``, ``V = 2(c_x²ν_x + c_y²ν_y)``, ``c = V/2μ``,
      ``ν = 2μ²/V``; left out when either axis carries a walk or is coarse.

    For a departure of z_x and z_y standard deviations the joint statistic sees
    ``z_x² + z_y²``: a gain change of z ≈ 3.5 on each axis (each near p = 10⁻³, inside its
    Bonferroni level) is z ≈ 5 together. ``residuals`` (N, 2) as :func:`drive_checks`' for
    each axis; ``fits`` the :func:`drive_fits` of ``state``, when already made (the per-axis
    checks' own). Empty when the run has no moving and held stretches."""
    run = ext.run
    moving = drive_state(run.tita)
    fits = drive_fits(ext, state, torque) if fits is None else fits
    if moving is None or fits is None:
        return []
    where = where_moving(run, moving)
    out: list[Check] = []

    (zl, fx), (_, fy) = fits[0]["level"], fits[1]["level"]
    if fx is not None and fy is not None:
        stat, dof = fx[0] + fy[0], fx[1] + fy[1]
        (sx, mx), (sy, my) = (_level_size(zl, f[2], moving) for f in (fx, fy))
        out.append(Check(
            "drive_level", "both", stat, _chi2_logsf(stat, dof), f"chi2({dof}), both axes",
            max(sx, sy), "m/s²",
            f"present while moving on both axes: a disturbance of the reading {where}, "
            f"{mx:+.3g} m/s² on x and {my:+.3g} m/s² on y on average against the held "
            f"stretches, up to {max(sx, sy):.3g} m/s² ({_shares([fx, fy])}) — the drive's "
            "field or current, a cable or a mount that pulls while the table turns"))

    (zx, fx), (zy, fy) = fits[0]["gain"], fits[1]["gain"]
    if fx is not None and fy is not None:
        stat, dof = fx[0] + fy[0], fx[1] + fy[1]
        size = max(float(np.max(np.abs(z @ f[2]))) for z, f in ((zx, fx), (zy, fy)))
        gx, gy = (100.0 * float(f[2][0]) for f in (fx, fy))
        out.append(Check(
            "drive_gain", "both", stat, _chi2_logsf(stat, dof), f"chi2({dof}), both axes",
            size, "m/s²",
            f"present while moving on both axes: the gain changes {where} — by {gx:+.3g} % "
            f"on x and {gy:+.3g} % on y while moving, up to {size:.3g} m/s² with the speed, "
            f"the acceleration or the drive torque ({_shares([fx, fy])})"))

    if coarse or any(st.q > 0 for st in state.axes):
        return out
    scales = [float(np.sqrt(st.sigma2_eff)) for st in state.axes]
    laws = [_excess_law(np.asarray(residuals[:, k], dtype=float) / scales[k], moving)
            for k in range(2)]
    if laws[0] is None or laws[1] is None:
        return out
    stat = laws[0][0] + laws[1][0]
    mean = sum(c * nu for _, c, nu in laws)
    var = 2.0 * sum(c * c * nu for _, c, nu in laws)
    c, nu = var / (2.0 * mean), 2.0 * mean * mean / var
    n_m = int(moving.sum())
    stds = [sc * float(np.sqrt(law[0] / n_m)) for sc, law in zip(scales, laws, strict=True)]
    added = [sc * float(np.sqrt(max(law[0] / n_m - 1.0, 0.0)))
             for sc, law in zip(scales, laws, strict=True)]
    out.append(Check(
        "drive_excess", "both", stat, _chi2_logsf(stat / c, nu),
        f"{c:.3g}·chi2({nu:.4g}), upper tail, both axes", max(added), "m/s²",
        f"present while moving on both axes: the noise is larger {where} — std "
        f"{stds[0]:.3g} m/s² on x and {stds[1]:.3g} m/s² on y while moving against the "
        f"model's {scales[0]:.3g} and {scales[1]:.3g} m/s² (added noise of std "
        f"{added[0]:.3g} and {added[1]:.3g} m/s²: a vibration or electrical noise of the "
        "drive)"))
    return out


def drive_checks(ext: Extensions, state: ModelState, k: int, residual: np.ndarray,
                 torque: np.ndarray | None = None, coarse: bool = False,
                 fits: dict[str, Fit] | None = None,
                 scans: tuple[np.ndarray, list[np.ndarray]] | None = None) -> list[Check]:
    """The six drive-state checks on axis k of the final model (those that apply).

    residual : (N,) the final model's residuals of axis k, m/s², white with the model's
        variance σ²_eff under the model (:func:`calib.gap.adequacy.run_battery`'s input).
    torque : (N,) the drive's joint torque at the samples, N·m (the bench's inverse
        dynamics of the replayed θ(t)), or None.
    coarse : the rounding is coarser than the noise: the variance and spectrum checks (which
        assume a continuous Gaussian residual) are left out, as the battery's tail checks are.
    fits : axis k's entry of :func:`drive_fits` of ``state``, when already made.
    scans : :func:`tone_scans` of ``state`` (both axes), when already made.
    """
    run = ext.run
    moving = drive_state(run.tita)
    if moving is None:
        return []
    axis = AXES[k]
    st = state.axes[k]
    scale = float(np.sqrt(st.sigma2_eff))
    z = np.asarray(residual, dtype=float) / scale
    where = where_moving(run, moving)
    if fits is None:
        fits = _axis_fits(AxisSpace(ext, state, k), run, k, moving, torque)
    found = [_level(fits["level"], moving, axis, where),
             _gain(fits["gain"], run, k, axis, where)]
    if not coarse:
        if scans is None:
            scan = _tone_scan([z], moving)
            scan = None if scan is None else (scan[0], scan[1][0])
        else:
            scan = (scans[0], scans[1][k])
        found += [_variance(z, moving, scale, axis, where),
                  None if st.q > 0 else _excess(z, moving, scale, axis, where),
                  _spectrum(z, run, moving, scale, axis, where),
                  _tone(z, run, moving, scale, axis, where, scan)]
    return [c for c in found if c is not None]

"""A static log's shaping filter: the low-pass filter an export applied to every reading.

Phones and many loggers do not hand out the sensor's raw samples: the readings went through a
low-pass (decimation) filter first. Its mark on the Allan deviation is at short τ: the curve
sits below the white noise's ``N/√τ`` and rises to meet it a few filter lengths later (the
real 6-hour Galaxy S5 log of docs/noise.md rises from τ = 0.2 to 3 s). No term of the noise
model has that shape, so without the filter the fit can only describe the octaves beyond it,
and a twin made of white noise is several times noisier than the log at short τ.

**The model.** Every process reaches the readings through one linear filter ``f`` with unit
gain at zero frequency (Σ f = 1): ``y = f ∗ x``, x the sum of the model's processes. The
octave-m Allan difference of ``y`` is then the difference filter ``h_m ∗ f`` applied to x,
so the exact moments of :mod:`calib.noise.allan_model` hold with ``h_m ∗ f`` in place of
``h_m`` (:func:`calib.noise.allan_model.record_moments` with ``shaping``). Beyond a few
filter lengths ``h_m ∗ f`` acts as ``h_m`` on every term, so N, B and K keep their meaning
(f passes zero frequency unchanged); the twin draws its processes and filters them with the
same ``f`` (:func:`bench.sensor_twin.simulate_axis`).

**The rule (when a log is shaped).** On the first :data:`MAX_SAMPLES` readings, a straight
line removed, both hold:

* the correlation time is longer than one sample: the autocorrelation at lag 1 is at least
  ``1/e`` (:func:`calib.logs.static_log.correlation_time`, the static check's: the first lag
  below 1/e, a line removed, on the first 2^17 readings);
* the Allan deviation does not fall over the first octave: ``σ_A(2τ0) ≥`` :data:`RISING_START`
  ``· σ_A(τ0)`` (0.85). White noise at the shortest τ gives 1/√2 = 0.71 whatever slow terms
  (flicker, a walk, a Gauss–Markov bias) ride on it — they can correlate the readings at
  lag 1 when they dominate the record's variance, but not the shortest τ — while an export's
  filter flattens or raises the curve there (the Galaxy S5 log: 0.90–0.92).

A log whose correlation time is longer than ``n/160`` readings (the filter's lags would not
fit 16 times in the record) is not shaped either.

**The estimate.** With the correlation time T (samples) the filter's lags are ``L =``
:data:`SPAN` · T. The spectrum ``S`` is Welch's (Blackman–Harris segments of the power of two
≥ 8(L + 1) readings, a line removed from each; a low-leakage window, so that the filter's
deep stopband is not filled by the passband's sidelobes), averaged over the log's records
when it has gaps. The passband runs from bin :data:`LOW_BINS` to where S falls to half its
peak; on its lower half (at least :data:`BAND_BINS` bins) ``S ≈ w + c·f₀/f`` — white noise
and flicker — is fitted by least squares in relative terms (each Welch bin has the same
relative error). The filter shapes every term, so ``|F(f)|² = S(f) / (w + c·f₀/f)``, set to 1
below bin :data:`LOW_BINS` (the passband is flat down to zero frequency); ``f`` is the
zero-phase filter with that gain, its inverse transform on lags −L … L, scaled to Σ f = 1. A
filter is only known up to its phase from second-order statistics, and the Allan variance
depends on nothing else. (Without the 1/f part, flicker at B = 0.2·N/√Hz made the passband
read 8 % high and Σ f² 8 % low; with it, 0.3 % on average.)

**What it leaves uncertain** (:func:`shaping_spread`). The passband's level relative to zero
frequency is read from the low frequencies alone, and the short-τ octaves tie N to it. A
seeded parametric bootstrap gives the covariance of each octave's log white Allan variance
over re-estimates; the fit widens N's interval by it and the twin closure adds it
(:mod:`calib.noise.allan`, :mod:`calib.noise.closure`).

**Block means.** A long log read in block means is fitted with the block means' filter
(:func:`blocked_filter`, exact from f's autocorrelation); the twin filters at the log's rate
and takes the same block means.

Hand-written because no library estimates an export filter from its output (scipy's
``signal`` designs filters from a specification, not from a record).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from calib.logs.static_log import correlation_time

RISING_START = 0.85
"""…and its Allan deviation at 2τ0 is at least this times the one at τ0: white noise gives
1/√2 = 0.71 (falling), a low-pass filter makes it level or rising."""


def _first_octave_ratio(y: np.ndarray) -> float:
    """σ_A(2τ0)/σ_A(τ0) of the readings (overlapping Allan deviations, written out here: the
    rule's two numbers)."""
    d1 = np.diff(y)
    pair = y[:-1] + y[1:]
    d2 = pair[2:] - pair[:-2]
    a1 = float(d1 @ d1) / (2.0 * d1.size)
    a2 = float(d2 @ d2) / (8.0 * d2.size)
    return math.sqrt(a2 / a1) if a1 > 0 else 0.0
SPAN = 10
"""The filter's lags: this many correlation times (about ten independent readings, the
window rule of the static check)."""
BAND_BINS = 8
"""Fewest bins the passband's level is fitted on."""
LOW_BINS = 3
"""Spectrum bins (of a segment of ≈ 8L readings) left to the slow terms: below them the
filter's passband is taken as flat (gain 1)."""
MAX_SAMPLES = 1 << 18
"""Readings the estimate reads (the first ones): far more than a filter of a few hundred lags
needs (the autocorrelation's spread is ≈ 1/√n = 0.002 at this length)."""
MAX_TAPS = 2049
"""Longest filter kept (lags −1024 … 1024): the moments' cost grows with the taps."""


def shaping_filter(y: np.ndarray | list[np.ndarray]) -> tuple[float, ...] | None:
    """The shaping filter of the readings ``y`` (module docstring: the rule and the
    estimate): its taps on lags −L … L, Σ = 1, as a tuple; None when the log is not shaped
    (or too short to tell: fewer than 64 readings). ``y`` may be a list of records (a log's
    segments between its gaps): the rule reads the longest, the spectrum is the mean of every
    record's that holds a Welch segment (weighted by their segments), at most
    :data:`MAX_SAMPLES` readings in all."""
    records = [np.asarray(r, dtype=float).ravel() for r in
               (y if isinstance(y, (list, tuple)) else [y])]
    records, budget = [r[:MAX_SAMPLES] for r in records], MAX_SAMPLES
    kept = []
    for r in sorted(records, key=lambda r: -r.size):
        if budget <= 0:
            break
        kept.append(r[:budget])
        budget -= kept[-1].size
    y = kept[0]
    n = y.size
    if n < 64 or not np.all(np.isfinite(y)):
        return None
    # the cheap half of the rule first (on 2^16 readings: ±0.005), most logs being white at
    # the shortest τ
    if _first_octave_ratio(y[:1 << 16]) < RISING_START:
        return None  # white noise at the shortest τ: slow terms correlate it, not a filter
    tau = correlation_time(y)  # the static check's: the first lag below 1/e, a line removed
    if tau <= 1:
        return None  # lag-1 autocorrelation below 1/e
    lags = SPAN * tau
    if 16 * lags > n or 2 * lags + 1 > MAX_TAPS:
        return None  # never below 1/e within n/160 lags: a slow process, not a filter
    from scipy import signal

    size = min(1 << int(math.ceil(math.log2(8 * (lags + 1)))), 1 << int(math.log2(n)))
    spectra, weights = [], []
    for rec in kept:
        if rec.size >= size and np.all(np.isfinite(rec)):
            spectra.append(signal.welch(rec, nperseg=size, window="blackmanharris",
                                        detrend="linear")[1])
            weights.append(rec.size // (size // 2))  # Welch's segments at half overlap
    psd = np.average(np.array(spectra), axis=0, weights=weights)
    # the passband: the bins from LOW_BINS up to where the spectrum falls to half its peak;
    # its white level and the slow terms from their lower half (module docstring)
    peak = float(psd[LOW_BINS:].max())
    edge = LOW_BINS + int(np.argmax(psd[LOW_BINS:] < peak / 2.0))
    k = np.arange(LOW_BINS, max(LOW_BINS + BAND_BINS, (LOW_BINS + edge) // 2))
    freq = k / size  # cycles per sample
    a = np.column_stack([np.ones(k.size), freq[0] / freq])  # white + flicker (1/f)
    weight = 1.0 / psd[k]  # each bin's relative error is the same (Welch, χ² bins)
    coef = np.linalg.lstsq(a * weight[:, None], np.ones(k.size), rcond=None)[0]
    white, flicker = float(coef[0]), max(float(coef[1]), 0.0)
    if not (white > 0.0 and math.isfinite(white)):
        return None
    # the filter shapes every term, flicker too: |F|² = S / (white + flicker·f₀/f)
    bins = np.arange(psd.size, dtype=float)
    power = psd / (white + flicker * k[0] / np.maximum(bins, 1.0))
    power[:LOW_BINS] = 1.0  # the passband is flat down to zero frequency
    return _zero_phase(np.sqrt(np.maximum(power, 0.0)), size, lags)


def _zero_phase(gain: np.ndarray, size: int, lags: int) -> tuple[float, ...] | None:
    """The zero-phase filter of amplitude response ``gain`` (rfft bins of ``size``), kept on
    lags −``lags`` … ``lags`` and scaled to Σ = 1; None when it does not pass zero frequency."""
    taps = np.fft.irfft(gain, size)
    f = np.concatenate([taps[size - lags:], taps[:lags + 1]])
    total = float(f.sum())
    if not math.isfinite(total) or total <= 0.0:
        return None
    return tuple(float(v) for v in f / total)


def blocked_filter(taps: tuple[float, ...], block: int) -> tuple[float, ...] | None:
    """The shaping filter of the block means (``block`` readings each) of a log shaped by
    ``taps``: the zero-phase filter whose autocorrelation is that of the block means of
    ``taps ∗ w`` (w white), ``r_b(k) = Σ_d (b − |d|)·r(kb + d) / b²`` with ``r = taps ⋆ taps``,
    normalized to Σ = 1: one filter, so the fit of the block means and the twin that filters
    at the log's rate describe the same readings. ``taps`` itself for ``block`` 1; None when
    the block means are white (the filter within one block)."""
    f = np.asarray(taps, dtype=float)
    if block == 1:
        return tuple(float(v) for v in f)
    r = np.correlate(f, f, mode="full")  # lags −(len−1) … len−1
    half = f.size - 1
    lags = (half + block - 1) // block  # r_b(k) = 0 beyond
    if lags == 0:
        return None
    d = np.arange(-(block - 1), block)
    weight = (block - np.abs(d)) / block ** 2

    def at(lag: np.ndarray) -> np.ndarray:
        inside = np.abs(lag) <= half
        return np.where(inside, r[np.clip(lag + half, 0, r.size - 1)], 0.0)

    rb = np.array([weight @ at(k * block + d) for k in range(lags + 1)])
    if rb[1] < 1e-6 * rb[0]:
        return None
    size = 1 << int(math.ceil(math.log2(8 * (lags + 1))))
    omega = 2.0 * np.pi * np.arange(size // 2 + 1) / size
    spectrum = rb[0] + 2.0 * np.cos(np.outer(omega, np.arange(1, lags + 1))) @ rb[1:]
    return _zero_phase(np.sqrt(np.maximum(spectrum, 0.0) / spectrum[0]), size, lags)


SPREAD_DRAWS = 24
"""Re-estimates of a filter behind :func:`shaping_spread`: a covariance of a few octaves that
are nearly one (the shaped octaves move together) is read well from a few dozen draws."""


def _white_allan(f: np.ndarray, ms: tuple[int, ...]) -> np.ndarray:
    """(k,) the Allan variance of unit white noise shaped by ``f`` at octaves ``ms``:
    ``Σ (h_m ∗ f)² / 2`` (:mod:`calib.noise.allan_model`, white column)."""
    from calib.noise.allan_model import difference_filter

    out = []
    for m in ms:
        d = difference_filter(m, tuple(f))
        out.append(float(d @ d) / 2.0)
    return np.array(out)


@lru_cache(maxsize=32)
def shaping_spread(taps: tuple[float, ...], n: int, ms: tuple[int, ...], block: int = 1,
                   seed: int = 0, draws: int = SPREAD_DRAWS) -> np.ndarray:
    """(k, k) covariance of the log of each octave's white Allan variance over re-estimates
    of the filter: the spread a filter read from ``n`` readings leaves in the model it shapes.

    A parametric bootstrap with ``taps`` taken as true: ``draws`` records of ``n`` readings
    (at most :data:`MAX_SAMPLES`, what the estimate reads) of white noise through ``taps``,
    the filter estimated on each (:func:`shaping_filter`; then :func:`blocked_filter` of
    ``block``), and ``log Σ(h_m ∗ g)²/2 − log Σ(h_m ∗ f)²/2`` at the fit's octaves ``ms``.
    The twin-closure test adds it to its covariance (:mod:`calib.noise.closure`: the filter
    was read from the log it is compared with). Seeded: the same numbers on every run."""
    from scipy import signal

    f = np.asarray(taps, dtype=float)
    fit_f = blocked_filter(tuple(f), block)
    size = min(int(n), MAX_SAMPLES)
    rows = []
    base = None if fit_f is None else _white_allan(np.asarray(fit_f), ms)
    rng = np.random.default_rng(seed)
    for _ in range(draws if fit_f is not None else 0):
        y = signal.fftconvolve(rng.standard_normal(size + f.size - 1), f, mode="valid")
        g = shaping_filter(y)
        gb = None if g is None else blocked_filter(g, block)
        if gb is None:
            continue
        rows.append(np.log(_white_allan(np.asarray(gb), ms) / base))
    out = (np.zeros((len(ms), len(ms))) if len(rows) < 2
           else np.atleast_2d(np.cov(np.array(rows), rowvar=False)))
    out.setflags(write=False)  # cached (the fit and the twin closure ask for the same one)
    return out


def shaping_summary(shaping: tuple[float, ...] | None, rate: float) -> str | None:
    """One line about a shaping filter: its lags and its equivalent noise bandwidth
    ``fs·Σf²/2`` (Hz; the one-sided band of an ideal low-pass with the same white-noise
    power); None for no filter."""
    if shaping is None:
        return None
    f = np.asarray(shaping, dtype=float)
    lags = (f.size - 1) // 2
    band = rate * float(f @ f) / 2.0
    return (f"shaped by the export's low-pass filter: {f.size} taps (±{lags} samples = "
            f"±{lags / rate:.3g} s), noise bandwidth {band:.3g} Hz of the {rate / 2:.3g} Hz "
            "Nyquist band")


__all__ = ["BAND_BINS", "LOW_BINS", "MAX_SAMPLES", "MAX_TAPS",
           "RISING_START", "SPAN", "SPREAD_DRAWS",
           "blocked_filter", "shaping_filter", "shaping_spread", "shaping_summary"]

"""An export's low-pass filter in the noise model (:mod:`calib.noise.shaping`; issue 32: the
twin of a real, filtered long log).

The filtered logs are made here with scipy.signal (a 4-pole Butterworth low-pass, as a phone's
export applies) on the readings of :mod:`validation.noise_independent.generator` (white noise
and a flicker bank of AR(1) processes: not the bench's processes), never by the bench:

* the exact moments with a shaping filter: a one-tap filter gives today's numbers bit for
  bit; filtered white noise's octave Allan variances have the shaped model's mean and
  variance over 400 simulated records;
* the rule: unfiltered logs of every family are not shaped, filtered ones are, and the filter
  read from a log has the true filter's noise power within 10 %;
* the block means' filter describes the same readings as the filter at the log's rate;
* ``noise --twin`` on a filtered log fits the whole octave grid and its twin closes; over R
  filtered logs the closure rejects a true twin at most at its α (binomial band) and a twin
  1.5× noisier nearly always.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import signal, stats

from bench.sensor_twin import ExportFilter, simulate_axis, twin_axis
from calib.noise.allan import characterize_noise, overlapping_adev
from calib.noise.allan_model import gm_columns, moments
from calib.noise.closure import CLOSURE_ALPHA, closure_test, twin_adev
from calib.noise.sensor_profile import load_profile
from calib.noise.shaping import _white_allan, blocked_filter, shaping_filter, shaping_spread
from tests.cli import run
from tests.test_twin_closure import band, noisier
from validation.noise_independent.generator import NoiseSpec, static_log

RATE = 10.0
MS = (1, 2, 4, 8, 16, 32, 64)


def butter(cut: float = 0.3) -> tuple[np.ndarray, np.ndarray]:
    return signal.butter(4, cut, fs=RATE)


def exported(y: np.ndarray, cut: float = 0.3) -> np.ndarray:
    """``y`` through the export's 4-pole Butterworth low-pass at ``cut`` Hz, the first 2000
    readings (its start-up) dropped."""
    b, a = butter(cut)
    return signal.lfilter(b, a, y)[2000:]


def true_taps(cut: float = 0.3) -> np.ndarray:
    b, a = butter(cut)
    h = signal.lfilter(b, a, np.r_[1.0, np.zeros(3999)])
    return h / h.sum()


def test_a_one_tap_filter_gives_the_unshaped_moments_bit_for_bit():
    a, b = moments(4096, MS), moments(4096, MS, (1.0,))
    assert np.array_equal(a.design, b.design) and np.array_equal(a.tensor, b.tensor)
    assert np.array_equal(gm_columns(4096, MS, 3.0), gm_columns(4096, MS, 3.0, (1.0,)))


def test_shaped_moments_match_filtered_white_noise():
    """400 records of white noise through a 9-tap FIR: each octave's mean Allan variance
    within 4 standard errors of the shaped model's, its variance within 5 standard errors of
    a sample variance (√(2/(R−1)) relative); the unshaped model is far outside both."""
    f = signal.firwin(9, 0.2)
    f = f / f.sum()
    n, r = 4096, 400
    mom = moments(n, MS, tuple(f))
    rng = np.random.default_rng(20261129)
    s = np.array([overlapping_adev(np.convolve(rng.standard_normal(n + 8), f, "valid"),
                                   1.0, MS)[1] ** 2 for _ in range(r)])
    mean, var = mom.design[:, 0], np.array([mom.tensor[i, i, 0, 0] for i in range(len(MS))])
    se = np.sqrt(var / r)
    assert np.all(np.abs(s.mean(axis=0) - mean) < 4.0 * se)
    assert np.all(np.abs(s.var(axis=0, ddof=1) / var - 1.0) < 5.0 * np.sqrt(2.0 / (r - 1)))
    plain = moments(n, MS).design[:, 0]
    assert np.abs(s.mean(axis=0)[0] - plain[0]) > 100.0 * se[0]


@pytest.mark.parametrize("spec", [
    NoiseSpec(rate=RATE, white=1e-3),
    NoiseSpec(rate=RATE, white=1e-3, flicker=5e-4, walk=1e-4),
    NoiseSpec(rate=RATE, white=1e-3, gm_sigma=1e-3, gm_tc=5.0),
    # correlated at lag 1 (a walk or a Gauss–Markov bias far above the white noise), but
    # with rough steps: not a low-pass (the rule's second condition)
    NoiseSpec(rate=RATE, white=4e-5, flicker=2.4e-5, walk=7e-6, read_step=4e-5),
    NoiseSpec(rate=RATE, white=1e-4, walk=1e-4),
    NoiseSpec(rate=RATE, white=1e-3, gm_sigma=1e-2, gm_tc=5.0)])
def test_unfiltered_logs_are_not_shaped(spec):
    rng = np.random.default_rng(1)
    for _ in range(10):
        assert shaping_filter(static_log(spec, 16384, rng)[0]) is None


def test_the_filter_read_from_a_log_errs_as_the_closure_assumes():
    """The closure adds the spread of the filter's estimate (:func:`shaping_spread`, a
    bootstrap). On 20 filtered white logs the estimate's error in the first octave's white
    Allan variance (log) has a mean within 4 standard errors of 0 and a variance inside the
    99.8 % χ²(19) band of the bootstrap's. (With flicker at B = 0.2·N per √Hz the estimate
    reads the passband ≈ 8 % low, sd 8 %: more than the bootstrap, which draws white noise
    only; docs/noise.md.)"""
    spec = NoiseSpec(rate=RATE, white=1e-3)
    truth = true_taps()[:301]
    truth = truth / truth.sum()
    n, r = 62000, 20
    base = _white_allan(truth, (1,))[0]
    rng = np.random.default_rng(2)
    err = []
    for _ in range(r):
        f = shaping_filter(exported(static_log(spec, n + 2000, rng)[0]))
        assert f is not None and abs(sum(f) - 1.0) < 1e-9 and len(f) % 2 == 1
        err.append(np.log(_white_allan(np.asarray(f), (1,))[0] / base))
    boot = shaping_spread(tuple(truth), n, (1,))[0, 0]
    err = np.array(err)
    assert abs(err.mean()) < 4.0 * np.sqrt(boot / r)
    lo, hi = stats.chi2.ppf([0.001, 0.999], r - 1) / (r - 1)
    assert lo < err.var(ddof=1) / boot < hi


@pytest.mark.parametrize("block", [1, 2, 4])
def test_the_block_means_filter_describes_the_same_readings(block):
    """The Allan variance of the block means at m equals the readings' at m·block (block
    means of a stationary series): the white column of ``blocked_filter`` at m, divided by
    the block, is the filter's at m·block."""
    f = true_taps()
    f = f[:161] / f[:161].sum()
    g = blocked_filter(tuple(f), block)
    ms = (2, 4, 8, 16, 32, 64)
    ratio = _white_allan(np.asarray(g), ms) / block / _white_allan(f, tuple(m * block
                                                                            for m in ms))
    assert np.allclose(ratio, 1.0, rtol=2e-3)


def test_the_twin_filters_without_an_edge():
    """:class:`ExportFilter` in the twin: every reading has its whole filter (the record is
    drawn longer and cut), so the first readings are as noisy as the middle ones."""
    f = true_taps()[:201]
    f = f / f.sum()
    from bench.sensors import AxisErrors

    errors = AxisErrors(noise_var=1.0, terms=(ExportFilter(taps=tuple(f)),))
    y = np.array([simulate_axis(errors, 400, RATE, np.random.default_rng(k))
                  for k in range(300)])
    head, middle = y[:, :50].var(), y[:, 175:225].var()
    assert abs(head / middle - 1.0) < 0.15
    assert abs(middle / float(f @ f) - 1.0) < 0.15


def write(path, acc: np.ndarray):
    t = np.arange(acc.shape[0]) / RATE
    np.savetxt(path, np.column_stack([t, acc]), delimiter=",", fmt="%.9g",
               header="t (s),ax (m/s^2),ay (m/s^2),az (m/s^2)", comments="")
    return path


def test_noise_on_a_filtered_log_fits_every_octave_and_saves_the_filter(tmp_path, capsys):
    spec = NoiseSpec(rate=RATE, white=2e-3, flicker=2e-4)
    rng = np.random.default_rng(3)
    acc = np.column_stack([exported(static_log(spec, 32000, rng)[0]) for _ in range(3)])
    path = write(tmp_path / "lp.csv", acc + [0.05, -0.03, 9.8])
    saved = tmp_path / "sensor.json"
    rc, out, err = run(capsys, "noise", path, "--twin", "--json", "--save", saved)
    assert rc == 0, err
    doc = json.loads(out)
    for axis in ("x", "y", "z"):
        fit = doc["axes"][axis]
        assert fit["export_filter"] is not None and fit["fit_ok"]
        assert fit["fit_range"][0] <= 0.4  # the filter's octaves (0.1–3 s) are described
    profile = load_profile(saved)
    assert profile.export_filter is not None
    assert any(isinstance(t, ExportFilter) for t in twin_axis(profile, "x", RATE).terms)
    rc, out, err = run(capsys, "noise", path)
    assert "shaped by the export's low-pass filter" in " ".join(out.split())
    # the twin on the MuJoCo table (generate --sensor) is filtered alike, and noise reads it
    rc, out, err = run(capsys, "generate", "static", "--sensor", saved, "--duration", "2000",
                       "--theta", "0", "--seed", "1", "--out", tmp_path / "twin")
    assert rc == 0, err
    truth = json.loads((tmp_path / "twin" / "truth.json").read_text())
    assert "export_filter" in {t["name"] for t in truth["sensor"]["x"]["terms"]}
    rc, out, err = run(capsys, "noise", tmp_path / "twin" / "static.mat", "--json")
    assert rc == 0, err
    assert json.loads(out)["axes"]["x"]["export_filter"] is not None


@pytest.mark.slow
def test_twin_closure_on_filtered_logs_has_its_size_and_power():
    """R = 40 axis-logs (20 calls × x, y) of 16 384 filtered readings: the true twin is
    rejected at most at α within the binomial band (the filter read from the log makes the
    test conservative, not liberal), the 1.5× noisier twin in ≥ 90 %, and N's interval
    (widened by the filter's spread) covers the true N at its level within the band.
    Measured (this seed): true twin rejected 1/40, the noisier one 40/40, N covered 23/40 at
    0.683 (R = 40 supports only these coarse claims)."""
    spec = NoiseSpec(rate=RATE, white=2e-3, flicker=2e-4)
    rng = np.random.default_rng(20261130)
    n = 2 ** 14
    same = louder = total = covered = 0
    for _ in range(20):
        cols = [exported(static_log(spec, n + 2000, rng)[0]) for _ in range(2)]
        res = characterize_noise(np.column_stack(cols), RATE, axes=("x", "y"))
        profile = res.to_profile()
        for fit in res.axes:
            assert fit.export_filter is not None
            errors = twin_axis(profile, fit.axis, RATE)
            same += closure_test(fit, twin_adev(fit, simulate_axis(errors, n, RATE, rng),
                                                RATE)).reject
            louder += closure_test(fit, twin_adev(fit, simulate_axis(noisier(errors, 1.5), n,
                                                                     RATE, rng), RATE)).reject
            total += 1
            lo, hi = fit.term("white_noise_density").interval
            covered += lo <= spec.white_eff <= hi
    assert same / total <= CLOSURE_ALPHA + band(CLOSURE_ALPHA, total)
    assert louder / total >= 0.9
    assert abs(covered / total - 0.683) <= band(0.683, total)


@pytest.mark.parametrize("taps, words", [([0.2, 0.3, 0.4], "sums to 0.9"),
                                         ([0.5, 0.5], "odd number"),
                                         ([-2.0, 4.0, -1.0], "within ±1")])
def test_a_profile_with_bad_filter_taps_is_refused_naming_the_field(tmp_path, taps, words):
    """``export_filter`` checked on load like every field: one line naming the file and the
    field (the checksum is recomputed, so the taps' own checks are what refuse)."""
    from calib.input_rules import DataError
    from calib.noise.sensor_profile import (
        NoiseTerm,
        SensorProfile,
        defining_checksum,
        profile_document,
    )

    term = NoiseTerm(value=1e-3, interval=(9e-4, 1.1e-3), tau_range=(0.1, 10.0), level=0.683)
    doc = profile_document(SensorProfile(sample_rate=10.0, white_noise_density=(term, term),
                                         export_filter=((0.25, 0.5, 0.25), None),
                                         extra={"level": 0.683, "alpha": 0.05, "n": 1000}))
    doc["axes"]["x"]["export_filter"] = taps
    doc["checksum"]["value"] = defining_checksum(doc)
    path = tmp_path / "sensor.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(DataError) as err:
        load_profile(path)
    line = str(err.value)
    assert "\n" not in line and str(path) in line and "axes.x.export_filter" in line
    assert words in line
    doc["axes"]["x"]["export_filter"] = [0.25, 0.5, 0.25]
    doc["checksum"]["value"] = defining_checksum(doc)
    path.write_text(json.dumps(doc))
    assert load_profile(path).export_filter[0] == (0.25, 0.5, 0.25)


def test_a_filtered_log_with_a_gap_is_shaped_from_all_its_segments(tmp_path, capsys):
    """A gap (2000 rows cut out): the log is split, the filter read from the spectrum of both
    segments, every octave fitted from τ ≤ 0.4 s, and the profile written (N's widened
    interval kept inside its physical range)."""
    spec = NoiseSpec(rate=RATE, white=2e-3, flicker=2e-4)
    rng = np.random.default_rng(3)
    acc = np.column_stack([exported(static_log(spec, 32000, rng)[0]) for _ in range(3)])
    t = np.arange(acc.shape[0]) / RATE
    keep = np.r_[0:14000, 16000:acc.shape[0]]
    path = tmp_path / "gap.csv"
    np.savetxt(path, np.column_stack([t[keep], acc[keep] + [0.05, -0.03, 9.8]]),
               delimiter=",", fmt="%.9g", comments="",
               header="t (s),ax (m/s^2),ay (m/s^2),az (m/s^2)")
    rc, out, err = run(capsys, "noise", path, "--twin", "--json", "--save",
                       tmp_path / "s.json")
    assert rc == 0, err
    doc = json.loads(out)
    assert len(doc["segments"]) == 2
    for axis in ("x", "y", "z"):
        fit = doc["axes"][axis]
        assert fit["export_filter"] is not None and fit["fit_range"][0] <= 0.4
    assert not doc["twin"]["x"]["reject"]

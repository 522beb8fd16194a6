"""``tiltbench noise`` on a static log with gaps in time: the log is split at its gaps (the
reader's rule, :data:`calib.logs.reader.GAP_FACTOR`), never filled, and the overlapping Allan
variance is pooled over the segments as independent records (:mod:`calib.noise.allan`: Logs
with gaps; :func:`calib.noise.allan_model.pooled_moments`).

What is checked:

* one segment is today's path: the same numbers (to 1e-12 relative) whether the segments are
  not given, given as one length or as one (start, stop) pair; the pooled moments of one
  segment are its own moments;
* the pooled Allan variance equals a hand computation written here (numpy cumulative sums,
  per segment, pooled by the counts of overlapping differences ``n_s − 2m + 1``);
* the pooled moments: the mean and variance of the pooled Allan variance of white noise plus a
  random walk over three short segments against a Monte Carlo of R = 4000 records (each
  octave's mean within 5 standard errors, its variance within 5 standard errors of the sample
  variance, the standard error from the same draws);
* coverage of the white-noise density N's interval on white noise split into three segments:
  R = 300 logs, at 68.3 % and 95 %: |hits/R − level| ≤ 4·sqrt(level·(1 − level)/R), the
  binomial band of the style guide (0.108 at 68.3 %, 0.050 at 95 %): R = 300 supports the
  claim "the coverage is within about ±0.1 (68.3 %) / ±0.05 (95 %) of the level", not finer;
* the command line end to end on a CSV with a gap (exit 0, the one-line note on stderr, the
  segments in ``--json`` and in the text), a log whose segments are all too short (refused in
  one line naming the longest), ``--twin`` with the log's segment lengths;
* the gap rule is the reader's (a step of 4 median steps is no gap, counted as missing sample
  times; 6 is), segments at another rate are refused, the static check's windows stay inside
  the segments and report the log's own time.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from calib.input_rules import DataError
from calib.logs.reader import GAP_FACTOR
from calib.logs.static_log import check_static, log_segments, sample_rate_of
from calib.noise.allan import characterize_noise, octave_factors, pooled_adev
from calib.noise.allan_model import moments, pooled_moments, record_moments
from calib.noise.closure import twin_adev
from tests.cli import one_line_error, run, unwrap

SEED = 20260331
G0 = 9.80665


# ------------------------------------------------------------------ helpers written here
def hand_avar(pieces: list[np.ndarray], ms: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Pooled overlapping Allan variance, written apart from the package: per segment the
    m-sample means from a cumulative sum, their differences m apart, ``s_s = Σd²/(2c_s)``
    with ``c_s`` differences; pooled ``Σ c_s s_s / Σ c_s`` (segments without a difference at
    m left out). Returns (avar (k,), counts (k,))."""
    avar, counts = [], []
    for m in ms:
        num = den = 0.0
        for y in pieces:
            c = np.concatenate([[0.0], np.cumsum(y)])
            means = (c[m:] - c[:-m]) / m
            d = means[m:] - means[:-m]
            if d.size == 0:
                continue
            s_seg = float(np.sum(d ** 2)) / (2.0 * d.size)
            num += d.size * s_seg
            den += d.size
        avar.append(num / den)
        counts.append(den)
    return np.array(avar), np.array(counts)


def write_csv(path, acc_g: np.ndarray, t: np.ndarray):
    """A CSV in g (the issue's header) with times ``t`` s."""
    body = np.column_stack([t, acc_g])
    np.savetxt(path, body, delimiter=",", fmt=["%.4f", "%.7f", "%.7f", "%.7f"],
               header="time (s),ax (g),ay (g),az (g)", comments="")
    return path


def still_g(rng, n: int, sigma: float = 2e-3) -> np.ndarray:
    """(n, 3) readings of a still sensor in g: white noise ``sigma`` g, z reading 1 g."""
    acc = rng.normal(0.0, sigma, (n, 3))
    acc[:, 2] += 1.0
    return acc


# ------------------------------------------------------------------ one segment is one record
def test_one_segment_gives_todays_numbers():
    rng = np.random.default_rng(SEED)
    acc = rng.normal(0.0, 0.02, (6000, 2))
    base = characterize_noise(acc, 100.0)
    for segs in ([6000], [(0, 6000)]):
        other = characterize_noise(acc, 100.0, segments=segs)
        assert other.segments == base.segments == ((0, 6000),)
        for a, b in zip(base.axes, other.axes, strict=True):
            assert a.rule == b.rule and a.octaves == b.octaves and a.ms == b.ms
            for name in ("adev", "adev_ci", "edf", "model_adev", "theta", "cov"):
                np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=1e-12,
                                           atol=0.0)
            assert b.k_rise_steps == a.k_rise_steps and b.n_fit_segments == ()
            for ta, tb in zip(a.terms, b.terms, strict=True):
                assert ta.resolved == tb.resolved
                np.testing.assert_allclose(tb.interval, ta.interval, rtol=1e-12)
        assert other.summary() == base.summary()
    # the pooled code with one segment is that segment's own moments
    ms = octave_factors(6000, 100.0)
    own, pooled = moments(6000, ms), pooled_moments((6000,), ms)
    assert record_moments((6000,), ms) is own
    np.testing.assert_allclose(pooled.design, own.design, rtol=1e-14)
    np.testing.assert_allclose(pooled.tensor, own.tensor, rtol=1e-14)
    np.testing.assert_allclose(pooled.full(3)[1], own.full(3)[1], rtol=1e-12)


def test_the_result_round_trips_with_its_segments():
    rng = np.random.default_rng(SEED + 1)
    acc = rng.normal(0.0, 0.02, (5000, 1))
    res = characterize_noise(acc, 50.0, axes=("x",), segments=[2000, 3, 2997])
    d = res.to_dict()
    assert [(s["start"], s["stop"]) for s in d["segments"]] == [(0, 2000), (2000, 2003),
                                                                  (2003, 5000)]
    assert d["segments"][1]["octaves"] == 1 and d["units"]["segments.*.duration"].startswith("s")
    back = type(res).from_dict(json.loads(json.dumps(d)))
    assert back.segments == res.segments
    assert back.axes[0].n_fit_segments == (2000, 3, 2997) == res.axes[0].fit_lengths
    assert "3 segments" in " ".join(res.notes) or "of 3 segments" in " ".join(res.notes)


# ------------------------------------------------------------------ the pooled estimator
def test_pooled_avar_equals_a_hand_computation():
    rng = np.random.default_rng(SEED + 2)
    lengths = (3000, 1700, 900, 40, 1)
    y = np.cumsum(rng.normal(0.0, 1e-3, sum(lengths))) + rng.normal(0.0, 0.05, sum(lengths))
    res = characterize_noise(y[:, None], 50.0, axes=("x",), segments=list(lengths))
    fit = res.axes[0]
    bounds = np.concatenate([[0], np.cumsum(lengths)])
    pieces = [y[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
    assert fit.ms == octave_factors(3000, 50.0)  # the longest segment's grid
    want, counts = hand_avar(pieces, fit.ms)
    np.testing.assert_allclose(fit.adev ** 2, want, rtol=1e-10)
    _, adev, got_counts = pooled_adev(pieces, 50.0, fit.ms)
    np.testing.assert_allclose(got_counts, counts)
    np.testing.assert_allclose(adev ** 2, want, rtol=1e-10)
    # the 1-sample segment holds no octave: left out, said so
    assert fit.n_fit_segments == (3000, 1700, 900, 40)
    assert any("contribute nothing" in n for n in res.notes)


def test_pooled_moments_against_monte_carlo():
    """White noise (θ = 1 per sample) plus a random walk (θ = 0.02 per sample) in three
    independent segments of 90, 50 and 32 samples, octaves 1 … 16 (the 32-sample one holds
    one difference at m = 16, the grid's last octave): mean and variance of each octave's
    pooled Allan variance, R = 4000 draws."""
    rng = np.random.default_rng(SEED + 3)
    lengths, ms, r = (90, 50, 32), (1, 2, 4, 8, 16), 4000
    theta = np.array([1.0, 0.0, 0.02, 0.0])
    mom = pooled_moments(lengths, ms)
    draws = np.empty((r, len(ms)))
    for k in range(r):
        pieces = [rng.standard_normal(n) + np.cumsum(np.sqrt(theta[2]) * rng.standard_normal(n))
                  for n in lengths]
        draws[k] = hand_avar(pieces, ms)[0]
    mean = mom.design @ theta
    var = np.einsum("a,iiab,b->i", theta, mom.tensor, theta)
    se_mean = draws.std(axis=0, ddof=1) / np.sqrt(r)
    assert np.all(np.abs(draws.mean(axis=0) - mean) <= 5.0 * se_mean)
    dev2 = (draws - draws.mean(axis=0)) ** 2
    se_var = dev2.std(axis=0, ddof=1) / np.sqrt(r)
    assert np.all(np.abs(dev2.mean(axis=0) - var) <= 5.0 * se_var)
    # the Gauss–Markov means do not depend on the record's length (pooled_moments' docstring)
    short = moments(32, ms)
    np.testing.assert_allclose(short.gm_design, mom.gm_design[:short.gm_tc.size], rtol=1e-12)


@pytest.mark.parametrize("level", [0.683, 0.95])
def test_white_noise_density_interval_covers_the_truth_across_gaps(level):
    rng = np.random.default_rng(SEED + 4)
    lengths, rate, sigma, r = (2400, 1500, 900), 50.0, 0.05, 300
    truth = sigma / np.sqrt(rate)
    hits = 0
    for _ in range(r):
        y = rng.normal(0.0, sigma, (sum(lengths), 1))
        res = characterize_noise(y, rate, axes=("x",), segments=lengths, level=level)
        lo, hi = res.axes[0].term("white_noise_density").interval
        hits += lo <= truth <= hi
    assert abs(hits / r - level) <= 4.0 * np.sqrt(level * (1.0 - level) / r), hits / r


def test_no_segment_long_enough_is_refused_in_one_line():
    y = np.random.default_rng(SEED + 5).normal(0.0, 0.02, (1000, 2))
    t = np.arange(1000) / 100.0 + 1.0 * (np.arange(1000) // 50)
    with pytest.raises(DataError) as err:
        characterize_noise(y, 100.0, segments=[50] * 20, t=t)
    msg = str(err.value)
    assert "\n" not in msg and "the longest of 20" in msg and "t = 0 to 0.49 s" in msg
    assert "holds 4" in msg and "at least 64 samples" in msg


# ------------------------------------------------------------------ splitting the log
def test_the_gap_rule_is_the_readers():
    t = np.arange(1000) / 100.0
    four = np.concatenate([t[:500], t[500:] + 3 * 0.01])  # a step of 4 median steps
    split = log_segments(four, None, "a.csv")
    assert split.count == 1 and split.missing == 3 and not split.gaps
    assert sample_rate_of(four, None, "a.csv") == split.rate  # one record: no refusal
    six = np.concatenate([t[:500], t[500:] + (GAP_FACTOR) * 0.01])  # 6 median steps
    split = log_segments(six, None, "a.csv")
    assert split.count == 2 and split.bounds == ((0, 500), (500, 1000))
    assert split.gaps[0][0] == 499 and split.rate == 100.0
    with pytest.raises(DataError, match=r"a\.csv: gap of .* after t = 4\.99 s"):
        sample_rate_of(six, None, "a.csv")
    other = np.concatenate([t[:700], t[699] + 1.0 + np.arange(300) / 50.0])  # 50 Hz after
    with pytest.raises(DataError,
                       match=r"segment 2 of 2 .* sampled every 0\.02 s, the log every 0\.01 s"):
        log_segments(other, None, "a.csv")


def test_the_static_check_stays_inside_the_segments():
    rng = np.random.default_rng(SEED + 6)
    acc = rng.normal(0.0, 0.02, (2000, 2)) + [0.0, -9.8]
    t = np.arange(2000) / 100.0
    t[1000:] += 30.0
    bounds = ((0, 1000), (1000, 2000))
    info = check_static(acc, 100.0, "log.csv", segments=bounds, t=t)
    assert info["max_shift"] < 0.05
    moved = acc.copy()
    moved[1000:, 0] += 0.5  # the pose changed during the gap
    with pytest.raises(DataError, match=r"window at t = 40 s, axis x"):
        check_static(moved, 100.0, "log.csv", segments=bounds, t=t)
    # a level step of 0.2 m/s² at a gap inside the window of rows 1000–1099: that window,
    # laid across the gap, would read a variance ≈ 25× the others'; laid inside the segments,
    # none straddles it (the first segment's 50-row tail is left out) and the step is a
    # window shift below the 0.3 m/s² limit
    stepped = acc.copy()
    stepped[1050:, 0] += 0.2
    t2 = np.arange(2000) / 100.0
    t2[1050:] += 30.0
    with pytest.raises(DataError, match=r"variance is .* the median window's"):
        check_static(stepped, 100.0, "log.csv")
    info = check_static(stepped, 100.0, "log.csv", segments=((0, 1050), (1050, 2000)), t=t2)
    assert info["max_var_ratio"] < 3.0 and 0.15 < info["max_shift"] < 0.25


# ------------------------------------------------------------------ the command line
@pytest.fixture(scope="module")
def gap_csv(tmp_path_factory):
    """The issue's log: 3-axis still CSV in g, 100 Hz, 20000 rows, white noise 2e-3 g, t
    shifted by +50 s from row 10000 on."""
    rng = np.random.default_rng(SEED + 7)
    t = np.arange(20000) / 100.0
    t[10000:] += 50.0
    return write_csv(tmp_path_factory.mktemp("seg") / "gap.csv", still_g(rng, 20000), t)


def test_noise_splits_a_log_with_a_gap(gap_csv, capsys):
    rc, out, err = run(capsys, "noise", gap_csv, "--json")
    assert rc == 0, err
    notes = [ln for ln in unwrap(err).splitlines() if "segments between" in ln]
    assert notes == [f"note: {gap_csv}: 2 segments between 1 gap(s) (the first 50.01 s after "
                     "t = 99.99 s); the Allan variance pooled over them, segments as "
                     "independent records"]
    doc = json.loads(out)
    assert [(s["start"], s["stop"], s["n"]) for s in doc["segments"]] == [
        (0, 10000, 10000), (10000, 20000, 10000)]
    assert doc["n"] == 20000 and doc["duration"] == 200.0 and doc["sample_rate"] == 100.0
    assert doc["axes"]["x"]["n_fit_segments"] == [10000, 10000]
    truth = 2e-3 * G0 / np.sqrt(100.0)
    for axis in ("x", "y", "z"):
        n_term = doc["axes"][axis]["terms"]["white_noise_density"]
        assert n_term["resolved"] and abs(n_term["value"] / truth - 1.0) < 0.05
    rc, out, _ = run(capsys, "noise", gap_csv)
    assert rc == 0 and "segments: 2 stretches between gaps in time, 10000 + 10000" in unwrap(out)


def test_noise_twin_uses_the_segment_lengths(gap_csv, capsys):
    rc, out, err = run(capsys, "noise", gap_csv, "--twin", "--json", "--seed", "4")
    assert rc == 0, err
    doc = json.loads(out)
    for axis, c in doc["twin"].items():
        k = len(doc["axes"][axis]["taus"])
        assert c["dof"] == k and len(c["twin_adev"]) == k and np.all(np.isfinite(c["z"]))
        assert c["p"] > 1e-3  # a true twin of white noise
    # the twin's pieces must have the log's segment lengths
    from calib.noise.allan import AxisNoise

    fit = AxisNoise.from_dict(doc["axes"]["x"])
    rng = np.random.default_rng(0)
    with pytest.raises(DataError, match="segment lengths"):
        twin_adev(fit, [rng.standard_normal(12000), rng.standard_normal(8000)], 100.0)
    assert twin_adev(fit, [rng.standard_normal(10000), rng.standard_normal(10000)],
                     100.0).size == len(fit.ms)


def test_noise_refuses_a_log_whose_segments_are_all_short(tmp_path, capsys):
    rng = np.random.default_rng(SEED + 8)
    t = np.arange(1000) / 100.0 + 1.0 * (np.arange(1000) // 50)  # a 1 s gap every 50 rows
    path = write_csv(tmp_path / "short.csv", still_g(rng, 1000), t)
    line = one_line_error(capsys, "noise", path, "--json")
    assert "no segment between the gaps holds the 5 octave" in line
    assert "the longest of 20 (t = 0 to 0.49 s, 50 samples" in line


def test_other_commands_still_refuse_a_gap_and_say_noise_splits(gap_csv, capsys):
    line = one_line_error(capsys, "import", gap_csv, "--out", gap_csv.parent / "imp")
    assert "--allow-gaps" in line and "`noise` use the stretches between gaps" in line
    assert "unbroken" not in line

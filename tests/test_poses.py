"""calib.logs.poses.detect_poses on simulated multi-pose logs with known boundaries (numpy + noise,
fixed seeds): the right number of poses, each inside its true hold and covering it but for
the window's reach into the turns, moving samples labelled -1, thresholds from the data."""

from __future__ import annotations

import json

import numpy as np
import pytest

from calib.logs.poses import MARGIN, PoseDetection, detect_poses, window_variance

G = 9.8


def multipose(seed: int, holds=(400, 250, 600, 300, 500, 350), turn: int = 120,
              sigma: float = 0.03, fs: float = 100.0, gyro_sigma: float | None = None):
    """Holds of the given lengths at random angles, smooth (cosine) turns between them."""
    rng = np.random.default_rng(seed)
    angles = np.cumsum(rng.uniform(0.4, 1.6, len(holds)) * rng.choice([-1, 1], len(holds)))
    theta, bounds = [], []
    for k, n in enumerate(holds):
        bounds.append((len(theta), len(theta) + n))
        theta += [angles[k]] * n
        if k + 1 < len(holds):
            s = 0.5 - 0.5 * np.cos(np.linspace(0, np.pi, turn + 2)[1:-1])
            theta += list(angles[k] + s * (angles[k + 1] - angles[k]))
    theta = np.array(theta)
    t = np.arange(theta.size) / fs
    acc = np.c_[-G * np.sin(theta), -G * np.cos(theta)] + sigma * rng.standard_normal(
        (theta.size, 2))
    gyro = None
    if gyro_sigma is not None:
        gyro = np.gradient(theta, t) + 0.01 + gyro_sigma * rng.standard_normal(theta.size)
    return t, acc, gyro, bounds


def _check_segments(det: PoseDetection, bounds, reach: int) -> None:
    assert det.count == len(bounds)
    for seg, (a, b) in zip(det.segments, bounds, strict=True):
        held = np.flatnonzero(det.labels == det.segments.index(seg))
        assert held.min() >= a and held.max() < b  # never a turning sample
        assert held.size >= (b - a) - 2 * reach  # the hold, less the window's reach each side
    turning = np.ones(det.labels.size, bool)
    for a, b in bounds:
        turning[a:b] = False
    assert np.all(det.labels[turning] == -1)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_finds_the_holds_with_times(seed):
    t, acc, _, bounds = multipose(seed)
    det = detect_poses(acc, t)
    assert det.window == 50 and det.min_samples == 100  # 0.5 s and 1 s at 100 Hz
    _check_segments(det, bounds, reach=det.window)
    for seg, (a, b) in zip(det.segments, bounds, strict=True):
        assert seg.t_start >= t[a] and seg.t_stop <= t[b - 1]
        assert np.all(np.abs(seg.mean - acc[a:b].mean(0)) < 5 * 0.03 / np.sqrt(seg.n) + 0.01)


def test_finds_the_holds_with_a_gyro_and_without_times():
    t, acc, gyro, bounds = multipose(7, gyro_sigma=0.005)
    det = detect_poses(acc, t, gyro)
    assert det.gyro_threshold is not None and det.gyro_threshold > det.gyro_quiet_level
    _check_segments(det, bounds, reach=det.window)
    det = detect_poses(acc, None, window=40, min_hold=150)
    assert det.window == 40 and det.min_samples == 150
    _check_segments(det, bounds, reach=det.window)
    assert det.segments[0].t_start is None


def test_a_short_hold_is_not_a_pose():
    t, acc, _, bounds = multipose(3, holds=(400, 60, 400))
    det = detect_poses(acc, t)
    assert det.count == 2  # the 0.6 s hold is below the 1 s minimum
    assert det.segments[0].stop <= bounds[0][1] and det.segments[1].start >= bounds[2][0]


def test_a_bump_while_holding_stays_one_pose():
    rng = np.random.default_rng(4)
    acc = np.c_[np.zeros(2000), -G * np.ones(2000)] + 0.02 * rng.standard_normal((2000, 2))
    acc[1000:1010] += 0.5  # a knock: moving for a moment, same pose after
    det = detect_poses(acc, np.arange(2000) / 100.0)
    assert det.count == 1
    assert np.all(det.labels[1000:1010] == -1) and det.segments[0].n < 2000


def test_static_white_noise_is_held_almost_everywhere():
    """A static log: the threshold is MARGIN × the static 99.9 % point, so a window exceeds
    it with probability far below 0.1 %; allow 1 % of samples for the ends' short windows."""
    rng = np.random.default_rng(11)
    acc = np.c_[np.full(20000, 3.0), np.full(20000, -9.0)] + 0.05 * rng.standard_normal(
        (20000, 2))
    det = detect_poses(acc, np.arange(20000) / 200.0)
    assert det.count == 1 and np.mean(det.labels == 0) > 0.99
    # the quiet level is the 10th percentile of var_x + var_y: about 2σ² (χ² quantile < 1)
    assert 0.5 * 2 * 0.05**2 < det.quiet_level < 2 * 0.05**2
    assert det.threshold > MARGIN * det.quiet_level


def test_a_quantized_sensor_gets_a_threshold_above_zero():
    """Noise below one step: the held poses read one constant value each; the quantization
    floor Δ²/12 keeps the threshold positive, so the poses are found."""
    q = 0.0383  # m/s² per count
    t, acc, _, bounds = multipose(5, sigma=0.001)
    det = detect_poses(np.round(acc / q) * q, t)
    assert det.quiet_level >= 2 * q**2 / 12 * (1 - 1e-12)
    _check_segments(det, bounds, reach=det.window)


def test_window_variance_matches_numpy():
    x = np.random.default_rng(0).standard_normal(300) + 1e3
    v = window_variance(x, 21)
    for i in (0, 5, 10, 150, 289, 299):
        lo, hi = max(0, i - 10), min(300, i + 11)
        assert abs(v[i] - np.var(x[lo:hi], ddof=1)) < 1e-9


def test_round_trip_and_summary():
    t, acc, _, _ = multipose(1)
    det = detect_poses(acc, t)
    back = PoseDetection.from_dict(json.loads(json.dumps(det.to_dict())))
    assert back == det and back.to_dict() == det.to_dict()
    text = det.summary()
    assert f"{det.count} held pose(s)" in text and "10th percentile" in text
    assert f"{det.threshold:.3g}" in text


def test_poses_of_different_noise_are_each_found_and_trimmed_at_their_own_level():
    """A hand-held pose 5× noisier in variance than the others (seen on a real YEI log) is
    still a hold, and each pose's own threshold scales with its noise."""
    t, acc, _, bounds = multipose(12, holds=(400, 400, 400, 400))
    rng = np.random.default_rng(13)
    a, b = bounds[2]
    acc[a:b] += 0.03 * 2.0 * rng.standard_normal((b - a, 2))  # σ² × (1 + 4)
    det = detect_poses(acc, t)
    _check_segments(det, bounds, reach=det.window)
    quiet = [s.threshold for k, s in enumerate(det.segments) if k != 2]
    assert det.segments[2].threshold > 3 * max(quiet)  # its own level, ≈ 5× (χ² spread)
    assert all(s.threshold <= det.threshold for s in det.segments)


def test_a_turn_that_moves_only_the_normal_axis_is_not_a_hold():
    """A 3-axis log on face +y turned about x in 3 s: y reads g·cos α (second order in α), z
    reads g·sin α (first order). Watching x, y alone the first 0.4 s of the turn read as held
    (they would bias the hold's mean); with the normal axis watched (``more_acc``) the hold
    ends within half a window of the turn's start, and the faces +y, +z stay two poses."""
    rng = np.random.default_rng(0)
    g = 9.81
    alpha = np.linspace(0, np.pi / 2, 300)  # +y up → +z up about x
    acc = np.vstack([np.tile([0.0, g, 0.0], (300, 1)),
                     np.column_stack([np.zeros(300), g * np.cos(alpha), g * np.sin(alpha)]),
                     np.tile([0.0, 0.0, g], (300, 1))])
    acc += rng.normal(0, 0.03, acc.shape)
    t = np.arange(acc.shape[0]) / 100.0
    plane = detect_poses(acc[:, :2], t, window=0.25, min_hold=1.0)
    both = detect_poses(acc[:, :2], t, window=0.25, min_hold=1.0, more_acc=acc[:, 2])
    assert both.axes_watched == 3 and "var_n" in both.thresholds_line()
    assert both.count == 2 and plane.count == 2
    assert both.segments[0].stop <= 300  # the turn starts at sample 300
    assert plane.segments[0].stop >= 330


def _exported_still(seed: int, n: int = 36000, fs: float = 10.0):
    """A phone-like export of a sensor lying still (made here, not by the bench): white noise
    through a 4-pole Butterworth at 0.3 Hz, then decimated by repeating readings — stretches of
    2–25 samples hold a value that drifts by 1e-6 m/s² a step, as the real Galaxy S5 export
    does (data/real/README.md)."""
    from scipy import signal

    rng = np.random.default_rng(seed)
    b, a = signal.butter(4, 0.3, fs=fs)
    raw = np.c_[0.01 + 0.03 * rng.standard_normal(n), 0.2 + 0.03 * rng.standard_normal(n),
                9.9 + 0.05 * rng.standard_normal(n)]
    acc = signal.filtfilt(b, a, raw, axis=0)
    k = 0
    while k < n:
        run = int(rng.integers(2, 26))
        if rng.random() < 0.3:  # a held stretch
            stop = min(n, k + run)
            acc[k:stop] = acc[k] + 1e-6 * np.arange(stop - k)[:, None]
        k += run
    t = np.arange(n) / fs
    gyro = 0.02 + 0.001 * rng.standard_normal((n, 3))
    return t, acc, gyro


@pytest.mark.parametrize("seed", [0, 1])
def test_an_export_still_throughout_is_one_pose(seed):
    """Its held stretches are far quieter than its noise: without the static check of the
    whole log the two stages cut it into many "holds" (the Galaxy S5 log: 1942)."""
    t, acc, gyro = _exported_still(seed)
    det = detect_poses(acc[:, :2], t, gyro, more_acc=acc[:, 2])
    assert det.still and det.count == 1 and np.all(det.labels == 0)
    seg = det.segments[0]
    assert (seg.start, seg.stop, seg.n) == (0, t.size, t.size)
    assert np.allclose(seg.mean, acc[:, :2].mean(0)) and np.allclose(seg.std, acc[:, :2].std(0,
                                                                                      ddof=1))
    assert "the whole log is still" in det.thresholds_line()
    back = PoseDetection.from_dict(json.loads(json.dumps(det.to_dict())))
    assert back.still and back.to_dict() == det.to_dict()


def test_an_export_with_two_poses_two_degrees_apart_is_not_one():
    """The static check allows 0.3 m/s² (≈ 1.75°) between window means: two holds 2° apart
    are not still throughout, and the stages look for holds."""
    t, acc, gyro = _exported_still(3)
    half = t.size // 2
    tilt = np.radians(2.0)
    acc[half:, 0] += 9.9 * np.sin(tilt)  # x reads the 2° tilt: 0.35 m/s²
    det = detect_poses(acc[:, :2], t, gyro, more_acc=acc[:, 2])
    assert not det.still


def test_a_still_log_is_not_told_to_shorten_the_windows():
    """One hold because the sensor never moved: the hint says so instead of suggesting
    shorter windows (which would find nothing more)."""
    t, acc, gyro = _exported_still(4)
    det = detect_poses(acc[:, :2], t, gyro, more_acc=acc[:, 2])
    hint = det.few_poses_hint(10.0)
    assert det.still and "whole log is still" in hint and "--static-window" not in hint

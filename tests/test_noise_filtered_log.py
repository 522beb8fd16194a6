"""A low-pass filtered static log (a digital filter below Nyquist, a decimated export such as a
10 Hz phone log) is still a static log (issue 31: no valid log refused; issue 32: a real long
log through ``noise --twin``).

Its readings are made here with scipy.signal (white noise through a 4-pole Butterworth
low-pass at 0.3 Hz, sampled at 10 Hz: a correlation time of about a second), not by the
bench:

* the static check lays windows of ``WINDOW_CORR`` correlation times and accepts it with the
  default options, while a white log keeps its 1-s windows and a burst in the filtered log is
  still refused (:func:`calib.logs.static_log.correlation_time`);
* ``noise --twin`` reads the export's filter (:mod:`calib.noise.shaping`), fits the whole
  octave grid with it and its twin, filtered alike, closes (tests/test_shaping.py measures
  the closure's size and power on filtered logs).
"""

from __future__ import annotations

import json

import numpy as np
from scipy import signal

from calib.logs.static_log import WINDOW_CORR, check_static, correlation_time
from tests.cli import one_line_error, run

RATE = 10.0


def filtered(n: int, seed: int) -> np.ndarray:
    """(n, 3) m/s²: a still sensor (z reads 9.8) whose noise went through a 4-pole Butterworth
    low-pass at 0.3 Hz, 2.5 mm/s² std."""
    rng = np.random.default_rng(seed)
    b, a = signal.butter(4, 0.3, fs=RATE)
    w = rng.standard_normal((n + 2000, 3))
    y = signal.lfilter(b, a, w, axis=0)[2000:]
    y *= 2.5e-3 / y.std(axis=0)
    return y + np.array([0.05, -0.03, 9.8])


def write(path, acc: np.ndarray):
    t = np.arange(acc.shape[0]) / RATE
    np.savetxt(path, np.column_stack([t, acc]), delimiter=",", fmt="%.8g",
               header="t (s),ax (m/s^2),ay (m/s^2),az (m/s^2)", comments="")
    return path


def test_the_correlation_time_of_white_and_filtered_noise():
    white = np.random.default_rng(1).standard_normal((20000, 3))
    assert correlation_time(white) == 1
    lag = correlation_time(filtered(20000, 2))
    assert 0.5 * RATE <= lag <= 2.0 * RATE  # about a second at 10 Hz


def test_a_filtered_still_log_passes_the_static_check_in_longer_windows():
    acc = filtered(30000, 3)
    info = check_static(acc, RATE, "f.csv")
    assert info["window"] >= WINDOW_CORR * info["correlation_time"] - 1.0 / RATE
    assert info["window"] > 5.0 and info["max_var_ratio"] < info["var_ratio"]
    white = np.random.default_rng(4).normal(0.0, 2.5e-3, (30000, 3)) + [0.0, 0.0, 9.8]
    assert check_static(white, RATE, "w.csv")["window"] == 1.0  # a white log: as asked


def test_a_burst_in_a_filtered_log_is_still_refused(tmp_path, capsys):
    acc = filtered(30000, 5)
    acc[12000:12300] += np.random.default_rng(6).normal(0.0, 0.03, (300, 3))  # 30 s shaken
    line = one_line_error(capsys, "noise", write(tmp_path / "burst.csv", acc))
    assert "not a static log" in line and "variance is" in line


def test_noise_twin_on_a_filtered_log_follows_the_filter(tmp_path, capsys):
    path = write(tmp_path / "lp.csv", filtered(30000, 8))
    rc, out, err = run(capsys, "noise", path, "--twin", "--json")
    assert rc == 0, err
    doc = json.loads(out)
    x = doc["axes"]["x"]
    assert x["export_filter"] is not None  # the export's filter is read and modelled
    assert x["fit_range"][0] <= 0.4  # so the filter's octaves are described
    twin = doc["twin"]["x"]
    assert not twin["reject"]  # (a true twin: rejected with probability ≤ α)
    rc, out, err = run(capsys, "noise", path, "--twin")
    assert rc == 0
    said = " ".join(out.split())
    assert "shaped by the export's low-pass filter" in said
    assert "correlation times of" in said  # the static check says why its windows are long


def test_the_read_note_names_every_gyro_axis(tmp_path, capsys):
    """A log with three gyro columns: the one-line read note names all three (noise
    characterizes each) and which one is about the tilt axis."""
    rng = np.random.default_rng(8)
    acc = rng.normal(0.0, 2e-3, (3000, 3)) + [0.0, 0.0, 9.8]
    gyro = rng.normal(0.0, 1e-3, (3000, 3))
    t = np.arange(3000) / RATE
    path = tmp_path / "g.csv"
    np.savetxt(path, np.column_stack([t, acc, gyro]), delimiter=",", fmt="%.8g", comments="",
               header="t (s),ax (m/s^2),ay (m/s^2),az (m/s^2),gx (rad/s),gy (rad/s),gz (rad/s)")
    rc, out, err = run(capsys, "noise", path)
    assert rc == 0, err
    note = " ".join(err.split())
    assert "gyro gx (rad/s), gy (rad/s), gz (rad/s) (about the tilt axis: gz (rad/s))" in note
    assert "axis gyro_x" in " ".join(out.split())

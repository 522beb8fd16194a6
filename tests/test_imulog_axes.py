"""The log record's three accelerometer and three gyro axes in the sensor frame
(``ImuLog.acc_s``, ``ImuLog.gyro_s``): the log's own columns in SI whatever ``--axes`` picks
for the tilt plane, cut with the rest when only held samples are kept."""

from __future__ import annotations

import numpy as np
import pytest

from calib.logs.reader import ImuLog, LogOptions, read_log
from tests.reference.real_data import REAL_DIR

G_UNIT = 9.80665


def _write(path, rows, header):
    path.write_text(header + "\n" + "".join(",".join(f"{v:.9g}" for v in r) + "\n"
                                            for r in rows))
    return path


@pytest.fixture
def log_csv(tmp_path):
    """Two held faces (z up, x up), 300 samples each, accelerations in g, gyro in deg/s."""
    rng = np.random.default_rng(3)
    n = 300
    acc = np.vstack([np.tile([0.01, -0.02, 1.0], (n, 1)), np.tile([1.0, 0.03, 0.02], (n, 1))])
    acc += rng.standard_normal(acc.shape) * 1e-3
    gyro = rng.standard_normal(acc.shape) * 0.05
    t = np.arange(2 * n) * 0.01
    rows = np.column_stack([t, acc, gyro])
    return _write(tmp_path / "two.csv", rows,
                  "t (s),acc_x (g),acc_y (g),acc_z (g),gyro_x (deg/s),gyro_y (deg/s),"
                  "gyro_z (deg/s)"), rows


@pytest.mark.parametrize("axes", [("x", "y"), ("-y", "z"), ("z", "-x")])
def test_sensor_frame_axes_do_not_follow_the_tilt_plane_mapping(log_csv, axes):
    path, rows = log_csv
    log = read_log(path, LogOptions(axes=axes, detect=False))
    assert log.acc_s.shape == (rows.shape[0], 3) and log.gyro_s.shape == (rows.shape[0], 3)
    assert np.allclose(log.acc_s, rows[:, 1:4] * G_UNIT, rtol=1e-8, atol=0)  # 9 digits
    assert np.allclose(log.gyro_s, np.radians(rows[:, 4:7]), rtol=1e-8, atol=0)
    # the tilt-plane view is a signed pick of the same columns
    k = "xyz".index(axes[0].lstrip("-"))
    sign = -1.0 if axes[0].startswith("-") else 1.0
    assert np.array_equal(log.acc[:, 0], sign * log.acc_s[:, k])
    assert log.provenance["units"]["gyro"] == "deg/s"
    assert "(3-axis accel)" in repr(log) and "gyro x, y, z" in repr(log)


def test_held_samples_only_cuts_every_axis_alike(log_csv):
    path, _ = log_csv
    full = read_log(path, LogOptions())
    assert full.pose is not None and full.pose.max() == 1
    held = read_log(path, LogOptions(poses=(0.0, 1.0), angle_unit="rad",
                                     axes=("x", "z")))
    keep = full.pose >= 0
    assert held.n == int(keep.sum())
    assert np.array_equal(held.acc_s, full.acc_s[keep])
    assert np.array_equal(held.gyro_s, full.gyro_s[keep])


def test_two_axis_logs_and_unstated_gyro_units_leave_them_none(tmp_path):
    rng = np.random.default_rng(4)
    rows = np.column_stack([np.arange(50) * 0.01, np.full(50, 0.1), np.full(50, 9.7),
                            np.full(50, 0.01), np.full(50, 0.02), np.full(50, 0.03)])
    rows[:, 1:] += rng.standard_normal((50, 5)) * 1e-3
    path = _write(tmp_path / "xy.csv", rows[:, :3], "t (s),ax (m/s2),ay (m/s2)")
    log = read_log(path, LogOptions(detect=False))
    assert log.acc_s is None and log.gyro_s is None
    path = _write(tmp_path / "nogyrounit.csv", np.column_stack([rows[:, :3], rows[:, 1],
                                                                rows[:, 3:]]),
                  "t (s),ax (m/s2),ay (m/s2),az (m/s2),gx,gy,gz")
    log = read_log(path, LogOptions(detect=False))
    assert log.acc_s is not None and log.gyro_s is None
    assert "gyro none" in repr(log)


def test_real_logs_carry_three_axes():
    yei = read_log(REAL_DIR / "yei-3space-z-flip.csv", LogOptions(units="g",
                                                                  gyro_unit="rad/s"))
    assert yei.acc_s.shape == (yei.n, 3) and yei.gyro_s.shape == (yei.n, 3)
    # every detected pose has z along the vertical (z up or down): |a| ≈ 1 g, mostly on z
    for k in range(int(yei.pose.max()) + 1):
        mean = yei.acc_s[yei.pose == k].mean(axis=0)
        assert abs(np.linalg.norm(mean) / G_UNIT - 1) < 0.05 and abs(mean[2]) > 0.95 * G_UNIT


def test_arrays_are_read_only():
    log = ImuLog(acc=np.zeros((3, 2)), acc_s=np.zeros((3, 3)), gyro_s=np.ones((3, 3)))
    with pytest.raises(ValueError):
        log.acc_s[0, 0] = 1.0
    assert "1 pose," in repr(ImuLog(acc=np.zeros((3, 2)), pose=np.array([0, 0, -1])))

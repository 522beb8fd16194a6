"""A still sensor reads 1 g (:mod:`calib.logs.physics`): unit mistakes are refused with the
likely unit named, in every command that reads a measured log, and logs that are right — or
that cannot tell (two axes out of the gravity plane, a vehicle run) — are not."""

from __future__ import annotations

import numpy as np
import pytest

from calib.input_rules import DataError
from calib.logs.reader import LogOptions, read_log
from tests.cli import one_line_error

G_UNIT = 9.80665


def _tilt_log(path, unit: str, scale: float, *, axes3: bool = False):
    """Eight held θ around the turn (course signs) with θ in degrees, written in ``unit``
    after multiplying the m/s² readings by ``scale``."""
    rng = np.random.default_rng(1)
    a = np.deg2rad(np.repeat(np.arange(0, 360, 45), 200))
    x = -9.8 * np.sin(a) + 0.05 + 0.02 * rng.standard_normal(a.size)
    y = -9.8 * np.cos(a) - 0.03 + 0.02 * rng.standard_normal(a.size)
    cols = [np.arange(a.size) / 100, np.rad2deg(a), scale * x, scale * y]
    head = f"t (s),theta (deg),ax ({unit}),ay ({unit})"
    if axes3:
        cols.append(scale * (0.02 * rng.standard_normal(a.size)))
        head += f",az ({unit})"
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=head, comments="",
               fmt="%.8g")
    return path


@pytest.mark.parametrize("unit, scale, words", [
    ("m/s^2", 1 / G_UNIT, "look like g"),           # g under an m/s² header
    ("g", 1.0, "m/s² read as g"),                   # m/s² under a g header
    ("g", 1000 / G_UNIT, "mg read as g"),           # mg under a g header
])
def test_calibrate_refuses_a_log_in_the_wrong_unit(capsys, tmp_path, unit, scale, words):
    path = _tilt_log(tmp_path / "log.csv", unit, scale)
    msg = one_line_error(capsys, "calibrate", path, ignore=("note:",))
    assert "a still sensor reads 1 g" in msg and words in msg and "log.csv" in msg


def test_import_refuses_and_writes_nothing(capsys, tmp_path):
    path = _tilt_log(tmp_path / "log.csv", "m/s^2", 1 / G_UNIT)
    msg = one_line_error(capsys, "import", path, "--out", tmp_path / "out",
                         ignore=("note:",))
    assert "look like g" in msg
    assert not (tmp_path / "out").exists()


def test_counts_with_the_wrong_sensitivity_name_the_counts_per_g(tmp_path):
    path = tmp_path / "c.csv"
    _tilt_log(path, "counts", 4096 / G_UNIT, axes3=True)  # 4096 counts per g
    with pytest.raises(DataError, match=r"give 4\d\d\d counts per g, not 256"):
        read_log(path, LogOptions(sensitivity=256.0), expect="ensayo")
    log = read_log(path, LogOptions(sensitivity=4096.0), expect="ensayo")
    assert abs(np.median(np.hypot(log.acc[:, 0], log.acc[:, 1])) - 9.8) < 0.1


def test_right_units_and_undecidable_logs_pass(tmp_path):
    read_log(_tilt_log(tmp_path / "ok.csv", "m/s^2", 1.0), expect="ensayo")
    read_log(_tilt_log(tmp_path / "okg.csv", "g", 1 / G_UNIT, axes3=True), expect="ensayo")
    # a board lying flat, x and y only: ≈ 0 on both is physical (gravity is out of the
    # plane) for a noise log; only a tilt-plane calibration needs gravity in the plane
    flat = tmp_path / "flat.csv"
    rng = np.random.default_rng(2)
    np.savetxt(flat, np.c_[np.arange(500) / 100, 0.01 * rng.standard_normal((500, 2))],
               delimiter=",", header="t (s),ax (m/s^2),ay (m/s^2)", comments="")
    read_log(flat)
    with pytest.raises(DataError, match="a still sensor reads 1 g"):
        read_log(flat, expect="ensayo")
    read_log(flat, expect="acel")  # a vehicle run: its readings are its motion

"""A Sensor Logger export is recognized from its content, under any file name: the header
(``seconds_elapsed`` and bare ``x y z``) says it is Sensor Logger, the median magnitude says
which export (with gravity, gravity removed, in g)."""

from __future__ import annotations

import numpy as np
import pytest

from calib.logs.reader import LogOptions, read_log
from tests.cli import one_line_error


def _export(path, scale, rng):
    n = 600
    u = np.repeat([[0, 0, 1], [1, 0, 0]], n // 2, axis=0).astype(float)
    acc = scale * u + rng.normal(0, 0.01 * max(scale, 0.1), (n, 3))
    t0 = 1_700_000_000_000_000_000
    rows = [f"{t0 + k * 10_000_000},{k * 0.01:.2f},{z:.5f},{y:.5f},{x:.5f}"
            for k, (x, y, z) in enumerate(acc)]
    path.write_text("time,seconds_elapsed,z,y,x\n" + "\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("name", ["my walk - TotalAcceleration (2).csv", "session7.csv",
                                  "phone.csv"])
def test_any_name_with_gravity_reads_in_m_s2(tmp_path, name):
    path = _export(tmp_path / name, 9.81, np.random.default_rng(1))
    log = read_log(path, LogOptions())
    assert log.provenance["format"] == "sensorlogger"
    assert log.provenance["units"]["acc"] == "m/s2"
    assert "with gravity" in log.provenance["reader"]["units_from_content"]
    assert log.pose.max() == 1


def test_gravity_removed_and_g_exports_are_refused_by_content(capsys, tmp_path):
    removed = _export(tmp_path / "renamed.csv", 0.0, np.random.default_rng(2))
    msg = one_line_error(capsys, "calibrate", removed)
    assert "gravity was removed" in msg and "TotalAcceleration" in msg
    in_g = _export(tmp_path / "uncal.csv", 1.0, np.random.default_rng(3))
    msg = one_line_error(capsys, "calibrate", in_g)
    assert "--units g" in msg
    log = read_log(in_g, LogOptions(units="g"))  # and with the unit stated it reads
    assert log.provenance["units"]["acc"] == "g"

"""phyphox's "CSV (zip)" export read directly (:mod:`calib.logs.ziplog`): the member with the
readings is found, read by the CSV reader, named in messages and in the provenance."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from calib.input_rules import DataError
from calib.logs.reader import LogOptions, read_log
from tests.cli import one_line_error, run

HEADER = '"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)"'


def _phyphox_csv(rng, faces=((0, 0, 1), (1, 0, 0), (0, -1, 0), (0, 0, -1)), n=400):
    """A phone held still in a few orientations, 100 Hz, 1 s moves between holds."""
    rows, t = [], 0.0
    prev = np.array(faces[0], float)
    for f in faces:
        u = np.array(f, float)
        for k in range(100):  # move
            v = prev + (u - prev) * (k + 1) / 100
            rows.append((t, *(9.81 * v / max(np.linalg.norm(v), 1e-9)
                              + rng.normal(0, 0.3, 3))))
            t += 0.01
        for _ in range(n):
            rows.append((t, *(9.81 * u + 0.05 + rng.normal(0, 0.02, 3))))
            t += 0.01
        prev = u
    return HEADER + "\n" + "".join(
        f"{r[0]:.6E},{r[1]:.6E},{r[2]:.6E},{r[3]:.6E}\n" for r in rows)


def _zip(path, members):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for name, text in members.items():
            z.writestr(name, text)
    return path


@pytest.fixture
def export(tmp_path):
    rng = np.random.default_rng(1)
    return _zip(tmp_path / "Acceleration with g 2026-11-29 10-00-00.zip", {
        "Accelerometer.csv": _phyphox_csv(rng),
        "meta/device.csv": '"property","value"\n"deviceModel","Pixel"\n',
        "meta/time.csv": '"event","experiment time"\n"START",0.0\n'})


def test_the_zip_reads_as_its_member(export):
    log = read_log(export, LogOptions())
    assert log.provenance["format"] == "phyphox"
    assert log.provenance["reader"]["zip_member"] == "Accelerometer.csv"
    assert log.provenance["source"]["name"] == export.name  # the zip, with its sha256
    assert log.acc_s.shape[1] == 3 and log.pose.max() + 1 == 4


def test_calibrate_and_import_take_the_zip_in_one_command(capsys, export, tmp_path):
    rc, out, err = run(capsys, "calibrate", export, "--json")
    assert rc == 0, err
    assert json.loads(out)["method"] in ("multiposition", "six-face")
    rc, out, err = run(capsys, "import", export, "--out", tmp_path / "set", "--json")
    assert rc == 0, err
    assert json.loads(out)["provenance"]["reader"]["zip_member"] == "Accelerometer.csv"


def test_messages_name_the_member_and_its_line(tmp_path):
    text = _phyphox_csv(np.random.default_rng(2)).splitlines()
    text[40] = text[40].replace("E", "x", 1)  # a cell that is not a number
    path = _zip(tmp_path / "bad.zip", {"Accelerometer.csv": "\n".join(text) + "\n"})
    with pytest.raises(DataError) as exc:
        read_log(path, LogOptions())
    assert f"{path}:Accelerometer.csv" in str(exc.value) and "line 41" in str(exc.value)
    assert "tiltbench-zip-" not in str(exc.value)


def test_ambiguous_and_empty_zips_are_refused_in_one_line(capsys, tmp_path):
    rng = np.random.default_rng(3)
    two = _zip(tmp_path / "two.zip", {"a.csv": _phyphox_csv(rng), "b.csv": _phyphox_csv(rng)})
    msg = one_line_error(capsys, "calibrate", two)
    assert "2 CSV members (a.csv, b.csv)" in msg and "unzip" in msg
    none = _zip(tmp_path / "meta.zip", {"meta/device.csv": "a,b\n1,2\n"})
    assert "no CSV member" in one_line_error(capsys, "calibrate", none)
    broken = tmp_path / "broken.zip"
    broken.write_bytes(b"PK\x03\x04" + b"\0" * 40)
    assert "not a readable zip" in one_line_error(capsys, "calibrate", broken)

"""``tiltbench apply LOG --calibration cal.json --out corrected.csv`` (issue 30 item 4): the
corrected CSV holds exactly the calibration's correction of the log's readings (read back
from the file), for a six-face and a tilt-plane file, in ``.json`` and ``.mat``; a file whose
axes or unit differ from the log's is refused in one line and nothing is written; an
existing output needs ``--force``; the CSV reads back as a log.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from calib.calibration.calfile import load_calibration_file
from calib.calibration.correct import correct
from calib.calibration.corrected_log import EQUATIONS
from calib.logs.reader import LogOptions, read_log
from calib.units import missing_units
from tests.cli import one_line_error, run
from tests.test_calfile_v3 import write_yz_log
from tests.test_sixface_cli import write_six_face_log


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """A six-face log (m/s² and the same in g) and a y,z tilt-plane sweep, each calibrated
    with --save (six-face: .json and .mat)."""
    from bench.cli import main

    d = tmp_path_factory.mktemp("apply")
    write_six_face_log(d / "six.csv")
    write_six_face_log(d / "six_g.csv", unit="g")
    write_yz_log(d / "yz.csv")
    for argv in (["calibrate", d / "six.csv", "--latitude", 45, "--save", d / "six.json"],
                 ["calibrate", d / "six.csv", "--latitude", 45, "--save", d / "six.mat"],
                 ["calibrate", d / "yz.csv", "--axes", "y,z", "--noise-var", "0.0025,0.0025",
                  "--save", d / "yz.json"]):
        assert main([str(a) for a in argv]) == 0
    return d


def _read_back(path) -> tuple[list[str], list[str], np.ndarray]:
    """(comment lines, header cells, numbers) of a corrected CSV."""
    lines = path.read_text(encoding="utf-8").splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    rest = [ln for ln in lines if not ln.startswith("#")]
    rows = np.array([[float(v) for v in ln.split(",")] for ln in rest[1:]])
    return comments, rest[0].split(","), rows


@pytest.mark.parametrize("cal", ["six.json", "six.mat"])
def test_six_face_correction_is_written_exactly(capsys, logs, tmp_path, cal):
    out = tmp_path / "corrected.csv"
    rc, text, err = run(capsys, "apply", logs / "six.csv", "--calibration", logs / cal,
                        "--out", out)
    assert rc == 0, err
    assert f"wrote: {out}" in text and "12000 samples" in text
    cf = load_calibration_file(logs / cal)
    log = read_log(logs / "six.csv", LogOptions(detect=False))
    want = cf.calibration.correct(np.column_stack([log.acc, log.acc_normal]))
    comments, header, rows = _read_back(out)
    assert header == ["t (s)", "acc_x (m/s^2)", "acc_y (m/s^2)", "acc_z (m/s^2)"]
    assert np.array_equal(rows[:, 0], log.t)
    assert np.array_equal(rows[:, 1:], want)  # float precision: the shortest round trip
    assert cal in comments[0] and cf.checksum in comments[0]
    assert load_calibration_file(logs / cal).calibration == cf.calibration
    assert "six.csv" in comments[0] and "sha256" in comments[0]
    assert EQUATIONS["six-face"] in comments[1]
    # still sensor on a face: the corrected specific force is g along that case axis
    held = np.abs(np.linalg.norm(want, axis=1) - cf.calibration.g) < 0.1
    assert held.mean() > 0.7


def test_tilt_plane_correction_is_the_course_equation(capsys, logs, tmp_path):
    out = tmp_path / "yz.csv"
    rc, _, err = run(capsys, "apply", logs / "yz.csv", "--axes", "y,z", "--calibration",
                     logs / "yz.json", "--out", out)
    assert rc == 0, err
    cal = load_calibration_file(logs / "yz.json").calibration
    log = read_log(logs / "yz.csv", LogOptions(axes=("y", "z"), detect=False))
    _, header, rows = _read_back(out)
    assert header == ["t (s)", "acc_x (m/s^2)", "acc_y (m/s^2)"]
    assert np.array_equal(rows[:, 1:], correct(log.acc, cal.bias, cal.scale))
    # the corrected tilt plane reads −g sin θ, −g cos θ (course signs) within the noise
    ref = np.column_stack([-cal.g * np.sin(log.theta), -cal.g * np.cos(log.theta)])
    assert np.sqrt(np.mean((rows[:, 1:] - ref) ** 2)) < 0.1


def test_the_corrected_csv_reads_back_as_a_log(capsys, logs, tmp_path):
    out = tmp_path / "c.csv"
    assert run(capsys, "apply", logs / "six.csv", "--calibration", logs / "six.json", "--out",
               out)[0] == 0
    back = read_log(out, LogOptions(detect=False))
    _, _, rows = _read_back(out)
    assert np.array_equal(back.acc, rows[:, 1:3]) and np.array_equal(back.acc_normal, rows[:, 3])
    assert back.provenance["units"]["acc"] == "m/s2"


def test_json_output_names_the_files_and_carries_units(capsys, logs, tmp_path):
    rc, out, err = run(capsys, "apply", logs / "six.csv", "--calibration", logs / "six.json",
                       "--out", tmp_path / "c.csv", "--json")
    assert rc == 0, err
    doc = json.loads(out)
    assert missing_units(doc) == []
    assert doc["samples"] == 12000 and doc["kind"] == "six-face"
    assert doc["axes"] == ["x", "y", "z"] and doc["log_axes"] == ["x", "y", "z"]
    assert doc["calibration"]["name"] == "six.json" and len(doc["calibration"]["sha256"]) == 64
    assert doc["log"]["name"] == "six.csv" and doc["out"] == str(tmp_path / "c.csv")


@pytest.mark.parametrize("argv, words", [
    (("six_g.csv", "six.json"), "calibrated on readings in m/s2, but"),
    (("six.csv", "six.json", "--axes=-y,z"), "calibrated on the log axes x,y"),
    (("yz.csv", "yz.json"), "calibrated on the log axes y,z"),
    (("yz.csv", "six.json", "--axes", "y,z"), "calibrated on the log axes x,y"),
], ids=["unit", "axes", "planar-axes", "six-face-axes"])
def test_a_calibration_of_other_axes_or_units_is_refused(capsys, logs, tmp_path, argv, words):
    log, cal, *extra = argv
    out = tmp_path / "c.csv"
    msg = one_line_error(capsys, "apply", logs / log, "--calibration", logs / cal, "--out",
                         out, *extra)
    assert words in msg and cal in msg
    assert not out.exists()


def test_course_files_and_the_third_axis(capsys, logs, tmp_path, course_dir):
    """A y,z calibration on the course's x,y acel.mat is refused; a six-face one too (the
    course file has two axes)."""
    out = tmp_path / "c.csv"
    msg = one_line_error(capsys, "apply", course_dir / "acel.mat", "--calibration",
                         logs / "yz.json", "--out", out)
    assert "course's axes x,y" in msg
    msg = one_line_error(capsys, "apply", course_dir / "acel.mat", "--calibration",
                         logs / "six.json", "--out", out)
    assert "corrects 3 axes" in msg
    assert not out.exists()


def test_force_and_the_csv_name(capsys, logs, tmp_path):
    out = tmp_path / "c.csv"
    out.write_text("keep\n")
    msg = one_line_error(capsys, "apply", logs / "six.csv", "--calibration",
                         logs / "six.json", "--out", out)
    assert "--force" in msg and out.read_text() == "keep\n"
    assert run(capsys, "apply", logs / "six.csv", "--calibration", logs / "six.json", "--out",
               out, "--force")[0] == 0
    assert out.read_text().startswith("# tiltbench apply")
    msg = one_line_error(capsys, "apply", logs / "six.csv", "--calibration",
                         logs / "six.json", "--out", tmp_path / "c.txt")
    assert ".csv" in msg and not (tmp_path / "c.txt").exists()
    msg = one_line_error(capsys, "apply", logs / "six.csv", "--calibration",
                         logs / "six.csv", "--out", tmp_path / "d.csv")
    assert "six.csv" in msg and not (tmp_path / "d.csv").exists()

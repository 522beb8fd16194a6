"""Provenance in every command that reads a log (issue 31, part 5): the ``--json`` output
carries how the log was read under ``provenance`` — the record of its one log, or
``{role: record}`` for a command that read two — and stderr has the one-line note.

Small CSV logs written here and the course files; no MuJoCo runs.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from bench.cli.output import forget_logs_read, logs_read_provenance, note_log_read
from calib.units import missing_units
from tests.cli import run

G = 9.80665


def _still_csv(path, n=3000, rate=100.0, seed=0):
    """A still sensor, z up, in g, with white noise: a log ``noise`` accepts."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    acc = np.array([0.01, -0.02, 1.0]) + rng.normal(0.0, 2e-3, (n, 3))
    rows = np.column_stack([t, acc])
    np.savetxt(path, rows, delimiter=",", fmt="%.7f",
               header="time (s),ax (g),ay (g),az (g)", comments="")
    return path


def _json(capsys, *argv):
    rc, out, err = run(capsys, *argv)
    assert rc == 0, err
    return json.loads(out), err


def test_noise_json_names_columns_units_and_source(tmp_path, capsys):
    log = _still_csv(tmp_path / "still.csv")
    doc, err = _json(capsys, "noise", log, "--json")
    prov = doc["provenance"]
    assert prov["source"]["name"] == "still.csv"
    assert prov["units"]["acc"] == "g"
    assert prov["mapping"]["x"] == "ax (g)"
    assert "note: read still.csv" in err.replace("\n    ", " ")


def test_calibrate_json_of_a_course_file_says_course(course_dir, capsys):
    doc, _ = _json(capsys, "calibrate", course_dir / "ensayo.mat", "--json")
    assert doc["provenance"]["format"] == "course"
    assert doc["provenance"]["source"]["name"] == "ensayo.mat"


def test_two_logs_give_one_record_per_role(course_dir, capsys):
    doc, _ = _json(capsys, "trajectory", "--ensayo", course_dir / "ensayo.mat",
                   "--acel", course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat",
                   "--datos", course_dir / "datos.txt", "--json")
    assert set(doc["provenance"]) == {"ensayo", "acel"}
    assert doc["provenance"]["acel"]["source"]["name"] == "acel.mat"


def test_a_command_reading_no_log_has_no_provenance(tmp_path, capsys):
    doc, _ = _json(capsys, "generate", "calibration", "--out", tmp_path / "c", "--json")
    assert "provenance" not in doc


def test_each_command_starts_with_no_log_read(tmp_path, capsys, course_dir):
    # one process, two commands: the second does not inherit the first one's log
    _json(capsys, "calibrate", course_dir / "ensayo.mat", "--json")
    doc, _ = _json(capsys, "generate", "calibration", "--out", tmp_path / "c", "--json")
    assert "provenance" not in doc


@pytest.mark.parametrize("roles", [["log"], ["ensayo", "acel"]])
def test_record_shape(roles):
    forget_logs_read()
    for r in roles:
        note_log_read(r, {"format": r})
    got = logs_read_provenance()
    assert got == ({"format": "log"} if roles == ["log"] else
                   {"ensayo": {"format": "ensayo"}, "acel": {"format": "acel"}})
    forget_logs_read()
    assert logs_read_provenance() is None


REAL = Path(__file__).resolve().parents[1] / "data" / "real"


@pytest.mark.parametrize("argv", [
    ("calibrate", REAL / "imucal-ferraris-session.csv.gz", "--units", "m/s2",
     "--gyro-unit", "deg/s"),
    ("calibrate", REAL / "axivity-ax3-wrist-night.csv.gz", "--sensitivity", "256"),
    ("gap", REAL / "imucal-ferraris-session.csv.gz", "--units", "m/s2", "--gyro-unit",
     "deg/s", "--noise-var", "0.0004,0.0004"),
], ids=["six-face", "detected-poses-counts", "gap-plane-faces"])
def test_every_number_of_a_real_logs_provenance_has_a_unit(capsys, argv):
    rc, out, err = run(capsys, *argv, "--json")
    assert rc in (0, 1), err  # gap: 1 = a gap found is a verdict, not an error
    doc = json.loads(out)
    assert doc["provenance"]["source"]["sha256"]
    assert [p for p in missing_units(doc) if p.startswith("provenance")] == []


def test_import_json_units_cover_its_provenance(tmp_path, capsys):
    log = _still_csv(tmp_path / "still.csv")
    doc, _ = _json(capsys, "import", log, "--out", tmp_path / "set", "--json")
    assert missing_units(doc) == []

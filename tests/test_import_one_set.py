"""``tiltbench import`` writes one set: ``--out ''`` is refused (it would write into the
current folder), and ``--force`` over an earlier import replaces the set as a whole — never a
new ``acel.mat`` beside an old ``ensayo.mat`` with a provenance naming only the new log."""

from __future__ import annotations

import json

import pytest

from tests.cli import one_line_error, run, unwrap
from tests.reference.real_data import REAL_DIR

YEI = (REAL_DIR / "yei-3space-z-flip.csv", "--units", "g", "--gyro-unit", "rad/s")  # 2 poses
NGIMU = (REAL_DIR / "ngimu-sensors.csv",)  # one pose: a vehicle-style acel.mat


@pytest.mark.parametrize("command", [("import", *NGIMU, "--out"),
                                     ("calibrate", REAL_DIR / "ngimu-sensors.csv", "--save"),
                                     ("calibrate", REAL_DIR / "ngimu-sensors.csv", "--plot")])
@pytest.mark.parametrize("empty", ["", "  "])
def test_an_empty_output_path_is_refused(capsys, tmp_path, monkeypatch, command, empty):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_:  # argparse refuses it while parsing
        run(capsys, *command, empty)
    assert exit_.value.code == 2
    cap = capsys.readouterr()
    msg = unwrap(cap.err).splitlines()[-1]
    assert cap.out == "" and "Traceback" not in cap.err
    assert f"argument {command[-1]}: an empty path" in msg
    assert list(tmp_path.iterdir()) == []


def test_force_replaces_the_set_as_one_set(capsys, tmp_path):
    out = tmp_path / "set"
    rc, _, err = run(capsys, "import", *YEI, "--out", out)
    assert rc == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["ensayo.mat", "provenance.json"]
    (out / "notes.txt").write_text("mine")  # not the set's: kept
    rc, _, err = run(capsys, "import", *NGIMU, "--out", out)
    assert rc != 0 and "already exist" in err  # without --force nothing changes
    rc, _, err = run(capsys, "import", *NGIMU, "--out", out, "--force")
    assert rc == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["acel.mat", "notes.txt", "provenance.json"]
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["source"]["name"] == "ngimu-sensors.csv"
    assert list(prov["written"]) == ["acel.mat"]
    # and back: the acel.mat goes when a calibration set replaces it
    rc, _, err = run(capsys, "import", *YEI, "--out", out, "--force")
    assert rc == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["ensayo.mat", "notes.txt", "provenance.json"]


def test_force_in_the_working_folder_replaces_the_set_too(capsys, tmp_path, monkeypatch):
    """A target holding the working directory is written file by file (it cannot be swapped):
    the old course file of the other kind is still removed."""
    monkeypatch.chdir(tmp_path)
    rc, _, err = run(capsys, "import", *YEI, "--out", ".")
    assert rc == 0, err
    rc, _, err = run(capsys, "import", *NGIMU, "--out", ".", "--force")
    assert rc == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["acel.mat", "provenance.json"]


def test_a_dropped_gyro_is_named_with_the_fix(capsys, tmp_path):
    """Gyro columns whose unit is not stated are not read, and import says so and how to fix
    it (not just "gyro none")."""
    import numpy as np

    rng = np.random.default_rng(1)
    rows = []
    for k in range(600):
        u = (0.0, 0.0, 9.8) if k < 300 else (9.8, 0.0, 0.0)
        acc = np.array(u) + rng.normal(0, 0.01, 3)
        rows.append(f"{k * 0.01:.2f}," + ",".join(f"{v:.4f}" for v in acc) + ","
                    + ",".join(f"{v:.4f}" for v in rng.normal(0, 0.01, 3)))
    path = tmp_path / "g.csv"
    path.write_text("t (s),ax (m/s2),ay (m/s2),az (m/s2),gx,gy,gz\n" + "\n".join(rows) + "\n")
    rc, out, err = run(capsys, "import", path, "--out", tmp_path / "o")
    assert rc == 0, err
    line = unwrap(out)
    assert "gyro none (gyro columns ignored: their unit is not stated (give --gyro-unit))" in line


def test_rate_gives_a_log_without_times_its_clock(capsys, tmp_path):
    """``import --rate``: a log without a time column (imucal's session: sample numbers, 102.4
    Hz by its source) gets t = k / rate; a log with times refuses it."""
    import scipy.io

    log = REAL_DIR / "imucal-ferraris-session.csv.gz"
    rc, out, err = run(capsys, "import", log, "--units", "m/s2", "--gyro-unit", "deg/s",
                       "--rate", "102.4", "--out", tmp_path / "o", "--json")
    assert rc == 0, err
    prov = json.loads(out)["provenance"]
    assert prov["units"]["t"] == "s, from --rate 102.4 Hz"
    t = scipy.io.loadmat(tmp_path / "o" / "ensayo.mat")["t"].ravel()
    assert abs(t[1] - t[0] - 1 / 102.4) < 1e-12 or abs(t[0] % (1 / 102.4)) < 1e-9
    line = one_line_error(capsys, "import", *NGIMU, "--rate", "50", "--out", tmp_path / "n")
    assert "has sample times" in line and "drop --rate" in line

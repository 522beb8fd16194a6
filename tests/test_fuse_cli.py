"""`tiltbench fuse` end to end: a generated course set with a receiver, fused, decided."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bench.cli import main


def _run(capsys, *argv) -> tuple[int, str, str]:
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    out = tmp_path_factory.mktemp("fuse") / "cs"
    assert main(["generate", "course", "--seed", "3", "--out", str(out), "--gps"]) == 0
    return out


def _files(d):
    return ["--acel", d / "acel.mat", "--gps", d / "gps.mat", "--puntos", d / "puntos.mat",
            "--datos", d / "datos.txt"]


def test_fused_arrival_is_metres_and_decides_the_truth(capsys, course):
    truth = json.loads((course / "truth.json").read_text())
    rc, out, _ = _run(capsys, "fuse", *_files(course), "--ensayo", course / "ensayo.mat",
                      "--json")
    assert rc == 0
    d = json.loads(out)
    fused = d["fusion"]
    est = np.array(fused["final_position"], dtype=float).reshape(2)
    cov = np.array(fused["final_position_cov"], dtype=float).reshape(2, 2)
    err = est - np.array(truth["true_final_position"])
    assert float(err @ np.linalg.solve(cov, err)) < 13.8  # χ²₂ at 0.999
    assert np.all(np.sqrt(np.diag(cov)) < 5.0)  # metres, not tens of metres
    assert d["decision"]["decision"] == truth["answer"]
    rc, out, _ = _run(capsys, "trajectory", *[a for a in _files(course) if "gps" not in
                                              str(a)], "--ensayo", course / "ensayo.mat",
                      "--json")
    dead = json.loads(out)
    assert rc == 0
    dr_std = np.array(dead["std"], dtype=float)
    assert np.all(np.sqrt(np.diag(cov)) < dr_std / 3)


def test_fuse_with_a_saved_calibration_equals_refitting(capsys, course, tmp_path):
    cal = tmp_path / "cal.json"
    assert _run(capsys, "calibrate", course / "ensayo.mat", "--datos", course / "datos.txt",
                "--save", cal)[0] == 0
    a = _run(capsys, "fuse", *_files(course), "--ensayo", course / "ensayo.mat", "--json")[1]
    b = _run(capsys, "fuse", *_files(course), "--calibration", cal, "--json")[1]
    assert json.loads(a)["fusion"]["final_position"] == json.loads(b)["fusion"]["final_position"]


def test_missing_gps_file_is_one_line(capsys, course, tmp_path):
    rc, _, err = _run(capsys, "fuse", "--acel", course / "acel.mat", "--gps",
                      tmp_path / "none.mat", "--puntos", course / "puntos.mat", "--ensayo",
                      course / "ensayo.mat", "--datos", course / "datos.txt")
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "none.mat" in err

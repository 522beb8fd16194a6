"""Class sets: K unique course sets without the truth, one private answer key."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import scipy.io

from bench.classset import (
    KEY_CSV,
    KEY_JSON,
    STUDENT_FILES,
    generate_class,
    student_seeds,
)
from bench.cli import main

COURSE_VARS = {"ensayo.mat": {"tita", "datos"}, "acel.mat": {"t", "Aerr"},
               "puntos.mat": {"A", "B", "C", "D"}}


@pytest.fixture(scope="module")
def klass(tmp_path_factory):
    out = tmp_path_factory.mktemp("class")
    return generate_class(out, count=3, seed=11)


def test_folders_hold_only_the_student_files(klass):
    assert sorted(p.name for p in klass.out.iterdir()) == sorted(
        [KEY_CSV, KEY_JSON, "student_001", "student_002", "student_003"])
    for name, folder in klass.folders.items():
        assert sorted(p.name for p in folder.iterdir()) == sorted(STUDENT_FILES), name
        for f, names in COURSE_VARS.items():
            mat = scipy.io.loadmat(str(folder / f))
            assert {k for k in mat if not k.startswith("__")} == names


def test_nothing_in_a_folder_reveals_the_truth(klass):
    key = json.loads(klass.key_json.read_text())
    for entry in key["students"]:
        folder = klass.out / entry["folder"]
        blob = b"".join((folder / f).read_bytes() for f in STUDENT_FILES)
        t = entry["truth"]
        assert str(entry["seed"]).encode() not in blob
        for a in "xy":  # true parameters, neither as text nor as float64 bytes
            for p in ("bias", "scale"):
                v = t["sensor"][a][p]
                assert repr(v).encode() not in blob
                assert np.float64(v).tobytes() not in blob
        assert b"answer" not in blob and b"truth" not in blob


def test_sets_are_unique_and_seeds_derived(klass):
    seeds = student_seeds(11, 3)
    assert [r["seed"] for r in klass.rows] == seeds
    assert len(set(seeds)) == 3 and student_seeds(12, 3) != seeds
    blobs = [(f / "ensayo.mat").read_bytes() for f in klass.folders.values()]
    assert len(set(blobs)) == 3
    params = {tuple(r[k] for k in ("bias_x", "scale_x", "bias_y", "scale_y"))
              for r in klass.rows}
    assert len(params) == 3


def test_answer_key_csv_and_json_agree(klass):
    rows = list(csv.DictReader(klass.key_csv.open()))
    key = json.loads(klass.key_json.read_text())
    assert key["class_seed"] == 11 and key["count"] == 3 and len(rows) == 3
    for row, entry in zip(rows, key["students"], strict=True):
        t = entry["truth"]
        assert row["student"] == entry["student"] and int(row["seed"]) == entry["seed"]
        assert row["answer"] == entry["answer"] == t["answer"]
        assert float(row["bias_x"]) == t["sensor"]["x"]["bias"]  # repr: exact
        assert float(row["scale_y"]) == t["sensor"]["y"]["scale"]
        assert json.loads(row["candidates"]) == t["candidates"]
        assert t["candidates"][t["answer"]] == t["true_final_position"]


def test_a_folder_is_reproduced_by_generate_course(klass, tmp_path):
    first = klass.rows[0]
    assert main(["generate", "course", "--seed", str(first["seed"]), "--out",
                 str(tmp_path)]) == 0
    for f in STUDENT_FILES:
        assert (tmp_path / f).read_bytes() == (klass.folders[first["student"]] / f).read_bytes()


def test_cli_generate_class_and_overwrite(tmp_path, capsys):
    out = tmp_path / "c"
    assert main(["generate", "class", "--students", "2", "--seed", "5", "--out", str(out),
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["count"] == 2 and set(summary["folders"]) == {"student_001", "student_002"}
    assert "answers" not in json.dumps(summary) and '"answer"' not in json.dumps(summary)
    csv_before = (out / KEY_CSV).read_bytes()
    assert main(["generate", "class", "--students", "2", "--seed", "5", "--out", str(out)]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["generate", "class", "--students", "2", "--seed", "5", "--out", str(out),
                 "--force"]) == 0
    assert (out / KEY_CSV).read_bytes() == csv_before  # same seed, same bytes


def test_validate_against_the_answer_key(klass, tmp_path, capsys):
    name = "student_002"
    assert main(["calibrate", str(klass.folders[name] / "ensayo.mat"), "--noise-var",
                 "0.25,0.64", "--json"]) == 0
    (tmp_path / "est.json").write_text(capsys.readouterr().out)
    rc = main(["validate", "--truth", str(klass.key_json), "--student", name, "--estimates",
               str(tmp_path / "est.json"), "--json"])
    res = json.loads(capsys.readouterr().out)
    assert rc == (0 if res["passed"] else 1)
    truth = json.loads(klass.key_json.read_text())["students"][1]["truth"]
    assert res["parameters"]["bias_x"]["truth"] == truth["sensor"]["x"]["bias"]
    assert main(["validate", "--truth", str(klass.key_json), "--estimates",
                 str(tmp_path / "est.json")]) == 2  # which student?

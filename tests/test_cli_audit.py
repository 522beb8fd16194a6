"""Command-line audit: bad input gives one clear line and exit code 2, refused runs write
nothing, option values may be negative pairs. Small synthetic files; no MuJoCo runs."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.io

from bench.cli import build_parser, main
from tests.cli import one_line_error as _error
from tests.cli import run as _run


@pytest.fixture
def ensayo(tmp_path):
    """A small valid calibration run in the course format."""
    rng = np.random.default_rng(3)
    tita = np.linspace(0.0, 2 * np.pi, 200)
    ref = np.column_stack([-9.8 * np.sin(tita), -9.8 * np.cos(tita)])
    datos = 1.01 * ref + 0.05 + rng.normal(0.0, 0.5, ref.shape)
    path = tmp_path / "ensayo.mat"
    scipy.io.savemat(path, {"tita": tita[:, None], "datos": datos})
    return path


@pytest.fixture
def vehicle_files(tmp_path):
    t = np.arange(300) * 0.01
    acel = tmp_path / "acel.mat"
    scipy.io.savemat(acel, {"t": t[:, None], "Aerr": np.zeros((t.size, 2))})
    puntos = tmp_path / "puntos.mat"
    scipy.io.savemat(puntos, {"A": np.array([[0.0, 9.0]]), "B": np.array([[50.0, 50.0]]),
                              "C": np.array([[-50.0, 50.0]]), "D": np.array([[0.0, -60.0]])})
    return acel, puntos


def test_negative_number_pairs_are_option_values():
    p = build_parser()
    a = p.parse_args(["calibrate", "e.mat", "--noise-var", "-0.25,0.64"])
    assert a.noise_var == "-0.25,0.64"
    a = p.parse_args(["generate", "calibration", "--out", "d", "--bias", "-0.02,0.08",
                      "--theta-range", "-1,1", "--scale", "-.03,-1e-2"])
    assert (a.bias, a.theta_range, a.scale) == ("-0.02,0.08", "-1,1", "-.03,-1e-2")
    a = p.parse_args(["trajectory", "--ensayo", "e", "--acel", "a", "--puntos", "p",
                      "--p0", "-5,3", "--v0", "-1,-2"])
    assert (a.p0, a.v0) == ("-5,3", "-1,-2")


def test_negative_noise_variance_is_a_clear_error(capsys, ensayo):
    msg = _error(capsys, "calibrate", ensayo, "--noise-var", "-0.25,0.64")
    assert "--noise-var" in msg and "positive" in msg


def test_empty_noise_var_is_not_ignored(capsys, ensayo):
    assert "--noise-var" in _error(capsys, "calibrate", ensayo, "--noise-var", "")


@pytest.mark.parametrize("value, kind", [("abc", "text"), (np.ones((3, 1)) * 1j, "complex"),
                                         ({"a": 1.0}, "struct")])
def test_non_numeric_variable_names_file_and_variable(capsys, tmp_path, value, kind):
    path = tmp_path / "odd.mat"
    scipy.io.savemat(path, {"tita": value, "datos": np.zeros((3, 2))})
    msg = _error(capsys, "calibrate", path, "--noise-var", "0.25,0.64")
    assert str(path) in msg and "'tita'" in msg and kind in msg


def test_non_numeric_candidate_point(capsys, tmp_path, ensayo, vehicle_files):
    acel, _ = vehicle_files
    puntos = tmp_path / "p.mat"
    scipy.io.savemat(puntos, {"A": "hello", "B": np.array([[1.0, 2.0]]),
                              "C": np.array([[3.0, 4.0]]), "D": np.array([[5.0, 6.0]])})
    msg = _error(capsys, "trajectory", "--ensayo", ensayo, "--acel", acel, "--puntos", puntos)
    assert str(puntos) in msg and "'A'" in msg


def test_directory_where_a_file_is_expected(capsys, tmp_path, ensayo):
    d = tmp_path / "adir"
    d.mkdir()
    assert "directory" in _error(capsys, "calibrate", d)
    msg = _error(capsys, "calibrate", ensayo, "--datos", d)
    assert str(d) in msg and "directory" in msg
    est = tmp_path / "est.json"
    est.write_text(json.dumps({"axes": {a: {"bias": 0.0, "scale": 0.0} for a in "xy"}}))
    assert "directory" in _error(capsys, "validate", "--truth", d, "--estimates", est)
    assert "directory" in _error(capsys, "calibrate", ensayo, "--rrd", d, "--force")


def test_output_directory_that_is_a_file(capsys, tmp_path):
    f = tmp_path / "plain.txt"
    f.write_text("x")
    msg = _error(capsys, "generate", "calibration", "--count", "5", "--out", f)
    assert str(f) in msg and "not a directory" in msg


def test_level_is_checked_before_any_output(capsys, ensayo):
    for level in ("0", "1", "2"):
        assert "--level" in _error(capsys, "calibrate", ensayo, "--level", level, "--json")
        assert "--level" in _error(capsys, "calibrate", ensayo, "--level", level)


@pytest.mark.parametrize("g", ["nan", "-9.8", "inf"])
def test_gravity_must_be_positive_and_finite(capsys, tmp_path, ensayo, vehicle_files, g):
    acel, puntos = vehicle_files
    assert "--g" in _error(capsys, "calibrate", ensayo, "--g", g)
    assert "--g" in _error(capsys, "trajectory", "--ensayo", ensayo, "--acel", acel,
                           "--puntos", puntos, "--g", g)
    assert "--g" in _error(capsys, "gap", ensayo, "--noise-var", "0.25,0.64", "--g", g)
    out = tmp_path / "gen"
    assert "--g" in _error(capsys, "generate", "calibration", "--count", "5", "--out", out,
                           "--g", g)
    assert "--g" in _error(capsys, "generate", "vehicle", "--out", out, "--g", g)
    assert not out.exists()


def test_theta_list_must_be_finite(capsys, tmp_path):
    out = tmp_path / "gen"
    msg = _error(capsys, "generate", "calibration", "--theta-list", "1,nan,2", "--out", out)
    assert "--theta-list" in msg
    assert not out.exists()


def test_refused_run_leaves_nothing_half_written(capsys, tmp_path, ensayo, vehicle_files):
    old = tmp_path / "old.rrd"
    old.write_bytes(b"old")
    png = tmp_path / "new.png"
    assert "--force" in _error(capsys, "calibrate", ensayo, "--plot", png, "--rrd", old)
    acel, puntos = vehicle_files
    assert "--force" in _error(capsys, "trajectory", "--ensayo", ensayo, "--acel", acel,
                               "--puntos", puntos, "--plot", png, "--rrd", old)
    assert not png.exists()
    for kind in ("calibration", "vehicle", "course"):
        out = tmp_path / kind
        assert "--force" in _error(capsys, "generate", kind, "--out", out, "--rrd", old)
        assert not out.exists()
    assert old.read_bytes() == b"old"


def test_demo_options_checked_before_writing(capsys, tmp_path):
    out = tmp_path / "demo"
    assert "--level" in _error(capsys, "demo", "--out", out, "--level", "2", "--quiet")
    assert "--coverage-runs" in _error(capsys, "demo", "--out", out, "--coverage-runs", "-1",
                                       "--quiet")
    assert not out.exists()


def test_validate_messages_name_the_given_files(capsys, tmp_path, ensayo):
    est = tmp_path / "mine.json"
    est.write_text("[1, 2]")
    truth = tmp_path / "key.json"
    truth.write_text(json.dumps({"sensor": {a: {"bias": 0.0, "scale": 0.0} for a in "xy"}}))
    assert str(est) in _error(capsys, "validate", "--truth", truth, "--estimates", est)
    est.write_text(json.dumps({"axes": {a: {"bias": 0.0, "scale": 0.0, "cov": "abc"}
                                        for a in "xy"}}))
    msg = _error(capsys, "validate", "--truth", truth, "--estimates", est)
    assert str(est) in msg and "cov" in msg
    bad_truth = tmp_path / "nothing.json"
    bad_truth.write_text("{}")
    est.write_text(json.dumps({"axes": {a: {"bias": 0.0, "scale": 0.0} for a in "xy"}}))
    assert str(bad_truth) in _error(capsys, "validate", "--truth", bad_truth, "--estimates", est)


def test_unidentifiable_design_names_the_file(capsys, tmp_path):
    path = tmp_path / "flat.mat"
    scipy.io.savemat(path, {"tita": np.full((5, 1), 0.5), "datos": np.ones((5, 2))})
    msg = _error(capsys, "calibrate", path, "--noise-var", "0.25,0.64")
    assert str(path) in msg and "scale_x" in msg


def test_record_entities_on_a_bad_file(capsys, tmp_path):
    bad = tmp_path / "bad.rrd"
    bad.write_bytes(b"not a recording")
    assert str(bad) in _error(capsys, "record", "entities", bad)
    assert "not found" in _error(capsys, "record", "entities", tmp_path / "none.rrd")


def test_trajectory_note_shows_the_initial_state_used(capsys, ensayo, vehicle_files):
    acel, puntos = vehicle_files
    rc, out, err = _run(capsys, "trajectory", "--ensayo", ensayo, "--acel", acel,
                        "--puntos", puntos, "--p0", "-5,3", "--json")
    assert rc == 0
    json.loads(out)
    note = [line for line in err.splitlines() if line.startswith("note:")]
    assert len(note) == 1 and "[-5.0, 3.0]" in note[0]


def test_unwritable_output_names_the_requested_file(capsys, tmp_path, monkeypatch, ensayo):
    import calib.files.atomic as calib_atomic

    def deny(dir=None, prefix="", suffix=""):
        raise PermissionError(13, "Permission denied", f"{dir}/{prefix}XXXX{suffix}")

    monkeypatch.setattr(calib_atomic.tempfile, "mkstemp", deny)
    png = tmp_path / "fit.png"
    msg = _error(capsys, "calibrate", ensayo, "--plot", png, "--json")
    assert f"{png}: Permission denied" in msg and ".tmp" not in msg


HELP_COMMANDS = [["generate", "calibration"], ["generate", "vehicle"], ["generate", "course"],
                 ["generate", "class"], ["calibrate"], ["trajectory"], ["nmin"], ["fuse"],
                 ["validate"], ["gap"], ["record", "read"], ["demo"], ["design"], ["fusion-study"]]


@pytest.mark.parametrize("command", HELP_COMMANDS, ids=" ".join)
def test_help_states_each_default_once(capsys, command):
    with pytest.raises(SystemExit) as exit_:
        main([*command, "--help"])
    assert exit_.value.code == 0
    text = " ".join(capsys.readouterr().out.split())  # undo argparse's line wrapping
    assert "(default: None)" not in text and "(default: False)" not in text
    assert "(default " not in text  # defaults are stated by the formatter, not by hand
    if "--seed" in text:
        assert "--seed SEED random seed" in text or "--seed SEED seed" in text
        assert "(default: 0)" in text


def test_version_and_bare_command(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out == "tiltbench 0.1.0\n"
    assert main([]) == 0
    cap = capsys.readouterr()
    assert cap.out.startswith("usage: tiltbench") and "generate" in cap.out and cap.err == ""


def test_help_imports_nothing_heavy():
    """Start-up time: building the parser of every command and printing the help import no
    numpy, scipy, mujoco, matplotlib or rerun (benchmarks/cli_startup.py times it). (A
    command's own help may: it shows defaults such as calib.conventions.G.)"""
    import subprocess
    import sys

    code = ("import sys, contextlib, io\n"
            "from bench.cli import main\n"
            "for argv in (['--help'], []):\n"
            "    with contextlib.redirect_stdout(io.StringIO()), "
            "contextlib.suppress(SystemExit):\n"
            "        main(argv)\n"
            "heavy = ('numpy', 'scipy', 'mujoco', 'matplotlib', 'rerun')\n"
            "print(sorted(m for m in heavy if m in sys.modules))\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=True)
    assert res.stdout.strip() == "[]", res.stdout + res.stderr


def test_existing_output_is_worded_by_the_command_line(capsys, tmp_path, ensayo):
    old = tmp_path / "old.rrd"
    old.write_bytes(b"old")
    msg = _error(capsys, "calibrate", ensayo, "--rrd", old)
    assert msg.endswith(f"{old}: exists; pass --force to overwrite")


def test_record_entities_json_is_one_object(capsys, tmp_path, ensayo):
    rrd = tmp_path / "fit.rrd"
    assert main(["calibrate", str(ensayo), "--noise-var", "0.25,0.64", "--rrd", str(rrd)]) == 0
    out = capsys.readouterr().out
    assert f"wrote: {rrd}" in out  # the readable output names every file written
    rc, out, _ = _run(capsys, "record", "entities", rrd, "--json")
    assert rc == 0
    obj = json.loads(out)
    assert obj["file"] == str(rrd) and obj["entities"]
    assert all(set(e) == {"path", "pattern"} for e in obj["entities"])
    rc, text, _ = _run(capsys, "record", "entities", rrd)
    assert len(text.strip().splitlines()) == len(obj["entities"])


def test_class_count_flag_is_students(capsys, tmp_path):
    msg = _error(capsys, "generate", "class", "--students", "0", "--out", tmp_path / "c")
    assert "--students" in msg
    with pytest.raises(SystemExit):
        main(["generate", "class", "--count", "2", "--out", str(tmp_path / "c")])
    assert not (tmp_path / "c").exists()

"""``tiltbench import`` and the log options of the reading commands, end to end in-process.

* The same simulated log (tests/logfixtures.py) imported from every format with its pose
  angles gives the same ensayo.mat numbers and identical ``calibrate --json`` results.
* θ unknown: ensayo.mat with datos, t, pose and no tita, read back with its labels; a single
  held pose: acel.mat (resampled onto a uniform grid when the steps jitter, and said so).
* Bad logs: one line on stderr naming the file and the line/column, exit 2, nothing written.
* The course files as CSV logs through trajectory/calibrate inputs give the course answers.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.io

from calib.files.course import read_acel
from calib.logs.reader import read_log
from tests import logfixtures as fx
from tests.checks import assert_same_tree, result_only
from tests.cli import one_line_error, run, unwrap

POSES = ["--poses", ",".join(str(a) for a in fx.ANGLES_DEG), "--angle-unit", "deg"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("imp")
    return {
        "csv": fx.write_csv(d / "a.csv"),
        "csv_semicolon_decimal_comma": fx.write_csv(d / "b.csv", sep=";", decimal_comma=True),
        "ros2": fx.write_ros2(d / "bag2"),
        "ros1": fx.write_ros1(d / "x.bag"),
        "csv_no_gyro": fx.write_csv(d / "e.csv", gyro=False),
        "phyphox": fx.write_phyphox(d / "Raw Data.csv"),
        "mat_map": fx.write_mat(d / "m.mat"),
    }


def _import(capsys, path, out, *extra):
    mapping = ["--map", "datos=acc,t=time"] if path.suffix == ".mat" else []
    rc, stdout, err = run(capsys, "import", path, "--out", out, *mapping, *extra)
    assert rc == 0, err
    return stdout


def test_every_format_imports_to_the_same_calibration(capsys, tmp_path, files):
    results, mats = {}, {}
    for name, path in files.items():
        out = tmp_path / name
        _import(capsys, path, out, *POSES)
        mats[name] = scipy.io.loadmat(out / "ensayo.mat")
        rc, stdout, err = run(capsys, "calibrate", out / "ensayo.mat", "--json")
        assert rc == 0, err
        results[name] = json.loads(stdout)
    gyro = ("csv", "csv_semicolon_decimal_comma", "ros2", "ros1")
    plain = ("csv_no_gyro", "phyphox", "mat_map")
    for group in (gyro, plain):
        ref = group[0]
        for name in group[1:]:
            for var in ("tita", "datos", "t", "pose"):
                a, b = mats[name][var], mats[ref][var]
                assert a.shape == b.shape and np.allclose(a, b, rtol=1e-12, atol=0), (name, var)
            assert results[name] == results[ref], name
    m = mats["ros1"]
    assert m["tita"].shape[1] == 1 and m["datos"].shape[1] == 2 and m["pose"].dtype.kind == "i"


def test_theta_unknown_writes_labels_and_no_tita(capsys, tmp_path, files):
    out = tmp_path / "u"
    text = _import(capsys, files["csv"], out)
    assert "5 held pose(s) found" in text and "(m/s²)²" in text and "10th percentile" in text
    mat = scipy.io.loadmat(out / "ensayo.mat")
    assert "tita" not in mat and {"datos", "t", "pose"} <= set(mat)
    assert mat["datos"].shape == (mat["t"].size, 2) and mat["pose"].shape == (mat["t"].size, 1)
    back = read_log(out / "ensayo.mat")
    orig = read_log(files["csv"])
    assert back.theta is None and np.array_equal(back.pose, orig.pose)
    assert np.array_equal(back.acc, orig.acc) and np.array_equal(back.t, orig.t)
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["source"]["name"] == "a.csv" and len(prov["source"]["sha256"]) == 64
    assert prov["tool"]["version"] and prov["format_version"] == 1
    assert len(prov["poses"]["detection"]["segments"]) == 5 and "tita" in prov["theta"]
    rc, _, err = run(capsys, "gap", out / "ensayo.mat", "--noise-var", "0.0004,0.0004")
    assert rc == 2 and "table angle is unknown" in unwrap(err) and "--poses" in err


def test_one_held_pose_becomes_an_acel_file_resampled(capsys, tmp_path):
    rng = np.random.default_rng(9)
    n = 3000
    t = np.arange(n) * 0.01 + 0.002 * rng.uniform(-1, 1, n)  # a phone's jittered steps
    acc = np.c_[np.full(n, 0.3), np.full(n, -9.79)] + 0.01 * rng.standard_normal((n, 2))
    body = "\n".join(f"{a!r},{b!r},{c!r}" for a, b, c in np.c_[t, acc].tolist())
    (tmp_path / "s.csv").write_text("t,ax (m/s^2),ay (m/s^2)\n" + body + "\n")
    rc, stdout, err = run(capsys, "import", tmp_path / "s.csv", "--out", tmp_path / "o",
                          "--json")
    assert rc == 0, err
    doc = json.loads(stdout)
    assert doc["files"][0].endswith("acel.mat")
    r = doc["provenance"]["resampled"]
    # the grid starts at the first (jittered) sample: deviations up to twice the jitter
    assert abs(r["step_s"] - 0.01) < 1e-3 and 0.001 < r["max_deviation_from_grid_s"] <= 0.004
    a = read_acel(tmp_path / "o" / "acel.mat")  # the course reader takes it: uniform t
    assert np.allclose(a.aerr.mean(0), acc.mean(0), atol=0.002)


def test_existing_output_needs_force(capsys, tmp_path, files):
    out = tmp_path / "f"
    _import(capsys, files["csv"], out, *POSES)
    err = one_line_error(capsys, "import", files["csv"], "--out", out, *POSES)
    assert "--force" in err
    _import(capsys, files["csv"], out, *POSES, "--force")


def _table(path, text: str):
    path.write_text(text)
    return path


BAD = {
    # name: (file name, content, extra options, words the message must hold)
    "no header": ("n.csv", "0,1,2\n0.01,1,2\n", [], ["line 1", "no header"]),
    "unknown units": ("u.csv", "t,ax,ay\n0,1,2\n0.01,1,2\n0.02,1,2\n", [],
                      ["'ax'", "--units"]),
    "non-numeric cell": ("c.csv", "t,ax (g),ay (g)\n0,1,2\n0.01,x1,2\n", [],
                         ["line 3", "'ax (g)'", "'x1'"]),
    "non-monotone time": ("m.csv", "t,ax (g),ay (g)\n0,1,2\n0.02,1,2\n0.01,1,2\n0.03,1,2\n",
                          [], ["line 4", "does not increase"]),
    "nan": ("nan.csv", "t,ax (g),ay (g)\n0,1,2\n0.01,nan,2\n0.02,1,2\n", [],
            ["NaN", "line 3"]),
    "gap": ("g.csv", "t,ax (g),ay (g)\n" + "".join(f"{0.01 * k},{k % 3},{k % 5}\n"
                                                 for k in range(50))
            + "".join(f"{2 + 0.01 * k},{k % 3},{k % 5}\n" for k in range(50)), [],
            ["gap", "line 51", "--allow-gaps"]),
    "saturated": ("s.csv", "t,ax (g),ay (g)\n" + "".join(
        f"{0.01 * k},{min(2.0, 0.1 * k)},{k % 3}\n" for k in range(60)), [],
        ["'ax (g)'", "extreme value 2", "saturated", "line 22"]),
    "linear acceleration": ("p.csv", '"Time (s)","Linear Acceleration x (m/s^2)",'
                            '"Linear Acceleration y (m/s^2)"\n0,1,2\n', [],
                            ["gravity was removed", "tilt signal"]),
    "sensor logger without gravity": ("Accelerometer.csv",
                                      "time,seconds_elapsed,z,y,x\n1,0,1,2,3\n", [],
                                      ["without gravity", "TotalAcceleration"]),
    "counts without sensitivity": ("k.csv", "t,ax,ay\n0,1,2\n", ["--units", "counts"],
                                   ["--sensitivity"]),
    "unknown column": ("q.csv", "t,ax (g),ay (g)\n0,1,2\n", ["--columns", "x=acc1"],
                       ["--columns x=acc1", "no such column"]),
}


@pytest.mark.parametrize("case", list(BAD), ids=list(BAD))
def test_bad_logs_give_one_line_and_write_nothing(capsys, tmp_path, case):
    name, content, extra, words = BAD[case]
    path = _table(tmp_path / name, content)
    out = tmp_path / "out"
    line = one_line_error(capsys, "import", path, "--out", out, *extra)
    for w in words:
        assert w in line, (w, line)
    assert not out.exists()


def test_pose_count_and_bag_and_mat_errors_name_what_to_do(capsys, tmp_path, files):
    out = tmp_path / "out"
    line = one_line_error(capsys, "import", files["csv"], "--out", out, "--poses", "0,90,180",
                          "--angle-unit", "deg")
    assert "--poses gives 3 angle(s) but 5 held pose(s) were detected" in line
    bag = fx.write_ros2(tmp_path / "two", topics=("/imu/a", "/imu/b"))
    line = one_line_error(capsys, "import", bag, "--out", out)
    assert "/imu/a, /imu/b" in line and "--columns topic=" in line
    line = one_line_error(capsys, "import", files["mat_map"], "--out", out, "--map",
                          "datos=nope")
    assert "no variable 'nope'" in line and "acc" in line
    assert not out.exists()


def test_gaps_allowed_are_recorded(capsys, tmp_path):
    """Two held poses on both sides of a gap: a calibration set, the gap recorded."""
    rows = "".join(f"{0.01 * k},{0.0},{-1.0}\n" for k in range(300))
    rows += "".join(f"{5 + 0.01 * k},{-1.0},{0.0}\n" for k in range(300))
    path = _table(tmp_path / "g.csv", "t,ax (g),ay (g)\n" + rows)
    rc, stdout, err = run(capsys, "import", path, "--out", tmp_path / "o", "--allow-gaps",
                          "--allow-saturation", "--json")
    assert rc == 0, err
    doc = json.loads(stdout)
    gaps = doc["provenance"]["gaps"]
    assert len(gaps) == 1 and gaps[0]["after"] == "line 301"
    assert list(doc["provenance"]["written"]) == ["ensayo.mat"]
    # t is written as read: nothing inside the 2-s gap
    t = scipy.io.loadmat(tmp_path / "o" / "ensayo.mat")["t"].ravel()
    assert t.size == 600 and not np.any((t > 2.995) & (t < 5.0))


def test_a_gap_is_never_filled_in_a_vehicle_run(capsys, tmp_path):
    """No held poses (a vehicle run, acel.mat on one uniform grid): a gap would be filled with
    readings the log does not have — refused, nothing written."""
    rng = np.random.default_rng(2)
    t = np.concatenate([0.01 * np.arange(400), 83.0 + 0.01 * np.arange(400)])
    acc = rng.standard_normal((800, 2)) * 0.5
    path = _table(tmp_path / "v.csv", "t,ax (m/s^2),ay (m/s^2)\n" + "".join(
        f"{a:.3f},{b:.5f},{c:.5f}\n" for a, (b, c) in zip(t, acc, strict=True)))
    line = one_line_error(capsys, "import", path, "--out", tmp_path / "o", "--allow-gaps")
    assert "gap(s) in time" in line and "never writes readings" in line
    assert not (tmp_path / "o").exists()


def test_jittered_times_report_their_true_deviation_from_the_grid(capsys, tmp_path):
    """A clock that runs slow for half the log: the largest |t_k − grid_k| is what import
    prints, not the distance to the nearest grid point (which would hide the drift)."""
    rng = np.random.default_rng(3)
    steps = np.where(np.arange(999) < 500, 0.0100, 0.0104) + rng.uniform(-1e-4, 1e-4, 999)
    t = np.concatenate([[0.0], np.cumsum(steps)])
    acc = rng.standard_normal((1000, 2)) * 0.5
    path = _table(tmp_path / "j.csv", "t,ax (m/s^2),ay (m/s^2)\n" + "".join(
        f"{a:.6f},{b:.5f},{c:.5f}\n" for a, (b, c) in zip(t, acc, strict=True)))
    rc, stdout, err = run(capsys, "import", path, "--out", tmp_path / "o", "--json")
    assert rc == 0, err
    r = json.loads(stdout)["provenance"]["resampled"]
    grid = t[0] + (t[-1] - t[0]) / 999 * np.arange(1000)
    # times written to 1 µs: equal within that
    assert r["max_deviation_from_grid_s"] == pytest.approx(np.max(np.abs(t - grid)), abs=2e-6)
    assert r["max_deviation_from_grid_s"] > 0.05  # the drift: far beyond one step


def test_course_files_as_csv_logs_give_the_course_trajectory(capsys, tmp_path, course_dir):
    """--ensayo and --acel as CSV logs: the same trajectory --json as the course .mat files."""
    e = scipy.io.loadmat(course_dir / "ensayo.mat")
    a = scipy.io.loadmat(course_dir / "acel.mat")
    rows = np.c_[e["tita"].ravel(), e["datos"]].tolist()
    _table(tmp_path / "e.csv", "tita,ax (m/s^2),ay (m/s^2)\n" + "\n".join(
        f"{x!r},{y!r},{z!r}" for x, y, z in rows) + "\n")
    rows = np.c_[a["t"].ravel(), a["Aerr"]].tolist()
    _table(tmp_path / "a.csv", "t,ax (m/s^2),ay (m/s^2)\n" + "\n".join(
        f"{x!r},{y!r},{z!r}" for x, y, z in rows) + "\n")
    common = ["--puntos", course_dir / "puntos.mat", "--datos", course_dir / "datos.txt",
              "--json"]
    rc, want, err = run(capsys, "trajectory", "--ensayo", course_dir / "ensayo.mat", "--acel",
                        course_dir / "acel.mat", *common)
    assert rc == 0, err
    rc, got, err = run(capsys, "trajectory", "--ensayo", tmp_path / "e.csv", "--acel",
                       tmp_path / "a.csv", *common)
    assert rc == 0, err
    # the CSV's arrays equal the .mat's by value but not in memory layout: BLAS may round
    # the last bits differently
    assert_same_tree(result_only(got), result_only(want))


def test_gap_reads_a_log_as_it_reads_its_import(capsys, tmp_path, files):
    """gap LOG --poses … gives the same report as gap on the imported ensayo.mat."""
    out = tmp_path / "g"
    _import(capsys, files["csv_no_gyro"], out, *POSES)
    nv = ["--noise-var", "0.0004,0.0004", "--json"]
    rc, direct, err = run(capsys, "gap", files["csv_no_gyro"], *POSES, *nv)
    assert rc == 0, err
    rc, imported, err = run(capsys, "gap", out / "ensayo.mat", *nv)
    assert rc == 0, err
    assert result_only(direct) == result_only(imported)


def test_label_column_with_poses_in_order_of_appearance(tmp_path):
    from calib.logs.reader import LogOptions

    rng = np.random.default_rng(8)
    labels = ["p1"] * 50 + ["-1"] * 10 + ["p2"] * 50 + ["-1"] * 10 + ["p3"] * 50
    ang = {"p1": 0.0, "p2": 1.0, "p3": 2.0, "-1": 0.5}
    th = np.array([ang[v] for v in labels])
    acc = np.c_[-9.8 * np.sin(th), -9.8 * np.cos(th)] + 0.01 * rng.standard_normal((170, 2))
    rows = [f"{lab};{x!r};{y!r}".replace(".", ",") for lab, (x, y) in
            zip(labels, acc.tolist(), strict=True)]
    path = _table(tmp_path / "l.csv", "pose;ax (m/s^2);ay (m/s^2)\n" + "\n".join(rows) + "\n")
    log = read_log(path, LogOptions(poses=(0.0, 1.0, 2.0)))
    assert log.n == 150 and np.array_equal(log.theta, np.repeat([0.0, 1.0, 2.0], 50))
    assert np.array_equal(log.pose, np.repeat([0, 1, 2], 50))


def test_mangled_logs_never_crash(capsys, tmp_path):
    """80 random edits (seeded) of a small valid CSV, plus binary junk and an empty file:
    each import either succeeds or fails with one error line and writes nothing."""
    rng = np.random.default_rng(21)
    base = fx.write_csv(tmp_path / "base.csv").read_text().splitlines()[:400]
    junk = "\n;,\t \"'#xeE+-.0123456789nainf"
    cases = [b"", bytes(rng.integers(0, 256, 300, dtype=np.uint8)), b"\x1f\x8b\x08junk"]
    for _ in range(80):
        text = list("\n".join(base) + "\n")
        for _ in range(int(rng.integers(1, 4))):
            i = int(rng.integers(0, len(text)))
            op = int(rng.integers(0, 3))
            if op == 0:
                del text[i]
            elif op == 1:
                text.insert(i, junk[int(rng.integers(0, len(junk)))])
            else:
                text[i] = junk[int(rng.integers(0, len(junk)))]
        cases.append("".join(text).encode())
    outcomes = set()
    for k, data in enumerate(cases):
        path = tmp_path / f"m{k}.csv"
        path.write_bytes(data)
        out = tmp_path / f"o{k}"
        rc, stdout, err = run(capsys, "import", path, "--out", out, "--allow-gaps")
        assert "Traceback" not in err
        if rc == 0:
            outcomes.add("read")
            continue
        assert rc == 2 and stdout == "" and not out.exists(), err
        lines = unwrap(err).splitlines()
        assert len(lines) == 1 and lines[0].startswith("tiltbench import: error: "), err
        outcomes.add("refused")
    assert outcomes == {"read", "refused"}

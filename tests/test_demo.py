"""`tiltbench demo`: runs end to end from a fresh directory, lists what it writes, and prints
the estimates `tiltbench calibrate --json` gives on the generated ensayo.mat."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from bench.cli import main
from bench.record import read_recording
from tests.checks import result_only

TILTBENCH = Path(sys.executable).parent / "tiltbench"


def run_cli(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    exe = [str(TILTBENCH)] if TILTBENCH.exists() else [sys.executable, "-m", "bench.cli"]
    return subprocess.run(exe + args, cwd=cwd, capture_output=True, text=True, timeout=300)


def listed_files(stdout: str, cwd: Path) -> list[Path]:
    block = stdout.split("Files written:", 1)[1].split("\n\n", 1)[0]
    out = []
    for line in block.strip().splitlines():
        m = re.match(r"\s*(\S+)\s+\(\d+ (?:B|KiB)\)$", line)
        assert m, line
        p = Path(m.group(1))
        out.append(p if p.is_absolute() else cwd / p)
    return out


def printed_estimates(stdout: str) -> dict[str, float]:
    rows = re.findall(r"^\s+(bias|scale)_([xy])\s+(?:m/s²|1)\s+(\S+)\s+(\S+)\s+(\S+)", stdout,
                      re.M)
    return {f"{p}_{a}": float(est) for p, a, _true, est, _std in rows}


@pytest.mark.slow
def test_demo_from_a_fresh_directory(tmp_path, capsys):
    """The README's first command (`make demo` = `tiltbench demo --out demo-out --force`)."""
    res = run_cli(["demo", "--out", "demo-out", "--force"], tmp_path)
    assert res.returncode == 0, res.stderr[-2000:]
    assert "[1/8]" in res.stderr and "done (" in res.stderr  # progress with elapsed time
    files = listed_files(res.stdout, tmp_path)
    names = {p.name for p in files}
    assert {"ensayo.mat", "acel.mat", "puntos.mat", "datos.txt", "truth.json", "demo.rrd",
            "report.md", "estimates.json", "trajectory.json", "validation.json",
            "calibration_x.png", "trajectory.png", "nmin.png"} <= names
    from bench.demo import FIGURE_NAMES
    assert {f"{n}.{f}" for n in FIGURE_NAMES for f in ("png", "svg")} <= names
    for p in files:
        assert p.exists() and p.stat().st_size > 0, p
    out = tmp_path / "demo-out"
    # the printed reproduce command names the final files, not the staging directory's
    assert f"tiltbench calibrate {Path('demo-out') / 'data' / 'ensayo.mat'} --datos" \
        in res.stdout
    assert ".tmp" not in res.stdout
    capsys.readouterr()
    assert main(["calibrate", str(out / "data" / "ensayo.mat"), "--datos",
                 str(out / "data" / "datos.txt"), "--json"]) == 0
    est = result_only(capsys.readouterr().out)  # the demo's file is the result, not the read
    assert json.loads((out / "estimates.json").read_text()) == est
    printed = printed_estimates(res.stdout)
    assert len(printed) == 4
    for a in "xy":
        for p in ("bias", "scale"):
            assert printed[f"{p}_{a}"] == pytest.approx(est["axes"][a][p], rel=5e-6, abs=1e-12)
    back = read_recording(out / "demo.rrd")
    assert back["estimates"] == est
    assert back["truth"] == json.loads((out / "data" / "truth.json").read_text())
    report = (out / "report.md").read_text(encoding="utf-8")
    for fig in ("calibration_x.png", "trajectory.png", "nmin.png"):
        assert f"figures/{fig}" in report
    # a second run without --force refuses before writing anything (exit 2)
    again = run_cli(["demo", "--out", "demo-out"], tmp_path)
    assert again.returncode == 2 and "--force" in again.stderr


def test_demo_library_truth_beside_estimates(tmp_path):
    """run_demo on a small budget (20 coverage runs, PNG figures only: both formats are the
    fresh-directory test's): decision, validation and recovered recording reported."""
    from bench.demo import run_demo

    res = run_demo(tmp_path / "d", seed=3, coverage_runs=20, formats=("png",))
    text = res.summary()
    assert res.recovered is True
    assert res.truth is not None and res.validation is not None
    assert f"true arrival point: {res.truth['answer']}" in text
    assert "Coverage at 95%:" in text and res.coverage["runs"] == 20
    # the fusion step: fixes of the default receiver on the same run, metres against tens
    f = res.fusion
    assert f["skipped"] is None and f["n_fixes"] == 60
    assert max(f["final_std"]) < 3.0 < 10.0 < min(f["dead_reckoning_std"])
    assert "smaller" in text and "## Fusion with position fixes" in (
        res.files["report.md"].read_text(encoding="utf-8"))
    for p in res.files.values():
        assert p.exists() and p.stat().st_size > 0


def test_demo_on_course_data(tmp_path, course_dir):
    res = run_cli(["demo", "--course-data", str(course_dir), "--out", "cd", "--quiet",
                   "--figures", "png"], tmp_path)
    assert res.returncode == 0, res.stderr[-2000:]
    assert "course files in" in res.stdout
    files = listed_files(res.stdout, tmp_path)
    assert {"demo.rrd", "report.md", "trajectory.png", "calibration_y.png"} <= {
        p.name for p in files}
    assert not (tmp_path / "cd" / "data").exists()  # course data read in place, not copied
    printed = printed_estimates(res.stdout)
    # the course answer (FreeMat 2009) to the digits it gives
    assert printed["scale_x"] == pytest.approx(-0.0301, abs=0.5e-4)
    assert printed["bias_x"] == pytest.approx(0.0767, abs=0.5e-4)
    assert read_recording(tmp_path / "cd" / "demo.rrd")["truth"] is None


def test_demo_json_is_one_object_and_steps_count_right(tmp_path, course_dir, capsys):
    out = tmp_path / "cd"
    assert main(["demo", "--course-data", str(course_dir), "--out", str(out), "--json",
                 "--figures", "png"]) == 0
    cap = capsys.readouterr()
    obj = json.loads(cap.out)  # one JSON object, nothing else on stdout
    assert obj["passed"] is True and obj["recovered"] is True and obj["answer"] is None
    assert obj["estimates"] == json.loads((out / "estimates.json").read_text())
    from calib.units import missing_units

    assert missing_units(obj) == []  # every number of the object has a unit (docs/units.md)
    for name in ("estimates.json", "trajectory.json"):
        assert missing_units(json.loads((out / name).read_text())) == [], name
    assert all(Path(p).exists() for p in obj["files"].values())
    # no truth.json, no generation: calibrate, figures, recording, report
    done = re.findall(r"\[(\d+)/(\d+)\] [^\n]*: done \(", cap.err)
    assert done == [(str(k), "5") for k in range(1, 6)]
    # no truth and no gps.mat: the fusion step says plainly it was skipped, and why
    assert "no gps.mat" in obj["fusion"]["skipped"]

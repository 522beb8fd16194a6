"""`tiltbench fuse` end to end: a generated course set with a receiver, fused, decided."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bench.cli import main
from tests.cli import run as _run
from tests.cli import unwrap


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
    assert rc == 2 and len(unwrap(err).splitlines()) == 1 and "none.mat" in err


def test_fuse_plot_shows_the_fused_region_smaller_than_dead_reckoning(capsys, course, tmp_path):
    png = tmp_path / "fuse.png"
    rc, out, _ = _run(capsys, "fuse", *_files(course), "--ensayo", course / "ensayo.mat",
                      "--plot", png)
    assert rc == 0 and png.stat().st_size > 0 and f"wrote: {png}" in out
    rc, _, err = _run(capsys, "fuse", *_files(course), "--ensayo", course / "ensayo.mat",
                      "--plot", png)
    assert rc == 2 and "--force" in err  # never overwritten without --force

    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon

    from bench.figures.fusion import fusion_figure
    from calib.calibration.tilt_plane import calibrate
    from calib.files.course import read_acel, read_datos, read_ensayo, read_gps, read_puntos
    from calib.fusion.linear import fuse
    from calib.vehicle.region import arrival_region
    from calib.vehicle.trajectory import compute_trajectory

    d = read_datos(course / "datos.txt")
    acel, fixes = read_acel(course / "acel.mat"), read_gps(course / "gps.mat")
    cal = calibrate(read_ensayo(course / "ensayo.mat"), d.noise_var, "ols")
    traj = compute_trajectory(acel, cal, d.p0, d.v0)
    region = arrival_region(traj, cal, read_puntos(course / "puntos.mat"), d.noise_var, 0.997)
    res = fuse(acel.t, acel.aerr, fixes.t_gps, fixes.pos, bias=cal.bias, scale=cal.scale,
               cal_cov=cal.cov, noise_var=d.noise_var, sigma_pos=3.0, p0=d.p0, v0=d.v0,
               p0_cov=0.0, v0_cov=0.0)
    fig = fusion_figure(traj, region, res, fixes.pos, 0.997, "D")
    polys = [p for p in fig.axes[0].patches if isinstance(p, Polygon)]
    areas = []
    for p in polys:
        x, y = p.get_xy().T
        areas.append(0.5 * abs(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1))))
    assert len(areas) == 2 and areas[1] < areas[0] / 20  # fused ≪ dead reckoning
    assert polys[1].get_zorder() > polys[0].get_zorder()  # drawn above, visible
    plt.close(fig)


def test_initial_uncertainty_options_widen_p0_and_are_printed(capsys, course):
    base = ["fuse", *_files(course), "--ensayo", course / "ensayo.mat"]
    rc, out, _ = _run(capsys, *base, "--p0-std", "2", "--v0-std", "0.5", "--json")
    assert rc == 0
    P0 = np.array(json.loads(out)["fusion"]["P0"])
    assert np.allclose(np.diag(P0)[:4], [4.0, 4.0, 0.25, 0.25])
    rc, out, _ = _run(capsys, *base)
    assert rc == 0 and "σ_p0 = 0 m" in out and "σ_v0 = 0 m/s" in out
    rc, _, err = _run(capsys, *base, "--p0-std", "-1")
    assert rc == 2 and "--p0-std" in err


def test_regenerating_without_gps_refuses_a_stale_gps_file(capsys, tmp_path):
    """A gps.mat of an earlier run must not stay beside a new set written without --gps."""
    out = tmp_path / "set"
    for kind in ("vehicle", "course"):
        d = out / kind
        assert main(["generate", kind, "--out", str(d), "--gps"]) == 0
        before = (d / "gps.mat").read_bytes()
        truth = (d / "truth.json").read_bytes()
        rc, _, err = _run(capsys, "generate", kind, "--out", d, "--force", "--seed", "5")
        assert rc == 2 and "gps.mat" in err and "--gps" in err
        assert (d / "gps.mat").read_bytes() == before and (d / "truth.json").read_bytes() == truth
        assert main(["generate", kind, "--out", str(d), "--force", "--seed", "5", "--gps"]) == 0
        assert (d / "gps.mat").read_bytes() != before


def test_fuse_rrd_holds_truth_fixes_fused_path_and_innovations(capsys, course, tmp_path):
    from bench.record import read_recording, recording_entities
    from bench.record.schema import documented

    rrd = tmp_path / "f.rrd"
    rc, out, _ = _run(capsys, "fuse", *_files(course), "--ensayo", course / "ensayo.mat",
                      "--rrd", rrd, "--json")
    assert rc == 0
    fused = json.loads(out)
    back = read_recording(rrd)
    assert back["truth"] == json.loads((course / "truth.json").read_text())
    rep = back["fusion_report"]
    assert rep["final_position"] == fused["fusion"]["final_position"]
    assert rep["decision"]["decision"] == fused["decision"]["decision"]
    assert max(rep["final_std"]) < min(rep["dead_reckoning_std"]) / 3
    ents = {str(e).lstrip("/") for e in recording_entities(rrd)}
    for e in ("vehicle/plane/path/true", "vehicle/plane/path/corrected", "vehicle/plane/fixes",
              "vehicle/plane/fused/path", "vehicle/plane/fused/ellipses",
              "fusion/innovation/x", "fusion/innovation_band/y/minus"):
        assert e in ents, e
    undocumented = [e for e in ents if documented(e) is None
                    or "fusion" not in documented(e).kinds]
    assert undocumented == []
    # refuses to overwrite the recording without --force
    rc, _, err = _run(capsys, "fuse", *_files(course), "--ensayo", course / "ensayo.mat",
                      "--rrd", rrd)
    assert rc == 2 and "--force" in err

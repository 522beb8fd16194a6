"""`tiltbench fuse` on each faulty input the issue-23 fuzzer reported (a generated seed-3 course
set with a receiver, linear and turning): every kind is corrected (a gated outlier), refused
in one line (exit 2: km, swapped columns, a 30 s time shift, a +50 m offset, a dead, °/s or
absurd gyro, a missing gyro, a heading of 1e6 rad or NaN, a malformed truth file) or
reported inconsistent (exit 3, no region) — never a confident answer tens of metres off."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
import scipy.io as sio

from bench.cli import main
from bench.cli.fuse import (
    CONSISTENCY_ALPHA,
    CONSISTENCY_ALPHA_MIN,
    EXIT_INCONSISTENT,
    GATE_ALPHA,
    NIS_WINDOW,
    NIS_WINDOW_MAX,
)
from calib.fusion import innovation_check
from calib.vehicle.arrival import NO_REGION
from tests.cli import one_line_error
from tests.cli import run as _run


def _make(tmp_path_factory, name: str, *extra: str):
    out = tmp_path_factory.mktemp(name) / "cs"
    assert main(["generate", "course", "--seed", "3", "--out", str(out), "--gps", *extra]) == 0
    return out


@pytest.fixture(scope="module")
def linear(tmp_path_factory):
    return _make(tmp_path_factory, "lin")


@pytest.fixture(scope="module")
def turning(tmp_path_factory):
    return _make(tmp_path_factory, "turn", "--turning")


def _variant(src, dst, gps=None, acel=None):
    """A copy of the set ``src`` in ``dst`` with gps.mat / acel.mat variables replaced
    (``None`` as a value deletes the variable)."""
    dst.mkdir(parents=True, exist_ok=True)
    for f in ("ensayo.mat", "puntos.mat", "datos.txt", "gps.mat", "acel.mat"):
        shutil.copy(src / f, dst / f)
    for name, changes in (("gps.mat", gps), ("acel.mat", acel)):
        if changes:
            m = {k: v for k, v in sio.loadmat(src / name).items() if not k.startswith("__")}
            for k, v in changes.items():
                if v is None:
                    m.pop(k)
                else:
                    m[k] = v
            sio.savemat(dst / name, m)
    return dst


def _args(d, *extra):
    return ["fuse", "--acel", d / "acel.mat", "--gps", d / "gps.mat", "--puntos",
            d / "puntos.mat", "--datos", d / "datos.txt", "--ensayo", d / "ensayo.mat", *extra]


def _gps(d):
    return sio.loadmat(d / "gps.mat")


def test_cli_defaults_are_the_library_ones():
    assert (GATE_ALPHA, CONSISTENCY_ALPHA, NIS_WINDOW, NIS_WINDOW_MAX,
            CONSISTENCY_ALPHA_MIN) == (
        innovation_check.GATE_ALPHA, innovation_check.CONSISTENCY_ALPHA,
        innovation_check.NIS_WINDOW, innovation_check.NIS_WINDOW_MAX,
        innovation_check.ALPHA_MIN)


def test_clean_run_is_consistent_and_decides_the_truth(capsys, linear):
    truth = json.loads((linear / "truth.json").read_text())
    rc, out, _ = _run(capsys, *_args(linear, "--json"))
    assert rc == 0
    d = json.loads(out)
    assert d["consistent"] is True and d["consistency"]["failing_windows"] == []
    assert d["decision"]["decision"] == truth["answer"]
    assert d["fusion"]["gate_alpha"] == GATE_ALPHA and d["fusion"]["units"]["gate_alpha"]


@pytest.mark.parametrize("kind, change, words", [
    ("km", lambda g: {"pos": g["pos"] / 1000.0}, ("'pos'", "km", "1000")),
    ("swap", lambda g: {"pos": g["pos"][:, ::-1]}, ("'pos'", "swapped")),
    ("shift", lambda g: {"t_gps": g["t_gps"] + 30.0}, ("'t_gps'", "late", "subtract")),
    ("offset", lambda g: {"pos": g["pos"] + [50.0, 0.0]}, ("'pos'", "offset", "subtract")),
])
def test_unit_axis_time_and_offset_mistakes_are_one_line(capsys, linear, tmp_path, kind,
                                                         change, words):
    d = _variant(linear, tmp_path / kind, gps=change(_gps(linear)))
    line = one_line_error(capsys, *_args(d))
    assert str(d / "gps.mat") in line
    for w in words:
        assert w in line, line
    if kind == "shift":  # the lag found is the shift, to a fraction of the 1 s fix interval
        tau = float(line.split("looks ")[1].split(" s")[0])
        assert abs(tau - 30.0) < 1.0


@pytest.mark.slow  # three fused runs: ~14 s on the 2-core machine
def test_one_200_m_outlier_is_gated_and_the_answer_kept(capsys, linear, tmp_path):
    g = _gps(linear)
    pos = g["pos"].copy()
    pos[30] += [200.0, 0.0]
    d = _variant(linear, tmp_path / "outlier", gps={"pos": pos})
    rc, out, _ = _run(capsys, *_args(d, "--json"))
    assert rc == 0
    res = json.loads(out)
    assert res["consistent"] is True and res["fusion"]["fixes_rejected"] == 1
    assert res["fusion"]["fix_used"][30] is False
    clean = json.loads(_run(capsys, *_args(linear, "--json"))[1])
    assert res["decision"]["decision"] == clean["decision"]["decision"]
    end, ref = (np.array(r["fusion"]["final_position"]) for r in (res, clean))
    sd = np.sqrt(np.diag(np.array(res["fusion"]["final_position_cov"])))
    assert np.all(np.abs(end - ref) < 3 * sd)
    rc, out, _ = _run(capsys, *_args(d))
    assert rc == 0 and "1 of 60 fixes rejected" in out and "(1 rejected by the gate)" in out


def test_a_small_offset_is_inconsistent_exit_3_and_no_region(capsys, linear, tmp_path,
                                                             monkeypatch):
    """+10 m passes the free-run check (the dead reckoning drifts that much) but not the
    windowed NIS: the result is printed with no region and exit 3; the figure draws no fused
    region, says so in its title and circles the rejected fixes."""
    from matplotlib.patches import Polygon

    import bench.figures.fusion as fig_mod

    figs = []
    real_save = fig_mod.save_figure

    def keep(fig, *a, **k):
        figs.append((fig.axes[0].get_title(), fig.axes[0].get_legend_handles_labels()[1],
                     sum(isinstance(p, Polygon) for p in fig.axes[0].patches)))
        return real_save(fig, *a, **k)

    monkeypatch.setattr(fig_mod, "save_figure", keep)
    d = _variant(linear, tmp_path / "off10", gps={"pos": _gps(linear)["pos"] + [10.0, 0.0]})
    rc, out, _ = _run(capsys, *_args(d, "--json"))
    assert rc == EXIT_INCONSISTENT == 3
    res = json.loads(out)
    assert res["consistent"] is False and res["consistency"]["failing_windows"]
    assert res["decision"]["decision"] is None and res["decision"]["reason"] == NO_REGION
    assert res["decision"]["mahalanobis"] == {}
    png = tmp_path / "f.png"
    rc, out, _ = _run(capsys, *_args(d, "--plot", png))
    assert rc == 3 and png.stat().st_size > 0
    assert "INCONSISTENT" in out and NO_REGION in out and "only" not in out
    title, labels, polygons = figs[-1]
    assert "INCONSISTENT" in title and "no region" in title
    assert polygons == 1  # the dead reckoning's region only
    n_rej = len(res["consistency"]["rejected"])
    assert n_rej > 0 and f"rejected by the gate ({n_rej})" in labels


def test_bad_doubt_options_are_one_line(capsys, linear):
    for opt, val in (("--gate-alpha", "1"), ("--gate-alpha", "nan"),
                     ("--consistency-alpha", "0"), ("--nis-window", "0"),
                     ("--nis-window", "1e6"), ("--consistency-alpha", "1e-300")):
        assert opt in one_line_error(capsys, *_args(linear, opt, val))


def test_malformed_truth_file_is_one_line(capsys, linear, tmp_path):
    for text, key in (("[1, 2]", "JSON object"), ('{"vehicle": 3}', "'vehicle'"),
                      ('{"vehicle": {"trajectory": {"samples": {"pos": "abc"}}}}', "pos"),
                      ('{"vehicle": {"trajectory": {"samples": {"pos": [1, 2, 3]}}}}', "n×2"),
                      ("{not json", "JSON")):
        bad = tmp_path / "truth.json"
        bad.write_text(text)
        line = one_line_error(capsys, *_args(linear, "--truth", bad, "--plot",
                                             tmp_path / "x.png"))
        assert str(bad) in line and key in line, line
        assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("kind, acel, words", [
    ("zeros", lambda a: {"gyro": np.zeros_like(a["gyro"])}, ("'gyro'", "constant")),
    ("degrees", lambda a: {"gyro": np.degrees(a["gyro"])}, ("'gyro'", "°/s", "π/180")),
    ("absurd", lambda a: {"gyro": a["gyro"] * 1e4}, ("'gyro'", "rad/s", "full scale")),
])
def test_an_implausible_gyro_is_refused(capsys, turning, tmp_path, kind, acel, words):
    d = _variant(turning, tmp_path / kind, acel=acel(sio.loadmat(turning / "acel.mat")))
    line = one_line_error(capsys, *_args(d))
    assert str(d / "acel.mat") in line
    for w in words:
        assert w in line, line


def test_a_turning_run_without_its_gyro_is_refused(capsys, turning, tmp_path):
    d = _variant(turning, tmp_path / "nogyro", acel={"gyro": None})
    line = one_line_error(capsys, *_args(d))
    assert "disagree with the dead-reckoned path" in line and "'gyro'" in line


def test_initial_heading_is_checked(capsys, turning):
    assert "--psi0" in one_line_error(capsys, *_args(turning, "--psi0", "1e6"))
    assert "--psi0" in one_line_error(capsys, *_args(turning, "--psi0", "nan"))
    assert "degrees?" in one_line_error(capsys, *_args(turning, "--psi0", "90"))
    # a wrong heading within a turn: the fixes match the path turned back by about -1 rad
    line = one_line_error(capsys, *_args(turning, "--psi0", "1.0"))
    assert "psi0" in line and "looks off" in line
    delta = float(line.split("turned by ")[1].split(" rad")[0])
    assert abs(delta + 1.0) < 0.05  # the true initial heading is 0 (the bench's)


def test_trajectory_and_nmin_refuse_a_turning_run(capsys, turning):
    files = ["--acel", turning / "acel.mat", "--puntos", turning / "puntos.mat", "--datos",
             turning / "datos.txt", "--ensayo", turning / "ensayo.mat"]
    for cmd in ("trajectory", "nmin"):
        line = one_line_error(capsys, cmd, *files)
        assert "turning" in line and "'gyro'" in line and "fuse" in line

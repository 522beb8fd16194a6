"""Rerun recordings: truth and estimates come back exactly; files verify; entities documented."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rerun.chunk import RrdReader

from bench.cli import main
from bench.record import (
    ENTITY_DOCS,
    documented,
    entity_table_markdown,
    log_tree,
    open_recording,
    read_blueprint,
    read_recording,
    record_calibration,
    record_course,
    record_series,
    recording_entities,
)
from bench.tilt import CalibrationConfig, ThetaDesign, generate_calibration, write_calibration
from calib.calibration.tilt_plane import calibrate
from calib.files.course import read_ensayo
from tests.checks import result_only

REPO = Path(__file__).resolve().parents[1]
RERUN = shutil.which("rerun", path=str(Path(__import__("sys").executable).parent))



def _assert_documented(entities, kinds: set[str]) -> None:
    """Every entity is in docs/recordings.md, documented for one of ``kinds``."""
    for e in entities:
        d = documented(e)
        assert d is not None, f"{e} is not in docs/recordings.md"
        assert kinds & set(d.kinds), f"{e} documented for {d.kinds} only"

def _entity_index(path) -> dict[str, tuple[set, set]]:
    """Entity → (timelines, columns) over all chunks of the recording."""
    out: dict[str, tuple[set, set]] = {}
    for ch in RrdReader(str(path)).stream().to_chunks():
        tls, cols = out.setdefault(ch.entity_path.lstrip("/"), (set(), set()))
        tls.update(ch.timeline_names)
        cols.update(ch.to_record_batch().schema.names)
    return out


def _query_matches(expr: str, origin: str, entities) -> set[str]:
    expr = expr.replace("$origin", origin).removeprefix("+").strip()
    assert not expr.startswith("-"), expr
    if expr.endswith("/**"):
        root = expr[:-3]
        return {e for e in entities if e == root or e.startswith(root + "/")}
    return {e for e in entities if e == expr}


def _assert_blueprint_shows_content(path) -> dict:
    """What the viewer needs to show every view on open, checked on the stored blueprint:
    collapsed time panel that does not play, on a timeline of the recording; every query
    names existing entities; text views show one document; time-series views span the whole
    timeline and plot data of the active timeline; 2-D views have bounds and show static data
    or data of the active timeline; no JSON tree in any view."""
    bp = read_blueprint(path)
    idx = _entity_index(path)
    tp = bp["time_panel"]
    assert tp.get("state") == "collapsed", tp
    # not playing: paused, or following = the cursor at the end (a vehicle run at its arrival)
    assert tp.get("play_state") == ("following" if tp.get("timeline") == "time" else "paused"), tp
    active = tp["timeline"]
    assert any(active in tls for tls, _ in idx.values()), active
    assert bp["views"]
    for v in bp["views"]:
        shown: set[str] = set()
        for expr in v["contents"]:
            hit = _query_matches(expr, v["origin"], idx)
            assert hit, f"{v['name']}: {expr} matches no entity"
            shown |= hit
        assert not any(e.split("/", 1)[0] in ("truth", "estimate", "trajectory", "gap_report")
                       for e in shown), v["name"]
        data = {e for e in shown if any(":" in c for c in idx[e][1])}
        if v["class"] == "TextDocument":
            texts = [e for e in shown if "TextDocument:text" in idx[e][1]]
            assert len(texts) == 1, (v["name"], texts)
        elif v["class"] == "TimeSeries":
            assert v["time_axis"] == ("Infinite", "Infinite"), v["name"]
            series = [e for e in data if "Scalars:scalars" in idx[e][1]]
            assert series, v["name"]
            assert all(active in idx[e][0] for e in series), (v["name"], active)
        elif v["class"] == "2D":
            assert v["visual_bounds"], v["name"]
            assert data and all(not idx[e][0] or active in idx[e][0] for e in data), v["name"]
        else:
            raise AssertionError(f"unexpected view class {v['class']}")
    return bp


def _shown(view: dict, path) -> set[str]:
    """Entities a blueprint view shows."""
    idx = _entity_index(path)
    return set().union(*(_query_matches(e, view["origin"], idx) for e in view["contents"]))


def _labels(path, entity: str) -> list[str]:
    chunk = next(c for c in RrdReader(str(path)).stream().to_chunks()
                 if c.entity_path == entity)
    return chunk.to_record_batch().column("Points2D:labels").to_pylist()[-1]


def _assert_plane_has_scale(path, bp: dict) -> None:
    """The vehicle plane view shows its grid with values in m and the axis names."""
    plane = next(v for v in bp["views"] if v["origin"] == "vehicle" and v["class"] == "2D")
    assert {"vehicle/plane/grid", "vehicle/plane/grid/labels"} <= _shown(plane, path)
    labels = _labels(path, "/vehicle/plane/grid/labels")
    assert "x (m)" in labels and "y (m)" in labels
    assert sum(1 for t in labels if t.lstrip("-").replace(".", "").isdigit()) >= 4


def _component(path, entity: str, name: str):
    chunk = next(c for c in RrdReader(str(path)).stream().to_chunks()
                 if c.entity_path == entity)
    return chunk.to_record_batch().column(name).to_pylist()[-1][-1]


def _assert_means_over_samples(path, plots: list[str]) -> None:
    """In each static plot the raw samples are translucent (alpha < 255) and drawn under the
    binned mean (a larger draw order)."""
    for p in plots:
        samples = next(f"{p}/{k}" for k in ("residual", "measured")
                       if f"{p}/{k}" in recording_entities(path))
        assert _component(path, samples, "Points2D:colors") & 0xFF < 255, samples
        assert (_component(path, f"{p}/mean", "LineStrips2D:draw_order")
                > _component(path, samples, "Points2D:draw_order")), p


def _cli_json(capsys, argv: list[str]) -> dict:
    capsys.readouterr()
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def _small_run(seed: int = 3, count: int = 801):
    cfg = CalibrationConfig(theta=ThetaDesign(kind="range", count=count))
    return generate_calibration(cfg, seed)


def test_calibration_roundtrip_equals_truth_and_calibrate_json(tmp_path, capsys):
    """generate → calibrate → record → read back == truth.json and `calibrate --json`."""
    run = _small_run()
    paths = write_calibration(run, tmp_path / "set")
    truth = json.loads(Path(paths["truth"]).read_text())
    est_cli = _cli_json(capsys, ["calibrate", paths["ensayo"], "--noise-var", "0.25,0.64",
                                 "--json"])
    ensayo = read_ensayo(paths["ensayo"])
    cal = calibrate(ensayo, [0.25, 0.64])
    rrd = record_calibration(cal, ensayo, tmp_path / "cal.rrd", truth=truth)
    back = read_recording(rrd)
    assert back["truth"] == truth
    assert back["estimates"] == result_only(est_cli)  # the recording holds the result
    assert back["trajectory"] is None


def test_generate_calibration_rrd_gives_truth_json(tmp_path, capsys):
    """`tiltbench generate calibration --rrd` records exactly what truth.json holds."""
    out = tmp_path / "gen"
    info = _cli_json(capsys, ["generate", "calibration", "--count", "301", "--seed", "11",
                              "--out", str(out), "--rrd", str(tmp_path / "t.rrd"), "--json"])
    truth = json.loads((out / "truth.json").read_text())
    back = read_recording(info["files"]["rrd"])
    assert back["truth"] == truth
    assert back["estimates"] is None
    _assert_documented(recording_entities(tmp_path / "t.rrd"), {"truth-run"})
    _assert_blueprint_shows_content(tmp_path / "t.rrd")


def test_calibrate_rrd_option(tmp_path, capsys):
    """`tiltbench calibrate --rrd` writes a recording whose estimates equal --json."""
    run = _small_run(5, 401)
    paths = write_calibration(run, tmp_path)
    rrd = tmp_path / "c.rrd"
    est = _cli_json(capsys, ["calibrate", paths["ensayo"], "--json", "--rrd", str(rrd)])
    assert read_recording(rrd)["estimates"] == result_only(est)
    bp = _assert_blueprint_shows_content(rrd)
    assert bp["time_panel"]["timeline"] == "theta_urad"
    # θ plots are static 2-D plots (θ in rad), three per axis, plus the estimates text
    assert sorted(v["class"] for v in bp["views"]) == ["2D"] * 6 + ["TextDocument"]
    # refuses to overwrite without --force (exit 2), replaces with it
    capsys.readouterr()
    assert main(["calibrate", paths["ensayo"], "--json", "--rrd", str(rrd)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["calibrate", paths["ensayo"], "--json", "--rrd", str(rrd), "--force"]) == 0


@pytest.fixture(scope="module")
def course_set(tmp_path_factory):
    """A generated course set on disk with its analysis (as `tiltbench demo` makes it)."""
    from bench.course import generate_course
    from bench.demo import analyze_course_dir

    d = tmp_path_factory.mktemp("course")
    course = generate_course(d, seed=4)
    return d, course, analyze_course_dir(d)


def test_course_set_roundtrip(course_set, tmp_path, capsys):
    """Course set: truth.json, `calibrate --json` and `trajectory --json` come back exactly."""
    d, course, ana = course_set
    truth = json.loads((d / "truth.json").read_text())
    rrd = record_course(tmp_path / "course.rrd", cal=ana.cal, ensayo=ana.ensayo, traj=ana.traj,
                        region=ana.region, truth=truth, true_path=course.vehicle.truth.pos,
                        true_acc=course.vehicle.truth.acc, tree=ana.trajectory_json())
    back = read_recording(rrd)
    assert back["truth"] == truth
    est = _cli_json(capsys, ["calibrate", str(d / "ensayo.mat"), "--datos",
                             str(d / "datos.txt"), "--json"])
    assert back["estimates"] == result_only(est)
    traj = _cli_json(capsys, ["trajectory", "--ensayo", str(d / "ensayo.mat"), "--acel",
                              str(d / "acel.mat"), "--puntos", str(d / "puntos.mat"),
                              "--datos", str(d / "datos.txt"), "--level",
                              str(ana.region.level), "--json"])
    assert back["trajectory"] == result_only(traj)
    # the seed is an int, every number bit-exact (dict equality above compares floats with ==)
    assert isinstance(back["truth"]["seed"], int)
    # CLI reader gives the same object
    assert _cli_json(capsys, ["record", "read", str(rrd), "--json"]) == json.loads(
        json.dumps(back))


@pytest.fixture(scope="module")
def course_data_rrd(course_dir, tmp_path_factory):
    from bench.demo import analyze_course_dir

    ana = analyze_course_dir(course_dir)
    path = tmp_path_factory.mktemp("rrd") / "course-data.rrd"
    record_course(path, cal=ana.cal, ensayo=ana.ensayo, traj=ana.traj, region=ana.region,
                  tree=ana.trajectory_json())
    return path, ana


def test_course_data_recording_loads_and_verifies(course_data_rrd):
    path, ana = course_data_rrd
    reader = RrdReader(str(path))
    assert len(reader.recordings()) == 1
    assert len(reader.blueprints()) == 1  # the default layout is in the file
    chunks = reader.stream().to_chunks()
    assert sum(c.num_rows for c in chunks) > ana.ensayo.n  # the data, not just metadata
    assert RERUN is not None, "the rerun binary should sit beside the Python interpreter"
    res = subprocess.run([RERUN, "rrd", "verify", str(path)], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "without error" in (res.stdout + res.stderr)


def test_course_data_entities_are_the_documented_ones(course_data_rrd):
    """Every entity matches a row of the table; every non-optional row is present."""
    path, _ = course_data_rrd
    ents = recording_entities(path)
    kinds = {"calibration", "vehicle"}
    _assert_documented(ents, kinds)
    for d in ENTITY_DOCS:
        if d.optional or not (kinds & set(d.kinds)):
            continue
        assert any(d.regex().match(e.lstrip("/")) for e in ents), f"{d.pattern} missing"
    assert not any(e.lstrip("/").startswith("truth") for e in ents)  # course data: no truth
    back = read_recording(path)
    assert back["truth"] is None and back["estimates"]["axes"]["x"]["n"] == 20001


def test_course_data_blueprint_shows_every_view_on_open(course_data_rrd):
    """Calibration and vehicle in one file: the active timeline is the vehicle's, so the
    calibration tab must be static 2-D plots (θ time series would be empty)."""
    path, _ = course_data_rrd
    bp = _assert_blueprint_shows_content(path)
    assert bp["time_panel"]["timeline"] == "time"
    cal = [v for v in bp["views"] if v["origin"].startswith("calibration/")]
    assert len(cal) == 6 and all(v["class"] == "2D" for v in cal)
    assert {v["origin"] for v in bp["views"] if v["class"] == "TextDocument"} == {
        "summary/decision", "summary/parameters"}
    _assert_plane_has_scale(path, bp)
    _assert_means_over_samples(path, [f"/calibration/{a}/{k}" for a in "xy"
                                      for k in ("residual_plot", "vs_ar")])
    for a in "xy":  # the axes are named with their units (θ in rad)
        assert "θ (rad)" in _labels(path, f"/calibration/{a}/theta_plot/axes/labels")
        assert "A_r (m/s²)" in _labels(path, f"/calibration/{a}/vs_ar/axes/labels")


def test_docs_table_is_generated_from_entity_docs():
    text = (REPO / "docs" / "recordings.md").read_text(encoding="utf-8")
    start, end = "<!-- entity-table:start -->", "<!-- entity-table:end -->"
    table = text[text.index(start) + len(start):text.index(end)].strip()
    assert table == entity_table_markdown()


def test_refuses_overwrite_and_leaves_no_partial_file(tmp_path):
    target = tmp_path / "x.rrd"
    target.write_bytes(b"old")
    with pytest.raises(FileExistsError):
        with open_recording(target) as rec:
            log_tree(rec, "truth", {"a": 1.0})
    assert target.read_bytes() == b"old"
    with pytest.raises(TypeError):
        with open_recording(tmp_path / "y.rrd") as rec:
            log_tree(rec, "truth", {"a": {1, 2}})  # a set is not JSON
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.rrd"]


def test_two_recordings_in_one_process_stay_separate(tmp_path):
    a, b = tmp_path / "a.rrd", tmp_path / "b.rrd"
    with open_recording(a) as ra, open_recording(b) as rb:
        log_tree(ra, "truth", {"who": "a", "v": 1.5})
        log_tree(rb, "truth", {"who": "b", "v": -2.5})
        log_tree(ra, "estimate", {"n": 3})
    assert read_recording(a)["truth"] == {"who": "a", "v": 1.5}
    assert read_recording(a)["estimates"] == {"n": 3}
    assert read_recording(b)["truth"] == {"who": "b", "v": -2.5}
    assert read_recording(b)["estimates"] is None


def test_record_series_values_are_exact(tmp_path):
    rng = np.random.default_rng(1)
    before, after = rng.normal(size=500), rng.normal(size=500) * 0.1
    theta = np.linspace(0, 2 * np.pi, 500)
    path = record_series(tmp_path / "s.rrd",
                         {"gap/x/residual/before": before, "gap/x/residual/after": after},
                         index=np.round(theta * 1e6).astype(int), timeline="theta_urad",
                         bands={"gap/x/residual/before": 0.5},
                         trees={"gap": {"effect": "misalignment", "delta": 0.0123}})
    got = {}
    for ch in RrdReader(str(path)).stream().to_chunks():
        rb = ch.to_record_batch()
        if "Scalars:scalars" in rb.schema.names and "theta_urad" in rb.schema.names:
            got[ch.entity_path] = np.array([v[0] for v in rb.column("Scalars:scalars")
                                            .to_pylist()])
    assert np.array_equal(got["/gap/x/residual/before"], before)
    assert np.array_equal(got["/gap/x/residual/after"], after)
    assert np.array_equal(got["/gap/x/residual/before_band/plus"], [0.5, 0.5])
    assert read_recording(path)["gap"] == {"effect": "misalignment", "delta": 0.0123}


JSON_LEAF = (st.none() | st.booleans() | st.integers(-2**63, 2**64)
             | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=12))
JSON_TREE = st.recursive(JSON_LEAF, lambda kids: st.lists(kids, max_size=4)
                         | st.dictionaries(st.text(max_size=8), kids, max_size=4), max_leaves=12)


@settings(max_examples=25, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(tree=st.dictionaries(st.text(max_size=8), JSON_TREE, max_size=5))
def test_any_json_tree_roundtrips(tmp_path, tree):
    """Keys with '/', spaces or unicode, empty containers, None, bools, 64-bit ints, -0.0."""
    path = tmp_path / "h.rrd"
    with open_recording(path, force=True) as rec:
        log_tree(rec, "truth", tree)
    back = read_recording(path)["truth"]
    assert back == tree
    assert json.dumps(back, sort_keys=True) == json.dumps(tree, sort_keys=True)


def test_special_floats_roundtrip(tmp_path):
    tree = {"nan": float("nan"), "neg_zero": -0.0, "tiny": 5e-324, "big": 1.7976931348623157e308}
    path = tmp_path / "f.rrd"
    with open_recording(path) as rec:
        log_tree(rec, "estimate", tree)
    back = read_recording(path)["estimates"]
    assert math.isnan(back["nan"])
    assert math.copysign(1.0, back["neg_zero"]) == -1.0
    assert back["tiny"] == 5e-324 and back["big"] == tree["big"]


def test_record_trajectory_vehicle_only(course_data_rrd, tmp_path):
    """The vehicle recording (future `trajectory --rrd`): trajectory tree back, documented."""
    from bench.record import record_trajectory

    _, ana = course_data_rrd
    tree = ana.trajectory_json()
    path = record_trajectory(ana.traj, ana.region, ana.cal, tmp_path / "v.rrd", tree=tree)
    back = read_recording(path)
    assert back["trajectory"] == json.loads(json.dumps(tree))
    assert back["estimates"] == json.loads(json.dumps(ana.cal.to_dict()))
    _assert_documented(recording_entities(path), {"vehicle"})
    bp = _assert_blueprint_shows_content(path)
    _assert_plane_has_scale(path, bp)
    assert not any(v["origin"].startswith("calibration") for v in bp["views"])


def test_gap_recording_entities_are_documented(tmp_path, capsys):
    """The discrepancy workflow's recording (bench/gap/recording.py) uses the documented paths."""
    run = _small_run(8, 1001)
    paths = write_calibration(run, tmp_path)
    rrd = tmp_path / "gap.rrd"
    assert main(["gap", paths["ensayo"], "--noise-var", "0.25,0.64", "--rrd", str(rrd)]) == 0
    capsys.readouterr()
    ents = recording_entities(rrd)
    assert ents
    _assert_documented(ents, {"gap"})
    for d in ENTITY_DOCS:
        if "gap" in d.kinds and not d.optional:
            assert any(d.regex().match(e.lstrip("/")) for e in ents), d.pattern
    bp = _assert_blueprint_shows_content(rrd)
    # θ in rad: static 2-D plots with frame, tick values and axis names (not µrad indices);
    # and each axis in time order (an untimed run: against the sample index)
    assert sorted(v["class"] for v in bp["views"]) == ["2D"] * 6 + ["TextDocument"]
    for v in bp["views"]:
        if v["class"] == "2D":
            assert ("θ (rad)" in v["name"]) != ("vs sample (time order)" in v["name"]), v
            assert any(e.endswith("/axes/labels") for e in _shown(v, rrd)), v["name"]
    _assert_means_over_samples(rrd, [f"/gap/{a}/plot_{w}" for a in "xy"
                                     for w in ("before", "after", "time")])
    for a in "xy":
        assert "sample" in _labels(rrd, f"/gap/{a}/plot_time/axes/labels")
        assert f"/gap/{a}/plot_time/mean_after" in ents
    # the effects text has no image: gap.png is a path relative to the report directory
    chunk = next(c for c in RrdReader(str(rrd)).stream().to_chunks()
                 if c.entity_path == "/gap/effects")
    text = chunk.to_record_batch().column("TextDocument:text").to_pylist()[-1][-1]
    assert "# Discrepancy workflow" in text and "![" not in text


@pytest.mark.parametrize("kind", ["vehicle", "course"])
def test_generate_vehicle_and_course_rrd_give_truth_json(tmp_path, capsys, kind):
    """`tiltbench generate vehicle|course --rrd` records exactly what truth.json holds, with
    only documented truth-run entities."""
    out = tmp_path / "gen"
    extra = ["--count", "301"] if kind == "course" else []
    info = _cli_json(capsys, ["generate", kind, "--seed", "4", "--out", str(out), *extra,
                              "--rrd", str(tmp_path / "t.rrd"), "--json"])
    truth = json.loads((out / "truth.json").read_text())
    back = read_recording(info["files"]["rrd"])
    assert back["truth"] == truth
    assert back["estimates"] is None
    ents = recording_entities(tmp_path / "t.rrd")
    assert "/vehicle/plane/path/true" in ents
    assert ("/vehicle/plane/candidates" in ents) == (kind == "course")
    _assert_documented(ents, {"truth-run"})
    bp = _assert_blueprint_shows_content(tmp_path / "t.rrd")
    _assert_plane_has_scale(tmp_path / "t.rrd", bp)
    assert any(v["origin"].startswith("calibration") for v in bp["views"]) == (kind == "course")


@pytest.fixture(scope="module")
def gps_course(tmp_path_factory):
    """The seed-3 course set with a receiver (gps.mat), as tests/test_fuse_faults.py."""
    out = tmp_path_factory.mktemp("rrdfuse") / "cs"
    assert main(["generate", "course", "--seed", "3", "--out", str(out), "--gps"]) == 0
    return out


def _fuse_variant(src: Path, dst: Path, change) -> Path:
    """A copy of the set with gps.mat's ``pos`` replaced by ``change(pos)``."""
    import scipy.io as sio

    dst.mkdir()
    for f in ("ensayo.mat", "puntos.mat", "datos.txt", "acel.mat", "truth.json"):
        shutil.copy(src / f, dst / f)
    m = {k: v for k, v in sio.loadmat(src / "gps.mat").items() if not k.startswith("__")}
    m["pos"] = change(np.array(m["pos"], float))
    sio.savemat(dst / "gps.mat", m)
    return dst


def _fuse_rrd(capsys, d: Path, rrd: Path) -> tuple[int, dict]:
    rc = main(["fuse", "--acel", str(d / "acel.mat"), "--gps", str(d / "gps.mat"),
               "--puntos", str(d / "puntos.mat"), "--datos", str(d / "datos.txt"),
               "--ensayo", str(d / "ensayo.mat"), "--rrd", str(rrd), "--json"])
    return rc, json.loads(capsys.readouterr().out)


def _series(path, entity: str) -> tuple[np.ndarray, np.ndarray]:
    """(time s, value) of a scalar series logged with send_columns."""
    t, v = [], []
    for c in RrdReader(str(path)).stream().to_chunks():
        b = c.to_record_batch()
        if c.entity_path == entity and "Scalars:scalars" in b.schema.names:
            t += [x.total_seconds() for x in b.column("time").to_pylist()]
            v += [x[0] for x in b.column("Scalars:scalars").to_pylist()]
    return np.array(t), np.array(v)


def _points(path, entity: str) -> np.ndarray:
    """The (n, 2) positions of a static Points2D entity."""
    chunk = next(c for c in RrdReader(str(path)).stream().to_chunks()
                 if c.entity_path == entity)
    return np.array(chunk.to_record_batch().column("Points2D:positions").to_pylist()[-1],
                    float).reshape(-1, 2)


def test_fuse_rrd_marks_the_one_rejected_outlier_fix(gps_course, tmp_path, capsys):
    """One fix moved 200 m (σ = 3 m, NIS in the thousands against a gate of 13.8): the
    recording holds exactly that fix as `rejected_fixes`, at its position and time, with its
    NIS as label and scalar above the gate; `fixes` holds the 59 others; the run stays
    consistent with its fused region; the numbers read back equal `fuse --json`'s."""
    import scipy.io as sio

    k = 30

    def outlier(p):
        p[k] += [200.0, 0.0]
        return p

    d = _fuse_variant(gps_course, tmp_path / "outlier", outlier)
    rrd = tmp_path / "o.rrd"
    rc, out = _fuse_rrd(capsys, d, rrd)
    assert rc == 0 and out["consistent"] and out["consistency"]["rejected"] == [k]
    g = sio.loadmat(d / "gps.mat")
    t0 = float(np.ravel(sio.loadmat(d / "acel.mat")["t"])[0])
    t_fix = float(np.ravel(g["t_gps"])[k]) - t0
    ents = recording_entities(rrd)
    _assert_documented(ents, {"fusion"})
    assert {"/vehicle/plane/rejected_fixes", "/fusion/nis/rejected", "/fusion/nis/gate",
            "/vehicle/plane/fused/arrival", "/vehicle/plane/fused/ellipses"} <= set(ents)
    assert "/fusion/window_nis/failing" not in ents
    rejected = _points(rrd, "/vehicle/plane/rejected_fixes")
    assert rejected.shape == (1, 2)
    np.testing.assert_allclose(rejected[0], g["pos"][k], atol=1e-3)  # float32 drawing
    assert _points(rrd, "/vehicle/plane/fixes").shape == (59, 2)
    tr, nis = _series(rrd, "/fusion/nis/rejected")
    gate = out["consistency"]["gate"]
    assert tr.shape == (1,) and abs(tr[0] - t_fix) < 1e-6
    assert nis[0] > 100 * gate
    assert f"rejected at {t_fix:.4g} s: NIS {nis[0]:.0f}" in _labels(
        rrd, "/vehicle/plane/rejected_fixes")
    tu, _ = _series(rrd, "/fusion/nis/used")
    assert tu.size == 59 and not np.any(np.isclose(tu, t_fix))
    assert _component(rrd, "/summary/consistency", "TextDocument:text").startswith(
        "**consistent:")
    back = read_recording(rrd)["fusion_report"]
    assert back["consistent"] is True and back["consistency"] == out["consistency"]
    assert back["final_position"] == out["fusion"]["final_position"]
    plane = next(v for v in _assert_blueprint_shows_content(rrd)["views"]
                 if v["origin"] == "vehicle")
    assert "1 rejected by the gate red" in plane["name"]
    assert "vehicle/plane/rejected_fixes" in _shown(plane, rrd)


def test_fuse_rrd_of_an_inconsistent_run_has_the_status_and_no_fused_region(gps_course,
                                                                            tmp_path, capsys):
    """Every fix +10 m in x passes the dead-reckoning check but the windowed NIS test fails
    (docs/fusion.md's table, exit 3): the recording says INCONSISTENT (status text, decision
    text, view names), draws no fused region, marks the failing window above its band, and
    `record read` gives back the truth and `consistent: false`."""
    d = _fuse_variant(gps_course, tmp_path / "off10", lambda p: p + [10.0, 0.0])
    rrd = tmp_path / "i.rrd"
    rc, out = _fuse_rrd(capsys, d, rrd)
    assert rc == 3 and out["consistent"] is False
    ents = set(recording_entities(rrd))
    _assert_documented(ents, {"fusion"})
    assert not {"/vehicle/plane/fused/arrival", "/vehicle/plane/fused/ellipses"} & ents
    assert "/vehicle/plane/fused/path" in ents  # the path is shown, its region is not
    status = _component(rrd, "/summary/consistency", "TextDocument:text")
    assert status.startswith("**INCONSISTENT:") and "No fused region" in status
    decision = _component(rrd, "/summary/decision", "TextDocument:text")
    assert decision.startswith("### INCONSISTENT:") and "Fused 99.7% ellipse" not in decision
    assert "### Fused arrival: none" in decision and "| high |" in decision
    failing = out["consistency"]["failing_windows"]
    tf, sf = _series(rrd, "/fusion/window_nis/failing")
    assert sf.size == len(failing) >= 1
    np.testing.assert_array_equal(sf, [w["nis_sum"] for w in failing])
    _, hi = _series(rrd, "/fusion/window_nis/band/hi")
    assert np.all(sf > [w["band"][1] for w in failing]) and hi.size == 2 * len(
        out["consistency"]["hi"])
    back = read_recording(rrd)
    assert back["truth"] == json.loads((d / "truth.json").read_text())
    assert back["fusion_report"]["consistent"] is False
    assert back["fusion_report"]["decision"]["decision"] is None
    names = [v["name"] for v in _assert_blueprint_shows_content(rrd)["views"]]
    assert any(n.startswith("INCONSISTENT inputs, no fused region") for n in names)

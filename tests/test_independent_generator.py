"""The independent generator (validation/independent): reproducible, valid course files, a
complete truth manifest, a stable split, and its physics checked against first principles.

The generator imports numpy/scipy only (tests/test_imports.py); this test may import calib to
read what it writes (``calib.files.course.read_ensayo``) and to check the effect vocabulary.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest
import scipy.io
import scipy.signal

from calib.conventions import EFFECTS
from calib.files.course import read_ensayo
from validation.independent import cases, designs, effects, generate, physics, score

# Floats produced twice by the same code on the same machine agree to the last bit; the
# tolerance only allows for a BLAS kernel that reorders a sum (QR in the sizing step).
RTOL = 1e-12


def _pick():
    """One case of every kind and timing (fast to build)."""
    want = {}
    for c in cases.CASES:
        want.setdefault((c.kind, c.timing), c)
    return list(want.values())


def test_same_seed_same_arrays_other_seed_other_arrays():
    for c in _pick():
        m1, d1, t1 = cases.build(c, 7)
        m2, d2, t2 = cases.build(c, 7)
        np.testing.assert_allclose(d1, d2, rtol=RTOL, atol=0)
        np.testing.assert_allclose(m1.theta, m2.theta, rtol=RTOL, atol=0)
        assert json.dumps(t1, default=float) == json.dumps(t2, default=float)
        _, d3, _ = cases.build(c, 8)
        assert not np.allclose(d1[: min(len(d1), len(d3))], d3[: min(len(d1), len(d3))])


def test_written_files_are_valid_course_files_and_the_manifest_is_complete(tmp_path):
    out = tmp_path / "held"
    man = generate.generate(out, seed=3, split="heldout")
    assert man["cases"], "the held-out split is empty"
    assert {c["split"] for c in man["cases"]} == {"heldout"}
    written = {c["case_id"] for c in man["cases"]}
    assert written | set(man["not_written"]) == set(cases.case_by_id())
    for c in man["cases"]:
        truth = json.loads((out / c["truth"]).read_text(encoding="utf-8"))
        e = read_ensayo(out / c["file"])          # the project's validated reader accepts it
        raw = scipy.io.loadmat(out / c["file"])
        assert raw["tita"].shape == (truth["n"], 1) and raw["datos"].shape == (truth["n"], 2)
        assert (e.t is not None) == (truth["timing"] == "t")
        assert 2001 <= truth["n"] <= 20001
        assert (truth["rate_hz"] is not None) == (truth["timing"] == "rate")
        assert len(truth["noise_var"]) == 2 and min(truth["noise_var"]) > 0
        assert truth["expected"]["verdict"] == {
            "catalog": "explained", "clean": "nothing_detected",
            "absorbed": "nothing_detected", "out_of_catalog": "unexplained"}[truth["kind"]]
        if truth["kind"] == "catalog":
            assert truth["expected"]["effects"]
            for eff in truth["expected"]["effects"]:
                info = EFFECTS[eff["name"]]
                assert eff["axis"] in info.axes
                assert set(eff["params"]) <= set(info.keys) and eff["params"]
        if truth["kind"] == "out_of_catalog":
            assert truth["mechanism"]["kind"] == truth["what"]
            assert truth["what"] not in EFFECTS
        size = truth["size"]
        if truth["what"] == "bias_random_walk":
            assert size["z_beyond_catalog"] == pytest.approx(size["z_target"], rel=1e-3)
        elif truth["kind"] == "catalog":
            assert size["z"] == pytest.approx(size["z_target"], rel=1e-3)
        if truth["kind"] == "out_of_catalog" and size["z_target"]:
            # sized on what the catalog's parametric signatures leave of it
            assert size["z_beyond_catalog"] == pytest.approx(size["z_target"], rel=1e-3)
            assert size["z"] >= size["z_beyond_catalog"] * (1 - 1e-9) or \
                truth["what"] == "flicker"
        assert c["expected"] == truth["expected"]


def test_split_is_the_documented_hash_of_the_id_whatever_the_seed():
    ids = [c.case_id for c in cases.CASES]
    assert len(set(ids)) == len(ids)
    for cid in ids:
        h = hashlib.sha256(f"tiltbench-independent-2026:{cid}".encode()).digest()
        want = "heldout" if int.from_bytes(h[:8], "big") / 2**64 < 0.4 else "tune"
        assert cases.split_of(cid) == want
    held = sum(cases.split_of(i) == "heldout" for i in ids)
    # the split is a Bernoulli(0.4) draw per id: |h/R − 0.4| ≤ 4·sqrt(0.4·0.6/R)
    assert abs(held / len(ids) - 0.4) <= 4 * np.sqrt(0.24 / len(ids))
    assert cases.build(cases.CASES[0], 1)[2]["split"] == cases.build(cases.CASES[0], 2)[2]["split"]


def test_generate_refuses_a_non_empty_folder_and_writes_one_split(tmp_path, capsys):
    (tmp_path / "keep.txt").write_text("x")
    assert generate.main(["--out", str(tmp_path), "--seed", "0"]) == 2
    assert "--force" in capsys.readouterr().err
    assert (tmp_path / "keep.txt").exists() and len(list(tmp_path.iterdir())) == 1


def test_static_force_and_lever_arm_from_first_principles():
    """Specific force of a point p of a table turning about +y, by finite differences of its
    world position, equals static_force + lever_force projected on the course axes."""
    g = physics.G
    m = designs.growing_rock(np.random.default_rng(0), 4001, rate=200.0)
    p = np.array([0.07, 0.0, -0.12])
    h = 1e-4
    k = np.arange(200, m.n - 200, 97)

    def rot(th):  # R_y(θ) applied to p, world frame
        return np.stack([np.cos(th) * p[0] + np.sin(th) * p[2], np.zeros_like(th),
                         -np.sin(th) * p[0] + np.cos(th) * p[2]], axis=-1)
    # θ(t ± h) = θ ± ωh + αh²/2 ± O(h³): the O(h³) terms cancel in the central difference
    segs_theta = m.theta[k]
    acc = (rot(segs_theta + m.omega[k] * h + 0.5 * m.alpha[k] * h * h)
           - 2 * rot(segs_theta)
           + rot(segs_theta - m.omega[k] * h + 0.5 * m.alpha[k] * h * h)) / h**2
    f_w = acc + np.array([0.0, 0.0, g])           # specific force = a − g_vec
    x_w = np.stack([np.cos(segs_theta), 0 * segs_theta, -np.sin(segs_theta)], -1)
    my_w = np.stack([-np.sin(segs_theta), 0 * segs_theta, -np.cos(segs_theta)], -1)  # −z
    want = np.column_stack([(f_w * x_w).sum(1), (f_w * my_w).sum(1)])
    got = physics.static_force(segs_theta, g) + np.column_stack(
        [physics.lever_force(m.omega[k], m.alpha[k], p[0], p[2], axis=i) for i in (0, 1)])
    np.testing.assert_allclose(got, want, atol=1e-5)  # O(h²·ω⁴·|p|) difference error
    # course signs at rest: θ = 90° reads (−g, 0)
    np.testing.assert_allclose(physics.static_force(np.array([np.pi / 2]), g), [[-g, 0.0]],
                               atol=1e-12)


def test_design_rates_are_the_derivatives_of_theta():
    for name, build in designs.DESIGNS.items():
        m = build(np.random.default_rng(1), 4001)
        if m.t is None or not m.moving:
            continue
        # central differences on the (uniform or jittered) grid: error O(h²·jerk) ≪ 1e-2
        w = np.gradient(m.theta, m.t)
        assert np.max(np.abs(w - m.omega)[2:-2]) < 2e-2 * max(1.0, np.abs(m.omega).max()), name
        assert np.all(np.diff(m.t) > 0), name


def test_lowpass_matches_scipy_on_a_uniform_grid():
    t = np.linspace(0, 5, 2001)
    u = np.sin(3 * t) + (t > 2)
    tau = 0.05
    _, want, _ = scipy.signal.lsim(([1.0], [tau, 1.0]), u, t, X0=[u[0] / 1.0 * tau], interp=True)
    got = effects.lowpass(u, t, tau)
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_judge_marks_contradictions_false_alarms_and_reports():
    base = {"case_id": "c", "split": "tune", "design": "d", "timing": "none", "n": 2001,
            "axis": "x", "what": "misalignment"}
    ok_gap = {"x": {"consistent": True}, "y": {"consistent": True}}
    bad_gap = {"x": {"consistent": False}, "y": {"consistent": True}}
    cat = {**base, "kind": "catalog", "expected": {"verdict": "explained", "effects": [
        {"name": "misalignment", "axis": "x", "params": {"delta": 0.01}}]}}

    def res(verdict, named, gap):
        return {"rc": 0, "seconds": 1.0, "stderr": "", "result": {
            "verdict": verdict, "effects": [{"name": n, "axis": a} for n, a in named],
            "gap_after": gap, "unexplained": []}}
    r = score.judge(cat, res("explained", [("misalignment", "x")], ok_gap))
    assert r["ok"] and not r["contradiction"]
    fit = res("explained", [("misalignment", "x")], ok_gap)
    fit["result"]["effects"][0].update(params={"delta": 0.013}, std={"delta": 0.001})
    assert score.judge(cat, fit)["param_z"] == pytest.approx(3.0)
    r = score.judge(cat, res("explained", [("misalignment", "x")], bad_gap))
    assert r["contradiction"]
    r = score.judge(cat, res("explained", [("misalignment", "x"), ("noise_level", "y")], ok_gap))
    assert not r["ok"] and r["loose"]
    clean = {**base, "kind": "clean", "expected": {"verdict": "nothing_detected", "effects": []}}
    assert not score.judge(clean, res("explained", [("bias_drift", "x")], ok_gap))["ok"]
    r = score.judge(clean, res("nothing_detected", [], bad_gap))
    assert r["ok"] and r["silent_flag"]
    ooc = {**base, "kind": "out_of_catalog", "expected": {"verdict": "unexplained",
                                                           "effects": []}}
    assert score.judge(ooc, res("unexplained", [], bad_gap))["ok"]
    assert score.judge(ooc, res("explained", [("bias_random_walk", "x")], bad_gap))["ok"]
    assert not score.judge(ooc, res("explained", [("bias_random_walk", "x")], ok_gap))["ok"]
    assert not score.judge(ooc, {"rc": 1, "seconds": 0.1, "stderr": "boom",
                                 "result": None})["ok"]
    s = score.summarize([score.judge(cat, res("explained", [("misalignment", "x")], bad_gap))])
    assert s["contradictions"] == {"hits": 1, "of": 1} and s["catalog_named_right"]["of"] == 1


def test_scorer_command_runs_the_cli_with_the_stated_noise_and_rate(tmp_path, capsys):
    """The scorer's command line is one the real CLI accepts; --rate only for uniform runs
    stored without t. One small clean static case through ``bench.cli.main`` in-process."""
    from tests.cli import run

    c = next(c for c in cases.CASES if c.kind == "clean" and c.n == 2001)
    motion, datos, truth = cases.build(c, 0)
    generate.write_case(tmp_path / c.case_id, motion, datos, truth)
    entry = {"file": f"{c.case_id}/ensayo.mat", "noise_var": truth["noise_var"],
             "timing": truth["timing"], "rate_hz": truth["rate_hz"]}
    cmd = score.gap_command(entry, tmp_path)
    assert cmd[1:4] == ["-m", "bench.cli", "gap"] and "--rate" not in cmd
    assert "--rate" in score.gap_command({**entry, "timing": "rate", "rate_hz": 50.0}, tmp_path)
    rc, out, err = run(capsys, *cmd[3:])
    assert rc == 0, err
    res = json.loads(out)
    assert res["verdict"] in ("nothing_detected", "explained", "unexplained")
    row = score.judge({**entry, **truth, "split": truth["split"]},
                      {"rc": 0, "seconds": 1.0, "result": res, "stderr": ""})
    assert row["expected"] == "nothing_detected" and row["verdict"] == res["verdict"]

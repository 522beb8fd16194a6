"""The drive validation part (``validation/drive/``): files, truth schema, split rule, sizes,
the scorer's judgement, and that its generator imports numpy/scipy only (fast: a handful of
cases into tmp_path, no ``tiltbench gap`` run)."""

from __future__ import annotations

import ast
import hashlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from validation.drive import cases, generate, motion, score, sensor

REPO = Path(__file__).resolve().parents[1]
DRIVE = REPO / "validation" / "drive"


def _pick() -> list[str]:
    """One case of each category, plus each file format and a --datos case (tune or
    held-out alike: generating is not scoring)."""
    want, out = {}, []
    for c in cases.CASES:
        for key in (c.category, c.fmt, f"datos-{c.stated_by}", f"timing-{c.timing}"):
            if key not in want:
                want[key] = c.case_id
    for key in ("drive_state", "step_like", "nil", "clean", "catalog", "csv_counts",
                "csv_ms2", "mat", "datos-datos", "timing-none", "timing-rate"):
        if want[key] not in out:
            out.append(want[key])
    return out


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    out = tmp_path_factory.mktemp("drive") / "set"
    man = generate.generate(out, seed=3, only=_pick())
    return out, man


def test_the_list_has_what_the_issue_asks():
    ids = cases.case_by_id()                       # unique ids
    by = {cat: [c for c in cases.CASES if c.category == cat] for cat in cases.CATEGORIES}
    assert len(by["clean"]) >= 300
    assert sum(c.fmt == "csv_counts" for c in by["clean"]) >= 100
    assert {c.fmt for c in by["clean"]} == {"mat", "csv_ms2", "csv_counts"}
    assert {c.what for c in by["drive_state"]} == set(sensor.DRIVE_KINDS)
    assert {c.what for c in by["step_like"]} == set(sensor.STEP_KINDS)
    assert {c.what for c in by["catalog"]} == set(sensor.CATALOG) - {"lever_arm",
                                                                     "gravity_mismatch"}
    assert all(6 <= c.z <= 12 for c in by["catalog"])
    assert all(2001 <= c.n <= 6001 for c in by["clean"])
    fine = [c for c in by["nil"] if c.what == "fine_counts"]
    assert fine and all(0.001 <= c.z <= 0.05 for c in fine)
    assert all(c.z < 1 for c in by["nil"])
    assert len(ids) == len(cases.CASES)


def test_split_rule_is_the_documented_hash():
    assert cases.SPLIT_SALT == "tiltbench-drive-2026"
    for c in cases.CASES[::7]:
        h = hashlib.sha256(("tiltbench-drive-2026:" + c.case_id).encode()).hexdigest()
        want = "heldout" if int(h[:8], 16) / 2**32 < 0.4 else "tune"
        assert cases.split_of(c.case_id) == want
    share = np.mean([cases.split_of(c.case_id) == "heldout" for c in cases.CASES])
    assert 0.33 < share < 0.47
    for cat in cases.CATEGORIES:   # every category has cases on both sides
        sides = {cases.split_of(c.case_id) for c in cases.CASES if c.category == cat}
        assert sides == {"tune", "heldout"}, cat


def test_written_files_and_truth_schema(written):
    out, man = written
    assert man["format"] == generate.MANIFEST_FORMAT
    assert man["split_rule"]["salt"] == cases.SPLIT_SALT
    assert len(man["splits"]) == len(cases.CASES)
    assert {c["case_id"] for c in man["cases"]} == set(_pick())
    for entry in man["cases"]:
        truth = json.loads((out / entry["truth"]).read_text(encoding="utf-8"))
        assert truth["format"] == cases.FORMAT
        assert truth["split"] == cases.split_of(truth["case_id"]) == entry["split"]
        for key in ("case_id", "seed", "category", "what", "axis", "design", "timing", "n",
                    "noise_var", "expected", "size", "sensor", "motion", "file", "options",
                    "gap_args", "units", "quantization_step"):
            assert key in truth, key
        exp = truth["expected"]
        assert exp["verdict"] == cases.EXPECTED[truth["category"]]
        if truth["category"] == "catalog":
            assert exp["effects"] and all({"name", "axis", "params"} <= set(e)
                                          for e in exp["effects"])
        else:
            assert exp["effects"] == []
        if truth["category"] in ("drive_state", "step_like"):
            assert exp["words"]["any"] and truth["mechanism"]["kind"] == truth["what"]
        n = truth["n"]
        path = out / entry["file"]
        assert path.exists()
        opts = truth["options"]
        assert (opts["noise_var"] is None) == (opts["datos"] is not None)
        if opts["datos"]:
            text = (path.parent / "datos.txt").read_text(encoding="utf-8")
            assert "varianza" in text and str(truth["noise_var"][0]) in text
        assert (opts["rate"] is not None) == (truth["timing"] == "rate")
        if truth["file"]["format"] == "course":
            mat = scipy.io.loadmat(path)
            assert mat["tita"].shape == (n, 1) and mat["datos"].shape == (n, 2)
            assert ("t" in mat) == (truth["timing"] == "t")
        else:
            info = truth["file"]
            lines = path.read_text(encoding="utf-8").splitlines()
            assert lines[0].split(info["delimiter"]) == info["header"]
            assert len(lines) == n + 1
            rows = np.array([[float(v) for v in ln.split(info["delimiter"])]
                             for ln in lines[1:]])
            acc = rows[:, -2:]
            if info["units"] == "counts":
                assert opts["units"] == "counts" and opts["sensitivity"] > 0
                assert np.all(acc == np.round(acc))
                acc = acc / opts["sensitivity"] * sensor.G_UNIT
            # held readings near 1 g in the tilt plane (the log readers' physics check)
            norm = np.hypot(acc[:, 0], acc[:, 1])
            assert 0.8 * sensor.G_UNIT < np.median(norm) < 1.25 * sensor.G_UNIT
            assert ("t" in " ".join(info["header"])) == (truth["timing"] == "t")


def test_same_seed_same_arrays_other_seed_other_noise():
    c = next(c for c in cases.CASES if c.category == "drive_state")
    m1, d1, t1 = cases.build(c, 5)
    m2, d2, t2 = cases.build(c, 5)
    _, d3, _ = cases.build(c, 6)
    assert np.array_equal(d1, d2) and np.array_equal(m1.theta, m2.theta)
    assert json.dumps(t1, default=str) == json.dumps(t2, default=str)
    assert not np.array_equal(d1, d3)


def test_signs_sizes_and_exact_rates():
    ref = sensor.reference(np.array([0.0, np.pi / 2]))
    assert np.allclose(ref, [[0.0, -sensor.G], [-sensor.G, 0.0]])   # course signs
    for c in cases.CASES:
        if c.category in ("catalog", "drive_state", "step_like") and c.what in (
                "misalignment", "bias_drift", "move_bias", "telegraph"):
            _, _, truth = cases.build(c, 1)
            s = truth["size"]
            got = s["z"] if c.category == "catalog" else s["z_beyond_catalog"]
            assert got == pytest.approx(c.z, rel=1e-6), c.case_id
    rng = np.random.default_rng(0)
    th0, segs = motion.BUILDERS["sweep_pause"](rng, 30.0)
    t = np.linspace(0.2, 29.0, 4001)
    h = 1e-5
    a, b, m = (motion.evaluate(th0, segs, x) for x in (t, t + h, t - h))
    assert np.allclose((b[0] - m[0]) / (2 * h), a[1], atol=1e-5)      # ω = dθ/dt
    assert np.allclose((b[1] - m[1]) / (2 * h), a[2], atol=1e-3)      # α = dω/dt


def test_scorer_judges_words_worse_and_contradictions():
    truth = {"case_id": "x", "split": "tune", "category": "drive_state", "what": "move_bias",
             "axis": "x", "design": "d", "timing": "t", "n": 4001, "size": {"z_target": 8},
             "file": {"format": "course"},
             "expected": {"verdict": "unexplained", "effects": [],
                          "words": cases.WORDS["drive_state"]}}
    res = {"verdict": "unexplained", "effects": [],
           "unexplained": [{"description": "a bias of 0.1 m/s² on x while the table is moving"}],
           "gap_before": {"x": {"chi2_dof": 1.00, "details": {"dof": 3998}}},
           "gap_after": {"x": {"chi2_dof": 1.30, "consistent": False,
                               "details": {"dof": 3998}}}}
    row = score.judge(truth, {"result": res, "seconds": 1.0, "stderr": ""})
    assert row["ok"] and row["worded"] and row["worse"] == ["x"]
    res["unexplained"][0]["description"] = "1/f-like drift on x"
    assert not score.judge(truth, {"result": res, "seconds": 1.0, "stderr": ""})["worded"]
    cat = {**truth, "category": "catalog", "expected": {
        "verdict": "explained", "effects": [{"name": "misalignment", "axis": "x",
                                             "params": {"delta": 0.01}}]}}
    res2 = {**res, "verdict": "explained", "effects": [
        {"name": "misalignment", "axis": "x", "params": {"delta": 0.0102},
         "std": {"delta": 0.001}}]}
    row = score.judge(cat, {"result": res2, "seconds": 1.0, "stderr": ""})
    assert row["ok"] and row["contradiction"] and row["param_z"] == pytest.approx(0.2)
    cmd = score.gap_command({"file": {"name": "log.csv"}, "options": {
        "noise_var": None, "datos": "datos.txt", "rate": 100.0, "units": "counts",
        "sensitivity": 4096.0, "columns": "theta=enc_rad,x=acc_u,y=acc_v"}}, Path("/c"))
    assert cmd[-13:] == ["gap", "/c/log.csv", "--datos", "/c/datos.txt", "--rate", "100.0",
                         "--columns", "theta=enc_rad,x=acc_u,y=acc_v", "--units", "counts",
                         "--sensitivity", "4096.0", "--json"]


ALLOWED_TOP = {"__future__", "argparse", "dataclasses", "hashlib", "json", "os", "shutil", "sys",
               "tempfile", "time", "pathlib", "collections", "typing", "numpy", "scipy"}


def test_generator_imports_numpy_scipy_and_itself_only():
    for path in sorted(DRIVE.glob("*.py")):
        if path.name == "score.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:          # relative: inside validation/drive only
                    assert node.level == 1, f"{path.name}: {ast.dump(node)}"
                    continue
                names = [node.module or ""]
            else:
                continue
            for name in names:
                assert name.split(".")[0] in ALLOWED_TOP, f"{path.name} imports {name}"
    code = ("import sys, validation.drive.generate, validation.drive.score; "
            "print(sorted({m.split('.')[0] for m in sys.modules} & "
            "{'calib', 'bench', 'mujoco'}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=REPO, check=True).stdout.strip()
    assert out == "[]"

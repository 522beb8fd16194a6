"""`tiltbench validate` on bad input (issue 11, parts 1 and 6): one-line errors naming the file
and the field, sizes refused before allocating, a reported std far from the design fails,
an ensayo of another run is refused. Small synthetic files; no MuJoCo runs."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
import scipy.io
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bench.validate import std_ratio_limits
from calib.calibration.tilt_plane import calibrate
from calib.conventions import reference_accel
from calib.files.course import Ensayo
from tests.cli import one_line_error, unwrap
from tests.cli import run as run_cli

G = 9.8
BIAS, SCALE, NOISE = np.array([0.08, -0.02]), np.array([-0.03, 0.01]), np.array([0.25, 0.64])
N = 200


def _truth(n: int = N) -> dict:
    """A truth.json as `generate calibration --count n` writes it (the keys validate reads)."""
    theta = np.linspace(0.0, 2 * np.pi, n)
    return {"kind": "calibration", "g": G, "n": n, "mode": "static",
            "sensor": {a: {"bias": float(BIAS[k]), "scale": float(SCALE[k]),
                           "noise_var": float(NOISE[k]), "terms": []}
                       for k, a in enumerate("xy")},
            "theta_design": {"kind": "range", "start": 0.0, "stop": 2 * np.pi, "count": n,
                             "values": [], "positions": 0, "per_position": 0},
            "theta_summary": {"min": 0.0, "max": float(theta.max()), "distinct": n}}


def _run_files(tmp_path, n: int = N, seed: int = 4, name: str = "run"):
    """truth.json, ensayo.mat and the calibrate --json est.json of one seeded static run."""
    d = tmp_path / name
    d.mkdir()
    theta = np.linspace(0.0, 2 * np.pi, n)
    rng = np.random.default_rng(seed)
    datos = (1 + SCALE) * reference_accel(theta, G) + BIAS + np.sqrt(NOISE) * \
        rng.standard_normal((n, 2))
    scipy.io.savemat(d / "ensayo.mat", {"tita": theta[:, None], "datos": datos})
    (d / "truth.json").write_text(json.dumps(_truth(n)))
    est = calibrate(Ensayo(theta, datos), NOISE).to_dict()
    (d / "est.json").write_text(json.dumps(est))
    return d / "truth.json", d / "est.json", d / "ensayo.mat"


def _cli(capsys, *argv) -> tuple[int, str, str]:
    return run_cli(capsys, "validate", *argv)


def _error(capsys, *argv) -> str:
    return one_line_error(capsys, "validate", *argv, prefix="tiltbench validate: error: ")


@pytest.fixture
def run(tmp_path):
    return _run_files(tmp_path)


def _with(truth_path, change) -> None:
    t = json.loads(truth_path.read_text())
    change(t)
    truth_path.write_text(json.dumps(t))


def test_the_generated_run_passes(capsys, run):
    truth, est, ensayo = run
    assert _cli(capsys, "--truth", truth, "--estimates", est)[0] == 0
    assert _cli(capsys, "--truth", truth, "--estimates", est, "--ensayo", ensayo)[0] == 0


BAD_VALUES = {"list": [1, 2], "null": None, "object": {"a": 1}}


@pytest.mark.parametrize("kind", list(BAD_VALUES))
@pytest.mark.parametrize("field", [("sensor", "x", "bias"), ("sensor", "y", "noise_var"),
                                   ("g",), ("theta_design", "count"), ("theta_design", "start"),
                                   ("theta_design", "kind"), ("theta_design",), ("sensor",),
                                   ("n",), ("theta_summary", "max")])
def test_truth_field_of_the_wrong_type_names_file_and_path(capsys, run, field, kind):
    truth, est, _ = run

    def change(t):
        d = t
        for k in field[:-1]:
            d = d[k]
        d[field[-1]] = copy.deepcopy(BAD_VALUES[kind])

    _with(truth, change)
    for std in ("auto", "design"):
        msg = _error(capsys, "--truth", truth, "--estimates", est, "--std", std)
        assert str(truth) in msg and ".".join(field) in msg


@pytest.mark.parametrize("text", ["a\u2028b", "x\x1cy", "p\nq", "r\u0085s"])
def test_bad_strings_are_quoted_on_one_line(capsys, run, text):
    """Characters that break lines (U+2028, U+0085, FS, LF) are escaped in the message."""
    truth, est, _ = run
    _with(truth, lambda t: t.__setitem__("g", text))
    msg = _error(capsys, "--truth", truth, "--estimates", est)
    assert "g:" in msg and len(msg.splitlines()) == 1


def test_the_example_message_of_the_issue(capsys, run):
    truth, est, _ = run
    _with(truth, lambda t: t["theta_design"].__setitem__("count", [1, 2]))
    msg = _error(capsys, "--truth", truth, "--estimates", est, "--std", "design")
    assert msg.endswith(f"{truth}: theta_design.count: expected a positive integer, got [1, 2]")


def test_unknown_theta_design_key(capsys, run):
    truth, est, _ = run
    _with(truth, lambda t: t["theta_design"].__setitem__("spacing", 0.1))
    msg = _error(capsys, "--truth", truth, "--estimates", est)
    assert "theta_design: unknown key \"spacing\"" in msg and "count" in msg


@pytest.mark.parametrize("text", ["[" * 100_000 + "]" * 100_000,
                                  '{"a": ' * 50_000 + "1" + "}" * 50_000])
def test_deeply_nested_json(capsys, run, text):
    truth, est, _ = run
    for target in (truth, est):
        saved = target.read_text()
        target.write_text(text)
        msg = _error(capsys, "--truth", truth, "--estimates", est)
        assert str(target) in msg and "nested too deeply" in msg
        target.write_text(saved)


def test_huge_count_is_refused_with_the_memory_needed(capsys, run):
    """count = 3e9 needs 447 GiB (160 B per sample): refused before anything is allocated,
    with the std from the design and with reported std (the std check needs the design)."""
    truth, est, _ = run
    _with(truth, lambda t: t["theta_design"].__setitem__("count", 3e9))
    for std in ("design", "auto"):
        msg = _error(capsys, "--truth", truth, "--estimates", est, "--std", std)
        assert "theta_design.count" in msg and "3,000,000,000 samples" in msg
        assert "447.0 GiB" in msg and "available" in msg


@pytest.mark.parametrize("text", ['{"axes": {"x": {"bias": NaN, "scale": 0}, "y": {}}}',
                                  '{"axes": {"x": {"bias": 1e999, "scale": 0}, "y": {}}}',
                                  '{"axes": {"x": {"bias": true, "scale": 0}, "y": {}}}',
                                  '{"axes": {"x": {"bias": 1%s, "scale": 0}, "y": {}}}'
                                  % ("0" * 400)])
def test_non_finite_estimates(capsys, run, text):
    truth, est, _ = run
    est.write_text(text)
    msg = _error(capsys, "--truth", truth, "--estimates", est)
    assert str(est) in msg and "axes.x.bias: expected a finite number" in msg


def test_reported_std_ten_times_too_large_fails_with_the_ratio(capsys, run):
    truth, est, _ = run
    e = json.loads(est.read_text())
    for a in "xy":
        ax = e["axes"][a]
        ax["bias_std"] *= 10
        ax["scale_std"] *= 10
        ax["cov"] = [[100 * c for c in row] for row in ax["cov"]]
    est.write_text(json.dumps(e))
    rc, out, _ = _cli(capsys, "--truth", truth, "--estimates", est)
    assert rc == 1
    assert "→ PASS" in out  # the joint test alone is fooled …
    assert "std check" in out and "bias_x 10" in out and "FAIL" in out.splitlines()[-1]
    rc, out, _ = _cli(capsys, "--truth", truth, "--estimates", est, "--json")
    res = json.loads(out)
    assert rc == 1 and res["passed"] is False and res["chi2"] <= res["chi2_limit"]
    assert res["std_check"]["ratio"]["scale_y"] == pytest.approx(10.0)
    assert res["std_check"]["limits"] == [0.5, 2.0]


def test_std_only_estimates_also_checked(capsys, run):
    """The stds without cov (a MATLAB est.json): 3× too small also fails."""
    truth, est, _ = run
    e = json.loads(est.read_text())
    e = {"axes": {a: {k: e["axes"][a][k] / (3 if k.endswith("_std") else 1)
                      for k in ("bias", "scale", "bias_std", "scale_std")} for a in "xy"}}
    est.write_text(json.dumps(e))
    rc, out, _ = _cli(capsys, "--truth", truth, "--estimates", est, "--json")
    assert rc == 1 and json.loads(out)["std_check"]["ratio"]["bias_x"] == pytest.approx(1 / 3)


def test_std_limits():
    """The union of [1/2, 2] with the χ²_{N−2} interval at α = 1e-6: [1/2, 2] for large N,
    wider for tiny N, and 10× always outside (N = 3: ν = 1, upper limit ≈ 5.0)."""
    assert std_ratio_limits(20001) == (0.5, 2.0)
    lo, hi = std_ratio_limits(3)
    assert lo < 1e-5 and 4.5 < hi < 5.5


def _readings(tita: np.ndarray) -> np.ndarray:
    """Noiseless readings of a calibrated sensor at θ (a plausible run, not a dead sensor)."""
    return np.column_stack([-9.8 * np.sin(tita), -9.8 * np.cos(tita)])


def test_ensayo_of_another_run_is_refused(capsys, tmp_path, run):
    truth, est, _ = run
    _, _, other_n = _run_files(tmp_path, n=2 * N + 1, name="other-n")
    msg = _error(capsys, "--truth", truth, "--estimates", est, "--ensayo", other_n)
    assert str(other_n) in msg and f"N = {2 * N + 1}" in msg and f"= {N}" in msg
    # the same N, another θ range
    d = tmp_path / "arc"
    d.mkdir()
    arc = np.linspace(0, 3, N)
    scipy.io.savemat(d / "ensayo.mat", {"tita": arc[:, None], "datos": _readings(arc)})
    msg = _error(capsys, "--truth", truth, "--estimates", est, "--ensayo", d / "ensayo.mat")
    assert "θ max" in msg and "theta_summary.max" in msg
    # the same N and range, other angles (no summary in the truth: the design decides)
    _with(truth, lambda t: t.pop("theta_summary"))
    tita = np.linspace(0.0, 2 * np.pi, N)
    tita[1:-1] += 1e-3
    scipy.io.savemat(d / "ensayo.mat", {"tita": tita[:, None], "datos": _readings(tita)})
    assert "θ design" in _error(capsys, "--truth", truth, "--estimates", est, "--ensayo",
                                d / "ensayo.mat")


def test_answer_key_of_the_wrong_shape(capsys, tmp_path, run):
    _, est, _ = run
    key = tmp_path / "answer_key.json"
    for students in ([1, 2], [{"student": "s1"}], {"a": 1}, None):
        key.write_text(json.dumps({"kind": "class", "students": students}))
        msg = _error(capsys, "--truth", key, "--estimates", est, "--student", "s1")
        assert str(key) in msg and "students" in msg


# --- property: random JSON never gives a traceback ------------------------------------------

SCALARS = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**25),
                    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=5))
JSON = st.recursive(SCALARS, lambda kids: st.one_of(
    st.lists(kids, max_size=3), st.dictionaries(st.text(max_size=4), kids, max_size=3)),
    max_leaves=8)
TRUTH_KEYS = ("sensor", "g", "theta_design", "sweep", "n", "theta_summary")
EST_KEYS = ("axes", "x", "g", "bias_x", "n")


def _mutated(base: dict, paths: list, values: list) -> dict:
    """``base`` with the value at each (random) path replaced by a random JSON tree."""
    out = copy.deepcopy(base)
    for path, value in zip(paths, values, strict=False):
        d = out
        for k in path[:-1]:
            if not isinstance(d, dict) or k not in d:
                break
            d = d[k]
        else:
            if isinstance(d, dict):
                d[path[-1]] = value
    return out


def _paths(base: dict) -> list[tuple]:
    out, queue = [], [((), base)]
    while queue:
        p, d = queue.pop()
        for k, v in d.items():
            out.append((*p, k))
            if isinstance(v, dict):
                queue.append(((*p, k), v))
    return sorted(out)


@settings(derandomize=True, max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_random_json_gives_a_verdict_or_a_one_line_error(capsys, tmp_path, data):
    """Random JSON trees put in place of random fields of a valid truth.json and est.json (or
    as the whole file): exit 0/1 (a verdict), or 2 with one line naming the file — never a
    traceback."""
    truth_path, est_path = tmp_path / "truth.json", tmp_path / "est.json"
    if not truth_path.exists():
        _run_files(tmp_path, n=40, name="base")
    base_truth = json.loads((tmp_path / "base" / "truth.json").read_text())
    base_est = json.loads((tmp_path / "base" / "est.json").read_text())
    docs = []
    for base in (base_truth, base_est):
        if data.draw(st.booleans(), label="whole file random"):
            docs.append(data.draw(JSON, label="file"))
        else:
            paths = data.draw(st.lists(st.sampled_from(_paths(base)), min_size=1, max_size=2))
            docs.append(_mutated(base, paths, [data.draw(JSON) for _ in paths]))
    truth_path.write_text(json.dumps(docs[0]))
    est_path.write_text(json.dumps(docs[1]))
    std = data.draw(st.sampled_from(["auto", "reported", "design"]))
    rc, out, err = _cli(capsys, "--truth", truth_path, "--estimates", est_path, "--std", std)
    assert "Traceback" not in err
    if rc == 2:
        lines = unwrap(err).splitlines()
        assert len(lines) == 1 and (str(truth_path) in lines[0] or str(est_path) in lines[0]), err
    else:
        assert rc in (0, 1) and "joint test" in out

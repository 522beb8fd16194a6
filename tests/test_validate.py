"""`tiltbench validate`: z-scores against the truth, exact pass rates, exit codes."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats

from bench.cli import main
from bench.validate import design_cov, design_theta, parse_estimates, validate
from calib.calibration.tilt_plane import calibrate
from calib.conventions import reference_accel
from calib.files.course import DataError, Ensayo

G = 9.8
BIAS = np.array([0.08, -0.02])
SCALE = np.array([-0.03, 0.01])
NOISE = np.array([0.25, 0.64])


def truth_for(theta_design: dict) -> dict:
    """A truth.json-like object (the keys validate reads) for a static θ design."""
    return {"kind": "calibration", "g": G, "theta_design": theta_design,
            "sensor": {a: {"bias": float(BIAS[k]), "scale": float(SCALE[k]),
                           "noise_var": float(NOISE[k]), "terms": []}
                       for k, a in enumerate("xy")}}


FULL_TURN = {"kind": "range", "start": 0.0, "stop": 2 * np.pi, "count": 40, "values": [],
             "positions": 0, "per_position": 0}
SHORT_ARC = {"kind": "range", "start": 0.2, "stop": 1.2, "count": 40, "values": [],
             "positions": 0, "per_position": 0}


def synthetic_estimates(truth: dict, rng: np.random.Generator) -> dict:
    """Fresh readings of the truth's design with the course model, calibrated (σ² known)."""
    theta = design_theta(truth)
    datos = (1 + SCALE) * reference_accel(theta, G) + BIAS + np.sqrt(NOISE) * rng.standard_normal(
        (theta.size, 2))
    return calibrate(Ensayo(theta, datos), NOISE).to_dict()


def minimal(est: dict) -> dict:
    return {"axes": {a: {"bias": est["axes"][a]["bias"], "scale": est["axes"][a]["scale"]}
                     for a in "xy"}}


@pytest.mark.parametrize("design", [FULL_TURN, SHORT_ARC], ids=["full-turn", "short-arc"])
def test_pass_rate_of_true_estimates_matches_level(design):
    """Monte Carlo, R = 400 seeded runs (N = 40) per design, L = 0.9.

    Under the model the joint test passes with probability exactly L (d² ~ χ²₄) and each
    single |z| ≤ Φ⁻¹((1+L)/2) with probability L; a pass count is Binomial(R, L), so the rate
    lies within 4·sqrt(L(1−L)/R) of L except with probability < 1e-4. The short arc makes
    bias and scale strongly correlated: the joint test must still hold its level. Checked with
    the reported covariance and with the minimal form (covariance recomputed from the design).
    """
    R, L = 400, 0.9
    truth = truth_for(design)
    tol = 4 * np.sqrt(L * (1 - L) / R)
    joint = joint_min = 0
    each = np.zeros(4)
    for ss in np.random.SeedSequence(20240611).spawn(R):
        est = synthetic_estimates(truth, np.random.default_rng(ss))
        v = validate(truth, est, L)
        joint += v.passed
        each += v.passed_each
        joint_min += validate(truth, minimal(est), L).passed
    assert abs(joint / R - L) <= tol
    assert abs(joint_min / R - L) <= tol
    assert np.all(np.abs(each / R - L) <= tol)


def test_correlation_is_real_in_the_short_arc_design():
    """The short arc correlates bias and scale (so 'all four |z| below q' would not have
    probability L⁴): |ρ| > 0.5 on both axes; the full turn is uncorrelated."""
    for design, big in ((SHORT_ARC, True), (FULL_TURN, False)):
        c = design_cov(design_theta(truth_for(design)), NOISE, G)
        for k in (0, 2):
            rho = c[k, k + 1] / np.sqrt(c[k, k] * c[k + 1, k + 1])
            assert (abs(rho) > 0.5) == big


@pytest.mark.parametrize("param", range(4))
def test_estimate_moved_by_5_sigma_fails(param):
    """Moving one estimate 5σ further from the truth gives |z| ≥ 5, so d² ≥ z² ≥ 25 > χ²₄(L)
    for any covariance (the marginal bound): the verdict must be fail, at L = 0.99."""
    truth = truth_for(FULL_TURN)
    est = synthetic_estimates(truth, np.random.default_rng(7 + param))
    v0 = validate(truth, est, 0.99)
    a, p = "xxyy"[param], ("bias", "scale")[param % 2]
    moved = json.loads(json.dumps(est))
    direction = 1.0 if v0.z[param] >= 0 else -1.0
    moved["axes"][a][p] += direction * 5 * v0.std[param]
    v = validate(truth, moved, 0.99)
    assert not v.passed and not v.passed_each[param]
    assert abs(v.z[param] - v0.z[param]) == pytest.approx(5.0, rel=1e-9)
    assert v.chi2 >= 25.0


def test_design_std_equals_calibrate_std_on_the_same_theta():
    truth = truth_for(SHORT_ARC)
    theta = design_theta(truth)
    est = synthetic_estimates(truth, np.random.default_rng(3))
    v = validate(truth, minimal(est), 0.99, "design", theta, "run")
    reported = np.array([est["axes"][a][f"{p}_std"] for a in "xy" for p in ("bias", "scale")])
    np.testing.assert_allclose(v.std, reported, rtol=1e-10)
    assert v.std_source == "design"


def test_accepted_forms_agree():
    truth = truth_for(FULL_TURN)
    est = synthetic_estimates(truth, np.random.default_rng(5))
    flat = {f"{p}_{a}": est["axes"][a][p] for a in "xy" for p in ("bias", "scale")}
    flat.update({f"{p}_std_{a}": est["axes"][a][f"{p}_std"] for a in "xy"
                 for p in ("bias", "scale")})
    forms = [est, {"x": est["axes"]["x"], "y": est["axes"]["y"]}, minimal(est)]
    zs = [validate(truth, f, 0.99).z for f in forms]
    for z in zs[1:]:
        np.testing.assert_allclose(z, zs[0], rtol=1e-9)
    assert parse_estimates(flat)["params"].tolist() == parse_estimates(est)["params"].tolist()


@pytest.mark.parametrize("bad", [{}, {"axes": {"x": {"bias": 1.0}}},
                                 {"axes": {"x": {"bias": 1, "scale": "a"}, "y": {}}},
                                 {"axes": {"x": {"bias": 1, "scale": 0, "cov": [[1, 2], [2, 1]]},
                                           "y": {"bias": 1, "scale": 0}}}])
def test_bad_estimates_are_data_errors(bad):
    with pytest.raises(DataError):
        validate(truth_for(FULL_TURN), bad)


def test_cli_exit_codes(tmp_path, capsys):
    truth = truth_for(FULL_TURN)
    est = synthetic_estimates(truth, np.random.default_rng(11))
    tp, ep = tmp_path / "truth.json", tmp_path / "est.json"
    tp.write_text(json.dumps(truth))
    v = validate(truth, est, 0.99)
    ep.write_text(json.dumps(est))
    assert main(["validate", "--truth", str(tp), "--estimates", str(ep)]) == (
        0 if v.passed else 1)
    est["axes"]["y"]["scale"] += 6 * est["axes"]["y"]["scale_std"] * (
        1 if v.z[3] >= 0 else -1)
    ep.write_text(json.dumps(est))
    capsys.readouterr()
    assert main(["validate", "--truth", str(tp), "--estimates", str(ep), "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["passed"] is False and out["parameters"]["scale_y"]["passed"] is False
    assert out["chi2_limit"] == pytest.approx(stats.chi2.ppf(0.99, 4))
    ep.write_text("{not json")
    assert main(["validate", "--truth", str(tp), "--estimates", str(ep)]) == 2
    assert main(["validate", "--truth", str(tmp_path / "missing.json"), "--estimates",
                 str(ep)]) == 2
    ep.write_text(json.dumps({"axes": {"x": {"bias": 0.1}}}))
    capsys.readouterr()
    assert main(["validate", "--truth", str(tp), "--estimates", str(ep)]) == 2
    assert "axes.x.scale" in capsys.readouterr().err


def test_generated_calibration_and_ensayo_option(tmp_path, capsys):
    """End to end on a bench run: generate → calibrate --json → validate (with --ensayo)."""
    out = tmp_path / "g"
    assert main(["generate", "calibration", "--count", "500", "--seed", "21", "--out",
                 str(out)]) == 0
    capsys.readouterr()
    assert main(["calibrate", str(out / "ensayo.mat"), "--noise-var", "0.25,0.64",
                 "--json"]) == 0
    est = json.loads(capsys.readouterr().out)
    (tmp_path / "est.json").write_text(json.dumps(minimal(est)))
    rc = main(["validate", "--truth", str(out / "truth.json"), "--estimates",
               str(tmp_path / "est.json"), "--ensayo", str(out / "ensayo.mat"), "--json"])
    res = json.loads(capsys.readouterr().out)
    assert rc == (0 if res["passed"] else 1)
    assert res["std_source"] == "design" and res["theta_source"].endswith("ensayo.mat")
    for a in "xy":
        for p in ("bias", "scale"):
            assert res["parameters"][f"{p}_{a}"]["std"] == pytest.approx(
                est["axes"][a][f"{p}_std"], rel=1e-9)


def test_std_check_accepts_honest_estimated_sigma_and_refuses_inflated_std():
    """Monte Carlo, R = 200 seeded runs (N = 40, short arc), σ² estimated from the residuals:
    reported/design std = s/σ = sqrt(χ²₃₈/38), inside the accepted range except with
    probability ≤ 1e-6 per run (``std_ratio_limits``), so every run passes the std check; the
    same estimates with stds 10× larger fail it every time, whatever d² says."""
    R = 200
    truth = truth_for(SHORT_ARC)
    theta = design_theta(truth)
    for ss in np.random.SeedSequence(20240612).spawn(R):
        rng = np.random.default_rng(ss)
        datos = (1 + SCALE) * reference_accel(theta, G) + BIAS + np.sqrt(NOISE) * \
            rng.standard_normal((theta.size, 2))
        est = calibrate(Ensayo(theta, datos)).to_dict()
        v = validate(truth, est, 0.99)
        assert v.std_passed is True
        for a in "xy":
            ax = est["axes"][a]
            ax["bias_std"], ax["scale_std"] = 10 * ax["bias_std"], 10 * ax["scale_std"]
            ax["cov"] = (100 * np.asarray(ax["cov"])).tolist()
        bad = validate(truth, est, 0.99)
        assert bad.std_passed is False and not bad.passed
        np.testing.assert_allclose(bad.std_ratio, 10 * v.std_ratio, rtol=1e-9)

"""calib.calibration.lackoffit: pure error and lack of fit (Draper & Smith), and its use in
calibrate."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats

from calib.calibration.calfile import calibration_document, load_calibration, save_calibration
from calib.calibration.lackoffit import (
    LackOfFit,
    groups_from,
    lack_of_fit,
    pure_error,
    pure_error_variance,
)
from calib.calibration.tilt_plane import Calibration, calibrate
from calib.conventions import G
from calib.files.course import Ensayo, read_ensayo
from calib.units import missing_units

TRUTH = (0.08, -0.03, -0.02, 0.01)
SIGMA2 = (0.25, 0.64)


def positions_run(rng, P=8, n=50, k2=0.0, sigma2=SIGMA2):
    """A held-positions run: P angles over the turn, n samples each; optional second-order
    term k2·A_r² (IEEE Std 1293 K2, 1/(m/s²)) on x — an effect the model lacks."""
    th = np.repeat(np.arange(P) * 2 * np.pi / P, n)
    a_r = np.column_stack([-G * np.sin(th), -G * np.cos(th)])
    b, s = np.array([TRUTH[0], TRUTH[2]]), np.array([TRUTH[1], TRUTH[3]])
    acc = b + (1 + s) * a_r + rng.standard_normal(a_r.shape) * np.sqrt(sigma2)
    acc[:, 0] += k2 * a_r[:, 0] ** 2
    return Ensayo(th, acc)


def test_groups_from_labels_and_repeated_theta():
    assert groups_from(np.array([0.1, 0.2, 0.3])) is None  # nothing repeats
    assert groups_from() is None
    g = groups_from(np.array([0.1, 0.2, 0.1, 0.2, 0.3]))
    assert g.tolist() == [0, 1, 0, 1, 2]
    # pose labels win over θ; each moving sample (−1) is a group of its own
    g = groups_from(np.zeros(6), np.array([0, 0, -1, 1, 1, -1]))
    assert len(set(g.tolist())) == 4 and g[0] == g[1] and g[3] == g[4] and g[2] != g[5]


def test_pure_error_is_the_scatter_about_the_group_means():
    rng = np.random.default_rng(0)
    v = rng.standard_normal((30, 2))
    grp = np.repeat(np.arange(6), 5)
    ss, dof = pure_error(v, grp)
    expect = sum(((v[grp == k] - v[grp == k].mean(0)) ** 2).sum(0) for k in range(6))
    assert dof == 24 and np.allclose(ss, expect, rtol=1e-13)
    s2, dof = pure_error_variance(v, grp)
    assert np.allclose(s2, expect / 24, rtol=1e-13)
    with pytest.raises(ValueError, match="no pose or θ value repeats"):
        pure_error_variance(v, np.arange(30))


def test_f_equals_the_extra_sum_of_squares_against_the_group_means_model():
    """Independent route: F = ((RSS_line − RSS_means)/(c − p)) / (RSS_means/(N − c)),
    RSS of two least-squares fits made here with numpy.linalg.lstsq (line vs one mean per
    group)."""
    rng = np.random.default_rng(1)
    x = np.repeat(np.linspace(0, 1, 7), [3, 1, 4, 2, 5, 3, 2])
    y = 1 + 2 * x + 0.3 * x**2 + 0.1 * rng.standard_normal(x.size)
    H = np.column_stack([np.ones_like(x), x])
    beta = np.linalg.lstsq(H, y, rcond=None)[0]
    r = y - H @ beta
    grp = groups_from(x)
    D = np.eye(7)[grp]
    rss_means = float(np.sum((y - D @ np.linalg.lstsq(D, y, rcond=None)[0]) ** 2))
    rss_line = float(r @ r)
    F = ((rss_line - rss_means) / 5) / (rss_means / (x.size - 7))
    lof = lack_of_fit(r, grp, 2)
    assert lof.value == pytest.approx(F, rel=1e-10)
    assert (lof.dof_lack_of_fit, lof.dof_pure_error, lof.groups) == (5, x.size - 7, 7)
    assert lof.p_value == pytest.approx(stats.f.sf(F, 5, x.size - 7), rel=1e-10)
    assert lof.ss_pure_error == pytest.approx(rss_means, rel=1e-10)


@pytest.mark.parametrize("seed", range(4))
def test_pure_error_and_lack_of_fit_add_up_to_the_residual_sum(seed):
    """RSS = SS_pe + SS_lof for any residuals and any grouping (Pythagoras within groups)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(10, 60))
    r = rng.standard_normal(n) * rng.uniform(0.1, 3)
    grp = groups_from(None, rng.integers(-1, 5, n))
    lof = lack_of_fit(r, grp, 1)
    if lof is not None:
        assert lof.ss_pure_error + lof.ss_lack_of_fit == pytest.approx(float(r @ r), rel=1e-12)


def test_undefined_test_returns_none():
    r = np.array([0.1, -0.1, 0.2, -0.2])
    assert lack_of_fit(r, np.array([0, 0, 1, 1]), 2) is None  # c = p: no lof dof
    assert lack_of_fit(r, np.arange(4), 2) is None             # no pure-error dof


def test_p_values_are_uniform_when_the_model_holds():
    """R = 400 runs (seed 7) of the right model: the test rejects at α = 0.05 with
    probability 0.05 per axis, so the rejection rate of each axis is binomial:
    |rate − 0.05| ≤ 4·sqrt(0.05·0.95/R) = 0.044."""
    rng = np.random.default_rng(7)
    R = 400
    rej = np.zeros(2)
    for _ in range(R):
        e = positions_run(rng, P=6, n=20)
        cal = calibrate(e, SIGMA2, groups=groups_from(e.tita))
        rej += [cal.lack_of_fit[a].p_value < 0.05 for a in ("x", "y")]
    assert np.all(np.abs(rej / R - 0.05) <= 4 * np.sqrt(0.05 * 0.95 / R)), rej / R


def test_calibrate_uses_the_pure_error_and_says_the_model_misses_something():
    """A K2 term of 0.01 /(m/s²) on x adds k2·g² sin²θ: its mean goes into the bias, the
    rest, ± k2·g²/2 ≈ ± 0.48 m/s² (variance ≈ 0.115), stays in the residuals. The residual
    variance absorbs it (χ²/dof = 1 by construction); the pure error does not (χ²/dof ≈
    1 + 0.115/0.25 ≈ 1.46), and the F test names the axis."""
    rng = np.random.default_rng(3)
    e = positions_run(rng, P=8, n=400, k2=0.01)
    grp = groups_from(e.tita)
    old = calibrate(e)
    assert old.fits["x"].chi2_dof == pytest.approx(1.0, abs=1e-12)
    cal = calibrate(e, groups=grp)
    fx = cal.fits["x"]
    s2, dof = pure_error_variance(e.datos, grp)
    assert fx.sigma2_source == "estimated" and fx.extra["sigma2_dof"] == dof == e.n - 8
    assert fx.sigma2.item() == pytest.approx(s2[0], rel=1e-12)
    assert np.array_equal(cal.params, old.params)  # OLS estimates do not depend on σ²
    assert fx.chi2_dof > 1.2  # the miss shows
    assert fx.quantile(0.95) == pytest.approx(stats.t.ppf(0.975, dof), rel=1e-12)
    assert cal.lack_of_fit["x"].misses() and not cal.lack_of_fit["y"].misses(1e-4)
    lines = cal.lack_of_fit_warnings()
    assert len(lines) == 1 and lines[0].startswith("axis x: the model misses something (F = ")
    assert lines[0].endswith("); run `tiltbench gap`") and len("warning: " + lines[0]) <= 100
    assert "axis x: lack of fit F" in cal.summary()


def test_given_noise_keeps_its_sigma2_and_still_tests():
    rng = np.random.default_rng(4)
    e = positions_run(rng)
    cal = calibrate(e, SIGMA2, "wls", groups=groups_from(e.tita))
    assert cal.fits["x"].sigma2_source == "given" and cal.lack_of_fit is not None
    plain = calibrate(e, SIGMA2, "wls")
    assert np.array_equal(cal.params, plain.params) and np.array_equal(cal.cov, plain.cov)


def test_round_trips_and_units(tmp_path):
    rng = np.random.default_rng(5)
    e = positions_run(rng, k2=0.001)
    cal = calibrate(e, groups=groups_from(e.tita))
    d = json.loads(json.dumps(cal.to_dict()))
    assert missing_units(d) == []
    assert d["axes"]["x"]["sigma2_dof"] == e.n - 8
    back = Calibration.from_dict(d)
    assert back.to_dict() == cal.to_dict()
    assert back.fits["x"].quantile(0.9) == cal.fits["x"].quantile(0.9)
    assert Calibration.from_dict(json.loads(json.dumps(cal.to_state()))) == cal
    assert LackOfFit.from_dict(cal.lack_of_fit["y"].to_dict()) == cal.lack_of_fit["y"]
    doc = calibration_document(cal, None, "estimated")
    assert missing_units(json.loads(json.dumps(doc))) == []
    assert load_calibration(save_calibration(tmp_path / "c.json", cal)) == cal


def test_course_run_is_unchanged(course_dir):
    """The course sweep never repeats θ: no groups, the fit and its document as before."""
    e = read_ensayo(course_dir / "ensayo.mat")
    assert groups_from(e.tita) is None
    cal = calibrate(e, groups=None)
    assert cal.lack_of_fit is None and "lack_of_fit" not in cal.to_dict()
    assert "sigma2_dof" not in cal.to_dict()["axes"]["x"]


def test_gap_takes_the_noise_from_the_held_poses(capsys, tmp_path):
    """``gap`` without --noise-var on a held-positions set: the within-pose scatter is the
    stated noise (said on stderr); a sweep (no θ repeats) is still refused in one line."""
    from calib.files.course import read_ensayo
    from tests.cli import one_line_error, run

    out = tmp_path / "set"
    assert run(capsys, "generate", "calibration", "--positions", 6, "--per-position", 100,
               "--seed", 2, "--out", out)[0] == 0
    rc, text, err = run(capsys, "gap", out / "ensayo.mat", "--json")
    assert rc == 0, err
    e = read_ensayo(out / "ensayo.mat")
    s2, dof = pure_error_variance(e.datos, groups_from(e.tita))
    assert json.loads(text)["noise_var"] == [float(s2[0]), float(s2[1])]
    assert "scatter within the held poses" in err and f"pure error, dof {dof}" in err
    sweep = tmp_path / "sweep"
    assert run(capsys, "generate", "calibration", "--count", 200, "--seed", 2, "--out",
               sweep)[0] == 0
    msg = one_line_error(capsys, "gap", sweep / "ensayo.mat")
    assert "--noise-var" in msg and "hold poses" in msg

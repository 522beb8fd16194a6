"""calib.calibration.multiposition: calibration without an angle reference (gravity-norm
constraint)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from calib.calibration.calfile import load_calibration, save_calibration
from calib.calibration.ls import NotIdentifiableError, PoorlyIdentifiedWarning
from calib.calibration.multiposition import (
    UNIDENTIFIED_STD,
    MultiPositionFit,
    OutOfPlaneWarning,
    Poses,
    compare_methods,
    distinct_orientations,
    fit_multiposition,
    pose_statistics,
)
from calib.calibration.tilt_plane import calibrate
from calib.conventions import G
from calib.files.course import Ensayo, read_ensayo
from calib.input_rules import DataError
from tests.checks import assert_honest_intervals
from tests.reference import course_2009 as ref

TRUTH = np.array([0.08, -0.03, -0.02, 0.01])  # [bias_x, scale_x, bias_y, scale_y]
SIGMA2 = np.array([0.25, 0.64])  # the course noise, (m/s²)²


def model_means(params, th, g=G):
    """(P, 2) noiseless pose readings b + (1 + s)·A_r(θ), course signs."""
    return np.column_stack([params[0] + (1 + params[1]) * (-g * np.sin(th)),
                            params[2] + (1 + params[3]) * (-g * np.cos(th))])


def samples(rng, th, n, params=TRUTH, sigma2=SIGMA2):
    """Readings (P·n, 2) of poses at ``th`` held for ``n`` samples each, with labels."""
    thr = np.repeat(th, n)
    acc = model_means(params, thr) + rng.standard_normal((thr.size, 2)) * np.sqrt(sigma2)
    return acc, np.repeat(np.arange(th.size), n)


def random_set(rng, sigma2=SIGMA2):
    """Sufficient statistics of one simulated multi-position set, drawn exactly from their
    distribution: 6–8 poses spread around the turn (even spacing, random start, ±11°
    jitter), 100–400 samples per pose; pose means ~ N(model, σ²/n), each pose's within sum of
    squares ~ σ²·χ²(n − 1), independent of its mean (normal samples). Equivalent to drawing
    the samples and calling pose_statistics, ~100× faster."""
    P = int(rng.integers(6, 9))
    n = int(rng.integers(100, 401))
    th = rng.uniform(0, 2 * np.pi) + np.arange(P) * 2 * np.pi / P + rng.uniform(-0.2, 0.2, P)
    means = model_means(TRUTH, th) + rng.standard_normal((P, 2)) * np.sqrt(sigma2 / n)
    ss = sigma2 * rng.chisquare(n - 1, size=(P, 2))
    return Poses(np.arange(P), np.full(P, n), means, ss)


@pytest.mark.parametrize("known", [True, False], ids=["sigma2-given", "sigma2-pure-error"])
def test_interval_coverage_and_nees(known):
    """R = 600 simulated sets (seed 19), 95 % intervals of each of the 4 parameters
    (:func:`tests.checks.assert_honest_intervals`).

    Hits/R has sd sqrt(p(1−p)/R) = 0.0089: |hits/R − p| ≤ 4 sd is ±0.036 (a false alarm
    ≈ 6e-5 per parameter). With σ² given, the NEES is χ²(4): its mean over R runs has sd
    sqrt(2·4/R) = 0.115; checked within 4 ± 4 sd. With σ² from the pure error (N − P ≥ 594
    dof) the NEES mean is 4·(dof/(dof − 2)) ≈ 4.01: the same band holds. The joint lack-of-fit
    test (χ² or F with P − 4 dof) rejects a right model at α = 0.05 with probability 0.05: its
    rate is checked within 4·sqrt(0.05·0.95/R) = 0.036.
    """
    rng = np.random.default_rng(19)
    R = 600
    assert_honest_intervals(
        (fit_multiposition(random_set(rng), SIGMA2 if known else None) for _ in range(R)),
        TRUTH)


def test_pose_statistics_matches_samples_and_order_is_irrelevant():
    rng = np.random.default_rng(3)
    th = np.radians([10, 70, 130, 190, 250, 310])
    acc, lab = samples(rng, th, 50)
    ps = pose_statistics(acc, lab)
    for k in range(6):
        sel = lab == k
        assert np.allclose(ps.means[k], acc[sel].mean(axis=0), rtol=0, atol=1e-12)
        assert np.allclose(ps.ss[k], ((acc[sel] - acc[sel].mean(0)) ** 2).sum(0), rtol=1e-12)
    perm = rng.permutation(lab.size)
    f1 = fit_multiposition(ps, SIGMA2)
    f2 = fit_multiposition(pose_statistics(acc[perm], lab[perm]), SIGMA2)
    assert np.allclose(f1.params, f2.params, rtol=0, atol=1e-13)
    # moving samples (label −1) are left out
    lab2 = lab.copy()
    lab2[::7] = -1
    assert pose_statistics(acc, lab2).n.sum() == np.count_nonzero(lab2 >= 0)


@pytest.mark.parametrize("seed", range(5))
def test_noiseless_poses_give_the_exact_parameters(seed):
    rng = np.random.default_rng(seed)
    P = int(rng.integers(4, 10))
    th = np.sort(rng.uniform(0, 2 * np.pi, P))
    th[: P // 2] = np.linspace(0, np.pi, P // 2, endpoint=False)  # keep them spread
    truth = np.array([rng.normal(0, 0.2), rng.normal(0, 0.03), rng.normal(0, 0.2),
                      rng.normal(0, 0.03)])
    poses = Poses(np.arange(P), np.full(P, 10), model_means(truth, th), np.ones((P, 2)))
    fit = fit_multiposition(poses, SIGMA2)
    assert np.allclose(fit.params, truth, rtol=0, atol=1e-9)
    assert np.allclose(np.cos(fit.angles - th), 1.0, rtol=0, atol=1e-12)
    assert fit.dof == P - 4 and fit.rank == 4 + P


def test_estimated_sigma2_is_the_pure_error():
    rng = np.random.default_rng(5)
    acc, lab = samples(rng, np.radians(np.arange(0, 360, 45)), 300)
    ps = pose_statistics(acc, lab)
    fit = fit_multiposition(ps, None)
    assert fit.sigma2_source == "estimated" and fit.sigma2_dof == acc.shape[0] - 8
    assert np.allclose(fit.sigma2, ps.ss.sum(0) / (acc.shape[0] - 8), rtol=1e-12)
    # the pure-error variance is within its χ² spread of the truth (dof 2392: rel. sd 2.9 %)
    assert np.all(np.abs(fit.sigma2 / SIGMA2 - 1) <= 4 * np.sqrt(2 / fit.sigma2_dof))
    assert fit.quantile(0.95) > 1.959964  # Student t, not normal


def test_identifiability_is_reported():
    th = np.radians(np.arange(0, 360, 60))
    fit = fit_multiposition(Poses(np.arange(6), [100] * 6, model_means(TRUTH, th),
                                  np.ones((6, 2))), SIGMA2)
    assert fit.max_gap == pytest.approx(np.pi / 3, abs=1e-9)
    assert fit.rank == 10 and 1 <= fit.cond < 10
    text = fit.summary()
    assert "6 poses" in text and "largest gap between pose directions 60.0°" in text


def _poses(deg, n=200, seed=0, noise=True):
    rng = np.random.default_rng(seed)
    th = np.radians(deg)
    m = model_means(TRUTH, th)
    if noise:
        m = m + rng.standard_normal(m.shape) * np.sqrt(SIGMA2 / n)
    return Poses(np.arange(len(deg)), np.full(len(deg), n), m, np.ones((len(deg), 2)))


def test_too_few_poses_is_refused_with_the_count_and_why():
    with pytest.raises(NotIdentifiableError, match=r"3 held poses.*at least 4.*4 unknowns"):
        fit_multiposition(_poses([0, 120, 240]), SIGMA2, source="log.csv")
    with pytest.raises(NotIdentifiableError, match="^log.csv: "):
        fit_multiposition(_poses([0, 120, 240]), SIGMA2, source="log.csv")


def test_repeated_orientations_count_once():
    poses = _poses([0, 0, 90, 90, 180, 180])
    assert distinct_orientations(poses, SIGMA2) == 3
    with pytest.raises(NotIdentifiableError, match="only 3 distinct orientations"):
        fit_multiposition(poses, SIGMA2)


def test_poses_that_do_not_turn_an_axis_name_its_scale():
    with pytest.raises(NotIdentifiableError, match="cannot identify scale_x"):
        fit_multiposition(_poses([0, 180, 0.5, 180.5, 1.0]), SIGMA2)
    with pytest.raises(NotIdentifiableError, match="cannot identify scale_y"):
        fit_multiposition(_poses([90, 270, 90.5, 270.5, 91]), SIGMA2)


@pytest.mark.parametrize("deg, named", [
    ([20, 160, 200, 340], "scale_x"),          # symmetric about both axes: a family fits
    ([0, 5, 10, 15, 20, 25], "scale_y"),       # a narrow arc
])
def test_poses_that_do_not_spread_are_refused_naming_the_parameter(deg, named):
    with pytest.raises(NotIdentifiableError, match=f"do not identify.*{named}|cannot "
                       f"identify.*{named}"):
        fit_multiposition(_poses(deg), SIGMA2)


def test_half_turn_is_accepted_with_a_larger_std():
    half = fit_multiposition(_poses([0, 30, 60, 90, 120, 150]), SIGMA2)
    full = fit_multiposition(_poses([0, 60, 120, 180, 240, 300]), SIGMA2)
    assert np.all(half.std > full.std)
    assert half.std[1] < UNIDENTIFIED_STD["scale"]


def test_poorly_spread_poses_warn():
    with pytest.warns(PoorlyIdentifiedWarning, match="condition number"):
        fit_multiposition(_poses([0, 10, 20, 30, 40, 50], n=20000), SIGMA2)


def test_single_sample_poses_need_the_noise():
    poses = Poses(np.arange(6), np.ones(6, int),
                  model_means(TRUTH, np.radians(np.arange(0, 360, 60))), np.zeros((6, 2)))
    with pytest.raises(DataError, match="single sample.*--noise-var"):
        fit_multiposition(poses, None)
    assert fit_multiposition(poses, SIGMA2).dof == 2


def test_out_of_plane_poses_are_left_out_with_a_warning():
    """A 3-axis IMU's six-position log: the z-up/z-down poses read ≈ 0 on x and y."""
    base = _poses([0, 90, 180, 270, 45, 225])
    means = np.vstack([base.means, [[0.05, 0.02], [-0.03, 0.01]]])
    poses = Poses(np.arange(8), np.full(8, 200), means, np.ones((8, 2)))
    with pytest.warns(OutOfPlaneWarning, match="poses 6, 7 left out"):
        fit = fit_multiposition(poses, SIGMA2)
    assert fit.poses.count == 6
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ref6 = fit_multiposition(base, SIGMA2)
    assert np.array_equal(fit.params, ref6.params)


def test_lack_of_fit_flags_a_misaligned_axis():
    """An x axis rotated by 2° about the hinge is outside the model: the pose means miss
    the ellipse by ≈ g·0.035 ≫ σ/√n; the joint χ² test rejects (p < 1e-6)."""
    rng = np.random.default_rng(11)
    th = np.radians(np.arange(0, 360, 30))
    acc, lab = samples(rng, th, 2000)
    delta = np.radians(2.0)
    thr = np.repeat(th, 2000)
    acc[:, 0] += (1 + TRUTH[1]) * -G * (np.sin(thr + delta) - np.sin(thr))
    fit = fit_multiposition(pose_statistics(acc, lab), SIGMA2)
    assert fit.lack_of_fit is not None and fit.lack_of_fit.p_value < 1e-6
    good = fit_multiposition(pose_statistics(*samples(rng, th, 2000)), SIGMA2)
    assert good.lack_of_fit.p_value > 1e-4


def test_round_trip_and_calibration_file(tmp_path):
    rng = np.random.default_rng(2)
    fit = fit_multiposition(pose_statistics(*samples(rng, np.radians(np.arange(0, 360, 45)),
                                                     100)), None)
    back = MultiPositionFit.from_dict(json.loads(json.dumps(fit.to_dict())))
    assert back == fit
    cal = fit.to_calibration()
    assert cal.method == "multiposition"
    assert np.array_equal(cal.params, fit.params) and np.array_equal(cal.cov, fit.cov)
    assert cal.cov[0, 2] != 0.0  # the shared angles couple the axes
    path = save_calibration(tmp_path / "cal.json", cal, sigma2_source="estimated")
    assert load_calibration(path) == cal
    # the t quantile of the pure error's dof travels with the calibration
    lo, hi = cal.fits["x"].conf_int(0.95)[0]
    assert (hi - lo) / 2 == pytest.approx(fit.conf_int(0.95)[0, 1] - fit.params[0], rel=1e-12)


def course_poses(ensayo, P=8, half=0.02):
    """Labels that turn the course sweep into P held poses: the samples within ±``half`` rad
    of P angles evenly spread (offset by half a step). Over ±0.02 rad the reading's mean
    differs from that at the centre by g·(1 − sinc) ≈ g·half²/6 ≈ 7e-4 m/s², under a tenth
    of σ/√n ≈ 0.045 m/s² (127 samples): the windows act as held poses."""
    centres = np.arange(P) * 2 * np.pi / P + np.pi / P
    d = np.angle(np.exp(1j * (ensayo.tita[:, None] - centres[None, :])))
    lab = np.full(ensayo.n, -1)
    for k in range(P):
        lab[np.abs(d[:, k]) < half] = k
    return lab


def test_course_positions_agree_with_least_squares(course_dir):
    """On the course run grouped into 8 poses, θ ignored: the multi-position estimates agree
    with the θ-based least squares on the same samples within the combined std (|z| ≤ 1
    for every parameter), and with the course answer (whole run) within 3 of their std."""
    e = read_ensayo(course_dir / "ensayo.mat")
    lab = course_poses(e)
    sel = lab >= 0
    fit = fit_multiposition(pose_statistics(e.datos, lab), ref.NOISE_VAR)
    ls = calibrate(Ensayo(e.tita[sel], e.datos[sel]), ref.NOISE_VAR)
    cmp = compare_methods(fit, ls)
    assert np.all(np.abs(cmp.z) <= 1.0), cmp.summary()
    course = np.array([ref.ESTIMATES[k][0] for k in ("bias_x", "scale_x", "bias_y",
                                                     "scale_y")])
    assert np.all(np.abs(fit.params - course) <= 3 * fit.std)
    # the angles come back: each pose's estimated θ is its window's centre within 4 std
    centres = np.angle(np.exp(1j * (np.arange(8) * np.pi / 4 + np.pi / 8)))
    assert np.all(np.abs(np.angle(np.exp(1j * (fit.angles - centres)))) <= 4 * fit.angles_std
                  + 0.02)
    assert "z = difference / sqrt" in cmp.summary()


def test_docs_python_example_runs():
    """The ```python block of docs/poses-calibration.md runs and recovers its parameters
    (bias 0.08, −0.02 m/s²; scale −0.03, 0.01) within 4 std."""
    import contextlib
    import io
    import re
    from pathlib import Path

    page = Path(__file__).resolve().parents[1] / "docs" / "poses-calibration.md"
    (code,) = re.findall(r"^```python\n(.*?)^```", page.read_text(encoding="utf-8"),
                         re.S | re.M)
    ns: dict = {"__name__": "__docs__"}
    with contextlib.redirect_stdout(io.StringIO()) as out:
        exec(compile(code, page.name, "exec"), ns)  # noqa: S102
    fit = ns["fit"]
    assert np.all(np.abs(fit.params - TRUTH) <= 4 * fit.std)
    assert "6 poses" in out.getvalue() and ns["cal"].method == "multiposition"


def test_figure_shows_every_pose_with_its_region_and_units(tmp_path):
    from matplotlib.patches import Ellipse

    from bench.figures.multiposition import multiposition_figure, save_multiposition_plot

    rng = np.random.default_rng(8)
    fit = fit_multiposition(pose_statistics(*samples(rng, np.radians(np.arange(0, 360, 45)),
                                                     200)), SIGMA2)
    fig = multiposition_figure(fit)
    ax, rx = fig.axes
    assert sum(isinstance(p, Ellipse) for p in ax.patches) == 8
    assert "m/s²" in ax.get_xlabel() and "m/s²" in ax.get_ylabel()
    assert "m/s²" in rx.get_ylabel() and "deg" in rx.get_xlabel()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("×" in t and "region of each mean" in t for t in labels)
    path = save_multiposition_plot(tmp_path / "mp.svg", fit)
    assert path.read_text().startswith("<?xml")
    with pytest.raises(FileExistsError):
        save_multiposition_plot(tmp_path / "mp.svg", fit)

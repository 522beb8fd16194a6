"""The six-face test (:mod:`calib.calibration.sixface`): coverage of every interval, with and
without hold-to-hold repeatability, at the minimum number of holds and under a placement
tilt, the lack-of-fit test's false alarms and power.

Generator (written here from the physics, not from the fitted model): each sensitive axis a
is a unit vector ``d_a`` tilted from case axis a by small angles; a still sensor on a face
reads ``b_a + β_h,a + (1 + s_a)·(d_a · g u'_h) + w``, with ``β_h,a ~ N(0, σ_B²)`` a bias that
changes from hold to hold (turn-on repeatability), white ``w ~ N(0, σ_W²)``, and ``u'_h`` the
face's up direction ``u_h`` rotated by the case's placement tilt of that hold: angles
``δ ~ N(0, σ_δ²)`` about the two horizontal case axes (Rodrigues). The tilt moves an axis that
lies level by ``g·δ`` and one along gravity by ``g·(1 − cos δ)`` — which is what the fit's two
classes of σ_B model, but the generator knows nothing of them. The truth in the fit's
parameters follows from the geometry: ``scale_a = (1 + s_a)·d_aa − 1`` and
``m_ab = d_ab / d_aa``. Sample statistics go through the log code
(:func:`calib.calibration.multiposition.pose_statistics`).

Band (STYLE): each parameter's 95 % interval covers in ``hits`` of R runs; with R = 400 the
binomial std is √(0.95·0.05/400) = 0.0109, and ``|hits/R − 0.95| ≤ 4·0.0109``. Run on four
designs (12 parameters each): no between-hold component with every face twice (the intervals
must not be wider than chance: the upper edge of the band), a dominant one with every face
three times, the minimum — six faces once, repeatability not measured — and a placement tilt
σ_δ = 0.002 rad with a bias repeatability of 0.003 m/s², each face held 2–3 times. Measured at
these seeds (per-parameter coverage, min–max over the 12, mean):

=====================  ===========================  ===========================
design                 one σ_B per axis (before)    two classes, per-parameter dof
=====================  ===========================  ===========================
no between-hold        0.958–0.988 (0.973)          0.965–0.988 (0.976)
σ_B dominant           0.945–0.973 (0.958)          0.938–0.978 (0.957)
six holds              0.940–0.970 (0.958)          0.940–0.970 (0.958)
placement tilt         0.873–1.000 (0.944)          0.950–0.970 (0.959)
=====================  ===========================  ===========================

Before, under the tilt the scales covered 0.998–1.000 (intervals 2.6–2.8× as wide as the two
classes give) and the misalignments 0.87–0.935 (intervals 0.78× as wide). With σ_B = 0 the
truncated ANOVA estimates err on the wide side (inside the band: 0.983–0.993 at the highest
over seeds 11–14; before, 0.980–0.990). With a σ_B that is the same in both classes the two
classes cost width: 7–24 % wider intervals than one pooled σ_B (fewer dof per class; the scale
most). Every design is also a null
for the lack-of-fit test: its false-alarm rate per axis is 0.03–0.06 (placement tilt 0.052–
0.058; the pooled test of before: 0.070–0.085), against the band's edge 0.094.
"""

import numpy as np
import pytest

from calib.calibration.ls import NotIdentifiableError
from calib.calibration.multiposition import pose_statistics
from calib.calibration.sixface import fit_six_face
from calib.input_rules import DataError

G = 9.81
R = 400
BAND = 4 * np.sqrt(0.95 * 0.05 / R)
FACES = np.vstack([np.eye(3), -np.eye(3)])


def _sensor(rng):
    bias = rng.normal(0, 0.1, 3)
    scale = rng.normal(0, 0.02, 3)
    d = np.eye(3) + rng.normal(0, 0.005, (3, 3)) * (1 - np.eye(3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    truth = []
    for a in range(3):
        others = [j for j in range(3) if j != a]
        truth += [bias[a], (1 + scale[a]) * d[a, a] - 1, *(d[a, j] / d[a, a] for j in others)]
    return bias, scale, d, np.array(truth)


def _tilted(rng, face, tilt: float):
    """The up direction of a hold placed on ``face`` (±e_k) tilted by the case's placement: a
    rotation by δ ~ N(0, tilt²) about each of the two horizontal case axes (Rodrigues; the
    rotation vector is perpendicular to the face, so ``u' = cos|δ|·u + sin|δ|·δ̂ × u``)."""
    k = int(np.argmax(np.abs(face)))
    d = np.zeros(3)
    d[[j for j in range(3) if j != k]] = rng.normal(0, tilt, 2)
    angle = float(np.sqrt(d @ d))
    if angle == 0.0:
        return face
    cross = np.array([d[1] * face[2] - d[2] * face[1], d[2] * face[0] - d[0] * face[2],
                      d[0] * face[1] - d[1] * face[0]])  # δ × u
    return np.cos(angle) * face + np.sin(angle) / angle * cross


def _log(rng, repeats, n: int, sigma_w: float, sigma_b: float, k2_z: float = 0.0,
         tilt: float = 0.0):
    """Every face held ``repeats`` times (``(lo, hi)``: each face a random lo–hi times; a
    list: the count of each face +x, +y, +z, -x, -y, -z), in shuffled order; ``tilt``: the
    placement tilt of each hold, rad."""
    bias, scale, d, truth = _sensor(rng)
    if isinstance(repeats, tuple):
        u = np.repeat(FACES, rng.integers(repeats[0], repeats[1] + 1, len(FACES)), axis=0)
    else:
        u = np.repeat(FACES, repeats, axis=0)
    rng.shuffle(u)
    acc, pose = [], []
    for h, face in enumerate(u):
        f = G * (_tilted(rng, face, tilt) if tilt else face)
        true = bias + rng.normal(0, sigma_b, 3) + (1 + scale) * (d @ f)
        true[2] += k2_z * (d[2] @ f) ** 2  # second-order term (IEEE 1293 K2) on z
        acc.append(true + rng.normal(0, sigma_w, (n, 3)))
        pose.append(np.full(n, h))
    return pose_statistics(np.vstack(acc), np.concatenate(pose)), truth


def _coverage(seed: int, repeats, sigma_b: float, tilt: float = 0.0):
    rng = np.random.default_rng(seed)
    hits = np.zeros(12)
    alarms = np.zeros(3)
    measured = 0
    for _ in range(R):
        poses, truth = _log(rng, repeats, n=50, sigma_w=0.03, sigma_b=sigma_b, tilt=tilt)
        fit = fit_six_face(poses, g=G)
        lo, hi = fit.conf_int(0.95).T
        hits += (lo <= truth) & (truth <= hi)
        alarms += fit.lack_of_fit_p < 0.05
        measured += fit.repeatability_measured
    return hits / R, alarms / R, measured


@pytest.mark.parametrize("seed, repeats, sigma_b, tilt",
                         [(1, 2, 0.0, 0.0), (2, 3, 0.02, 0.0), (3, 1, 0.0, 0.0),
                          (4, (2, 3), 0.003, 0.002)],
                         ids=["no-between-hold", "between-hold-dominant", "six-holds-minimum",
                              "placement-tilt"])
def test_every_interval_covers_at_its_stated_rate(seed, repeats, sigma_b, tilt):
    """Every design is a null for the lack-of-fit test (the linear model is right): its
    false-alarm rate per axis stays within the binomial band of α = 0.05 too."""
    cover, alarms, measured = _coverage(seed, repeats, sigma_b, tilt)
    assert np.all(np.abs(cover - 0.95) <= BAND), (cover, BAND)
    assert np.all(alarms <= 0.05 + 4 * np.sqrt(0.05 * 0.95 / R)), alarms
    assert measured == (R if repeats != 1 else 0)


def test_placement_tilt_moves_the_level_holds_only():
    """σ_δ = 0.002 rad: each axis' σ_B is ≈ g·σ_δ = 0.020 m/s² on the faces where it lies
    level and the bias repeatability (0.003 m/s²) on ±a; the scale (read from ±a) keeps the
    vertical class' dof, the misalignments the level class': with every face twice, exactly
    2 and about 4 (the scale's G has no weight on the level holds; m_ab leans on K_aa only
    by K_ab/K_aa²). A σ_B pooled over all holds gave the scale 5–8× too wide intervals."""
    rng = np.random.default_rng(17)
    fits = [fit_six_face(_log(rng, 2, 50, 0.03, 0.003, tilt=0.002)[0], g=G) for _ in range(30)]
    sb = np.median([f.sigma_between for f in fits], axis=0)  # (3, 2)
    assert np.all((sb[:, 1] > 0.013) & (sb[:, 1] < 0.028)), sb
    assert np.all(sb[:, 0] < 0.006), sb
    for f in fits:
        assert f.dof.shape == (12,)
        for a in range(3):
            if f.sigma_between[a, 0] > 0 and not f.misfit_in_intervals[a]:
                assert f.dof[4 * a + 1] == pytest.approx(2.0, rel=1e-6)
            if f.sigma_between[a, 1] > 0 and not f.misfit_in_intervals[a]:
                assert f.dof[4 * a + 2:4 * a + 4] == pytest.approx(4.0, rel=0.02)
    lines = fits[0].repeatability_line().splitlines()
    assert lines[0].startswith("σ_B (m/s², axis vertical / level): x ")
    assert max(len(line) for line in lines) <= 100


def test_a_class_with_no_reheld_face_borrows_the_others():
    """Only ±x held twice: for x the level class has no re-held face and takes the vertical
    class' σ_B; for y and z the vertical class takes the level one (±x lie level for them).
    The summary marks them, and the fit reads back equal."""
    from calib.calibration.sixface import SixFaceFit
    rng = np.random.default_rng(23)
    fit = fit_six_face(_log(rng, [2, 1, 1, 2, 1, 1], 50, 0.03, 0.01)[0], g=G)
    assert fit.borrowed().tolist() == [[False, True], [True, False], [True, False]]
    sb = fit.sigma_between
    assert sb[0, 1] == sb[0, 0] and sb[1, 0] == sb[1, 1] and sb[2, 0] == sb[2, 1]
    assert "* no face of that class held twice" in fit.summary()
    assert SixFaceFit.from_dict(fit.to_dict()) == fit
    assert fit.hold_dof().shape == (8, 3) and np.all(fit.hold_dof() > 0)


def test_repeatability_widens_only_when_present():
    rng = np.random.default_rng(7)
    wide = [fit_six_face(_log(rng, 3, 50, 0.03, 0.02)[0], g=G).widening for _ in range(20)]
    none = [fit_six_face(_log(rng, 3, 50, 0.03, 0.0)[0], g=G).widening for _ in range(20)]
    # σ_B = 0.02 m/s² against σ_W/√n = 0.0042: the bias interval is several times wider
    assert np.median(wide) > 3.0
    assert np.median(none) < 1.5
    fit = fit_six_face(_log(rng, 1, 50, 0.03, 0.0)[0], g=G)
    assert "not measured" in fit.repeatability_line()
    assert np.all(np.isnan(fit.sigma_between))


def _log_with_face_errors(rng, sigma_f: float, n: int = 50, sigma_w: float = 0.03,
                          sigma_b: float = 0.003):
    """Each face carries its own error ``φ_f ~ N(0, σ_F²)`` per axis, shared by its re-holds (a
    face that is not flat); faces held 1–3 times in shuffled order."""
    bias, scale, d, truth = _sensor(rng)
    phi = rng.normal(0, sigma_f, (6, 3))
    faces = np.repeat(np.arange(6), rng.integers(1, 4, 6))
    rng.shuffle(faces)
    acc, pose = [], []
    for h, fi in enumerate(faces):
        true = bias + phi[fi] + rng.normal(0, sigma_b, 3) + (1 + scale) * (d @ (G * FACES[fi]))
        acc.append(true + rng.normal(0, sigma_w, (n, 3)))
        pose.append(np.full(n, h))
    return pose_statistics(np.vstack(acc), np.concatenate(pose)), truth


@pytest.mark.slow
def test_a_misfit_the_test_sees_is_in_the_intervals():
    """R = 300 logs (seed 21) whose faces are not flat: σ_F = 0.05 m/s² per face and axis,
    against a hold-mean noise σ_W/√n = 0.0042 m/s². The lack-of-fit test flags most axes (its
    power, ≥ 80 %), and on the flagged axes each parameter's 95 % interval — from the face
    means' scatter, Student t on F − 4 dof — covers at least at its rate. The four parameters
    of an axis share one s², so the unit of the band is the flagged axis-fit, m ≈ 860: the
    coverage must not fall below 0.95 − 4·√(0.95·0.05/m) (−0.030). It is conservative
    (measured 0.969: a pre-test picks the fits whose scatter came out large), and stays below
    0.995, far from the useless. Without the rule those intervals count the repeatability
    alone and cover about a quarter of the time."""
    rng = np.random.default_rng(21)
    hits, flagged = [], 0
    for _ in range(300):
        poses, truth = _log_with_face_errors(rng, 0.05)
        fit = fit_six_face(poses, g=G)
        lo, hi = fit.conf_int(0.95).T
        for a in range(3):
            if fit.misfit_in_intervals[a]:
                flagged += 1
                hits.extend(((lo <= truth) & (truth <= hi))[4 * a:4 * a + 4])
    assert flagged >= 0.8 * 900
    cover = float(np.mean(hits))
    assert 0.95 - 4 * np.sqrt(0.95 * 0.05 / flagged) <= cover < 0.995, cover
    fit = fit_six_face(_log_with_face_errors(np.random.default_rng(5), 0.05)[0], g=G)
    if any(fit.misfit_in_intervals):
        assert "lack of fit on" in fit.summary() and "Student t" in fit.summary()


def test_lack_of_fit_catches_a_missing_second_order_term():
    """Power of the per-axis F test (α = 0.05) with every face twice, σ_B = 0.01 m/s²: a K2 of
    z of 5e-4 /(m/s²) (0.048 m/s² at 1 g, ≈ 5 σ of a hold mean) is caught in at least 80 % of
    100 runs, and z's false-alarm rate without it stays below 0.05 + 4·√(0.05·0.95/100)."""
    rng = np.random.default_rng(11)
    caught = [fit_six_face(_log(rng, 2, 50, 0.03, 0.01, k2_z=5e-4)[0], g=G).lack_of_fit_p[2]
              < 0.05 for _ in range(100)]
    false = [fit_six_face(_log(rng, 2, 50, 0.03, 0.01)[0], g=G).lack_of_fit_p[2] < 0.05
             for _ in range(100)]
    assert np.mean(caught) >= 0.8
    assert np.mean(false) <= 0.05 + 4 * np.sqrt(0.05 * 0.95 / 100)


def test_noiseless_faces_give_the_exact_geometry():
    rng = np.random.default_rng(5)
    poses, truth = _log(rng, 2, 50, 1e-9, 0.0)
    fit = fit_six_face(poses, g=G)
    np.testing.assert_allclose(fit.params, truth, atol=1e-9)


def test_designs_that_cannot_identify_are_named():
    rng = np.random.default_rng(6)
    poses, _ = _log(rng, 1, 50, 0.03, 0.0)
    keep = np.abs(poses.means[:, 2]) < 5  # drop both z faces
    from calib.calibration.multiposition import Poses
    sub = Poses(poses.labels[keep], poses.n[keep], poses.means[keep], poses.ss[keep])
    with pytest.raises(NotIdentifiableError, match=r"misalignment_xz.*\+z, -z"):
        fit_six_face(sub, g=G)


def test_a_tilted_hold_is_not_a_face():
    from calib.calibration.multiposition import Poses
    means = np.vstack([G * FACES, [[G * 0.7, G * 0.7, 0.5]]])
    with pytest.raises(DataError, match="hold 6 is not on a face"):
        fit_six_face(Poses(np.arange(7), np.full(7, 10), means, np.ones((7, 3))), g=G)


def test_round_trip_and_summary_units():
    from calib.calibration.sixface import SixFaceFit
    rng = np.random.default_rng(8)
    fit = fit_six_face(_log(rng, 2, 50, 0.03, 0.01)[0], g=G, g_source="--g")
    assert SixFaceFit.from_dict(fit.to_dict()) == fit
    text = fit.summary()
    assert "m/s²" in text and "rad" in text and "95 % interval" in text
    assert max(len(line) for line in text.splitlines()) <= 100
    fit6 = fit_six_face(_log(rng, 1, 50, 0.03, 0.0)[0], g=G)
    assert SixFaceFit.from_dict(fit6.to_dict()) == fit6


def test_readings_without_scatter_are_refused_not_divided_by_zero():
    from calib.calibration.multiposition import Poses
    means = 9.81 * np.repeat(FACES, 2, axis=0)
    ss = np.ones((12, 3))
    ss[:, 1] = 0.0  # y never changes within a hold (coarse quantization)
    with pytest.raises(DataError, match="axis y does not vary within any hold"):
        fit_six_face(Poses(np.arange(12), np.full(12, 50), means, ss), g=G)

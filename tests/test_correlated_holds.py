"""Holds whose noise is correlated (a low-pass filtered or decimated log: a phone export at
10 Hz) count their samples over the integrated autocorrelation time in the intervals
(:func:`calib.calibration.lackoffit.integrated_correlation`), so a six-face fit on
such a log keeps its coverage without a spurious lack of fit, and white logs keep their
counts.

The noise is made here with scipy.signal — white noise through a 4-pole Butterworth low-pass
at 0.3 Hz sampled at 10 Hz, τ_int = (Σh)²/Σh² = 16.3 samples — not by the bench. Before the
correction 85 % of such six-face fits flagged a lack of fit ("a term is missing or a face is
not flat") and fell back on dof-2 intervals from the face means.
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from calib.calibration.lackoffit import integrated_correlation
from calib.calibration.multiposition.shared import pose_statistics
from calib.calibration.sixface import fit_six_face
from tests.cli import run

G = 9.80665
FACES = np.array([(0, 0, 1), (0, 0, -1), (1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0)], float)
B, A = signal.butter(4, 0.3, fs=10.0)
TRUE_TAU = 16.25  # (Σh)²/Σh² of the filter's impulse response
SCALE, BIAS = np.array([1.01, 0.99, 1.005]), np.array([0.05, -0.03, 0.08])
HOLD = 300


def filtered(rng, shape) -> np.ndarray:
    return signal.lfilter(B, A, rng.standard_normal((shape[0] + 2000, *shape[1:])),
                          axis=0)[2000:]


def six_face_log(seed: int, white: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(readings (1800, 3) m/s², pose labels): six faces held 30 s each at 10 Hz."""
    rng = np.random.default_rng(seed)
    acc = np.repeat(FACES * G, HOLD, axis=0)
    noise = rng.standard_normal(acc.shape) if white else filtered(rng, acc.shape)
    return acc * SCALE + BIAS + 0.01 * noise, np.repeat(np.arange(6), HOLD)


def test_the_integrated_correlation_time_of_filtered_and_white_noise():
    pose = np.repeat(np.arange(6), HOLD)
    est = []
    for seed in range(30):
        x = filtered(np.random.default_rng(seed), (6 * HOLD,))
        for k in range(6):
            x[pose == k] -= x[pose == k].mean()
        est.append(integrated_correlation(x[:, None], pose)[0])
    assert 0.8 * TRUE_TAU < np.median(est) < 1.2 * TRUE_TAU
    white = [pose_statistics(*six_face_log(s, white=True)).tau_int
             for s in range(50)]
    assert white == [1.0] * 50  # white logs keep their counts


def test_six_face_intervals_cover_on_filtered_holds():
    """R = 200 logs: each bias and scale's 95 % interval covers within the binomial band
    (3 sd: 0.904–0.996), and the lack of fit fires near its 5 % (≤ 0.05 + 3 sd over 600 axis
    tests: 0.077), against 85 % before holds counted their correlation."""
    from scipy import stats

    truth = {"bias_x": BIAS[0], "scale_x": SCALE[0] - 1, "bias_y": BIAS[1],
             "scale_y": SCALE[1] - 1, "bias_z": BIAS[2], "scale_z": SCALE[2] - 1}
    r = 200
    hits = dict.fromkeys(truth, 0)
    flags = 0
    for seed in range(r):
        poses = pose_statistics(*six_face_log(seed))
        assert poses.tau_int > 5.0
        fit = fit_six_face(poses, g=G, level=0.95)
        flags += sum(fit.misfit_in_intervals)
        dof = np.atleast_1d(fit.dof)
        for i, name in enumerate(fit.param_names):
            if name in truth:
                q = stats.t.ppf(0.975, dof["xyz".index(name[-1])] if dof.size == 3 else dof[0])
                hits[name] += abs(fit.params[i] - truth[name]) <= q * fit.std[i]
    sd = np.sqrt(0.95 * 0.05 / r)
    for name, h in hits.items():
        assert 0.95 - 3 * sd <= h / r <= 0.95 + 3 * sd, (name, h / r)
    assert flags / (3 * r) <= 0.05 + 3 * np.sqrt(0.05 * 0.95 / (3 * r)), flags


def test_calibrate_says_the_holds_are_correlated(tmp_path, capsys):
    acc, _ = six_face_log(3)
    moves = [np.linspace(a, b, 40) + 0.3 for a, b in zip(FACES[:-1] * G, FACES[1:] * G,
                                                         strict=True)]
    parts = [acc[:HOLD]]
    for k, mv in enumerate(moves):
        parts += [mv, acc[(k + 1) * HOLD:(k + 2) * HOLD]]
    log = np.concatenate(parts)
    t = np.arange(log.shape[0]) / 10.0
    path = tmp_path / "six.csv"
    np.savetxt(path, np.column_stack([t, log]), delimiter=",", fmt="%.8g", comments="",
               header="t (s),ax (m/s^2),ay (m/s^2),az (m/s^2)")
    rc, out, err = run(capsys, "calibrate", path)
    assert rc == 0, err
    said = " ".join(err.split())
    assert "the noise within the holds is correlated" in said
    shown = " ".join(out.split())
    assert "six-face calibration" in shown and "6 holds on 6 faces" in shown


def test_theta_least_squares_with_groups_cover_on_filtered_holds():
    """The θ-based least squares with repeated poses (groups): twelve angles held 30 s at
    10 Hz with Butterworth-filtered noise, R = 200. σ² from the pure error, read per τ_int
    samples: each bias and scale's 95 % interval (Student t on the effective pure-error dof)
    covers within the binomial band, and the lack of fit fires near its 5 %."""
    from scipy import stats

    from calib import Ensayo, calibrate
    from calib.calibration.lackoffit import groups_from

    th = np.repeat(np.radians(np.arange(0, 360, 30)), HOLD)
    ref = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)])
    truth = {"x": (0.05, 0.01), "y": (-0.03, -0.02)}
    r = 200
    hits, flags, taus = 0, 0, []
    for seed in range(r):
        noise = 0.02 * filtered(np.random.default_rng(seed), ref.shape)
        datos = ref * (1 + np.array([0.01, -0.02])) + np.array([0.05, -0.03]) + noise
        cal = calibrate(Ensayo(th, datos), groups=groups_from(th))
        for a, (b, s) in truth.items():
            fit = cal.fits[a]
            taus.append(fit.extra.get("tau_int", 1.0))
            q = stats.t.ppf(0.975, fit.extra["sigma2_dof"])
            hits += abs(fit.params[0] - b) <= q * fit.std[0]
            hits += abs(fit.params[1] - s) <= q * fit.std[1]
        flags += sum(v.p_value < 0.05 for v in cal.lack_of_fit.values())
    assert np.median(taus) > 8.0
    sd = np.sqrt(0.95 * 0.05 / (4 * r))
    assert 0.95 - 3 * sd <= hits / (4 * r) <= 0.95 + 3 * sd, hits / (4 * r)
    assert flags / (2 * r) <= 0.05 + 3 * np.sqrt(0.05 * 0.95 / (2 * r)), flags
    white = calibrate(Ensayo(th, ref + 0.02 * np.random.default_rng(9).standard_normal(
        ref.shape)), groups=groups_from(th))
    assert "tau_int" not in white.fits["x"].extra  # white samples keep their counts

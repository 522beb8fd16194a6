"""Pictures of a fused turning run: the turning dead reckoning (calib.vehicle.turning_trajectory)
against MuJoCo's truth, and ``tiltbench fuse --plot/--rrd`` on a generated turning course set.

Dead reckoning against the truth. The bench holds the world acceleration ``a_k = R(ψ_k) A_k``
over each step ``[t_k, t_k+1)`` (bench.vehicle) and its yaw acceleration likewise, so the
truth is exactly the zero-order-hold recursion ``v⁺ = v + a h``, ``p⁺ = p + v h + a h²/2``
and ψ is exactly the trapezoid of ω (linear over a step). The double cumulative trapezoid of
the same samples (the dead reckoning's integrator) differs from that recursion by exactly::

    e_k = (h²/4) Σ_{j<k} (a_j + a_{j+1} - 2 a_0)

(trapezoid V_k = v_k + h (a_k - a_0)/2; summing its trapezoid against the exact step), so
``|e_k| ≤ h t_k max_j |a_j - a_0| / 2``. With the true calibration and noise-free readings the
dead reckoning must equal the truth plus e_k up to floating-point rounding (1e-9 m over 6000
steps of ~1e-13 m each; measured 3e-11 m), and lie within the bound. With a wrong calibration
the path drifts by the double integral of ``R(ψ) (Â - A_r)``: at the end
``Σ_k w_k R(ψ_k) (Â_k - A_r,k)`` with the trajectory weights ``w``
(:func:`calib.vehicle.trajectory.double_integral_weights`) — an independent route to the same
number.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from bench.cli import main
from bench.vehicle import VehicleConfig, simulate_vehicle
from calib.calibration.correct import apply_errors, correct
from calib.fusion.turning import body_to_world
from calib.vehicle.trajectory import double_integral_weights
from calib.vehicle.turning_trajectory import (
    TurningTrajectory,
    heading_error,
    turning_dead_reckoning,
)

BIAS = np.array([0.08, -0.05])    # m/s², true
SCALE = np.array([-0.03, 0.02])   # true
ROUNDING = 1e-9                   # m, floating-point budget over 6000 steps


@pytest.fixture(scope="module")
def truth():
    return simulate_vehicle(VehicleConfig(turning=True))  # the course's 60 s at 100 Hz


def test_dead_reckoning_with_the_true_calibration_is_the_truth_up_to_the_trapezoid(truth):
    tr = truth
    a_m = apply_errors(tr.acc, BIAS, SCALE)               # noise-free readings
    dr = turning_dead_reckoning(tr.t, a_m, tr.yaw_rate, BIAS, SCALE, tr.pos[0], tr.vel[0],
                                psi0=float(tr.heading[0]))
    assert np.max(np.abs(dr.heading - tr.heading)) < 1e-12  # rad: trapezoid exact here
    h = float(tr.t[1] - tr.t[0])
    a = body_to_world(tr.heading, tr.acc)
    e = np.vstack([np.zeros(2), h * h / 4 * np.cumsum(a[:-1] + a[1:] - 2 * a[0], axis=0)])
    err = dr.pos - tr.pos
    assert np.max(np.abs(err - e)) < ROUNDING
    bound = h * (tr.t - tr.t[0])[:, None] * np.max(np.abs(a - a[0]), axis=0) / 2
    assert np.all(np.abs(err) <= bound + ROUNDING)
    assert np.max(np.abs(err)) > 0.01  # the integration error is real (cm), not zero
    assert TurningTrajectory.from_dict(dr.to_state()) == dr


def test_a_wrong_calibration_drifts_by_the_rotated_double_integral(truth):
    tr = truth
    a_m = apply_errors(tr.acc, BIAS, SCALE)
    args = (tr.t, a_m, tr.yaw_rate)
    init = (tr.pos[0], tr.vel[0])
    psi0 = float(tr.heading[0])
    # calibration errors of a few σ of the course's calibration (σ_b ≈ 4e-3 m/s²)
    b_hat, s_hat = BIAS + [0.012, -0.009], SCALE + [1e-3, -2e-3]
    good = turning_dead_reckoning(*args, BIAS, SCALE, *init, psi0=psi0)
    bad = turning_dead_reckoning(*args, b_hat, s_hat, *init, psi0=psi0)
    w = double_integral_weights(tr.t)
    expected = w @ body_to_world(tr.heading, correct(a_m, b_hat, s_hat) - tr.acc)
    drift = bad.pos[-1] - good.pos[-1]
    assert np.allclose(drift, expected, rtol=0, atol=1e-8)
    assert np.hypot(*drift) > 10.0  # metres: far above the cm of the integrator
    # the heading comes from the gyro alone: the calibration does not touch it
    assert np.array_equal(bad.heading, good.heading)


def test_heading_error_wraps_and_interpolates():
    t = np.array([0.0, 1.0, 2.0])
    psi = np.array([3.1, 3.2, 3.3])                      # past π: unwrapped
    err = heading_error(t, psi, [0.5, 2.0], [3.15 - 2 * np.pi, 3.3])
    assert np.allclose(err, [0.0, 0.0], atol=1e-12)


@pytest.fixture(scope="module")
def turning_set(tmp_path_factory):
    out = tmp_path_factory.mktemp("turnpic") / "tc"
    assert main(["generate", "course", "--turning", "--gps", "--seed", "3",
                 "--out", str(out)]) == 0
    return out


def _inputs(d):
    return [str(a) for a in ("--acel", d / "acel.mat", "--gps", d / "gps.mat", "--puntos",
                             d / "puntos.mat", "--datos", d / "datos.txt", "--ensayo",
                             d / "ensayo.mat")]


def test_fuse_writes_the_figure_and_the_recording_of_a_turning_run(capsys, turning_set,
                                                                  tmp_path):
    from bench.record import read_recording, recording_entities
    from bench.record.reader import read_blueprint
    from bench.record.schema import documented

    png, rrd = tmp_path / "f.png", tmp_path / "f.rrd"
    assert main(["fuse", *_inputs(turning_set), "--plot", str(tmp_path / "t.png")]) == 0
    assert "decision (dead reckoning): D" in capsys.readouterr().out  # text: both decisions
    assert main(["fuse", *_inputs(turning_set), "--plot", str(png), "--rrd", str(rrd),
                 "--json"]) == 0
    fused = json.loads(capsys.readouterr().out)
    assert png.stat().st_size > 0
    truth = json.loads((turning_set / "truth.json").read_text())
    back = read_recording(rrd)
    assert back["truth"] == truth
    rep = back["fusion_report"]
    assert rep["final_position"] == fused["fusion"]["final_position"]
    assert len(rep["dead_reckoning_std"]) == 2 and min(rep["dead_reckoning_std"]) > 1.0
    ents = {str(e).lstrip("/") for e in recording_entities(rrd)}
    for e in ("vehicle/plane/path/true", "vehicle/plane/path/corrected", "vehicle/plane/fixes",
              "vehicle/plane/fused/path", "vehicle/plane/fused/ellipses",
              "fusion/innovation/x", "fusion/heading/fused", "fusion/heading/true",
              "fusion/heading/dead_reckoning", "fusion/heading_std",
              "fusion/heading_error/fused", "fusion/heading_error_band/plus",
              "vehicle/plane/arrival/ellipse", "vehicle/plane/arrival/estimate",
              "fusion/nis/used", "fusion/window_nis/sum", "fusion/window_nis/band/hi",
              "summary/consistency"):
        assert e in ents, e
    # the extended filter's doubts are recorded as `fuse --json` states them
    assert rep["consistent"] is fused["consistent"] is True
    assert rep["consistency"] == fused["consistency"]
    assert [e for e in ents if documented(e) is None
            or "fusion" not in documented(e).kinds] == []
    names = [v["name"] for v in read_blueprint(rrd)["views"]]
    assert any(n.startswith("heading ψ") for n in names)
    assert not any("no region" in n for n in names)
    # never overwritten without --force
    assert main(["fuse", *_inputs(turning_set), "--plot", str(png)]) == 2
    assert "--force" in capsys.readouterr().err


def test_turning_figure_has_the_dead_reckoning_region_and_a_heading_panel(turning_set):
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon

    from bench.figures.fusion import fusion_figure
    from calib.calibration.tilt_plane import calibrate
    from calib.files.course import read_acel, read_datos, read_ensayo, read_gps, read_puntos
    from calib.fusion.turning import fuse_turning
    from calib.vehicle.turning_trajectory import turning_arrival_region

    d = read_datos(turning_set / "datos.txt")
    acel, fixes = read_acel(turning_set / "acel.mat"), read_gps(turning_set / "gps.mat")
    cal = calibrate(read_ensayo(turning_set / "ensayo.mat"), d.noise_var, "ols")
    res = fuse_turning(acel.t, acel.aerr, acel.gyro, fixes.t_gps, fixes.pos, bias=cal.bias,
                       scale=cal.scale, cal_cov=cal.cov, noise_var=d.noise_var,
                       gyro_var=0.005 ** 2, sigma_pos=3.0, p0=d.p0, v0=d.v0)
    dr = turning_dead_reckoning(acel.t, acel.aerr, acel.gyro, cal.bias, cal.scale, d.p0, d.v0)
    samples = json.loads((turning_set / "truth.json").read_text())["vehicle"]["trajectory"][
        "samples"]
    cands = read_puntos(turning_set / "puntos.mat")
    reg = turning_arrival_region(dr, acel.aerr, acel.gyro, cal_cov=cal.cov,
                                 noise_var=d.noise_var, gyro_var=0.005 ** 2, candidates=cands)
    assert reg.decision == "D"  # the generated set's answer, seed 3
    fig = fusion_figure(dr, reg, res, fixes.pos, 0.997, "D",
                        true_path=np.array(samples["pos"]),
                        true_heading=(np.array(samples["t"]), np.array(samples["heading"])))
    assert len(fig.axes) == 3  # plane, heading, heading error
    polys = [p for p in fig.axes[0].patches if isinstance(p, Polygon)]
    assert len(polys) == 2  # dead reckoning and fused
    assert np.allclose(polys[0].get_xy()[:256], reg.ellipse.boundary())
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any(lb.startswith("99.7 % region, dead reckoning") for lb in labels)
    assert not any("no region" in lb for lb in labels)
    plt.close(fig)
    fig = fusion_figure(dr, reg, res, fixes.pos, 0.997, "D")
    assert len(fig.axes) == 2  # without the truth: no error panel
    plt.close(fig)

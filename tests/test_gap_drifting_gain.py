"""A drifting or stepping gain, backlash, common-mode noise, a warm-up, noise that follows the
load (issue 20).

Mechanisms that neither validation set had, which the walk absorbed or a noise level
"explained": at the session start (d9d19be) ``python tools/mechanism_probe.py`` (14 runs each
over seven designs of the independent generator, 10 runs for the mechanisms that need motion
both ways or rates) found unexplained: scale drift 0/14, backlash 6/10, a gain step 7/14, a
creeping tilt 2/14, a warm-up 9/14, heating 1/10, common-mode noise 0/14, load noise (0.6
σ·|A_r|/g) 0/14; now 14/14, 10/10, 13/14, 10/14, 13/14, 10/10, 14/14, 9/14. The runs are a
clean run of the independent generator (``validation.independent``: its own designs and
sensor chain) with the mechanism added from its physics here, sized 10 σ beyond the
catalog's linear signatures:

* scale drift: ``A_r·(1 + s·u)``, u = time mapped onto [-½, ½];
* backlash: the table stops b short of the encoder's θ in the direction it moved, so the
  reading is ``A_r(θ - d·b) ≈ A_r - d·b·dA_r/dθ``;
* a gain step: ``A_r·(1 + s·[t > t₀])``;
* common-mode noise: one white series times 0.8 σ added to both axes;
* a warm-up: ``e^{-t/T}`` from the start, T = 15 % of the run;
* a creeping tilt: ``dA_r/dθ·c·u`` (a tilt growing linearly in time);
* heating: a bias proportional to the travel so far ``∫|dθ|`` (nothing while holding);
* noise that follows the load: white noise of σ·|A_r|/g added (variance up to 2× at 1 g).

Expected: verdict "unexplained", no walk named, the words saying what was seen. The level of
the new battery checks on clean runs is checked with the clean runs of
``tests/test_gap_calib.py::test_false_alarm_rate_on_clean_runs``.
"""

from __future__ import annotations

import numpy as np
import pytest

from calib.files.course import validate_ensayo
from calib.gap import analyze_gap


def _run(mechanism: str, design: str, timing: str, k: int, seed: int):
    from validation.independent.cases import CL, CaseDef, build
    from validation.independent.effects import catalog_columns
    from validation.independent.physics import static_force

    case = CaseDef(CL, "clean", "-", design, timing, "jitter" if timing == "t" else "uniform",
                   rate=100, n=4001 + 2 * seed, noise=seed % 4)
    motion, datos, truth = build(case, seed=500 + seed)
    rng = np.random.default_rng([seed, 7])
    sd = np.sqrt(truth["noise_var"])
    a = static_force(motion.theta)
    u = (motion.clock - motion.clock.mean()) / np.ptp(motion.clock)
    datos = datos.copy()
    if mechanism == "common_noise":
        datos += 0.8 * sd * rng.standard_normal(motion.n)[:, None]
    elif mechanism == "load_noise":
        datos[:, k] += sd[k] * np.abs(a[:, k]) / 9.8 * rng.standard_normal(motion.n)
    else:
        slope = a[:, 1] if k == 0 else -a[:, 0]  # dA_r/dθ (course signs)
        shape = {"scale_drift": a[:, k] * u,
                 "backlash": slope * motion.last_dir,
                 "gain_step": a[:, k] * (u > 0.1),
                 "warm_up": np.exp(-(u + 0.5) / 0.15),
                 "tilt_drift": slope * u,
                 "heating": np.cumsum(np.abs(np.diff(motion.theta, prepend=motion.theta[0])))
                 }[mechanism]
        basis = np.column_stack([np.ones(motion.n), a[:, k],
                                 catalog_columns(motion)["xy"[k]]])
        q, _ = np.linalg.qr(basis)
        left = shape - q @ (q.T @ shape)
        datos[:, k] += 10.0 * sd[k] / np.linalg.norm(left) * shape
    rate = 100.0 if timing == "rate" else None
    return analyze_gap(validate_ensayo(motion.theta, datos, motion.t), truth["noise_var"],
                       rate=rate)


@pytest.mark.parametrize("mechanism,design,timing,k,words", [
    ("scale_drift", "slow_fast_turns", "rate", 0, "gain on x changes during the run"),
    ("scale_drift", "random_poses", "none", 1, "gain on y changes during the run"),
    ("backlash", "backforth_dwell", "rate", 0, "direction of the last motion"),
    ("gain_step", "growing_rock", "rate", 1, "gain on y"),
    ("common_noise", "stop_and_go", "rate", 0, "noise of x and y is correlated"),
    ("warm_up", "backforth_dwell", "rate", 0, "a warm-up after power-on"),
    ("load_noise", "slow_fast_turns", "rate", 1, "noise on y grows with the specific force"),
    ("tilt_drift", "stop_and_go", "rate", 0, "the tilt of x creeps during the run"),
    ("heating", "backforth_dwell", "rate", 1, "grows with the motion done so far"),
])
def test_the_mechanism_is_unexplained_and_said(mechanism, design, timing, k, words):
    res = _run(mechanism, design, timing, k, seed=k + 3)
    assert res.verdict == "unexplained", res.summary()
    assert ("bias_random_walk", "xy"[k]) not in res.named
    said = " ".join(u["description"] for u in res.unexplained)
    assert words in said, said


def test_shapes_that_fit_alike_are_both_said_whatever_comes_first(monkeypatch):
    """A gain step where the specific force on y is constant is a bias step to the last bits:
    which of the two the rival list holds first moves with the CPU's float kernels (OpenBLAS'
    Sandybridge and Haswell kernels ordered them differently), so ``walk_rivals`` says both,
    the same words in either order."""
    import calib.gap.walk as walk

    def said():
        res = _run("gain_step", "growing_rock", "rate", 1, seed=4)
        return [u["description"] for u in res.unexplained
                if "on top of the walk" in u["description"]]

    forward = said()
    rivals = walk.rivals
    monkeypatch.setattr(walk, "rivals", lambda *a, **k: rivals(*a, **k)[::-1])
    assert said() == forward
    assert len(forward) == 1
    assert "the gain on y steps by" in forward[0] and "a step of" in forward[0], forward

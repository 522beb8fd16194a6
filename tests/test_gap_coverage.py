"""Honesty of the std that ``calib.gap`` prints for the linear-extension effects (Monte Carlo).

``analyze_gap`` reports every named effect as ``estimate ± std``. For the effects that are
extra linear terms of the model (``misalignment``, ``tilt_offset``, ``nonlinearity_k2``,
``cross_axis``, ``bias_drift``) and for ``noise_level`` (its std ``σ̂²·sqrt(2/dof)`` is
printed too) this file checks by Monte Carlo that the printed std has the coverage it claims.
The random walk is checked in ``tests/test_gap_calib.py``; saturation, low-pass and
quantization in ``benchmarks/gap_uncertainty_mc.py``.

Design
------
Synthetic runs come from :func:`tests.gap_synthetic.synth`, plain numpy straight from the
equations of ``docs/effects.md`` (never through ``calib`` or the bench): a static full turn
(its "uniform" design: θ uniform over [0, 2π), sorted, no timing: drift per sample), N = 1000,
random bias U(-0.3, 0.3) m/s² and scale U(-0.03, 0.03) on both axes, white noise of the course
(σ² = 0.25, 0.64 (m/s²)², the stated values), and ONE effect. Per-axis effects alternate
between x (even replicates) and y (odd ones). Sizes: ``|estimate - null|/std`` ≈ 10 on each
axis (null = 0, or the stated σ² for noise_level), far above the selection threshold (per-step
α = 0.001/17 ≈ 5.9e-5, |z| ≈ 4.0), so the workflow names the effect in essentially every run.
The drift is ≈ 20 std: a ramp is also fitted by a random walk (the documented drift / walk
confusion), and at 10 std the walk's p-value beat the drift's in 1-4 % of y runs (log-p margin
3.5 ± 1.5; at 20 std 6.9 ± 1.6, none of 150 runs below 0.4). The std of a linear coefficient
does not depend on the size, so the larger size changes nothing in what is checked. The test
also asserts this premise (median size ≥ 8 on each axis). ``analyze_gap`` runs end to end and
``z = (estimate - truth)/std`` is taken from the printed ``params`` / ``std``.

R = 80 replicates per effect (40 per axis), R_tot = 480 in all, on two pool workers with
one BLAS thread each (≈ 0.23 s of CPU per run, ≈ 115 s of CPU in all: ≈ 60 s wall on two idle
cores, ~70 s on a loaded machine; hence ``slow``). Seeds:
``np.random.default_rng([SEED, effect index, replicate])``, fixed, never searched. The
measured numbers are in every failure message.

Tolerances (derived, not tuned)
-------------------------------
For an honest Gaussian estimate z ~ N(0, 1); over R runs (R = the runs that name the effect):

* coverage of ``estimate ± 1.96 std``: hits H ~ Binomial(R, 0.95), so
  ``|H/R - 0.95| ≤ 4·sqrt(0.95·0.05/R)`` (4 binomial standard errors; 0.097 at R = 80);
* ``mean(z²)`` (NEES, one parameter): var z² = 2, so ``|mean(z²) - 1| ≤ 4·sqrt(2/R)``
  (0.63 at R = 80);
* ``mean(z)``: ``|mean(z)| ≤ 4/sqrt(R)`` (0.45 at R = 80; a bias the std does not cover).

Each holds per effect (R = 80: the weaker tolerance) and pooled over the six effects
(R_tot = 480: 0.040 for the coverage, 0.26 for mean z², 0.18 for mean z; the replicates are
independent, so under honest stds the pooled z are i.i.d. N(0, 1) and the pooled checks are
the sensitive ones: a std 15 % too small gives mean z² ≈ 1.38). Each check fails an honest
estimator with P ≈ 6e-5 (4 standard errors), ≈ 1.3e-3 for the 21 checks together.

Known small departures, all far inside these bands: misalignment and tilt offset are
generated as exact rotations ``-g sin(θ+δ)`` (the misalignment fit is exact through
``δ = atan2(c, 1 + s)``; the tilt column uses the nominal gain, so its coefficient is
``tan δ`` and ``arcsin(tan δ)`` is off by δ³/2 ≈ 0.002 std, the gain's own error adds
≈ 0.02 std); the ratio effects (k2, k_ip) use the delta method for ``c/(1 + s)``;
noise_level's std is σ̂²·sqrt(2/dof) (a skew of order sqrt(2/N) ≈ 0.045 in z) and σ̂² divides
by N - 1 instead of dof (a bias of ≈ 0.02 std).

Naming: a run is right when it names exactly the true effect on the true axis. A correct
selector errs when it adds a spurious effect (P ≤ family_alpha = 0.001 per run, Bonferroni;
measured ≈ 0.2 % on clean runs in ``tests/test_gap_calib.py``) or misses the effect or names
another one in its place (at ≥ 10 std P(miss) ≈ Φ(3.6 - 10) < 1e-9; swaps: see the drift
above). With p = 0.001 the wrong runs K ~ Binomial(R, p) and the test asserts
``K ≤ binom.ppf(0.999, R, 0.001)`` (2 at R = 80; a correct selector fails with P ≤ 0.001 per
effect) and lists the wrong runs (replicate, axis, what was named) in the message. The z
statistics use every run that names the true effect (a spurious extra effect only adds a
column, and the std accounts for it).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from calib.files.course import Ensayo
from calib.gap import analyze_gap
from calib.gap.selection import FAMILY_ALPHA  # analyze_gap's default false-alarm rate
from tests.gap_synthetic import STATED, synth
from tests.pools import process_pool

SEED = 20240617
N = 1000
R_PER_EFFECT = 80
Z95 = float(stats.norm.ppf(0.975))

# (effect, printed key = its parameter, {axis: true value}): about 10 printed std on each
# axis at N = 1000, 20 for the drift (module docstring)
# (std: misalignment σ/(g·sqrt(N/2)); tilt 1/sqrt(Σ_a g²N/(2σ_a²)); k2, k_ip ≈ 2σ/(g²·
# sqrt(N/2)); drift per sample ≈ σ·sqrt(12/N³), ×1.6 on x where the ramp shares its sin θ
# component with the scale column; noise level σ²·sqrt(2/N)).
CASES: tuple[tuple[str, str, dict[str, float]], ...] = (
    ("misalignment", "delta", {"x": 0.023, "y": -0.037}),
    ("tilt_offset", "delta", {"both": 0.019}),
    ("nonlinearity_k2", "k2", {"x": 0.0047, "y": -0.0076}),
    ("cross_axis", "k_ip", {"x": -0.0047, "y": 0.0075}),
    ("bias_drift", "rate_per_sample", {"x": 1.76e-3, "y": -1.76e-3}),
    ("noise_level", "sigma2", {"x": 0.45, "y": 0.44}),
)


def _axis_of(case: int, i: int) -> str:
    axes = list(CASES[case][2])
    return axes[i % len(axes)]


def _replicate(job: tuple[int, int]) -> tuple[int, int, str, list, float, float]:
    """Run i of effect ``case`` through analyze_gap: (case, i, axis, named, estimate, std)."""
    case, i = job
    name, key, truth = CASES[case]
    axis = _axis_of(case, i)
    rng = np.random.default_rng([SEED, case, i])
    th, y, _ = synth("uniform", N, rng, [(name, axis, {key: truth[axis]})])
    res = analyze_gap(Ensayo(th, y), STATED)
    try:
        est = res.effect(name, axis)
    except KeyError:
        return case, i, axis, res.named, float("nan"), float("nan")
    return case, i, axis, res.named, float(est.params[key]), float(est.std[key])


# ------------------------------------------------------------------------------ the test

def _stats(z: np.ndarray) -> dict[str, float]:
    r = z.size
    return {"R": r, "cover": float(np.mean(np.abs(z) <= Z95)), "mean_z2": float(np.mean(z * z)),
            "mean_z": float(np.mean(z)), "sd_z": float(np.std(z, ddof=1)),
            "band_cover": 4.0 * np.sqrt(0.95 * 0.05 / r), "band_z2": 4.0 * np.sqrt(2.0 / r),
            "band_z": 4.0 / np.sqrt(r)}


def _fails(s: dict[str, float]) -> list[str]:
    out = []
    if abs(s["cover"] - 0.95) > s["band_cover"]:
        out.append(f"coverage {s['cover']:.3f} not within 0.95 ± {s['band_cover']:.3f}")
    if abs(s["mean_z2"] - 1.0) > s["band_z2"]:
        out.append(f"mean z² {s['mean_z2']:.3f} not within 1 ± {s['band_z2']:.3f}")
    if abs(s["mean_z"]) > s["band_z"]:
        out.append(f"mean z {s['mean_z']:+.3f} not within 0 ± {s['band_z']:.3f}")
    return out


def _line(label: str, s: dict[str, float]) -> str:
    return (f"{label:28s} R = {s['R']:3d}  cover = {s['cover']:.3f}  mean z² = "
            f"{s['mean_z2']:.3f}  mean z = {s['mean_z']:+.3f}  sd z = {s['sd_z']:.3f}")


@pytest.mark.slow
def test_linear_effect_std_has_its_coverage():
    """Per effect (R = 80) and pooled (R = 480): coverage of ``estimate ± 1.96 std``, mean z²
    and mean z within their binomial / χ² bands; the true effect and axis (alone) named in all
    but ``binom.ppf(0.999, R, FAMILY_ALPHA)`` runs (module docstring)."""
    jobs = [(c, i) for i in range(R_PER_EFFECT) for c in range(len(CASES))]
    with process_pool(2) as ex:
        results = list(ex.map(_replicate, jobs, chunksize=10))

    k_max = int(stats.binom.ppf(0.999, R_PER_EFFECT, FAMILY_ALPHA))
    lines, problems, pooled = [], [], []
    for c, (name, key, truth) in enumerate(CASES):
        rows = [r for r in results if r[0] == c]
        wrong = [(i, ax, named) for _, i, ax, named, _, _ in rows if named != [(name, ax)]]
        if len(wrong) > k_max:
            problems.append(f"{name}: {len(wrong)} runs name the wrong thing (> {k_max}): "
                            f"{wrong}")
        est = np.array([r[4] for r in rows])
        std = np.array([r[5] for r in rows])
        true = np.array([truth[r[2]] for r in rows])
        ok = np.isfinite(est)
        z = (est[ok] - true[ok]) / std[ok]
        sizes = {}
        for ax in truth:  # the design's premise: a clearly detectable effect on each axis
            on = ok & np.array([r[2] == ax for r in rows])
            null = STATED["xy".index(ax)] if name == "noise_level" else 0.0
            sizes[ax] = float(np.median(np.abs(est[on] - null) / std[on])) if on.any() else 0.0
            if sizes[ax] < 8.0:
                problems.append(f"{name} ({ax}): median |estimate - null|/std = "
                                f"{sizes[ax]:.1f} < 8")
        pooled.append(z)
        s = _stats(z)
        size_txt = ", ".join(f"{ax} {v:.1f}" for ax, v in sizes.items())
        lines.append(_line(f"{name}.{key}", s) + f"  size: {size_txt}  wrong: {len(wrong)}")
        lines += [f"    run {i} ({ax}) named {named}" for i, ax, named in wrong]
        problems += [f"{name}: {f}" for f in _fails(s)]
    s = _stats(np.concatenate(pooled))
    lines.append(_line("pooled", s))
    problems += [f"pooled: {f}" for f in _fails(s)]
    assert not problems, "\n".join(problems + [""] + lines)

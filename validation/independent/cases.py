"""The fixed list of cases of the independent set and how one is built from a seed.

A case is (id, kind, effect or mechanism, axis, design, timing, stated noise, size). The list
does not depend on the seed: the seed only draws the nominal bias and scale, the design's
random choices, the noise and the random paths. Sizes are set on the effect's mean signature
(:func:`.effects.effect_z`: how many noise σ the effect stands above the noise once bias and
scale are refitted), 6–12 σ for catalog effects and ~10 σ for mechanisms outside the catalog,
so a detector that misses one misses a clear signal.

Kinds and the answer expected of ``tiltbench gap``:

* ``catalog``: the effect named on its axis (``tilt_offset``: axis ``both``), verdict
  ``explained``;
* ``clean`` and ``absorbed`` (a different local g, absorbed by the scale factors, docs/effects.md
  "Known confusions"): verdict ``nothing_detected``;
* ``out_of_catalog``: verdict ``unexplained`` (a catalog name with the gap after still flagged
  also counts).

The split: ``heldout`` when the first 8 bytes of sha256(f"{SPLIT_SALT}:{case_id}") read as
an integer, divided by 2⁶⁴, are below :data:`HELDOUT_FRACTION`; otherwise ``tune``. It depends
on the case id only, so it is the same for every seed and stays put when cases are added.
"""

from __future__ import annotations

import hashlib
import zlib
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from . import designs
from .effects import (
    AXES,
    Draws,
    catalog_columns,
    effect_z,
    mean_readings,
    neutral_axis,
    readings,
    z_vs_nearest,
)
from .physics import G, static_force, walk_trace

SPLIT_SALT = "tiltbench-independent-2026"
HELDOUT_FRACTION = 0.4
FORMAT = "tiltbench-independent-truth/1"

NOISE_SETS = ((0.25, 0.64), (0.04, 0.09), (0.01, 0.0225), (0.0025, 0.0049))
"""Stated noise variances (x, y) in (m/s²)², the course's first."""


@dataclass(frozen=True)
class CaseDef:
    kind: str                      # catalog | clean | absorbed | out_of_catalog
    what: str                      # effect name, mechanism kind, or "clean"
    axis: str                      # x | y | both | "-"
    design: str
    timing: str = "none"           # none | rate | t
    sampling: str = "uniform"
    rate: float = 100.0
    n: int = 4001
    noise: int = 0                 # index into NOISE_SETS
    z: float = 8.0                 # target size in σ (catalog / mechanisms)
    extra: dict = field(default_factory=dict)

    @property
    def case_id(self) -> str:
        tag = {"catalog": "cat", "clean": "clean", "absorbed": "abs",
               "out_of_catalog": "ooc"}[self.kind]
        samp = "" if self.sampling == "uniform" else f"-{self.sampling}"
        return (f"{tag}-{self.what}-{self.axis}-{self.design}-{self.timing}{samp}"
                f"-n{self.n}-s{self.noise}").replace("_", "").lower()


def split_of(case_id: str) -> str:
    """``tune`` or ``heldout`` (module docstring)."""
    h = hashlib.sha256(f"{SPLIT_SALT}:{case_id}".encode()).digest()
    return "heldout" if int.from_bytes(h[:8], "big") / 2**64 < HELDOUT_FRACTION else "tune"


BAND = 16
"""Low-frequency bins of the band size of a 1/f path (:func:`.effects.effect_z`)."""

SCALED = {"settling_transient": "amp", "direction_hysteresis": "h", "dead_zone": "d",
          "fractional_harmonic": "amp", "bias_jump": "jump", "flicker": "amp",
          "ringing": "amp", "drive_vibration": "amp", "thermal_cycle": "amp",
          "scale_asymmetry": "kappa", "cubic_k3": "k3"}
"""Mechanisms sized on their mean signature (z σ), and the parameter that sets the size. The
others (extra noise, spikes, rails, a stuck stretch) are sized in their own terms (note)."""

C, CL, A, OOC = "catalog", "clean", "absorbed", "out_of_catalog"

# A table, one case per row: its rows are alike in shape, not in logic (nothing to share).
CASES: tuple[CaseDef, ...] = (
    # --- catalog effects, three each, on designs validation/ does not use
    CaseDef(C, "noise_level", "x", "random_poses", noise=0, z=8),
    CaseDef(C, "noise_level", "y", "growing_rock", "rate", rate=100, noise=1, z=7),
    CaseDef(C, "noise_level", "both", "partial_sweep", "t", "jitter", noise=2, z=10),
    CaseDef(C, "misalignment", "x", "repeated_poses", noise=0, z=8),
    CaseDef(C, "misalignment", "y", "negative_turns", "rate", rate=200, noise=1, z=6),
    CaseDef(C, "misalignment", "y", "partial_poses", "rate", rate=50, noise=3, z=10),
    CaseDef(C, "tilt_offset", "both", "random_poses", noise=1, z=8),
    CaseDef(C, "tilt_offset", "both", "stop_and_go", "rate", rate=100, noise=0, z=10),
    CaseDef(C, "tilt_offset", "both", "partial_sweep", "t", "jitter", noise=3, z=7),
    CaseDef(C, "nonlinearity_k2", "x", "slow_fast_turns", "rate", rate=200, noise=2, z=8),
    CaseDef(C, "nonlinearity_k2", "y", "repeated_poses", noise=0, z=10),
    CaseDef(C, "nonlinearity_k2", "x", "random_poses", "rate", rate=50, noise=1, z=7),
    CaseDef(C, "cross_axis", "y", "random_poses", noise=0, z=8),
    CaseDef(C, "cross_axis", "x", "stop_and_go", "rate", rate=100, noise=2, z=10),
    CaseDef(C, "cross_axis", "y", "negative_turns", "t", "bursty", noise=1, z=7),
    CaseDef(C, "bias_drift", "x", "partial_poses", noise=0, z=8),
    CaseDef(C, "bias_drift", "y", "backforth_dwell", "rate", rate=100, noise=1, z=10),
    CaseDef(C, "bias_drift", "x", "slow_fast_turns", "t", "jitter", rate=200, noise=3, z=7),
    CaseDef(C, "bias_random_walk", "y", "random_poses", noise=0, z=12),
    CaseDef(C, "bias_random_walk", "x", "growing_rock", "rate", rate=100, noise=2, z=12),
    CaseDef(C, "bias_random_walk", "y", "stop_and_go", "t", "jitter", noise=1, z=12),
    CaseDef(C, "quantization", "x", "random_poses", noise=2, z=1.5),
    CaseDef(C, "quantization", "y", "slow_fast_turns", "rate", rate=100, noise=1, z=1.0),
    CaseDef(C, "quantization", "both", "backforth_dwell", "t", "jitter", noise=0, z=2.0),
    CaseDef(C, "saturation", "y", "slow_fast_turns", "rate", rate=100, noise=0, z=8),
    CaseDef(C, "saturation", "x", "random_poses", noise=1, z=10),
    CaseDef(C, "saturation", "x", "negative_turns", "rate", rate=200, noise=2, z=7),
    CaseDef(C, "lowpass_lag", "x", "backforth_dwell", "rate", rate=100, noise=1, z=8),
    CaseDef(C, "lowpass_lag", "y", "growing_rock", "rate", rate=200, noise=0, z=10),
    CaseDef(C, "lowpass_lag", "x", "partial_sweep", "t", "jitter", noise=2, z=8),
    CaseDef(C, "lever_arm", "y", "growing_rock", "rate", rate=200, noise=1, z=10),
    CaseDef(C, "lever_arm", "x", "backforth_dwell", "rate", rate=100, noise=2, z=8),
    CaseDef(C, "lever_arm", "x", "slow_fast_turns", "t", "jitter", rate=200, noise=3, z=10),
    # --- a different local gravity: absorbed by the scale factors, nothing to name
    CaseDef(A, "gravity_mismatch", "both", "random_poses", noise=0, extra={"g": 9.79}),
    CaseDef(A, "gravity_mismatch", "both", "slow_fast_turns", "rate", rate=100, noise=3,
            extra={"g": 9.83}),
    # --- clean runs on every design, timing and noise level
    CaseDef(CL, "clean", "-", "random_poses", noise=0),
    CaseDef(CL, "clean", "-", "random_poses", "rate", rate=50, noise=3, n=8001),
    CaseDef(CL, "clean", "-", "repeated_poses", noise=1),
    CaseDef(CL, "clean", "-", "partial_poses", noise=2, n=2001),
    CaseDef(CL, "clean", "-", "backforth_dwell", "rate", rate=100, noise=0),
    CaseDef(CL, "clean", "-", "backforth_dwell", "t", "jitter", noise=3),
    CaseDef(CL, "clean", "-", "slow_fast_turns", "rate", rate=200, noise=1),
    CaseDef(CL, "clean", "-", "negative_turns", "t", "bursty", noise=0),
    CaseDef(CL, "clean", "-", "stop_and_go", "rate", rate=100, noise=2),
    CaseDef(CL, "clean", "-", "stop_and_go", "none", rate=100, noise=1),
    CaseDef(CL, "clean", "-", "growing_rock", "rate", rate=200, noise=3),
    CaseDef(CL, "clean", "-", "partial_sweep", "t", "jitter", noise=0),
    CaseDef(CL, "clean", "-", "partial_sweep", "rate", rate=100, noise=2, n=12001),
    CaseDef(CL, "clean", "-", "slow_fast_turns", "none", rate=100, noise=0, n=20001),
    # --- mechanisms outside the catalog, two designs each
    CaseDef(OOC, "settling_transient", "x", "stop_and_go", "rate", rate=100, noise=1, z=10),
    CaseDef(OOC, "settling_transient", "y", "random_poses", "rate", rate=50, noise=0, z=10),
    CaseDef(OOC, "direction_hysteresis", "y", "backforth_dwell", "rate", rate=100, noise=0, z=10),
    CaseDef(OOC, "direction_hysteresis", "x", "partial_poses", noise=2, z=10),
    CaseDef(OOC, "dead_zone", "y", "random_poses", noise=1, z=10),
    CaseDef(OOC, "dead_zone", "x", "slow_fast_turns", "rate", rate=100, noise=0, z=10),
    CaseDef(OOC, "fractional_harmonic", "x", "slow_fast_turns", "rate", rate=100, noise=2, z=10,
            extra={"nu": 1.5}),
    CaseDef(OOC, "fractional_harmonic", "y", "random_poses", noise=0, z=10, extra={"nu": 2.5}),
    CaseDef(OOC, "bias_jump", "y", "backforth_dwell", "t", "jitter", noise=1, z=10),
    CaseDef(OOC, "bias_jump", "x", "random_poses", noise=3, z=10),
    CaseDef(OOC, "flicker", "x", "repeated_poses", noise=0, z=10),
    CaseDef(OOC, "flicker", "y", "partial_sweep", "t", "jitter", noise=1, z=10),
    CaseDef(OOC, "ringing", "x", "stop_and_go", "rate", rate=200, noise=2, z=10),
    CaseDef(OOC, "ringing", "y", "growing_rock", "rate", rate=200, noise=0, z=10),
    CaseDef(OOC, "drive_vibration", "y", "slow_fast_turns", "rate", rate=200, noise=1, z=10),
    CaseDef(OOC, "drive_vibration", "x", "negative_turns", "rate", rate=200, noise=3, z=10),
    CaseDef(OOC, "thermal_cycle", "x", "random_poses", "rate", rate=50, noise=0, z=10),
    CaseDef(OOC, "thermal_cycle", "y", "backforth_dwell", "rate", rate=100, noise=2, z=10),
    CaseDef(OOC, "scale_asymmetry", "x", "random_poses", noise=1, z=10),
    CaseDef(OOC, "scale_asymmetry", "y", "stop_and_go", "rate", rate=100, noise=2, z=10),
    CaseDef(OOC, "cubic_k3", "y", "slow_fast_turns", "rate", rate=100, noise=0, z=10),
    CaseDef(OOC, "cubic_k3", "x", "partial_poses", noise=1, z=10),
    CaseDef(OOC, "speed_noise", "y", "growing_rock", "rate", rate=200, noise=1, z=2.0),
    CaseDef(OOC, "speed_noise", "x", "slow_fast_turns", "t", "jitter", noise=0, z=2.0),
    CaseDef(OOC, "impulsive_spikes", "x", "random_poses", noise=2, z=7.0),
    CaseDef(OOC, "impulsive_spikes", "y", "backforth_dwell", "rate", rate=100, noise=0, z=7.0),
    CaseDef(OOC, "asymmetric_clip", "y", "slow_fast_turns", "rate", rate=100, noise=1),
    CaseDef(OOC, "asymmetric_clip", "x", "random_poses", noise=0),
    CaseDef(OOC, "frozen_output", "both", "backforth_dwell", "rate", rate=100, noise=0,
            extra={"length": 300}),
    CaseDef(OOC, "frozen_output", "both", "partial_poses", noise=2, extra={"length": 200}),
)


def case_by_id() -> dict[str, CaseDef]:
    out = {c.case_id: c for c in CASES}
    if len(out) != len(CASES):
        raise RuntimeError("two cases share an id")
    return out


def case_rng(seed: int, case_id: str) -> np.random.Generator:
    """One stream per (seed, case): the same case gives the same arrays whatever else is
    generated, and in any order."""
    return np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(case_id.encode())]))


def _motion(c: CaseDef, rng) -> designs.Motion:
    build = designs.DESIGNS[c.design]
    if c.design in ("random_poses", "repeated_poses", "partial_poses"):
        return build(rng, c.n, timing=c.timing, rate=c.rate)
    timing = "rate" if c.timing == "none" else c.timing
    m = build(rng, c.n, rate=c.rate, timing=timing, sampling=c.sampling)
    if c.timing == "none":  # a moving run logged without timing: samples in time order only
        m = designs.Motion(m.design, m.theta, m.omega, m.alpha, None, "none", None,
                           np.searchsorted(m.t, m.stop_times).astype(float), m.stop_dirs,
                           m.last_dir)
    return m


def _solve(zfun, lo: float, hi: float, target: float) -> float:
    """The size s in [lo, hi] with zfun(s) = target (zfun increasing on the bracket)."""
    if zfun(hi) < target:
        raise ValueError(f"size {target} σ not reached below {hi:g}: the effect is too weak "
                         "on this design and noise (change the case)")
    return float(brentq(lambda s: zfun(s) - target, lo, hi, xtol=1e-12, rtol=1e-10))


def _with(base: dict, axes: tuple[str, ...], **kv) -> dict:
    spec = {**base, "axes": {a: dict(p) for a, p in base["axes"].items()}}
    for a in axes:
        spec["axes"][a].update(kv)
    return spec


def _axes_of(axis: str) -> tuple[str, ...]:
    return AXES if axis in ("both", "-") else (axis,)


def build(c: CaseDef, seed: int):
    """(motion, datos (N, 2), truth dict) of one case."""
    rng = case_rng(seed, c.case_id)
    motion = _motion(c, rng)
    stated = NOISE_SETS[c.noise]
    base = {"g": G, "tilt_offset": 0.0, "mechanisms": [], "axes": {
        ax: neutral_axis(float(rng.uniform(-0.3, 0.3)), float(rng.uniform(-0.03, 0.03)),
                         stated[i]) for i, ax in enumerate(AXES)}}
    draws = Draws.draw(rng, motion.n)
    phase = float(rng.uniform(0, 2 * np.pi))
    beta = float(rng.uniform(0, 2 * np.pi))
    sign = float(rng.choice([-1.0, 1.0]))
    axes = _axes_of(c.axis)
    spec, params, size_note = _make(c, motion, base, draws, axes, phase, beta, sign)
    datos = readings(motion, spec, draws)
    truth = _truth(c, seed, motion, base, spec, draws, params, size_note, stated)
    return motion, datos, truth


def _make(c, motion, base, draws, axes, phase, beta, sign):  # noqa: C901 - one branch per effect
    """The case's spec, its catalog params per axis (docs/effects.md keys) and a size note."""
    z = c.z
    timed = motion.t is not None
    if c.kind in ("clean",):
        return base, {}, "no effect"
    if c.kind == "absorbed":
        spec = {**base, "g": c.extra["g"]}
        return spec, {"both": {"g": c.extra["g"]}}, "absorbed by the scale factors"

    def lin(key, unit_size, lo=None, hi=None, signed=True):
        """Size of a parameter by bisection on the effect's z (``sign`` drawn per case)."""
        sg = sign if signed else 1.0

        def zf(s):
            return effect_z(motion, base, _with(base, axes, **{key: sg * s}), draws)
        s = _solve(zf, lo or unit_size * 1e-6, hi or unit_size * 10, z)
        return sg * s

    w = c.what
    if w == "noise_level":
        r = z * np.sqrt(2.0 / motion.n)   # χ²/dof excess of z σ: (σ²_true/σ² − 1)·√(N/2) = z
        spec = {**base, "axes": {a: dict(p) for a, p in base["axes"].items()}}
        params = {}
        for a in axes:
            spec["axes"][a]["sigma2"] = base["axes"][a]["sigma2"] * (1 + r)
            params[a] = {"sigma2": spec["axes"][a]["sigma2"]}
        return spec, params, f"σ²_true/σ²_stated = {1 + r:.4f} (χ² excess {z} σ)"
    if w == "misalignment":
        d = lin("misalignment", 0.01)
        return _with(base, axes, misalignment=d), {axes[0]: {"delta": d}}, f"z = {z}"
    if w == "tilt_offset":
        def zf(s):
            return effect_z(motion, base, {**base, "tilt_offset": sign * s}, draws)
        d = sign * _solve(zf, 1e-7, 0.3, z)
        return {**base, "tilt_offset": d}, {"both": {"delta": d}}, f"z = {z}"
    if w == "nonlinearity_k2":
        k = lin("k2", 1e-3)
        return _with(base, axes, k2=k), {axes[0]: {"k2": k}}, f"z = {z}"
    if w == "cross_axis":
        k = lin("k_ip", 1e-3)
        return _with(base, axes, k_ip=k), {axes[0]: {"k_ip": k}}, f"z = {z}"
    if w == "bias_drift":
        r = lin("drift", 1e-3)
        key = "rate" if timed else "rate_per_sample"
        return _with(base, axes, drift=r), {axes[0]: {key: r}}, f"z = {z}"
    if w == "bias_random_walk":
        # The path's size varies a lot between draws (‖P⊥b‖² is a weighted χ² dominated by
        # a few slow components), so q is set on the drawn path: the walk stands z σ above
        # the noise in every case, measured on what the catalog's parametric signatures leave
        # of it — on a single monotone turn a slow path is a smooth function of θ, and a
        # drift plus a misalignment can take most of it (then no detector could name it).
        # The expected size at that q is in the note.
        ax = axes[0]
        i = AXES.index(ax)
        dt = np.diff(motion.clock, prepend=motion.clock[0])
        ref = static_force(motion.theta)[:, i]
        unit = effect_z(motion, base, _with(base, axes, q=1.0), draws,
                        rivals=catalog_columns(motion))
        q = z / unit
        z_expected = q * np.sqrt(walk_trace(dt, ref) / base["axes"][ax]["sigma2"])
        key = "q" if timed else "q_per_sample"
        return (_with(base, axes, q=q), {ax: {key: q}},
                f"z = {z} on the drawn path (expected size at this q: {z_expected:.1f})")
    if w == "quantization":
        spec = base
        params = {}
        for a in axes:
            lsb = z * np.sqrt(base["axes"][a]["sigma2"])
            spec = _with(spec, (a,), lsb=lsb)
            params[a] = {"lsb": lsb}
        return spec, params, f"lsb = {z} σ"
    if w == "saturation":
        ax = axes[0]

        def zf(lim):
            return effect_z(motion, base, _with(base, axes, limit=lim), draws)
        lim = _solve(lambda s: -zf(s), 0.2 * G, 0.99999 * G, -z)
        return _with(base, axes, limit=lim), {ax: {"limit": lim}}, f"z = {z}"
    if w == "lowpass_lag":
        tau = lin("tau", 0.01, 1e-6, 2.0, signed=False)
        return _with(base, axes, tau=tau), {axes[0]: {"tau": tau}}, f"z = {z}"
    if w == "lever_arm":
        u = (np.cos(beta), np.sin(beta))

        def zf(r):
            return effect_z(motion, base, _with(base, axes, lever=(r * u[0], r * u[1])), draws)
        r = _solve(zf, 1e-5, 20.0, z)
        pos = (r * u[0], r * u[1])
        return (_with(base, axes, lever=pos),
                {axes[0]: {"pos_x": pos[0], "pos_z": pos[1]}}, f"z = {z}, |p| = {r:.3f} m")
    # --- mechanisms outside the catalog
    rivals = catalog_columns(motion)
    mech = {"kind": w, "axis": c.axis}
    mech.update(_mechanism_defaults(w, motion, c, phase))

    # sized on what the catalog's parametric effects leave of it (catalog_columns), and a
    # 1/f path on its low band (effect_z, band): a fair miss is a clear structure missed
    band = BAND if w == "flicker" else 0

    def mz(key, lo, hi):
        def zf(s):
            return effect_z(motion, base, {**base, "mechanisms": [{**mech, key: s}]}, draws,
                            rivals=rivals, band=band)
        return _solve(zf, lo, hi, z)
    sig = np.sqrt(base["axes"][axes[0]]["sigma2"])
    if w in SCALED:
        key = SCALED[w]
        # upper ends of plausible sizes: a dead zone below g/2 (beyond, its z falls again as
        # the whole signal vanishes into the scale), a gain asymmetry below 50 %, |K3| below
        # 0.01 /(m/s²)²; a dead zone has no sign
        hi = {"dead_zone": 0.5 * G, "scale_asymmetry": 0.5, "cubic_k3": 1e-2}.get(w, 50.0)
        mech[key] = mz(key, 1e-9, hi) * (1.0 if w == "dead_zone" else sign)
        note = f"z = {z} beyond the catalog's parametric signatures"
    elif w == "speed_noise":
        mech["amp"] = z * sig
        note = f"extra noise std {z} σ at the top speed"
    elif w == "impulsive_spikes":
        mech.update(frac=0.004, size=z)
        note = f"0.4 % of samples displaced by ±{z} σ"
    elif w == "asymmetric_clip":
        mech.update(hi=0.8 * G, lo=-0.93 * G)
        note = "rails at +0.80 g and −0.93 g"
    elif w == "frozen_output":
        mech.update(at=0.45, length=int(c.extra["length"]))
        note = f"{mech['length']} identical samples on both axes"
    else:
        raise ValueError(w)
    spec = {**base, "mechanisms": [mech]}
    if w in SCALED:
        # the sign may flip the direction of a monotone size: check the size reached
        real = effect_z(motion, base, spec, draws, rivals=rivals, band=band)
        if abs(real - z) > 1e-3 * z:
            raise RuntimeError(f"{c.case_id}: size {real} instead of {z}")
    return spec, {}, note


def _mechanism_defaults(w: str, motion, c: CaseDef, phase: float) -> dict:
    dur = float(motion.clock[-1] - motion.clock[0])
    if w == "settling_transient":
        return {"tau_s": 2.0 if motion.t is not None else 150.0}
    if w == "fractional_harmonic":
        return {"nu": c.extra.get("nu", 1.5), "phase": phase}
    if w == "bias_jump":
        return {"at": 0.55}
    if w == "ringing":
        return {"freq": 4.0, "zeta": 0.03}
    if w == "drive_vibration":
        return {"teeth": 23, "phase": phase}
    if w == "thermal_cycle":
        return {"period": dur / 1.6, "phase": phase}
    return {}


def _truth(c, seed, motion, base, spec, draws, params, size_note, stated) -> dict:
    expected_verdict = {"catalog": "explained", "clean": "nothing_detected",
                        "absorbed": "nothing_detected",
                        "out_of_catalog": "unexplained"}[c.kind]
    effects = [{"name": c.what, "axis": ax, "params": p} for ax, p in params.items()] \
        if c.kind == "catalog" else []
    sized = c.kind == "catalog" or c.what in SCALED
    z_real = effect_z(motion, base, spec, draws) if sized else None
    z_beyond = None
    if (c.kind == "out_of_catalog" and sized) or c.what == "bias_random_walk":
        z_beyond = effect_z(motion, base, spec, draws, rivals=catalog_columns(motion),
                            band=BAND if c.what == "flicker" else 0)
    if c.what in ("noise_level", "quantization"):
        z_real = c.z  # not a change of the mean: χ² excess in σ / lsb in σ (size note)
    z_near, near = None, ""
    if c.kind == "catalog" and c.what in ("misalignment", "tilt_offset", "nonlinearity_k2",
                                          "cross_axis", "bias_drift", "saturation",
                                          "lowpass_lag", "lever_arm"):
        z_near, near = z_vs_nearest(motion, base, spec, draws, c.what, _axes_of(c.axis))
    mu = mean_readings(motion, spec, draws)
    return {
        "format": FORMAT, "case_id": c.case_id, "split": split_of(c.case_id), "seed": seed,
        "kind": c.kind, "what": c.what, "axis": c.axis,
        "design": c.design, "timing": motion.timing, "sampling": c.sampling,
        "rate_hz": motion.rate, "n": motion.n,
        "noise_var": list(stated), "g_nominal": G,
        "expected": {"verdict": expected_verdict, "effects": effects},
        "mechanism": spec.get("mechanisms", [None])[0] if c.kind == "out_of_catalog" else None,
        "size": {"z_target": c.z if sized else None,
                 "z": z_real, "z_beyond_catalog": z_beyond, "z_vs_nearest": z_near,
                 "nearest_rival": near,
                 "note": size_note},
        "sensor": {"g": spec.get("g", G), "tilt_offset": spec.get("tilt_offset", 0.0),
                   "axes": {a: {k: (list(v) if isinstance(v, tuple) else v)
                                for k, v in p.items()} for a, p in spec["axes"].items()}},
        "motion": {"theta_min": float(motion.theta.min()), "theta_max": float(motion.theta.max()),
                   "omega_max": float(np.abs(motion.omega).max()),
                   "alpha_max": float(np.abs(motion.alpha).max()),
                   "stops": int(motion.stop_times.size),
                   "duration": float(motion.t[-1]) if motion.t is not None else None},
        "mean_reading_range": [float(mu.min()), float(mu.max())],
        "units": {"noise_var": "(m/s²)²", "rate_hz": "Hz", "n": "count", "seed": "—",
                  "g_nominal": "m/s²", "size.z": "1", "size.z_target": "1",
                  "size.z_vs_nearest": "1", "size.z_beyond_catalog": "1",
                  "motion.theta_min": "rad",
                  "motion.theta_max": "rad", "motion.omega_max": "rad/s",
                  "motion.alpha_max": "rad/s²", "motion.stops": "count",
                  "motion.duration": "s", "mean_reading_range": "m/s²",
                  "expected.effects.params": "docs/effects.md units per key",
                  "sensor.axes.*.bias": "m/s²", "sensor.axes.*.scale": "1",
                  "sensor.axes.*.sigma2": "(m/s²)²", "sensor.g": "m/s²",
                  "sensor.tilt_offset": "rad"},
    }

"""The effect catalog on the simulated bench: error terms, ``--effect`` parsing, config edits.

Every effect of the discrepancy workflow (``docs/effects.md``) can be put into a generated run,
so the bench can make data with it and the workflow (:mod:`bench.gap`) can add it back to the
model. Where the effect is physical it is a :class:`bench.model.TableEdits` field, applied to
the MJCF model through ``mujoco.MjSpec`` (MuJoCo then produces it):

=================== ======================================================================
``misalignment``    site rotated by δ about the hinge (+y): ``TableEdits.misalignment``
``tilt_offset``     both sites rotated by δ (table = encoder + δ): ``TableEdits.tilt_offset``
``lever_arm``       site moved to (pos_x, 0, pos_z) in the table frame: ``TableEdits.lever_arm``
``saturation``      MuJoCo sensor ``cutoff`` = limit: ``TableEdits.cutoff``
``gravity_mismatch`` ``option.gravity = (0, 0, -g)``: ``TableEdits.g``
=================== ======================================================================

The others are sensor-model terms (:class:`bench.sensors.ErrorTerm`, registered by name so
``truth.json`` round-trips through ``AxisErrors.to_dict`` / ``from_dict``), or, for
``noise_level``, the axis' white-noise variance ``AxisErrors.noise_var``.

Stages (see :mod:`bench.sensors`: response → ``(1 + scale)·a + bias`` → white noise → output)
follow the catalog's model column exactly:

* ``nonlinearity_k2``, ``cross_axis`` — response stage, so ``A_m = bias + (1 + scale)·(a_i +
  k2·a_i² + k_ip·a_i·a_p) + v`` as in the catalog's reading equation.
* ``lowpass_lag`` — response stage: the first-order low-pass acts on the signal, the white noise
  ``v`` is the noise *of the reading* (the stated σ² is measured at the output). The filter is
  linear with unit DC gain, so ``LPF(bias + (1 + scale)·a) = bias + (1 + scale)·LPF(a)``: the
  deterministic reading is the catalog's "low-pass on the output"; only the noise stays white
  (filtering it too would make the stated σ² wrong by the factor ``(1 - e^{-h/τ}) /
  (1 + e^{-h/τ})`` and colour the residuals).
* ``bias_drift``, ``bias_random_walk`` — output stage, additive at the bias level, so the reading
  is ``bias + rate·(t - t0) + …`` exactly as the catalog writes it (a response term would be
  multiplied by ``1 + scale``).
* ``quantization`` — output stage: the noisy reading is rounded to a multiple of ``lsb``.

Canonical term order inside a stage: :data:`TERM_ORDER`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from bench.model import TableEdits
from bench.sensors import AxisErrors, SensorContext, SensorErrorModel, Stage, register_term
from calib.conventions import AXES, EFFECT_NAMES, EFFECTS, PER_AXIS, EffectInfo, Timing
from calib.io import DataError

if TYPE_CHECKING:  # pragma: no cover
    from bench.tilt import CalibrationConfig

TERM_ORDER: tuple[str, ...] = ("lowpass_lag", "nonlinearity_k2", "cross_axis", "bias_drift",
                               "bias_random_walk", "quantization")
"""Order in which sensor terms are applied (stage first, then this order)."""


CATALOG = EFFECTS
"""The effect vocabulary (:data:`calib.conventions.EFFECTS`), under the bench's old name."""


def needs_timing(name: str) -> Timing:
    """"yes" / "units" / "no": what the effect needs from sample times (catalog column)."""
    return CATALOG[name].timing


def _finite(value: float, what: str) -> float:
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"{what} must be finite, got {value}")
    return value


def _positive(value: float, what: str) -> float:
    value = _finite(value, what)
    if value <= 0:
        raise ValueError(f"{what} must be positive, got {value}")
    return value


def _one_of(a: float | None, b: float | None, names: tuple[str, str], effect: str) -> None:
    if (a is None) == (b is None):
        raise ValueError(f"{effect}: give exactly one of {names[0]} (with timing) or "
                         f"{names[1]} (samples in time order)")


def _per_sample_or_time(ctx: SensorContext, n: int, per_second: bool, effect: str,
                        key: str) -> np.ndarray:
    """Elapsed time t - t0 (s) or the sample index k (samples) for a drift-type term."""
    if per_second:
        if ctx.t is None:
            raise ValueError(f"{effect}: '{key}' is per second and needs sample times (a "
                             f"sweep); use '{key}_per_sample' for a run without timing")
        t = np.asarray(ctx.t, dtype=float)
        return t - t[0]
    return np.arange(n, dtype=float)


# --- sensor error terms --------------------------------------------------------------------


@register_term
@dataclass(frozen=True)
class NonlinearityK2:
    """Second-order response (IEEE Std 1293 K2/K1): ``a ↦ a + k2·a²``.

    Parameters
    ----------
    k2 : 1/(m/s²). Positive raises the reading at both ends of the range (cos 2θ phase on the
        tilt table: ``a_x² = g²(1 - cos 2θ)/2``).
    """

    k2: float
    name: ClassVar[str] = "nonlinearity_k2"
    stage: ClassVar[Stage] = "response"

    def __post_init__(self) -> None:
        _finite(self.k2, "nonlinearity_k2 k2")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + k2·a²`` (a: (N,) m/s²)."""
        return a + self.k2 * a * a

    def to_dict(self) -> dict:
        return {"k2": float(self.k2)}


@register_term
@dataclass(frozen=True)
class CrossAxis:
    """Cross-coupling (IEEE Std 1293 K_ip/K1): ``a_i ↦ a_i + k_ip·a_i·a_p``.

    Parameters
    ----------
    k_ip : 1/(m/s²). ``a_p`` is the true specific force on the other in-plane axis (x ↔ y); on
        the tilt table ``a_x·a_y = g² sin 2θ / 2`` (sin 2θ phase).
    """

    k_ip: float
    name: ClassVar[str] = "cross_axis"
    stage: ClassVar[Stage] = "response"

    def __post_init__(self) -> None:
        _finite(self.k_ip, "cross_axis k_ip")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + k_ip·a·a_p``; ``a_p = ctx.a_true[:, other axis]``."""
        a_p = np.asarray(ctx.a_true, dtype=float)[:, 1 - ctx.axis]
        return a + self.k_ip * a * a_p

    def to_dict(self) -> dict:
        return {"k_ip": float(self.k_ip)}


@register_term
@dataclass(frozen=True)
class BiasDrift:
    """Linear bias drift, additive at the bias level: ``A_m ↦ A_m + rate·(t - t0)``.

    Exactly one of ``rate`` (m/s² per s, needs sample times) or ``rate_per_sample`` (m/s² per
    sample, ``t - t0`` replaced by the sample index k = 0…N-1) is given. The drift is zero at
    the first sample, so ``bias`` is the bias at the start of the run.
    """

    rate: float | None = None
    rate_per_sample: float | None = None
    name: ClassVar[str] = "bias_drift"
    stage: ClassVar[Stage] = "output"

    def __post_init__(self) -> None:
        _one_of(self.rate, self.rate_per_sample, ("rate", "rate_per_sample"), self.name)
        _finite(self.rate if self.rate is not None else self.rate_per_sample, "bias_drift rate")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + rate·(t - t0)`` (or ``a + rate_per_sample·k``)."""
        per_second = self.rate is not None
        x = _per_sample_or_time(ctx, a.shape[0], per_second, self.name, "rate")
        return a + (self.rate if per_second else self.rate_per_sample) * x

    def to_dict(self) -> dict:
        if self.rate is not None:
            return {"rate": float(self.rate)}
        return {"rate_per_sample": float(self.rate_per_sample)}


@register_term
@dataclass(frozen=True)
class BiasRandomWalk:
    """Bias random walk, additive at the bias level: ``b_k = b_{k-1} + q·√Δt_k·w_k``, b_0 = 0.

    Exactly one of ``q`` (m/s²/√s, Δt from the sample times) or ``q_per_sample`` (m/s² per
    √sample, Δt = 1) is given. Draws N - 1 standard normals w_k from the run's generator.
    """

    q: float | None = None
    q_per_sample: float | None = None
    name: ClassVar[str] = "bias_random_walk"
    stage: ClassVar[Stage] = "output"

    def __post_init__(self) -> None:
        _one_of(self.q, self.q_per_sample, ("q", "q_per_sample"), self.name)
        q = self.q if self.q is not None else self.q_per_sample
        if _finite(q, "bias_random_walk q") < 0:
            raise ValueError(f"bias_random_walk q must be >= 0, got {q}")

    def walk(self, n: int, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """The (N,) bias path b_k, m/s² (b_0 = 0)."""
        per_second = self.q is not None
        x = _per_sample_or_time(ctx, n, per_second, self.name, "q")
        q = self.q if per_second else self.q_per_sample
        w = rng.standard_normal(max(n - 1, 0))
        return np.concatenate([[0.0], np.cumsum(q * np.sqrt(np.diff(x)) * w)])[:n]

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + b`` with ``b`` a fresh random-walk path (see :meth:`walk`)."""
        return a + self.walk(a.shape[0], ctx, rng)

    def to_dict(self) -> dict:
        if self.q is not None:
            return {"q": float(self.q)}
        return {"q_per_sample": float(self.q_per_sample)}


@register_term
@dataclass(frozen=True)
class Quantization:
    """Output quantization: the reading is rounded to the nearest multiple of ``lsb`` (m/s²).

    Ties round up (``lsb·floor(a/lsb + 1/2)``), so the result does not depend on numpy's
    round-half-to-even.
    """

    lsb: float
    name: ClassVar[str] = "quantization"
    stage: ClassVar[Stage] = "output"

    def __post_init__(self) -> None:
        _positive(self.lsb, "quantization lsb")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``lsb·floor(a/lsb + 1/2)``."""
        return self.lsb * np.floor(a / self.lsb + 0.5)

    def to_dict(self) -> dict:
        return {"lsb": float(self.lsb)}


def lowpass(u: np.ndarray, t: np.ndarray, tau: float) -> np.ndarray:
    """First-order low-pass ``τ·dy/dt + y = u`` on samples ``u`` at times ``t``.

    Exact for an input linear between samples (first-order hold): with ``h = t_k - t_{k-1}``,
    ``a = e^{-h/τ}`` and ``c = (u_k - u_{k-1})/h``::

        y_k = u_k - τ·c + a·(y_{k-1} - u_{k-1} + τ·c)

    The filter starts at rest on the first sample (``y_0 = u_0``), as the bench starts at rest.
    For a ramp of slope c the output lags by τ: ``y = u - τ·c`` in steady state.
    """
    u = np.asarray(u, dtype=float)
    t = np.asarray(t, dtype=float)
    if u.shape != t.shape:
        raise ValueError(f"lowpass: u {u.shape} and t {t.shape} differ")
    if u.size == 0:
        return u.copy()
    h = np.diff(t)
    a = np.exp(-h / tau)
    c = np.diff(u) / h
    drive = u[1:] - tau * c  # y_k = drive_k + a_k·(y_{k-1} - u_{k-1} + τ c_k)
    carry = tau * c - u[:-1]
    y = np.empty_like(u)
    y[0] = u[0]
    prev = u[0]
    for k in range(h.size):  # a scalar recursion: ~0.3 µs per sample
        prev = drive[k] + a[k] * (prev + carry[k])
        y[k + 1] = prev
    return y


@register_term
@dataclass(frozen=True)
class LowpassLag:
    """First-order low-pass ``τ·dy/dt + y = u`` with time constant ``tau`` (s).

    Needs sample times. Response stage (see the module docstring): the deterministic reading is
    the catalog's low-passed output, the reading's white noise stays white. For a constant rate
    ω the reading lags like an angle offset −τ·ω.
    """

    tau: float
    name: ClassVar[str] = "lowpass_lag"
    stage: ClassVar[Stage] = "response"

    def __post_init__(self) -> None:
        _positive(self.tau, "lowpass_lag tau")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return the low-passed signal (see :func:`lowpass`)."""
        if ctx.t is None:
            raise ValueError("lowpass_lag needs sample times (a sweep); a static run has none")
        return lowpass(a, ctx.t, self.tau)

    def to_dict(self) -> dict:
        return {"tau": float(self.tau)}


TERM_CLASSES: dict[str, type] = {c.name: c for c in (
    NonlinearityK2, CrossAxis, BiasDrift, BiasRandomWalk, Quantization, LowpassLag)}
"""Catalog name → sensor term class (the non-physical effects except ``noise_level``)."""


# --- effects as data: parse, validate, apply ------------------------------------------------


@dataclass(frozen=True)
class EffectSpec:
    """One effect with its catalog parameters.

    name : catalog name.  axis : "x", "y" or "both".  params : JSON keys → values (SI units,
    catalog conventions). ``axis="both"`` on a per-axis effect means the same on both axes.
    """

    name: str
    axis: str
    params: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.name not in CATALOG:
            raise ValueError(f"unknown effect {self.name!r}; known: {', '.join(EFFECT_NAMES)}")
        info = CATALOG[self.name]
        allowed = info.axes + (("both",) if info.axes == PER_AXIS else ())
        if self.axis not in allowed:
            raise ValueError(f"effect {self.name}: axis must be one of {', '.join(allowed)}, "
                             f"got {self.axis!r}")
        unknown = sorted(set(self.params) - set(info.keys))
        if unknown:
            raise ValueError(f"effect {self.name}: unknown parameter(s) {', '.join(unknown)}; "
                             f"expected {', '.join(info.keys)}")
        clean = {k: _finite(v, f"{self.name} {k}") for k, v in self.params.items()}
        object.__setattr__(self, "params", clean)
        self._check()

    def _check(self) -> None:
        p, name = self.params, self.name
        if name in ("bias_drift", "bias_random_walk"):
            keys = CATALOG[name].keys
            if len(p) != 1:
                raise ValueError(f"effect {name}: give exactly one of {keys[0]} (per s, needs "
                                 f"timing) or {keys[1]} (per sample)")
            if name == "bias_random_walk" and next(iter(p.values())) < 0:
                raise ValueError(f"effect {name}: q must be >= 0")
            return
        if name == "lever_arm":
            if not p:
                raise ValueError("effect lever_arm: give pos_x and/or pos_z (m)")
            return
        (key,) = CATALOG[name].keys
        if key not in p:
            raise ValueError(f"effect {name}: parameter {key} is required")
        if key in ("sigma2", "lsb", "limit", "tau", "g") and p[key] <= 0:
            raise ValueError(f"effect {name}: {key} must be positive, got {p[key]}")

    @property
    def axes(self) -> tuple[str, ...]:
        """The sensor axes the effect touches."""
        return AXES if self.axis == "both" else (self.axis,)

    def to_dict(self) -> dict:
        return {"name": self.name, "axis": self.axis, "params": dict(self.params)}

    def option(self) -> str:
        """The ``--effect`` text that gives this effect back."""
        kv = ",".join(f"{k}={v!r}" for k, v in self.params.items())
        return f"{self.name}:{self.axis}:{kv}"


def parse_effect_option(text: str) -> EffectSpec:
    """Parse ``NAME:AXIS:KEY=VALUE[,KEY=VALUE]`` (the ``--effect`` option).

    Examples: ``misalignment:x:delta=0.02``, ``tilt_offset:both:delta=0.01``,
    ``lever_arm:y:pos_x=0.2,pos_z=0.05``, ``bias_drift:x:rate_per_sample=1e-4``.
    Raises :class:`calib.io.DataError` naming the option and what is wrong.
    """
    where = f"--effect {text!r}"
    parts = text.strip().split(":")
    if len(parts) != 3:
        raise DataError(f"{where}: expected NAME:AXIS:KEY=VALUE[,KEY=VALUE], e.g. "
                        "misalignment:x:delta=0.02")
    name, axis, body = (s.strip() for s in parts)
    params: dict[str, float] = {}
    for item in filter(None, (s.strip() for s in body.split(","))):
        key, eq, value = item.partition("=")
        if not eq:
            raise DataError(f"{where}: parameter {item!r} must be KEY=VALUE")
        try:
            params[key.strip()] = float(value)
        except ValueError:
            raise DataError(f"{where}: value of {key.strip()!r} is not a number: "
                            f"{value!r}") from None
    try:
        return EffectSpec(name, axis, params)
    except ValueError as exc:
        raise DataError(f"{where}: {exc}") from None


def make_term(effect: EffectSpec):
    """The sensor term of a non-physical effect (not ``noise_level``)."""
    return TERM_CLASSES[effect.name](**effect.params)


def _sorted_terms(terms) -> tuple:
    stage_rank = {"response": 0, "output": 1}
    return tuple(sorted(terms, key=lambda t: (stage_rank[t.stage], TERM_ORDER.index(t.name))))


def apply_to_model(effects, table: TableEdits, sensor: SensorErrorModel
                   ) -> tuple[TableEdits, SensorErrorModel]:
    """Put ``effects`` into a table (MjSpec edits) and a sensor error model.

    Physical effects set their :class:`TableEdits` field (replacing any earlier value on that
    axis); ``noise_level`` sets the axis' noise variance; the others add a sensor term (an
    existing term of the same name on that axis is replaced). Terms are kept in the canonical
    order (:data:`TERM_ORDER`).
    """
    mis = list(table.misalignment)
    lever = [tuple(p) for p in table.lever_arm]
    cutoff = list(table.cutoff)
    g, offset = table.g, table.tilt_offset
    axes = {a: sensor.axis(a) for a in AXES}
    for e in effects:
        if e.name == "gravity_mismatch":
            g = e.params["g"]
        elif e.name == "tilt_offset":
            offset = e.params["delta"]
        for a in e.axes if CATALOG[e.name].axes == PER_AXIS else ():
            k = AXES.index(a)
            if e.name == "misalignment":
                mis[k] = e.params["delta"]
            elif e.name == "lever_arm":
                lever[k] = (e.params.get("pos_x", 0.0), e.params.get("pos_z", 0.0))
            elif e.name == "saturation":
                cutoff[k] = e.params["limit"]
            elif e.name == "noise_level":
                axes[a] = replace(axes[a], noise_var=e.params["sigma2"])
            else:
                kept = [t for t in axes[a].terms if t.name != e.name]
                axes[a] = replace(axes[a], terms=_sorted_terms([*kept, make_term(e)]))
    table = TableEdits(g=g, misalignment=tuple(mis), tilt_offset=offset,
                       lever_arm=tuple(lever), cutoff=tuple(cutoff))
    return table, SensorErrorModel(axes["x"], axes["y"])


def apply_effects(config: CalibrationConfig, effects) -> CalibrationConfig:
    """Return ``config`` with ``effects`` (iterable of :class:`EffectSpec`) added.

    Checks that the run can show the effect: ``lowpass_lag``, ``lever_arm`` and the per-second
    forms of ``bias_drift`` / ``bias_random_walk`` need a sweep (sample times); a static run
    gets :class:`calib.io.DataError` with the fix. The result serializes the effects into
    ``truth.json`` through ``config.to_dict()`` (table edits and sensor terms).
    """
    effects = list(effects)
    if config.mode != "sweep":
        for e in effects:
            timing = CATALOG[e.name].timing
            if timing == "yes" or (timing == "units"
                                   and not next(iter(e.params)).endswith("_per_sample")):
                hint = (" (use the *_per_sample form for a static run)"
                        if CATALOG[e.name].timing == "units" else "")
                raise DataError(f"--effect {e.name}: needs sample times; use --mode sweep"
                                f"{hint}")
    table, sensor = apply_to_model(effects, config.table, config.sensor)
    return replace(config, table=table, sensor=sensor)


def effects_from_truth(truth: dict, stated_noise_var=None) -> list[EffectSpec]:
    """The catalog effects present in a calibration ``truth.json`` (or ``config.to_dict()``).

    ``noise_level`` is listed only when ``stated_noise_var`` (x, y) is given and differs from
    the true noise variance. ``gravity_mismatch`` is listed when the true g differs from 9.8.
    """
    from calib.conventions import G

    out: list[EffectSpec] = []
    table, sensor = truth["table"], truth["sensor"]
    if not np.isclose(float(truth.get("g", table["g"])), G, rtol=0, atol=1e-12):
        out.append(EffectSpec("gravity_mismatch", "both", {"g": float(table["g"])}))
    if float(table["tilt_offset"]) != 0.0:
        out.append(EffectSpec("tilt_offset", "both", {"delta": float(table["tilt_offset"])}))
    for k, a in enumerate(AXES):
        if float(table["misalignment"][k]) != 0.0:
            out.append(EffectSpec("misalignment", a, {"delta": float(table["misalignment"][k])}))
        px, pz = (float(v) for v in table["lever_arm"][k])
        if px or pz:
            out.append(EffectSpec("lever_arm", a, {"pos_x": px, "pos_z": pz}))
        if float(table["cutoff"][k]) > 0:
            out.append(EffectSpec("saturation", a, {"limit": float(table["cutoff"][k])}))
        ax = AxisErrors.from_dict(sensor[a])
        if stated_noise_var is not None and not np.isclose(ax.noise_var,
                                                           float(stated_noise_var[k])):
            out.append(EffectSpec("noise_level", a, {"sigma2": ax.noise_var}))
        out.extend(EffectSpec(t.name, a, t.to_dict()) for t in ax.terms)
    return out


def catalog_table() -> str:
    """The catalog as a plain-text table (for ``--help`` epilogues and reports)."""
    rows = [f"{'name':18s} {'axis':6s} {'params (units)':40s} timing"]
    for e in CATALOG.values():
        params = ", ".join(f"{k} ({u})" for k, u in zip(e.keys, e.units, strict=True))
        rows.append(f"{e.name:18s} {'/'.join(e.axes):6s} {params:40s} {e.timing}")
    return "\n".join(rows)


__all__ = [
    "CATALOG", "EFFECT_NAMES", "TERM_ORDER", "EffectInfo", "EffectSpec", "NonlinearityK2",
    "CrossAxis", "BiasDrift", "BiasRandomWalk", "Quantization", "LowpassLag", "lowpass",
    "parse_effect_option", "apply_effects", "apply_to_model", "effects_from_truth",
    "make_term", "needs_timing", "catalog_table",
]

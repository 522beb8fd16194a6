"""The effect catalog on the simulated bench: model and config edits, ``--effect`` parsing.

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

The others are sensor-model terms (:mod:`bench.terms`: the term classes, their stages and
:data:`~bench.terms.TERM_ORDER`, registered by name so ``truth.json`` round-trips through
``AxisErrors.to_dict`` / ``from_dict``), or, for ``noise_level``, the axis' white-noise variance
``AxisErrors.noise_var``. The term classes are re-exported here.

Layering (no import circle): :mod:`bench.terms` ← :mod:`bench.sensors` ← :mod:`bench.tilt` ←
this module (catalog edits of a model and a config, ``--effect`` parsing).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from bench.model import TableEdits
from bench.sensors import AxisErrors, SensorErrorModel
from bench.terms import (
    TERM_CLASSES,
    TERM_ORDER,
    BiasDrift,
    BiasRandomWalk,
    CrossAxis,
    LowpassLag,
    NonlinearityK2,
    Quantization,
    require_finite,
)
from bench.tilt import CalibrationConfig
from calib.conventions import AXES, EFFECT_NAMES, EFFECTS, PER_AXIS, EffectInfo, G, Timing
from calib.files.course import DataError

CATALOG = EFFECTS
"""The effect vocabulary (:data:`calib.conventions.EFFECTS`), under the bench's old name."""


def needs_timing(name: str) -> Timing:
    """"yes" / "units" / "no": what the effect needs from sample times (catalog column)."""
    return CATALOG[name].timing


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
        clean = {k: require_finite(v, f"{self.name} {k}") for k, v in self.params.items()}
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
    Raises :class:`calib.files.course.DataError` naming the option and what is wrong.
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
    gets :class:`calib.files.course.DataError` with the fix. The result serializes the effects into
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
    "CrossAxis", "BiasDrift", "BiasRandomWalk", "Quantization", "LowpassLag",
    "parse_effect_option", "apply_effects", "apply_to_model", "effects_from_truth",
    "make_term", "needs_timing", "catalog_table",
]

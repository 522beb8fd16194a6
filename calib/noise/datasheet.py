"""A sensor's datasheet against the measured noise terms (``tiltbench noise --datasheet``).

A datasheet prints each noise term in its own units — an accelerometer's noise density in
µg/√Hz, its bias instability in µg; a gyro's angle random walk in °/√h (or a rate noise
density in °/s/√Hz), its bias instability in °/h. Each value is read with its unit
(:func:`calib.noise.term_units.unit_factor`: any spelling of a unit of the right dimension,
``µg/√Hz``, ``ug/rtHz``, ``ug/sqrt(Hz)``, ``mg/√Hz``, ``(m/s^2)/sqrt(Hz)``…), converted to SI
and compared with the term measured on every axis it applies to.

**The spec** (:func:`parse_datasheet`), comma- (or semicolon-) separated items::

    [SCOPE.]TERM=VALUE UNIT        e.g.  N=60ug/rtHz,B=20ug,ARW=0.2deg/rth,BI=5deg/h,x.N=45ug/rtHz

=========================  ==========================================================
TERM (any case)            the term
=========================  ==========================================================
N, white_noise_density,    white-noise density (ARW: a gyro's angle random walk, VRW:
noise_density, ARW, VRW    an accelerometer's velocity random walk)
B, BI, bias_instability    bias instability (the Allan floor / 0.664)
K, RRW, rate_random_walk   rate random walk (the +½ slope)
=========================  ==========================================================

SCOPE is ``acc`` (or ``accel``, ``accelerometer``), ``gyro``, or one axis (``x``, ``y``,
``z``, ``gyro_x``, ``gyro_y``, ``gyro_z``). Without a scope the unit tells the kind (µg/√Hz is
an accelerometer's, °/√h a gyro's); a kind's value applies to every axis of that kind, an
axis's value to that axis only (it wins over its kind's). The value is a positive finite
number, written before its unit with or without a space.

**The JSON file** (:func:`load_datasheet`): the same, keyed by scope and term, a value either
``{"value": 60, "unit": "µg/√Hz"}`` or the string ``"60 µg/√Hz"``, and an optional ``name``::

    {"name": "my IMU",
     "accelerometer": {"white_noise_density": {"value": 25, "unit": "µg/√Hz"},
                       "bias_instability": "10 µg"},
     "gyro": {"ARW": "0.2 °/√h", "BI": "5 °/h"},
     "x": {"N": "22 ug/rtHz"}}

:func:`read_datasheets` reads several (the repeated option): a spec when the text holds
``=``, else a file; a later value replaces an earlier one of the same scope and term, and one
spec or file may not give the same scope and term twice.

**Refused**, each in one line (``ValueError`` naming the item or the file's field and what is
accepted): an unknown term or scope, a value that is not a positive finite number, a missing
unit, a unit that cannot be read or of the wrong dimension (``µg`` for a noise density), a
scope and a term of different kinds (``acc.ARW``).

**The verdict** (:func:`verdict`, :func:`compare_term`). Datasheets state typical or maximum
values; the value D is taken as an upper limit the sensor should not exceed. With the term's
interval [lo, hi] at the fit's ``level`` (:class:`calib.noise.allan.TermFit`):

===================  ==============================  =======================================
the measured term    condition                       verdict
===================  ==============================  =======================================
resolved             hi ≤ D                          meets (the whole interval at or below)
resolved             lo > D                          exceeds (the whole interval above)
resolved             lo ≤ D < hi                     inconclusive (the interval holds D)
not resolved         upper bound ≤ D                 meets
not resolved         upper bound > D                 inconclusive (never "exceeds": the
                                                     term is reported as a bound only)
absent               no axis of the log it applies   not measured
                     to
===================  ==============================  =======================================

The ratio measured/D is reported (the estimate's; a bound's for a term not resolved), with
the interval's ends over D. The verdict is at the intervals' level: at the one-sigma default
of ``noise`` a third of the true values fall outside, so a term within a standard error of D
is "inconclusive", not a pass or a fail; ``--level 0.95`` asks for more.

Units: every ``si`` value in the term's SI unit (:data:`calib.noise.term_units.SI_UNITS`);
``datasheet_units`` in the unit the datasheet gave (its canonical spelling of
:data:`calib.noise.term_units.DATASHEET` when it is that unit, e.g. ``µg/√Hz`` for
``ug/rtHz``); ratios dimensionless.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from calib.input_rules import DataError, check_file
from calib.noise.term_units import (
    ACCEPTED_UNITS,
    DATASHEET,
    KINDS,
    SI_UNITS,
    TERM_DIMENSIONS,
    format_dimension,
    kind_of,
    parse_unit,
    unit_factor,
)
from calib.results import ResultMixin

if TYPE_CHECKING:
    from calib.noise.allan import NoiseCharacterization, TermFit

DATASHEET_TERMS: tuple[str, ...] = ("white_noise_density", "bias_instability",
                                    "rate_random_walk")
"""The terms a datasheet is checked for, in the order they are printed."""
SYMBOLS: dict[str, str] = {"white_noise_density": "N", "bias_instability": "B",
                           "rate_random_walk": "K"}
"""Each term's symbol (IEEE Std 952)."""
AXES: tuple[str, ...] = ("x", "y", "z", "gyro_x", "gyro_y", "gyro_z")
"""The axis names of ``tiltbench noise`` a value may be scoped to."""
KIND_SCOPES: dict[str, str] = {"acc": "accelerometer", "accel": "accelerometer",
                               "accelerometer": "accelerometer", "gyro": "gyro"}
"""Scope spellings of a sensor kind."""
TERM_KEYS: dict[str, tuple[str, str | None]] = {
    "n": ("white_noise_density", None), "white_noise_density": ("white_noise_density", None),
    "noise_density": ("white_noise_density", None), "arw": ("white_noise_density", "gyro"),
    "vrw": ("white_noise_density", "accelerometer"),
    "b": ("bias_instability", None), "bi": ("bias_instability", None),
    "bias_instability": ("bias_instability", None),
    "k": ("rate_random_walk", None), "rrw": ("rate_random_walk", None),
    "rate_random_walk": ("rate_random_walk", None),
}
"""Term spellings (lower case) → (the term, the kind the spelling implies or None)."""
VERDICTS: tuple[str, ...] = ("meets", "exceeds", "inconclusive", "not measured")
"""Every verdict (module docstring)."""
RULE = ("a datasheet value D is a maximum: meets when the measured interval is at or below D, "
        "exceeds when it is above D, inconclusive when it holds D; a term not resolved meets "
        "when its upper bound is at or below D, else inconclusive")
"""The verdict rule in one sentence (the JSON's ``rule``)."""
_SI_LIST = "; ".join(f"{kind} " + ", ".join(f"{t} {SI_UNITS[kind][t]}" for t in DATASHEET_TERMS)
                    for kind in KINDS)


def json_units(prefix: str = "") -> dict[str, str]:
    """Units of the JSON object of :class:`DatasheetCheck`, its keys (and the keys the units
    refer to) under ``prefix`` (``"datasheet."`` inside ``noise --json``)."""
    p = prefix
    return {f"{p}level": "1", f"{p}counts": "count", f"{p}checks.*.level": "1",
            f"{p}checks.*.ratio": "1", f"{p}checks.*.ratio_interval": "1",
            f"{p}checks.*.si.*": f"{p}checks.*.si.unit (SI: {_SI_LIST})",
            f"{p}checks.*.datasheet_units.*": f"{p}checks.*.datasheet_units.unit (the "
            "datasheet's unit)",
            f"{p}checks.*.limit.value": f"{p}checks.*.limit.unit",
            f"{p}checks.*.limit.si": f"{p}checks.*.limit.si_unit"}


UNITS: dict[str, str] = json_units()
"""Units of the JSON object of :class:`DatasheetCheck` (keys relative to it)."""

_TERMS_HELP = ("N (noise density; ARW: a gyro's, VRW: an accelerometer's), B or BI (bias "
               "instability), K or RRW (rate random walk), or white_noise_density, "
               "bias_instability, rate_random_walk")
_SCOPES_HELP = "acc (accelerometer), gyro, or an axis " + ", ".join(AXES)
_NUMBER = re.compile(r"\s*([+-]?(?:(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan))"
                     r"(.*)$", re.IGNORECASE | re.DOTALL)


def _term_label(kind: str, term: str) -> str:
    return f"{kind}'s {term.replace('_', ' ')} {SYMBOLS[term]}"


# --- the datasheet --------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class DatasheetValue(ResultMixin):
    """One value of a datasheet, as given and in SI.

    scope : ``accelerometer``, ``gyro`` (every axis of that kind) or an axis name (that axis).
    kind : ``accelerometer`` or ``gyro``.
    term : a name of :data:`DATASHEET_TERMS`.
    value : the number the datasheet prints, in ``unit`` (> 0).
    unit : the unit as given (e.g. ``ug/rtHz``).
    si : the value in the term's SI unit (:data:`calib.noise.term_units.SI_UNITS`), e.g.
        (m/s²)/√Hz for an accelerometer's N: ``value · factor`` of the unit.
    """

    scope: str
    kind: str
    term: str
    value: float
    unit: str
    si: float

    _TITLE = "Datasheet value"
    _UNITS = "value in unit; si in the term's SI unit (calib.noise.term_units)"

    @property
    def factor(self) -> float:
        """SI per unit of ``unit``."""
        return self.si / self.value

    @property
    def si_unit(self) -> str:
        return SI_UNITS[self.kind][self.term]

    @property
    def symbol(self) -> str:
        return SYMBOLS[self.term]

    @property
    def display_unit(self) -> str:
        """``unit`` in the canonical datasheet spelling (µg/√Hz, °/√h, …;
        :data:`calib.noise.term_units.DATASHEET`) when it is that unit, else as given."""
        canonical, to_datasheet = DATASHEET[self.kind][self.term]
        if math.isclose(self.factor * to_datasheet, 1.0, rel_tol=1e-9):
            return canonical
        return self.unit

    def summary(self) -> str:
        return (f"{self.scope} {self.symbol} = {self.value:g} {self.display_unit} "
                f"({self.si:.6g} {self.si_unit})")

    def to_dict(self) -> dict:
        return {"scope": self.scope, "kind": self.kind, "term": self.term,
                "value": float(self.value), "unit": self.unit, "si": float(self.si),
                "si_unit": self.si_unit}

    @classmethod
    def from_dict(cls, d: dict) -> DatasheetValue:
        return cls(scope=d["scope"], kind=d["kind"], term=d["term"], value=float(d["value"]),
                   unit=d["unit"], si=float(d["si"]))


@dataclass(frozen=True, eq=False)
class Datasheet(ResultMixin):
    """The values of a datasheet (:func:`parse_datasheet`, :func:`load_datasheet`), one per
    scope and term; ``name``: the sensor's, if the file gave it."""

    values: tuple[DatasheetValue, ...]
    name: str | None = None

    _TITLE = "Datasheet"
    _UNITS = "each value in its unit and in SI (calib.noise.term_units)"

    def __post_init__(self) -> None:
        object.__setattr__(self, "values", tuple(self.values))

    def lookup(self, axis: str, kind: str, term: str) -> DatasheetValue | None:
        """The value of ``term`` for ``axis`` (of ``kind``): the axis's own, else its kind's,
        else None."""
        for scope in (axis, kind):
            for v in self.values:
                if v.scope == scope and v.term == term:
                    return v
        return None

    def merged(self, later: Datasheet) -> Datasheet:
        """This datasheet with ``later``'s values replacing those of the same scope and term
        (and its name, if it has one)."""
        values = {(v.scope, v.term): v for v in self.values}
        values.update({(v.scope, v.term): v for v in later.values})
        return Datasheet(values=tuple(values.values()), name=later.name or self.name)

    def summary(self) -> str:
        head = f"datasheet {self.name}" if self.name else "datasheet"
        return "\n".join([head] + ["  " + v.summary() for v in self.values])

    def to_dict(self) -> dict:
        return {"name": self.name, "values": [v.to_dict() for v in self.values]}

    @classmethod
    def from_dict(cls, d: dict) -> Datasheet:
        return cls(values=tuple(DatasheetValue.from_dict(v) for v in d["values"]),
                   name=d.get("name"))


def datasheet_value(scope: str | None, key: str, value: Any, unit: str, where: str
                    ) -> DatasheetValue:
    """One checked :class:`DatasheetValue` from a scope (None: the unit tells the kind), a
    term spelling (:data:`TERM_KEYS`), a number and its unit. ``where`` starts every refusal
    (the item, or the file and field): ``ValueError`` for an unknown term or scope, a value
    that is not a positive finite number, no unit, a unit of the wrong dimension, a scope and
    term of different kinds (module docstring)."""
    term, key_kind = TERM_KEYS.get(str(key).strip().lower(), (None, None))
    if term is None:
        raise ValueError(f"{where}: unknown term {key!r}; accepted: {_TERMS_HELP}")
    scope_name = scope_kind = None
    if scope is not None:
        s = str(scope).strip().lower()
        if s in KIND_SCOPES:
            scope_name = scope_kind = KIND_SCOPES[s]
        elif s in AXES:
            scope_name, scope_kind = s, kind_of(s)
        else:
            raise ValueError(f"{where}: unknown scope {scope!r}; accepted: {_SCOPES_HELP}")
    if key_kind and scope_kind and key_kind != scope_kind:
        article = "an" if scope_kind == "accelerometer" else "a"
        raise ValueError(f"{where}: {key} is the {_term_label(key_kind, term)}, not {article} "
                         f"{scope_kind}'s" + ("" if scope_name == scope_kind else
                                              f" ({scope_name} is {article} {scope_kind} axis)"))
    kind = scope_kind or key_kind
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{where}: the value {value!r} is not a number")
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{where}: the value {value:g} is not a positive finite number (a "
                         "datasheet states a positive maximum, e.g. N=60ug/rtHz)")
    unit = str(unit).strip()
    kinds = (kind,) if kind else KINDS
    if not unit:
        raise ValueError(f"{where}: no unit (a value is read with its unit, never guessed); "
                         "accepted units: " + "; ".join(
                             f"{k}: {ACCEPTED_UNITS[k][term]}" for k in kinds))
    if kind:
        try:
            factor = unit_factor(unit, kind, term)
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
    else:
        try:
            factor, dim = parse_unit(unit)
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
        fits = [k for k in KINDS if TERM_DIMENSIONS[k][term] == dim]
        if not fits:
            acc, gyro = (f"{format_dimension(TERM_DIMENSIONS[k][term])}; accepted units: "
                         f"{ACCEPTED_UNITS[k][term]}" for k in ("accelerometer", "gyro"))
            raise ValueError(f"{where}: unit {unit!r} is {format_dimension(dim)}, neither an "
                             f"accelerometer's {term.replace('_', ' ')} ({acc}) nor a gyro's "
                             f"({gyro})")
        kind = fits[0]
    si = value * factor
    if not (math.isfinite(si) and si > 0):
        raise ValueError(f"{where}: {value:g} {unit} is {si:g} {SI_UNITS[kind][term]} in SI: "
                         "not a positive finite number")
    return DatasheetValue(scope=scope_name or kind, kind=kind, term=term, value=value,
                          unit=unit, si=si)


def _one_each(values: list[DatasheetValue], wheres: list[str], what: str) -> None:
    """Refuse one spec or file that gives a scope's term twice."""
    seen: dict[tuple[str, str], str] = {}
    for v, where in zip(values, wheres, strict=True):
        key = (v.scope, v.term)
        if key in seen:
            raise ValueError(f"{where}: {v.scope} {v.symbol} ({v.term}) is given twice in "
                             f"{what} (also by {seen[key]})")
        seen[key] = where


def parse_datasheet(spec: str) -> Datasheet:
    """The :class:`Datasheet` of a spec ``[SCOPE.]TERM=VALUE UNIT, …`` (module docstring).

    >>> sheet = parse_datasheet("N=60ug/rtHz,ARW=0.2deg/rt(h)")
    >>> [(v.kind, v.term, v.display_unit) for v in sheet.values]
    [('accelerometer', 'white_noise_density', 'µg/√Hz'), ('gyro', 'white_noise_density', '°/√h')]
    >>> round(sheet.values[0].si / 9.80665e-6, 9)
    60.0
    """
    items = [s.strip() for s in re.split(r"[,;]", str(spec))]
    if not any(items):
        raise ValueError(f"{spec!r}: no TERM=VALUE UNIT item (e.g. N=60ug/rtHz,B=20ug)")
    values, wheres = [], []
    for item in items:
        if not item:
            continue
        where = f"item {item!r}"
        left, eq, right = item.partition("=")
        if not eq or "=" in right:
            raise ValueError(f"{where}: expected [SCOPE.]TERM=VALUE UNIT, e.g. N=60ug/rtHz or "
                             "x.B=20ug")
        parts = left.split(".")
        if len(parts) > 2 or not all(p.strip() for p in parts):
            raise ValueError(f"{where}: expected [SCOPE.]TERM before '=', SCOPE {_SCOPES_HELP}")
        scope, key = (None, parts[0]) if len(parts) == 1 else parts
        m = _NUMBER.match(right)
        if m is None:
            raise ValueError(f"{where}: no number after '=' (VALUE UNIT, e.g. 60ug/rtHz)")
        values.append(datasheet_value(scope, key, float(m.group(1)), m.group(2), where))
        wheres.append(where)
    _one_each(values, wheres, "one --datasheet")
    return Datasheet(values=tuple(values))


def datasheet_from_dict(doc: Any, where: str = "datasheet") -> Datasheet:
    """The :class:`Datasheet` of a JSON object (module docstring); ``where`` (the file's name)
    starts every refusal, which names the field."""
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: expected a JSON object {{\"accelerometer\": {{...}}, "
                         f"\"gyro\": {{...}}}}, got {type(doc).__name__}")
    name = doc.get("name")
    if name is not None and not isinstance(name, str):
        raise ValueError(f"{where}: field 'name' must be a string (the sensor's name)")
    values, wheres = [], []
    for scope, terms in doc.items():
        if scope == "name":
            continue
        if str(scope).strip().lower() not in (*KIND_SCOPES, *AXES):
            raise ValueError(f"{where}: unknown field {scope!r}; accepted: name, "
                             f"{_SCOPES_HELP}")
        if not isinstance(terms, dict):
            raise ValueError(f"{where}: field {scope!r} must be an object of terms, e.g. "
                             "{\"white_noise_density\": {\"value\": 60, \"unit\": \"µg/√Hz\"}}")
        for key, given in terms.items():
            field = f"{where}: field '{scope}.{key}'"
            if isinstance(given, str):
                m = _NUMBER.match(given)
                if m is None:
                    raise ValueError(f"{field}: expected \"VALUE UNIT\" (e.g. \"60 µg/√Hz\") or "
                                     "{\"value\": 60, \"unit\": \"µg/√Hz\"}")
                number, unit = float(m.group(1)), m.group(2)
            elif isinstance(given, dict):
                extra = set(given) - {"value", "unit"}
                if extra or "value" not in given or "unit" not in given:
                    raise ValueError(f"{field}: expected {{\"value\": NUMBER, \"unit\": UNIT}}"
                                     + (f", not {sorted(extra)}" if extra else ""))
                number, unit = given["value"], given["unit"]
                if not isinstance(unit, str):
                    raise ValueError(f"{field}.unit: expected a string such as \"µg/√Hz\"")
            else:
                raise ValueError(f"{field}: expected {{\"value\": NUMBER, \"unit\": UNIT}} or "
                                 "\"VALUE UNIT\"")
            values.append(datasheet_value(scope, key, number, unit, field))
            wheres.append(field)
    if not values:
        raise ValueError(f"{where}: no datasheet value (e.g. {{\"accelerometer\": "
                         "{\"white_noise_density\": {\"value\": 60, \"unit\": \"µg/√Hz\"}}})")
    _one_each(values, wheres, where)
    return Datasheet(values=tuple(values), name=name)


def load_datasheet(path: str | Path) -> Datasheet:
    """The :class:`Datasheet` of a JSON file (module docstring); :class:`DataError` naming the
    file for one that is missing or not JSON, ``ValueError`` naming the field otherwise."""
    path = Path(path)
    check_file(path, "a datasheet JSON file", "datasheet file")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataError(f"{path}: not a JSON datasheet ({exc}); or give the values as "
                        "N=60ug/rtHz,B=20ug,…") from None
    return datasheet_from_dict(doc, str(path))


def read_datasheet(text: str) -> Datasheet:
    """A spec when ``text`` holds ``=`` (:func:`parse_datasheet`), else a JSON file
    (:func:`load_datasheet`)."""
    if not str(text).strip():
        raise ValueError("an empty value; give [SCOPE.]TERM=VALUE UNIT items (e.g. "
                         "N=60ug/rtHz,B=20ug) or a JSON file")
    return parse_datasheet(text) if "=" in text else load_datasheet(text)


def read_datasheets(texts: Iterable[str]) -> Datasheet:
    """The datasheets of ``texts`` (:func:`read_datasheet`) merged in order: a later value
    replaces an earlier one of the same scope and term."""
    sheet: Datasheet | None = None
    for text in texts:
        one = read_datasheet(text)
        sheet = one if sheet is None else sheet.merged(one)
    if sheet is None:
        raise ValueError("no datasheet given")
    return sheet


# --- the comparison -------------------------------------------------------------------------


def verdict(lo: float, hi: float, limit: float) -> str:
    """``meets`` when ``hi ≤ limit``, ``exceeds`` when ``lo > limit``, else ``inconclusive``
    (an interval [lo, hi] against a datasheet maximum, all in one unit; module docstring).

    >>> verdict(45.9, 48.3, 60.0), verdict(61.0, 65.0, 60.0), verdict(55.0, 65.0, 60.0)
    ('meets', 'exceeds', 'inconclusive')
    """
    if hi <= limit:
        return "meets"
    if lo > limit:
        return "exceeds"
    return "inconclusive"


def _num(x: float) -> str:
    """``x`` to 3 significant digits as ``:.3g`` prints it, but without an exponent from 1e-3
    to 1e6 (5100, not 5.1e+03)."""
    if x == 0 or not 1e-3 <= abs(x) < 1e6:
        return f"{x:.3g}"
    decimals = 2 - math.floor(math.log10(abs(x)))
    text = f"{round(x, decimals):.{max(decimals, 0)}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def _times(r: float) -> str:
    return f"{_num(r)}×"


@dataclass(frozen=True, eq=False)
class TermCheck(ResultMixin):
    """One measured term of one axis against its datasheet value (module docstring).

    axis : the axis; for a value no axis of the log takes (``not measured``), its scope.
    limit : the :class:`DatasheetValue` D.
    verdict : one of :data:`VERDICTS`.
    level : two-sided level of the interval.
    resolved : whether the log resolves the term (None: not measured).
    value : the estimate, SI, or None (not resolved, not measured).
    interval : (lo, hi), SI, or None (not measured).
    upper_bound : hi, SI — what a term not resolved is reported as; None when not measured.
    note : why it was not measured, or that no model describes the axis's Allan curve.
    """

    axis: str
    limit: DatasheetValue
    verdict: str
    level: float
    resolved: bool | None = None
    value: float | None = None
    interval: tuple[float, float] | None = None
    upper_bound: float | None = None
    note: str = ""

    _TITLE = "Datasheet check of one term"
    _UNITS = "value, interval, upper bound SI; ratios 1"

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict {self.verdict!r}: one of {', '.join(VERDICTS)}")
        if self.interval is not None:
            object.__setattr__(self, "interval", tuple(float(v) for v in self.interval))

    @property
    def kind(self) -> str:
        return self.limit.kind

    @property
    def term(self) -> str:
        return self.limit.term

    @property
    def ratio(self) -> float | None:
        """measured / D: the estimate's, or the upper bound's when not resolved."""
        if self.verdict == "not measured":
            return None
        top = self.value if self.resolved else self.upper_bound
        return float(top / self.limit.si)

    @property
    def ratio_interval(self) -> tuple[float, float] | None:
        """(lo, hi) / D."""
        if self.interval is None:
            return None
        return (self.interval[0] / self.limit.si, self.interval[1] / self.limit.si)

    def _shown(self, x: float | None) -> float | None:
        """``x`` (SI) in the datasheet's unit."""
        return None if x is None else float(x / self.limit.factor)

    def verdict_text(self) -> str:
        """The verdict with its ratio to D: ``meets (0.79×)``, ``exceeds by 2.9× (at least
        2.8×)``, ``inconclusive (0.95–1.02×)`` (the interval's ends), ``meets (≤ 0.3×, not
        resolved)`` (the upper bound's)."""
        r, ri = self.ratio, self.ratio_interval
        if self.verdict == "not measured":
            return "not measured"
        if not self.resolved:
            if self.verdict == "meets":
                return f"meets (≤ {_times(r)}, not resolved)"
            return f"inconclusive (≤ {_times(r)}, not resolved)"
        if self.verdict == "meets":
            return f"meets ({_times(r)})"
        if self.verdict == "exceeds":
            return f"exceeds by {_times(r)} (at least {_times(ri[0])})"
        return f"inconclusive ({_num(ri[0])}–{_times(ri[1])})"

    def summary(self) -> str:
        u = self.limit.display_unit
        head = f"{self.axis:<6} {self.limit.symbol}"
        sheet = f"datasheet {self.limit.value:g} {u}"
        if self.verdict == "not measured":
            return f"{head} not measured ({self.note}); {sheet}"
        lo, hi = (self._shown(v) for v in self.interval)
        if self.resolved:
            measured = f"{_num(self._shown(self.value))} {u} [{_num(lo)}, {_num(hi)}]"
        else:
            measured = f"< {_num(self._shown(self.upper_bound))} {u}"
        line = f"{head} {measured} vs {sheet}: {self.verdict_text()}"
        return line + (f" — note: {self.note}" if self.note else "")

    def to_dict(self) -> dict:
        def block(unit: str, conv) -> dict:
            return {"unit": unit, "value": conv(self.value),
                    "interval": None if self.interval is None else [conv(v)
                                                                    for v in self.interval],
                    "upper_bound": conv(self.upper_bound)}

        si = block(self.limit.si_unit, lambda v: None if v is None else float(v))
        si["datasheet"] = float(self.limit.si)
        shown = block(self.limit.display_unit, self._shown)
        shown["datasheet"] = float(self.limit.value)
        ri = self.ratio_interval
        return {"axis": self.axis, "kind": self.kind, "term": self.term,
                "symbol": self.limit.symbol, "verdict": self.verdict,
                "resolved": self.resolved, "level": float(self.level), "ratio": self.ratio,
                "ratio_interval": None if ri is None else [float(v) for v in ri],
                "si": si, "datasheet_units": shown, "limit": self.limit.to_dict(),
                "note": self.note}

    @classmethod
    def from_dict(cls, d: dict) -> TermCheck:
        si = d["si"]
        opt = lambda v: None if v is None else float(v)  # noqa: E731
        return cls(axis=d["axis"], limit=DatasheetValue.from_dict(d["limit"]),
                   verdict=d["verdict"], level=float(d["level"]), resolved=d["resolved"],
                   value=opt(si["value"]),
                   interval=None if si["interval"] is None else tuple(si["interval"]),
                   upper_bound=opt(si["upper_bound"]), note=d.get("note", ""))


def compare_term(axis: str, fit: TermFit | None, limit: DatasheetValue, *,
                 level: float = 0.683, fit_ok: bool = True) -> TermCheck:
    """The :class:`TermCheck` of one axis's measured term ``fit``
    (:class:`calib.noise.allan.TermFit`: SI value, interval at its level, upper bound,
    resolved) against ``limit`` (module docstring's table). ``fit`` None: not measured (the
    axis's model has no such term). ``fit_ok`` False adds a note (no model describes the
    axis's Allan curve). ``level``: used when ``fit`` is None."""
    if fit is None:
        return TermCheck(axis=axis, limit=limit, verdict="not measured", level=level,
                         note=f"axis {axis} has no {limit.term} term")
    lo, hi = (float(v) for v in fit.interval)
    if fit.resolved:
        said = verdict(lo, hi, limit.si)
    else:  # reported as an upper bound only, so never "exceeds"
        said = verdict(0.0, float(fit.upper_bound), limit.si)
    note = "" if fit_ok else ("no model of the rule describes this axis's Allan curve "
                              "(fit_ok false): read it with the figure")
    return TermCheck(axis=axis, limit=limit, verdict=said, level=float(fit.level),
                     resolved=bool(fit.resolved),
                     value=None if fit.value is None else float(fit.value), interval=(lo, hi),
                     upper_bound=float(fit.upper_bound), note=note)


@dataclass(frozen=True, eq=False)
class DatasheetCheck(ResultMixin):
    """Every datasheet value against the measured terms (:func:`check_datasheet`): one
    :class:`TermCheck` per axis and term the datasheet gives, in the order of the axes and
    :data:`DATASHEET_TERMS`, then the values no axis of the log takes (``not measured``).
    ``level``: the intervals'; ``name``: the datasheet's."""

    checks: tuple[TermCheck, ...]
    level: float
    name: str | None = None

    _TITLE = "Datasheet check"
    _UNITS = "measured and datasheet values in the datasheet's units and in SI; ratios 1"

    def __post_init__(self) -> None:
        object.__setattr__(self, "checks", tuple(self.checks))

    @property
    def counts(self) -> dict[str, int]:
        """How many checks have each verdict of :data:`VERDICTS`."""
        return {v: sum(c.verdict == v for c in self.checks) for v in VERDICTS}

    def summary(self) -> str:
        name = f" ({self.name})" if self.name else ""
        head = (f"datasheet check{name}, intervals at {self.level:.1%}: {RULE}")
        tally = ", ".join(f"{v} {n}" for v, n in self.counts.items())
        return "\n".join([head] + [c.summary() for c in self.checks]
                         + [f"datasheet: {tally}"])

    def to_dict(self) -> dict:
        return {"name": self.name, "level": float(self.level), "rule": RULE,
                "counts": self.counts, "checks": [c.to_dict() for c in self.checks]}

    @classmethod
    def from_dict(cls, d: dict) -> DatasheetCheck:
        return cls(checks=tuple(TermCheck.from_dict(c) for c in d["checks"]),
                   level=float(d["level"]), name=d.get("name"))


def check_datasheet(result: NoiseCharacterization, sheet: Datasheet) -> DatasheetCheck:
    """Compare every value of ``sheet`` with the terms of ``result``
    (:class:`calib.noise.allan.NoiseCharacterization`) on every axis it applies to: an axis's
    own value, else its kind's (:meth:`Datasheet.lookup`). A value no axis of the log takes
    (a gyro's on a log without a gyro, an axis left out) is reported ``not measured``."""
    checks = []
    used: set[tuple[str, str]] = set()
    for axis in result.axes:
        for term in DATASHEET_TERMS:
            limit = sheet.lookup(axis.axis, axis.kind, term)
            if limit is None:
                continue
            used.add((limit.scope, term))
            checks.append(compare_term(axis.axis, axis.term(term), limit, level=result.level,
                                       fit_ok=axis.fit_ok))
    kinds = {a.kind for a in result.axes}
    for v in sheet.values:
        if (v.scope, v.term) in used:
            continue
        if v.scope in KINDS and v.kind in kinds:
            continue  # every axis of the kind has its own value
        why = (f"the log has no {v.kind} axis" if v.scope in KINDS
               else f"the log has no axis {v.scope}")
        checks.append(TermCheck(axis=v.scope, limit=v, verdict="not measured",
                                level=result.level, note=why))
    return DatasheetCheck(checks=tuple(checks), level=float(result.level), name=sheet.name)


__all__ = ["AXES", "DATASHEET_TERMS", "KIND_SCOPES", "RULE", "SYMBOLS", "TERM_KEYS", "UNITS",
           "VERDICTS", "Datasheet", "DatasheetCheck", "DatasheetValue", "TermCheck",
           "check_datasheet", "compare_term", "datasheet_from_dict", "datasheet_value",
           "json_units", "load_datasheet", "parse_datasheet", "read_datasheet",
           "read_datasheets", "verdict"]

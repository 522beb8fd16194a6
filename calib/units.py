"""Units of the JSON outputs: the top-level ``"units"`` object and how to read it.

Every JSON object tiltbench prints (``--json``) or writes (``cal.json``, ``truth.json``,
``gap.json``, ``trajectory.json``, ``validation.json``, …) carries a top-level ``"units"``
object mapping the *key path* of each numeric value to its unit (``docs/units.md``)::

    "units": {"g": "m/s²", "axes.*.bias": "m/s²", "axes.*.scale": "1", ...}

Key paths: keys joined by ``.``; a list adds no segment (a list of numbers has one unit for all
its elements, a list of objects gives its elements' keys after the list's key); ``*`` stands
for any one key (an axis name, an effect name, a candidate point). The first pattern that
matches a path, in the order of the object, gives its unit. Unit spellings: SI with ``²`` and
``√``; ``"1"`` dimensionless (scale factors, ratios, χ²/dof, p-values, probabilities);
``"count"`` integer counts (samples, runs, degrees of freedom); ``"—"`` a number that is not a
quantity (a seed, a format version, an index). Covariances are in the product of their
parameters' units: a list unit such as ``"[(m/s²)², m/s², m/s², 1]"`` lists the entries of a
flattened matrix row by row.

Each result type builds its ``"units"`` in one place (a ``_JSON_UNITS`` table or a
``_units()`` method next to its ``to_dict``); :func:`missing_units` is the check the tests
run on every output. Adding the key changes no existing key: readers that ignore unknown
keys read the files as before.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from typing import Any

__all__ = ["UNITS_KEY", "effect_units", "format_estimate", "format_p", "missing_units", "nest",
           "numeric_paths", "unit_of", "with_units"]

UNITS_KEY = "units"
"""The top-level key of the units object in every JSON output."""


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) or (
        hasattr(x, "dtype") and getattr(x, "shape", None) == () and x.dtype.kind in "iuf")


def numeric_paths(obj: Any, prefix: str = "") -> Iterator[str]:
    """Key path (module docstring) of every numeric leaf of a JSON-like tree, in order, once
    per leaf; the top-level ``"units"`` object itself is skipped."""
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            if not prefix and k == UNITS_KEY:
                continue
            yield from numeric_paths(v, f"{prefix}.{k}" if prefix else str(k))
    elif isinstance(obj, (list, tuple)):
        for v in obj:
            yield from numeric_paths(v, prefix)
    elif _is_number(obj):
        yield prefix


def _regex(pattern: str) -> re.Pattern:
    return re.compile("\\.".join("[^.]+" if s == "*" else re.escape(s)
                                 for s in pattern.split(".")) + "$")


def unit_of(units: Mapping[str, str], path: str) -> str | None:
    """The unit ``units`` gives the key path ``path`` (exact key first, then the first
    matching pattern), or None."""
    if path in units:
        return units[path]
    for pattern, unit in units.items():
        if "*" in pattern and _regex(pattern).match(path):
            return unit
    return None


def missing_units(obj: Mapping) -> list[str]:
    """Key paths of the numeric leaves of ``obj`` that its ``"units"`` object does not cover
    (every path once); ``[]`` when every number has a unit."""
    units = obj.get(UNITS_KEY) or {}
    out: list[str] = []
    for p in numeric_paths(obj):
        if p not in out and unit_of(units, p) is None:
            out.append(p)
    return out


def with_units(d: dict, units: Mapping[str, str]) -> dict:
    """``d`` with ``"units"`` set to the entries of ``units`` (a copy, in order), the key
    placed last so that the existing keys keep their order."""
    out = {k: v for k, v in d.items() if k != UNITS_KEY}
    out[UNITS_KEY] = dict(units)
    return out


def nest(prefix: str, units: Mapping[str, str]) -> dict[str, str]:
    """``units`` of an object embedded under ``prefix`` (``"calibration"`` →
    ``"calibration.axes.*.bias"``)."""
    return {f"{prefix}.{k}": v for k, v in units.items()}


# ------------------------------------------------------------------ printed numbers
P_FLOOR = 1e-300
"""Below this a p-value is printed as a bound (``p < 1e-300``): the float underflowed."""


def format_p(p: float | None) -> str:
    """``"p = 0.0123"`` (3 significant digits), or ``"p < 1e-300"`` when ``p`` underflowed
    (a p-value of exactly 0 is never true: only the tail probability was too small for a
    double); ``"p = —"`` when there is none (a test this design cannot make)."""
    if p is None or float(p) != float(p):  # None or nan
        return "p = —"
    p = float(p)
    if p < P_FLOOR:
        return f"p < {P_FLOOR:.0e}"
    return f"p = {p:.3g}"


def format_stat(x: float | None, spec: str = ".4g") -> str:
    """A test statistic for the text reports, ``"—"`` when there is none."""
    return "—" if x is None or float(x) != float(x) else format(float(x), spec)


def effect_units() -> dict[str, str]:
    """Parameter key → unit of every catalog effect (:data:`calib.conventions.EFFECTS`, the
    one home of effect units; a key means the same in every effect that has it)."""
    from calib.conventions import EFFECTS

    return {k: u for e in EFFECTS.values() for k, u in zip(e.keys, e.units, strict=True)}


def format_estimate(value: float, std: float, unit: str = "") -> str:
    """``"0.01952 ± 0.0012 rad"``: the std to 2 significant digits, the value to one digit
    past the std's last digit (all of it, 6 significant digits, when the std is 0 or not
    finite), then the unit."""
    import math

    value, std = float(value), float(std)
    if math.isfinite(std) and std > 0 and math.isfinite(value):
        last = math.floor(math.log10(std)) - 1  # decimal exponent of the std's 2nd digit
        decimals = max(0, -(last - 1))
        v = f"{value:.{decimals}f}" if abs(value) < 1e15 else f"{value:.6g}"
        out = f"{v} ± {std:.2g}"
    else:
        out = f"{value:.6g} ± {std:.2g}"
    return f"{out} {unit}".rstrip()

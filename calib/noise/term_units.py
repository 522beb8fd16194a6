"""Units of the noise terms per sensor kind: SI (as the JSON outputs write them) and as
datasheets print them (µg/√Hz, µg, °/√h, °/h), with the factor between the two.

=====================  ======================  ===========  =====================  ===========
term                   accelerometer, SI       datasheet    gyro, SI               datasheet
=====================  ======================  ===========  =====================  ===========
white_noise_density N  (m/s^2)/sqrt(Hz)        µg/√Hz       (rad/s)/sqrt(Hz)       °/√h (ARW)
bias_instability B     m/s^2                   µg           rad/s                  °/h
rate_random_walk K     m/s^2/sqrt(s)           µg/√s        rad/s/sqrt(s)          °/h/√h
quantization_noise Q   m/s (Δv step/√12)       mm/s         rad (Δθ step/√12)      µrad
gauss_markov σ         m/s^2                   µg           rad/s                  °/h
correlation time T_c   s                       s            s                      s
=====================  ======================  ===========  =====================  ===========

Factors: 1 g = 9.80665 m/s² (the standard gravity that datasheets' "g" means, not the local
g), so 1 µg = 9.80665e-6 m/s²; 1 rad = 180/π °; 1 h = 3600 s, so a gyro's white-noise
density N in rad/s/√Hz = rad/√s is ``N·(180/π)·√3600 = N·(180/π)·60`` °/√h (angle random walk,
IEEE Std 952: the −½ line at τ = 1 h read in °/h·√h), a bias instability in rad/s is
``B·(180/π)·3600`` °/h, a rate random walk in rad/s/√s is ``K·(180/π)·3600·60`` °/h/√h.

**Units as people type them** (:func:`parse_unit`, :func:`unit_factor`; ``noise --datasheet``,
:mod:`calib.noise.datasheet`). A unit is an expression of the names of :data:`UNIT_ATOMS`
(``g mg ug m mm s min h Hz rad mrad urad deg mdeg dps mdps dph``, any case; ``µ``/``μ`` read
as ``u``, ``°`` as ``deg``) with ``/`` and ``*`` (left to right), ``^`` or ``**`` with a
number or ``(p/q)`` (``s2`` is ``s^2``), parentheses, and square roots written ``√x``,
``sqrt(x)``, ``sqrtx``, ``rt(x)`` or ``rtx`` (``rtHz``). It evaluates to (factor to SI,
dimension), the dimension as exponents of (m, s, rad), so ``µg/√Hz``, ``ug/rtHz`` and
``ug/sqrt(Hz)`` are one unit (9.80665e-6 (m/s²)/√Hz), ``°/h/√h`` and ``deg/h^1.5`` another,
and a unit of the wrong dimension for a term (``µg`` for a noise density) is told apart from a
right one by :data:`TERM_DIMENSIONS`, never by its spelling. The atoms are built from the
factors above (``_MICRO_G``, ``_DEG``, the hour), so a datasheet unit of :data:`DATASHEET`
parses back to ``1/factor`` (to rounding) (``tests/test_noise_datasheet.py``).
"""

from __future__ import annotations

import math
import re
from fractions import Fraction

from calib.conventions import STANDARD_GRAVITY

KINDS: tuple[str, ...] = ("accelerometer", "gyro")
"""Sensor kinds an axis belongs to."""

SI_UNITS: dict[str, dict[str, str]] = {
    "accelerometer": {"white_noise_density": "(m/s^2)/sqrt(Hz)", "bias_instability": "m/s^2",
                      "rate_random_walk": "m/s^2/sqrt(s)", "quantization_noise": "m/s",
                      "gauss_markov": "m/s^2", "correlation_time": "s",
                      "reading": "m/s^2"},
    "gyro": {"white_noise_density": "(rad/s)/sqrt(Hz)", "bias_instability": "rad/s",
             "rate_random_walk": "rad/s/sqrt(s)", "quantization_noise": "rad",
             "gauss_markov": "rad/s", "correlation_time": "s", "reading": "rad/s"},
}
"""SI unit of each term's value, interval and upper bound (and of the readings), per kind."""

_MICRO_G = STANDARD_GRAVITY * 1e-6
_DEG = 180.0 / math.pi
DATASHEET: dict[str, dict[str, tuple[str, float]]] = {
    "accelerometer": {"white_noise_density": ("µg/√Hz", 1.0 / _MICRO_G),
                      "bias_instability": ("µg", 1.0 / _MICRO_G),
                      "rate_random_walk": ("µg/√s", 1.0 / _MICRO_G),
                      "quantization_noise": ("mm/s", 1e3),
                      "gauss_markov": ("µg", 1.0 / _MICRO_G),
                      "correlation_time": ("s", 1.0)},
    "gyro": {"white_noise_density": ("°/√h", _DEG * 60.0),
             "bias_instability": ("°/h", _DEG * 3600.0),
             "rate_random_walk": ("°/h/√h", _DEG * 3600.0 * 60.0),
             "quantization_noise": ("µrad", 1e6),
             "gauss_markov": ("°/h", _DEG * 3600.0),
             "correlation_time": ("s", 1.0)},
}
"""Per kind and term: (the datasheet unit, the factor from SI): datasheet = SI × factor."""


def kind_of(axis: str) -> str:
    """The sensor kind of an axis name: ``gyro_*`` is a gyro, anything else an
    accelerometer."""
    return "gyro" if axis.startswith("gyro") else "accelerometer"


def si_unit(name: str, kind: str) -> str:
    """SI unit of term ``name`` for ``kind`` (module table)."""
    return SI_UNITS[kind][name]


def datasheet(name: str, kind: str, value: float | None) -> tuple[float | None, str]:
    """``value`` (SI) in the datasheet unit of term ``name`` for ``kind``: (value, unit)."""
    unit, factor = DATASHEET[kind][name]
    return (None if value is None else float(value) * factor), unit


# --- units as people type them ----------------------------------------------------------

Dimension = tuple[Fraction, Fraction, Fraction]
"""Exponents of (m, s, rad) of a unit: m/s² is (1, -2, 0), °/√h is (0, -½, 1)."""


def _dim(length: float = 0, time: float = 0, angle: float = 0) -> Dimension:
    return (Fraction(length), Fraction(time), Fraction(angle))


_ACC = _dim(1, -2)
_HOUR = 3600.0
UNIT_ATOMS: dict[str, tuple[float, Dimension]] = {
    "g": (STANDARD_GRAVITY, _ACC), "mg": (1e3 * _MICRO_G, _ACC), "ug": (_MICRO_G, _ACC),
    "m": (1.0, _dim(1)), "mm": (1e-3, _dim(1)),
    "s": (1.0, _dim(0, 1)), "sec": (1.0, _dim(0, 1)), "min": (60.0, _dim(0, 1)),
    "h": (_HOUR, _dim(0, 1)), "hr": (_HOUR, _dim(0, 1)), "hour": (_HOUR, _dim(0, 1)),
    "hz": (1.0, _dim(0, -1)),
    "rad": (1.0, _dim(0, 0, 1)), "mrad": (1e-3, _dim(0, 0, 1)), "urad": (1e-6, _dim(0, 0, 1)),
    "deg": (1.0 / _DEG, _dim(0, 0, 1)), "mdeg": (1e-3 / _DEG, _dim(0, 0, 1)),
    "dps": (1.0 / _DEG, _dim(0, -1, 1)), "mdps": (1e-3 / _DEG, _dim(0, -1, 1)),
    "dph": (1.0 / _DEG / _HOUR, _dim(0, -1, 1)),
}
"""Unit names (lower case) → (factor to SI, dimension): g is the standard gravity 9.80665
m/s² (a datasheet's g, not the local one), deg = π/180 rad, h = 3600 s; dps = °/s, dph = °/h."""

TERM_DIMENSIONS: dict[str, dict[str, Dimension]] = {
    "accelerometer": {"white_noise_density": _dim(1, -1.5), "bias_instability": _ACC,
                      "rate_random_walk": _dim(1, -2.5), "quantization_noise": _dim(1, -1),
                      "gauss_markov": _ACC, "correlation_time": _dim(0, 1)},
    "gyro": {"white_noise_density": _dim(0, -0.5, 1), "bias_instability": _dim(0, -1, 1),
             "rate_random_walk": _dim(0, -1.5, 1), "quantization_noise": _dim(0, 0, 1),
             "gauss_markov": _dim(0, -1, 1), "correlation_time": _dim(0, 1)},
}
"""Dimension of each term's value per kind (the units of :data:`SI_UNITS`)."""

ACCEPTED_UNITS: dict[str, dict[str, str]] = {
    "accelerometer": {
        "white_noise_density": "µg/√Hz, ug/rtHz, ug/sqrt(Hz), mg/√Hz, (m/s^2)/sqrt(Hz), m/s/√h",
        "bias_instability": "µg, ug, mg, g, m/s^2",
        "rate_random_walk": "µg/√s, ug/rt(s), mg/√s, (m/s^2)/sqrt(s), m/s/h/√h"},
    "gyro": {
        "white_noise_density": "°/√h, deg/rt(h), deg/sqrt(h), °/s/√Hz, dps/rtHz, mdps/√Hz, "
                               "(rad/s)/sqrt(Hz)",
        "bias_instability": "°/h, deg/h, deg/hr, dph, °/s, dps, rad/s",
        "rate_random_walk": "°/h/√h, deg/h^1.5, deg/h/rt(h), °/s/√s, (rad/s)/sqrt(s)"},
}
"""Spellings of each datasheet term's unit that a refusal offers (examples: any unit of the
right dimension is accepted, :func:`unit_factor`)."""

_SPELLINGS = (("µ", "u"), ("μ", "u"), ("°", "deg"), ("º", "deg"), ("√", "sqrt"),
              ("²", "^2"), ("³", "^3"), ("**", "^"), ("·", "*"), ("⋅", "*"), ("×", "*"))
_TOKEN = re.compile(r"[a-z]+|\d+(?:\.\d+)?|[/*^()\-]")
_ROOTS = ("sqrt", "rt")
_KNOWN = ("g, mg, µg, m, mm, s, min, h, Hz, rad, mrad, µrad, deg or °, mdeg, dps, mdps, dph; "
          "/ * ^ ( ) and √, sqrt( ), rt( )")


class _UnitParser:
    """Recursive descent over the tokens of a unit (module docstring): ``expr := factor
    (('/' | '*') factor)*``, ``factor := primary ('^' exponent)?``, ``primary := '(' expr ')'
    | root primary | name [integer]``."""

    def __init__(self, text: str) -> None:
        self.text = text
        norm = text
        for a, b in _SPELLINGS:
            norm = norm.replace(a, b)
        norm = "".join(norm.split()).lower()
        self.tokens: list[str] = []
        at = 0
        while at < len(norm):
            m = _TOKEN.match(norm, at)
            if m is None:
                self.fail(f"unexpected character {norm[at]!r}")
            self.tokens.append(m.group())
            at = m.end()
        self.pos = 0

    def fail(self, why: str):
        raise ValueError(f"unit {self.text!r}: {why} (units are written with {_KNOWN})")

    def peek(self) -> str | None:
        return self.tokens[self.pos] if self.pos < len(self.tokens) else None

    def take(self) -> str:
        tok = self.peek()
        if tok is None:
            self.fail("it ends too early")
        self.pos += 1
        return tok

    def parse(self) -> tuple[float, Dimension]:
        if not self.tokens:
            self.fail("no unit")
        value = self.expr()
        if self.peek() is not None:
            self.fail(f"unexpected {self.peek()!r}")
        return value

    def expr(self) -> tuple[float, Dimension]:
        f, d = self.factor()
        while self.peek() in ("/", "*"):
            sign = -1 if self.take() == "/" else 1
            f2, d2 = self.factor()
            f = f / f2 if sign < 0 else f * f2
            d = tuple(a + sign * b for a, b in zip(d, d2, strict=True))
        return f, d

    def factor(self) -> tuple[float, Dimension]:
        value = self.primary()
        if self.peek() == "^":
            self.take()
            value = _power(value, self.exponent())
        return value

    def exponent(self) -> Fraction:
        if self.peek() == "(":
            self.take()
            e = self.number()
            if self.peek() == "/":
                self.take()
                e /= self.number()
            if self.take() != ")":
                self.fail("an exponent in parentheses is (p) or (p/q)")
            return e
        return self.number()

    def number(self) -> Fraction:
        sign = 1
        if self.peek() == "-":
            self.take()
            sign = -1
        tok = self.take()
        if not tok[0].isdigit():
            self.fail(f"expected a number, got {tok!r}")
        value = sign * Fraction(tok)
        if value == 0:
            self.fail("a zero exponent or divisor")
        return value

    def primary(self) -> tuple[float, Dimension]:
        tok = self.take()
        if tok == "(":
            value = self.expr()
            if self.take() != ")":
                self.fail("a '(' without its ')'")
            return value
        if tok in _ROOTS:
            return _power(self.primary(), Fraction(1, 2))
        if not tok.isalpha():
            self.fail(f"unexpected {tok!r}")
        if tok in UNIT_ATOMS:
            value = UNIT_ATOMS[tok]
        else:
            root = next((r for r in _ROOTS if tok.startswith(r) and tok[len(r):] in UNIT_ATOMS),
                        None)
            if root is None:
                self.fail(f"unknown unit name {tok!r}")
            value = _power(UNIT_ATOMS[tok[len(root):]], Fraction(1, 2))
        nxt = self.peek()
        if nxt is not None and nxt.isdigit():  # s2: s^2
            value = _power(value, Fraction(self.take()))
        return value


def _power(value: tuple[float, Dimension], e: Fraction) -> tuple[float, Dimension]:
    f, d = value
    return f ** float(e), tuple(a * e for a in d)


def parse_unit(text: str) -> tuple[float, Dimension]:
    """(factor to SI, dimension) of a unit as people type it (module docstring): the SI value
    is ``value · factor``. ``ValueError`` naming the unit for one that cannot be read.

    >>> factor, dim = parse_unit("ug/rtHz")
    >>> round(factor / 9.80665e-6, 12), format_dimension(dim)
    (1.0, 'm·s^-3/2')
    """
    return _UnitParser(str(text)).parse()


def format_dimension(d: Dimension) -> str:
    """A dimension as SI base units, m and rad before s: ``(1, -3/2, 0)`` → ``m·s^-3/2``,
    ``(0, -1, 1)`` → ``rad·s^-1``."""
    parts = [u if e == 1 else f"{u}^{e}" for u, e in (("m", d[0]), ("rad", d[2]), ("s", d[1]))
             if e != 0]
    return "·".join(parts) or "1"


def unit_factor(text: str, kind: str, name: str) -> float:
    """Factor to SI of the unit ``text`` for term ``name`` of a ``kind`` sensor: the term's SI
    value is ``value · factor``. ``ValueError`` for a unit that cannot be read or is of
    another dimension than the term's (:data:`TERM_DIMENSIONS`), naming the accepted units
    (:data:`ACCEPTED_UNITS`).

    >>> round(unit_factor("deg/rt(h)", "gyro", "white_noise_density") * 60 * 180 / math.pi, 12)
    1.0
    """
    factor, dim = parse_unit(text)
    want = TERM_DIMENSIONS[kind][name]
    if dim != want:
        accepted = ACCEPTED_UNITS.get(kind, {}).get(name, DATASHEET[kind][name][0])
        raise ValueError(f"unit {text!r} is {format_dimension(dim)}, but the {kind}'s "
                         f"{name.replace('_', ' ')} is {format_dimension(want)}; accepted "
                         f"units: {accepted}")
    return factor


__all__ = ["ACCEPTED_UNITS", "DATASHEET", "KINDS", "SI_UNITS", "TERM_DIMENSIONS", "UNIT_ATOMS",
           "Dimension", "datasheet", "format_dimension", "kind_of", "parse_unit", "si_unit",
           "unit_factor"]

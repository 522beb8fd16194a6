"""The course ``datos.txt`` parser: text as people and editors write it, read strictly.

The course file (UTF-8, no final newline)::

    Posición inicial = [0 0]
    Velocidad inicial = [1 3]
    varianza del ruido de los acelerómetros = [0.25 0.64]

Accepted, because editors and keyboards produce it and the meaning is not in doubt:

* encodings: UTF-8 (with or without a BOM), UTF-16 with a BOM, Windows-1252 / Latin-1 (tried
  in that order: a Latin-1 ``ó`` is not valid UTF-8, so nothing is misread);
* line ends LF, CRLF or CR; blank lines; comment lines starting with ``%`` or ``#``;
* the field by keyword, any case and accents: ``posici``/``position``, ``velocidad``/
  ``velocity``, ``varianza``/``variance``;
* minus written as the Unicode minus U+2212, a hyphen U+2010/U+2011, the figure dash U+2012,
  the en dash U+2013, the em dash U+2014 or the horizontal bar U+2015 (word processors turn
  ``-`` into these; dropping them would silently flip a sign);
* numbers separated by spaces (any Unicode space), commas or semicolons (``[1 3]``,
  ``[1, 3]``, ``[1,3]``, ``[1; 3]``);
* decimal commas where that is the only reading giving two numbers: ``[0,25 0,64]``,
  ``[0,25; 0,64]``, ``[0,25, 0,64]``.

Refused, with the file, the line number and the field: a field twice (``Posición`` on lines
1 and 4), a field missing, anything but exactly two numbers in ``[ ]``, text that is not a
number (``abc``), an ambiguous comma (``[1,5,2,5]``: 1.5 and 2.5, or four numbers?), decimal
comma and decimal point mixed in one pair, NaN/Inf, variances that are not positive, values
too large to be positions (m), velocities (m/s) or variances ((m/s²)²). Bracketed lines of
no known field are ignored and named in a :class:`calib.files.course.DataNote`.
"""

from __future__ import annotations

import math
import re
import unicodedata
import warnings

from calib.input_rules import MAX_ABS_POSITION, MAX_ABS_VELOCITY, DataError, DataNote

FIELDS: dict[str, tuple[tuple[str, ...], str, str]] = {
    "p0": (("posici", "position"), "Posición inicial = [x y]", "initial position, m"),
    "v0": (("velocidad", "velocity"), "Velocidad inicial = [vx vy]", "initial velocity, m/s"),
    "noise_var": (("varianza", "variance"), "varianza del ruido de los acelerómetros = "
                  "[σx² σy²]", "noise variances, (m/s²)²"),
}
"""Field → (keywords, the course wording, meaning and unit)."""

NOISE_VAR_RANGE = (1e-30, 1e30)
"""Accepted noise variances, (m/s²)²: beyond them σ⁻² or products with it leave float range."""

MINUS_SIGNS = "\u2212\u2010\u2011\u2012\u2013\u2014\u2015\ufe58\ufe63\uff0d"
"""Characters read as '-': minus, hyphens, figure/en/em dash, bar, small/full-width minus."""

_MINUS = str.maketrans({c: "-" for c in MINUS_SIGNS} | {"\uff0b": "+"})
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_COMMA_DECIMAL = re.compile(r"[+-]?\d+,\d+(?:[eE][+-]?\d+)?", re.ASCII)


def decode(data: bytes, where: str) -> str:
    """Bytes of a text file → str (module docstring: BOM, UTF-8, UTF-16, cp1252, Latin-1)."""
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    elif data.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return data.decode("utf-16")
        except UnicodeDecodeError as exc:
            raise DataError(f"{where}: starts with a UTF-16 mark but is not UTF-16 text "
                            f"({exc.reason} at byte {exc.start})") from None
    if b"\x00" in data:
        raise DataError(f"{where}: a binary file, not text; expected the course datos.txt")
    for encoding in ("utf-8", "cp1252"):
        try:
            return data.decode(encoding)
        except UnicodeDecodeError:
            continue
    return data.decode("latin-1")  # every byte is a character: never fails


def _fold(text: str) -> str:
    """Lower case without accents (``Posición`` → ``posicion``) for keyword matching."""
    return "".join(c for c in unicodedata.normalize("NFKD", text.lower())
                   if not unicodedata.combining(c))


def _field_of(label: str) -> list[str]:
    folded = _fold(label)
    return [key for key, (words, _, _) in FIELDS.items() if any(w in folded for w in words)]


def _tokens(content: str, here: str) -> list[str]:
    """The number tokens of ``[ … ]`` with dots as decimal points (module docstring)."""
    text = content.translate(_MINUS).replace(";", " ")
    tokens = [t.strip(",") for t in text.split()]
    tokens = [t for t in tokens if t]
    if len(tokens) == 1 and "," in tokens[0]:  # [1,3] / [0.25,0.64]: the comma separates
        parts = tokens[0].split(",")
        if len(parts) != 2 or not all(parts):
            raise DataError(
                f"{here}: {content.strip()!r} is ambiguous (a decimal comma or a separator?); "
                "write the two numbers with '.' decimals separated by a space, e.g. [1.5 2.5]")
        return parts
    out = []
    comma = dot = False
    for tok in tokens:
        if "," in tok:
            if not _COMMA_DECIMAL.fullmatch(tok):
                raise DataError(f"{here}: {tok!r} is not a number (a comma is read as the "
                                "decimal separator only in forms like 0,25)")
            comma = True
            tok = tok.replace(",", ".")
        elif "." in tok:
            dot = True
        out.append(tok)
    if comma and dot:
        raise DataError(f"{here}: {content.strip()!r} mixes decimal commas and decimal points; "
                        "use one of them")
    return out


def _pair(content: str, here: str) -> tuple[float, float]:
    tokens = _tokens(content, here)
    values = []
    for tok in tokens:
        if not _NUMBER.fullmatch(tok):
            raise DataError(f"{here}: {tok!r} is not a number")
        v = float(tok)
        if not math.isfinite(v):
            raise DataError(f"{here}: {tok!r} is too large to be a finite number")
        values.append(v)
    if len(values) != 2:
        raise DataError(f"{here}: expected two numbers in [ ], found {len(values)} "
                        f"({content.strip()!r})")
    return values[0], values[1]


def _check_range(key: str, values: tuple[float, float], here: str) -> None:
    if key == "noise_var":
        lo, hi = NOISE_VAR_RANGE
        if not all(lo <= v <= hi for v in values):
            raise DataError(f"{here}: noise variances must be positive, between {lo:g} and "
                            f"{hi:g} (m/s²)², got {list(values)}")
        return
    limit, unit = (MAX_ABS_POSITION, "m") if key == "p0" else (MAX_ABS_VELOCITY, "m/s")
    if any(abs(v) > limit for v in values):
        raise DataError(f"{here}: {list(values)} is beyond ±{limit:g} {unit}; check the units")


def parse_datos(data: bytes, where: str) -> dict[str, tuple[float, float]]:
    """Parse the bytes of a ``datos.txt``; return ``{"p0", "v0", "noise_var"}`` → pair.

    Raises :class:`calib.files.course.DataError` naming ``where``, the line and the field (module
    docstring for what is accepted and refused).
    """
    lines = decode(data, where).splitlines()
    found: dict[str, tuple[tuple[float, float], int]] = {}
    for number, raw in enumerate(lines, start=1):
        line = raw.strip().lstrip("\ufeff")
        if not line or line[0] in "%#":
            continue
        label = re.split(r"[=\[]", line, maxsplit=1)[0].strip()
        keys = _field_of(label)
        here = f"{where}: line {number} ({label or line[:30]!r})"
        if len(keys) > 1:
            raise DataError(f"{here}: names more than one field ({', '.join(keys)}); put each "
                            "on its own line")
        if not keys:
            if "[" in line:
                warnings.warn(DataNote(f"{where}: line {number} ignored ({line[:40]!r}): not "
                                       "one of position, velocity, noise variances"),
                              stacklevel=3)
            continue
        key = keys[0]
        if line.count("[") != 1 or line.count("]") != 1 or line.index("[") > line.index("]"):
            raise DataError(f"{here}: expected the two numbers in one pair of [ ], as in "
                            f"'{FIELDS[key][1]}'")
        if key in found:
            raise DataError(f"{here}: {FIELDS[key][2].split(',')[0]} given twice (first on "
                            f"line {found[key][1]}); keep one")
        content = line[line.index("[") + 1:line.index("]")]
        values = _pair(content, here)
        _check_range(key, values, here)
        found[key] = (values, number)
    missing = [k for k in FIELDS if k not in found]
    if missing:
        wanted = "; ".join(f"'{FIELDS[k][1]}' ({FIELDS[k][2]})" for k in missing)
        raise DataError(f"{where}: missing {wanted} in its {len(lines)} line(s)")
    return {k: v for k, (v, _) in found.items()}

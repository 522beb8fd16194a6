"""CSV/TSV logs with a header: generic tables, phyphox exports, Sensor Logger exports.

Layout read
-----------
* Optional gzip (``.csv.gz``; recognized from the gzip magic bytes, not the name).
* Text in UTF-8 (with or without BOM), else Latin-1. Blank lines and lines starting with ``#``
  are skipped (line numbers in messages are the file's own, 1-based).
* The first other line is the header; it must name the columns (a first line of numbers is
  refused: the reader cannot know which column is which). A YEI 3-Space export's first line,
  ``# Data format: "%int(ChipTimeUS),%float(RawAccelX),…"``, is read as its header
  (``chip_time_us``, ``raw_accel_x`` …; its accelerations need ``--units``).
* Delimiter sniffed from the header: tab, ``;`` or ``,`` (the most frequent), else runs of
  spaces. Quoted cells are allowed (phyphox quotes its header).
* Decimal comma: with a ``;``, tab or space delimiter, numbers such as ``1,23`` are read as
  1.23 (phyphox's and spreadsheets' "semicolon, decimal comma" export). A ``,``-delimited file
  has decimal points.

Columns by role (``--columns t=…,x=…,y=…,z=…,theta=…,label=…,gyro=…`` overrides any)
----------------------------------------------------------------------------------
Recognized names (case and spaces ignored; unit in brackets or as a suffix, see
:func:`calib.logs.table.split_unit`):

====================  ===============================================================
role                  names
====================  ===============================================================
time ``t``            ``t``, ``time``, ``timestamp``, ``seconds_elapsed`` (Sensor Logger)
acceleration x/y/z    ``acc_x``, ``accx``, ``ax``, ``a_x``, ``accel_x``, ``acceleration x``
                      (phyphox), ``accelerometer_x``; Sensor Logger's bare ``x y z``
gyro x/y/z            ``gyro_x``, ``gx``, ``gyr_x``, ``gyroscope x`` (phyphox), ``wx``,
                      ``omega_x``
θ                     ``theta``, ``tita``, ``angle``, ``tilt``
pose label            ``label``, ``pose``
====================  ===============================================================

phyphox's gravity-removed export ("Linear Acceleration x (m/s^2)") is refused: gravity was
removed, so the tilt signal — the projection of g on each axis — is gone. Sensor Logger
(https://github.com/tszheichoi/awesome-sensor-logger, UNITS.md): ``time`` is ns since the
epoch, ``seconds_elapsed`` s since the start (used when present), accelerations in m/s².
Its ``TotalAcceleration.csv`` includes gravity and is read; its ``Accelerometer.csv`` holds
acceleration *without* gravity (user motion only) and is refused for the same reason as
phyphox's linear export; ``AccelerometerUncalibrated.csv`` includes gravity but is in g on iOS
and m/s² on Android, so it needs ``--units``.

A time column without a stated unit is in seconds (``t_ms``, ``time (ns)`` … state others).
"""

from __future__ import annotations

import csv
import gzip
import io
import re
from pathlib import Path

import numpy as np

from calib.input_rules import DataError
from calib.logs.table import (
    RawLog,
    accel_unit,
    angle_unit,
    gyro_unit,
    split_unit,
    time_factor,
)

_PREFIX = r"(?:raw_?|corrected_?|calibrated_?|cal_|imu_)?"
_ACC = re.compile(rf"^{_PREFIX}(?:acc|accel|accelerometer|acceleration|a)_?([xyz])$")
_GYRO = re.compile(rf"^{_PREFIX}(?:gyr|gyro|gyroscope|angular_velocity|omega|w|g)_?([xyz])$")
_LINEAR = re.compile(r"^(?:linear|user)_?acc(?:el(?:eration)?)?_?[xyz]$")
_TIME = ("t", "time", "timestamp", "seconds_elapsed", "chip_time", "elapsed_time",
         "time_stamp")
_YEI = re.compile(r"%\w+\((\w+)\)")
_THETA = ("theta", "tita", "angle", "tilt")
_LABEL = ("label", "pose")
ROLES = ("t", "x", "y", "z", "theta", "label", "gyro")
"""Roles ``--columns`` may name (``gyro``: one rate column about the tilt axis)."""


def load_text(path: Path) -> str:
    """The file's text: gunzipped when it starts with the gzip magic, UTF-8 (BOM stripped) or
    else Latin-1."""
    data = path.read_bytes()
    if data[:2] == b"\x1f\x8b":
        try:
            data = gzip.decompress(data)
        except (OSError, EOFError) as exc:
            raise DataError(f"{path}: a damaged gzip file ({exc})") from exc
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def looks_like_table(path: Path) -> bool:
    """True when the file's first lines read as a header plus a numeric row under one
    delimiter — how ``--format auto`` tells a log in a ``.txt`` from other text files."""
    try:
        lines = [(i, ln) for i, ln in _content_lines(load_text(path))][:2]
    except (OSError, DataError):
        return False
    if len(lines) < 2:
        return False
    delim = _sniff(lines[0][1])
    head, row = _split(lines[0][1], delim), _split(lines[1][1], delim)
    if len(head) < 2 or len(row) != len(head):
        return False
    decimal_comma = delim != ","
    return (not all(_is_number(c, decimal_comma) for c in head)
            and all(_is_number(c, decimal_comma) for c in row if c.strip()))


def _content_lines(text: str):
    for i, line in enumerate(text.splitlines(), start=1):
        if line.strip() and not line.lstrip().startswith("#"):
            yield i, line


def _sniff(header: str) -> str | None:
    counts = {d: header.count(d) for d in ("\t", ";", ",")}
    best = max(counts, key=counts.get)
    return best if counts[best] else None  # None: runs of spaces


def _split(line: str, delim: str | None) -> list[str]:
    if delim is None:
        return line.split()
    return next(csv.reader([line], delimiter=delim))


def _is_number(cell: str, decimal_comma: bool) -> bool:
    try:
        _number(cell, decimal_comma)
    except ValueError:
        return False
    return True


def _number(cell: str, decimal_comma: bool) -> float:
    text = cell.strip()
    if decimal_comma:
        text = text.replace(",", ".")
    return float(text)


def _recognize(names: list[str]) -> tuple[dict[str, int], dict[str, str | None], str]:
    """Roles found in a header: role → column index, role → unit text, and the format's name
    (``phyphox`` when its header style is seen, ``sensorlogger`` for its bare x/y/z with
    ``seconds_elapsed``, else ``csv``)."""
    found: dict[str, list[int]] = {}
    units: dict[str, str | None] = {}
    bases = [split_unit(n) for n in names]
    plain = [b for b, _ in bases]
    fmt = "csv"
    if "seconds_elapsed" in plain and {"x", "y", "z"} <= set(plain):
        fmt = "sensorlogger"
    elif (names[0].strip().strip('"') == "Time (s)"
          and any(n.strip().strip('"').startswith(("Acceleration x (", "Gyroscope x ("))
                  for n in names)):
        fmt = "phyphox"  # its header style: "Time (s)" first, lower-case axis letters
    for i, (base, unit) in enumerate(bases):
        role = None
        m_acc, m_gyro = _ACC.match(base), _GYRO.match(base)
        if fmt == "sensorlogger" and base in ("x", "y", "z"):
            role = f"acc.{base}"
        elif m_acc:
            role = f"acc.{m_acc.group(1)}"
        elif m_gyro:
            role = f"gyro.{m_gyro.group(1)}"
        elif base in _TIME:
            role = "t"
        elif base in _THETA:
            role = "theta"
        elif base in _LABEL:
            role = "label"
        if role is not None:
            found.setdefault(role, []).append(i)
            units[role] = unit
    if fmt == "sensorlogger" and "t" in found:  # prefer seconds since the start to epoch ns
        idx = [i for i in found["t"] if plain[i] == "seconds_elapsed"]
        found["t"] = idx or found["t"]
        units["t"] = "s" if idx else "ns"
    return found, units, fmt


def read_csv(path: Path, columns: dict[str, str] | None = None,
             fmt: str = "auto") -> RawLog:
    """Read a CSV/TSV log (module docstring) into a :class:`RawLog` (units as stated).

    Parameters
    ----------
    path : the file.
    columns : role → column name (``--columns``), overriding recognition for that role.
    fmt : ``auto``/``csv``/``phyphox``/``sensorlogger`` (the last two only check that the
        header is that app's).

    Raises
    ------
    DataError : no header, a delimiter-less header, an unknown column in ``--columns``,
        a role matched by two columns, a row of the wrong length, a non-numeric cell (named
        by line and column), a gravity-removed export.
    """
    columns = dict(columns or {})
    bad = sorted(set(columns) - set(ROLES) - {"topic"})
    if bad:
        raise DataError(f"--columns: unknown role(s) {', '.join(bad)}; roles are "
                        f"{', '.join(ROLES)}")
    text = load_text(path)
    lines = list(_content_lines(text))
    if not lines:
        raise DataError(f"{path}: empty (no header, no samples)")
    yei = _yei_header(text)
    if yei is not None:  # YEI 3-Space: the header is a '#' line holding a format string
        lines.insert(0, yei)
    head_line, head_text = lines[0]
    delim = _sniff(head_text)
    names = [c.strip() for c in _split(head_text, delim)]
    decimal_comma = delim != ","
    if all(_is_number(c, decimal_comma) for c in names if c):
        raise DataError(f"{path}: line {head_line} holds numbers, not column names: the file "
                        "has no header; add a first line naming the columns (e.g. t,ax,ay,az) "
                        "and give their units in it (e.g. 'ax (m/s^2)') or with --units")
    if len(names) < 2:
        raise DataError(f"{path}: line {head_line}: one column only; expected a header with "
                        "at least two columns separated by ',', ';', tab or spaces")
    lowered = [n.strip('"').lower() for n in names]
    if any(_LINEAR.match(split_unit(n)[0]) for n in names):
        col = next(n for n in names if _LINEAR.match(split_unit(n)[0]))
        raise DataError(f"{path}: column '{col}' is linear acceleration (a phyphox 'Linear "
                        "Acceleration' or similar export): gravity was removed, so the tilt "
                        "signal is gone; record with gravity included (phyphox: "
                        "'Acceleration with g')")
    found, units, detected = _recognize(names)
    if fmt in ("phyphox", "sensorlogger") and detected != fmt:
        raise DataError(f"{path}: --format {fmt} but the header is not a {fmt} export "
                        f"(columns: {', '.join(names)}); use --format csv with --columns")
    stem = path.name.lower()
    if detected == "sensorlogger":
        if stem.startswith(("accelerometer.", "accelerometer_")) or stem == "accelerometer":
            raise DataError(f"{path}: Sensor Logger's Accelerometer.csv holds acceleration "
                            "without gravity (user motion only): the tilt signal is gone; "
                            "read TotalAcceleration.csv (Android) or "
                            "AccelerometerUncalibrated.csv with --units")
        if stem.startswith(("gravity", "gyroscope", "magnetometer", "orientation")):
            raise DataError(f"{path}: a Sensor Logger {path.stem} file, not accelerometer "
                            "readings; read TotalAcceleration.csv")
        documented = stem.startswith("totalacceleration")
        for axis in "xyz":
            units[f"acc.{axis}"] = "m/s^2" if documented else None
    # --columns: role → column index, overriding what was recognized
    for role, name in columns.items():
        if role == "topic":
            continue
        key = f"acc.{role}" if role in ("x", "y", "z") else role
        matches = [i for i, n in enumerate(names) if n.strip('"') == name or
                   lowered[i] == name.lower()]
        if not matches:
            raise DataError(f"{path}: --columns {role}={name}: no such column (columns: "
                            f"{', '.join(names)})")
        found[key] = matches[:1]
        units[key] = split_unit(names[matches[0]])[1]
    for role, idx in found.items():
        if len(idx) > 1:
            raise DataError(f"{path}: columns {', '.join(repr(names[i]) for i in idx)} all "
                            f"look like {role}; name the one to use with --columns")
    index = {role: idx[0] for role, idx in found.items()}
    if not any(r.startswith("acc.") for r in index):
        raise DataError(f"{path}: no acceleration column recognized (columns: "
                        f"{', '.join(names)}); name them with --columns x=…,y=…[,z=…]")
    # the data rows: parse only the columns that have a role
    reader = csv.reader((ln for _, ln in lines[1:]), delimiter=delim) if delim else (
        ln.split() for _, ln in lines[1:])
    rows = np.array([i for i, _ in lines[1:]], dtype=int)
    if rows.size == 0:
        raise DataError(f"{path}: a header but no samples")
    want = {role: i for role, i in index.items() if role != "label"}
    values = _fast(lines, delim, decimal_comma, want)
    labels = [] if "label" in index else None
    if values is not None and labels is None:
        reader = iter(())  # every number read by the fast path: nothing left to do
    else:
        values = {role: np.empty(rows.size) for role in want}
    for k, cells in enumerate(reader):
        if len(cells) != len(names):
            raise DataError(f"{path}: line {rows[k]} has {len(cells)} cells but the header "
                            f"has {len(names)}; repair or remove that line")
        for role, i in want.items():
            try:
                values[role][k] = _number(cells[i], decimal_comma)
            except ValueError:
                raise DataError(f"{path}: line {rows[k]}, column '{names[i]}': "
                                f"{cells[i].strip()!r} is not a number; repair or remove "
                                "that line") from None
        if labels is not None:
            labels.append(cells[index["label"]].strip())
    acc = {r[4:]: v for r, v in values.items() if r.startswith("acc.")}
    gyro = {r[5:]: v for r, v in values.items() if r.startswith("gyro.")}
    if "gyro" in values:
        gyro = {"tilt": values["gyro"]}
    acc_units = {accel_unit(units.get(f"acc.{a}")) for a in acc}
    stated = {units.get(f"acc.{a}") for a in acc}
    for a in acc:
        text_unit = units.get(f"acc.{a}")
        if text_unit is not None and accel_unit(text_unit) is None:
            raise DataError(f"{path}: column '{names[index[f'acc.{a}']]}': unit "
                            f"'{text_unit}' is not an acceleration unit read here (m/s^2, g, "
                            "mg, counts); fix the header or give --units")
    if len(acc_units) > 1:
        raise DataError(f"{path}: the acceleration columns state different units "
                        f"({', '.join(sorted(str(u) for u in stated))}); convert them to one")
    t = None
    if "t" in values:
        factor = time_factor(units.get("t") or "s")
        if factor is None:
            raise DataError(f"{path}: column '{names[index['t']]}': time unit "
                            f"'{units.get('t')}' not read here (s, ms, us, ns)")
        t = values["t"] * factor
    g_roles = [r for r in index if r.startswith("gyro") or r == "gyro"]
    g_units = {gyro_unit(units.get(r)) for r in g_roles if units.get(r) is not None}
    if len(g_units) > 1 or None in g_units:
        raise DataError(f"{path}: gyro column unit(s) "
                        f"{', '.join(str(units.get(r)) for r in g_roles)} not read here "
                        "(rad/s, deg/s); fix the header or give --gyro-unit")
    mapping = {("x" if r == "acc.x" else "y" if r == "acc.y" else "z" if r == "acc.z"
                else r.replace("gyro.", "gyro_")): names[i] for r, i in index.items()}
    return RawLog(
        fmt=detected, acc=acc, acc_unit=acc_units.pop(), t=t,
        theta=values.get("theta"),
        theta_unit=angle_unit(units.get("theta")),
        label=None if labels is None else np.array(labels, dtype=object),
        gyro=gyro, gyro_unit=g_units.pop() if g_units else None,
        rows=rows, row_word="line", mapping=mapping,
        notes={"delimiter": {"\t": "tab", None: "spaces"}.get(delim, delim),
               "decimal": "," if decimal_comma and _has_decimal_comma(lines) else ".",
               "gzip": path.read_bytes()[:2] == b"\x1f\x8b",
               "time_unit": units.get("t") or ("s (not stated: taken as seconds)"
                                               if "t" in index else None)})


def _yei_header(text: str) -> tuple[int, str] | None:
    """A YEI 3-Space export's header: its first line is ``# Data format:
    "%int(ChipTimeUS),%float(RawAccelX),…"``; the names, CamelCase split into snake_case
    (``chip_time_us``: time in µs; ``raw_accel_x``), as a header line."""
    first = text.split("\n", 1)[0]
    if "data format" not in first.lower():
        return None
    names = _YEI.findall(first)
    if len(names) < 2:
        return None
    snake = [re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", n).lower() for n in names]
    return 1, ",".join(snake)


def _fast(lines, delim: str | None, decimal_comma: bool,
          want: dict[str, int]) -> dict[str, np.ndarray] | None:
    """numpy's C parser on the role columns; None when it refuses anything (a bad cell, a
    short row): the line-by-line loop then names the line. It does not check that a row has
    no extra cells — a row the header does not describe still gets its numbers read."""
    import warnings

    body = "\n".join(ln for _, ln in lines[1:])
    if decimal_comma:
        body = body.replace(",", ".")
    cols = sorted(set(want.values()))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # "empty input" and the like: use the slow path
            arr = np.loadtxt(io.StringIO(body), delimiter=delim, usecols=cols, ndmin=2,
                             dtype=float, quotechar='"', comments=None)
    except (ValueError, UserWarning, IndexError):
        return None
    if arr.shape[0] != len(lines) - 1:
        return None
    return {role: np.ascontiguousarray(arr[:, cols.index(i)]) for role, i in want.items()}


def _has_decimal_comma(lines) -> bool:
    return any("," in ln for _, ln in lines[1:4])


__all__ = ["ROLES", "load_text", "looks_like_table", "read_csv"]

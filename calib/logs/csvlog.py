"""CSV/TSV logs with a header: generic tables, phyphox exports, Sensor Logger exports.

Layout read
-----------
* Optional gzip (``.csv.gz``; recognized from the gzip magic bytes, not the name).
* Text in UTF-8 (with or without BOM), else Latin-1 (a file with any byte sequence that is
  not UTF-8 is Latin-1 throughout). Lines end at ``\\n``, ``\\r\\n`` or ``\\r``. Blank lines and
  lines starting with ``#`` are skipped (line numbers in messages are the file's own, 1-based).
* The first other line is the header; it must name the columns (a first line of numbers is
  refused: the reader cannot know which column is which). A YEI 3-Space export's first line,
  ``# Data format: "%int(ChipTimeUS),%float(RawAccelX),…"``, is read as its header
  (``chip_time_us``, ``raw_accel_x`` …; its accelerations need ``--units``).
* Delimiter sniffed from the header: tab, ``;`` or ``,`` (the most frequent), else runs of
  spaces. Quoted cells are allowed (phyphox quotes its header).
* **Every data row has the header's number of cells.** A row with more or fewer is refused
  with its line number; no row is read in part.
* Decimal comma: with a ``;``, tab or space delimiter, numbers such as ``1,23`` are read as
  1.23 (phyphox's and spreadsheets' "semicolon, decimal comma" export). A ``,``-delimited file
  has decimal points. A comma-delimited file written with decimal commas (``0,01,-9,81``)
  has rows with more cells than its header: it is refused at its first row, and the message
  says that the commas look like decimal commas and asks for ``;`` or tab. The ambiguity is
  never resolved from the header, not even when every row has exactly twice the header's
  cells: a single value written without decimals (``0`` for ``0,0``) shifts every later cell
  of its row, so pairing cells would be a guess.

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

Units: header or option
-----------------------
A time column without a stated unit is in seconds. Which unit wins:

==============  ==================================================  =========================
column          the header states a unit read here                  the header's unit text is
                                                                    not a unit read here
==============  ==================================================  =========================
acceleration    it; ``--units`` that differs is refused              ``--units`` (else refused)
                (:func:`calib.logs.reader.assemble`)
gyro            ``--gyro-unit`` when given (the option wins)         ``--gyro-unit`` (else
                                                                    refused)
time            it; ``--time-unit`` that differs is refused          ``--time-unit`` (else
                                                                    refused)
==============  ==================================================  =========================

Streaming, and the parser chosen
--------------------------------
The file is read in blocks of :data:`CHUNK_BYTES` (cut after a line end; a gzip file is
decompressed as it is read). Each block is parsed into columns that are allocated once,
from the size of the file and the bytes per row seen so far, and grown in place (``realloc``:
no copy) when the estimate falls short, so the peak memory is the columns kept — 8 bytes per
sample and role — plus one block's working set; the file's text is never held whole. Line
numbers are kept as runs (:class:`calib.logs.table.LineIndex`), not one integer per sample.

A block is parsed by pandas' C parser (``pandas.read_csv`` on the block: every column, no
NaN markers, so an empty cell or ``NA`` stays text); the block's result is taken only when
every role column came out as numbers and nothing can hide a bad row (a block with a text
column is also checked by counting its delimiters and line ends). A block with comment or
blank lines is parsed again without them; anything else — a row of another length, a cell
that is not a number, a quote left open — goes through the line-by-line parser (each line
split on its own), which names the first bad line in the file's own numbering. Both give the
same numbers (correctly rounded, the same as ``float``). Files smaller than
:data:`SMALL_BYTES` are parsed line by line only: importing pandas (≈ 0.35 s) costs more than
parsing them.

Why pandas (measured on the 2-core development VM, a 1-hour 100 Hz log of 7 columns, 33 MB):
numpy's ``loadtxt`` on the same blocks takes 3.7× the time of one plain ``pandas.read_csv``
of the file and ``numpy.fromstring`` 4.6×, and neither checks a row's length when only some
columns are read; ``pandas.read_csv`` on 1 MiB blocks takes the time of the plain read. The
goal — at most 1.5× the plain pandas read's time and 2× the numeric array's memory — is out
of numpy's reach, so pandas is a dependency. pandas' working set is ≈ 6× the block, hence
1 MiB blocks. Each block's working set is kept allocated for the next one
(:func:`_keep_block_memory`: glibc would hand it back to the kernel after every block, and
the page faults of the next block cost ≈ 15 % of the read). ``benchmarks/csv_reader.py``
gives, for 1- and 10-hour logs, 0.94–1.14× and 1.10–1.49× the plain pandas read's CPU time
run to run (1.5–1.9× and 2.0–2.5× its wall time: pandas ≥ 3.1 parses a long file on two
threads; the file's hash runs on a second thread here, :class:`_Hashed`) and 1.6–1.7× and
1.1× the array's memory (pandas: 3.2–3.7×; this reader before it streamed: 12.8× the array and ≈ 7×
pandas' time on the 10-hour log).
"""

from __future__ import annotations

import csv
import functools
import gzip
import hashlib
import io
import os
import re
import warnings
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from calib.input_rules import DataError
from calib.logs.table import (
    TIME_UNITS,
    LineIndex,
    RawLog,
    accel_unit,
    angle_unit,
    split_unit,
    time_factor,
)
from calib.logs.table import gyro_unit as gyro_unit_of

CHUNK_BYTES = 1 << 20
"""Bytes of the file read and parsed at a time (1 MiB: pandas' working set is ≈ 6× that)."""
HEAP_MMAP_BYTES = 4 * CHUNK_BYTES
"""glibc's ``M_MMAP_THRESHOLD`` while blocks are parsed (:func:`_keep_block_memory`)."""
HEAP_TRIM_BYTES = 8 * CHUNK_BYTES
"""glibc's ``M_TRIM_THRESHOLD`` while blocks are parsed: above one block's working set."""
SMALL_BYTES = 4 << 20
"""Files (gzip: compressed) smaller than this are parsed line by line, without pandas."""
GZIP_MAGIC = b"\x1f\x8b"
BOM = b"\xef\xbb\xbf"

Progress = Callable[[int, int], None]
"""``progress(done, total)``: bytes of the file (compressed, for gzip) read so far, of all."""

_PREFIX = r"(?:raw_?|corrected_?|calibrated_?|cal_|imu_)?"
_ACC = re.compile(rf"^{_PREFIX}(?:acc|accel|accelerometer|acceleration|a)_?([xyz])$")
_GYRO = re.compile(rf"^{_PREFIX}(?:gyr|gyro|gyroscope|angular_velocity|omega|w|g)_?([xyz])$")
_LINEAR = re.compile(r"^(?:linear|user)_?acc(?:el(?:eration)?)?_?[xyz]$")
_TIME = ("t", "time", "timestamp", "seconds_elapsed", "chip_time", "elapsed_time",
         "time_stamp")
_YEI = re.compile(r"%\w+\((\w+)\)")
_THETA = ("theta", "tita", "angle", "tilt")
_LABEL = ("label", "pose")
_EOL = re.compile(rb"\r\n|\r|\n")
_INTEGER = re.compile(r"\s*[+-]?\d+\s*")
ROLES = ("t", "x", "y", "z", "theta", "label", "gyro")
"""Roles ``--columns`` may name (``gyro``: one rate column about the tilt axis)."""


def load_text(path: Path) -> str:
    """The file's text: gunzipped when it starts with the gzip magic, UTF-8 (BOM stripped) or
    else Latin-1. (The whole file in memory: :func:`read_csv` streams instead.)"""
    data = path.read_bytes()
    if data[:2] == GZIP_MAGIC:
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
    delimiter — how ``--format auto`` tells a log in a ``.txt`` from other text files. Reads
    the file's first block only."""
    try:
        with _Source(path, None, None) as src:
            block = src.block() or b""
            lines = [ln for _, ln, _ in _take(_content(block, src.encoding), 2)]
    except (OSError, DataError, _NotUtf8Error):
        return False
    if len(lines) < 2:
        return False
    delim = _sniff(lines[0])
    head, row = _split(lines[0], delim), _split(lines[1], delim)
    if len(head) < 2 or len(row) != len(head):
        return False
    decimal_comma = delim != ","
    return (not all(_is_number(c, decimal_comma) for c in head)
            and all(_is_number(c, decimal_comma) for c in row if c.strip()))


def _content(data: bytes, encoding: str, start: int = 0, first: int = 1):
    """``(line number, line text, end offset)`` of the content lines of the bytes ``data``
    from offset ``start`` (whose line is ``first``), lazily: blank and ``#`` lines skipped."""
    number, pos = first, start
    while pos < len(data):
        m = _EOL.search(data, pos)
        end, nxt = (m.start(), m.end()) if m else (len(data), len(data))
        line = data[pos:end].decode(encoding)
        if _is_content(line):
            yield number, line, nxt
        number, pos = number + 1, nxt


def _take(it, k: int) -> list:
    """The first ``k`` items of the iterator ``it`` (fewer when it ends first)."""
    out = []
    for item in it:
        out.append(item)
        if len(out) == k:
            break
    return out


def _lines(text: str) -> list[str]:
    """The lines of ``text`` (ends ``\\n``, ``\\r\\n``, ``\\r``; no empty last line)."""
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return lines


def _is_content(line: str) -> bool:
    stripped = line.strip()
    return bool(stripped) and not stripped.startswith("#")


def _sniff(header: str) -> str | None:
    counts = {d: header.count(d) for d in ("\t", ";", ",")}
    best = max(counts, key=counts.get)
    return best if counts[best] else None  # None: runs of spaces


def _split(line: str, delim: str | None) -> list[str]:
    if delim is None:
        return line.split()
    if '"' not in line:  # what csv.reader does with a line without quotes
        return line.split(delim)
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


def _recognize(names: list[str]) -> tuple[dict[str, list[int]], dict[str, str | None], str]:
    """Roles found in a header: role → column indices, role → unit text, and the format's
    name (``phyphox`` when its header style is seen, ``sensorlogger`` for its bare x/y/z with
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


def _yei_header(text: str) -> tuple[int, str] | None:
    """A YEI 3-Space export's header: its first line is ``# Data format:
    "%int(ChipTimeUS),%float(RawAccelX),…"``; the names, CamelCase split into snake_case
    (``chip_time_us``: time in µs; ``raw_accel_x``), as a header line."""
    first = text.splitlines()[0] if text else ""
    if "data format" not in first.lower():
        return None
    names = _YEI.findall(first)
    if len(names) < 2:
        return None
    snake = [re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", n).lower() for n in names]
    return 1, ",".join(snake)


# --- the file, block by block ---------------------------------------------------------------

class _NotUtf8Error(Exception):
    """A block that is not UTF-8 after non-ASCII text was read as UTF-8: the whole file is
    Latin-1 and is read again as such."""


class _Hashed:
    """A binary file read front to back, its bytes fed to a sha256 as they are read: the
    provenance's hash of a log without reading the file a second time
    (:func:`calib.logs.reader.file_sha256` gives the same digest).

    The hash runs on a thread of its own, in read order (hashlib releases the GIL on large
    updates): on a 10-hour log it is ≈ 0.2 s of the read's 1.2 s, which the parse no longer
    waits for. What it hashes is an owned copy of each read (the reader reuses its buffer).
    """

    def __init__(self, f) -> None:
        from concurrent.futures import ThreadPoolExecutor

        self.f, self._sha = f, hashlib.sha256()
        self.mode, self.name = "rb", getattr(f, "name", "")
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="log-sha256")
        self._pending = None

    def _update(self, data: bytes) -> None:
        if data:  # one worker: the updates run in the order they were submitted
            self._pending = self._pool.submit(self._sha.update, data)

    def _wait(self) -> None:
        if self._pending is not None:
            self._pending.result()
            self._pending = None

    def read(self, size: int = -1) -> bytes:
        data = self.f.read(size)
        self._update(data)
        return data

    def readinto(self, view) -> int:
        data = self.f.read(len(view))
        view[:len(data)] = data
        self._update(data)
        return len(data)

    def tell(self) -> int:
        return self.f.tell()

    def seek(self, offset: int, whence: int = 0) -> int:
        """Only back to the start (the hash starts again): the reader reads front to back."""
        if (offset, whence) != (0, 0):
            raise io.UnsupportedOperation("a hashed log is read front to back")
        self._wait()
        self._sha = hashlib.sha256()
        return self.f.seek(0)

    def fileno(self) -> int:
        return self.f.fileno()

    def close(self) -> None:
        self._pool.shutdown(wait=True)
        self.f.close()

    def hexdigest(self) -> str:
        """The sha256 of the whole file: what was read, then the rest of it."""
        while block := self.f.read(1 << 20):
            self._update(block)
        self._wait()
        return self._sha.hexdigest()


class _Source:
    """The file's bytes in blocks of about :data:`CHUNK_BYTES` that end after a line end
    (gunzipped as read; the BOM dropped), the text encoding found so far and the progress.

    The encoding is UTF-8 until a block is not; the file is then Latin-1 — at once when every
    earlier block was ASCII (the same text in both), else by raising :class:`_NotUtf8Error`
    so that the reader starts again in Latin-1.
    """

    def __init__(self, path: Path, encoding: str | None, progress: Progress | None) -> None:
        self.path = path
        self.raw = _Hashed(open(path, "rb"))  # noqa: SIM115  (closed by close())
        self.total = os.fstat(self.raw.fileno()).st_size
        self.gzip = self.raw.read(2) == GZIP_MAGIC
        self.raw.seek(0)
        self.stream = gzip.GzipFile(fileobj=self.raw, mode="rb") if self.gzip else self.raw
        self.encoding = encoding or "utf-8"
        self._forced = encoding is not None
        self._non_ascii = False  # a non-ASCII block was read as UTF-8
        self._eof = False
        self.progress = progress
        self._reported = -1
        # the bytes read and not yet handed out: _buf[:_have] (a line's start, at most)
        self._buf = bytearray(len(BOM))
        self._have = self._readinto(memoryview(self._buf))
        if bytes(self._buf) == BOM:  # the BOM says UTF-8; it is not text
            self._have = 0

    def __enter__(self) -> _Source:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self.stream is not self.raw:
            self.stream.close()
        self.raw.close()

    @property
    def position(self) -> int:
        """Bytes of the file (compressed, for gzip) read so far."""
        return min(self.raw.tell(), self.total)

    def _readinto(self, view: memoryview) -> int:
        if not self.gzip:
            return self.stream.readinto(view)
        try:
            return self.stream.readinto(view)
        except (OSError, EOFError, zlib.error) as exc:
            raise DataError(f"{self.path}: a damaged gzip file ({exc})") from exc

    def block(self) -> bytes | None:
        """The next block (whole lines; the last one may lack its line end), or None."""
        # read into one reused buffer and copy each block out once: fresh 1 MiB objects per
        # read, slice and join cost more than pandas' parse of a block's first quarter
        cut = -1
        while not self._eof:
            start, end = self._have, self._have + CHUNK_BYTES
            if len(self._buf) < end:
                self._buf.extend(bytes(end - len(self._buf)))
            with memoryview(self._buf) as view:
                got = self._readinto(view[start:end])
            if not got:
                self._eof = True
                break
            self._have = start + got
            cut = self._buf.rfind(b"\n", start, self._have)
            if cut >= 0:
                break  # else no line end yet (a long line, or \r line ends): read on
        size = cut + 1 if cut >= 0 and not self._eof else self._have
        with memoryview(self._buf) as view:
            buf = bytes(view[:size])
        rest = self._have - size  # the start of the next block's first line
        self._buf[:rest] = self._buf[size:self._have]
        self._have = rest
        if not buf:
            return None
        self._check_encoding(buf)
        self.report(self.position)
        return buf

    def report(self, done: int) -> None:
        """Call the progress callback with ``done`` bytes, unless that was the last call."""
        if self.progress is not None and done != self._reported:
            self._reported = done
            self.progress(done, self.total)

    def _check_encoding(self, block: bytes) -> None:
        if self._forced or self.encoding != "utf-8" or block.isascii():
            return
        try:
            block.decode("utf-8")
        except UnicodeDecodeError:
            if self._non_ascii:
                raise _NotUtf8Error from None
            self.encoding = "latin-1"  # every earlier block was ASCII: the same in Latin-1
            return
        self._non_ascii = True

    def decode(self, block: bytes) -> str:
        return block.decode(self.encoding)


# --- the columns read ----------------------------------------------------------------------

@dataclass
class _Columns:
    """The samples read so far: one float64 array per role (allocated for the rows the file
    is expected to hold, grown in place), the labels, and the line runs."""

    roles: tuple[str, ...]
    source: _Source
    with_labels: bool
    n: int = 0
    capacity: int = 0
    values: dict[str, np.ndarray] = field(default_factory=dict)
    labels: list[str] | None = None
    starts: list[int] = field(default_factory=list)
    lines: list[int] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.values = {r: np.empty(0) for r in self.roles}
        self.labels = [] if self.with_labels else None

    def _grow(self, need: int) -> None:
        # rows expected in the whole file from the bytes per row so far (2 % spare); pages
        # never written are never touched, so a generous estimate costs address space only
        done = self.source.position
        expected = int(need * self.source.total / done * 1.02) + 1024 if done else need
        capacity = max(need, expected, int(self.capacity * 1.25))
        for role, arr in self.values.items():
            if self.capacity == 0:  # pages are committed as they are written
                self.values[role] = np.empty(capacity)
            else:  # realloc (mremap for large blocks: no copy); the new part is zeroed
                arr.resize(capacity, refcheck=False)
        self.capacity = capacity

    def add(self, cols: dict[str, np.ndarray], labels: list[str] | None,
            lines: int | list[int]) -> None:
        """Append rows: their role values, labels, and their lines (the first line of
        consecutive ones, or one per row)."""
        m = len(next(iter(cols.values()))) if cols else (
            len(labels) if labels is not None else len(lines))
        if m == 0:
            return
        end = self.n + m
        if end > self.capacity:
            self._grow(end)
        for role, v in cols.items():
            self.values[role][self.n:end] = v
        if self.labels is not None and labels is not None:
            self.labels.extend(labels)
        if isinstance(lines, int):
            self._run(self.n, lines)
        else:
            index = LineIndex.from_lines(lines)
            for s, ln in zip(index.starts.tolist(), index.lines.tolist(), strict=True):
                self._run(self.n + s, ln)
        self.n = end

    def _run(self, sample: int, line: int) -> None:
        if self.starts and line - self.lines[-1] == sample - self.starts[-1]:
            return  # continues the previous run
        self.starts.append(sample)
        self.lines.append(line)

    def finish(self) -> tuple[dict[str, np.ndarray], LineIndex]:
        for arr in self.values.values():
            arr.resize(self.n, refcheck=False)
        index = LineIndex(np.array(self.starts, dtype=np.int64),
                          np.array(self.lines, dtype=np.int64), self.n)
        return self.values, index


# --- parsing blocks -------------------------------------------------------------------------

@dataclass
class _Parser:
    """Parses blocks of data rows into :class:`_Columns` (module docstring: pandas' C parser
    where its result is exact, else line by line)."""

    path: Path
    names: list[str]
    delim: str | None
    decimal_comma: bool
    want: dict[str, int]
    label: int | None
    source: _Source
    fast: bool
    firsts: list[str] = field(default_factory=list)
    """The first three data rows (the decimal mark the provenance reports)."""

    def piece(self, data: bytes, first: int, out: _Columns) -> int:
        """Parse whole lines ``data`` (bytes of the file) whose first line is ``first``;
        returns the number of lines they span."""
        if len(self.firsts) < 3:
            self.firsts += [ln for _, ln, _ in _take(_content(data, self.source.encoding),
                                                     3 - len(self.firsts))]
        if self.fast:
            rows = self._pandas(data, out, first)
            if rows is not None:
                return rows
        lines = _lines(self.source.decode(data))
        kept = [(first + i, ln) for i, ln in enumerate(lines) if _is_content(ln)]
        if self.fast and kept and len(kept) < len(lines):  # comments or blank lines: parse
            joined = "\n".join(ln for _, ln in kept) + "\n"  # the rest with pandas again
            if self._pandas(joined, out, [k for k, _ in kept]) is not None:
                return len(lines)
        self._exact(kept, out)
        return len(lines)

    def _pandas(self, data: bytes | str, out: _Columns, lines: int | list[int]) -> int | None:
        """Rows parsed by pandas and appended to ``out``; None (nothing appended) when the
        block needs the line-by-line parser."""
        import pandas as pd

        n = len(self.names)
        buf = io.BytesIO(data) if isinstance(data, bytes) else io.StringIO(data)
        dtype = {self.label: object} if self.label is not None else None
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                df = pd.read_csv(
                    buf, sep=self.delim if self.delim is not None else r"\s+", header=None,
                    index_col=False, dtype=dtype, na_filter=False, skip_blank_lines=False,
                    quoting=csv.QUOTE_NONE if self.delim is None else csv.QUOTE_MINIMAL,
                    quotechar='"', decimal="," if self.decimal_comma else ".",
                    encoding=self.source.encoding, engine="c")
        except Exception:  # noqa: BLE001 — any refusal: the line-by-line parser names it
            return None
        rows = len(df)
        if df.shape[1] != n:
            return None
        columns = [df[i] for i in range(n)]
        cols = {}
        for role, i in self.want.items():
            if columns[i].dtype.kind not in "fiu":
                return None
            cols[role] = columns[i].to_numpy()
        if any(c.dtype.kind not in "fiu" for c in columns) and not _counted(
                data, self.delim, rows, n):
            return None
        labels = None
        if self.label is not None:
            labels = [str(v).strip() for v in columns[self.label].tolist()]
        out.add(cols, labels, lines)
        return rows

    def _exact(self, kept: list[tuple[int, str]], out: _Columns) -> None:
        """The line-by-line parser: every row's cell count, every role cell a number."""
        n = len(self.names)
        values = {role: np.empty(len(kept)) for role in self.want}
        labels: list[str] | None = [] if self.label is not None else None
        for k, (line_no, line) in enumerate(kept):
            cells = _split(line, self.delim)
            if len(cells) != n:
                raise self._count_error(line_no, cells)
            for role, i in self.want.items():
                try:
                    values[role][k] = _number(cells[i], self.decimal_comma)
                except ValueError:
                    raise DataError(f"{self.path}: line {line_no}, column '{self.names[i]}': "
                                    f"{cells[i].strip()!r} is not a number; repair or remove "
                                    "that line") from None
            if labels is not None:
                labels.append(cells[self.label].strip())
        out.add(values, labels, [k for k, _ in kept])

    def _count_error(self, line_no: int, cells: list[str]) -> DataError:
        n = len(self.names)
        if (self.delim == "," and len(cells) > n
                and all(_INTEGER.fullmatch(c) for c in cells)):
            return DataError(f"{self.path}: line {line_no} has {len(cells)} cells but the "
                             f"header has {n}: decimal commas in a comma-separated file? "
                             f"('{cells[0].strip()},{cells[1].strip()}' can be one number or "
                             "two); export with ';' or tab between the columns, or with "
                             "decimal points")
        return DataError(f"{self.path}: line {line_no} has {len(cells)} cells but the header "
                         f"has {n}; repair or remove that line")


def _counted(data: bytes | str, delim: str | None, rows: int, n: int) -> bool:
    """True when ``data`` holds exactly ``rows`` lines of ``n`` cells each, counted from its
    delimiters and line ends. Needed when a column came out as text: pandas fills a short row
    with "" and takes a blank or ``#`` line as a row of text. Never true with quotes (a
    quoted cell may hold a delimiter or a line end), ``#`` or runs of spaces."""
    if delim is None:
        return False

    def enc(c: str) -> bytes | str:
        return c.encode() if isinstance(data, bytes) else c

    if enc('"') in data or enc("#") in data:
        return False
    ends = data.count(enc("\n")) + (not data.endswith(enc("\n")))
    # a lone \r is a line end to pandas: one more row than line feeds
    return ends == rows and data.count(enc(delim)) == rows * (n - 1)


# --- the reader -----------------------------------------------------------------------------

@functools.cache
def _keep_block_memory() -> None:
    """Keep one block's working set allocated from one block to the next (glibc only).

    Each block's parse allocates and frees the same ≈ 6 MiB (pandas' tokenizer, the block's
    columns). glibc hands such memory back to the kernel when it is freed (an ``mmap``
    chunk, or a heap top above its trim threshold) and the next block faults every page in
    again: on a 1-hour log 12 000–16 000 more page faults than one plain ``pandas.read_csv``
    (which allocates once), ≈ 15 % of its CPU time (``benchmarks/csv_reader.py``). Setting
    the thresholds to :data:`HEAP_MMAP_BYTES` and :data:`HEAP_TRIM_BYTES` keeps the working
    set on the heap: at most 8 MiB more resident memory, once per process (the settings are
    the process's; glibc's own adaptive thresholds reach 32/64 MiB; cached: the first call
    sets them). Elsewhere (no glibc, no ``mallopt``) nothing is changed.
    """
    import ctypes
    import platform

    if platform.libc_ver()[0] != "glibc":
        return
    try:
        libc = ctypes.CDLL(None)
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return
    m_trim_threshold, m_mmap_threshold = -1, -3  # <malloc.h>
    mallopt(m_mmap_threshold, HEAP_MMAP_BYTES)
    mallopt(m_trim_threshold, HEAP_TRIM_BYTES)


def read_csv(path: str | Path, columns: dict[str, str] | None = None, fmt: str = "auto", *,
             units: str | None = None, gyro_unit: str | None = None,
             time_unit: str | None = None, progress: Progress | None = None) -> RawLog:
    """Read a CSV/TSV log (module docstring) into a :class:`RawLog` (units as stated).

    Parameters
    ----------
    path : the file (a path or its name).
    columns : role → column name (``--columns``), overriding recognition for that role.
    fmt : ``auto``/``csv``/``phyphox``/``sensorlogger`` (the last two only check that the
        header is that app's).
    units : ``--units``: the acceleration unit when a header's unit text is not one read here
        (a stated unit that differs is refused later, by :func:`calib.logs.reader.assemble`).
    gyro_unit : ``--gyro-unit``: the gyro columns' unit, whatever the header says.
    time_unit : ``--time-unit`` (``s``, ``ms``, ``us``, ``ns``): the time column's unit when
        the header states none or an unknown one; a different stated unit is refused.
    progress : called as ``progress(done, total)`` with the file's bytes (compressed, for
        gzip) read so far, after each block.

    Raises
    ------
    DataError : no header, a delimiter-less header, an unknown column in ``--columns``,
        a role matched by two columns, a row with more or fewer cells than the header
        (named by line), a non-numeric cell (named by line and column), a gravity-removed
        export, a unit not read here and not given by its option, a damaged gzip file.
    """
    path = Path(path)
    columns = dict(columns or {})
    bad = sorted(set(columns) - set(ROLES) - {"topic"})
    if bad:
        raise DataError(f"--columns: unknown role(s) {', '.join(bad)}; roles are "
                        f"{', '.join(ROLES)}")
    if time_unit is not None and time_unit not in TIME_UNITS:
        raise DataError(f"--time-unit {time_unit}: expected one of {', '.join(TIME_UNITS)}")
    options = {"units": units, "gyro_unit": gyro_unit, "time_unit": time_unit}
    try:
        return _read(path, columns, fmt, options, progress, None)
    except _NotUtf8Error:
        return _read(path, columns, fmt, options, progress, "latin-1")


def _header(src: _Source, path: Path) -> tuple[tuple[int, str], bytes, int, int]:
    """The header ``(line, text)``, the bytes read so far (whole lines), the offset where
    the data rows start in them and their first line."""
    data = b""
    while (block := src.block()) is not None:
        data = data + block if data else block
        if next(_content(data, src.encoding), None) is not None:
            break
    found = next(_content(data, src.encoding), None)
    if found is None:
        raise DataError(f"{path}: empty (no header, no samples)")
    line_no, line, end = found
    m = _EOL.search(data)
    first_end = m.end() if m else len(data)
    yei = _yei_header(data[:first_end].decode(src.encoding))
    if yei is not None:  # YEI 3-Space: the header is line 1, a '#' line; every content
        return yei, data, first_end, 2  # line is a row
    return (line_no, line), data, end, line_no + 1


def _read(path: Path, columns: dict[str, str], fmt: str, options: dict[str, str | None],
          progress: Progress | None, encoding: str | None) -> RawLog:
    with _Source(path, encoding, progress) as src:
        (head_line, head_text), data, start, first = _header(src, path)
        delim = _sniff(head_text)
        names = [c.strip() for c in _split(head_text, delim)]
        decimal_comma = delim != ","
        if all(_is_number(c, decimal_comma) for c in names if c):
            raise DataError(f"{path}: line {head_line} holds numbers, not column names: the "
                            "file has no header; add a first line naming the columns (e.g. "
                            "t,ax,ay,az) and give their units in it (e.g. 'ax (m/s^2)') or "
                            "with --units")
        if len(names) < 2:
            raise DataError(f"{path}: line {head_line}: one column only; expected a header "
                            "with at least two columns separated by ',', ';', tab or spaces")
        index, units, detected, mapping = _roles(path, names, columns, fmt)
        want = {role: i for role, i in index.items() if role != "label"}
        parser = _Parser(path, names, delim, decimal_comma, want, index.get("label"), src,
                         fast=src.total >= SMALL_BYTES)
        if parser.fast:
            _keep_block_memory()
        out = _Columns(tuple(want), src, "label" in index)
        rest = data[start:]
        del data
        line = first + parser.piece(rest, first, out)
        del rest
        while (block := src.block()) is not None:
            line += parser.piece(block, line, out)
        values, rows = out.finish()
        src.report(src.total)
        labels = out.labels
        notes_gzip = src.gzip
        sha256 = src.raw.hexdigest()
    if rows.n == 0:
        raise DataError(f"{path}: a header but no samples")
    acc = {r[4:]: v for r, v in values.items() if r.startswith("acc.")}
    gyro = {r[5:]: v for r, v in values.items() if r.startswith("gyro.")}
    if "gyro" in values:
        gyro = {"tilt": values["gyro"]}
    acc_units = _acc_units(path, names, index, units, acc, options["units"])
    content_note = None
    if detected == "sensorlogger" and acc_units is None and options["units"] is None:
        acc_units, content_note = _sensor_logger_units(path, acc)
    t, time_note = _time(path, names, index, units, values, options["time_unit"])
    g_unit = _gyro_units(path, index, units, options["gyro_unit"])
    return RawLog(
        fmt=detected, acc=acc, acc_unit=acc_units, t=t,
        theta=values.get("theta"),
        theta_unit=angle_unit(units.get("theta")),
        label=None if labels is None else np.array(labels, dtype=object),
        gyro=gyro, gyro_unit=g_unit,
        rows=rows, row_word="line", mapping=mapping, sha256=sha256,
        notes={"delimiter": {"\t": "tab", None: "spaces"}.get(delim, delim),
               "decimal": "," if decimal_comma and any("," in s for s in parser.firsts)
               else ".",
               "gzip": notes_gzip, "time_unit": time_note,
               **({"units_from_content": content_note} if content_note else {})})


def _roles(path: Path, names: list[str], columns: dict[str, str], fmt: str
           ) -> tuple[dict[str, int], dict[str, str | None], str, dict[str, str]]:
    """Role → column index, role → unit text, the format and the provenance mapping (role →
    column name) of a header, after ``--columns``; refuses what cannot be read."""
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
    mapping = {("x" if r == "acc.x" else "y" if r == "acc.y" else "z" if r == "acc.z"
                else r.replace("gyro.", "gyro_")): names[i] for r, i in index.items()}
    return index, units, detected, mapping


SENSOR_LOGGER_G = 9.80665
"""m/s²: what a still phone's Sensor Logger readings with gravity average to, in magnitude."""


def _sensor_logger_units(path: Path, acc: dict[str, np.ndarray]) -> tuple[str | None, str]:
    """The unit of a Sensor Logger file whose name does not say which export it is (renamed,
    prefixed), from its content: its calibrated files are in m/s² (the app's UNITS.md), and
    the median magnitude ``|a|`` over the log tells the exports apart — ≈ 9.8 (0.8–1.25 g):
    acceleration with gravity (TotalAcceleration), read in m/s²; below 0.3 g: gravity removed
    (Accelerometer.csv: user motion only), refused; ≈ 1 (0.8–1.25, checked first): readings in
    g (iOS's AccelerometerUncalibrated), refused asking for ``--units g``. Else None: the unit stays
    unstated and the reader asks for ``--units``."""
    if not all(k in acc for k in "xyz"):
        return None, ""
    mag = float(np.median(np.sqrt(acc["x"] ** 2 + acc["y"] ** 2 + acc["z"] ** 2)))
    g = SENSOR_LOGGER_G
    if 0.8 * g <= mag <= 1.25 * g:
        return "m/s2", (f"a Sensor Logger export with gravity: median |a| = {mag:.4g}, read in "
                        "m/s² (the app's unit)")
    if 0.8 <= mag <= 1.25:
        raise DataError(f"{path}: a Sensor Logger export whose readings average |a| = "
                        f"{mag:.3g}: in g, not m/s² (AccelerometerUncalibrated on iOS): give "
                        "--units g — unless it is a gravity-removed export of a moving phone "
                        "(then read TotalAcceleration.csv)")
    if mag < 0.3 * g:
        raise DataError(f"{path}: a Sensor Logger export whose readings average |a| = "
                        f"{mag:.3g} m/s², far below g: gravity was removed (Accelerometer.csv "
                        "holds user motion only), so the tilt signal is gone; read "
                        "TotalAcceleration.csv")
    return None, ""


def _acc_units(path: Path, names: list[str], index: dict[str, int],
               units: dict[str, str | None], acc: dict[str, np.ndarray],
               option: str | None) -> str | None:
    """The acceleration unit the header states (None: not stated); ``--units`` wins over a
    unit text not read here."""
    stated: dict[str, str | None] = {}
    for a in acc:
        text_unit = units.get(f"acc.{a}")
        unit = accel_unit(text_unit)
        if text_unit is not None and unit is None:
            if option is None:
                raise DataError(f"{path}: column '{names[index[f'acc.{a}']]}': unit "
                                f"'{text_unit}' is not an acceleration unit read here (m/s^2, "
                                "g, mg, counts); fix the header or give --units")
            unit = option  # the stated option wins over a unit text not read here
        stated[a] = unit
    found = set(stated.values())
    if len(found) > 1:
        texts = {units.get(f"acc.{a}") for a in acc}
        raise DataError(f"{path}: the acceleration columns state different units "
                        f"({', '.join(sorted(str(u) for u in texts))}); convert them to one")
    return found.pop() if found else None


def _time(path: Path, names: list[str], index: dict[str, int], units: dict[str, str | None],
          values: dict[str, np.ndarray], option: str | None
          ) -> tuple[np.ndarray | None, str | None]:
    """The time column in s (scaled in place) and the note of its unit."""
    if "t" not in values:
        return None, None
    column = names[index["t"]]
    text_unit = units.get("t")
    unit = text_unit
    if option is not None:
        stated = time_factor(text_unit)
        if stated is not None and stated != time_factor(option):
            raise DataError(f"{path}: column '{column}' states the time in {text_unit} but "
                            f"--time-unit {option}; drop --time-unit or fix the header")
        unit = option
    factor = time_factor(unit or "s")
    if factor is None:
        raise DataError(f"{path}: column '{column}': time unit '{unit}' not read here "
                        f"({', '.join(TIME_UNITS)}); fix the header or give --time-unit")
    t = values["t"]
    if factor != 1.0:
        t *= factor
    if option is not None:
        note = f"{option} (--time-unit)"
    else:
        note = text_unit or "s (not stated: taken as seconds)"
    return t, note


def _gyro_units(path: Path, index: dict[str, int], units: dict[str, str | None],
                option: str | None) -> str | None:
    """The gyro columns' unit: ``--gyro-unit`` when given, else the one the header states."""
    if option is not None:
        return option
    g_roles = [r for r in index if r.startswith("gyro") or r == "gyro"]
    g_units = {gyro_unit_of(units.get(r)) for r in g_roles if units.get(r) is not None}
    if len(g_units) > 1 or None in g_units:
        raise DataError(f"{path}: gyro column unit(s) "
                        f"{', '.join(str(units.get(r)) for r in g_roles)} not read here "
                        "(rad/s, deg/s); fix the header or give --gyro-unit")
    return g_units.pop() if g_units else None


__all__ = ["BOM", "CHUNK_BYTES", "GZIP_MAGIC", "ROLES", "SMALL_BYTES", "Progress", "load_text",
           "looks_like_table", "read_csv"]

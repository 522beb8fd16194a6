"""The CSV reader streams (:mod:`calib.logs.csvlog`): block by block it gives what one pass
over the whole file gives.

Every case runs under both block parsers — pandas' C parser (``SMALL_BYTES = 0``) and the
line-by-line parser (``SMALL_BYTES`` huge) — and several block sizes (:data:`CHUNK_BYTES`
from 1 byte, one line per block, to 1 MiB, the whole file), so rows straddle every block
boundary. The values are written with ``repr`` (they round-trip), so the arrays read must equal
the written ones exactly, the line numbers must be the file's own (comment and blank lines
counted), and a bad line deep in the file must be named by its own number. Small files
(≤ 2000 rows; 20 000 numbers for the exactness of the block parser): about 10 s.
"""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest

from calib.input_rules import DataError
from calib.logs import csvlog
from calib.logs.csvlog import load_text, read_csv
from calib.logs.reader import LogOptions, read_log
from calib.logs.table import LineIndex

HEADER = ["t (s)", "ax (m/s^2)", "ay (m/s^2)", "az (m/s^2)"]
ENGINES = ("pandas", "lines")
CHUNKS = (1, 200, 4096, 1 << 20)


def _values(n: int, seed: int = 0) -> np.ndarray:
    """(n, 4): t from 1000 s at 100 Hz, a still sensor with noise (full-precision floats)."""
    rng = np.random.default_rng(seed)
    acc = rng.normal([0.0, -9.8, 0.05], 0.02, (n, 3))
    return np.c_[1000.0 + 0.01 * np.arange(n), acc]


def _cells(values: np.ndarray, decimal_comma: bool = False) -> list[list[str]]:
    rows = [[repr(float(v)) for v in row] for row in values]
    if decimal_comma:
        rows = [[c.replace(".", ",") for c in row] for row in rows]
    return rows


def _write(path: Path, lines: list[str], newline: str = "\n", bom: bool = False,
           gz: bool = False, encoding: str = "utf-8") -> Path:
    data = (newline.join(lines) + newline).encode(encoding)
    if bom:
        data = csvlog.BOM + data
    path.write_bytes(gzip.compress(data, mtime=0) if gz else data)
    return path


@pytest.fixture(params=[(e, c) for e in ENGINES for c in CHUNKS],
                ids=[f"{e}-{c}" for e in ENGINES for c in CHUNKS])
def blocks(request, monkeypatch) -> tuple[str, int]:
    """The block parser and block size the reader runs with."""
    engine, chunk = request.param
    monkeypatch.setattr(csvlog, "SMALL_BYTES", 0 if engine == "pandas" else 1 << 40)
    monkeypatch.setattr(csvlog, "CHUNK_BYTES", chunk)
    return engine, chunk


def _one_shot(path: Path, monkeypatch, **kw):
    """The whole file as one block, line by line (the reference)."""
    with monkeypatch.context() as m:
        m.setattr(csvlog, "SMALL_BYTES", 1 << 40)
        m.setattr(csvlog, "CHUNK_BYTES", 1 << 30)
        return read_csv(path, **kw)


def _table(raw) -> np.ndarray:
    return np.c_[raw.t, raw.acc["x"], raw.acc["y"], raw.acc["z"]]


def _same(raw, values: np.ndarray, lines) -> None:
    got = _table(raw)
    assert got.shape == values.shape and np.array_equal(got, values)
    assert np.asarray(raw.rows).tolist() == list(lines)
    assert raw.where(len(lines) - 1) == f"line {lines[-1]}"


def test_rows_straddling_blocks_give_the_one_shot_arrays(tmp_path, blocks, monkeypatch):
    values = _values(150 if blocks[1] < 4096 else 2000)
    path = _write(tmp_path / "a.csv", [",".join(HEADER)] +
                  [",".join(r) for r in _cells(values)])
    raw = read_csv(path)
    _same(raw, values, range(2, values.shape[0] + 2))
    ref = _one_shot(path, monkeypatch)
    assert np.array_equal(_table(raw), _table(ref)) and raw.notes == ref.notes
    assert isinstance(raw.rows, LineIndex) and raw.rows.starts.tolist() == [0]  # one run


def test_comment_and_blank_lines_keep_the_files_line_numbers(tmp_path, blocks):
    values = _values(220)
    lines, data_lines = ["# a logger's preamble", "", ",".join(HEADER)], []
    for k, row in enumerate(_cells(values)):
        if k % 37 == 5:
            lines.append("# a note in the middle")
        if k % 53 == 7:
            lines += ["", "   "]
        lines.append(",".join(row))
        data_lines.append(len(lines))
    lines.append("")  # a blank last line, as many loggers end
    raw = read_csv(_write(tmp_path / "c.csv", lines))
    _same(raw, values, data_lines)
    # a bad cell deep in the file: named by its own line
    bad = data_lines[200]
    lines[bad - 1] = lines[bad - 1].replace(lines[bad - 1].split(",")[2], "x12", 1)
    with pytest.raises(DataError, match=rf"line {bad}, column 'ay \(m/s\^2\)': 'x12' is not"):
        read_csv(_write(tmp_path / "bad.csv", lines))


@pytest.mark.parametrize("shape", ["short", "long"])
def test_a_row_of_another_length_deep_in_the_file_is_named(tmp_path, blocks, shape):
    values = _values(200)
    lines = [",".join(HEADER)] + [",".join(r) for r in _cells(values)]
    k = 166
    lines[k] = ",".join(lines[k].split(",")[:3]) if shape == "short" else lines[k] + ",1.0"
    cells = 3 if shape == "short" else 5
    with pytest.raises(DataError, match=rf"line {k + 1} has {cells} cells but the header has 4"):
        read_csv(_write(tmp_path / "r.csv", lines))


def test_gzip_is_decompressed_as_it_is_read(tmp_path, blocks):
    values = _values(150)
    lines = [",".join(HEADER)] + [",".join(r) for r in _cells(values)]
    path = _write(tmp_path / "z.csv.gz", lines, gz=True)
    seen = []
    raw = read_csv(path, progress=lambda done, total: seen.append((done, total)))
    _same(raw, values, range(2, 152))
    assert raw.notes["gzip"] is True
    size = path.stat().st_size  # progress counts the compressed bytes
    assert seen[-1] == (size, size) and all(t == size for _, t in seen)
    assert all(a[0] <= b[0] for a, b in zip(seen, seen[1:], strict=False))
    data = path.read_bytes()
    (tmp_path / "cut.csv.gz").write_bytes(data[:len(data) // 2])  # a transfer cut short
    with pytest.raises(DataError, match="cut.csv.gz: a damaged gzip file"):
        read_csv(tmp_path / "cut.csv.gz")


def test_crlf_and_bom(tmp_path, blocks):
    values = _values(150)
    lines = [",".join(HEADER)] + [",".join(r) for r in _cells(values)]
    raw = read_csv(_write(tmp_path / "w.csv", lines, newline="\r\n", bom=True))
    _same(raw, values, range(2, 152))
    assert raw.mapping["t"] == "t (s)"  # the BOM is not part of the first name
    lines[120] = lines[120].replace(",", ";", 1)
    with pytest.raises(DataError, match="line 121 has 3 cells but the header has 4"):
        read_csv(_write(tmp_path / "w2.csv", lines, newline="\r\n"))


def test_old_mac_line_ends(tmp_path, blocks):
    values = _values(100)
    lines = ["# from an old logger", ",".join(HEADER)] + [",".join(r) for r in _cells(values)]
    raw = read_csv(_write(tmp_path / "cr.csv", lines, newline="\r"))
    assert raw.n == 100  # the comment line and the header are not samples
    _same(raw, values, range(3, 103))


@pytest.mark.parametrize("sep", [";", "\t", "  "])
def test_decimal_comma_across_blocks(tmp_path, blocks, sep):
    values = _values(120)
    lines = [sep.join(h.replace(" ", "_") for h in HEADER) if sep == "  " else sep.join(HEADER)]
    lines += [(" " if sep == "  " else "") + sep.join(r)
              for r in _cells(values, decimal_comma=True)]
    raw = read_csv(_write(tmp_path / "d.csv", lines))
    _same(raw, values, range(2, 122))
    assert raw.notes["decimal"] == ","


def test_latin1_text_and_a_late_non_utf8_byte(tmp_path, blocks, monkeypatch):
    """The file is UTF-8 unless any of it is not; then all of it is Latin-1, as when it was
    decoded whole (:func:`calib.logs.csvlog.load_text`), however late the byte comes."""
    values = _values(150)
    body = [",".join(r) for r in _cells(values)]
    head = ",".join(HEADER + ["gz (°/s)"])
    body = [f"{ln},0.5" for ln in body]
    raw = read_csv(_write(tmp_path / "l1.csv", [head] + body, encoding="latin-1"))
    assert raw.gyro_unit == "deg/s" and np.array_equal(_table(raw), values)
    # ASCII header, a Latin-1 note deep in the file: read on, the same numbers
    late = [",".join(HEADER + ["gz (deg/s)"])] + body[:120] + ["# réglage"] + body[120:]
    path = tmp_path / "l2.csv"
    path.write_bytes("\n".join(late).encode("latin-1") + b"\n")
    raw = read_csv(path)
    assert np.array_equal(_table(raw), values) and raw.where(120) == "line 123"
    # a UTF-8 header, then a Latin-1 byte: the whole file is Latin-1 (its header too)
    utf8 = [head] + body[:120] + ["# réglage"] + body[120:]
    path = tmp_path / "l3.csv"
    path.write_bytes("\n".join(utf8[:121]).encode() + b"\n" +
                     "\n".join(utf8[121:]).encode("latin-1") + b"\n")
    assert "Â°/s" in load_text(path).splitlines()[0]
    with pytest.raises(DataError, match="Â°/s"):
        read_csv(path)


def test_label_column_and_runs_of_spaces(tmp_path, blocks):
    values = _values(150)
    labels = [("a" if k < 60 else "moving" if k < 80 else "01") for k in range(150)]
    lines = ["  ".join(["label", "t", "ax_mps2", "ay_mps2", "az_mps2"])]
    lines += ["   " + "  ".join([lab, *r]) for lab, r in zip(labels, _cells(values),
                                                                strict=True)]
    raw = read_csv(_write(tmp_path / "s.txt", lines))
    assert np.array_equal(_table(raw), values) and raw.label.tolist() == labels
    assert raw.notes["delimiter"] == "spaces"


def test_text_cells_nan_and_yei(tmp_path, blocks):
    values = _values(150)
    lines = [",".join(HEADER)] + [",".join(r) for r in _cells(values)]
    lines[101] = lines[101].replace(lines[101].split(",")[1], "nan", 1)  # sample 100
    raw = read_csv(_write(tmp_path / "n.csv", lines))
    assert np.isnan(raw.acc["x"][100]) and np.sum(np.isnan(raw.acc["x"])) == 1
    with pytest.raises(DataError, match=r"1 NaN/Inf value\(s\), first at line 102"):
        read_log(tmp_path / "n.csv", LogOptions(detect=False))
    yei = ['# Data format: "%int(ChipTimeUS),%float(RawAccelX),%float(RawAccelY),'
           '%float(RawAccelZ)"']
    us = [f"{1_000_000 + 10_000 * k},{r[1]},{r[2]},{r[3]}" for k, r in
          enumerate(_cells(values))]
    raw = read_csv(_write(tmp_path / "yei.csv", yei + us))
    assert np.array_equal(raw.t, (1_000_000 + 10_000 * np.arange(150)) * 1e-6)
    assert np.array_equal(raw.acc["y"], values[:, 2]) and raw.where(0) == "line 2"


def test_progress_reports_the_files_bytes(tmp_path, blocks):
    values = _values(150)
    path = _write(tmp_path / "p.csv", [",".join(HEADER)] + [",".join(r)
                                                             for r in _cells(values)])
    seen = []
    read_csv(path, progress=lambda done, total: seen.append((done, total)))
    size = path.stat().st_size
    assert seen and seen[-1] == (size, size) and all(t == size for _, t in seen)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    if blocks[1] < 4096:  # one report per block
        assert len(seen) > 3


def test_rows_longer_than_the_first_ones_grow_the_columns(tmp_path, monkeypatch):
    """The columns are sized from the first block's bytes per row; a file whose rows get
    shorter holds more rows than that: the columns grow in place, values unchanged."""
    monkeypatch.setattr(csvlog, "SMALL_BYTES", 0)
    monkeypatch.setattr(csvlog, "CHUNK_BYTES", 2048)
    long = _values(40)
    short = np.c_[np.arange(3000.0), np.zeros((3000, 3))]
    values = np.r_[long, short]
    lines = [",".join(HEADER)] + [",".join(r) for r in _cells(long)]
    lines += [f"{int(r[0])},0,0,0" for r in short]
    raw = read_csv(_write(tmp_path / "g.csv", lines))
    assert np.array_equal(_table(raw), values)


def test_pandas_numbers_are_the_ones_float_reads(tmp_path, monkeypatch):
    """The block parser must read every number as ``float`` does (correctly rounded): random
    doubles over 40 decades, written with ``repr`` and with fewer digits."""
    monkeypatch.setattr(csvlog, "SMALL_BYTES", 0)
    rng = np.random.default_rng(7)
    n = 20_000
    x = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-20, 20, (n, 3))
    text = [[repr(float(v)) if k % 2 else f"{v:.7g}" for v in row]
            for k, row in enumerate(x)]
    lines = [",".join(HEADER)] + [",".join([str(k), *r]) for k, r in enumerate(text)]
    raw = read_csv(_write(tmp_path / "f.csv", lines))
    want = np.array([[float(c) for c in r] for r in text])
    assert np.array_equal(np.c_[raw.acc["x"], raw.acc["y"], raw.acc["z"]], want)


def test_line_index():
    index = LineIndex.from_lines([2, 3, 4, 9, 10, 12])
    assert index.starts.tolist() == [0, 3, 5] and index.lines.tolist() == [2, 9, 12]
    assert [index[i] for i in range(6)] == [2, 3, 4, 9, 10, 12] and index[-1] == 12
    assert np.asarray(index).tolist() == [2, 3, 4, 9, 10, 12] and len(index) == 6
    with pytest.raises(IndexError):
        index[6]
    assert len(LineIndex.from_lines([])) == 0


def test_a_long_logs_progress_goes_to_stderr_only(tmp_path, capsys, monkeypatch):
    """``import --json`` of a log counted as long (the threshold lowered to 0 bytes): the
    reading progress is on stderr, in MiB with a rate, and stdout is the one JSON object; a
    short log piped (stderr not a terminal) reports nothing."""
    import io
    import json

    from bench.cli import progress
    from tests.cli import run

    values = _values(600)  # still: one pose, read as a vehicle run (acel.mat)
    path = _write(tmp_path / "long.csv", [",".join(HEADER)] + [",".join(r)
                                                                for r in _cells(values)])
    assert progress.log_progress("import", path, io.StringIO()) is None
    monkeypatch.setattr(progress, "LONG_LOG_BYTES", 0)
    monkeypatch.setattr(csvlog, "CHUNK_BYTES", 4096)
    rc, out, err = run(capsys, "import", path, "--out", tmp_path / "o", "--json")
    assert rc == 0, err
    assert json.loads(out)["provenance"]["source"]["name"] == "long.csv"
    lines = [ln for ln in err.splitlines() if "reading long.csv" in ln]
    assert lines and all(ln.startswith("[import") for ln in lines)
    assert "KiB (100 %)" in lines[-1] and sum("(100 %)" in ln for ln in lines) == 1
    assert any("MiB/s, ETA" in ln for ln in lines)
    assert progress.log_progress("import", path, quiet=True) is None

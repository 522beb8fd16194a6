"""Readers that never guess (issue 31, item 6).

* A CSV row with more or fewer cells than the header is refused with its line number — also a
  row one cell longer, which was once read in part, and a short row hidden by a text column.
* A comma-separated file written with decimal commas is refused at its first row, saying so;
  ``;`` with decimal commas still reads.
* Unit suffixes: the ``_deg_per_s``, ``_rad_per_s``, ``_m_per_s2``, ``_mps2``, ``_g``, ``_mg``
  families are read; an explicit option wins over a unit text that is not read here (the
  option the message recommends works); a stated unit that contradicts ``--units`` or
  ``--time-unit`` is still refused.
* ``--time-unit s|ms|us|ns`` states a CSV time column's unit (nanosecond stamps without a
  header edit), through the library and the command line.
* A ROS 1 bag with flipped bytes ends in one line naming the file, never a traceback.

Each CSV case runs under both block parsers of :mod:`calib.logs.csvlog` (pandas' and the
line-by-line one).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from calib.input_rules import DataError
from calib.logs import csvlog
from calib.logs.csvlog import read_csv
from calib.logs.reader import LogOptions, read_log
from tests import logfixtures as fx
from tests.cli import one_line_error, run

N = 400
"""Samples of the still logs (100 Hz)."""


@pytest.fixture(params=["pandas", "lines"])
def engine(request, monkeypatch) -> str:
    monkeypatch.setattr(csvlog, "SMALL_BYTES", 0 if request.param == "pandas" else 1 << 40)
    monkeypatch.setattr(csvlog, "CHUNK_BYTES", 4096)
    return request.param


def _still(n: int = N, seed: int = 0) -> np.ndarray:
    """(n, 3) m/s²: a still sensor, gravity along -y."""
    rng = np.random.default_rng(seed)
    return rng.normal([0.0, -9.8, 0.05], 0.02, (n, 3))


def _write(path: Path, header: str, rows: list[str]) -> Path:
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def _rows(t: np.ndarray, *cols: np.ndarray, sep: str = ",") -> list[str]:
    return [sep.join(repr(float(v)) for v in row) for row in np.column_stack([t, *cols])]


# ---------------------------------------------------------------- cell counts
@pytest.mark.parametrize("change, cells", [("longer", 5), ("shorter", 3), ("empty", 1)])
def test_a_row_of_another_length_is_refused_with_its_line(tmp_path, engine, change, cells):
    rows = _rows(0.01 * np.arange(N), _still())
    k = 250  # data row k is line k + 2
    rows[k] = {"longer": rows[k] + ",0.0", "shorter": rows[k].rsplit(",", 1)[0],
               "empty": "  \t x"}[change]
    path = _write(tmp_path / "a.csv", "t,ax,ay,az", rows)
    with pytest.raises(DataError, match=rf"a.csv: line {k + 2} has {cells} cells but the "
                                        r"header has 4; repair or remove that line"):
        read_csv(path)


def test_a_short_row_behind_a_text_column_is_refused(tmp_path, engine):
    """A text column (here a note nobody reads) turns a missing cell into "" for pandas: the
    reader counts the cells instead of trusting the parsed table."""
    acc = _still()
    rows = [f"{r},note {k}" for k, r in enumerate(_rows(0.01 * np.arange(N), acc))]
    rows[300] = rows[300].rsplit(",", 1)[0]
    with pytest.raises(DataError, match="line 302 has 4 cells but the header has 5"):
        read_csv(_write(tmp_path / "n.csv", "t,ax,ay,az,note", rows))
    rows[300] += ",x"  # repaired: read, the note ignored
    raw = read_csv(_write(tmp_path / "n.csv", "t,ax,ay,az,note", rows))
    assert np.array_equal(raw.acc["y"], acc[:, 1])


def test_decimal_commas_in_a_comma_separated_file_are_refused(tmp_path, engine):
    t, acc = 0.01 * np.arange(N), _still()
    rows = [",".join(f"{v:.4f}".replace(".", ",") for v in row) for row in np.c_[t, acc]]
    with pytest.raises(DataError) as err:
        read_csv(_write(tmp_path / "dc.csv", "t,ax,ay,az", rows))
    line = str(err.value)
    assert "\n" not in line and "dc.csv: line 2 has 8 cells but the header has 4" in line
    assert "decimal commas in a comma-separated file?" in line and "';' or tab" in line
    # the same numbers with ';' between the columns: read, decimal commas noted
    semi = [";".join(f"{v:.4f}".replace(".", ",") for v in row) for row in np.c_[t, acc]]
    raw = read_csv(_write(tmp_path / "ok.csv", "t;ax;ay;az", semi))
    assert np.array_equal(raw.acc["x"], np.round(acc[:, 0], 4))
    assert raw.notes["decimal"] == ","
    # a row with one cell too many and decimal points: no decimal-comma hint
    rows = _rows(t, acc)
    rows[10] += ",1.5"
    with pytest.raises(DataError, match=r"line 12 has 5 cells but the header has 4; repair"):
        read_csv(_write(tmp_path / "one.csv", "t,ax,ay,az", rows))


# ---------------------------------------------------------------- units
@pytest.mark.parametrize("acc_head, factor", [
    ("ax_m_per_s2,ay_m_per_s2,az_m_per_s2", 1.0),
    ("acc_x_mps2,acc_y_mps2,acc_z_mps2", 1.0),
    ("ax_g,ay_g,az_g", 1 / 9.80665),
    ("ax_mg,ay_mg,az_mg", 1000 / 9.80665),
])
@pytest.mark.parametrize("gyro_head, scale", [("gx_deg_per_s,gy_deg_per_s,gz_deg_per_s",
                                               180 / np.pi),
                                              ("gyro_x_rad_per_s,gyro_y_rad_per_s,"
                                               "gyro_z_rad_per_s", 1.0)])
def test_unit_suffix_families(tmp_path, engine, acc_head, factor, gyro_head, scale):
    acc = _still()
    rate = np.random.default_rng(1).normal(0.0, 0.01, (N, 3))  # rad/s
    rows = _rows(0.01 * np.arange(N), acc * factor, rate * scale)
    path = _write(tmp_path / "u.csv", f"time_s,{acc_head},{gyro_head}", rows)
    log = read_log(path, LogOptions(detect=False))
    assert np.allclose(log.acc, acc[:, :2], rtol=1e-12, atol=1e-12)
    assert np.allclose(log.gyro, rate[:, 2], rtol=1e-12, atol=1e-15)


def test_the_option_wins_over_a_unit_text_not_read_here(tmp_path, engine):
    acc = _still()
    rate = np.random.default_rng(2).normal(0.0, 0.01, N)
    rows = _rows(0.01 * np.arange(N), acc, np.rad2deg(rate))
    # a suffix that once parsed as unit "s": now deg/s, with or without the option
    path = _write(tmp_path / "g.csv", "t,ax,ay,az,gyro_z_deg_per_s", rows)
    for gyro_unit in (None, "deg/s"):
        log = read_log(path, LogOptions(units="m/s2", gyro_unit=gyro_unit, detect=False))
        assert np.allclose(log.gyro, rate, rtol=1e-12, atol=1e-15)
    # a unit text not read here: refused naming the option, which then wins
    path = _write(tmp_path / "h.csv", "t,ax (furlongs),ay (furlongs),az (furlongs),"
                                      "gz (deg/h)", rows)
    with pytest.raises(DataError, match=r"unit 'furlongs' is not an acceleration unit.*--units"):
        read_log(path, LogOptions(gyro_unit="deg/s", detect=False))
    with pytest.raises(DataError, match=r"gyro column unit\(s\) deg/h not read here.*"
                                        r"--gyro-unit"):
        read_log(path, LogOptions(units="m/s2", detect=False))
    log = read_log(path, LogOptions(units="m/s2", gyro_unit="deg/s", detect=False))
    assert np.array_equal(log.acc, acc[:, :2]) and np.allclose(log.gyro, rate, rtol=1e-12)
    # a stated unit that contradicts the option: still refused
    path = _write(tmp_path / "s.csv", "t,ax (g),ay (g),az (g)", _rows(0.01 * np.arange(N),
                                                                       acc / 9.80665))
    with pytest.raises(DataError, match="states the acceleration in g but --units m/s2"):
        read_log(path, LogOptions(units="m/s2", detect=False))


def test_time_unit(tmp_path, engine):
    acc = _still()
    t_ns = 1_700_000_000_000_000_000 + 10_000_000 * np.arange(N, dtype=np.int64)
    rows = [f"{t},{r}" for t, r in zip(t_ns.tolist(), (",".join(repr(float(v)) for v in row)
                                                      for row in acc), strict=True)]
    path = _write(tmp_path / "ns.csv", "time,ax,ay,az", rows)
    with pytest.raises(DataError, match=r"reaches 1\.7e\+18 s.*or with --time-unit"):
        read_log(path, LogOptions(units="m/s2", detect=False))
    log = read_log(path, LogOptions(units="m/s2", time_unit="ns", detect=False))
    assert np.array_equal(log.t, t_ns.astype(float) * 1e-9)
    assert log.provenance["reader"]["time_unit"] == "ns (--time-unit)"
    ms = _write(tmp_path / "ms.csv", "time (ms),ax,ay,az",
                [f"{10 * k},{r}" for k, r in enumerate(rows[i].split(",", 1)[1]
                                                       for i in range(N))])
    with pytest.raises(DataError, match=r"'time \(ms\)' states the time in ms but "
                                        r"--time-unit ns; drop --time-unit or fix the header"):
        read_log(ms, LogOptions(units="m/s2", time_unit="ns", detect=False))
    log = read_log(ms, LogOptions(units="m/s2", time_unit="ms", detect=False))
    assert np.allclose(log.t, 0.01 * np.arange(N), rtol=1e-15, atol=1e-15)
    with pytest.raises(DataError, match="--time-unit min: expected one of s, ms, us, ns"):
        read_csv(path, time_unit="min")


def test_time_unit_on_the_command_line(tmp_path, capsys):
    acc = _still()
    t_ns = 1_700_000_000_000_000_000 + 10_000_000 * np.arange(N, dtype=np.int64)
    rows = [f"{t},{r}" for t, r in zip(t_ns.tolist(), (",".join(repr(float(v)) for v in row)
                                                      for row in acc), strict=True)]
    path = _write(tmp_path / "ns.csv", "time,ax (m/s^2),ay (m/s^2),az (m/s^2)", rows)
    rc, out, err = run(capsys, "import", path, "--time-unit", "ns", "--out", tmp_path / "o",
                       "--json")
    assert rc == 0, err
    doc = json.loads(out)  # stdout: the one JSON object, nothing else
    assert doc["provenance"]["reader"]["time_unit"] == "ns (--time-unit)"
    bag = fx.write_ros2(tmp_path / "bag")
    line = one_line_error(capsys, "import", bag, "--time-unit", "ns", "--out", tmp_path / "b")
    assert "--time-unit applies to CSV/TSV logs only" in line and "bag" in line


# ---------------------------------------------------------------- bags
def test_a_ros1_bag_with_flipped_bytes_is_refused_in_one_line(tmp_path, capsys):
    """Four bytes inverted at 30 places through a copy of a small ROS 1 bag: each copy is
    read (a flip inside a number) or refused with a DataError that names the file, on one
    line — never another exception. At least some flips land in record headers."""
    bag = fx.write_ros1(tmp_path / "x.bag")
    data = bag.read_bytes()
    path = tmp_path / "flipped.bag"

    def flip(off: int) -> None:
        damaged = bytearray(data)
        damaged[off:off + 4] = bytes(b ^ 0xFF for b in damaged[off:off + 4])
        path.write_bytes(bytes(damaged))

    refused = {}
    for off in np.linspace(13, len(data) - 4, 30).astype(int).tolist():
        flip(off)
        try:
            read_log(path)
        except DataError as exc:
            text = str(exc)
            assert text.startswith(f"{path}: ") and "\n" not in text, text
            refused[off] = text
    assert len(refused) >= 3
    inside = [off for off, text in refused.items() if "a damaged ROS bag: message" in text]
    assert inside
    # one of them through the command line: one error line, no traceback
    flip(inside[0])
    line = one_line_error(capsys, "import", path, "--out", tmp_path / "o")
    assert "flipped.bag: a damaged ROS bag: message" in line

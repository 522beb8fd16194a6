"""data/real/: the shipped real IMU logs are what their README says, and the independent
reference values of tests/reference/real_data.py are sane.

What is checked, file by file: listed in the README's checksum table (and nothing unlisted
shipped), sha256, row and byte counts as listed; every row parses with plain ``csv`` to
finite numbers with the header's number of cells; time strictly increasing without gaps; the
acceleration columns the reference reads are the ones the header names. Then the reference
numbers: each held pose is held (small scatter, gyro quiet), its norm is g within 5 % and its
vertical axis carries it; the turn-over really turns the sensor over; the six-position bias
and scale are plausible for a MEMS part (|scale| < 0.1, |bias| < 1 m/s²). The reference
formulas themselves are checked on a synthetic file with known bias and scale.
"""

from __future__ import annotations

import ast
import csv
import gzip
import hashlib
import math
import re
from pathlib import Path

import numpy as np
import pytest

from tests.reference import real_data as ref

REAL = ref.REAL_DIR
README = REAL / "README.md"
G = 9.80665  # m/s²: the checks below compare with standard gravity; local g differs < 0.3 %
LOGS = ("yei-3space-z-flip.csv", "ngimu-sensors.csv", "pololu-minimu9-x-flip.csv",
        "axivity-ax3-wrist-night.csv.gz")
AX3 = "axivity-ax3-wrist-night.csv.gz"


def _checksums() -> dict[str, tuple[str, int, int]]:
    """The README's checksum table: file -> (sha256, rows, bytes)."""
    text = README.read_text()
    section = text.split("## Checksums", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| `([^`]+)` \| `([0-9a-f]{64})` \| (\d+) \| (\d+) \|$", section, re.M)
    return {name: (digest, int(n), int(size)) for name, digest, n, size in rows}


CHECKSUMS = _checksums()


def test_readme_lists_exactly_the_shipped_files():
    shipped = {p.name for p in REAL.iterdir() if p.name not in ("README.md", ".gitattributes")}
    assert set(CHECKSUMS) == shipped
    assert set(LOGS) <= shipped


@pytest.mark.parametrize("name", sorted(CHECKSUMS))
def test_file_matches_its_checksum_rows_and_size(name):
    digest, rows, size = CHECKSUMS[name]
    data = (REAL / name).read_bytes()
    assert len(data) == size
    assert hashlib.sha256(data).hexdigest() == digest
    if name.endswith(".gz"):
        data = gzip.decompress(data)
    lines = data.splitlines()
    assert len(lines) - (ref.SPECS[name].header_lines if name in ref.SPECS else 0) == rows


def test_readme_pose_table_is_the_reference_spec():
    """The held poses the README documents are the ones the reference computes with."""
    section = README.read_text().split("## Held poses", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| `([^`]+)` \| `(\w+)` \| (\d+)–(\d+) \| ([^|]+) \|", section, re.M)
    documented = set()
    for f, pose, a, b, reads in rows:
        axis_up = re.fullmatch(r"(\w): ([+−])g", reads.strip())
        axis, sign = ((axis_up[1], 1 if axis_up[2] == "+" else -1) if axis_up else (None, 0))
        documented.add((f, pose, int(a), int(b), axis, sign))
    specified = {(f, p.name, p.start, p.stop, p.axis, p.sign)
                 for f in LOGS for p in ref.SPECS[f].poses}
    assert documented == specified


def test_readme_tilted_pose_readings_are_the_reference_means():
    """The README's "tilted: x …, y …, z … g" is each AX3 pose mean rounded to 0.01 g."""
    section = README.read_text().split("## Held poses", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| `([^`]+)` \| `(\w+)` \| [\d–]+ \| tilted: x ([+−][\d.]+), "
                      r"y ([+−][\d.]+), z ([+−][\d.]+) g \|", section, re.M)
    poses = ref.pose_means(REAL / AX3)["poses"]
    assert {pose for f, pose, *_ in rows if f == AX3} == set(poses)
    for _, pose, *reads in rows:
        for axis, text in zip("xyz", reads, strict=True):
            value = float(text.replace("−", "-"))
            assert abs(value - poses[pose]["mean"][axis] / ref.G_UNIT) <= 0.005 + 1e-9, (pose, axis)


def test_licence_copy_is_the_bsd_3_clause_notice():
    text = (REAL / "LICENSE-scikit-kinematics").read_text()
    assert "Copyright (C) 2016 Thomas Haslwanter" in text
    assert "Redistribution and use in source and binary forms" in text
    assert "Redistributions of source code must retain the above copyright" in text


@pytest.mark.parametrize("name", LOGS)
def test_log_parses_with_plain_csv(name):
    spec = ref.SPECS[name]
    with ref.open_text(REAL / name) as f:
        lines = list(csv.reader(f))
    header, body = lines[: spec.header_lines], lines[spec.header_lines:]
    width = len(header[-1])
    assert all(len(line) == width for line in body)
    table = np.array([[float(cell) for cell in line] for line in body])
    assert np.isfinite(table).all()
    for column, expected in zip(spec.acc_columns, spec.acc_names, strict=True):
        assert expected in header[-1][column]
    t = table[:, spec.time_column] * spec.time_to_s
    step = np.diff(t)
    assert (step > 0).all(), "time must increase strictly"
    assert step.max() < 1.5 * np.median(step), "a gap in the log"


@pytest.mark.parametrize("name", LOGS)
def test_each_held_pose_is_held_and_reads_g(name):
    result = ref.pose_means(REAL / name)
    assert result["units"]["mean"] == "m/s^2" and result["units"]["gyro_rms"] == "rad/s"
    assert result["poses"]
    for pose_name, pose in result["poses"].items():
        assert pose["n"] == pose["stop"] - pose["start"] >= 50, pose_name
        assert abs(pose["norm"] / G - 1) < result["norm_tolerance"], pose_name
        if pose["axis"] is not None:  # a tumble-test pose: that axis carries g
            vertical = pose["mean"][pose["axis"]]
            assert math.copysign(1, vertical) == pose["sign"], pose_name
            assert abs(vertical) > 0.98 * pose["norm"], pose_name  # within ~11° of vertical
        assert max(pose["std"].values()) < 0.05 * G, pose_name  # scatter of a held sensor
        if pose["gyro_rms"] is not None:  # the Pololu excerpt has no gyro column
            assert pose["gyro_rms"] < 0.02, pose_name  # rad/s: about 1 deg/s, not turning


def test_turn_over_turns_the_sensor_over():
    poses = ref.pose_means(REAL / "yei-3space-z-flip.csv")["poses"]
    up = np.array(list(poses["z_up"]["mean"].values()))
    down = np.array(list(poses["z_down"]["mean"].values()))
    angle = math.degrees(math.acos(up @ down / (np.linalg.norm(up) * np.linalg.norm(down))))
    assert angle > 170


def test_repeated_pose_repeats():
    """z up before and after the session: the same reading within 0.05 m/s² (5 mg)."""
    poses = ref.pose_means(REAL / "yei-3space-z-flip.csv")["poses"]
    for axis in "xyz":
        assert abs(poses["z_up"]["mean"][axis] - poses["z_up_end"]["mean"][axis]) < 0.05


@pytest.mark.parametrize(("name", "axis", "up", "down"), [
    ("yei-3space-z-flip.csv", "z", "z_up", "z_down"),
    ("pololu-minimu9-x-flip.csv", "x", "x_up", "x_down"),
])
def test_six_position_values_are_plausible(name, axis, up, down):
    result = ref.six_position(REAL / name, G)
    assert result["units"]["bias"] == "m/s^2" and result["units"]["scale"] == "1"
    assert set(result["axes"]) == {axis}  # only this axis is turned over in the log
    fit = result["axes"][axis]
    assert (fit["up"], fit["down"]) == (up, down)
    assert abs(fit["scale"]) < 0.1 and abs(fit["bias"]) < 1.0
    assert 0 < fit["bias_std"] < 0.01
    assert fit["scale_std"] == pytest.approx(fit["bias_std"] / G)


@pytest.mark.parametrize("name", ["ngimu-sensors.csv", AX3])
def test_no_up_and_down_pair_gives_no_six_position_axis(name):
    """One pose (NGIMU), or only tilted poses (AX3): no axis seen straight up and down."""
    assert ref.six_position(REAL / name, G)["axes"] == {}


def test_ax3_counts_are_whole_steps_of_four():
    """The README's quantization: counts per g 256, values multiples of 4 (15.6 mg steps)."""
    _, rows = ref.read_rows(REAL / AX3)
    counts = np.array(rows)[:, 1:4]
    assert np.array_equal(counts % 4, np.zeros_like(counts))
    assert ref.SPECS[AX3].acc_in_g == 1 / 256


def test_ax3_poses_are_distinct_and_span_every_axis():
    """Twelve holds in at least eight orientations more than 10° apart (there are eleven:
    p05 and p08 are 4.9° apart); along every axis the unit direction of gravity takes
    both signs (|component| > 0.05 each way), so a multi-position fit sees each axis from both
    sides; and the directions are not confined to one plane (which would make the smallest
    singular value of the 12×3 matrix of unit directions 0): it is > 0.5."""
    poses = ref.pose_means(REAL / AX3)["poses"]
    assert len(poses) == 12
    u = np.array([[p["mean"][a] for a in "xyz"] for p in poses.values()])
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    distinct: list[np.ndarray] = []
    for d in u:
        if all(math.degrees(math.acos(min(1.0, float(d @ e)))) > 10 for e in distinct):
            distinct.append(d)
    assert len(distinct) >= 8
    assert (u.max(axis=0) > 0.05).all() and (u.min(axis=0) < -0.05).all()
    assert np.linalg.svd(u, compute_uv=False).min() > 0.5


def _synthetic_yei(path: Path, scale: float, bias_g: float) -> None:
    """A file laid out like the YEI log with z = (1 + scale)·(±1 g) + bias in its poses and a
    ±0.01 g alternating pattern (zero mean over an even count) on every axis."""
    spec = ref.SPECS["yei-3space-z-flip.csv"]
    n = max(p.stop for p in spec.poses)
    z = np.zeros(n)
    for pose in spec.poses:
        z[pose.start:pose.stop] = (1 + scale) * pose.sign + bias_g
    wiggle = 0.01 * (-1.0) ** np.arange(n)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([f"c{i}" for i in range(10)])
        for i in range(n):
            acc = (wiggle[i], -wiggle[i], z[i] + wiggle[i])
            w.writerow([9000 * i, 0, 0, 0, 0, 0, 0, *(repr(float(a)) for a in acc)])


def test_six_position_formulas_on_known_bias_and_scale(tmp_path):
    spec = ref.SPECS["yei-3space-z-flip.csv"]
    assert all((p.stop - p.start) % 2 == 0 for p in spec.poses[:2])  # the wiggle averages out
    path = tmp_path / "yei-3space-z-flip.csv"
    _synthetic_yei(path, scale=0.02, bias_g=-0.003)
    z = ref.six_position(path, ref.G_UNIT)["axes"]["z"]
    assert z["scale"] == pytest.approx(0.02, abs=1e-12)
    assert z["bias"] == pytest.approx(-0.003 * ref.G_UNIT, abs=1e-12)
    # std of a ±0.01 g alternation over n samples (ddof=1): 0.01 g·sqrt(n/(n−1))
    up, down = (p.stop - p.start for p in spec.poses[:2])
    s = [0.01 * ref.G_UNIT * math.sqrt(n / (n - 1)) for n in (up, down)]
    assert z["bias_std"] == pytest.approx(0.5 * math.sqrt(s[0] ** 2 / up + s[1] ** 2 / down),
                                          rel=1e-9)


def test_g_unit_converts_logs_in_g_and_counts():
    """A command converting g with 9.8 m/s² is compared with ``g_unit=9.8``: means scale."""
    for name in ("yei-3space-z-flip.csv", "pololu-minimu9-x-flip.csv"):
        std = ref.pose_means(REAL / name)["poses"]
        low = ref.pose_means(REAL / name, g_unit=9.8)["poses"]
        for pose in std:
            for axis in "xyz":
                assert low[pose]["mean"][axis] == pytest.approx(
                    std[pose]["mean"][axis] * 9.8 / ref.G_UNIT, rel=1e-12)


def test_six_position_refuses_a_bad_g():
    with pytest.raises(ValueError, match="g must be"):
        ref.six_position(REAL / "yei-3space-z-flip.csv", 0.0)


def test_reference_module_is_independent_of_the_code_under_test():
    tree = ast.parse(Path(ref.__file__).read_text())
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            imported.add((node.module or "").split(".")[0])
    assert imported <= {"__future__", "csv", "functools", "gzip", "math", "dataclasses", "pathlib",
                        "numpy"}

"""data/real/: the shipped real IMU logs are what their README says, and the independent
reference values of tests/reference/real_data.py are sane.

What is checked, file by file: listed in the README's checksum table (and nothing unlisted
shipped), sha256, row and byte counts as listed; every row parses with plain ``csv`` to
finite numbers with the header's number of cells; time strictly increasing without gaps (a
log without times: its sample counter steps by exactly 1); the acceleration columns the
reference reads are the ones the header names; each licence copy is its notice. Then the
reference numbers: each held pose is held (small scatter, gyro quiet), its norm is g within
the log's tolerance (5 % unless the README says why not) and its vertical axis carries it; the
turn-over really turns the sensor over; the six-position bias and scale are plausible for a
MEMS part (|scale| < 0.1, |bias| < 1 m/s²). The imucal session's poses are the source's own
annotation, byte for byte the shipped JSON. The reference formulas themselves (six-position,
six-face least squares with its stds) are checked on synthetic files with known values.
"""

from __future__ import annotations

import ast
import csv
import gzip
import hashlib
import json
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
        "axivity-ax3-wrist-night.csv.gz", "imucal-ferraris-session.csv.gz")
AX3 = "axivity-ax3-wrist-night.csv.gz"
IMUCAL = "imucal-ferraris-session.csv.gz"
IMUCAL_LIST = "imucal-ferraris-session-list.json"


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


BSD_3 = ("Redistribution and use in source and binary forms",
         "Redistributions of source code must retain the above copyright")
MIT = ("MIT License",
       "Permission is hereby granted, free of charge, to any person obtaining a copy",
       "The above copyright notice and this permission notice shall be included in all\n"
       "copies or substantial portions of the Software.")


AGPL_3 = ("GNU AFFERO GENERAL PUBLIC LICENSE", "Version 3, 19 November 2007",
          "Everyone is permitted to copy and distribute verbatim copies")


@pytest.mark.parametrize(("name", "copyright_line", "terms"), [
    ("LICENSE-scikit-kinematics", "Copyright (C) 2016 Thomas Haslwanter", BSD_3),
    ("LICENSE-scikit-diveMove", "Copyright (C) 2007 Free Software Foundation, Inc.", AGPL_3),
    ("LICENSE-labda-accelerometers", "Copyright (c) 2025, Josef Heidler", BSD_3),
    ("LICENSE-imucal", "Copyright (c) 2018 MaD-Lab Erlangen", MIT),
])
def test_licence_copy_is_its_notice(name, copyright_line, terms):
    """Each licence file is the notice its licence requires to travel with the copies (BSD
    3-Clause, MIT; the AGPL's whole text), and the README names it for its files."""
    text = (REAL / name).read_text()
    assert copyright_line in text
    for words in terms:
        assert words in text
    assert f"[`{name}`]({name})" in README.read_text()


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
    if spec.time_column is None:  # a sample counter instead: no sample missing or repeated
        counter = table[:, spec.sample_column]
        assert counter[0] == 0 and (np.diff(counter) == 1).all()
    t = ref.times(spec, table)
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


def test_imucal_poses_are_the_source_annotation():
    """The six face holds of the imucal session are the source's own annotation, the shipped
    JSON: imucal takes ``data.iloc[start:end]`` (end exclusive, rows counted from 0 after the
    header, n_samples = row), the reference ``[start, stop)``. x_p: the x axis up, reading +g
    (imucal's FerrarisCalibration docstring: "x-acc measures +1g"); x_a: x down, −g. The three
    rotations (x_rot, y_rot, z_rot) are not held poses and are not used."""
    listed = json.loads((REAL / IMUCAL_LIST).read_text())
    assert set(listed) == {"x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_rot", "y_rot", "z_rot"}
    spec = ref.SPECS[IMUCAL]
    assert {p.name: (p.start, p.stop) for p in spec.poses} == {
        k: (v["start"], v["end"]) for k, v in listed.items() if not k.endswith("_rot")}
    for pose in spec.poses:
        assert (pose.axis, pose.sign) == (pose.name[0], +1 if pose.name[2] == "p" else -1)
    assert "annotation" in spec.pose_source


def test_imucal_readings_are_whole_steps_of_16_bit_counts():
    """The README's observation: every acceleration is a whole multiple of 9.81/2048 m/s²
    (16 bit at ±16 g, converted with g = 9.81) and every gyro reading of 2000/32768 deg/s
    (16 bit at ±2000 deg/s), none at a 16-bit limit."""
    _, rows = ref.read_rows(REAL / IMUCAL)
    table = np.array(rows)
    for columns, step in (((4, 5, 6), 9.81 / 2048), ((1, 2, 3), 2000 / 32768)):
        counts = table[:, list(columns)] / step
        assert np.abs(counts - np.round(counts)).max() < 1e-6
        assert np.abs(counts).max() < 32767


def test_imucal_six_position_covers_all_three_axes():
    result = ref.six_position(REAL / IMUCAL, G)
    assert set(result["axes"]) == {"x", "y", "z"}
    for axis, fit in result["axes"].items():
        assert (fit["up"], fit["down"]) == (f"{axis}_p", f"{axis}_a")
        assert abs(fit["scale"]) < 0.1 and abs(fit["bias"]) < 1.0


def test_six_face_scale_is_the_six_position_scale():
    """Six faces held once each: the least-squares K_aa is (m_up − m_down)/(2g), so its scale
    is the six-position scale; its bias is the mean of the six readings (module docstring)."""
    lsq = ref.six_face(REAL / IMUCAL, G)
    two = ref.six_position(REAL / IMUCAL, G)["axes"]
    params = dict(zip(lsq["param_names"], lsq["params"], strict=True))
    assert lsq["faces"] == ["x_p", "x_a", "y_p", "y_a", "z_p", "z_a"] and lsq["dof"] == 2
    poses = ref.pose_means(REAL / IMUCAL)["poses"]
    for axis in "xyz":
        assert params[f"scale_{axis}"] == pytest.approx(two[axis]["scale"], abs=1e-12)
        mean = np.mean([p["mean"][axis] for p in poses.values()])
        assert params[f"bias_{axis}"] == pytest.approx(mean, abs=1e-12)


def _synthetic_imucal(path: Path, b: np.ndarray, k: np.ndarray, g: float,
                      shift: dict[tuple[str, int], float]) -> None:
    """A gzip CSV laid out like the imucal session: in each face pose the readings
    ``b + g·K·u + shift`` (``shift[(pose, axis index)]`` m/s², default 0) with a ±0.02 m/s²
    alternation that sums to zero over the pose (the last sample of an odd pose is left out of
    it), zeros elsewhere."""
    spec = ref.SPECS[IMUCAL]
    n = max(p.stop for p in spec.poses) + 10
    acc = np.zeros((n, 3))
    for pose in spec.poses:
        u = np.zeros(3)
        u["xyz".index(pose.axis)] = pose.sign
        m = b + g * k @ u + np.array([shift.get((pose.name, a), 0.0) for a in range(3)])
        length = pose.stop - pose.start
        wiggle = 0.02 * (-1.0) ** np.arange(length)
        if length % 2:
            wiggle[-1] = 0.0
        acc[pose.start:pose.stop] = m + wiggle[:, None] * np.array([1.0, -1.0, 1.0])
    lines = ["n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z"]
    lines += [f"{i},0,0,0," + ",".join(repr(float(v)) for v in acc[i]) for i in range(n)]
    path.write_bytes(gzip.compress(("\n".join(lines) + "\n").encode()))


def test_six_face_formulas_on_known_bias_scale_and_misalignment(tmp_path):
    """Exact readings: the fit returns b, K_aa − 1 and K_ab/K_aa to 1e-12 with zero residual
    scatter. Then both readings of axis z on the x faces are shifted by δ (a hold that read
    differently): b_z moves by δ/3, the residuals are +2δ/3 on the x pair and −δ/3 on the
    others, σ̂_z² = RSS/2 = 2δ²/3, std(b_z) = σ̂_z/√6 = δ/3; K is untouched."""
    g = 9.8
    b = np.array([0.5, -0.6, 0.4])
    k = np.array([[0.997, -0.013, -0.008], [0.007, 1.004, 0.003], [0.013, 0.002, 1.025]])
    path = tmp_path / IMUCAL
    _synthetic_imucal(path, b, k, g, {})
    fit = ref.six_face(path, g)
    params = dict(zip(fit["param_names"], fit["params"], strict=True))
    for a, axis in enumerate("xyz"):
        assert params[f"bias_{axis}"] == pytest.approx(b[a], abs=1e-12)
        assert params[f"scale_{axis}"] == pytest.approx(k[a, a] - 1, abs=1e-12)
        for j in (j for j in range(3) if j != a):
            assert params[f"misalignment_{axis}{'xyz'[j]}"] == pytest.approx(
                k[a, j] / k[a, a], abs=1e-12)
        assert fit["hold_sigma"][axis] < 1e-12
    # within-pose stds: the ±0.02 alternation, s²/n per pose mean, through the OLS weights
    assert 0 < max(fit["std_within"]) < 0.02

    delta = 0.03
    _synthetic_imucal(path, b, k, g, {("x_p", 2): delta, ("x_a", 2): delta})
    shifted = ref.six_face(path, g)
    p2 = dict(zip(shifted["param_names"], shifted["params"], strict=True))
    s2 = dict(zip(shifted["param_names"], shifted["std"], strict=True))
    assert p2["bias_z"] == pytest.approx(b[2] + delta / 3, abs=1e-12)
    assert s2["bias_z"] == pytest.approx(delta / 3, rel=1e-9)
    assert shifted["hold_sigma"]["z"] == pytest.approx(delta * math.sqrt(2 / 3), rel=1e-9)
    for name in ("scale_z", "misalignment_zx", "misalignment_zy", "bias_x", "bias_y"):
        assert p2[name] == pytest.approx(params[name], abs=1e-12), name
    resid = np.array(shifted["residuals"])[:, 2]
    np.testing.assert_allclose(resid, [2 * delta / 3] * 2 + [-delta / 3] * 4, atol=1e-12)


def test_six_face_needs_faces_along_every_axis():
    """The YEI log has z poses only: bias, scale and misalignment of three axes cannot be
    fitted from them, and the reference says so instead of returning numbers."""
    with pytest.raises(ValueError, match="do not identify"):
        ref.six_face(REAL / "yei-3space-z-flip.csv", G)


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

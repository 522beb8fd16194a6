"""Every command's terminal output fits 100 columns, on the course files and the README
examples, and its printed numbers carry units (issue 22, part 3).

Lines longer than 100 columns are broken at spaces by ``bench.cli.output.fit_columns``
(``main`` runs every command inside it), error lines included (issue 29); a single word wider
than 100 columns (a long path) stays whole on its own line. Error lines are checked on the fuzz
corpus's refusals in ``tests/test_error_lines.py``; these are the commands of a user who got the
inputs right.
"""

from __future__ import annotations

import doctest
import json
import re

from hypothesis import given
from hypothesis import strategies as st

from bench.cli import output
from bench.cli.output import COLUMNS, FitColumns, fit_line
from tests.cli import run, unwrap
from validation.fuzz.runner import wide_lines


def _fits(capsys, *argv) -> str:
    """Run ``tiltbench ARGV``: exit 0 or 1 (validate's FAIL), no line wider than 100
    columns on stdout or stderr; return stdout."""
    try:
        rc, out, err = run(capsys, *argv)
    except SystemExit as exc:  # --help
        cap = capsys.readouterr()
        rc, out, err = exc.code, cap.out, cap.err
    assert rc in (0, 1), err
    wide = wide_lines(out + err, COLUMNS)
    assert wide == [], f"{argv[0]}: {len(wide)} line(s) wider than {COLUMNS}: {wide[:2]}"
    return out


def test_fit_line_breaks_at_spaces_with_a_hanging_indent():
    line = "  " + " ".join(f"word{i:03d}" for i in range(40))
    parts = fit_line(line)
    assert len(parts) > 1 and all(len(p) <= COLUMNS for p in parts)
    assert parts[0].startswith("  word000") and all(p.startswith("      ") for p in parts[1:])
    assert " ".join(p.strip() for p in parts) == line.strip()  # no word lost or split
    path = "/" + "x" * 150  # a path wider than the terminal: whole, alone on its line
    assert fit_line(f"wrote: {path}") == ["wrote:", f"    {path}"]
    assert fit_line(f"tiltbench calibrate: error: {path}: file not found") == [
        "tiltbench calibrate: error:", f"    {path}:", "    file not found"]
    near = "/" + "y" * 95  # fits alone, not after its label: moved to the next line, whole
    assert fit_line(f"wrote: {near}") == ["wrote:", f"    {near}"]
    url = "https://example.org/" + "-".join(["a-long-anchor"] * 8)  # hyphens: no break
    assert fit_line(f"see {url} for the format of the file named above {'z' * 30}")[1] == (
        f"    {url}")
    assert doctest.testmod(output).failed == 0


WORDS = st.text(st.sampled_from("ab/-.:=…"), min_size=1, max_size=130)


@given(st.lists(WORDS, min_size=1, max_size=40), st.integers(0, 8))
def test_fit_line_never_loses_or_splits_a_word(words, indent):
    """Any line: the parts give back its words in order (unwrapped: the line itself), every
    part fits 100 columns or is one word alone, continuations indented 4 past the line."""
    line = " " * indent + " ".join(words)
    parts = fit_line(line)
    assert [w for p in parts for w in p.split()] == words
    assert wide_lines("\n".join(parts)) == []
    assert all(p.startswith(" " * (indent + 4)) for p in parts[1:])
    assert unwrap("\n".join(parts)) == line.strip()


def test_fit_columns_passes_carriage_return_redraws_through():
    import io

    sink = io.StringIO()
    s = FitColumns(sink)
    s.write("\r" + "#" * 120)  # a progress bar redrawn in place: untouched
    s.write("a" * 60 + " ")
    s.write("b" * 60 + "\n")
    s.close_pending()
    assert sink.getvalue() == "\r" + "#" * 120 + "a" * 60 + "\n    " + "b" * 60 + "\n"


def test_course_commands_fit(capsys, course_dir, tmp_path):
    d = course_dir
    common = ["--acel", d / "acel.mat", "--puntos", d / "puntos.mat", "--datos", d / "datos.txt"]
    _fits(capsys, "calibrate", d / "ensayo.mat", "--datos", d / "datos.txt",
          "--save", tmp_path / "cal.json")
    _fits(capsys, "trajectory", "--ensayo", d / "ensayo.mat", *common)
    out = _fits(capsys, "nmin", "--ensayo", d / "ensayo.mat", *common, "--confirm-runs", "0")
    assert "N ≥" in out
    _fits(capsys, "gap", d / "ensayo.mat", "--datos", d / "datos.txt")
    _fits(capsys, "generate", "course", "--seed", "1", "--out", tmp_path / "course")
    out = _fits(capsys, "validate", "--truth", tmp_path / "course" / "truth.json",
                "--calibration", tmp_path / "cal.json")
    head, *rows = [ln for ln in out.splitlines() if re.match(r"^(parameter|bias|scale)", ln)]
    assert "unit" in head.split() and "z (σ)" in head
    assert {r.split()[0]: r.split()[1] for r in rows} == {
        "bias_x": "m/s²", "scale_x": "1", "bias_y": "m/s²", "scale_y": "1"}


def test_readme_examples_fit(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _fits(capsys, "examples", "ex")
    _fits(capsys, "gap", "ex/data/misalignment/ensayo.mat", "--noise-var", "0.25,0.64",
          "--report", "gap-report")
    _fits(capsys, "generate", "calibration", "--count", "4001", "--effect",
          "tilt_offset:both:delta=0.02", "--seed", "1", "--out", "eff")
    _fits(capsys, "gap", "eff/ensayo.mat", "--noise-var", "0.25,0.64")
    _fits(capsys, "generate", "class", "--students", "2", "--seed", "7", "--out", "class",
          "--workers", "1")
    _fits(capsys, "design", "--runs", "0", "--count", "201", "--workers", "1")
    # the measured-data examples (README "Measured data")
    out = _fits(capsys, "calibrate", "ex/data/real/axivity-ax3-wrist-night.csv.gz", "--units",
                "counts", "--sensitivity", "256", "--min-hold", "100")
    assert "multi-position, 3 axes" in out
    out = _fits(capsys, "import", "ex/data/real/yei-3space-z-flip.csv", "--units", "g",
                "--gyro-unit", "rad/s", "--axes", "x,-z", "--min-hold", "0.5", "--poses",
                "0,0,180,0,0", "--angle-unit", "deg", "--out", "yei")
    assert "wrote: yei/ensayo.mat" in out
    for cmd in ("calibrate", "trajectory", "nmin", "gap", "fuse", "design", "fusion-study",
                "validate", "generate", "import", "noise"):
        _fits(capsys, cmd, "--help")


def test_fusion_study_prints_a_summary_and_names_the_full_table(capsys, tmp_path,
                                                                 monkeypatch):
    from bench import fusion_study

    monkeypatch.setattr(fusion_study, "SCENARIOS", fusion_study.SCENARIOS[:1])
    out = _fits(capsys, "fusion-study", "--runs", "2", "--workers", "1", "--out",
                tmp_path / "fs")
    assert "RMS error (m)" in out and "fusion-study.md" in out
    table = (tmp_path / "fs" / "fusion-study.md").read_text(encoding="utf-8")
    assert "mean NEES (band)" in table and max(map(len, table.splitlines())) > COLUMNS


def test_record_read_prints_units(capsys, course_dir, tmp_path):
    rrd = tmp_path / "c.rrd"
    _fits(capsys, "calibrate", course_dir / "ensayo.mat", "--datos", course_dir / "datos.txt",
          "--rrd", rrd)
    out = _fits(capsys, "record", "read", rrd)
    units = json.loads(run(capsys, "record", "read", rrd, "--json")[1])["estimates"]["units"]
    leaves = [ln.split(" = ", 1) for ln in out.splitlines() if " = " in ln]
    numbers = [(k.strip(), v) for k, v in leaves if re.match(r"^-?[\d.]+(e-?\d+)?\b", v)]
    assert numbers and units
    for key, value in numbers:
        if key.rsplit("/", 1)[-1] == "n":  # a sample count: no unit
            continue
        assert " " in value, f"{key} = {value}: no unit"
    got = dict(numbers)
    assert got["axes/x/bias"].endswith(" m/s²") and got["axes/x/cov/0/0"].endswith(" (m/s²)²")
    assert got["axes/x/cov/1/1"].endswith("(dimensionless)")

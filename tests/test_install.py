"""An installed tiltbench works like the README: the wheel carries every package (found by
discovery: ``bench*``, ``calib*``), the datasets and docs pages (and their pictures), and
nothing else (no ``validation``); ``tiltbench examples DIR`` writes the shipped files, and the
shell examples of the README and of every docs page name only files that exist after it (never
the checkout's ``data/``, which a ``pip install`` does not have). The README's tour runs, line
by line, from an empty folder.

The wheel is built once per module (``pip wheel --no-deps --no-build-isolation`` of a copy of
the sources with the test environment's setuptools, ≈ 5 s: no download). The slow test
installs it into a fresh venv whose dependencies come from this environment's site-packages
(a ``.pth`` line, no download), so tiltbench itself can only come from the wheel, and runs
every command's ``--help`` and one real run of each command there, from a temporary folder.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

from bench.cli import build_parser, main
from bench.cli.examples import FOLDERS, shipped_files
from tests.cli import unwrap

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> tuple[Path, str]:
    """The wheel built from a copy of the sources (the build leaves nothing in the
    checkout), and the build's log (``-v``: setuptools' own output, warnings included)."""
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    src.mkdir()
    for name in ("pyproject.toml", "setup.py", "README.md", "LICENSE"):
        shutil.copy(ROOT / name, src / name)
    for name in ("bench", "calib", "models", "validation", *FOLDERS):
        shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__"))
    # PYTHONDONTWRITEBYTECODE (set on some machines) makes distutils warn that it skips
    # byte-compiling: the environment's warning, not the package's
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    log = subprocess.run([sys.executable, "-m", "pip", "wheel", "-v", "--no-deps",
                          "--no-build-isolation", "-w", str(tmp), str(src)],
                         check=True, capture_output=True, text=True, env=env)
    (path,) = tmp.glob("tiltbench-*.whl")
    return path, log.stdout + log.stderr


@pytest.fixture(scope="module")
def wheel(built) -> zipfile.ZipFile:
    return zipfile.ZipFile(built[0])


def _sh_lines(page: Path = README) -> list[str]:
    """Command lines of a page's ```sh blocks (comments stripped)."""
    blocks = re.findall(r"^```sh\n(.*?)^```", page.read_text(encoding="utf-8"), re.S | re.M)
    return [ln.split("  #")[0].strip() for b in blocks for ln in b.splitlines()
            if ln.strip() and not ln.lstrip().startswith("#")]


SH_PAGES = [README] + [p for p in sorted((ROOT / "docs").glob("*.md")) if _sh_lines(p)]
"""The README and every docs page with shell examples (the README's details moved there)."""


def _help_texts(parser) -> list[str]:
    """The help of the parser and of every subcommand, recursively."""
    out = [parser.format_help()]
    for action in parser._actions:  # argparse keeps subparsers here only
        if hasattr(action, "choices") and isinstance(action.choices, dict):
            for sub in action.choices.values():
                out += _help_texts(sub)
    return out


def test_wheel_has_every_package_and_no_validation(wheel, built):
    """Discovery ships every package under bench/ and calib/ (``calib.design`` was once left
    out of a hand-written list), the test-side generator ``validation`` stays out, and the
    build prints no setuptools warning."""
    names = set(wheel.namelist())
    packages = sorted(p.parent.relative_to(ROOT).as_posix() for top in ("bench", "calib")
                      for p in (ROOT / top).rglob("__init__.py"))
    assert "calib/design" in packages
    missing = [p for p in packages if f"{p}/__init__.py" not in names]
    assert not missing, missing
    modules = sorted(p.relative_to(ROOT).as_posix() for top in ("bench", "calib")
                     for p in (ROOT / top).rglob("*.py") if "__pycache__" not in p.parts)
    assert set(modules) <= names, sorted(set(modules) - names)
    tops = {n.split("/", 1)[0] for n in names if not n.split("/", 1)[0].endswith(".dist-info")}
    assert tops == {"bench", "calib"}, tops
    log = built[1]
    assert "Successfully built tiltbench" in log
    warnings = [ln for ln in log.splitlines() if re.search(r"warn|would be ignored", ln, re.I)]
    assert not warnings, warnings[:5]


def test_wheel_carries_the_models_datasets_and_docs(wheel):
    """A non-editable install has no models/, data/ or docs/ beside bench/: the wheel carries
    them as bench/models, bench/data, bench/docs (every file ``tiltbench examples`` ships)."""
    names = set(wheel.namelist())
    models = {f"bench/models/{p.name}" for p in (ROOT / "models").glob("*.xml")}
    assert models and models <= names
    expected = {f"bench/{rel}" for rel in shipped_files()}
    assert any(n.startswith("bench/data/") for n in expected)
    assert any(n.startswith("bench/docs/") for n in expected)
    assert expected <= names, sorted(expected - names)


def test_recordings_are_an_extra(wheel):
    """rerun-sdk (≈ 0.65 GB) is not installed by ``pip install .``, only by the ``rrd`` extra."""
    (meta,) = [n for n in wheel.namelist() if n.endswith(".dist-info/METADATA")]
    requires = [ln for ln in wheel.read(meta).decode().splitlines()
                if ln.startswith("Requires-Dist: ")]
    rerun = [ln for ln in requires if "rerun-sdk" in ln]
    assert rerun and all('extra == "rrd"' in ln for ln in rerun)
    core = [ln for ln in requires if "extra ==" not in ln]
    assert any("mujoco[sysid]" in ln for ln in core)  # the gap workflow needs mujoco.sysid


def test_examples_writes_every_shipped_file_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "ex"
    assert main(["examples", str(out)]) == 0
    printed = unwrap(capsys.readouterr().out)  # "wrote: PATH" over 100 columns: two lines
    files = shipped_files()
    for rel, src in files.items():
        assert (out / rel).read_bytes() == src.read_bytes(), rel
        assert f"wrote: {out / rel}" in printed
    (out / "docs" / "gap.md").write_text("edited")
    assert main(["examples", str(out)]) == 2  # exists: nothing is written
    assert "pass --force" in unwrap(capsys.readouterr().err)
    assert (out / "docs" / "gap.md").read_text() == "edited"
    assert main(["examples", str(out), "--force"]) == 0
    assert (out / "docs" / "gap.md").read_bytes() == files["docs/gap.md"].read_bytes()


def test_examples_without_dir_names_where_they_are(capsys):
    assert main(["examples"]) == 0
    printed = capsys.readouterr().out
    assert all(f"{folder}/: " in printed for folder in FOLDERS)


def test_moved_shell_examples_are_still_checked():
    """The README kept a few real lines; the pages its details moved to are checked too."""
    names = {p.name for p in SH_PAGES}
    assert {"README.md", "install.md", "demo.md", "gap.md", "real-data.md"} <= names, names


@pytest.mark.parametrize("page", SH_PAGES, ids=lambda p: p.name)
def test_shell_examples_name_files_the_examples_command_writes(page, tmp_path, monkeypatch,
                                                               capsys):
    """Every shell line of the page that reads a shipped file reads it from the folder that
    ``tiltbench examples DIR`` (a line of the same page) wrote, so it runs from any directory;
    no line reads the checkout's ``data/`` or ``docs/``."""
    lines = [shlex.split(ln) for ln in _sh_lines(page) if ln.startswith("tiltbench ")]
    dirs = [argv[2] for argv in lines if argv[1] == "examples" and len(argv) > 2]
    if page == README:
        assert dirs, "the README never runs `tiltbench examples DIR`"
    monkeypatch.chdir(tmp_path)
    for d in dirs:
        assert main(["examples", d, "--force"]) == 0
    capsys.readouterr()
    shipped = tuple(f"{d}/{folder}/" for d in dirs for folder in FOLDERS)
    used = [tok for argv in lines for tok in argv if tok.startswith(shipped)]
    if page == README:
        assert any(tok.endswith("ensayo.mat") for tok in used)
    missing = [tok for tok in used if not Path(tok).is_file()]
    assert not missing, missing
    # a shipped-looking path (X/data/…, X/docs/…) whose X no `examples` line of the page wrote
    orphans = [tok for argv in lines for tok in argv
               if re.match(r"^[\w.-]+/(data|docs)/", tok) and not tok.startswith(shipped)]
    assert not orphans, f"{page.name}: run `tiltbench examples DIR` first: {orphans}"
    bare = [" ".join(argv) for argv in lines
            if any(tok.startswith(("data/", "docs/")) for tok in argv)]
    assert not bare, f"{page.name} lines that read the checkout's data/ or docs/: {bare}"


@pytest.mark.slow
def test_the_readme_tour_runs(tmp_path, monkeypatch, capsys):
    """Every ``tiltbench`` line of the README, in order, from an empty folder: exit 0, and the
    numbers the README quotes beside them are what the commands print."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    lines = [ln for ln in _sh_lines() if ln.startswith("tiltbench ")]
    assert len(lines) >= 6
    printed = {}
    for ln in lines:
        argv = shlex.split(ln)[1:]
        rc = main(argv)
        out, err = capsys.readouterr()
        assert rc == 0, f"{ln}: exit {rc}\n{err[-2000:]}"
        printed[argv[0]] = printed.get(argv[0], "") + out
    text = {cmd: " ".join(out.split()) for cmd, out in printed.items()}  # wrapped lines joined
    readme = " ".join(README.read_text(encoding="utf-8").split())
    assert "std 14.5 m × 24.7 m" in readme and "from (14.5, 24.7) m to (1.35, 1.56) m" in readme
    assert "std = (14.52, 24.66) m" in text["trajectory"] and "decision: C" in text["trajectory"]
    fused = re.search(r"final position \(.*?\) m, std \(([\d.]+), ([\d.]+)\) m", text["fuse"])
    assert [round(float(v), 2) for v in fused.groups()] == [1.35, 1.56]
    assert "0.0195 ± 0.0012 rad, hidden as 0.02 rad" in readme
    assert "misalignment (x): delta = 0.01952 ± 0.0012 rad" in text["gap"]
    assert "21 holds, 3 axes" in readme and "multi-position, 3 axes" in text["calibrate"]
    assert "21 poses" in text["calibrate"]


def test_docs_pages_named_by_help_and_readme_are_shipped():
    """``docs/X.md`` (or a picture, ``docs/images/X.png``) named by any --help text or the
    README is a file ``tiltbench examples`` writes (and the wheel carries)."""
    texts = _help_texts(build_parser()) + [README.read_text(encoding="utf-8")]
    named = {m for t in texts
             for m in re.findall(r"docs/[\w./-]+\.(?:md|png)", " ".join(t.split()))}
    assert "docs/images/demo-trajectory.png" in named
    assert named
    assert named <= set(shipped_files()), sorted(named - set(shipped_files()))


def test_missing_recording_extra_is_one_line(monkeypatch, capsys, tmp_path):
    """Without the ``rrd`` extra a command that records says which extra to install."""
    import bench.cli as cli

    def no_rerun(args):
        raise ModuleNotFoundError("No module named 'rerun'", name="rerun")

    parser_main = cli.main
    monkeypatch.setattr(cli, "build_parser", _parser_with_handler(cli.build_parser, no_rerun))
    rc = parser_main(["examples", str(tmp_path / "ex")])
    err = unwrap(capsys.readouterr().err).splitlines()
    assert rc == 2 and len(err) == 1 and 'pip install "tiltbench[rrd]"' in err[0]


def _parser_with_handler(build, handler):
    def patched(only=None):
        parser = build(only=only)
        parser.set_defaults(handler=handler)
        for action in parser._subparsers._group_actions:
            for sub in action.choices.values():
                sub.set_defaults(handler=handler)
        return parser
    return patched


# ---- the wheel in a fresh venv ----------------------------------------------------------------

COURSE = ["--ensayo", "course/ensayo.mat", "--acel", "course/acel.mat", "--puntos",
          "course/puntos.mat", "--datos", "course/datos.txt"]
RUNS = [  # one real run per command (small sizes), in order: later runs read earlier outputs
    ["examples", "ex"],
    ["generate", "calibration", "--count", "201", "--out", "cal", "--rrd", "cal.rrd", "--json"],
    ["generate", "vehicle", "--duration", "5", "--out", "veh", "--json"],
    ["generate", "course", "--count", "201", "--duration", "10", "--gps", "--out", "course",
     "--json"],
    ["generate", "class", "--students", "1", "--workers", "1", "--out", "class", "--json"],
    ["generate", "static", "--duration", "20", "--rate", "50", "--out", "st", "--json"],
    ["calibrate", "cal/ensayo.mat", "--save", "cal.json", "--json"],
    ["noise", "st/static.mat", "--json"],
    ["import", "ex/data/real/yei-3space-z-flip.csv", "--units", "g", "--gyro-unit", "rad/s",
     "--axes", "x,-z", "--min-hold", "0.5", "--poses", "0,0,180,0,0", "--angle-unit", "deg",
     "--out", "imp", "--json"],
    ["trajectory", *COURSE, "--json"],
    ["nmin", *COURSE, "--runs", "0", "--draws", "0", "--json"],
    ["design", "--designs", "uniform", "--count", "201", "--runs", "0", "--json"],
    ["fuse", *COURSE, "--gps", "course/gps.mat", "--json"],
    ["apply", "course/acel.mat", "--calibration", "cal.json", "--out", "corrected.csv",
     "--json"],
    ["fusion-study", "--runs", "2", "--workers", "1", "--out", "fs", "--quiet", "--json"],
    ["record", "read", "cal.rrd", "--json"],
    ["record", "entities", "cal.rrd"],
    ["validate", "--truth", "cal/truth.json", "--estimates", "est.json", "--json"],
    ["gap", "cal/ensayo.mat", "--noise-var", "0.25,0.64", "--json"],
    ["demo", "--out", "demo", "--course-data", "course", "--figures", "png", "--no-rrd",
     "--quiet", "--json"],
]

# Runs inside the fresh venv: where bench and calib come from, every command's --help (the
# parser's tree, so a new command is covered without editing this), then RUNS; one JSON line.
DRIVER = r'''
import contextlib, io, json, sys
import bench, calib
from bench.cli import build_parser, main

def commands(parser, path=()):
    for action in parser._actions:
        if hasattr(action, "choices") and isinstance(action.choices, dict):
            for name, sub in action.choices.items():
                yield (*path, name)
                yield from commands(sub, (*path, name))

def run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(argv)
        except SystemExit as exc:  # --help
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()

helps = {" ".join(c): run([*c, "--help"]) for c in [(), *commands(build_parser())]}
runs = []
for argv in json.loads(sys.argv[1]):
    rc, out, err = run(argv)
    if argv[0] == "calibrate":
        open("est.json", "w").write(out)
    runs.append({"argv": argv, "rc": rc, "out": out, "err": err[-500:]})
print(json.dumps({"prefix": sys.prefix, "bench": bench.__file__, "calib": calib.__file__,
                  "helps": {k: [rc, out[:200]] for k, (rc, out, err) in helps.items()},
                  "runs": runs}))
'''


@pytest.fixture(scope="module")
def fresh_venv(built, tmp_path_factory) -> Path:
    """A new venv with only the wheel installed; the dependencies (numpy, mujoco, rerun …)
    come from this environment's site-packages, added after the install by a ``.pth`` line
    (a plain path: this environment's own ``.pth`` files, its editable tiltbench among them,
    are not processed there)."""
    venv = tmp_path_factory.mktemp("venv") / "v"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "-q",
                    "--no-deps", "--no-index", str(built[0])], check=True, capture_output=True)
    purelib = subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_path("
                              "'purelib'))"], check=True, capture_output=True, text=True)
    deps = {sysconfig.get_path("purelib"), sysconfig.get_path("platlib")}
    Path(purelib.stdout.strip(), "_test_deps.pth").write_text("\n".join(sorted(deps)) + "\n")
    return venv


@pytest.mark.slow
def test_the_installed_wheel_runs_every_command(fresh_venv, tmp_path):
    """From a temporary folder, with the checkout nowhere on the path: ``bench`` and ``calib``
    are the wheel's copies in the new venv; ``tiltbench --help`` works as a script; every
    command's and subcommand's ``--help`` exits 0; one real run of every command and of every
    ``generate``/``record`` kind exits 0 (``design`` included, which a hand-written package
    list once left out)."""
    parser_commands = {name for name, _ in _subcommands(build_parser())}
    assert parser_commands == {argv[0] for argv in RUNS}, "give every command a run in RUNS"
    for group in ("generate", "record"):
        sub = dict(_subcommands(build_parser()))[group]
        assert {n for n, _ in _subcommands(sub)} == {a[1] for a in RUNS if a[0] == group}
    work = tmp_path / "run"
    work.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env["MPLBACKEND"] = "Agg"
    script = subprocess.run([fresh_venv / "bin" / "tiltbench", "--help"], cwd=work, env=env,
                            capture_output=True, text=True)
    assert script.returncode == 0 and "design" in script.stdout, script.stderr
    proc = subprocess.run([fresh_venv / "bin" / "python", "-c", DRIVER, json.dumps(RUNS)],
                          cwd=work, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    venv = Path(got["prefix"]).resolve()
    assert venv == fresh_venv.resolve()
    for pkg in ("bench", "calib"):
        assert Path(got[pkg]).resolve().is_relative_to(venv), got[pkg]
        assert not Path(got[pkg]).resolve().is_relative_to(ROOT)
    assert {"", "design", "generate calibration", "record read"} <= set(got["helps"])
    bad_help = {k: v for k, v in got["helps"].items() if v[0] != 0 or "usage:" not in v[1]}
    assert not bad_help, bad_help
    failed = [(" ".join(r["argv"]), r["rc"], r["err"]) for r in got["runs"] if r["rc"] != 0]
    assert not failed, failed
    by_cmd = {r["argv"][0]: r for r in got["runs"]}
    design = json.loads(by_cmd["design"]["out"])
    assert "units" in design
    demo = json.loads(by_cmd["demo"]["out"])
    assert "demo.rrd" not in demo["files"] and (work / "demo" / "report.md").is_file()
    assert by_cmd["demo"]["err"] == ""  # --no-rrd: no note
    assert (work / "ex" / "docs" / "design.md").is_file()


def _subcommands(parser) -> list[tuple[str, object]]:
    return [(name, sub) for action in parser._actions
            if hasattr(action, "choices") and isinstance(action.choices, dict)
            for name, sub in action.choices.items()]


@pytest.mark.slow
def test_demo_without_the_recording_extra_writes_everything_else(monkeypatch, capsys,
                                                                 tmp_path, course_dir):
    """A core install (rerun-sdk missing: ``sys.modules["rerun"] = None`` makes every import
    of it fail) gets every output but ``demo.rrd``, one note line on stderr naming the extra
    and ``--no-rrd``, and says so in the summary and the report; exit 0."""
    monkeypatch.setitem(sys.modules, "rerun", None)
    out = tmp_path / "demo"
    rc = main(["demo", "--out", str(out), "--course-data", str(course_dir), "--figures", "png",
               "--quiet"])
    printed = capsys.readouterr()
    assert rc == 0, printed.err
    err = printed.err.strip().splitlines()
    assert len(err) == 1, err
    assert "demo.rrd" in err[0] and 'pip install "tiltbench[rrd]"' in err[0]
    assert "--no-rrd" in err[0]
    assert not (out / "demo.rrd").exists()
    for name in ("estimates.json", "trajectory.json", "report.md", "figures/trajectory.png"):
        assert (out / name).is_file(), name
    assert "Recording (demo.rrd): skipped, rerun-sdk is not installed" in printed.out
    assert "Open the recording" not in printed.out
    assert "Recording (`demo.rrd`): skipped" in (out / "report.md").read_text()

"""An installed tiltbench works like the README: the wheel carries the datasets and docs pages,
``tiltbench examples DIR`` writes them, and the README's shell examples name only files that
exist after it (never the checkout's ``data/``, which a ``pip install`` does not have).

The wheel is built once (``pip wheel --no-deps`` of a copy of the sources, ≈ 5 s), as in
``tests/test_model.py``; nothing is installed.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from bench.cli import build_parser, main
from bench.cli.examples import FOLDERS, shipped_files

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> zipfile.ZipFile:
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"  # a copy, so the build leaves nothing in the checkout
    src.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(ROOT / name, src / name)
    for name in ("bench", "calib", "models", "validation", *FOLDERS):
        shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(tmp),
                    str(src)], check=True, capture_output=True)
    (path,) = tmp.glob("tiltbench-*.whl")
    return zipfile.ZipFile(path)


def _sh_lines() -> list[str]:
    """Command lines of the README's ```sh blocks (comments stripped)."""
    blocks = re.findall(r"^```sh\n(.*?)^```", README.read_text(encoding="utf-8"), re.S | re.M)
    return [ln.split("  #")[0].strip() for b in blocks for ln in b.splitlines() if ln.strip()]


def _help_texts(parser) -> list[str]:
    """The help of the parser and of every subcommand, recursively."""
    out = [parser.format_help()]
    for action in parser._actions:  # argparse keeps subparsers here only
        if hasattr(action, "choices") and isinstance(action.choices, dict):
            for sub in action.choices.values():
                out += _help_texts(sub)
    return out


def test_wheel_carries_the_datasets_and_docs(wheel):
    names = set(wheel.namelist())
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
    printed = capsys.readouterr().out
    files = shipped_files()
    for rel, src in files.items():
        assert (out / rel).read_bytes() == src.read_bytes(), rel
        assert f"wrote: {out / rel}" in printed
    (out / "docs" / "gap.md").write_text("edited")
    assert main(["examples", str(out)]) == 2  # exists: nothing is written
    assert "pass --force" in capsys.readouterr().err
    assert (out / "docs" / "gap.md").read_text() == "edited"
    assert main(["examples", str(out), "--force"]) == 0
    assert (out / "docs" / "gap.md").read_bytes() == files["docs/gap.md"].read_bytes()


def test_examples_without_dir_names_where_they_are(capsys):
    assert main(["examples"]) == 0
    printed = capsys.readouterr().out
    assert all(f"{folder}/: " in printed for folder in FOLDERS)


def test_readme_examples_name_files_the_examples_command_writes(tmp_path, monkeypatch, capsys):
    """Every README shell line that reads a shipped file reads it from the folder that
    ``tiltbench examples DIR`` (a line of the same README) wrote, so it runs from any
    directory; no line reads the checkout's ``data/``."""
    lines = [shlex.split(ln) for ln in _sh_lines() if ln.startswith("tiltbench ")]
    dirs = [argv[2] for argv in lines if argv[1] == "examples"]
    assert dirs, "the README never runs `tiltbench examples DIR`"
    monkeypatch.chdir(tmp_path)
    for d in dirs:
        assert main(["examples", d, "--force"]) == 0
    capsys.readouterr()
    shipped = tuple(f"{d}/{folder}/" for d in dirs for folder in FOLDERS)
    used = [tok for argv in lines for tok in argv if tok.startswith(shipped)]
    assert any(tok.endswith("ensayo.mat") for tok in used)
    missing = [tok for tok in used if not Path(tok).is_file()]
    assert not missing, missing
    bare = [" ".join(argv) for argv in lines
            if any(tok.startswith(("data/", "docs/")) for tok in argv)]
    assert not bare, f"README lines that read the checkout's data/ or docs/: {bare}"


def test_docs_pages_named_by_help_and_readme_are_shipped():
    """``docs/X.md`` named by any --help text or the README is a page ``tiltbench examples``
    writes (and the wheel carries)."""
    texts = _help_texts(build_parser()) + [README.read_text(encoding="utf-8")]
    named = {m for t in texts for m in re.findall(r"docs/[\w.-]+\.md", " ".join(t.split()))}
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
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and 'pip install "tiltbench[rrd]"' in err[0]


def _parser_with_handler(build, handler):
    def patched():
        parser = build()
        parser.set_defaults(handler=handler)
        for action in parser._subparsers._group_actions:
            for sub in action.choices.values():
                sub.set_defaults(handler=handler)
        return parser
    return patched

"""data/: the shipped datasets are what the bench makes with the commands data/README.md lists.

Each command is run again into a temporary folder; every variable of every .mat file must
equal the shipped one (to 1e-12, so that a MuJoCo/numpy patch release that moves the last bit
does not fail CI while a changed generator does) and truth.json must be the same apart from
the package versions. The gap workflow names what each README row says it names.
"""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from bench.cli import main
from bench.dataset import without_versions
from bench.gap import run_gap
from calib.files.course import read_ensayo

DATA = Path(__file__).resolve().parent.parent / "data"


def _commands() -> list[list[str]]:
    block = re.search(r"```sh\n(.*?)```", (DATA / "README.md").read_text(), re.S).group(1)
    return [shlex.split(line)[1:] for line in block.splitlines() if line.startswith("tiltbench ")]


def _out(argv: list[str]) -> str:
    return argv[argv.index("--out") + 1]


COMMANDS = _commands()


def test_every_shipped_folder_has_its_command():
    # real/ holds measured logs copied from their publishers (data/real/README.md), not made here
    shipped = {p.name for p in DATA.iterdir() if p.is_dir() and p.name != "real"}
    assert shipped == {_out(argv) for argv in COMMANDS}
    assert all((DATA / name / "truth.json").is_file() for name in shipped)


@pytest.mark.parametrize("argv", COMMANDS, ids=_out)
def test_shipped_dataset_is_what_the_command_makes(argv, tmp_path, capsys):
    name = _out(argv)
    argv = list(argv)
    argv[argv.index("--out") + 1] = str(tmp_path / name)
    assert main(argv) == 0
    capsys.readouterr()
    made, shipped = tmp_path / name, DATA / name
    assert sorted(p.name for p in made.iterdir()) == sorted(p.name for p in shipped.iterdir())
    for mat in sorted(shipped.glob("*.mat")):
        ours, theirs = scipy.io.loadmat(made / mat.name), scipy.io.loadmat(mat)
        keys = sorted(k for k in theirs if not k.startswith("__"))
        assert keys == sorted(k for k in ours if not k.startswith("__")), mat
        for key in keys:
            np.testing.assert_allclose(ours[key], theirs[key], rtol=0, atol=1e-12,
                                       err_msg=f"{mat}: {key}")
    truth = [json.loads((d / "truth.json").read_text()) for d in (made, shipped)]
    assert without_versions(truth[0]) == without_versions(truth[1])


@pytest.mark.parametrize("name, expected", [("misalignment", [("misalignment", "x")]),
                                            ("sweep-lever-arm", [("lever_arm", "x")]),
                                            ("positions", [])])
def test_gap_names_what_the_readme_says(name, expected):
    report = run_gap(read_ensayo(DATA / name / "ensayo.mat"), (0.25, 0.64), 9.8).to_dict()
    assert [(e["name"], e["axis"]) for e in report["effects"]] == expected

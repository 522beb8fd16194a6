"""Every Python snippet of the user docs runs as written.

The pages are ``docs/*.md`` and ``README.md``. On each page, the ```python blocks, in order and
in one namespace, are one program (a page may build its example over several blocks, as
``docs/python-api.md`` does; a block alone may be a fragment of it). Each page runs in a fresh
temporary folder holding only the course files the page names (``"ensayo.mat"``,
``"datos.txt"``, …), copied there first, as a reader would have them — nothing else, so a
snippet that needs a file it neither names nor writes fails, and one that writes without
``force`` cannot collide with an earlier run. What a page says is printed is: a ``# prints X``
comment in a block, and on ``docs/python-api.md`` the prose ``prints `X` `` and its ```text
blocks. No page cites the maintainers' DESIGN.md or STYLE.md, files a user of the repository
does not have.
"""

from __future__ import annotations

import contextlib
import io
import re
import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PAGES = sorted((REPO / "docs").glob("*.md")) + [REPO / "README.md"]
API_PAGE = REPO / "docs" / "python-api.md"


def _blocks(text: str, lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```", text, re.S | re.M)


def _named_inputs(code: str) -> set[str]:
    """File names the code quotes (``"ensayo.mat"``): the inputs to copy if they exist."""
    return set(re.findall(r"""["']([\w.-]+\.(?:mat|txt|json|csv))["']""", code))


def _claims(page: Path, text: str) -> list[str]:
    claims = [c.strip() for code in _blocks(text, "python")
              for c in re.findall(r"#\s*prints\s+(.+)$", code, re.M)]
    if page == API_PAGE:
        claims += re.findall(r"prints `([^`]+)`", text)
        claims += [ln for block in _blocks(text, "text") for ln in block.splitlines()
                   if ln.strip()]
    return claims


PYTHON_PAGES = [p for p in PAGES if _blocks(p.read_text(encoding="utf-8"), "python")]


def test_the_pages_with_python_are_found():
    names = {p.name for p in PYTHON_PAGES}
    assert {"python-api.md", "calibration-file.md", "montecarlo.md", "recordings.md"} <= names


@pytest.mark.parametrize("page", PYTHON_PAGES, ids=lambda p: p.name)
def test_python_snippets_run_as_written(page, tmp_path, monkeypatch, course_dir):
    text = page.read_text(encoding="utf-8")
    blocks = _blocks(text, "python")
    for name in sorted(_named_inputs("".join(blocks))):
        if (course_dir / name).is_file():
            shutil.copy(course_dir / name, tmp_path / name)
    given = {p.name for p in tmp_path.iterdir()}
    monkeypatch.chdir(tmp_path)
    ns: dict = {"__name__": "__docs__"}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        for i, code in enumerate(blocks):
            exec(compile(code, f"{page.name} python block {i + 1}", "exec"), ns)  # noqa: S102
    printed = out.getvalue()
    missing = [c for c in _claims(page, text) if c not in printed]
    assert not missing, f"{page.name} claims output that is not printed: {missing}"
    written = {p.name for p in tmp_path.iterdir()} - given
    if page == API_PAGE:
        assert "cal.json" in written  # the page writes into the current folder only
        assert len(blocks) >= 4


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_docs_cite_no_maintainer_files(page):
    text = page.read_text(encoding="utf-8")
    assert not re.search(r"DESIGN\.md|STYLE\.md", text), (
        f"{page.name} cites DESIGN.md/STYLE.md, which users do not have: point to "
        "docs/conventions.md")

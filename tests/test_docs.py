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

The README is a landing page (at most 12 KB): it opens with the two commands, shows one
picture, and its details live in ``docs/``; every link of the README and of the pages resolves,
every page is reachable from the README, and the synopsis of ``docs/commands.md`` lists every
command with options the command has.
"""

from __future__ import annotations

import contextlib
import io
import re
import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
PAGES = sorted((REPO / "docs").glob("*.md")) + [README]
API_PAGE = REPO / "docs" / "python-api.md"
README_MAX_BYTES = 12 * 1024
"""A landing page: the details belong in docs/."""
PICTURE_MAX_BYTES = 200_000


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
    if "data/real/" in "".join(blocks):  # the shipped real logs, where a clone has them
        shutil.copytree(REPO / "data" / "real", tmp_path / "data" / "real")
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


def _links(text: str) -> list[str]:
    """Targets of the Markdown links and images that are files (no URL, no bare anchor), without
    their ``#anchor``."""
    targets = re.findall(r"\]\(([^)\s]+)\)", text)
    return [t.split("#")[0] for t in targets if not re.match(r"^(?:[a-z]+:|#)", t)]


def test_readme_is_a_landing_page():
    """At most 12 KB; it opens with `make demo` and `make test`; one picture, a small PNG."""
    size = len(README.read_bytes())
    assert size <= README_MAX_BYTES, (
        f"README.md is {size} bytes (at most {README_MAX_BYTES}): move the details to docs/")
    text = README.read_text(encoding="utf-8")
    first = re.search(r"^```sh\n(.*?)^```", text, re.S | re.M)
    assert first and first.start() < text.index("\n## "), "the two commands come first"
    assert [ln.split()[:2] for ln in first.group(1).splitlines()] == [["make", "demo"],
                                                                    ["make", "test"]]
    (picture,) = re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", text)
    data = (REPO / picture).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) < PICTURE_MAX_BYTES, picture
    assert "tiltbench demo --out demo-out" in text  # the command that makes it is named


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_links_resolve(page):
    """Every relative link and image of the page is a file (relative to the page), and every
    ``docs/…`` file the README names in its text exists."""
    text = page.read_text(encoding="utf-8")
    missing = [t for t in _links(text) if not (page.parent / t).is_file()]
    if page == README:
        missing += [t for t in re.findall(r"docs/[\w./-]+\.(?:md|png)", text)
                    if not (REPO / t).is_file()]
    assert not missing, f"{page.name} links to files that do not exist: {missing}"


def test_every_docs_page_is_reachable_from_the_readme():
    seen, todo = set(), [README]
    while todo:
        page = todo.pop()
        if page in seen or page.suffix != ".md" or not page.is_file():
            continue
        seen.add(page)
        todo += [(page.parent / t).resolve() for t in _links(page.read_text(encoding="utf-8"))]
    pages = {p.resolve() for p in (REPO / "docs").glob("*.md")}
    unreachable = sorted(p.name for p in pages - seen)
    assert not unreachable, f"docs pages no link from the README leads to: {unreachable}"


def _commands(parser, path=()):
    """(command words, parser) of every command and subcommand."""
    for action in parser._actions:  # argparse keeps subparsers here only
        if hasattr(action, "choices") and isinstance(action.choices, dict):
            for name, sub in action.choices.items():
                yield (*path, name), sub
                yield from _commands(sub, (*path, name))


def test_the_commands_page_lists_every_command_with_real_options():
    """docs/commands.md's synopsis: one entry per command (leaf of the parser's tree), and
    every ``--option`` an entry names is an option of that command (a renamed option is
    caught here)."""
    from bench.cli import build_parser

    parser = build_parser()
    tree = dict(_commands(parser))
    leaves = {p for p in tree if not any(q[:len(p)] == p and q != p for q in tree)}
    text = (REPO / "docs" / "commands.md").read_text(encoding="utf-8")
    block = text.split("## Synopsis", 1)[1].split("```\n", 2)[1]
    entries = re.split(r"\n(?=tiltbench )", block.strip())
    listed, wrong = set(), {}
    for entry in entries:
        words = entry.split()[1:]
        path = ()
        while words and (*path, words[0]) in tree:
            path, words = (*path, words[0]), words[1:]
        sub = tree.get(path, parser)
        known = {o for a in sub._actions for o in a.option_strings}
        named = set(re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", entry))
        if named - known:
            wrong[" ".join(path) or "tiltbench"] = sorted(named - known)
        listed.add(path)
    assert not wrong, f"docs/commands.md names options the commands do not have: {wrong}"
    assert leaves <= listed, f"commands missing from docs/commands.md: {sorted(leaves - listed)}"

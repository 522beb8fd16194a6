"""The Python API page runs: every ```python block of ``docs/python-api.md`` is executed in
order, in one namespace, inside a temporary folder; what the page says is printed is."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

PAGE = Path(__file__).resolve().parents[1] / "docs" / "python-api.md"


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```", PAGE.read_text(encoding="utf-8"), re.S | re.M)


def test_python_api_page_runs_and_prints_what_it_says(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    blocks = _blocks("python")
    assert len(blocks) >= 4
    ns: dict = {"__name__": "__docs__"}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        for i, code in enumerate(blocks):
            exec(compile(code, f"{PAGE.name} python block {i + 1}", "exec"), ns)  # noqa: S102
    printed = out.getvalue()
    claims = re.findall(r"prints `([^`]+)`", PAGE.read_text(encoding="utf-8"))
    claims += [ln for block in _blocks("text") for ln in block.splitlines() if ln.strip()]
    missing = [c for c in claims if c not in printed]
    assert not missing, f"the page claims output that is not printed: {missing}"
    written = {p.name for p in tmp_path.iterdir()}
    assert "cal.json" in written  # the page writes into the current folder only

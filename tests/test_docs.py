"""Every Python block in docs/*.md runs (so the documentation cannot rot)."""

import re
from pathlib import Path

import pytest

from smd_statespace.effects import EFFECTS

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = sorted(path for path in DOCS.glob("*.md") if "```python" in path.read_text(encoding="utf-8"))


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_python_blocks_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    registered = dict(EFFECTS)
    blocks = re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S)
    namespace = {"__name__": f"docs_{page.stem}"}
    try:
        for block in blocks:
            exec(compile(block, str(page), "exec"), namespace)
    finally:
        EFFECTS.clear()
        EFFECTS.update(registered)

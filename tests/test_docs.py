"""Every example in README.md and docs/*.md runs (so the documentation cannot rot).

Two kinds of fenced blocks are executed, in page order, in one temporary working directory
per page (so a later block sees the files an earlier one wrote):

- ```` ```python ```` blocks: executed in one namespace per page; a block fenced
  ```` ```python file=NAME.py ```` is also written to ``NAME.py`` in that directory first (a file
  the page's commands use, e.g. ``--effects my_effects.py``);
- ```` ```console ```` blocks: every line that starts with ``$ smd-statespace`` is run through
  :func:`smd_statespace.cli.main` and must exit 0 (other lines are shown output).

Blocks fenced any other way (```` ``` ````, ```` ```text ````, ```` ```bash ````) are not run;
use them for set-up commands and printed output. Registered effects are restored after
each page, and matplotlib draws off-screen.
"""

import os
import re
import shlex
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

from smd_statespace.cli import main as cli_main  # noqa: E402
from smd_statespace.effects import EFFECTS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
FENCE = re.compile(r"^```(python|console)(?: file=(\S+))?\n(.*?)^```", flags=re.S | re.M)
PAGES = sorted(
    [path for path in DOCS.glob("*.md") if FENCE.search(path.read_text(encoding="utf-8"))
     and not (DOCS / "notebooks" / f"{path.stem}.ipynb").exists()]
    + [ROOT / "README.md"]
)
"""Pages whose examples run here; a tutorial with a notebook runs as that notebook (``test_notebooks.py``)."""


def blocks(page: Path):
    """``(kind, code, line, file)`` of every executed block of ``page`` (``file``: None or the name to write)."""
    text = page.read_text(encoding="utf-8")
    return [(m.group(1), m.group(3), text[:m.start()].count("\n") + 2, m.group(2)) for m in FENCE.finditer(text)]


def run_console(code: str, where: str):
    for line in code.splitlines():
        if not line.startswith("$ "):
            continue
        words = shlex.split(line[2:])
        assert words[0] == "smd-statespace", f"{where}: only smd-statespace commands are run, got {line!r}"
        status = cli_main(words[1:])
        assert status == 0, f"{where}: {line!r} exited {status}"


SLOW_PAGES = {"effects.md", "person.md"}
"""Pages whose examples take 20 s or more (record-level fits and diagnoses): CI runs them, the developer run
(``-m "not slow"``) does not."""


@pytest.mark.parametrize("page", [pytest.param(p, marks=pytest.mark.slow) if p.name in SLOW_PAGES else p
                                  for p in PAGES], ids=[p.name for p in PAGES])
def test_examples_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    registered = dict(EFFECTS)
    namespace = {"__name__": f"docs_{page.stem}"}
    try:
        for kind, code, line, file in blocks(page):
            where = f"{page.name}:{line}"
            if file:
                Path(file).write_text(code, encoding="utf-8")
            if kind == "python":
                exec(compile("\n" * (line - 1) + code, str(page), "exec"), namespace)
            else:
                run_console(code, where)
    finally:
        EFFECTS.clear()
        EFFECTS.update(registered)
        import matplotlib.pyplot as plt

        plt.close("all")


def test_every_page_is_reachable_from_the_index():
    index = (DOCS / "index.md").read_text(encoding="utf-8")
    missing = [p.name for p in DOCS.glob("*.md") if p.name != "index.md" and f"({p.name}" not in index]
    assert not missing, f"docs/index.md does not link to {missing}"

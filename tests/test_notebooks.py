"""The tutorials as Jupyter notebooks: in step with their Markdown pages, and every cell runs.

The notebooks (``docs/notebooks/``) are written from the tutorial pages by ``tools/notebooks.py``
(jupytext); a page edited without rewriting its notebook fails here. Each notebook's cells are
run in order in one namespace, in a temporary working directory, as a kernel would: Python cells
executed, ``!smd-statespace ...`` lines through the command line's entry point (exit status 0
required). The pages' own examples are therefore run here, not again by ``test_docs.py``.
"""

import ast
import importlib.util
import json
import os
import shlex
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

from smd_statespace.cli import main as cli_main  # noqa: E402
from smd_statespace.effects import EFFECTS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SLOW = {"tutorial-missing-physics"}
"""Notebooks whose cells take 20 s or more (record-level diagnoses): CI runs them, the developer run does not."""


def _tool():
    spec = importlib.util.spec_from_file_location("notebooks", ROOT / "tools" / "notebooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


notebooks = _tool()
PAGES = notebooks.tutorials()


def test_every_tutorial_has_its_notebook_in_step(capsys):
    assert PAGES, "no tutorial pages found"
    for page in PAGES:
        path = notebooks.path_of(page)
        assert path.exists(), f"{path} is missing: run python tools/notebooks.py"
        assert path.read_text(encoding="utf-8") == notebooks.text(page), (
            f"{path} is out of step with {page.name}: run python tools/notebooks.py")
    assert notebooks.main(["--check"]) == 0


def test_a_console_block_becomes_shell_lines_and_python_stays_code(tmp_path):
    page = tmp_path / "tutorial-x.md"
    page.write_text("# T\n\nText.\n\n```console\n$ smd-statespace demo --out d\nprinted line\n```\n\n"
                    "```python\nx = 1\n```\n", encoding="utf-8")
    cells = json.loads(notebooks.text(page))["cells"]
    assert [c["cell_type"] for c in cells] == ["markdown", "code", "code"]
    assert "".join(cells[1]["source"]) == "!smd-statespace demo --out d"
    assert "".join(cells[2]["source"]) == "x = 1"


def run_cells(path: Path):
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    namespace = {"__name__": f"notebook_{path.stem}"}
    for number, cell in enumerate(cells):
        if cell["cell_type"] != "code":
            continue
        source = "".join(cell["source"])
        where = f"{path.name}, cell {number}"
        if source.startswith("from IPython.display import Image, display"):
            # a kernel shows the figures inline; here (no IPython needed) each must have been written as a PNG
            shown = ast.literal_eval(source.split("for figure in ", 1)[1].split(":", 1)[0])
            for figure in shown:
                assert Path(figure).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", f"{where}: {figure} not written"
        elif source.startswith("!"):
            for line in source.splitlines():
                words = shlex.split(line[1:])
                assert words[0] == "smd-statespace", f"{where}: only smd-statespace commands are run"
                assert cli_main(words[1:]) == 0, f"{where}: {line!r} failed"
        else:
            exec(compile(source, where, "exec"), namespace)


@pytest.mark.parametrize("page", [pytest.param(p, marks=pytest.mark.slow) if p.stem in SLOW else p for p in PAGES],
                         ids=[p.stem for p in PAGES])
def test_notebook_runs(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    registered = dict(EFFECTS)
    try:
        run_cells(notebooks.path_of(page))
    finally:
        EFFECTS.clear()
        EFFECTS.update(registered)
        import matplotlib.pyplot as plt

        plt.close("all")

"""Write the tutorials as Jupyter notebooks for teaching, kept in step with their Markdown pages.

Each ``docs/tutorial-*.md`` becomes ``docs/notebooks/tutorial-*.ipynb`` through jupytext
(its Markdown format: ```` ```python ```` blocks are code cells, the prose Markdown cells), and
every ```` ```console ```` block becomes a code cell of ``!smd-statespace ...`` shell lines (the
shown output lines are left out: the notebook prints its own). A code cell that writes figures
(``"name.png"`` literals) is followed by one that shows them inline. The Markdown page stays the
source; ``tests/test_notebooks.py`` fails when a notebook is not what this script makes of
its page, and runs every notebook's cells.

Run from the repository root::

    python tools/notebooks.py            # rewrite docs/notebooks/*.ipynb
    python tools/notebooks.py --check    # exit 1 if a notebook is out of step with its page
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"
"""The repository's docs folder (this script lives in ``tools/``, beside it)."""

NOTEBOOKS = DOCS / "notebooks"
"""Where the notebooks are written."""

_CONSOLE = re.compile(r"^```console\n(.*?)^```[ \t]*\n?", flags=re.S | re.M)

_PNG = re.compile(r"""["']([\w./-]+\.png)["']""")
"""A figure file a code cell writes (a ``.png`` string literal): shown inline in the cell after it."""


def tutorials(docs: Path = DOCS) -> list[Path]:
    """The tutorial pages that have notebooks, in name order."""
    return sorted(docs.glob("tutorial-*.md"))


def notebook(page: Path):
    """The notebook of ``page`` (an ``nbformat`` notebook, nbformat 4.5 with stable cell ids)."""
    import jupytext
    from nbformat.v4 import new_code_cell, new_markdown_cell

    source = jupytext.read(page, fmt="md")
    cells = []
    for cell in source.cells:
        if cell.cell_type != "markdown":
            cells.append(new_code_cell(cell.source))
            figures = list(dict.fromkeys(_PNG.findall(cell.source)))
            if figures:  # the page's code writes them to files; the notebook also shows them, inline
                cells.append(new_code_cell("from IPython.display import Image, display\n\n"
                                           f"for figure in {figures!r}:\n    display(Image(figure))"))
            continue
        pieces = _CONSOLE.split(cell.source)
        for k, piece in enumerate(pieces):
            if k % 2 == 0:
                if piece.strip():
                    cells.append(new_markdown_cell(piece.strip("\n")))
                continue
            commands = ["!" + line[2:] for line in piece.splitlines() if line.startswith("$ ")]
            if commands:
                cells.append(new_code_cell("\n".join(commands)))
    for k, cell in enumerate(cells):
        cell.id = f"{page.stem}-{k:03d}"
    source.cells = cells
    source.metadata = {"kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
                       "language_info": {"name": "python"},
                       "smd_statespace": {"source": f"docs/{page.name}", "written_by": "tools/notebooks.py"}}
    return source


def text(page: Path) -> str:
    """The ``.ipynb`` file text of ``page``'s notebook."""
    import nbformat

    return nbformat.writes(notebook(page)) + "\n"


def path_of(page: Path, folder: Path = NOTEBOOKS) -> Path:
    """Where ``page``'s notebook lives."""
    return folder / f"{page.stem}.ipynb"


def main(argv=None) -> int:
    """Write (or with ``--check`` compare) every tutorial's notebook; return the exit status."""
    parser = argparse.ArgumentParser(prog="python tools/notebooks.py", description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="do not write; exit 1 if a notebook is out of date")
    args = parser.parse_args(argv)
    stale = []
    NOTEBOOKS.mkdir(exist_ok=True)
    for page in tutorials():
        wanted, path = text(page), path_of(page)
        if args.check:
            if not path.exists() or path.read_text(encoding="utf-8") != wanted:
                stale.append(str(path))
        else:
            path.write_text(wanted, encoding="utf-8")
            print(f"wrote {path}")
    if stale:
        print("out of step with their pages (run python tools/notebooks.py): " + ", ".join(stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

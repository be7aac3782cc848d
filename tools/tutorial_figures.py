"""Make the figures the tutorials show from the tutorials' own code, so that a page and its figure agree.

Each tutorial page writes figures in its ```` ```python ```` blocks (``plot_spectrum(person,
"spectrum_before_after.png")``); the page shows one of them from ``docs/figures/``. This script runs a
page's Python blocks and the ``$ `` lines of its ```` ```console ```` blocks in order, as the notebook
does, in a temporary folder, until every figure it shows has been written,
and copies them to ``docs/figures/`` under the names the page uses (:data:`FIGURES`). Run it after a
change that moves a tutorial's numbers (the notebook test, ``tests/test_notebooks.py``, checks the
numbers but not the picture), then look at the figures::

    python tools/tutorial_figures.py                              # every page of FIGURES
    python tools/tutorial_figures.py tutorial-missing-physics.md  # one page
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"

FIGURES = {
    "tutorial-identify.md": {"parameters.png": "tutorial_parameters.png"},
    "tutorial-compare.md": {"compare.png": "tutorial_compare.png"},
    "tutorial-floor.md": {"floor.png": "tutorial_floor.png"},
    "tutorial-structure.md": {"beam_crowd/structure_frf.png": "structure_frf.png",
                              "beam_crowd/structure_rms.png": "structure_rms.png",
                              "sdof_draws/structure_draws.png": "structure_draws.png"},
    "tutorial-missing-physics.md": {"spectrum_before_after.png": "tutorial_missing_spectrum.png",
                                    "held_out.png": "tutorial_missing_held_out.png"},
}
"""Per page: the file a code block writes -> the name it has in ``docs/figures/``."""

_BLOCK = re.compile(r"^```(python|console)\n(.*?)^```", flags=re.S | re.M)


def make_figures(page: str) -> list[Path]:
    """Run ``page``'s code and commands until its figures exist; copy them to ``docs/figures/``; return their paths."""
    wanted = FIGURES[page]
    blocks = _BLOCK.findall((DOCS / page).read_text(encoding="utf-8"))
    here = Path.cwd()
    with tempfile.TemporaryDirectory() as folder:
        os.chdir(folder)
        try:
            namespace = {"__name__": "__main__"}
            # the commands find this Python's smd-statespace, as the notebook's !-lines do in its kernel
            env = {**os.environ, "PATH": os.pathsep.join([str(Path(sys.executable).parent), os.environ["PATH"]])}
            for kind, block in blocks:  # the page's own code and commands, in the page's order
                if kind == "python":
                    exec(compile(block, page, "exec"), namespace)
                    continue
                for line in block.splitlines():
                    if line.startswith("$ "):
                        subprocess.run(line[2:], shell=True, check=True, stdout=subprocess.DEVNULL, env=env)
                if all(Path(name).exists() for name in wanted):
                    break
            missing = [name for name in wanted if not Path(name).exists()]
            if missing:
                raise SystemExit(f"{page}: its code wrote no {', '.join(missing)}; update FIGURES")
            written = []
            for name, target in wanted.items():
                written.append(Path(shutil.copy(name, DOCS / "figures" / target)))
            return written
        finally:
            os.chdir(here)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("pages", nargs="*", metavar="PAGE", help=f"tutorial pages (default all: {', '.join(FIGURES)})")
    args = parser.parse_args(argv)
    unknown = [page for page in args.pages if page not in FIGURES]
    if unknown:
        parser.error(f"no figures known for {', '.join(unknown)}; pages: {', '.join(FIGURES)}")
    os.environ.setdefault("MPLBACKEND", "Agg")
    for page in args.pages or list(FIGURES):
        for path in make_figures(page):
            print(f"{page}: wrote {path.relative_to(DOCS.parent)}", file=sys.stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main())

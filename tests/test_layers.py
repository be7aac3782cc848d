"""The package's layers hold: import-linter's contracts (setup.cfg) and no private name imported across packages.

The contracts (``[importlinter:contract:*]`` in setup.cfg): records at the bottom, then the model,
effects, estimators and the record-level person, answers (identify, diagnose, simulate,
population, studies), figures and the command line on top; a private module (``_name``) imported
only inside its own package; no import cycles between the modules of one folder. docs/index.md
("Layers") says where new code goes.
"""

import ast
from pathlib import Path

import pytest

import smd_statespace

importlinter_cli = pytest.importorskip("importlinter.cli", reason="import-linter is in the [test] extra")

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = Path(smd_statespace.__file__).resolve().parent


def test_the_import_contracts_hold(capsys):
    code = importlinter_cli.lint_imports(config_filename=str(ROOT / "setup.cfg"), no_cache=True, no_logo=True)
    out = capsys.readouterr().out
    assert code == 0, out
    assert "4 kept, 0 broken" in out


def imported_names(path: Path, package_dir: Path):
    """``(line, module imported from, name)`` of every ``from X import name`` of the package in ``path``."""
    module = ".".join(path.relative_to(package_dir.parent).with_suffix("").parts)
    package = module.removesuffix(".__init__") if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                source = ".".join(parts[:len(parts) - node.level + 1] + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            if source.split(".")[0] == package_dir.name:
                for alias in node.names:
                    yield node.lineno, source, alias.name


def top_package(module: str) -> str:
    """``smd_statespace.X`` of a module (``X`` a subpackage or a top-level module)."""
    return ".".join(module.split(".")[:2])


def private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def private_crossings(package_dir: Path) -> list:
    """``file:line: module.name`` of every private name (or a name from a private module) imported from another
    package than the importer's."""
    found = []
    for path in sorted(package_dir.rglob("*.py")):
        here = ".".join(path.relative_to(package_dir.parent).with_suffix("").parts)
        for line, source, name in imported_names(path, package_dir):
            if top_package(source) != top_package(here) and (private(name) or any(map(private, source.split(".")))):
                found.append(f"{path.relative_to(package_dir.parent)}:{line}: {source}.{name}")
    return found


def test_no_private_name_is_imported_across_packages():
    """A name with a leading underscore may be shared inside its package (``person``, ``simulation``, ...), never
    imported from another: what crosses a package boundary is public and documented."""
    assert private_crossings(PACKAGE) == []


def test_the_private_name_check_finds_crossings(tmp_path):
    """On a small package: a private name from a sibling package is found (relative and absolute imports, and a
    name from a private module); inside one package, or a public name, is not."""
    package = tmp_path / "smd_statespace"
    for folder in ("a", "b"):
        (package / folder).mkdir(parents=True)
        (package / folder / "__init__.py").write_text("")
    (package / "__init__.py").write_text("")
    (package / "b" / "n.py").write_text("_x = 1\ny = 2\n")
    (package / "b" / "_hidden.py").write_text("z = 3\n")
    (package / "b" / "m.py").write_text("from .n import _x\n")  # inside b: allowed
    (package / "a" / "m.py").write_text("from ..b.n import _x, y\nfrom smd_statespace.b.n import _x\n"
                                        "from ..b._hidden import z\n")
    assert private_crossings(package) == ["smd_statespace/a/m.py:1: smd_statespace.b.n._x",
                                          "smd_statespace/a/m.py:2: smd_statespace.b.n._x",
                                          "smd_statespace/a/m.py:3: smd_statespace.b._hidden.z"]


def test_matplotlib_is_imported_only_in_plotting():
    """Every figure is drawn in plotting/ (a result's plot method calls it there): no other module imports matplotlib."""
    outside = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.relative_to(PACKAGE).parts[0] == "plotting":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else [])
            outside += [f"{path.relative_to(PACKAGE.parent)}:{node.lineno}" for name in names
                        if name.split(".")[0] == "matplotlib"]
    assert outside == []

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


LONGEST_MODULE = 600
"""Lines of the longest module: a longer one holds more than one responsibility (issue 25)."""

LONGEST_FUNCTION = 80
"""Lines of code of the longest function or method, its docstring not counted (a public function's manual,
``simulate_bouncing``'s 186 lines of parameters and generators, is not code to split)."""


def code_lines(node) -> int:
    """Lines of a function from its ``def`` to its end, less its docstring's."""
    lines = node.end_lineno - node.lineno + 1
    first = node.body[0]
    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
        lines -= first.end_lineno - first.lineno + 1
    return lines


WHOLE = {"sensitivity_pass": "smd_statespace/person/sensitivity.py", "augmented_pass": "smd_statespace/person/kalman.py"}
"""Compiled loops kept in one function: split into compiled steps (functions of their own, or inlined by numba's
``inline="always"``) the same arithmetic ran 20-40 % (sensitivity_pass) and 5-13 % (augmented_pass) slower,
measured side by side in one process on 2026-11-27; they are most of the record-level search's time. The
particle filter's pass, split the same way, kept its speed (96-99 ns per particle-step either way) and is split."""


def oversized(package_dir: Path) -> list:
    """``file: N lines`` of every module over :data:`LONGEST_MODULE` and ``file:line name: N lines of code`` of every
    function over :data:`LONGEST_FUNCTION`."""
    found = []
    for path in sorted(package_dir.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        where = path.relative_to(package_dir.parent)
        if text.count("\n") > LONGEST_MODULE:
            found.append(f"{where}: {text.count(chr(10))} lines")
        for node in ast.walk(ast.parse(text)):
            if (isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and code_lines(node) > LONGEST_FUNCTION
                    and WHOLE.get(node.name) != where.as_posix()):
                found.append(f"{where}:{node.lineno} {node.name}: {code_lines(node)} lines of code")
    return found


def test_no_module_over_600_lines_and_no_function_over_80_lines_of_code():
    """One module, one responsibility; one function, one job (docs/index.md, "Layers")."""
    assert oversized(PACKAGE) == []


def test_the_size_check_finds_a_long_module_and_a_long_function(tmp_path):
    package = tmp_path / "smd_statespace"
    package.mkdir()
    body = "\n".join(f"    x{i} = {i}" for i in range(LONGEST_FUNCTION))
    documented = '    """' + "\n".join(["Docs."] * 200) + '"""\n'
    (package / "long.py").write_text(f"def long():\n{body}\n\n\ndef manual():\n{documented}    return 1\n")
    (package / "big.py").write_text("\n" * (LONGEST_MODULE + 1))
    assert oversized(package) == ["smd_statespace/big.py: 601 lines",
                                  f"smd_statespace/long.py:1 long: {LONGEST_FUNCTION + 1} lines of code"]

"""The generated references: the API reference builds from the docstrings, the CLI reference is current."""

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _load_tool(name):
    """A script of ``tools/`` (not part of the installed package) loaded as a module."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


docs_reference = _load_tool("docs_reference")


def test_api_reference_builds():
    """Every public object has a docstring griffe parses without warnings, with known sections only.

    And docs/api.md is what the docstrings give now: a new module, function or docstring change
    without regenerating the page fails, like docs/cli.md below.
    """
    text = docs_reference.build_api()
    for module in docs_reference.public_modules():
        assert f"## `{module}`" in text
    assert "### class `CycleRunner(" in text and "#### `SMDModel.transition(" in text
    assert (DOCS / "api.md").read_text(encoding="utf-8") == text, (
        "docs/api.md is out of date: run python tools/docs_reference.py")


def test_cli_reference_is_current():
    """docs/cli.md is exactly what the argument parser gives: a new option without regenerating fails."""
    assert (DOCS / "cli.md").read_text(encoding="utf-8") == docs_reference.build_cli(), (
        "docs/cli.md is out of date: run python tools/docs_reference.py")


def _visit(source):
    """A module of griffe objects made from ``source`` (as the reference tool sees the library's code)."""
    import griffe

    return griffe.visit("example", filepath=Path("example.py"), code=source, docstring_parser="numpy")


@pytest.mark.parametrize("mistake, message", [
    ('"""Summary.\n\n    Parameters\n    ----------\n    y : int\n        Not an argument.\n    """',
     "Parameter 'y' does not appear in the function signature"),
    ('"""Summary.\n\n    Weird Heading\n    -------------\n    text\n    """', "Unknown section Weird Heading"),
    (None, "no docstring"),
])
def test_a_broken_docstring_fails_the_build(mistake, message):
    source = "def f(x):\n    " + (mistake or "pass") + "\n"
    problems = []
    docs_reference.parse(_visit(source)["f"], "f", problems)
    assert problems and message in problems[0]


def test_qualified_section_heading_is_accepted():
    source = '''
class Example:
    """Summary.

    Attributes (after :meth:`run`)
    ------------------------------
    table_ : DataFrame
        The table.
    """
'''
    problems = []
    parsed = docs_reference.parse(_visit(source)["Example"], "Example", problems)
    assert problems == [] and parsed.qualifiers == {"Attributes": "after :meth:`run`"}
    assert "**Attributes (after `run`)**" in docs_reference.render_doc(parsed, "Example", 3)


def test_a_method_without_a_docstring_inherits_its_base_class_one():
    source = '''
class Base:
    """Base."""

    def slots(self):
        """The slots."""


class Child(Base):
    """Child."""

    def slots(self):
        return ()
'''
    import griffe

    with griffe.temporary_visited_module(source, docstring_parser="numpy") as module:  # bases resolve in a loader
        problems = []
        parsed = docs_reference.parse(module["Child"]["slots"], "Child.slots", problems, owner=module["Child"])
    assert problems == [] and "The slots." in docs_reference.render_doc(parsed, "slots", 4)


def test_check_mode_reports_a_stale_page(tmp_path, capsys):
    (tmp_path / "cli.md").write_text("stale\n", encoding="utf-8")
    (tmp_path / "api.md").write_text(docs_reference.build_api(), encoding="utf-8")
    assert docs_reference.main(["--docs", str(tmp_path), "--check"]) == 1
    assert "cli.md" in capsys.readouterr().err
    assert docs_reference.main(["--docs", str(tmp_path)]) == 0
    assert docs_reference.main(["--docs", str(tmp_path), "--check"]) == 0


def test_relative_links_in_docs_resolve():
    """Every relative link and image in README.md and docs/*.md points to a file that exists."""
    root = DOCS.parent
    broken = []
    for page in [root / "README.md", *sorted(DOCS.glob("*.md"))]:
        text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"^[a-z]+:", target) or target.startswith("#"):
                continue
            if not (page.parent / target.split("#")[0]).exists():
                broken.append(f"{page.name}: {target}")
    assert not broken, broken

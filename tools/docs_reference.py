"""Generate the API and command-line references in ``docs/`` (and check they are current).

Two Markdown pages are written from the code itself, so they cannot drift from it:

``docs/api.md``
    Every public module, class, function, method and documented constant of the
    library, loaded and parsed by `griffe <https://mkdocstrings.github.io/griffe/>`_
    (the library behind mkdocstrings; static analysis of the source, numpy-style
    docstrings), rendered to Markdown here. The build *fails* when a public
    function, class or method has no docstring (nor one to inherit), when griffe
    warns about a docstring (a ``Parameters`` entry the signature does not have,
    say) or when a docstring has a section numpydoc does not know.
``docs/cli.md``
    Every subcommand and option of ``smd-statespace``, from the argparse parser
    :func:`smd_statespace.cli.build_parser`.

Run from the repository root::

    python tools/docs_reference.py            # rewrite docs/api.md and docs/cli.md
    python tools/docs_reference.py --check    # exit 1 if either is out of date

``tests/test_reference.py`` runs the same build and comparison, so a broken
docstring or a new option without a regenerated reference fails the tests.
"""

from __future__ import annotations

import argparse
import io
import logging
import re
import sys
import textwrap
from contextlib import redirect_stdout
from pathlib import Path

PACKAGE = "smd_statespace"

DOCS = Path(__file__).resolve().parents[1] / "docs"
"""The repository's docs folder (this script lives in ``tools/``, beside it)."""

EXCLUDED_MODULES = ("smd_statespace.__main__", "smd_statespace.cli")
"""Modules left out of the API reference (the commands are documented in ``docs/cli.md``)."""

API_HEADER = """# API reference

Generated from the numpydoc docstrings with griffe by `python tools/docs_reference.py`; do not
edit by hand (the tests regenerate it and fail if it differs). Equation numbers are those of
Wang, Chen & Nagayama (2019); the [theory page](theory.md) maps them to this code, and the
[command-line reference](cli.md) lists the `smd-statespace` options.
"""

CLI_HEADER = """# Command-line reference

Generated from the argument parser (`smd_statespace.cli.build_parser`) by
`python tools/docs_reference.py`; do not edit by hand (the tests regenerate it and
fail if it differs). Errors are one line on stderr, `smd-statespace: error: ...`, with exit
status 2. Worked examples: [tutorial-identify.md](tutorial-identify.md).
"""

SECTIONS = ("Parameters", "Other Parameters", "Returns", "Yields", "Receives", "Raises", "Warns",
            "Attributes", "Methods")


class ReferenceError_(Exception):
    """The reference cannot be built: the message lists every offending object."""


# ---------------------------------------------------------------------------
# Loading the package with griffe and finding the public objects
# ---------------------------------------------------------------------------

ROOT = Path(__file__).resolve().parents[1]


def load(package: str = PACKAGE):
    """The package as griffe sees it: modules, classes, functions, attributes and their docstrings."""
    import griffe

    return griffe.load(package, docstring_parser="numpy", search_paths=[str(ROOT)])


def public_modules(package=None) -> list[str]:
    """Dotted names of the modules the API reference documents, packages first."""
    package = load() if package is None else package
    names = []

    def walk(module):
        name = module.path
        if any(part.startswith("_") for part in name.split(".")[1:]):
            return
        if any(name == excluded or name.startswith(excluded + ".") for excluded in EXCLUDED_MODULES):
            return
        names.append(name)
        for child in module.modules.values():
            walk(child)

    walk(package)
    return sorted(names, key=lambda n: (n.count("."), n))


def _kind(obj) -> str:
    return obj.kind.value


def public_members(module):
    """``(name, object)`` of a module's public classes and functions (aliases resolved).

    A module with ``__all__`` lists exactly those names (re-exports included);
    otherwise every non-underscore class or function defined in the module.
    """
    if module.exports is not None:
        names = [n if isinstance(n, str) else n.name for n in module.exports]
        members = [(n, module.members[n]) for n in names if not n.startswith("_") and n in module.members]
    else:
        members = [(n, m) for n, m in module.members.items() if not n.startswith("_") and not m.is_alias]
    out = []
    for name, member in members:
        target = _target(member)
        if target is not None and _kind(target) in ("class", "function"):
            out.append((name, member))
    return out


def _target(member):
    """What ``member`` is: itself, or the object an alias (an import) points at; None if griffe cannot tell."""
    import griffe

    try:
        return member.final_target if member.is_alias else member
    except griffe.AliasResolutionError:  # e.g. names bound by tuple unpacking, which griffe does not track
        return None


def documented_constants(module) -> list[tuple[str, str, str]]:
    """``(name, value, docstring)`` of the module's own attributes that have a docstring."""
    out = []
    for name, member in module.members.items():
        if name.startswith("_") or member.is_alias or _kind(member) != "attribute" or member.docstring is None:
            continue
        value = " ".join(str(member.value).split()) if member.value is not None else ""
        if len(value) > 70:
            value = value[:67] + "..."
        out.append((name, value, member.docstring.value))
    return out


def class_members(cls):
    """``(name, object, kind)`` of a class's own public methods and properties, in source order."""
    out = []
    for name, member in cls.members.items():
        if name.startswith("_") or member.is_alias:
            continue
        if _kind(member) == "function":
            out.append((name, member, "method"))
        elif _kind(member) == "attribute" and "property" in member.labels:
            out.append((name, member, "property"))
    return out


# ---------------------------------------------------------------------------
# Parsing and checking a docstring
# ---------------------------------------------------------------------------

KNOWN_ADMONITIONS = ("Notes", "References", "See Also", "Warnings", "Warning")
"""numpydoc sections that griffe keeps as free text (admonitions); any other heading is a mistake."""


def docstring(obj, owner=None):
    """``obj``'s docstring text, inherited from the same member of a base class of ``owner`` when it has none."""
    if obj.docstring is not None and obj.docstring.value.strip():
        return obj.docstring
    if owner is not None:
        for base in owner.mro():
            if obj.name in base.members and base.members[obj.name].docstring is not None:
                return base.members[obj.name].docstring
    return None


_QUALIFIED = re.compile(r"^(?P<title>" + "|".join(SECTIONS) + r") \((?P<note>[^)]*)\)\n(?P<rule>-+)$", re.M)


def _qualified_headings(doc: str):
    """Accept ``Attributes (after :meth:`run`)`` as the ``Attributes`` section, keeping the note for the title."""
    qualifiers = {}

    def plain(match):
        qualifiers[match.group("title")] = match.group("note")
        return match.group("title") + "\n" + "-" * len(match.group("title"))

    return _QUALIFIED.sub(plain, doc), qualifiers


class _Collect(logging.Handler):
    """Collects griffe's warnings while one docstring is parsed."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages = []

    def emit(self, record):
        self.messages.append(record.getMessage())


def parse(obj, where: str, problems: list, owner=None):
    """Parse ``obj``'s docstring with griffe; append problems (missing, griffe warnings, unknown sections).

    Returns the list of griffe docstring sections (with ``qualifiers``: notes of qualified
    headings such as ``Attributes (after :meth:`run`)``, shown in the section's title), or None.
    """
    import griffe

    found = docstring(obj, owner)
    if found is None:
        problems.append(f"{where}: no docstring")
        return None
    text, qualifiers = _qualified_headings(found.value)
    handler = _Collect()
    logger = logging.getLogger("griffe")
    logger.addHandler(handler)
    try:
        sections = griffe.Docstring(text, lineno=found.lineno, parent=obj, parser="numpy").parse()
    finally:
        logger.removeHandler(handler)
    for message in handler.messages:
        problems.append(f"{where}: {message.split(': ', 1)[-1]}")
    for section in sections:
        if section.kind.value == "admonition" and section.title not in KNOWN_ADMONITIONS:
            problems.append(f"{where}: Unknown section {section.title}")
    return _Parsed(sections, qualifiers)


class _Parsed:
    """griffe's sections of one docstring, by kind, with the notes of qualified headings."""

    TITLES = {"parameters": "Parameters", "other_parameters": "Other Parameters", "returns": "Returns",
              "yields": "Yields", "receives": "Receives", "raises": "Raises", "warns": "Warns",
              "attributes": "Attributes"}

    def __init__(self, sections, qualifiers):
        self.sections = sections
        self.qualifiers = qualifiers


# ---------------------------------------------------------------------------
# reST -> Markdown (the small subset the docstrings use)
# ---------------------------------------------------------------------------

_ROLE = re.compile(r":(?:py:)?(?:class|func|meth|attr|data|mod|obj|exc|ref|const):`~?([^`]+)`")
_LITERAL = re.compile(r"``([^`]+)``")


def _inline(text: str) -> str:
    def role(match):
        target = match.group(1)
        if "<" in target and target.endswith(">"):
            target = target.split("<")[0].strip()
        return f"`{target}`"

    return _LITERAL.sub(r"`\1`", _ROLE.sub(role, text))


def rst_to_markdown(lines) -> str:
    """Paragraphs, ``::`` literal blocks and simple tables of a docstring section as Markdown."""
    text = "\n".join(lines) if not isinstance(lines, str) else lines
    text = textwrap.dedent(text).strip("\n")
    if not text:
        return ""
    out = []
    blocks = re.split(r"\n\s*\n", text)
    literal_next = False
    for block in blocks:
        block_lines = block.split("\n")
        indented = all(line.startswith((" ", "\t")) or not line.strip() for line in block_lines)
        table = block_lines[0].lstrip().startswith(("===", "+--", ">>>"))
        if literal_next or indented or table:
            if out and out[-1].startswith("```") and out[-1].endswith("```") and indented:
                # continue the previous literal block across a blank line
                out[-1] = out[-1][:-3] + "\n" + textwrap.dedent(block) + "\n```"
            else:
                out.append("```\n" + textwrap.dedent(block).rstrip() + "\n```")
            literal_next = block.rstrip().endswith("::") and not indented
            continue
        paragraph = " ".join(line.strip() for line in block_lines)
        literal_next = paragraph.endswith("::")
        if paragraph.endswith(" ::"):
            paragraph = paragraph[:-3]
        elif literal_next:
            paragraph = paragraph[:-1]
        marker = re.compile(r"^\s*(?:[-*]|\d+\.) ")
        if marker.match(block_lines[0]):
            items, current = [], []
            for line in block_lines:
                if marker.match(line) and current:
                    items.append(" ".join(current))
                    current = []
                current.append(line.strip())
            items.append(" ".join(current))
            out.append("\n".join(_inline(item if not item.startswith("* ") else "- " + item[2:]) for item in items))
            continue
        out.append(_inline(paragraph))
    return "\n\n".join(out)


def module_prose(doc: str) -> str:
    """A module docstring as Markdown: free prose whose ``Title`` / ``-----`` headings become level-4 headings.

    Module docstrings are narrative (the numpy-style sections are for functions and classes), so
    they are not parsed into sections.
    """
    lines = doc.splitlines()
    out, chunk = [], []
    i = 0
    while i < len(lines):
        if i + 1 < len(lines) and lines[i].strip() and re.fullmatch(r"-{3,}|={3,}", lines[i + 1].strip()) \
                and len(lines[i + 1].strip()) >= len(lines[i].strip()) - 1 and not lines[i].startswith(" "):
            if chunk:
                out.append(rst_to_markdown(chunk))
                chunk = []
            out.append(f"#### {_inline(lines[i].strip())}")
            i += 2
            continue
        chunk.append(lines[i])
        i += 1
    if chunk:
        out.append(rst_to_markdown(chunk))
    return "\n\n".join(part for part in out if part)


def _section(title: str, params) -> str:
    if not params:
        return ""
    rows = []
    for p in params:
        name = p.name.replace("*", "\\*")
        head = f"`{name}`" if name else ""
        if p.type:
            head = f"{head} : {_inline(p.type)}" if head else _inline(p.type)
        desc = rst_to_markdown(p.desc).replace("\n\n", " ") if p.desc else ""
        if "```" in desc:  # keep literal blocks out of list items
            desc = " ".join(line for line in rst_to_markdown(p.desc).splitlines() if not line.startswith("```"))
        rows.append(f"- {head}" + (f" — {desc}" if desc else ""))
    return f"**{title}**\n\n" + "\n".join(rows)


def _items(title, items) -> str:
    rows = []
    for item in items:
        name = (getattr(item, "name", "") or "").replace("*", "\\*")
        annotation = getattr(item, "annotation", None)
        kind = str(annotation) if annotation else ""
        head = f"`{name}`" if name else ""
        if kind:
            head = f"{head} : {_inline(kind)}" if head else _inline(kind)
        desc = rst_to_markdown(item.description).replace("\n\n", " ") if item.description else ""
        if "```" in desc:  # keep literal blocks out of list items
            desc = " ".join(line for line in rst_to_markdown(item.description).splitlines()
                            if not line.startswith("```"))
        rows.append(f"- {head}" + (f" — {desc}" if desc else ""))
    return f"**{title}**\n\n" + "\n".join(rows) if rows else ""


def render_doc(parsed, heading: str, level: int) -> str:
    """One object's reference: heading, the text, then every section griffe parsed, in order."""
    parts = [f"{'#' * level} {heading}"]
    for section in parsed.sections:
        kind = section.kind.value
        if kind == "text":
            parts.append(rst_to_markdown(section.value))
        elif kind in _Parsed.TITLES:
            title = _Parsed.TITLES[kind]
            note = parsed.qualifiers.get(title)
            parts.append(_items(f"{title} ({_inline(note)})" if note else title, section.value))
        elif kind == "admonition":
            body = rst_to_markdown(section.value.description)
            if section.title == "See Also":
                body = " ".join(body.split("\n"))
            parts.append(f"**{section.title}**\n\n{body}")
        elif kind == "examples":
            body = "\n\n".join(rst_to_markdown(text) if k.value == "text" else f"```\n{text}\n```"
                                for k, text in section.value)
            parts.append(f"**Examples**\n\n{body}")
    return "\n\n".join(part for part in parts if part)


def _signature(name, obj) -> str:
    """``name(a, b=1, *args, **kw)`` from griffe's parameters (``self``/``cls`` dropped)."""
    target = obj.final_target if obj.is_alias else obj
    if _kind(target) == "class":
        init = target.members.get("__init__")
        for base in target.mro() if init is None else ():
            if "__init__" in base.members:
                init = base.members["__init__"]
                break
        if init is None:
            return f"{name}()"
        target = init
    pieces, star_done = [], False
    for parameter in target.parameters:
        if parameter.name in ("self", "cls") and not pieces:
            continue
        kind = parameter.kind.value
        text = parameter.name
        if kind == "variadic positional":
            text, star_done = "*" + text, True
        elif kind == "variadic keyword":
            text = "**" + text
        elif kind == "keyword-only" and not star_done:
            pieces.append("*")
            star_done = True
        if parameter.annotation is not None:
            text += f": {parameter.annotation}"
        if parameter.default is not None and not kind.startswith("variadic"):
            text += (" = " if parameter.annotation is not None else "=") + str(parameter.default)
        pieces.append(text)
    return f"{name}({', '.join(pieces)})"


# ---------------------------------------------------------------------------
# Building the pages
# ---------------------------------------------------------------------------


def _anchor(text: str) -> str:
    return re.sub(r"[^a-z0-9 _-]", "", text.lower()).replace(" ", "-")


def build_api() -> str:
    """The text of ``docs/api.md``; raises :class:`ReferenceError_` listing every docstring problem."""
    package = load()
    problems: list[str] = []
    sections = []
    contents = []
    for module_name in public_modules(package):
        module = package[module_name[len(PACKAGE) + 1:]] if module_name != PACKAGE else package
        parts = [f"## `{module_name}`"]
        contents.append(f"- [`{module_name}`](#{_anchor(module_name)})")
        if module.docstring is None:
            problems.append(f"{module_name}: no module docstring")
        else:
            parts.append(module_prose(module.docstring.value))
        constants = documented_constants(module)
        if constants:
            rows = ["| constant | value | meaning |", "|---|---|---|"]
            for name, value, doc in constants:
                meaning = _inline(" ".join(doc.split())).replace("|", "\\|")
                rows.append(f"| `{name}` | `{value.replace('|', '/')}` | {meaning} |")
            parts.append("\n".join(rows))
        for name, member in public_members(module):
            where = f"{module_name}.{name}"
            target = _target(member)
            if target.parent.path != module_name:
                origin = target.parent.path
                parts.append(f"### `{name}`\n\nRe-exported from [`{origin}`](#{_anchor(origin)}).")
                continue
            is_class = _kind(target) == "class"
            heading = f"class `{_signature(name, target)}`" if is_class else f"`{_signature(name, target)}`"
            doc = parse(target, where, problems)
            if doc is None:
                continue
            parts.append(render_doc(doc, heading, 3))
            if is_class:
                for member_name, child, kind in class_members(target):
                    member_doc = parse(child, f"{where}.{member_name}", problems, owner=target)
                    if member_doc is None:
                        continue
                    label = f"`{name}.{member_name}`" + (" (property)" if kind == "property" else "")
                    if kind == "method":
                        label = f"`{name}.{_signature(member_name, child)}`"
                    parts.append(render_doc(member_doc, label, 4))
        sections.append("\n\n".join(parts))
    if problems:
        raise ReferenceError_("the API reference cannot be built:\n  " + "\n  ".join(problems))
    return API_HEADER + "\n" + "\n".join(contents) + "\n\n" + "\n\n".join(sections).rstrip() + "\n"


def _help(parser) -> str:
    buffer = io.StringIO()
    with redirect_stdout(buffer):
        parser.print_help()
    return buffer.getvalue().rstrip()


def build_cli() -> str:
    """The text of ``docs/cli.md``: ``--help`` of the command and of every subcommand."""
    import os

    from smd_statespace.cli import build_parser

    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal; fix the width so the page is stable
    try:
        parser = build_parser()
        subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parts = [CLI_HEADER]
        names = list(subparsers.choices)
        parts.append("Commands: " + ", ".join(f"[`{n}`](#{n})" for n in names) + ".")
        parts.append("## smd-statespace\n\n```\n" + _help(parser) + "\n```")
        for name, sub in subparsers.choices.items():
            parts.append(f"## {name}\n\n```\n{_help(sub)}\n```")
    finally:
        if old is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = old
    return "\n\n".join(parts).rstrip() + "\n"


PAGES = {"api.md": build_api, "cli.md": build_cli}
"""Generated pages of ``docs/`` and the functions that build them."""


def main(argv=None) -> int:
    """Write (or with ``--check`` compare) the generated pages; return the exit status."""
    parser = argparse.ArgumentParser(prog="python tools/docs_reference.py", description=__doc__.split("\n")[0])
    parser.add_argument("--docs", default=str(DOCS), help=f"the docs directory (default: {DOCS})")
    parser.add_argument("--check", action="store_true", help="do not write; exit 1 if a page is out of date")
    args = parser.parse_args(argv)
    docs = Path(args.docs)
    stale = []
    for page, build in PAGES.items():
        try:
            text = build()
        except ReferenceError_ as exc:
            print(exc, file=sys.stderr)
            return 1
        path = docs / page
        if args.check:
            if not path.exists() or path.read_text(encoding="utf-8") != text:
                stale.append(str(path))
        else:
            path.write_text(text, encoding="utf-8")
            print(f"wrote {path}")
    if stale:
        print("out of date (run python tools/docs_reference.py): " + ", ".join(stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""Generate the API and command-line references in ``docs/`` (and check they are current).

Two Markdown pages are written from the code itself, so they cannot drift from it:

``docs/api.md``
    Every public module, class, function, method and documented constant of the
    library, from its numpydoc docstring, parsed with :mod:`numpydoc.docscrape`
    (numpydoc is in the ``test`` extra). The build *fails* when a public
    function, class or method has no docstring, when numpydoc cannot parse a
    docstring or warns about it (an unknown section, say), or when a
    ``Parameters`` section names an argument the signature does not have.
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
import ast
import importlib
import inspect
import io
import pkgutil
import re
import sys
import textwrap
import warnings
from contextlib import redirect_stdout
from pathlib import Path

PACKAGE = "smd_statespace"

DOCS = Path(__file__).resolve().parents[1] / "docs"
"""The repository's docs folder (this script lives in ``tools/``, beside it)."""

EXCLUDED_MODULES = ("smd_statespace.__main__", "smd_statespace.cli")
"""Modules left out of the API reference (the commands are documented in ``docs/cli.md``)."""

API_HEADER = """# API reference

Generated from the numpydoc docstrings by `python tools/docs_reference.py`; do not
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
# Finding the public objects
# ---------------------------------------------------------------------------


def public_modules() -> list[str]:
    """Names of the library's modules that the API reference documents, in import order."""
    package = importlib.import_module(PACKAGE)
    names = [PACKAGE]
    for info in pkgutil.walk_packages(package.__path__, prefix=PACKAGE + "."):
        name = info.name
        if any(part.startswith("_") for part in name.split(".")[1:]):
            continue
        if any(name == excluded or name.startswith(excluded + ".") for excluded in EXCLUDED_MODULES):
            continue
        names.append(name)
    return sorted(names, key=lambda n: (n.count("."), n))


def _is_own(obj, module) -> bool:
    return getattr(obj, "__module__", None) == module.__name__


def public_members(module):
    """``(name, object)`` of the module's public classes and functions.

    A module with ``__all__`` lists exactly those names (re-exports included);
    otherwise every non-underscore class or function defined in the module.
    """
    if hasattr(module, "__all__"):
        names = [n for n in module.__all__ if not n.startswith("_")]
        members = [(n, getattr(module, n)) for n in names]
        return [(n, obj) for n, obj in members if inspect.isclass(obj) or inspect.isfunction(obj)]
    members = []
    for name, obj in vars(module).items():
        if name.startswith("_") or not (inspect.isclass(obj) or inspect.isfunction(obj)):
            continue
        if _is_own(obj, module):
            members.append((name, obj))
    return members


def documented_constants(module) -> list[tuple[str, str, str]]:
    """``(name, value source, docstring)`` of module constants followed by a string literal."""
    try:
        tree = ast.parse(inspect.getsource(module))
    except (OSError, TypeError):  # pragma: no cover - source not available
        return []
    out = []
    body = tree.body
    for node, following in zip(body, body[1:]):
        if not isinstance(node, (ast.Assign, ast.AnnAssign)):
            continue
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        if len(targets) != 1 or not isinstance(targets[0], ast.Name) or targets[0].id.startswith("_"):
            continue
        if not (isinstance(following, ast.Expr) and isinstance(following.value, ast.Constant)
                and isinstance(following.value.value, str)):
            continue
        value = ast.get_source_segment(inspect.getsource(module), node.value) or ""
        value = " ".join(value.split())
        if len(value) > 70:
            value = value[:67] + "..."
        out.append((targets[0].id, value, inspect.cleandoc(following.value.value)))
    return out


def class_members(cls):
    """``(name, object, kind)`` of a class's own public methods and properties, in source order."""
    out = []
    for name, raw in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(raw, property):
            out.append((name, raw, "property"))
        elif isinstance(raw, (staticmethod, classmethod)):
            out.append((name, raw.__func__, "method"))
        elif inspect.isfunction(raw):
            out.append((name, raw, "method"))
    return out


# ---------------------------------------------------------------------------
# Parsing and checking a docstring
# ---------------------------------------------------------------------------


def docstring(obj, owner=None):
    """``obj``'s docstring, inherited from the same member of a base class of ``owner`` when it has none."""
    doc = inspect.getdoc(obj.fget if isinstance(obj, property) else obj)
    if (not doc or not doc.strip()) and owner is not None:
        name = (obj.fget if isinstance(obj, property) else obj).__name__
        for base in owner.__mro__[1:]:
            if name in vars(base):
                raw = vars(base)[name]
                doc = inspect.getdoc(raw.fget if isinstance(raw, property) else raw)
                if doc:
                    break
    return doc


_QUALIFIED = re.compile(r"^(?P<title>" + "|".join(SECTIONS) + r") \((?P<note>[^)]*)\)\n(?P<rule>-+)$", re.M)


def _qualified_headings(doc: str):
    """Accept ``Attributes (after :meth:`run`)`` as the ``Attributes`` section, keeping the note for the title."""
    qualifiers = {}

    def plain(match):
        qualifiers[match.group("title")] = match.group("note")
        return match.group("title") + "\n" + "-" * len(match.group("title"))

    return _QUALIFIED.sub(plain, doc), qualifiers


def parse(obj, where: str, problems: list, owner=None):
    """Parse ``obj``'s docstring with numpydoc; append problems (missing, warnings, errors) to ``problems``.

    Section headings may carry a note in brackets (``Attributes (after :meth:`run`)``); the note
    is kept in ``parsed.qualifiers`` and shown in the section's title.
    """
    from numpydoc.docscrape import NumpyDocString

    doc = docstring(obj, owner)
    if not doc or not doc.strip():
        problems.append(f"{where}: no docstring")
        return None
    doc, qualifiers = _qualified_headings(doc)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            parsed = NumpyDocString(doc)
        except Exception as exc:  # numpydoc raises ValueError and friends on malformed sections
            problems.append(f"{where}: numpydoc cannot parse the docstring: {exc}")
            return None
    for warning in caught:
        problems.append(f"{where}: numpydoc: {warning.message}")
    parsed.qualifiers = qualifiers
    if callable(obj) and not isinstance(obj, property):
        _check_parameters(obj, parsed, where, problems)
    return parsed


def _check_parameters(obj, parsed, where, problems):
    """Every name in ``Parameters`` must be an argument of the signature (catches renamed arguments)."""
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        signature = inspect.signature(target)
    except (TypeError, ValueError):  # pragma: no cover - builtins
        return
    accepted = set()
    for p in signature.parameters.values():
        accepted.add(p.name)
        if p.kind is p.VAR_POSITIONAL:
            accepted.add("*" + p.name)
        if p.kind is p.VAR_KEYWORD:
            accepted.add("**" + p.name)
    for param in list(parsed["Parameters"]) + list(parsed["Other Parameters"]):
        for name in (n.strip() for n in param.name.split(",")):
            if name and name not in accepted:
                problems.append(f"{where}: documents parameter {name!r}, which the signature "
                                f"{inspect.signature(target)} does not have")


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

    Module docstrings are narrative (the numpydoc sections are for functions and classes), so
    they are not parsed by numpydoc.
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


def render_doc(parsed, heading: str, level: int) -> str:
    """One object's reference: heading, summary, extended summary and every numpydoc section."""
    parts = [f"{'#' * level} {heading}"]
    summary = rst_to_markdown(parsed["Summary"])
    if summary:
        parts.append(summary)
    extended = rst_to_markdown(parsed["Extended Summary"])
    if extended:
        parts.append(extended)
    for title in SECTIONS:
        note = getattr(parsed, "qualifiers", {}).get(title)
        block = _section(f"{title} ({_inline(note)})" if note else title, parsed[title])
        if block:
            parts.append(block)
    if parsed["See Also"]:
        names = []
        for funcs, desc in parsed["See Also"]:
            for name, _role in funcs:
                names.append(f"`{name}`" + (f" ({' '.join(desc)})" if desc else ""))
        parts.append("**See also** " + ", ".join(names))
    for title in ("Notes", "References", "Examples"):
        body = rst_to_markdown(parsed[title])
        if body:
            parts.append(f"**{title}**\n\n{body}")
    return "\n\n".join(parts)


def _signature(name, obj) -> str:
    target = obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):  # pragma: no cover
        return f"{name}(...)"
    params = list(sig.parameters.values())
    if params and params[0].name in ("self", "cls"):
        params = params[1:]
    text = str(sig.replace(parameters=params, return_annotation=inspect.Signature.empty))
    text = re.sub(r"<([\w.]+) object at 0x[0-9a-f]+>", r"\1", text)  # stable defaults
    text = re.sub(r"(: |-> )'([^']*)'", r"\1\2", text)  # postponed annotations without their quotes
    return f"{name}{text}"


# ---------------------------------------------------------------------------
# Building the pages
# ---------------------------------------------------------------------------


def _anchor(text: str) -> str:
    return re.sub(r"[^a-z0-9 _-]", "", text.lower()).replace(" ", "-")


def build_api() -> str:
    """The text of ``docs/api.md``; raises :class:`ReferenceError_` listing every docstring problem."""
    problems: list[str] = []
    sections = []
    contents = []
    for module_name in public_modules():
        module = importlib.import_module(module_name)
        parts = [f"## `{module_name}`"]
        contents.append(f"- [`{module_name}`](#{_anchor(module_name)})")
        module_doc = inspect.getdoc(module)
        if not module_doc:
            problems.append(f"{module_name}: no module docstring")
        else:
            parts.append(module_prose(module_doc))
        constants = documented_constants(module)
        if constants:
            rows = ["| constant | value | meaning |", "|---|---|---|"]
            for name, value, doc in constants:
                meaning = _inline(" ".join(doc.split())).replace("|", "\\|")
                rows.append(f"| `{name}` | `{value.replace('|', '/')}` | {meaning} |")
            parts.append("\n".join(rows))
        for name, obj in public_members(module):
            where = f"{module_name}.{name}"
            heading = f"`{_signature(name, obj)}`" if not inspect.isclass(obj) else \
                f"class `{_signature(name, obj)}`"
            if inspect.isclass(obj) and obj.__module__ != module_name:
                parts.append(f"### `{name}`\n\nRe-exported from [`{obj.__module__}`](#{_anchor(obj.__module__)}).")
                continue
            if inspect.isfunction(obj) and obj.__module__ != module_name:
                parts.append(f"### `{name}`\n\nRe-exported from [`{obj.__module__}`](#{_anchor(obj.__module__)}).")
                continue
            doc = parse(obj, where, problems)
            if doc is None:
                continue
            parts.append(render_doc(doc, heading, 3))
            if inspect.isclass(obj):
                for member_name, member, kind in class_members(obj):
                    member_where = f"{where}.{member_name}"
                    member_doc = parse(member, member_where, problems, owner=obj)
                    if member_doc is None:
                        continue
                    label = f"`{name}.{member_name}`" + (" (property)" if kind == "property" else "")
                    if kind == "method":
                        label = f"`{name}.{_signature(member_name, member)}`"
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

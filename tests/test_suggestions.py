"""Every command a CLI output suggests runs exactly as printed (issue 15, part 4)."""

import re
import shlex

import pytest

from smd_statespace.cli import main

COMMANDS = ("simulate", "demo", "identify", "compare", "diagnose", "stats", "crowd", "hsi")
SUGGESTION = re.compile(r"smd-statespace (?:%s)(?=\s|$)" % "|".join(COMMANDS))


def suggestions(text):
    """The ``smd-statespace COMMAND ...`` commands printed in ``text`` (in backticks, or up to two spaces)."""
    found = []
    for line in text.splitlines():
        for quoted in re.findall(r"`([^`]*)`", line):
            if SUGGESTION.match(quoted):
                found.append(quoted)
        line = re.sub(r"`[^`]*`", "", line)
        match = SUGGESTION.search(line)
        if match:
            found.append(re.split(r"\s{2,}", line[match.start():].rstrip())[0])
    return found


def test_the_parser_finds_printed_commands_and_not_prose():
    text = ("smd-statespace demo: the SMD model, step by step\n"
            "    smd-statespace crowd --people 5 --out c.csv\n"
            "warning: ... run `smd-statespace diagnose 'my rec.csv' --mass 70 --estimator record`\n"
            "  smd-statespace hsi   Section 6\n"
            "expected the results.csv of 'smd-statespace identify'")
    assert suggestions(text) == ["smd-statespace crowd --people 5 --out c.csv",
                                 "smd-statespace diagnose 'my rec.csv' --mass 70 --estimator record",
                                 "smd-statespace hsi"]
    assert shlex.split(suggestions(text)[1])[2] == "my rec.csv"


@pytest.mark.slow
def test_every_printed_suggestion_runs_as_printed(tmp_path, monkeypatch, capsys):
    """The demo's next steps, in order, and whatever those commands suggest in turn, from one directory."""
    monkeypatch.chdir(tmp_path)
    assert main(["demo"]) == 0
    printed = capsys.readouterr().out
    todo = suggestions(printed.split("\nNext")[1])
    assert len(todo) >= 7 and todo[0].startswith("smd-statespace simulate")
    assert {shlex.split(command)[1] for command in todo} >= {"simulate", "identify", "compare", "diagnose", "stats",
                                                              "crowd", "hsi"}
    assert not any(re.search(r"\b(REC|KG|FOLDER|DIR)\b|\.\.\.|\[", command) for command in todo)  # no placeholders
    done = []
    while todo:
        command = todo.pop(0)
        if command in done:
            continue
        status = main(shlex.split(command)[1:])
        captured = capsys.readouterr()
        assert status == 0, f"{command!r} exited {status}: {captured.err.strip()}"
        done.append(command)
        todo += suggestions(captured.out + captured.err)
    assert (tmp_path / "crowd.csv").is_file() and (tmp_path / "rec_truth.json").is_file()

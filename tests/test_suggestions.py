"""Every command a CLI output suggests runs exactly as printed (issue 15, part 4)."""

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import smd_statespace
from smd_statespace.cli import main
from smd_statespace.io import read_record
from smd_statespace.signals import preprocess
from smd_statespace.simulation import sample_path, sample_truth_path

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


def installed_command() -> list:
    """The installed command as a user runs it: the console script, or ``python -m`` where it is not installed."""
    here = Path(sys.executable).parent / ("smd-statespace.exe" if os.name == "nt" else "smd-statespace")
    script = str(here) if here.exists() else shutil.which("smd-statespace")
    return [script] if script else [sys.executable, "-m", "smd_statespace"]


def check_demo_report(text: str, out: Path):
    """The demo's report of the packaged sample: its cycles, the person first, then the per-cycle method, and the
    figures it names."""
    mass = json.loads(sample_truth_path().read_text())["mass"]
    pre = preprocess(read_record(sample_path(), mass))
    f_b = np.median([c.f_b for c in pre.valid_cycles])
    assert f"{len(pre.cycles)} ({len(pre.valid_cycles)} valid)" in text
    assert f"median {f_b:.3f} Hz" in text
    assert ", ".join(smd_statespace.SMDModel().state_names[:4]) in text.replace(" |", ",")
    # the answer first: the person from the whole record, against the sample's truth, before the per-cycle method
    person = json.loads((out / "person" / "person.json").read_text())
    interval = f"{person['f_h_low']:.2f}-{person['f_h_high']:.2f} Hz"
    assert f"f_h          {person['f_h']:.3f} Hz, 90 % interval {interval}" in text
    assert text.index("The person, from the whole record") < text.index("Per cycle, the article's method")
    identified = pd.read_csv(out / "results.csv")
    assert f"{int((identified.status == 'ok').sum())} cycles identified" in text
    assert (out / "parameters.png").exists() and (out / "convergence.png").exists()
    assert (out / "pipeline.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert str(Path(out.name) / "pipeline.png") in text
    # prose and tables fit a terminal; lines naming files (the installed sample's path, what was written) may not
    assert max(len(line) for line in text.splitlines() if out.name not in line and ".csv" not in line) <= 110


@pytest.mark.slow
def test_every_printed_suggestion_runs_as_printed(tmp_path, monkeypatch, capsys):
    """A user's first session: the installed command's demo (its report checked), then its next steps in order,
    and whatever those commands suggest in turn, from one directory."""
    monkeypatch.chdir(tmp_path)
    done = subprocess.run([*installed_command(), "demo"], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    printed = done.stdout
    check_demo_report(printed, tmp_path / "smd_demo_output")
    assert "identify" in printed
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

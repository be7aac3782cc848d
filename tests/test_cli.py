"""The command line: simulate, demo, and one-line errors with exit status 2."""

import json
import os
import re
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

SIMULATE = ["simulate", "--mass", "70", "--fb", "2.0", "--fh", "2.5", "--xi", "0.3", "--duration", "12",
            "--seed", "1"]


def simulate(tmp_path, *extra, name="rec.csv"):
    out = tmp_path / name
    return main(SIMULATE + ["--out", str(out), *extra]), out


def test_simulate_writes_a_readable_record_and_its_truth(tmp_path, capsys):
    status, out = simulate(tmp_path, "--truth", str(tmp_path / "t.json"))
    assert status == 0
    record = read_record(out, 70.0)
    assert record.duration == pytest.approx(12.0)
    assert record.fs == pytest.approx(100.0)
    assert record.floor_acc is None
    truth = json.loads((tmp_path / "t.json").read_text())
    assert (truth["f_h"], truth["xi_h"], truth["f_b"], truth["seed"], truth["mass"]) == (2.5, 0.3, 2.0, 1, 70.0)
    line = capsys.readouterr().out.strip()
    assert "\n" not in line and str(out) in line and "t.json" in line and "12.00 s" in line


def test_simulate_default_truth_path_and_options(tmp_path):
    status, out = simulate(tmp_path, "--fs", "200", "--noise", "0", "--blf", "0.3,0.1", "--fb-variation", "0",
                           "--coef-variation", "0", "--phase-variation", "0.05")
    assert status == 0
    truth = json.loads((tmp_path / "rec_truth.json").read_text())
    assert truth["fs"] == 200.0 and truth["noise"] == 0.0 and truth["blf"] == [0.3, 0.1]
    assert truth["variations"]["fb_variation"] == 0.0 and truth["variations"]["phase_jitter_rad"] == 0.05
    assert read_record(out, 70.0).fs == pytest.approx(200.0)


def test_same_seed_gives_the_identical_file(tmp_path):
    assert simulate(tmp_path, name="a.csv")[0] == 0
    assert simulate(tmp_path, name="b.csv")[0] == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert main(SIMULATE[:-1] + ["2", "--out", str(tmp_path / "c.csv")]) == 0
    assert (tmp_path / "a.csv").read_bytes() != (tmp_path / "c.csv").read_bytes()


def test_effects_reach_the_simulator(tmp_path):
    status, out = simulate(tmp_path, "--effect", "floor_mode:frequency=3.48,modal_mass=8583",
                           "--effect", "harmonics:blf=0.04/0.03")
    assert status == 0
    record = read_record(out, 70.0)
    assert record.floor_acc is not None and np.std(record.floor_acc) > 0
    assert list(np.genfromtxt(out, delimiter=",", names=True, max_rows=1).dtype.names) == \
        ["time", "force", "floor_acc"]
    truth = json.loads((tmp_path / "rec_truth.json").read_text())
    assert truth["effects"]["floor_mode"]["frequency"] == 3.48
    assert truth["effects"]["harmonics"]["blf"] == [0.04, 0.03]


def test_simulate_effect_specs_are_checked_by_the_effect(tmp_path, capsys):
    for bad, words in (("", "effect name"), ("floor_mode:frequency", "key=value"),
                       ("floor_mode:frequency=fast", "frequency"), ("cubic_stiffness:beta=1", "'beta'.*beta_3"),
                       ("harmonics:blf=0.1/x", "blf")):
        assert simulate(tmp_path, "--effect", bad)[0] == 2
        assert re.search(words, capsys.readouterr().err)


def test_demo_on_a_simulated_record_shows_its_truth(tmp_path, capsys):
    status, out = simulate(tmp_path, "--effect", "floor_mode")
    assert status == 0
    assert main(["demo", "--record", str(out), "--mass", "70", "--out", str(tmp_path / "d")]) == 0
    text = capsys.readouterr().out
    assert "f_h 2.5 Hz, xi_h 0.3" in text and "floor acceleration recorded" in text
    assert (tmp_path / "d" / "pipeline.png").exists()
    # the record's length and the run time, each named: not "N force cycles, 58 s" for a 30 s record
    duration = float(pd.read_csv(out)["time"].iloc[-1])
    assert re.search(rf"force cycles in {duration:.0f} s, fitted in \d+ s", text), text


@pytest.mark.slow
def test_demo_says_when_the_truth_beside_a_record_is_unreadable(tmp_path, capsys):
    status, out = simulate(tmp_path, "--duration", "8")  # 8 s: about 6 s of demo
    assert status == 0
    beside = out.with_name(f"{out.stem}_truth.json")
    beside.write_text('{"f_h": 2.5,')  # cut short
    capsys.readouterr()
    assert main(["demo", "--record", str(out), "--mass", "70", "--out", str(tmp_path / "d")]) == 0
    captured = capsys.readouterr()
    assert f"warning: {beside}: not valid JSON" in captured.err and "without its truth" in captured.err
    assert "f_h 2.5 Hz, xi_h 0.3" not in captured.out


def error_line(capsys):
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("smd-statespace: error: ")
    return lines[0]


@pytest.mark.parametrize(
    "argv,pattern",
    [
        (["--mass", "-70"], "--mass: body mass must be a positive number"),
        (["--mass", "heavy"], "--mass: invalid float value"),
        (["--mass", "700"], "implausible"),
        (["--effect", "wobble"], "unknown effect 'wobble'; choose one of cubic_stiffness, floor_mode"),
        (["--effect", "floor_mode:freq=3"], "unknown option 'freq'; valid options: source, frequency"),
        (["--effect", "floor_mode:frequency=fast"], "frequency (Hz) must be a number, got 'fast'"),
        (["--effect", "floor_mode", "--effect", "floor_mode"], "given twice"),
        (["--fb", "-2"], "argument --fb: must be a positive number"),
        (["--fs", "10"], "fs 10 Hz is too low"),
        (["--phase-variation", "0.1", "--variation", "smooth"], "--phase-variation applies to --variation jumps"),
        (["--seed", "1.5"], "argument --seed"),
        (["--out", "/nonexistent-dir/rec.csv"], "does not exist"),
    ],
)
def test_simulate_bad_inputs_are_one_line_errors(tmp_path, capsys, argv, pattern):
    assert main(SIMULATE + ["--out", str(tmp_path / "r.csv")] + argv) == 2
    assert re.search(re.escape(pattern), error_line(capsys))
    assert capsys.readouterr().out == ""


@pytest.mark.parametrize(
    "argv,pattern",
    [
        (["simulate", "--mass", "70", "--fb", "2", "--fh", "2.5", "--xi", "0.3", "--duration", "30"],
         "required: --out"),
        (["demo", "--record", "no-such-record.csv", "--mass", "70"], "no-such-record.csv: no such file"),
        (["frobnicate"], "invalid choice"),
        ([], "choose a command: simulate, demo"),
        (["demo", "--bogus"], "unrecognized arguments: --bogus"),
    ],
)
def test_usage_and_record_errors_are_one_line(tmp_path, capsys, monkeypatch, argv, pattern):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert pattern in error_line(capsys)
    assert list(tmp_path.iterdir()) == []  # a failed command leaves nothing behind


def test_demo_out_must_be_a_directory(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    assert main(["demo", "--out", str(tmp_path / "file")]) == 2
    assert "not a directory" in error_line(capsys)
    assert capsys.readouterr().out == ""  # fails before printing a report


def test_version_and_help(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"smd-statespace {smd_statespace.__version__}"
    assert main(["simulate", "--help"]) == 0
    assert "--effect" in capsys.readouterr().out


def test_python_dash_m_version():
    done = subprocess.run([sys.executable, "-m", "smd_statespace", "--version"], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"smd-statespace {smd_statespace.__version__}"


def test_starting_the_cli_loads_no_heavy_module():
    """``--version``, ``--help`` and a bad option answer without scipy.signal, scipy.stats, matplotlib, statsmodels,
    filterpy or numba (about 2 s of imports, docs/performance.md "Imports"): each command imports what it uses."""
    heavy = ("scipy.signal", "scipy.stats", "matplotlib", "statsmodels", "filterpy", "numba")
    # the parser itself is built and used: until 2026-11-29 --noise-floor's default, read from
    # smd_statespace.person.noise_floor, imported the whole person package (scipy.stats, numba: 1.8 s for --version)
    for argv in (None, ["--version"], ["--help"], ["identify", "--rate", "fast"]):
        run = "" if argv is None else ("import contextlib, io; from smd_statespace.cli import main\n"
                                       "with contextlib.redirect_stdout(io.StringIO()), "
                                       "contextlib.redirect_stderr(io.StringIO()):\n"
                                       f"    try:\n        main({argv!r})\n    except SystemExit:\n        pass\n")
        code = (f"import sys; import smd_statespace.cli.main\n{run}"
                f"print(','.join(name for name in {heavy!r} if name in sys.modules))")
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        assert done.stdout.strip() == "", (argv, done.stdout)


def console_script():
    here = Path(sys.executable).parent / ("smd-statespace.exe" if os.name == "nt" else "smd-statespace")
    return str(here) if here.exists() else shutil.which("smd-statespace")


def test_console_script_error_is_one_line(tmp_path):
    script = console_script()
    if script is None:
        pytest.skip("the smd-statespace console script is not installed")
    done = subprocess.run([script, "simulate", "--out", "r.csv", "--mass", "-1", "--fb", "2", "--fh", "2",
                           "--xi", "0.3", "--duration", "5"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2
    assert len(done.stderr.splitlines()) == 1 and done.stderr.startswith("smd-statespace: error: --mass")


@pytest.fixture(scope="module")
def short_record(tmp_path_factory):
    folder = tmp_path_factory.mktemp("identify")
    out = folder / "rec.csv"
    assert main(["simulate", "--out", str(out), "--mass", "66", "--fb", "2.4", "--fh", "2.8", "--xi", "0.3",
                 "--duration", "7", "--seed", "3"]) == 0
    return out


def test_identify_writes_results_sidecar_and_figures(short_record, tmp_path, capsys):
    out = tmp_path / "id"
    assert main(["identify", str(short_record), "--mass", "66", "--estimator", "ekf", "--max-passes", "3",
                 "--seed", "9", "--out", str(out), "--truth", str(short_record.with_name("rec_truth.json")),
                 "--quiet"]) == 0
    table = pd.read_csv(out / "results.csv")
    for column in ("cycle", "t_start", "t_end", "f_b", "f_h", "f_h_sd", "xi_h", "xi_h_sd", "blf_1", "blf_4", "a0",
                   "k_h", "c_h", "passes", "converged", "log_likelihood", "estimator", "f_h_determined"):
        assert column in table.columns
    assert (table.loc[table.status == "ok", "passes"] <= 3).all()
    sidecar = json.loads((out / "run.json").read_text())
    assert sidecar["seed"] == 9 and sidecar["estimator"] == "ekf" and "version" in sidecar
    assert (out / "parameters.png").stat().st_size > 10_000 and (out / "convergence.png").exists()
    printed = capsys.readouterr().out
    ok = table[table.status == "ok"]
    assert f"{len(ok)} cycles identified" in printed and "truth" in printed
    # the record's answer from its cycles, in the person's vocabulary, printed and written
    pooled = pd.read_csv(out / "pooled.csv", index_col=0)
    assert list(pooled.columns[:5]) == ["value", "sd", "low", "high", "determined"]
    assert "the record's answer from its cycles" in printed and "pooled.csv" in printed
    # and how the cycles meet the record: the tests and free run every estimator's answer carries, and the figure
    assert "the cycles against the record: free-run fit" in printed and "Ljung-Box p" in printed
    assert (out / "diagnostics.png").stat().st_size > 10_000


def test_progress_bars_stay_out_of_logs(short_record, tmp_path, capsys):
    """Without --quiet, a bar is drawn on a terminal only: stderr captured (a log, a pipe) gets no bar lines."""
    assert main(["identify", str(short_record), "--mass", "66", "--estimator", "ekf", "--max-passes", "1",
                 "--out", str(tmp_path / "id")]) == 0
    err = capsys.readouterr().err
    assert "\r" not in err and "it/s" not in err and "s/it" not in err, err


def test_compare_runs_estimators_on_the_same_cycles(short_record, tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", str(short_record), "--mass", "66", "--estimators", "ekf,ukf", "--max-passes", "2",
                 "--out", str(out), "--truth", str(short_record.with_name("rec_truth.json")), "--quiet"]) == 0
    combined = pd.read_csv(out / "compare.csv")
    assert set(combined.estimator) == {"ekf", "ukf"}
    cycles = {name: set(group.cycle) for name, group in combined.groupby("estimator")}
    assert cycles["ekf"] == cycles["ukf"]
    printed = capsys.readouterr().out
    assert "|err| f_h" in printed and "f_h 90 %" in printed and (out / "compare.png").exists()
    assert "blf_1_low" not in printed  # the BLFs' intervals are in compare_table.csv, not on the terminal
    # every row answers in the person's vocabulary: its cycles pooled (identify.pooled), the error that answer's
    from smd_statespace.identify.pooled import pooled_row

    table = pd.read_csv(out / "compare_table.csv", index_col=0)
    truth = json.loads(short_record.with_name("rec_truth.json").read_text())
    for name, group in combined.groupby("estimator"):
        answer = pooled_row(group)
        for key in ("f_h", "f_h_low", "f_h_high", "f_h_determined", "xi_h", "xi_h_low", "xi_h_high"):
            assert table.loc[name, key] == pytest.approx(answer[key])
        assert table.loc[name, "|err| f_h"] == pytest.approx(abs(answer["f_h"] - truth["f_h"]))


@pytest.mark.parametrize(
    "extra,message",
    [(["--estimator", "kalman"], "invalid choice: 'kalman'"), (["--particles", "0"], "--particles"),
     (["--effect", "floor"], "unknown effect 'floor'"), (["--effect", "harmonics:size=2"], "unknown option 'size'"),
     (["--mass", "-3"], "positive")],
)
def test_identify_bad_options_exit_2(short_record, tmp_path, capsys, extra, message):
    argv = ["identify", str(short_record), "--mass", "66", "--out", str(tmp_path / "o"), "--quiet"] + extra
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and "Traceback" not in err[0]


def test_compare_unknown_estimator_exit_2(short_record, tmp_path, capsys):
    assert main(["compare", str(short_record), "--mass", "66", "--estimators", "ekf,kf", "--out",
                 str(tmp_path / "c")]) == 2
    assert "unknown 'kf'" in capsys.readouterr().err


def test_per_cycle_identify_decimates_a_fast_record_and_records_the_rate(tmp_path, capsys):
    fast = tmp_path / "fast.csv"
    assert main(["simulate", "--out", str(fast), "--mass", "66", "--fb", "2.4", "--fh", "2.8", "--xi", "0.3",
                 "--duration", "7", "--seed", "3", "--fs", "1000"]) == 0
    capsys.readouterr()
    out = tmp_path / "id"
    assert main(["identify", str(fast), "--mass", "66", "--estimator", "ekf", "--max-passes", "2", "--out", str(out),
                 "--quiet"]) == 0
    assert "note: fitted at 100 Hz: the record (1000 Hz)" in capsys.readouterr().out
    assert json.loads((out / "run.json").read_text())["rate"] == 100.0
    table = pd.read_csv(out / "results.csv")
    assert (table.status == "ok").sum() >= 6
    kept = tmp_path / "kept"
    assert main(["identify", str(fast), "--mass", "66", "--estimator", "ekf", "--max-passes", "1", "--rate", "0",
                 "--out", str(kept), "--quiet"]) == 0
    assert "note:" not in capsys.readouterr().out and json.loads((kept / "run.json").read_text())["rate"] is None
    assert main(["compare", str(fast), "--mass", "66", "--estimators", "ekf", "--rate", "-1", "--out",
                 str(tmp_path / "c")]) == 2
    assert "--rate" in capsys.readouterr().err

"""Batch identification: many records, failures contained, atomic parts, --resume after a kill, any --jobs."""

import os
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest

from smd_statespace.identify.batch import collect_records, read_manifest, record_key, run_batch
from smd_statespace.cli import main
from smd_statespace.errors import OptionError, RecordError
from smd_statespace.io import write_record
from smd_statespace.simulation import simulate_bouncing

OPTIONS = dict(max_passes=2, seed=11)


def write_records(folder, count, duration=8.0):
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(count):
        synthetic = simulate_bouncing(mass=60.0 + i, f_b=1.8 + 0.15 * i, f_h=2.4, xi_h=0.3, duration=duration,
                                      seed=100 + i)
        write_record(folder / f"rec{i}.csv", synthetic.record)
    return folder


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    folder = write_records(tmp_path_factory.mktemp("batch") / "records", 3)
    (folder / "flat.csv").write_text("time,force\n" + "".join(f"{k / 100},700\n" for k in range(800)))
    (folder / "manifest.csv").write_text("file,mass\nrec0.csv,60\nrec1.csv,61\nrec2.csv,62\nflat.csv,70\n")
    return folder


def results(folder):
    """A run's results without the wall-clock column (the only thing allowed to differ between runs)."""
    return pd.read_csv(folder / "results.csv").drop(columns="seconds")


def test_records_from_folder_glob_and_manifest(records):
    by_folder = collect_records(records, manifest=records / "manifest.csv")
    assert [r.name for r in by_folder] == ["flat.csv", "rec0.csv", "rec1.csv", "rec2.csv"]  # not the manifest
    assert [r.mass for r in by_folder] == [70.0, 60.0, 61.0, 62.0]
    by_glob = collect_records(str(records / "rec*.csv"), mass=75)
    assert [r.path.name for r in by_glob] == ["rec0.csv", "rec1.csv", "rec2.csv"] and {r.mass for r in by_glob} == {75}
    only_manifest = collect_records(None, manifest=records / "manifest.csv")
    assert [r.name for r in only_manifest] == ["rec0.csv", "rec1.csv", "rec2.csv", "flat.csv"]
    # The seed key depends on the name only: the same wherever the record sits in the batch.
    assert by_folder[1].key == only_manifest[0].key == record_key("rec0.csv")
    assert len({r.part for r in by_folder}) == 4


def test_a_folder_of_plate_exports_is_a_batch_of_them(tmp_path):
    """A lab's folder of exports (Qualisys' .tsv, BioWare's .txt, C3D): every file of a record's suffix, not the
    others."""
    for name in ("b.tsv", "a.txt", "c.C3D", "notes.md", "d.csv"):
        (tmp_path / name).write_text("x")
    (tmp_path / "sub.csv").mkdir()
    assert [r.name for r in collect_records(tmp_path, mass=70)] == ["a.txt", "b.tsv", "c.C3D", "d.csv"]
    (tmp_path / "only").mkdir()
    (tmp_path / "only" / "notes.md").write_text("x")
    with pytest.raises(RecordError, match=r"no record files \(\*\.csv, \*\.tsv, \*\.txt, \*\.c3d"):
        collect_records(tmp_path / "only", mass=70)


@pytest.mark.parametrize("text,message", [
    ("file,weight\na.csv,60\n", "missing column 'mass'"),
    ("file,mass\n", "no records listed"),
    ("file,mass\nrec0.csv,sixty\n", "row 2 (rec0.csv) has mass 'sixty'"),
    ("file,mass\nrec0.csv,60\nrec0.csv,61\n", "row 3 lists 'rec0.csv' a second time"),
    ("file,mass\nrec0.csv,600\n", "row 2 (rec0.csv)"),
])
def test_bad_manifest_is_one_clear_line(tmp_path, text, message):
    manifest = tmp_path / "m.csv"
    manifest.write_text(text)
    with pytest.raises(RecordError if "600" not in text else ValueError, match=message.replace("(", r"\(")
                       .replace(")", r"\)")):
        read_manifest(manifest)


def test_missing_masses_and_files_are_named(records, tmp_path):
    assert {r.mass for r in collect_records(records)} == {None}  # no mass nor manifest: each plate weighs its person
    manifest = tmp_path / "m.csv"
    manifest.write_text("file,mass\nrec0.csv,60\n")
    with pytest.raises(RecordError, match="no mass for flat.csv"):
        collect_records(records, manifest=manifest)
    with pytest.raises(RecordError, match="no record files"):
        collect_records(str(tmp_path / "nothing*.csv"), mass=70)


def test_failures_are_contained_and_jobs_do_not_change_results(records, tmp_path):
    found = collect_records(records, manifest=records / "manifest.csv")
    one = run_batch(found, tmp_path / "one", estimator="ekf", runner_options=OPTIONS, progress=False)
    two = run_batch(found, tmp_path / "two", estimator="ekf", runner_options=OPTIONS, jobs=2, progress=False)
    assert one.failed_records == ["flat.csv"] and one.identified == 4
    table = results(tmp_path / "one")
    flat = table[table["record"] == "flat.csv"]
    assert len(flat) == 1 and flat["status"].iloc[0] == "failed"
    assert "not a bouncing record (not_rhythmic): the force is constant" in flat["reason"].iloc[0]
    assert (table.loc[table["record"] != "flat.csv", "status"] != "failed").all()
    assert table["record"].drop_duplicates().tolist() == [r.name for r in found]  # the run's order
    pd.testing.assert_frame_equal(table, results(tmp_path / "two"))
    assert two.cycles == one.cycles
    # Implausible cycles are counted from the flags the runner wrote (max_passes=2 leaves some here).
    ok = table[table["status"] == "ok"]
    flagged = ok["implausible"].astype(str).str.lower() == "true"
    assert one.implausible == int(flagged.sum()) and sum(one.implausible_reasons.values()) >= one.implausible
    assert (ok.loc[flagged, "implausible_reason"].fillna("").astype(str).str.len() > 0).all()
    assert (f"({one.implausible} of them implausible)" in one.line()) == (one.implausible > 0)
    # Each record's rows are those of identifying it alone (seed from its name, not its position).
    alone = run_batch([found[2]], tmp_path / "alone", estimator="ekf", runner_options=OPTIONS, progress=False)
    assert alone.identified == 1
    single = results(tmp_path / "alone")
    within = table[table["record"] == found[2].name].reset_index(drop=True)[single.columns]
    pd.testing.assert_frame_equal(single, within, check_dtype=False)  # the batch's cycle column has a NaN row


def test_resume_keeps_finished_records_and_refuses_other_settings(records, tmp_path):
    found = collect_records(records, manifest=records / "manifest.csv")
    out = tmp_path / "run"
    # as if killed after two records...
    run_batch(found[:2], out, estimator="ekf", runner_options=OPTIONS, progress=False)
    (out / "results.csv").unlink()
    with pytest.raises(OptionError, match="the records differ"):
        run_batch(found, out, estimator="ekf", runner_options=OPTIONS, resume=True, progress=False)
    with pytest.raises(OptionError, match="holds a previous batch run"):
        run_batch(found[:2], out, estimator="ekf", runner_options=OPTIONS, progress=False)
    with pytest.raises(OptionError, match="the options differ"):
        run_batch(found[:2], out, estimator="ekf", runner_options=dict(OPTIONS, max_passes=3), resume=True,
                  progress=False)
    with pytest.raises(OptionError, match="no run in"):
        run_batch(found, tmp_path / "empty", estimator="ekf", runner_options=OPTIONS, resume=True, progress=False)
    again = run_batch(found[:2], out, estimator="ekf", runner_options=OPTIONS, resume=True, progress=False)
    assert again.resumed == 2 and again.identified == 0


@pytest.mark.slow
def test_sigkill_mid_run_then_resume_gives_the_clean_results(tmp_path):
    """A real process killed with SIGKILL after its first record; --resume completes it, nothing lost or doubled."""
    folder = write_records(tmp_path / "records", 6, duration=10.0)
    argv = ["identify", str(folder), "--mass", "65", "--estimator", "ekf", "--max-passes", "2", "--seed", "5",
            "--quiet"]
    killed = tmp_path / "killed"
    process = subprocess.Popen([sys.executable, "-m", "smd_statespace", *argv, "--out", str(killed)],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    parts = killed / "parts"
    deadline = time.monotonic() + 120
    while not (parts.is_dir() and any(parts.glob("*.csv"))):
        assert process.poll() is None, "the run ended before it could be killed"
        assert time.monotonic() < deadline, "no record finished within 120 s"
        time.sleep(0.02)
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    done = sorted(parts.glob("*.csv"))
    assert 1 <= len(done) < 6 and not (killed / "results.csv").exists()
    for part in done:  # every part on disk is whole
        assert pd.read_csv(part)["record"].nunique() == 1
    assert main(argv + ["--out", str(killed), "--resume"]) == 0
    assert main(argv + ["--out", str(tmp_path / "clean")]) == 0
    resumed, clean = results(killed), results(tmp_path / "clean")
    pd.testing.assert_frame_equal(resumed, clean)
    assert resumed["record"].nunique() == 6


def test_cli_batch_reports_each_bad_file_and_exits_1(records, tmp_path, capsys):
    status = main(["identify", str(records), "--manifest", str(records / "manifest.csv"), "--estimator", "ekf",
                   "--max-passes", "2",
                   "--out", str(tmp_path / "o"), "--quiet"])
    captured = capsys.readouterr()
    assert status == 1
    errors = captured.err.strip().splitlines()
    assert len(errors) == 1 and errors[0].startswith("smd-statespace: error: ") and "flat.csv" in errors[0]
    assert "4 records: 4 identified now" in captured.out and (tmp_path / "o" / "results.csv").exists()
    # each record's cycles pooled into one row in the person's columns (identify.pooled), which stats reads as people
    from smd_statespace.identify.pooled import pooled_row

    cycles = pd.read_csv(tmp_path / "o" / "results.csv")
    pooled = pd.read_csv(tmp_path / "o" / "pooled.csv").set_index("record")
    assert list(pooled.index) == cycles["record"].drop_duplicates().tolist() and "pooled.csv" in captured.out
    assert pooled.loc["flat.csv", "status"] == "failed" and "not a bouncing record" in pooled.loc["flat.csv", "reason"]
    answer = pooled_row(cycles[cycles["record"] == "rec1.csv"])
    for key in ("f_h", "f_h_low", "f_h_high", "f_h_determined", "blf_2", "n_cycles"):
        assert pooled.loc["rec1.csv", key] == pytest.approx(answer[key])
    assert main(["stats", str(tmp_path / "o" / "pooled.csv"), "--out", str(tmp_path / "s"), "--bootstrap", "5"]) == 0
    assert "4 people read from 1 file(s): 3 ok, 1 failed left out" in capsys.readouterr().out
    # without masses the plate weighs each person: on its whole cycles here (bouncing end to end), the same masses
    assert main(["identify", str(records), "--estimator", "ekf", "--max-passes", "2", "--out", str(tmp_path / "p"),
                 "--quiet"]) == 1
    weighed = pd.read_csv(tmp_path / "p" / "results.csv").groupby("record")["mass"].first()
    assert weighed[["rec0.csv", "rec1.csv", "rec2.csv"]].tolist() == pytest.approx([60.0, 61.0, 62.0], rel=0.005)


def test_a_new_run_rewrites_settings_left_in_its_folder(records, tmp_path):
    found = collect_records(records, manifest=records / "manifest.csv")[1:2]
    out = tmp_path / "run"
    out.mkdir()
    (out / "run.json").write_text('{"records": [], "options": {}}')  # left by something else, no parts
    run_batch(found, out, estimator="ekf", runner_options=OPTIONS, progress=False)
    # compared with the new settings
    again = run_batch(found, out, estimator="ekf", runner_options=OPTIONS, resume=True, progress=False)
    assert again.resumed == 1


@pytest.mark.slow
def test_record_estimator_batch_command_gives_one_person_per_record_that_stats_reads(records, tmp_path, capsys):
    """The documented study path through the command line (docs/batch.md): ``identify FOLDER --manifest M
    --jobs 2`` (the record-level person, by default as for one record) writes one person per record and the
    people's figure, fails the flat record in one line (exit 1, no traceback), resumes without refitting; ``stats``
    reads the table as people."""
    out = tmp_path / "people"
    argv = ["identify", str(records), "--manifest", str(records / "manifest.csv"), "--out", str(out), "--jobs", "2",
            "--quiet"]
    assert main(argv) == 1  # flat.csv fails; the others are people
    printed = capsys.readouterr()
    assert "Traceback" not in printed.err and "flat.csv" in printed.err and len(printed.err.strip().splitlines()) == 1
    assert "rows (one person per record)" in printed.out and (out / "people.png").stat().st_size > 10_000
    table = pd.read_csv(out / "results.csv")
    people = table[table["status"] == "ok"].set_index("record")
    assert list(people.index) == ["rec0.csv", "rec1.csv", "rec2.csv"]
    assert people["f_h"].between(2.4 * 0.9, 2.4 * 1.1).all()  # the simulated people all have f_h 2.4 Hz
    assert (people["f_b"] - [1.8, 1.95, 2.1]).abs().max() < 0.05
    assert {"f_h_sd", "xi_h", "blf_1", "mass", "implausible", "model_adequate", "ljung_box_p"} <= set(people.columns)

    assert main(argv + ["--resume"]) == 1  # nothing is fitted again; the flat record's failure is kept
    assert "0 identified now, 4 taken from the earlier run, 1 failed" in capsys.readouterr().out
    assert pd.read_csv(out / "results.csv").equals(table)

    assert main(["stats", str(out / "results.csv"), "--out", str(tmp_path / "stats"), "--bootstrap", "5"]) == 0
    report = capsys.readouterr().out
    assert "4 people read from 1 file(s): 3 ok, 1 failed left out" in report
    assert "too few people: need" in report and "cycles" not in report.replace("n_cycles", "")


@pytest.mark.slow
def test_record_estimator_batch_resumed_on_a_dask_cluster_gives_the_serial_table(records, tmp_path):
    """``run_batch(executor=...)`` runs the record-level model on a Dask cluster: a run killed after its first
    record, resumed on a ``LocalCluster`` (127.0.0.1, one worker process), identifies only the others there and
    ends with the serial run's table (docs/performance.md, "The record-level person")."""
    distributed = pytest.importorskip("distributed")
    import shutil

    found = collect_records(records, manifest=records / "manifest.csv")[:3]  # flat.csv (fails), rec0, rec1
    serial = run_batch(found, tmp_path / "serial", estimator="record", progress=False)
    assert serial.failed_records == ["flat.csv"] and serial.identified == 3
    killed = tmp_path / "cluster"
    shutil.copytree(tmp_path / "serial", killed)
    (killed / "results.csv").unlink()
    for record in found[1:]:  # as if killed after the first record
        (killed / "parts" / record.part).unlink()
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        resumed = run_batch(found, killed, estimator="record", resume=True, progress=False,
                            executor=client.get_executor())
    assert resumed.identified == 2 and resumed.resumed == 1 and resumed.failed_records == ["flat.csv"]
    pd.testing.assert_frame_equal(pd.read_csv(killed / "results.csv"), pd.read_csv(tmp_path / "serial" / "results.csv"))

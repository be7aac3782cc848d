"""Force plates' exports as lab software writes them: read to the force they hold, or refused in one line."""

import sys
from pathlib import Path

import numpy as np
import pytest

from smd_statespace.errors import RecordError
from smd_statespace.io import G, read_record

MASS = 70.0
RATE = 1000.0


def bouncing(n=3000, fs=RATE):
    """Time (s) and a bouncing person's vertical force (N), with the weight shifting between two plates."""
    t = np.arange(n) / fs
    force = MASS * G * (1 + 0.4 * np.sin(2 * np.pi * 2.2 * t))
    share = 0.5 + 0.2 * np.sin(2 * np.pi * 0.3 * t)
    return t, force, share


def write(path, lines, encoding="utf-8"):
    path.write_text("\n".join(lines) + "\n", encoding=encoding)
    return path


def test_a_vicon_nexus_devices_block_of_two_plates_reads_as_their_upward_sum(tmp_path):
    """Nexus writes 'Devices', the rate, the devices' names, Frame,Sub Frame,Fx,Fy,Fz,... for each plate, a row of
    units, the rows, then an empty row and the 'Trajectories' block; its Fz is the force on the plate (z up), so
    negative under a person. The time is the rows counted at the rate."""
    t, force, share = bouncing()
    names = ",,Force Plate 1 - Force,,,Force Plate 1 - CoP,,,Force Plate 2 - Force,,,Force Plate 2 - CoP,,"
    rows = [f"{k // 10 + 1},{k % 10},3.1,-2.0,{-f * s:.6f},101,250,0,-1.5,2.2,{-f * (1 - s):.6f},98,760,0"
            for k, (f, s) in enumerate(zip(force, share))]
    lines = ["Devices", "1000", names, "Frame,Sub Frame,Fx,Fy,Fz,Cx,Cy,Cz,Fx,Fy,Fz,Cx,Cy,Cz",
             ",,N,N,N,mm,mm,mm,N,N,N,mm,mm,mm", *rows, "", "Trajectories", "100", ",,LASI,,", "Frame,Sub Frame,X,Y,Z",
             ",,mm,mm,mm", "1,,1.0,2.0,3.0", "2,,1.0,2.0,3.0", "3,,1.0,2.0,3.0"]
    record = read_record(write(tmp_path / "trial01.csv", lines), MASS)
    np.testing.assert_allclose(record.force, force, atol=2e-6)
    np.testing.assert_allclose(record.time, t, atol=1e-12)
    notes = " ".join(record.extra["reading"])
    assert "Vicon Nexus export, header on line 4" in notes and "rows counted at 1000 Hz" in notes
    assert ("sum of 2 plates' vertical columns 'Fz' (column 5, Force Plate 1 - Force), 'Fz' (column 11, Force Plate 2 "
            "- Force)") in notes and "sign turned" in notes


def test_a_nexus_export_with_its_plates_combined_reads_the_combined_force_alone(tmp_path):
    """Nexus names each device on the row above the header; a 'Combined Force' device repeats the plates' sum as
    plain 'Fz' (a real export summed all three: twice the force). The raw channels (V) are not forces."""
    t, force, share = bouncing(n=1500)
    names = ",,FP_links - Force,,,FP_links - Raw,,FP_rechts - Force,,,Combined Force,,"
    rows = [f"{k // 10 + 1},{k % 10},3.1,-2.0,{-f * s:.6f},0.1,0.2,-1.5,2.2,{-f * (1 - s):.6f},1.6,0.2,{-f:.6f}"
            for k, (f, s) in enumerate(zip(force, share))]
    lines = ["Devices", "1000", names, "Frame,Sub Frame,Fx,Fy,Fz,FZ1,FZ2,Fx,Fy,Fz,Fx,Fy,Fz",
             ",,N,N,N,V,V,N,N,N,N,N,N", *rows]
    record = read_record(write(tmp_path / "squat.csv", lines), MASS)
    np.testing.assert_allclose(record.force, force, atol=2e-6)
    assert "force from 'Fz' (column 13, Combined Force)" in record.extra["reading"][0]


def test_vertical_force_columns_qualified_by_side_or_limb_are_summed_and_horizontal_ones_left(tmp_path):
    """A balance lab's two plates, one per foot: 'dominant Fvert (N)' and 'non-dominant Fvert (N)' (tab-separated,
    beside the anterior-posterior force and centre of pressure)."""
    t, force, share = bouncing(n=500, fs=100.0)
    rows = [f"{tk:.6f}\t-1.8\t{f * s:.6f}\t0.22\t1.6\t{f * (1 - s):.6f}\t0.21" for tk, f, s in zip(t, force, share)]
    header = "time (s)\tdominant Fap (N)\tdominant Fvert (N)\tdominant CPap (m)\tnon-dominant Fap (N)\t" \
             "non-dominant Fvert (N)\tnon-dominant CPap (m)"
    record = read_record(write(tmp_path / "Control 0 trial 0.txt", [header, *rows]), MASS)
    np.testing.assert_allclose(record.force, force, atol=1e-5)
    assert "'dominant Fvert (N)' (column 3), 'non-dominant Fvert (N)' (column 6)" in record.extra["reading"][0]


def test_blank_cells_in_the_first_rows_of_an_unused_column_leave_the_table_where_it_starts(tmp_path):
    """A centre of pressure left blank in the first two rows (the plate not yet loaded): those rows are the table's
    first, not its header (they were, and the file was refused for a time column it has). A blank force is refused
    naming its column and data row."""
    t, force, share = bouncing(n=600)
    rows = [f"{tk:.4f},{f:.6f},{'' if k < 2 else '12.5'}" for k, (tk, f) in enumerate(zip(t, force))]
    record = read_record(write(tmp_path / "cop.csv", ["Time (s),Fz (N),COPx (mm)", *rows]), MASS)
    np.testing.assert_allclose(record.force, force, atol=1e-6)
    np.testing.assert_allclose(record.time, t, atol=1e-9)
    rows[300] = f"{t[300]:.4f},,12.5"
    with pytest.raises(RecordError, match=r"column 'Fz \(N\)' row 301 \(line 302\) holds ''"):
        read_record(write(tmp_path / "gap.csv", ["Time (s),Fz (N),COPx (mm)", *rows]), MASS)


def test_a_qualisys_tsv_reads_its_time_and_force_z(tmp_path):
    t, force, _ = bouncing()
    block = ["NO_OF_SAMPLES\t3000", "FREQUENCY\t1000", "TIME_STAMP\t2026-11-30, 10:00:00", "FIRST_SAMPLE\t0",
             "DESCRIPTION\tForce data in local (force plate) coordinates", "DATA_INCLUDED\tForce",
             "FORCE_PLATE_TYPE\tAmti", "FORCE_PLATE_NAME\tForce-plate 1",
             "SAMPLE\tTIME\tFORCE_X\tFORCE_Y\tFORCE_Z\tMOMENT_X\tMOMENT_Y\tMOMENT_Z\tCOP_X\tCOP_Y\tCOP_Z"]
    rows = [f"{k + 1}\t{tk:.3f}\t1.0\t-2.0\t{f:.4f}\t5\t6\t7\t0.1\t0.2\t0" for k, (tk, f) in enumerate(zip(t, force))]
    record = read_record(write(tmp_path / "trial_f_1.tsv", block + rows), MASS)
    np.testing.assert_allclose(record.force, force, atol=1e-4)
    np.testing.assert_allclose(record.time, t, atol=1e-12)
    assert "Qualisys export, header on line 9: time from 'TIME', force from 'FORCE_Z' (column 5)" \
        in record.extra["reading"][0]


def test_a_european_export_with_decimal_commas_a_title_and_time_in_ms_reads_in_seconds(tmp_path):
    """Semicolons, decimal commas, a title in Windows' code page (not UTF-8), time in ms, two plates as Fz1 and Fz2
    in kN."""
    t, force, share = bouncing()
    rows = [f"{1000 * tk:.1f};{f * s / 1000:.7f};{f * (1 - s) / 1000:.7f};0,5".replace(".", ",")
            for tk, f, s in zip(t, force, share)]
    lines = ["Kraftmessplatte \u00ae Messung 3", "Sampling rate: 1000 Hz", "", "Zeit (ms);Fz1 (kN);Fz2 (kN);Mx (kNm)",
             *rows]
    record = read_record(write(tmp_path / "messung.txt", lines, encoding="cp1252"), MASS)
    np.testing.assert_allclose(record.time, t, atol=1e-9)
    np.testing.assert_allclose(record.force, force, rtol=1e-6)
    assert "force the sum of 2 plates' vertical columns 'Fz1 (kN)' (column 2), 'Fz2 (kN)' (column 3)" \
        in record.extra["reading"][0]
    assert "time from the rows counted at 1000 Hz" in record.extra["reading"][0]  # 'Zeit' is not a time it knows


def test_a_jump_plate_of_two_sides_and_their_total_reads_the_total_alone(tmp_path):
    """Vertical-only plates export each side and their sum (Left (N), Right (N), Combined (N)): the sum is the
    force, not the sum of all three."""
    t, force, share = bouncing(n=1000)
    rows = [f"{tk:.3f},{f * s:.4f},{f * (1 - s):.4f},{f:.4f}" for tk, f, s in zip(t, force, share)]
    record = read_record(write(tmp_path / "jump.csv", ["Time (s),Left (N),Right (N),Combined (N)", *rows]), MASS)
    np.testing.assert_allclose(record.force, force, atol=1e-4)
    assert "force from 'Combined (N)' (column 4)" in record.extra["reading"][0]
    two = read_record(write(tmp_path / "sides.csv", ["Time (s),Left (N),Right (N)",
                                                       *(row.rsplit(",", 1)[0] for row in rows)]), MASS)
    np.testing.assert_allclose(two.force, force, atol=2e-4)


def test_a_tab_separated_opensim_file_and_our_format_with_semicolons_read_the_same(tmp_path):
    t, force, _ = bouncing(n=400, fs=100.0)
    mot = ["Trial", "nRows=400", "endheader", "time\tground_force1_vy\tground_force1_vx",
           *(f"{tk:.2f}\t{f:.6f}\t0.5" for tk, f in zip(t, force))]
    semicolons = ["time;force;floor_acc", *(f"{tk:.2f};{f:.6f};{0.01 * tk:.4f}" for tk, f in zip(t, force))]
    for record in (read_record(write(tmp_path / "grf.mot", mot), MASS),
                   read_record(write(tmp_path / "semi.csv", semicolons), MASS)):
        np.testing.assert_allclose(record.force, force, atol=1e-6)
        np.testing.assert_allclose(record.time, t, atol=1e-12)
    np.testing.assert_allclose(record.floor_acc, 0.01 * t, atol=1e-9)  # this library's own columns, semicolons


@pytest.mark.parametrize("lines,expected", [
    (["Trial,,", "endheader,,", "time,fx,fy", "0,1,2", "0.01,1,2", "0.02,1,2"],
     "missing column 'force' (or each plate's vertical force: Fz, FZ1, FORCE_Z, 'Fz (N)', ground_force1_vy, ...); "
     "the header is 'time,fx,fy' (line 3)"),
    (["Frame,Sub Frame,Fx,Fy,Fz", "1,0,1,2,686", "1,1,1,2,686", "1,2,1,2,686"],
     "missing column 'time' (in s or ms), and no sampling rate above the header; the header is "
     "'Frame,Sub Frame,Fx,Fy,Fz' (line 1)"),
    (["Sampling rate,1000", "Frame,Fz1,Fz2", "V,V,V", "1,0.1,0.2", "2,0.1,0.2", "3,0.1,0.2"],
     "vertical force columns in 'v'; expected N, kN, lbf or kgf (the header is 'Frame,Fz1,Fz2' (line 2))"),
    (["a trial", "time,force", "0,abc", "x,y"], "no table of numbers in its first 200 rows"),
])
def test_an_export_without_what_a_record_needs_is_refused_in_one_line_naming_its_header(tmp_path, lines, expected):
    path = write(tmp_path / "export.csv", lines)
    with pytest.raises(RecordError) as info:
        read_record(path, MASS)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and expected in message and "\n" not in message, message


DATA = Path(__file__).parent / "data" / "plates"


def test_a_real_kistler_bioware_trial_reads_the_same_from_its_text_export_and_its_c3d_file():
    """One real countermovement jump (tests/data/plates/README.md), as BioWare writes it as text (a block of 17 rows
    of settings, 'abs time (s)', a row of units) and as C3D (a type-3 plate's eight channels, which ezc3d turns into
    the force): the same 8000 samples at 1000 Hz, the same force to its quantisation."""
    text = read_record(DATA / "kistler_cmj_1plate.txt", 68.0)
    c3d = read_record(DATA / "kistler_cmj_1plate.c3d", 68.0)
    assert text.time.size == c3d.time.size == 8000 and text.fs == pytest.approx(1000.0) and c3d.fs == pytest.approx(
        1000.0)
    difference = c3d.force - text.force  # the C3D's integers and the text's six decimals
    assert np.sqrt(np.mean(difference ** 2)) < 0.1 and np.abs(difference).max() < 1.0
    assert text.force.max() > 1.5 * 68.0 * G and text.force.min() < 0.05 * 68.0 * G  # a jump: it leaves the plate
    assert text.extra["reading"] == ["read as a Kistler BioWare export, header on line 18: time from 'abs time (s)', "
                                     "force from 'Fz' (column 4)"]
    assert c3d.extra["reading"][0].startswith("read as a C3D file (ezc3d): time from the analog rate 1000 Hz")


def test_a_c3d_file_without_ezc3d_or_that_ezc3d_cannot_parse_is_refused_in_one_line(tmp_path, monkeypatch):
    broken = tmp_path / "trial.c3d"
    broken.write_bytes(b"\x02\x50" + bytes(510) + b"PARAMETER" + bytes(100))
    with pytest.raises(RecordError, match=r"trial.c3d: not a C3D file ezc3d can read"):
        read_record(broken, MASS)
    monkeypatch.setitem(sys.modules, "ezc3d", None)  # as if it were not installed
    with pytest.raises(RecordError, match=r"kistler_cmj_1plate.c3d: a C3D file is read with the ezc3d package: pip "
                                          r"install ezc3d"):
        read_record(DATA / "kistler_cmj_1plate.c3d", MASS)
    other = tmp_path / "trial.bin"
    other.write_bytes(bytes(64))
    with pytest.raises(RecordError, match=r"trial.bin: not a text CSV file \(binary data\)"):
        read_record(other, MASS)


def test_a_table_without_header_or_time_reads_with_the_rate_and_force_column_given(tmp_path):
    """AMTI NetForce's text files: an empty line, then Fx, Fy, Fz, Mx, My, Mz without a header or a clock."""
    t, force, _ = bouncing(n=600, fs=100.0)
    lines = ["", *(f" 6.57320,  3.06925, {f:9.5f}, -26.97418,  2.69687,  0.19899" for f in force)]
    path = write(tmp_path / "netforce.txt", lines)
    with pytest.raises(RecordError, match="no header row above the numbers .* --force-columns 3 .* --fs HZ"):
        read_record(path, MASS)
    record = read_record(path, MASS, fs=100.0, force_columns=[3])
    np.testing.assert_allclose(record.force, force, atol=1e-5)
    np.testing.assert_allclose(record.time, t, atol=1e-12)
    assert record.extra["reading"] == ["read as an export, without a header: time from the rows counted at 100 Hz "
                                       "(as given), force from column 3"]
    from smd_statespace.identify.batch import collect_records

    batch = collect_records(str(path), MASS, reading={"fs": 100.0, "force_columns": ["3"]})
    np.testing.assert_allclose(batch[0].read().force, record.force)


@pytest.mark.parametrize("options,message", [
    (["--fs", "-5"], "--fs -5: a sampling rate must be a positive number of Hz"),
    (["--force-columns", "Fz,,Fz"], "--force-columns 'Fz,,Fz': expected names or numbers separated by commas"),
    (["--fs", "100", "--accelerometer"], "--fs reads a force plate's export, not a phone's (--accelerometer)"),
    (["--force-columns", "Fy"], "missing column 'time' (in s or ms), and no sampling rate above the header"),
])
def test_the_reading_options_are_checked_in_one_line_with_exit_status_2(tmp_path, capsys, options, message):
    from smd_statespace.cli import main

    t, force, _ = bouncing(n=300, fs=100.0)
    path = write(tmp_path / "plate.txt", ["Fx\tFy\tFz", *(f"1\t2\t{f:.4f}" for f in force)])
    assert main(["identify", str(path), "--mass", str(MASS), "--out", str(tmp_path / "out"), *options]) == 2
    error = capsys.readouterr().err.strip()
    assert message in error and "\n" not in error, error

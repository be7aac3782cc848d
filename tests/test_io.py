"""Record reading and checking: every bad input is a one-line typed error."""

import numpy as np
import pytest

from smd_statespace.errors import MassError, RecordError, SMDInputError
from smd_statespace.io import G, make_record, read_record, write_record

MASS = 70.0


def good_rows(n=400, fs=100.0):
    t = np.arange(n) / fs
    force = MASS * G * (1 + 0.3 * np.sin(2 * np.pi * 2 * t))
    return t, force


def write_csv(path, text):
    path.write_text(text)
    return path


def test_round_trip(tmp_path):
    t, force = good_rows()
    record = make_record(t, force, MASS, floor_acc=0.01 * np.sin(t))
    write_record(tmp_path / "r.csv", record)
    back = read_record(tmp_path / "r.csv", MASS)
    np.testing.assert_allclose(back.time, t, atol=1e-6)
    np.testing.assert_allclose(back.force, force, atol=1e-6)
    np.testing.assert_allclose(back.floor_acc, record.floor_acc, atol=1e-6)
    assert back.fs == pytest.approx(100.0)
    assert back.source.endswith("r.csv")


@pytest.mark.parametrize(
    "mass,pattern",
    [(0, "positive"), (-5, "positive"), (float("nan"), "positive"), (700, "implausible"), (3, "implausible"),
     ("heavy", "not a number")],
)
def test_bad_mass(mass, pattern):
    t, force = good_rows()
    with pytest.raises(MassError, match=pattern):
        make_record(t, force, mass)


def csv_text(t, force):
    return "time,force\n" + "".join(f"{a},{b}\n" for a, b in zip(t, force))


@pytest.mark.parametrize(
    "mutate,pattern",
    [
        (lambda t, f: (t, f / (MASS * G)), "body weights"),
        (lambda t, f: (t, f / 1000.0), "kN"),
        (lambda t, f: (t, f * 3), "expected about mass\\*g"),
        (lambda t, f: (np.r_[t[:10], t[9], t[11:]], f), r"repeats at row 11 \(line 12\)"),
        (lambda t, f: (np.r_[t[:10], t[8], t[11:]], f), r"decreases at row 11 \(line 12\)"),
        (lambda t, f: (np.r_[t[:50], t[50:] + 0.004], f), r"non-uniform sampling at row 51 \(line 52\)"),
    ],
)
def test_bad_values(tmp_path, mutate, pattern):
    t, force = mutate(*good_rows())
    path = write_csv(tmp_path / "bad.csv", csv_text(t, force))
    with pytest.raises(RecordError, match=pattern) as info:
        read_record(path, MASS)
    assert "bad.csv" in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("token", ["nan", "inf", "-inf", "abc", ""])
def test_non_numeric_cell_names_column_and_row(tmp_path, token):
    t, force = good_rows()
    lines = csv_text(t, force).splitlines()
    lines[8] = f"{t[7]},{token}"
    path = write_csv(tmp_path / "cell.csv", "\n".join(lines) + "\n")
    with pytest.raises(RecordError, match=r"column 'force' row 8 \(line 9\)"):
        read_record(path, MASS)


def test_a_bad_row_is_named_by_its_file_line_across_blank_lines(tmp_path):
    """Blank lines between rows are skipped, and a bad value's message names the line an editor shows it on: its
    data row counts the values only."""
    t, force = good_rows()
    lines = csv_text(t, force).splitlines()
    lines[20] = f"{t[19]},heavy"  # data row 20
    lines[3:3] = ["", ""]  # two blank lines after data row 2: row 20 is now on line 23
    path = write_csv(tmp_path / "blank.csv", "\n".join(lines) + "\n")
    with pytest.raises(RecordError, match=r"column 'force' row 20 \(line 23\) holds 'heavy'"):
        read_record(path, MASS)
    with pytest.raises(RecordError, match=r"column 'force' row 20 \(line 23\)"):
        read_record(path)  # weighed: the provisional mass reads the force first
    lines[22] = f"{t[19]},{force[19]}"
    lines[30] = lines[29]  # data row 28 repeats row 27's time
    with pytest.raises(RecordError, match=r"column 'time' repeats at row 28 \(line 31\)"):
        read_record(write_csv(tmp_path / "again.csv", "\n".join(lines) + "\n"), MASS)


def test_structural_problems(tmp_path):
    t, force = good_rows()
    with pytest.raises(RecordError, match="no such file"):
        read_record(tmp_path / "missing.csv", MASS)
    with pytest.raises(RecordError, match="empty"):
        read_record(write_csv(tmp_path / "empty.csv", ""), MASS)
    with pytest.raises(RecordError, match="header only"):
        read_record(write_csv(tmp_path / "header.csv", "time,force\n"), MASS)
    with pytest.raises(RecordError, match="missing column 'force'"):
        read_record(write_csv(tmp_path / "cols.csv", csv_text(t, force).replace("force", "load", 1)), MASS)
    with pytest.raises(RecordError, match=r"data row 3 \(line 4\) has 3 fields"):
        lines = csv_text(t, force).splitlines()
        lines[3] += ",1"
        read_record(write_csv(tmp_path / "ragged.csv", "\n".join(lines)), MASS)
    with pytest.raises(RecordError, match="is a directory"):
        read_record(tmp_path, MASS)
    binary = tmp_path / "binary.csv"
    binary.write_bytes(b"\xff\xfe\x00\x81" * 20)
    with pytest.raises(SMDInputError):
        read_record(binary, MASS)


def test_errors_are_value_errors():
    assert issubclass(RecordError, ValueError) and issubclass(MassError, ValueError)


@pytest.mark.parametrize("value,options,problem", [
    ((2.0, 1.0), {}, "must satisfy low < high"),
    ((1.0, float("nan")), {}, "must satisfy low < high"),
    ((1.0,), {}, "must be a pair (low, high)"),
    ((1.0, 2.0, 3.0), {}, "must be a pair (low, high)"),
    ("fast", {}, "must be a pair (low, high)"),
    (None, {}, "must be a pair (low, high)"),
    ((0.0, 2.0), {"positive": True}, "must satisfy 0 < low < high"),
    ((-1.0, 2.0), {"minimum": 0.0}, "must not go below 0"),
])
def test_check_range_refuses_in_one_line_naming_the_option(value, options, problem):
    from smd_statespace.errors import OptionError, check_range

    with pytest.raises(OptionError) as info:
        check_range(value, "floor_mode: frequency_range", **options)
    message = str(info.value)
    assert message.startswith("floor_mode: frequency_range ") and problem in message and "\n" not in message


def test_check_range_gives_floats_and_is_the_check_of_every_range_option():
    """One validator: the model's prior ranges, an effect's ranges and the pipeline's fb_range all refuse with its
    words."""
    from smd_statespace.effects import make_effect
    from smd_statespace.errors import OptionError, check_range
    from smd_statespace.model import SMDModel

    assert check_range(("1", 2), "r") == (1.0, 2.0) and check_range([0.0, 1.0], "r", minimum=0.0) == (0.0, 1.0)
    with pytest.raises(OptionError, match="xi_h_range must not go below 0"):
        SMDModel(xi_h_range=(-0.1, 1.0))
    with pytest.raises(OptionError, match="floor_mode: damping_range must satisfy 0 < low < high"):
        make_effect("floor_mode:damping_range=0/0.1")
    with pytest.raises(OptionError, match="cubic_stiffness: beta_range must satisfy low < high"):
        make_effect("cubic_stiffness:beta_range=5/-5")


def test_a_record_with_the_empty_plate_before_and_after_is_read():
    """A lab's export reads 0 N before stepping on and after stepping off (BMClab's jump2.txt: 5 s of 10 off the
    plate, refused as 'mean 389 N, check the units'); the unit check takes the mean while someone is on the plate."""
    from smd_statespace.io import G, make_record

    t = np.arange(0.0, 10.0, 0.002)
    force = np.where((t > 2.0) & (t < 7.0), 70 * G * (1 + 0.3 * np.sin(2 * np.pi * 2 * t)), 0.0)
    assert make_record(t, force, 70.0).mass == 70.0
    with pytest.raises(RecordError, match="it looks like kN"):
        make_record(t, force / 1000.0, 70.0)
    with pytest.raises(RecordError, match="check the units"):
        make_record(t, force, 140.0)  # a wrong mass is still refused
    on = (t > 2.0) & (t < 7.0)  # a plate whose z axis points down: the force is negative under a load
    with pytest.raises(RecordError, match="vertical axis points down; multiply by -1"):
        make_record(t[on], -force[on], 70.0)
    with pytest.raises(RecordError, match=r"body weight was subtracted .* add mass\*g = 686.5 N"):
        make_record(t[on], force[on] - 70 * G, 70.0)  # a plate zeroed with the person standing on it
    with pytest.raises(RecordError, match="check the units"):
        make_record(t[on], np.full(on.sum(), 1e-3), 70.0)  # about 0 and flat: no body weight to have been taken off


def test_a_time_column_in_milliseconds_is_refused_in_one_line_that_says_so(tmp_path, capsys):
    """A plate's export in ms read as s samples at 0.1 Hz: it was taken, and the front end's filter then failed with
    a traceback (scipy: 'Wn[0] must be less than Wn[1]'). A rate under MIN_SAMPLING_RATE is refused, with the hint
    where the rate in ms would be one; a slow but readable rate is kept."""
    import pandas as pd

    from smd_statespace.cli import main
    from smd_statespace.io import G, MIN_SAMPLING_RATE, make_record

    t = np.arange(0.0, 12.0, 0.01)
    force = 70 * G * (1 + 0.3 * np.sin(2 * np.pi * 2 * t))
    with pytest.raises(RecordError, match=r"samples 10 s apart \(0.1 Hz\).*is 'time' in milliseconds"):
        make_record(t * 1000.0, force, 70.0)
    with pytest.raises(RecordError, match=r"at least 10 Hz \(time in s\)$"):
        make_record(t[::200] * 1000.0, force[::200], 70.0)  # 0.0005 Hz: not a rate in ms either
    step = 1.0 / MIN_SAMPLING_RATE
    assert make_record(np.arange(0.0, 12.0, step), np.full(round(12.0 / step), 70 * G), 70.0).mass == 70.0
    path = tmp_path / "ms.csv"
    pd.DataFrame({"time": t * 1000.0, "force": force}).to_csv(path, index=False)
    assert main(["identify", str(path), "--mass", "70", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "divide it by 1000" in err and "Traceback" not in err


def test_an_opensim_ground_reaction_file_is_read_as_the_plates_vertical_force(tmp_path):
    """OpenSim's ground-reaction files (a header block ending in endheader; each plate's ground_force1_vx, _vy,
    _vz, ..., y up) were refused as 'missing column time; the header is Squat Jump,,,...' (a real squat-jump export
    of two plates). The force is the sum of the plates' vertical columns; the other columns are not read."""
    t, force = good_rows()
    share = 0.4 + 0.1 * np.sin(2 * np.pi * 0.5 * t)  # the person's weight shifting between the two plates
    names = ["time", "ground_force1_vx", "ground_force1_vy", "ground_force1_vz", "ground_force1_px",
             "ground_force2_vx", "ground_force2_vy", "ground_force2_vz", "ground_force2_px"]
    preamble = ["Squat Jump" + "," * 8, "version=1" + "," * 8, f"nRows={t.size}" + "," * 8, "nColumns=9" + "," * 8,
                "inDegrees=yes" + "," * 8, "endheader" + "," * 8, ",".join(names)]
    rows = [",".join(f"{v:.9g}" for v in (ti, 4.2, fi * s, 53.4, 0.24, -2.2, fi * (1 - s), -53.8, 0.28))
            for ti, fi, s in zip(t, force, share)]
    record = read_record(write_csv(tmp_path / "grf.csv", "\n".join(preamble + rows) + "\n"), MASS)
    np.testing.assert_allclose(record.time, t, atol=1e-12)
    np.testing.assert_allclose(record.force, force, rtol=1e-8)
    plain = read_record(write_csv(tmp_path / "plain.csv", "time,force\n" + "\n".join(
        f"{ti:.9g},{fi:.9g}" for ti, fi in zip(t, force)) + "\n"), MASS)  # the same record in our own format
    np.testing.assert_allclose(record.force, plain.force, rtol=1e-8)

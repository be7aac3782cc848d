"""``smd-statespace structure``: its files and figures, bad input in one line with exit 2, Monte Carlo seeds."""

import json
from concurrent.futures import ThreadPoolExecutor

import pandas as pd
import pytest

from smd_statespace.cli import main
from smd_statespace.errors import OptionError, RecordError
from smd_statespace.structure.modes import beam, read_modal_model
from smd_statespace.structure.montecarlo import CrowdDraws, monte_carlo, percentiles


@pytest.fixture
def files(tmp_path):
    """A 3-mode beam written as modes.csv and shapes.csv, and a small people.csv."""
    modes, shapes = beam().write(tmp_path / "modes.csv", tmp_path / "shapes.csv")
    people = tmp_path / "people.csv"
    people.write_text("point,mass_kg,f_h,xi_h,active\nx15,70,2.8,0.3,1\nx10,,,,0\nx20,80,,,1\n", encoding="utf-8")
    return modes, shapes, people


def test_the_command_writes_the_summary_the_response_and_the_figures(files, tmp_path, capsys):
    modes, shapes, people = files
    out = tmp_path / "run"
    assert main(["structure", "--modes", str(modes), "--shapes", str(shapes), "--people", str(people),
                 "--duration", "6", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert [round(m["f_hz"], 6) for m in summary["empty_modes"]] == [4.0, 16.0, 36.0]
    assert len(summary["occupied_modes"]) == 3 and summary["occupied_modes"][0]["f_hz"] < 4.0
    assert summary["people"] == {"total": 3, "active": 2, "mass_kg": pytest.approx(summary["people"]["mass_kg"]),
                                 "contact_lost": 0}
    point = summary["points"][0]
    assert point["point"] == "x15" and set(point["coupled"]) == {"peak", "rms_1s_max", "vdv", "rms_1s_max_wb", "vdv_wb"}
    assert point["coupled"]["peak"] > 0 and point["force_only"]["peak"] > 0
    response = pd.read_csv(out / "response.csv")
    assert list(response.columns[:3]) == ["time", "x15_coupled", "x15_force_only"] and len(response) == 1201
    for name in ("structure_frf.png", "structure_rms.png"):
        assert (out / name).stat().st_size > 10_000
    printed = capsys.readouterr().out
    assert "mode 1: empty 4.000 Hz" in printed
    assert summary["limits"]["name"] == "istructe2008-route2" and summary["limits"]["measure"] == "rms_1s_max"
    assert point["limits"]["coupled"]["value"] == point["coupled"]["rms_1s_max"]
    assert point["limits"]["coupled"]["band"] in (0, 1, 2, 3) and point["limits"]["force_only"]["words"]
    assert f"limits at {summary['worst_point']} (IStructE/DCLG/DCMS (2008) Route 2 criteria" in printed
    worst = next(item for item in summary["points"] if item["point"] == summary["worst_point"])
    assert f"coupled: rms_1s_max {worst['coupled']['rms_1s_max']:.3f} m/s^2" in printed


def test_draws_write_their_table_percentiles_and_histogram(tmp_path):
    out = tmp_path / "mc"
    assert main(["structure", "--example", "sdof", "--people", "10", "--duration", "3", "--draws", "3",
                 "--out", str(out)]) == 0
    draws = pd.read_csv(out / "draws.csv")
    assert sorted(draws["draw"].unique()) == [0, 1, 2]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["draws"]["count"] == 3 and "P1" in summary["draws"]["points"]
    p95 = summary["draws"]["points"]["P1"]["coupled_rms_1s_max"]
    assert summary["draws"]["limits"]["P1"]["coupled"]["value"] == pytest.approx(p95)
    assert (out / "structure_draws.png").stat().st_size > 10_000


def write(path, text):
    path.write_text(text, encoding="utf-8")
    return str(path)


SHAPES = "point,x_m,y_m,phi_1,phi_2\nA,0,0,1,0.5\nB,1,0,0.5,-1\n"
MODES = "f_hz,zeta,mass_kg\n3,0.01,10000\n8,0.02,5000\n"


@pytest.mark.parametrize("modes, shapes, people, words", [
    ("f_hz,zeta,mass_kg\n3,0.01,10000\n", SHAPES, "point\nA\n", "phi_1 ... phi_1"),
    (MODES, SHAPES, "point\nA\nC\n", "row 2, column point: 'C' is not a point"),
    ("f_hz,zeta,mass_kg\n3,0.01,-10000\n8,0.02,5000\n", SHAPES, "point\nA\n", "row 1, column mass_kg"),
    ("f_hz,zeta,mass_kg\n3,-0.01,10000\n8,0.02,5000\n", SHAPES, "point\nA\n", "row 1, column zeta"),
    ("f_hz,zeta,mass_kg\n3,0.01,10000\n-8,0.02,5000\n", SHAPES, "point\nA\n", "row 2, column f_hz"),
    ("f_hz,zeta,mass_kg\n3,0.01,10000\n120,0.02,5000\n", SHAPES, "point\nA\n", "Nyquist frequency 100 Hz"),
    ("f_hz,mass_kg\n3,10000\n8,5000\n", SHAPES, "point\nA\n", "missing column 'zeta'"),
    (MODES, "point,x_m,y_m,phi_1\nA,0,0,1\n", "point\nA\n", "phi_1 ... phi_2"),
    (MODES, SHAPES, "point,mass_kg\nA,-70\n", "row 1, column mass_kg"),
    (MODES, SHAPES, "point,active\nA,2\n", "row 1, column active"),
    (MODES, SHAPES, "mass_kg\n70\n", "missing column 'point'"),
])
def test_bad_input_is_one_line_naming_file_row_and_column_and_exit_2(tmp_path, capsys, modes, shapes, people,
                                                                     words):
    args = ["structure", "--modes", write(tmp_path / "modes.csv", modes), "--shapes",
            write(tmp_path / "shapes.csv", shapes), "--people", write(tmp_path / "people.csv", people),
            "--duration", "2", "--out", str(tmp_path / "out")]
    assert main(args) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and words in error, error
    assert ".csv" in error or "Nyquist" in error


def test_the_library_raises_input_errors(tmp_path):
    with pytest.raises(RecordError, match="row 1, column zeta"):
        read_modal_model(write(tmp_path / "m.csv", "f_hz,zeta,mass_kg\n3,-1,1\n"),
                         write(tmp_path / "s.csv", "point,x_m,y_m,phi_1\nA,0,0,1\n"))
    with pytest.raises(OptionError, match="Nyquist"):
        beam().check_rate(50.0)
    assert issubclass(RecordError, ValueError) and issubclass(OptionError, ValueError)


def test_monte_carlo_gives_the_same_table_with_one_or_two_workers():
    spec = CrowdDraws(beam(), 12, active_share=0.5, duration=3.0)
    serial = monte_carlo(spec, 4, seed=11)
    with ThreadPoolExecutor(max_workers=2) as pool:
        threaded = monte_carlo(spec, 4, seed=11, executor=pool)
    pd.testing.assert_frame_equal(serial, threaded)
    assert serial["coupled_rms_1s_max"].nunique() > 1  # the draws differ from each other
    table = percentiles(serial)
    assert set(table.index) == set(serial["point"]) and (table["force_only_peak"] > 0).all()


def test_monte_carlo_on_a_dask_cluster_gives_the_serial_table():
    distributed = pytest.importorskip("distributed")
    spec = CrowdDraws(beam(), 8, active_share=0.5, duration=2.0)
    serial = monte_carlo(spec, 2, seed=3)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        clustered = monte_carlo(spec, 2, seed=3, executor=client.get_executor())
    pd.testing.assert_frame_equal(serial, clustered)


def test_identified_people_come_from_their_person_json(tmp_path):
    """A row naming a person.json (identify's answer: f_h, xi_h, f_b, blf_i, k_h) takes its values; cells given in
    people.csv win; a missing file is one line naming the row and column."""
    from smd_statespace.model import k_h
    from smd_statespace.structure.people import read_occupants

    person = {"f_h": 2.7, "xi_h": 0.33, "f_b": 2.1, "blf_1": 0.42, "blf_2": 0.11, "blf_3": 0.03,
              "k_h": float(k_h(2.7, 72.0)), "warnings": []}
    (tmp_path / "anna").mkdir()
    (tmp_path / "anna" / "person.json").write_text(json.dumps(person), encoding="utf-8")
    people = write(tmp_path / "people.csv", "point,mass_kg,xi_h,person_json\nx15,,,anna/person.json\n"
                                            "x10,80,0.5,anna/person.json\n")
    table = read_occupants(people, beam(), duration=3.0, seed=1).table
    first, second = table.iloc[0], table.iloc[1]
    assert (first["f_h"], first["xi_h"], first["f_b"], first["blf1"]) == (2.7, 0.33, 2.1, 0.42)
    assert first["mass"] == pytest.approx(72.0, rel=1e-12)
    assert (second["mass"], second["xi_h"], second["f_h"]) == (80.0, 0.5, 2.7)
    missing = write(tmp_path / "bad.csv", "point,person_json\nx15,nobody/person.json\n")
    with pytest.raises(RecordError, match="row 1, column person_json"):
        read_occupants(missing, beam(), duration=3.0, seed=1)

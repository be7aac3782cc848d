"""Human-structure interaction (Section 6): the coupled person-floor simulator and the study."""

import numpy as np
import pandas as pd
import pytest

from smd_statespace import OptionError, article
from smd_statespace.cli import main
from smd_statespace.simulation.floor import FloorModel, coupled_frf, coupled_response, simulate_on_floor
from smd_statespace.plotting.hsi import plot_floor, plot_parameters
from smd_statespace.studies.hsi import HSIStudy, hsi_study, pooled_least_squares
from smd_statespace.io import G
from smd_statespace.simulation import integrate_response, simulate_bouncing

PERSON = dict(mass=70.0, f_b=1.75, f_h=1.81, xi_h=0.33, blf=(0.241, 0.335, 0.082, 0.02))
THREE_MODES = FloorModel(frequency=(3.48, 6.14, 9.0), damping=(0.02, 0.03, 0.05), modal_mass=(2000.0, 1500.0, 3000.0),
                         shape=(1.0, 0.6, -0.8), name="three modes")


def harmonic_cycles(f, a1, t_end, b1=0.0):
    """One long 'cycle' of a pure harmonic force g (a1 cos + b1 sin)(2 pi f t)."""
    return pd.DataFrame({"t_start": [0.0], "t_end": [t_end], "f_b": [f], "a0": [0.0], "a1": [a1], "b1": [b1]})


def second_order(mass, f_h, xi_h, floor):
    """Masses, damping and stiffness of person + modes in (u, q_1..q_r), written out by hand."""
    phi = np.asarray(floor.shape)
    w_h = 2 * np.pi * f_h
    k_h, c_h = mass * w_h**2, 2 * xi_h * mass * w_h
    r = floor.n_modes
    big_m, big_c, big_k = np.zeros((r + 1, r + 1)), np.zeros((r + 1, r + 1)), np.zeros((r + 1, r + 1))
    big_m[0, 0] = mass
    # spring and damper between u and z = sum phi_k q_k
    big_k[0, 0], big_c[0, 0] = k_h, c_h
    for k in range(r):
        w_k = 2 * np.pi * floor.frequency[k]
        m_k = floor.modal_mass[k]
        big_m[k + 1, k + 1] = m_k
        big_k[k + 1, k + 1] += m_k * w_k**2
        big_c[k + 1, k + 1] += 2 * floor.damping[k] * m_k * w_k
        big_k[0, k + 1] = big_k[k + 1, 0] = -k_h * phi[k]
        big_c[0, k + 1] = big_c[k + 1, 0] = -c_h * phi[k]
        for j in range(r):
            big_k[k + 1, j + 1] += k_h * phi[k] * phi[j]
            big_c[k + 1, j + 1] += c_h * phi[k] * phi[j]
    return big_m, big_c, big_k


def test_one_mode_and_rigid_floor_match_the_ode_simulator():
    """The exact solution equals simulate_bouncing's DOP853 integration (floor_mode = mode 1 of Table 3)."""
    synthetic = simulate_bouncing(**PERSON, duration=12, seed=3, effects={"floor_mode": {}})
    exact = coupled_response(synthetic.cycles, synthetic.states["time"], 70.0, 1.81, 0.33, FloorModel.table3([1]))
    for column in ("u", "u_dot", "u_ddot", "z", "z_dot", "z_ddot"):
        reference = synthetic.states[column].to_numpy()
        assert np.max(np.abs(exact[column] - reference)) < 1e-7 * np.max(np.abs(reference)), column
    np.testing.assert_allclose(exact["force_bio"], synthetic.states["force_bio"], atol=1e-9)
    # from a given start, not the steady state
    start = [0.01, -0.05, 0.002, 0.01]
    ode = integrate_response(synthetic.cycles, synthetic.states["time"], 1.81, 0.33, mass=70.0,
                             effects={"floor_mode": {}}, initial_state=start)
    exact = coupled_response(synthetic.cycles, synthetic.states["time"], 70.0, 1.81, 0.33, FloorModel.table3([1]),
                             initial_state=start)
    for column in ("u", "u_ddot", "z", "z_ddot"):
        assert np.max(np.abs(exact[column] - ode[column])) < 1e-7 * np.max(np.abs(ode[column])), column
    rigid = simulate_bouncing(**PERSON, duration=8, seed=4)
    exact = coupled_response(rigid.cycles, rigid.states["time"], 70.0, 1.81, 0.33)
    assert "z" not in exact
    # one floor type: a floor written as an effect is the same floor in the exact solver, and back
    spec = "floor_mode:frequency=5.2,damping=0.01,modal_mass=3000"
    floor = FloorModel.from_effect(spec, 70.0)
    assert (floor.frequency, floor.damping, floor.modal_mass) == ((5.2,), (0.01,), (3000.0,))
    assert FloorModel.from_effect("floor_mode", 70.0) == FloorModel(*(getattr(FloorModel.table3([1]), key) for key in
                                                                        ("frequency", "damping", "modal_mass")),
                                                                      name="floor_mode 3.48 Hz")
    assert floor.as_effect(70.0).values == {"f_f": 5.2, "xi_f": 0.01, "mass_ratio": 70.0 / 3000.0}
    coupled = simulate_bouncing(**PERSON, duration=6, seed=5, effects=[spec], noise=0.0)
    replay, states = simulate_on_floor(simulate_bouncing(**PERSON, duration=6, seed=5, noise=0.0), spec)
    assert np.max(np.abs(states["z_ddot"] - coupled.states["z_ddot"])) < 1e-6 * np.max(np.abs(states["z_ddot"]))
    assert np.max(np.abs(exact["u_ddot"] - rigid.states["u_ddot"])) < 1e-7 * np.max(np.abs(rigid.states["u_ddot"]))


def energy(states, mass, f_h, floor):
    """Kinetic + elastic energy of person and modes (J)."""
    k_h = mass * (2 * np.pi * f_h) ** 2
    total = 0.5 * mass * states["u_dot"] ** 2 + 0.5 * k_h * (states["u"] - states["z"]) ** 2
    for k in range(floor.n_modes):
        m_k, w_k = floor.modal_mass[k], 2 * np.pi * floor.frequency[k]
        total += 0.5 * m_k * states[f"q{k + 1}_dot"] ** 2 + 0.5 * m_k * w_k**2 * states[f"q{k + 1}"] ** 2
    return total.to_numpy()


def test_undamped_free_vibration_conserves_energy():
    """No damping, no force: person and three modes trade energy, the sum stays put."""
    floor = FloorModel(THREE_MODES.frequency, (0.0, 0.0, 0.0), THREE_MODES.modal_mass, THREE_MODES.shape)
    time = np.linspace(0.0, 20.0, 4001)
    cycles = harmonic_cycles(1.0, 0.0, 21.0)
    start = [0.02, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    states = coupled_response(cycles, time, 70.0, 2.0, 0.0, floor, initial_state=start)
    e = energy(states, 70.0, 2.0, floor)
    np.testing.assert_allclose(e, e[0], rtol=1e-10)
    floor_share = 1.0 - (0.5 * 70.0 * states["u_dot"] ** 2 + 0.5 * 70.0 * (4 * np.pi) ** 2
                         * (states["u"] - states["z"]) ** 2) / e[0]
    assert floor_share.max() > 0.01  # the floor really takes part (a flipped coupling sign breaks the sum)


def test_work_of_the_biomechanical_force_is_the_energy_change():
    """Undamped and forced: E(t) - E(0) = integral of M g F (u' - z') dt (the internal force pair)."""
    floor = FloorModel(THREE_MODES.frequency, (0.0, 0.0, 0.0), THREE_MODES.modal_mass, THREE_MODES.shape)
    cycles = pd.DataFrame({"t_start": [0.0, 0.55], "t_end": [0.55, 1.1], "f_b": [1.8, 1.7], "a0": [0.0, 0.0],
                           "a1": [0.2, 0.25], "b1": [0.1, -0.05], "a2": [0.1, 0.12], "b2": [0.0, 0.05]})
    time = np.linspace(0.0, 1.0999, 22000)
    states = coupled_response(cycles, time, 70.0, 2.0, 0.0, floor, initial_state=np.zeros(8))
    e = energy(states, 70.0, 2.0, floor)
    power = 70.0 * states["force_bio"] * (states["u_dot"] - states["z_dot"])
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:].to_numpy() + power[:-1].to_numpy()) * np.diff(time))])
    assert e[-1] > 1.0  # the force did real work
    np.testing.assert_allclose(e - e[0], work, atol=1e-5 * e.max())


@pytest.mark.parametrize("floor", [FloorModel.table3([1]), THREE_MODES], ids=["one mode", "three modes"])
def test_steady_state_matches_the_analytic_frequency_response(floor):
    """From rest, after the transient has died out, the amplitudes are those of (K + i w C - w^2 M)^-1 F."""
    if floor.n_modes == 1:  # a livelier, better damped mode 1 so the transient dies within the run
        floor = FloorModel(floor.frequency, (0.04,), (2000.0,), name="mode 1, 2 t")
    mass, f_h, xi_h, f, a1 = 70.0, 2.0, 0.3, 3.3, 0.1
    time = np.arange(0.0, 30.0, 0.002)
    states = coupled_response(harmonic_cycles(f, a1, 31.0), time, mass, f_h, xi_h, floor,
                              initial_state=np.zeros(floor.n_state))
    big_m, big_c, big_k = second_order(mass, f_h, xi_h, floor)
    w = 2 * np.pi * f
    load = mass * G * a1 * np.concatenate([[1.0], -np.asarray(floor.shape)])
    amplitude = np.linalg.solve(big_k + 1j * w * big_c - w**2 * big_m, load)
    z_hat = amplitude[1:] @ np.asarray(floor.shape)
    late = time > 26.0
    assert np.max(np.abs(states["z_ddot"][late])) == pytest.approx(w**2 * abs(z_hat), rel=2e-3)
    assert np.max(np.abs(states["u_ddot"][late])) == pytest.approx(w**2 * abs(amplitude[0]), rel=2e-3)
    frf = coupled_frf(f, mass, f_h, xi_h, floor)
    assert abs(frf["z_ddot"][0]) * G * a1 == pytest.approx(w**2 * abs(z_hat), rel=1e-9)
    # the floor changes the person's response substantially here, so the check has teeth
    rigid = abs(coupled_frf(f, mass, f_h, xi_h)["u_ddot"][0]) * G * a1
    assert abs(w**2 * abs(amplitude[0]) / rigid - 1.0) > 0.1


def test_floor_model_table3_and_checks():
    plate = FloorModel.table3()
    assert plate.n_modes == 6 and plate.n_state == 14 and plate.shape == (1.0,) * 6
    assert plate.frequency == tuple(m.frequency for m in article.TABLE3)
    assert plate.modal_mass[0] == 8583.0 and plate.damping[0] == pytest.approx(0.0037)
    one = FloorModel.table3([1], shape=[0.5])
    assert one.n_modes == 1 and one.shape == (0.5,)
    assert FloorModel().n_modes == 0 and FloorModel().n_state == 2
    with pytest.raises(OptionError, match="modes must be among 1-6"):
        FloorModel.table3([7])
    with pytest.raises(OptionError, match="damping has 1 values, frequency has 2"):
        FloorModel(frequency=(3.0, 4.0), damping=(0.01,), modal_mass=(1.0, 2.0))
    with pytest.raises(OptionError, match="must be positive"):
        FloorModel(frequency=(3.0,), damping=(0.01,), modal_mass=(-5.0,))


def test_least_squares_recover_the_person_and_isolate_the_artefact():
    """Exact states: rigid floor -> the truth; plate with the floor term -> the truth; plate without -> biased."""
    synthetic = simulate_bouncing(**PERSON, duration=40, noise=0.0, seed=0)
    inside = synthetic.cycles[(synthetic.cycles.t_start >= 10) & (synthetic.cycles.t_end <= 40)]
    rigid = pooled_least_squares(synthetic.states, inside)
    assert (rigid["f_h"], rigid["xi_h"]) == (pytest.approx(1.81, rel=1e-6), pytest.approx(0.33, rel=1e-6))
    assert rigid["blf_2"] == pytest.approx(0.335, rel=0.05) and rigid["cycles"] == len(inside)
    _, states = simulate_on_floor(synthetic, FloorModel.table3(), seed=1)
    with_floor = pooled_least_squares(states, inside, floor=True)
    assert (with_floor["f_h"], with_floor["xi_h"]) == (pytest.approx(1.81, rel=1e-6), pytest.approx(0.33, rel=1e-6))
    ignored = pooled_least_squares(states, inside)
    assert ignored["f_h"] < 1.81 * 0.97 and ignored["xi_h"] > 0.33 * 1.05
    with pytest.raises(OptionError, match="fewer than two complete cycles"):
        pooled_least_squares(states, inside.iloc[:1])


def test_plate_record_keeps_the_force_and_noise_of_the_rigid_one():
    synthetic = simulate_bouncing(**PERSON, duration=10, seed=2)
    record, states = simulate_on_floor(synthetic, FloorModel.table3([1]), seed=5)
    noise = synthetic.record.force - 70.0 * (G + synthetic.states["u_ddot"].to_numpy())
    np.testing.assert_allclose(record.force - 70.0 * (G + states["u_ddot"].to_numpy()), noise, atol=1e-8)
    assert record.floor_acc is not None
    assert np.std(record.floor_acc - states["z_ddot"]) == pytest.approx(0.01 * np.sqrt(np.mean(states["z_ddot"] ** 2)),
                                                                        rel=0.1)
    with pytest.raises(OptionError, match="without effects"):
        simulate_on_floor(simulate_bouncing(**PERSON, duration=3, seed=1, effects={"floor_mode": {}}),
                          FloorModel.table3([1]))


def test_study_structure_and_the_direction_of_its_finding(tmp_path):
    """Short run: the table's layout, Table 4 copied right, and the artefact's direction."""
    study = hsi_study(duration=30, repeats=3, seed=0, identify=False)
    assert isinstance(study, HSIStudy)
    assert list(study.table.index) == ["f_h", "xi_h", "blf_1", "blf_2", "blf_3"]
    assert study.table.loc["f_h", "article_change_%"] == pytest.approx(-17.7)
    assert study.table.loc["blf_3", "article_plate"] == 0.046
    assert study.table.loc["xi_h", "truth"] == 0.33
    assert study.table["ekf_change_%"].isna().all()  # identify=False
    # the floor term removes the artefact exactly; ignoring it lowers f_h and raises xi_h ...
    assert np.abs(study.table["ls_floor_mode_change_%"]).max() < 1e-6
    assert study.table.loc["f_h", "ls_change_%"] < -1.0 and study.table.loc["xi_h", "ls_change_%"] > 5.0
    # ... but by much less than the article's -17.7 % for f_h, even with a floor twice as lively
    assert study.table.loc["f_h", "ls_change_%"] > 0.5 * -17.7
    assert study.sensitivity.loc[0.25, "floor_acc_rms"] > 1.8 * study.sensitivity.loc[1.0, "floor_acc_rms"]
    assert study.sensitivity.loc[0.25, "f_h_change_%"] > -17.7
    # modes 2-6 barely change the GRF: the one-mode artefact is within a few per cent of the six-mode one
    assert study.table.loc["f_h", "ls_mode1_change_%"] == pytest.approx(study.table.loc["f_h", "ls_change_%"], abs=1.5)
    floors = study.floors
    assert floors.loc["plate, 6 modes", "grf_change_rms_bw"] == pytest.approx(
        floors.loc["plate, mode 1", "grf_change_rms_bw"], rel=0.05)
    assert 0.5 < floors.loc["plate, 6 modes", "floor_acc_rms"] < 5.0
    text = study.finding()
    assert "NOT" in text and "f_h" in text and "-17.7 %" in text
    paths = study.write(tmp_path)
    assert (tmp_path / "hsi_table.csv").exists() and (tmp_path / "hsi_record_plate_6_modes.csv").exists()
    assert pd.read_csv(tmp_path / "hsi_table.csv", index_col=0).shape == study.table.shape
    assert len(paths) == 6
    plot_floor(study, tmp_path / "floor.png")
    plot_parameters(study, tmp_path / "parameters.png")
    assert (tmp_path / "floor.png").stat().st_size > 10_000


def test_study_identifies_with_the_library_and_the_command_line(tmp_path, capsys):
    """The whole command on a short record: tables, records, figures, the finding."""
    status = main(["hsi", "--out", str(tmp_path), "--duration", "10", "--repeats", "2", "--max-passes", "2",
                   "--quiet"])
    assert status == 0
    out = capsys.readouterr().out
    assert "Article (Table 4)" in out and "library identification (ekf" in out
    table = pd.read_csv(tmp_path / "hsi_table.csv", index_col=0)
    assert np.isfinite(table["ekf_change_%"]).all() and np.isfinite(table["ekf_floor_mode_change_%"]).all()
    cycles = pd.read_csv(tmp_path / "hsi_cycles.csv")
    assert set(cycles["condition"]) == {"rigid floor / rigid model", "plate, 6 modes / rigid model",
                                        "plate, 6 modes / floor_mode model"}
    for name in ("hsi_floor.png", "hsi_parameters.png", "hsi_run.json", "hsi_record_rigid_floor.csv"):
        assert (tmp_path / name).exists(), name


@pytest.mark.parametrize("argv, message", [
    (["hsi", "--duration", "5"], "too short"),
    (["hsi", "--duration", "-3"], "positive"),
    (["hsi", "--repeats", "0"], "whole number >= 1"),
    (["hsi", "--estimator", "magic"], "invalid choice"),
    (["hsi", "--seed", "x"], "non-negative whole number"),
])
def test_bad_options_are_one_line_and_status_2(argv, message, tmp_path, capsys):
    assert main(argv + ["--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and message in err


def test_out_must_be_a_directory(tmp_path, capsys):
    target = tmp_path / "file.txt"
    target.write_text("x")
    assert main(["hsi", "--out", str(target), "--quiet"]) == 2
    assert "not a directory" in capsys.readouterr().err


def test_batch_response_of_one_output_row_equals_the_states_route():
    """``output=(C, D)`` sums ``C x + D g F`` in the eigenbasis per cycle without forming the states: the same
    numbers as the states' route, for people on a rigid floor (the crowd's u'') and on the article's plate."""
    from smd_statespace.simulation.floor import batch_response, system_matrices
    from smd_statespace.simulation.person_forces import person_cycles

    rng = np.random.default_rng(np.random.SeedSequence(48))
    time = np.arange(0.0, 12.0, 0.005)
    f_h, xi_h, mass = rng.uniform(2, 4, 5), rng.uniform(0.1, 0.5, 5), rng.uniform(50, 90, 5)
    cycles = [person_cycles(np.random.SeedSequence([i]), 2.1, f_h[i], xi_h[i], [0.4, 0.2, 0.05], 13)[0]
              for i in range(5)]
    plate = FloorModel.table3()
    for floor in (None, plate):
        systems = [system_matrices(mass[i], f_h[i], xi_h[i], floor) for i in range(5)]
        a, b = np.stack([s[0] for s in systems]), np.stack([s[1] for s in systems])
        _, rates, _ = batch_response(a, b, cycles, time)
        u_ddot = batch_response(a, b, cycles, time, output=(a[:, 1], b[:, 1]))
        np.testing.assert_allclose(u_ddot, rates[:, :, 1], rtol=0, atol=1e-12 * np.abs(rates[:, :, 1]).max())

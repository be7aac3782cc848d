"""A crowd on a structure (smd_statespace.structure): closed forms, the one-person floor, limits, energy, metrics."""

import numpy as np
import pandas as pd
import pytest

from smd_statespace.io import G
from smd_statespace.simulation.bouncing import simulate_bouncing
from smd_statespace.simulation.floor import FloorModel, coupled_response, system_matrices
from smd_statespace.simulation.person_forces import rigid_floor_grf
from smd_statespace.structure.analysis import analyse_structure
from smd_statespace.structure.coupled import (Coupling, coupled_eigenvalues, modes_of, occupied_eigenvalues,
                                              person_coefficients, state_matrix)
from smd_statespace.structure.modes import beam, plate, sdof
from smd_statespace.structure.people import Occupants, draw_occupants
from smd_statespace.structure.response import measures, running_rms
from smd_statespace.structure.solve import solve


def quartic_roots(m, c, k, mp, cp, kp):
    """Eigenvalues of the 2-DOF system (structure m, c, k; people lumped mp, cp, kp on it), from its determinant."""
    # det [[m s^2 + (c + cp) s + k + kp, -(cp s + kp)], [-(cp s + kp), mp s^2 + cp s + kp]] = 0
    a = np.polymul([m, c + cp, k + kp], [mp, cp, kp])
    b = np.polymul([cp, kp], [cp, kp])
    return np.roots(np.polysub(a, np.concatenate([[0, 0], b])))


def test_identical_passive_people_at_one_point_of_an_sdof_are_a_two_dof_system():
    model = sdof(f_hz=4.0, zeta=0.01, mass_kg=20000.0)
    n, mass, f_h, xi_h = 40, 70.0, 5.0, 0.4
    coupling = Coupling(model, np.zeros(n, int), np.full(n, mass), np.full(n, f_h), np.full(n, xi_h))
    w, wh = 2 * np.pi * 4.0, 2 * np.pi * f_h
    roots = quartic_roots(20000.0, 2 * 0.01 * w * 20000.0, 20000.0 * w**2, n * mass, n * mass * 2 * xi_h * wh,
                          n * mass * wh**2)
    occupied = occupied_eigenvalues(coupling)[0]
    assert np.min(np.abs(roots - occupied)) < 1e-6 * abs(occupied)
    dense = coupled_eigenvalues(coupling)
    for root in roots:  # both pairs are eigenvalues of the full system; the other 2N - 2 are the people's own
        assert np.min(np.abs(dense - root)) < 1e-6 * abs(root)
    closest = roots[np.argmin(np.abs(roots - occupied))]
    mode = modes_of([occupied])[0]
    assert mode["f_hz"] == pytest.approx(abs(closest) / (2 * np.pi), rel=1e-6)
    assert mode["zeta"] == pytest.approx(-closest.real / abs(closest), rel=1e-6)
    assert mode["f_hz"] < 4.0 and mode["zeta"] > 0.01  # the crowd adds mass and damping


def test_person_coefficients_are_eq2_and_the_state_matrix_is_the_floor_modules_for_one_person():
    k, c = person_coefficients(2.5, 0.3)
    assert k == pytest.approx((2 * np.pi * 2.5) ** 2) and c == pytest.approx(2 * 0.3 * 2 * np.pi * 2.5)
    coupling = Coupling(plate(), [0], [70.0], [2.8], [0.3])
    ours = np.sort_complex(np.linalg.eigvals(state_matrix(coupling)))
    theirs = np.sort_complex(np.linalg.eigvals(system_matrices(70.0, 2.8, 0.3, FloorModel.table3())[0]))
    np.testing.assert_allclose(ours, theirs, rtol=1e-10)


def test_newton_eigenvalues_are_among_the_dense_ones_for_a_drawn_crowd():
    model = beam()
    occupants = draw_occupants(model, 60, active_share=0.5, duration=2.0, seed=4)
    table = occupants.table
    coupling = Coupling(model, table.point_index, table["mass"], table.f_h, table.xi_h)
    dense = coupled_eigenvalues(coupling)
    for root in occupied_eigenvalues(coupling):
        assert np.min(np.abs(dense - root)) < 1e-8 * abs(root)


def test_people_of_vanishing_mass_leave_the_force_only_response():
    """The difference falls in proportion to the people's mass (forcing at the first mode's resonance, 4 Hz)."""
    model = beam()
    rng = np.random.default_rng(1)
    points, f_h, xi_h = rng.integers(0, 31, 50), rng.uniform(2, 5, 50), rng.uniform(0.2, 0.5, 50)
    time = np.arange(2000) / 200.0
    loads = np.outer([300.0, -50.0, 20.0], np.sin(2 * np.pi * 4.0 * time))
    differences = []
    for mass in (1e-5, 1e-6):
        solution = solve(Coupling(model, points, np.full(50, mass), f_h, xi_h), loads, 200.0)
        scale = np.abs(solution.force_only).max()
        differences.append(np.abs(solution.coupled - solution.force_only).max() / scale)
    assert scale > 0.1
    assert differences[1] < 1e-6
    assert differences[0] / differences[1] == pytest.approx(10.0, rel=0.01)


def test_a_rigid_structure_does_not_move_and_each_persons_force_is_their_rigid_floor_grf():
    synthetic = simulate_bouncing(mass=70.0, f_b=2.0, f_h=2.8, xi_h=0.3, blf=(0.4, 0.15, 0.05), duration=10.0,
                                  fs=200.0, noise=0.0, seed=2)
    time, cycles = synthetic.record.time, synthetic.cycles
    grf = rigid_floor_grf([70.0], [2.8], [0.3], [cycles], time)
    np.testing.assert_allclose(grf[0], synthetic.record.force, atol=1e-6)  # the library's simulator, same person
    model = sdof(f_hz=4.0, zeta=0.01, mass_kg=1e12)
    table = pd.DataFrame({"person": [0], "point": ["P1"], "point_index": [0], "mass": [70.0], "f_h": [2.8],
                          "xi_h": [0.3], "active": [True], "f_b": [2.0]})
    occupants = Occupants(table, time, grf, [cycles], {"f_b": 2.0, "fs": 200.0})
    result = analyse_structure(model, occupants)
    coupled, force_only = result.accelerations()
    assert np.abs(coupled).max() < 1e-8 and np.abs(force_only).max() < 1e-8
    floor = result.solution.person_floor_response(result.coupling, [0])[0]
    on_structure = 70.0 * (G + synthetic.states["u_ddot"].to_numpy() + floor)
    np.testing.assert_allclose(on_structure, synthetic.record.force, atol=1e-6)


def one_person_on_the_plate(fs, variation):
    """Floor acceleration and COM acceleration of one person on the plate: ours and simulation.floor's (exact)."""
    synthetic = simulate_bouncing(mass=70.0, f_b=1.75, f_h=2.8, xi_h=0.3, blf=(0.5, 0.2, 0.05), duration=30.0,
                                  fs=fs, noise=0.0, seed=3, fb_variation=variation / 5, coef_variation=variation)
    cycles = synthetic.cycles.copy()
    cycles[["t_start", "t_end"]] -= cycles["t_start"].iloc[0]  # the first cycle starts at t = 0
    time = synthetic.record.time[synthetic.record.time < cycles["t_end"].iloc[-1]]
    rigid = coupled_response(cycles, time, 70.0, 2.8, 0.3)
    start = np.zeros(14)
    start[:2] = rigid["u"].iloc[0], rigid["u_dot"].iloc[0]  # the person as on a rigid floor, the plate at rest
    exact = coupled_response(cycles, time, 70.0, 2.8, 0.3, FloorModel.table3(), initial_state=start)
    coupling = Coupling(plate(), [0], [70.0], [2.8], [0.3])
    solution = solve(coupling, -70.0 * rigid["u_ddot"].to_numpy()[None].repeat(6, axis=0), fs)
    floor = solution.at(plate().shapes[0])[0][0]
    person = rigid["u_ddot"].to_numpy() + solution.person_floor_response(coupling, [0])[0]
    return floor, person, exact["z_ddot"].to_numpy(), exact["u_ddot"].to_numpy()


@pytest.mark.parametrize("fs, variation, tolerance", [(200.0, 0.0, 1e-3), (1000.0, 0.1, 2e-3)])
def test_one_person_on_the_articles_plate_is_the_section_6_coupling(fs, variation, tolerance):
    """Measured: 5.9e-4 (smooth force, 200 Hz) and 8.1e-4 (cycle-to-cycle variation, 1000 Hz) relative RMS error
    of the floor acceleration; the force's jumps at cycle boundaries give an error ~ 1/fs (3.9e-3 at 200 Hz)."""
    floor, person, exact_floor, exact_person = one_person_on_the_plate(fs, variation)
    error = np.sqrt(np.mean((floor - exact_floor) ** 2) / np.mean(exact_floor**2))
    assert error < tolerance
    assert np.sqrt(np.mean((person - exact_person) ** 2) / np.mean(exact_person**2)) < tolerance


def test_no_active_people_leaves_the_structure_at_rest():
    model = beam()
    occupants = draw_occupants(model, 30, active_share=0.0, duration=5.0, seed=5)
    assert occupants.grf.shape == (0, occupants.time.size)
    result = analyse_structure(model, occupants)
    coupled, force_only = result.accelerations()
    assert not coupled.any() and not force_only.any()
    point = result.summary()["points"][0]  # nothing to compare: no ratio (JSON null, not NaN)
    assert point["coupled"]["peak"] == 0.0 and point["coupled_over_force_only"]["peak"] is None


def test_free_decay_of_the_occupied_structure_follows_its_eigenvalues():
    """An impulse on the occupied SDOF, then free decay: the solution against exp(A t) of the 2-DOF state matrix
    (N identical people at one point move alike: one lumped person of N times the mass)."""
    model = sdof(f_hz=4.0, zeta=0.01, mass_kg=20000.0)
    n = 40
    coupling = Coupling(model, np.zeros(n, int), np.full(n, 70.0), np.full(n, 5.0), np.full(n, 0.4))
    fs, impulse = 200.0, 1000.0  # N s
    loads = np.zeros((1, 4000))
    loads[0, 1] = impulse * fs
    computed = solve(coupling, loads, fs).coupled[0]
    # exact: the structure and one lumped person (the N identical people move alike), x = [q, u, q', u']
    lumped = Coupling(model, [0], [n * 70.0], [5.0], [0.4])
    a_matrix = state_matrix(lumped)
    lam, vectors = np.linalg.eig(a_matrix)
    kick = np.linalg.solve(vectors, np.array([0, 0, impulse / 20000.0, 0], dtype=complex))
    tau = np.arange(2, 4000) / fs - 1.0 / fs
    states = (vectors @ (kick[:, None] * np.exp(lam[:, None] * tau[None]))).real
    exact = (a_matrix @ states)[2]
    # the band-limited impulse rings near its sample (Gibbs, ~1/t; measured 1.5e-2 of the peak at once, 1.0e-4 after
    # 1 s at 200 Hz): the free decay from 1 s on
    error = np.abs(computed[2:] - exact)[int(fs):]
    assert error.max() < 3e-4 * np.max(np.abs(exact))
    # and the decay rate of the late envelope is the structure-like eigenvalue's
    late = slice(200, 1200)  # 1-6 s: then the response is below 2e-3 of its peak
    envelope = np.array([np.abs(computed[k:k + 50]).max() for k in range(late.start, late.stop - 50, 50)])
    rate = -np.polyfit(np.arange(envelope.size) * 50 / fs, np.log(envelope), 1)[0]
    assert rate == pytest.approx(-occupied_eigenvalues(coupling)[0].real, rel=0.05)


def test_measures_of_a_sine_are_the_closed_forms():
    fs, amplitude, duration = 200.0, 0.5, 10.0
    time = np.arange(int(duration * fs)) / fs
    sine = amplitude * np.sin(2 * np.pi * 2.0 * time)
    values = measures(sine, fs)
    assert values["peak"] == pytest.approx(amplitude, rel=1e-12)
    assert values["rms_1s_max"] == pytest.approx(amplitude / np.sqrt(2), rel=1e-12)
    assert values["vdv"] == pytest.approx((3 * duration / 8) ** 0.25 * amplitude, rel=1e-12)
    np.testing.assert_allclose(running_rms(sine, fs), amplitude / np.sqrt(2), rtol=1e-9)
    assert running_rms(sine[:100], fs).size == 0


@pytest.mark.parametrize("modes", [None, [1], [2, 5]])
def test_the_plate_example_is_the_floor_modules_table3(modes):
    """``structure.plate`` takes its modes from ``FloorModel.table3`` (one selection of Table 3, not two)."""
    ours, theirs = plate(modes), FloorModel.table3(modes)
    for name in ("frequency", "damping", "modal_mass"):
        np.testing.assert_array_equal(getattr(ours, name), getattr(theirs, name))
    np.testing.assert_array_equal(ours.shapes, [theirs.shape])
    assert ours.points == ("mid-span",) and ours.name == "plate of Table 3, mid-span"


def test_a_standing_crowd_on_a_measured_bridge_adds_the_damping_it_measured_with_straight_knees():
    """Math. Probl. Eng. 2017, 1710820, Table 3 (benchmarks/structure_published.py has every row): the bridge's
    first mode 2.83 Hz, 0.42 % empty; with 15 people standing, the authors' FE with them as masses gives 2.42 Hz
    (so their sum phi^2 M is (2.82 / 2.42)^2 - 1 of the modal mass) and the bridge measured 2.40 Hz, 1.44 % with
    straight knees, 2.42 Hz, 9.57 % with bent knees. The passive person (5.0 Hz, 0.40) lumped at that share gives
    the straight-knee mode; the bent-knee damping it does not (another posture, another system)."""
    from smd_statespace.structure import PASSIVE

    mu = (2.82 / 2.42) ** 2 - 1.0
    coupling = Coupling(sdof(2.83, 0.0042, 1000.0), [0], [mu * 1000.0], [PASSIVE["f_h"]], [PASSIVE["xi_h"]])
    mode = modes_of(occupied_eigenvalues(coupling))[0]
    assert mode["f_hz"] == pytest.approx(2.40, abs=0.06) and mode["zeta"] == pytest.approx(0.0144, abs=0.0025)
    assert mode["zeta"] < 0.0957 / 4

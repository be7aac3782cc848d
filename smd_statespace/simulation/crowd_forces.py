"""A crowd's forces: each person's force cycles and GRF, solved exactly or integrated with effects.

:func:`_person_cycles` draws a person's cycles in the order of
:func:`~smd_statespace.simulation.simulate_bouncing`; :func:`_simulate_forces`
turns them into GRFs, by the exact vectorised linear solution of
:func:`smd_statespace.simulation.floor.batch_response` (``CHUNK`` people at a
time) or, with effects, by integrating each person's model
(:func:`_with_extra_harmonics` adds an effect's force harmonics). Used by
:func:`~smd_statespace.simulation.crowd.simulate_crowd`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..io import G
from ..model import SMDModel
from .dynamics import _cycle_states, _simulation_effects, _System
from .effect_adapter import force_harmonics
from .force_shape import default_phases
from .variation import TRUNCATION_SD, _draw_cycles

N_HARMONICS = 3
"""Harmonics of each person's biomechanical force: BLF1-3, the ones Table 2 gives."""

CHUNK = 64
"""People integrated together by :func:`simulate_crowd` (memory ~ CHUNK x samples)."""


def _person_cycles(force_seed, f_b, f_h, xi_h, blf, duration, fb_variation, coef_variation, phase_spread):
    """One person's force cycles, drawn in the order of :func:`~smd_statespace.simulation.simulate_bouncing`."""
    rng = np.random.default_rng(force_seed)
    n = blf.size
    shortest = 1.0 / (f_b * (1.0 + TRUNCATION_SD * fb_variation))
    longest = 1.0 / (f_b * (1.0 - TRUNCATION_SD * fb_variation))
    n_max = int(np.ceil((duration + longest) / shortest)) + 2

    def normals(shape):
        return np.clip(rng.standard_normal(shape), -TRUNCATION_SD, TRUNCATION_SD)

    start_fraction = phase_spread * rng.random()
    eps = normals(n_max)
    amp_noise, phase_noise = normals((n_max, n)), normals((n_max, n))
    phases, _ = default_phases(blf, f_b, f_h, xi_h)
    t_start, t_end, frequency, amplitude, phase = _draw_cycles(
        (start_fraction, eps, amp_noise, phase_noise), duration, f_b, blf, phases, fb_variation, coef_variation)
    columns = {"cycle": np.arange(t_start.size), "t_start": t_start, "t_end": t_end, "f_b": frequency,
               "a0": np.zeros(t_start.size)}
    for i in range(n):
        columns[f"a{i + 1}"] = amplitude[:, i] * np.cos(phase[:, i])
        columns[f"b{i + 1}"] = amplitude[:, i] * np.sin(phase[:, i])
    return pd.DataFrame(columns), start_fraction


def _simulate_forces(indices, parameters, cycles, time, out, effects=()):
    """GRFs (N) of people ``indices`` into rows of ``out``: Eq. 2-3 solved exactly, ``CHUNK`` people at a time.

    With ``effects``, each person's model (Eq. 2 plus the effects' own
    terms, prepared for that person's mass) is integrated instead, one
    person at a time (:func:`~smd_statespace.simulation.integrate_response`'s
    engine); an effect's extra force harmonics join the person's cycles
    with the simulator's default phases and no cycle-to-cycle variation.
    """
    from .floor import batch_response, system_matrices

    if effects:
        person = SMDModel(n_harmonics=1)
        for i in indices:
            mass = float(parameters["mass"][i])
            prepared = _simulation_effects(effects, mass, where="crowd")
            harmonics = [force_harmonics(effect, person) for effect in prepared]
            person_cycles = _with_extra_harmonics(cycles[i], [h for h in harmonics if h is not None],
                                                  parameters, i)
            system = _System(parameters["f_h"][i], parameters["xi_h"][i],
                             [effect for effect, h in zip(prepared, harmonics) if h is None])
            states = _cycle_states(system, person_cycles, time)
            out[i] = mass * (G + states["u_ddot"].to_numpy())  # Eq. 3
        return
    for start in range(0, len(indices), CHUNK):
        chunk = indices[start:start + CHUNK]
        mass = parameters["mass"][chunk]
        systems = [system_matrices(parameters["mass"][i], parameters["f_h"][i], parameters["xi_h"][i]) for i in chunk]
        a_matrices = np.stack([a for a, _ in systems])
        b_vectors = np.stack([b for _, b in systems])
        u_ddot = batch_response(a_matrices, b_vectors, [cycles[i] for i in chunk], time,
                                output=(a_matrices[:, 1], b_vectors[:, 1]))  # Eq. 2's row: u''
        out[chunk] = mass[:, None] * (G + u_ddot)  # Eq. 3


def _with_extra_harmonics(cycles, extra, parameters, i):
    """A person's cycles with the extra force harmonics ``[(blf, phases), ...]`` of effects appended."""
    if not extra:
        return cycles
    blf = np.concatenate([np.asarray(amplitudes, dtype=float) for amplitudes, _ in extra])
    base = np.array([parameters[f"blf{k}"][i] for k in range(1, N_HARMONICS + 1)])
    given = [phases for _, phases in extra]
    default = default_phases(base, float(np.median(cycles["f_b"])), parameters["f_h"][i], parameters["xi_h"][i],
                             blf)[1]
    phases = default if all(p is None for p in given) else np.concatenate(
        [default[:len(a)] if p is None else np.asarray(p, float) for (a, _), p in zip(extra, given)])
    cycles = cycles.copy()
    for k, (amplitude, phase) in enumerate(zip(blf, phases), start=N_HARMONICS + 1):
        cycles[f"a{k}"], cycles[f"b{k}"] = amplitude * np.cos(phase), amplitude * np.sin(phase)
    return cycles

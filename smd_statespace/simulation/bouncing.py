"""Synthetic bouncing records with known truth.

A forward simulator of the spring-mass-damper (SMD) model of a bouncing
person, so that it can check the estimators. It shares with the estimators
only what defines the physics of an effect (each effect's own terms, see
:class:`~smd_statespace.model.Effect`); the base equation, the force, its
variation and the integration are its own, independent of the estimators'
discretisation:

- Eq. 2, ``u'' + 2 xi_h w_h u' + w_h^2 u = g F(t)``, integrated with
  :func:`scipy.integrate.solve_ivp` (DOP853, ``rtol`` 1e-10), restarted at every
  force-cycle boundary when the force coefficients jump there
  (:mod:`.dynamics`);
- Eq. 4, the biomechanical force in units of g,
  ``F = a0 + sum_i [a_i cos(i phi) + b_i sin(i phi)]`` with a bouncing phase
  ``phi`` that advances by 2 pi per force cycle, with cycle-to-cycle variation
  of five kinds (:data:`~.variation.VARIATIONS`): every cycle has its own frequency and
  coefficients, jumping at the cycle boundaries (``"jumps"``), or the
  frequency and coefficients drift smoothly in time (``"smooth"``,
  :mod:`.variation`); every coefficient jittered on its own from a start at
  rest (``"coefficients"``), one smooth pulse per cycle instead of a Fourier
  series (``"pulses"``), or a fixed shape under a wandering tempo
  (``"tempo"``, :mod:`.generators`);
- Eq. 3, ``GRF = M_h (g + u'')``, plus white measurement noise;
- optional physical effects beyond the base model, any registered effect
  (:mod:`smd_statespace.effects`: a vibrating floor mode, force harmonics
  above ``n``, a cubic leg spring, a user's), integrated from the effect's
  own acceleration and slot rates.

Symbols and names
-----------------
============ ============ ======== ==========================================
symbol       name         unit     meaning
============ ============ ======== ==========================================
``M_h``      ``mass``     kg       body mass
``f_b``      ``f_b``      Hz       bouncing frequency (force cycles per s)
``f_h``      ``f_h``      Hz       SMD natural frequency, ``w_h = 2 pi f_h``
``xi_h``     ``xi_h``     \\-      SMD damping ratio
``K_h``      ``K_h``      N/m      stiffness, Eq. 17
``C_h``      ``C_h``      N s/m    damping coefficient, Eq. 18
``BLF_i``    ``blf``      g        harmonic amplitude ``sqrt(a_i^2 + b_i^2)``, Eq. 5
``u``        ``u``        m        COM displacement from static equilibrium (absolute)
``z``        ``z``        m        floor displacement (floor_mode only), upward
============ ============ ======== ==========================================

Phase convention: harmonic ``i`` of a cycle is
``a_i cos(i theta) + b_i sin(i theta) = BLF_i cos(i theta - psi_i)`` with
``theta = 2 pi f_b (t - t_start)``, i.e. ``a_i = BLF_i cos psi_i`` and
``b_i = BLF_i sin psi_i``; ``phases`` are the ``psi_i`` (rad). With
``variation="smooth"`` or ``"tempo"`` ``theta(t)`` is the continuous phase
``2 pi int f_b(t) dt``, a multiple of 2 pi at every cycle start.

Random numbers come only from a :class:`numpy.random.Generator` built with
:func:`numpy.random.default_rng` from the ``seed`` argument, and are drawn in a
fixed order of fixed-size blocks, so switching an effect on or off does not
change the random numbers used by the rest of the record (with
``variation="smooth"`` the knots of the smooth processes take the place of the
cycles, and the knots of the run-in before the record come last; the
generators of :mod:`.generators` draw their own blocks first, then the noise).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd

from ..errors import OptionError
from ..io import G, Record, check_mass, make_record, write_record
from ..model import SMDModel, c_h, k_h
from ..model import acceleration_frf
from .dynamics import _cycle_states, _number, _simulation_effects, _System, _vector
from .effect_adapter import draw_inputs, force_harmonics, measured_signals, simulation_truth
from .generators import GENERATORS, TEMPO_MAX_FB_VARIATION, _check_pulses
from .variation import (SMOOTH_CORRELATION_CYCLES, TRUNCATION_SD, VARIATIONS, _cycles_frame, _draw_cycles,
                        _smooth_cycles, _smooth_force, _smooth_geometry, _smooth_run_in, _smooth_states)

__all__ = [
    "DEFAULT_BLF",
    "GRF_PHASE_LAG",
    "SAMPLE_SETTINGS",
    "SyntheticRecord",
    "simulate_bouncing",
    "default_phases",
    "write_sample",
    "sample_path",
    "sample_truth_path",
]

DEFAULT_BLF = (0.25, 0.15, 0.05, 0.02)
"""Default harmonic amplitudes ``BLF_1..BLF_4`` of the biomechanical force (g)."""

GRF_PHASE_LAG = math.pi / 4
"""Phase lag (rad) of every GRF harmonic in the default force shape.

With ``phases=None`` the force phases are chosen so that, on a rigid floor in
steady state, harmonic ``i`` of the dynamic GRF is
``A_i cos(i theta - pi/4)`` (then shifted so that the main peak is at the
cycle start): a sharp main peak with a fast rise and a slower fall, between
the symmetric all-cosine shape (peak 1.5-1.7 BW, shallow double trough) and a
sawtooth (all-sine, peak-to-trough range largest).
"""

SAMPLE_SETTINGS = {
    "mass": 70.0,
    "f_b": 2.0,
    "f_h": 2.5,
    "xi_h": 0.3,
    "duration": 30.0,
    "fs": 100.0,
    "seed": 2019,
}
"""Settings of the shipped sample record (other arguments at their defaults)."""

SAMPLE_CSV = "sample.csv"
SAMPLE_TRUTH = "sample_truth.json"


# ---------------------------------------------------------------------------
# small helpers


def steady_grf_shape(grf_amplitude, points):
    """Dynamic GRF over one cycle from its harmonics' amplitudes, with the phases of :func:`default_phases`.

    Harmonic ``k`` contributes ``A_k cos(k theta - pi/4)`` (:data:`GRF_PHASE_LAG`).

    Parameters
    ----------
    grf_amplitude : array_like, shape (..., K)
        Amplitudes ``A_k = |H(k f_b)| BLF_k`` of harmonics 1..K (body weights, or g).
    points : int
        Phases ``theta`` per cycle.

    Returns
    -------
    theta : ndarray, shape (points,)
        Cycle phases (rad), from 0, not reaching ``2 pi``.
    shape : ndarray, shape (..., points)
        The dynamic GRF at each phase, in the amplitudes' unit.
    """
    grf_amplitude = np.asarray(grf_amplitude, dtype=float)
    orders = np.arange(1, grf_amplitude.shape[-1] + 1)
    theta = np.linspace(0.0, 2.0 * np.pi, int(points), endpoint=False)
    return theta, grf_amplitude @ np.cos(np.outer(orders, theta) - GRF_PHASE_LAG)


def default_phases(blf, f_b, f_h, xi_h, extra_blf=()):
    """Force phases that give a realistic GRF shape on a rigid floor.

    The phases ``psi_i`` (rad, see the module docstring for the convention) are
    chosen so that in steady state harmonic ``i`` of the dynamic GRF is
    ``|H_i| BLF_i cos(i (theta + theta_p) - pi/4)``, ``H_i`` the response of
    Eq. 2 at ``i f_b`` (:func:`acceleration_frf`) and ``theta_p`` the shift
    that puts the main GRF peak of the base harmonics at the start of each
    cycle (``theta = 0``), where the article starts its cycles.

    Parameters
    ----------
    blf : array_like, shape (n,)
        Base harmonic amplitudes (g).
    f_b, f_h, xi_h : float
        Bouncing frequency (Hz), SMD natural frequency (Hz), damping ratio.
    extra_blf : array_like, shape (m,), optional
        Amplitudes of harmonics ``n+1..n+m`` (the ``harmonics`` effect); they
        get phases by the same rule without changing ``theta_p``.

    Returns
    -------
    base : ndarray, shape (n,)
        Phases of harmonics 1..n (rad, in (-pi, pi]).
    extra : ndarray, shape (m,)
        Phases of harmonics n+1..n+m (rad).
    """
    blf = np.asarray(blf, dtype=float)
    extra_blf = np.asarray(extra_blf, dtype=float).reshape(-1)
    n = blf.size
    orders = np.arange(1, n + extra_blf.size + 1)
    response = acceleration_frf(orders * f_b, f_h, xi_h)
    grf_amplitude = np.abs(response[:n]) * blf
    theta, shape = steady_grf_shape(grf_amplitude, 4096)
    theta_peak = float(theta[np.argmax(shape)]) if np.any(grf_amplitude > 0) else 0.0
    grf_phase = GRF_PHASE_LAG - orders * theta_peak
    force_phase = grf_phase + np.angle(response)
    wrapped = np.pi - np.mod(np.pi - force_phase, 2.0 * np.pi)
    return wrapped[:n], wrapped[n:]


def _resolve_seed(seed):
    """Return ``(generator, record)``: the Generator and a JSON-able seed record."""
    if isinstance(seed, np.random.Generator):
        return np.random.default_rng(seed), None  # the same Generator, its state not recordable
    if seed is None:
        seed = np.random.SeedSequence()
    if isinstance(seed, np.random.SeedSequence):
        if seed.spawn_key:
            record = {"entropy": seed.entropy, "spawn_key": list(seed.spawn_key)}
        else:
            record = seed.entropy
        return np.random.default_rng(seed), record
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise OptionError(
            f"seed must be None, a non-negative int, a numpy SeedSequence or a numpy Generator, got {seed!r}"
        )
    return np.random.default_rng(int(seed)), int(seed)


# ---------------------------------------------------------------------------
# the simulated record


@dataclass(frozen=True)
class SyntheticRecord:
    """A simulated record with everything that produced it.

    Attributes
    ----------
    record : Record
        The measurement an estimator sees: ``time`` (s), ``force`` (GRF, N,
        Eq. 3 plus noise), ``mass`` (kg) and, with ``floor_mode``,
        ``floor_acc`` (m/s^2, plus noise).
    truth : dict
        JSON-serialisable settings and derived values: ``mass, f_b, f_h,
        xi_h, K_h, C_h`` (Eq. 17-18), ``n_harmonics`` (base harmonics of the
        model, ``n``), ``n_force_harmonics`` (including the ``harmonics``
        effect), ``blf, phases, a0``, ``effects`` (with all parameters),
        ``seed, fs, duration, noise, variations``, ``n_cycles``.
    states : pandas.DataFrame
        Noise-free states per sample: ``time, cycle, u, u_dot, u_ddot,
        force_bio`` (absolute COM, SI; ``force_bio = g F`` in m/s^2) and, with
        a floor, ``z, z_dot, z_ddot``.
    cycles : pandas.DataFrame
        One row per force cycle: ``cycle, t_start, t_end, f_b, a0, a1, b1,
        ..., blf1, ...``: the coefficients of Eq. 4 referred to the cycle's
        own start (``F = a0 + sum a_i cos(2 pi i f_b (t - t_start)) + b_i
        sin(...)``) and the amplitudes (Eq. 5). The first cycle may start
        before ``t = 0`` and the last end after the record.
    """

    record: Record
    truth: dict
    states: pd.DataFrame
    cycles: pd.DataFrame

    def write(self, csv_path, truth_path=None):
        """Write the record as CSV and the truth as JSON.

        Parameters
        ----------
        csv_path : str or path-like
            Record file (columns ``time, force[, floor_acc]``, 6 decimals).
        truth_path : str or path-like, optional
            Truth file; default ``<csv stem>_truth.json`` beside the CSV. It
            holds :attr:`truth` plus ``"cycles"``: the per-cycle table as a
            dict of columns.

        Returns
        -------
        tuple of pathlib.Path
            ``(csv_path, truth_path)``.
        """
        csv_path = Path(csv_path)
        truth_path = csv_path.with_name(f"{csv_path.stem}_truth.json") if truth_path is None else Path(truth_path)
        write_record(csv_path, self.record)
        content = dict(self.truth)
        content["cycles"] = {
            column: [round(float(v), 10) if column != "cycle" else int(v) for v in self.cycles[column]]
            for column in self.cycles.columns
        }
        truth_path.write_text(_format_json(content), encoding="utf-8")
        return csv_path, truth_path


def _format_json(content):
    """JSON text with one top-level key (or one key of a nested dict) per line."""
    lines = []
    for key, value in content.items():
        if isinstance(value, dict) and value:
            inner = [f"  {json.dumps(k)}: {json.dumps(v)}" for k, v in value.items()]
            lines.append(f" {json.dumps(key)}: {{\n" + ",\n".join(inner) + "\n }")
        else:
            lines.append(f" {json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(lines) + "\n}\n"


# ---------------------------------------------------------------------------
# the public simulator's parts


def _check_simulation(mass, f_b, f_h, xi_h, duration, fs, blf, phases, a0, fb_variation, coef_variation, noise,
                      effects, variation):
    """Validate the arguments of :func:`simulate_bouncing`; return them checked and completed (a namespace)."""
    mass = check_mass(mass, source="mass")
    f_b = _number(f_b, "f_b (Hz)", positive=True)
    f_h = _number(f_h, "f_h (Hz)", positive=True)
    xi_h = _number(xi_h, "xi_h", positive=True)
    duration = _number(duration, "duration (s)", positive=True)
    fs = _number(fs, "fs (Hz)", positive=True)
    blf = _vector(blf, "blf (g)", nonnegative=True)
    a0 = _number(a0, "a0 (g)")
    fb_variation = _number(fb_variation, "fb_variation", nonnegative=True)
    coef_variation = _number(coef_variation, "coef_variation", nonnegative=True)
    noise = _number(noise, "noise", nonnegative=True)
    if fb_variation > 0.2:
        raise OptionError(f"simulate_bouncing: fb_variation must be 0-0.2 (relative), got {fb_variation!r}")
    if coef_variation > 1.0:
        raise OptionError(f"simulate_bouncing: coef_variation must be 0-1 (relative), got {coef_variation!r}")
    if not isinstance(variation, str) or variation not in VARIATIONS:
        raise OptionError(
            f"simulate_bouncing: variation must be one of {', '.join(map(repr, VARIATIONS))}, got {variation!r}"
        )
    if variation == "tempo" and fb_variation > TEMPO_MAX_FB_VARIATION:
        raise OptionError(f"simulate_bouncing: fb_variation must be 0-{TEMPO_MAX_FB_VARIATION:g} with "
                          f"variation='tempo', got {fb_variation!r}")
    if duration < 1.0 / f_b:
        raise OptionError(
            f"simulate_bouncing: duration {duration:g} s is shorter than one bouncing cycle (1/f_b = {1 / f_b:.3g} s)"
        )
    effects = _simulation_effects(effects, mass)
    person = SMDModel(n_harmonics=1)
    forcing = [force_harmonics(effect, person) for effect in effects]
    extra = [pair for pair in forcing if pair is not None]
    extra_blf = np.concatenate([np.asarray(pair[0], dtype=float) for pair in extra]) if extra else np.empty(0)
    given_extra = [pair[1] for pair in extra]
    system = _System(f_h, xi_h, [effect for effect, pair in zip(effects, forcing) if pair is None])
    n_base, n_extra = blf.size, extra_blf.size
    natural = np.abs(system.eigenvalues().imag).max() / (2.0 * np.pi) if system.effects else 0.0
    highest = max((n_base + n_extra) * f_b, natural)
    if fs < 4.0 * highest:
        raise OptionError(
            f"simulate_bouncing: fs {fs:g} Hz is too low; it must be at least 4 x the highest frequency "
            f"({highest:g} Hz), i.e. >= {4 * highest:g} Hz"
        )
    default_base, default_extra = default_phases(blf, f_b, f_h, xi_h, extra_blf)
    phases_given = phases is not None
    if phases is None:
        phases = default_base
    else:
        phases = _vector(phases, "phases (rad)")
        if phases.size != n_base:
            raise OptionError(f"simulate_bouncing: phases has {phases.size} values, blf has {n_base}")
    extra_phases = np.asarray(default_extra, dtype=float)
    if any(given is not None for given in given_extra):
        extra_phases = np.concatenate([default_extra[:len(pair[0])] if given is None else np.asarray(given, float)
                                       for pair, given in zip(extra, given_extra)])
    settings = SimpleNamespace(
        mass=mass, f_b=f_b, f_h=f_h, xi_h=xi_h, duration=duration, fs=fs, blf=blf, phases=phases, a0=a0,
        fb_variation=fb_variation, coef_variation=coef_variation, noise=noise, effects=effects, system=system,
        extra_phases=extra_phases, phases_given=phases_given,
        variation=variation, all_blf=np.concatenate([blf, extra_blf]),
        all_phases=np.concatenate([phases, extra_phases]),
    )
    if variation == "pulses":
        _check_pulses(settings)
    return settings


def _draw_blocks(rng, n_rows, n_base, n_extra, n_samples):
    """All random numbers but the ambient floor's, in their fixed order of fixed-size blocks.

    Returns ``((start_fraction, eps, amp_noise, phase_noise), grf_noise,
    floor_noise)``: ``n_rows`` truncated normals per cycle-variation quantity
    (cycles in jumps mode, knots in smooth mode), base harmonics' before the
    noise, extra harmonics' after it.
    """

    def normals(shape):
        return np.clip(rng.standard_normal(shape), -TRUNCATION_SD, TRUNCATION_SD)

    start_fraction = rng.random()
    eps = normals(n_rows)
    base_blocks = (normals((n_rows, n_base)), normals((n_rows, n_base)))
    grf_noise = rng.standard_normal(n_samples)
    floor_noise = rng.standard_normal(n_samples)
    extra_blocks = (normals((n_rows, n_extra)), normals((n_rows, n_extra)))
    amp_noise = np.concatenate([base_blocks[0], extra_blocks[0]], axis=1)
    phase_noise = np.concatenate([base_blocks[1], extra_blocks[1]], axis=1)
    return (start_fraction, eps, amp_noise, phase_noise), grf_noise, floor_noise


def _jump_record(settings, rng_blocks, time):
    """``(cycles, states)`` of the jumps variation."""
    s = settings
    t_start, t_end, frequency, amplitude, phase = _draw_cycles(
        rng_blocks, s.duration, s.f_b, s.all_blf, s.all_phases, s.fb_variation, s.coef_variation,
    )
    n_total = amplitude.shape[1]
    a = np.column_stack([amplitude[:, i] * np.cos(phase[:, i]) for i in range(n_total)])
    b = np.column_stack([amplitude[:, i] * np.sin(phase[:, i]) for i in range(n_total)])
    cycles = _cycles_frame(t_start, t_end, frequency, s.a0, a, b, amplitude)
    return cycles, _cycle_states(s.system, cycles, time)


def _smooth_record(settings, rng_blocks, run_in_knots, geometry, time):
    """``(cycles, states)`` of the smooth variation (``geometry`` from :func:`_smooth_geometry`)."""
    s = settings
    force = _smooth_force(rng_blocks, run_in_knots, geometry, s.f_b, s.fb_variation, s.a0, s.all_blf,
                          s.all_phases, s.coef_variation)
    first = int(np.floor(float(force.theta(force.pieces.x[0])) / (2.0 * np.pi))) + 1  # the run-in's first cycle
    t_start, t_end, frequency, a, b = _smooth_cycles(force, min(first, 0), s.duration)
    run_in = (t_start[0], t_end[0], frequency[0], a[0], b[0])
    keep = slice(-min(first, 0), None)  # cycles 0, 1, ...: the one holding t = 0 and the later ones
    cycles = _cycles_frame(t_start[keep], t_end[keep], frequency[keep], s.a0, a[keep], b[keep],
                           np.hypot(a[keep], b[keep]))
    return cycles, _smooth_states(s.system, force, run_in, cycles, time)


def _with_drawn_inputs(settings, rng):
    """``settings`` with each effect's random simulation inputs drawn (a new system when one drew any)."""
    drawn = tuple(draw_inputs(effect, rng, settings.duration) for effect in settings.effects)
    if all(new is old for new, old in zip(drawn, settings.effects)):
        return settings
    dynamic = [effect for effect in drawn if force_harmonics(effect, SMDModel(n_harmonics=1)) is None]
    system = settings.system.with_drawn_inputs(dynamic) if dynamic else settings.system
    return SimpleNamespace(**{**vars(settings), "effects": drawn, "system": system})


def _measured_record(settings, states, grf_noise, floor_noise):
    """The :class:`Record` an estimator sees: Eq. 3 plus noise (and the noisy floor acceleration)."""
    s = settings
    weight = s.mass * G
    force = s.mass * (G + states["u_ddot"].to_numpy()) + s.noise * weight * grf_noise  # Eq. 3
    columns = {}
    for effect in s.effects:
        columns.update(measured_signals(effect, states, floor_noise, s.noise))
    return make_record(states["time"].to_numpy(), force, s.mass, source="synthetic", **columns)


def _effects_truth(settings):
    """``{name: {key: value}}`` of the simulated effects, with the extra harmonics' phases as simulated."""
    out = {}
    for effect in settings.effects:
        truth = {key: (list(value) if isinstance(value, tuple) else value)
                 for key, value in simulation_truth(effect).items()}
        if "phases" in truth and force_harmonics(effect, SMDModel(n_harmonics=1)) is not None:
            truth["phases"] = [float(v) for v in settings.extra_phases]
        out[effect.name] = truth
    return out


def _truth(settings, seed_record, n_cycles, generator=None):
    """The JSON-serialisable truth of :attr:`SyntheticRecord.truth`.

    ``generator`` (the generators of :mod:`.generators`) holds the truth's
    ``variations`` and, for ``"pulses"``, its ``blf`` and ``phases``.
    """
    s = settings
    generator = generator or {}
    variations = generator.get("variations") or {
        "fb_variation": s.fb_variation,
        "coef_variation": s.coef_variation,
        "phase_jitter_rad": s.coef_variation,
        "truncation_sd": TRUNCATION_SD,
        "generator": s.variation,
    }
    if s.variation == "smooth":
        variations["correlation_cycles"] = SMOOTH_CORRELATION_CYCLES
        variations["correlation_time_s"] = SMOOTH_CORRELATION_CYCLES / s.f_b
    return {
        "source": "smd_statespace.simulation.simulate_bouncing",
        "mass": s.mass,
        "f_b": s.f_b,
        "f_h": s.f_h,
        "xi_h": s.xi_h,
        "K_h": float(k_h(s.f_h, s.mass)),  # Eq. 17
        "C_h": float(c_h(s.xi_h, s.f_h, s.mass)),  # Eq. 18
        "n_harmonics": int(s.blf.size),
        "n_force_harmonics": int(s.all_blf.size),
        "blf": generator.get("blf", [float(v) for v in s.blf]),
        "phases": generator.get("phases", [float(v) for v in s.phases]),
        "a0": s.a0,
        "effects": _effects_truth(s),
        "seed": seed_record,
        "fs": s.fs,
        "duration": s.duration,
        "noise": s.noise,
        "variations": variations,
        "n_cycles": int(n_cycles),
        "units": {
            "mass": "kg", "f_b": "Hz", "f_h": "Hz", "xi_h": "-", "K_h": "N/m", "C_h": "N*s/m",
            "blf": "g", "a0": "g", "phases": "rad", "fs": "Hz", "duration": "s", "noise": "body weight",
        },
    }


# ---------------------------------------------------------------------------
# the public simulator


def simulate_bouncing(
    mass=70.0,
    f_b=2.0,
    f_h=2.5,
    xi_h=0.3,
    duration=30.0,
    fs=100.0,
    blf=DEFAULT_BLF,
    phases=None,
    a0=0.0,
    fb_variation=0.02,
    coef_variation=0.10,
    noise=0.01,
    effects=None,
    seed=None,
    variation="jumps",
):
    """Simulate one person bouncing: GRF record plus the truth behind it.

    The COM obeys Eq. 2 under the biomechanical force of Eq. 4, integrated
    accurately (DOP853, ``rtol`` :data:`RTOL`), and the GRF is Eq. 3 plus
    noise. The force varies from cycle to cycle in one of five ways
    (:data:`VARIATIONS`):

    ``variation="jumps"`` (default)
        Each force cycle ``j`` has its own frequency ``f_b (1 + eps_j)``,
        ``eps_j ~ N(0, fb_variation)``, and its own harmonics: amplitude
        ``BLF_i (1 + delta)``, ``delta ~ N(0, coef_variation)``, phase
        ``psi_i + eta``, ``eta ~ N(0, coef_variation)`` rad (together a
        complex perturbation of relative size ``coef_variation``); all normals
        truncated at :data:`TRUNCATION_SD`, constant within a cycle, jumping at
        its boundaries (integrated by :func:`integrate_response`, restarted at
        each boundary).
    ``variation="smooth"``
        The same quantities are smooth processes of time with the same
        standard deviations and truncation, correlated over
        :data:`SMOOTH_CORRELATION_CYCLES` mean cycles (how they are made is
        described there): ``F(t) = a0 + sum_i BLF_i (1 + delta_i(t)) cos(i
        theta(t) - psi_i - eta_i(t))``, amplitudes floored at 0, with the
        continuous phase ``theta(t) = 2 pi int f_b (1 + eps(t)) dt``. A cycle
        is one advance of ``theta`` by 2 pi; its row of :attr:`cycles
        <SyntheticRecord.cycles>` has ``f_b = 1 / (t_end - t_start)`` and the
        time-averages over the cycle of ``a_i(t) = A_i(t) cos phi_i(t)`` and
        ``b_i(t) = A_i(t) sin phi_i(t)`` (referred to the cycle's own start,
        where ``theta`` is a multiple of 2 pi), so Eq. 4 with a cycle's row
        reproduces the force within the drift of the coefficients and
        frequency inside that cycle. The per-cycle ``f_b`` spread is about
        0.97 ``fb_variation`` (0.99 with jumps, from the truncation; a
        smooth cycle also averages the frequency over its length), and
        neighbouring cycles are alike (correlation about 0.85). One
        integration covers the run-in and the record.
    ``variation="coefficients"``
        Each cycle ``j`` has its own frequency ``f_b (1 + eps_j)`` as with
        ``"jumps"``, and each Fourier coefficient is jittered on its own:
        ``a_ij = a_i (1 + coef_variation N)``, ``b_ij = b_i (1 +
        coef_variation N)``, ``a_i = BLF_i cos psi_i``, ``b_i = BLF_i sin
        psi_i``, independent standard normals truncated at
        :data:`TRUNCATION_SD` (extra harmonics alike). The phase is
        continuous across cycle boundaries, the coefficients jump there. Cycle 0
        starts at ``t = 0`` with the person at rest (``u = u' = 0`` and every
        dynamic slot of the effects 0): no periodic steady state, the first
        cycles carry the start-up transient.
    ``variation="pulses"``
        No Fourier series: cycle ``j`` (frequency ``f_b (1 + eps_j)``) holds one
        squared-sine pulse on a baseline, ``F = a0 + h_j (sin^2(pi x) - r_j /
        2)``, ``x = (tau - s_j) / r_j`` within the pulse (``0 < x < 1``, else
        ``sin^2`` is 0), ``tau`` the cycle phase (0 to 1). Its width ``r_j =
        r (1 + c N)`` (:data:`~.generators.PULSE_CONTACT_RATIO` ``r``,
        clipped to 0.05-1), height ``h_j = h (1 + c N)`` and start ``s_j = (1 -
        r_j) / 2 + c N / (2 pi)`` (the first harmonic's phase jitters by ``c
        N`` rad; clipped to keep the pulse in its cycle) vary per cycle, ``c
        = coef_variation``. The force's mean over every cycle is ``a0`` (body
        weight carried) and ``1 + F`` stays above 0: an OptionError says
        when ``blf`` or ``coef_variation`` is too large for that, or when the
        GRF would fall below zero. The mean pulse cycle is a cycle's force
        averaged over the jitter of width, height and timing (quadrature
        over the truncated normals; without variation the centred pulse of
        width ``r``, height ``h``); its Fourier coefficients are the expected
        coefficients of a cycle, what a force template estimates. ``h`` makes
        its first-harmonic amplitude ``blf[0]``; its higher harmonics follow
        from the pulse shape (ratios about 1 : 0.66 : 0.29 : 0.05, a little
        less for the higher ones with jitter), the rest of ``blf`` sets only
        how many harmonics the truth and the cycles table hold. The truth's
        ``blf`` and ``phases`` are the Fourier coefficients (Eq. 4, the phase
        convention above) of the mean pulse cycle, the cycles table's each
        cycle's own (plus ``pulse_start``, ``pulse_width`` as fractions of
        the cycle and ``pulse_height`` in g), both computed numerically
        (FFT, :data:`~.generators.PULSE_GRID` points per cycle), so
        identified BLFs can be compared with them. ``phases`` must be None
        and the ``harmonics`` effect cannot be used.
    ``variation="tempo"``
        The force's shape is fixed (``blf``, ``phases``; no coefficient
        jitter, ``coef_variation`` unused) and the tempo wanders slowly, as
        a person following music: ``f_b(t) = f_b (1 + fb_variation e(t))``,
        ``e(t)`` a linear ramp of :data:`~.generators.TEMPO_RAMP` over the
        record (up or down at random) plus a random Fourier series of
        standard deviation 1 with periods of
        :data:`~.generators.TEMPO_WANDER_PERIOD` s and longer; the phase
        ``theta(t) = 2 pi int f_b(t) dt`` is exact and continuous.
        ``fb_variation`` at most 0.1. Cycles, the start and the run-in are
        as with ``"smooth"`` (``a_i``, ``b_i`` of every cycle are the fixed
        ones).

    ``a0`` is the same at all times. The record starts at a random point of
    the first cycle without a start-up transient: with ``"jumps"`` in the
    periodic steady state of that cycle's force (but a lightly damped floor,
    ``floor_mode``, needs its decay time to settle under cycle-to-cycle
    variation: see :class:`~smd_statespace.effects.FloorMode`); with ``"smooth"`` the integration starts
    :data:`SMOOTH_RUN_IN_DECAYS` decay times earlier (at most
    :data:`SMOOTH_RUN_IN_MAX`), in the periodic steady state of the
    averaged coefficients of the cycle there, so that the mismatch has
    decayed by ``t = 0``. Every registered effect works with both
    variations (extra harmonics vary like the base ones). ``"pulses"``
    and ``"tempo"`` start like ``"jumps"`` and ``"smooth"`` respectively,
    ``"coefficients"`` from rest at ``t = 0``; every effect works with
    them, except ``harmonics`` with ``"pulses"``.

    Parameters
    ----------
    mass : float
        Body mass ``M_h`` (kg).
    f_b : float
        Mean bouncing frequency (Hz).
    f_h : float
        SMD natural frequency (Hz), > 0.
    xi_h : float
        SMD damping ratio (-), > 0.
    duration : float
        Record length (s); samples at ``0, 1/fs, ..., duration``.
    fs : float
        Sampling frequency (Hz), at least 4 times the highest frequency in
        the record (highest harmonic ``n f_b``, floor frequency).
    blf : sequence of float
        Harmonic amplitudes ``BLF_1..BLF_n`` of the force (g), >= 0.
    phases : sequence of float, optional
        Harmonic phases ``psi_i`` (rad): ``a_i = BLF_i cos psi_i``,
        ``b_i = BLF_i sin psi_i``. Default :func:`default_phases`: a
        realistic GRF with its main peak at each cycle start.
    a0 : float
        Constant term of Eq. 4 (g).
    fb_variation : float
        Relative standard deviation of the cycle frequency, 0-0.2; with
        ``"tempo"`` the scale of the ramp and the wander, 0-0.1.
    coef_variation : float
        Relative standard deviation of the harmonic amplitudes (and standard
        deviation of the phase jitter, rad), 0-1; with ``"coefficients"`` of
        each ``a_i`` and ``b_i``, with ``"pulses"`` of the pulse's width and
        height (and its timing jitter, rad of the first harmonic); unused
        with ``"tempo"``.
    noise : float
        GRF noise standard deviation as a fraction of body weight
        ``M_h g``; also the default floor-acceleration noise (fraction of
        its RMS).
    effects : list of Effect or str, or dict, optional
        Physical effects beyond the base model, each defined once in
        :mod:`smd_statespace.effects` (a user's registered effect too):
        objects, ``NAME[:key=value,...]`` specs as on the command line, or
        ``{name: {key: value}}``. Keys are the effect's options or its
        parameter slots' true values (``cubic_stiffness:beta_3=400``,
        ``floor_mode:frequency=3.48,damping=0.0037,ambient=0.5``,
        ``harmonics:blf=0.04/0.03``); parameters not given take the effect's
        :attr:`~smd_statespace.model.Effect.simulation_defaults`. The
        simulator integrates the effect's own acceleration and slot rates
        (:class:`~smd_statespace.model.Effect`).
    seed : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Source of randomness (through :func:`numpy.random.default_rng`). With
        None a fresh SeedSequence is made and its entropy stored in the truth,
        so every record can be reproduced. The same seed gives the same
        record; with ``"smooth"`` the knots take the place of the cycles in
        the fixed order of blocks, so effects still leave the other random
        numbers unchanged.
    variation : {"jumps", "smooth", "coefficients", "pulses", "tempo"}
        Generator of the cycle-to-cycle variation (see above); the truth's
        ``variations["generator"]`` records it with its settings (with
        ``"smooth"`` also ``correlation_cycles`` and
        ``correlation_time_s``; ``"coefficients"``: ``initial_state``;
        ``"pulses"``: ``contact_ratio``, ``pulse_height_g``,
        ``requested_blf``, ...; ``"tempo"``: ``ramp``, ``ramp_direction``,
        ``wander_sd``, ``run_in_s``, ...).

    Returns
    -------
    SyntheticRecord

    Raises
    ------
    MassError
        Implausible body mass.
    OptionError
        Any other invalid argument (the message names it).
    """
    s = _check_simulation(mass, f_b, f_h, xi_h, duration, fs, blf, phases, a0, fb_variation, coef_variation, noise,
                          effects, variation)
    rng, seed_record = _resolve_seed(seed)
    n_samples = int(np.floor(s.duration * s.fs + 1e-9)) + 1
    time = np.arange(n_samples) / s.fs
    # Fixed-size blocks in a fixed order (see the module docstring).
    if s.variation != "smooth":
        shortest = 1.0 / (s.f_b * (1.0 + TRUNCATION_SD * s.fb_variation))
        longest = 1.0 / (s.f_b * (1.0 - TRUNCATION_SD * s.fb_variation))
        n_rows = int(np.ceil((s.duration + longest) / shortest)) + 2
    else:
        geometry = _smooth_geometry(s.duration, s.f_b, s.fb_variation)
        n_rows = geometry[1]
    if s.variation in GENERATORS:  # the generators of .generators: their own blocks, then the noise
        draw, make = GENERATORS[s.variation]
        rng_blocks, grf_noise, floor_noise = draw(rng, s, n_rows, n_samples)
    else:
        rng_blocks, grf_noise, floor_noise = _draw_blocks(rng, n_rows, s.blf.size, s.all_blf.size - s.blf.size,
                                                          n_samples)
    s = _with_drawn_inputs(s, rng)  # drawn last, so that they leave every other random number unchanged
    generator = None
    if s.variation in GENERATORS:
        cycles, states, generator = make(s, rng_blocks, time)
    elif s.variation == "jumps":
        cycles, states = _jump_record(s, rng_blocks, time)
    else:
        # Drawn last: the run-in's length depends on the effects; the record's processes do not use them.
        n_run = int(np.ceil(_smooth_run_in(s.system) * s.f_b))
        run_in_knots = np.clip(rng.standard_normal((n_run, 1 + 2 * s.all_blf.size)), -TRUNCATION_SD,
                               TRUNCATION_SD)
        cycles, states = _smooth_record(s, rng_blocks, run_in_knots, geometry, time)
    record = _measured_record(s, states, grf_noise, floor_noise)
    return SyntheticRecord(record=record, truth=_truth(s, seed_record, len(cycles), generator), states=states,
                           cycles=cycles)


# ---------------------------------------------------------------------------
# the shipped sample


def sample_path() -> Path:
    """Path of the shipped sample record ``data/sample.csv`` (70 kg, see :data:`SAMPLE_SETTINGS`)."""
    return Path(str(resources.files("smd_statespace").joinpath("data", SAMPLE_CSV)))


def sample_truth_path() -> Path:
    """Path of the truth of the shipped sample, ``data/sample_truth.json``."""
    return Path(str(resources.files("smd_statespace").joinpath("data", SAMPLE_TRUTH)))


def write_sample(directory) -> SyntheticRecord:
    """Regenerate the shipped sample (:data:`SAMPLE_SETTINGS`) into ``directory``.

    Writes ``sample.csv`` and ``sample_truth.json``; with the package's own
    ``data`` directory this reproduces the shipped files.

    Parameters
    ----------
    directory : str or path-like
        Existing directory.

    Returns
    -------
    SyntheticRecord
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise OptionError(f"write_sample: {directory} is not a directory")
    synthetic = simulate_bouncing(**SAMPLE_SETTINGS)
    synthetic.write(directory / SAMPLE_CSV, directory / SAMPLE_TRUTH)
    return synthetic

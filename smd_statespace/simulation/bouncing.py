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

Where the parts live
--------------------
:func:`simulate_bouncing`, its fixed blocks of random numbers and the jumps
and smooth records are here; the checked settings and the seed policy in
:mod:`.settings`, the default force shape (:func:`default_phases`) in
:mod:`.force_shape`, the result (:class:`SyntheticRecord`) in
:mod:`.synthetic`, its truth in :mod:`.truth`, the shipped sample's settings
and files in :mod:`.sample`. Every name is importable from here too.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ..errors import OptionError
from .dynamics import _cycle_states
from .effect_adapter import draw_inputs
from .force_shape import DEFAULT_BLF, GRF_PHASE_LAG, default_phases, steady_grf_shape  # noqa: F401 (from here too)
from .generators import GENERATORS
from .sample import SAMPLE_CSV, SAMPLE_SETTINGS, SAMPLE_TRUTH, sample_path, sample_truth_path  # noqa: F401
from .settings import _check_simulation, _resolve_seed
from .synthetic import SyntheticRecord, _measured_record
from .truth import _truth
from .variation import (SMOOTH_KERNELS, TRUNCATION_SD, _cycles_frame, _draw_cycles, _smooth_cycles, _smooth_force,
                        _smooth_geometry, _smooth_run_in, _smooth_states)

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


# ---------------------------------------------------------------------------
# the public simulator's parts


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
        rng_blocks, s.duration, s.f_b, s.all_blf, s.all_phases, s.fb_variation, s.coef_variation, s.phase_variation,
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
                          s.all_phases, s.coef_variation, SMOOTH_KERNELS[s.variation])
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
    drawn_for = {id(old): new for old, new in zip(settings.effects, drawn)}
    system = settings.system  # its effects are the settings' own (those with terms of their own, not harmonics)
    if system.effects:
        system = system.with_drawn_inputs([drawn_for[id(effect)] for effect in system.effects])
    return SimpleNamespace(**{**vars(settings), "effects": drawn, "system": system})


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
    phase_variation=None,
):
    """Simulate one person bouncing: GRF record plus the truth behind it.

    The COM obeys Eq. 2 under the biomechanical force of Eq. 4, integrated
    accurately (DOP853, ``rtol`` :data:`RTOL`), and the GRF is Eq. 3 plus
    noise. The force varies from cycle to cycle in one of six ways
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
    ``variation="matern"``
        As ``"smooth"``, with processes of Matern-3/2 covariance (the
        record-level model's own smooth variation) of the same correlation
        time: rougher, their spectrum falling as ``f^-4`` rather than
        ``exp(-f^2)`` (:data:`~.variation.VARIATIONS`).
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
    variation : {"jumps", "smooth", "coefficients", "pulses", "tempo", "matern"}
        Generator of the cycle-to-cycle variation (see above); the truth's
        ``variations["generator"]`` records it with its settings (with
        ``"smooth"`` and ``"matern"`` also ``correlation_cycles`` and
        ``correlation_time_s``; ``"coefficients"``: ``initial_state``;
        ``"pulses"``: ``contact_ratio``, ``pulse_height_g``,
        ``requested_blf``, ...; ``"tempo"``: ``ramp``, ``ramp_direction``,
        ``wander_sd``, ``run_in_s``, ...).
    phase_variation : float, optional
        With ``"jumps"``: the standard deviation (rad, 0-1) of each harmonic's
        phase jitter on its own, ``coef_variation`` then setting only the
        amplitudes'. None (default): ``coef_variation``, a perturbation of the
        same size in every direction of each harmonic's ``(a_i, b_i)``, as the
        record-level model's variation assumes. ``coef_variation=0`` with
        ``phase_variation=0.1``: a force whose harmonics keep their size and
        shift their phases from cycle to cycle (the truth's
        ``phase_jitter_rad``).

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
                          effects, variation, phase_variation)
    rng, seed_record = _resolve_seed(seed)
    n_samples = int(np.floor(s.duration * s.fs + 1e-9)) + 1
    time = np.arange(n_samples) / s.fs
    # Fixed-size blocks in a fixed order (see the module docstring).
    if s.variation not in SMOOTH_KERNELS:
        shortest = 1.0 / (s.f_b * (1.0 + TRUNCATION_SD * s.fb_variation))
        longest = 1.0 / (s.f_b * (1.0 - TRUNCATION_SD * s.fb_variation))
        n_rows = int(np.ceil((s.duration + longest) / shortest)) + 2
    else:
        geometry = _smooth_geometry(s.duration, s.f_b, s.fb_variation, SMOOTH_KERNELS[s.variation])
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

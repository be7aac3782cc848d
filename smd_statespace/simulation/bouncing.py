"""Synthetic bouncing records with known truth.

A forward simulator of the spring-mass-damper (SMD) model of a bouncing
person, independent of the estimator-side model (:mod:`smd_statespace.model`),
so that it can check the estimators:

- Eq. 2, ``u'' + 2 xi_h w_h u' + w_h^2 u = g F(t)``, integrated with
  :func:`scipy.integrate.solve_ivp` (DOP853, ``rtol`` 1e-10), restarted at every
  force-cycle boundary when the force coefficients jump there;
- Eq. 4, the biomechanical force in units of g,
  ``F = a0 + sum_i [a_i cos(i phi) + b_i sin(i phi)]`` with a bouncing phase
  ``phi`` that advances by 2 pi per force cycle, with cycle-to-cycle variation
  of two kinds (:data:`VARIATIONS`): every cycle has its own frequency and
  coefficients, jumping at the cycle boundaries (``"jumps"``), or the
  frequency and coefficients drift smoothly in time (``"smooth"``);
- Eq. 3, ``GRF = M_h (g + u'')``, plus white measurement noise;
- optional physical effects beyond the base model: a vibrating floor mode
  (human-structure interaction, Section 6), force harmonics above ``n`` and a
  cubic (hardening or softening) leg spring.

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
``variation="smooth"`` ``theta(t)`` is the continuous phase
``2 pi int f_b(t) dt``, a multiple of 2 pi at every cycle start.

Random numbers come only from a :class:`numpy.random.Generator` built with
:func:`numpy.random.default_rng` from the ``seed`` argument, and are drawn in a
fixed order of fixed-size blocks, so switching an effect on or off does not
change the random numbers used by the rest of the record (with
``variation="smooth"`` the knots of the smooth processes take the place of the
cycles, and the knots of the run-in before the record come last).
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
from scipy import optimize
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline, PPoly

from ..errors import OptionError
from ..io import G, Record, check_mass, make_record, write_record
from ..effects import build_effect, make_effect
from ..model import CycleInputs, SMDModel, c_h, k_h

__all__ = [
    "VARIATIONS",
    "SMOOTH_CORRELATION_CYCLES",
    "DEFAULT_BLF",
    "GRF_PHASE_LAG",
    "POPULATION_BOUNDS",
    "MASS_DISTRIBUTION",
    "SAMPLE_SETTINGS",
    "SyntheticRecord",
    "simulate_bouncing",
    "integrate_response",
    "default_phases",
    "acceleration_frf",
    "sample_population",
    "write_sample",
    "sample_path",
    "sample_truth_path",
]

RTOL = 1e-10
"""Relative tolerance of the DOP853 integration."""

ATOL = 1e-13
"""Absolute tolerance of the DOP853 integration (m and m/s)."""

TRUNCATION_SD = 3.0
"""Cycle-to-cycle variations are normal, truncated at this many standard deviations."""

VARIATIONS = ("jumps", "smooth")
"""Generators of the cycle-to-cycle force variation (``variation`` of :func:`simulate_bouncing`).

``"jumps"``
    Each force cycle ``j`` has its own frequency ``f_b (1 + eps_j)`` and
    harmonics (amplitude ``BLF_i (1 + delta_ij)``, phase ``psi_i + eta_ij``),
    constant within the cycle and jumping at its boundaries.
``"smooth"``
    The frequency ``f_b (1 + eps(t))`` and every harmonic's ``delta_i(t)`` and
    ``eta_i(t)`` are smooth random processes of time with the same standard
    deviations, correlated over :data:`SMOOTH_CORRELATION_CYCLES` cycles: the
    force has no jump anywhere.
"""

SMOOTH_CORRELATION_CYCLES = 2.5
"""Correlation time of the ``"smooth"`` variation, in mean bouncing cycles ``1 / f_b``.

Each process (``eps``, ``delta_i``, ``eta_i``) is made from independent
standard normals truncated at :data:`TRUNCATION_SD`, one per knot, the knots
``1 / f_b`` apart; a Gaussian kernel of standard deviation
``s = SMOOTH_CORRELATION_CYCLES / (2 f_b)`` sums them, divided at every time by
the root-sum-square of the kernel weights, so that the variance is the knots'
(that of the jumps) at every time. The autocorrelation is then
``exp(-tau^2 / (4 s^2))``: 1/e at ``tau = 2 s``, the correlation time (2.5
cycles: 0.85 at one cycle's lag, 0.53 at two, 0.24 at three, 0.02 at five). The smoothed
values, clipped at :data:`TRUNCATION_SD`, are sampled :data:`SMOOTH_GRID`
times per mean cycle and joined by a cubic spline (twice continuously
differentiable); the phase is its exact integral.
"""

SMOOTH_GRID = 32
"""Samples per mean bouncing cycle of the ``"smooth"`` processes (joined by a cubic spline)."""

SMOOTH_RUN_IN_DECAYS = 5.0
"""Run-in of the ``"smooth"`` variation, in decay times of the slowest mode.

A smoothly drifting force has no periodic steady state to start from, so the
integration starts this many decay times ``1 / (xi w)`` (the person's and,
with ``floor_mode``, the floor's) before the record, at most
:data:`SMOOTH_RUN_IN_MAX`, from the periodic steady state of the cycle there:
what is left of the mismatch at ``t = 0`` is ``exp(-5)`` = 0.7 % of it (the
mismatch itself is a few per cent of the COM motion).
"""

SMOOTH_RUN_IN_MAX = 60.0
"""Longest run-in (s) of the ``"smooth"`` variation (see :data:`SMOOTH_RUN_IN_DECAYS`)."""

_KERNEL_REACH = 6.0
"""The Gaussian kernel of the smooth processes is cut at this many standard deviations."""

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


def _number(value, name, *, positive=False, nonnegative=False, where="simulate_bouncing"):
    """Return ``value`` as a finite float or raise a one-line :class:`OptionError`."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {name} must be a number, got {value!r}") from None
    if not np.isfinite(number):
        raise OptionError(f"{where}: {name} must be finite, got {value!r}")
    if positive and number <= 0:
        raise OptionError(f"{where}: {name} must be positive, got {value!r}")
    if nonnegative and number < 0:
        raise OptionError(f"{where}: {name} must be zero or positive, got {value!r}")
    return number


def _vector(values, name, *, nonnegative=False, where="simulate_bouncing"):
    """Return a non-empty 1-D finite float array or raise :class:`OptionError`."""
    try:
        array = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {name} must be a sequence of numbers, got {values!r}") from None
    if array.ndim != 1 or array.size == 0:
        raise OptionError(f"{where}: {name} must be a non-empty 1-D sequence of numbers, got {values!r}")
    if not np.all(np.isfinite(array)):
        raise OptionError(f"{where}: {name} must hold finite numbers, got {values!r}")
    if nonnegative and np.any(array < 0):
        raise OptionError(f"{where}: {name} must hold amplitudes >= 0 (use phases for the sign), got {values!r}")
    return array


def acceleration_frf(frequency, f_h, xi_h):
    """Frequency response of Eq. 2 from force (in g) to COM acceleration (in g).

    Parameters
    ----------
    frequency : float or array_like
        Excitation frequency (Hz).
    f_h : float
        SMD natural frequency (Hz).
    xi_h : float
        SMD damping ratio (-).

    Returns
    -------
    complex ndarray
        ``H = -w^2 / (w_h^2 - w^2 + 2 i xi_h w_h w)``: the harmonic
        ``g C e^{i w t}`` of ``g F`` produces ``H g C e^{i w t}`` in ``u''``.
    """
    omega = 2.0 * np.pi * np.asarray(frequency, dtype=float)
    omega_h = 2.0 * np.pi * f_h
    return -(omega**2) / (omega_h**2 - omega**2 + 2j * xi_h * omega_h * omega)


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
    theta = np.linspace(0.0, 2.0 * np.pi, 4096, endpoint=False)
    shape = grf_amplitude @ np.cos(np.outer(orders[:n], theta) - GRF_PHASE_LAG)
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
# effects


def _simulation_effects(effects, mass, where="simulate_bouncing"):
    """Effects ready for forward simulation (every parameter at its true value), in the order given.

    ``effects`` is a sequence of :class:`~smd_statespace.model.Effect`
    objects or ``NAME[:key=value,...]`` specs, or a dict ``{name: {key:
    value}}`` with the same keys (:func:`~smd_statespace.effects.build_effect`).
    """
    if effects is None:
        return ()
    if isinstance(effects, str):
        effects = [effects]
    try:
        if hasattr(effects, "items"):
            built = [build_effect(name, options) for name, options in effects.items()]
        else:
            built = [make_effect(effect) for effect in effects]
    except OptionError as exc:
        raise OptionError(f"{where}: {exc}") from None
    except TypeError:
        raise OptionError(
            f"{where}: effects must be a list of effects or specs (e.g. ['floor_mode', 'cubic_stiffness:beta_3=400']) "
            f"or a dict {{name: {{option: value}}}}, got {effects!r}"
        ) from None
    names = [effect.name for effect in built]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise OptionError(f"{where}: effect {twice[0]!r} is given twice; give each effect once")
    person = SMDModel(n_harmonics=1)
    try:
        return tuple(effect.for_simulation(person, mass) for effect in built)
    except OptionError as exc:
        raise OptionError(f"{where}: {exc}") from None


# ---------------------------------------------------------------------------
# the dynamical system


def _slot_width(where: slice) -> int:
    return where.stop - where.start


class _System:
    """Right-hand side of Eq. 2 plus the effects' own terms, for forward simulation.

    The integrated state is ``[u, u', (the effects' dynamic slots)]`` (m,
    m/s, ...); the input is ``g F(t)`` (m/s^2). The effects' terms are their
    own :meth:`~smd_statespace.model.Effect.acceleration` and
    :meth:`~smd_statespace.model.Effect.slot_rates`, evaluated on the
    augmented state of an :class:`~smd_statespace.model.SMDModel` whose
    parameters are the truth (``f_h``, ``xi_h`` and every effect parameter a
    known value; the model's own force coefficients are zero, the force is
    the simulator's).
    """

    def __init__(self, f_h, xi_h, effects=()):
        self.omega_h = 2.0 * np.pi * float(f_h)
        self.xi_h = float(xi_h)
        self.effects = tuple(effects)
        self.model = SMDModel(n_harmonics=1, effects=self.effects) if self.effects else None
        if self.model is None:
            self.names = ("u", "u_dot")
        else:
            dynamic = [i for i, slot in enumerate(self.model.slots) if slot.kind == "dynamic"]
            self.dynamic = np.array(dynamic)
            self.names = tuple(self.model.state_names[i] for i in dynamic)
            self.template = np.zeros(self.model.n_state)
            self.template[self.model.index("f_h")] = f_h
            self.template[self.model.index("xi_h")] = xi_h
            self.inputs = CycleInputs(f_b=1.0)
            self._widths = [(effect, _slot_width(self.model.effect_slice(effect))) for effect in self.effects]
        self.n_state = len(self.names)
        self.a_matrix, self.b_vector = self._linear_matrices()
        self.linear = self._is_linear()

    def rates(self, x, force_g, t):
        """``(dx/dt, u'')`` for states ``x`` (shape (n_state, ...)) under input ``g F`` at time(s) ``t``."""
        w2, c = self.omega_h**2, 2.0 * self.xi_h * self.omega_h
        acc = -w2 * x[0] - c * x[1] + force_g  # Eq. 2
        if self.model is None:
            return np.stack(np.broadcast_arrays(x[1], acc)), acc
        x = np.asarray(x, dtype=float)
        full = np.broadcast_to(self.template, x.shape[1:] + self.template.shape).copy()
        full[..., self.dynamic] = np.moveaxis(x, 0, -1)
        for effect in self.effects:
            acc = acc + effect.acceleration(self.model, full, t, self.inputs)
        parts = [np.broadcast_to(x[1], np.shape(acc)), acc]
        for effect in self.effects:
            own = effect.slot_rates(self.model, full, t, self.inputs, acc)
            parts.extend(np.moveaxis(own, -1, 0))
        return np.stack(parts), acc

    def rhs(self, t, x, force):
        """Time derivative of the state ``x`` (shape (n_state,)) at time ``t`` (s)."""
        u, v = x[0], x[1]
        acc = -(self.omega_h**2) * u - 2.0 * self.xi_h * self.omega_h * v + G * force.scalar(t)  # Eq. 2
        if self.model is None:  # the fast path of the base model
            return np.array([v, acc])
        full = self.template.copy()
        full[self.dynamic] = x
        for effect in self.effects:
            acc = acc + effect.acceleration(self.model, full, t, self.inputs)
        out = np.empty(self.n_state)
        out[0], out[1] = v, acc
        start = 2
        for effect, width in self._widths:
            if width:
                out[start:start + width] = effect.slot_rates(self.model, full, t, self.inputs, acc)
                start += width
        return out

    def _linear_matrices(self):
        """``(A, B)`` of the linearisation at rest: ``x' = A x + B g F`` (central differences, step 1e-4)."""
        step = 1e-4
        eye = np.eye(self.n_state) * step
        a_matrix = (self.rates(eye, 0.0, 0.0)[0] - self.rates(-eye, 0.0, 0.0)[0]) / (2.0 * step)
        zero = np.zeros(self.n_state)
        b_vector = (self.rates(zero, 1.0, 0.0)[0] - self.rates(zero, -1.0, 0.0)[0]) / 2.0
        return a_matrix, b_vector

    def _is_linear(self):
        """Whether the rates are linear in the state (superposition holds at typical amplitudes)."""
        if self.model is None:
            return True
        scale = np.array([0.02, 0.2] + [self.model.slots[i].nominal or 0.02 for i in self.dynamic[2:]])
        first, second = scale * np.linspace(1.0, -0.7, self.n_state), scale * np.linspace(-0.4, 0.9, self.n_state)
        rest = self.rates(np.zeros(self.n_state), 0.0, 0.0)[0]

        def moved(x):
            return self.rates(x, 0.0, 0.0)[0] - rest

        both = moved(first + second)
        return bool(np.allclose(both, moved(first) + moved(second), rtol=1e-8, atol=1e-10 * np.abs(both).max()))

    def eigenvalues(self):
        """Eigenvalues of the linearisation (1/s): natural frequencies and decay rates of the system."""
        return np.linalg.eigvals(self.a_matrix)

    def slowest_decay(self):
        """Longest decay time (s) of the linearisation, 60 s when undamped."""
        rate = float(np.min(-self.eigenvalues().real))
        return 1.0 / rate if rate > 0 else 60.0


class _CycleForce:
    """Biomechanical force of one cycle (g), Eq. 4, referred to the cycle start."""

    def __init__(self, t_start, f_b, a0, a, b):
        self.t_start = float(t_start)
        self.omega = 2.0 * np.pi * float(f_b)
        self.a0 = float(a0)
        self.a = np.asarray(a, dtype=float)
        self.b = np.asarray(b, dtype=float)
        self.orders = np.arange(1, self.a.size + 1, dtype=float)

        self._terms = tuple(zip(self.a.tolist(), self.b.tolist()))

    def scalar(self, t):
        """Force (g) at one time ``t`` (s): the fast path for the ODE solver."""
        theta = self.omega * (t - self.t_start)
        cos_1, sin_1 = math.cos(theta), math.sin(theta)
        cos_i, sin_i = cos_1, sin_1
        total = self.a0
        for a_i, b_i in self._terms:  # Eq. 4, cos(i theta), sin(i theta) by rotation
            total += a_i * cos_i + b_i * sin_i
            cos_i, sin_i = cos_i * cos_1 - sin_i * sin_1, sin_i * cos_1 + cos_i * sin_1
        return total

    def __call__(self, t):
        """Force (g) at times ``t`` (s), any shape."""
        angle = np.multiply.outer(self.orders, self.omega * (np.asarray(t, dtype=float) - self.t_start))
        return self.a0 + self.a @ np.cos(angle) + self.b @ np.sin(angle)  # Eq. 4


class _Multisine:
    """A smooth random signal: ``sum_j A_j cos(2 pi f_j t + phi_j)`` (m/s^2)."""

    def __init__(self, frequencies, amplitudes, phases):
        self.omega = 2.0 * np.pi * np.asarray(frequencies, dtype=float)
        self.amplitudes = np.asarray(amplitudes, dtype=float)
        self.phases = np.asarray(phases, dtype=float)

    def scalar(self, t):
        """Value at one time ``t`` (s)."""
        return float(self.amplitudes @ np.cos(self.omega * t + self.phases))

    def __call__(self, t):
        """Values at times ``t`` (s), shape (T,)."""
        return self.amplitudes @ np.cos(np.multiply.outer(self.omega, np.asarray(t, dtype=float))
                                        + self.phases[:, None])


def ambient_floor_excitation(rms, f_f, xi_f, duration, phases):
    """External floor acceleration that makes the bare floor vibrate with RMS acceleration ``rms``.

    White in the band ``0.5 f_f``-``1.5 f_f``: lines ``1 / duration`` apart
    with the given random ``phases`` (rad, one per line, drawn by the caller;
    :func:`ambient_line_count` says how many). The amplitude makes the
    steady-state acceleration of the floor mode alone,
    ``z'' = -w_f^2 z - 2 xi_f w_f z' + e(t)``, have RMS ``rms`` (m/s^2).

    Returns
    -------
    _Multisine or None
        None when ``rms`` is 0.
    """
    if rms == 0.0:
        return None
    frequencies = 0.5 * f_f + np.arange(len(phases)) / duration
    omega, omega_f = 2.0 * np.pi * frequencies, 2.0 * np.pi * f_f
    gain = omega**2 / np.abs(omega_f**2 - omega**2 + 2j * xi_f * omega_f * omega)  # |z''| per unit e
    amplitude = rms / np.sqrt(0.5 * np.sum(gain**2))
    return _Multisine(frequencies, np.full(frequencies.size, amplitude), phases)


def ambient_line_count(f_f, duration):
    """Number of lines of :func:`ambient_floor_excitation` (band ``f_f`` wide, ``1 / duration`` apart)."""
    return int(np.floor(f_f * duration)) + 1


def _cycle_coefficients(cycles):
    """``(n_harmonics, a, b)`` arrays of shape (n_cycles, n) from a cycles table."""
    n = 0
    while f"a{n + 1}" in cycles.columns and f"b{n + 1}" in cycles.columns:
        n += 1
    a = cycles[[f"a{i}" for i in range(1, n + 1)]].to_numpy(dtype=float).reshape(len(cycles), n)
    b = cycles[[f"b{i}" for i in range(1, n + 1)]].to_numpy(dtype=float).reshape(len(cycles), n)
    return n, a, b


def _linear_steady_state(system, force):
    """State at the cycle start of the periodic response of the linear part to ``force``."""
    a_matrix, b_vector = system.a_matrix, system.b_vector
    identity = np.eye(system.n_state)
    try:
        state = -np.linalg.solve(a_matrix, b_vector * G * force.a0)
        for order, (a_i, b_i) in enumerate(zip(force.a, force.b), start=1):
            complex_amplitude = (a_i - 1j * b_i) * G  # g F term = Re(C e^{i w t})
            response = np.linalg.solve(1j * order * force.omega * identity - a_matrix, b_vector * complex_amplitude)
            state = state + response.real
    except np.linalg.LinAlgError:
        raise OptionError(
            "the undamped model is forced at its natural frequency: no steady state; "
            "give xi_h > 0 or an initial_state"
        ) from None
    return state


def _integrate_cycle(system, force, x0, t_start, t_end, t_eval):
    """Integrate one cycle; return (states at t_eval, state at t_end)."""
    times = np.append(t_eval, t_end)
    solution = solve_ivp(
        system.rhs,
        (t_start, t_end),
        x0,
        method="DOP853",
        t_eval=times,
        rtol=RTOL,
        atol=ATOL,
        args=(force,),
    )
    if solution.status != 0 or not np.all(np.isfinite(solution.y)):
        hint = ""
        if not system.linear:
            hint = f"; the effect(s) {', '.join(e.spec for e in system.effects)} may make the system unstable"
        raise OptionError(f"integration failed at t={t_start:.3f} s ({solution.message}){hint}")
    return solution.y[:, :-1], solution.y[:, -1]


def _periodic_state(system, force, period, t_start):
    """Periodic steady state at the cycle start under a repeated cycle force.

    Exact for the linear model; with a cubic spring the linear solution is the
    initial guess of a shooting (Newton) solve over one period, then a run-in
    of several decay times if shooting fails.
    """
    guess = _linear_steady_state(system, force)
    if system.linear:
        return guess
    empty = np.empty(0)

    def mismatch(x0):
        return _integrate_cycle(system, force, x0, t_start, t_start + period, empty)[1] - x0

    scale = np.maximum(np.abs(guess), 1e-6)
    solution = optimize.root(lambda s: mismatch(s * scale) / scale, guess / scale, method="hybr", tol=1e-12)
    state = solution.x * scale
    if solution.success and np.all(np.abs(mismatch(state)) <= 1e-9 * scale + 1e-12):
        return state
    decay = system.slowest_decay()
    for _ in range(int(np.ceil(min(60.0, max(3.0, 10.0 * decay)) / period))):
        guess = _integrate_cycle(system, force, guess, t_start, t_start + period, empty)[1]
    return guess


def integrate_response(cycles, time, f_h, xi_h, mass=70.0, effects=None, initial_state=None):
    """Integrate the SMD model (Eq. 2) under a piecewise-constant cycle force.

    The low-level engine of :func:`simulate_bouncing`, for user-defined forces
    and initial conditions. One :func:`scipy.integrate.solve_ivp` (DOP853,
    ``rtol`` = :data:`RTOL`) per force cycle, restarted at each boundary.

    Parameters
    ----------
    cycles : pandas.DataFrame
        One row per force cycle with columns ``t_start, t_end`` (s), ``f_b``
        (Hz), ``a0`` and ``a1, b1, ..., an, bn`` (g), the force of Eq. 4
        referred to the cycle start: ``F = a0 + sum a_i cos(2 pi i f_b
        (t - t_start)) + b_i sin(...)``. Consecutive cycles must be contiguous.
    time : array_like, shape (T,)
        Increasing output times (s) within ``[t_start[0], t_end[-1])``.
    f_h : float
        SMD natural frequency (Hz), > 0.
    xi_h : float
        SMD damping ratio (-), >= 0 (0 allowed here, for energy checks).
    mass : float
        Body mass (kg); matters only to effects that use it (a floor's
        ``modal_mass``).
    effects : list of Effect or str, or dict, optional
        Registered effects (:mod:`smd_statespace.effects`, a user's
        included) as objects, ``NAME[:key=value,...]`` specs or ``{name:
        {key: value}}``; their parameters take the given values, else the
        effect's :attr:`~smd_statespace.model.Effect.simulation_defaults`.
        Extra force harmonics are simply extra columns of ``cycles`` (the
        ``harmonics`` effect belongs to :func:`simulate_bouncing`), and the
        random ``ambient`` floor vibration too.
    initial_state : array_like, optional
        ``[u, u']`` (m, m/s), then the effects' dynamic slots (``[u, u', z,
        z']`` with a floor), at ``t_start[0]``. Default: the periodic steady
        state of the first cycle's force (no start-up transient).

    Returns
    -------
    pandas.DataFrame
        Columns ``time, cycle, u, u_dot, u_ddot, force_bio`` (m, m/s, m/s^2,
        ``g F`` in m/s^2) and every dynamic slot of the effects with its rate
        (a floor: ``z, z_dot, z_ddot``). Accelerations are evaluated from the
        equations of motion, not by differencing.
    """
    where = "integrate_response"
    f_h = _number(f_h, "f_h (Hz)", positive=True, where=where)
    xi_h = _number(xi_h, "xi_h", nonnegative=True, where=where)
    mass = check_mass(mass, source="mass")
    effects = _simulation_effects(effects, mass, where=where)
    person = SMDModel(n_harmonics=1)
    if any(effect.force_harmonics(person) is not None for effect in effects):
        raise OptionError(f"{where}: extra force harmonics are columns a5, b5, ... of cycles, not an effect here")
    required = {"t_start", "t_end", "f_b", "a0"}
    if not isinstance(cycles, pd.DataFrame) or not required <= set(cycles.columns) or len(cycles) == 0:
        raise OptionError(
            f"{where}: cycles must be a non-empty DataFrame with columns t_start, t_end, f_b, a0, a1, b1, ..."
        )
    time = np.asarray(time, dtype=float).reshape(-1)
    t_start = cycles["t_start"].to_numpy(dtype=float)
    t_end = cycles["t_end"].to_numpy(dtype=float)
    if time.size == 0 or not np.all(np.isfinite(time)) or np.any(np.diff(time) <= 0):
        raise OptionError(f"{where}: time must be a non-empty, finite, strictly increasing array")
    if time[0] < t_start[0] or time[-1] >= t_end[-1]:
        raise OptionError(
            f"{where}: time spans {time[0]:g}-{time[-1]:g} s, the cycles {t_start[0]:g}-{t_end[-1]:g} s; "
            "the cycles must cover every output time"
        )
    if np.any(t_end <= t_start) or np.any(np.abs(t_start[1:] - t_end[:-1]) > 1e-9):
        raise OptionError(f"{where}: cycles must have t_end > t_start and be contiguous (t_start[j+1] == t_end[j])")
    system = _System(f_h, xi_h, effects)
    if initial_state is not None:
        initial_state = _vector(initial_state, "initial_state", where=where)
        if initial_state.size != system.n_state:
            raise OptionError(
                f"{where}: initial_state needs {system.n_state} values ({', '.join(system.names)}), "
                f"got {initial_state.size}"
            )
    return _cycle_states(system, cycles, time, initial_state)


def _cycle_states(system, cycles, time, state=None):
    """The states table of ``system`` under the piecewise cycle force (checked arguments)."""
    t_start = cycles["t_start"].to_numpy(dtype=float)
    t_end = cycles["t_end"].to_numpy(dtype=float)
    _, a, b = _cycle_coefficients(cycles)
    f_b = cycles["f_b"].to_numpy(dtype=float)
    a0 = cycles["a0"].to_numpy(dtype=float)
    forces = [_CycleForce(t_start[j], f_b[j], a0[j], a[j], b[j]) for j in range(len(cycles))]
    if state is None:
        state = _periodic_state(system, forces[0], 1.0 / f_b[0], t_start[0])

    bounds = np.searchsorted(time, t_start, side="left")
    bounds = np.append(bounds, time.size)
    states = np.empty((system.n_state, time.size))
    cycle_index = np.empty(time.size, dtype=int)
    for j, force in enumerate(forces):
        inside = slice(bounds[j], bounds[j + 1])
        if time[inside].size == 0 and t_start[j] > time[-1]:
            break
        states[:, inside], state = _integrate_cycle(system, force, state, t_start[j], t_end[j], time[inside])
        cycle_index[inside] = j

    force_g = np.empty(time.size)
    for j in np.unique(cycle_index):
        mask = cycle_index == j
        force_g[mask] = G * forces[j](time[mask])
    return _states_frame(system, time, cycle_index, states, force_g)


def _states_frame(system, time, cycle_index, states, force_g):
    """The states table of :func:`integrate_response`; accelerations from the equations of motion.

    Every dynamic slot of the effects gets a column and so does its rate,
    named by differentiation (``z`` -> ``z_dot``, ``z_dot`` -> ``z_ddot``)
    unless that is a slot already.
    """
    rates, u_ddot = system.rates(states, force_g, time)
    frame = {
        "time": time,
        "cycle": cycle_index,
        "u": states[0],
        "u_dot": states[1],
        "u_ddot": u_ddot,
        "force_bio": force_g,
    }
    for k, name in enumerate(system.names[2:], start=2):
        frame[name] = states[k]
        rate = name[:-4] + "_ddot" if name.endswith("_dot") else name + "_dot"
        if rate not in system.names:
            frame[rate] = rates[k]
    return pd.DataFrame(frame)


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


def _draw_cycles(rng_blocks, duration, f_b, blf, phases, fb_variation, coef_variation):
    """Cycle table from pre-drawn standard normals; see :func:`simulate_bouncing`."""
    start_fraction, eps, amp_noise, phase_noise = rng_blocks
    frequency = f_b * (1.0 + fb_variation * eps)
    t_end = np.cumsum(1.0 / frequency) - start_fraction / f_b
    n_cycles = int(np.searchsorted(t_end, duration, side="right")) + 1
    frequency, t_end = frequency[:n_cycles], t_end[:n_cycles]
    t_start = np.concatenate([[-start_fraction / f_b], t_end[:-1]])
    amplitude = blf * np.maximum(1.0 + coef_variation * amp_noise[:n_cycles], 0.0)
    phase = phases + coef_variation * phase_noise[:n_cycles]
    return t_start, t_end, frequency, amplitude, phase


def _cycles_frame(t_start, t_end, frequency, a0, a, b, blf):
    """The cycles table: ``cycle, t_start, t_end, f_b, a0, a1, b1, ..., blf1, ...``."""
    n_cycles, n_total = a.shape
    columns = {
        "cycle": np.arange(n_cycles),
        "t_start": t_start,
        "t_end": t_end,
        "f_b": frequency,
        "a0": np.full(n_cycles, a0),
    }
    for i in range(n_total):
        columns[f"a{i + 1}"] = a[:, i]
        columns[f"b{i + 1}"] = b[:, i]
    for i in range(n_total):
        columns[f"blf{i + 1}"] = blf[:, i]
    return pd.DataFrame(columns)


# ---------------------------------------------------------------------------
# the smooth variation (VARIATIONS, SMOOTH_CORRELATION_CYCLES)


def _smooth_geometry(duration, f_b, fb_variation):
    """Grid and knots of the smooth processes: ``(t_lo, n_knots, reach)``.

    The grid ``t_lo + k / (SMOOTH_GRID f_b)`` starts a whole number of mean
    cycles before the earliest possible start of the first cycle and ends
    after the latest possible end of the last (``duration`` plus the longest
    cycle); the knots, one per mean cycle, start ``reach`` knots before the
    grid and end ``reach`` knots after it. All of it depends only on
    ``duration``, ``f_b`` and ``fb_variation``, so the number of random
    numbers drawn does too.
    """
    period = 1.0 / f_b
    longest = period / (1.0 - TRUNCATION_SD * fb_variation)
    before = int(np.ceil(longest / period)) + 1
    n_span = before + int(np.ceil((duration + longest) / period)) + 1
    reach = int(np.ceil(_KERNEL_REACH * 0.5 * SMOOTH_CORRELATION_CYCLES))
    return -before * period, n_span + 2 * reach + 1, reach


def _smooth_normals(knots, reach):
    """Gaussian-kernel smoothing of knot values onto the grid (:data:`SMOOTH_CORRELATION_CYCLES`).

    Parameters
    ----------
    knots : ndarray, shape (n_knots, m)
        Truncated standard normals, one per mean cycle.
    reach : int
        Knots beyond each end of the grid (the kernel's half-width in knots).

    Returns
    -------
    ndarray, shape ((n_knots - 1 - 2 reach) SMOOTH_GRID + 1, m)
        The processes at :data:`SMOOTH_GRID` points per knot interval, from
        knot ``reach`` to knot ``n_knots - 1 - reach``: the kernel-weighted
        sum of the knots divided by the root-sum-square of the weights (the
        knots' variance at every point), clipped at :data:`TRUNCATION_SD`.
    """
    width = 0.5 * SMOOTH_CORRELATION_CYCLES * SMOOTH_GRID  # kernel SD in grid steps
    offsets = np.arange(-reach * SMOOTH_GRID, reach * SMOOTH_GRID + 1)
    kernel = np.exp(-0.5 * (offsets / width) ** 2)
    spikes = np.zeros((knots.shape[0] - 1) * SMOOTH_GRID + 1)
    spikes[::SMOOTH_GRID] = 1.0
    scale = np.sqrt(np.convolve(spikes, kernel**2, mode="valid"))
    values = np.empty((scale.size, knots.shape[1]))
    for column in range(knots.shape[1]):
        spikes[::SMOOTH_GRID] = knots[:, column]
        values[:, column] = np.convolve(spikes, kernel, mode="valid") / scale
    return np.clip(values, -TRUNCATION_SD, TRUNCATION_SD)


class _SmoothForce:
    """Biomechanical force (g) of Eq. 4 with a smoothly varying frequency and coefficients.

    ``F(t) = a0 + sum_i A_i(t) cos(i theta(t) - phi_i(t))``, with the phase
    ``theta = theta_0 + 2 pi f_b (t + fb_variation E(t))``, ``E = int_0^t eps``,
    the amplitudes ``A_i = BLF_i max(1 + coef_variation delta_i(t), 0)`` and
    the phases ``phi_i = psi_i + coef_variation eta_i(t)``. ``pieces`` holds
    ``[E, eps, delta_1..m, eta_1..m]`` as one piecewise polynomial (degree 4,
    uniform breakpoints).
    """

    def __init__(self, pieces, theta_0, f_b, fb_variation, a0, blf, phases, coef_variation):
        self.pieces = pieces
        self.theta_0 = float(theta_0)
        self.f_b = float(f_b)
        self.omega = 2.0 * np.pi * self.f_b
        self.fb_variation = float(fb_variation)
        self.a0 = float(a0)
        self.blf = np.asarray(blf, dtype=float)
        self.phases = np.asarray(phases, dtype=float)
        self.coef_variation = float(coef_variation)
        self.orders = np.arange(1, self.blf.size + 1, dtype=float)
        self._breaks = pieces.x.tolist()
        self._step = (pieces.x[-1] - pieces.x[0]) / (pieces.x.size - 1)
        self._local = np.ascontiguousarray(np.moveaxis(pieces.c, 1, 0).transpose(0, 2, 1))  # (interval, column, power)
        self._terms = tuple(zip(self.blf.tolist(), self.phases.tolist()))
        self._interval, self._columns = -1, None  # the interval last used by scalar() and its coefficients

    def _parts(self, columns, t):
        """``(theta, A, phi)`` from the columns (shape (..., 2 + 2m)) at times ``t`` (shape (...))."""
        m = self.blf.size
        theta = self.theta_0 + self.omega * (t + self.fb_variation * columns[..., 0])
        amplitude = self.blf * np.maximum(1.0 + self.coef_variation * columns[..., 2 : 2 + m], 0.0)
        return theta, amplitude, self.phases + self.coef_variation * columns[..., 2 + m :]

    def scalar(self, t):
        """Force (g) at one time ``t`` (s): the fast path for the ODE solver (plain floats)."""
        interval = min(max(int((t - self._breaks[0]) / self._step), 0), len(self._breaks) - 2)
        if interval != self._interval:  # the solver mostly stays in one interval for several calls
            self._interval, self._columns = interval, self._local[interval].tolist()
        dt = t - self._breaks[interval]
        values = [(((c0 * dt + c1) * dt + c2) * dt + c3) * dt + c4 for c0, c1, c2, c3, c4 in self._columns]
        theta = self.theta_0 + self.omega * (t + self.fb_variation * values[0])
        variation, m = self.coef_variation, len(self._terms)
        total = self.a0
        for i, (blf_i, psi_i) in enumerate(self._terms):
            amplitude = blf_i * max(1.0 + variation * values[2 + i], 0.0)
            total += amplitude * math.cos((i + 1) * theta - psi_i - variation * values[2 + m + i])
        return total

    def __call__(self, t):
        """Force (g) at times ``t`` (s), any shape."""
        t = np.asarray(t, dtype=float)
        theta, amplitude, phase = self._parts(self.pieces(t), t)
        return self.a0 + np.sum(amplitude * np.cos(self.orders * theta[..., None] - phase), axis=-1)

    def theta(self, t):
        """Bouncing phase ``theta(t)`` (rad), continuous; a cycle is one advance by 2 pi."""
        t = np.asarray(t, dtype=float)
        return self.theta_0 + self.omega * (t + self.fb_variation * self.pieces(t)[..., 0])

    def frequency(self, t):
        """Instantaneous bouncing frequency ``f_b (1 + fb_variation eps(t))`` (Hz)."""
        return self.f_b * (1.0 + self.fb_variation * self.pieces(np.asarray(t, dtype=float))[..., 1])

    def coefficients(self, t):
        """``(a, b)`` at times ``t``, shape (..., m): ``a_i = A_i cos phi_i``, ``b_i = A_i sin phi_i`` (g)."""
        t = np.asarray(t, dtype=float)
        _, amplitude, phase = self._parts(self.pieces(t), t)
        return amplitude * np.cos(phase), amplitude * np.sin(phase)


def _smooth_run_in(system):
    """Run-in (s) before the record in smooth mode (:data:`SMOOTH_RUN_IN_DECAYS` of the slowest decay)."""
    return min(SMOOTH_RUN_IN_DECAYS * system.slowest_decay(), SMOOTH_RUN_IN_MAX)


def _smooth_force(rng_blocks, run_in_knots, geometry, f_b, fb_variation, a0, blf, phases, coef_variation):
    """The :class:`_SmoothForce` made from pre-drawn truncated standard normals at the knots.

    ``rng_blocks`` holds the start fraction and the knots of the record
    (columns ``eps``, ``delta_i``, ``eta_i``); ``run_in_knots`` (shape
    (n_run, 1 + 2m)) extends them into the past, nearest knot first, so the
    processes over the record do not depend on them.
    """
    start_fraction, eps, amp_noise, phase_noise = rng_blocks
    t_lo, _, reach = geometry
    knots = np.concatenate([run_in_knots[::-1], np.column_stack([eps, amp_noise, phase_noise])])
    values = _smooth_normals(knots, reach)
    grid = t_lo - run_in_knots.shape[0] / f_b + np.arange(values.shape[0]) / (SMOOTH_GRID * f_b)
    spline = CubicSpline(grid, values, axis=0)
    integral = spline.antiderivative()
    coefficients = np.zeros((5, grid.size - 1, values.shape[1] + 1))
    coefficients[:, :, 0] = integral.c[:, :, 0]
    coefficients[-1, :, 0] -= integral(0.0)[0]  # E(0) = 0
    coefficients[1:, :, 1:] = spline.c
    pieces = PPoly(coefficients, grid)
    return _SmoothForce(pieces, 2.0 * np.pi * start_fraction, f_b, fb_variation, a0, blf, phases, coef_variation)


def _smooth_cycles(force, first, duration, nodes=24):
    """Cycles ``first, first + 1, ...`` of a smooth force: ``(t_start, t_end, f_b, a, b)``.

    Cycle ``j`` is the advance of ``theta`` from ``2 pi j`` to ``2 pi (j + 1)``
    (boundaries by Newton's method from a linear interpolation on the grid):
    cycle 0 starts at or before ``t = 0``, the last one ends after
    ``duration``. ``f_b = 1 / (t_end - t_start)``; ``a, b`` (shape
    (n_cycles, m)) are the time-averages over the cycle of ``a_i(t)`` and
    ``b_i(t)`` (Gauss-Legendre quadrature with ``nodes`` points).
    """
    last = int(np.floor(force.theta(duration) / (2.0 * np.pi))) + 1
    targets = 2.0 * np.pi * np.arange(first, last + 1)
    breaks = force.pieces.x
    times = np.interp(targets, force.theta(breaks), breaks)
    for _ in range(8):
        times = times - (force.theta(times) - targets) / (2.0 * np.pi * force.frequency(times))
    if np.abs(force.theta(times) - targets).max() > 1e-8:
        raise RuntimeError("the cycle boundaries of the smooth variation did not converge")  # pragma: no cover
    t_start, t_end = times[:-1], times[1:]
    points, weights = np.polynomial.legendre.leggauss(nodes)
    inside = 0.5 * (t_start + t_end)[:, None] + 0.5 * (t_end - t_start)[:, None] * points
    a, b = force.coefficients(inside)
    return t_start, t_end, 1.0 / (t_end - t_start), 0.5 * weights @ a, 0.5 * weights @ b


def _smooth_states(system, force, run_in, cycles, time):
    """Integrate Eq. 2 under a smooth force: one DOP853 run through the run-in and the record.

    ``run_in`` is the cycle that starts the run-in, ``(t_start, t_end, f_b,
    a, b)``; the integration starts there, in the periodic steady state of
    that cycle's averaged coefficients at its frequency, the nearest periodic
    force to the smooth one (:data:`SMOOTH_RUN_IN_DECAYS`).
    """
    t_start, t_end, f_first, a, b = run_in
    state = _periodic_state(system, _CycleForce(t_start, f_first, force.a0, a, b), 1.0 / f_first, t_start)
    states, _ = _integrate_cycle(system, force, state, t_start, float(cycles["t_end"].iloc[-1]), time)
    cycle_index = np.searchsorted(cycles["t_start"].to_numpy(), time, side="right") - 1
    return _states_frame(system, time, cycle_index, states, G * force(time))


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
    if duration < 1.0 / f_b:
        raise OptionError(
            f"simulate_bouncing: duration {duration:g} s is shorter than one bouncing cycle (1/f_b = {1 / f_b:.3g} s)"
        )
    effects = _simulation_effects(effects, mass)
    person = SMDModel(n_harmonics=1)
    forcing = [effect.force_harmonics(person) for effect in effects]
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
    return SimpleNamespace(
        mass=mass, f_b=f_b, f_h=f_h, xi_h=xi_h, duration=duration, fs=fs, blf=blf, phases=phases, a0=a0,
        fb_variation=fb_variation, coef_variation=coef_variation, noise=noise, effects=effects, system=system,
        extra_phases=extra_phases,
        variation=variation, all_blf=np.concatenate([blf, extra_blf]),
        all_phases=np.concatenate([phases, extra_phases]),
    )


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


def _measured_record(settings, states, grf_noise, floor_noise):
    """The :class:`Record` an estimator sees: Eq. 3 plus noise (and the noisy floor acceleration)."""
    s = settings
    weight = s.mass * G
    force = s.mass * (G + states["u_ddot"].to_numpy()) + s.noise * weight * grf_noise  # Eq. 3
    columns = {}
    for effect in s.effects:
        columns.update(effect.measured_signals(states, floor_noise, s.noise))
    return make_record(states["time"].to_numpy(), force, s.mass, source="synthetic", **columns)


def _effects_truth(settings):
    """``{name: {key: value}}`` of the simulated effects, with the extra harmonics' phases as simulated."""
    out = {}
    for effect in settings.effects:
        truth = {key: (list(value) if isinstance(value, tuple) else value)
                 for key, value in effect.simulation_truth().items()}
        if "phases" in truth and effect.force_harmonics(SMDModel(n_harmonics=1)) is not None:
            truth["phases"] = [float(v) for v in settings.extra_phases]
        out[effect.name] = truth
    return out


def _truth(settings, seed_record, n_cycles):
    """The JSON-serialisable truth of :attr:`SyntheticRecord.truth`."""
    s = settings
    variations = {
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
        "blf": [float(v) for v in s.blf],
        "phases": [float(v) for v in s.phases],
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
    noise. The force varies from cycle to cycle in one of two ways
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

    ``a0`` is the same at all times. The record starts at a random point of
    the first cycle without a start-up transient: with ``"jumps"`` in the
    periodic steady state of that cycle's force (but a lightly damped floor,
    ``floor_mode``, needs its decay time to settle under cycle-to-cycle
    variation: see :class:`~smd_statespace.effects.FloorMode`); with ``"smooth"`` the integration starts
    :data:`SMOOTH_RUN_IN_DECAYS` decay times earlier (at most
    :data:`SMOOTH_RUN_IN_MAX`), in the periodic steady state of the
    averaged coefficients of the cycle there, so that the mismatch has
    decayed by ``t = 0``. Every registered effect works with both
    variations (extra harmonics vary like the base ones).

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
        Relative standard deviation of the cycle frequency, 0-0.2.
    coef_variation : float
        Relative standard deviation of the harmonic amplitudes (and standard
        deviation of the phase jitter, rad), 0-1.
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
    variation : {"jumps", "smooth"}
        Generator of the cycle-to-cycle variation (see above); the truth's
        ``variations["generator"]`` records it (with ``"smooth"`` also
        ``correlation_cycles`` and ``correlation_time_s``).

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
    if s.variation == "jumps":
        shortest = 1.0 / (s.f_b * (1.0 + TRUNCATION_SD * s.fb_variation))
        longest = 1.0 / (s.f_b * (1.0 - TRUNCATION_SD * s.fb_variation))
        n_rows = int(np.ceil((s.duration + longest) / shortest)) + 2
    else:
        geometry = _smooth_geometry(s.duration, s.f_b, s.fb_variation)
        n_rows = geometry[1]
    rng_blocks, grf_noise, floor_noise = _draw_blocks(rng, n_rows, s.blf.size, s.all_blf.size - s.blf.size,
                                                      n_samples)
    for effect in s.effects:  # drawn last, so that they leave every other random number unchanged
        effect.draw_simulation_inputs(rng, s.duration)
    if s.variation == "jumps":
        cycles, states = _jump_record(s, rng_blocks, time)
    else:
        # Drawn last: the run-in's length depends on the effects; the record's processes do not use them.
        n_run = int(np.ceil(_smooth_run_in(s.system) * s.f_b))
        run_in_knots = np.clip(rng.standard_normal((n_run, 1 + 2 * s.all_blf.size)), -TRUNCATION_SD,
                               TRUNCATION_SD)
        cycles, states = _smooth_record(s, rng_blocks, run_in_knots, geometry, time)
    record = _measured_record(s, states, grf_noise, floor_noise)
    return SyntheticRecord(record=record, truth=_truth(s, seed_record, len(cycles)), states=states, cycles=cycles)


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


# the population sampler lives in its own module; its names stay importable from here
from .population import MASS_DISTRIBUTION, POPULATION_BOUNDS, sample_population  # noqa: E402

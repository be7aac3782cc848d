"""Three more generators of the cycle-to-cycle force variation: ``"coefficients"``, ``"pulses"``, ``"tempo"``.

Written against assumptions of their own, unlike the two of :mod:`.variation`
(``"jumps"``, ``"smooth"``), so that the record-level identification can be
checked on forces it was not tuned on (:data:`~.variation.VARIATIONS`):

``"coefficients"``
    Every cycle jitters each Fourier coefficient separately,
    ``a_ij = a_i (1 + c N)``, ``b_ij = b_i (1 + c N)``, and its rate by
    ``fb_variation``; the person starts from rest at ``t = 0``.
``"pulses"``
    The force is no Fourier series: one squared-sine pulse per cycle on a
    constant baseline (:data:`PULSE_CONTACT_RATIO`), its width, height and
    timing jittered per cycle; the truth's ``blf`` and ``phases`` are the
    Fourier coefficients of the mean pulse cycle (the expectation of a
    cycle's force over the jitter, :func:`_mean_pulse`), computed numerically.
``"tempo"``
    A fixed Fourier shape under a slowly wandering tempo: a ramp over the
    record plus a slow random wander (:data:`TEMPO_RAMP`,
    :data:`TEMPO_WANDER_PERIOD`).

Each generator draws its random numbers from the simulator's Generator in a
fixed order of fixed-size blocks: its own blocks first, then the GRF and
floor noise, then (``"coefficients"``) the extra harmonics' jitter, then the
effects' inputs, so switching an effect on or off leaves the rest unchanged.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import OptionError
from ..io import G
from .dynamics import _cycle_states, _forces_states, _periodic_state, fourier_scalar
from .variation import TRUNCATION_SD, _cycles_frame, _phase_crossings, _smooth_run_in, _smooth_states

__all__ = ["NEW_VARIATIONS", "PULSE_CONTACT_RATIO", "PULSE_GRID", "TEMPO_MAX_FB_VARIATION", "TEMPO_RAMP",
           "TEMPO_WANDER_PERIOD"]

NEW_VARIATIONS = ("coefficients", "pulses", "tempo")
"""The generators of this module (names of :data:`~.variation.VARIATIONS`)."""

PULSE_CONTACT_RATIO = 0.45
"""Mean width of the ``"pulses"`` pulse, as a fraction of its cycle.

A squared-sine pulse of this width has harmonic amplitudes in the ratio
1 : 0.66 : 0.29 : 0.05 (``|sin(pi i r)| / (pi i |1 - i^2 r^2|)`` for width
``r``), close to the default ``blf`` (1 : 0.6 : 0.2 : 0.08), and no zero among
the first four.
"""

PULSE_GRID = 2048
"""Samples per cycle of the FFT that gives a pulse cycle's Fourier coefficients."""

PULSE_QUADRATURE = 24
"""Gauss-Legendre nodes per jittered quantity of the mean pulse cycle (:func:`_mean_pulse`)."""

PULSE_STEADY_HARMONICS = 64
"""Harmonics of a pulse cycle used for its linear periodic steady state (the start of the record)."""

PULSE_MIN_WIDTH = 0.05
"""Narrowest pulse (fraction of its cycle): the jittered width is clipped here and at 1."""

TEMPO_RAMP = 3.0
"""Change of the ``"tempo"`` frequency over the record, in units of ``fb_variation`` (relative).

The ramp runs linearly from ``f_b (1 - 1.5 fb_variation)`` at ``t = 0`` to
``f_b (1 + 1.5 fb_variation)`` at the end of the record, or down (the
direction is random): 9 % at ``fb_variation`` 0.03, over the record whatever
its length.
"""

TEMPO_WANDER_PERIOD = 10.0
"""Shortest period (s) of the ``"tempo"`` wander (:func:`_tempo_geometry`)."""

TEMPO_MAX_FB_VARIATION = 0.1
"""Largest ``fb_variation`` of ``"tempo"`` (ramp and wander together keep the frequency well above 0)."""


def _normals(rng, shape):
    """Standard normals truncated at :data:`TRUNCATION_SD`."""
    return np.clip(rng.standard_normal(shape), -TRUNCATION_SD, TRUNCATION_SD)


def _boundaries(frequency, duration, first_start):
    """``(t_start, t_end, frequency)`` of contiguous cycles from ``first_start`` until one ends after ``duration``."""
    t_end = first_start + np.cumsum(1.0 / frequency)
    n_cycles = int(np.searchsorted(t_end, duration, side="right")) + 1
    t_end, frequency = t_end[:n_cycles], frequency[:n_cycles]
    return np.concatenate([[first_start], t_end[:-1]]), t_end, frequency


# ---------------------------------------------------------------------------
# "coefficients": each coefficient jittered on its own, from rest


def _coefficients_draw(rng, s, n_rows, n_samples):
    """Blocks of ``"coefficients"``: ``(eps, a_noise, b_noise)``, GRF and floor noise."""
    n_base, n_extra = s.blf.size, s.all_blf.size - s.blf.size
    eps = _normals(rng, n_rows)
    base = (_normals(rng, (n_rows, n_base)), _normals(rng, (n_rows, n_base)))
    grf_noise = rng.standard_normal(n_samples)
    floor_noise = rng.standard_normal(n_samples)
    extra = (_normals(rng, (n_rows, n_extra)), _normals(rng, (n_rows, n_extra)))
    blocks = (eps, np.concatenate([base[0], extra[0]], axis=1), np.concatenate([base[1], extra[1]], axis=1))
    return blocks, grf_noise, floor_noise


def _coefficients_record(s, blocks, time):
    """``(cycles, states, truth)`` of ``"coefficients"``; cycle 0 starts at ``t = 0``, the person at rest."""
    eps, a_noise, b_noise = blocks
    t_start, t_end, frequency = _boundaries(s.f_b * (1.0 + s.fb_variation * eps), s.duration, 0.0)
    n_cycles = t_start.size
    a = s.all_blf * np.cos(s.all_phases) * (1.0 + s.coef_variation * a_noise[:n_cycles])
    b = s.all_blf * np.sin(s.all_phases) * (1.0 + s.coef_variation * b_noise[:n_cycles])
    cycles = _cycles_frame(t_start, t_end, frequency, s.a0, a, b, np.hypot(a, b))
    states = _cycle_states(s.system, cycles, time, np.zeros(s.system.n_state))
    variations = {"fb_variation": s.fb_variation, "coef_variation": s.coef_variation,
                  "truncation_sd": TRUNCATION_SD, "generator": "coefficients", "initial_state": "rest"}
    return cycles, states, {"variations": variations}


# ---------------------------------------------------------------------------
# "pulses": one squared-sine pulse per cycle on a baseline


def _pulse_jitter(coef_variation, width_noise, timing_noise):
    """``(start, width)`` (fractions of the cycle) of pulses with the given standard normals."""
    width = np.clip(PULSE_CONTACT_RATIO * (1.0 + coef_variation * width_noise), PULSE_MIN_WIDTH, 1.0)
    start = np.clip(0.5 - 0.5 * width + coef_variation * timing_noise / (2.0 * np.pi), 0.0, 1.0 - width)
    return start, width


def _mean_pulse(coef_variation, n):
    """Fourier coefficients ``(a, b)`` (shape (n,), per g of pulse height) of the mean pulse cycle.

    The mean cycle is the expectation of a cycle's force over the jitter of
    its pulse (width, height, timing: independent normals truncated at
    :data:`TRUNCATION_SD`), so its coefficients are the expected
    coefficients of a cycle: a product Gauss-Legendre rule of
    :data:`PULSE_QUADRATURE` nodes on ``[-TRUNCATION_SD, TRUNCATION_SD]`` per
    normal, weighted by the normal density (exact to about 1e-10 while no
    pulse is clipped; at coefficient variations that clip, 1e-4). Without
    variation it is the nominal pulse (width :data:`PULSE_CONTACT_RATIO`,
    centred); the timing jitter shrinks harmonic ``i`` by about ``exp(-i^2
    c^2 / 2)``, the width's spread changes it too (``c`` = 0.1: harmonic 1
    1.5 %, harmonic 2 3.5 % below the nominal pulse's).
    """
    nodes, weights = np.polynomial.legendre.leggauss(PULSE_QUADRATURE if coef_variation > 0 else 1)
    nodes = TRUNCATION_SD * nodes if coef_variation > 0 else np.zeros(1)
    weights = weights * np.exp(-0.5 * nodes**2)
    weights = weights / weights.sum()
    width_noise, timing_noise = (grid.ravel() for grid in np.meshgrid(nodes, nodes, indexing="ij"))
    start, width = _pulse_jitter(coef_variation, width_noise, timing_noise)
    a, b = _pulse_coefficients(start, width, np.ones(width.size), 0.0, n)
    pair = np.outer(weights, weights).ravel()
    scale = float(weights @ np.maximum(1.0 + coef_variation * nodes, 0.0))  # E max(1 + c N, 0) of the height
    return scale * (pair @ a), scale * (pair @ b)


def _pulse_height(blf_1, coef_variation):
    """Nominal pulse height (g) whose mean pulse cycle (:func:`_mean_pulse`) has first harmonic ``blf_1`` (g)."""
    a, b = _mean_pulse(coef_variation, 1)
    return blf_1 / float(np.hypot(a[0], b[0]))


def _check_pulses(s):
    """OptionError unless ``"pulses"`` can carry the settings ``s`` (a namespace of checked arguments)."""
    if s.all_blf.size > s.blf.size:
        raise OptionError("simulate_bouncing: the harmonics effect needs a Fourier force; with variation='pulses' "
                          "every harmonic follows from the pulse (use it with jumps, smooth, coefficients or tempo)")
    if s.phases_given:
        raise OptionError("simulate_bouncing: phases: with variation='pulses' the phases follow from the pulse; "
                          "leave phases None")
    if s.blf[0] <= 0.0:
        raise OptionError(f"simulate_bouncing: blf[0] must be > 0 with variation='pulses', got {s.blf[0]!r}")
    worst = 1.0 + TRUNCATION_SD * s.coef_variation
    height = _pulse_height(float(s.blf[0]), s.coef_variation)
    if 0.5 * height * worst * min(1.0, PULSE_CONTACT_RATIO * worst) >= 1.0 + s.a0:
        raise OptionError(
            f"simulate_bouncing: blf[0] {s.blf[0]:g} g with coef_variation {s.coef_variation:g} lets the pulse force "
            f"fall below zero (feet off the plate); lower blf[0] or coef_variation (pulse height {height:.3g} g)")


def _pulse_coefficients(start, width, height, a0, n):
    """Fourier coefficients ``(a, b)`` (shape (n_cycles, n), g) of pulse cycles, by FFT on :data:`PULSE_GRID` points.

    Each cycle's force is :meth:`_PulseForce.__call__` over one cycle; ``a_i
    = 2 <F cos(2 pi i tau)>``, ``b_i = 2 <F sin(2 pi i tau)>`` over its
    phase ``tau`` in [0, 1) (the convention of Eq. 4 referred to the cycle
    start). The force is continuously differentiable over the cycle, so the
    rectangle rule converges as ``PULSE_GRID^-3`` (better than 1e-9 g).
    """
    tau = np.arange(PULSE_GRID) / PULSE_GRID
    force = _pulse_shape(tau, start[:, None], width[:, None], height[:, None], a0)
    spectrum = np.fft.rfft(force, axis=1)[:, 1 : n + 1] * (2.0 / PULSE_GRID)
    return spectrum.real, -spectrum.imag


def _pulse_shape(tau, start, width, height, a0):
    """Force (g) at cycle phase ``tau`` in [0, 1): ``a0 + h (sin^2(pi x) - r / 2)``, ``x = (tau - start) / r``.

    ``sin^2(pi x)`` is 0 outside the pulse (``x`` not in (0, 1)); ``r`` is
    ``width``, ``h`` ``height`` (g).
    """
    x = (tau - start) / width
    pulse = np.where((x > 0.0) & (x < 1.0), np.sin(np.pi * np.clip(x, 0.0, 1.0)) ** 2, 0.0)
    return a0 + height * (pulse - 0.5 * width)


class _PulseForce:
    """Force (g) of one ``"pulses"`` cycle: a squared-sine pulse on a baseline, mean ``a0`` over the cycle.

    ``F = a0 + h (sin^2(pi x) - r / 2)`` with ``x = (tau - s) / r`` in the
    pulse (0 < x < 1) and ``sin^2`` replaced by 0 outside it; ``tau = (t -
    t_start) f_b`` is the cycle phase, ``s`` the pulse start and ``r`` its
    width (fractions of the cycle), ``h`` its height. ``a``, ``b`` and
    ``omega`` are its first :data:`PULSE_STEADY_HARMONICS` Fourier terms,
    which the periodic steady state needs.
    """

    def __init__(self, t_start, f_b, start, width, height, a0, a, b):
        self.t_start, self.f_b = float(t_start), float(f_b)
        self.start, self.width, self.height = float(start), float(width), float(height)
        self.a0 = float(a0)
        self.level = self.a0 - 0.5 * self.height * self.width
        self.omega = 2.0 * np.pi * self.f_b
        self.a, self.b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)

    def scalar(self, t):
        """Force (g) at one time ``t`` (s): the fast path for the ODE solver."""
        x = ((t - self.t_start) * self.f_b - self.start) / self.width
        if 0.0 < x < 1.0:
            return self.level + self.height * math.sin(math.pi * x) ** 2
        return self.level

    def __call__(self, t):
        """Force (g) at times ``t`` (s), any shape."""
        tau = (np.asarray(t, dtype=float) - self.t_start) * self.f_b
        return _pulse_shape(tau, self.start, self.width, self.height, self.a0)


def _pulses_draw(rng, s, n_rows, n_samples):
    """Blocks of ``"pulses"``: ``(start_fraction, eps, width, height, timing)``, GRF and floor noise."""
    start_fraction = rng.random()
    blocks = (start_fraction,) + tuple(_normals(rng, n_rows) for _ in range(4))
    return blocks, rng.standard_normal(n_samples), rng.standard_normal(n_samples)


def _pulses_record(s, blocks, time):
    """``(cycles, states, truth)`` of ``"pulses"``; the record starts in the periodic state of cycle 0."""
    start_fraction, eps, width_noise, height_noise, timing_noise = blocks
    t_start, t_end, frequency = _boundaries(s.f_b * (1.0 + s.fb_variation * eps), s.duration,
                                            -start_fraction / s.f_b)
    n_cycles, c = t_start.size, s.coef_variation
    height = _pulse_height(float(s.blf[0]), c)
    starts, widths = _pulse_jitter(c, width_noise[:n_cycles], timing_noise[:n_cycles])
    heights = height * np.maximum(1.0 + c * height_noise[:n_cycles], 0.0)
    n_steady = max(PULSE_STEADY_HARMONICS, s.blf.size)
    a, b = _pulse_coefficients(starts, widths, heights, s.a0, n_steady)
    forces = [_PulseForce(t_start[j], frequency[j], starts[j], widths[j], heights[j], s.a0, a[j], b[j])
              for j in range(n_cycles)]
    state = _periodic_state(s.system, forces[0], 1.0 / frequency[0], t_start[0])
    states = _forces_states(s.system, forces, t_start, t_end, time, state)
    if np.min(states["u_ddot"].to_numpy()) <= -G:
        raise OptionError(f"simulate_bouncing: with variation='pulses' and blf[0] {s.blf[0]:g} g the GRF falls "
                          "below zero (the feet would leave the plate); lower blf[0] or coef_variation")
    n = s.blf.size
    cycles = _cycles_frame(t_start, t_end, frequency, s.a0, a[:, :n], b[:, :n], np.hypot(a[:, :n], b[:, :n]))
    cycles["pulse_start"], cycles["pulse_width"], cycles["pulse_height"] = starts, widths, heights
    mean_a, mean_b = (height * v for v in _mean_pulse(c, n))
    mean_a, mean_b = np.where(np.abs(mean_a) > 1e-12, mean_a, 0.0), np.where(np.abs(mean_b) > 1e-12, mean_b, 0.0)
    variations = {"fb_variation": s.fb_variation, "coef_variation": c, "phase_jitter_rad": c,
                  "truncation_sd": TRUNCATION_SD, "generator": "pulses", "pulse": "squared sine on a baseline",
                  "contact_ratio": PULSE_CONTACT_RATIO, "pulse_height_g": height,
                  "width_variation": c, "height_variation": c, "requested_blf": [float(v) for v in s.blf]}
    truth = {"blf": [float(v) for v in np.hypot(mean_a, mean_b)],
             "phases": [float(v) for v in np.arctan2(mean_b, mean_a)], "variations": variations}
    return cycles, states, truth


# ---------------------------------------------------------------------------
# "tempo": a fixed shape under a wandering tempo


def _tempo_geometry(duration, f_b):
    """``(period, n_terms)`` of the tempo wander: a Fourier series of period ``2 (duration + 2 / f_b)``.

    Its terms have periods ``period / k``, ``k = 1..n_terms``, none shorter
    than :data:`TEMPO_WANDER_PERIOD` (at least one term); the record and its
    first and last cycles span half a period, so the series shows no
    periodicity. Both depend only on ``duration`` and ``f_b``.
    """
    period = 2.0 * (duration + 2.0 / f_b)
    return period, max(1, int(np.floor(period / TEMPO_WANDER_PERIOD)))


class _TempoForce:
    """Force (g) of Eq. 4 with fixed coefficients and a wandering tempo.

    ``F = a0 + sum_i a_i cos(i theta) + b_i sin(i theta)``, ``theta = theta_0
    + 2 pi f_b (t + v E(t))``, ``E = int_0^t e``, the relative frequency
    change ``e(t) = R d (t / D - 1/2) + K^-1/2 sum_k (alpha_k cos(nu_k t) +
    beta_k sin(nu_k t))`` (``d = +-1``, ``R`` = :data:`TEMPO_RAMP`, ``D`` the
    record length, ``nu_k = 2 pi k / P``, :func:`_tempo_geometry`), so that
    ``f(t) = f_b (1 + v e(t))`` with ``v = fb_variation``.
    """

    def __init__(self, theta_0, f_b, fb_variation, duration, direction, period, alpha, beta, a0, a, b):
        self.theta_0, self.f_b, self.fb_variation = float(theta_0), float(f_b), float(fb_variation)
        self.slope = TEMPO_RAMP * float(direction) / float(duration)
        self.nu = 2.0 * np.pi * np.arange(1, alpha.size + 1) / float(period)
        scale = 1.0 / math.sqrt(alpha.size)
        self.alpha, self.beta = scale * np.asarray(alpha, dtype=float), scale * np.asarray(beta, dtype=float)
        self.a0, self.a, self.b = float(a0), np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        self.orders = np.arange(1, self.a.size + 1, dtype=float)
        self._wander = tuple(zip(self.nu.tolist(), (self.alpha / self.nu).tolist(), (self.beta / self.nu).tolist()))
        self._terms = tuple(zip(self.a.tolist(), self.b.tolist()))
        self._half = 0.5 * float(duration)

    def theta(self, t):
        """Bouncing phase ``theta(t)`` (rad), continuous; a cycle is one advance by 2 pi."""
        t = np.asarray(t, dtype=float)
        phase = np.multiply.outer(t, self.nu)
        wander = np.sin(phase) @ (self.alpha / self.nu) + (1.0 - np.cos(phase)) @ (self.beta / self.nu)
        drift = 0.5 * self.slope * t * (t - 2.0 * self._half) + wander
        return self.theta_0 + 2.0 * np.pi * self.f_b * (t + self.fb_variation * drift)

    def frequency(self, t):
        """Instantaneous bouncing frequency ``f_b (1 + fb_variation e(t))`` (Hz)."""
        t = np.asarray(t, dtype=float)
        phase = np.multiply.outer(t, self.nu)
        change = self.slope * (t - self._half) + np.cos(phase) @ self.alpha + np.sin(phase) @ self.beta
        return self.f_b * (1.0 + self.fb_variation * change)

    def scalar(self, t):
        """Force (g) at one time ``t`` (s): the fast path for the ODE solver."""
        wander = 0.0
        for nu, alpha, beta in self._wander:
            wander += alpha * math.sin(nu * t) + beta * (1.0 - math.cos(nu * t))
        drift = 0.5 * self.slope * t * (t - 2.0 * self._half) + wander
        theta = self.theta_0 + 2.0 * math.pi * self.f_b * (t + self.fb_variation * drift)
        return fourier_scalar(theta, self.a0, self._terms)  # Eq. 4

    def __call__(self, t):
        """Force (g) at times ``t`` (s), any shape."""
        angle = np.multiply.outer(self.theta(t), self.orders)
        return self.a0 + np.cos(angle) @ self.a + np.sin(angle) @ self.b


def _tempo_draw(rng, s, n_rows, n_samples):
    """Blocks of ``"tempo"``: ``(start_fraction, direction, alpha, beta)``, GRF and floor noise."""
    _, n_terms = _tempo_geometry(s.duration, s.f_b)
    start_fraction = rng.random()
    direction = 1.0 if rng.random() < 0.5 else -1.0
    blocks = (start_fraction, direction, _normals(rng, n_terms), _normals(rng, n_terms))
    return blocks, rng.standard_normal(n_samples), rng.standard_normal(n_samples)


def _tempo_record(s, blocks, time):
    """``(cycles, states, truth)`` of ``"tempo"``: one integration from a run-in before the record."""
    start_fraction, direction, alpha, beta = blocks
    period, _ = _tempo_geometry(s.duration, s.f_b)
    a, b = s.all_blf * np.cos(s.all_phases), s.all_blf * np.sin(s.all_phases)
    force = _TempoForce(2.0 * np.pi * start_fraction, s.f_b, s.fb_variation, s.duration, direction, period,
                        alpha, beta, s.a0, a, b)
    run_in = _smooth_run_in(s.system)
    grid = np.arange(-run_in - 2.0 / s.f_b, s.duration + 4.0 / s.f_b, 0.125 / s.f_b)
    if force.frequency(grid).min() <= 0.25 * s.f_b:
        raise OptionError(f"simulate_bouncing: the tempo fell below f_b / 4 with fb_variation {s.fb_variation:g}; "
                          "lower fb_variation or change the seed")  # pragma: no cover  (beyond 8 SD)
    first = int(np.floor(float(force.theta(-run_in)) / (2.0 * np.pi)))
    last = int(np.floor(float(force.theta(s.duration)) / (2.0 * np.pi))) + 1
    times = _phase_crossings(force, first, last, grid, "tempo")
    t_start, t_end = times[:-1], times[1:]
    frequency = 1.0 / (t_end - t_start)
    keep = slice(-min(first, 0), None)  # cycles 0, 1, ...: the one holding t = 0 and the later ones
    n_cycles = t_start[keep].size
    a_rows, b_rows = np.tile(a, (n_cycles, 1)), np.tile(b, (n_cycles, 1))
    cycles = _cycles_frame(t_start[keep], t_end[keep], frequency[keep], s.a0, a_rows, b_rows,
                           np.hypot(a_rows, b_rows))
    states = _smooth_states(s.system, force, (t_start[0], t_end[0], frequency[0], a, b), cycles, time)
    variations = {"fb_variation": s.fb_variation, "coef_variation": 0.0, "phase_jitter_rad": 0.0,
                  "truncation_sd": TRUNCATION_SD, "generator": "tempo", "ramp": TEMPO_RAMP * s.fb_variation,
                  "ramp_direction": int(direction), "wander_sd": s.fb_variation,
                  "wander_shortest_period_s": TEMPO_WANDER_PERIOD, "run_in_s": float(-t_start[0])}
    return cycles, states, {"variations": variations}


GENERATORS = {
    "coefficients": (_coefficients_draw, _coefficients_record),
    "pulses": (_pulses_draw, _pulses_record),
    "tempo": (_tempo_draw, _tempo_record),
}
"""``name: (draw(rng, settings, n_rows, n_samples), record(settings, blocks, time))`` of every generator here."""

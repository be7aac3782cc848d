"""Cycle-to-cycle variation of the biomechanical force: the first two generators of :data:`VARIATIONS`.

``"jumps"``: every cycle its own frequency and harmonics, drawn as
truncated normals (:func:`_draw_cycles`). ``"smooth"``: the frequency and
harmonics are smooth random processes of time (:class:`_SmoothForce`, made
as :data:`SMOOTH_CORRELATION_CYCLES` describes), integrated through a run-in
before the record. The random numbers come from the simulator
(:func:`~smd_statespace.simulation.simulate_bouncing`) in its fixed order of blocks.
The other three generators (``"coefficients"``, ``"pulses"``, ``"tempo"``)
are in :mod:`.generators`.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ..io import G
from .dynamics import _CycleForce, _integrate_cycle, _periodic_state, _states_frame

__all__ = ["TRUNCATION_SD", "VARIATIONS", "SMOOTH_KERNELS", "SMOOTH_CORRELATION_CYCLES", "SMOOTH_GRID",
           "SMOOTH_RUN_IN_DECAYS", "SMOOTH_RUN_IN_MAX"]

TRUNCATION_SD = 3.0
"""Cycle-to-cycle variations are normal, truncated at this many standard deviations."""

VARIATIONS = ("jumps", "smooth", "coefficients", "pulses", "tempo", "matern")
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
``"coefficients"``
    Each cycle ``j`` has its own frequency ``f_b (1 + eps_j)`` and every
    Fourier coefficient is jittered on its own, ``a_ij = a_i (1 + c N)``,
    ``b_ij = b_i (1 + c N)`` (``c = coef_variation``, independent truncated
    normals); the person starts from rest at ``t = 0``, so the first cycles
    carry the start-up transient.
``"pulses"``
    No Fourier series: one squared-sine pulse per cycle on a constant
    baseline, mean force ``a0`` over every cycle, the pulse's width, height
    and timing jittered per cycle (:data:`~.generators.PULSE_CONTACT_RATIO`).
    The truth's ``blf`` and ``phases`` are the mean pulse's Fourier
    coefficients; ``blf[0]`` sets the pulse height, the higher harmonics
    follow from its shape.
``"tempo"``
    The fixed Fourier shape of ``blf`` and ``phases`` under a slowly wandering
    tempo: ``f_b(t)`` ramps by :data:`~.generators.TEMPO_RAMP` ``fb_variation``
    over the record plus a slow random wander of standard deviation
    ``fb_variation`` (periods of :data:`~.generators.TEMPO_WANDER_PERIOD` s
    and longer); no coefficient jitter.
``"matern"``
    As ``"smooth"``, but the processes have the Matern-3/2 covariance of the
    record-level model's own smooth variation
    (:mod:`smd_statespace.person.variation`): their spectrum falls as ``f^-4``
    away from each harmonic, where ``"smooth"``'s falls as ``exp(-f^2)``. The
    pair tells what the person's answer owes to the assumed shape of the
    force's variation (``docs/person.md``).
"""

SMOOTH_KERNELS = {"smooth": "gaussian", "matern": "exponential"}
"""The kernel that makes each smooth generator's processes from its knots (:func:`_smooth_normals`)."""

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

_EXPONENTIAL_REACH = 12.0
"""The exponential kernel of the ``"matern"`` processes is cut at this many decay lengths (``exp(-12)``)."""

MATERN_E_FOLD = 2.1462
"""``x`` with ``(1 + x) exp(-x) = exp(-1)``: the Matern-3/2 autocorrelation ``(1 + tau / w) exp(-tau / w)`` is 1/e
at ``tau = MATERN_E_FOLD w``, so the exponential kernel's length ``w = SMOOTH_CORRELATION_CYCLES / MATERN_E_FOLD``
cycles gives ``"matern"`` the correlation time of ``"smooth"``."""


# ---------------------------------------------------------------------------
# the jumps


def _draw_cycles(rng_blocks, duration, f_b, blf, phases, fb_variation, coef_variation, phase_variation=None):
    """Cycle table from pre-drawn standard normals; see :func:`simulate_bouncing` (``phase_variation`` None: the
    phases jitter by ``coef_variation`` rad)."""
    start_fraction, eps, amp_noise, phase_noise = rng_blocks
    frequency = f_b * (1.0 + fb_variation * eps)
    t_end = np.cumsum(1.0 / frequency) - start_fraction / f_b
    n_cycles = int(np.searchsorted(t_end, duration, side="right")) + 1
    frequency, t_end = frequency[:n_cycles], t_end[:n_cycles]
    t_start = np.concatenate([[-start_fraction / f_b], t_end[:-1]])
    amplitude = blf * np.maximum(1.0 + coef_variation * amp_noise[:n_cycles], 0.0)
    phase = phases + (coef_variation if phase_variation is None else phase_variation) * phase_noise[:n_cycles]
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


def _smooth_geometry(duration, f_b, fb_variation, kernel="gaussian"):
    """Grid and knots of the smooth processes: ``(t_lo, n_knots, reach)``.

    The grid ``t_lo + k / (SMOOTH_GRID f_b)`` starts a whole number of mean
    cycles before the earliest possible start of the first cycle and ends
    after the latest possible end of the last (``duration`` plus the longest
    cycle); the knots, one per mean cycle, start ``reach`` knots before the
    grid and end ``reach`` knots after it. All of it depends only on
    ``duration``, ``f_b``, ``fb_variation`` and the ``kernel``
    (:data:`SMOOTH_KERNELS`), so the number of random numbers drawn does too.
    """
    period = 1.0 / f_b
    longest = period / (1.0 - TRUNCATION_SD * fb_variation)
    before = int(np.ceil(longest / period)) + 1
    n_span = before + int(np.ceil((duration + longest) / period)) + 1
    reach = int(np.ceil(_KERNEL_REACH * 0.5 * SMOOTH_CORRELATION_CYCLES if kernel == "gaussian" else
                        _EXPONENTIAL_REACH * SMOOTH_CORRELATION_CYCLES / MATERN_E_FOLD))
    return -before * period, n_span + 2 * reach + 1, reach


def _smooth_normals(knots, reach, kernel="gaussian"):
    """Kernel smoothing of knot values onto the grid (:data:`SMOOTH_CORRELATION_CYCLES`).

    ``kernel="gaussian"`` (``"smooth"``) or ``"exponential"`` (``"matern"``:
    ``exp(-|t| / w)``, whose sum of white knots has the Matern-3/2 spectrum
    ``(1 + (2 pi f w)^2)^-2``; :data:`MATERN_E_FOLD`).

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
    offsets = np.arange(-reach * SMOOTH_GRID, reach * SMOOTH_GRID + 1)
    if kernel == "gaussian":
        width = 0.5 * SMOOTH_CORRELATION_CYCLES * SMOOTH_GRID  # kernel SD in grid steps
        weights = np.exp(-0.5 * (offsets / width) ** 2)
    else:
        weights = np.exp(-np.abs(offsets) / (SMOOTH_CORRELATION_CYCLES / MATERN_E_FOLD * SMOOTH_GRID))
    spikes = np.zeros((knots.shape[0] - 1) * SMOOTH_GRID + 1)
    spikes[::SMOOTH_GRID] = 1.0
    scale = np.sqrt(np.convolve(spikes, weights**2, mode="valid"))
    values = np.empty((scale.size, knots.shape[1]))
    for column in range(knots.shape[1]):
        spikes[::SMOOTH_GRID] = knots[:, column]
        values[:, column] = np.convolve(spikes, weights, mode="valid") / scale
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


def _smooth_force(rng_blocks, run_in_knots, geometry, f_b, fb_variation, a0, blf, phases, coef_variation,
                  kernel="gaussian"):
    """The :class:`_SmoothForce` made from pre-drawn truncated standard normals at the knots.

    ``rng_blocks`` holds the start fraction and the knots of the record
    (columns ``eps``, ``delta_i``, ``eta_i``); ``run_in_knots`` (shape
    (n_run, 1 + 2m)) extends them into the past, nearest knot first, so the
    processes over the record do not depend on them.
    """
    from scipy.interpolate import CubicSpline, PPoly  # imported here: 0.4 s (not needed to start)

    start_fraction, eps, amp_noise, phase_noise = rng_blocks
    t_lo, _, reach = geometry
    knots = np.concatenate([run_in_knots[::-1], np.column_stack([eps, amp_noise, phase_noise])])
    values = _smooth_normals(knots, reach, kernel)
    grid = t_lo - run_in_knots.shape[0] / f_b + np.arange(values.shape[0]) / (SMOOTH_GRID * f_b)
    spline = CubicSpline(grid, values, axis=0)
    integral = spline.antiderivative()
    coefficients = np.zeros((5, grid.size - 1, values.shape[1] + 1))
    coefficients[:, :, 0] = integral.c[:, :, 0]
    coefficients[-1, :, 0] -= integral(0.0)[0]  # E(0) = 0
    coefficients[1:, :, 1:] = spline.c
    pieces = PPoly(coefficients, grid)
    return _SmoothForce(pieces, 2.0 * np.pi * start_fraction, f_b, fb_variation, a0, blf, phases, coef_variation)


def _phase_crossings(force, first, last, grid, name):
    """Times (s) where ``force.theta`` passes ``2 pi j``, ``j = first .. last``: the cycle boundaries.

    Linear interpolation of ``theta`` on ``grid`` (s, increasing), then
    Newton's method with the phase rate ``2 pi force.frequency(t)``.
    """
    targets = 2.0 * np.pi * np.arange(first, last + 1)
    times = np.interp(targets, force.theta(grid), grid)
    for _ in range(8):
        times = times - (force.theta(times) - targets) / (2.0 * np.pi * force.frequency(times))
    if np.abs(force.theta(times) - targets).max() > 1e-8:
        raise RuntimeError(f"the cycle boundaries of the {name} variation did not converge")  # pragma: no cover
    return times


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
    times = _phase_crossings(force, first, last, force.pieces.x, "smooth")
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



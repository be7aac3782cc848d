"""The equations of motion of a simulated person and their accurate integration.

Eq. 2, ``u'' + 2 xi_h w_h u' + w_h^2 u = g F(t)``, plus every effect's own
terms (:meth:`~smd_statespace.model.Effect.acceleration` and, for an effect
with dynamic slots such as a floor mode, :meth:`~smd_statespace.model.Effect.slot_rates`)
evaluated with the parameters at their true values (:class:`_System`),
integrated with :func:`scipy.integrate.solve_ivp` (DOP853, ``rtol``
:data:`RTOL`) under a force given cycle by cycle, restarted at every
cycle boundary (:func:`integrate_response`), from the periodic steady state
of the first cycle (exact for a linear system, by shooting otherwise).
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pandas as pd

from ..effects import build_effect, make_effect
from ..errors import OptionError
from ..io import G, check_mass
from ..model import CycleInputs, SMDModel, equations
from .effect_adapter import for_simulation, force_harmonics

__all__ = ["RTOL", "ATOL", "integrate_response"]

RTOL = 1e-10
"""Relative tolerance of the DOP853 integration."""

ATOL = 1e-13
"""Absolute tolerance of the DOP853 integration (m and m/s)."""


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
    names = [effect.key for effect in built]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise OptionError(f"{where}: effect {twice[0]!r} is given twice; give each effect once")
    person = SMDModel(n_harmonics=1)
    try:
        return tuple(for_simulation(effect, person, mass) for effect in built)
    except OptionError as exc:
        raise OptionError(f"{where}: {exc}") from None


# ---------------------------------------------------------------------------
# the dynamical system


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
        self.f_h = float(f_h)
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
            self.person = [self.model.index("f_h"), self.model.index("xi_h")]  # where rates' f_h, xi_h go
            self.template[self.person] = f_h, xi_h
            self.inputs = CycleInputs(f_b=1.0)
        self.n_state = len(self.names)
        self.a_matrix, self.b_vector = self._linear_matrices()
        self.linear = self._is_linear()

    def with_drawn_inputs(self, effects) -> "_System":
        """This system with ``effects`` (the same ones, their random inputs drawn) in place of its own.

        The inputs are additive forcing of the effects' slots (a floor's
        ambient excitation), not dynamics, so the linearisation at rest
        (:attr:`a_matrix`, :attr:`linear`) is kept as computed without them.
        """
        twin = copy.copy(self)
        twin.effects = tuple(effects)
        twin.model = SMDModel(n_harmonics=1, effects=twin.effects)
        return twin

    def rates(self, x, force_g, t, f_h=None, xi_h=None):
        """``(dx/dt, u'')`` for states ``x`` (shape (n_state, ...)) under input ``g F`` at time(s) ``t``; ``f_h``,
        ``xi_h`` (Hz, -; broadcast with the samples) in place of the system's own where given (a person who
        changes during the record)."""
        changing = f_h is not None or xi_h is not None  # a person who changes: not the template's f_h, xi_h
        f_h = self.f_h if f_h is None else f_h
        xi_h = self.xi_h if xi_h is None else xi_h
        acc = equations.smd_acceleration(x[0], x[1], f_h, xi_h, force_g)  # Eq. 2
        if self.model is None:
            return np.stack(np.broadcast_arrays(x[1], acc)), acc
        x = np.asarray(x, dtype=float)
        full = np.empty(x.shape[1:] + self.template.shape)
        full[...] = self.template
        if changing:
            full[..., self.person[0]], full[..., self.person[1]] = f_h, xi_h
        full[..., self.dynamic] = x.T if x.ndim <= 2 else np.moveaxis(x, 0, -1)  # (the ODE solver: one state)
        for effect in self.effects:
            acc = acc + effect.acceleration(self.model, full, t, self.inputs)
        parts = [x[1] if np.shape(x[1]) == np.shape(acc) else np.broadcast_to(x[1], np.shape(acc)), acc]
        for effect in self.effects:
            own = np.asarray(effect.slot_rates(self.model, full, t, self.inputs, acc))
            parts.extend(own.T if own.ndim <= 2 else np.moveaxis(own, -1, 0))
        return np.stack(parts), acc

    def rhs(self, t, x, force):
        """Time derivative of the state ``x`` (shape (n_state,)) at time ``t`` (s): :meth:`rates` at one state."""
        if self.model is None:  # the fast path of the base model: Eq. 2 on plain floats
            return np.array([x[1], equations.smd_acceleration(x[0], x[1], self.f_h, self.xi_h, G * force.scalar(t))])
        return self.rates(np.asarray(x, dtype=float), G * force.scalar(t), t)[0]

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


def fourier_scalar(theta, a0, terms):
    """Eq. 4 at one phase ``theta`` (rad) in plain floats: ``a0 + sum a_i cos(i theta) + b_i sin(i theta)``.

    ``terms`` are the pairs ``(a_i, b_i)``; ``cos(i theta)``, ``sin(i theta)`` come by rotation from the first
    (the ODE solver's fast path: no array per call).
    """
    cos_1, sin_1 = math.cos(theta), math.sin(theta)
    cos_i, sin_i = cos_1, sin_1
    total = a0
    for a_i, b_i in terms:
        total += a_i * cos_i + b_i * sin_i
        cos_i, sin_i = cos_i * cos_1 - sin_i * sin_1, sin_i * cos_1 + cos_i * sin_1
    return total


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
        return fourier_scalar(self.omega * (t - self.t_start), self.a0, self._terms)

    def __call__(self, t):
        """Force (g) at times ``t`` (s), any shape."""
        angle = np.multiply.outer(self.orders, self.omega * (np.asarray(t, dtype=float) - self.t_start))
        return self.a0 + self.a @ np.cos(angle) + self.b @ np.sin(angle)  # Eq. 4


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
    from scipy.integrate import solve_ivp  # imported here: with scipy.optimize, 0.3 s (not needed to start)

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

    from scipy import optimize  # imported here: 0.3 s (not needed to start the command line)

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
    if any(force_harmonics(effect, person) is not None for effect in effects):
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
    return _forces_states(system, forces, t_start, t_end, time, state)


def _forces_states(system, forces, t_start, t_end, time, state):
    """The states table under one force object per cycle, integrated cycle by cycle from ``state``.

    ``forces[j]`` (anything with ``scalar(t)`` and ``__call__(t)``, in g)
    acts from ``t_start[j]`` to ``t_end[j]``; the integration restarts at
    every boundary, so the force may jump there.
    """
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



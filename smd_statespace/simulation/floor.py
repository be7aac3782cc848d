"""A bouncing person on a modal floor: the exact coupled person-floor response.

The coupled model
-----------------
A person (Eq. 2, the spring and damper acting on the COM motion relative to
the floor, as the ``floor_mode`` effect of :mod:`smd_statespace.simulation`) on
``r`` floor modes with modal coordinates ``q_k`` (m), natural frequencies
``f_k``, damping ratios ``xi_k``, modal masses ``m_k`` and mode-shape
ordinates ``phi_k`` at the person::

    z   = sum_k phi_k q_k                                   (floor under the person)
    u'' = -w_h^2 (u - z) - 2 xi_h w_h (u' - z') + g F(t)     (Eq. 2 relative to the floor)
    q_k'' + 2 xi_k w_k q_k' + w_k^2 q_k = -(M_h phi_k / m_k) u''

``F(t)`` is the biomechanical force of Eq. 4 in units of g; the floor is
driven by the dynamic GRF ``-M_h u''`` (the static weight only sets the
static deflection). The state is ``x = [u, u', q_1, q_1', ..., q_r, q_r']``;
with one mode and ``phi = 1`` it is exactly the ``floor_mode`` system of
:func:`smd_statespace.simulation.integrate_response` (tested), and with no mode
it is the rigid floor. :func:`system_matrices` takes the person's row and each
mode's drive from :func:`smd_statespace.model.coupling.modal_coupling`, the
coupling the ``floor_mode`` effect and :mod:`smd_statespace.structure` use too;
:func:`coupled_frf` writes it out again from ``K_h``, ``C_h`` (Eq. 17, 18) as
the independent check.

Mode-shape assumption at mid-span
---------------------------------
Table 3 gives modal masses but not mode shapes. :meth:`FloorModel.table3`
takes ``phi_k = 1`` for every mode, i.e. reads the modal masses as
driving-point modal masses at mid-span (as :class:`smd_statespace.article.PlateMode`
does). For mode 1 that is consistent with the numbers: 8583 kg is 0.52 of the
plate's 16.5 t, close to the ``M/2`` of a one-way simply supported slab whose
first mode is normalised to 1 at mid-span. For the higher modes it is an
upper bound: mode 2 (2587 kg, close to the ``M/6`` of a torsion mode
normalised at a corner) probably has a nodal line through mid-span. The
study measures whether it matters (:func:`hsi_study` runs mode 1 alone and
all six modes): modes 2-6 lie between and above the force harmonics, and the
leg transmits little above ``f_h``, so they change the floor acceleration at
mid-span but barely the GRF.

Integration
-----------
The model is linear and the force is a sum of harmonics whose coefficients
jump at cycle boundaries, so the response is computed exactly rather than by
an ODE solver: within cycle ``j`` the state is the periodic (particular)
response to that cycle's harmonics plus a free (homogeneous) response
``exp(A tau) d_j`` that carries the state continuously across the boundary,
evaluated in the eigenbasis of ``A`` (:func:`coupled_response`). It is
vectorised over samples and over a batch of people
(:func:`batch_response`, used by the crowd generator of
:mod:`smd_statespace.simulation.crowd`). By default the start is the periodic steady
state of the first cycle's force, as in
:func:`~smd_statespace.simulation.integrate_response`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import article
from ..errors import OptionError
from ..io import G, check_mass, make_record
from ..model import c_h, coupling, k_h

__all__ = ["FloorModel", "system_matrices", "coupled_frf", "batch_response", "coupled_response", "simulate_on_floor"]


# ---------------------------------------------------------------------------
# the floor


@dataclass(frozen=True)
class FloorModel:
    """Modes of a floor as seen at the person's position.

    An empty model (no modes) is a rigid floor.

    Parameters
    ----------
    frequency : tuple of float
        Natural frequencies ``f_k`` (Hz).
    damping : tuple of float
        Damping ratios ``xi_k`` (-, fractions), >= 0.
    modal_mass : tuple of float
        Modal masses ``m_k`` (kg), for modes normalised to ``max |phi| = 1``.
    shape : tuple of float
        Mode-shape ordinates ``phi_k`` at the person (-); 1 when the modal
        masses are driving-point masses.
    name : str
        Label for tables and figures.
    """

    frequency: tuple = ()
    damping: tuple = ()
    modal_mass: tuple = ()
    shape: tuple = ()
    name: str = "rigid floor"

    def __post_init__(self):
        where = "FloorModel"
        arrays = {}
        for label in ("frequency", "damping", "modal_mass", "shape"):
            try:
                values = tuple(float(v) for v in np.atleast_1d(getattr(self, label)))
            except (TypeError, ValueError):
                raise OptionError(f"{where}: {label} must be numbers, got {getattr(self, label)!r}") from None
            if not all(np.isfinite(values)):
                raise OptionError(f"{where}: {label} must be finite, got {values!r}")
            arrays[label] = values
        n = len(arrays["frequency"])
        if not arrays["shape"] and n:
            arrays["shape"] = (1.0,) * n
        for label, values in arrays.items():
            if len(values) != n:
                raise OptionError(f"{where}: {label} has {len(values)} values, frequency has {n}")
            object.__setattr__(self, label, values)
        if any(v <= 0 for v in self.frequency) or any(v <= 0 for v in self.modal_mass):
            raise OptionError(f"{where}: frequencies and modal masses must be positive")
        if any(v < 0 for v in self.damping):
            raise OptionError(f"{where}: damping ratios must be >= 0, got {self.damping!r}")

    @classmethod
    def table3(cls, modes=None, shape=None) -> "FloorModel":
        """The article's plate (Table 3) at mid-span.

        Parameters
        ----------
        modes : sequence of int, optional
            Mode numbers 1-6 to keep (default all six).
        shape : sequence of float, optional
            Ordinates ``phi_k`` at mid-span of the kept modes (default 1 for
            each: the modal masses read as driving-point masses, see the
            module docstring).
        """
        numbers = tuple(range(1, len(article.TABLE3) + 1)) if modes is None else tuple(int(m) for m in modes)
        bad = [m for m in numbers if not 1 <= m <= len(article.TABLE3)]
        if bad or not numbers:
            raise OptionError(f"FloorModel.table3: modes must be among 1-{len(article.TABLE3)}, got {modes!r}")
        chosen = [article.TABLE3[m - 1] for m in numbers]
        label = "plate, mode 1" if numbers == (1,) else f"plate, modes {','.join(map(str, numbers))}"
        if numbers == tuple(range(1, len(article.TABLE3) + 1)):
            label = f"plate, {len(numbers)} modes"
        return cls(
            frequency=tuple(m.frequency for m in chosen),
            damping=tuple(m.damping for m in chosen),
            modal_mass=tuple(m.modal_mass for m in chosen),
            shape=() if shape is None else tuple(shape),
            name=label,
        )

    @classmethod
    def from_effect(cls, effect, mass) -> "FloorModel":
        """The one-mode floor of a ``floor_mode`` effect (object or spec) under a person of ``mass`` kg.

        The floor the simulator integrates for that effect: its frequency,
        damping and modal mass (``M_h / mass_ratio``), the article's plate
        mode 1 (Table 3) for what is not given. So a floor written once, as
        an effect, serves the one-person simulator, this exact solver, the
        crowd and the HSI study.

        Examples
        --------
        >>> FloorModel.from_effect("floor_mode", mass=70.0).modal_mass
        (8583.0,)
        """
        from ..effects import FloorMode, make_effect

        effect = make_effect(effect)
        if not isinstance(effect, FloorMode):
            raise OptionError(f"FloorModel.from_effect: needs a floor_mode effect, got {effect.spec!r}")
        mass = check_mass(mass, source="mass")
        values = effect.simulation_values(mass)
        return cls((values["f_f"],), (values["xi_f"],), (mass / values["mass_ratio"],),
                   name=f"floor_mode {values['f_f']:g} Hz")

    def as_effect(self, mass, mode=1):
        """Mode ``mode`` (1-based) as a known ``floor_mode`` effect under a person of ``mass`` kg.

        The effect's mass ratio is ``M_h phi_k^2 / m_k``: the person sees the
        mode through its ordinate ``phi_k``, which also scales the floor
        motion, so the effect's ``z`` is ``phi_k q_k``.
        """
        from ..effects import FloorMode

        if not 1 <= int(mode) <= self.n_modes:
            raise OptionError(f"FloorModel.as_effect: mode must be 1-{self.n_modes}, got {mode!r}")
        k = int(mode) - 1
        mass = check_mass(mass, source="mass")
        return FloorMode("modal", frequency=self.frequency[k], damping=self.damping[k],
                         mass_ratio=mass * self.shape[k] ** 2 / self.modal_mass[k])

    @property
    def n_modes(self) -> int:
        """Number of modes (0: rigid floor)."""
        return len(self.frequency)

    @property
    def n_state(self) -> int:
        """Length of the coupled state ``[u, u', q_1, q_1', ...]``."""
        return 2 + 2 * self.n_modes


def system_matrices(mass, f_h, xi_h, floor: FloorModel | None = None):
    """``(A, B)`` of the coupled person-floor system ``x' = A x + B g F(t)``.

    Parameters
    ----------
    mass : float
        Body mass ``M_h`` (kg).
    f_h, xi_h : float
        SMD natural frequency (Hz) and damping ratio (-), Eq. 2.
    floor : FloorModel, optional
        The floor (default rigid).

    Returns
    -------
    A : ndarray, shape (n, n)
    B : ndarray, shape (n,)
        For the state ``x = [u, u', q_1, q_1', ..., q_r, q_r']`` (m, m/s) and
        the input ``g F`` (m/s^2); see the module docstring for the equations.
    """
    floor = FloorModel() if floor is None else floor
    n = floor.n_state
    a_matrix, b_vector = np.zeros((n, n)), np.zeros(n)
    # the person row: Eq. 2 on the motion relative to the floor z = sum phi_k q_k, from model.coupling
    links = coupling.modal_coupling([float(mass)], [f_h], [xi_h], [floor.shape])
    person = np.zeros(n)
    person[0], person[1] = links["u"][0], links["u_dot"][0]
    person[2::2], person[3::2] = links["q"][0], links["q_dot"][0]
    a_matrix[0, 1] = 1.0
    a_matrix[1] = person
    b_vector[1] = links["force_g"][0]
    for k in range(floor.n_modes):
        w_k = 2.0 * np.pi * floor.frequency[k]
        drive = links["drive"][0, k] / floor.modal_mass[k]  # the reaction -phi_k M_h u'' per unit modal mass
        row = 2 + 2 * k
        a_matrix[row, row + 1] = 1.0
        a_matrix[row + 1] = drive * person
        a_matrix[row + 1, row] += -(w_k**2)
        a_matrix[row + 1, row + 1] += -2.0 * floor.damping[k] * w_k
        b_vector[row + 1] = drive * b_vector[1]
    return a_matrix, b_vector


def coupled_frf(frequency, mass, f_h, xi_h, floor: FloorModel | None = None):
    """Steady-state response of the coupled system to a unit harmonic force.

    Built from the second-order matrices (masses, damping, stiffness) in the
    coordinates ``(u, q_1, ..., q_r)``, independently of :func:`system_matrices`.

    Parameters
    ----------
    frequency : float or array_like
        Excitation frequency (Hz).
    mass, f_h, xi_h : float
        Person (kg, Hz, -).
    floor : FloorModel, optional

    Returns
    -------
    dict of complex ndarray
        ``"u_ddot"`` (COM acceleration) and ``"z_ddot"`` (floor acceleration
        at the person), both per unit ``g F`` (m/s^2 per m/s^2): the
        harmonic ``g C e^{i w t}`` of the input produces ``H g C e^{i w t}``.
    """
    floor = FloorModel() if floor is None else floor
    omega = 2.0 * np.pi * np.atleast_1d(np.asarray(frequency, dtype=float))
    r = floor.n_modes
    phi = np.asarray(floor.shape)
    relative = np.concatenate([[1.0], -phi])  # u - z = relative . (u, q)
    stiffness = k_h(f_h, mass) * np.outer(relative, relative)  # Eq. 17
    damping = c_h(xi_h, f_h, mass) * np.outer(relative, relative)  # Eq. 18
    masses = np.diag(np.concatenate([[mass], floor.modal_mass]))
    for k in range(r):
        w_k = 2.0 * np.pi * floor.frequency[k]
        stiffness[1 + k, 1 + k] += floor.modal_mass[k] * w_k**2
        damping[1 + k, 1 + k] += 2.0 * floor.damping[k] * floor.modal_mass[k] * w_k
    load = mass * relative  # the internal pair M_h g F: up on the COM, down on the floor
    dynamic = stiffness[None] + 1j * omega[:, None, None] * damping[None] - omega[:, None, None] ** 2 * masses[None]
    displacement = np.linalg.solve(dynamic, np.broadcast_to(load, (omega.size, r + 1))[..., None])[..., 0]
    u_ddot = -(omega**2) * displacement[:, 0]
    z_ddot = -(omega**2) * (displacement[:, 1:] @ phi) if r else np.zeros(omega.size, complex)
    return {"u_ddot": u_ddot, "z_ddot": z_ddot}


# ---------------------------------------------------------------------------
# exact response to a piecewise Fourier force


def _cycle_arrays(cycles_list):
    """Pad a list of cycle tables to arrays ``(t_start, t_end, f_b, a0, a, b)`` of shape (P, J[, H])."""
    n_people = len(cycles_list)
    n_cycles = np.array([len(c) for c in cycles_list])
    n_harm = [0] * n_people
    for p, cycles in enumerate(cycles_list):
        while f"a{n_harm[p] + 1}" in cycles.columns and f"b{n_harm[p] + 1}" in cycles.columns:
            n_harm[p] += 1
    width, height = int(n_cycles.max()), max(max(n_harm), 1)
    t_start = np.empty((n_people, width))
    t_end = np.empty(n_people)
    f_b = np.ones((n_people, width))
    a0 = np.zeros((n_people, width))
    a = np.zeros((n_people, width, height))
    b = np.zeros((n_people, width, height))
    for p, cycles in enumerate(cycles_list):
        j = n_cycles[p]
        starts = cycles["t_start"].to_numpy(dtype=float)
        ends = cycles["t_end"].to_numpy(dtype=float)
        if np.any(ends <= starts) or np.any(np.abs(starts[1:] - ends[:-1]) > 1e-9):
            raise OptionError("cycles must have t_end > t_start and be contiguous (t_start[j+1] == t_end[j])")
        t_start[p, :j], t_start[p, j:] = starts, ends[-1]
        t_end[p] = ends[-1]
        f_b[p, :j] = cycles["f_b"].to_numpy(dtype=float)
        a0[p, :j] = cycles["a0"].to_numpy(dtype=float)
        for i in range(n_harm[p]):
            a[p, :j, i] = cycles[f"a{i + 1}"].to_numpy(dtype=float)
            b[p, :j, i] = cycles[f"b{i + 1}"].to_numpy(dtype=float)
    return n_cycles, t_start, t_end, f_b, a0, a, b


def batch_response(a_matrices, b_vectors, cycles_list, time, initial_states=None, output=None):
    """Exact response of a batch of linear systems to piecewise Fourier forces (Eq. 4).

    System ``p`` obeys ``x' = A_p x + B_p g F_p(t)`` where ``F_p`` is the
    force of its own cycle table (the layout of
    :func:`~smd_statespace.simulation.integrate_response`: columns ``t_start,
    t_end, f_b, a0, a1, b1, ...``; within a cycle ``F = a0 + sum a_i cos(2 pi
    i f_b tau) + b_i sin(2 pi i f_b tau)``, ``tau = t - t_start``). Within each
    cycle the state is the periodic response to that cycle's harmonics plus
    ``exp(A tau) d_j``, evaluated in the eigenbasis of ``A``; ``d_j`` makes
    the state continuous at the cycle start. No time stepping: the result is
    exact to rounding at every sample (agreement with the DOP853 integration
    of :func:`~smd_statespace.simulation.integrate_response` is about 1e-9
    relative).

    Parameters
    ----------
    a_matrices : array_like, shape (P, n, n)
        System matrices (diagonalisable, e.g. from :func:`system_matrices`;
        no eigenvalue on the imaginary axis at a forcing frequency or 0).
    b_vectors : array_like, shape (P, n)
        Input vectors for ``g F`` (m/s^2).
    cycles_list : sequence of pandas.DataFrame
        One cycle table per system; each must cover every sample time.
    time : array_like, shape (T,)
        Output times (s), shared by the batch.
    initial_states : array_like, shape (P, n), optional
        State at each system's first cycle start; default the periodic steady
        state of the first cycle's force.
    output : (array_like, array_like), optional
        ``(C, D)`` of shapes (P, n) and (P,): only the output ``y = C x + D g F``
        is wanted (the crowd's GRFs need ``u''`` alone: ``C = A[:, 1]``,
        ``D = B[:, 1]``). It is then summed in the eigenbasis per cycle, and
        the states are never formed (measured: 200 people, 60 s at 200 Hz,
        0.81 -> 0.42 s; equal to the states' route to 1e-15).

    Returns
    -------
    states : ndarray, shape (P, T, n)
        ``x`` at the sample times.
    rates : ndarray, shape (P, T, n)
        ``x'`` (from the equations of motion, not by differencing).
    force_g : ndarray, shape (P, T)
        ``g F`` (m/s^2).

    With ``output``, the array ``y`` of shape (P, T) instead.
    """
    a_matrices = np.asarray(a_matrices, dtype=float)
    b_vectors = np.asarray(b_vectors, dtype=float)
    time = np.asarray(time, dtype=float).reshape(-1)
    n_people, n = b_vectors.shape
    if a_matrices.shape != (n_people, n, n) or len(cycles_list) != n_people:
        raise OptionError("batch_response: a_matrices (P, n, n), b_vectors (P, n) and P cycle tables must agree")
    n_cycles, t_start, t_end, f_b, a0, a, b = _cycle_arrays(cycles_list)
    if np.any(time[0] < t_start[:, 0]) or np.any(time[-1] >= t_end):
        raise OptionError("batch_response: the cycles must cover every output time")
    lam, vectors = np.linalg.eig(a_matrices)  # (P, n), (P, n, n)
    condition = np.linalg.cond(vectors)
    if not np.all(condition < 1e8):
        raise OptionError(
            "batch_response: a system matrix is (nearly) defective, e.g. exactly critical damping "
            f"(eigenvector condition number {np.max(condition):.3g}); change the damping ratio slightly"
        )
    inverse = np.linalg.inv(vectors)
    w_in = np.einsum("pij,pj->pi", inverse, b_vectors.astype(complex))  # input in modal coordinates
    orders = np.arange(1, a.shape[2] + 1)
    omega = 2.0 * np.pi * f_b  # (P, J)
    w = omega[..., None] * orders  # (P, J, H)
    coef = G * (a - 1j * b)  # g F harmonic i = Re(coef e^{i w tau})
    # periodic response in modal coordinates: Y_h = W C_h / (i w_h - lam), Y_0 = W g a0 / (-lam)
    y_h = w_in[:, None, None, :] * coef[..., None] / (1j * w[..., None] - lam[:, None, None, :])  # (P, J, H, n)
    y_0 = w_in[:, None, :] * (G * a0)[..., None] / (-lam[:, None, :])  # (P, J, n)

    def particular(j_index, tau):
        """Physical periodic response (P, n) of cycle j_index (P,) at tau (P,)."""
        rows = np.arange(n_people)
        phase = np.exp(1j * w[rows, j_index] * tau[:, None])  # (P, H)
        modal = y_0[rows, j_index] + np.einsum("phn,ph->pn", y_h[rows, j_index], phase)
        return np.einsum("pij,pj->pi", vectors, modal).real

    rows = np.arange(n_people)
    first = np.zeros(n_people, dtype=int)
    zero = np.zeros(n_people)
    if initial_states is None:
        d = np.zeros((n_people, n), dtype=complex)
    else:
        x0 = np.asarray(initial_states, dtype=float).reshape(n_people, n)
        d = np.einsum("pij,pj->pi", inverse, x0 - particular(first, zero))
    free = np.empty((n_people, t_start.shape[1], n), dtype=complex)  # d_j of every cycle
    free[:, 0] = d
    for j in range(t_start.shape[1] - 1):
        index = np.full(n_people, j)
        length = np.where(j + 1 < n_cycles, t_start[:, j + 1] - t_start[:, j], 0.0)
        end = particular(index, length) + np.einsum("pij,pj->pi", vectors, np.exp(lam * length[:, None]) * d).real
        d_next = np.einsum("pij,pj->pi", inverse, end - particular(index + 1, zero))
        d = np.where((j + 1 < n_cycles)[:, None], d_next, d)
        free[:, j + 1] = d
    # every sample: its cycle, the time into it, periodic + free response
    cycle_of = np.stack([np.searchsorted(t_start[p, : n_cycles[p]], time, side="right") - 1
                         for p in range(n_people)])  # (P, T)
    tau = time[None, :] - np.take_along_axis(t_start, cycle_of, axis=1)
    here = (rows[:, None], cycle_of)
    # exp(i h w tau) of every order h from the first by multiplication (one complex exponential per sample)
    first_order = np.exp(1j * omega[here] * tau)
    phase = np.cumprod(np.repeat(first_order[..., None], len(orders), axis=-1), axis=-1)  # (P, T, H)
    force_g = G * a0[here] + np.einsum("pth,pth->pt", coef[here], phase).real
    decay = np.exp(lam[:, None, :] * tau[..., None])  # (P, T, n)
    if output is not None:  # the output row taken into the eigenbasis once per system, summed per cycle
        c_row, d_gain = (np.asarray(part, dtype=float) for part in output)
        row = np.einsum("pi,pij->pj", c_row, vectors)  # (P, n)
        periodic = np.einsum("pjn,pn->pj", y_0, row)[here] + np.einsum(
            "pth,pth->pt", np.einsum("pjhn,pn->pjh", y_h, row)[here], phase)
        return (periodic + np.einsum("ptn,ptn->pt", (free * row[:, None, :])[here], decay)).real + \
            d_gain[:, None] * force_g
    modal = y_0[here] + np.einsum("pthn,pth->ptn", y_h[here], phase) + free[here] * decay
    states = np.einsum("pij,ptj->pti", vectors, modal).real
    rates = np.einsum("pij,ptj->pti", a_matrices, states) + b_vectors[:, None, :] * force_g[..., None]
    return states, rates, force_g


def coupled_response(cycles, time, mass, f_h, xi_h, floor: FloorModel | None = None, initial_state=None):
    """Response of one person on a floor (or a rigid floor) to a cycle force.

    The exact counterpart of :func:`~smd_statespace.simulation.integrate_response`
    for any number of floor modes (:func:`batch_response` with one system).

    Parameters
    ----------
    cycles : pandas.DataFrame
        Cycle table (``t_start, t_end, f_b, a0, a1, b1, ...``, g), e.g.
        ``SyntheticRecord.cycles``.
    time : array_like, shape (T,)
        Output times (s) inside the cycles.
    mass, f_h, xi_h : float
        Body mass (kg), SMD natural frequency (Hz), damping ratio (-).
    floor : FloorModel, optional
        Default rigid.
    initial_state : array_like, shape (n,), optional
        ``[u, u', q_1, q_1', ...]`` at the first cycle start; default the
        periodic steady state of the first cycle's force.

    Returns
    -------
    pandas.DataFrame
        ``time, u, u_dot, u_ddot, force_bio`` (m, m/s, m/s^2, ``g F`` in
        m/s^2) and, with modes, ``z, z_dot, z_ddot`` (floor under the person,
        m, m/s, m/s^2) and ``q1, q1_dot, ...`` (modal coordinates).
    """
    floor = FloorModel() if floor is None else floor
    mass = check_mass(mass, source="mass")
    if not (np.isfinite(f_h) and f_h > 0 and np.isfinite(xi_h) and xi_h >= 0):
        raise OptionError(f"coupled_response: f_h must be > 0 Hz and xi_h >= 0, got {f_h!r}, {xi_h!r}")
    a_matrix, b_vector = system_matrices(mass, f_h, xi_h, floor)
    init = None if initial_state is None else np.asarray(initial_state, dtype=float)[None]
    if init is not None and init.shape[1] != floor.n_state:
        raise OptionError(f"coupled_response: initial_state needs {floor.n_state} values, got {init.shape[1]}")
    states, rates, force_g = batch_response(a_matrix[None], b_vector[None], [cycles], time, init)
    states, rates = states[0], rates[0]
    frame = {"time": np.asarray(time, dtype=float), "u": states[:, 0], "u_dot": states[:, 1],
             "u_ddot": rates[:, 1], "force_bio": force_g[0]}
    if floor.n_modes:
        phi = np.asarray(floor.shape)
        frame.update(z=states[:, 2::2] @ phi, z_dot=states[:, 3::2] @ phi, z_ddot=rates[:, 3::2] @ phi)
        for k in range(floor.n_modes):
            frame[f"q{k + 1}"], frame[f"q{k + 1}_dot"] = states[:, 2 + 2 * k], states[:, 3 + 2 * k]
    return pd.DataFrame(frame)


def simulate_on_floor(synthetic, floor: FloorModel, seed=None, floor_noise=None):
    """The record of a rigid-floor simulation, replayed on a floor: same force, same GRF noise.

    Parameters
    ----------
    synthetic : SyntheticRecord
        A rigid-floor record of :func:`~smd_statespace.simulation.simulate_bouncing`
        (no effects). Its force cycles drive the coupled system; its GRF
        noise (``force - M_h (g + u'')``) is added unchanged, so the two
        records differ only by the floor.
    floor : FloorModel, FloorMode or str
        The floor under the person (a ``floor_mode`` effect or spec is
        taken through :meth:`FloorModel.from_effect`).
    seed : None, int, SeedSequence or Generator
        Randomness of the floor-acceleration noise.
    floor_noise : float, optional
        Standard deviation of the floor-acceleration noise as a fraction of
        its RMS (default: the record's GRF noise fraction).

    Returns
    -------
    record : Record
        ``time, force`` (N) and, with modes, ``floor_acc`` (m/s^2, the
        floor under the person plus noise).
    states : pandas.DataFrame
        Noise-free coupled states (:func:`coupled_response`).
    """
    truth = synthetic.truth
    if not isinstance(floor, FloorModel):  # a floor written as an effect
        floor = FloorModel.from_effect(floor, truth["mass"])
    if truth.get("effects"):
        raise OptionError("simulate_on_floor: needs a rigid-floor record without effects, "
                          f"got {sorted(truth['effects'])}")
    mass = float(truth["mass"])
    time = synthetic.record.time
    grf_noise = synthetic.record.force - mass * (G + synthetic.states["u_ddot"].to_numpy())
    states = coupled_response(synthetic.cycles, time, mass, truth["f_h"], truth["xi_h"], floor)
    force = mass * (G + states["u_ddot"].to_numpy()) + grf_noise  # Eq. 3
    floor_acc = None
    if floor.n_modes:
        level = truth["noise"] if floor_noise is None else float(floor_noise)
        z_ddot = states["z_ddot"].to_numpy()
        rng = np.random.default_rng(seed)
        floor_acc = z_ddot + level * float(np.sqrt(np.mean(z_ddot**2))) * rng.standard_normal(time.size)
    record = make_record(time, force, mass, floor_acc=floor_acc, source=floor.name)
    return record, states

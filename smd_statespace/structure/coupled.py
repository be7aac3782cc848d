"""The coupled model: a crowd of SMD people (Eq. 2) on a structure's modes, its dynamic stiffness and eigenvalues.

Derivation
----------
Mode ``j`` of the structure has the modal coordinate ``q_j`` (m), natural
frequency ``w_j``, damping ratio ``zeta_j`` and modal mass ``m_j``; person ``i``
(mass ``M_i``, Eq. 2's ``f_h``, ``xi_h``) stands at a point where the shapes are
``phi_i = (phi_1(p_i), ..., phi_m(p_i))``, so the floor under them moves
``z_i = phi_i . q``. As in :mod:`smd_statespace.simulation.floor` (the one-person
coupling of Section 6), ``u_i`` is the person's absolute COM displacement and the
spring and damper of Eq. 2 act on the motion relative to the floor::

    u_i'' = -k_i (u_i - z_i) - c_i (u_i' - z_i') + g F_i(t)                   (Eq. 2)

with ``k_i = w_h^2`` and ``c_i = 2 xi_h w_h`` per unit mass. Neither equation is
written again here: both are :mod:`smd_statespace.model.coupling` (Eq. 2 on ``u - z``
through the Eq. 2 every estimator uses, and the reaction on the modes), read as
linear maps on unit inputs by :func:`~smd_statespace.model.coupling.modal_coupling`
(exact: both are linear). The ``floor_mode`` effect and
:func:`smd_statespace.simulation.floor.system_matrices` use the same coupling.
``g F_i`` is the biomechanical force of Eq. 4 per unit mass (0 for a passive
person). The plate under a person measures their GRF ``M_i (g + u_i'')``
(Eq. 3); by Newton's third law the person pushes the floor down with it, so
the dynamic force on the structure is ``-M_i u_i''`` (the weight only sets
the static deflection) and::

    m_j q_j'' + 2 zeta_j w_j m_j q_j' + w_j^2 m_j q_j = sum_i phi_j(p_i) (-M_i u_i'')

Write ``u_i = r_i + v_i`` where ``r_i`` is the person's motion on a rigid floor
(Eq. 2 with ``z = 0``, the response the crowd generator computes) and ``v_i``
the extra motion the floor causes (Eq. 2 with ``F = 0``, driven by ``z_i``).
Then, in the Laplace domain with ``T_i(s) = (k_i + c_i s) / (s^2 + c_i s + k_i)``
(the SMD's transmissibility, ``V_i = T_i Z_i``)::

    D(s) Q(s) = P(s),   D(s) = D_0(s) + sum_i M_i s^2 T_i(s) phi_i phi_i^T
    D_0(s) = diag(m_j (s^2 + 2 zeta_j w_j s + w_j^2)),  P(t) = -sum_i phi_i M_i r_i''(t)

``P`` is the force-only load: every active person's dynamic GRF on a rigid
floor, applied to the empty structure (``D_0 Q_0 = P``). The coupled
structure differs only by the people's apparent mass ``M_i s^2 T_i(s)``: a
passive person adds mass at low frequency, damping near ``f_h`` and nothing
far above it. Each person's GRF on the structure is ``M_i (g + r_i'' + v_i'')``.

The eigenvalues of the occupied structure are those of the linear system of
:func:`state_matrix` (``2 m + 2 N`` states): all of them by a dense
eigen-solution for a small crowd (:func:`coupled_eigenvalues`), or, for any
crowd, the ``m`` that continue the empty modes by Newton's method on
``det D(s) = 0`` with the crowd's mass brought in step by step
(:func:`occupied_eigenvalues`; ``m x m`` matrices, ``O(N m^2)`` per step); the
tests check one against the other.
"""

from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..model.coupling import leg_derivatives, modal_coupling
from .modes import ModalModel

__all__ = ["person_coefficients", "transmissibility", "Coupling", "state_matrix", "coupled_eigenvalues",
           "occupied_eigenvalues", "modes_of"]


def person_coefficients(f_h, xi_h):
    """Stiffness and damping per unit mass of Eq. 2, ``(k, c)`` with ``u'' = -k (u - z) - c (u' - z') + g F``.

    Read off :func:`~smd_statespace.model.coupling.leg_derivatives` (Eq. 2 on ``u - z``, linear):
    ``k = w_h^2`` (1/s^2), ``c = 2 xi_h w_h`` (1/s).

    Parameters
    ----------
    f_h, xi_h : float or ndarray
        SMD natural frequency (Hz) and damping ratio (-).
    """
    leg = leg_derivatives(0.0, 0.0, 0.0, 0.0, f_h, xi_h)
    return -leg["u"], -leg["u_dot"]


def transmissibility(s, k, c):
    """``T(s) = (k + c s) / (s^2 + c s + k)``: floor motion to COM motion of Eq. 2 without force.

    Parameters
    ----------
    s : complex ndarray
        Laplace variable (1/s), broadcast against ``k`` and ``c``.
    k, c : ndarray
        :func:`person_coefficients`.
    """
    return (k + c * s) / (s * s + c * s + k)


class Coupling:
    """A modal structure with people on it: the matrices of the coupled model.

    Parameters
    ----------
    model : ModalModel
    point_index : array_like of int, shape (N,)
        Row of each person's point in ``model.shapes``.
    mass, f_h, xi_h : array_like, shape (N,)
        Body masses (kg), SMD frequencies (Hz) and damping ratios (-).
    """

    def __init__(self, model: ModalModel, point_index, mass, f_h, xi_h):
        self.model = model
        self.point_index = np.asarray(point_index, dtype=int).reshape(-1)
        self.mass = np.asarray(mass, dtype=float).reshape(-1)
        self.f_h = np.asarray(f_h, dtype=float).reshape(-1)
        self.xi_h = np.asarray(xi_h, dtype=float).reshape(-1)
        n = self.point_index.size
        if not (self.mass.size == self.f_h.size == self.xi_h.size == n):
            raise OptionError("Coupling: point_index, mass, f_h and xi_h must have one value per person")
        if n and not (np.all(self.mass > 0) and np.all(self.f_h > 0) and np.all(self.xi_h > 0)):
            raise OptionError("Coupling: every person needs mass > 0 kg, f_h > 0 Hz and xi_h > 0")
        self.phi = model.shapes[self.point_index] if n else np.zeros((0, model.n_modes))  # (N, m)
        m = model.n_modes
        self._links = modal_coupling(self.mass, self.f_h, self.xi_h, self.phi)
        self.k, self.c = -self._links["u"], -self._links["u_dot"]  # person_coefficients, from the same coupling
        # M_i phi_i phi_i^T: the reaction on the modes per unit u_i'' (-M_i phi_i) times the floor under i, phi_i . q
        self._outer = -np.einsum("ij,ik->ijk", self._links["drive"], self.phi).reshape(n, m * m)

    @property
    def n_people(self) -> int:
        """Number of people ``N``."""
        return self.point_index.size

    def empty_stiffness(self, s):
        """Diagonal of ``D_0(s)`` (N/m), shape ``s.shape + (m,)``."""
        model = self.model
        s = np.asarray(s, dtype=complex)[..., None]
        return model.modal_mass * (s * s + 2.0 * model.damping * model.omega * s + model.omega**2)

    def dynamic_stiffness(self, s, scale=1.0):
        """``D(s) = D_0(s) + scale sum_i M_i s^2 T_i(s) phi_i phi_i^T`` (N/m), shape ``s.shape + (m, m)``.

        ``scale`` multiplies the people's masses (the continuation of
        :func:`occupied_eigenvalues`).
        """
        s = np.asarray(s, dtype=complex)
        m = self.model.n_modes
        flat = s.reshape(-1)
        people = (flat[:, None] ** 2 * transmissibility(flat[:, None], self.k, self.c)) @ self._outer
        out = scale * people.reshape(flat.size, m, m)
        out[:, np.arange(m), np.arange(m)] += self.empty_stiffness(flat)
        return out.reshape(s.shape + (m, m))

    def stiffness_derivative(self, s, scale=1.0):
        """``dD/ds`` (N s/m) at scalar ``s``, shape (m, m)."""
        model = self.model
        numerator, denominator = self.k + self.c * s, s * s + self.c * s + self.k
        # d/ds of s^2 T(s) = s^2 numerator / denominator
        term = ((2 * s * numerator + s * s * self.c) / denominator
                - s * s * numerator * (2 * s + self.c) / denominator**2)
        out = scale * (term @ self._outer).reshape(model.n_modes, model.n_modes)
        out[np.diag_indices(model.n_modes)] += model.modal_mass * (2 * s + 2 * model.damping * model.omega)
        return out

    def second_order(self):
        """Mass, damping and stiffness matrices ``(M, C, K)`` in the coordinates ``(q_1..q_m, u_1..u_N)``.

        Built from :func:`~smd_statespace.model.coupling.modal_coupling`: person ``i``'s row is ``M_i`` times
        Eq. 2 on ``u_i - phi_i . q``, each mode's row takes the reaction ``-phi_i M_i u_i''`` of every person with
        that ``u_i''`` put in; together ``M_i k_i`` and ``M_i c_i`` between ``u_i`` and the floor ``phi_i . q``.
        """
        model, n, m = self.model, self.n_people, self.model.n_modes
        size = m + n
        masses = np.diag(np.concatenate([model.modal_mass, self.mass]))
        stiffness, damping = np.zeros((size, size)), np.zeros((size, size))
        stiffness[:m, :m] = np.diag(model.modal_mass * model.omega**2)
        damping[:m, :m] = np.diag(2.0 * model.damping * model.omega * model.modal_mass)
        links = self._links
        load = np.vstack([links["drive"].T, np.diag(self.mass)])  # on (q, u) per unit u_i'': the reaction, M_i u_i''
        for matrix, on_q, on_u in ((stiffness, "q", "u"), (damping, "q_dot", "u_dot")):
            matrix -= load @ np.hstack([links[on_q], np.diag(links[on_u])])  # u_i'' on (q, u), without g F_i
        return masses, damping, stiffness


def state_matrix(coupling: Coupling) -> np.ndarray:
    """The coupled system's state matrix ``A`` (``x = [q, u, q', u']``, ``2 m + 2 N`` states), dense."""
    masses, damping, stiffness = coupling.second_order()
    size = masses.shape[0]
    inverse = 1.0 / np.diag(masses)
    return np.block([[np.zeros((size, size)), np.eye(size)],
                     [-inverse[:, None] * stiffness, -inverse[:, None] * damping]])


def coupled_eigenvalues(coupling: Coupling) -> np.ndarray:
    """Every eigenvalue of :func:`state_matrix` (1/s), by a dense eigen-solution: for small crowds and checks."""
    return np.linalg.eigvals(state_matrix(coupling))


def occupied_eigenvalues(coupling: Coupling, steps=8, tolerance=1e-12, max_iterations=50) -> np.ndarray:
    """The ``m`` eigenvalues that continue the empty structure's modes: ``det D(s) = 0`` solved by Newton.

    Starting from each empty mode's ``s_j = -zeta_j w_j + i w_j sqrt(1 - zeta_j^2)``,
    the crowd's mass is brought in over ``steps`` equal steps, Newton's method
    on ``det D`` (step ``1 / tr(D^-1 dD/ds)``) converging at each.

    Returns
    -------
    complex ndarray, shape (m,)
        Upper-half-plane eigenvalues (1/s), in the order of the empty modes.

    Raises
    ------
    OptionError
        Newton does not converge (a crowd so heavy that a mode is lost).
    """
    model = coupling.model
    roots = (-model.damping * model.omega + 1j * model.omega * np.sqrt(np.maximum(1 - model.damping**2, 0.0)))
    roots = roots.astype(complex)
    if coupling.n_people == 0:
        return roots
    for scale in np.linspace(1.0 / steps, 1.0, steps):
        for j in range(model.n_modes):
            roots[j] = _newton(coupling, roots[j], scale, tolerance, max_iterations, j)
    return roots


def _newton(coupling, s, scale, tolerance, max_iterations, mode):
    """One root of ``det D(s) = 0`` near ``s``."""
    for _ in range(max_iterations):
        stiffness = coupling.dynamic_stiffness(np.array(s), scale)
        try:
            step = 1.0 / np.trace(np.linalg.solve(stiffness, coupling.stiffness_derivative(s, scale)))
        except np.linalg.LinAlgError:  # D(s) exactly singular: s is a root
            return s
        s = s - step
        if abs(step) <= tolerance * abs(s):
            return s
    raise OptionError(f"structure: the occupied mode {mode + 1} was not found (Newton on det D(s) = 0 did not "
                      f"converge at crowd-mass fraction {scale:.2f}); the crowd may be too heavy for its modes")


def modes_of(eigenvalues) -> list:
    """``[{"f_hz", "zeta"}, ...]`` of eigenvalues ``s``: ``f = |s| / 2 pi``, ``zeta = -Re(s) / |s|``."""
    s = np.asarray(eigenvalues, dtype=complex)
    return [{"f_hz": float(abs(v) / (2 * np.pi)), "zeta": float(-v.real / abs(v))} for v in s]

"""The variation models of the force coefficients from cycle to cycle, each written once.

A :class:`Variation` says everything the record-level model needs to know
about one model of how the force's Fourier coefficients (Eq. 4) change from
cycle to cycle: its parameters (which log variance ratios it has), the code
and state size of the compiled pass (:mod:`~smd_statespace.person.kalman`,
which implements the four models in one numba function), and its
state-space matrices for statsmodels (:class:`~smd_statespace.person.statespace.RecordStateSpace`:
smoother, residual tests). The pass and the matrices describe the same model
and the tests check that their likelihoods agree to rounding.

The force state is ``alpha`` (``p`` coefficients: the template's ``2n + 1``
and, with a phase template, a phase and a rate error), deviating from the
template ``tau``:

* ``independent``: each cycle draws ``alpha = tau + d``, ``d ~ N(0, D)``;
* ``random_walk``: each cycle adds ``e ~ N(0, E)`` to the last cycle's ``alpha``;
* ``both``: a walking base ``m := m + e`` and ``alpha = m + d`` per cycle;
* ``smooth``: ``alpha - tau`` is a Matern-3/2 process in time (variance ``D``,
  length scale ``ell``), with its rate as a second state per coefficient.

Every model may add a drift per sample (variance ``S``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from . import kalman

if TYPE_CHECKING:  # annotations only
    from .model import RecordSystem

__all__ = ["StateSpaceLayout", "Variation", "VARIATIONS"]


@dataclass(frozen=True)
class StateSpaceLayout:
    """Where the parts of the state sit in the statsmodels matrices: ``[x (n_x), alpha (p), extra]``.

    ``starts`` are statsmodels' times of the cycles' new draws (the sample
    before each cycle's first: its time ``t`` maps sample ``t`` to ``t + 1``).
    """

    nx: int
    p: int
    n_template: int
    starts: np.ndarray

    @property
    def alpha(self) -> slice:
        """The force coefficients ``alpha``."""
        return slice(self.nx, self.nx + self.p)

    @property
    def extra(self) -> slice:
        """The second block: the walking base ``m`` (``both``) or the coefficients' rates (``smooth``)."""
        return slice(self.nx + self.p, self.nx + 2 * self.p)


@dataclass(frozen=True)
class Variation:
    """One variation model of the force coefficients (see the module's description).

    Attributes
    ----------
    name : str
        ``"independent"``, ``"random_walk"``, ``"both"`` or ``"smooth"``.
    code : int
        Its branch in the compiled passes (:data:`~smd_statespace.person.kalman.INDEPENDENT`, ...).
    per_cycle : bool
        Whether it has the per-cycle deviation variances ``D`` (``log_var_d_*``).
    walks : bool
        Whether it has the random walk's variances ``E`` (``log_var_e_*``).
    smooth : bool
        Whether it has the smooth deviation's length scale (``log_smooth_time``).
    """

    name: str
    code: int
    per_cycle: bool
    walks: bool
    smooth: bool = False

    def variance_names(self, groups) -> list:
        """Names of its variance parameters for the coefficient ``groups`` (0 for ``a0``, 1..n the harmonics)."""
        names = [f"log_var_d_{i}" for i in groups] if self.per_cycle else []
        if self.smooth:
            names.append("log_smooth_time")
        if self.walks:
            names += [f"log_var_e_{i}" for i in groups]
        return names

    def state_size(self, nx: int, p: int, n_template: int) -> int:
        """Length of the filter's state with ``nx`` dynamic states and ``p`` force states."""
        return kalman.state_size(self.code, nx, p, n_template)

    def fill_statespace(self, sys: "RecordSystem", tau, layout: StateSpaceLayout, transition, intercept,
                        state_cov) -> tuple:
        """Write the model's cycle draws into statsmodels' time-varying matrices (in place); its initial state.

        ``transition`` (m, m, N), ``intercept`` (m, N) and ``state_cov``
        (m, m, N) hold the dynamics and the per-sample drift already;
        ``tau`` is the template (zero for the phase and rate errors).

        Returns
        -------
        mean, cov : ndarray, shapes (p_model,), (p_model, p_model)
            The initial mean and covariance of the state after ``x``
            (``alpha`` and the extra block), to be placed by the caller.
        """
        alpha, starts = layout.alpha, layout.starts
        D, E, drift = np.diag(sys.D), np.diag(sys.E), np.diag(sys.drift)
        size = self.state_size(layout.nx, layout.p, layout.n_template) - layout.nx
        mean, cov = np.zeros(size), np.zeros((size, size))
        mean[:layout.p] = tau
        if self.code == kalman.INDEPENDENT:
            transition[alpha, :, starts] = 0.0
            intercept[alpha, starts] = tau[:, None]
            state_cov[alpha, alpha, starts] = D[:, :, None]
            cov[:layout.p, :layout.p] = D
        elif self.code == kalman.RANDOM_WALK:
            state_cov[alpha, alpha, starts] = (E + drift)[:, :, None]
        elif self.code == kalman.SMOOTH:
            self._fill_smooth(sys, tau, layout, transition, intercept, state_cov, cov)
        else:  # both: m := m + e, alpha := m + e + d
            self._fill_both(sys, layout, transition, state_cov)
            mean[layout.p:] = tau
            cov[:layout.p, :layout.p] = D
        return mean, cov

    @staticmethod
    def _fill_smooth(sys, tau, layout, transition, intercept, state_cov, cov):
        """The Matern-3/2 pairs ``(alpha_i, alpha_i')`` of the template coefficients; timing errors drawn per cycle."""
        nx, p, n_template, starts = layout.nx, layout.p, layout.n_template, layout.starts
        f, qs, p0 = sys.smooth_phi, sys.smooth_q, sys.smooth_p0
        cov[:p, :p] = np.diag(sys.D)
        for i in range(n_template):
            rows = [nx + i, nx + p + i]
            transition[np.ix_(rows, rows)] = f[:, :, None]
            intercept[rows[0], :] += (1.0 - f[0, 0]) * tau[i]
            intercept[rows[1], :] -= f[1, 0] * tau[i]
            state_cov[np.ix_(rows, rows)] += sys.D[i] * qs[:, :, None]
            own = [i, p + i]
            cov[np.ix_(own, own)] = sys.D[i] * p0
        timing = slice(nx + n_template, nx + p)  # the phase and rate errors are drawn again per cycle
        transition[timing, :, starts] = 0.0
        state_cov[timing, timing, starts] = np.diag(sys.D[n_template:])[:, :, None]

    @staticmethod
    def _fill_both(sys, layout, transition, state_cov):
        """A walking base ``m`` (the extra block) and a fresh deviation ``d`` around it per cycle."""
        nx, p, starts = layout.nx, layout.p, layout.starts
        alpha, base = layout.alpha, layout.extra
        D, E, drift = np.diag(sys.D), np.diag(sys.E), np.diag(sys.drift)
        state_cov[base, base, :] += drift[:, :, None]
        transition[alpha, :, starts] = 0.0
        for i in range(p):
            transition[nx + i, nx + p + i, starts] = 1.0
        step = E + drift
        state_cov[alpha, alpha, starts] = (step + D)[:, :, None]
        state_cov[alpha, base, starts] = step[:, :, None]
        state_cov[base, alpha, starts] = step[:, :, None]
        state_cov[base, base, starts] = step[:, :, None]


VARIATIONS = {
    "independent": Variation("independent", kalman.INDEPENDENT, per_cycle=True, walks=False),
    "random_walk": Variation("random_walk", kalman.RANDOM_WALK, per_cycle=False, walks=True),
    "both": Variation("both", kalman.BOTH, per_cycle=True, walks=True),
    "smooth": Variation("smooth", kalman.SMOOTH, per_cycle=True, walks=False, smooth=True),
}
"""The variation models by name."""

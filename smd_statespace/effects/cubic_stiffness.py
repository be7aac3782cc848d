"""The ``cubic_stiffness`` effect: a hardening or softening leg spring."""

from __future__ import annotations

import numpy as np

from ..errors import check_range
from ..model import equations
from ..model.core import F_H, U, XI_H, Slot
from ..model.effect import Effect

__all__ = ["CubicStiffness"]


class CubicStiffness(Effect):
    """A nonlinear leg spring: restoring force ``K_h (u + beta_3 u^3)``.

    Adds the parameter ``beta_3`` (1/m^2) and the acceleration term
    ``-omega_h^2 beta_3 r^3`` with ``r = u - z`` the leg's compression (``z``
    the floor displacement when a ``floor_mode`` effect is present, else 0).
    Its Jacobian is the automatic one (central differences). ``beta_3 > 0`` hardens the spring (the
    apparent natural frequency rises with amplitude), ``beta_3 < 0`` softens it.
    A simulation without a given ``beta_3`` uses 400 1/m^2: at a COM
    amplitude of 2 cm the stiffness is then 16 % higher at the extremes,
    which raises the apparent natural frequency by about 6 %.

    Parameters
    ----------
    beta_range : (float, float)
        Uniform prior of ``beta_3`` (1/m^2). At a COM amplitude of 3 cm,
        ``beta_3 = 1000`` changes the stiffness by 90 %.

    Examples
    --------
    >>> CubicStiffness().with_values(beta_3=400).values  # known: simulated truth, or fixed in identification
    {'beta_3': 400.0}
    """

    name = "cubic_stiffness"
    simulation_defaults = {"beta_3": 400.0}

    def __init__(self, beta_range=(-1000.0, 1000.0)):
        self.beta_range = check_range(beta_range, "cubic_stiffness: beta_range")

    def slots(self, model):
        low, high = self.beta_range
        return (Slot("beta_3", "parameter", "1/m^2", low, high, nominal=max(abs(low), abs(high)) / 4.0,
                     description="cubic stiffness coefficient", linear=False),)

    def acceleration(self, model, x, t, inputs):
        compression = x[..., U] - model.floor_motion(x, t, inputs)[0]  # the leg acts on u - z (Section 6)
        spring = equations.smd_acceleration(1.0, 0.0, x[..., F_H], x[..., XI_H], 0.0)  # -omega_h^2, Eq. 2's
        return spring * model.value(x, "beta_3") * compression**3

    STIFFNESS_CHANGE = 2.0
    """Largest change of the leg's stiffness at the record's RMS displacement that ``diagnose`` searches:
    ``|beta_3| <= STIFFNESS_CHANGE / (3 u_rms^2)`` (the tangent stiffness is ``K_h (1 + 3 beta_3 u^2)``)."""

    @classmethod
    def propose(cls, fitted):
        """The candidate both diagnoses try, and ``identify --effect cubic_stiffness`` fits
        (:func:`~smd_statespace.model.fitted.propose`): ``beta_range`` scaled to the record's displacement.

        The fixed default (+-1000 1/m^2) can be too narrow: a spring whose tangent stiffness is 2.8 times K_h at 2 cm
        (``beta_3`` 1500, a simulated record with ``f_h`` 3.1 Hz) ended on the bound 1000 and was
        not proposed, where the data asked for more (LR 362). The range is the one in which the
        stiffness changes by at most :data:`STIFFNESS_CHANGE` (200 %) at the RMS of the COM
        displacement within cycles that the fit without the spring predicts (``fitted``, a
        :class:`~smd_statespace.model.fitted.FittedRecord`: its
        :attr:`~smd_statespace.model.fitted.FittedRecord.swing`; rounded up to 100 1/m^2, at least +-1000).
        """
        swing = fitted.swing
        bound = 1000.0 if swing <= 0 else max(1000.0, 100.0 * np.ceil(cls.STIFFNESS_CHANGE / (3 * swing**2) / 100.0))
        return cls(beta_range=(-bound, bound))

    TRIAL_STARTS = ((0.25, 1.0), (0.25, 0.85), (0.5, 0.85), (0.25, 0.7), (0.5, 0.7), (1.0, 0.7), (-0.2, 1.1))
    """The record-level search's trial starts besides the spring absent: ``(change, ratio)``, the tangent stiffness
    ``change`` (``3 beta_3 u^2`` at the RMS displacement within cycles) with ``f_h`` at ``ratio`` times the fit's
    without the spring. A hardening spring raises the apparent ``f_h``: fitted without the spring, the mean force
    of each cycle takes up what is missed, and a search started with the spring absent stays there (``beta_3``
    -1 to 5 where the truth was 1500, ``f_h`` +16 to +92 %, on 3 of 6 simulated records with a large spring)."""

    def record_starts(self, fitted) -> list:
        """Trial starts of the record-level search (:data:`TRIAL_STARTS`): the spring absent, then the spring with
        ``f_h`` lowered to what a hardening spring raised it from (raised for a softening one).

        Where they are tried (:func:`~smd_statespace.person.extend.fit_effects`): from the variances at their
        defaults, not the fit's without the spring, which put the misfit into the variation of each cycle's mean
        force; each start's likelihood about its own predicted path. None for the per-cycle method.
        """
        if fitted.per_cycle or not np.isfinite(fitted.f_h):
            return []
        low, high = self.beta_range
        scale = 1.0 / (3.0 * max(fitted.swing, 1e-4) ** 2)
        return [{}] + [{"beta_3": float(np.clip(change * scale, low, high)), "f_h": ratio * fitted.f_h}
                       for change, ratio in self.TRIAL_STARTS]

    def __repr__(self):
        return f"CubicStiffness(beta_range={self.beta_range})"

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
        displacement the fit without the spring predicts (``fitted``, a
        :class:`~smd_statespace.model.fitted.FittedRecord`; rounded up to 100 1/m^2, at least +-1000).
        """
        rms = float(np.sqrt(np.mean(fitted.displacement**2)))
        bound = 1000.0 if rms <= 0 else max(1000.0, 100.0 * np.ceil(cls.STIFFNESS_CHANGE / (3 * rms**2) / 100.0))
        return cls(beta_range=(-bound, bound))

    def __repr__(self):
        return f"CubicStiffness(beta_range={self.beta_range})"

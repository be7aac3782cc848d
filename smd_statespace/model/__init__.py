"""The augmented-state spring-mass-damper model of a bouncing person (Eq. 1-18).

======================= =======================================================
module                  what it holds
======================= =======================================================
:mod:`.core`            :class:`SMDModel` (state layout, rate, transition,
                        observation, prior); the names of the four
                        modules below are importable from it too
:mod:`.slots`           :class:`Slot`, the base slots and their positions
                        ``U, U_DOT, F_H, XI_H`` (Eq. 7)
:mod:`.equations`       Eq. 2 (:func:`smd_acceleration`, :func:`acceleration_frf`),
                        ``K_h``, ``C_h``, ``BLF`` (Eq. 5, 17, 18)
:mod:`.coupling`        a person on a moving floor (Section 6): Eq. 2 on
                        ``u - z`` and the reaction on each floor mode
:mod:`.discretisation`  one Euler or Runge-Kutta step and its exact
                        Jacobian (Eq. 11-12)
:mod:`.prior`           :class:`Prior`, the independent prior of the slots
:mod:`.inputs`          :class:`CycleInputs`, a cycle's known inputs
:mod:`.effect`          :class:`Effect`, the base class of physical effects
                        (the built-ins and a user's are in :mod:`smd_statespace.effects`)
:mod:`.jacobians`       automatic derivatives of effects' terms and their checks
======================= =======================================================
"""

from .core import (DISCRETISATIONS, F_H, OBSERVATIONS, ONE_WORD_PER_DOUBLE, TWO_PI, U, U_DOT, XI_H, CycleInputs,
                   Prior, SMDModel, Slot, acceleration_derivatives, acceleration_frf, blf, c_h, k_h,
                   smd_acceleration)
from .effect import Effect

__all__ = ["SMDModel", "Slot", "CycleInputs", "Prior", "Effect", "k_h", "c_h", "blf", "acceleration_frf", "smd_acceleration",
           "acceleration_derivatives",
           "TWO_PI", "U", "U_DOT", "F_H",
           "XI_H", "DISCRETISATIONS", "OBSERVATIONS", "ONE_WORD_PER_DOUBLE"]

"""The augmented-state spring-mass-damper model of a bouncing person (Eq. 1-18).

=================== ==========================================================
module              what it holds
=================== ==========================================================
:mod:`.core`        :class:`SMDModel` (state layout, rate, transition,
                    observation, prior), :class:`Slot`, :class:`CycleInputs`,
                    ``K_h``, ``C_h``, ``BLF`` (Eq. 5, 17, 18)
:mod:`.effect`      :class:`Effect`, the base class of physical effects
                    (the built-ins and a user's are in :mod:`smd_statespace.effects`)
:mod:`.jacobians`   automatic derivatives of effects' terms and their checks
=================== ==========================================================
"""

from .core import (DISCRETISATIONS, F_H, OBSERVATIONS, ONE_WORD_PER_DOUBLE, TWO_PI, U, U_DOT, XI_H, CycleInputs,
                   Prior, SMDModel, Slot, acceleration_frf, blf, c_h, k_h, smd_acceleration)
from .effect import Effect

__all__ = ["SMDModel", "Slot", "CycleInputs", "Prior", "Effect", "k_h", "c_h", "blf", "acceleration_frf", "smd_acceleration",
           "TWO_PI", "U", "U_DOT", "F_H",
           "XI_H", "DISCRETISATIONS", "OBSERVATIONS", "ONE_WORD_PER_DOUBLE"]

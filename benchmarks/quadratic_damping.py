"""The user's quadratic leg damper of docs/effects.md, as a file for ``--effects`` (benchmarks/person_effects.py)."""

import numpy as np

from smd_statespace.effects import register_effect
from smd_statespace.model import U_DOT, Effect, Slot


@register_effect
class QuadraticDamping(Effect):
    """Velocity-squared leg damping: adds -c_q r'|r'| to the COM acceleration, r' = u' - z' (c_q in 1/m)."""

    name = "quadratic_damping"
    simulation_defaults = {"c_q": 8.0}

    def __init__(self, c_q_max=20.0):
        self.c_q_max = float(c_q_max)

    def slots(self, model):
        return (Slot("c_q", "parameter", "1/m", 0.0, self.c_q_max, nominal=self.c_q_max / 4,
                     description="quadratic damping coefficient", linear=False),)

    def acceleration(self, model, x, t, inputs):
        rate = x[..., U_DOT] - model.floor_motion(x, t, inputs)[1]
        return -model.value(x, "c_q") * rate * np.abs(rate)

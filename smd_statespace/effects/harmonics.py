"""The ``harmonics`` effect: force harmonics above the model's ``n`` (Eq. 4)."""

from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..io import G
from ..model.core import Slot
from ..model.effect import Effect
from .options import numbers

__all__ = ["Harmonics"]


class Harmonics(Effect):
    """Extra Fourier harmonics of the biomechanical force.

    Adds the coefficients ``a_k, b_k`` (g) for ``k = n+1 ... n+count`` and
    their terms ``g (a_k cos(k theta) + b_k sin(k theta))`` to the
    acceleration, with the same prior range as the base coefficients. In a
    simulation they are extra harmonics of the force with amplitudes ``blf``
    and ``phases``, varying from cycle to cycle like the base ones.

    Parameters
    ----------
    count : int, optional
        Number of harmonics to add (default 2, or ``len(blf)``).
    blf : float or sequence of float, optional
        Simulation: amplitudes ``BLF_k`` (g) of the added harmonics (default
        :data:`DEFAULT_BLF`, cut to ``count``).
    phases : sequence of float, optional
        Simulation: their phases (rad); default the simulator's GRF-shape rule
        (:func:`~smd_statespace.simulation.default_phases`).
    """

    name = "harmonics"
    DEFAULT_BLF = (0.04, 0.03, 0.02, 0.01)

    def __init__(self, count: int | None = None, blf=None, phases=None):
        where = "harmonics"
        self.blf = None if blf is None else tuple(float(v) for v in np.atleast_1d(numbers(blf, "blf", where)))
        if self.blf is not None and (not self.blf or min(self.blf) < 0):
            raise OptionError(f"{where}: blf must be amplitudes >= 0 (g), got {blf!r}")
        if count is None:
            count = 2 if self.blf is None else len(self.blf)
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
            raise OptionError(f"{where}: count must be a whole number >= 1, got {count!r}")
        self.count = int(count)
        if self.blf is not None and len(self.blf) != self.count:
            raise OptionError(f"{where}: blf has {len(self.blf)} amplitudes, count is {self.count}")
        self.phases = None if phases is None else tuple(float(v) for v in np.atleast_1d(numbers(phases, "phases",
                                                                                                   where)))
        if self.phases is not None and len(self.phases) != self.count:
            raise OptionError(f"{where}: phases has {len(self.phases)} values, the effect adds {self.count} harmonics")

    @property
    def options(self) -> dict:
        """The options built with, ``count`` always first: a spec says how many harmonics it adds."""
        return {"count": self.count, **super().options}

    def orders(self, model) -> np.ndarray:
        """Harmonic orders this effect adds to ``model``."""
        return np.arange(model.n_harmonics + 1, model.n_harmonics + self.count + 1)

    def slots(self, model):
        low, high = model.options["coefficient_range"]
        nominal = max(abs(low), abs(high)) / 2.0
        return tuple(
            Slot(f"{c}{k}", "parameter", "g", low, high, nominal=nominal,
                 description=f"{'cosine' if c == 'a' else 'sine'} coefficient of harmonic {k}")
            for k in self.orders(model) for c in "ab"
        )

    def _names(self, model):
        return [f"{c}{k}" for k in self.orders(model) for c in "ab"]

    def acceleration(self, model, x, t, inputs):
        basis = model.fourier_basis(t, inputs, harmonics=self.orders(model))
        coefficients = np.stack(np.broadcast_arrays(*(model.value(x, name) for name in self._names(model))), -1)
        return G * np.sum(coefficients * basis, axis=-1)

    def acceleration_jacobian(self, model, x, t, inputs):
        jac = np.zeros(x.shape)
        jac[..., model.effect_slice(self)] = G * model.fourier_basis(t, inputs, harmonics=[
            int(name[1:]) for name in self._names(model) if name in model.state_names][::2])
        return jac

    def for_simulation(self, model, mass):
        """The coefficient slots at 0: the simulator puts these harmonics into the force itself."""
        return self.with_values(**{name: 0.0 for name in self._names(model)})

    def force_harmonics(self, model):
        """``(blf, phases)`` of the extra harmonics for the simulator: the given amplitudes (g), else the first
        ``count`` of :data:`DEFAULT_BLF`, and the given phases (rad) or None."""
        if self.blf is None and self.count > len(self.DEFAULT_BLF):
            raise OptionError(f"harmonics: give blf=... (g) to simulate {self.count} extra harmonics")
        return (self.blf or self.DEFAULT_BLF[:self.count]), self.phases

    def record_harmonics(self, model) -> int:
        """Record level: ``count`` more harmonics of the force's template and spread."""
        return self.count

    def simulation_truth(self):
        """The simulated extra harmonics' amplitudes (g) and phases (rad, None for the simulator's default)."""
        return {"blf": list(self.blf or self.DEFAULT_BLF[:self.count]),
                "phases": None if self.phases is None else list(self.phases)}

    def __repr__(self):
        return f"Harmonics(count={self.count})"

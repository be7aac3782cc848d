"""The independent prior of the state slots (:class:`Prior`) and how it draws states.

:meth:`SMDModel.prior <smd_statespace.model.core.SMDModel.prior>` builds it;
the estimators draw their initial particles from it. Re-exported by
:mod:`smd_statespace.model.core` and :mod:`smd_statespace.model`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


ONE_WORD_PER_DOUBLE = (np.random.SFC64, np.random.PCG64, np.random.PCG64DXSM, np.random.Philox)
"""Bit generators whose ``random()`` uses exactly one ``random_raw`` word per number (not MT19937: two)."""


@dataclass(frozen=True)
class Prior:
    """Independent prior of every state slot.

    Parameters slots are uniform on ``[low, high]``; dynamic slots are normal
    with ``mean`` and ``std``. ``kinds[i]`` says which.
    """

    names: tuple[str, ...]
    kinds: tuple[str, ...]
    first: np.ndarray
    second: np.ndarray

    @property
    def mean(self) -> np.ndarray:
        """Prior mean of every slot."""
        uniform = np.array([kind == "uniform" for kind in self.kinds])
        return np.where(uniform, 0.5 * (self.first + self.second), self.first)

    @property
    def std(self) -> np.ndarray:
        """Prior standard deviation of every slot (the yardstick for identifiability)."""
        uniform = np.array([kind == "uniform" for kind in self.kinds])
        return np.where(uniform, (self.second - self.first) / np.sqrt(12.0), self.second)

    @property
    def cov(self) -> np.ndarray:
        """Diagonal prior covariance."""
        return np.diag(self.std**2)

    def sample(self, rng: np.random.Generator, size: int, columns=None) -> np.ndarray:
        """Draw ``size`` states, shape ``(size, n_state)``.

        ``columns`` (a boolean mask over the slots, or slot indices in
        increasing order) returns only those slots, and leaves ``rng`` exactly where the
        full draw would: the uniform slots' numbers are skipped, not computed,
        when none of them is asked for (a restart needs only the two motion
        slots). The uniform slots draw first, then the normal ones.
        """
        uniform = np.array([kind == "uniform" for kind in self.kinds])
        normal = ~uniform
        wanted = np.ones(len(self.names), dtype=bool)
        if columns is not None:
            wanted[:] = False
            wanted[columns] = True  # a boolean mask or slot indices
        draws = np.empty((size, len(self.names)))
        n_uniform = int(uniform.sum())
        if (wanted & uniform).any() or not isinstance(rng.bit_generator, ONE_WORD_PER_DOUBLE):
            # low + (high - low) * U and mean + std * Z, in place: what rng.uniform and rng.normal compute
            # element by element (the same numbers), without their slow per-element parameter broadcasting.
            values = rng.random((size, n_uniform))
            values *= self.second[uniform] - self.first[uniform]
            values += self.first[uniform]
            draws[:, uniform] = values
        else:
            rng.bit_generator.random_raw(size * n_uniform)  # the words rng.random would have used
        values = rng.standard_normal((size, int(normal.sum())))
        values *= self.second[normal]
        values += self.first[normal]
        draws[:, normal] = values
        return draws if columns is None else draws[:, wanted]

"""A series against the bouncing-cycle phase: what repeats every cycle, and where in the cycle.

Functions over arrays, used by :meth:`ModelCheck.phase_locked
<smd_statespace.diagnostics.check.ModelCheck.phase_locked>`,
:meth:`~smd_statespace.diagnostics.check.ModelCheck.phase_profile` and the
force-basis removal of :meth:`~smd_statespace.diagnostics.check.ModelCheck.remove_force_harmonics`:

- :func:`phase_locked`: the least-squares fit of a Fourier series in the phase, common to every cycle;
- :func:`phase_profile`: mean and spread of a series in equal phase bins;
- :func:`harmonic_regressors`: the force regressors ``1, cos(k theta), sin(k theta)`` of Eq. 4.

The phase of a sample is ``(t - t_start) / (t_end - t_start)`` of its cycle,
in [0, 1] (0 and 1 at the GRF peaks that bound it).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import OptionError
from ..model import TWO_PI

__all__ = ["phase_locked", "phase_profile", "harmonic_regressors"]


def phase_locked(values, phase, orders) -> np.ndarray:
    """The part of a series that repeats with the bouncing cycle (least squares over all samples).

    The series is regressed on ``1, cos(2 pi k p), sin(2 pi k p)``,
    ``k = 1 .. orders``, ``p`` the cycle phase, with coefficients common to
    every cycle. What the person does every cycle (a missing force
    harmonic, a nonlinearity of the periodic motion) is phase-locked; what
    another source does to the floor is not, whatever its frequency, even
    at a multiple of ``f_b``.

    Parameters
    ----------
    values : ndarray, shape (T,)
        The series (any unit).
    phase : ndarray, shape (T,)
        Cycle phase of each sample, in [0, 1].
    orders : int
        Highest order ``k`` (0 or less: the mean only).

    Returns
    -------
    ndarray, shape (T,)
        The fitted phase-locked part, in the series' unit.
    """
    angle = TWO_PI * phase[:, None] * np.arange(1, max(int(orders), 0) + 1)
    design = np.column_stack([np.ones_like(phase), np.cos(angle), np.sin(angle)])
    coefficients, *_ = np.linalg.lstsq(design, values, rcond=None)
    return design @ coefficients


def phase_profile(values, phase, weight, n_cycles, bins=24) -> pd.DataFrame:
    """A series against the bouncing-cycle phase: where in the cycle it is large.

    Parameters
    ----------
    values : ndarray, shape (T,)
        The series (N for a GRF residual).
    phase : ndarray, shape (T,)
        Cycle phase of each sample, in [0, 1].
    weight : float
        Body weight ``M_h g`` (N), for the columns in % of body weight.
    n_cycles : int
        Number of cycles the samples come from, for the standard error.
    bins : int
        Number of equal phase bins.

    Returns
    -------
    pandas.DataFrame
        One row per bin: ``phase`` (centre), ``phase_low``,
        ``phase_high``, ``n`` (samples), ``mean`` and ``sd`` of the
        series (N), ``mean_bw`` and ``sd_bw`` (% body weight), and
        ``sem`` (N): the standard error of the mean over cycles
        (``sd / sqrt(n_cycles)``).

    Raises
    ------
    OptionError
        ``bins`` below 1.
    """
    bins = int(bins)
    if bins < 1:
        raise OptionError(f"bins must be a whole number >= 1, got {bins!r}")
    edges = np.linspace(0.0, 1.0, bins + 1)
    which = np.clip(np.searchsorted(edges, phase, side="right") - 1, 0, bins - 1)
    count = np.bincount(which, minlength=bins)
    total = np.bincount(which, weights=values, minlength=bins)
    square = np.bincount(which, weights=values**2, minlength=bins)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = total / count
        sd = np.sqrt(np.maximum(square / count - mean**2, 0.0) * count / np.maximum(count - 1, 1))
    return pd.DataFrame({
        "phase": 0.5 * (edges[:-1] + edges[1:]), "phase_low": edges[:-1], "phase_high": edges[1:], "n": count,
        "mean": mean, "sd": sd, "mean_bw": 100.0 * mean / weight, "sd_bw": 100.0 * sd / weight,
        "sem": sd / np.sqrt(max(n_cycles, 1)),
    })


def harmonic_regressors(theta, orders) -> np.ndarray:
    """The force regressors of Eq. 4: ``1, cos(k theta), sin(k theta)`` per order ``k``, shape (m, 1 + 2 len(orders)).

    Parameters
    ----------
    theta : ndarray, shape (m,)
        Cycle angle ``2 pi f_b (t - t_start)`` (rad).
    orders : sequence of int
        Harmonic orders, in column order (each order's cosine, then its sine).
    """
    return np.column_stack([np.ones_like(theta)] + [f(k * theta) for k in orders for f in (np.cos, np.sin)])

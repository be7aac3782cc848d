"""The article's population (Table 2): people bouncing at a given frequency, drawn from the band's fits.

:func:`sample_population` draws ``f_h``, ``xi_h`` and ``BLF1..3`` from the
skew-normal fits (Eq. 19) of the band that holds ``f_b``, and a body mass;
``K_h``, ``C_h`` follow from Eq. 17-18. The crowd generator
(:mod:`smd_statespace.simulation.crowd`) and the simulator's users draw their people
here.
"""

from __future__ import annotations

import functools

import numpy as np
import pandas as pd

from .. import article
from ..errors import OptionError
from ..model import c_h, k_h

__all__ = ["POPULATION_BOUNDS", "MASS_DISTRIBUTION", "sample_population"]

POPULATION_BOUNDS = {
    "f_h": (1.0, 6.0),
    "xi_h": (0.02, 1.0),
    "blf": (0.0, 1.0),
    "mass": (45.0, 100.0),
}
"""Physical ranges used by :func:`sample_population`; draws outside are redrawn.

``f_h`` (Hz) may exceed ``f_b``; the upper limit 6 Hz is above the estimator's
initial range (1-4 Hz) because Table 2 puts 53 % (2.95-3.35 Hz band) and 73 %
(3.35-3.75 Hz band) of ``f_h`` above 4 Hz. ``xi_h`` (-), BLFs (g), mass (kg).
"""

MASS_DISTRIBUTION = (65.0, 10.0)
"""Mean and standard deviation (kg) of the normal body-mass distribution of
:func:`sample_population` (the article publishes no mass distribution)."""

@functools.lru_cache(maxsize=256)
def _bounded_distribution(kind, parameters, low, high, name):
    """Frozen ``skewnorm(a, loc=m, scale=s)`` (``kind="skewnorm"``, ``parameters=(m, s, a)``) or
    ``norm(loc, scale)``, checked to put enough mass in [low, high]; cached, as freezing costs about 1 ms."""
    from scipy.stats import norm, skewnorm

    if kind == "skewnorm":
        m, s, a = parameters
        distribution = skewnorm(a, loc=m, scale=s)
    else:
        distribution = norm(*parameters)
    accept = float(distribution.cdf(high) - distribution.cdf(low))
    if accept < 1e-3:
        raise OptionError(
            f"sample_population: the {name} distribution puts only {accept:.2g} of its mass in {low:g}-{high:g}"
        )
    return distribution


def _draw_bounded(distribution, n, low, high, rng):
    """Draw ``n`` values of a frozen distribution, redrawing those outside [low, high]."""
    values = distribution.rvs(size=n, random_state=rng)
    while True:
        bad = (values < low) | (values > high)
        if not bad.any():
            return values
        values[bad] = distribution.rvs(size=int(bad.sum()), random_state=rng)


def _population_columns(n, f_b, seed, table=None, bounds=None):
    """The draws of :func:`sample_population` as arrays: ``f_b, f_h, xi_h, blf1..3, mass``."""
    from .bouncing import _resolve_seed  # the simulator's seed policy
    from .dynamics import _number  # and its argument checks

    where = "sample_population"
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 1:
        raise OptionError(f"{where}: n must be a positive integer, got {n!r}")
    f_b = _number(f_b, "f_b (Hz)", positive=True, where=where)
    band = article.band_of(f_b)
    if band is None:
        edges = ", ".join(f"{lo:g}-{hi:g}" for lo, hi in article.BANDS)
        raise OptionError(f"{where}: f_b = {f_b:g} Hz is outside the article's bands ({edges} Hz)")
    table = article.TABLE2 if table is None else table
    limits = dict(POPULATION_BOUNDS)
    if bounds is not None:
        for key in bounds:
            if key not in POPULATION_BOUNDS:
                raise OptionError(f"{where}: unknown bounds key {key!r}; valid keys: {', '.join(POPULATION_BOUNDS)}")
        limits.update(bounds)
    rng, _ = _resolve_seed(seed)

    columns = {"f_b": np.full(n, f_b)}
    for parameter, column, limit in (
        ("f_h", "f_h", "f_h"),
        ("xi_h", "xi_h", "xi_h"),
        ("BLF1", "blf1", "blf"),
        ("BLF2", "blf2", "blf"),
        ("BLF3", "blf3", "blf"),
    ):
        try:
            m, s, a = (float(v) for v in table[parameter][band])
        except (KeyError, IndexError, TypeError, ValueError):
            raise OptionError(
                f"{where}: table has no (m, s, a) fit for {parameter!r} in band {band}; "
                "expected the layout of article.TABLE2"
            ) from None
        low, high = (float(v) for v in limits[limit])
        distribution = _bounded_distribution("skewnorm", (m, s, a), low, high, parameter)
        columns[column] = _draw_bounded(distribution, n, low, high, rng)
    low, high = (float(v) for v in limits["mass"])
    distribution = _bounded_distribution("norm", tuple(float(v) for v in MASS_DISTRIBUTION), low, high, "mass")
    columns["mass"] = _draw_bounded(distribution, n, low, high, rng)
    return columns


def sample_population(n, f_b, seed=None, table=None, bounds=None):
    """Draw ``n`` people bouncing at ``f_b`` from the article's Table 2.

    ``f_h``, ``xi_h`` and ``BLF1..3`` are drawn independently (the article
    gives only marginals) from the skew-normal fits (Eq. 19,
    ``scipy.stats.skewnorm(a, loc=m, scale=s)``) of the band holding ``f_b``;
    values outside :data:`POPULATION_BOUNDS` are redrawn (truncated
    distributions). The body mass is not in Table 2: it is drawn from
    ``N(65, 10)`` kg (:data:`MASS_DISTRIBUTION`) truncated to 45-100 kg. ``K_h``
    and ``C_h`` follow from Eq. 17-18 (Table 2's own ``K_h``/``C_h`` fits are
    not used; they are not consistent with its ``f_h`` fits).

    Parameters
    ----------
    n : int
        Number of people, >= 1.
    f_b : float
        Bouncing frequency (Hz), within one of :data:`article.BANDS`.
    seed : None, int, SeedSequence or Generator
        Source of randomness (:func:`numpy.random.default_rng`).
    table : mapping, optional
        Fits in the layout of :data:`article.TABLE2` (``table[parameter][band]
        = (m, s, a)`` for ``f_h, xi_h, BLF1, BLF2, BLF3``); default Table 2.
    bounds : dict, optional
        Overrides of :data:`POPULATION_BOUNDS` (keys ``f_h, xi_h, blf, mass``).

    Returns
    -------
    pandas.DataFrame
        Columns ``f_b`` (Hz), ``f_h`` (Hz), ``xi_h``, ``blf1, blf2, blf3``
        (g), ``mass`` (kg), ``K_h`` (N/m), ``C_h`` (N s/m); one row per person.

    Raises
    ------
    OptionError
        ``f_b`` outside every band, bad ``n``, ``table`` or ``bounds``.
    """
    return pd.DataFrame(with_stiffness_and_damping(_population_columns(n, f_b, seed, table, bounds)))


def with_stiffness_and_damping(columns):
    """``columns`` (a mapping or table with ``f_h``, ``xi_h``, ``mass``) with ``K_h`` (N/m) and ``C_h`` (N s/m) added."""
    columns["K_h"] = k_h(columns["f_h"], columns["mass"])  # Eq. 17
    columns["C_h"] = c_h(columns["xi_h"], columns["f_h"], columns["mass"])  # Eq. 18
    return columns

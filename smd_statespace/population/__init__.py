"""Population statistics of many identified cycles (Section 5): bands, skew-normal fits (Eq. 19), trends.

:mod:`.statistics` holds them; the figures are :mod:`smd_statespace.plotting.population`'s and the
sampler that draws people from Table 2 is :mod:`smd_statespace.simulation.population`'s.
"""

from .statistics import Bands, PopulationStats, fit_skewnorm, fit_trend, population_stats, read_results

__all__ = ["Bands", "PopulationStats", "fit_skewnorm", "fit_trend", "population_stats", "read_results"]

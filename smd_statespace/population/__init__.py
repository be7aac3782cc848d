"""Population statistics of many identified cycles (Section 5): bands, skew-normal fits (Eq. 19), trends.

=================== ==========================================================
module              what it holds
=================== ==========================================================
:mod:`.bands`       :class:`Bands`: the article's frequency bands or your own
:mod:`.results`     :func:`read_results`: identified cycles from ``results.csv``
                    tables, the parameters of Table 2 (:data:`PARAMETERS`)
:mod:`.skewnormal`  Eq. 19: :func:`fit_skewnorm` (maximum likelihood),
                    :func:`bootstrap_skewnorm`
:mod:`.trends`      :func:`fit_trend`: polynomials in ``f_b``, the "preferred
                    frequency"
:mod:`.statistics`  :func:`population_stats`: all of it per band and
                    parameter in the layout of Table 2, :func:`compare_table2`
=================== ==========================================================

The figures are :mod:`smd_statespace.plotting.population`'s; the sampler that draws people
from Table 2 is :mod:`smd_statespace.simulation.population`'s.
"""

from .bands import Bands
from .results import ADEQUATE_COLUMN, PARAMETERS, ParameterSpec, parse_parameters, read_results
from .skewnormal import A_MAX, N_BOOTSTRAP, SkewNormalResult, bootstrap_skewnorm, fit_skewnorm
from .statistics import MIN_CYCLES, CellFit, PopulationStats, compare_table2, population_stats
from .trends import TREND_DEGREES, TrendResult, fit_trend

__all__ = ["Bands", "ParameterSpec", "PARAMETERS", "ADEQUATE_COLUMN", "parse_parameters", "read_results",
           "N_BOOTSTRAP", "A_MAX", "SkewNormalResult", "fit_skewnorm", "bootstrap_skewnorm", "TREND_DEGREES",
           "TrendResult", "fit_trend", "MIN_CYCLES", "CellFit", "PopulationStats", "population_stats",
           "compare_table2"]

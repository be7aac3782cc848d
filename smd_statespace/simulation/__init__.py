"""Synthetic records with known truth: one person, the population sampler, a crowd.

=================== ==========================================================
module              what it holds
=================== ==========================================================
:mod:`.bouncing`    :func:`simulate_bouncing` (Eq. 2-4, cycle-to-cycle
                    variation, any registered effect), :func:`integrate_response`
                    and the shipped sample
:mod:`.population`  :func:`sample_population`: people drawn from Table 2
:mod:`.crowd`       :func:`~.crowd.simulate_crowd`: many people bouncing together
:mod:`.floor`       :class:`~.floor.FloorModel` and the exact coupled
                    person-floor response (several floor modes)
=================== ==========================================================
"""

from .bouncing import (DEFAULT_BLF, GRF_PHASE_LAG, SAMPLE_SETTINGS, SMOOTH_CORRELATION_CYCLES, VARIATIONS,
                       SyntheticRecord, acceleration_frf, ambient_floor_excitation, ambient_line_count, default_phases,
                       integrate_response, sample_path, sample_truth_path, simulate_bouncing, write_sample)
from .population import MASS_DISTRIBUTION, POPULATION_BOUNDS, sample_population

__all__ = ["VARIATIONS", "SMOOTH_CORRELATION_CYCLES", "DEFAULT_BLF", "GRF_PHASE_LAG", "POPULATION_BOUNDS",
           "MASS_DISTRIBUTION", "SAMPLE_SETTINGS", "SyntheticRecord", "simulate_bouncing", "integrate_response",
           "default_phases", "acceleration_frf", "ambient_floor_excitation", "ambient_line_count", "sample_population",
           "write_sample", "sample_path", "sample_truth_path"]

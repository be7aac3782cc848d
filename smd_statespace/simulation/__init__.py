"""Synthetic records with known truth: one person, the population sampler, a crowd.

===================== ========================================================
module                what it holds
===================== ========================================================
:mod:`.bouncing`      :func:`simulate_bouncing`: the record (Eq. 2-4, GRF
                      plus noise, any registered effect); the public names
                      of the five modules below are importable from it too
:mod:`.settings`      its arguments checked and completed, the seed policy
:mod:`.force_shape`   the default force shape (:func:`default_phases`)
:mod:`.synthetic`     its result, :class:`SyntheticRecord`, and the measured
                      record (Eq. 3 plus noise)
:mod:`.truth`         the truth behind a record
:mod:`.sample`        the shipped sample's settings and files
:mod:`.dynamics`      the equations of motion with the effects' own terms and
                      their integration, :func:`integrate_response`
:mod:`.variation`     cycle-to-cycle variation of the force: jumps or smooth
:mod:`.generators`    more generators of it: coefficients, pulses, tempo
:mod:`.population`    :func:`sample_population`: people drawn from Table 2
:mod:`.crowd`         :func:`~.crowd.simulate_crowd`: many people bouncing together
:mod:`.crowd_table`   the skew-normal fits a crowd is drawn from (``fit_table``)
:mod:`.crowd_forces`  each person's force cycles and GRF, exact or with effects
:mod:`.floor`         :class:`~.floor.FloorModel` and the exact coupled
                      person-floor response (several floor modes)
:mod:`.lab`           :func:`~.lab.simulate_lab_record`: a lab's force-plate
                      export of a whole trial (standing, ramps, a tiring
                      bout, hum, drift); typical ones drawn over wide ranges
===================== ========================================================
"""

from .bouncing import (DEFAULT_BLF, GRF_PHASE_LAG, SAMPLE_SETTINGS, SyntheticRecord, default_phases, sample_path,
                       sample_truth_path, simulate_bouncing, write_sample)
from ..model import acceleration_frf
from ..effects.excitation import ambient_floor_excitation, ambient_line_count
from .dynamics import integrate_response
from .lab import LAB_RANGES, LabRanges, draw_lab_settings, simulate_lab_record, simulate_typical_lab_record
from .population import MASS_DISTRIBUTION, POPULATION_BOUNDS, sample_population

__all__ = ["VARIATIONS", "SMOOTH_CORRELATION_CYCLES", "DEFAULT_BLF", "GRF_PHASE_LAG", "POPULATION_BOUNDS",
           "MASS_DISTRIBUTION", "SAMPLE_SETTINGS", "SyntheticRecord", "simulate_bouncing", "integrate_response",
           "default_phases", "acceleration_frf", "ambient_floor_excitation", "ambient_line_count", "sample_population",
           "write_sample", "sample_path", "sample_truth_path", "simulate_lab_record", "simulate_typical_lab_record",
           "draw_lab_settings", "LabRanges", "LAB_RANGES"]
from .variation import SMOOTH_CORRELATION_CYCLES, VARIATIONS

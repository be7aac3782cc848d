"""A crowd of SMD people on a structure's modes: occupied modes, responses, coupled vs force-only (issue 48).

=================== ==============================================================
module              what it holds
=================== ==============================================================
:mod:`.modes`       :class:`ModalModel`: ``modes.csv`` and ``shapes.csv`` read and
                    checked; the examples :func:`sdof`, :func:`beam`, :func:`plate`
:mod:`.people`      who stands where: drawn (Table 2) or ``people.csv``; the active
                    people's force cycles and rigid-floor GRFs
:mod:`.coupled`     the coupled model (Eq. 2 on the modes): dynamic stiffness,
                    state matrix, eigenvalues (dense; Newton on ``det D = 0``)
:mod:`.solve`       coupled and force-only time histories (frequency domain)
:mod:`.response`    peak, maximum 1 s running RMS, VDV; accelerance
:mod:`.analysis`    :func:`analyse_structure` -> :class:`StructureResult`
:mod:`.montecarlo`  many random crowds on any executor
:mod:`.weighting`   ``W_b`` (BS 6841) and ``W_k`` (ISO 2631-1) frequency weightings
:mod:`.limits`      published acceptance limits with their sources (:data:`ROUTE2`);
                    a value or a result's worst point classified against them
=================== ==============================================================
"""

from .analysis import StructureResult, analyse_structure
from .coupled import Coupling, coupled_eigenvalues, occupied_eigenvalues
from .limits import LIMITS, ROUTE2, Criterion, Limits
from .modes import EXAMPLES, ModalModel, beam, plate, read_modal_model, sdof
from .montecarlo import CrowdDraws, monte_carlo, percentiles
from .people import PASSIVE, Occupants, draw_occupants, read_occupants
from .response import measures, running_rms
from .weighting import WEIGHTINGS, weighted, weighting_gain

__all__ = ["StructureResult", "analyse_structure", "Coupling", "coupled_eigenvalues", "occupied_eigenvalues",
           "EXAMPLES", "ModalModel", "beam", "plate", "read_modal_model", "sdof", "CrowdDraws", "monte_carlo",
           "percentiles", "PASSIVE", "Occupants", "draw_occupants", "read_occupants", "measures", "running_rms",
           "WEIGHTINGS", "weighted", "weighting_gain", "LIMITS", "ROUTE2", "Criterion", "Limits"]

"""smd_statespace: identify the spring-mass-damper (SMD) model of a bouncing person.

Implements H. Wang, J. Chen, T. Nagayama, "Parameter identification of
spring-mass-damper model for bouncing people", J. Sound Vib. 456 (2019) 13-29:
the augmented-state SMD model (Eq. 7-16) with pluggable physical effects, the
signal pipeline that turns a ground reaction force (GRF) into centre-of-mass
motion (Eq. 3), interchangeable estimators (particle filter, UKF, EKF, exact
grid) run cycle by cycle with repeated passes, model checking and the search
for missing effects, batch runs, population statistics (Section 5), a crowd-load
generator and the human-structure interaction study (Section 6), with a
simulator of records with known truth. Map of the modules: docs/index.md.
"""

__version__ = "0.1.0"

from .model import SMDModel, Slot, Effect, CycleInputs, k_h, c_h, blf  # noqa: E402
from .errors import (  # noqa: E402
    SMDInputError,
    RecordError,
    MassError,
    OptionError,
    CycleError,
)

__all__ = [
    "__version__",
    "SMDInputError",
    "RecordError",
    "MassError",
    "OptionError",
    "CycleError",
    "SMDModel",
    "Slot",
    "Effect",
    "CycleInputs",
    "k_h",
    "c_h",
    "blf",
]

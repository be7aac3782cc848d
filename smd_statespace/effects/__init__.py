"""Physical effects that extend the SMD model: one class, one file each, and the registry that names them.

An effect adds slots to the augmented state and terms to the COM
acceleration (the base class is :class:`smd_statespace.model.Effect`);
the same class serves estimation, simulation and diagnosis. Combine them
with ``SMDModel(effects=[...])`` or ``model.with_effects(...)``; every
estimator works with any combination unchanged.

======================== ================================================== ===========================
name                     what it adds                                       module
======================== ================================================== ===========================
``harmonics``            Fourier harmonics ``n+1 ... n+count`` (Eq. 4)      :mod:`.harmonics`
``cubic_stiffness``      a hardening (``beta_3 > 0``) or softening spring   :mod:`.cubic_stiffness`
``floor_mode``           a vibrating floor under the person (Section 6):    :mod:`.floor_mode`
                         measured floor motion, or one floor mode
``term``                 one generic restoring, damping or time term        :mod:`.generic`
                         (``kind=abs_u``, ``u3``, ``v_abs_v``, ``f_drift``...)
======================== ================================================== ===========================

:mod:`.registry` names them (:data:`EFFECTS`), parses the command-line form
``NAME:key=value,key=value`` (:func:`make_effect`), and lets a user's
effect join with one call (:func:`register_effect`) or from a file
(:func:`load_effects_file`, ``smd-statespace --effects FILE.py``).
"""

from .cubic_stiffness import CubicStiffness
from .floor_mode import FloorMode
from .generic import TERMS, GenericTerm
from .harmonics import Harmonics
from .registry import (EFFECTS, build_effect, load_effects_file, load_installed_effects, make_effect, parse_spec,
                       register_effect)

__all__ = ["Harmonics", "CubicStiffness", "FloorMode", "GenericTerm", "TERMS", "EFFECTS", "register_effect", "load_effects_file",
           "load_installed_effects", "parse_spec", "make_effect", "build_effect"]

"""Interchangeable estimators of the augmented-state SMD model.

============ ==================================== ==========================================
name         class                                what it is
============ ==================================== ==========================================
``"pf"``     :class:`ParticleFilter`              the article's particle filter (SIR)
``"ukf"``    :class:`UnscentedFilter`             filterpy's ``UnscentedKalmanFilter``
``"ekf"``    :class:`ExtendedFilter`              filterpy's ``ExtendedKalmanFilter``
``"rbpf"``   :class:`RaoBlackwellisedFilter`      particles over (f_h, xi_h), Kalman filters for the rest
``"grid"``   :class:`GridReference`               exact Kalman filters on an (f_h, xi_h) grid
============ ==================================== ==========================================

All consume an :class:`~smd_statespace.model.SMDModel` and a :class:`CycleData`
and return a :class:`FilterResult`; :func:`get_estimator` builds one by name.
"""

from .base import (ESTIMATORS, CycleData, Estimator, EstimatorFailure, FilterResult, GaussianStart, cycle_data,
                   get_estimator, register_estimator)
from .particle import ParticleFilter
from .ukf import UnscentedFilter
from .ekf import ExtendedFilter
from .rbpf import RaoBlackwellisedFilter
from .grid import GridReference

__all__ = [
    "ESTIMATORS", "CycleData", "Estimator", "EstimatorFailure", "FilterResult", "GaussianStart", "cycle_data",
    "get_estimator", "register_estimator", "ParticleFilter", "UnscentedFilter", "ExtendedFilter", "RaoBlackwellisedFilter",
    "GridReference",
]

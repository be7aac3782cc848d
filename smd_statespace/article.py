"""The article's published numbers, as plain read-only constants.

Source: H. Wang, J. Chen, T. Nagayama, "Parameter identification of
spring-mass-damper model for bouncing people", J. Sound Vib. 456 (2019) 13-29,
doi:10.1016/j.jsv.2019.05.034. Table and equation numbers match the article.

Units: frequencies in Hz, damping ratios as fractions (Table 3 prints them in
per cent; they are divided by 100 here), stiffness in N/m, damping coefficients
in N*s/m, masses in kg, biomechanical load factors (BLF, Eq. 5) in units of g
(the biomechanical force is normalised to body weight, Eq. 4).

The mappings are read-only (:class:`types.MappingProxyType`) and hold tuples,
so the numbers cannot be changed by accident.

================= =====================================================
name              content
================= =====================================================
``BANDS``         the six bouncing-frequency bands of Section 5 (Hz)
``TABLE1``        converged estimates for one typical cycle (Table 1)
``TABLE2``        skew-normal fits (m, s, a) per parameter and band (Eq. 19)
``TABLE3``        modes of the laboratory plate (Section 6)
``TABLE4``        one person on a rigid floor vs the vibrating plate
``CHECK_VALUES``  the worked example of Eq. 17-18
================= =====================================================
"""

from __future__ import annotations

from types import MappingProxyType
from typing import NamedTuple

import numpy as np
import pandas as pd

__all__ = [
    "BANDS",
    "TABLE1",
    "TABLE1_CONDITIONS",
    "SkewNormalFit",
    "TABLE2",
    "TABLE2_PARAMETERS",
    "PlateMode",
    "TABLE3",
    "PLATE",
    "TABLE4",
    "TABLE4_CONDITIONS",
    "CHECK_VALUES",
    "band_of",
    "table2_frame",
]

BANDS: tuple[tuple[float, float], ...] = (
    (1.35, 1.75),
    (1.75, 2.15),
    (2.15, 2.55),
    (2.55, 2.95),
    (2.95, 3.35),
    (3.35, 3.75),
)
"""Bouncing-frequency bands (Hz) of the statistical analysis, Section 5.

Each is ``(low, high)``; the bands are contiguous. :func:`band_of` assigns a
frequency to a band with the convention ``low <= f_b < high`` (the last band
also includes its upper edge, 3.75 Hz).
"""

TABLE1_CONDITIONS = MappingProxyType({"mass": 57.4, "f_b": 2.0})
"""Conditions of Table 1: body mass ``M_h`` (kg) and bouncing frequency (Hz)."""

TABLE1 = MappingProxyType(
    {
        "force_plate": MappingProxyType({"f_h": 1.776, "xi_h": 0.586, "BLF1": 0.125, "BLF2": 0.215, "BLF3": 0.064}),
        "insoles": MappingProxyType({"f_h": 1.784, "xi_h": 0.568, "BLF1": 0.121, "BLF2": 0.212, "BLF3": 0.060}),
    }
)
"""Table 1: converged estimates for one typical cycle, by measuring system.

``TABLE1[source][parameter]`` with ``source`` in ``{"force_plate", "insoles"}``
and ``parameter`` in ``{"f_h" (Hz), "xi_h" (-), "BLF1", "BLF2", "BLF3" (g)}``.
One person (57.4 kg) bouncing at 2 Hz, see :data:`TABLE1_CONDITIONS`.
"""


class SkewNormalFit(NamedTuple):
    """Skew-normal fit of Eq. 19: location ``m``, scale ``s``, shape ``a``.

    The density is ``f(x) = (2/s) phi((x-m)/s) Phi(a (x-m)/s)``, i.e.
    ``scipy.stats.skewnorm(a, loc=m, scale=s)`` (see :meth:`dist`).
    """

    m: float
    s: float
    a: float

    def dist(self):
        """The frozen ``scipy.stats.skewnorm`` distribution of this fit."""
        from scipy.stats import skewnorm

        return skewnorm(self.a, loc=self.m, scale=self.s)


TABLE2_PARAMETERS: tuple[str, ...] = ("f_h", "xi_h", "K_h", "C_h", "BLF1", "BLF2", "BLF3")
"""Parameters of Table 2 and their units: f_h (Hz), xi_h (-), K_h (N/m), C_h (N*s/m), BLF1-3 (g)."""


def _fits(*rows):
    return tuple(SkewNormalFit(*row) for row in rows)


TABLE2 = MappingProxyType(
    {
        "f_h": _fits(
            (1.7344, 0.3671, 3.5150),
            (2.0981, 0.3283, 3.8383),
            (2.4314, 0.4314, 4.1657),
            (2.8634, 0.7717, 8.4628),
            (3.2391, 1.2011, 14.5146),
            (3.5414, 1.3501, 16.2412),
        ),
        "xi_h": _fits(
            (0.1229, 0.1609, 3.9977),
            (0.0963, 0.1250, 5.0906),
            (0.0781, 0.1477, 4.9991),
            (0.0811, 0.1378, 7.1938),
            (0.0875, 0.1524, 8.2652),
            (0.0905, 0.1626, 5.9160),
        ),
        "K_h": _fits(
            (6717.5, 2714.6, 1.3713),
            (10011.5, 3386.8, 1.5475),
            (13458.9, 5014.8, 2.430),
            (18118.9, 8959.3, 3.5828),
            (17581.1, 9620.7, 0.8246),
            (19718.3, 10266.7, 0.6680),
        ),
        "C_h": _fits(
            (116.2537, 192.8070, 3.9194),
            (122.7600, 175.0183, 5.1436),
            (111.9995, 207.2037, 4.5361),
            (135.3333, 207.7530, 4.3247),
            (155.5664, 234.4910, 4.1732),
            (184.5520, 251.6296, 3.5600),
        ),
        "BLF1": _fits(
            (0.1968, 0.1005, 2.6126),
            (0.1808, 0.0937, 2.3134),
            (0.1626, 0.1502, 3.6431),
            (0.1500, 0.1984, 4.6241),
            (0.1404, 0.2385, 2.9479),
            (0.1585, 0.2444, 3.0493),
        ),
        "BLF2": _fits(
            (0.1549, 0.1317, 0.7517),
            (0.1046, 0.1306, 2.8725),
            (0.1189, 0.1021, 1.6303),
            (0.1060, 0.0921, 2.2067),
            (0.1092, 0.0767, 1.0348),
            (0.1184, 0.0750, 1.0399),
        ),
        "BLF3": _fits(
            (0.0116, 0.0609, 8.0118),
            (0.0140, 0.0503, 2.8241),
            (0.0125, 0.0530, 8.9577),
            (0.0119, 0.0504, 4.7477),
            (0.0045, 0.0370, 7.5927),
            (0.0052, 0.0265, 6.4426),
        ),
    }
)
"""Table 2: skew-normal fits (Eq. 19) of each parameter in each band.

``TABLE2[parameter][band]`` is a :class:`SkewNormalFit` ``(m, s, a)``;
``parameter`` is one of :data:`TABLE2_PARAMETERS`, ``band`` indexes
:data:`BANDS`. Units as in :data:`TABLE2_PARAMETERS`.

The fits were made per parameter (marginals only; no correlations are
published). They are not mutually consistent: for the two highest bands the
``f_h`` fits put more than half their mass above 4 Hz (means 4.2 and 4.6 Hz),
above the estimator's initial range of 1-4 Hz, while the ``K_h`` fits imply
``f_h`` near 3 Hz for a 60-70 kg person.
"""

class PlateMode(NamedTuple):
    """One mode of the laboratory plate (Table 3)."""

    mode: int
    frequency: float
    """Natural frequency (Hz)."""
    damping: float
    """Damping ratio (fraction, not per cent)."""
    modal_mass: float
    """Modal mass (kg), mass-normalised at mid-span."""


TABLE3 = (
    PlateMode(1, 3.48, 0.0037, 8583.0),
    PlateMode(2, 6.14, 0.0051, 2587.0),
    PlateMode(3, 6.74, 0.0061, 9625.0),
    PlateMode(4, 14.12, 0.0091, 2423.0),
    PlateMode(5, 15.19, 0.0067, 2898.0),
    PlateMode(6, 18.09, 0.0149, 4900.0),
)
"""Table 3: the first six modes of the pre-stressed concrete plate (Section 6).

Frequencies in Hz, damping ratios as fractions (the article prints per cent),
modal masses in kg.
"""

PLATE = MappingProxyType({"length": 10.0, "width": 6.0, "mass": 16500.0})
"""The laboratory plate of Section 6: length and width (m), total mass (kg)."""

TABLE4_CONDITIONS = MappingProxyType({"f_b": 1.75})
"""Conditions of Table 4: the person bounced at mid-span at 1.75 Hz (Hz)."""

TABLE4 = MappingProxyType(
    {
        "rigid_floor": MappingProxyType({"f_h": 1.81, "xi_h": 0.33, "BLF1": 0.241, "BLF2": 0.335, "BLF3": 0.082}),
        "vibrating_plate": MappingProxyType({"f_h": 1.49, "xi_h": 0.41, "BLF1": 0.348, "BLF2": 0.267, "BLF3": 0.046}),
        "difference": MappingProxyType({"f_h": -0.177, "xi_h": 0.242, "BLF1": 0.444, "BLF2": -0.203, "BLF3": -0.439}),
    }
)
"""Table 4: one person's estimates on a rigid floor and on the vibrating plate.

``TABLE4[condition][parameter]`` with ``condition`` in ``{"rigid_floor",
"vibrating_plate", "difference"}``; the difference is the relative change
(plate - rigid) / rigid as a fraction, as printed (-17.7 % -> -0.177).
"""

CHECK_VALUES = MappingProxyType(
    {"mass": 57.4, "f_h": 1.784, "xi_h": 0.568, "K_h": 7212.1, "C_h": 730.9}
)
"""Worked example of Eq. 17-18: ``M_h`` = 57.4 kg, ``f_h`` = 1.784 Hz,
``xi_h`` = 0.568 give ``K_h`` = 7212.1 N/m and ``C_h`` = 730.9 N*s/m
(printed to 0.1)."""


def band_of(f_b) -> int | None:
    """Index into :data:`BANDS` of the band holding bouncing frequency ``f_b``.

    Parameters
    ----------
    f_b : float
        Bouncing frequency (Hz).

    Returns
    -------
    int or None
        ``i`` such that ``BANDS[i][0] <= f_b < BANDS[i][1]`` (the last band
        includes 3.75 Hz), or None when ``f_b`` is outside every band or not
        a finite number.
    """
    try:
        value = float(f_b)
    except (TypeError, ValueError):
        return None
    if not np.isfinite(value):
        return None
    last = len(BANDS) - 1
    for index, (low, high) in enumerate(BANDS):
        if low <= value < high or (index == last and value == high):
            return index
    return None


def table2_frame() -> pd.DataFrame:
    """Table 2 as a DataFrame with a (parameter, band) MultiIndex.

    Returns
    -------
    pandas.DataFrame
        Columns ``m, s, a, low, high``; index levels ``parameter`` (as in
        :data:`TABLE2_PARAMETERS`) and ``band`` (0-5, see :data:`BANDS`);
        ``low`` and ``high`` are the band edges (Hz).
    """
    rows = []
    index = []
    for parameter in TABLE2_PARAMETERS:
        for band, fit in enumerate(TABLE2[parameter]):
            rows.append((fit.m, fit.s, fit.a, *BANDS[band]))
            index.append((parameter, band))
    return pd.DataFrame(
        rows,
        index=pd.MultiIndex.from_tuples(index, names=["parameter", "band"]),
        columns=["m", "s", "a", "low", "high"],
    )

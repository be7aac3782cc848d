"""The state's entries: :class:`Slot`, the base slots' positions and the base slots themselves (Eq. 7).

The augmented state opens with the base slots ``u, u_dot, f_h, xi_h, a0, a1,
b1, ..., an, bn`` (:func:`base_slots`); effects append their own
(:meth:`Effect.slots <smd_statespace.model.Effect.slots>`). ``U, U_DOT, F_H,
XI_H`` are the positions of the first four. Re-exported by
:mod:`smd_statespace.model.core` and :mod:`smd_statespace.model`.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import OptionError

# Positions of the base slots, which always open the state vector (Eq. 7).
U, U_DOT, F_H, XI_H = 0, 1, 2, 3


@dataclass(frozen=True)
class Slot:
    """One entry of the augmented state.

    Parameters
    ----------
    name : str
        Name used by :meth:`SMDModel.index <smd_statespace.model.core.SMDModel.index>` (e.g. ``"f_h"``).
    kind : {"dynamic", "parameter"}
        Dynamic slots (``u``, ``u_dot``, a floor displacement, ...) evolve by
        the model's rate; parameters are random walks.
    unit : str
        SI unit, for tables and plots.
    low, high : float, optional
        Uniform prior range of a parameter.
    nominal : float, optional
        Nominal magnitude; the default process noise of the slot is
        ``process_noise * nominal`` per step. For dynamic slots that are
        scaled by the data, leave ``None`` and set ``scale``.
    scale : str, optional
        For dynamic slots: the data channel (``"u"`` or ``"u_dot"``) whose RMS
        is the slot's nominal magnitude and prior spread.
    description : str
        One line for documentation and reports.
    linear : bool
        Whether the rate and observation are linear in this slot once the
        non-linear slots are fixed (``f_h`` and ``xi_h`` are not linear; ``u``,
        ``u_dot`` and the Fourier coefficients are). Rao-Blackwellised
        estimators sample the non-linear slots and Kalman-filter the rest.
    search : (float, float), optional
        A parameter's search range in the record-level maximum likelihood
        (:class:`~smd_statespace.person.model.RecordModel`), where it differs
        from the prior range ``low``-``high`` of the per-cycle estimators. A
        prior is information (a particle filter spreads its particles over it);
        a search range only boxes the optimiser, so it may be wider.
    limit : bool
        True when the lower end of the search range is a physical limit (a
        damping ratio of 0): an estimate there says "no more than the record
        can tell apart from it", not that the fit ran away, and is not
        counted as sitting on a search bound.
    """

    name: str
    kind: str
    unit: str
    low: float | None = None
    high: float | None = None
    nominal: float | None = None
    scale: str | None = None
    description: str = ""
    linear: bool = True
    search: tuple | None = None
    limit: bool = False

    def __post_init__(self):
        if self.kind not in ("dynamic", "parameter"):
            raise OptionError(f"slot {self.name!r}: kind must be 'dynamic' or 'parameter', got {self.kind!r}")
        if self.kind == "parameter" and (self.low is None or self.high is None or not self.low < self.high):
            raise OptionError(f"slot {self.name!r}: a parameter needs a prior range low < high")
        if self.search is not None and not self.search[0] <= self.low < self.high <= self.search[1]:
            raise OptionError(f"slot {self.name!r}: the search range {tuple(self.search)} must hold the prior "
                              f"range ({self.low}, {self.high})")
        if self.nominal is None and self.scale is None:
            raise OptionError(f"slot {self.name!r}: give a nominal magnitude or a data channel to scale by")


def base_slots(options) -> tuple[Slot, ...]:
    """The base slots of a model (Eq. 7): motion, the SMD's parameters and the Fourier coefficients.

    Parameters
    ----------
    options : mapping
        The model's checked options (:attr:`SMDModel.options
        <smd_statespace.model.core.SMDModel>`): ``n_harmonics``,
        ``f_h_range``, ``xi_h_range``, ``coefficient_range`` and ``a0_range``
        (None: ``coefficient_range``) set the prior ranges and nominal
        magnitudes.

    Returns
    -------
    tuple of Slot
        ``u, u_dot, f_h, xi_h, a0, a1, b1, ..., an, bn``.
    """
    coef_lo, coef_hi = options["coefficient_range"]
    a0_lo, a0_hi = options["a0_range"] or options["coefficient_range"]
    coef_nominal = max(abs(coef_lo), abs(coef_hi)) / 2.0
    f_lo, f_hi = options["f_h_range"]
    x_lo, x_hi = options["xi_h_range"]
    slots = [
        Slot("u", "dynamic", "m", scale="u", description="COM displacement from static equilibrium"),
        Slot("u_dot", "dynamic", "m/s", scale="u_dot", description="COM velocity"),
        Slot("f_h", "parameter", "Hz", f_lo, f_hi, nominal=0.5 * (f_lo + f_hi),
             description="SMD natural frequency", linear=False),
        Slot("xi_h", "parameter", "-", x_lo, x_hi, nominal=0.5 * (x_lo + x_hi),
             description="SMD damping ratio", linear=False),
        Slot("a0", "parameter", "g", a0_lo, a0_hi, nominal=max(abs(a0_lo), abs(a0_hi)) / 2.0,
             description="mean biomechanical force"),
    ]
    for i in range(1, options["n_harmonics"] + 1):
        slots.append(Slot(f"a{i}", "parameter", "g", coef_lo, coef_hi, nominal=coef_nominal,
                          description=f"cosine coefficient of harmonic {i}"))
        slots.append(Slot(f"b{i}", "parameter", "g", coef_lo, coef_hi, nominal=coef_nominal,
                          description=f"sine coefficient of harmonic {i}"))
    return tuple(slots)

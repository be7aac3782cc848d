"""The ``term`` effect: one generic restoring, damping or time term, each a one-parameter effect with a physical name.

A research user's missing effect is rarely on a short list of named effects. As SINDy and SysIdentPy users
expect, :data:`TERMS` is a library of simple terms in the leg's compression ``r = u - z`` (``z`` the floor's
displacement when a ``floor_mode`` effect is present, else 0; ``u`` the COM displacement, m, up positive), its rate
``r'`` and the time ``t``; each adds one dimensionless coefficient ``c`` to the COM acceleration (Eq. 2):

======== ============================================ =====================================================
kind     acceleration term                            the physics it stands for
======== ============================================ =====================================================
abs_u    ``-w_h^2 c |r|``                             a spring stiffer on one side of its rest position
u2       ``-w_h^2 c r^2 / r_0``                       a spring that stiffens on one side the further it moves
u_abs_u  ``-w_h^2 c r |r| / r_0``                     a spring that hardens (softens) with amplitude
u3       ``-w_h^2 c r^3 / r_0^2``                     a spring that hardens (softens) with amplitude, cubic
v2       ``-2 xi_h w_h c r'^2 / v_0``                 damping that differs between moving up and down
v_abs_v  ``-2 xi_h w_h c r' |r'| / v_0``              damping that grows with speed (turbulent-like)
u_v      ``-2 xi_h w_h c r r' / r_0``                 damping that changes with the leg's compression
f_drift  ``-w_h^2 c r (t - t_0) / T``                 a leg stiffness (``f_h``) that drifts over the record
xi_drift ``-2 xi_h w_h c r' (t - t_0) / T``           a leg damping (``xi_h``) that drifts over the record
f_step   ``-w_h^2 c r (H(t - t_s) - 1/2)``            a leg stiffness (``f_h``) that steps to another value
xi_step  ``-2 xi_h w_h c r' (H(t - t_s) - 1/2)``      a leg damping (``xi_h``) that steps to another value
======== ============================================ =====================================================

with ``w_h = 2 pi f_h``. ``r_0`` and ``v_0`` (the option ``scale``: m, or m/s for the damping terms) are the
record's RMS compression and compression rate, so that ``c`` is the term's size at the record's own motion
relative to the spring's (or the damper's) linear force: ``c = 0.1`` is 10 % of it. For the time terms ``t_0``
is the middle of the record and ``T`` its length (``scale`` = ``T``, ``start``): ``c = 0.2`` changes ``w_h^2``
(or ``xi_h w_h``) by 20 % from the record's start to its end. A step is at ``t_s = start + at T`` (``at``, a
fraction of the record, default 1/2; ``H`` the unit step): ``c = 0.2`` is ``w_h^2`` 20 % higher after it than
before, ``f_h`` the middle of the two. A person who changes once (tires, changes stance) is a step; one who
changes gradually a drift. :func:`~smd_statespace.person.screen.generic_library`
builds every term scaled to a fitted person's record.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import OptionError
from ..model import equations
from ..model.core import F_H, U, U_DOT, XI_H, Slot
from ..model.effect import Effect

__all__ = ["TERMS", "SAME_AS", "GenericTerm", "label"]

TERMS = {
    "abs_u": ("restoring", "a spring stiffer on one side of its rest position (in compression or in extension)"),
    "u2": ("restoring", "a spring that stiffens on one side the further it is compressed (or extended)"),
    "u_abs_u": ("restoring", "a spring that hardens (or softens) with amplitude"),
    "u3": ("restoring", "a spring that hardens (or softens) with amplitude, as a cube"),
    "v2": ("damping", "damping that differs between moving up and moving down"),
    "v_abs_v": ("damping", "damping that grows with speed (turbulent-like)"),
    "u_v": ("damping", "damping that changes with the leg's compression"),
    "f_drift": ("time", "a leg stiffness (f_h) that drifts over the record"),
    "xi_drift": ("time", "a leg damping (xi_h) that drifts over the record"),
    "f_step": ("time", "a leg stiffness (f_h) that steps to another value during the record"),
    "xi_step": ("time", "a leg damping (xi_h) that steps to another value during the record"),
}
"""``kind: (family, physical name)`` of the generic terms; the family says what ``scale`` is (m, m/s or s)."""

SAME_AS = {"u3": "cubic_stiffness"}
"""Generic terms that are a registered effect in another unit: ``u3``'s ``-w_h^2 c r^3 / r_0^2`` is
``cubic_stiffness``'s ``-w_h^2 beta_3 r^3`` with ``beta_3 = c / r_0^2``. Where the effect is a candidate (or in the
model) the term is not screened: the same model twice splits the verdict between two names (a hidden cubic spring
came out as ``term:u3`` on 2 of 7 records, seed 92) and costs a test."""

COEFFICIENT_RANGE = (-2.0, 2.0)
"""Search range of the coefficient ``c``: the term at most twice the linear force at the record's own motion."""


class GenericTerm(Effect):
    """One generic term of :data:`TERMS`: one dimensionless coefficient ``c_<kind>``.

    Parameters
    ----------
    kind : str
        A key of :data:`TERMS` (required: ``term:kind=abs_u,scale=0.012``).
    scale : float
        ``r_0`` (m) for the restoring terms, ``v_0`` (m/s) for the damping terms, ``T`` (s) for the time terms:
        the record's RMS compression, compression rate, or length. Must be positive.
    start : float
        For the time terms, the record's first time (s, on its own time axis); ``t_0 = start + T / 2``.
    at : float
        For a step, where it is as a fraction of the record, between 0 and 1 (default 0.5).

    Examples
    --------
    >>> effect = GenericTerm("abs_u", scale=0.012).with_values(c_abs_u=-0.2)
    >>> effect.spec
    'term:kind=abs_u,scale=0.012,c_abs_u=-0.2'
    >>> effect.physics
    'a spring stiffer on one side of its rest position (in compression or in extension)'
    """

    name = "term"

    scan = None
    """For a step whose time a scan found (:func:`~smd_statespace.person.breaks.located_step`): ``{"trim",
    "lm_robust", "p", "time_s"}``, the scan's largest robust score statistic and its p-value as the largest of
    many; the step's tests then refer to that distribution. None for a step placed by hand (its time is known)."""

    def __init__(self, kind: str, scale: float, start: float = 0.0, at: float = 0.5):
        if kind not in TERMS:
            raise OptionError(f"term: kind={kind!r}; give one of {', '.join(TERMS)}")
        if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not (math.isfinite(scale) and scale > 0):
            raise OptionError(f"term: scale={scale!r}; give the record's RMS motion (m, m/s) or length (s), > 0")
        if isinstance(start, bool) or not isinstance(start, (int, float)) or not math.isfinite(start):
            raise OptionError(f"term: start={start!r}; give the record's first time in s")
        if isinstance(at, bool) or not isinstance(at, (int, float)) or not 0.0 < at < 1.0:
            raise OptionError(f"term: at={at!r}; give where a step is as a fraction of the record, between 0 and 1")
        self.kind, self.scale, self.start, self.at = kind, float(scale), float(start), float(at)
        self.family, self.physics = TERMS[kind]
        if kind.endswith("step"):  # where it is, in the record's time
            self.physics += f" (at {self.start + self.at * self.scale:.2f} s)"

    @property
    def coefficient(self) -> str:
        """The name of the term's parameter slot, ``c_<kind>``."""
        return f"c_{self.kind}"

    @property
    def key(self) -> str:
        """``term:<kind>``: terms of different kinds go in one model together (each its own ``c_<kind>``)."""
        return f"{self.name}:{self.kind}"

    @property
    def changes(self) -> str | None:
        """The person's parameter a time term lets change during the record (``"f_h"`` or ``"xi_h"``); None for
        the terms in the compression and its rate."""
        if self.family != "time":
            return None
        return "f_h" if self.kind.startswith("f_") else "xi_h"

    @property
    def breaks(self) -> tuple[float, ...]:
        """Where a step is (s, ``start + at T``); none for the other kinds."""
        return (self.start + self.at * self.scale,) if self.kind.endswith("step") else ()

    def moment(self, t):
        """``m(t)`` of a time term (s): ``(t - t_0) / T`` for a drift, ``H(t - t_s) - 1/2`` for a step; from -1/2 at
        the record's start (before the step) to +1/2 at its end (after it). The changed parameter's ``w_h^2`` (or
        ``xi_h w_h``) is its fitted value times ``1 + c m(t)``."""
        if self.family != "time":
            raise AttributeError(f"term:{self.kind} does not change in time")
        since = np.asarray(t, dtype=float) - self.start
        if self.kind.endswith("step"):
            return (since >= self.at * self.scale) - 0.5
        return (since - self.scale / 2.0) / self.scale

    def slots(self, model):
        low, high = COEFFICIENT_RANGE
        return (Slot(self.coefficient, "parameter", "-", low, high, nominal=0.1,
                     description=f"relative size of {self.physics}", linear=self.family == "time"),)

    def acceleration(self, model, x, t, inputs):
        c = model.value(x, self.coefficient)
        displacement, velocity = model.floor_motion(x, t, inputs)
        r, rate = x[..., U] - displacement, x[..., U_DOT] - velocity
        # the terms are sized by the person's own spring and damper per unit mass, w_h^2 and 2 xi_h w_h (Eq. 2's)
        spring = -equations.smd_acceleration(1.0, 0.0, x[..., F_H], x[..., XI_H], 0.0)
        damper = -equations.smd_acceleration(0.0, 1.0, x[..., F_H], x[..., XI_H], 0.0)
        kind, s = self.kind, self.scale
        if self.family == "time":
            return -c * self.moment(t) * (spring * r if kind.startswith("f_") else damper * rate)
        terms = {"abs_u": lambda: spring * np.abs(r), "u2": lambda: spring * r**2 / s,
                 "u_abs_u": lambda: spring * r * np.abs(r) / s, "u3": lambda: spring * r**3 / s**2,
                 "v2": lambda: damper * rate**2 / s, "v_abs_v": lambda: damper * rate * np.abs(rate) / s,
                 "u_v": lambda: damper * r * rate / s}
        return -c * terms[kind]()

    @classmethod
    def propose(cls, fitted):
        """None: a generic term is not one of the diagnoses' default candidates (the record-level diagnosis
        screens nine, one per kind, built by :func:`~smd_statespace.person.screen.generic_library`)."""
        return None

    def __repr__(self):
        return f"GenericTerm(kind={self.kind!r}, scale={self.scale:g}, start={self.start:g}, at={self.at:g})"


def label(effect) -> str:
    """How tables and figures name an effect: its registry name, with the kind for a generic term
    (``term:abs_u``) and where a step is (``term:f_step@0.33``)."""
    if not isinstance(effect, GenericTerm):
        return effect.name
    return f"{effect.name}:{effect.kind}" + (f"@{effect.at:.2g}" if effect.kind.endswith("step") else "")

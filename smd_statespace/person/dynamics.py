"""The person's dynamics for the record-level model, taken from the one SMD model and its effects.

The record-level model (:mod:`smd_statespace.person.model`) does not write
Eq. 2 again: it asks :class:`~smd_statespace.model.SMDModel` — the same
object every per-cycle estimator and the simulator use — for the rates of its
dynamic slots and their Jacobians, with the force coefficients at zero (the
force enters through its own input column), and discretises them exactly
over one sample.

For the dynamic states ``x = [u, u_dot, (effects' own dynamic slots)]`` and a
force per unit mass ``F`` (m/s^2):

    x' = A x + b F + c(t),     y = GRF / M_h - g = h_x x + F + d(t)

- Eq. 2 alone: ``A = [[0, 1], [-w_h^2, -2 xi_h w_h]]``, ``b = [0, 1]``,
  ``h_x = A[1]``, ``c = d = 0``;
- an effect linear in the state with a measured input (a floor with
  ``floor_acc``): ``c(t)``, ``d(t)`` carry the input's terms, exactly;
- an effect with linear dynamics of its own (a floor mode without an
  accelerometer, Section 6): more rows of ``x`` and of ``A``, exactly;
- a nonlinear effect (a cubic spring, quadratic damping, a user's): ``A``,
  ``c``, ``h_x``, ``d`` are its first-order expansion about a *nominal path*
  (the one-step predicted states of the previous fit), different at every
  sample; the fit is repeated about the new predicted path until it settles
  (at the fixed point, an extended Kalman filter), so the likelihood is
  approximate and says so.

The effects' parameters (``beta_3``, ``f_f``, ...) are parameters of the
likelihood search, with the bounds of their slots.
"""

from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..io import G
from ..model import F_H, U_DOT, XI_H, CycleInputs, SMDModel
from ..model.jacobians import JACOBIAN_STEP, expand_time

__all__ = ["PersonDynamics", "LinearisedSystem"]

LINEARITY_TOLERANCE = 1e-9
"""Relative change of the state Jacobian between two states below which the dynamics count as linear."""


class LinearisedSystem:
    """Continuous-time ``A, b, c, h_x, d`` of :class:`PersonDynamics` at one parameter vector.

    Attributes
    ----------
    A : ndarray, shape (K, n_x, n_x)
        State matrix (``K = 1``: the same at every sample).
    b : ndarray, shape (K, n_x)
        Input column of the force per unit mass.
    c : ndarray, shape (N, n_x) or None
        Known part of the rates (inputs, linearisation remainder); None when zero.
    hx : ndarray, shape (K, n_x)
        Observation row of ``x``.
    d : ndarray, shape (N,) or None
        Known part of the observation; None when zero.
    """

    def __init__(self, A, b, c, hx, d):
        self.A, self.b, self.c, self.hx, self.d = A, b, c, hx, d


class PersonDynamics:
    """The dynamic part of an :class:`~smd_statespace.model.SMDModel` along one record.

    Parameters
    ----------
    model : SMDModel
        The person's model with its effects (built with the record-level
        model's ``n_harmonics``; effects that add force harmonics are taken
        by the record-level model's force, not here).
    time : ndarray, shape (N,)
        Sample times (s).
    signals : dict of str to ndarray, optional
        Measured inputs the effects need (``floor_disp``, ``floor_vel``), at ``time``.

    Attributes
    ----------
    names : list of str
        The dynamic states (``u``, ``u_dot``, then the effects' own).
    parameters : list of Slot
        The effects' parameter slots estimated by the likelihood search.
    linear : bool
        Whether the rates are linear in the dynamic states and their Jacobian
        does not change in time (then ``A`` is the same at every sample and the
        discretisation is exact). An effect that changes in time (a parameter
        that drifts with ``t``, the record's time in s from its first sample)
        is expanded at every sample like a nonlinear one.
    in_state : bool
        Whether the rates are linear in the dynamic states, at every time (``linear``, or an effect that
        changes in time): the expansion about any path is then the dynamics themselves, and the likelihood
        is exact even where it is computed along a path.
    """

    def __init__(self, model: SMDModel, time, signals=None):
        self.model = model
        self.time = np.asarray(time, dtype=float)
        signals = dict(signals or {})
        missing = [name for name in model.requires if name not in signals]
        if missing:
            raise OptionError(f"the model's effects need the measured signal(s) {', '.join(missing)}")
        self.inputs = CycleInputs(f_b=1.0, time=self.time, signals=signals)
        self.dynamic = [i for i, slot in enumerate(model.slots) if slot.kind == "dynamic"]
        self.names = [model.state_names[i] for i in self.dynamic]
        coefficients = set(model.coefficient_names)
        self.parameters = [slot for slot in model.slots
                           if slot.kind == "parameter" and slot.name not in coefficients
                           and model.index(slot.name) not in (F_H, XI_H)]
        self._a0 = model.index("a0")
        self.linear, self.in_state = self._linearity()

    @property
    def n_dynamic(self) -> int:
        """Number of dynamic states ``n_x``."""
        return len(self.dynamic)

    @property
    def parameter_names(self) -> list:
        """Names of the effects' estimated parameters."""
        return [slot.name for slot in self.parameters]

    def _states(self, f_h, xi_h, values, nominal, count):
        x = np.zeros((count, self.model.n_state))
        x[:, F_H], x[:, XI_H] = f_h, xi_h
        for name, value in values.items():
            x[:, self.model.index(name)] = value
        if nominal is not None:
            x[:, self.dynamic] = nominal
        return x

    def _linearity(self) -> tuple:
        """``(linear, in_state)``: compare the state Jacobian at rest and at a displaced state (effects' parameters
        at their nominals), then at five times.

        Checks on the way that the force enters the acceleration as in Eq. 2 (a gain of 1 on ``g F``) at
        both states: the record-level model takes the force of Eq. 4 as it is.
        """
        if not self.model.effects:
            return True, True
        values = {slot.name: slot.nominal for slot in self.parameters}
        scales = np.array([0.02 if i == 0 else 0.2 for i in range(self.n_dynamic)])
        rest = self._states(2.5, 0.3, values, np.zeros((1, self.n_dynamic)), 1)
        moved = self._states(2.5, 0.3, values, scales[None, :] * np.linspace(1.0, 1.7, self.n_dynamic), 1)
        t = self.time[:1]
        first, second = (self.model.rate_jacobian(x, t, self.inputs)[0] for x in (rest, moved))
        gains = np.array([first[U_DOT, self._a0], second[U_DOT, self._a0]]) / G
        if np.max(np.abs(gains - 1.0)) > 1e-6:
            raise OptionError(f"the effects {', '.join(e.name for e in self.model.effects)}: one changes how the "
                              "force enters the acceleration; the record-level model takes the force of Eq. 4 "
                              "as it is")
        first, second = (jac[np.ix_(self.dynamic, self.dynamic)] for jac in (first, second))
        scale = LINEARITY_TOLERANCE * max(np.max(np.abs(first)), 1.0)
        if np.max(np.abs(first - second)) > scale:
            return False, False
        # an effect whose terms change in time (a parameter that drifts, f_h (1 + k t)) is linear in the state
        # but its Jacobian is not the one of the first sample: it is linearised at every sample (the path's
        # expansion is then exact); until 2026-11-28 it was frozen at the first sample and k was lost
        # (checked with the parameters at their nominals and between their bounds: a drift's nominal may be 0)
        between = {slot.name: slot.low + 0.37 * (slot.high - slot.low) if np.isfinite(slot.high - slot.low)
                   else slot.nominal + 1.0 for slot in self.parameters}
        times = self.time[np.linspace(0, self.time.size - 1, 5).astype(int)]
        for state in (rest, self._states(2.5, 0.3, between, np.zeros((1, self.n_dynamic)), 1)):
            jacobians = [self.model.rate_jacobian(state, t[None], self.inputs)[0] for t in times]
            start = jacobians[0][np.ix_(self.dynamic, self.dynamic)]
            if any(np.max(np.abs(j[np.ix_(self.dynamic, self.dynamic)] - start)) > scale for j in jacobians[1:]):
                return False, True
        return True, True

    def _path_jacobian(self, at) -> np.ndarray:
        """Central differences of the dynamic slots' rates along a path, in the dynamic slots, shape (N, n_x, n_x).

        Only the block a linearisation needs (the model's full ``rate_jacobian``
        differences every slot, five times the work, and fills an (N, n, n) array of which this is a corner).
        """
        columns = self.dynamic
        step = JACOBIAN_STEP * np.maximum(1.0, np.abs(at[:, columns]))  # (N, c)
        shift = np.zeros((at.shape[0], len(columns), at.shape[1]))
        shift[:, np.arange(len(columns)), columns] = step
        moment = expand_time(self.time)
        plus = self.model.rate(at[:, None, :] + shift, moment, self.inputs)
        minus = self.model.rate(at[:, None, :] - shift, moment, self.inputs)
        return np.ascontiguousarray(np.swapaxes((plus - minus)[:, :, columns], 1, 2) / (2.0 * step[:, None, :]))

    def linearise(self, f_h, xi_h, values=None, nominal=None) -> LinearisedSystem:
        """``A, b, c, h_x, d`` at ``f_h`` (Hz), ``xi_h`` and the effects' parameter ``values``.

        ``nominal`` (shape (N, n_x)) is the path a nonlinear effect is
        expanded about; linear dynamics ignore it.
        """
        values = dict(values or {})
        model, dyn = self.model, self.dynamic
        # the observation is the COM acceleration, the rate of u_dot: its row of the rates gives h_x and d
        if self.linear:
            at = self._states(f_h, xi_h, values, None, 1)
            jac = model.rate_jacobian(at, self.time[:1], self.inputs)
            c = d = None
            if model.effects:  # terms an effect adds at rest: a measured input, a known function of time
                rest = self._states(f_h, xi_h, values, None, self.time.size)
                known = model.rate(rest, self.time, self.inputs)[:, dyn]
                if np.any(known != 0.0):
                    c, d = known, known[:, dyn.index(U_DOT)]
        else:
            if nominal is None:
                raise OptionError("a nonlinear effect needs a nominal path to be linearised about")
            at = self._states(f_h, xi_h, values, nominal, self.time.size)
            A = self._path_jacobian(at)
            c = model.rate(at, self.time, self.inputs)[:, dyn] - np.einsum("kij,kj->ki", A, nominal)
            d = c[:, dyn.index(U_DOT)]
            # the force enters linearly with a gain that does not depend on the state (checked in _linearity):
            # its column from the rest state, exact, where differences along a far path lose it to rounding
            # (the force's gain of 1 was checked once, _linearity; along a path the differences' rounding grows
            # with the rates, so it is not checked again here)
            rest = self._states(f_h, xi_h, values, None, 1)
            column = model.rate_jacobian(rest, self.time[:1], self.inputs)[0, dyn, self._a0] / G
            return LinearisedSystem(A, np.repeat(column[None, :], A.shape[0], axis=0), c,
                                    np.ascontiguousarray(A[:, dyn.index(U_DOT), :]), d)
        A = jac[:, dyn][:, :, dyn]
        b = jac[:, dyn, self._a0] / G
        hx = jac[:, U_DOT, dyn]
        return LinearisedSystem(A, b, c, hx, d)

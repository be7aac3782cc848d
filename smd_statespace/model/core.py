"""The augmented-state spring-mass-damper (SMD) model of a bouncing person (Eq. 1-18).

A bouncing person is one mass ``M_h`` (kg) at the centre of mass (COM), a leg
spring ``K_h`` and damper ``C_h``, excited by an internal biomechanical force
``F_bio`` (Eq. 1). Divided by the mass (Eq. 2)::

    u'' + 2 xi_h omega_h u' + omega_h**2 u = F_bio / M_h,     omega_h = 2 pi f_h

and the force is a Fourier series at the bouncing frequency ``f_b`` (Eq. 4),
read in units of g::

    F_bio / M_h = g [a0 + sum_i a_i cos(2 pi i f_b t) + b_i sin(2 pi i f_b t)]

Symbols used in code and docs (SI units throughout):

============ ============= ====================================================
symbol       attribute     meaning (unit)
============ ============= ====================================================
``u``        ``"u"``       COM displacement from static equilibrium (m)
``u'``       ``"u_dot"``   COM velocity (m/s)
``u''``      ``"u_ddot"``  COM acceleration (m/s^2), observed through Eq. 3
``f_h``      ``"f_h"``     natural frequency of the SMD (Hz)
``xi_h``     ``"xi_h"``    damping ratio of the SMD (-)
``a0``       ``"a0"``      mean biomechanical force (g)
``a_i, b_i`` ``"a1"...``   cosine / sine Fourier coefficients (g)
``f_b``      ``f_b``       bouncing frequency of the cycle (Hz), an input
``BLF_i``    ``blf``       biomechanical load factor sqrt(a_i^2 + b_i^2) (g), Eq. 5
``K_h``      ``k_h``       leg stiffness M_h (2 pi f_h)^2 (N/m), Eq. 17
``C_h``      ``c_h``       leg damping 2 xi_h M_h 2 pi f_h (N s/m), Eq. 18
============ ============= ====================================================

The augmented state (Eq. 7) stacks motion and parameters::

    X = [u, u', f_h, xi_h, a0, a1, b1, ..., an, bn]

Its rate (Eq. 8-10) has one non-trivial row, the acceleration; parameters are
random walks (zero rate plus process noise, Eq. 6). :meth:`SMDModel.transition`
discretises it with forward Euler (Eq. 11-12, ``discretisation="euler"``, as in
the article) or with classical Runge-Kutta (``"rk4"``, the default: Euler
amplifies an undamped 4 Hz oscillation by 3 % per 100 Hz step). The
observation (Eq. 13-16) is ``[u, u', u'']`` or, with ``observation="acc"``,
the acceleration alone.

Extending the model
-------------------
A physical :class:`Effect` (a vibrating floor, extra harmonics, a cubic
spring, ...) adds slots to the state and terms to the acceleration row, with
their Jacobians. ``model.with_effects(effect, ...)`` returns a new model with a
longer state; estimators only ever call the methods below, so they work with
any combination of effects unchanged.

Every function is vectorised over leading axes: ``x`` may be one state of
shape ``(n_state,)`` or a particle cloud of shape ``(n_particles, n_state)``.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from ..errors import OptionError, check_range
from ..io import G
from .discretisation import step, step_jacobian
from .effect import Effect, FloorMotion, HarmonicOrders
from . import equations
from .equations import (acceleration_derivatives, acceleration_frf, blf, c_h, k_h,  # noqa: F401 (importable here too)
                        smd_acceleration)
from .inputs import TWO_PI, CycleInputs
from .prior import ONE_WORD_PER_DOUBLE, Prior  # noqa: F401 (importable from here too)
from .slots import F_H, U, U_DOT, XI_H, Slot, base_slots  # noqa: F401 (Slot importable from here too)

DISCRETISATIONS = ("euler", "rk4")
"""Names accepted by ``SMDModel(discretisation=...)``."""

OBSERVATIONS = {"full": ("u", "u_dot", "u_ddot"), "acc": ("u_ddot",)}
"""Observation options: channel names observed by each (Eq. 14-16)."""


# ---------------------------------------------------------------------------
# The model
# ---------------------------------------------------------------------------


class SMDModel:
    """Augmented-state SMD model (Eq. 7-16), shared by every estimator.

    Parameters
    ----------
    n_harmonics : int
        Number ``n`` of Fourier harmonics of the biomechanical force (Eq. 4);
        the article uses 4.
    effects : sequence of Effect
        Physical effects that extend the model (see :class:`Effect`).
    discretisation : {"rk4", "euler"}
        ``"euler"``: ``X_k = X_{k-1} + A(X_{k-1}, t) X_{k-1} dt`` (Eq. 11-12),
        as in the article. ``"rk4"``: classical fourth-order Runge-Kutta.
    substeps : int
        Integration steps per sample interval.
    observation : {"full", "acc"}
        ``"full"`` observes ``[u, u', u'']`` (Eq. 14-16); ``"acc"`` only ``u''``.
    f_h_range : (float, float)
        Uniform prior of ``f_h`` (Hz); the article's 1-4 Hz.
    xi_h_range : (float, float)
        Uniform prior of ``xi_h``; the article's 0-1.
    coefficient_range : (float, float)
        Uniform prior of every ``a_i``, ``b_i`` (g). The article prints 0-0.4;
        since cosine and sine coefficients take either sign, the default is
        the symmetric -0.4-0.4.
    a0_range : (float, float), optional
        Prior of ``a0`` (g); defaults to ``coefficient_range``.
    process_noise : float
        Process-noise standard deviation per step as a fraction of each
        slot's nominal magnitude (the article: about 1 %).
    observation_noise : float
        Observation-noise standard deviation as a fraction of each observed
        channel's RMS (the article: 10 %).
    """

    def __init__(
        self,
        n_harmonics: int = 4,
        effects: Sequence[Effect] = (),
        discretisation: str = "rk4",
        substeps: int = 1,
        observation: str = "full",
        f_h_range=(1.0, 4.0),
        xi_h_range=(0.0, 1.0),
        coefficient_range=(-0.4, 0.4),
        a0_range=None,
        process_noise: float = 0.01,
        observation_noise: float = 0.10,
    ):
        self._check_options(n_harmonics, discretisation, observation, substeps, process_noise, observation_noise)
        self.options = dict(
            n_harmonics=int(n_harmonics),
            discretisation=discretisation,
            substeps=int(substeps),
            observation=observation,
            f_h_range=tuple(map(float, check_range(f_h_range, "f_h_range", minimum=0.0))),
            xi_h_range=tuple(map(float, check_range(xi_h_range, "xi_h_range", minimum=0.0))),
            coefficient_range=tuple(map(float, check_range(coefficient_range, "coefficient_range"))),
            a0_range=None if a0_range is None else tuple(map(float, check_range(a0_range, "a0_range"))),
            process_noise=float(process_noise),
            observation_noise=float(observation_noise),
        )
        self.n_harmonics = int(n_harmonics)
        self.discretisation = discretisation
        self.substeps = int(substeps)
        self.observation = observation
        self.process_noise = float(process_noise)
        self.observation_noise = float(observation_noise)
        self.effects = self._checked_effects(effects)
        self._floor = next((effect for effect in self.effects if isinstance(effect, FloorMotion)), None)
        base = base_slots(self.options)
        effect_slots, self.constants = self._effect_slots()
        self._set_layout(base, effect_slots)
        self.channels = OBSERVATIONS[observation]
        self.n_obs = len(self.channels)
        self.requires = tuple(sorted({name for effect in self.effects for name in effect.requires}))
        if self.effects:
            self._probe_effects()

    def _probe_effects(self):
        """Run the effects' terms once, on two states at the slots' nominal magnitudes: an effect whose arrays have
        the wrong shape is refused here, naming the effect, the method and both shapes, before any command runs."""
        magnitudes = np.array([0.01 if slot.nominal is None else slot.nominal for slot in self.slots])
        x = np.stack([magnitudes, 0.5 * magnitudes])
        inputs = CycleInputs(f_b=2.0, time=np.array([0.0, 1.0]),
                             signals={name: np.zeros(2) for name in self.requires})
        self.rate(x, 0.0, inputs)
        self.rate_jacobian(x, 0.0, inputs)

    @staticmethod
    def _check_options(n_harmonics, discretisation, observation, substeps, process_noise, observation_noise):
        """Raise an OptionError for a bad number of harmonics, scheme, observation, substeps or noise fraction."""
        if isinstance(n_harmonics, bool) or not isinstance(n_harmonics, (int, np.integer)) or n_harmonics < 1:
            raise OptionError(f"n_harmonics must be a whole number >= 1, got {n_harmonics!r}")
        if discretisation not in DISCRETISATIONS:
            raise OptionError(f"discretisation {discretisation!r} is unknown; "
                              f"choose one of {', '.join(DISCRETISATIONS)}")
        if observation not in OBSERVATIONS:
            raise OptionError(f"observation {observation!r} is unknown; choose one of {', '.join(OBSERVATIONS)}")
        if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
            raise OptionError(f"substeps must be a whole number >= 1, got {substeps!r}")
        for label, value in (("process_noise", process_noise), ("observation_noise", observation_noise)):
            if not np.isfinite(value) or value <= 0:
                raise OptionError(f"{label} must be a positive fraction, got {value!r}")

    @staticmethod
    def _checked_effects(effects) -> tuple[Effect, ...]:
        """``effects`` as a tuple, after checking that each is an :class:`Effect` given once (by name)."""
        effects = tuple(effects)
        for effect in effects:
            if not isinstance(effect, Effect):
                raise OptionError(f"effects must be Effect objects, got {effect!r}")
        names = [effect.key for effect in effects]
        for name in names:
            if names.count(name) > 1:
                raise OptionError(f"effect {name!r} is given twice; give each effect once")
        return effects

    def _effect_slots(self):
        """Each effect's own slots (those it was not given a value for) and the values it was given.

        Returns
        -------
        effect_slots : list of tuple of Slot
            One group per effect, in the order of :attr:`effects`.
        constants : dict
            ``{slot name: value}`` of the parameters the effects were given
            (:attr:`Effect.values <smd_statespace.model.Effect.values>`): known, not estimated.
        """
        effect_slots = []
        constants = {}
        for effect in self.effects:
            declared = tuple(effect.slots(self))
            known = effect.values
            parameters = {slot.name for slot in declared if slot.kind == "parameter"}
            unknown = [name for name in known if name not in parameters]
            if unknown:
                raise OptionError(
                    f"effect {effect.name!r} has no parameter slot {unknown[0]!r} to give a value; "
                    f"its parameters: {', '.join(sorted(parameters)) or 'none'}"
                )
            constants.update(known)
            effect_slots.append(tuple(slot for slot in declared if slot.name not in known))
        return effect_slots, constants

    def _set_layout(self, base, effect_slots):
        """The state vector's layout: :attr:`slots`, :attr:`state_names`, the index and the effects' slices.

        Raises an OptionError when two slots share a name.
        """
        self.slots = base + tuple(slot for group in effect_slots for slot in group)
        self.state_names = tuple(slot.name for slot in self.slots)
        seen = set()
        for name in self.state_names:
            if name in seen:
                owners = [e.name for e, group in zip(self.effects, effect_slots) if name in [s.name for s in group]]
                raise OptionError(
                    f"state slot {name!r} is declared twice (by {', '.join(owners) or 'the base model'}); "
                    "an effect combination must not duplicate a state"
                )
            seen.add(name)
        self._index = {name: i for i, name in enumerate(self.state_names)}
        self.n_state = len(self.slots)
        # Offsets of the effects' own slots in the state vector.
        self._effect_slices = []
        start = len(base)
        for group in effect_slots:
            self._effect_slices.append(slice(start, start + len(group)))
            start += len(group)

    # -- layout -------------------------------------------------------------

    def index(self, name: str) -> int:
        """Position of slot ``name`` in the state vector."""
        try:
            return self._index[name]
        except KeyError:
            raise OptionError(f"no state slot {name!r}; the model has {', '.join(self.state_names)}") from None

    def value(self, x, name: str):
        """Slot ``name`` of state(s) ``x``, or its known constant when an effect was given one.

        Returns an array of shape ``x.shape[:-1]`` (a float for a constant,
        which broadcasts the same way).
        """
        if name in self._index:
            return np.asarray(x)[..., self._index[name]]
        if name in self.constants:
            return self.constants[name]
        raise OptionError(f"no state slot or known value {name!r}; the model has {', '.join(self.state_names)}")

    def floor_motion(self, x, t, inputs: CycleInputs):
        """Floor displacement ``z`` (m) and velocity ``z'`` (m/s) under the person: the first effect's that has one, else 0.

        The leg acts on the COM motion relative to the floor (Section 6), so
        every effect with a leg term (a cubic spring, a user's nonlinear
        damper) reads ``u - z`` through this.
        """
        floor = self._floor
        return (0.0, 0.0) if floor is None else floor.floor_motion(self, x, t, inputs)

    def effect_slice(self, effect: Effect) -> slice:
        """Positions of ``effect``'s own slots in the state vector."""
        for candidate, where in zip(self.effects, self._effect_slices):
            if candidate is effect:
                return where
        raise OptionError(f"effect {effect.name!r} is not part of this model")

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the random-walk parameter slots."""
        return tuple(slot.name for slot in self.slots if slot.kind == "parameter")

    @property
    def nonlinear_names(self) -> tuple[str, ...]:
        """Slots in which the model is not linear (``f_h``, ``xi_h`` and effects' such parameters)."""
        return tuple(slot.name for slot in self.slots if not slot.linear)

    @property
    def coefficient_names(self) -> tuple[str, ...]:
        """Names of the base Fourier coefficients ``a0, a1, b1, ..., an, bn``."""
        return ("a0",) + tuple(f"{c}{i}" for i in range(1, self.n_harmonics + 1) for c in "ab")

    def with_effects(self, *effects: Effect) -> "SMDModel":
        """A new model with ``effects`` added to this one's (state grows; nothing else changes)."""
        return SMDModel(effects=self.effects + tuple(effects), **self.options)

    def __repr__(self):
        extra = f", effects=[{', '.join(e.name for e in self.effects)}]" if self.effects else ""
        return (
            f"SMDModel(n_harmonics={self.n_harmonics}, discretisation={self.discretisation!r}, "
            f"observation={self.observation!r}, n_state={self.n_state}{extra})"
        )

    # -- physics ------------------------------------------------------------

    def harmonic_orders(self) -> np.ndarray:
        """Force harmonic orders of the model (Eq. 4): ``1..n`` plus those of any ``orders``-bearing effect."""
        orders = set(range(1, int(self.n_harmonics) + 1))
        for effect in self.effects:
            if isinstance(effect, HarmonicOrders):
                orders.update(int(k) for k in np.atleast_1d(effect.orders(self)))
        return np.array(sorted(orders), dtype=int)

    def fourier_basis(self, t, inputs: CycleInputs, harmonics: Sequence[int] | None = None):
        """Regressors ``[1, cos(theta), sin(theta), ..., cos(n theta), sin(n theta)]`` of Eq. 4.

        ``theta = 2 pi f_b (t - t0)``. Returns shape ``np.shape(t) + (1 + 2n,)``
        for the base harmonics, or ``(2 len(harmonics),)`` columns (no constant)
        when ``harmonics`` is given.
        """
        theta = np.asarray(inputs.phase(t))[..., None]
        lead = 1 if harmonics is None else 0
        orders = np.arange(1, self.n_harmonics + 1) if harmonics is None else np.asarray(harmonics)
        angles = orders * theta
        basis = np.empty(theta.shape[:-1] + (lead + 2 * orders.size,))
        if lead:
            basis[..., 0] = 1.0
        basis[..., lead::2], basis[..., lead + 1::2] = np.cos(angles), np.sin(angles)
        return basis

    def force(self, x, t, inputs: CycleInputs, basis=None):
        """Biomechanical force per unit mass ``F_bio / M_h`` (m/s^2), Eq. 4; ``basis``: :meth:`fourier_basis` at
        ``t`` where it is at hand."""
        x = np.asarray(x, dtype=float)
        start = self._index["a0"]
        coefficients = x[..., start:start + 1 + 2 * self.n_harmonics]
        if not np.any(coefficients):  # no force (the record-level model linearises at such states): no basis to build
            return np.zeros(np.broadcast_shapes(coefficients.shape[:-1], np.shape(t)))
        basis = self.fourier_basis(t, inputs) if basis is None else basis
        return G * np.sum(coefficients * basis, axis=-1)

    def acceleration(self, x, t, inputs: CycleInputs, basis=None):
        """COM acceleration ``u''`` (m/s^2): the acceleration row of Eq. 10 plus effects.

        ``u'' = -omega_h^2 u - 2 xi_h omega_h u' + F_bio / M_h``; ``basis`` as :meth:`force`.
        """
        x = np.asarray(x, dtype=float)
        u, v = x[..., U], x[..., U_DOT]
        acc = equations.smd_acceleration(u, v, x[..., F_H], x[..., XI_H], self.force(x, t, inputs, basis))  # Eq. 2, 10
        for effect in self.effects:
            acc = acc + _checked_shape(effect.acceleration(self, x, t, inputs), acc.shape, effect, "acceleration")
        return acc

    def acceleration_jacobian(self, x, t, inputs: CycleInputs, basis=None):
        """Derivative of :meth:`acceleration` with respect to the state, shape ``x.shape``; ``basis`` as
        :meth:`force`."""
        x = np.asarray(x, dtype=float)
        eq2 = equations.acceleration_derivatives(x[..., U], x[..., U_DOT], x[..., F_H], x[..., XI_H])  # Eq. 2's own
        jac = np.zeros(x.shape)
        for column, name in ((U, "u"), (U_DOT, "u_dot"), (F_H, "f_h"), (XI_H, "xi_h")):
            jac[..., column] = eq2[name]
        start = self._index["a0"]
        basis = self.fourier_basis(t, inputs) if basis is None else basis
        jac[..., start:start + 1 + 2 * self.n_harmonics] = G * np.asarray(eq2["force_g"])[..., None] * basis
        for effect in self.effects:
            jac = jac + _checked_shape(effect.acceleration_jacobian(self, x, t, inputs), jac.shape, effect,
                                       "acceleration_jacobian")
        return jac

    def rate(self, x, t, inputs: CycleInputs):
        """Continuous-time rate ``dX/dt = A(X, t) X`` (Eq. 8-10), shape ``x.shape``.

        Rows: ``du/dt = u'``; ``du'/dt = u''`` (:meth:`acceleration`);
        parameter rows zero; effects' dynamic slots by their own rates.
        """
        x = np.asarray(x, dtype=float)
        return self._rate(x, t, inputs, self.acceleration(x, t, inputs))

    def _rate(self, x, t, inputs: CycleInputs, acc):
        """:meth:`rate` at ``x`` whose acceleration is ``acc``."""
        rate = np.zeros(x.shape)
        rate[..., U] = x[..., U_DOT]
        rate[..., U_DOT] = acc
        for effect, where in zip(self.effects, self._effect_slices):
            if where.stop > where.start:
                rate[..., where] = _checked_shape(effect.slot_rates(self, x, t, inputs, acc), rate[..., where].shape,
                                                  effect, "slot_rates")
        return rate

    def rate_jacobian(self, x, t, inputs: CycleInputs, basis=None, acc=None):
        """Derivative of :meth:`rate`, shape ``x.shape + (n_state,)``; ``basis`` as :meth:`force`, ``acc`` the
        acceleration at ``x`` where it is at hand."""
        x = np.asarray(x, dtype=float)
        basis = self.fourier_basis(t, inputs) if basis is None else basis
        acc = self.acceleration(x, t, inputs, basis) if acc is None else acc
        acc_jac = self.acceleration_jacobian(x, t, inputs, basis)
        jac = np.zeros(x.shape + (self.n_state,))
        jac[..., U, U_DOT] = 1.0
        jac[..., U_DOT, :] = acc_jac
        for effect, where in zip(self.effects, self._effect_slices):
            if where.stop > where.start:
                jac[..., where, :] = effect.slot_rates_jacobian(self, x, t, inputs, acc, acc_jac)
        return jac

    def rate_and_jacobian(self, x, t, inputs: CycleInputs):
        """:meth:`rate` and :meth:`rate_jacobian` together (a step's stage needs both), the Fourier basis and the
        acceleration computed once: ``(rate, jacobian)``."""
        x = np.asarray(x, dtype=float)
        basis = self.fourier_basis(t, inputs)
        acc = self.acceleration(x, t, inputs, basis)
        return self._rate(x, t, inputs, acc), self.rate_jacobian(x, t, inputs, basis, acc)

    def transition(self, x, t, dt, inputs: CycleInputs):
        """State at ``t + dt`` from state ``x`` at ``t`` without process noise (Eq. 11-12).

        Parameters
        ----------
        x : ndarray, shape (..., n_state)
        t : float
            Time (s) of ``x``.
        dt : float
            Step (s); 1 / sampling frequency in the article.
        inputs : CycleInputs
        """
        x = np.asarray(x, dtype=float)
        h = dt / self.substeps
        for i in range(self.substeps):
            x = step(self, x, t + i * h, h, inputs)
        return x

    def transition_jacobian(self, x, t, dt, inputs: CycleInputs):
        """Derivative of :meth:`transition` with respect to ``x``, shape ``x.shape + (n_state,)``.

        Exact for the chosen discretisation (chain rule through the stages),
        so it is the ``A_d`` of Eq. 12 for Euler.
        """
        return self.transition_and_jacobian(x, t, dt, inputs)[1]

    def transition_and_jacobian(self, x, t, dt, inputs: CycleInputs):
        """:meth:`transition` and :meth:`transition_jacobian` from one pass through the stages (an extended
        Kalman filter's prediction needs both): ``(x_next, jacobian)``."""
        x = np.asarray(x, dtype=float)
        eye = np.broadcast_to(np.eye(self.n_state), x.shape + (self.n_state,))
        jac = eye.copy()
        h = dt / self.substeps
        for i in range(self.substeps):
            x, step_jac = step_jacobian(self, x, t + i * h, h, inputs, eye)
            jac = step_jac @ jac
        return x, jac

    def observe(self, x, t, inputs: CycleInputs):
        """Noise-free observation ``Y = C_d X`` (Eq. 13-16), shape ``x.shape[:-1] + (n_obs,)``.

        Channels are :attr:`channels`: ``("u", "u_dot", "u_ddot")`` or ``("u_ddot",)``.
        """
        x = np.asarray(x, dtype=float)
        acc = self.acceleration(x, t, inputs)
        if self.observation == "acc":
            return acc[..., None]
        return np.stack([x[..., U], x[..., U_DOT], acc], axis=-1)

    def observation_jacobian(self, x, t, inputs: CycleInputs):
        """Derivative of :meth:`observe`, shape ``x.shape[:-1] + (n_obs, n_state)``."""
        x = np.asarray(x, dtype=float)
        acc_jac = self.acceleration_jacobian(x, t, inputs)
        if self.observation == "acc":
            return acc_jac[..., None, :]
        jac = np.zeros(x.shape[:-1] + (3, self.n_state))
        jac[..., 0, U] = 1.0
        jac[..., 1, U_DOT] = 1.0
        jac[..., 2, :] = acc_jac
        return jac

    # -- noise and prior ----------------------------------------------------

    def data_scale(self, y, inputs: CycleInputs) -> dict:
        """RMS magnitude of ``u``, ``u_dot`` and ``u_ddot`` in a cycle's observations.

        With ``observation="acc"`` the displacement and velocity scales are
        inferred from the acceleration RMS at the bouncing frequency.
        """
        y = np.atleast_2d(np.asarray(y, dtype=float))
        rms = np.sqrt(np.mean(y**2, axis=0))
        scale = dict(zip(self.channels, rms))
        if self.observation == "acc":
            omega_b = TWO_PI * inputs.f_b
            scale["u_dot"] = scale["u_ddot"] / omega_b
            scale["u"] = scale["u_ddot"] / omega_b**2
        floor = 1e-12
        return {name: max(float(value), floor) for name, value in scale.items()}

    def nominal(self, scale: Mapping[str, float]) -> np.ndarray:
        """Nominal magnitude of every slot (dynamic slots from ``scale``)."""
        return np.array([slot.nominal if slot.scale is None else scale[slot.scale] for slot in self.slots])

    def process_noise_std(self, scale: Mapping[str, float]) -> np.ndarray:
        """Per-step process-noise standard deviation of every slot (Eq. 6), shape ``(n_state,)``.

        ``process_noise`` (default 1 %) times each slot's nominal magnitude.
        """
        return self.process_noise * self.nominal(scale)

    def observation_noise_std(self, scale: Mapping[str, float]) -> np.ndarray:
        """Observation-noise standard deviation per channel (Eq. 13), shape ``(n_obs,)``.

        ``observation_noise`` (default 10 %) times each channel's RMS.
        """
        return self.observation_noise * np.array([scale[name] for name in self.channels])

    def prior(self, y0, scale: Mapping[str, float]) -> Prior:
        """Prior of the state at a cycle's first sample.

        Parameters are uniform on their ranges (the article's initial ranges).
        Dynamic slots observed in ``y0`` (the first observation) are normal
        around it with the observation-noise spread; unobserved ones are
        normal around zero with their data scale as spread.
        """
        y0 = np.atleast_1d(np.asarray(y0, dtype=float))
        observed = dict(zip(self.channels, y0))
        noise = dict(zip(self.channels, self.observation_noise_std(scale)))
        kinds, first, second = [], [], []
        for slot in self.slots:
            if slot.kind == "parameter":
                kinds.append("uniform")
                first.append(slot.low)
                second.append(slot.high)
            elif slot.name in observed:
                kinds.append("normal")
                first.append(observed[slot.name])
                second.append(noise[slot.name])
            else:
                kinds.append("normal")
                first.append(0.0)
                second.append(slot.nominal if slot.scale is None else scale[slot.scale])
        return Prior(self.state_names, tuple(kinds), np.array(first), np.array(second))

    # -- derived quantities -------------------------------------------------

    def derived(self, x, mass: float) -> dict:
        """``K_h`` (Eq. 17), ``C_h`` (Eq. 18) and ``BLF_i`` (Eq. 5) from state(s) ``x``.

        Returns a dict of arrays with keys ``k_h`` (N/m), ``c_h`` (N s/m) and
        ``blf_1 ... blf_n`` (g), each of shape ``x.shape[:-1]``.
        """
        x = np.asarray(x, dtype=float)
        f, xi = x[..., self.index("f_h")], x[..., self.index("xi_h")]
        out = {"k_h": k_h(f, mass), "c_h": c_h(xi, f, mass)}
        for i in range(1, self.n_harmonics + 1):
            out[f"blf_{i}"] = blf(x[..., self.index(f"a{i}")], x[..., self.index(f"b{i}")])
        return out


_SHAPE_RULES = {"acceleration": "x.shape[:-1], one value per state",
                "acceleration_jacobian": "x.shape, one row of derivatives per state",
                "slot_rates": "x.shape[:-1] + (the effect's slot count,)"}


def _checked_shape(term, expected, effect, method):
    """``term`` as an array that broadcasts to ``expected`` without changing it, or an :class:`OptionError` naming the
    effect, the method and both shapes (a wrong shape would broadcast into a wrong model, or fail far from its cause).
    """
    term = np.asarray(term, dtype=float)
    if term.shape == tuple(expected):
        return term
    try:
        fits = np.broadcast_shapes(term.shape, tuple(expected)) == tuple(expected)  # a known constant's scalar fits
    except ValueError:
        fits = False
    if not fits:
        raise OptionError(f"effect {effect.name!r}: {method} returned shape {term.shape}, expected {tuple(expected)} "
                          f"({_SHAPE_RULES[method]})")
    return term

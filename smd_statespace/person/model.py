"""The record-level model of one bouncing person: one (f_h, xi_h) for a whole record.

The per-cycle method of the article (Sections 3.2 and 4) re-estimates every
parameter in every cycle. Here the person is fixed over the record and only
the force varies:

- Eq. 2, ``u'' + 2 xi_h w_h u' + w_h^2 u = g F(t)``, with ``f_h``, ``xi_h``
  constant over the record and ``u, u'`` carried across cycle boundaries;
- Eq. 4, ``F = a0 + sum_i [a_i cos(i theta) + b_i sin(i theta)]`` (g), with
  the phase ``theta(t)`` of :class:`~smd_statespace.person.timing.CycleTiming`
  and coefficients ``alpha_j = [a0, a1, b1, ..., an, bn]`` that change from
  cycle to cycle around the person's record-level *template* ``tau``;
- Eq. 3, the observation ``y = GRF / M_h - g = u''`` plus white noise of
  variance ``sigma^2`` (the only observation: ``u`` and ``u'`` are latent, so
  no high-pass filter or integration touches the data).

Variation models of the coefficients (chosen by likelihood in
:func:`~smd_statespace.person.fit.identify_person`):

``"independent"``
    ``alpha_j = tau + d_j``, ``d_j ~ N(0, D)`` independent per cycle.
``"random_walk"``
    ``alpha_j = alpha_{j-1} + e_j``, ``e_j ~ N(0, E)``; ``tau`` is ``alpha_0``.
``"both"``
    ``alpha_j = m_j + d_j``, ``m_j = m_{j-1} + e_j``: a wandering template.
``"smooth"``
    ``alpha(t) = tau + d(t)`` with no jump at cycle boundaries: every
    coefficient's deviation ``d(t)`` is a stationary Matern-3/2 process of
    time (once differentiable, variance ``D``, length scale ``ell``, one
    ``ell`` for all coefficients, at least :data:`SMOOTH_MIN_CYCLES` mean cycles; ``d'' = -2 lambda d' - lambda^2 d + white
    noise``, ``lambda = sqrt(3) / ell``), sampled exactly at every sample.

``D`` and ``E`` are diagonal with one variance for ``a0`` and one per harmonic
(shared by ``a_i`` and ``b_i``: a perturbation of the harmonic's complex
amplitude with no preferred phase).

The transition is the exact discretisation of Eq. 2 over one sample with the
force of Eq. 4 inside the step (phase linear in time), so no discretisation
error enters the likelihood (the article's Euler step, Eq. 11-12, is not used).

Parameters estimated by maximum likelihood (:attr:`RecordModel.param_names`):
``f_h`` (Hz), ``xi_h`` (-), ``log_var_d_0 .. log_var_d_n`` (log of ``D``'s
variances relative to ``sigma^2``), likewise ``log_var_e_*``,
``log_smooth_time`` (``log ell``, ``ell`` in s; variation "smooth"), and with
``process_noise=True`` ``log_var_w`` (a white force on the COM, variance per
second relative to ``sigma^2``). ``sigma^2``, the template, ``u_0``, ``u'_0``
and the coefficients of effects' regressors are concentrated out (generalised
least squares inside :mod:`smd_statespace.person.kalman`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import OptionError
from ..io import G
from . import kalman
from .discretisation import exponentials, harmonic_gains
from .fade import fade_regressor
from .dynamics import PersonDynamics
from .system import RecordSystem, Regressor, integrated_white_noise, matern32_step, regressor_steps, step_mean
from .timing import CycleTiming
from .variation import VARIATIONS

__all__ = ["PERSON", "VARIATIONS", "Regressor", "RecordSystem", "RecordModel", "coefficient_names"]

PERSON = ("f_h", "xi_h")
"""The person's parameters: they lead :attr:`RecordModel.param_names`, so ``params[:len(PERSON)]`` are
``f_h`` (Hz) and ``xi_h`` (-) in every fit, whatever the variation model and effects."""


F_H_BOUNDS = (0.5, 6.0)
"""Search range of ``f_h`` (Hz).

The article's per-band skew-normals (Table 2) put practically every person
below 5.5 Hz. A fit that runs to the upper bound is the model imitating
something it lacks with the person's resonance (measured: a hidden cubic
spring gave 7.05 Hz for 2.75 with the smooth variation); on the bound it is
reported as no estimate, and ``variation="auto"`` prefers a fit off it.
"""

XI_H_BOUNDS = (1e-3, 3.0)
"""Search range of ``xi_h`` (-)."""

LOG_VAR_BOUNDS = (-25.0, 12.0)
"""Search range of every log variance ratio."""

SMOOTH_MIN_CYCLES = 1.0
"""Shortest length scale ``ell`` of the smooth variation, in mean force cycles.

Faster variation is the ``"independent"`` model's domain; without this bound
the smooth deviations, made nearly white, absorb whatever the model lacks
(measured: hidden 5th and 6th harmonics taken up by a first harmonic with
``ell`` = 0.03 s, ``f_h`` 2.24 Hz for 2.5).
"""

LONGEST_SMOOTH_TIME = 100.0
"""Longest length scale ``ell`` (s) of the smooth variation."""

DYNAMICS_CACHE = 4
"""Discretised dynamics kept per model (the last ``f_h``, ``xi_h`` and effect parameters seen)."""


def coefficient_names(n_harmonics):
    """``["a0", "a1", "b1", ..., "an", "bn"]``: the coefficients of Eq. 4."""
    names = ["a0"]
    for i in range(1, n_harmonics + 1):
        names += [f"a{i}", f"b{i}"]
    return names


@dataclass
class RecordModel:
    """The record-level state-space model of one person over one record.

    Parameters
    ----------
    time : ndarray, shape (N,)
        Sample times (s), uniform.
    y : ndarray, shape (N,)
        Measured COM acceleration ``GRF / M_h - g`` (m/s^2), Eq. 3.
    timing : CycleTiming
        Force-cycle boundaries (the phase of Eq. 4).
    n_harmonics : int
        Harmonics ``n`` of Eq. 4.
    variation : {"independent", "random_walk", "both", "smooth"}
        How the force coefficients change from cycle to cycle.
    process_noise : bool
        Add a white force on the COM with an estimated level.
    drift : bool
        Let the force coefficients also wander within a cycle (a per-sample
        random walk, one variance per harmonic group).
    regressors : tuple of Regressor
        Effects' known signals with unknown coefficients.
    phase_template : ndarray, shape (2 n + 1,), optional
        A force template (g). When given, two more force states correct the
        cycle timing to first order: a phase shift ``phi_j`` (rad) and a
        phase-rate error ``rho_j`` (rad/s) per cycle, each drawn afresh at
        every cycle start, entering the force as
        ``(phi_j + rho_j (t - t_mid)) dF/dtheta`` with ``F`` this template.
    dynamics : PersonDynamics, optional
        The person's dynamics from the one SMD model and its effects
        (:mod:`smd_statespace.person.dynamics`); default Eq. 2 alone,
        ``SMDModel(n_harmonics)``. The effects' parameters join
        :attr:`param_names`.
    nominal : ndarray, shape (N, n_x), optional
        The path a nonlinear effect is linearised about (the smoothed
        dynamic states of a previous fit); needed only then.
    observed : ndarray of bool, shape (N,), optional
        False at samples that were not measured (a gap in a phone's clock, where
        ``y`` holds an interpolation): the likelihood predicts over them and does
        not use their value. Default: every sample measured.
    fade : bool
        The force's harmonics scaled by ``1 + c s(t)``, linear over the record (a
        force that fades: :mod:`~smd_statespace.person.fade`), ``phase_template``
        their shape; ``c`` joins the regressors' coefficients (:attr:`all_regressors`).
        Only with a ``phase_template``. False (default): no fade.

    Attributes
    ----------
    all_regressors : tuple of Regressor
        ``regressors`` and the fade's, in the order of their coefficients in ``delta``.
    """

    time: np.ndarray
    y: np.ndarray
    timing: CycleTiming
    n_harmonics: int = 4
    variation: str = "independent"
    process_noise: bool = False
    drift: bool = False
    regressors: tuple = ()
    phase_template: np.ndarray | None = None
    dynamics: PersonDynamics | None = None
    nominal: np.ndarray | None = None
    observed: np.ndarray | None = None
    fade: bool = False
    _phase: tuple = field(init=False, repr=False)

    def __post_init__(self):
        if self.variation not in VARIATIONS:
            raise OptionError(f"variation {self.variation!r} is not one of: {', '.join(VARIATIONS)}")
        self.time = np.asarray(self.time, dtype=float)
        self.y = np.asarray(self.y, dtype=float)
        self.observed = (np.ones(self.y.size, dtype=np.bool_) if self.observed is None
                         else np.asarray(self.observed, dtype=np.bool_))
        if self.observed.shape != self.y.shape:
            raise OptionError(f"observed has shape {self.observed.shape}; the record has {self.y.size} samples")
        if self.dynamics is None:
            from ..model import SMDModel

            self.dynamics = PersonDynamics(SMDModel(n_harmonics=self.n_harmonics), self.time)
        cycle, theta, rate = self.timing.locate(self.time)
        reset = np.zeros(self.time.size, dtype=np.bool_)
        reset[1:] = cycle[1:] != cycle[:-1]
        self._phase = (cycle, theta, rate, reset)
        orders = np.arange(1, self.n_harmonics + 1)
        angle = theta[:, None] * orders
        basis = np.empty((self.time.size, self.n_coefficients))
        basis[:, 0] = 1.0
        basis[:, 1::2] = np.cos(angle)
        basis[:, 2::2] = np.sin(angle)
        self._H = G * basis
        self._rotation = np.exp(1j * angle)  # (N, n)
        self._timing_columns = self._phase_columns() if self.phase_template is not None else None
        self._H_all = self._H if self._timing_columns is None else np.hstack([self._H, self._timing_columns[0]])
        self._smooth_index = self.param_names.index("log_smooth_time") if VARIATIONS[self.variation].smooth else None
        faded = self.fade and self.phase_template is not None
        self.all_regressors = tuple(self.regressors) + ((fade_regressor(self.time, basis, self.phase_template),)
                                                        if faded else ())
        every = self.all_regressors
        self._X = np.column_stack([r.values for r in every]) if every else np.zeros((self.time.size, 0))
        self._X_obs = self._X * np.array([r.observed for r in every], dtype=float)

    # ------------------------------------------------------------------ layout
    @property
    def n_coefficients(self) -> int:
        """``p = 2 n + 1`` force coefficients per cycle."""
        return 2 * self.n_harmonics + 1

    @property
    def n_force_states(self) -> int:
        """Force states per cycle: the ``p`` coefficients, plus the phase and rate errors with a phase template."""
        return self.n_coefficients + (2 if self.phase_template is not None else 0)

    def _phase_columns(self):
        """Observation and step columns of the phase and rate errors, ``(H (N, 2), mid-step values (N, 2))``."""
        tau = np.asarray(self.phase_template, dtype=float)
        cycle, theta, rate, _ = self._phase
        b = self.timing.boundaries
        middle = 0.5 * (b[cycle] + b[cycle + 1])
        orders = np.arange(1, self.n_harmonics + 1)

        def slope(angle):  # dF/dtheta of the template (g per rad)
            a = angle[:, None] * orders
            return (orders * (-tau[1::2] * np.sin(a) + tau[2::2] * np.cos(a))).sum(axis=1)

        half = 0.5 * self.dt
        at_sample = slope(theta)
        at_middle = slope(theta + rate * half)
        h = np.column_stack([at_sample, at_sample * (self.time - middle)])
        step = np.column_stack([at_middle, at_middle * (self.time + half - middle)])
        return G * h, G * step

    @property
    def n_dynamic(self) -> int:
        """Dynamic states ``n_x`` at the head of the state (``u``, ``u_dot`` and any effect's own)."""
        return self.dynamics.n_dynamic

    @property
    def approximate(self) -> bool:
        """True when an effect is expanded about a path: a nonlinear one, or one that changes in time.

        The path is then settled by re-linearisation and the force's constant is held at 0
        (:attr:`held_delta`). Whether the likelihood is exact is :attr:`exact`.
        """
        return not self.dynamics.linear

    @property
    def exact(self) -> bool:
        """True when the likelihood is exact: the rates are linear in the state (an effect that changes in time,
        ``f_h (1 + k t)``, is expanded about a path, exactly); False for a nonlinear effect (an extended Kalman
        filter about the one-step predicted path)."""
        return self.dynamics.in_state

    @property
    def effect_parameters(self) -> list:
        """Names of the effects' parameters in :attr:`param_names` (they come last)."""
        return self.dynamics.parameter_names

    @property
    def n_observed(self) -> int:
        """Samples that were measured (``observed``)."""
        return int(np.count_nonzero(self.observed))

    @property
    def dt(self) -> float:
        """Sampling interval (s)."""
        return float(self.time[1] - self.time[0])

    @property
    def coefficient_names(self) -> list:
        """Names of the force coefficients, ``a0, a1, b1, ...``."""
        return coefficient_names(self.n_harmonics)

    @property
    def force_state_names(self) -> list:
        """Names of the force states of a cycle: the coefficients, then ``phase``, ``rate`` with a phase template."""
        return self.coefficient_names + (["phase", "rate"] if self.phase_template is not None else [])

    @property
    def held_delta(self) -> tuple:
        """Entries of ``delta`` held at 0: the force's constant ``a0`` when a nonlinear effect is linearised.

        ``u`` is the displacement from the static equilibrium (Eq. 1), about
        which an effect's law (a cubic spring's ``u^3``) is written, so the
        constant of Eq. 4 is 0. A linear model cannot see it anyway: a constant
        force only moves the static displacement, which the initial state
        takes up (``a0`` and ``u0`` are one unknown, and the likelihood leaves
        it undetermined). Through a nonlinear term it would choose the point
        the law acts about (an extra unknown: a cubic spring about a shifted
        point is a softer or stiffer spring with a quadratic term), and on clean
        records gave the spring likelihood ratios of about 6 where
        chi-square(1) has 0.45.
        """
        return (self.n_dynamic,) if self.approximate else ()

    @property
    def delta_names(self) -> list:
        """Names of the concentrated linear unknowns: ``u0, u_dot0``, the template, the regressors' coefficients."""
        return [f"{name}0" for name in self.dynamics.names] + [f"template_{c}" for c in self.coefficient_names] + [
            r.name for r in self.all_regressors]

    def unknowns(self, params) -> int:
        """How many unknowns a fit estimates: the searched ``params`` and the concentrated :attr:`delta_names`."""
        return len(params) + len(self.delta_names)

    @property
    def variance_groups(self) -> list:
        """Names of the variance groups: ``0`` (a0) and ``1..n`` (harmonics)."""
        return list(range(self.n_harmonics + 1))

    @property
    def param_names(self) -> list:
        """Names of the parameters searched by maximum likelihood."""
        names = list(PERSON) + VARIATIONS[self.variation].variance_names(self.variance_groups)
        if self.phase_template is not None:
            names += ["log_var_phase", "log_var_rate"]
        if self.drift:
            names += [f"log_var_s_{i}" for i in self.variance_groups]
        if self.process_noise:
            names.append("log_var_w")
        return names + self.effect_parameters

    @property
    def bounds(self) -> list:
        """Search bounds of the parameters, in the order of :attr:`param_names`."""
        smooth = (np.log(SMOOTH_MIN_CYCLES / np.mean(self.timing.f_b)), np.log(LONGEST_SMOOTH_TIME))
        effects = {slot.name: tuple(slot.search or (slot.low, slot.high)) for slot in self.dynamics.parameters}
        return [F_H_BOUNDS, XI_H_BOUNDS] + [
            smooth if name == "log_smooth_time" else effects.get(name, LOG_VAR_BOUNDS)
            for name in self.param_names[len(PERSON):]]

    @property
    def scales(self) -> np.ndarray:
        """Typical size of each parameter (1, or an effect's slot's nominal magnitude): the search's units."""
        nominal = {slot.name: abs(slot.nominal) or 1.0 for slot in self.dynamics.parameters}
        return np.array([nominal.get(name, 1.0) for name in self.param_names])

    def position(self, name) -> int:
        """Where the parameter ``name`` sits in a parameter vector (an :class:`OptionError` naming the valid ones)."""
        if name not in self.param_names:
            raise OptionError(f"no parameter {name!r}; the model has {', '.join(self.param_names)}")
        return self.param_names.index(name)

    def bound(self, name) -> tuple:
        """Search range ``(low, high)`` of the parameter ``name``."""
        return tuple(self.bounds[self.position(name)])

    def at_bound(self, params, which) -> bool:
        """True when parameter ``which`` (a name, or a position in ``params``) is within 0.1 % of its search range
        from a bound (not an estimate).

        A lower end that is a physical limit (:attr:`Slot.limit <smd_statespace.model.Slot>`: a floor's
        damping ratio of 0) does not count: an estimate there is an upper limit of what the record tells.
        """
        which = self.position(which) if isinstance(which, str) else which
        low, high = self.bounds[which]
        limit = self._limits.get(self.param_names[which], False)
        near_low = params[which] - low < 1e-3 * (high - low) and not limit
        return bool(near_low or high - params[which] < 1e-3 * (high - low))

    @property
    def _limits(self) -> dict:
        """Whether each effect parameter's lower search bound is a physical limit, by name."""
        return {slot.name: slot.limit for slot in self.dynamics.parameters}

    def unpack(self, params) -> dict:
        """The parameters by name, ``{"f_h": Hz, "xi_h": -, "log_var_d_1": ..., ...}`` (:attr:`param_names`).

        Code outside this class reads a parameter by name, never by its position."""
        params = np.asarray(params, dtype=float)
        if params.shape != (len(self.param_names),):
            raise OptionError(f"parameters: {len(self.param_names)} values expected ({', '.join(self.param_names)}), "
                              f"got shape {params.shape}")
        return dict(zip(self.param_names, params.tolist()))

    def pack(self, values) -> np.ndarray:
        """The parameter vector of a mapping ``name -> value`` holding every name of :attr:`param_names` (extra
        names are ignored: another model's parameters can start this one)."""
        missing = [name for name in self.param_names if name not in values]
        if missing:
            raise OptionError(f"parameters: no value for {', '.join(missing)}")
        return np.array([float(values[name]) for name in self.param_names])

    def person_at_bound(self, params) -> bool:
        """True when ``f_h`` or ``xi_h`` sits on a search bound."""
        return self.at_bound(params, "f_h") or self.at_bound(params, "xi_h")

    def start_params(self, f_h=2.5, xi_h=0.3, log_var=-3.0) -> np.ndarray:
        """A starting point: the given ``f_h``, ``xi_h``, one log variance ratio for every group and,
        for variation "smooth", a length scale of two mean bouncing cycles."""
        values = np.full(len(self.param_names), float(log_var))
        values[0], values[1] = f_h, xi_h
        if "log_smooth_time" in self.param_names:
            values[self.param_names.index("log_smooth_time")] = np.log(2.0 / np.mean(self.timing.f_b))
        for slot in self.dynamics.parameters:  # an effect starts absent where it can, else at its nominal
            values[self.param_names.index(slot.name)] = 0.0 if slot.low < 0.0 < slot.high else slot.nominal
        return values

    # ------------------------------------------------------------------ system
    def _variances(self, params):
        """``D``, ``E`` (per coefficient) and the process-noise rate from the parameter vector."""
        params = np.r_[np.asarray(params, dtype=float), -np.inf]  # index -1: a variance of 0
        index = self._variance_index
        zeros = np.zeros(self.n_force_states)
        D, E, S = (np.exp(params[index[name]]) if index[name] is not None else zeros
                   for name in ("log_var_d", "log_var_e", "log_var_s"))
        w = float(np.exp(params[index["log_var_w"]])) if index["log_var_w"] is not None else 0.0
        return D, E, S, w

    @property
    def _variance_index(self) -> dict:
        """Where each force state's log variance sits in the parameter vector (None: the model has none)."""
        cached = self.__dict__.get("_variance_index_cache")
        if cached is not None:
            return cached
        names = self.param_names
        group = np.concatenate([[0], np.repeat(np.arange(1, self.n_harmonics + 1), 2)])
        index = {}
        for kind in ("log_var_d", "log_var_e", "log_var_s"):
            if f"{kind}_0" not in names:
                index[kind] = None
                continue
            rows = [names.index(f"{kind}_{g}") for g in group]
            if self.phase_template is not None:  # the phase and rate errors: drawn per cycle (D), never walk
                rows += [names.index("log_var_phase"), names.index("log_var_rate")] if kind == "log_var_d" else [-1, -1]
            index[kind] = np.array(rows)
        if self.phase_template is not None and index["log_var_d"] is None:
            index["log_var_d"] = np.r_[np.full(self.n_coefficients, -1), names.index("log_var_phase"),
                                       names.index("log_var_rate")]
        index["log_var_w"] = names.index("log_var_w") if "log_var_w" in names else None
        self.__dict__["_variance_index_cache"] = index
        return index

    def _dynamics(self, params) -> dict:
        """The arrays of :meth:`system` that depend on ``f_h``, ``xi_h`` and the effects' parameters only.

        Kept for the last few parameter vectors (:data:`DYNAMICS_CACHE`): a
        finite-difference gradient moves the variance ratios one by one, and
        those leave the discretised dynamics as they are.
        """
        named = self.unpack(params)
        effect_values = {name: named[name] for name in self.effect_parameters}
        key = (float(params[0]), float(params[1])) + tuple(float(v) for v in effect_values.values())
        cache = self.__dict__.setdefault("_dynamics_cache", {})
        if key in cache:
            return cache[key]
        lin = self.dynamics.linearise(key[0], key[1], effect_values, self.nominal)
        dt = self.dt
        A, b = lin.A, lin.b
        if A.shape[0] > 1:  # a path-linearised effect: each step from k holds A, b at the step's midpoint
            A, b = step_mean(A), step_mean(b)
        phi, integral = exponentials(A, dt)  # exact over a step with A held (Eq. 2 and the effects)
        g0 = np.einsum("kij,kj->ki", integral, b)  # constant force: W b
        cycle = self._phase[0]
        orders = np.arange(1, self.n_harmonics + 1)
        if A.shape[0] == 1:  # one gain per cycle rate and order, rotated to each sample
            nu = self.timing_rates()[:, None] * orders  # (J, n)
            per_sample = harmonic_gains(A, phi, b, nu, dt)[cycle] * self._rotation[..., None]
        else:  # a nonlinear effect: every sample has its own A
            nu = self.timing_rates()[cycle][:, None] * orders
            per_sample = harmonic_gains(A, phi, b, nu, dt) * self._rotation[..., None]
        nx = self.n_dynamic
        gam = np.empty((self.time.size, nx, self.n_force_states))
        gam[:, :, 0] = g0
        gam[:, :, 1:self.n_coefficients:2] = per_sample.real.transpose(0, 2, 1)
        gam[:, :, 2:self.n_coefficients:2] = per_sample.imag.transpose(0, 2, 1)
        gam[:, :, :self.n_coefficients] *= G
        if self._timing_columns is not None:  # (their columns are in g already)
            gam[:, :, self.n_coefficients:] = g0[:, :, None] * self._timing_columns[1][:, None, :]
        dynamic = np.array([r.dynamic for r in self.all_regressors], dtype=bool)
        out = {
            "hx": np.ascontiguousarray(lin.hx),
            "Phi": np.ascontiguousarray(phi),
            "Gam": gam,
            "offset": np.zeros((self.time.size, nx)) if lin.c is None else np.einsum(
                "kij,kj->ki", integral, step_mean(lin.c)),
            "y_known": np.zeros(self.time.size) if lin.d is None else lin.d,
            "X_tr": regressor_steps(g0, self._X * dynamic),
            "noise_A": A.mean(axis=0),
            "noise_b": b.mean(axis=0),
        }
        if len(cache) >= DYNAMICS_CACHE:
            cache.pop(next(iter(cache)))
        cache[key] = out
        return out

    def system(self, params) -> RecordSystem:
        """The arrays of the compiled pass for a parameter vector (:class:`RecordSystem`)."""
        dynamics = self._dynamics(params)
        D, E, S, w = self._variances(params)
        nx = self.n_dynamic
        qx = w * integrated_white_noise(dynamics["noise_A"], dynamics["noise_b"], self.dt) if w > 0 else np.zeros(
            (nx, nx))
        where = self._smooth_index
        smooth = matern32_step(np.exp(params[where]), self.dt) if where is not None else (np.zeros((2, 2)),) * 3
        return RecordSystem(hx=dynamics["hx"], H=self._H_all, Phi=dynamics["Phi"], Gam=dynamics["Gam"], Qx=qx,
                            offset=dynamics["offset"], y_known=dynamics["y_known"], X_obs=self._X_obs,
                            X_tr=dynamics["X_tr"], reset=self._phase[3], code=VARIATIONS[self.variation].code, D=D, E=E,
                            drift=S, smooth_phi=smooth[0], smooth_q=smooth[1], smooth_p0=smooth[2],
                            observed=self.observed)

    def timing_rates(self) -> np.ndarray:
        """Phase rate ``2 pi f_b`` of every cycle (rad/s), shape (J,)."""
        return 2.0 * np.pi * self.timing.f_b

    # ------------------------------------------------------------------ likelihood
    def filter(self, params) -> dict:
        """Run the compiled pass and concentrate; returns the pass's arrays and :func:`kalman.concentrate`'s."""
        sys = self.system(params)
        e, Ev, f, S, s, ee = kalman.augmented_pass(*sys.pass_arguments(self.y, self.n_coefficients))
        out = kalman.concentrate(S, s, ee, f, self.n_observed, self.held_delta)
        out.update(innovations_raw=e, innovation_regression=Ev, innovation_variance_unscaled=f)
        return out

    def loglike(self, params) -> float:
        """Profile log-likelihood: template, initial state, regressors and ``sigma^2`` at their maximum."""
        return self.filter(params)["loglike"]

    def sample_loglike(self, params, delta, sigma2) -> np.ndarray:
        """Log-density of every one-step innovation at fixed linear unknowns ``delta`` and scale ``sigma2``.

        Their sum is the profile log-likelihood when ``delta`` and ``sigma2``
        are at their estimates; their derivatives there are the per-sample
        scores (the envelope theorem), from which a cycle-clustered
        (sandwich) covariance is built.
        """
        out = self.filter(params)
        raw = out["innovations_raw"] - out["innovation_regression"] @ delta
        variance = out["innovation_variance_unscaled"] * sigma2
        return np.where(self.observed, -0.5 * (np.log(2.0 * np.pi * variance) + raw**2 / variance), 0.0)

    def innovations(self, params, fitted=None) -> tuple:
        """Standardised one-step innovations and their raw values (m/s^2) at the fitted ``delta``."""
        fitted = self.filter(params) if fitted is None else fitted
        raw = fitted["innovations_raw"] - fitted["innovation_regression"] @ fitted["delta"]
        standard = raw / np.sqrt(fitted["innovation_variance_unscaled"] * fitted["sigma2"])
        return standard, raw

    def free_run(self, params, delta) -> np.ndarray:
        """The output ``GRF / M_h - g`` (m/s^2) simulated freely over the record, without the measurement.

        The force is the template of ``delta`` in every cycle (the cycles' own variation is what the model
        leaves to chance), on the model's cycle timing; the dynamics start from ``delta``'s initial state and
        are never corrected by the measurement (MATLAB's ``sim``/``compare``). A nonlinear effect runs
        linearised about its fitted path.

        Parameters
        ----------
        params : ndarray
            The searched parameters.
        delta : ndarray, shape (q,) or (q, m)
            Linear unknowns ``[initial state, template, regressor coefficients]`` (``delta_names``); with
            ``m`` columns, ``m`` runs at once.

        Returns
        -------
        ndarray, shape (T,) or (T, m)
        """
        delta = np.asarray(delta, dtype=float)
        columns = delta.reshape(delta.shape[0], -1)
        system = self.system(params)
        nx, p, n = self.n_dynamic, self.n_coefficients, self.y.size
        force = np.zeros((system.H.shape[1], columns.shape[1]))
        force[:p] = columns[nx:nx + p]  # the template; phase errors 0
        beta = columns[nx + p:]
        phi = np.broadcast_to(system.Phi, (n, nx, nx))
        drive = np.einsum("kij,jm->kim", system.Gam, force) + system.offset[:, :, None]
        if beta.size:
            drive = drive + np.einsum("kir,rm->kim", system.X_tr, beta)
        states = np.empty((n, nx, columns.shape[1]))
        states[0] = columns[:nx]
        for k in range(1, n):
            states[k] = phi[k - 1] @ states[k - 1] + drive[k - 1]
        out = (np.einsum("ki,kim->km", np.broadcast_to(system.hx, (n, nx)), states)
               + system.H @ force + system.y_known[:, None])
        if beta.size:
            out = out + system.X_obs @ beta
        return out.reshape((n,) + delta.shape[1:])

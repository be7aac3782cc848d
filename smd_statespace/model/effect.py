"""The base class of physical effects: a small declaration of slots and terms, used by every package.

Write a subclass (see docs/effects.md), register it with
:func:`smd_statespace.effects.register_effect`, and every estimator, the
simulator, the diagnosis and every command know it.

An effect declares its state slots, its term in the COM acceleration and the
rates of its own dynamic slots (optionally their Jacobians). Everything else
is derived from those by the package that needs it, with defaults there:
:mod:`smd_statespace.simulation.effect_adapter` (the truth of a simulation,
random inputs, extra force harmonics, measured columns),
:mod:`smd_statespace.diagnostics.effect_adapter` (per-cycle candidates,
score terms and notes) and :mod:`smd_statespace.person.effect_adapter` (record-level
candidates, trial starts, search sizes). An effect that can say more than
the default implements the method the adapter's ``Protocol`` names (the
floor mode: its random ambient excitation, its measured column). Two
capabilities the model itself reads are declared here: :class:`FloorMotion`
and :class:`HarmonicOrders`.

An effect is immutable: its methods return new objects (:meth:`Effect.with_values`,
``draw_simulation_inputs``) and never change the one they are called on.
"""

from __future__ import annotations

import copy
import inspect
from typing import TYPE_CHECKING, Mapping, Protocol, runtime_checkable

import numpy as np

from ..errors import OptionError

if TYPE_CHECKING:  # annotations only
    from .core import CycleInputs, SMDModel, Slot

__all__ = ["Effect", "FloorMotion", "HarmonicOrders", "slot_count", "spec_value"]


class Effect:
    """A physical effect that extends the SMD model, defined once for every use.

    Subclasses declare extra state slots and add terms to the COM
    acceleration (the only non-trivial row of Eq. 10). Effects with dynamic
    slots of their own (a floor displacement, ...) also give those slots'
    rates. Every method receives the full state ``x`` of shape
    ``(..., n_state)`` and the ``model``; read a slot with
    ``model.value(x, name)`` (which also serves a parameter given a known
    value) or ``x[..., model.index(name)]``; returned arrays keep the
    leading axes.

    The same two terms serve every use of the effect:

    - estimation: every estimator (per cycle and record level) runs the
      model's rate, with Jacobians by central differences unless the
      effect gives analytic ones (:func:`~smd_statespace.model.jacobians.check_jacobians`
      compares them);
    - forward simulation: :func:`~smd_statespace.simulation.simulate_bouncing`
      and :func:`~smd_statespace.simulation.integrate_response` integrate the
      same acceleration and slot rates with the parameters at known values
      (:meth:`with_values`, :attr:`simulation_defaults`), so
      ``simulate --effect NAME:slot=value`` works for every registered effect;
    - diagnosis: the terms a missing effect would add to the acceleration
      are the derivatives of :meth:`acceleration` in its parameters, which
      ``diagnose`` correlates with the residual and the record-level
      diagnosis fits.

    A parameter slot given a value (``NAME:slot=value`` on the command line,
    :meth:`with_values` in code) is a known constant: it leaves the
    estimated state, and the simulator uses it as the truth.

    Attributes
    ----------
    name : str
        Registry name (``--effect NAME``).
    requires : tuple of str
        Exogenous signals the effect needs from :class:`CycleInputs`.
    requires_columns : tuple of str
        Columns of the record the effect reads (the floor's measured
        acceleration ``floor_acc``); identification refuses a record without
        them, naming the column.
    record_parameters : int
        Values read off the whole record to configure the effect before any
        cycle is identified (e.g. a floor frequency taken from the residual
        spectrum); the missing-effect test counts them as fitted parameters.
    """

    name = "effect"
    requires: tuple[str, ...] = ()
    requires_columns: tuple[str, ...] = ()
    record_parameters: int = 0
    simulation_defaults: Mapping[str, float] = {}
    """Typical true values of the effect's parameter slots (by slot name), used by the simulator when not given."""

    def __new__(cls, *args, **kwargs):
        # the options the effect was built with, so that spec can write them and make_effect read them back
        effect = super().__new__(cls)
        effect._options = _given_options(cls, args, kwargs)
        return effect

    @property
    def options(self) -> dict:
        """The options this effect was built with (its constructor's arguments that differ from their defaults)."""
        return dict(self.__dict__.get("_options", {}))

    @property
    def values(self) -> dict:
        """Known values of the effect's parameter slots (slot name to value, SI units); default none."""
        return dict(self.__dict__.get("_values", {}))

    @property
    def constants(self) -> dict:
        """Fixed physical values the effect was given (name to value, SI units): its :attr:`values`."""
        return self.values

    def with_values(self, **values) -> "Effect":
        """A copy of this effect with parameter slots fixed at known values (SI units).

        The model drops those slots from the estimated state and reads the
        constants instead (:meth:`SMDModel.value`); the simulator takes them
        as the truth. Names are checked against :meth:`slots` when a model is
        built.

        Examples
        --------
        >>> from smd_statespace.effects import CubicStiffness
        >>> CubicStiffness().with_values(beta_3=400.0).values
        {'beta_3': 400.0}
        """
        twin = copy.copy(self)
        merged = self.values
        for key, value in values.items():
            try:
                merged[key] = float(value)
            except (TypeError, ValueError):
                raise OptionError(f"effect {self.name!r}: value of {key!r} must be a number, got {value!r}") from None
            if not np.isfinite(merged[key]):
                raise OptionError(f"effect {self.name!r}: value of {key!r} must be finite, got {value!r}")
        twin._values = merged
        return twin

    @property
    def spec(self) -> str:
        """The ``--effect`` text that builds this effect again (``NAME[:key=value,...]``).

        Its :attr:`options` and its known :attr:`values`, so that
        ``make_effect(effect.spec)`` builds the same effect: what ``person.json``,
        ``run.json`` and the commands ``diagnose`` prints carry. A subclass
        need not write its own.

        Examples
        --------
        >>> from smd_statespace.effects import CubicStiffness
        >>> CubicStiffness(beta_range=(-500, 500)).with_values(beta_3=412.5).spec
        'cubic_stiffness:beta_range=-500/500,beta_3=412.5'
        """
        given = {**self.options, **self.values}
        if not given:
            return self.name
        return f"{self.name}:" + ",".join(f"{key}={spec_value(value, self.name, key)}" for key, value in given.items())

    @property
    def key(self) -> str:
        """What two effects of one model must not share (their parameter slots would): the effect's
        :attr:`name`, or a kind of it where one name makes several (``term:f_drift`` and ``term:f_step``)."""
        return self.name

    @property
    def breaks(self) -> tuple[float, ...]:
        """Times (s, on the record's time axis) where the effect's term changes abruptly, such as a step; default none.

        A fit on one side of a break cannot predict the other side, so the held-out check
        (:func:`~smd_statespace.person.validation.cross_validated_loglike`) cuts the record away from them.
        """
        return ()

    def slots(self, model: "SMDModel") -> tuple[Slot, ...]:
        """State slots the effect adds (default: none).

        ``model`` is the model being built; its base options (such as
        ``n_harmonics``) are set, its state layout is not yet.
        """
        return ()

    def acceleration(self, model: "SMDModel", x, t, inputs: CycleInputs):
        """Extra COM acceleration (m/s^2), shape ``x.shape[:-1]``."""
        return np.zeros(x.shape[:-1])

    def acceleration_jacobian(self, model: "SMDModel", x, t, inputs: CycleInputs):
        """Derivative of :meth:`acceleration` with respect to ``x``, shape ``x.shape``.

        Default: central differences of :meth:`acceleration` itself
        (:func:`~smd_statespace.model.jacobians.numeric_jacobian`), so an effect
        that gives only its acceleration is right in every estimator. An
        analytic override is faster; :func:`~smd_statespace.model.jacobians.check_jacobians`
        compares the two.
        """
        from .jacobians import expand_time, numeric_jacobian

        moment = expand_time(t)
        return numeric_jacobian(lambda z: self.acceleration(model, z, moment, inputs), x)

    def slot_rates(self, model: "SMDModel", x, t, inputs: CycleInputs, acc):
        """Rates of the effect's own slots, shape ``x.shape[:-1] + (len(slots),)``.

        ``acc`` is the total COM acceleration. The default (all zeros) makes
        every slot a random-walk parameter.
        """
        return np.zeros(x.shape[:-1] + (slot_count(model, self),))

    def slot_rates_jacobian(self, model: "SMDModel", x, t, inputs: CycleInputs, acc, acc_jacobian):
        """Derivative of :meth:`slot_rates`, shape ``x.shape[:-1] + (len(slots), n_state)``.

        ``acc_jacobian`` is the derivative of the total acceleration. Default:
        central differences of :meth:`slot_rates` in ``x`` at fixed ``acc``,
        plus their derivative in ``acc`` times ``acc_jacobian`` (the chain rule).
        """
        from .jacobians import JACOBIAN_STEP, expand_time, numeric_jacobian

        x = np.asarray(x, dtype=float)
        width = slot_count(model, self)
        if width == 0:
            return np.zeros(x.shape[:-1] + (0, x.shape[-1]))
        acc = np.asarray(acc, dtype=float)
        moment = expand_time(t)
        held = acc[..., None] if acc.ndim else acc
        in_x = numeric_jacobian(lambda z: self.slot_rates(model, z, moment, inputs, held), x)
        step = JACOBIAN_STEP * np.maximum(1.0, np.abs(acc))
        in_acc = (self.slot_rates(model, x, t, inputs, acc + step)
                  - self.slot_rates(model, x, t, inputs, acc - step)) / (2.0 * np.asarray(step)[..., None])
        return in_x + in_acc[..., :, None] * np.asarray(acc_jacobian)[..., None, :]

    def __repr__(self):
        return f"{type(self).__name__}({', '.join(f'{key}={value!r}' for key, value in self.options.items())})"


@runtime_checkable
class FloorMotion(Protocol):
    """An effect that moves the floor under the person (a floor mode).

    The model reads the first such effect's ``(z, z')`` (m, m/s) in
    :meth:`~smd_statespace.model.SMDModel.floor_motion`, so that every leg
    term acts on the motion relative to the floor (Section 6).
    """

    def floor_motion(self, model: "SMDModel", x, t, inputs: CycleInputs):
        """Floor displacement ``z`` (m) and velocity ``z'`` (m/s), each of shape ``x.shape[:-1]``."""


@runtime_checkable
class HarmonicOrders(Protocol):
    """An effect whose slots are more harmonics of the force (Eq. 4): the model's basis includes its orders."""

    def orders(self, model: "SMDModel"):
        """The harmonic orders (integers above ``model.n_harmonics``) the effect adds."""


def slot_count(model, effect) -> int:
    """Number of state slots ``effect`` has in ``model`` (its known parameters left out)."""
    where = model.effect_slice(effect)
    return where.stop - where.start


def _given_options(cls, args, kwargs) -> dict:
    """The constructor arguments of ``cls`` in ``args``/``kwargs`` that differ from their defaults, by name.

    Empty when they do not bind (the constructor itself then raises its ``TypeError``).
    """
    try:
        bound = inspect.signature(cls.__init__).bind(None, *args, **kwargs)
    except TypeError:
        return {}
    parameters = inspect.signature(cls.__init__).parameters
    given = {}
    for key, value in list(bound.arguments.items())[1:]:
        kind = parameters[key].kind
        if kind == inspect.Parameter.VAR_KEYWORD:
            given.update(value)
        elif kind != inspect.Parameter.VAR_POSITIONAL and not _same(value, parameters[key].default):
            given[key] = value
    return given


def _same(value, default) -> bool:
    """Whether an option's value is its default (numbers and sequences compared by value)."""
    if default is inspect.Parameter.empty:
        return False
    try:
        return bool(np.array_equal(np.asarray(value, dtype=object), np.asarray(default, dtype=object)))
    except (TypeError, ValueError):
        return value is default


def spec_value(value, name="effect", key="option") -> str:
    """An option's value as ``make_effect`` reads it back: numbers exactly, pairs as ``low/high``, words.

    Floats are written as short as reading them back allows (``3.48``, not ``3.4800000000000004``).

    Examples
    --------
    >>> spec_value((-500.0, 500.0)), spec_value(0.1 + 0.2), spec_value(True)
    ('-500/500', '0.30000000000000004', 'true')
    """
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (tuple, list)):
        return "/".join(spec_value(v, name, key) for v in value)
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if value is None:
        return "none"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        short = f"{float(value):g}"
        return short if float(short) == float(value) else repr(float(value))
    text = str(value)
    if not text or any(mark in text for mark in ",:=/;") or text != text.strip():
        raise OptionError(f"effect {name!r}: option {key}={value!r} cannot be written in a spec (NAME:key=value): "
                          "use numbers, number pairs or single words")
    return text

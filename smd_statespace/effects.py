"""Physical effects that extend the SMD model.

An effect adds slots to the augmented state and terms to the COM
acceleration (see :class:`smd_statespace.model.Effect`). Combine them with
``SMDModel(effects=[...])`` or ``model.with_effects(...)``; every estimator
works with any combination unchanged.

Built in:

=================== ==========================================================
name                what it adds
=================== ==========================================================
``harmonics``       Fourier harmonics ``n+1 ... n+count`` of the force (Eq. 4)
``cubic_stiffness`` a hardening (``beta_3 > 0``) or softening leg spring
=================== ==========================================================

Effects are looked up by name with :func:`make_effect`, which also parses the
command-line form ``NAME:key=value,key=value``.
"""

from __future__ import annotations

import numpy as np

from .errors import OptionError
from .io import G
from .model import F_H, TWO_PI, U, Effect, Slot


class Harmonics(Effect):
    """Extra Fourier harmonics of the biomechanical force.

    Adds the coefficients ``a_k, b_k`` (g) for ``k = n+1 ... n+count`` and
    their terms ``g (a_k cos(k theta) + b_k sin(k theta))`` to the
    acceleration, with the same prior range as the base coefficients.

    Parameters
    ----------
    count : int
        Number of harmonics to add.
    """

    name = "harmonics"

    def __init__(self, count: int = 2):
        if isinstance(count, bool) or int(count) != count or count < 1:
            raise OptionError(f"harmonics: count must be a whole number >= 1, got {count!r}")
        self.count = int(count)

    def orders(self, model) -> np.ndarray:
        """Harmonic orders this effect adds to ``model``."""
        return np.arange(model.n_harmonics + 1, model.n_harmonics + self.count + 1)

    def slots(self, model):
        low, high = model.options["coefficient_range"]
        nominal = max(abs(low), abs(high)) / 2.0
        return tuple(
            Slot(f"{c}{k}", "parameter", "g", low, high, nominal=nominal,
                 description=f"{'cosine' if c == 'a' else 'sine'} coefficient of harmonic {k}")
            for k in self.orders(model) for c in "ab"
        )

    def acceleration(self, model, x, t, inputs):
        basis = model.fourier_basis(t, inputs, harmonics=self.orders(model))
        return G * np.sum(x[..., model.effect_slice(self)] * basis, axis=-1)

    def acceleration_jacobian(self, model, x, t, inputs):
        jac = np.zeros(x.shape)
        jac[..., model.effect_slice(self)] = G * model.fourier_basis(t, inputs, harmonics=self.orders(model))
        return jac

    def __repr__(self):
        return f"Harmonics(count={self.count})"


class CubicStiffness(Effect):
    """A nonlinear leg spring: restoring force ``K_h (u + beta_3 u^3)``.

    Adds the parameter ``beta_3`` (1/m^2) and the acceleration term
    ``-omega_h^2 beta_3 u^3``. ``beta_3 > 0`` hardens the spring (the
    apparent natural frequency rises with amplitude), ``beta_3 < 0`` softens it.

    Parameters
    ----------
    beta_range : (float, float)
        Uniform prior of ``beta_3`` (1/m^2). At a COM amplitude of 3 cm,
        ``beta_3 = 1000`` changes the stiffness by 90 %.
    """

    name = "cubic_stiffness"

    def __init__(self, beta_range=(-1000.0, 1000.0)):
        low, high = (float(v) for v in beta_range)
        if not low < high:
            raise OptionError(f"cubic_stiffness: beta_range must satisfy low < high, got {beta_range!r}")
        self.beta_range = (low, high)

    def slots(self, model):
        low, high = self.beta_range
        return (Slot("beta_3", "parameter", "1/m^2", low, high, nominal=max(abs(low), abs(high)) / 4.0,
                     description="cubic stiffness coefficient", linear=False),)

    def acceleration(self, model, x, t, inputs):
        omega = TWO_PI * x[..., F_H]
        beta = x[..., model.index("beta_3")]
        return -(omega**2) * beta * x[..., U] ** 3

    def acceleration_jacobian(self, model, x, t, inputs):
        omega = TWO_PI * x[..., F_H]
        i_beta = model.index("beta_3")
        beta, u = x[..., i_beta], x[..., U]
        jac = np.zeros(x.shape)
        jac[..., U] = -3.0 * omega**2 * beta * u**2
        jac[..., F_H] = -2.0 * TWO_PI * omega * beta * u**3
        jac[..., i_beta] = -(omega**2) * u**3
        return jac

    def __repr__(self):
        return f"CubicStiffness(beta_range={self.beta_range})"


EFFECTS = {effect.name: effect for effect in (Harmonics, CubicStiffness)}
"""Registry of effects by name; :func:`register_effect` adds user-written ones."""


def register_effect(cls):
    """Register an :class:`Effect` subclass under ``cls.name`` (usable as a decorator)."""
    if not (isinstance(cls, type) and issubclass(cls, Effect)):
        raise OptionError(f"register_effect needs an Effect subclass, got {cls!r}")
    EFFECTS[cls.name] = cls
    return cls


def _parse_value(text):
    text = text.strip()
    if "/" in text or ";" in text:
        parts = [p for p in text.replace(";", "/").split("/") if p]
        return tuple(_parse_value(p) for p in parts)
    try:
        number = float(text)
    except ValueError:
        return text
    return int(number) if number.is_integer() and "." not in text and "e" not in text.lower() else number


def make_effect(spec) -> Effect:
    """Build an effect from a name, ``"NAME:key=value,..."``, or pass an :class:`Effect` through.

    Examples
    --------
    >>> make_effect("harmonics:count=3")
    Harmonics(count=3)
    >>> make_effect("cubic_stiffness:beta_range=-500/500")
    CubicStiffness(beta_range=(-500.0, 500.0))
    """
    if isinstance(spec, Effect):
        return spec
    name, _, rest = str(spec).partition(":")
    name = name.strip()
    if name not in EFFECTS:
        raise OptionError(f"unknown effect {name!r}; choose one of {', '.join(sorted(EFFECTS))}")
    kwargs = {}
    for item in filter(None, (part.strip() for part in rest.split(","))):
        key, eq, value = item.partition("=")
        if not eq:
            raise OptionError(f"effect {name!r}: option {item!r} must look like key=value")
        kwargs[key.strip()] = _parse_value(value)
    try:
        return EFFECTS[name](**kwargs)
    except TypeError:
        import inspect

        valid = [p for p in inspect.signature(EFFECTS[name].__init__).parameters if p != "self"]
        bad = [key for key in kwargs if key not in valid]
        raise OptionError(
            f"effect {name!r}: unknown option {', '.join(map(repr, bad)) or repr(kwargs)}; valid: {', '.join(valid) or 'none'}"
        ) from None

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
``floor_mode``      a vibrating floor under the person (Section 6): measured
                    floor motion, or one estimated floor mode
=================== ==========================================================

Effects are looked up by name with :func:`make_effect`, which also parses the
command-line form ``NAME:key=value,key=value``.
"""

from __future__ import annotations

import numpy as np

from . import article
from .errors import OptionError
from .io import G
from .model import F_H, TWO_PI, U, XI_H, Effect, Slot


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

    @property
    def spec(self) -> str:
        return f"{self.name}:count={self.count}"

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

    @property
    def spec(self) -> str:
        return f"{self.name}:beta_range={_spec_value(self.beta_range)}"

    def __repr__(self):
        return f"CubicStiffness(beta_range={self.beta_range})"


class FloorMode(Effect):
    """The person bounces on a vibrating floor (human-structure interaction, Section 6).

    The leg spring and damper act on the COM motion relative to the floor
    displacement ``z`` (m, upward)::

        u'' = -omega_h^2 (u - z) - 2 xi_h omega_h (u' - z') + F_bio / M_h

    so the effect adds ``omega_h^2 z + 2 xi_h omega_h z'`` to the acceleration
    of Eq. 10. ``u''`` stays the absolute COM acceleration, which the GRF
    measures through Eq. 3. Where ``z`` comes from depends on ``source``:

    ``"measured"`` (default)
        The record has a ``floor_acc`` column; its high-passed, integrated
        velocity and displacement (:func:`smd_statespace.signals.preprocess`)
        are exogenous inputs (``requires = ("floor_disp", "floor_vel")``). No
        slots are added.
    ``"modal"``
        No floor measurement: the floor is one modal oscillator whose state
        and parameters are estimated with the person's::

            z'' = -omega_f^2 z - 2 xi_f omega_f z' - mass_ratio u''

        i.e. ``m_f z'' + c_f z' + k_f z = -M_h u''`` divided by the modal mass
        ``m_f = M_h / mass_ratio``: the floor is driven by the dynamic GRF.
        Slots ``z`` (m), ``z_dot`` (m/s), then the parameters ``f_f`` (Hz),
        ``xi_f`` (-) and ``mass_ratio`` (-), all three non-linear.

    =============== ================ =========================================
    symbol          slot / option    meaning (unit)
    =============== ================ =========================================
    ``z``           ``"z"``          floor displacement at the person (m)
    ``z'``          ``"z_dot"``      floor velocity (m/s)
    ``f_f``         ``"f_f"``        floor modal frequency (Hz)
    ``xi_f``        ``"xi_f"``       floor modal damping ratio (-)
    ``M_h / m_f``   ``"mass_ratio"`` person mass over floor modal mass (-)
    =============== ================ =========================================

    Parameters
    ----------
    source : {"measured", "modal"}
        Where the floor motion comes from (see above).
        :meth:`for_record` picks it from the record.
    frequency : float, optional
        ``"modal"`` only: a seed of the floor frequency (Hz), e.g. a peak of
        the residual spectrum. The prior of ``f_f`` is then uniform on
        ``frequency * (1 -+ frequency_spread)``.
    frequency_spread : float, optional
        ``"modal"`` only: relative half-width of that prior (default 0.15).
    frequency_range : (float, float), optional
        ``"modal"`` only: the prior range of ``f_f`` (Hz) given directly;
        default 2-20 Hz when no ``frequency`` is given.
    damping_range : (float, float), optional
        ``"modal"`` only: prior range of ``xi_f`` (default 0.001-0.05).
    mass_ratio_range : (float, float), optional
        ``"modal"`` only: prior range of ``M_h / m_f`` (default 0.001-0.05;
        one 70 kg person on the article's plate, 8583 kg: 0.008).
    damping, mass_ratio : float, optional
        ``"modal"`` only: a *known* mode. With ``frequency`` and ``damping``
        (and ``mass_ratio``, default 0.008: 70 kg on mode 1 of the article's
        plate) given, ``f_f``, ``xi_f`` and ``M_h / m_f`` are constants, as
        from a modal test of the floor (the article's Table 3), and only the
        floor's motion ``z``, ``z_dot`` is estimated. Fewer values per cycle
        than an estimated mode: a floor mode is one frequency for the whole
        record.
    displacement, velocity : float, optional
        ``"modal"`` only: nominal magnitudes of ``z`` (m, default 1e-3) and
        ``z'`` (m/s, default 1e-2): the prior spread of the unobserved floor
        state and, times ``process_noise``, its process noise per step. They
        are fixed, not scaled by the person's data, because the floor moves
        one or two orders of magnitude less than the COM.

    Attributes
    ----------
    requires : tuple of str
        Exogenous signals needed: ``("floor_disp", "floor_vel")`` when
        measured, none when modal.
    requires_columns : tuple of str
        Record columns those signals come from: ``("floor_acc",)`` when measured.
    slot_names : tuple of str
        Names of the slots the ``"modal"`` source adds, in state order
        (``z``, ``z_dot`` only for a known mode).
    known : bool
        Whether the modal floor's ``f_f``, ``xi_f`` and mass ratio are given constants.

    Examples
    --------
    >>> make_effect("floor_mode")
    FloorMode(source='measured')
    >>> make_effect("floor_mode:source=modal,frequency=3.48").slot_names
    ('z', 'z_dot', 'f_f', 'xi_f', 'mass_ratio')
    >>> make_effect("floor_mode:source=modal,frequency=3.48,damping=0.0037").slot_names
    ('z', 'z_dot')
    """

    name = "floor_mode"
    SOURCES = ("measured", "modal")
    MODAL_DEFAULTS = {
        "frequency_spread": 0.15,
        "frequency_range": (2.0, 20.0),
        "damping_range": (0.001, 0.05),
        "mass_ratio_range": (0.001, 0.05),
        "displacement": 1e-3,
        "velocity": 1e-2,
    }
    KNOWN_MASS_RATIO = 70.0 / article.TABLE3[0].modal_mass
    """Default ``M_h / m_f`` of a known mode: a 70 kg person on mode 1 of the article's plate (0.008)."""
    slot_names = ("z", "z_dot", "f_f", "xi_f", "mass_ratio")
    known = False

    def __init__(self, source="measured", *, frequency=None, frequency_spread=None, frequency_range=None,
                 damping_range=None, mass_ratio_range=None, displacement=None, velocity=None, damping=None,
                 mass_ratio=None, **unknown):
        where = "floor_mode"
        if unknown:
            valid = ["source", "frequency", "damping", "mass_ratio"] + list(self.MODAL_DEFAULTS)
            raise OptionError(
                f"effect {where!r}: unknown option {', '.join(map(repr, unknown))}; valid: {', '.join(valid)}"
            )
        if source not in self.SOURCES:
            raise OptionError(
                f"{where}: source {source!r} is unknown; choose 'measured' (the record has a floor_acc column) "
                "or 'modal' (estimate one floor mode)"
            )
        self.source = source
        modal = {"frequency": frequency, "frequency_spread": frequency_spread, "frequency_range": frequency_range,
                 "damping_range": damping_range, "mass_ratio_range": mass_ratio_range,
                 "displacement": displacement, "velocity": velocity, "damping": damping, "mass_ratio": mass_ratio}
        given = [key for key, value in modal.items() if value is not None]
        if source == "measured":
            if given:
                raise OptionError(
                    f"{where}: option {given[0]!r} applies to source='modal' only; the measured floor has no "
                    "parameters to estimate"
                )
            self.requires = ("floor_disp", "floor_vel")
            self.requires_columns = ("floor_acc",)
            self.given = {}
            return
        self.requires = ()
        self.requires_columns = ()
        self.given = {key: modal[key] for key in given}
        if frequency is not None and frequency_range is not None:
            raise OptionError(f"{where}: give frequency (a seed) or frequency_range, not both")
        if frequency is None and frequency_spread is not None:
            raise OptionError(f"{where}: frequency_spread needs a seed frequency")
        defaults = self.MODAL_DEFAULTS
        if damping is not None or mass_ratio is not None:
            self._set_known(frequency, damping, mass_ratio, given, where)
        if frequency is not None:
            frequency = _positive(frequency, "frequency (Hz)", where)
            spread = _positive(defaults["frequency_spread"] if frequency_spread is None else frequency_spread,
                               "frequency_spread", where)
            if spread >= 1.0:
                raise OptionError(f"{where}: frequency_spread must be a fraction below 1, got {spread!r}")
            frequency_range = (frequency * (1.0 - spread), frequency * (1.0 + spread))
        self.frequency = frequency
        self.frequency_range = _positive_range(frequency_range or defaults["frequency_range"], "frequency_range", where)
        self.damping_range = _positive_range(damping_range or defaults["damping_range"], "damping_range", where)
        self.mass_ratio_range = _positive_range(mass_ratio_range or defaults["mass_ratio_range"],
                                                "mass_ratio_range", where)
        self.displacement = _positive(defaults["displacement"] if displacement is None else displacement,
                                      "displacement (m)", where)
        self.velocity = _positive(defaults["velocity"] if velocity is None else velocity, "velocity (m/s)", where)

    def _set_known(self, frequency, damping, mass_ratio, given, where):
        """Make this a known mode (constants ``f_f``, ``xi_f``, ``M_h / m_f``); check the options agree."""
        if frequency is None or damping is None:
            raise OptionError(f"{where}: a known mode needs both frequency (Hz) and damping (ratio); "
                              f"got {', '.join(given)}")
        clash = [key for key in ("frequency_spread", "frequency_range", "damping_range", "mass_ratio_range")
                 if key in given]
        if clash:
            raise OptionError(f"{where}: {clash[0]} is a prior range of an estimated mode; a known mode "
                              "(frequency, damping, mass_ratio given) has none")
        damping = _positive(damping, "damping (ratio)", where)
        if damping >= 1.0:
            raise OptionError(f"{where}: damping must be a ratio below 1, got {damping!r}")
        self.known = True
        self.slot_names = ("z", "z_dot")
        self.known_values = (float(frequency), damping,
                             _positive(self.KNOWN_MASS_RATIO if mass_ratio is None else mass_ratio,
                                       "mass_ratio", where))

    def _modal_values(self, model, x):
        """Floor frequency ``f_f`` (Hz), damping ratio ``xi_f`` and mass ratio of state(s) ``x``."""
        if self.known:
            return self.known_values
        return tuple(x[..., model.index(name)] for name in ("f_f", "xi_f", "mass_ratio"))

    @classmethod
    def for_record(cls, record, **options) -> "FloorMode":
        """The measured floor when ``record`` has a floor acceleration, else the estimated mode.

        ``record`` is a :class:`~smd_statespace.io.Record` or a
        :class:`~smd_statespace.signals.Preprocessed` (anything with a
        ``floor_acc`` attribute); ``options`` are the ``"modal"`` options and
        are ignored when the floor is measured.
        """
        if getattr(record, "floor_acc", None) is not None:
            return cls("measured")
        return cls("modal", **options)

    @property
    def modal(self) -> bool:
        """Whether the floor mode is estimated (``source="modal"``)."""
        return self.source == "modal"

    def slots(self, model):
        if not self.modal:
            return ()
        f_lo, f_hi = self.frequency_range
        d_lo, d_hi = self.damping_range
        m_lo, m_hi = self.mass_ratio_range
        motion = (
            Slot("z", "dynamic", "m", nominal=self.displacement, description="floor displacement at the person"),
            Slot("z_dot", "dynamic", "m/s", nominal=self.velocity, description="floor velocity at the person"),
        )
        if self.known:
            return motion
        return motion + (
            Slot("f_f", "parameter", "Hz", f_lo, f_hi, nominal=0.5 * (f_lo + f_hi),
                 description="floor modal frequency", linear=False),
            Slot("xi_f", "parameter", "-", d_lo, d_hi, nominal=0.5 * (d_lo + d_hi),
                 description="floor modal damping ratio", linear=False),
            Slot("mass_ratio", "parameter", "-", m_lo, m_hi, nominal=0.5 * (m_lo + m_hi),
                 description="person mass over floor modal mass", linear=False),
        )

    def floor_motion(self, model, x, t, inputs):
        """Floor displacement ``z`` (m) and velocity ``z'`` (m/s) seen by state(s) ``x`` at ``t``."""
        if self.modal:
            return x[..., model.index("z")], x[..., model.index("z_dot")]
        return inputs.signal("floor_disp", t), inputs.signal("floor_vel", t)

    def acceleration(self, model, x, t, inputs):
        omega = TWO_PI * x[..., F_H]
        z, z_dot = self.floor_motion(model, x, t, inputs)
        return omega**2 * z + 2.0 * x[..., XI_H] * omega * z_dot  # Section 6: spring and damper on u - z

    def acceleration_jacobian(self, model, x, t, inputs):
        omega = TWO_PI * x[..., F_H]
        xi = x[..., XI_H]
        z, z_dot = self.floor_motion(model, x, t, inputs)
        jac = np.zeros(x.shape)
        jac[..., F_H] = TWO_PI * (2.0 * omega * z + 2.0 * xi * z_dot)
        jac[..., XI_H] = 2.0 * omega * z_dot
        if self.modal:
            jac[..., model.index("z")] = omega**2
            jac[..., model.index("z_dot")] = 2.0 * xi * omega
        return jac

    def slot_rates(self, model, x, t, inputs, acc):
        rates = np.zeros(x.shape[:-1] + (len(self.slot_names) if self.modal else 0,))
        if not self.modal:
            return rates
        z, z_dot = x[..., model.index("z")], x[..., model.index("z_dot")]
        f_f, xi_f, mu = self._modal_values(model, x)
        omega_f = TWO_PI * f_f
        rates[..., 0] = z_dot
        rates[..., 1] = -(omega_f**2) * z - 2.0 * xi_f * omega_f * z_dot - mu * acc
        return rates

    def slot_rates_jacobian(self, model, x, t, inputs, acc, acc_jacobian):
        width = len(self.slot_names) if self.modal else 0
        jac = np.zeros(x.shape[:-1] + (width, x.shape[-1]))
        if not self.modal:
            return jac
        i_z, i_v = model.index("z"), model.index("z_dot")
        z, z_dot = x[..., i_z], x[..., i_v]
        f_f, xi_f, mu = self._modal_values(model, x)
        omega_f = TWO_PI * f_f
        jac[..., 0, i_v] = 1.0
        row = -np.asarray(mu)[..., None] * acc_jacobian
        row[..., i_z] += -(omega_f**2)
        row[..., i_v] += -2.0 * xi_f * omega_f
        if not self.known:
            i_f, i_xi, i_mu = (model.index(name) for name in ("f_f", "xi_f", "mass_ratio"))
            row[..., i_f] += -TWO_PI * (2.0 * omega_f * z + 2.0 * xi_f * z_dot)
            row[..., i_xi] += -2.0 * omega_f * z_dot
            row[..., i_mu] += -acc
        jac[..., 1, :] = row
        return jac

    @property
    def constants(self) -> dict:
        if not self.known:
            return {}
        return dict(zip(("f_f", "xi_f", "mass_ratio"), self.known_values))

    @property
    def spec(self) -> str:
        if not self.modal:
            return self.name
        options = "".join(f",{key}={_spec_value(value)}" for key, value in self.given.items())
        return f"{self.name}:source=modal{options}"

    def __repr__(self):
        options = "".join(f", {key}={value!r}" for key, value in self.given.items())
        return f"FloorMode(source={self.source!r}{options})"


def _spec_value(value) -> str:
    """An option value as ``make_effect`` reads it (pairs as ``low/high``)."""
    if isinstance(value, (tuple, list)):
        return "/".join(_spec_value(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def _positive(value, label, where):
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {label} must be a number, got {value!r}") from None
    if not (np.isfinite(number) and number > 0):
        raise OptionError(f"{where}: {label} must be a positive number, got {value!r}")
    return number


def _positive_range(value, label, where):
    try:
        low, high = (float(v) for v in value)
    except (TypeError, ValueError):
        raise OptionError(f"{where}: {label} must be a pair low/high, got {value!r}") from None
    if not (np.isfinite(low) and np.isfinite(high) and 0 < low < high):
        raise OptionError(f"{where}: {label} must satisfy 0 < low < high, got {value!r}")
    return low, high


EFFECTS = {effect.name: effect for effect in (Harmonics, CubicStiffness, FloorMode)}
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


def parse_spec(spec, option="--effect") -> tuple:
    """Parse ``NAME[:key=value,key=value]`` into ``(name, {key: value})``: the one parser of effect specs.

    Values are numbers (integers stay integers), tuples written ``a/b``, or
    words. The effect's own code checks names, keys and kinds of values.

    Examples
    --------
    >>> parse_spec("floor_mode:frequency=3.48,modal_mass=8583")
    ('floor_mode', {'frequency': 3.48, 'modal_mass': 8583})
    >>> parse_spec("harmonics:blf=0.04/0.03")
    ('harmonics', {'blf': (0.04, 0.03)})
    """
    name, _, rest = str(spec).partition(":")
    name = name.strip()
    if not name:
        raise OptionError(f"{option} {spec!r}: give an effect name, e.g. floor_mode or harmonics:count=2")
    values = {}
    for item in filter(None, (part.strip() for part in rest.split(","))):
        key, eq, value = item.partition("=")
        key = key.strip()
        if not eq or not key or not value.strip():
            raise OptionError(f"{option} {spec!r}: {item!r} must look like key=value")
        values[key] = _parse_value(value)
    return name, values


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
    name, kwargs = parse_spec(spec, "effect")
    if name not in EFFECTS:
        raise OptionError(f"unknown effect {name!r}; choose one of {', '.join(sorted(EFFECTS))}")
    try:
        return EFFECTS[name](**kwargs)
    except TypeError:
        import inspect

        valid = [p for p in inspect.signature(EFFECTS[name].__init__).parameters if p != "self"]
        bad = [key for key in kwargs if key not in valid]
        raise OptionError(
            f"effect {name!r}: unknown option {', '.join(map(repr, bad)) or repr(kwargs)}; valid: {', '.join(valid) or 'none'}"
        ) from None

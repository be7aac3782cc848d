"""The registry of physical effects: names, specs, a user's effects.

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
``term``            one generic restoring, damping or time term (``kind=``)
=================== ==========================================================

Effects are looked up by name with :func:`make_effect`, which also parses the
command-line form ``NAME:key=value,key=value``.
"""

from __future__ import annotations

import inspect

from ..errors import OptionError
from ..model.effect import Effect
from .cubic_stiffness import CubicStiffness
from .floor_mode import FloorMode
from .generic import GenericTerm
from .harmonics import Harmonics

__all__ = ["EFFECTS", "register_effect", "load_effects_file", "load_installed_effects", "parse_spec", "make_effect",
           "build_effect"]


EFFECTS = {effect.name: effect for effect in (Harmonics, CubicStiffness, FloorMode, GenericTerm)}
"""Registry of effects by name; :func:`register_effect` adds user-written ones."""


def register_effect(cls):
    """Register an :class:`Effect` subclass under ``cls.name`` (usable as a decorator).

    Every command then knows it by name: ``simulate --effect NAME:slot=value``,
    ``identify``/``compare``/``crowd --effect NAME``, and ``diagnose`` tries
    it as a candidate. On the command line, load the file that defines it
    with ``smd-statespace --effects FILE.py COMMAND ...``, or ship it in a
    package under the entry-point group ``smd_statespace.effects``
    (:func:`load_installed_effects`).
    """
    if not (isinstance(cls, type) and issubclass(cls, Effect)):
        raise OptionError(f"register_effect needs an Effect subclass, got {cls!r}")
    if not isinstance(getattr(cls, "name", None), str) or not cls.name.isidentifier() or cls.name == "effect":
        raise OptionError(f"register_effect: {cls.__name__} needs a class attribute name, a word such as "
                          "'quadratic_damping'")
    EFFECTS[cls.name] = cls
    return cls


def load_effects_file(path) -> list:
    """Run the Python file ``path`` so that the effects it registers join :data:`EFFECTS`.

    Returns the names it added. The file is imported as a module named after
    it (its ``@register_effect`` classes register themselves).
    """
    import importlib.util
    import sys
    from pathlib import Path

    path = Path(path)
    if not path.is_file() or path.suffix != ".py":
        raise OptionError(f"--effects {path}: give an existing Python file (.py) that registers effects")
    before = dict(EFFECTS)
    module_name = f"smd_statespace_user_effects_{path.stem}"
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module
    try:
        spec.loader.exec_module(module)
    except OptionError:
        raise
    except Exception as exc:  # the user's code: report where it failed, in one line
        raise OptionError(f"--effects {path}: running it failed: {type(exc).__name__}: {exc}") from None
    added = sorted(name for name, cls in EFFECTS.items() if before.get(name) is not cls)
    if not added:
        raise OptionError(f"--effects {path}: it registers no effect (decorate the class with @register_effect)")
    return added


def load_installed_effects() -> list:
    """Register the effects that installed packages declare under the entry-point group ``smd_statespace.effects``.

    Each entry point names an :class:`Effect` subclass, e.g. in a
    ``setup.cfg``::

        [options.entry_points]
        smd_statespace.effects =
            quadratic_damping = my_package.effects:QuadraticDamping

    Returns the names added.
    """
    from importlib.metadata import entry_points

    added = []
    for point in entry_points(group="smd_statespace.effects"):
        cls = point.load()
        register_effect(cls)
        added.append(cls.name)
    return added


def _parse_value(text):
    text = text.strip()
    if "/" in text or ";" in text:
        parts = [p for p in text.replace(";", "/").split("/") if p]
        return tuple(_parse_value(p) for p in parts)
    words = {"true": True, "false": False, "none": None}
    if text.lower() in words:
        return words[text.lower()]
    try:
        number = float(text)
    except ValueError:
        return text
    return int(number) if number.is_integer() and "." not in text and "e" not in text.lower() else number


def parse_spec(spec, option="--effect") -> tuple:
    """Parse ``NAME[:key=value,key=value]`` into ``(name, {key: value})``: the one parser of effect specs.

    Values are numbers (integers stay integers), tuples written ``a/b``,
    ``true``/``false``/``none``, or words: what :attr:`Effect.spec
    <smd_statespace.model.Effect.spec>` writes. The effect's own code checks
    names, keys and kinds of values.

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


def make_effect(spec, option="effect") -> Effect:
    """Build an effect from a name, ``"NAME:key=value,..."``, or pass an :class:`Effect` through.

    Keys are the effect's options (its constructor's arguments) or the
    names of its parameter slots, which fix those at known values
    (:meth:`Effect.with_values`): the truth in a simulation, a constant in
    identification.

    Examples
    --------
    >>> make_effect("harmonics:count=3")
    Harmonics(count=3)
    >>> make_effect("cubic_stiffness:beta_range=-500/500")
    CubicStiffness(beta_range=(-500.0, 500.0))
    """
    if isinstance(spec, Effect):
        return spec
    name, options = parse_spec(spec, option)
    return build_effect(name, options)


def build_effect(name: str, options=None) -> Effect:
    """The registered effect ``name`` from a dict of options and known parameter values (see :func:`make_effect`).

    Examples
    --------
    >>> build_effect("cubic_stiffness", {"beta_3": 400.0}).values
    {'beta_3': 400.0}
    """
    if name not in EFFECTS:
        raise OptionError(f"unknown effect {name!r}; choose one of {', '.join(sorted(EFFECTS))}")
    options = {} if options is None else options
    if not hasattr(options, "items"):
        raise OptionError(f"effect {name!r} takes a dict of options, got {options!r}")
    cls = EFFECTS[name]
    signature = inspect.signature(cls.__init__).parameters
    named = [key for key, p in signature.items() if key != "self" and p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)]
    arguments = {key: value for key, value in options.items() if key in named}
    values = {key: value for key, value in options.items() if key not in named}
    try:
        effect = cls(**arguments)
    except TypeError as exc:
        raise OptionError(f"effect {name!r}: {exc}; valid options: {', '.join(named) or 'none'}") from None
    if values:
        from ..model.core import SMDModel

        parameters = [slot.name for slot in effect.slots(SMDModel()) if slot.kind == "parameter"]
        bad = [key for key in values if key not in parameters]
        if bad:
            raise OptionError(
                f"effect {name!r}: unknown option {', '.join(map(repr, bad))}; valid options: "
                f"{', '.join(named) or 'none'}; parameters that take a known value: {', '.join(parameters) or 'none'}"
            )
        effect = effect.with_values(**values)
    return effect

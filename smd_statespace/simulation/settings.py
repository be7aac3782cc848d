"""The simulator's arguments checked and completed, and its seed policy.

:func:`_check_simulation` turns the arguments of
:func:`~smd_statespace.simulation.simulate_bouncing` into the settings the
rest of the simulator reads (a namespace: the checked numbers, the prepared
effects split into extra force harmonics and the integrated system, the force
phases); :func:`_resolve_seed` turns a seed into a Generator and a
JSON-able record of it. Both are shared inside :mod:`smd_statespace.simulation`
(re-exported by :mod:`.bouncing`).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..errors import OptionError
from ..io import check_mass
from ..model import SMDModel
from .dynamics import _number, _simulation_effects, _System, _vector
from .effect_adapter import force_harmonics
from .force_shape import default_phases
from .generators import TEMPO_MAX_FB_VARIATION, _check_pulses
from .variation import VARIATIONS


def _resolve_seed(seed):
    """Return ``(generator, record)``: the Generator and a JSON-able seed record."""
    if isinstance(seed, np.random.Generator):
        return np.random.default_rng(seed), None  # the same Generator, its state not recordable
    if seed is None:
        seed = np.random.SeedSequence()
    if isinstance(seed, np.random.SeedSequence):
        if seed.spawn_key:
            record = {"entropy": seed.entropy, "spawn_key": list(seed.spawn_key)}
        else:
            record = seed.entropy
        return np.random.default_rng(seed), record
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise OptionError(
            f"seed must be None, a non-negative int, a numpy SeedSequence or a numpy Generator, got {seed!r}"
        )
    return np.random.default_rng(int(seed)), int(seed)


def _check_simulation(mass, f_b, f_h, xi_h, duration, fs, blf, phases, a0, fb_variation, coef_variation, noise,
                      effects, variation, phase_variation=None):
    """Validate the arguments of :func:`simulate_bouncing`; return them checked and completed (a namespace)."""
    checked = _check_numbers(mass, f_b, f_h, xi_h, duration, fs, blf, a0, fb_variation, coef_variation, noise,
                             variation)
    effects = _simulation_effects(effects, checked["mass"])
    system, extra = _split_effects(effects, checked["f_h"], checked["xi_h"])
    extra_blf = np.concatenate([np.asarray(pair[0], dtype=float) for pair in extra]) if extra else np.empty(0)
    _check_sampling(checked["fs"], checked["f_b"], system, checked["blf"].size, extra_blf.size)
    phases, extra_phases, phases_given = _force_phases(phases, checked, extra_blf, extra)
    c = checked
    settings = SimpleNamespace(
        mass=c["mass"], f_b=c["f_b"], f_h=c["f_h"], xi_h=c["xi_h"], duration=c["duration"], fs=c["fs"],
        blf=c["blf"], phases=phases, a0=c["a0"], fb_variation=c["fb_variation"],
        coef_variation=c["coef_variation"], noise=c["noise"], effects=effects, system=system,
        extra_phases=extra_phases, phases_given=phases_given,
        variation=variation, all_blf=np.concatenate([c["blf"], extra_blf]),
        all_phases=np.concatenate([phases, extra_phases]),
    )
    settings.phase_variation = _phase_variation(phase_variation, c["coef_variation"], variation)
    if variation == "pulses":
        _check_pulses(settings)
    return settings


def _phase_variation(value, coef_variation: float, variation: str) -> float:
    """``phase_variation`` checked (rad, 0-1, only with the jumps variation); None is ``coef_variation``."""
    if value is None:
        return coef_variation
    if variation != "jumps":
        raise OptionError(f"simulate_bouncing: phase_variation is a setting of variation='jumps', not {variation!r}")
    value = _number(value, "phase_variation", nonnegative=True)
    if value > 1.0:
        raise OptionError(f"simulate_bouncing: phase_variation must be 0-1 (rad), got {value!r}")
    return value


def _check_numbers(mass, f_b, f_h, xi_h, duration, fs, blf, a0, fb_variation, coef_variation, noise, variation):
    """The numeric arguments and the variation, checked one by one and against each other.

    Returns
    -------
    dict
        ``mass, f_b, f_h, xi_h, duration, fs, a0, fb_variation,
        coef_variation, noise`` as floats (``mass`` checked as a body mass),
        ``blf`` as an array of amplitudes >= 0 and ``variation``.

    Raises
    ------
    MassError, OptionError
        The first argument that is not a valid value, a variation out of
        range, or a record shorter than one bouncing cycle.
    """
    mass = check_mass(mass, source="mass")
    f_b = _number(f_b, "f_b (Hz)", positive=True)
    f_h = _number(f_h, "f_h (Hz)", positive=True)
    xi_h = _number(xi_h, "xi_h", positive=True)
    duration = _number(duration, "duration (s)", positive=True)
    fs = _number(fs, "fs (Hz)", positive=True)
    blf = _vector(blf, "blf (g)", nonnegative=True)
    a0 = _number(a0, "a0 (g)")
    fb_variation = _number(fb_variation, "fb_variation", nonnegative=True)
    coef_variation = _number(coef_variation, "coef_variation", nonnegative=True)
    noise = _number(noise, "noise", nonnegative=True)
    if fb_variation > 0.2:
        raise OptionError(f"simulate_bouncing: fb_variation must be 0-0.2 (relative), got {fb_variation!r}")
    if coef_variation > 1.0:
        raise OptionError(f"simulate_bouncing: coef_variation must be 0-1 (relative), got {coef_variation!r}")
    if not isinstance(variation, str) or variation not in VARIATIONS:
        raise OptionError(
            f"simulate_bouncing: variation must be one of {', '.join(map(repr, VARIATIONS))}, got {variation!r}"
        )
    if variation == "tempo" and fb_variation > TEMPO_MAX_FB_VARIATION:
        raise OptionError(f"simulate_bouncing: fb_variation must be 0-{TEMPO_MAX_FB_VARIATION:g} with "
                          f"variation='tempo', got {fb_variation!r}")
    if duration < 1.0 / f_b:
        raise OptionError(
            f"simulate_bouncing: duration {duration:g} s is shorter than one bouncing cycle (1/f_b = {1 / f_b:.3g} s)"
        )
    return dict(mass=mass, f_b=f_b, f_h=f_h, xi_h=xi_h, duration=duration, fs=fs, blf=blf, a0=a0,
                fb_variation=fb_variation, coef_variation=coef_variation, noise=noise, variation=variation)


def _split_effects(effects, f_h, xi_h):
    """The prepared effects split into extra force harmonics and the integrated system.

    Returns
    -------
    system : _System
        Eq. 2 with the effects that have their own dynamics or terms.
    extra : list of (blf, phases)
        The extra force harmonics of the effects that have them (the
        ``harmonics`` effect), in the effects' order; ``phases`` None when
        not given.
    """
    person = SMDModel(n_harmonics=1)
    forcing = [force_harmonics(effect, person) for effect in effects]
    extra = [pair for pair in forcing if pair is not None]
    system = _System(f_h, xi_h, [effect for effect, pair in zip(effects, forcing) if pair is None])
    return system, extra


def _check_sampling(fs, f_b, system, n_base, n_extra):
    """Raise an OptionError when ``fs`` is below 4 x the highest harmonic or natural frequency of the record."""
    natural = np.abs(system.eigenvalues().imag).max() / (2.0 * np.pi) if system.effects else 0.0
    highest = max((n_base + n_extra) * f_b, natural)
    if fs < 4.0 * highest:
        raise OptionError(
            f"simulate_bouncing: fs {fs:g} Hz is too low; it must be at least 4 x the highest frequency "
            f"({highest:g} Hz), i.e. >= {4 * highest:g} Hz"
        )


def _force_phases(phases, checked, extra_blf, extra):
    """The phases of the base and extra harmonics: given, or :func:`default_phases`.

    Returns
    -------
    phases : ndarray
        Base harmonics' phases (rad).
    extra_phases : ndarray
        Extra harmonics' phases (rad): each effect's given ones or the defaults.
    phases_given : bool
        Whether the base phases were given.
    """
    c = checked
    n_base = c["blf"].size
    given_extra = [pair[1] for pair in extra]
    default_base, default_extra = default_phases(c["blf"], c["f_b"], c["f_h"], c["xi_h"], extra_blf)
    phases_given = phases is not None
    if phases is None:
        phases = default_base
    else:
        phases = _vector(phases, "phases (rad)")
        if phases.size != n_base:
            raise OptionError(f"simulate_bouncing: phases has {phases.size} values, blf has {n_base}")
    extra_phases = np.asarray(default_extra, dtype=float)
    if any(given is not None for given in given_extra):
        extra_phases = np.concatenate([default_extra[:len(pair[0])] if given is None else np.asarray(given, float)
                                       for pair, given in zip(extra, given_extra)])
    return phases, extra_phases, phases_given

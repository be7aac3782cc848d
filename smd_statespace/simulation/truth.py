"""The truth of a simulated record: the JSON-serialisable settings and derived values behind it.

:func:`_truth` is :attr:`SyntheticRecord.truth
<smd_statespace.simulation.synthetic.SyntheticRecord>`: the person (Eq. 17-18),
the force, the effects with all their parameters (:func:`_effects_truth`),
the seed and the variation's settings.
"""

from __future__ import annotations

from ..model import SMDModel, c_h, k_h
from .effect_adapter import force_harmonics, simulation_truth
from .variation import SMOOTH_CORRELATION_CYCLES, TRUNCATION_SD


def _effects_truth(settings):
    """``{name: {key: value}}`` of the simulated effects, with the extra harmonics' phases as simulated."""
    out = {}
    for effect in settings.effects:
        truth = {key: (list(value) if isinstance(value, tuple) else value)
                 for key, value in simulation_truth(effect).items()}
        if "phases" in truth and force_harmonics(effect, SMDModel(n_harmonics=1)) is not None:
            truth["phases"] = [float(v) for v in settings.extra_phases]
        out[effect.name] = truth
    return out


def _truth(settings, seed_record, n_cycles, generator=None):
    """The JSON-serialisable truth of :attr:`SyntheticRecord.truth`.

    ``generator`` (the generators of :mod:`.generators`) holds the truth's
    ``variations`` and, for ``"pulses"``, its ``blf`` and ``phases``.
    """
    s = settings
    generator = generator or {}
    variations = generator.get("variations") or {
        "fb_variation": s.fb_variation,
        "coef_variation": s.coef_variation,
        "phase_jitter_rad": s.phase_variation,
        "truncation_sd": TRUNCATION_SD,
        "generator": s.variation,
    }
    if s.variation in ("smooth", "matern"):
        variations["correlation_cycles"] = SMOOTH_CORRELATION_CYCLES
        variations["correlation_time_s"] = SMOOTH_CORRELATION_CYCLES / s.f_b
    return {
        "source": "smd_statespace.simulation.simulate_bouncing",
        "mass": s.mass,
        "f_b": s.f_b,
        "f_h": s.f_h,
        "xi_h": s.xi_h,
        "K_h": float(k_h(s.f_h, s.mass)),  # Eq. 17
        "C_h": float(c_h(s.xi_h, s.f_h, s.mass)),  # Eq. 18
        "n_harmonics": int(s.blf.size),
        "n_force_harmonics": int(s.all_blf.size),
        "blf": generator.get("blf", [float(v) for v in s.blf]),
        "phases": generator.get("phases", [float(v) for v in s.phases]),
        "a0": s.a0,
        "effects": _effects_truth(s),
        "seed": seed_record,
        "fs": s.fs,
        "duration": s.duration,
        "noise": s.noise,
        "variations": variations,
        "n_cycles": int(n_cycles),
        "units": {
            "mass": "kg", "f_b": "Hz", "f_h": "Hz", "xi_h": "-", "K_h": "N/m", "C_h": "N*s/m",
            "blf": "g", "a0": "g", "phases": "rad", "fs": "Hz", "duration": "s", "noise": "body weight",
        },
    }

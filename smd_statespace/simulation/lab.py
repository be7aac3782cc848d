"""Force-plate records as a lab exports them: a person standing, bouncing and standing again, with known truth.

:func:`simulate_lab_record` makes the export of a whole trial: the person stands (swaying a little), ramps
up, bounces and tires, ramps down and stands again, on a plate with mains hum, a drifting zero and white
noise; :func:`simulate_typical_lab_record` draws all of it over wide ranges declared in one place
(:class:`LabRanges`). The force (N) is Eq. 3 plus the plate's extras, ``GRF = M_h (g + u'') + sway + hum +
drift + e``, with ``u''`` of Eq. 2 under the enveloped, tiring force,
``u'' + 2 xi_h(t) w_h(t) u' + w_h(t)^2 u = g S(t) F(tau(t))``, ``w_h = 2 pi f_h(t)``, integrated with
:func:`scipy.integrate.solve_ivp` (DOP853, ``rtol`` :data:`~.dynamics.RTOL`), restarted at every jump of the
force and every kink of the schedule:

- ``F(tau)`` (g, Eq. 4) is a force of :func:`simulate_bouncing`'s ``"jumps"``, ``"smooth"`` or ``"matern"`` variation
  (:data:`LAB_VARIATIONS`), made by the same code (:mod:`.variation`) in the person's own time ``tau``;
- ``S(t) = E(t) (1 - tire p(t))``: the envelope ``E`` is 0 while standing, a raised cosine up to 1 over
  ``ramp_up`` cycles, 1 through the bout, a raised cosine back to 0 over ``ramp_down`` cycles; ``p(t)``, the
  progress through the full bout (0 to 1, held outside it), makes every BLF fall by the fraction ``tire``;
- ``tau(t) = int (1 - slow p) dt``: the person's clock slows, ``f_b`` falls to ``f_b (1 - slow)``;
- ``f_h(t)``, ``xi_h(t)``: constant, or changed by the fractions ``f_h_change``, ``xi_h_change`` linearly
  over the bout (``change="drift"``) or at once at ``change_time`` (``"step"``);
- while standing ``S = 0`` and the person is at rest (``u = u' = u'' = 0``): the force is ``M_h g`` plus
  the extras. ``sway``: sinusoids in :data:`SWAY_BAND` (N RMS), faded out as the person bounces; ``hum``:
  the mains frequency and its harmonics, optionally slowly modulated; ``drift``: the plate's zero, 0 at
  ``t = 0``, reaching ``+-drift`` N, a random cubic (Legendre) polynomial of time or another of
  ``drift_shape`` (:mod:`.plate_extras`); ``e``: white noise of sd ``noise`` N.

One :class:`numpy.random.SeedSequence` spawns independent streams (:data:`STREAMS`): the same seed gives the
same record; other hum leaves the person unchanged.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import OptionError
from ..io import G, check_mass, make_record
from ..model import c_h, equations, k_h
from .dynamics import ATOL, RTOL, _CycleForce, _number, _simulation_effects, _System, _vector
from .effect_adapter import force_harmonics
from .force_shape import DEFAULT_BLF, default_phases
from .plate_extras import DRIFT_SHAPES, SWAY_BAND, drift_path, hum_force, sway_force
from .generators import _normals
from .settings import _resolve_seed
from .synthetic import SyntheticRecord
from .truth import _effects_truth
from .variation import (SMOOTH_KERNELS, TRUNCATION_SD, _cycles_frame, _draw_cycles, _smooth_cycles, _smooth_force,
                        _smooth_geometry)

__all__ = ["LAB_VARIATIONS", "LAB_CHANGES", "SWAY_BAND", "LabRanges", "LAB_RANGES", "simulate_lab_record",
           "draw_lab_settings", "simulate_typical_lab_record"]

LAB_VARIATIONS = ("jumps", "smooth", "matern")
"""Generators of the cycle-to-cycle force variation a lab record can use (those of :mod:`.variation`)."""

LAB_CHANGES = ("drift", "step")
"""How ``f_h`` and ``xi_h`` change over the bout: linearly over it, or at once at ``change_time``."""

FS_RANGE = (200.0, 10000.0)
"""Accepted sampling rates (Hz) of a lab record."""

STREAMS = ("force", "sway", "hum", "drift", "noise")
"""The independent random streams spawned from a record's seed, in spawn order."""


# ---------------------------------------------------------------------------
# the schedule: envelope, tiring, slowing, f_h(t), xi_h(t)


@dataclass(frozen=True)
class _Schedule:
    """Times (s) of the bout and the slow changes of the person over it (see the module docstring)."""

    t_on: float
    t_full: float
    t_down: float
    t_off: float
    tire: float
    slow: float
    f_h: tuple
    xi_h: tuple
    change: str
    t_change: float

    def envelope(self, t):
        """The envelope ``E`` at one time ``t`` (s): raised cosines up over the ramp-up, down over the ramp-down."""
        up = min(max((t - self.t_on) / (self.t_full - self.t_on), 0.0), 1.0)
        down = min(max((self.t_off - t) / (self.t_off - self.t_down), 0.0), 1.0)
        return 0.25 * (1.0 - math.cos(math.pi * up)) * (1.0 - math.cos(math.pi * down))

    def at(self, t):
        """``(S, tau, f_h, xi_h)`` at one time ``t`` (s), in plain floats: the ODE solver's fast path."""
        span = self.t_down - self.t_full
        x = min(max(t - self.t_full, 0.0), span)
        progress = x / span
        envelope = self.envelope(t)
        tau = t - self.slow * (x * x / (2.0 * span) + max(t - self.t_down, 0.0))
        weight = progress if self.change == "drift" else float(t >= self.t_change)
        f_h = self.f_h[0] + weight * (self.f_h[1] - self.f_h[0])
        xi_h = self.xi_h[0] + weight * (self.xi_h[1] - self.xi_h[0])
        return envelope * (1.0 - self.tire * progress), tau, f_h, xi_h

    def arrays(self, t):
        """``(S, tau, f_h, xi_h)`` at times ``t`` (s), arrays of the shape of ``t``."""
        return np.vectorize(self.at, otypes=[float] * 4)(np.asarray(t, dtype=float))

    def t_of_tau(self, tau):
        """Times ``t`` (s) at which the person's clock reads ``tau`` (Newton's method; ``tau(t)`` is concave)."""
        target = t = np.asarray(tau, dtype=float)
        for _ in range(60):
            rate = 1.0 - self.slow * np.clip((t - self.t_full) / (self.t_down - self.t_full), 0.0, 1.0)
            step = (self.arrays(t)[1] - target) / rate
            t = t - step
            if np.all(np.abs(step) < 1e-12):
                return t
        return t  # pragma: no cover

    def breaks(self):
        """Times (s) where the schedule has a kink or a jump: the integration restarts there."""
        times = [self.t_on, self.t_full, self.t_down, self.t_off]
        if self.change == "step":
            times.append(self.t_change)
        return sorted(set(times))

    def means(self):
        """``(f_h, xi_h)`` averaged over the full bout (``t_full`` to ``t_down``)."""
        weight = 0.5 if self.change == "drift" else (self.t_down - self.t_change) / (self.t_down - self.t_full)
        return tuple(float(p[0] + weight * (p[1] - p[0])) for p in (self.f_h, self.xi_h))


_NO_FORCE = _CycleForce(0.0, 1.0, 0.0, [0.0], [0.0])
"""The force after the bout (the envelope is 0 there)."""


# ---------------------------------------------------------------------------
# the person's force in their own time, by the generators of .variation


def _bout_force(rng, variation, span, f_b, blf, phases, fb_variation, coef_variation):
    """The force of Eq. 4 over ``tau`` in ``[0, span]`` s: ``(cycles, pieces)``; ``a0`` 0 (weight carried).

    ``cycles`` is ``(t_start, t_end, f_b, a, b)`` in the person's time (``"smooth"``: cycle averages);
    ``pieces`` lists ``(tau_start, tau_end, force)``: one per cycle with ``"jumps"`` (the force jumps at its
    boundaries), one for the whole span with ``"smooth"`` and ``"matern"``.
    """
    m = blf.size
    if variation == "jumps":
        longest, shortest = (1.0 / (f_b * (1.0 + sign * TRUNCATION_SD * fb_variation)) for sign in (-1.0, 1.0))
        n_rows = int(np.ceil((span + longest) / shortest)) + 2
        blocks = (rng.random(), _normals(rng, n_rows), _normals(rng, (n_rows, m)), _normals(rng, (n_rows, m)))
        t_start, t_end, frequency, amplitude, phase = _draw_cycles(blocks, span, f_b, blf, phases, fb_variation,
                                                                   coef_variation)
        a, b = amplitude * np.cos(phase), amplitude * np.sin(phase)
        pieces = [(t_start[j], t_end[j], _CycleForce(t_start[j], frequency[j], 0.0, a[j], b[j]))
                  for j in range(t_start.size)]
        return (t_start, t_end, frequency, a, b), pieces
    geometry = _smooth_geometry(span, f_b, fb_variation, SMOOTH_KERNELS[variation])
    n_knots = geometry[1]
    blocks = (rng.random(), _normals(rng, n_knots), _normals(rng, (n_knots, m)), _normals(rng, (n_knots, m)))
    force = _smooth_force(blocks, np.empty((0, 1 + 2 * m)), geometry, f_b, fb_variation, 0.0, blf, phases,
                          coef_variation, SMOOTH_KERNELS[variation])
    cycles = _smooth_cycles(force, 0, span)
    return cycles, [(cycles[0][0], cycles[1][-1], force)]


def _pieces_in_time(schedule, pieces, t_end):
    """``(t_start, t_end, force)`` pieces in lab time from ``t_on`` to ``t_end``, split at the schedule's breaks."""
    edges = np.array([piece[0] for piece in pieces] + [pieces[-1][1]])
    times = schedule.t_of_tau(edges)
    cuts = np.concatenate([times, schedule.breaks(), [t_end]])
    cuts = np.unique(cuts[(cuts >= schedule.t_on) & (cuts <= t_end)])
    out = []
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        if hi - lo < 1e-12:
            continue
        if lo >= schedule.t_off:
            out.append((lo, hi, _NO_FORCE))
            continue
        index = min(max(int(np.searchsorted(times, 0.5 * (lo + hi), side="right")) - 1, 0), len(pieces) - 1)
        out.append((lo, hi, pieces[index][2]))
    return out


def _effects_system(effects, s):
    """The person's equation of motion with ``effects`` (a ``dynamics._System``), None without; an effect that is
    more than terms in it is refused in one line."""
    built = _simulation_effects(effects, s["mass"], where="simulate_lab_record")
    if not built:
        return None
    system = _System(s["f_h"], s["xi_h"], built)
    for effect in built:
        if force_harmonics(effect, system.model) is not None or any(
                slot.kind == "dynamic" for slot in effect.slots(system.model)):
            raise OptionError(f"simulate_lab_record: effect {effect.name!r} adds force harmonics or states of its "
                              "own, which a lab record does not simulate (simulate_bouncing does: simulate without "
                              "--lab)")
    return system


def _integrate(schedule, pieces, time, system=None):
    """``(u, u_dot, u_ddot, force_bio, f_h, xi_h)`` at ``time`` (m, m/s, m/s^2, m/s^2, Hz, -): Eq. 2 from rest,
    with the terms of ``system``'s effects where given."""
    from scipy.integrate import solve_ivp  # imported here: with scipy.optimize, 0.3 s (not needed to start)

    def rhs(t, x, force):
        scale, tau, f_h, xi_h = schedule.at(t)
        if system is not None:
            return system.rates(np.asarray(x, dtype=float), G * scale * force.scalar(tau), t, f_h, xi_h)[0]
        return [x[1], equations.smd_acceleration(x[0], x[1], f_h, xi_h, G * scale * force.scalar(tau))]  # Eq. 2

    states = np.zeros((2, time.size))
    force_bio = np.zeros(time.size)
    state = np.zeros(2)  # at rest while standing
    for lo, hi, force in pieces:
        inside = np.flatnonzero((time >= lo) & (time < hi))
        solution = solve_ivp(rhs, (lo, hi), state, method="DOP853", t_eval=np.append(time[inside], hi),
                             rtol=RTOL, atol=ATOL, args=(force,))
        if solution.status != 0 or not np.all(np.isfinite(solution.y)):
            raise OptionError(f"simulate_lab_record: integration failed at t={lo:.3f} s ({solution.message})")
        states[:, inside], state = solution.y[:, :-1], solution.y[:, -1]
        scale, tau = schedule.arrays(time[inside])[:2]
        force_bio[inside] = G * scale * force(tau)
    _, _, f_h, xi_h = schedule.arrays(time)
    u_ddot = (equations.smd_acceleration(states[0], states[1], f_h, xi_h, force_bio) if system is None  # Eq. 2
              else system.rates(states, force_bio, time, f_h, xi_h)[1])
    return states[0], states[1], u_ddot, force_bio, f_h, xi_h


# ---------------------------------------------------------------------------
# checks, seed, truth


def _check_lab(s):
    """Refuse invalid settings (a dict of :func:`simulate_lab_record`'s arguments) naming the first; fill them."""
    where = "simulate_lab_record"
    s["mass"] = check_mass(s["mass"], source="mass")
    for name in ("f_b", "f_h", "xi_h", "bout", "ramp_up", "ramp_down", "fs"):
        s[name] = _number(s[name], name, positive=True, where=where)
    for name in ("stand_before", "stand_after", "fb_variation", "coef_variation", "sway", "drift", "noise",
                 "hum_variation", "tire", "slow"):
        s[name] = _number(s[name], name, nonnegative=True, where=where)
    for name in ("f_h_change", "xi_h_change"):
        s[name] = _number(s[name], name, where=where)
    s["blf"] = _vector(s["blf"], "blf (g)", nonnegative=True, where=where)
    s["hum"] = _vector(s["hum"], "hum (N)", nonnegative=True, where=where) if np.size(s["hum"]) else np.zeros(0)
    limits = (("fb_variation", 0.2), ("coef_variation", 1.0), ("hum_variation", 1.0), ("tire", 0.9),
              ("slow", 0.5), ("ramp_up", 10.0), ("ramp_down", 10.0), ("f_h_change", 1.0), ("xi_h_change", 2.0))
    for name, top in limits:
        if s[name] > top or (name.endswith("_change") and s[name] <= -0.9):
            low = "-0.9 (exclusive)" if name.endswith("_change") else "0"
            raise OptionError(f"{where}: {name} must be {low} to {top:g}, got {s[name]!r}")
    if s["variation"] not in LAB_VARIATIONS:
        raise OptionError(f"{where}: variation must be one of {', '.join(map(repr, LAB_VARIATIONS))}, "
                          f"got {s['variation']!r}")
    if s["drift_shape"] not in DRIFT_SHAPES:
        raise OptionError(f"{where}: drift_shape must be one of {', '.join(map(repr, DRIFT_SHAPES))}, "
                          f"got {s['drift_shape']!r}")
    if s["change"] not in LAB_CHANGES:
        raise OptionError(f"{where}: change must be one of {', '.join(map(repr, LAB_CHANGES))}, got {s['change']!r}")
    if not FS_RANGE[0] <= s["fs"] <= FS_RANGE[1]:
        raise OptionError(f"{where}: fs {s['fs']:g} Hz is outside {FS_RANGE[0]:g}-{FS_RANGE[1]:g} Hz")
    if s["hum_frequency"] not in (50, 60):
        raise OptionError(f"{where}: hum_frequency must be 50 or 60 (Hz, the mains), got {s['hum_frequency']!r}")
    if s["hum"].size and s["hum"].size * s["hum_frequency"] >= 0.4 * s["fs"]:
        raise OptionError(f"{where}: fs {s['fs']:g} Hz is too low for {s['hum'].size} hum harmonics of "
                          f"{s['hum_frequency']:g} Hz; give fs > {2.5 * s['hum'].size * s['hum_frequency']:g} Hz")
    if s["bout"] < 1.0 / s["f_b"]:
        raise OptionError(f"{where}: bout {s['bout']:g} s is shorter than one bouncing cycle ({1 / s['f_b']:.3g} s)")
    if s["phases"] is None:
        s["phases"] = default_phases(s["blf"], s["f_b"], s["f_h"], s["xi_h"])[0]
    s["phases"] = _vector(s["phases"], "phases (rad)", where=where)
    if s["phases"].size != s["blf"].size:
        raise OptionError(f"{where}: phases has {s['phases'].size} values, blf has {s['blf'].size}")
    return s


def _schedule(s):
    """The :class:`_Schedule` of checked settings ``s``, and the record's length (s)."""
    t_on = s["stand_before"]
    t_full = t_on + s["ramp_up"] / s["f_b"]
    t_down = t_full + s["bout"]
    t_off = t_down + s["ramp_down"] / (s["f_b"] * (1.0 - s["slow"]))
    t_change = 0.5 * (t_full + t_down) if s["change_time"] is None else s["change_time"]
    if s["change"] == "step" and not t_full <= t_change <= t_down:
        raise OptionError(f"simulate_lab_record: change_time {t_change!r} s must lie in the bout, "
                          f"{t_full:.3f}-{t_down:.3f} s")
    schedule = _Schedule(t_on, t_full, t_down, t_off, s["tire"], s["slow"],
                         (s["f_h"], s["f_h"] * (1.0 + s["f_h_change"])),
                         (s["xi_h"], s["xi_h"] * (1.0 + s["xi_h_change"])), s["change"], float(t_change))
    return schedule, t_off + s["stand_after"]


def _seed_sequence(seed):
    """``(SeedSequence, JSON-able record)`` of ``seed``, by :func:`simulate_bouncing`'s policy (:mod:`.settings`)."""
    rng, record = _resolve_seed(seed)
    return rng.bit_generator.seed_seq, record


def _lab_truth(s, schedule, duration, seed_record, extras, n_cycles):
    """The JSON-able truth of a lab record (see :func:`simulate_lab_record`)."""
    f_h, xi_h = schedule.means()
    changed = s["f_h_change"] != 0 or s["xi_h_change"] != 0
    blf = s["blf"]
    return {
        "source": "smd_statespace.simulation.simulate_lab_record",
        "mass": s["mass"], "f_b": s["f_b"] * (1.0 - 0.5 * s["slow"]), "f_b_start": s["f_b"],
        "f_b_end": s["f_b"] * (1.0 - s["slow"]), "f_h": f_h, "f_h_start": schedule.f_h[0],
        "f_h_end": schedule.f_h[1], "xi_h": xi_h, "xi_h_start": schedule.xi_h[0], "xi_h_end": schedule.xi_h[1],
        "K_h": float(k_h(f_h, s["mass"])), "C_h": float(c_h(xi_h, f_h, s["mass"])),  # Eq. 17-18, of the means
        "change": {"kind": s["change"] if changed else "none", "f_h": s["f_h_change"], "xi_h": s["xi_h_change"],
                   "time_s": schedule.t_change if changed and s["change"] == "step" else None},
        "n_harmonics": int(blf.size), "n_force_harmonics": int(blf.size),
        "blf": (blf * (1.0 - 0.5 * s["tire"])).tolist(), "blf_start": blf.tolist(),
        "blf_end": (blf * (1.0 - s["tire"])).tolist(), "phases": s["phases"].tolist(), "a0": 0.0,
        "tire": s["tire"], "slow": s["slow"],
        "span": {"bouncing_start_s": schedule.t_on, "full_start_s": schedule.t_full, "full_end_s": schedule.t_down,
                 "bouncing_end_s": schedule.t_off, "ramp_up_cycles": s["ramp_up"],
                 "ramp_down_cycles": s["ramp_down"], "stand_before_s": s["stand_before"],
                 "stand_after_s": s["stand_after"], "bout_s": s["bout"]},
        **extras,
        "noise": s["noise"] / (s["mass"] * G), "noise_n": s["noise"], "effects": {}, "seed": seed_record,
        "fs": s["fs"], "duration": duration,
        "variations": {"fb_variation": s["fb_variation"], "coef_variation": s["coef_variation"],
                       "phase_jitter_rad": s["coef_variation"], "truncation_sd": TRUNCATION_SD,
                       "generator": s["variation"]},
        "n_cycles": int(n_cycles),
        "units": {"mass": "kg", "f_b": "Hz", "f_h": "Hz", "xi_h": "-", "K_h": "N/m", "C_h": "N*s/m", "blf": "g",
                  "phases": "rad", "span": "s", "fs": "Hz", "duration": "s", "noise": "body weight",
                  "noise_n": "N", "tire": "fraction of the BLFs lost over the bout",
                  "slow": "fraction of f_b lost over the bout"},
    }


def _cycles_in_time(schedule, cycles):
    """The force cycles that act in lab time (a :func:`_cycles_frame` table plus ``scale, f_h, xi_h``).

    Boundaries mapped from the person's time, ``f_b = 1 / (t_end - t_start)``; coefficients the generator's
    times ``scale`` (``S`` at the cycle's middle); ``f_h``, ``xi_h`` their values there.
    """
    t_start, t_end, _, a, b = cycles
    starts, ends = schedule.t_of_tau(t_start), schedule.t_of_tau(t_end)
    keep = (ends > schedule.t_on) & (starts < schedule.t_off)
    starts, ends, a, b = starts[keep], ends[keep], a[keep], b[keep]
    scale, _, f_h, xi_h = schedule.arrays(0.5 * (starts + ends))
    a, b = a * scale[:, None], b * scale[:, None]
    frame = _cycles_frame(starts, ends, 1.0 / (ends - starts), 0.0, a, b, np.hypot(a, b))
    return frame.assign(scale=scale, f_h=f_h, xi_h=xi_h)


def simulate_lab_record(mass=70.0, f_b=2.0, f_h=2.5, xi_h=0.3, *, blf=DEFAULT_BLF, phases=None, variation="jumps",
                        fb_variation=0.02, coef_variation=0.10, fs=1000.0, stand_before=4.0, stand_after=4.0,
                        bout=30.0, ramp_up=2.0, ramp_down=2.0, sway=2.0, hum_frequency=50, hum=(5.0, 0.0, 2.0),
                        hum_variation=0.0, drift=10.0, noise=1.0, tire=0.0, slow=0.0, f_h_change=0.0,
                        xi_h_change=0.0, change="drift", change_time=None, drift_shape="cubic",
                        effects=None, seed=None) -> SyntheticRecord:
    """Simulate a lab's force-plate export of one trial: standing, bouncing, standing, with the plate's artefacts.

    The person is the SMD of Eq. 2 (the module docstring gives every term); the GRF is Eq. 3 plus sway, hum,
    drift and noise. Times in s, forces in N, BLFs in g.

    Parameters
    ----------
    mass, f_b, f_h, xi_h : float
        Body mass ``M_h`` (kg); at the start of the bout, bouncing and SMD
        natural frequencies (Hz) and damping ratio (-).
    blf : sequence of float
        ``BLF_1..BLF_n`` at the start of the bout (g, Eq. 5).
    phases : sequence of float, optional
        Harmonic phases (rad); default :func:`default_phases` (a realistic GRF shape).
    variation : {"jumps", "smooth", "matern"}
        Cycle-to-cycle variation of the force, as in :func:`simulate_bouncing` (:data:`LAB_VARIATIONS`), with
        ``fb_variation`` (0-0.2) and ``coef_variation`` (0-1).
    fs : float
        Sampling rate (Hz), :data:`FS_RANGE`.
    stand_before, stand_after : float
        Standing still before and after bouncing (s).
    bout : float
        Full bouncing between the ramps (s).
    ramp_up, ramp_down : float
        Length of the ramps of the force's amplitude, in cycles (up to 10).
    sway : float
        RMS of the standing sway force (N), below :data:`SWAY_BAND` Hz.
    hum_frequency, hum, hum_variation : {50, 60}, sequence of float, float
        Mains frequency (Hz); hum amplitudes at it and its harmonics 2, 3,
        ... (N; empty for none); their relative slow modulation, 0-1.
    drift, noise : float
        Largest excursion of the plate's drifting zero (N); white noise sd (N).
    drift_shape : {"cubic", "settling", "walk", "steps"}
        The drifting zero's shape (:func:`~smd_statespace.simulation.plate_extras.drift_path`).
    effects : list of Effect or str, or dict, optional
        Physical effects beyond the base model acting on the person, as in :func:`simulate_bouncing`, each
        with its terms in the equation of motion alone (a cubic spring, a quadratic damper, a generic term);
        one with states of its own (a floor mode) or force harmonics is refused (simulate it with
        :func:`simulate_bouncing`). Its terms read ``f_h`` and ``xi_h`` as they change over the bout.
    tire, slow : float
        Fractions of every BLF (0-0.9) and of ``f_b`` (0-0.5) lost linearly over the bout.
    f_h_change, xi_h_change, change, change_time : float, float, {"drift", "step"}, float
        Relative changes of ``f_h``, ``xi_h`` over the bout (e.g. 0.14;
        above -0.9), linear over it or a step at ``change_time`` (s, within
        the bout; default its middle).
    seed : None, int or numpy.random.SeedSequence
        Root of the record's random streams (:data:`STREAMS`); None draws fresh entropy, kept in the truth.

    Returns
    -------
    SyntheticRecord
        ``record`` (the plate's export); ``states`` per sample (``time, cycle, u, u_dot, u_ddot, force_bio``
        as :func:`simulate_bouncing`'s, plus ``scale`` ``S(t)``, ``f_h``, ``xi_h``, ``sway``, ``hum``,
        ``drift`` in N; ``cycle`` -1 outside the force's cycles); ``cycles``, the force cycles in lab time
        (:func:`_cycles_in_time`); ``truth``: the person (``f_h``, ``xi_h``, ``f_b``, ``blf`` as means over
        the bout with their ``_start`` and ``_end`` values; ``K_h``, ``C_h`` of the means, Eq. 17-18),
        ``change``, ``span`` (the bout's times), ``hum``, ``drift`` (its path: start, end, at the bouncing's
        start and end), ``sway``, ``noise`` (body weights, as :func:`simulate_bouncing`) and ``noise_n`` (N),
        ``fs``, ``duration``, ``seed``, ``variations``, ``effects`` (``{name: {key: value}}``).

    Raises
    ------
    MassError
        Implausible body mass.
    OptionError
        Any other invalid argument (the message names it), or a GRF below zero (the person would leave the plate).
    """
    import pandas as pd  # imported here: the command line imports this module to start

    s = _check_lab({key: value for key, value in locals().items() if key not in ("seed", "effects")})
    system = _effects_system(effects, s)
    schedule, duration = _schedule(s)
    sequence, seed_record = _seed_sequence(seed)
    rngs = dict(zip(STREAMS, (np.random.default_rng(child) for child in sequence.spawn(len(STREAMS)))))
    time = np.arange(int(np.floor(duration * s["fs"] + 1e-9)) + 1) / s["fs"]
    cycles, pieces = _bout_force(rngs["force"], s["variation"], schedule.at(schedule.t_off)[1], s["f_b"], s["blf"],
                                 s["phases"], s["fb_variation"], s["coef_variation"])
    u, u_dot, u_ddot, force_bio, f_h_t, xi_h_t = _integrate(
        schedule, _pieces_in_time(schedule, pieces, time[-1] + 0.5 / s["fs"]), time, system)
    person = s["mass"] * (G + u_ddot)  # Eq. 3
    if person.min() <= 0.0:
        raise OptionError(f"simulate_lab_record: the GRF falls to {person.min():.1f} N: the person would leave the "
                          "plate; lower blf or move f_h away from a harmonic of f_b")
    envelope = np.vectorize(schedule.envelope, otypes=[float])(time)
    sway_n, sway_truth = sway_force(rngs["sway"], time, s["sway"], envelope)
    hum_n, hum_truth = hum_force(rngs["hum"], time, float(s["hum_frequency"]), s["hum"], s["hum_variation"])
    drift_n, drift_truth = drift_path(rngs["drift"], time, s["drift"], s["drift_shape"])
    drift_truth.update(at_bouncing_start_n=float(np.interp(schedule.t_on, time, drift_n)),
                       at_bouncing_end_n=float(np.interp(schedule.t_off, time, drift_n)))
    force = person + sway_n + hum_n + drift_n + s["noise"] * rngs["noise"].standard_normal(time.size)
    table = _cycles_in_time(schedule, cycles)
    cycle = np.searchsorted(table["t_start"].to_numpy(), time, side="right") - 1
    cycle[(time >= table["t_end"].to_numpy()[-1]) | (cycle < 0)] = -1
    states = pd.DataFrame({"time": time, "cycle": cycle, "u": u, "u_dot": u_dot, "u_ddot": u_ddot,
                           "force_bio": force_bio, "scale": schedule.arrays(time)[0], "f_h": f_h_t, "xi_h": xi_h_t,
                           "sway": sway_n, "hum": hum_n, "drift": drift_n})
    extras = {"hum": hum_truth, "drift": drift_truth, "sway": sway_truth}
    truth = _lab_truth(s, schedule, float(time[-1]), seed_record, extras, len(table))
    if system is not None:
        truth["effects"] = _effects_truth(system)
    return SyntheticRecord(record=make_record(time, force, s["mass"], source="simulate_lab_record"), truth=truth,
                           states=states, cycles=table)


# ---------------------------------------------------------------------------
# typical lab records


@dataclass(frozen=True)
class LabRanges:
    """What :func:`draw_lab_settings` draws, and from where: one place, so a benchmark can hold out combinations.

    A pair ``(lo, hi)`` is drawn uniformly (units of :func:`simulate_lab_record`); ``variation``, ``fs``,
    ``hum_frequency``, ``change`` are equally likely choices; ``blf``, ``hum`` hold a pair per harmonic.
    ``f_h_change``, ``xi_h_change`` are magnitudes with a random sign (0 when ``change`` is ``"none"``); a step
    comes at the fraction ``step_at`` of the bout; ``stand``, ``ramp`` are drawn for before and after apart. A
    draw whose steady dynamic GRF (the BLFs through Eq. 2 at the extremes of ``f_h``, ``xi_h``, grown by two
    ``coef_variation``) could exceed ``max_peak_g`` body weights is drawn again.
    """

    mass: tuple = (45.0, 120.0)
    f_b: tuple = (1.4, 3.6)
    f_h: tuple = (1.4, 4.5)
    xi_h: tuple = (0.08, 0.8)
    blf: tuple = ((0.05, 0.45), (0.02, 0.3), (0.0, 0.1), (0.0, 0.04))
    variation: tuple = ("jumps", "smooth")  # not "matern": a study's generator, and the draws stay as they were
    fb_variation: tuple = (0.0, 0.05)
    coef_variation: tuple = (0.02, 0.2)
    fs: tuple = (500.0, 1000.0, 1200.0, 2000.0)
    stand: tuple = (2.0, 8.0)
    bout: tuple = (20.0, 40.0)
    ramp: tuple = (1.0, 3.0)
    sway: tuple = (0.3, 6.0)
    hum_frequency: tuple = (50, 60)
    hum: tuple = ((0.0, 20.0), (0.0, 5.0), (0.0, 10.0))
    hum_variation: tuple = (0.0, 0.3)
    drift: tuple = (1.0, 30.0)
    drift_shape: tuple = ("cubic",)  # drawn after every other setting, and only where there is a choice
    noise: tuple = (0.2, 4.0)
    tire: tuple = (0.0, 0.3)
    slow: tuple = (0.0, 0.08)
    change: tuple = ("none", "drift", "step")
    f_h_change: tuple = (0.03, 0.2)
    xi_h_change: tuple = (0.0, 0.4)
    step_at: tuple = (0.2, 0.8)
    max_peak_g: float = 0.8


LAB_RANGES = LabRanges()
"""The default ranges of typical lab records (:class:`LabRanges`)."""


def _draw_once(rng, r):
    """One draw of every setting from the ranges ``r`` (a fixed count of random numbers), and the step's fraction."""
    def uniform(pair):
        return float(rng.uniform(*pair))

    def pick(choices):
        return choices[int(rng.integers(len(choices)))]

    s = dict(mass=uniform(r.mass), f_b=uniform(r.f_b), f_h=uniform(r.f_h), xi_h=uniform(r.xi_h),
             blf=tuple(uniform(pair) for pair in r.blf), variation=pick(r.variation),
             fb_variation=uniform(r.fb_variation), coef_variation=uniform(r.coef_variation), fs=float(pick(r.fs)),
             stand_before=uniform(r.stand), stand_after=uniform(r.stand), bout=uniform(r.bout),
             ramp_up=uniform(r.ramp), ramp_down=uniform(r.ramp), sway=uniform(r.sway),
             hum_frequency=pick(r.hum_frequency), hum=tuple(uniform(pair) for pair in r.hum),
             hum_variation=uniform(r.hum_variation), drift=uniform(r.drift), noise=uniform(r.noise),
             tire=uniform(r.tire), slow=uniform(r.slow))
    kind, signs = pick(r.change), rng.choice([-1.0, 1.0], 2)
    changes = (signs[0] * uniform(r.f_h_change), signs[1] * uniform(r.xi_h_change))
    fraction = uniform(r.step_at)
    s.update(drift_shape=r.drift_shape[0])  # the others are drawn once the draw is taken (draw_lab_settings)
    s.update(change="step" if kind == "step" else "drift", change_time=None,
             f_h_change=0.0 if kind == "none" else changes[0], xi_h_change=0.0 if kind == "none" else changes[1])
    return s, fraction


def _peak_g(s):
    """Largest steady dynamic GRF (body weights) the settings ``s`` can make: Eq. 2's response, summed harmonics."""
    blf = np.asarray(s["blf"], dtype=float)
    orders = np.arange(1, blf.size + 1)
    worst = 0.0
    for f_h in (s["f_h"], s["f_h"] * (1.0 + s["f_h_change"])):
        for xi_h in (s["xi_h"], s["xi_h"] * (1.0 + s["xi_h_change"])):
            worst = max(worst, float(blf @ np.abs(equations.acceleration_frf(orders * s["f_b"], f_h, xi_h))))
    return worst * (1.0 + 2.0 * s["coef_variation"])


def draw_lab_settings(seed=None, ranges=LAB_RANGES, **fixed) -> dict:
    """Draw the settings of one typical lab record: keyword arguments of :func:`simulate_lab_record`.

    Parameters
    ----------
    seed : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Source of the draw (:func:`numpy.random.default_rng`).
    ranges : LabRanges
        Where each setting is drawn from.
    **fixed
        Settings given instead of drawn (the same random numbers are drawn regardless, so the others do not
        move); the step's time and the check on the GRF use them.

    Returns
    -------
    dict
        Every argument of :func:`simulate_lab_record` but ``seed``.
    """
    unknown = sorted(set(fixed) - set(_draw_once(np.random.default_rng(0), ranges)[0]))
    if unknown:
        raise OptionError(f"draw_lab_settings: unknown setting {unknown[0]!r}")
    rng = np.random.default_rng(seed)
    for _ in range(200):
        s, fraction = _draw_once(rng, ranges)
        s.update(fixed)
        if s["change"] == "step" and "change_time" not in fixed:
            s["change_time"] = s["stand_before"] + s["ramp_up"] / s["f_b"] + fraction * s["bout"]
        if _peak_g(s) <= ranges.max_peak_g:
            if len(ranges.drift_shape) > 1 and "drift_shape" not in fixed:  # after the rest: their draws stay
                s["drift_shape"] = ranges.drift_shape[int(rng.integers(len(ranges.drift_shape)))]
            return s
    raise OptionError(f"draw_lab_settings: 200 draws all make a GRF peak above {ranges.max_peak_g:g} body "
                      "weights; widen the ranges of f_h or xi_h or narrow blf's")


def simulate_typical_lab_record(seed=None, ranges=LAB_RANGES, **fixed) -> SyntheticRecord:
    """A lab record of settings drawn by :func:`draw_lab_settings` (``fixed`` ones given), seeded as a whole.

    The seed's :class:`~numpy.random.SeedSequence` spawns two streams, the draw's and the record's; the truth's
    ``"typical"`` holds the seed, the names of the fixed settings and the ranges.
    """
    sequence, record = _seed_sequence(seed)
    draw, own = sequence.spawn(2)
    effects = fixed.pop("effects", None)  # not drawn: the person's effects, as given
    synthetic = simulate_lab_record(**draw_lab_settings(draw, ranges, **fixed), effects=effects, seed=own)
    synthetic.truth["typical"] = {"seed": record, "fixed": sorted(fixed), "ranges": asdict(ranges)}
    return synthetic

"""A simulated phone at the waist: the accelerometer record of a simulated bouncing person.

:func:`simulate_phone` takes a person simulated by
:func:`~smd_statespace.simulation.simulate_bouncing` (its noise-free COM
acceleration ``u_ddot``, Eq. 2) and records it as a phone would: along the
phone's own three axes, tilted and slowly swaying, with gravity, a little
horizontal motion, a per-axis bias, white noise, a jittered clock and dropped
samples, after the sensor's own anti-aliasing low-pass. Phenomena real phones show on top, each off by default
(issue 44): instantaneous samples with no sensor filter (``anti_alias=False``), the phone rocking with the pelvis
at the bouncing frequency (``rocking``) and its tilt wandering slowly at random (``wander``), noisy time stamps
of samples taken on a uniform grid (``stamp_jitter``), bursts of dropped samples (``gaps``), per-axis gain errors
(``scale``) and the body's slow horizontal sway (``body_sway``). :meth:`PhoneRecord.write`
writes it in phyphox's CSV export format ("Acceleration with g"), which
:func:`smd_statespace.accelerometer.read_accelerometer` reads, and the truth beside it.

What the phone measures is the *specific force* ``f = a - g_vec``: with ``a`` the
COM acceleration (``u_ddot`` up, plus the horizontal part) and ``g_vec`` pointing
down, the world-frame specific force is ``[a_x, a_y, u_ddot + g]``; the phone sees
it rotated into its frame, ``f_phone = R(t)' f_world``, where ``R(t)`` turns the
phone's axes into the world's (a fixed tilt, then a slow sway about a horizontal
axis; with ``rocking`` or ``wander``, a time-varying rotation before them).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import OptionError
from ..io import G

__all__ = ["PhoneRecord", "simulate_phone", "sensor_filter", "PHONE_DEFAULTS", "SENSOR_BANDWIDTH",
           "SENSOR_FILTER_ORDER", "WANDER_TIME", "BODY_SWAY_FREQUENCY"]

PHONE_DEFAULTS = {"fs": 200.0, "tilt": 20.0, "sway": 3.0, "sway_frequency": 0.1, "bias": 0.1, "noise": 0.05,
                  "jitter": 0.3e-3, "drop": 0.005, "horizontal": 0.3}
"""Defaults of :func:`simulate_phone`: rate (Hz), tilt and sway (degrees), sway frequency (Hz), bias bound and
noise sd (m/s^2), clock jitter sd (s), fraction of dropped samples, horizontal acceleration amplitude (m/s^2)."""


SENSOR_BANDWIDTH = 0.4
"""Cut-off of the simulated sensor's anti-aliasing low-pass as a fraction of its rate (80 Hz at 200 Hz)."""

WANDER_TIME = 3.0
"""Time scale (s) of the tilt's random wander (``simulate_phone(wander=...)``): each of its two components is
white noise through two first-order low-passes of this time constant (a smoothed random walk that stays bounded)."""

BODY_SWAY_FREQUENCY = 0.5
"""Default frequency (Hz) of the body's horizontal sway (``simulate_phone(body_sway=...)``)."""

_WANDER_STEP = 0.01
"""Grid (s) on which the wander is made before it is interpolated to the sampling instants."""

SENSOR_FILTER_ORDER = 2
"""Order of that (causal Butterworth) low-pass: its delay, about 2 ms at 200 Hz, is the same for the force and the
response, so it moves no parameter."""


def sensor_filter(acceleration, fs, fine) -> np.ndarray:
    """A sensor's anti-aliasing low-pass: causal Butterworth of :data:`SENSOR_FILTER_ORDER` at
    :data:`SENSOR_BANDWIDTH` ``* fs`` (Hz), applied to ``acceleration`` sampled at ``fine`` Hz.

    It starts in its steady state at the first value: a real sensor's filter runs before the recording
    starts (started from zero, its start-up ringing alone moved an undetermined ``f_h`` by +165 % on a
    record of the smooth generator)."""
    from scipy import signal  # imported here: with scipy.stats, ~1 s (the CLI imports this module to start)

    sos = signal.butter(SENSOR_FILTER_ORDER, SENSOR_BANDWIDTH * fs, fs=fine, output="sos")
    return signal.sosfilt(sos, acceleration, zi=signal.sosfilt_zi(sos) * acceleration[0])[0]


def _rotation(axis, angle) -> np.ndarray:
    """Rotation matrices (Rodrigues) about the unit ``axis`` by ``angle`` (rad, shape (T,)): shape (T, 3, 3)."""
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    angle = np.atleast_1d(np.asarray(angle, dtype=float))
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle)[:, None, None] * k + (1.0 - np.cos(angle))[:, None, None] * (k @ k)


@dataclass(frozen=True)
class PhoneRecord:
    """A phone's accelerometer record with the truth behind it.

    Attributes
    ----------
    time : ndarray, shape (T,)
        Time stamps (s) as the phone gives them: jittered, with samples dropped (and noisy with
        ``stamp_jitter``).
    acc : ndarray, shape (T, 3)
        Specific force along the phone's x, y, z axes (m/s^2), gravity included.
    truth : dict
        The person's truth (:attr:`SyntheticRecord.truth
        <smd_statespace.simulation.SyntheticRecord.truth>`) and, under ``"phone"``,
        the phone's settings and draws (tilt axis, biases, samples dropped).
    vertical : ndarray, shape (T,)
        The true vertical COM acceleration at the stamps (m/s^2, ``u_ddot``) as the sensor's anti-aliasing
        filter passes it (:data:`SENSOR_BANDWIDTH`).
    person : SyntheticRecord
        The simulated person (noise-free, sampled finely): :meth:`plate_record` gives the force plate's
        record of the same bounce.
    instants : ndarray, shape (T,), optional
        The true sampling instants (s); equal to ``time`` unless the stamps are noisy (``stamp_jitter``).
    """

    time: np.ndarray
    acc: np.ndarray
    truth: dict
    vertical: np.ndarray
    person: object = None
    instants: np.ndarray = None

    def plate_record(self, fs=100.0, noise=0.01, seed=None, filtered=False):
        """The same bounce on a force plate: GRF (Eq. 3) at ``fs`` (Hz) with white noise ``noise`` (in body
        weights), for comparing the phone with the plate on one and the same person.

        ``fs`` must divide the fine simulation's rate. The force is read at the instants, unfiltered, unless
        ``filtered``: then through the phone's sensor filter at ``fs`` (:func:`sensor_filter`), for comparing
        like with like.
        """
        from ..io import make_record

        fine = float(self.person.truth["fs"])
        step = int(round(fine / fs))
        if step < 1 or abs(step * fs - fine) > 1e-9 * fine:
            raise OptionError(f"plate_record: fs {fs!r} Hz does not divide the simulation's {fine:g} Hz")
        mass = float(self.person.truth["mass"])
        rng = np.random.default_rng(seed)
        acceleration = self.person.states["u_ddot"].to_numpy()
        if filtered:
            acceleration = sensor_filter(acceleration, fs, fine)
        acceleration = acceleration[::step]
        force = mass * (G + acceleration) + noise * mass * G * rng.normal(size=acceleration.size)
        return make_record(self.person.states["time"].to_numpy()[::step], force, mass, source="plate")

    def write(self, csv_path, truth_path=None) -> tuple:
        """Write phyphox's CSV export ("Time (s)", "Acceleration x (m/s^2)", ...) and the truth as JSON.

        Returns
        -------
        tuple of pathlib.Path
            ``(csv_path, truth_path)``; the truth defaults to ``<csv stem>_truth.json`` beside the CSV.
        """
        csv_path = Path(csv_path)
        truth_path = csv_path.with_name(f"{csv_path.stem}_truth.json") if truth_path is None else Path(truth_path)
        header = '"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)",' \
                 '"Absolute acceleration (m/s^2)"'
        table = np.column_stack([self.time, self.acc, np.linalg.norm(self.acc, axis=1)])
        lines = [header] + [",".join(f"{v:.9E}" for v in row) for row in table]
        csv_path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        truth_path.write_text(json.dumps(self.truth, indent=1), encoding="utf-8")
        return csv_path, truth_path


def _check_phone_options(fs, drop, amounts) -> None:
    """Refuse invalid phone options with an :class:`OptionError` naming the option.

    A rate ``fs`` outside 50-500 Hz, a ``drop`` outside [0, 0.5) or any of the
    ``(name, value)`` ``amounts`` that is not a finite number >= 0.
    """
    if not 50.0 <= float(fs) <= 500.0:
        raise OptionError(f"simulate_phone: fs {fs!r} Hz is outside 50-500 Hz (phones' accelerometer rates)")
    if not 0.0 <= float(drop) < 0.5:
        raise OptionError(f"simulate_phone: drop {drop!r} must be a fraction in [0, 0.5)")
    for name, value in amounts:
        if not np.isfinite(value) or value < 0:
            raise OptionError(f"simulate_phone: {name} {value!r} must be a finite number >= 0")


def _sample_instants(rng, n: int, fs: float, jitter: float, drop: float, fine_time: np.ndarray) -> tuple:
    """``(t, keep)``: the phone's sampling instants (s) and which of the ``n`` nominal samples were kept.

    The nominal instants ``k / fs`` are jittered (sd ``jitter``), a fraction ``drop``
    is lost (never the first or last), and the rest are sorted and kept within
    ``fine_time``.
    """
    instants = np.arange(n) / fs + rng.normal(0.0, jitter, n)
    keep = rng.random(n) >= drop
    keep[[0, -1]] = True
    return np.sort(np.clip(instants[keep], fine_time[0], fine_time[-1])), keep


def _rotation_vectors(vectors) -> np.ndarray:
    """Rotation matrices (Rodrigues) of the rotation vectors ``vectors`` (rad, shape (T, 3)): shape (T, 3, 3)."""
    angle = np.linalg.norm(vectors, axis=1)
    axis = vectors / np.maximum(angle, 1e-300)[:, None]
    k = np.zeros((angle.size, 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    k -= np.transpose(k, (0, 2, 1))
    return np.eye(3) + np.sin(angle)[:, None, None] * k + (1.0 - np.cos(angle))[:, None, None] * (k @ k)


def _check_gaps(gaps, duration: float):
    """``gaps`` as ``(count, longest)`` (int, s), or None; refused unless they fit the record apart from each
    other (each within its own share of the record's middle)."""
    if gaps is None:
        return None
    try:
        count, longest = int(gaps[0]), float(gaps[1])
    except (TypeError, ValueError, IndexError):
        raise OptionError(f"simulate_phone: gaps {gaps!r} must be (count, longest seconds)") from None
    if count < 0 or not np.isfinite(longest) or longest <= 0 or count * longest > 0.5 * (duration - 2.0):
        raise OptionError(f"simulate_phone: gaps {gaps!r}: count >= 0 gaps of at most longest > 0 s must take "
                          "under half the record's middle (all but its first and last second)")
    return count, longest


def _new_draws(rng, size: int, duration: float, gaps, wander_time: float) -> dict:
    """The draws of the phenomena added for issue 44, taken from the phone's stream after every older draw (so a
    record with them off is the record made before they existed), in a fixed order whatever is switched on."""
    draws = {"rocking_phase": rng.uniform(0.0, 2.0 * np.pi), "rocking_heading": rng.uniform(0.0, 2.0 * np.pi),
             "body_sway_phase": rng.uniform(0.0, 2.0 * np.pi), "body_sway_heading": rng.uniform(0.0, 2.0 * np.pi),
             "gains": rng.uniform(-1.0, 1.0, 3), "stamps": rng.normal(size=size)}
    count = 0 if gaps is None else gaps[0]
    draws["gap_places"], draws["gap_lengths"] = rng.random(count), rng.uniform(0.5, 1.0, count)
    steps = int(np.ceil(duration / _WANDER_STEP)) + 1 + _burn_in(wander_time)
    draws["wander"] = rng.normal(size=(steps, 2))
    return draws


def _burn_in(wander_time: float) -> int:
    """Steps of the wander's grid before ``t = 0`` (``10 wander_time``): the wander starts in its steady state."""
    return int(np.ceil(10.0 * wander_time / _WANDER_STEP))


def _wander(white: np.ndarray, t: np.ndarray, wander: float, wander_time: float) -> np.ndarray:
    """The tilt's random wander at the instants ``t``: two angles (rad, shape (T, 2)) about the world's x and y
    axes, each ``white`` noise (on a :data:`_WANDER_STEP` grid that starts ``10 wander_time`` s early, so the
    wander is in its steady state at 0) through two first-order low-passes of time constant ``wander_time``,
    scaled to a steady-state sd of ``wander`` degrees."""
    from scipy import signal

    a = np.exp(-_WANDER_STEP / wander_time)
    smooth = signal.lfilter([(1.0 - a) ** 2], np.convolve([1.0, -a], [1.0, -a]), white, axis=0)
    steady_sd = np.sqrt((1.0 - a) ** 4 * (1.0 + a * a) / (1.0 - a * a) ** 3)
    grid = (np.arange(white.shape[0]) - _burn_in(wander_time)) * _WANDER_STEP
    angles = np.radians(wander) * smooth / steady_sd
    return np.column_stack([np.interp(t, grid, angles[:, 0]), np.interp(t, grid, angles[:, 1])])


def _cycle_phase(states, f_b: float, t: np.ndarray) -> np.ndarray:
    """The person's bouncing phase (cycles) at ``t``: the cycle's number plus the fraction of it gone, from the
    simulated cycles' starts (so a rocking with the pelvis follows the person's own timing), extended at the
    nominal ``f_b`` before the first and after the last start."""
    time, cycle = states["time"].to_numpy(), states["cycle"].to_numpy()
    starts = np.flatnonzero(np.diff(cycle)) + 1
    knots, numbers = time[starts], cycle[starts].astype(float)
    if knots.size == 0:
        return f_b * t
    knots = np.concatenate([[time[0]], knots, [time[-1]]])
    numbers = np.concatenate([[numbers[0] - (knots[1] - time[0]) * f_b], numbers,
                              [numbers[-1] + (time[-1] - knots[-2]) * f_b]])
    return np.interp(t, knots, numbers)


def _moving_frame(draws: dict, t: np.ndarray, phase: np.ndarray, rocking: float, wander: float,
                  wander_time: float) -> np.ndarray:
    """The rotation (shape (T, 3, 3)) put before the tilt and sway: the rocking with the pelvis, ``rocking``
    degrees at the bouncing phase ``phase`` about a random horizontal axis, and the wander about x and y."""
    heading = draws["rocking_heading"]
    vectors = np.zeros((t.size, 3))
    if rocking:
        angle = np.radians(rocking) * np.sin(2.0 * np.pi * phase + draws["rocking_phase"])
        vectors += angle[:, None] * np.array([np.cos(heading), np.sin(heading), 0.0])
    if wander:
        vectors[:, :2] += _wander(draws["wander"], t, wander, wander_time)
    return _rotation_vectors(vectors)


def _gap_mask(draws: dict, t: np.ndarray, fs: float, gaps, duration: float) -> tuple:
    """``(keep, spans)``: the samples left after ``gaps = (count, longest)`` bursts of dropped samples and each
    burst's ``[start, length]`` (s, the interval between the samples around it). Burst ``i`` lies in the ``i``-th
    of ``count`` equal shares of the record without its first and last second; the first is ``longest`` long,
    the others 0.5-1 times that."""
    keep = np.ones(t.size, dtype=bool)
    if gaps is None or gaps[0] == 0:
        return keep, []
    count, longest = gaps
    share = (duration - 2.0) / count
    lengths = longest * draws["gap_lengths"]
    lengths[0] = longest
    spans = []
    for i, (place, length) in enumerate(zip(draws["gap_places"], lengths)):
        missing = max(int(round(length * fs)) - 1, 1)  # samples lost: the stamps around them ``length`` apart
        first = int(np.searchsorted(t, 1.0 + share * (i + place * (1.0 - length / share))))
        keep[first:first + missing] = False
        spans.append([float(t[first - 1]), float(t[min(first + missing, t.size - 1)] - t[first - 1])])
    return keep, spans


def simulate_phone(mass=70.0, f_b=2.0, f_h=2.5, xi_h=0.3, duration=30.0, *, fs=PHONE_DEFAULTS["fs"],
                   tilt=PHONE_DEFAULTS["tilt"], sway=PHONE_DEFAULTS["sway"],
                   sway_frequency=PHONE_DEFAULTS["sway_frequency"], bias=PHONE_DEFAULTS["bias"],
                   noise=PHONE_DEFAULTS["noise"], jitter=PHONE_DEFAULTS["jitter"], drop=PHONE_DEFAULTS["drop"],
                   horizontal=PHONE_DEFAULTS["horizontal"], anti_alias=True, rocking=0.0, wander=0.0,
                   wander_time=WANDER_TIME, stamp_jitter=0.0, gaps=None, scale=0.0, body_sway=0.0,
                   body_sway_frequency=BODY_SWAY_FREQUENCY, seed=None, **person) -> PhoneRecord:
    """Simulate a person bouncing and record their COM acceleration with a phone at the waist.

    Parameters
    ----------
    mass, f_b, f_h, xi_h, duration
        The person and the record's length, as :func:`~smd_statespace.simulation.simulate_bouncing`
        (kg, Hz, Hz, -, s).
    fs : float
        The phone's nominal sampling rate (Hz), 50-500.
    tilt : float
        Tilt of the phone from level (degrees) about a random horizontal axis (0: z axis up).
    sway, sway_frequency : float
        Amplitude (degrees) and frequency (Hz) of a slow sinusoidal sway about another horizontal axis.
    bias : float
        Per-axis sensor bias drawn uniformly in ``[-bias, bias]`` (m/s^2).
    noise : float
        White noise sd on every axis (m/s^2).
    jitter : float
        Sd of the sampling instants about the nominal grid (s); the stamps are the true instants.
    drop : float
        Fraction of samples lost, in [0, 0.5).
    horizontal : float
        Amplitude of the COM's horizontal acceleration at ``f_b`` and ``2 f_b`` (m/s^2).
    anti_alias : bool
        True: the sensor low-passes before its output rate (:func:`sensor_filter`); False: every sample is the
        acceleration at its instant, no filter in front (many phones).
    rocking : float
        Amplitude (degrees) of the phone's rocking with the pelvis about a random horizontal axis, a sinusoid
        locked to the person's own bouncing cycles (at ``f_b``, random phase); 0: none.
    wander, wander_time : float
        Steady-state sd (degrees) of a slow random wander of the tilt about each horizontal axis (white noise
        through two first-order low-passes of time constant ``wander_time``, s), besides the sinusoidal
        ``sway``; 0: none.
    stamp_jitter : float
        Sd (s) of white noise on the written time stamps (the samples themselves are taken at the instants,
        on the ``jitter``'s grid: use ``jitter=0`` for a uniform one); 0: the stamps are the instants.
    gaps : (int, float), optional
        ``(count, longest)``: bursts of consecutive dropped samples, the longest ``longest`` s between the
        samples around it (the others 0.5-1 times that), one in each of ``count`` equal shares of the record
        without its first and last second; None: none.
    scale : float
        Per-axis gain errors drawn uniformly in ``[-scale, scale]`` (fractions): the axes read ``(1 + s_i)``
        times the specific force (before the bias and noise); 0: none.
    body_sway, body_sway_frequency : float
        Amplitude (m/s^2) and frequency (Hz) of the body's slow horizontal sway, a sinusoidal COM acceleration
        in a random horizontal direction (random phase), besides ``horizontal``; 0: none.
    seed : int, optional
        Root of the ``SeedSequence``: one stream for the person, one for the phone. The phenomena of issue 44
        (``anti_alias`` to ``body_sway``) draw from the phone's stream after every older draw: with them off, a
        record is bit for bit the one made before they existed.
    **person
        More options of :func:`~smd_statespace.simulation.simulate_bouncing` (``blf``, ``variation``,
        ``effects``, ...); its force-plate ``noise`` is 0 here (the phone has its own).

    Returns
    -------
    PhoneRecord
    """
    from .bouncing import simulate_bouncing

    _check_phone_options(fs, drop, (("tilt", tilt), ("sway", sway), ("bias", bias), ("noise", noise),
                                    ("jitter", jitter), ("horizontal", horizontal),
                                    ("sway_frequency", sway_frequency), ("rocking", rocking), ("wander", wander),
                                    ("stamp_jitter", stamp_jitter), ("scale", scale), ("body_sway", body_sway)))
    _check_new_options(wander_time, scale, body_sway_frequency)
    gaps = _check_gaps(gaps, duration)
    person_seed, phone_seed = np.random.SeedSequence(seed).spawn(2)
    fine = max(1000.0, 5.0 * float(fs))  # the person's response finely, then read at the phone's instants
    synthetic = simulate_bouncing(mass=mass, f_b=f_b, f_h=f_h, xi_h=xi_h, duration=duration, fs=fine, noise=0.0,
                                  seed=int(person_seed.generate_state(1)[0]), **person)
    rng = np.random.default_rng(phone_seed)
    states = synthetic.states
    fine_time = states["time"].to_numpy()
    # the sensor's own anti-aliasing filter (a MEMS accelerometer low-passes before its output rate): without
    # it, the simulated force's instant steps at cycle starts, read at jittered instants, put spikes of up to
    # 0.2 m/s^2 into the record that no real, continuous force makes (one record's f_h moved by +60 %)
    sensed = sensor_filter(states["u_ddot"].to_numpy(), fs, fine) if anti_alias else states["u_ddot"].to_numpy()
    n = int(np.floor(duration * fs)) + 1
    t, keep = _sample_instants(rng, n, fs, jitter, drop, fine_time)
    vertical = np.interp(t, fine_time, sensed)
    w = 2.0 * np.pi * f_b
    world = np.column_stack([horizontal * np.sin(w * t + 1.0), 0.7 * horizontal * np.sin(2.0 * w * t),
                             vertical + G])
    heading = rng.uniform(0.0, 2.0 * np.pi)
    tilt_axis = np.array([np.cos(heading), np.sin(heading), 0.0])
    sway_axis = np.array([-np.sin(heading), np.cos(heading), 0.0])
    phone_to_world = _rotation(sway_axis, np.radians(sway) * np.sin(2.0 * np.pi * sway_frequency * t)) @ _rotation(
        tilt_axis, np.radians(tilt))
    biases = rng.uniform(-bias, bias, 3)
    white = rng.normal(size=(t.size, 3))
    draws = _new_draws(rng, t.size, duration, gaps, wander_time)
    if body_sway:
        along = body_sway * np.sin(2.0 * np.pi * body_sway_frequency * t + draws["body_sway_phase"])
        world[:, :2] += along[:, None] * [np.cos(draws["body_sway_heading"]), np.sin(draws["body_sway_heading"])]
    if rocking or wander:
        phase = _cycle_phase(states, f_b, t)
        phone_to_world = _moving_frame(draws, t, phase, rocking, wander, wander_time) @ phone_to_world
    acc = np.einsum("tji,tj->ti", phone_to_world, world)  # world -> phone: the transpose
    gains = 1.0 + scale * draws["gains"]
    if scale:
        acc = acc * gains
    acc = acc + biases + noise * white
    stamps = t + stamp_jitter * draws["stamps"] if stamp_jitter else t
    kept, spans = _gap_mask(draws, t, fs, gaps, duration)
    truth = dict(synthetic.truth)
    truth["phone"] = {"fs": float(fs), "tilt_deg": float(tilt), "tilt_axis": tilt_axis.round(6).tolist(),
                      "sway_deg": float(sway), "sway_frequency": float(sway_frequency), "bias": biases.tolist(),
                      "noise": float(noise), "jitter": float(jitter), "drop": float(drop),
                      "n_dropped": int(n - keep.sum() + (~kept).sum()), "horizontal": float(horizontal),
                      "seed": None if seed is None else int(seed)}
    if not (anti_alias and rocking == wander == stamp_jitter == scale == body_sway == 0 and gaps is None):
        truth["phone"].update(anti_alias=bool(anti_alias), rocking_deg=float(rocking), wander_deg=float(wander),
                              wander_time=float(wander_time), stamp_jitter=float(stamp_jitter),
                              gaps=spans, scale=float(scale), gains=gains.tolist(), body_sway=float(body_sway),
                              body_sway_frequency=float(body_sway_frequency))
    return PhoneRecord(time=stamps[kept], acc=acc[kept], truth=truth, vertical=vertical[kept], person=synthetic,
                       instants=t[kept])


def _check_new_options(wander_time, scale, body_sway_frequency) -> None:
    """Refuse a ``wander_time`` that is not a positive number, a ``scale`` of 0.5 or more (an axis reading half
    or none of its force) and a ``body_sway_frequency`` outside (0, 5] Hz, with an :class:`OptionError`."""
    if not (np.isfinite(wander_time) and wander_time > 0):
        raise OptionError(f"simulate_phone: wander_time {wander_time!r} s must be a positive number")
    if not scale < 0.5:
        raise OptionError(f"simulate_phone: scale {scale!r} must be a fraction below 0.5")
    if not 0.0 < body_sway_frequency <= 5.0:
        raise OptionError(f"simulate_phone: body_sway_frequency {body_sway_frequency!r} Hz must be in (0, 5]")

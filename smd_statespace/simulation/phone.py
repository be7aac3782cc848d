"""A simulated phone at the waist: the accelerometer record of a simulated bouncing person.

:func:`simulate_phone` takes a person simulated by
:func:`~smd_statespace.simulation.simulate_bouncing` (its noise-free COM
acceleration ``u_ddot``, Eq. 2) and records it as a phone would: along the
phone's own three axes, tilted and slowly swaying, with gravity, a little
horizontal motion, a per-axis bias, white noise, a jittered clock and dropped
samples, after the sensor's own anti-aliasing low-pass. :meth:`PhoneRecord.write`
writes it in phyphox's CSV export format ("Acceleration with g"), which
:func:`smd_statespace.accelerometer.read_accelerometer` reads, and the truth beside it.

What the phone measures is the *specific force* ``f = a - g_vec``: with ``a`` the
COM acceleration (``u_ddot`` up, plus the horizontal part) and ``g_vec`` pointing
down, the world-frame specific force is ``[a_x, a_y, u_ddot + g]``; the phone sees
it rotated into its frame, ``f_phone = R(t)' f_world``, where ``R(t)`` turns the
phone's axes into the world's (a fixed tilt, then a slow sway about a horizontal
axis).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import OptionError
from ..io import G

__all__ = ["PhoneRecord", "simulate_phone", "sensor_filter", "PHONE_DEFAULTS", "SENSOR_BANDWIDTH",
           "SENSOR_FILTER_ORDER"]

PHONE_DEFAULTS = {"fs": 200.0, "tilt": 20.0, "sway": 3.0, "sway_frequency": 0.1, "bias": 0.1, "noise": 0.05,
                  "jitter": 0.3e-3, "drop": 0.005, "horizontal": 0.3}
"""Defaults of :func:`simulate_phone`: rate (Hz), tilt and sway (degrees), sway frequency (Hz), bias bound and
noise sd (m/s^2), clock jitter sd (s), fraction of dropped samples, horizontal acceleration amplitude (m/s^2)."""


SENSOR_BANDWIDTH = 0.4
"""Cut-off of the simulated sensor's anti-aliasing low-pass as a fraction of its rate (80 Hz at 200 Hz)."""

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
        Time stamps (s) as the phone gives them: jittered, with samples dropped.
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
    """

    time: np.ndarray
    acc: np.ndarray
    truth: dict
    vertical: np.ndarray
    person: object = None

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


def simulate_phone(mass=70.0, f_b=2.0, f_h=2.5, xi_h=0.3, duration=30.0, *, fs=PHONE_DEFAULTS["fs"],
                   tilt=PHONE_DEFAULTS["tilt"], sway=PHONE_DEFAULTS["sway"],
                   sway_frequency=PHONE_DEFAULTS["sway_frequency"], bias=PHONE_DEFAULTS["bias"],
                   noise=PHONE_DEFAULTS["noise"], jitter=PHONE_DEFAULTS["jitter"], drop=PHONE_DEFAULTS["drop"],
                   horizontal=PHONE_DEFAULTS["horizontal"], seed=None, **person) -> PhoneRecord:
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
    seed : int, optional
        Root of the ``SeedSequence``: one stream for the person, one for the phone.
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
                                    ("sway_frequency", sway_frequency)))
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
    sensed = sensor_filter(states["u_ddot"].to_numpy(), fs, fine)
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
    acc = np.einsum("tji,tj->ti", phone_to_world, world)  # world -> phone: the transpose
    biases = rng.uniform(-bias, bias, 3)
    acc = acc + biases + noise * rng.normal(size=acc.shape)
    truth = dict(synthetic.truth)
    truth["phone"] = {"fs": float(fs), "tilt_deg": float(tilt), "tilt_axis": tilt_axis.round(6).tolist(),
                      "sway_deg": float(sway), "sway_frequency": float(sway_frequency), "bias": biases.tolist(),
                      "noise": float(noise), "jitter": float(jitter), "drop": float(drop),
                      "n_dropped": int(n - keep.sum()), "horizontal": float(horizontal),
                      "seed": None if seed is None else int(seed)}
    return PhoneRecord(time=t, acc=acc, truth=truth, vertical=vertical, person=synthetic)

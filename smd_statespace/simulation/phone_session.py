"""A phone record as people make one: picked up, strapped on, standing, bouncing, standing, taken off.

:func:`simulate_phone_session` records a whole trial of :func:`~smd_statespace.simulation.lab.simulate_lab_record`
(standing, a ramp in, bouncing that may tire and slow, a ramp out, standing; the plate's artefacts off) with a phone
at the waist, and puts the handling around it: the phone lies on a table, is picked up and turned and carried
about (a hand's acceleration, its orientation swinging) until it sits at the waist in its worn orientation; at the
end the same backwards. What the phone measures is the specific force ``f = a - g_vec`` in its own frame, as
:mod:`~smd_statespace.simulation.phone` explains; worn, ``a`` is the person's COM acceleration (Eq. 2's
``u_ddot`` plus the standing sway force over the mass). The truth carries the spans of every part in the
phone's time.
"""

from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..io import G
from .phone import PhoneRecord, _rotation, sensor_filter

__all__ = ["SESSION_DEFAULTS", "simulate_phone_session"]

SESSION_DEFAULTS = {"fs": 200.0, "pick_up": 4.0, "take_off": 4.0, "tilt": 80.0, "bias": 0.1, "noise": 0.05,
                    "handling": 2.0, "table": 1.0}
"""Defaults of :func:`simulate_phone_session`: the phone's rate (Hz); handling before and after (s); the worn
tilt from lying flat (degrees: 80, a phone upright in a pocket or on a belt); per-axis bias bound and noise sd
(m/s^2); RMS of the hand's acceleration while handling (m/s^2); time on the table at each end (s)."""

HANDLING_BAND = (0.3, 3.0)
"""Band (Hz) of the hand's acceleration and of the orientation's swings while the phone is handled."""

FINE_RATE = 1000.0
"""Rate (Hz) at which the person is simulated before the phone reads it."""


def _band_limited(rng, n, fs, band, rms) -> np.ndarray:
    """Three channels of band-limited Gaussian noise (``band`` Hz) with the given RMS, shape (n, 3)."""
    from scipy import signal

    sos = signal.butter(2, band, btype="bandpass", fs=fs, output="sos")
    x = signal.sosfiltfilt(sos, rng.normal(size=(n + 2 * int(fs), 3)), axis=0)[int(fs):int(fs) + n]
    return rms * x / max(float(np.sqrt(np.mean(x**2))), 1e-12)


def _handling(rng, t, fs, handling, tilt_axis, tilt, table, worn_first) -> tuple:
    """``(rotation (n, 3, 3), world acceleration (n, 3))`` of the phone handled over ``t`` (s from its start).

    On the table for ``table`` s (flat, at rest), then turned to the worn tilt while carried; ``worn_first``
    reverses the path (taken off and laid down).
    """
    n = t.size
    duration = max(float(t[-1] - t[0]), 1e-9)
    s = np.clip((t - t[0] - table) / max(duration - table, 1e-9), 0.0, 1.0)  # 0 on the table, 1 worn
    if worn_first:
        s = s[::-1]
    ease = 0.5 - 0.5 * np.cos(np.pi * s)
    moving = np.sin(np.pi * s) ** 2  # the hand moves between table and waist, not at either
    wobble = np.radians(25.0) * moving[:, None] * _band_limited(rng, n, fs, HANDLING_BAND, 1.0)
    rotation = _rotation(tilt_axis, np.radians(tilt) * ease)
    for axis in range(3):
        rotation = _rotation(np.eye(3)[axis], wobble[:, axis]) @ rotation
    acceleration = handling * moving[:, None] * _band_limited(rng, n, fs, HANDLING_BAND, 1.0)
    return rotation, acceleration


def simulate_phone_session(mass=70.0, f_b=2.0, f_h=2.5, xi_h=0.3, *, bout=30.0, stand_before=5.0,
                           stand_after=5.0, fs=SESSION_DEFAULTS["fs"], pick_up=SESSION_DEFAULTS["pick_up"],
                           take_off=SESSION_DEFAULTS["take_off"], tilt=SESSION_DEFAULTS["tilt"],
                           bias=SESSION_DEFAULTS["bias"], noise=SESSION_DEFAULTS["noise"],
                           handling=SESSION_DEFAULTS["handling"], table=SESSION_DEFAULTS["table"], seed=None,
                           **person) -> PhoneRecord:
    """Simulate a phone's whole record of a bouncing trial, handling included.

    Parameters
    ----------
    mass, f_b, f_h, xi_h : float
        The person (kg, Hz, Hz, -), as :func:`~smd_statespace.simulation.lab.simulate_lab_record`.
    bout, stand_before, stand_after : float
        Bouncing between the ramps, and standing still with the phone worn before and after (s).
    fs : float
        The phone's rate (Hz), 50-500; the samples pass the sensor's anti-aliasing filter
        (:func:`~smd_statespace.simulation.phone.sensor_filter`).
    pick_up, take_off : float
        Handling before and after (s): on the table ``table`` s, then carried and turned to (from) the
        worn orientation. 0: the record starts (ends) worn.
    tilt : float
        The worn orientation: the phone turned by ``tilt`` degrees from lying flat about a random
        horizontal axis.
    bias, noise : float
        Per-axis bias bound and white noise sd (m/s^2).
    handling : float
        RMS of the hand's acceleration while the phone is carried (m/s^2).
    table : float
        Time on the table at the start of ``pick_up`` and the end of ``take_off`` (s).
    seed : None, int or numpy.random.SeedSequence
        Root of the streams: the person's (:func:`simulate_lab_record`) and the phone's.
    **person
        More options of ``simulate_lab_record`` (``ramp_up``, ``ramp_down``, ``variation``, ``blf``, ``tire``,
        ``slow``, ``sway``, ``f_h_change``, ...); its plate's hum, drift and noise are off.

    Returns
    -------
    PhoneRecord
        ``truth["session"]``: the phone's time of every part (``table_before``, ``pick_up``, ``worn``,
        ``bouncing``, ``take_off``, ``table_after``: ``[start, end]`` in s) and the settings.
    """
    from .lab import simulate_lab_record

    for name, value in (("pick_up", pick_up), ("take_off", take_off), ("tilt", tilt), ("bias", bias),
                        ("noise", noise), ("handling", handling), ("table", table)):
        if not np.isfinite(value) or value < 0:
            raise OptionError(f"simulate_phone_session: {name} {value!r} must be a finite number >= 0")
    if not 50.0 <= float(fs) <= 500.0:
        raise OptionError(f"simulate_phone_session: fs {fs!r} Hz is outside 50-500 Hz (phones' accelerometer rates)")
    for name, value in (("pick_up", pick_up), ("take_off", take_off)):
        if 0 < value < table + 1.0:
            raise OptionError(f"simulate_phone_session: {name} {value!r} s must be 0 or at least {table + 1.0:g} s "
                              f"({table:g} s on the table and 1 s carried)")
    person_seed, phone_seed = np.random.SeedSequence(seed).spawn(2) if not isinstance(
        seed, np.random.SeedSequence) else seed.spawn(2)
    lab = simulate_lab_record(mass, f_b, f_h, xi_h, fs=FINE_RATE, stand_before=stand_before, stand_after=stand_after,
                              bout=bout, hum=(), drift=0.0, noise=0.0, seed=person_seed, **person)
    states = lab.states
    worn_time = states["time"].to_numpy()
    com = sensor_filter(states["u_ddot"].to_numpy() + states["sway"].to_numpy() / mass, fs, FINE_RATE)
    rng = np.random.default_rng(phone_seed)
    heading = rng.uniform(0.0, 2.0 * np.pi)
    tilt_axis = np.array([np.cos(heading), np.sin(heading), 0.0])
    total = pick_up + float(worn_time[-1]) + take_off
    t = np.arange(int(np.floor(total * fs)) + 1) / fs
    vertical = np.interp(t - pick_up, worn_time, com, left=0.0, right=0.0)
    world = np.zeros((t.size, 3))
    world[:, 2] = G + vertical
    rotation = np.broadcast_to(_rotation(tilt_axis, np.radians(tilt)), (t.size, 3, 3)).copy()
    before, after = t < pick_up, t > pick_up + worn_time[-1]
    for part, worn_first in ((before, False), (after, True)):
        if part.any():
            turn, hand = _handling(rng, t[part], fs, handling, tilt_axis, tilt, table, worn_first)
            rotation[part], world[part] = turn, world[part] + hand
    acc = np.einsum("tji,tj->ti", rotation, world)  # world -> phone: the transpose
    biases = rng.uniform(-bias, bias, 3)
    acc = acc + biases + noise * rng.normal(size=acc.shape)
    span = lab.truth["span"]
    worn_end = pick_up + float(worn_time[-1])
    truth = dict(lab.truth)
    truth["session"] = {
        "table_before": [0.0, min(table, pick_up)], "pick_up": [0.0, pick_up], "worn": [pick_up, worn_end],
        "bouncing": [pick_up + span["bouncing_start_s"], pick_up + span["bouncing_end_s"]],
        "full_bouncing": [pick_up + span["full_start_s"], pick_up + span["full_end_s"]],
        "take_off": [worn_end, total], "table_after": [max(total - table, worn_end) if take_off else total, total],
        "fs": float(fs), "tilt_deg": float(tilt), "tilt_axis": tilt_axis.round(6).tolist(), "bias": biases.tolist(),
        "noise": float(noise), "handling": float(handling)}
    return PhoneRecord(time=t, acc=acc, truth=truth, vertical=vertical, person=lab)

"""A record made ready for the record-level fit: the bouncing part only, without mains hum, at a safe rate.

:func:`prepare_record` is what ``identify_person`` (and ``identify REC``) does to a record
before the fit. A record that is bouncing from its first sample to its last (a simulator's,
or one trimmed by hand) is only decimated, as before. A record as labs export it — the person
stands, starts bouncing over a few cycles, bounces, stops and stands again; mains hum; a
plate zero that drifts; 500-2000 Hz — goes through the front end
(:mod:`~smd_statespace.signals.frontend`):

1. mains hum (50 or 60 Hz and harmonics) found and subtracted at the record's own rate;
2. the record split into standing, ramps, bouncing, other movement and no contact; the
   steady part of the longest bout of bouncing is fitted (two bouts: the other is named, with
   the ``span`` that fits it); the standing parts give the body weight before and after
   (the plate's zero and its drift, said against the given mass) and the noise level;
3. decimated whole to about :data:`~smd_statespace.signals.RECORD_RATE` (:func:`safe_factor`:
   with hum, to a rate whose Nyquist frequency lies :data:`HUM_MARGIN` or more from every multiple
   of the hum, so that what the subtraction left is not at the new Nyquist frequency), then
   trimmed to the bout.

Every step is said in words in :attr:`PreparedRecord.notes`, e.g. ``bouncing 4.1-33.9 s
fitted (62 cycles); standing 0.0-3.4 s and 34.6-38.0 s used for the body weight and the
plate's zero``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import OptionError, RecordError
from ..io import G, Record
from .decimation import RECORD_RATE, check_rate, decimate_record, decimation_factor, decimation_note
from .frontend import Bouts, Hum, find_bouts, mains_hum, remove_hum, trim_record

__all__ = ["ACROSS_LIMIT", "HUM_MARGIN", "MASS_TOLERANCE", "OFF_PLATE", "TURN_LIMIT", "WEIGHT_RATIO", "PreparedRecord",
           "safe_factor", "prepare_record", "parse_span"]

HUM_MARGIN = 3.0
"""Least distance (Hz) between the fitting rate's Nyquist frequency and a multiple of the mains hum."""

MASS_TOLERANCE = 0.02
"""A standing weight that differs from ``M_h g`` by more than this fraction is said in a warning."""

WEIGHT_RATIO = (0.6, 1.6)
"""A standing weight outside these multiples of ``M_h g`` is not this person alone: refused (two people, a wrong mass)."""

OFF_PLATE = 1.0
"""No contact this long (s) with contact before and after is stepping off mid-record (a jump's flight is shorter)."""

TURN_LIMIT = 30.0
"""Largest turn (degrees) of a phone's gravity direction over the part fitted: more is a loose phone, refused.

Fixed at the waist, a phone turns with the pelvis's slow sway: 3 degrees in the simulator's baseline, at most
18 with a wander of 5 degrees (sd) added (``benchmarks/phone_phenomena.py``, 720 records)."""

ACROSS_LIMIT = 1.0
"""Largest ratio of a phone's movement across the vertical to its movement along it (rms) over the part fitted.

Bouncing is vertical: the horizontal COM acceleration is a tenth of the vertical's, a rocking of 5 degrees at the
bouncing frequency reads 0.85 m/s^2 across (a third); a phone swinging loose reads gravity across the vertical."""

_OTHER_PARTS = ("standing", "movement", "no_contact")


@dataclass(frozen=True)
class PreparedRecord:
    """A record ready for the fit, and what was done to it.

    Attributes
    ----------
    record : Record
        What the fit takes: hum removed, decimated, trimmed to the bouncing span.
    original : Record
        The record as read.
    span : (float, float) or None
        The fitted span (s, on the record's own time axis); None: the whole record.
    factor : int
        Decimation factor (1: every sample kept).
    hum : Hum or None
        The mains hum found (None: not looked for, ``span=None``).
    bouts : Bouts or None
        The record's parts (None: not looked for).
    trimmed : bool
        True when parts that are not bouncing (standing, other movement, no contact) were left
        out: a slowly drifting plate zero is then worth modelling (``identify_person`` adds a
        drift of the measurement's zero).
    notes, warnings : list of str
        What was done, and what the user should know, in words.
    extra : list of ndarray
        Signals given with the record (regressors), decimated and trimmed alike.
    """

    record: Record
    original: Record
    span: tuple | None
    factor: int
    hum: Hum | None = None
    bouts: Bouts | None = None
    trimmed: bool = False
    notes: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    extra: list = field(default_factory=list)


def safe_factor(fs: float, rate, hum: Hum | None) -> int:
    """The decimation factor for a record at ``fs`` Hz: ``floor(fs / rate)`` (:func:`decimation_factor`), raised while
    the new Nyquist is on the hum.

    With hum at ``f`` Hz, the fitting rate's Nyquist frequency ``fs / (2 q)`` must lie at least
    :data:`HUM_MARGIN` away from every multiple of ``f``: at ``fs / q = 2 f`` (1000 Hz to 100 Hz with 50 Hz
    hum) what the subtraction left of the line sits on the new Nyquist frequency (innovations alternating
    in sign at every lag); one sample fewer in ``q`` moves it below the line, which the decimation's
    low-pass then removes.

    Examples
    --------
    >>> hum = Hum(True, 50.0, np.array([50.0]), np.array([1.0]), np.array([True]), np.zeros(1))
    >>> safe_factor(1000.0, 100.0, None), safe_factor(1000.0, 100.0, hum), safe_factor(1000.0, 200.0, hum)
    (10, 11, 6)
    """
    factor = decimation_factor(fs, rate)
    if factor < 2 or hum is None or not hum.found:
        return max(factor, 1)

    def on_the_hum(q):
        nyquist = fs / (2.0 * q)
        return abs(nyquist - hum.frequency * max(round(nyquist / hum.frequency), 1)) < HUM_MARGIN

    while on_the_hum(factor):
        factor += 1
    return factor


def parse_span(text: str, option: str = "--span"):
    """``"START:END"`` (s) as a pair of floats, ``"all"`` as None (the whole record), ``"auto"`` as itself.

    Examples
    --------
    >>> parse_span("4.5:33"), parse_span("all"), parse_span("auto")
    ((4.5, 33.0), None, 'auto')
    """
    text = str(text).strip()
    if text.lower() in ("auto", "all"):
        return "auto" if text.lower() == "auto" else None
    start, colon, end = text.partition(":")
    try:
        if not colon:
            raise ValueError
        span = (float(start), float(end))
    except ValueError:
        raise OptionError(f"{option} {text!r}: give START:END in s (e.g. 4.5:33), auto (find the bouncing part) or "
                          "all (the whole record)") from None
    if not (all(math.isfinite(v) for v in span) and span[0] < span[1]):
        raise OptionError(f"{option} {text!r}: START must be below END (s)")
    return span


def prepare_record(record: Record, rate=RECORD_RATE, span="auto", extra=()) -> PreparedRecord:
    """The record the fit takes: its bouncing part, hum removed, decimated at a rate safe from the hum.

    Parameters
    ----------
    record : Record
    rate : float or None
        Lowest fitting rate (Hz; :func:`~smd_statespace.signals.decimate_record`); None keeps
        every sample.
    span : "auto", (float, float) or None
        ``"auto"`` (default): the front end finds the bouncing part (the record is kept whole
        when it is bouncing from end to end); ``(start, end)`` (s, on the record's time axis):
        that part, hum removed; None: the whole record, only decimated (what the library did
        before the front end).
    extra : sequence of ndarray
        Signals sampled with the record (the same length), decimated and trimmed alike.

    Returns
    -------
    PreparedRecord

    Raises
    ------
    RecordError
        ``span="auto"`` and no bouncing part (the message says what the record holds), or a
        ``span`` outside the record.
    OptionError
        A malformed ``span`` or ``rate``.
    """
    check_rate(rate)
    extra = [np.asarray(values, dtype=float) for values in extra]
    if isinstance(span, str):
        span = parse_span(span, "span")  # "auto", None ("all") or a pair
    if span is None:
        _refuse_a_loose_phone(record, None)
        decimated, factor, moved = decimate_record(record, rate, extra)
        notes = [*record.extra.get("reading", ()), *_rate_notes(record, decimated, factor, rate)]
        return PreparedRecord(decimated, record, None, factor, notes=notes, extra=moved)
    said = getattr(span, "said", "as given")  # where a span that was not found here came from, for its note
    if span != "auto":
        trim_record(record, span)  # a malformed span, or one outside the record: one line before any work
        span = (float(span[0]), float(span[1]))
    hum = mains_hum(record)
    clean = remove_hum(record, hum)
    bouts = find_bouts(clean) if span == "auto" else None
    notes = [*record.extra.get("reading", ()), *([hum.describe() + ", subtracted"] if hum.found else [])]
    warnings = []
    trimmed = True
    if span == "auto":
        _refuse_what_is_not_one_person(bouts, record)
        span, trimmed, said = _bouncing_span(clean, bouts)
        notes += said
        warnings += _weight_warnings(bouts, record)
    else:
        notes.append(f"span {span[0]:g}-{span[1]:g} s fitted, {said}")
    _refuse_a_loose_phone(record, span)
    factor = safe_factor(record.fs, rate, hum)
    decimated, factor, moved = decimate_record(clean, None if factor < 2 else record.fs / factor, extra)
    notes += _rate_notes(record, decimated, factor, rate, hum)
    if span is None:
        return PreparedRecord(decimated, record, None, factor, hum, bouts, False, notes, warnings, moved)
    fitted = trim_record(decimated, span)
    keep = np.isin(decimated.time, fitted.time)
    return PreparedRecord(fitted, record, span, factor, hum, bouts, trimmed, notes, warnings,
                          [values[keep] for values in moved])


def _refuse_what_is_not_one_person(bouts: Bouts, record: Record):
    """A one-line :class:`RecordError` for two people on the plate (or a wrong mass) and for stepping off mid-record."""
    weight = record.mass * G
    for level in (bouts.level_before, bouts.level_after):
        if np.isfinite(level) and not WEIGHT_RATIO[0] <= level / weight <= WEIGHT_RATIO[1]:
            raise RecordError(f"{record.source}: standing, the plate reads {level:.0f} N = {level / G:.1f} kg at g, "
                              f"{level / weight:.2f} times the given mass ({record.mass:g} kg): two people on the "
                              "plate, or a wrong --mass")
    parts = bouts.segments
    for before, part, after in zip(parts, parts[1:], parts[2:]):
        if part.kind == "no_contact" and part.end - part.start >= OFF_PLATE and "no_contact" not in (
                before.kind, after.kind):
            bouncing = ", ".join(f"{b.start:.1f}-{b.end:.1f} s" for b in bouts.bouts) or "none"
            raise RecordError(f"{record.source}: the person leaves the plate at {part.start:.1f}-{part.end:.1f} s "
                              f"and comes back (stepped off mid-record); bouncing {bouncing}: identify one part "
                              "with --span START:END (span=(start, end))")


def _refuse_a_loose_phone(record: Record, span) -> None:
    """A one-line :class:`RecordError` for a phone that turned (:data:`TURN_LIMIT`) or moved across the vertical
    (:data:`ACROSS_LIMIT`) over ``span`` (s; None: the whole record): not fixed to the body. Records without
    ``extra["direction"]`` (a plate's) pass."""
    direction, across = record.extra.get("direction"), record.extra.get("across")
    if direction is None or across is None:
        return
    inside = np.ones(record.time.size, bool) if span is None else (record.time >= span[0]) & (record.time <= span[1])
    mean = direction[inside].mean(axis=0)
    turn = float(np.degrees(np.arccos(np.clip(direction[inside] @ (mean / np.linalg.norm(mean)), -1.0, 1.0))).max())
    along = record.force[inside] / record.mass - G
    along_rms, across_rms = float(np.std(along)), float(np.sqrt(np.mean(across[inside] ** 2)))
    where = f"{record.time[inside][0]:.1f}-{record.time[inside][-1]:.1f} s"
    if turn > TURN_LIMIT:
        raise RecordError(f"{record.source}: the phone turned by {turn:.0f} degrees over {where} (fixed at the waist "
                          f"it turns by under {TURN_LIMIT:g}): loose in a bag or a hand; fix it to the body")
    if across_rms > ACROSS_LIMIT * along_rms:
        raise RecordError(f"{record.source}: the phone moved more across the vertical than along it over {where} "
                          f"(rms {across_rms:.2f} against {along_rms:.2f} m/s^2): swinging loose (a bag, a hand) or "
                          "not bouncing; fix it to the body at the waist")


def _bouncing_span(record: Record, bouts: Bouts) -> tuple:
    """``(span, trimmed, notes)``: the steady part of the longest bout, or None when the record bounces end to end."""
    bouts.require()
    others = [s for s in bouts.segments if s.kind in _OTHER_PARTS]
    if not others and len(bouts.bouts) == 1:  # bouncing from end to end (ramps of a cycle or less at the ends)
        return None, False, []
    chosen = max(bouts.bouts, key=lambda bout: bout.cycles)
    phone = record.extra.get("sensor") == "accelerometer"
    notes = [f"bouncing {chosen.start:.1f}-{chosen.end:.1f} s fitted ({chosen.cycles} cycles)" + _left_out(bouts, phone)]
    if len(bouts.bouts) > 1:
        rest = [b for b in bouts.bouts if b is not chosen]
        notes.append(f"{len(bouts.bouts)} bouts of bouncing: the longest is fitted; "
                     + "; ".join(f"{b.start:.1f}-{b.end:.1f} s ({b.cycles} cycles): span=({b.start:.2f}, {b.end:.2f})"
                                 f" or --span {b.start:.2f}:{b.end:.2f}" for b in rest))
    return chosen.span, True, notes


def _left_out(bouts: Bouts, phone: bool = False) -> str:
    """``; standing 0.0-3.4 s and 34.6-38.0 s used for ...; ramps ... left out`` for the note of the fitted span
    (a phone's record: still parts and handling named as a phone's)."""
    words = []
    uses = (("standing", "used for the body weight and the plate's zero"), ("ramp", "left out"),
            ("movement", "left out (not bouncing)"), ("no_contact", "left out (no contact with the plate)"))
    if phone:
        uses = (("standing", "still (the phone worn standing, or put down) left out"), ("ramp", "left out"),
                ("movement", "left out (the phone handled, or not bouncing)"),
                ("no_contact", "left out (free fall: a jump or a drop)"))
    for kind, use in uses:
        spans = [s for s in bouts.segments if s.kind == kind]
        if spans:
            listed = " and ".join(f"{s.start:.1f}-{s.end:.1f} s" for s in spans[:3]) + (" ..." if len(spans) > 3
                                                                                          else "")
            label = {"ramp": "starting and stopping", "no_contact": "off the plate"}.get(kind, kind)
            words.append(f"{label} {listed} {use}")
    return "; " + "; ".join(words) if words else ""


def _weight_warnings(bouts: Bouts, record: Record) -> list:
    """What the standing parts say against the given mass, and the plate zero's drift, as warnings (or none)."""
    out = []
    weight = record.mass * G
    for label, level in (("before", bouts.level_before), ("after", bouts.level_after)):
        if np.isfinite(level) and abs(level / weight - 1.0) > MASS_TOLERANCE:
            out.append(f"standing {label} bouncing the plate reads {level:.0f} N = {level / G:.1f} kg at g, the given "
                       f"mass is {record.mass:g} kg ({100 * (level / weight - 1):+.1f} %): check --mass; the fit "
                       "takes the difference as the plate's zero (its offset)")
            break
    return out


def _rate_notes(record: Record, decimated: Record, factor: int, rate, hum: Hum | None = None) -> list:
    """The decimation in words, and why the rate is below ``rate`` when hum lowered it."""
    notes = decimation_note(record.fs, decimated, factor, rate)
    if factor > 1 and hum is not None and hum.found and rate is not None and decimated.fs < rate:
        notes.append(f"fitted at {decimated.fs:.4g} Hz rather than {rate:g}: so that its Nyquist frequency is not on "
                     f"the {hum.frequency:.0f} Hz hum or one of its multiples, where what the subtraction left would "
                     "stay")
    return notes

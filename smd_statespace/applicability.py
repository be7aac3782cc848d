"""Is this record bouncing? Checks made before any identification.

The SMD model of the article describes one person bouncing on the spot in
continuous contact with the plate: a rhythmic force with one hump per cycle,
a mean equal to the body weight. :func:`check_bouncing` looks at a record the
way a careful experimentalist would before fitting anything, and says in
words what it found:

``contact_lost`` (refusal)
    The force falls below :data:`CONTACT_FRACTION` of body weight for at least
    :data:`CONTACT_MIN_DURATION`, to about zero (median under :data:`FLIGHT_FRACTION`,
    :func:`flights`): the person leaves the plate (jumping,
    running, hopping, walking on an insole). The model assumes contact.
``saturated`` (refusal)
    The force sits exactly at its largest (or smallest) value for runs of
    samples: the amplifier or the plate clipped, and the peaks are lost.
``not_rhythmic`` (refusal)
    No repeating force pattern: the autocorrelation of the force never
    reaches :data:`RHYTHM_MIN` at a lag of one bouncing period (a single
    jump, a squat, stepping on or off, noise), or fewer than
    :data:`MIN_REGULAR_CYCLES` periods fit in the active part of the record.
``another_gait`` (refusal)
    Consecutive cycles that alternate (a left/right rhythm) with pairs
    slower than anyone bounces (below :data:`BOUNCING_RANGE`): walking
    strides, not bouncing. Faster alternating pairs are bouncing with a
    dominant second harmonic as often as steps, and only warn (``two_humps``).
``two_humps`` (warning)
    Two force humps of similar size in the mean cycle: two steps per cycle
    as in walking with both feet on the plate, but also what bouncing with a
    resonance near twice the bouncing frequency gives (measured: 4 of 80
    simulated bouncing records, all with ``f_h / f_b`` 1.5-2), so it only warns.
``unusual_rate`` (warning)
    The force repeats at a rate outside :data:`BOUNCING_RANGE`.
``partly_active`` (warning)
    The person bounces only in part of the record (quiet standing elsewhere).
``mass_mismatch`` (warning)
    The mean force over the record, or over quiet standing, differs from
    ``M g`` by more than :data:`MASS_TOLERANCE`: the body mass given or the
    plate's zero is off.

The refusals raise :class:`NotBouncingError` (one line naming the reason and
the times; exit status 2 from the command line) unless the caller asks to go
on anyway, in which case they become warnings.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import SMDInputError
from .io import CONTACT_FRACTION, G, Record  # noqa: F401 - CONTACT_FRACTION is read here by signals.frontend

__all__ = ["NotBouncingError", "Finding", "BouncingCheck", "check_bouncing", "check_clipping", "repeating_period",
           "runs", "flights"]

CONTACT_MIN_DURATION = 0.03
"""Shortest loss of contact (s) reported: shorter dips are noise or impact transients."""

FLIGHT_FRACTION = 0.025
"""A dip under :data:`CONTACT_FRACTION` is a loss of contact only when the force in it is at most this fraction of
body weight at its median: off the plate the force is zero up to the plate's noise (about 1 %). A deep bounce near
the person's resonance dips to a few per cent of body weight each cycle and stays in contact (measured: a simulated
person at f_b 2.40 Hz, f_h 2.50 Hz, xi_h 0.105 dips to 4.7 %, and was cut into pieces of "no contact")."""

SATURATION_MIN_RUN = 4
"""Consecutive samples at exactly the record's extreme value that mark clipping."""

PERIOD_RANGE = (0.2, 1.25)
"""Lags searched for the bouncing period (s): bouncing frequencies 0.8-5 Hz."""

RHYTHM_MIN = 0.5
"""Least autocorrelation of the force at one period for a rhythmic record (bouncing: 0.7-1)."""

MIN_REGULAR_CYCLES = 8
"""Fewest bouncing periods in the active part of the record (the record-level model needs 8)."""

HUMP_RATIO = 0.5
"""A second hump of the mean cycle at least this fraction of the first's prominence is a second hump."""

ALTERNATION_MIN = 0.15
"""Relative difference of consecutive mean cycles (over two periods) above which the rhythm alternates.

Bouncing's consecutive cycles differ only at random, which the mean over a
record's pairs of cycles averages to a few per cent of the swing; a 0.12 BW
left/right difference in a 0.3 BW step force gives 0.28.
"""

BOUNCING_RANGE = (1.0, 4.5)
"""Bouncing frequencies (Hz) outside which a warning is given (the article's people: 1.5-3.5 Hz)."""

ACTIVE_FRACTION = 0.8
"""Below this fraction of the record bouncing, a warning says where the person bounced."""

ACTIVE_SPREAD = 0.03
"""Standard deviation of the force over one period, as a fraction of body weight, above which the person moves.

The front end's measure of movement takes this value (:data:`~smd_statespace.signals.frontend.ACTIVE_LEVEL`: the
RMS of the 0.7-10 Hz force over 1 s; for a force swinging by ``A`` both are about ``A / sqrt(2)``), so a bout it
keeps is not then counted as no cycles here. At 5 % (until 2026-11-30) a gentle bouncer, 110 kg swinging by about
70 N (a lab export of ``benchmarks/lab_records.py``'s held-out row, seed 4360, record 18), was refused as "0.0 force
cycles of 0.58 s in 30.3 s" after the front end had found 36 cycles of bouncing in it."""

MASS_TOLERANCE = 0.05
"""Relative difference between the mean force and ``M g`` that is reported."""


class NotBouncingError(SMDInputError):
    """The record is not one person bouncing in contact with the plate."""


@dataclass(frozen=True)
class Finding:
    """One thing the checks found.

    Attributes
    ----------
    kind : str
        ``contact_lost``, ``saturated``, ``not_rhythmic``, ``another_gait``,
        ``two_humps``, ``unusual_rate``, ``partly_active`` or ``mass_mismatch``.
    refuse : bool
        True when the model does not apply at all (a refusal), False for a warning.
    message : str
        What was found, in words, with times (s).
    """

    kind: str
    refuse: bool
    message: str


@dataclass
class BouncingCheck:
    """The checks of one record.

    Attributes
    ----------
    source : str
        The record's name.
    findings : list of Finding
    period : float
        The repeating period (s) found by the autocorrelation (nan if none).
    rhythm : float
        The autocorrelation of the force at that period (-1 to 1).
    active_seconds : float
        Time (s) in which the force varies like bouncing.
    """

    source: str
    findings: list = field(default_factory=list)
    period: float = float("nan")
    rhythm: float = float("nan")
    active_seconds: float = 0.0

    @property
    def refusals(self) -> list:
        """The findings that make the model inapplicable."""
        return [f for f in self.findings if f.refuse]

    @property
    def warnings(self) -> list:
        """The messages of the findings that only warn."""
        return [f.message for f in self.findings if not f.refuse]

    @property
    def bouncing(self) -> bool:
        """True when nothing refuses the record."""
        return not self.refusals

    def raise_if_refused(self, override=False) -> list:
        """Raise :class:`NotBouncingError` for the first refusal; with ``override``, return every finding as a warning.

        Returns
        -------
        list of str
            The warnings to print (``override`` turns refusals into warnings).
        """
        if self.refusals and not override:
            first = self.refusals[0]
            raise NotBouncingError(f"{self.source}: not a bouncing record ({first.kind}): {first.message}")
        return [f"{f.message} (checked, then identified anyway)" if f.refuse else f.message for f in self.findings]


def runs(mask):
    """``(start, stop)`` index pairs of the runs of True in ``mask`` (stop exclusive)."""
    edges = np.diff(np.r_[0, mask.astype(np.int8), 0])
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def flights(fraction, dt: float):
    """``(start, stop)`` index pairs where the force (as a fraction of body weight) shows the person off the plate.

    A run under :data:`CONTACT_FRACTION` at least :data:`CONTACT_MIN_DURATION` long whose median is at most
    :data:`FLIGHT_FRACTION`.
    """
    fraction = np.asarray(fraction, dtype=float)
    starts, stops = runs(fraction < CONTACT_FRACTION)
    keep = np.array([(b - a) * dt >= CONTACT_MIN_DURATION and np.median(fraction[a:b]) <= FLIGHT_FRACTION
                     for a, b in zip(starts, stops)], dtype=bool)
    return starts[keep], stops[keep]


def _times(time, starts, stops, limit=3) -> str:
    """``"3.61-4.02 s, 5.10-5.40 s, ..."`` for the first ``limit`` runs."""
    text = ", ".join(f"{time[a]:.2f}-{time[b - 1]:.2f} s" for a, b in zip(starts[:limit], stops[:limit]))
    return text + (", ..." if len(starts) > limit else "")


_PLATE_WORDS = {"leaves": "the person leaves the plate", "clipped": "plate or amplifier clipped",
                "force": "the force"}
_PHONE_WORDS = {"leaves": "the phone is in free fall: the person leaves the ground",
                "clipped": "accelerometer clipped (its range is too small)",
                "force": "the specific force M (g + a) from the phone"}


def _words(record) -> dict:
    """What the record's sensor is called in a finding: a force plate or a body-worn accelerometer."""
    return _PHONE_WORDS if (record.extra or {}).get("sensor") == "accelerometer" else _PLATE_WORDS


def _contact(time, weight_fraction, dt, words=_PLATE_WORDS) -> Finding | None:
    starts, stops = flights(weight_fraction, dt)
    if starts.size == 0:
        return None
    total = float(np.sum(stops - starts) * dt)
    ends = starts[0] == 0 or stops[-1] == len(time)  # the plate empty at the record's start or end
    how = ("stepping on or off, walking across, jumping, running" if ends and words is _PLATE_WORDS
           else "jumping, running, hopping")
    return Finding("contact_lost", True,
                   f"{words['force']} falls below {CONTACT_FRACTION:.0%} of body weight {starts.size} times "
                   f"({total:.2f} s in all: {_times(time, starts, stops)}): {words['leaves']} "
                   f"({how}); the SMD model assumes continuous contact")


def _saturation(time, force, weight, words=_PLATE_WORDS) -> Finding | None:
    span = float(np.ptp(force))
    if span <= 0.0:
        return Finding("not_rhythmic", True, "the force is constant: no measurement to identify")
    for label, extreme in (("largest", force.max()), ("smallest", force.min())):
        if label == "smallest" and extreme < CONTACT_FRACTION * weight:
            continue  # an empty plate reading its zero: no contact (``contact_lost``), not clipping
        starts, stops = runs(np.abs(force - extreme) <= 1e-9 * span)
        keep = stops - starts >= SATURATION_MIN_RUN
        if np.any(keep):
            return Finding("saturated", True,
                           f"the force sits at its {label} value {extreme:.1f} N for {int(keep.sum())} runs of "
                           f"{SATURATION_MIN_RUN} or more samples ({_times(time, starts[keep], stops[keep])}): the "
                           f"{words['clipped']}; record again with a larger range")
    return None


def _autocorrelation(x):
    """Normalised autocorrelation of ``x`` (mean removed), lags 0..len-1."""
    x = x - x.mean()
    n = x.size
    spectrum = np.fft.rfft(x, 2 * n)
    acf = np.fft.irfft(spectrum * np.conj(spectrum))[:n]
    return acf / acf[0] if acf[0] > 0 else np.zeros(n)


def repeating_period(weight_fraction, dt):
    """The bouncing period (s) and the autocorrelation there; the shortest lag near the best peak.

    Lags of :data:`PERIOD_RANGE` are searched; ``(nan, ...)`` when there is no peak there. Used by
    :func:`check_bouncing` and by the record front end (:func:`~smd_statespace.signals.find_bouts`).

    The lag is refined between samples by a parabola through the peak and its
    neighbours (a period of 62.5 samples read as 62 would slide the mean cycle
    by 24 samples over 48 cycles).
    """
    from scipy import signal  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)

    acf = _autocorrelation(weight_fraction)
    lo, hi = int(round(PERIOD_RANGE[0] / dt)), min(int(round(PERIOD_RANGE[1] / dt)), acf.size - 2)
    if hi <= lo + 2:
        return float("nan"), float("nan")
    peaks, _ = signal.find_peaks(acf[lo:hi + 1])
    if peaks.size == 0:
        return float("nan"), float(np.max(acf[lo:hi + 1]))
    values = acf[lo + peaks]
    # a multiple of the period correlates about as well as the period itself: take the shortest
    good = peaks[values >= values.max() - 0.1 * abs(values.max())]  # (the highest itself when all are negative)
    lag = lo + int(good[0])
    left, centre, right = acf[lag - 1], acf[lag], acf[lag + 1]
    curvature = left - 2.0 * centre + right
    shift = 0.5 * (left - right) / curvature if curvature < 0 else 0.0
    return (lag + float(np.clip(shift, -0.5, 0.5))) * dt, float(centre)


def _active(time, weight_fraction, period):
    """Mask of samples inside windows (one period long) whose force's sd is over :data:`ACTIVE_SPREAD` of body weight.

    A window at either end of the record holds only the record's own samples (the moving sums divided by how many
    samples they add): padded with zeros, a person standing at the start or the end looked as if bouncing there, and
    the warning of a partly active record named 0.00-0.25 s and 29.75-30.00 s of a lab export that stands for 4 s at
    both ends."""
    n = max(int(round(period / (time[1] - time[0]))), 3)
    window = np.ones(n)
    count = np.convolve(np.ones_like(weight_fraction), window, mode="same")
    mean = np.convolve(weight_fraction, window, mode="same") / count
    spread = np.sqrt(np.maximum(np.convolve(weight_fraction**2, window, mode="same") / count - mean**2, 0.0))
    return spread > ACTIVE_SPREAD


def _mean_cycle(weight_fraction, dt, period, count):
    """Mean force over ``count`` consecutive periods, by phase (``round(count period / dt)`` bins)."""
    bins = int(round(count * period / dt))
    if weight_fraction.size * dt < 2 * count * period or bins < 4:
        return None
    phase = (np.arange(weight_fraction.size) * dt / (count * period)) % 1.0
    index = np.minimum((phase * bins).astype(int), bins - 1)
    total = np.bincount(index, weights=weight_fraction, minlength=bins)
    number = np.bincount(index, minlength=bins)
    return total / np.maximum(number, 1)


def _gait(weight_fraction, dt, period) -> Finding | None:
    one = _mean_cycle(weight_fraction, dt, period, 1)
    two = _mean_cycle(weight_fraction, dt, period, 2)
    if one is None or two is None:
        return None
    samples = one.size
    swing = float(np.ptp(one))
    if swing <= 0:
        return None
    halves = np.vstack([two[: two.size // 2], two[two.size // 2: 2 * (two.size // 2)]])
    alternation = float(np.sqrt(np.mean((halves[0] - halves[1]) ** 2)) / swing)
    if alternation > ALTERNATION_MIN:
        if 0.5 / period < BOUNCING_RANGE[0]:  # pairs of cycles slower than anyone bounces: strides
            return Finding("another_gait", True,
                           f"consecutive {period:.2f} s cycles alternate (they differ by {alternation:.0%} of the "
                           f"force swing; pairs repeat at {0.5 / period:.2f} Hz): a left/right rhythm like walking, "
                           "not bouncing")
        return Finding("two_humps", False,
                       f"consecutive {period:.2f} s force humps alternate (they differ by {alternation:.0%} of the "
                       f"force swing): bouncing at {0.5 / period:.2f} Hz with a dominant second harmonic, or two "
                       "steps per cycle as in walking; the SMD model describes only the first")
    circular = np.r_[one, one, one]
    from scipy import signal  # imported here: scipy.signal, scipy.stats take ~1 s (not needed to start)

    peaks, props = signal.find_peaks(circular, prominence=0.05 * swing)
    inside = (peaks >= samples) & (peaks < 2 * samples)
    prominence = np.sort(props["prominences"][inside])[::-1]
    if prominence.size >= 2 and prominence[1] >= HUMP_RATIO * prominence[0]:
        return Finding("two_humps", False,
                       f"the mean {period:.2f} s cycle has two force humps (the second {prominence[1] / prominence[0]:.0%} "
                       "of the first): two steps per cycle as in walking, or bouncing "
                       "with a dominant second harmonic (a resonance near twice the bouncing frequency); the SMD "
                       "model describes only the second")
    return None


def _mass_mismatch(mass: float, fraction: np.ndarray, active: np.ndarray, dt: float):
    """A ``mass_mismatch`` warning, or None if the body mass fits the force.

    The warning says that the mean force while bouncing, or else over at least 1 s of
    quiet standing, differs from ``M g`` by more than :data:`MASS_TOLERANCE`
    (``fraction`` is the force in units of ``M g``).
    """
    quiet = ~active
    mean_ratio = float(np.mean(fraction[active]))
    if abs(mean_ratio - 1.0) > MASS_TOLERANCE:
        return Finding(
            "mass_mismatch", False,
            f"the mean force while bouncing is {mean_ratio:.3f} times M g ({mass:.1f} kg): the body mass "
            f"given or the plate's zero is off (the force says {mass * mean_ratio:.1f} kg)")
    if quiet.sum() * dt >= 1.0 and abs(float(np.mean(fraction[quiet])) - 1.0) > MASS_TOLERANCE:
        ratio = float(np.mean(fraction[quiet]))
        return Finding(
            "mass_mismatch", False,
            f"quiet standing ({quiet.sum() * dt:.1f} s) weighs {ratio:.3f} times M g ({mass:.1f} kg): the "
            f"body mass given or the plate's zero is off (standing says {mass * ratio:.1f} kg)")
    return None


def check_clipping(record: Record) -> BouncingCheck:
    """The ``saturated`` refusal of :func:`check_bouncing` alone, cheap on a record at any rate.

    For the record as read: a decimation's low-pass rounds clipped tops off, so the full check, run on the
    decimated record, no longer sees them. Its findings are empty or the one refusal.
    """
    found = _saturation(np.asarray(record.time, dtype=float), np.asarray(record.force, dtype=float),
                        record.mass * G, _words(record))
    return BouncingCheck(source=str(record.source), findings=[] if found is None else [found])


def check_bouncing(record: Record) -> BouncingCheck:
    """Check that ``record`` is one person bouncing in contact with the plate.

    Parameters
    ----------
    record : Record
        The measurement (``time`` in s, ``force`` in N, ``mass`` in kg).

    Returns
    -------
    BouncingCheck
        The findings (refusals and warnings), the period found and its
        autocorrelation. Call :meth:`BouncingCheck.raise_if_refused` to
        refuse.

    Examples
    --------
    >>> import numpy as np
    >>> from smd_statespace.io import make_record
    >>> t = np.arange(0, 20, 0.01)
    >>> standing = make_record(t, np.full(t.size, 700.0) + np.random.default_rng(0).normal(0, 5, t.size), 71.4)
    >>> check_bouncing(standing).refusals[0].kind
    'not_rhythmic'
    """
    time = np.asarray(record.time, dtype=float)
    force = np.asarray(record.force, dtype=float)
    dt = float(time[1] - time[0])
    weight = record.mass * G
    fraction = force / weight
    check = BouncingCheck(source=str(record.source))
    words = _words(record)
    for finding in (_contact(time, fraction, dt, words), _saturation(time, force, weight, words)):
        if finding is not None:
            check.findings.append(finding)
    period, rhythm = repeating_period(fraction, dt)
    check.period, check.rhythm = period, rhythm
    duration = float(time[-1] - time[0] + dt)
    if not np.isfinite(period) or not rhythm >= RHYTHM_MIN:
        spread = float(np.std(fraction[fraction > CONTACT_FRACTION])) if (fraction > CONTACT_FRACTION).any() else 0.0
        what = (f"the sd of {words['force']} is {spread:.1%} of body weight: standing (or swaying) still, not bouncing"
                if spread < ACTIVE_SPREAD else "a single event (a jump, a squat, stepping on or off) or noise")
        check.findings.append(Finding(
            "not_rhythmic", True,
            f"no repeating force pattern in {duration:.1f} s (autocorrelation at most "
            f"{0.0 if not np.isfinite(rhythm) else rhythm:.2f} at lags of {PERIOD_RANGE[0]:g}-{PERIOD_RANGE[1]:g} s, "
            f"bouncing gives more than {RHYTHM_MIN:g}): {what}"))
        return check
    active = _active(time, fraction, period)
    check.active_seconds = float(active.sum() * dt)
    cycles = check.active_seconds / period
    if cycles < MIN_REGULAR_CYCLES:
        check.findings.append(Finding(
            "not_rhythmic", True,
            f"{cycles:.1f} force cycles of {period:.2f} s in {duration:.1f} s; bouncing needs at least "
            f"{MIN_REGULAR_CYCLES} regular cycles (the force's sd over a period is above {ACTIVE_SPREAD:.0%} of body "
            f"weight for {check.active_seconds:.1f} s: a shorter bout, or bouncing gentler than that, which is not "
            "told from standing)"))
        return check
    gait = _gait(fraction, dt, period)
    if gait is not None:
        check.findings.append(gait)
    if not BOUNCING_RANGE[0] <= 1.0 / period <= BOUNCING_RANGE[1]:
        check.findings.append(Finding(
            "unusual_rate", False,
            f"the force repeats every {period:.2f} s ({1.0 / period:.2f} Hz), outside "
            f"{BOUNCING_RANGE[0]:g}-{BOUNCING_RANGE[1]:g} Hz where people bounce (the article: 1.5-3.5 Hz)"))
    if check.active_seconds < ACTIVE_FRACTION * duration:
        starts, stops = runs(active)
        check.findings.append(Finding(
            "partly_active", False,
            f"the person bounces in {check.active_seconds:.1f} s of {duration:.1f} s "
            f"({_times(time, starts, stops)}); the quiet parts carry no information on the person"))
    mass = _mass_mismatch(record.mass, fraction, active, dt)
    if mass is not None:
        check.findings.append(mass)
    return check

"""What a phone's record shows of a phone's own artefacts, in words, when the person is not determined.

A force plate samples on a clock that does not drift or stall, along an axis that does not turn.
A phone does neither: it drops samples and bursts of them (the samples in a gap are left out of the
likelihood, :data:`~smd_statespace.accelerometer.record.GAP_SAMPLES`), samples at scattered instants or stamps
its samples late or early (the reading tells which: ``clock["samples_at"]``), and turns with the body (the
vertical is a low-pass of the gravity it sees). When a phone record leaves ``f_h`` or ``xi_h`` undetermined, or
its innovations are heavy-tailed, :func:`phone_words` says which of these the record shows and how strongly, from what the reading
measured (``record.extra["clock"]``, ``["geometry"]``), so that a user knows whether to record
again (and how) or whether the person is what the record leaves open.
"""

from __future__ import annotations

from ..accelerometer.record import GAP_SAMPLES

__all__ = ["JITTER_FRACTION", "TURN_DEGREES", "HEAVY_TAILS", "phone_words"]

JITTER_FRACTION = 0.1
"""Stamps scattered about the phone's fitted clock by more than this fraction of a sample interval are named (1 ms
at 200 Hz, 20 %, raised the vertical's kurtosis from 3 to 4-6 on simulated records)."""

TURN_DEGREES = 10.0
"""A gravity direction that turns by more than this over the record is named (the phone tilting or swaying with
the body; its component at the bouncing frequency is not followed)."""

HEAVY_TAILS = 5.0
"""Kurtosis of the innovations from which they are called heavy-tailed (3 for Gaussian ones)."""


def _clock_words(clock: dict) -> list:
    words = []
    fs = float(clock.get("fs_nominal", 0.0) or 0.0)
    gap = float(clock.get("largest_gap", 0.0) or 0.0)
    if fs > 0 and gap > GAP_SAMPLES / fs:
        dropped = int(clock.get("n_dropped", 0))
        share = 100.0 * dropped / max(int(clock.get("n_samples_in", 1)) + dropped, 1)
        words.append(f"{dropped} samples missing ({share:.1f} %), the longest gap {gap:.3g} s at "
                     f"{float(clock.get('largest_gap_at', 0.0)):.1f} s ({gap * fs:.0f} samples; the gaps are left "
                     "out of the likelihood, and the person is read across them)")
    jitter = float(clock.get("jitter_sd", 0.0) or 0.0)
    if fs > 0 and jitter * fs > JITTER_FRACTION:
        how = ("read as samples taken on the clock and stamped late or early" if clock.get("samples_at") ==
               "regular clock" else "read as samples taken at their stamps: if they were taken on time and stamped "
               "late, every value is read at the wrong instant")
        words.append(f"time stamps scattered by {1e3 * jitter:.2g} ms about the phone's clock "
                     f"({100 * jitter * fs:.0f} % of a sample, {how})")
    return words


def phone_words(result) -> str:
    """One warning about a phone record's own artefacts, or ``""``.

    Said for an accelerometer's record whose ``f_h`` or ``xi_h`` is not determined or whose
    innovations are heavy-tailed (kurtosis over :data:`HEAVY_TAILS`): the gaps, the stamps' scatter
    and the turning of the gravity direction that exceed
    :data:`~smd_statespace.accelerometer.record.GAP_SAMPLES`,
    :data:`JITTER_FRACTION` and :data:`TURN_DEGREES`, each with its size; or that none does.
    """
    extra = result.record.extra
    if extra.get("sensor") != "accelerometer":
        return ""
    kurtosis = result.test_pvalues()["kurtosis"]
    open_ = [name for name in ("f_h", "xi_h") if not result.determined(name)]
    if not open_ and kurtosis <= HEAVY_TAILS:
        return ""
    words = _clock_words(extra.get("clock", {}))
    turned = (extra.get("geometry", {}) or {}).get("direction_change_deg")
    if turned is not None and turned > TURN_DEGREES:
        words.append(f"the gravity direction turned by {turned:.0f} degrees over the record (the phone tilting with "
                     "the body, or handled; the part of it at the bouncing frequency is not followed)")
    what = (f"{' and '.join(open_)} not determined" if open_ else "") + (
        f"{'; ' if open_ else ''}innovations heavy-tailed (kurtosis {kurtosis:.1f})" if kurtosis > HEAVY_TAILS
        else "")
    if not words:
        return (f"{what}: this phone record shows none of a phone's known artefacts strongly (gaps under "
                f"{GAP_SAMPLES:g} samples, stamps within {100 * JITTER_FRACTION:.0f} % of a sample, the direction "
                f"within {TURN_DEGREES:g} degrees): what is open is the person or the force, as on a plate")
    return f"{what}; this phone record shows: " + "; ".join(words) + (
        ": record with the phone held firm, at its highest rate, with nothing else running")

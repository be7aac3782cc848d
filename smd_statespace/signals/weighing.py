"""The plate weighs the person: the body mass from a record's standing, when none is given.

A lab trial starts and ends with the person standing still on the plate (the front end's
:func:`~smd_statespace.signals.find_bouts` finds those parts): the force there is the body weight
``M_h g``, which is how labs weigh their subjects. A record read without a mass
(:func:`~smd_statespace.io.read_record` with ``mass=None``, ``identify REC`` without ``--mass``) carries a
provisional mass (the median of its loaded force over ``g``) and ``extra["weigh"]``;
:func:`weigh_record` replaces it with what the plate says:

1. the mean force while standing before the first bout of bouncing (at least :data:`MIN_STANDING` s, the
   0.25 s next to any movement left out), over ``g``: where the plate's zero is nearest to where it was set;
2. else the mean force over the longest bout's whole cycles (peak to peak): over whole cycles of a periodic
   motion the body's momentum returns to itself, so the mean GRF is the weight (Eq. 3 averaged), with the
   zero's drift averaged over the bout in it (standing after bouncing has all of the drift in it, so it is not
   used);
3. else, with no bouncing, the standing;
4. else (no standing, no bouncing) it cannot be weighed, and says so in one line.

The plate's zero goes into the weight: a zero off by 5 N makes the mass 0.5 kg heavier (the fit takes a zero's
offset either way; ``f_h`` and ``xi_h`` do not depend on the mass, ``K_h``, ``C_h`` and the BLFs scale with it).
A note says which part weighed the person.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import RecordError
from ..io import G, Record, check_mass
from .frontend import Bouts, find_bouts, mains_hum, remove_hum

__all__ = ["MIN_STANDING", "LEVELS_APART", "weigh_record"]

MIN_STANDING = 0.3
"""Shortest standing part (s) that weighs the person (the front end's standing parts already leave out the 0.25 s
next to any movement)."""

LEVELS_APART = 0.02
"""Standing levels before and after bouncing further apart than this fraction of the weight are said in the note
(the plate's zero drifted, or the person picked something up): the level before is the weight."""


def weigh_record(record: Record) -> Record:
    """``record`` with its body mass weighed on the plate, when it was read without one (``extra["weigh"]``).

    Parameters
    ----------
    record : Record
        A force plate's record (force in N). One read with a mass, or weighed already, is returned as it is.

    Returns
    -------
    Record
        The mass (kg) from the standing parts or the bouncing cycles (the module's docstring), the way it was
        weighed in words appended to ``extra["reading"]`` and kept in ``extra["weighed"]``.

    Raises
    ------
    RecordError
        Neither standing nor bouncing to weigh the person on.
    MassError
        What the plate reads is no person's weight (outside :data:`~smd_statespace.io.MASS_RANGE`).
    """
    if not record.extra.get("weigh"):
        return record
    clean = remove_hum(record, mains_hum(record))
    bouts = find_bouts(clean)
    level, words = _level(bouts, clean)
    if abs(level / (record.mass * G) - 1.0) > 0.05:  # the thresholds scale with the mass: find the parts again
        bouts = find_bouts(replace(clean, mass=level / G))
        level, words = _level(bouts, clean)
    mass = check_mass(level / G, f"{record.source}: weighed on the plate ({words})")
    note = f"body mass {mass:.1f} kg weighed on the plate: {words} (no mass given)"
    extra = {**record.extra, "weigh": False, "weighed": words, "reading": [*record.extra.get("reading", ()), note]}
    return replace(record, mass=mass, extra=extra)


def _standing(bouts: Bouts) -> list:
    """The standing parts of at least :data:`MIN_STANDING` s before the first bout."""
    if not bouts.found:
        return []
    return [s for s in bouts.segments if s.kind == "standing" and s.end - s.start >= MIN_STANDING
            and s.end <= bouts.bouts[0].start]


def _level(bouts: Bouts, record: Record) -> tuple:
    """``(force, words)``: the weight (N) the record says, and which part said it."""
    spans = _standing(bouts)
    if spans and np.isfinite(bouts.level_before):
        level = bouts.level_before
        words = f"standing {' and '.join(f'{s.start:.1f}-{s.end:.1f} s' for s in spans)} reads {level:.1f} N"
        if np.isfinite(bouts.level_after) and abs(bouts.level_after / level - 1.0) > LEVELS_APART:
            words += f" ({bouts.level_after:.1f} N after bouncing: the plate's zero drifted, or the load changed)"
        return level, words
    drifted = "; a drift of the plate's zero since it was set is in it: give --mass if you know it"
    if bouts.found:  # the zero's drift averaged over the bout: nearer its start than standing after it is
        bout = max(bouts.bouts, key=lambda b: b.cycles)
        inside = (record.time >= bout.start) & (record.time <= bout.end)
        level = float(np.mean(record.force[inside]))
        return level, (f"the mean force over {bout.cycles} whole bouncing cycles, {bout.start:.1f}-{bout.end:.1f} s, "
                       f"reads {level:.1f} N (no standing of {MIN_STANDING:g} s or more before bouncing{drifted})")
    if np.isfinite(bouts.level_before):
        return bouts.level_before, f"standing reads {bouts.level_before:.1f} N (no bouncing found)"
    raise RecordError(f"{record.source}: no mass given, and the record has neither standing nor bouncing to weigh "
                      "the person on; give the body mass with --mass KG (mass=KG)")

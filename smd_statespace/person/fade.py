"""A force that fades (or grows) over the record: a person who tires.

A bout of 20-30 s on a plate is rarely bounced with one effort: people tire, and the force's harmonics fall
over the bout (a simulated lab export whose BLFs lose 30 % over it: ``simulate --lab --tire 0.3``). The
variation models of :mod:`~smd_statespace.person.model` let the coefficients wander about one template; a
steady fall is not in them, and what they cannot take went into the person. On 13 such records
(``simulate_lab_record(tire=0.3)``, seeds 1-13) ``f_h`` was determined on 3 and one was 49 % off: the
score tests of a change in time (:func:`~smd_statespace.person.screen.time_change`) read the fading force as
the person changing, and the intervals were widened across the halves' answers.

With the fade in the model the force's harmonics are scaled by ``1 + c s(t)``, ``s`` from -1 at the first
sample to 1 at the last (the template is the force at mid-record; ``1 - c`` of it at the start, ``1 + c`` at
the end). The shape scaled is the template of the fit before (the ``phase_template`` with which the model
places the cycle starts, :mod:`~smd_statespace.person.timing`), so ``c`` is one more linear unknown,
concentrated out with the template (generalised least squares): no search dimension is added. One factor for
every harmonic, not a fade of its own for each: a leg that stiffens or softens changes each harmonic's
response by its own amount and phase (Eq. 2), which a free drift of every harmonic would take for a fading
force (measured: with the first two harmonics fading freely, an 8 % step of ``f_h`` in a lab export was no
longer found by the score tests of a change in time).

Measured: on the 13 tiring records above, ``f_h`` determined on 9 instead of 3, the worst 14 % off instead of 49 %,
every interval holding the truth; 6 of the same people not tiring gave the same ``f_h`` within 0.3 % (code
375ebac). On 31 lab exports of ``benchmarks/lab_records.py`` (seeds 4349, 4350; people tiring by 0-30 %), the
stationary people said to change fell from 14 to 0 and ``f_h`` was determined on 14 instead of 8, all covered;
the median error moved from 2.2 and 3.5 % to 3.3 and 4.5 % (``benchmarks/results/lab_records_fade.md``).

``identify_person(fade="auto")`` models the fade where the record was trimmed to a bout of bouncing (a trial
as labs export it, with standing before and after); ``fade=True`` on any record, ``fade=False`` never. The
fits at the first cycle timing, which have no template yet, are made without it.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import OptionError
from ..io import G
from .system import Regressor

__all__ = ["FADE_OPTIONS", "NOTE_TAIL", "fading", "fade_regressor", "fade_shift", "fade_table", "fade_note"]

FADE_OPTIONS = ("auto", True, False)
"""Values of ``identify_person``'s ``fade``."""

NOTE_TAIL = "its harmonics were let fade linearly with the person"
"""What every note of :func:`fade_note` says, by which :func:`~smd_statespace.person.answer.person_result` gives a fit
its own note, not one handed on from the fit it extends."""

CLEAR_FADE = 2.576
"""A fade is said in words when ``|c|`` is at least this many of its sds (two-sided level 0.01, the level of the
person's other tests in words: a change in time, whiteness); else it is "within its noise". On 24 steady lab
exports (20 s bouts) ``c / sd`` scattered as a standard normal (at 2 sds, 2 of them were told their force faded
or grew: one in twenty, as a standard normal has it); a person tiring by 30-40 % gives 20 sds or more."""


def fading(fade, trimmed: bool, timing: str = "model") -> bool:
    """Whether the fade is modelled: ``fade`` True, or "auto" on a ``trimmed`` record, with ``timing="model"``
    (the fade scales the template that the model's own timing estimates; another timing has none, and "auto"
    leaves the fade out). An :class:`OptionError` names a value not in :data:`FADE_OPTIONS`, or ``fade=True``
    with another timing."""
    if fade is not True and fade is not False and fade != "auto":
        raise OptionError(f"fade={fade!r} is not one of: 'auto' (where the record was trimmed to a bout), True, False")
    if fade is True and timing != "model":
        raise OptionError(f"fade=True needs timing='model' (the default; --timing model): the fade scales the force "
                          f"template that timing estimates, and timing={timing!r} has none")
    return fade is True or (fade == "auto" and trimmed)


def _scaled_time(time) -> np.ndarray:
    """``s(t)``: -1 at the first sample, 1 at the last."""
    time = np.asarray(time, dtype=float)
    return 2.0 * (time - time[0]) / max(time[-1] - time[0], 1e-12) - 1.0


def fade_regressor(time, basis, template) -> Regressor:
    """The fade's regressor ``s(t) g F~(theta(t))``: ``F~`` the harmonics of ``template`` (Eq. 4 without ``a0``).

    Parameters
    ----------
    time : ndarray, shape (N,)
        Sample times (s).
    basis : ndarray, shape (N, 2 n + 1)
        Eq. 4's functions at the samples: ``1, cos(theta), sin(theta), ..., sin(n theta)``.
    template : ndarray, shape (2 n + 1,)
        The force's coefficients (g) whose harmonics fade.

    Returns
    -------
    Regressor
        ``fade`` (dimensionless ``c``: the harmonics are ``1 - c`` of the template's at the first sample, ``1 + c``
        at the last), dynamic (the force moves the person).

    Examples
    --------
    >>> basis = np.column_stack([np.ones(3), np.cos([0.0, 1.0, 2.0]), np.sin([0.0, 1.0, 2.0])])
    >>> fade_regressor([0.0, 1.0, 2.0], basis, np.array([0.0, 0.3, 0.0])).values / G
    array([-0.3       ,  0.        , -0.12484405])
    """
    template = np.asarray(template, dtype=float)
    return Regressor("fade", _scaled_time(time) * G * (basis[:, 1:] @ template[1:]), "-")


def fade_shift(result, samples) -> np.ndarray:
    """What the fade adds to the force's coefficients at ``samples`` (indices into the record), shape
    ``(len(samples), n_coefficients)`` (g): ``c s(t)`` times the faded template's harmonics, 0 for ``a0`` and
    everywhere without the fade. The smoother's coefficient states hold the template and each cycle's deviation,
    not the fade (a regressor's); with this added they are the cycles' forces
    (:attr:`~smd_statespace.person.results.PersonResult.cycles`)."""
    model = result.model
    out = np.zeros((len(samples), model.n_coefficients))
    if "fade" in model.delta_names:
        c = result.regressor_coefficients().loc["fade", "value"]
        out[:, 1:] = c * _scaled_time(model.time)[samples, None] * np.asarray(model.phase_template)[None, 1:]
    return out


def fade_table(result) -> pd.DataFrame:
    """Each harmonic's load factor at the record's start, middle and end (g), with the fade ``c`` and its sd.

    Columns ``start``, ``middle`` (the template's ``BLF_i``), ``end``, and ``c``, ``c_sd`` (the same on every
    row). Empty when the fade is not in ``result``'s model.
    """
    columns = ["start", "middle", "end", "c", "c_sd"]
    model = result.model
    if "fade" not in model.delta_names:
        return pd.DataFrame(columns=columns)
    fade = result.regressor_coefficients().loc["fade"]
    c, c_sd = float(fade["value"]), float(fade["sd"])
    delta = result.filtered["delta"]  # the fit's own template
    template, faded = delta[model.n_dynamic:model.n_dynamic + model.n_coefficients], np.asarray(model.phase_template)
    rows = {}
    for i in range(1, model.n_harmonics + 1):
        pair, shape = template[2 * i - 1:2 * i + 1], faded[2 * i - 1:2 * i + 1]
        rows[i] = {"start": float(np.hypot(*(pair - c * shape))), "middle": float(np.hypot(*pair)),
                   "end": float(np.hypot(*(pair + c * shape))), "c": c, "c_sd": c_sd}
    return pd.DataFrame.from_dict(rows, orient="index", columns=columns).rename_axis("harmonic")


def fade_note(result) -> str:
    """The line that says what the fade found: BLF1 at the start and the end, or that the fade is within its
    noise (:data:`CLEAR_FADE`); empty without the fade."""
    table = fade_table(result)
    if table.empty:
        return ""
    first = table.loc[1]
    values = f"BLF1 {first['start']:.3f} g at its start, {first['end']:.3f} g at its end"
    if abs(first["c"]) >= CLEAR_FADE * first["c_sd"]:
        change = 100 * (first["end"] / first["start"] - 1) if first["start"] > 0 else np.inf
        said = (f"the force {'fades' if first['c'] < 0 else 'grows'} over the record: {values} ({change:+.0f} %; "
                f"c {first['c']:+.3f}, sd {first['c_sd']:.3f})")
    else:
        said = f"the force's fade over the record is within its noise ({values})"
    return f"{said}; {NOTE_TAIL} (fade=False or --fade off leaves it out; docs/lab-records.md)"

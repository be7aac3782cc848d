"""Every bout of a session: one person per bout of bouncing, against the bouncing frequency.

A lab that repeats the article's protocol (Section 5: each subject bouncing at several metronome rates) often
records one trial per subject: standing, bouncing at one rate, standing, bouncing at the next, ... The front end
(:func:`~smd_statespace.signals.find_bouts`) finds the bouts, and :func:`~smd_statespace.person.identify_person`
fits the longest and names the others. :func:`identify_bouts` fits each bout's steady part on its own (its
``span``), so that the person's parameters can be read against the bouncing frequency as in the article's
Figs. 6-8 (``identify REC --span each``; :func:`~smd_statespace.plotting.people.plot_people` draws them).

A bout that cannot be identified (too few cycles, not bouncing after all) is kept as a failed row with its reason;
the others are answered.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import SMDInputError
from ..io import Record
from ..signals import find_bouts, mains_hum, remove_hum
from ..signals.weighing import weigh_record

__all__ = ["BoutAnswer", "BoutSpan", "identify_bouts"]


class BoutSpan(tuple):
    """A bout's steady part ``(start, end)`` (s), as a span for :func:`~smd_statespace.person.identify_person`, that
    says where it came from (``said``) in the note of the fitted span: "bout 2's steady part", not "as given"."""

    def __new__(cls, start: float, end: float, said: str):
        span = super().__new__(cls, (float(start), float(end)))
        span.said = said
        return span


@dataclass(frozen=True)
class BoutAnswer:
    """One bout of bouncing and its person.

    Attributes
    ----------
    number : int
        The bout's number in the record, from 1, in time order.
    start, end : float
        The steady part fitted (s, on the record's time axis).
    cycles : int
        Its whole cycles, as the front end counted them.
    f_b : float
        Its bouncing frequency (Hz): one over the front end's period, or the fitted timing's median.
    result : PersonResult or None
        The person (None when the bout could not be identified).
    error : str
        Why not, in one line ("" when identified).
    """

    number: int
    start: float
    end: float
    cycles: int
    f_b: float
    result: object = None
    error: str = ""

    @property
    def name(self) -> str:
        """``bout 2 (25.1-44.9 s)``."""
        return f"bout {self.number} ({self.start:.1f}-{self.end:.1f} s)"

    def row(self) -> dict:
        """One row of the session's table: the bout (``label`` names it in figures), ``status`` and ``reason``, and
        the person's :meth:`~smd_statespace.person.results.PersonResult.table_row` when identified."""
        out = {"bout": self.number, "label": self.name, "start_s": self.start, "end_s": self.end,
               "cycles": self.cycles, "status": "ok" if self.result is not None else "failed",
               "reason": self.error}
        if self.result is not None:
            out.update(self.result.table_row())
        out.setdefault("f_b", self.f_b)
        return out

    def line(self) -> str:
        """The bout's answer in one line."""
        if self.result is None:
            return f"{self.name}, {self.cycles} cycles at f_b {self.f_b:.2f} Hz: not identified: {self.error}"
        r = self.result
        determined = r.to_dict()
        parts = []
        for name in ("f_h", "xi_h"):
            low, high = (float(v) for v in r.intervals[name])
            value = getattr(r, name)
            unit = " Hz" if name == "f_h" else ""
            flag = "" if determined[f"{name}_determined"] else " NOT DETERMINED"
            parts.append(f"{name} {value:.3f}{unit} ({low:.2f}-{high:.2f}){flag}")
        said = [w for w in r.warnings if "is not determined" not in w]  # "NOT DETERMINED" says those
        warned = f"; warning: {said[0].split(':')[0]}" + (f" (and {len(said) - 1} more)" if len(said) > 1 else "") \
            if said else ""
        return f"{self.name}, {self.cycles} cycles at f_b {self.f_b:.2f} Hz: " + ", ".join(parts) + warned


def identify_bouts(record: Record, **options) -> list:
    """Identify the person of every bout of bouncing in ``record``, each on its own.

    Parameters
    ----------
    record : Record
        A whole trial (force in N), with one or more bouts of bouncing (read without a mass, it is weighed on the
        plate first: :func:`~smd_statespace.signals.weighing.weigh_record`).
    **options
        :func:`~smd_statespace.person.identify_person`'s keyword arguments but ``span`` (each bout's steady part
        is its span).

    Returns
    -------
    list of BoutAnswer
        In time order; a bout that could not be identified has ``result`` None and its reason.

    Raises
    ------
    RecordError
        The record has no bout of bouncing (the front end's words), or cannot be weighed.
    OptionError
        ``span`` among the options.
    """
    from ..errors import OptionError
    from .fit import identify_person

    if "span" in options:
        raise OptionError("identify_bouts: each bout's steady part is its span; give no span (or use "
                          "identify_person(record, span=...) for one part)")
    record = weigh_record(record)
    bouts = find_bouts(remove_hum(record, mains_hum(record))).require()
    answers = []
    for number, bout in enumerate(bouts.bouts, start=1):
        f_b = 1.0 / bout.period
        try:
            result = identify_person(record, span=BoutSpan(*bout.span, f"bout {number}'s steady part"), **options)
        except SMDInputError as exc:
            answers.append(BoutAnswer(number, bout.start, bout.end, bout.cycles, f_b, None,
                                      " ".join(str(exc).split())))
            continue
        answers.append(BoutAnswer(number, bout.start, bout.end, bout.cycles, f_b, result))
    return answers

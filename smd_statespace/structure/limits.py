"""Acceptance limits from published guidance, with where each number was read, and a response classified against them.

Only numbers read in a named source are here. What was found (searched for in the stored public corpora,
2026-11-29):

- :data:`ROUTE2` -- the IStructE/DCLG/DCMS (2008) grandstand guide's Route 2 criteria, one per event scenario, on
  the maximum 1 s RMS vertical acceleration: 3, 7.5 and 20 %g for scenarios 2, 3 and 4. Read in an open-source
  implementation of Route 2, not in the guide: ``sgettler/grandstand-dynamics`` (MIT licence),
  ``grandstand-dynamics/src-old/runIstructeTerraceAnalysis.m`` at commit a09e62f (its criteria array, "rms
  criteria by scenario (%g)"; it reports a scenario's criterion as exceeded when the maximum 1 s RMS is above
  it), with the scenarios' loads in ``getScenarioResponse.m`` and the measure in ``getCrowdStructureResponse.m``
  (the largest RMS over consecutive, non-overlapping 1 s windows of the acceleration as computed, no frequency
  weighting; %g with g = 9.81 m/s^2). The guide's own table, its number and its words for the levels were not
  found: the stored copies of the guide yield its front matter only. So the bands below carry no words of the
  guide; they say which scenarios' criteria a value is within.

Not found, so not here: the guide's comfort words for its levels; BS 6472-1:2008's VDV ranges (only a
repository's prompt text quotes them, not a source one can cite); ISO 10137 or Eurocode-related floor limits for a
crowd.

The library's ``rms_1s_max`` slides its 1 s window one sample at a time (:func:`~.response.running_rms`), so it is
the source's non-overlapping maximum or larger: a classification here is never the more lenient one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .response import MEASURES

__all__ = ["Criterion", "Limits", "ROUTE2", "LIMITS", "G_SOURCE", "MODELS"]

MODELS = {"coupled": "coupled", "force_only": "force-only"}
"""The two models of a structure's response, as its tables prefix their columns (``coupled_rms_1s_max``), and as
they are printed."""

G_SOURCE = 9.81
"""m/s^2: the g the Route 2 source converts %g with (``/9.81*100``); the criteria in m/s^2 are ``%g / 100 * 9.81``."""


@dataclass(frozen=True)
class Criterion:
    """One criterion of a set of limits.

    Attributes
    ----------
    name : str
        What it applies to, e.g. ``"2"`` (scenario 2).
    limit : float
        m/s^2 (or m/s^1.75 for a VDV); a value equal to it is within it.
    stated : str
        The limit as the source states it, e.g. ``"3 %g"``.
    load : str
        What the source loads the structure with for it.
    """

    name: str
    limit: float
    stated: str
    load: str


@dataclass(frozen=True)
class Limits:
    """A set of criteria on one measure, from one source: the data, the bands between them, the classification.

    Attributes
    ----------
    name : str
        Short name (the key in :data:`LIMITS`).
    measure : str
        The :data:`~.response.MEASURES` name the criteria apply to (e.g. ``"rms_1s_max"``).
    kind : str
        What a criterion's name counts (``"scenario"``).
    criteria : tuple of Criterion
        In increasing ``limit``.
    citation : str
        The guidance the numbers are from.
    label : str
        A short form of the citation and source for one printed line.
    source : str
        Where they were read (and what of the guidance was not).
    """

    name: str
    measure: str
    kind: str
    criteria: tuple
    citation: str
    label: str
    source: str

    def __post_init__(self):
        limits = [c.limit for c in self.criteria]
        if self.measure not in MEASURES or not limits or np.any(np.diff(limits) <= 0) or limits[0] <= 0:
            raise ValueError(f"limits {self.name!r}: measure must be one of {MEASURES} and the criteria positive, "
                             "in increasing order")

    @property
    def edges(self) -> np.ndarray:
        """The criteria's limits (m/s^2), increasing: the upper edges of every band but the last."""
        return np.array([c.limit for c in self.criteria])

    def _phrase(self, criteria) -> str:
        names = [c.name for c in criteria]
        joined = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
        return f"criterion of {self.kind} {joined}" if len(names) == 1 else f"criteria of {self.kind}s {joined}"

    def words(self, band: int) -> str:
        """What band ``band`` (0 to ``len(criteria)``) means: which criteria a value in it exceeds and is within."""
        exceeded, within = self.criteria[:band], self.criteria[band:]
        if not exceeded:
            return f"within the {self._phrase(within)}"
        if not within:
            return f"exceeds the {self._phrase(exceeded)}"
        return f"exceeds the {self._phrase(exceeded)}; within the {self._phrase(within)}"

    def bands(self) -> list:
        """Every band: ``lower`` (exclusive, except 0 in the first band) and ``upper`` (inclusive; None for the last)
        in m/s^2, and its words."""
        edges = [0.0, *self.edges.tolist(), None]
        return [{"lower": edges[k], "upper": edges[k + 1], "words": self.words(k)} for k in range(len(edges) - 1)]

    def band(self, value) -> int:
        """Band of ``value``: the number of criteria it exceeds (a value equal to a limit is within it).

        Parameters
        ----------
        value : float
            Of :attr:`measure` (m/s^2), finite and >= 0 (a ValueError otherwise).

        Returns
        -------
        int
            0 to ``len(criteria)``.
        """
        value = float(value)
        if not np.isfinite(value) or value < 0:
            raise ValueError(f"limits {self.name}: {self.measure} must be a finite value >= 0, got {value!r}")
        return int(np.searchsorted(self.edges, value, side="left"))

    def classify(self, value) -> dict:
        """``value`` against the criteria, JSON-able.

        Parameters
        ----------
        value : float
            Of :attr:`measure` (m/s^2), finite and >= 0.

        Returns
        -------
        dict
            ``measure``, ``value`` (m/s^2), ``percent_g`` (``100 value / G_SOURCE``), ``band``, ``words`` and
            ``within``: per criterion (``"scenario 2"``), whether the value is within it (at most its limit).
        """
        band = self.band(value)
        return {"measure": self.measure, "value": float(value), "percent_g": 100.0 * float(value) / G_SOURCE,
                "band": band, "words": self.words(band),
                "within": {f"{self.kind} {c.name}": k >= band for k, c in enumerate(self.criteria)}}

    def classify_models(self, row) -> dict:
        """Each model's value of :attr:`measure` in ``row`` (columns ``<model>_<measure>`` of :data:`MODELS`, as the
        result's and the Monte Carlo percentiles' tables have), classified: ``{model: classify(value)}``."""
        return {model: self.classify(row[f"{model}_{self.measure}"]) for model in MODELS}

    def describe(self) -> dict:
        """The limits as data, for ``summary.json``: name, measure, criteria, bands, citation and source."""
        return {"name": self.name, "measure": self.measure, "citation": self.citation, "label": self.label,
                "source": self.source,
                "criteria": [{"name": f"{self.kind} {c.name}", "limit": c.limit, "stated": c.stated, "load": c.load}
                             for c in self.criteria],
                "bands": self.bands()}

    def sentence(self, value) -> str:
        """One line for ``value`` (m/s^2): ``rms_1s_max 0.412 m/s^2 (4.2 %g): exceeds the criterion of scenario 2;
        within the criteria of scenarios 3 and 4``."""
        item = self.classify(value)
        return f"{self.measure} {item['value']:.3f} m/s^2 ({item['percent_g']:.1f} %g): {item['words']}"


def _percent_g(percent: float) -> float:
    return percent / 100.0 * G_SOURCE


ROUTE2 = Limits(
    name="istructe2008-route2",
    measure="rms_1s_max",
    kind="scenario",
    criteria=(
        Criterion("2", _percent_g(3.0), "3 %g", "all people active; per kg of crowd 9.81 rho(f) sum_k GLF_k "
                  "cos(2 pi k f t), GLF 0.12, 0.015, 0, rho = exp(-2 (f - 1.8)^2), f 1-3 Hz"),
        Criterion("3", _percent_g(7.5), "7.5 %g", "as scenario 2 with GLF 0.188, 0.047, 0.013"),
        Criterion("4", _percent_g(20.0), "20 %g", "as scenario 2 with GLF 0.375, 0.095, 0.026 and rho = "
                  "sech(f - 2)"),
    ),
    citation="IStructE/DCLG/DCMS (2008), Dynamic performance requirements for permanent grandstands subject to "
             "crowd action: recommendations for management, design and assessment, The Institution of Structural "
             "Engineers, London, ISBN 978-1-906335-12-0: Route 2, criteria by event scenario",
    label="IStructE/DCLG/DCMS (2008) Route 2 criteria, as coded in sgettler/grandstand-dynamics",
    source="read in sgettler/grandstand-dynamics (MIT licence), grandstand-dynamics/src-old/"
           "runIstructeTerraceAnalysis.m (criteria), getScenarioResponse.m (loads), getCrowdStructureResponse.m "
           "(maximum RMS over non-overlapping 1 s windows, unweighted), commit a09e62f; not checked against the "
           "guide's text, whose table number and words for the levels were not found",
)
"""The Route 2 criteria of the IStructE/DCLG/DCMS (2008) grandstand guide as an open-source implementation codes
them (see the module docstring): maximum 1 s RMS, unweighted, 3 / 7.5 / 20 %g for scenarios 2 / 3 / 4."""

LIMITS = {ROUTE2.name: ROUTE2}
"""Every set of limits, by name."""

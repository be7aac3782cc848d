"""One crowd on one structure: empty and occupied modes, responses at chosen points, coupled vs force-only.

:func:`analyse_structure` takes a :class:`~.modes.ModalModel` and the people on
it (:class:`~.people.Occupants`), solves the coupled and the force-only models
(:mod:`.solve`) and gathers what an engineer checks (:mod:`.response`) into a
:class:`StructureResult`, which classifies it against published limits (:mod:`.limits`) and writes
``summary.json`` and ``response.csv``.
"""

from __future__ import annotations

import json
import time as _time
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd

from .coupled import Coupling, coupled_eigenvalues, modes_of, occupied_eigenvalues
from .limits import MODELS, ROUTE2, Limits
from .modes import ModalModel
from .people import Occupants
from .response import MEASURES, measures
from .solve import Solution, solve

__all__ = ["StructureResult", "analyse_structure", "antinodes", "DENSE_CHECK"]

DENSE_CHECK = 200
"""Crowds up to this size also get every eigenvalue by a dense solution, to check the Newton roots against."""


def antinodes(model: ModalModel) -> np.ndarray:
    """Rows of the points where each mode's ``|phi|`` is largest (first of ties), in mode order, without repeats."""
    return np.array(list(dict.fromkeys(int(k) for k in np.argmax(np.abs(model.shapes), axis=0))), dtype=int)


@dataclass
class StructureResult:
    """A crowd on a structure, solved (:func:`analyse_structure`).

    Attributes
    ----------
    model : ModalModel
    occupants : Occupants
    coupling : Coupling
    solution : Solution
    points : ndarray of int
        Rows (in the shapes) of the response points.
    occupied : complex ndarray, shape (m,)
        Eigenvalues continuing the empty modes (1/s).
    dense_check : float or None
        Largest distance (1/s) from a Newton eigenvalue to the dense solution's nearest (small crowds).
    seconds : float
        Wall-clock time of the solution (s), forces not included.
    """

    model: ModalModel
    occupants: Occupants
    coupling: Coupling
    solution: Solution
    points: np.ndarray
    occupied: np.ndarray
    dense_check: float | None
    seconds: float

    @property
    def fs(self) -> float:
        """Sampling frequency (Hz)."""
        return float(self.occupants.settings["fs"])

    def accelerations(self):
        """``(coupled, force_only)`` accelerations (m/s^2) at the response points, each (P, T)."""
        return self.solution.at(self.model.shapes[self.points])

    def table(self) -> pd.DataFrame:
        """One row per response point: ``point`` and ``coupled_*``, ``force_only_*``, ``ratio_*`` of each measure."""
        return self._measured.copy()

    @cached_property
    def _measured(self) -> pd.DataFrame:
        """:meth:`table`, computed once (the summary, the printout, the worst point and the figures all read it)."""
        coupled, force_only = (measures(a, self.fs) for a in self.accelerations())
        frame = pd.DataFrame({"point": [self.model.points[k] for k in self.points]})
        for name in MEASURES:
            frame[f"coupled_{name}"] = coupled[name]
            frame[f"force_only_{name}"] = force_only[name]
            frame[f"ratio_{name}"] = coupled[name] / np.where(force_only[name] > 0, force_only[name], np.nan)
        return frame

    def worst(self) -> int:
        """Position (in :attr:`points`) of the point with the largest coupled ``rms_1s_max``, force-only if larger."""
        table = self._measured
        return int(np.argmax(np.maximum(table["coupled_rms_1s_max"], table["force_only_rms_1s_max"])))

    def classify(self, limits: Limits = ROUTE2, point=None) -> dict:
        """Both models' values at a response point against ``limits`` (:meth:`.limits.Limits.classify`).

        Parameters
        ----------
        limits : Limits
            Default :data:`~.limits.ROUTE2`.
        point : int, optional
            Position in :attr:`points`; default the worst point (:meth:`worst`).

        Returns
        -------
        dict
            ``point`` (its name), ``coupled`` and ``force_only``: each the classification of that model's value of
            ``limits.measure`` there.
        """
        k = self.worst() if point is None else int(point)
        row = self._measured.iloc[k]
        return {"point": row["point"], **limits.classify_models(row)}

    def summary(self, limits: Limits = ROUTE2) -> dict:
        """JSON-able summary: modes empty and occupied, people, per point both models' measures and their
        classification against ``limits`` (default :data:`~.limits.ROUTE2`)."""
        people = self.occupants.table
        rows = []
        for k, row in enumerate(self._measured.itertuples(index=False)):
            item = {"point": row.point}
            for model in ("force_only", "coupled"):
                item[model] = {name: float(getattr(row, f"{model}_{name}")) for name in MEASURES}
            ratios = {name: float(getattr(row, f"ratio_{name}")) for name in MEASURES}
            item["coupled_over_force_only"] = {name: (v if np.isfinite(v) else None) for name, v in ratios.items()}
            classified = self.classify(limits, k)
            item["limits"] = {model: classified[model] for model in MODELS}
            rows.append(item)
        settings = self.occupants.settings
        return {
            "structure": self.model.name,
            "empty_modes": self.model.empty_modes(),
            "occupied_modes": modes_of(self.occupied),
            "dense_eigenvalue_check": self.dense_check,
            "people": {"total": int(len(people)), "active": int(people["active"].sum()),
                       "mass_kg": float(people["mass"].sum()), "contact_lost": self.occupants.contact_lost()},
            "settings": {key: (value if isinstance(value, (str, float, int)) or value is None else str(value))
                         for key, value in settings.items()},
            "frequency_weighting": "peak, rms_1s_max, vdv: none (the vertical acceleration as computed); "
                                   "rms_1s_max_wb, vdv_wb: W_b of BS 6841:1987 (structure.weighting)",
            "limits": limits.describe(),
            "worst_point": rows[self.worst()]["point"] if rows else None,
            "points": rows,
            "seconds": self.seconds,
        }

    def _limits_lines(self, limits: Limits) -> list:
        """The worst point against ``limits``, both models, in words, and the limits' source (for :meth:`text`)."""
        item = self.classify(limits)
        return [f"limits at {item['point']} ({limits.label}):",
                *(f"  {label}: {limits.sentence(item[model]['value'])}"
                  for model, label in MODELS.items())]

    def response_frame(self) -> pd.DataFrame:
        """``time`` and, per response point, ``<point>_coupled`` and ``<point>_force_only`` accelerations (m/s^2)."""
        coupled, force_only = self.accelerations()
        frame = {"time": self.solution.time}
        for k, index in enumerate(self.points):
            name = self.model.points[index]
            frame[f"{name}_coupled"], frame[f"{name}_force_only"] = coupled[k], force_only[k]
        return pd.DataFrame(frame)

    def write(self, directory) -> list:
        """Write ``summary.json``, ``response.csv`` and ``people.csv`` into ``directory``; return the paths."""
        directory = Path(directory)
        paths = [directory / "summary.json", directory / "response.csv", directory / "people.csv"]
        paths[0].write_text(json.dumps(self.summary(), indent=1) + "\n", encoding="utf-8")
        self.response_frame().to_csv(paths[1], index=False, float_format="%.6g")
        self.occupants.table.to_csv(paths[2], index=False, float_format="%.6g")
        return paths

    def text(self) -> str:
        """A few lines for the terminal."""
        s = self.summary()
        lines = [f"{s['structure']}: {s['people']['total']} people ({s['people']['active']} bouncing at "
                 f"{self.occupants.settings['f_b']:g} Hz), {s['people']['mass_kg'] / 1000:.1f} t; solved in "
                 f"{self.seconds:.2f} s"]
        for j, (empty, full) in enumerate(zip(s["empty_modes"], s["occupied_modes"]), start=1):
            lines.append(f"mode {j}: empty {empty['f_hz']:.3f} Hz, zeta {empty['zeta']:.4f} -> occupied "
                         f"{full['f_hz']:.3f} Hz, zeta {full['zeta']:.4f}")
        for item in s["points"]:
            parts = [f"{name} {item['coupled'][name]:.3f} vs {item['force_only'][name]:.3f}" for name in MEASURES]
            lines.append(f"point {item['point']}: coupled vs force-only " + ", ".join(parts))
        if s["points"]:
            lines += self._limits_lines(ROUTE2)
        if s["people"]["contact_lost"]:
            lines.append(f"warning: {s['people']['contact_lost']} active people's rigid-floor GRF goes below zero "
                         "(the SMD model has no flight phase)")
        return "\n".join(lines)


def analyse_structure(model: ModalModel, occupants: Occupants, points=None) -> StructureResult:
    """Solve the coupled and the force-only model of ``occupants`` on ``model``.

    Parameters
    ----------
    model : ModalModel
    occupants : Occupants
        People and the active people's rigid-floor forces (:func:`~.people.draw_occupants`,
        :func:`~.people.read_occupants`); their ``settings["fs"]`` is the rate.
    points : sequence of str, optional
        Response points (default :func:`antinodes`).

    Returns
    -------
    StructureResult
    """
    started = _time.perf_counter()
    table = occupants.table
    coupling = Coupling(model, table["point_index"].to_numpy(), table["mass"].to_numpy(), table["f_h"].to_numpy(),
                        table["xi_h"].to_numpy())
    rows = antinodes(model) if points is None else model.index(points, source="--points")
    occupied = occupied_eigenvalues(coupling)
    solution = solve(coupling, occupants.modal_loads(model), occupants.settings["fs"], occupied)
    check = None
    if coupling.n_people <= DENSE_CHECK:
        dense = coupled_eigenvalues(coupling)
        check = float(max(np.min(np.abs(dense - root)) for root in occupied))
    return StructureResult(model, occupants, coupling, solution, rows, occupied, check,
                           _time.perf_counter() - started)

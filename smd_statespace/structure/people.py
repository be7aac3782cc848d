"""The people on a structure: where they stand, their SMD parameters, and the active ones' forces.

Every person is the article's SMD model (Eq. 2) standing at a point of the
structure's shapes. *Active* people bounce: their biomechanical force is the
Fourier force of Eq. 4 at the crowd's bouncing frequency ``f_b``, each with their
own phase offset (uniform over ``phase_spread`` of a cycle; 1 = unsynchronised,
the default; 0 = all in step) and cycle-to-cycle variation of frequency and
harmonics (2 % and 10 % SD, :data:`~smd_statespace.simulation.crowd.CROWD_SETTINGS`).
*Passive* people stand and add mass and damping: an SMD without a force.

Where the parameters come from
------------------------------
- drawn (:func:`draw_occupants`): positions uniform over the shapes' points; the
  active people are :func:`~smd_statespace.simulation.crowd.simulate_crowd`'s
  crowd (Table 2's skew-normal fits for the band of ``f_b``, body mass
  ``N(65, 10)`` kg truncated to 45-100 kg, redrawn while their GRF would go
  below zero); passive people's masses from the same distribution
  (:func:`~smd_statespace.simulation.crowd.draw_people`) and the passive SMD
  :data:`PASSIVE`;
- a ``people.csv`` (:func:`read_occupants`): ``point`` and any of ``mass_kg, f_h,
  xi_h, active`` (0/1, default 1), ``f_b``, ``blf_1, blf_2, blf_3`` and
  ``person_json``, the ``person.json`` that ``smd-statespace identify`` wrote for
  that person (a path relative to the people file): its ``f_h``, ``xi_h``,
  ``f_b``, ``blf_1..3`` and, when the mass was known, the mass behind its
  ``k_h`` (Eq. 17) fill the row's empty cells; a cell still empty is drawn as above.

The active people's forces on a rigid floor (their GRFs, Eq. 3) are computed
exactly by :mod:`smd_statespace.simulation.person_forces`; on the structure they
are the force-only model's load, and the coupled model adds each person's
response to the structure's motion (:mod:`.coupled`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import OptionError, RecordError
from ..io import G
from ..model import k_h
from ..simulation.crowd import CROWD_SETTINGS, draw_people, simulate_crowd
from ..simulation.person_forces import person_cycles, rigid_floor_grf
from .modes import ModalModel, _column, _read_csv

__all__ = ["PASSIVE", "Occupants", "draw_occupants", "read_occupants", "PEOPLE_COLUMNS"]

PASSIVE = {"f_h": 5.0, "xi_h": 0.40}
"""SMD of a passive (standing or seated, not bouncing) person: 5.0 Hz, damping ratio 0.40.

The passive-crowd values an open-source implementation of the IStructE/DCLG/DCMS (2008) grandstand guide's Route 2
uses: ``sgettler/grandstand-dynamics``, ``grandstand-dynamics/src-old/getCrowdStructureResponse.m`` (commit
a09e62f), which gives 5.0 Hz, 0.40 for passive and 2.3 Hz, 0.25 for active people and cites for its crowd model
Dougill et al. (2006), "Human structure interaction during rhythmic bobbing", The Structural Engineer 84(22),
32-39, as implemented by Pavic and Reynolds (2008), "Experimental verification of novel 3DOF model of grandstand
crowd-structure dynamic interaction", 26th International Modal Analysis Conference, Orlando. Neither the guide's
text nor those papers were read here (the stored copies of the guide give its front matter only), so that the guide
itself states these values is not confirmed. Here active people are the article's own (Table 2), not 2.3 Hz, 0.25."""

PEOPLE_COLUMNS = ("point", "mass_kg", "f_h", "xi_h", "active", "f_b", "blf_1", "blf_2", "blf_3", "person_json")
"""Columns of ``people.csv``: ``point`` is required, the others may be missing or empty (taken from the row's
``person_json`` if it names one, otherwise drawn)."""

FROM_PERSON_JSON = {"f_h": "f_h", "xi_h": "xi_h", "f_b": "f_b", "blf1": "blf_1", "blf2": "blf_2", "blf3": "blf_3"}
"""People-table columns filled from an identified person's ``person.json`` (``identify``'s answer), by its keys."""


@dataclass
class Occupants:
    """People on a structure and the active people's rigid-floor forces.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per person: ``person, point, point_index, mass`` (kg), ``f_h``
        (Hz), ``xi_h``, ``active`` (bool), ``f_b`` (Hz), ``blf1..3`` (g; NaN
        for passive people).
    time : ndarray, shape (T,)
        Sample times (s).
    grf : ndarray, shape (A, T)
        GRFs (N, weight included) of the active people, in table order, on a rigid floor.
    cycles : list of pandas.DataFrame
        The active people's force cycles (Eq. 4).
    settings : dict
        How they were made (``f_b, phase_spread, fb_variation, coef_variation, seed``).
    """

    table: pd.DataFrame
    time: np.ndarray
    grf: np.ndarray
    cycles: list
    settings: dict

    @property
    def active(self) -> np.ndarray:
        """Boolean mask of the active people (table order)."""
        return self.table["active"].to_numpy(dtype=bool)

    def modal_loads(self, model: ModalModel) -> np.ndarray:
        """The active people's dynamic rigid-floor forces on the modes, ``-sum_i phi_j(p_i) (GRF_i - M_i g)`` (N).

        Returns
        -------
        ndarray, shape (m, T)
            Generalised forces, positive up: a person pushes the floor down by their GRF.
        """
        rows = self.table[self.active]
        dynamic = self.grf - (rows["mass"].to_numpy() * G)[:, None]
        return -(model.shapes[rows["point_index"].to_numpy()].T @ dynamic)

    def contact_lost(self) -> int:
        """Active people whose rigid-floor GRF goes below zero somewhere (the SMD model has no flight phase)."""
        return int(np.count_nonzero(self.grf.min(axis=1) < 0.0)) if self.grf.size else 0


def _time(duration, fs):
    return np.arange(int(np.floor(float(duration) * float(fs) + 1e-9)) + 1) / float(fs)


def _settings(f_b, phase_spread, seed, fs, duration):
    """The settings an :class:`Occupants` records."""
    return {"f_b": float(f_b), "fs": float(fs), "duration": float(duration), "phase_spread": float(phase_spread),
            "fb_variation": CROWD_SETTINGS["fb_variation"], "coef_variation": CROWD_SETTINGS["coef_variation"],
            "seed": seed}


def _split(seed):
    """Three independent SeedSequences (places and roles, active crowd, passive masses) from ``seed``."""
    root = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    return root, root.spawn(3)


def draw_occupants(model: ModalModel, n, active_share=1.0, f_b=2.0, duration=30.0, fs=200.0, seed=None,
                   phase_spread=1.0, points=None) -> Occupants:
    """Draw ``n`` people on ``model``: places, who bounces, their parameters and the active people's forces.

    Parameters
    ----------
    model : ModalModel
    n : int
        Number of people (>= 0).
    active_share : float
        Fraction who bounce (0-1); ``round(active_share n)`` people, chosen at random.
    f_b : float
        Bouncing frequency (Hz), within the article's bands (1.35-3.75 Hz).
    duration, fs : float
        Length (s) and sampling frequency (Hz) of the forces.
    seed : None, int or numpy.random.SeedSequence
        Everything random comes from it (child 0: places and roles; 1: the
        active crowd; 2: passive masses), so a draw does not depend on where
        or in what order it is computed.
    phase_spread : float
        Phase offsets uniform over this fraction of a cycle (0-1).
    points : sequence of str, optional
        Points people may stand on (default every point of the shapes).

    Returns
    -------
    Occupants
    """
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 0:
        raise OptionError(f"structure: the number of people must be a whole number >= 0, got {n!r}")
    if not 0.0 <= float(active_share) <= 1.0:
        raise OptionError(f"structure: --active must be a share from 0 to 1, got {active_share!r}")
    root, (places, active_seed, passive_seed) = _split(seed)
    allowed = np.arange(len(model.points)) if points is None else model.index(points, source="--points")
    rng = np.random.default_rng(places)
    where = allowed[rng.integers(0, allowed.size, size=n)]
    n_active = int(round(float(active_share) * n))
    is_active = np.zeros(n, dtype=bool)
    is_active[rng.permutation(n)[:n_active]] = True
    time = _time(duration, fs)
    table = pd.DataFrame({"person": np.arange(n), "point": [model.points[k] for k in where], "point_index": where,
                          "mass": np.nan, "f_h": np.nan, "xi_h": np.nan, "active": is_active, "f_b": float(f_b),
                          "blf1": np.nan, "blf2": np.nan, "blf3": np.nan})
    grf, cycles = np.empty((0, time.size)), []
    if n_active:
        crowd = simulate_crowd(n_active, f_b, duration=float(duration), fs=fs, seed=active_seed,
                               phase_spread=phase_spread)
        columns = ["mass", "f_h", "xi_h", "blf1", "blf2", "blf3"]
        table.loc[is_active, columns] = crowd.people[columns].to_numpy()
        grf = crowd.forces.drop(columns=["time", "total"]).to_numpy().T
        cycles = crowd.cycles
    if n - n_active:
        table.loc[~is_active, "mass"] = draw_people(n - n_active, f_b, seed=passive_seed)["mass"].to_numpy()
        table.loc[~is_active, "f_h"], table.loc[~is_active, "xi_h"] = PASSIVE["f_h"], PASSIVE["xi_h"]
    return Occupants(table, time, grf, cycles, _settings(f_b, phase_spread, root.entropy, fs, duration))


def _people_column(frame, name, path, strict=True):
    """Column ``name`` of a people table as floats, NaN where empty (:func:`~.modes._column`: > 0, or >= 0 when not
    ``strict``); a one-line error for a bad value."""
    return _column(frame, name, path, low=0.0, strict=strict, optional=True)


def read_occupants(path, model: ModalModel, f_b=2.0, duration=30.0, fs=200.0, seed=None,
                   phase_spread=1.0) -> Occupants:
    """Read ``people.csv`` (module docstring), draw what is missing, and make the active people's forces.

    Parameters
    ----------
    path : str or path-like
    model : ModalModel
        Every ``point`` must be one of its points.
    f_b : float
        The crowd's bouncing frequency (Hz) for people without their own ``f_b``
        and for the band their missing parameters are drawn from.
    duration, fs, seed, phase_spread
        As :func:`draw_occupants` (a person ``i``'s draws and force come
        from the children of ``seed`` for row ``i``).

    Returns
    -------
    Occupants
        Active people whose rigid-floor GRF dips below zero are kept (they
        are given, not drawn); :meth:`Occupants.contact_lost` counts them.
    """
    frame = _read_csv(path, "--people", dtype={"point": str})
    if "point" not in frame.columns:
        raise RecordError(f"{path}: missing column 'point' (columns: {', '.join(PEOPLE_COLUMNS)}; only point "
                          "is required)")
    where = model.index(frame["point"].astype(str).tolist(), source=str(path))
    active = _people_column(frame, "active", path, strict=False)
    if np.any(~np.isnan(active) & ~np.isin(active, (0.0, 1.0))):
        row = int(np.flatnonzero(~np.isnan(active) & ~np.isin(active, (0.0, 1.0)))[0])
        raise RecordError(f"{path} row {row + 1}, column active: {frame['active'].tolist()[row]!r}; it must be 0 or 1")
    table = pd.DataFrame({"person": np.arange(len(frame)), "point": [model.points[k] for k in where],
                          "point_index": where, "mass": _people_column(frame, "mass_kg", path),
                          "f_h": _people_column(frame, "f_h", path), "xi_h": _people_column(frame, "xi_h", path),
                          "active": np.where(np.isnan(active), 1.0, active).astype(bool),
                          "f_b": _people_column(frame, "f_b", path)})
    for k in (1, 2, 3):
        table[f"blf{k}"] = _people_column(frame, f"blf_{k}", path, strict=False)
    _fill_from_person_json(frame, table, path)
    root, (_, active_seed, _) = _split(seed)
    return _complete(table, f_b, duration, fs, phase_spread, active_seed, root.entropy)


def _fill_from_person_json(frame, table, path):
    """Empty cells of ``table`` filled from the ``person.json`` each row of ``frame`` names (column ``person_json``)."""
    if "person_json" not in frame.columns:
        return
    for row, name in enumerate(frame["person_json"]):
        if pd.isna(name) or not str(name).strip():
            continue
        file = Path(path).parent / str(name).strip()
        try:
            person = json.loads(file.read_text(encoding="utf-8"))
            values = {column: float(person[key]) for column, key in FROM_PERSON_JSON.items() if key in person}
            if "k_h" in person and "f_h" in person:
                values["mass"] = float(person["k_h"]) / float(k_h(float(person["f_h"]), 1.0))  # Eq. 17
        except (OSError, ValueError, TypeError, AttributeError) as exc:
            raise RecordError(f"{path} row {row + 1}, column person_json: {file} is not a readable person.json "
                              f"({' '.join(str(exc).split())})") from None
        bad = [column for column, value in values.items() if not (np.isfinite(value) and value >= 0)]
        if bad or values.get("f_h", 1.0) <= 0 or values.get("xi_h", 1.0) <= 0:
            raise RecordError(f"{path} row {row + 1}, column person_json: {file} has an invalid "
                              f"{(bad or ['f_h or xi_h'])[0]}; f_h and xi_h must be > 0, the others >= 0")
        for column, value in values.items():
            if np.isnan(table.at[row, column]):
                table.at[row, column] = value


def _complete(table, f_b, duration, fs, phase_spread, seed, entropy):
    """Fill a people table's empty cells (drawn) and make the active people's cycles and rigid-floor GRFs."""
    n = len(table)
    drawn = draw_people(n, f_b, seed=seed) if n else None
    table["f_b"] = table["f_b"].fillna(float(f_b))
    table["mass"] = table["mass"].fillna(pd.Series(drawn["mass"].to_numpy() if n else [], dtype=float))
    active = table["active"].to_numpy(dtype=bool)
    for column in ("f_h", "xi_h"):
        fallback = np.where(active, drawn[column].to_numpy(), PASSIVE[column]) if n else []
        table[column] = table[column].fillna(pd.Series(fallback, dtype=float))
    for k in (1, 2, 3):
        fallback = np.where(active, drawn[f"blf{k}"].to_numpy(), np.nan) if n else []
        table[f"blf{k}"] = np.where(active, table[f"blf{k}"].fillna(pd.Series(fallback, dtype=float)), np.nan)
    time = _time(duration, fs)
    rows = table[active]
    force_seeds = seed.spawn(n) if n else []
    cycles = [person_cycles(force_seeds[i], row.f_b, row.f_h, row.xi_h, [row.blf1, row.blf2, row.blf3],
                            float(duration), CROWD_SETTINGS["fb_variation"], CROWD_SETTINGS["coef_variation"],
                            phase_spread)[0] for i, row in zip(rows.index, rows.itertuples())]
    grf = (rigid_floor_grf(rows["mass"], rows["f_h"], rows["xi_h"], cycles, time) if len(rows)
           else np.empty((0, time.size)))
    return Occupants(table, time, grf, cycles, _settings(f_b, phase_spread, entropy, fs, duration))

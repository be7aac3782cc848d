"""Monte Carlo over crowds: many random crowds on one structure, the distribution of the response.

Draw ``k`` of :func:`monte_carlo` is the crowd of :func:`~.people.draw_occupants`
with the ``k``-th child of ``numpy.random.SeedSequence(seed)`` (people, places,
who bounces, phases, cycle-to-cycle variation), solved by
:func:`~.analysis.analyse_structure`. Draws are independent tasks: they run on
any :class:`concurrent.futures.Executor` (threads, processes, or a Dask
cluster's ``client.get_executor()``, as :func:`smd_statespace.identify.batch.identify_batch`
takes), and the table is the same whatever the executor or number of workers,
since each draw's numbers come from its own seed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .analysis import analyse_structure
from .coupled import modes_of
from .modes import ModalModel
from .people import draw_occupants
from .response import MEASURES

__all__ = ["CrowdDraws", "one_draw", "monte_carlo", "percentiles"]


@dataclass(frozen=True)
class CrowdDraws:
    """What every draw shares: the structure and how its crowd is drawn (see :func:`~.people.draw_occupants`).

    Parameters
    ----------
    model : ModalModel
    n : int
        People per draw.
    active_share, f_b, duration, fs, phase_spread
        As :func:`~.people.draw_occupants`.
    points : tuple of str, optional
        Response points (default the antinodes).
    """

    model: ModalModel
    n: int
    active_share: float = 1.0
    f_b: float = 2.0
    duration: float = 30.0
    fs: float = 200.0
    phase_spread: float = 1.0
    points: tuple | None = None


def one_draw(spec: CrowdDraws, seed) -> list:
    """Rows of one draw: per response point, both models' measures and the occupied modes' frequencies and damping.

    Parameters
    ----------
    spec : CrowdDraws
    seed : numpy.random.SeedSequence
        The draw's own seed.

    Returns
    -------
    list of dict
    """
    occupants = draw_occupants(spec.model, spec.n, spec.active_share, spec.f_b, spec.duration, spec.fs, seed=seed,
                               phase_spread=spec.phase_spread, points=None)
    result = analyse_structure(spec.model, occupants, points=spec.points)
    modes = {}
    for j, mode in enumerate(modes_of(result.occupied), start=1):
        modes[f"f{j}_hz"], modes[f"zeta{j}"] = mode["f_hz"], mode["zeta"]
    rows = []
    for row in result.table().to_dict("records"):
        rows.append({**row, **modes})
    return rows


def monte_carlo(spec: CrowdDraws, draws, seed=0, executor=None) -> pd.DataFrame:
    """``draws`` random crowds on ``spec.model``: one row per draw and response point.

    Parameters
    ----------
    spec : CrowdDraws
    draws : int
        Number of crowds (>= 1).
    seed : int or numpy.random.SeedSequence
        Draw ``k`` uses child ``k`` of ``SeedSequence(seed)``.
    executor : concurrent.futures.Executor, optional
        Where the draws run (default one after another here); not shut down.

    Returns
    -------
    pandas.DataFrame
        ``draw, point``, ``coupled_*``, ``force_only_*`` and ``ratio_*`` of
        every measure (m/s^2, VDV m/s^1.75), ``f<j>_hz`` and ``zeta<j>`` of the
        occupied modes; the same for any executor.
    """
    root = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    children = root.spawn(int(draws))
    if executor is None:
        results = [one_draw(spec, child) for child in children]
    else:
        results = list(executor.map(one_draw, [spec] * len(children), children))
    return pd.DataFrame([{"draw": k, **row} for k, rows in enumerate(results) for row in rows])


def percentiles(frame: pd.DataFrame, q=95.0) -> pd.DataFrame:
    """The ``q``-th percentile over draws of every measure, per response point (m/s^2, VDV m/s^1.75).

    Parameters
    ----------
    frame : pandas.DataFrame
        :func:`monte_carlo`'s table.
    q : float
        Percentile (0-100).
    """
    columns = [f"{model}_{name}" for model in ("coupled", "force_only") for name in MEASURES]
    return frame.groupby("point", sort=False)[columns].quantile(float(q) / 100.0)


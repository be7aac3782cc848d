"""Where a search with effects starts: the effects' trial starts, a grid of them coarse to fine, a nonlinear
effect's start about its own predicted path, and a start from earlier fits of the same effects.

:func:`~smd_statespace.person.extend.fit_effects` searches from the best of these (:func:`search_starts`), or,
given fits of its effects already (``diagnose``'s screened candidates), from them (:func:`start_pieces`,
:func:`joined_start`).
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np

from .effect_adapter import record_grid_start, record_starts
from .model import RecordModel
from .threads import spare_best, spare_map

__all__ = ["GRID_STRIDE", "GRID_KEEP", "START_LINEARISATIONS", "START_TOLERANCE", "grid_best", "search_starts",
           "combined_starts", "own_path", "start_pieces", "joined_start"]

GRID_STRIDE = 2
""":func:`grid_best` first computes the likelihood at every ``GRID_STRIDE``-th point of a grid of trial starts."""

GRID_KEEP = 10
"""... and then at every point within ``GRID_STRIDE - 1`` of the ``GRID_KEEP`` best of those.

Measured on the floor mode's 233 trial frequencies (1 % apart, after the innovations' line) of simulated records
(clean ones and people on a floor mode, ``jumps`` and ``smooth`` generators; ``benchmarks/floor_grid.py``): the same
start as the likelihood at every trial on 125 of 125 records (seeds 92 and 93), at 133 likelihoods instead of 234.
Keeping the 5 best missed it on 2: on one the best coarse start was the 10th (a near tie, 0.4 in log-likelihood)."""


def grid_best(function, items, leading: int = 0, stride: int = GRID_STRIDE, keep: int = GRID_KEEP):
    """The first of ``items`` with the largest ``function`` value, where ``items[leading:]`` is an ordered grid.

    As :func:`~smd_statespace.person.threads.spare_best`, but on a grid whose neighbours give close values the
    value is computed at the ``leading`` items and every ``stride``-th grid point first, then at the grid points
    within ``stride - 1`` of the ``keep`` best of those: the best of the whole grid is missed only if none of
    its neighbours is among them. Each stage's values are computed by
    :func:`~smd_statespace.person.threads.spare_map` (half in an idle thread).

    Examples
    --------
    Values at every other point (1, 3, 5, 7) first, then around the best of them (3): 2 and 4.

    >>> values = [0.0, 1.0, 2.0, 5.0, 9.0, 3.0, 4.0, 0.0]
    >>> grid_best(values.__getitem__, range(8), leading=1, keep=1)
    4
    """
    items = list(items)
    first = sorted(set(range(min(leading, len(items)))) | set(range(leading, len(items), stride)))
    values = dict(zip(first, spare_map(function, [items[i] for i in first])))
    kept = sorted((i for i in first if i >= leading), key=lambda i: -values[i])[:keep]
    near = sorted({j for i in kept for j in range(i - stride + 1, i + stride) if leading <= j < len(items)}
                  - set(values))
    values.update(zip(near, spare_map(function, [items[j] for j in near])))
    return items[max(sorted(values), key=values.__getitem__)]


START_LINEARISATIONS = 12
"""Most re-linearisations of a nonlinear effect's path at one trial start, before its likelihood ranks the start."""

START_TOLERANCE = 0.5
"""Change of the log-likelihood between two linearisations at a trial start below which its path has settled for
ranking the starts (the search itself settles to :data:`~smd_statespace.person.extend.NOMINAL_TOLERANCE`)."""


def search_starts(model: RecordModel, result, root, effects) -> list:
    """Starts of the search, one per fit the model could grow from: ``(model, params)`` pairs.

    From ``result`` (the fit the effects are added to) by name, the best of the added effects' own trial starts
    (:func:`~smd_statespace.person.effect_adapter.record_starts`) by likelihood, else the model's. When ``result``
    holds effects already, a second start from ``root`` (the fit without any) with ``result``'s effect parameters: a
    variance that an earlier effect's fit drove to zero sits on a flat
    plateau of the likelihood that a search started there does not leave.

    A nonlinear model's trial starts that are not an ordered grid (a cubic spring's) are tried from the model's
    default variances instead (the fit without the effect put what it missed into the variation of each cycle's
    mean force, and the displacement it predicts wanders by centimetres), each ranked by its likelihood about its
    own predicted path (:func:`own_path`), the other effects at their first trial: the best of them is one more
    start. From ``result`` such an effect then starts at its first trial (a cubic spring absent), while a grid
    (a floor mode's, fitted with the spring) is searched there as it is without one. (Every combination of a
    spring's 8 trials and a floor's 233 frequencies, each about its own path, took over 10 minutes.)
    """
    default = model.start_params(result.f_h, result.xi_h)
    trials = [record_starts(effect, result) or [{}] for effect in effects]
    many = [i for i, starts in enumerate(trials) if len(starts) > 1]
    # a nonlinear model's trials that are not an ordered grid (a cubic spring's, not a floor mode's frequencies) are
    # tried from the default variances, each about its own path; from result, such an effect starts at its first
    fresh = [i for i in many if record_grid_start(effects[i]) is None] if model.approximate else []
    kept = [i for i in many if i not in fresh]
    # one effect's trials on an ordered grid (a floor mode's frequencies), the others single: a grid in that order
    leading = record_grid_start(effects[kept[0]]) if len(kept) == 1 else None
    origins = [result.model.unpack(result.params)]
    if root is not result:
        origins.append({**origins[0], **root.model.unpack(root.params)})
    out = []
    for named in origins:
        starts = combined_starts(model, named,
                                 [starts[:1] if i in fresh else starts for i, starts in enumerate(trials)], default)
        out.append((model, spare_best(model.loglike, starts) if leading is None  # half of them in an idle thread
                    else grid_best(model.loglike, starts, leading)))
    if fresh:
        ranked = spare_map(lambda start: own_path(model, start), combined_starts(
            model, dict(zip(model.param_names, default)),
            [starts if i in fresh else starts[:1] for i, starts in enumerate(trials)], default))
        out.append(max(ranked, key=lambda pair: pair[0])[1:])
    return out


def combined_starts(model: RecordModel, named: dict, trials: list, default) -> list:
    """Every combination of the effects' ``trials`` (one dict of values from each) over the values ``named``, as
    parameter vectors of ``model`` (``default`` where neither names a parameter), within its bounds."""
    low, high = np.asarray(model.bounds).T
    starts = []
    for combination in itertools.product(*trials):
        values = dict(named)
        for part in combination:
            values.update(part)
        starts.append(np.clip([values.get(name, value) for name, value in zip(model.param_names, default)], low, high))
    return starts


def own_path(model: RecordModel, params) -> tuple:
    """``(loglike, model, params)``: ``model`` linearised about the path it predicts at ``params``, again until the
    likelihood settles (:data:`START_TOLERANCE`, at most :data:`START_LINEARISATIONS` times).

    A start far from the fit the path came from (a hardening spring's ``f_h`` 30 % lower) is judged about its
    own path: about the first path its log-likelihood read -4671 where, about its own, 1954 (its search's end).
    A path that runs away (a softening spring whose stiffness turns negative at the extremes) or a likelihood that
    is not finite gives -inf: the start is never taken.
    """
    from .statespace import nominal_path

    loglike = -np.inf
    try:
        with np.errstate(over="ignore", invalid="ignore"):  # a runaway overflows on its way to -inf, said by the value
            for _ in range(START_LINEARISATIONS):
                model = replace(model, nominal=nominal_path(model, params))
                loglike, earlier = model.loglike(params), loglike
                if abs(loglike - earlier) < START_TOLERANCE:
                    break
    except (ArithmeticError, np.linalg.LinAlgError):  # a path that runs away (a spring gone negative): not a start
        return -np.inf, model, params
    return (loglike if np.isfinite(loglike) else -np.inf), model, params


def start_pieces(start, result, effects) -> list | None:
    """The fits of ``start`` (one, or a sequence) to start ``fit_effects`` from: each on ``result`` itself, each of
    some of the added ``effects`` and together of all of them, once; ``None`` where they are not (a start of other
    effects is not used)."""
    if start is None or isinstance(start, tuple) and isinstance(start[0], RecordModel):
        return None
    pieces = [start] if not isinstance(start, (list, tuple)) else list(start)
    present = [e.spec for e in result.effects]
    if any(piece.before is not result or [e.spec for e in piece.effects[:len(present)]] != present
           for piece in pieces):
        return None
    added = sorted(e.spec for piece in pieces for e in piece.effects[len(present):])
    return pieces if added == sorted(e.spec for e in effects[len(present):]) else None


def joined_start(model: RecordModel, result, pieces) -> tuple:
    """``(model, params)``: the start of a search with the effects of several fits ``pieces`` on ``result``: the
    person (and the effects ``result`` has) of the best of them by likelihood, each added effect's parameters from
    the fit that has it, about that start's own predicted path when the model is linearised (:func:`own_path`)."""
    best = max(pieces, key=lambda piece: piece.loglike)
    named = dict(best.model.unpack(best.params))
    known = set(result.model.param_names)
    for piece in pieces:
        named.update({name: value for name, value in piece.model.unpack(piece.params).items() if name not in known})
    low, high = np.asarray(model.bounds).T
    default = model.start_params(best.f_h, best.xi_h)
    params = np.clip([named.get(name, value) for name, value in zip(model.param_names, default)], low, high)
    if not model.approximate:
        return model, params
    _, model, params = own_path(model, params)
    return model, params

"""The person with physical effects: the one SMD model's effects added to a record-level fit.

``identify_person(record, effects=[...])`` and ``identify REC --effect SPEC``
end here: the person is identified without the effects first (the "before"
of the comparison), then the record-level model is rebuilt from
``SMDModel(n_harmonics, effects=[...])`` (:mod:`smd_statespace.person.dynamics`)
and every static parameter — ``f_h``, ``xi_h``, the effects' parameters, the
variation and noise variances — is estimated again by maximum likelihood
over the whole record, first at the person's cycle starts and variation model
(where the likelihood ratio is taken, and where ``diagnose`` screens its
candidates), then with the cycle starts re-placed and the variation model
chosen again by the model with the effects, as ``identify`` does without
them. A fit that has effects already can take more (``diagnose REC --effect
A`` tries each candidate on top of ``A``): the comparison is then with the
fit that has ``A``.

How an effect enters:

- force harmonics (``harmonics``): more harmonics of the force, with their
  template coefficients and cycle-to-cycle spread (:func:`~smd_statespace.person.effect_adapter.record_harmonics`);
- linear in the state with a measured input (a floor with ``floor_acc``):
  exactly, the input's terms are known parts of the rates and of the
  observation;
- linear dynamics of their own (a floor mode without an accelerometer,
  Section 6): exactly, its states join the person's before the exact
  discretisation;
- nonlinear (a cubic spring, quadratic damping, asymmetric stiffness, any
  user's effect): linearised about the one-step predicted path of the
  previous fit (:func:`~smd_statespace.person.statespace.nominal_path`) and fitted again about the new path
  until the log-likelihood changes by less than :data:`NOMINAL_TOLERANCE`, or by less than
  :data:`NOMINAL_RELATIVE` of its gain over the fit without the effects (at
  most :data:`NOMINAL_ITERATIONS` times): at the fixed point, an extended
  Kalman filter inside the likelihood. Its likelihood is then approximate,
  and the result says so.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import OptionError
from ..model import SMDModel
from ..model.effect import FloorMotion
from ..progress import tqdm
from .dynamics import PersonDynamics
from ..model.fitted import propose
from .effect_adapter import fitted_record, record_harmonics
from .model import RecordModel
from .search import WIDER_SANDWICH
from .starts import joined_start, search_starts, start_pieces
from .threads import one_blas_thread, record_cores

__all__ = ["NOMINAL_ITERATIONS", "NOMINAL_TOLERANCE", "NOMINAL_RELATIVE", "check_effects", "record_effects",
           "configured_for_record", "split_effects", "record_signals", "effect_model", "model_on_top", "root_fit",
           "at_zero", "fit_effects"]

NOMINAL_ITERATIONS = 6
"""Most re-linearisations of a nonlinear effect about the new predicted path."""

NOMINAL_TOLERANCE = 0.05
"""Change of the log-likelihood between two linearisations below which the path has settled."""

NOMINAL_RELATIVE = 1e-3
"""Or a change below this fraction of the log-likelihood's gain over the fit without the effects: a path that
moves the likelihood by 0.2 of a gain of 510 (a spring stiffer on one side, its likelihood ratio 1021 steady to
0.05 %) has settled for the test; a runaway that keeps rising (a cubic spring on a clean record, by units per
linearisation) has not. A path whose likelihood comes back within as much of its value two linearisations
before swings between two paths: it has settled on that cycle, and the better of the two is kept."""


def check_effects(effects, record) -> tuple:
    """The effects as objects (from names or specs), checked against the record before any fit.

    Raises
    ------
    OptionError
        An unknown effect or option (one line naming the valid ones), or an
        effect that needs a column the record lacks (naming the column).
    """
    from ..effects import make_effect

    effects = tuple(make_effect(effect) for effect in effects)
    for effect in effects:
        columns = effect.requires_columns
        missing = [column for column in columns if getattr(record, column, None) is None]
        if missing:
            raise OptionError(f"{record.source}: effect {effect.spec!r} needs the column {missing[0]} "
                              "(the floor's measured acceleration, m/s^2), which the record does not have; "
                              "without one use floor_mode:source=modal")
    SMDModel(effects=[e for e in effects if not record_harmonics(e, SMDModel())])  # duplicates, bad values
    return effects


def record_effects(record, effects=(), measured_floor=True) -> tuple:
    """``effects`` and the effect the record brings with it: the measured floor when it has ``floor_acc``.

    A record with a floor acceleration is of a person on that floor: the
    leg acts between the COM and the floor (Eq. 2 relative to the floor's
    displacement), a known input that adds no unknown. Left out, the floor's
    response to the force is taken up by the template and the variation with
    a wrong resonance: on 21 simulated records of people on a moving floor
    (``person_effects.py --kinds floor_measured --seed 81``) 3 answers were
    determined and missed the truth by 12-19 % (a smoothly drifting force),
    none with the floor; on ``jumps`` records the median ``f_h`` error fell
    from 2.3 to 1.3 % (small floors) and 10.1 to 4.0 % (large). The likelihood
    often cannot tell the two apart (ratios of -51 to +114): the fit without
    the floor reaches the same likelihood by a wrong damping and a free cycle
    rate, so the floor is in the model because it was measured, not because
    a test found it.

    Parameters
    ----------
    record : Record
        The measurement.
    effects : sequence of Effect or str
        The effects asked for.
    measured_floor : bool
        False leaves the floor out (``--no-floor``).

    Returns
    -------
    tuple
        ``("floor_mode", *effects)`` when the record has ``floor_acc``, the floor is
        wanted and no ``floor_mode`` is among ``effects``; else ``tuple(effects)``.
    """
    from ..effects import make_effect

    effects = tuple(effects)
    named = {make_effect(effect).name for effect in effects}
    if measured_floor and getattr(record, "floor_acc", None) is not None and "floor_mode" not in named:
        return ("floor_mode",) + effects
    return effects


def configured_for_record(effect, result):
    """``effect`` as the record-level model takes it: a bare name (no options) as its class configures itself.

    ``identify --effect cubic_stiffness`` then searches the range ``diagnose`` proposed it with
    (:func:`~smd_statespace.model.fitted.propose`, from ``result``, the fit
    without it: a cubic spring's range scaled to the record's displacement), not a fixed default that a
    strong spring ends on. Specs with options and :class:`Effect` objects are taken as given.
    """
    from ..effects import EFFECTS, make_effect

    if isinstance(effect, str) and effect.strip() in EFFECTS:
        configured = propose(EFFECTS[effect.strip()], fitted_record(result))
        if configured is not None and configured.name == effect.strip():
            return configured
    return make_effect(effect)


def split_effects(effects, n_harmonics: int) -> tuple:
    """``(harmonics, model)``: the record model's force harmonics and the SMD model of the other effects."""
    base = SMDModel(n_harmonics=n_harmonics)
    extra = sum(record_harmonics(effect, base) for effect in effects)
    dynamic = [effect for effect in effects if not record_harmonics(effect, base)]
    return n_harmonics + extra, SMDModel(n_harmonics=n_harmonics + extra, effects=dynamic)


def record_signals(record, model: SMDModel) -> dict:
    """The measured inputs ``model``'s effects need, from the record's columns (``floor_disp``, ``floor_vel``).

    The floor acceleration is high-passed and integrated twice as the
    per-cycle pipeline does (:func:`smd_statespace.signals.preprocess`).
    """
    if not model.requires:
        return {}
    from ..signals import motion

    if record.floor_acc is None:
        raise OptionError(f"{record.source}: the effects {', '.join(e.name for e in model.effects)} need the "
                          "column floor_acc, which the record does not have")
    acc, vel, disp = motion(record.floor_acc, record.fs)
    return {"floor_acc": acc, "floor_vel": vel, "floor_disp": disp}


def effect_model(result, effects, path=None) -> RecordModel:
    """The record-level model of ``result`` (its timing, variation, regressors) with ``effects`` added.

    ``result`` is a fit without effects. A nonlinear effect's first nominal
    path is the predicted dynamic states (:func:`~smd_statespace.person.statespace.nominal_path`) of ``path`` (default ``result``: its
    ``u``, ``u'``; a fit with some of ``effects`` already in, those first, gives
    theirs too); the states it does not have start at zero.
    """
    base = result.model
    path = result if path is None else path
    n_harmonics, smd = split_effects(effects, base.n_harmonics)
    dynamics = PersonDynamics(smd, base.time, record_signals(result.record, smd))
    nominal = None
    if not dynamics.linear:
        nominal = np.zeros((base.time.size, dynamics.n_dynamic))
        nominal[:, :path.model.n_dynamic] = path.predicted_path()
    template = base.phase_template
    if template is not None and n_harmonics > base.n_harmonics:
        template = np.r_[template, np.zeros(2 * (n_harmonics - base.n_harmonics))]
    return RecordModel(base.time, base.y, base.timing, n_harmonics, base.variation, base.process_noise,
                       drift=base.drift, regressors=base.regressors, phase_template=template, dynamics=dynamics,
                       nominal=nominal, observed=base.observed, fade=base.fade)


def model_on_top(result, effects) -> RecordModel:
    """``result``'s model, its own effects in it, with ``effects`` added on top of them: at ``result``'s cycle
    starts, variation model and phase template (a fit with effects re-places them, :func:`fit_effects`), where
    its parameters give its own likelihood with the added effects absent.

    Built from the fit without any effect (:func:`root_fit`, the model's structure) by :func:`effect_model`, the
    nonlinear effects linearised about ``result``'s predicted path."""
    root = root_fit(result)
    model = effect_model(root, list(result.effects) + list(effects), path=result)
    if root is result:
        return model
    template = result.model.phase_template
    if template is not None and model.n_harmonics > result.model.n_harmonics:
        template = np.r_[template, np.zeros(2 * (model.n_harmonics - result.model.n_harmonics))]
    return replace(model, timing=result.model.timing, variation=result.model.variation, phase_template=template)


def root_fit(result):
    """The fit without any effect that ``result`` grew from (``result`` itself when it has none): the record-level
    model's structure, to which :func:`effect_model` adds effects."""
    while result.effects:
        result = result.before
    return result


def at_zero(result, effect) -> tuple:
    """``(model, params, j)``: ``result``'s model with the one-parameter ``effect``, at the fit with its
    coefficient (index ``j``) at 0: the model a score test of the effect works in (it is ``result``'s there).

    The effects ``result`` has stay in the model, ``effect`` on top of them (as :func:`fit_effects` adds it): until
    2026-12-01 they were left out, and ``diagnose REC --effect A`` screened the library against the person without
    ``A`` (on a record with a hidden spring, the model at ``c = 0`` read 921 in log-likelihood where the person
    with the spring reads 1213)."""
    model = model_on_top(result, [effect])
    added = [name for name in model.param_names if name not in result.model.param_names]
    if len(added) != 1:
        raise ValueError(f"{effect.spec}: a score test takes an effect of one parameter, this adds {added}")
    named = result.model.unpack(result.params)
    default = model.start_params(result.f_h, result.xi_h)
    params = np.array([named.get(name, value) for name, value in zip(model.param_names, default)], dtype=float)
    j = model.position(added[0])
    params[j] = 0.0
    return model, params, j


@one_blas_thread
@record_cores
def fit_effects(result, effects, *, intervals="calibrated", cov_type=WIDER_SANDWICH, progress=False, timing=True,
                threads=1, start=None):
    """Identify the person of ``result`` again with ``effects`` added to its model.

    Parameters
    ----------
    result : PersonResult
        The fit to extend: the search starts from its variation model, cycle
        timing and estimates. It may hold effects already (``result.effects``):
        the new ones are added on top of them, and the comparison (``before``,
        the likelihood ratio) is with ``result``.
    effects : sequence of Effect or str
        The effects to add (not already in ``result``). A bare name takes the
        options its class chooses for this record (:func:`configured_for_record`).
    intervals, cov_type : str
        As :func:`~smd_statespace.person.fit.identify_person`.
    progress : bool
        A progress bar over the searches (one per linearisation).
    timing : bool
        True (default; ``identify --effect``): when ``result`` placed its cycle
        starts with its own fit (``identify_person``'s default ``timing="model"``),
        they and the variation model are estimated again with the effects in the
        model, as :func:`~smd_statespace.person.fit.identify_person` estimates
        them without effects: every variation model ``result`` compared re-places
        the starts with its own fit and the lowest AIC off the search bounds is
        kept (``result.comparison`` then lists these fits). False (``diagnose``'s
        screening of candidates, one search each): ``result``'s variation model
        and cycle starts are kept. Starts placed by a model that misses an
        effect can be wrong for the model that has it: on 8 records with large
        hidden harmonics 5-6 the re-placed starts raised the log-likelihood with
        the harmonics by 170-700, Ljung-Box passed on 5 (0 at the person's
        starts) and ``f_h`` left its search bound on one (docs/person.md).
    threads : int
        Threads for the variation models' re-placed starts (:mod:`~smd_statespace.person.threads`).
    start : PersonResult or sequence of PersonResult or (RecordModel, ndarray), optional
        A fit of the same effects on ``result`` at its cycle starts (``diagnose``'s screening of the candidate
        it proposes, ``timing=False``; or a search's end, ``(model, params)``, as a screen's quick fit of a term
        leaves it, :func:`~smd_statespace.person.screen.quick_ratio`): the search starts at its estimates, about
        its path, instead of searching the trial starts again (for a cubic spring, 1-2 s). Several fits on
        ``result``, each of some of the
        effects and together of all of them (``diagnose``'s joint fit of its two best candidates): the search
        starts from the person of the best of them with each effect's parameters from its own fit (about that
        start's own path, :func:`~smd_statespace.person.starts.own_path`); should it end below any of them by more than
        :data:`NOMINAL_TOLERANCE` (the model nests each), the trial starts are searched as well and the better
        end is kept.

    Returns
    -------
    PersonResult
        With ``before`` (``result``), ``effects`` and ``linearisations`` (how
        many paths a nonlinear effect was linearised about; 0 when exact).
    """
    from .answer import person_result
    from .search import FitError, fit_model

    present = tuple(result.effects)
    added = check_effects([configured_for_record(effect, result) for effect in effects], result.record)
    already = sorted({e.key for e in present} & {e.key for e in added})
    if already:
        raise OptionError(f"{result.record.source}: the effect {already[0]!r} is in the model already "
                          f"(it has {', '.join(e.spec for e in present)})")
    effects = present + added
    root = root_fit(result)
    model = model_on_top(result, added)
    pieces = start_pieces(start, result, effects)

    def searched(starts):
        best = max(((at, fit_model(at, params, quick=at.approximate)) for at, params in starts),
                   key=lambda pair: pair[1]["loglike"])
        return _settle_path(*best, result.loglike, progress)

    if isinstance(start, tuple) and isinstance(start[0], RecordModel) and start[0].param_names == model.param_names:
        model, fitted, linearisations, settled = searched([start])
    elif pieces is None:
        model, fitted, linearisations, settled = searched(search_starts(model, result, root, added))
    elif len(pieces) == 1 and pieces[0].model.param_names == model.param_names:  # the same effects' fit
        model, fitted, linearisations, settled = searched([(pieces[0].model, pieces[0].params)])
    else:
        model, fitted, linearisations, settled = searched([joined_start(model, result, pieces)])
        if fitted["loglike"] < max(piece.loglike for piece in pieces) - NOMINAL_TOLERANCE:
            model, fitted, linearisations, settled = max(
                [(model, fitted, linearisations, settled), searched(search_starts(model, result, root, added))],
                key=lambda ended: ended[1]["loglike"])
    # the test is made here, at result's starts and variation model: its statistic and its count of added unknowns
    comparison, tested = result.comparison, fitted["loglike"]
    tested_df = model.unknowns(fitted["params"]) - result.model.unknowns(result.params)
    if timing and any(row.timing == "re-placed" for row in result.comparison):
        model, fitted, comparison = _with_own_timing(model, fitted, result, effects, progress, threads)
        if model.approximate:  # the starts moved: the path is predicted again about them
            model, fitted, more, settled = _settle_path(model, fitted, result.loglike, progress)
            linearisations += more
    if not fitted["converged"]:
        raise FitError(f"{result.record.source}: the likelihood search with {', '.join(e.spec for e in effects)} "
                       f"did not converge ({fitted['message']})")
    notes, warnings = list(root.notes), list(root.record_warnings)
    if model.approximate:
        names = ", ".join(e.name for e in effects)
        notes.append(f"the likelihood is exact: {names} changes in time but is linear in the state, so its "
                     "expansion about the path at every sample is the dynamics themselves" if model.exact else
                     f"the likelihood is approximate: {names} linearised about the one-step predicted path, "
                     f"{linearisations} time(s) (an extended Kalman filter at the fixed point)")
        if not settled:
            warnings.append(f"the path of {names} had not settled after {NOMINAL_ITERATIONS} linearisations: its "
                            "estimates are approximate")
    return person_result(result.record, model, fitted, intervals=intervals, level=result.level, cov_type=cov_type,
                         comparison=comparison, record_warnings=warnings, notes=notes,
                         before=result, effects=tuple(effects), linearisations=linearisations,
                         settled=settled, tested_loglike=tested, tested_df=tested_df,
                         change=_change_left(root.change, effects),
                         prepared=root.prepared, threads=threads)


def _change_left(change, effects):
    """``change`` (the tests of one unchanging person, made without effects) less the parameters whose change a
    time term among ``effects`` now models (:attr:`~smd_statespace.effects.generic.GenericTerm.changes`): once
    the model has the drift or the step, the person's answer no longer warns of it nor withholds "determined"
    for it, nor for the other parameter, withheld only because a score test found a change (what the halves or
    a test named of it stays)."""
    modelled = {getattr(effect, "changes", None) for effect in effects} - {None}
    if not change or not modelled & set(change["changed"]):
        return change
    found = set(change.get("by_halves", change["changed"])) | set(change.get("time", {}).get("changed", []))
    return {**change, "changed": [name for name in change["changed"] if name in found - modelled]}


def _settle_path(model: RecordModel, fitted, reference: float, progress=False) -> tuple:
    """A nonlinear effect's model linearised again about each new fit's predicted path until it settles, or until
    two fits in a row put ``f_h`` or ``xi_h`` on a search bound.

    ``reference``: the log-likelihood of the fit without the effects (:data:`NOMINAL_RELATIVE`).

    Returns ``(model, fitted, linearisations, settled)``; a linear model comes back as it is (0, True).
    """
    from .search import fit_model
    from .statespace import nominal_path

    linearisations, settled, earlier = 0, True, None
    with tqdm(total=NOMINAL_ITERATIONS, desc="effects (record)", unit="fit", disable=not progress or not
              model.approximate, leave=False) as bar:
        while model.approximate and linearisations < NOMINAL_ITERATIONS:
            linearisations += 1
            moved = replace(model, nominal=nominal_path(model, fitted["params"]))
            again = fit_model(moved, fitted["params"], quick=True)
            bar.update()
            tolerance = max(NOMINAL_TOLERANCE, NOMINAL_RELATIVE * abs(again["loglike"] - reference))
            # a path that swings between two (a spring stiffer on one side: LR 529.2, 530.2, 529.2, ... on a
            # record where it is the truth) has settled on a cycle, not run away: the better of the two is kept
            cycle = earlier is not None and abs(again["loglike"] - earlier) < tolerance
            settled = cycle or abs(again["loglike"] - fitted["loglike"]) < tolerance
            earlier = fitted["loglike"]
            if cycle and again["loglike"] < fitted["loglike"]:
                break
            # a person run onto a search bound by the fit about one path and again about the next has not found
            # the effect (diagnose does not propose it): more paths do not bring it back (a cubic spring on a record
            # with hidden harmonics: f_h on its 6 Hz bound in all 6 linearisations, 13 s)
            on_bound = model.person_at_bound(fitted["params"]) and moved.person_at_bound(again["params"])
            model, fitted = moved, again
            if settled or on_bound:
                break
        if linearisations:  # the last path's search run to the full tolerance
            fitted = fit_model(model, fitted["params"])
    return model, fitted, linearisations, settled


def _with_own_timing(model: RecordModel, fitted, result, effects, progress=False, threads=1) -> tuple:
    """Re-place the cycle starts and choose the variation model again, with the effects in the model.

    The same procedure as :func:`~smd_statespace.person.fit.identify_person`'s
    (:func:`~smd_statespace.person.search.choose_with_own_timing`) over the
    variation models ``result`` compared, started at ``result``'s cycle starts:
    ``model`` (``result``'s variation, fitted as ``fitted``) from its fit, the
    others from the coarse start search. Returns ``(model, fitted, rows)``,
    ``rows`` for the result's ``comparison``, each marked with the effects'
    specs.

    With a floor among the effects (a :class:`~smd_statespace.model.effect.FloorMotion`:
    the measured floor, a floor mode), a variation model that put the person
    on a search bound in the fits without them (``result`` and the fits it
    grew from) stays suspect (``suspect`` of
    :func:`~smd_statespace.person.search.choose_with_own_timing`) even when the
    floor brings it in. The floor does that by itself: its terms ``w_h^2 z +
    2 xi_h w_h z'`` grow with ``f_h``, so a model whose force absorbs the
    whole response, and whose ``f_h`` therefore runs to the bound (a stiff
    leg, the COM moving with the force), is stopped short of it where a
    still stiffer leg would drag the COM along with the floor: an ``f_h``
    set by the floor's motion, not by the person. Until 2026-11-28 it then
    won by AIC: on records whose force jumps at its peak (the package's
    simulator with phases 0, 1, 2, 2.5 rad, floor 5 Hz, 1000 kg, 2 %;
    ``tests/test_floor_measured_physics.py`` integrates its own) "smooth",
    at 6 Hz without the floor, came in at 2.9-5.4 Hz and was kept: ``f_h``
    +17 % to +114 % where the person without the floor was 3-6 % off (with
    the floor now 1.5-4 % off, "independent" kept).
    Other effects may bring a model in for what they explain (missing
    harmonics), and are not held to this.
    """
    from .search import TIMING_ITERATIONS, choose_with_own_timing, fit_model

    def model_for(timing_, variation_, template):
        return replace(model, timing=timing_, variation=variation_, phase_template=template)

    # called only when result re-placed its starts: its comparison lists every variation model it fitted,
    # the one it kept among them
    variations = list(dict.fromkeys(row.variation for row in result.comparison))
    suspect, earlier = set(), result
    while earlier is not None and any(isinstance(effect, FloorMotion) for effect in effects):
        suspect |= {row.variation for row in earlier.comparison if row.on_bound}
        earlier = earlier.before
    fits = []
    with tqdm(total=len(variations) * (TIMING_ITERATIONS + 2) + 1, desc="effects: cycle starts", unit="fit",
              disable=not progress, leave=False) as bar:
        for variation in variations:
            if variation == model.variation:
                fits.append((model, fitted))
            else:
                other = model_for(model.timing, variation, None)
                fits.append((other, fit_model(other, quick=True)))
            bar.update()
        first = variations.index(model.variation)
        chosen, chosen_fit, rows = choose_with_own_timing(model_for, model.timing, fits, first, bar.update,
                                                          suspect=suspect, threads=threads)
    specs = [effect.spec for effect in effects]
    rows = [replace(row, effects=tuple(specs)) for row in rows]
    return chosen, chosen_fit, rows

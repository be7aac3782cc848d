"""Identify the person from a whole record: maximum likelihood on the record-level model.

:func:`identify_person` estimates one ``f_h``, one ``xi_h`` and the force's
template and cycle-to-cycle variation from a whole bouncing record
(:mod:`smd_statespace.person.model`), with standard errors from the observed
information and profile-likelihood intervals for ``f_h`` and ``xi_h``, and
returns a :class:`~smd_statespace.person.results.PersonResult`.

Steps:

1. COM acceleration ``y = GRF / M_h - g`` (Eq. 3), not filtered;
2. force-cycle boundaries (:func:`~smd_statespace.person.timing.estimate_timing`);
3. for each variation model, a coarse search over ``f_h`` and ``xi_h`` and then
   Fisher scoring on the profile likelihood with its exact gradient
   (:mod:`smd_statespace.person.score`) (template, initial state, offset and
   ``sigma^2`` concentrated out); the variation model with the lowest AIC wins;
4. the observed information (differences of the exact gradient) and,
   for ``f_h`` and ``xi_h``, the profile-likelihood interval (every other
   parameter re-maximised at each point).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..applicability import NotBouncingError, check_bouncing, check_clipping
from ..errors import CycleError, OptionError, RecordError, SMDInputError
from ..io import G, Record
from ..progress import tqdm
from ..signals import RECORD_RATE, prepare_record
from ..signals.weighing import weigh_record
# the steps below identify_person (the names of __all__ were defined here up to 2026-11-27, and stay importable)
from .answer import honest_intervals, person_result, undetermined_interval
from .change import change_test
from .comparison import aic, comparison_row
from .model import PERSON, VARIATIONS, Regressor, RecordModel
from .fade import fading
from .noise_floor import NOISE_FLOOR, check_noise_floor, raise_to_floor
from .screen import time_change
from .profile import profile_interval
from .search import COV_TYPES, TIMING_ITERATIONS, WIDER_SANDWICH, FitError, choose_with_own_timing, fit_model
from .threads import one_blas_thread, record_cores, search_threads, thread_map
from .timing import TIMING_METHODS, estimate_timing, floor_share

__all__ = ["FitError", "MIN_CYCLES", "UNMEASURED_SHARE", "ZERO_DRIFT_SECONDS", "ZERO_DRIFT_MAX_DEGREE",
           "ZERO_WANDERS_SECONDS", "ZERO_WANDERS_ALPHA", "zero_drift",
           "identify_person", "fit_model", "person_result", "profile_interval", "honest_intervals",
           "undetermined_interval"]

UNMEASURED_SHARE = 0.02
"""A fitted sample whose value the decimation's low-pass drew more than this share from samples inside a gap of a
phone's clock (:data:`~smd_statespace.accelerometer.record.GAP_SAMPLES`) is left out of the likelihood."""

ZERO_DRIFT_SECONDS = 10.0
"""Span (s) per degree of the polynomial drift of the measurement's zero first fitted with a lab-shaped record's
person.

A plate's zero that drifts slowly over the record (a few to tens of N) is a slow term of the measured
``GRF / M_h - g`` that the person does not feel: Legendre polynomials of degree 1 to ``ceil(T / 10 s)``
(at least 2, at most :data:`ZERO_DRIFT_MAX_DEGREE`) over the fitted span ``T``, each with an unknown coefficient
concentrated out with the template (no search dimension), beside the constant offset. Added when the front end
left standing parts out (:attr:`~smd_statespace.signals.PreparedRecord.trimmed`); a record bouncing end to end
is fitted as before. Where the zero moves faster (:data:`ZERO_WANDERS_SECONDS`) the person is fitted again.

Measured on lab records of the ``smooth`` generator, three people, drifts of 20-25 N: a cubic (the generator's
own) left ``f_h`` at +11/-16/+6 %, a settling ``25 (1 - exp(-t / 8 s))`` N at +12/+51 %, and a random walk smoothed
over 2 s at +24/+78 % (degree 2: +120/+54/+72 % on the cubic).
"""

ZERO_WANDERS_SECONDS = 2.0
"""Span (s) per degree of the zero's drift where it moves faster than :data:`ZERO_DRIFT_SECONDS` follows.

At the person fitted with the slow drift, the likelihood with a degree every 2 s (one filter pass: the
coefficients are concentrated out) is compared with it; where the ratio is significant at
:data:`ZERO_WANDERS_ALPHA` (chi-squared on the extra degrees), the person is fitted again with the dense drift
and a note says so. Bouncing is at 1.2 Hz or faster; a degree every 2 s follows a zero that moves within 4 s.
On the ``zero`` row of ``benchmarks/lab_records.py`` (the lab row's 40 records with a settling, wandering or
stepping zero of 1-30 N; seeds 4601, 4602) the dense drift on every record determined ``f_h`` on 15/38 and 9/40
records instead of 7/38 and 5/40 and the wandering zero's worst error fell from 46-51 % to 14-22 %, every interval
covering; but on the lab row (a cubic zero) it lost one determined answer of 38-40 on each seed and cost 15-25 %
more time. Tested so, 14/38 and 10/40 of the zero row are determined, every interval covering, and the lab row
keeps its 19/38 and 12/40, 36/38 and 39/40 of its answers unchanged (docs/lab-records.md).
"""

ZERO_WANDERS_ALPHA = 0.01
"""Level of the likelihood-ratio test of :data:`ZERO_WANDERS_SECONDS`' drift against the slow one."""

ZERO_DRIFT_MAX_DEGREE = 30
"""Highest degree of the zero's drift (a span over 60 s gets one degree per ``T / 30``): unmeasured beyond."""

MIN_CYCLES = 8
"""Fewest force cycles for the record-level model (the cycle-to-cycle spread needs several)."""

AUTO_VARIATIONS = ("independent", "smooth")
"""Variation models compared by ``variation="auto"``."""

INTERVAL_METHODS = ("calibrated", "wald", "profile")
"""Interval methods of :func:`identify_person`."""

FIRST_GAIN = 0.1
"""Stop rule of the first fits with ``timing="model"`` (log-likelihood gained by the last scoring step), before any
force template: where the fits of the phase template and the re-placed cycle starts start from, not an answer.

The first fit of the "smooth" model converges linearly and took up to 44 derivative passes to
:data:`~smd_statespace.person.search.QUICK_GAIN`. Measured 2026-11-30 against the stop rule of the other
intermediate fits: ``identify_person`` in one thread 177 -> 123 s over 47 records of six generators
(``person_accuracy.py --seed 2031``), ``f_h`` error median 3.23 -> 3.23 % (mean 8.13 -> 8.26 %), ``xi_h``
0.073 -> 0.069, every 90 % interval still holding the truth; on the 40-record journal (``person_fits.py``, seed
77) 34 records within 0.1 sd, the others up to 0.76 sd in ``f_h`` and 2.1 sd in ``xi_h``, where the chain of
re-placements ended at another of the record's maxima (higher on three, lower on one)."""


@one_blas_thread
@record_cores
def identify_person(record: Record, n_harmonics=4, variation="auto", timing="model", process_noise=False,
                    intervals="calibrated", level=0.9, regressors=(), cov_type=WIDER_SANDWICH, drift=False, check=True,
                    rate=RECORD_RATE, progress=False, effects=(), measured_floor=True, span="auto",
                    check_change=True, noise_floor=NOISE_FLOOR, fade="auto", threads=None):
    """Identify one person's SMD model from a whole bouncing record.

    Parameters
    ----------
    record : Record
        The measurement (``time``, ``force`` in N, ``mass`` in kg). One read without a mass
        (``read_record(path)``) is weighed on the plate first
        (:func:`~smd_statespace.signals.weighing.weigh_record`; a note says how).
    n_harmonics : int
        Harmonics ``n`` of the force, Eq. 4.
    variation : {"auto", "independent", "smooth", "random_walk", "both"}
        How the force coefficients vary (:mod:`~smd_statespace.person.model`):
        jumping at every cycle start (``"independent"``), drifting smoothly
        in time (``"smooth"``), a random walk from cycle to cycle
        (``"random_walk"``) or a wandering template plus draws (``"both"``).
        ``"auto"`` (default) fits
        :data:`AUTO_VARIATIONS` at the first cycle timing and keeps the lowest
        AIC among the fits whose ``f_h`` and ``xi_h`` are off their search
        bounds (the list of fits is ``result.comparison``); with
        ``timing="model"`` each model then re-places the cycle starts with
        its own fit and the choice is made again there.
    timing : {"model", "template", "peaks"}
        How the force-cycle boundaries are placed: ``"template"`` and
        ``"peaks"`` as :func:`~smd_statespace.person.timing.estimate_timing`
        places them; ``"model"`` (default) starts from the template
        alignment and then lets the model place them: each cycle gets a
        phase error and a phase-rate error (states of the model, drawn afresh
        every cycle), and the starts are moved by their smoothed values,
        :data:`TIMING_ITERATIONS` times; the fit with the highest likelihood
        is kept.
    process_noise : bool
        Add a white force on the COM with an estimated level.
    intervals : {"calibrated", "wald", "profile"}
        ``"calibrated"`` (default): estimate +- z * standard error, the
        standard errors of ``f_h`` and ``xi_h`` (and of ``k_h``, ``c_h``)
        multiplied by :data:`CALIBRATION`, the intervals widened by
        :data:`MODEL_ERROR_FLOOR`; ``"wald"``: the same from the
        observed information alone (too narrow: docs/person-benchmark.md);
        both cut at the search bounds (:func:`wald_interval`: ``xi_h`` never below 0);
        ``"profile"``: profile-likelihood intervals (measured: about 9 s more
        on a 30 s record; as narrow as the Wald ones).
    level : float
        Confidence level of the intervals.
    regressors : sequence of Regressor
        Effects' signals with unknown coefficients (a constant offset, for an
        imprecise body mass or plate zero, is always included).
    cov_type : {"oim_or_robust", "oim", "robust"}
        Covariance of the estimates (:func:`information`): the inverse observed
        information with the sds of ``f_h`` and ``xi_h`` raised to the cycle-clustered
        sandwich's where that is wider (default, :data:`~smd_statespace.person.search.WIDER_SANDWICH`),
        the inverse observed information alone, or the sandwich.
    drift : bool
        Let the force coefficients also wander within cycles (a per-sample
        random walk with one estimated variance per harmonic group).
    check : bool
        True (default): refuse a record that is not one person bouncing in
        contact with the plate (:func:`~smd_statespace.applicability.check_bouncing`);
        False: identify anyway, its findings become warnings.
    rate : float or None
        A record sampled at twice this rate (Hz) or faster is low-pass filtered and
        decimated to between ``rate`` and ``2 rate`` before the fit
        (:func:`~smd_statespace.signals.decimate_record`; default
        :data:`~smd_statespace.signals.RECORD_RATE`, the rate the calibration was
        measured at), with the regressors; ``result.notes`` says so. None keeps every sample
        (slower: the likelihood's cost grows with the samples, and the calibrated intervals
        were not measured there).
    span : "auto", (float, float) or None
        The part of the record the person is identified from
        (:func:`~smd_statespace.signals.prepare_record`). ``"auto"`` (default): a record as labs
        export it (standing before and after, ramps, mains hum, a drifting zero) is fitted on the
        steady part of its longest bout of bouncing, the hum subtracted and the fitting rate kept
        clear of it, the standing parts read for the body weight and the plate's zero, and a
        slow drift of the measurement's zero (:data:`ZERO_DRIFT_SECONDS`) estimated with the person;
        a record bouncing from end to end is fitted whole, as before. ``(start, end)`` (s): that
        part. None: the whole record as it is (decimated only). ``result.notes`` says what was done.
    check_change : bool
        True (default): the person is fitted again on each half of the record and the halves
        compared (:func:`~smd_statespace.person.change.change_test`, ``result.change``): a person
        whose ``f_h`` or ``xi_h`` differs between them is said in words, and that parameter is
        not called determined; so is one that score tests of a drift or a step in time, made at the
        fitted person, find (:func:`~smd_statespace.person.screen.time_change`,
        ``result.change["time"]``). False skips the two fits and the tests.
    noise_floor : float or None
        Fraction of body weight (default :data:`~smd_statespace.person.noise_floor.NOISE_FLOOR`, 1 % BW):
        a record whose measured noise per fitted sample is lower is fitted with white noise added up to it,
        seeded by the record (:mod:`~smd_statespace.person.noise_floor`: a quiet plate otherwise lets details
        of the force's variation that no variation model describes set ``f_h`` and ``xi_h``); ``result.notes``
        says so. None (or 0) fits the record as measured.
    fade : {"auto", True, False}
        Let the force's harmonics fade (or grow) linearly over the record by one factor, estimated with the
        person (a person who tires, :mod:`~smd_statespace.person.fade`; no search dimension: the factor is
        estimated with the template). "auto" (default): where ``span``
        trimmed the record to a bout of bouncing (a trial as labs export it); True: on any record; False:
        never. ``result.notes`` says what the fade found. It scales the template of ``timing="model"``: with
        another timing "auto" leaves it out and True is an :class:`OptionError`.
    threads : int or None
        Threads for the searches that do not depend on each other (each variation model's re-placed cycle
        starts, the halves' fits; :mod:`~smd_statespace.person.threads`): the same answer, sooner on two
        cores. None: :func:`~smd_statespace.person.threads.search_threads` (two, or the environment variable
        ``SMD_STATESPACE_THREADS``).
    progress : bool
        Show a progress bar (tqdm) over the likelihood searches (one per variation model,
        ``TIMING_ITERATIONS + 1`` more for ``timing="model"`` and the winner's final fit, then the
        information matrix):
        a 30 s record takes 7-25 s.
    effects : sequence of Effect or str
        Physical effects added to the person's model (objects, names or
        ``NAME:key=value`` specs, as ``--effect``): the same effects every
        estimator and the simulator use (:mod:`smd_statespace.effects`). The
        person is first identified without them (``result.before``), then with
        them, their parameters estimated jointly with ``f_h`` and ``xi_h``, the
        cycle starts and the variation model chosen again with the effects in
        the model (:func:`~smd_statespace.person.extend.fit_effects`). A bare name
        takes the options its class chooses for the record, as ``diagnose``
        proposes it (a cubic spring's search range scaled to the record's
        displacement).
    measured_floor : bool
        When the record has a ``floor_acc`` column, the person rides the floor it
        measured: the measured floor (``floor_mode``, source "measured": the floor's
        displacement and velocity are known inputs of Eq. 2, no unknown is added) is
        one of ``effects`` unless a ``floor_mode`` is given there or this is False
        (``--no-floor``). Without it, on simulated records of people on a moving
        floor the person came out wrong with an interval that missed the truth on 3
        of 21 (:func:`~smd_statespace.person.extend.record_effects`).

    Returns
    -------
    PersonResult

    Raises
    ------
    NotBouncingError
        The record is not bouncing (contact lost, clipped, not rhythmic, walking) and ``check`` is True.
    CycleError
        No bouncing cycles, or fewer than :data:`MIN_CYCLES`.
    OptionError
        Unknown ``variation``, ``timing``, ``intervals`` or effect, or an effect that needs a
        column the record lacks (``floor_acc``).
    FitError
        The fit does not converge or does not determine ``f_h`` and ``xi_h``.
    """
    from .extend import check_effects, fit_effects, record_effects

    effects_asked = tuple(effects)
    given = record_effects(record, effects_asked, measured_floor)
    effects = check_effects(given, record)  # bad specs and missing columns fail before any fit
    record = weigh_record(record)  # read without a mass: the plate weighs the person
    _check_options(variation, intervals, timing, cov_type)
    noise_floor, threads = check_noise_floor(noise_floor), search_threads(threads)
    prepared, observed = _prepared(record, rate, span, regressors, check)
    record_warnings = _applicable(record, prepared, check)
    measured_force, record = record.force, prepared.record  # the force as read seeds the noise floor's draw
    regressors = [replace(r, values=v) for r, v in zip(regressors, prepared.extra)]
    zero = tuple(zero_drift(record.time)) if prepared.trimmed else ()
    faded = fading(fade, prepared.trimmed, timing)
    y, floor_notes = raise_to_floor(record.force / record.mass - G, observed, record.fs, noise_floor,  # Eq. 3
                                    seed_from=measured_force)
    notes = list(prepared.notes) + floor_notes
    first = "template" if timing == "model" else timing
    cycle_timing = _first_timing(record, record.force, n_harmonics, first)
    offset = Regressor("offset", np.ones_like(y), "m/s^2", dynamic=False)
    all_regressors = (offset,) + tuple(regressors)
    names = AUTO_VARIATIONS if variation == "auto" else (variation,)

    def model_for(timing_, variation_, template, zero_=None):
        return RecordModel(record.time, y, timing_, n_harmonics, variation_, process_noise, drift=drift,
                           regressors=all_regressors + (zero if zero_ is None else zero_), phase_template=template,
                           observed=observed, fade=faded)

    steps = len(names) * (1 + (TIMING_ITERATIONS + 1 if timing == "model" else 0)) + (2 if timing == "model" else 1)
    steps += 1 if check_change else 0  # the halves' fits
    zero_note = ""

    def person_at(cycle_timing, bar):  # the person from these first cycle starts, with the effects asked for
        nonlocal zero, zero_note
        model, fitted, comparison = _search(model_for, cycle_timing, names, timing, bar.update, threads)
        if zero and not zero_note:  # a lab-shaped record: does its zero move faster than the slow drift follows?
            denser = tuple(zero_drift(record.time, ZERO_WANDERS_SECONDS))
            said = _zero_wanders(model, fitted, model_for(model.timing, model.variation, model.phase_template, denser))
            if said:
                bar.total += steps - 1
                zero, zero_note = denser, said
                model, fitted, comparison = _search(model_for, cycle_timing, names, timing, bar.update, threads)
        if not fitted["converged"]:
            raise FitError(f"{record.source}: the likelihood search did not converge ({fitted['message']}); try "
                           "--variation independent, a longer record or a per-cycle estimator (--estimator ekf)")
        change = None
        if check_change:
            change = change_test(model, fitted["params"], level, threads)
            bar.update()
        result = person_result(record, model, fitted, intervals=intervals, level=level, cov_type=cov_type,
                               comparison=comparison, record_warnings=list(record_warnings),
                               notes=notes + ([zero_note] if zero_note else []), change=change, prepared=prepared,
                               threads=threads)
        result = _changed_in_time(result, threads) if change is not None else result
        bar.update()
        if effects:  # as given: a bare name is configured for the record (extend.configured_for_record)
            result = fit_effects(result, given, intervals=intervals, cov_type=cov_type, progress=progress,
                                 threads=threads)
        return result

    with tqdm(total=steps, desc="identify (record)", unit="fit", disable=not progress, leave=False) as bar:
        result = person_at(cycle_timing, bar)

        def again(placed):
            bar.total += steps
            return person_at(placed, bar)

        if _rides_measured_floor(result):
            result = _starts_without_floor(result, cycle_timing, again, n_harmonics, first)
    if len(given) > len(effects_asked):  # the record brought its floor
        result.notes.append(_floor_note(result))
        result.record_warnings.extend(_floor_worse(result))
    return result


def _check_options(variation, intervals, timing, cov_type):
    """An :class:`~smd_statespace.errors.OptionError` naming the first of :func:`identify_person`'s options that is
    not one of its choices."""
    if variation != "auto" and variation not in VARIATIONS:
        raise OptionError(f"variation {variation!r} is not one of: auto, {', '.join(VARIATIONS)}")
    if intervals not in INTERVAL_METHODS:
        raise OptionError(f"intervals {intervals!r} is not one of: {', '.join(INTERVAL_METHODS)}")
    if timing not in ("model",) + TIMING_METHODS:
        raise OptionError(f"timing {timing!r} is not one of: model, {', '.join(TIMING_METHODS)}")
    if cov_type not in COV_TYPES:
        raise OptionError(f"cov_type {cov_type!r} is not one of: {', '.join(COV_TYPES)}")


def _first_timing(record, force, n_harmonics, method):
    """The cycle starts estimated from ``force`` (N, or anything affine in it) before any fit; refused where they
    are fewer than :data:`MIN_CYCLES` whole cycles."""
    cycle_timing = estimate_timing(record.time, force, n_harmonics, method, source=record.source)
    inside = np.sum((cycle_timing.boundaries > record.time[0]) & (cycle_timing.boundaries < record.time[-1]))
    if inside - 1 < MIN_CYCLES:
        raise CycleError(f"{record.source}: {max(inside - 1, 0)} whole bouncing cycles found; the record-level model "
                         f"needs at least {MIN_CYCLES} to estimate the cycle-to-cycle variation: use a longer record "
                         "or a per-cycle estimator (--estimator ekf)")
    return cycle_timing


def _starts_without_floor(result, cycle_timing, person_at, n_harmonics, method):
    """The person again from cycle starts placed on the force less the measured floor's share, where they differ.

    The first cycle starts are placed on the GRF (:func:`_first_timing`), whose peaks a floor near resonance
    moves: on simulated records of people on a 3.48 Hz floor they were up to half a cycle off, and the fit with
    the floor then fitted worse than the one without it (likelihood ratio down to -534, ``f_h`` -27 %;
    docs/effects.md, "Why a measured floor can fit worse than no floor"). Here the floor's share of the body's
    acceleration at ``result``'s ``f_h`` and ``xi_h`` (:func:`~smd_statespace.person.timing.floor_share`; those of
    the fit without the floor where ``result``'s sit on a search bound and its do not: on two records the floor's
    first fit ran to 0.5 Hz, the fit without it was at 3.2 and 3.5 Hz) is taken out, the starts are placed again
    on what is left, and the person is identified from them (``person_at``, the whole of :func:`identify_person`
    from its first starts on). Of the two the fit with the lower AIC is kept (the same model, its variation model
    chosen in each; the starts are estimated as ``f_h`` is), and a note says both.
    """
    record, person = result.record, result
    if result.model.person_at_bound(result.params) and result.before is not None and \
            not result.before.model.person_at_bound(result.before.params):
        person = result.before  # the floor's fit is degenerate there: the person without the floor
    share = floor_share(record.time, record.floor_acc, person.f_h, person.xi_h)
    try:
        placed = _first_timing(record, record.force - record.mass * share, n_harmonics, method)
    except CycleError:
        return result
    before, after = cycle_timing.boundaries, placed.boundaries
    if before.size == after.size and np.max(np.abs(after - before)) < 0.5 / record.fs:
        return result  # the same starts to the sample
    again = person_at(placed)
    kept = min((again, result), key=lambda fit: aic({"params": fit.params, "loglike": fit.loglike}))
    which = "the new starts" if kept is again else "the GRF's starts"
    whose = ", the fit without the floor's: the first fit's sat on a search bound" if person is not result else ""
    kept.notes.append(f"the cycle starts were placed again on the force less the measured floor's share (the "
                      f"person's response to floor_acc at f_h {person.f_h:.3f} Hz, xi_h {person.xi_h:.3f}{whose}): "
                      f"log-likelihood {again.loglike:.1f} from them, {result.loglike:.1f} from the starts placed on "
                      f"the GRF; the fit from {which} is kept")
    return kept


def _rides_measured_floor(result) -> bool:
    """Whether ``result``'s model has a measured floor (``floor_mode``, source "measured") and its record the
    ``floor_acc`` it measured."""
    return getattr(result.record, "floor_acc", None) is not None and any(
        effect.name == "floor_mode" and getattr(effect, "source", None) == "measured" for effect in result.effects)


def _search(model_for, cycle_timing, names, timing: str, step, threads: int) -> tuple:
    """``(model, fit, comparison rows)``: every variation model of ``names`` fitted at the first cycle timing and
    compared by AIC there; with ``timing="model"`` each then re-places the cycle starts with its own fit, and the
    choice is made again (:func:`~smd_statespace.person.search.choose_with_own_timing`)."""
    fits = thread_map(lambda name: _fitted(model_for(cycle_timing, name, None), timing == "model"), names, threads)
    step(len(names))
    comparison = [comparison_row(m, f, "first") for m, f in fits]
    # a fit with f_h or xi_h on its search bound has not estimated them (a variation model that is
    # too flexible lets the person's resonance imitate a missing effect): it wins only if all do
    eligible = [i for i, row in enumerate(comparison) if not row.on_bound] or list(range(len(fits)))
    best = min(eligible, key=lambda i: comparison[i].aic)
    model, fitted = fits[best]
    if timing == "model":
        suspect = {row.variation for row in comparison if row.on_bound}  # at the first timing
        model, fitted, refined = choose_with_own_timing(model_for, cycle_timing, fits, best, step, suspect, threads)
        comparison += refined
    return model, fitted, comparison


def _zero_wanders(model, fitted, denser) -> str:
    """The note of a zero that moves faster than the slow drift follows, or "": the likelihood ratio of ``denser``
    (the same model with :data:`ZERO_WANDERS_SECONDS`' drift) at ``fitted``'s parameters, chi-squared on the extra
    degrees (:data:`ZERO_WANDERS_ALPHA`)."""
    from scipy.stats import chi2

    extra = len(denser.regressors) - len(model.regressors)
    if extra <= 0:  # a span so short that the slow drift has as many degrees
        return ""
    ratio = 2.0 * (denser.loglike(fitted["params"]) - model.loglike(fitted["params"]))
    p_value = float(chi2.sf(ratio, extra)) if np.isfinite(ratio) else 1.0
    if p_value >= ZERO_WANDERS_ALPHA:
        return ""
    return (f"the plate's zero moves faster than a slow drift follows (likelihood ratio {ratio:.1f} on {extra} "
            f"degrees, p {p_value:.2g}): the person was fitted again with its drift of a degree every "
            f"{ZERO_WANDERS_SECONDS:g} s")


def _changed_in_time(result, threads: int):
    """``result`` with the halves' test of a person who changes joined by the score tests of ``f_h`` and ``xi_h``
    changing in time (:func:`~smd_statespace.person.screen.time_change`, ``result.change["time"]``): a parameter
    the halves name, and both ``f_h`` and ``xi_h`` when a score test finds a change, are not determined, their
    intervals spanning the halves' (:func:`honest_intervals`); ``result.change["by_halves"]`` keeps what the
    halves named. A score test names the parameter whose term fits best, not surely the one that changed: in
    lab exports of people who tire and whose ``f_h`` steps by 8-9 %, with the fade in the model, a step of
    ``xi_h`` fitted better, and ``f_h``, called determined, was 12 and 15 % off outside its interval."""
    try:
        tests = time_change(result, threads=threads)
    except (SMDInputError, ArithmeticError, np.linalg.LinAlgError) as exc:  # the fit stands; the check is said
        result.notes.append(f"the score tests of a change in time failed ({' '.join(str(exc).split())})")
        return result
    change = result.change
    change["time"], change["by_halves"] = tests, list(change["changed"])
    named = set(change["changed"]) | (set(PERSON) if tests["changed"] else set())
    change["changed"] = [name for name in PERSON if name in named]
    if result.narrow_intervals:
        result.intervals.update(honest_intervals(result))
    return result


def _fitted(model, first: bool) -> tuple:
    """``(model, its fit)``: :func:`~smd_statespace.person.search.fit_model` from the coarse start; ``first``: a
    first fit, to :data:`FIRST_GAIN` (else the fit is the answer, to full precision)."""
    return model, fit_model(model, quick=FIRST_GAIN if first else False)


def _floor_note(result) -> str:
    """The note of a fit with the floor its record brought: what it is and its likelihood ratio, with the two
    log-likelihoods the ratio is of (both at the cycle starts and variation model of the fit without it)."""
    test = result.effect_test()
    return (f"the record's floor_acc is in the model (floor_mode, measured: the person rides the floor, no unknown "
            f"added; likelihood ratio against the person without it {test['lr']:.1f} = 2 x "
            f"({test['loglike_tested']:.1f} - {test['loglike_before']:.1f}), both at the cycle starts and variation "
            "model of the fit without it); --no-floor (measured_floor=False) leaves it out")


FLOOR_WORSE = -10.0
"""A record's measured floor whose likelihood ratio against the person without it is below this is warned of
(:func:`_floor_worse`). The two models have the same unknowns (the floor adds none), so the ratio is their AIC
difference: over 10, the worse model has essentially no support (Burnham & Anderson 2002, Sect. 2.6). On the floor
rows of ``benchmarks/floor_starts.py`` (seed 92: 32 records of ``person_effects.py``, one refused, and 12 of a
person at the floor's resonance) 12 of 43 were below it with the starts placed on the GRF, 3 with them placed
again without the floor's share (:func:`_starts_without_floor`; docs/effects.md, "Why a measured floor can fit
worse than no floor")."""


def _floor_worse(result) -> list:
    """The warning of a record whose own floor makes the fit worse by more than :data:`FLOOR_WORSE`, with ``f_h``
    with and without the floor; none otherwise."""
    lr = result.effect_test()["lr"]
    if not lr < FLOOR_WORSE:
        return []
    return [f"the record's floor_acc makes the fit worse, not better (likelihood ratio {lr:.1f} against the person "
            "without it, the same unknowns): is it the vertical acceleration of the floor under the plate, upward "
            "positive, in m/s^2? (one with its sign flipped fits worse than no floor) Else the model misses "
            "something, and each cycle's force takes up the floor's terms better than the physics does; f_h is "
            f"{result.f_h:.3f} Hz with the floor and {result.before.f_h:.3f} Hz without it (--no-floor): read "
            "neither beyond its interval"]


def zero_drift(time, seconds=ZERO_DRIFT_SECONDS) -> list:
    """Regressors of a slowly drifting zero of the measurement: Legendre polynomials in time.

    Degree 1 to ``ceil(T / seconds)`` (at least 2, at most :data:`ZERO_DRIFT_MAX_DEGREE`) over the span ``T``;
    measurement-only (``dynamic=False``): the plate's zero moves the measured acceleration, not the person.

    Examples
    --------
    >>> [r.name for r in zero_drift(np.linspace(4.0, 34.0, 7))]
    ['zero_drift_1', 'zero_drift_2', 'zero_drift_3']
    >>> [r.name for r in zero_drift(np.linspace(4.0, 34.0, 7), ZERO_WANDERS_SECONDS)][-1]
    'zero_drift_15'
    """
    time = np.asarray(time, dtype=float)
    span = max(time[-1] - time[0], 1e-12)
    degree = min(ZERO_DRIFT_MAX_DEGREE, max(2, int(np.ceil(span / seconds - 1e-9))))
    scaled = 2.0 * (time - time[0]) / span - 1.0
    return [Regressor(f"zero_drift_{k}", np.polynomial.legendre.Legendre.basis(k)(scaled), "m/s^2", dynamic=False)
            for k in range(1, degree + 1)]


def _prepared(record, rate, span, regressors, check):
    """``(prepared, observed)``: the record the fit takes (:func:`~smd_statespace.signals.prepare_record`) and which
    of its samples were measured (None: all; a phone's gaps, ``record.extra["unmeasured"]``, decimated and trimmed
    with it: a fitted sample that the decimation's low-pass drew more than :data:`UNMEASURED_SHARE` from a gap is
    not measured). A record with no bouncing part is refused with the applicability check's words when it has
    them, the front end's otherwise (with ``check`` False: the whole record, with a warning)."""
    unmeasured = record.extra.get("unmeasured")
    gaps = [] if unmeasured is None or not np.any(unmeasured) else [np.asarray(unmeasured, dtype=float)]
    prepared = _front_end(record, rate, span, [r.values for r in regressors] + gaps, check)
    if not gaps:
        return prepared, None
    observed = np.abs(prepared.extra[-1]) <= UNMEASURED_SHARE
    return replace(prepared, extra=prepared.extra[:-1]), observed


def _applicable(record, prepared, check) -> list:
    """The front end's and the applicability check's warnings on the part of ``record`` the front end kept
    (``prepared``). Where that part is refused, the record as read is refused in its own words when it has them:
    a resonant simulated person whose force went below zero 61 times had 2.1 s kept, "not rhythmic", where the
    whole record says the person leaves the plate."""
    found = check_bouncing(prepared.record)
    if found.refusals and check:
        check_bouncing(record).raise_if_refused()
        if prepared.trimmed:  # the part refused is the front end's choice: say which, and what else it found
            try:
                found.raise_if_refused()
            except NotBouncingError as exc:
                raise NotBouncingError(f"{exc}; that is the part of the record the front end kept "
                                       f"({prepared.bouts.describe()}); --span START:END fits another") from None
    return prepared.warnings + found.raise_if_refused(override=not check)


def _front_end(record, rate, span, extra, check):
    """:func:`_prepared`'s front end with the arrays ``extra`` moved along."""
    # clipping is seen on the record as read: the decimation's low-pass rounds the flat tops off
    clipped = check_clipping(record).raise_if_refused(override=not check)
    try:
        prepared = prepare_record(record, rate, span, extra)
        return replace(prepared, warnings=clipped + prepared.warnings)
    except RecordError as exc:
        if not (isinstance(span, str) and span == "auto"):
            raise
        found = check_bouncing(record).raise_if_refused(override=not check)  # its own words first: jumping, walking
        if check:
            raise
        prepared = prepare_record(record, rate, None, extra)
        return replace(prepared, warnings=found + [f"{exc}; fitted whole as asked (check=False)"])

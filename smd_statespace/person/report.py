"""The record-level answer in words: warnings, the flat summary (``person.json``), a table row, the text.

Functions of a :class:`~smd_statespace.person.results.PersonResult`; the
result's ``warnings``, ``to_dict``, ``table_row`` and ``summary`` call them.
"""

from __future__ import annotations

import numpy as np

from ..io import G
from .detection import printed_limits, unseen_change
from .fade import fade_table
from .in_time import in_time_words
from .judgement import (DETERMINED_FRACTION, F_B_COINCIDENCE, MISFIT_SHARE, PRIOR_SD, STARTING_RANGE, WHITENESS_ALPHA,
                        narrowed)
from .phone_report import phone_words

__all__ = ["CONFOUNDED", "change_words", "one_person_line", "person_warnings", "ratio_words", "result_dict",
           "summary_text", "table_row", "unit_suffix"]


CONFOUNDED = 0.9
"""An effect's parameter not determined and correlated beyond this with ``f_h`` or ``xi_h`` (in the estimates'
covariance) is said to be indistinguishable from it on the record."""


def _told_from(result, name) -> str:
    """``": on this record it cannot be told from f_h (correlation -0.999)"``, or "" when neither ``f_h`` nor
    ``xi_h`` is correlated with the parameter ``name`` beyond :data:`CONFOUNDED`."""
    cov = np.asarray(result.cov, dtype=float)
    i = result.model.position(name)
    best, partner = 0.0, ""
    for other in ("f_h", "xi_h"):
        j = result.model.position(other)
        scale = np.sqrt(cov[i, i] * cov[j, j])
        correlation = cov[i, j] / scale if scale > 0 else 0.0
        if np.isfinite(correlation) and abs(correlation) > abs(best):
            best, partner = float(correlation), other
    if abs(best) <= CONFOUNDED:
        return ""
    return (f": on this record it cannot be told from {partner} (correlation {best:.3f}): the two change the "
            "prediction alike, and its likelihood ratio says nothing about it")


def person_warnings(result) -> list:
    """Plain-word warnings: the record's checks, parameters at a bound or not determined, residual tests that reject."""
    out = list(result.record_warnings) + [words for words in [change_words(result.change)] if words]
    named = result.model.unpack(result.params)
    for name in ("f_h", "xi_h"):
        low, high = result.model.bound(name)
        value = named[name]
        if result.model.at_bound(result.params, name):
            out.append(f"{name} = {value:.3g} sits on its search bound ({low:g}-{high:g}): not an estimate; "
                       "the model may not fit this record (run diagnose)")
        elif name == "f_h" and result.mimicked_harmonic:
            i = result.mimicked_harmonic
            where = "the bouncing frequency" if i == 1 else f"{i} times the bouncing frequency"
            out.append(f"f_h = {value:.3g} Hz is within {F_B_COINCIDENCE:.0%} of {where} with xi_h = "
                       f"{result.xi_h:.2g}: an undamped resonance there stands in for the force's harmonic {i} "
                       f"(BLF{i} near 0), so f_h, xi_h and BLF{i} are not determined; bouncing people show "
                       "xi_h 0.1-0.6")
        elif name == "f_h" and result.at_bouncing_frequency:
            out.append(f"f_h = {value:.3g} Hz is within {F_B_COINCIDENCE:.0%} of the bouncing frequency: with a "
                       "smoothly drifting force, a person resonating at f_b and the drift look alike, so f_h is "
                       "not determined (on simulated records ending here the median error was 16 %)")
        elif result.misfit:
            continue  # said once, with the whiteness test below
        elif result.change and name in result.change["changed"]:  # not its sd: a yardstick beside it misled
            out.append(f"{name} is not determined: the person changes during the record (above), so no one value "
                       "describes it; read its interval, which spans the parts'")
        elif not result.determined(name):
            sd, unit, (low, high) = result.sd(name), " Hz" if name == "f_h" else "", STARTING_RANGE[name]
            why = (f": its sd {sd:.3g}{unit} is more than {DETERMINED_FRACTION:g} of {PRIOR_SD[name]:.3g}{unit}, the "
                   f"sd of the article's starting range ({low:g}-{high:g}{unit}), which a record that determines it "
                   "narrows fourfold" if np.isfinite(sd) and not narrowed(sd, name) else "")
            out.append(f"{name} is not determined by this record{why}; read its interval, not its value")
    blf = result.template_blf()
    undetermined = [f"BLF{i}" for i in blf.index[~blf["determined"].astype(bool)]]
    if undetermined:
        out.append(f"{', '.join(undetermined)} not determined: the force is read through Eq. 2 at a person this "
                   f"record does not settle (over the intervals of f_h and xi_h they span more than their own "
                   f"value); read their intervals")
    if result.xi_h > 1.0:
        out.append(f"xi_h = {result.xi_h:.2f} > 1 (over-damped): outside what bouncing people show (0.1-0.6)")
    disagreement = result.variation_disagreement()
    if disagreement:
        out.append(disagreement)
    for name, row in result.effect_estimates().iterrows():
        unit = unit_suffix(row["unit"])
        if row["on_bound"]:
            out.append(f"{name} = {row['value']:.4g}{unit} sits on its search bound ({row['range_low']:g}-"
                       f"{row['range_high']:g}): not an estimate; the record does not show this effect as "
                       "modelled")
        elif not np.isfinite(row["sd"]) or row["sd"] > 0.25 * (row["range_high"] - row["range_low"]):
            out.append(f"{name} is not determined by this record (sd {row['sd']:.3g}{unit} against its "
                       f"range {row['range_low']:g}-{row['range_high']:g}){_told_from(result, name)}")
    phone = phone_words(result)
    if phone:
        out.append(phone)
    tests = result.test_pvalues()
    command = f"`smd-statespace diagnose {result.record_arguments()}`"
    if result.misfit or tests["ljung_box_p"] < WHITENESS_ALPHA:
        if result.misfit:
            share = f"{100 * result.misfit_share:.1f} % of the signal, over {100 * MISFIT_SHARE:g} %"
            seen = (f"innovations are serially correlated (Ljung-Box p = {tests['ljung_box_p']:.2g}; their "
                    f"predictable part is {share})" if tests["ljung_box_p"] < WHITENESS_ALPHA else
                    f"the innovations' own past predicts part of them ({share}), although Ljung-Box does not "
                    f"flag it (p = {tests['ljung_box_p']:.2g})")
            out.append(f"{seen}: the model misses something, which it puts into f_h and xi_h, "
                       "so they are not determined (their intervals are as wide as the yardstick) until the "
                       f"missing effect is in the model; run {command}")
        else:
            out.append(f"innovations are serially correlated (Ljung-Box p = {tests['ljung_box_p']:.2g}): the "
                       f"model misses something, and f_h, xi_h and their intervals may be biased; run {command}")
    return out


def result_dict(result) -> dict:
    """Flat JSON-able summary (the content of ``person.json``)."""
    out = {"f_h": result.f_h, "f_h_sd": result.sd("f_h"), "xi_h": result.xi_h, "xi_h_sd": result.sd("xi_h")}
    for name in ("f_h", "xi_h"):
        low, high = result.intervals[name]
        out[f"{name}_low"], out[f"{name}_high"] = float(low), float(high)
        out[f"{name}_determined"] = result.determined(name)
    out["misfit"] = result.misfit
    out["misfit_share"] = result.misfit_share
    out["interval_level"] = result.level
    out["interval_method"] = result.interval_method
    out.update(result.derived())
    extra = result.record.extra
    out["sensor"] = extra.get("sensor", "force plate")
    out["mass_known"] = result.mass_known
    if out["sensor"] == "accelerometer":
        out["accelerometer"] = {"format": extra.get("format"), "units_read": extra.get("units_read"),
                                **{f"clock_{k}": v for k, v in extra.get("clock", {}).items()},
                                **{f"geometry_{k}": v for k, v in extra.get("geometry", {}).items()}}
    blf = result.template_blf()
    for i, row in blf.iterrows():
        out[f"blf_{i}"] = float(row["blf"])
        out[f"blf_{i}_sd"] = float(row["sd"])
        out[f"blf_{i}_low"], out[f"blf_{i}_high"] = float(row["low"]), float(row["high"])
        out[f"blf_{i}_determined"] = bool(row["determined"])
        out[f"blf_{i}_sd_given_person"] = float(row["sd_given_person"])
        out[f"blf_{i}_spread"] = float(row["spread"])
    walk = result.spread("e")
    for i in range(1, result.model.n_harmonics + 1):
        out[f"blf_{i}_walk"] = float(walk[i])
    out["a0_spread"] = float(result.spread()[0])
    out["noise_sd"] = result.sigma
    out["noise_bw"] = result.sigma / G
    for name, row in result.regressor_coefficients().iterrows():
        out[name], out[f"{name}_sd"] = float(row["value"]), float(row["sd"])
    fade = fade_table(result)
    if not fade.empty:  # the fading harmonics' load factors at the record's start and end
        out["fade"] = {"c": float(fade["c"].iloc[0]), "c_sd": float(fade["c_sd"].iloc[0]),
                       **{f"blf_{i}_{key}": float(row[key]) for i, row in fade.iterrows() for key in ("start", "end")}}
    out["variation"] = result.model.variation
    out["timing"] = result.model.timing.method
    out["f_b"] = float(np.median(result.model.timing.f_b))
    out["n_harmonics"] = result.model.n_harmonics
    out["log_likelihood"] = result.loglike
    out["n_params"] = int(len(result.params))
    out["n_cycles"] = result.n_cycles
    out["n_samples"] = int(result.model.y.size)
    out.update(result.test_pvalues())
    out["fs"] = result.record.fs
    if result.change is not None:  # the halves of the record and whether the person changed between them
        out["change"] = result.change
    if result.effects:
        out["effects"] = [effect.spec for effect in result.effects]
        for name, row in result.effect_estimates().iterrows():
            out[name], out[f"{name}_sd"] = row["value"], row["sd"]
            out[f"{name}_low"], out[f"{name}_high"] = row["low"], row["high"]
            out[f"{name}_on_bound"] = bool(row["on_bound"])
        out.update(result.effect_test())
        in_time = result.in_time()
        if not in_time.empty:  # f_h, xi_h at the span's ends and either side of a step
            out["in_time"] = in_time.to_dict("records")
        out["likelihood"] = "exact" if result.model.exact else "approximate"
        out["linearisations"] = result.linearisations
        out["settled"] = result.settled
        before = result.before.to_dict()
        out["before"] = {key: before[key] for key in ("f_h", "f_h_sd", "f_h_low", "f_h_high", "xi_h", "xi_h_sd",
                                                      "xi_h_low", "xi_h_high", "log_likelihood", "noise_sd",
                                                      "ljung_box_p")}
    out["warnings"] = result.warnings
    out["notes"] = list(result.notes)
    out["variation_models"] = [row.to_dict() for row in result.comparison]
    return out


def table_row(result) -> dict:
    """One flat row for a table of people (a batch's ``results.csv``; what ``stats`` reads).

    The scalars of :meth:`to_dict`, the warnings joined by ``" | "``, and
    the flags ``stats`` uses: ``implausible`` (``f_h`` or ``xi_h`` on a
    search bound: not an estimate) with ``implausible_reason``, and
    ``model_adequate`` (the innovations pass the Ljung-Box test at
    :data:`WHITENESS_ALPHA`); ``f_h_drift_limit_pct`` and ``f_h_step_limit_pct``,
    the change of ``f_h`` (%) over the record or across a step in its middle that
    the record's tests would have found where they found none and ``f_h`` is
    determined (:func:`~smd_statespace.person.detection.printed_limits`; blank
    otherwise).
    """
    row = {key: value for key, value in result.to_dict().items() if np.isscalar(value)}
    row["warnings"] = " | ".join(result.warnings)
    reasons = [f"{name} on search bound" for name in ("f_h", "xi_h") if result.model.at_bound(result.params, name)]
    row["implausible"] = bool(reasons)
    row["implausible_reason"] = "; ".join(reasons)
    row["model_adequate"] = bool(row["ljung_box_p"] >= WHITENESS_ALPHA)
    limits = printed_limits(result)  # the change of f_h the record would have shown (blank where it says none)
    row["f_h_drift_limit_pct"], row["f_h_step_limit_pct"] = (limits.get(k, np.nan) for k in ("f_drift", "f_step"))
    return row


def summary_text(result, verbose=False) -> str:
    """The person in a few lines: the answer first, then noise, force, tests, warnings.

    ``verbose`` adds how the intervals were made (also in ``person.json``, ``interval_method``).
    """
    d = result.to_dict()
    pct = int(round(100 * result.level))
    lines = [
        f"person from {d['n_cycles']} cycles (f_b {d['f_b']:.2f} Hz, {result.model.variation} variation, "
        f"{result.model.timing.method} timing):",
        f"  f_h  = {d['f_h']:.3f} Hz  (sd {d['f_h_sd']:.3f}; {pct} % interval {d['f_h_low']:.2f}-{d['f_h_high']:.2f} "
        f"Hz){'' if d['f_h_determined'] else '  NOT DETERMINED'}",
        f"  xi_h = {d['xi_h']:.3f}     (sd {d['xi_h_sd']:.3f}; {pct} % interval {d['xi_h_low']:.2f}-"
        f"{d['xi_h_high']:.2f}){'' if d['xi_h_determined'] else '  NOT DETERMINED'}",
        (f"  K_h  = {d['k_h']:.0f} N/m (sd {d['k_h_sd']:.0f}), C_h = {d['c_h']:.0f} N s/m (sd {d['c_h_sd']:.0f})"
         if result.mass_known else "  K_h, C_h: not computed without the body mass (give --mass KG); f_h, xi_h and "
         "the BLFs do not need it"),
        "  BLF (g): " + ", ".join(
            (f"{i}: {d[f'blf_{i}']:.3f} ± {d[f'blf_{i}_sd']:.3f}" if not result.person_widened
             else f"{i}: {d[f'blf_{i}']:.3f} ({d[f'blf_{i}_low']:.3f}-{d[f'blf_{i}_high']:.3f}"
             + ("" if d[f"blf_{i}_determined"] else ", NOT DETERMINED") + ")")
            + f" (cycle spread {d[f'blf_{i}_spread']:.3f})" for i in range(1, result.model.n_harmonics + 1)),
        f"  noise sd {d['noise_sd']:.3f} m/s^2 ({100 * d['noise_bw']:.2f} % BW); log-likelihood "
        f"{d['log_likelihood']:.1f}",
        f"  innovations: Ljung-Box p {d['ljung_box_p']:.2g} ({d['ljung_box_lags']} lags), Jarque-Bera p "
        f"{d['jarque_bera_p']:.2g}, kurtosis {d['kurtosis']:.2f}",
    ]
    one = one_person_line(result.change, unseen_change(result))
    lines += [one] if one else []
    if verbose:
        lines.insert(3, f"  intervals: {result.interval_method}; BLF sds with the person's uncertainty "
                        "(sd_given_person in person.json)")
    if result.effects:
        lines[0] = lines[0][:-1] + f" with {', '.join(e.spec for e in result.effects)}:"
        for name, row in result.effect_estimates().iterrows():
            lines.append(f"  {name} = {row['value']:.4g}{unit_suffix(row['unit'])}  (sd {row['sd']:.3g}; {pct} % "
                         f"interval {row['low']:.4g} to {row['high']:.4g})")
        lines += in_time_words(result)
        before = d["before"]
        lines.append(f"  without the effect(s): f_h {before['f_h']:.3f} Hz, xi_h {before['xi_h']:.3f}, "
                     f"log-likelihood {before['log_likelihood']:.1f}, Ljung-Box p {before['ljung_box_p']:.2g}")
        lines.append(ratio_words(result))
    lines += [f"note: {n}" for n in d["notes"]]
    lines += [f"warning: {w}" for w in d["warnings"]]
    return "\n".join(lines)


def ratio_words(result) -> str:
    """The likelihood ratio of ``result``'s effects as printed: the statistic and the two log-likelihoods it is of.

    ``2 x (with - without)``, both at the cycle starts and variation model of the fit without the effects
    (:meth:`~smd_statespace.person.results.PersonResult.effect_test`). When the fit kept with the effects then
    re-placed the starts (and perhaps chose another variation model), its own log-likelihood, printed above it,
    is not the one tested, and the line says so. Until 2026-11-28 the tested one was given in passing and the
    ratio said "compare log-likelihoods": a user compared the two printed first, 1973.5 with the floor (its own
    starts, another variation model) and 1960.7 without, above a ratio of -79.8 (issue 45).
    """
    test = result.effect_test()
    p = f"p {test['lr_p']:.2g}" if np.isfinite(test["lr_p"]) else "not nested: no p-value"
    words = (f"  likelihood ratio {test['lr']:.1f} on {test['lr_df']} parameter(s) ({p}) = 2 x "
             f"({test['loglike_tested']:.1f} with - {test['loglike_before']:.1f} without)")
    if result.tested_loglike in (None, result.loglike):
        return words
    tested_variation, kept = result.before.model.variation, result.model.variation
    chose = "" if kept == tested_variation else f" and chose the {kept} variation"
    return (f"{words}, both at the cycle starts and {tested_variation} variation of the fit without them; the fit "
            f"above then re-placed the starts with them{chose}: its log-likelihood {result.loglike:.1f} is not "
            "the one tested")


def unit_suffix(unit: str) -> str:
    """A unit as printed after a value: `` Hz``, nothing for a dimensionless one (``"-"``)."""
    return "" if unit in ("-", "") else f" {unit}"


def one_person_line(change, unseen: str = "") -> str:
    """The summary's line of the tests of one unchanging person: the halves' z and the smallest score-test p-value of
    a change in time (Holm over the terms), and ``unseen`` (what the tests would have found, where none changed:
    :func:`~smd_statespace.person.detection.unseen_change`); "" when they were not made."""
    if not change:
        return ""
    parts = [f"halves {', '.join(f'{name} {abs(z):.1f} sd apart' for name, z in change['z'].items())}"]
    tests = change.get("time")
    if tests and tests["terms"]:
        best = tests["terms"][0]
        parts.append(f"a change in time: smallest p {best['p_holm']:.2g} ({best['term']}, Holm over "
                     f"{len(tests['terms'])} score tests; a change below {tests['alpha']:g})")
    return "  one person? " + "; ".join(parts) + (f"\n    no change found: {unseen}" if unseen else "")


def change_words(change) -> str:
    """The warning that names a person who changes, with both halves' numbers and the score test that found it, if
    one did ("" when none changed)."""
    if not change or not change["changed"]:
        return ""
    first, second = change["halves"]
    parts = []
    tests = change.get("time", {"terms": [], "changed": []})
    for name in change["changed"]:
        unit = " Hz" if name == "f_h" else ""
        found = next((term for term in tests["terms"] if term["parameter"] == name), None)  # smallest p first
        evidence = "" if name not in tests["changed"] else (
            f"{found['physics']} fits the record better (score test of {found['term']}: p {found['p']:.1g}, "
            f"{found['p_holm']:.1g} over {len(tests['terms'])} terms of a change in time); ")
        parts.append(f"{evidence}{name} {first[name]:.3g}{unit} ({first[f'{name}_low']:.3g}-"
                     f"{first[f'{name}_high']:.3g}) in {first['start']:.1f}-{first['end']:.1f} s, {second[name]:.3g}"
                     f"{unit} ({second[f'{name}_low']:.3g}-{second[f'{name}_high']:.3g}) in {second['start']:.1f}-"
                     f"{second['end']:.1f} s ({abs(change['z'][name]):.1f} sd apart)")
    prefix = {"f_h": "f", "xi_h": "xi"}  # the generic terms of a parameter that changes in time
    kinds = ", ".join(f"term:{prefix[name]}_{shape}" for name in change["changed"] if name in prefix
                      for shape in ("step", "drift"))
    # a xi_h that changes stands in for a force that changes as well: alone, it does not say that the person changed
    force_too = tests["changed"] == ["xi_h"] and not change.get("by_halves", change["changed"])
    return (f"the person{' or the force' if force_too else ''} changes during the record: " + "; ".join(parts) +
            ". One SMD model does not describe the "
            "whole record: read the halves, not one value; a parameter that varies in time (tiring, warming up, a "
            "change of stance; a force that fades shows as a drifting xi_h) is the likely missing piece: diagnose "
            f"tries it as a step or a drift ({kinds}), or "
            "identify parts separately with --span START:END")

"""Is a physical effect missing? Each candidate identified with the person, compared by likelihood ratio.

``diagnose`` is "identify with each candidate" plus the test: every candidate
effect is added to the record-level model by the same estimator as
``identify --effect`` (:func:`~smd_statespace.person.extend.fit_effects`: the
one SMD model with the effect, its parameters estimated jointly with ``f_h``,
``xi_h``, the variation and the noise), and the likelihood-ratio statistic
against the fit without it is referred to chi-square with the candidate's
true number of added unknowns
(:meth:`~smd_statespace.person.results.PersonResult.effect_test`), at
``alpha`` over the number of candidates (Bonferroni; a candidate found as the
best of many trials, a floor mode's frequency grid, is also tested as that many:
:func:`~smd_statespace.person.effect_adapter.record_search_size`). The table shows, before
and after, ``f_h``, ``xi_h``, the effect's parameters, the noise and the
whiteness of the innovations. Every candidate is screened at the person's
cycle starts and variation model (``fit_effects(..., timing=False)``, one search
each); the one proposed first is then identified as ``identify --effect`` does
it, the cycle starts re-placed and the variation model chosen again with it in
the model, so that its row shows the numbers ``identify --effect`` gives (its
test stays the screening's, made where the person without it was fitted).

Candidates, by default (:func:`~smd_statespace.model.fitted.propose`): every registered effect
(a user's too); the floor as the measured floor when the record has a
``floor_acc`` column, else as an estimated floor mode (``floor_mode:source=modal``),
whose frequency is searched from the best of a fine grid of about 230 trials (the likelihood at every
other one and around the best of those: :func:`~smd_statespace.person.starts.grid_best`), which costs about a
second, and whose test counts them (Bonferroni).

Generic terms: besides those, every generic term of the library
(:data:`~smd_statespace.effects.generic.TERMS`: a spring stiffer on one side, one that hardens with amplitude,
damping that grows with speed or differs up and down, a stiffness or damping that drifts or steps) is
screened at the fitted person (:func:`~smd_statespace.person.screen.screen`): a score test (no fit) rules out
the terms the record does not pull away from zero, the others get a quick fit, and the :data:`SCREENED` whose
quick likelihood ratio is largest among those significant over the library (Holm, at ``alpha``) are fitted as
candidates like the others. The Bonferroni level counts every term screened, so the chance of a false alarm
does not grow with the library.

A candidate that passes the test is also validated on held-out data
(:func:`~smd_statespace.person.validation.cross_validated_loglike`): the
person with and without it fitted on each half of the record and scored on the
other half; one that predicts the held-out halves worse, or better by less than the spread of the cycles'
gains (:data:`~smd_statespace.person.verdict.CLEAR_GAIN`), is not proposed, whatever its likelihood ratio on the
whole record.

When two candidates both explain the residual (a cubic spring makes
harmonics of the bouncing frequency; so does an asymmetric stiffness), the
two best are fitted together and each is tested on top of the other: the
one that still adds likelihood is what separates them.
"""

from __future__ import annotations

import math
import shlex
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..effects import EFFECTS
from ..errors import OptionError, SMDInputError
from ..model.fitted import propose
from .effect_adapter import fitted_record, record_search_size
from ..effects.generic import SAME_AS, label
from .detection import unseen_change
from .extend import configured_for_record, fit_effects
from .in_time import in_time_words
from .report import unit_suffix
from .robust import MIN_SCALE, added_unknowns, robust_scale
from .screen import generic_library, screen
from .supremum import log_p_value, scan_trim
from .threads import one_blas_thread, record_cores, search_threads, thread_map
from .validation import MIN_HALF_CYCLES
from .verdict import (HEAVY_TAILS, HELD_OUT, LESS_WHITE, even_term_notes, held_out, held_out_checks, held_out_z,
                      less_white, needed_z, verdict, without_key)

__all__ = ["HEAVY_TAILS", "LESS_WHITE", "SCALE_NOTE", "SCREENED", "ZERO_Z", "held_out_z", "PersonDiagnosis",
           "diagnose_person", "candidate_row", "held_out", "verdict", "less_white", "HELD_OUT", "label",
           "indistinguishable_from_zero", "without_key", "fitted_terms"]

FREE_RUN_POINTS = 0.05
"""A held-out free run's fit lower by more than this many points with a candidate is told in a note."""

SCREENED = 2
"""How many generic terms (:mod:`~smd_statespace.person.screen`) whose quick fit is significant over the library
(Holm) are fitted as candidates, the largest likelihood ratio first."""

ZERO_Z = 2.0
"""A candidate whose added parameters and harmonics are all within this many sds of zero is not proposed."""

SCALE_NOTE = 1.5
"""A candidate whose likelihood ratio is scaled by more than this
(:func:`~smd_statespace.person.robust.robust_scale`) gets a note in words."""

def candidate_row(base, fitted, level: float) -> dict:
    """One candidate's row: the test, the person before and after, the effect's parameters, noise, whiteness."""
    test = fitted.effect_test()
    df, lr = test["lr_df"], test["lr"]
    added = fitted.effects[len(base.effects):]  # the candidate, on top of the effects already in the model
    # the ratio scaled by how much the likelihood overstates the evidence where the rest of the model is wrong
    # (robust.py: a quiet plate's misfit gave clean records a cubic spring at LR 52.6, scale 6.3)
    scale = robust_scale(fitted.model, fitted.params, added_unknowns(fitted, base))
    # a candidate with nothing to estimate (a measured floor) is not nested: it must beat chi-square(1);
    # one found as the best of many trials (a floor mode's frequency grid) is tested as that many (Bonferroni)
    trials = int(np.prod([record_search_size(effect, base) for effect in added]))
    log_p = min(log_p_value(lr / scale, df, added) + math.log(trials), 0.0)
    estimates = fitted.effect_estimates()
    before_tests, after_tests = base.test_pvalues(), fitted.test_pvalues()
    person_on_bound = fitted.model.person_at_bound(fitted.params)
    effect_on_bound = bool(estimates["on_bound"].any()) if len(estimates) else False
    row = {"effect": "+".join(label(e) for e in added),
           "physics": "; ".join(getattr(e, "physics", "") for e in added),
           "spec": " ".join(e.spec for e in fitted.effects), "df": df, "lr": lr, "lr_scale": scale,
           "lr_robust": lr / scale, "p_value": math.exp(log_p),
           "log_p": log_p, "trials": trials, "scan_trim": scan_trim(added), "f_h_before": base.f_h, "f_h": fitted.f_h,
           "xi_h_before": base.xi_h, "xi_h": fitted.xi_h, "noise_change_%": 100.0 * (fitted.sigma / base.sigma - 1.0),
           "ljung_box_p_before": before_tests["ljung_box_p"], "ljung_box_p": after_tests["ljung_box_p"],
           "ljung_box_q_before": before_tests["ljung_box_q"], "ljung_box_q": after_tests["ljung_box_q"],
           "parameters": _parameters_text(base, fitted, estimates),
           "likelihood": "exact" if fitted.model.exact else "approximate",
           "on_bound": person_on_bound or effect_on_bound, "settled": bool(fitted.settled)}
    # a refit that runs f_h, xi_h or the effect's parameter to a search bound has not found the effect:
    # the term and the person's resonance together imitate the residual
    # a nonlinear term whose path never settles follows the data, not the physics: its likelihood ratio is no
    # evidence (on clean records such a runaway gave a cubic spring LR 184, f_h 2.30 -> 1.40 Hz)
    # nor one whose added unknowns are all indistinguishable from zero (harmonics of 0.0004 +- 0.0003 g imitate
    # a misfit elsewhere), nor (unless the held-out halves say otherwise: verdict) one that leaves the innovations
    # less white than without it
    row["zero"] = indistinguishable_from_zero(base, fitted, estimates)
    row["less_white"] = less_white(before_tests, after_tests)
    row["passed"] = (bool(log_p < math.log(level)) and not row["on_bound"] and row["settled"] and lr > 0
                     and not row["zero"])
    row.update({key: math.nan for key in HELD_OUT}, held_out_worse=False, held_out_weak=False,
               held_out_unjudged=False)
    return verdict(row)


def indistinguishable_from_zero(base, fitted, estimates, z: float = ZERO_Z) -> bool:
    """True when every parameter the candidate estimates, and every harmonic it adds, is within ``z`` sds of 0."""
    values = [(row["value"], row["sd"]) for _, row in estimates.iterrows()]
    values += [(blf["blf"], blf["sd"]) for _, blf in _added_harmonics(base, fitted).iterrows()]
    return bool(values) and all(np.isfinite(sd) and abs(value) < z * sd for value, sd in values)


def _parameters_text(base, fitted, estimates) -> str:
    """The effect's estimates in words: its parameters, the load factors of added harmonics, or 'known input'."""
    def text(name, r):  # a parameter held at its search bound has no sd: said so, not "± nan"
        if r["on_bound"] and not np.isfinite(r["sd"]):
            return f"{name} {r['value']:.4g}{unit_suffix(r['unit'])} (on its search bound)"
        return f"{name} {r['value']:.4g} ± {r['sd']:.2g} {r['unit']}".rstrip()

    parts = [text(name, r) for name, r in estimates.iterrows()]
    parts += [f"BLF{i} {blf['blf']:.3g} ± {blf['sd']:.2g} g" for i, blf in _added_harmonics(base, fitted).iterrows()]
    return "; ".join(parts) or "none (a known input)"


def fitted_terms(screened: pd.DataFrame, alpha: float) -> list:
    """The specs of the screened generic terms fitted as candidates: those whose quick likelihood ratio is significant
    over the library (``p_quick_holm`` below ``alpha``), at most :data:`SCREENED`, in the table's order (largest
    first); none where no quick fit was made."""
    if "p_quick_holm" not in screened:
        return []
    return list(screened.index[screened["p_quick_holm"] < alpha][:SCREENED])


def _added_harmonics(base, fitted) -> pd.DataFrame:
    """The rows of ``fitted``'s load factors (:meth:`~smd_statespace.person.results.PersonResult.template_blf`) of
    the harmonics it adds to ``base``. A candidate that adds none does not read them: they cost a concentrated
    template per parameter, and one per point of a grid across the person's interval where it is not determined."""
    if fitted.model.n_harmonics <= base.model.n_harmonics:
        return pd.DataFrame(columns=["blf", "sd"])
    return fitted.template_blf().loc[base.model.n_harmonics + 1:]


@dataclass
class PersonDiagnosis:
    """The candidates' fits, table and verdict of :func:`diagnose_person`.

    Attributes
    ----------
    base : PersonResult
        The fit without any effect.
    fits : dict
        Candidate name -> its :class:`~smd_statespace.person.results.PersonResult` (with the effect).
    rows : list of dict
        One per candidate (:func:`candidate_row`), with ``seconds``: the wall time of its fit.
    failed : dict
        Candidate name -> why its fit failed, in words.
    alpha : float
        Family-wise significance level (Bonferroni over the candidates).
    joint : dict
        When two candidates were significant: ``effects`` (the two names), ``loglike`` of the joint
        fit and, per name, ``lr`` and ``p_value`` of that effect on top of the other.
    screened : pandas.DataFrame
        The generic terms' score tests (:func:`~smd_statespace.person.screen.screen`), with ``fitted`` (the
        terms fitted as candidates: :func:`fitted_terms`); empty when candidates were given.
    tests : int
        How many tests the Bonferroni level counts: the candidates fitted and every generic term screened.
    scans : dict
        Per kind of step (``"f_step"``, ``"xi_step"``) whose time a scan found
        (:func:`~smd_statespace.person.breaks.located_step`): the scan's ``table`` (score statistics at every
        time tested), ``time_s`` (where the step was placed), ``lm_robust`` and ``p`` (the largest robust
        statistic, as the largest of many), ``trim``. Empty when the library was not screened.
    validation : dict
        Held-out validation (:func:`~smd_statespace.person.validation.cross_validated_loglike`) of the person
        without any candidate (``"without"``) and with each candidate that passed its test (by name); for a
        candidate with a change in time (a step) the person without it on that candidate's cut too
        (:func:`without_key`). :meth:`held_out_pair` gives the two to compare.
    """

    base: object
    fits: dict
    rows: list
    failed: dict
    alpha: float
    joint: dict = field(default_factory=dict)
    screened: pd.DataFrame = field(default_factory=pd.DataFrame)
    tests: int = 0
    validation: dict = field(default_factory=dict)
    scans: dict = field(default_factory=dict)

    def table(self) -> pd.DataFrame:
        """The candidates: those that pass first, by their held-out log-likelihood gain per held-out sample (by
        their tests' p-values where they were judged on different folds: a change in time on its own), the joint
        fit's choice first when it separated two; then the others by the log p-value of their likelihood ratio."""
        if not self.rows:
            return pd.DataFrame()
        table = pd.DataFrame(self.rows).set_index("effect")
        # the significant ones by how well they predict the held-out halves, per held-out sample, the others by
        # their test. A change in time is judged on folds fitted across it (validation.break_folds), the others on
        # the halves: gains on different data do not compare, so where the significant ones were judged on different
        # folds they are ranked by their tests too, whose p-values count their searches (a step's scan, a floor's
        # grid). On jumps records whose f_h drifts, a step placed by the scan gained +20.9 on 1437 held-out samples
        # where the drift gained +18.4 on 3001, though the drift's test was the stronger (p 9e-11 against 1e-7) and
        # the joint fit kept the drift on top of the step (p 0.008) but not the step on top of the drift (p 0.57)
        gain = np.where(table["significant"], (table["held_out"] - table["held_out_before"])
                        / table["held_out_samples"], np.nan)
        folds = {tuple((fold["start"], fold["end"]) for fold in (self.validation.get(name) or {}).get("folds", ()))
                 for name in table.index[table["significant"]]}
        if len(folds) > 1:
            gain = np.where(table["significant"], 0.0, np.nan)
        table = table.assign(_gain=np.nan_to_num(gain, nan=-np.inf))
        order = list(table.sort_values(["significant", "_gain", "log_p"], ascending=[False, False, True]).index)
        table = table.drop(columns="_gain")
        if self.joint.get("first") in order:  # the joint fit decided between the two best
            order.remove(self.joint["first"])
            order.insert(0, self.joint["first"])
        return table.loc[order]

    @property
    def level(self) -> float:
        """The level each candidate is tested at: ``alpha`` over :attr:`tests` (Bonferroni)."""
        return self.alpha / max(self.tests or len(self.rows) + len(self.failed), 1)

    @property
    def missing(self) -> list:
        """Names of the significant candidates, best first."""
        table = self.table()
        return [] if table.empty else list(table.index[table["significant"]])

    @property
    def adequate(self) -> bool:
        """True when no candidate is a significant improvement."""
        return not self.missing

    def verdict(self) -> str:
        """The verdict in one line, as ``diagnose`` prints it after ``verdict:``: the level it was tested at when
        nothing is missing, else the best candidate with its physics, its (scaled) likelihood ratio and p-value,
        and the person before and after it."""
        if self.adequate:
            tests = self.tests or len(self.rows) + len(self.failed)
            return (f"no candidate effect is a significant improvement at alpha {self.alpha:g} (Bonferroni over "
                    f"{tests}: each at {self.level:.2g})")
        name = self.missing[0]
        best = self.table().loc[name]
        physics = f" = {best['physics']}" if best.get("physics") else ""
        scaled = f" / {best['lr_scale']:.2g}" if best["lr_scale"] > 1 else ""
        in_time = [line.strip() for line in in_time_words(self.fits[name])] if name in self.fits else []
        return (f"missing effect '{name}'{physics} (LR {best['lr']:.1f}{scaled} on {int(best['df'])} parameter(s), "
                f"p {best['p_value']:.2g}); with it f_h {best['f_h_before']:.3f} -> {best['f_h']:.3f} Hz, xi_h "
                f"{best['xi_h_before']:.3f} -> {best['xi_h']:.3f}, {best['parameters']}"
                + "".join(f"; {line}" for line in in_time))

    def held_out_pair(self, name: str) -> tuple | None:
        """``(without, with)``: the held-out validation of the person without and with candidate ``name``, on the
        same cut of the record; None when it was not judged on held-out data."""
        key = without_key(name) if without_key(name) in self.validation else "without"
        pair = (self.validation.get(key), self.validation.get(name))
        return None if None in pair else pair

    def command(self, record: str, mass, extra: str = "", options: str = "") -> str:
        """The ``identify`` command that adds the best candidate (runs as printed); empty when adequate.

        ``mass`` may be None for an accelerometer's record identified without one; ``extra``: the command line's
        options before ``identify``, ``options``: the person's options after the record (``--fade off``), so that
        the command fits the person diagnosed.
        """
        if self.adequate:
            return ""
        spec = self.table().loc[self.missing[0], "spec"]
        effects = " ".join(f"--effect {shlex.quote(part)}" for part in spec.split(" "))
        return f"smd-statespace {extra}identify {self.base.record_arguments(record, mass)} {options}{effects}"

    def notes(self) -> list:
        """Plain-word notes: heavy-tailed innovations, refits on a bound, failures, what the joint fit of two
        candidates separated."""
        out = []
        kurtosis = self.base.test_pvalues()["kurtosis"] if self.base is not None else math.nan
        table = self.table()
        if kurtosis > HEAVY_TAILS and not self.adequate:
            out.append(f"the person's innovations are heavy-tailed (kurtosis {kurtosis:.1f}; a Gaussian's is 3): the "
                       "likelihood ratios assume Gaussian innovations and may overstate the evidence (on clean "
                       "lab exports of a quiet plate they proposed effects that were not there), so weigh the "
                       "held-out gains more than the ratios")
        if not table.empty and float(table["lr_scale"].max()) > SCALE_NOTE:
            worst = table["lr_scale"].idxmax()
            out.append(f"the person misses something that none of the candidates describes (a quiet record shows "
                       f"how the force varies from cycle to cycle): the likelihood overstates the evidence for a "
                       f"candidate by up to {table.loc[worst, 'lr_scale']:.2g} times ({worst}), so each ratio is "
                       "divided by its own factor (lr_scale: the scores' spread between cycles over the likelihood's "
                       "information) before it is tested")
        if not table.empty:
            for name in table.index[table["on_bound"].astype(bool)]:
                out.append(f"{name}: its fit put f_h, xi_h or the effect's parameter on a search bound (f_h "
                           f"{table.loc[name, 'f_h']:.3g} Hz, xi_h {table.loc[name, 'xi_h']:.3g}; "
                           f"{table.loc[name, 'parameters']}): the term and the person's resonance together "
                           "imitate the residual, so it is not proposed")
            for name in table.index[table["zero"].astype(bool)]:
                out.append(f"{name}: what it adds is indistinguishable from zero ({table.loc[name, 'parameters']}, "
                           f"each within {ZERO_Z:g} sd): a likelihood ratio of {table.loc[name, 'lr']:.1f} from "
                           "terms of no size is something else imitated, so it is not proposed")
            for name in table.index[table["less_white"].astype(bool) & ~table["zero"].astype(bool)]:
                row = table.loc[name]
                whiteness = (f"with it the innovations are less white (Ljung-Box Q {row['ljung_box_q_before']:.1f} -> "
                             f"{row['ljung_box_q']:.1f}, more than {LESS_WHITE:g} sd of its own; p "
                             f"{row['ljung_box_p_before']:.2g} -> {row['ljung_box_p']:.2g})")
                if np.isfinite(row["held_out"]):  # judged on held-out data, which decides (verdict)
                    out.append(f"{name}: {whiteness}, but the held-out halves judge it (log-likelihood "
                               f"{row['held_out_before']:.1f} -> {row['held_out']:.1f}): where the model misses this "
                               "much elsewhere the whiteness of its innovations does not decide")
                elif row["passed"]:
                    out.append(f"{name}: {whiteness}: it does not take what the model misses, and no held-out data "
                               "judged it, so it is not proposed")
            for name in table.index[table["held_out_worse"].astype(bool)]:
                out.append(f"{name}: fitted on each half of the record, it predicts the other half worse than the "
                           f"person without it (held-out log-likelihood {table.loc[name, 'held_out_before']:.1f} -> "
                           f"{table.loc[name, 'held_out']:.1f}): it fits this record, not the person, so it is not "
                           "proposed")
            heavy = kurtosis > HEAVY_TAILS  # what held_out_checks asked (a change in time is weak only there)
            asked = f"under {needed_z(self.level, heavy):.2f}, " + (
                "its test's level, asked where the innovations are heavy-tailed" if heavy
                else "the spread of the cycles' gains")
            for name in table.index[table["held_out_weak"].astype(bool)]:
                row = table.loc[name]
                out.append(f"{name}: fitted on each half of the record, it predicts the other half better than the "
                           f"person without it by only {row['held_out'] - row['held_out_before']:+.1f} in "
                           f"log-likelihood, {row['held_out_z']:.1f} sd of that gain's noise from cycle to cycle "
                           f"({asked}): the held-out halves do not show it, so it is not proposed")
            for name in table.index[table.get("held_out_unjudged", pd.Series(False, table.index)).eq(True)]:
                why = ("no cut of the record leaves the change a sixth of the record away with "
                       f"{MIN_HALF_CYCLES} cycles held out" if without_key(name) in self.validation else
                       f"the record is too short to halve into two parts of {MIN_HALF_CYCLES} cycles")
                out.append(f"{name}: it passes its test (LR {table.loc[name, 'lr']:.1f}), but it could not be judged "
                           f"on held-out data ({why}, or a part's fit did not converge): a term the record cannot "
                           "check on data it was not fitted to is not proposed")
            for name in table.index[~table["settled"].astype(bool)]:
                out.append(f"{name}: its linearised path had not settled after the last linearisation (the "
                           f"approximate likelihood kept rising, LR {table.loc[name, 'lr']:.1f}, as the path "
                           "followed the data): not evidence, so it is not proposed")
            out += even_term_notes(self.missing)
            approximate = list(table.index[table["likelihood"] == "approximate"])
            if approximate:
                out.append(f"{', '.join(approximate)}: nonlinear, so its likelihood is approximate (linearised about "
                           "the one-step predicted path until it settles: an extended Kalman filter)")
        out += self._held_out_notes(table)
        for name, why in self.failed.items():
            out.append(f"{name}: not fitted ({why})")
        out += self._change_notes()
        if self.joint:
            first, second = self.joint["effects"]
            out.append(f"{first} and {second} both explain the residual; fitted together, {first} adds "
                       f"{_ratio_text(self.joint[first])} on top of {second}, and {second} adds "
                       f"{_ratio_text(self.joint[second])} on top of {first}: {self.joint['verdict']}")
        return out

    def _change_notes(self) -> list:
        """Where nothing is missing, what identify's score tests of a change in time said of the person: the change
        they would have found (none found), or that its warning of a person who changes stands (one found)."""
        if self.base is None or not self.adequate:
            return []
        unseen = unseen_change(self.base)
        if unseen:  # nothing found: what a change of the person in time would have had to be to show
            return [f"no change of the person in time found by identify's score tests: {unseen}"]
        changed = (self.base.change or {}).get("changed", [])
        if changed:  # identify warned of a change that no candidate here could take: its warning is not withdrawn
            return [f"identify found that the person changes during the record ({', '.join(changed)} not "
                    "determined), and no term of a change in time passed the checks above: that warning stands; "
                    "read the halves it gives, or identify parts of the record with --span START:END"]
        return []

    def _held_out_notes(self, table) -> list:
        """Notes on the held-out validation: the person with each candidate that passed, a worse free run, and a
        change in time judged on the folds fitted across it."""
        if table.empty:
            return []
        out = []
        for name in table.index[table["significant"].astype(bool) | table["held_out_worse"].astype(bool)]:
            if without_key(name) not in self.validation:  # not a change in time
                continue
            checked = self.validation.get(name)
            if checked is not None:  # one that could not be judged is said so (and not proposed) above
                fitted = " and ".join(f"{fold['start']:.1f}-{fold['end']:.1f} s" for fold in checked["folds"])
                out.append(f"{name}: a fit that has not seen a change in time cannot predict it, so it is judged "
                           f"on {'one fold' if len(checked['folds']) == 1 else 'two folds'} that hold the change: "
                           f"the person fitted on {fitted}, each predicting the rest of the record")
        significant = table[table["significant"].astype(bool)]
        if len(significant) >= 2:
            out.append("candidates that pass, by how well they predict the held-out halves (held-out "
                       "log-likelihood gain per held-out sample; f_h, xi_h with each): " + "; ".join(
                           f"{name} {row['held_out'] - row['held_out_before']:+.1f} on {row['held_out_samples']:.0f} "
                           f"samples (f_h {row['f_h']:.3f} Hz, xi_h {row['xi_h']:.3f})"
                           for name, row in significant.iterrows()))
        for name, row in significant.iterrows():
            if row["held_out_free_run_fit"] < row["held_out_free_run_fit_before"] - FREE_RUN_POINTS:
                out.append(f"{name}: it predicts the held-out halves one step ahead better, but their free run "
                           f"(the template in every cycle) fits {row['held_out_free_run_fit_before']:.1f} -> "
                           f"{row['held_out_free_run_fit']:.1f} %: what it adds varies from cycle to cycle (a "
                           "harmonic's phase), which a free run cannot follow")
        return out

    def report(self) -> dict:
        """JSON-able report: base person, candidates, verdict, notes."""
        table = self.table()
        screened = self.screened.reset_index().to_dict(orient="records") if len(self.screened) else []
        return {"base": self.base.to_dict(), "candidates": table.reset_index().to_dict(orient="records"),
                "missing": self.missing, "adequate": self.adequate, "verdict": self.verdict(), "alpha": self.alpha,
                "notes": self.notes(),
                "joint": self.joint, "screened": screened, "tests": self.tests,
                "step_scans": {kind: {key: value for key, value in scan.items() if key != "table"}
                               for kind, scan in self.scans.items()}}


def _ratio_text(test: dict) -> str:
    """``LR 52.6 / 6.3 (p 0.004)``: a likelihood ratio, its misspecification scale where above 1, its p-value."""
    scale = test.get("lr_scale", MIN_SCALE)
    scaled = f" / {scale:.2g}" if scale > MIN_SCALE else ""
    return f"LR {test['lr']:.1f}{scaled} (p {test['p_value']:.2g})"


def _joint(base, fits: dict, names: list, level: float) -> dict:
    """Fit the two best candidates together and test each on top of the other."""
    first, second = names[:2]
    present = len(base.effects)
    both = fit_effects(base, list(fits[first].effects[present:]) + list(fits[second].effects[present:]),
                       timing=False, start=[fits[first], fits[second]])  # from the two fits: it nests both
    out = {"effects": [first, second], "loglike": both.loglike}
    for name, other in ((first, second), (second, first)):
        lr = 2.0 * (both.loglike - fits[other].loglike)
        df = max(both.added_unknowns(fits[other]), 1)
        trials = int(np.prod([record_search_size(e, base) for e in fits[name].effects[present:]]))
        scale = robust_scale(both.model, both.params, added_unknowns(fits[name], base))
        out[name] = {"lr": float(lr), "lr_scale": scale,
                     "p_value": min(math.exp(log_p_value(lr / scale, df, fits[name].effects[present:])) * trials,
                                    1.0)}
    keeps = [name for name in (first, second) if out[name]["p_value"] < level]
    if len(keeps) == 1:
        out["first"] = keeps[0]
        out["verdict"] = f"only {keeps[0]} still adds to the other, so it is ranked first"
    elif keeps:
        out["verdict"] = ("each adds to the other: both may be present (identify with both); the one that predicts "
                          "the held-out halves better is ranked first")
    else:
        out["verdict"] = ("neither adds to the other: the likelihood cannot tell them apart, so the one that "
                          "predicts the held-out halves better is ranked first")
    return out


@one_blas_thread
@record_cores
def diagnose_person(result, candidates=None, alpha=0.01, progress=False, library=None,
                    threads=None) -> PersonDiagnosis:
    """Identify the person with each candidate effect and test it by likelihood ratio.

    Parameters
    ----------
    result : PersonResult
        The fit to diagnose (:func:`~smd_statespace.person.fit.identify_person`), with or without effects:
        each candidate is added on top of those it has.
    candidates : sequence of str or Effect, optional
        Effects to try (names, ``NAME:key=value`` specs or objects), none of them in ``result`` already;
        a bare name as its class configures itself for this record (as by default).
        Default: every registered effect not in ``result`` as its class configures itself for this
        record (:func:`~smd_statespace.model.fitted.propose`).
    alpha : float
        Family-wise significance level; each candidate is tested at
        ``alpha / len(candidates)``.
    progress : bool
        A progress bar over the candidates.
    library : bool, optional
        Also screen the generic terms by score tests and fit the :data:`SCREENED` most significant
        (default: when ``candidates`` is None; given candidates are what the user asked for).
    threads : int, optional
        Threads for the candidates' fits and their held-out folds, which do not depend on each other
        (:func:`~smd_statespace.person.threads.search_threads`: default two): the same diagnosis, sooner.

    Returns
    -------
    PersonDiagnosis
    """
    present, threads = {label(effect) for effect in result.effects}, search_threads(threads)
    screened, failed, ends = pd.DataFrame(), {}, {}  # ends: the screened terms' quick fits, where their fits go on
    if candidates is None:
        fitted = fitted_record(result)
        effects = [effect for name, cls in EFFECTS.items() if name not in present
                   for effect in [propose(cls, fitted)] if effect is not None]
    else:
        effects = [configured_for_record(candidate, result) for candidate in candidates]
        names = [label(effect) for effect in effects]
        twice = sorted({name for name in names if names.count(name) > 1})
        if twice:
            raise OptionError(f"candidate {twice[0]!r} is given twice; each candidate is tried once (a name, or "
                              "one spec of it)")
        already = [name for name in names if name in present]
        if already:
            raise OptionError(f"candidate {already[0]!r} is in the model already; candidates are effects to try on "
                              f"top of it ({', '.join(sorted(present))})")
    tests = len(effects)
    library_screened = candidates is None if library is None else library
    if library_screened:
        taken = present | {label(effect) for effect in effects}
        # a candidate in another unit is screened once
        terms = [term for term in generic_library(result, scan=True, threads=threads)
                 if label(term) not in taken and SAME_AS.get(term.kind) not in taken]
        tests += len(terms)  # Bonferroni counts every term screened, fitted or not
        try:
            screened = screen(result, terms, alpha=alpha, threads=threads, ends=ends)
        except (SMDInputError, ArithmeticError, np.linalg.LinAlgError) as exc:
            failed["generic terms (score tests)"] = " ".join(str(exc).split())
        else:
            flagged = set(fitted_terms(screened, alpha))
            screened = screened.assign(fitted=screened.index.isin(flagged))  # what the figure colours as fitted
            effects += [effect for effect in terms if effect.spec in flagged]
    level = alpha / max(tests, 1)
    fits, rows = _fit_candidates(result, effects, level, failed, threads, progress, ends)
    validation = held_out_checks(result, fits, rows, level, threads)
    scans = {term.kind: term.scan for term in terms if term.scan} if library_screened else {}
    diagnosis = PersonDiagnosis(base=result, fits=fits, rows=rows, failed=failed, alpha=alpha, screened=screened,
                                tests=tests, validation=validation, scans=scans)
    significant = diagnosis.missing
    if len(significant) >= 2:
        try:
            diagnosis.joint = _joint(result, fits, significant, level)
        except (SMDInputError, ArithmeticError, np.linalg.LinAlgError) as exc:
            failed[" + ".join(significant[:2])] = " ".join(str(exc).split())
    if diagnosis.missing:  # the proposed effect as identify --effect gives it: the cycle starts re-placed with it
        name = diagnosis.missing[0]  # (after the joint test, which compares the screened fits)
        started = time.perf_counter()
        try:
            # a nonlinear candidate from its screened fit, not its trial starts again, each about its own path (1-2 s
            # for a cubic spring); a linear one's search is cheap and identical to identify --effect's to the last digit
            start = fits[name] if fits[name].model.approximate else None
            fitted = fit_effects(result, fits[name].effects[len(result.effects):], threads=threads, start=start)
        except (SMDInputError, ArithmeticError, np.linalg.LinAlgError) as exc:
            failed[name] = " ".join(str(exc).split())
        else:
            index = next(i for i, row in enumerate(rows) if row["effect"] == name)
            fits[name] = fitted
            screened = {key: rows[index][key] for key in HELD_OUT + ("held_out_worse", "held_out_weak",
                                                                      "held_out_unjudged")}
            rows[index] = verdict({**candidate_row(result, fitted, level), **screened,
                                   "seconds": rows[index]["seconds"] + time.perf_counter() - started})
    return diagnosis


def _fit_candidates(result, effects, level: float, failed: dict, threads: int, progress: bool, ends: dict) -> tuple:
    """Every candidate fitted with the person (one search each, at ``result``'s starts; in threads; a screened term on
    from its quick fit, ``ends``) and its row: ``(fits by name, rows)``; a failed fit is said in ``failed``."""
    from ..progress import tqdm

    fits, rows = {}, []
    with tqdm(total=len(effects), desc="diagnose (record)", unit="effect", disable=not progress, leave=False) as bar:
        def fit_candidate(effect):
            started = time.perf_counter()
            try:
                return (fit_effects(result, [effect], timing=False, start=ends.get(effect.spec)),
                        time.perf_counter() - started)
            except (SMDInputError, ArithmeticError, np.linalg.LinAlgError) as exc:
                return exc, None
            finally:
                bar.update()

        for effect, (fitted, seconds) in zip(effects, thread_map(fit_candidate, effects, threads)):
            if seconds is None:
                failed[label(effect)] = " ".join(str(fitted).split())
                continue
            fits[label(effect)] = fitted
            rows.append({**candidate_row(result, fitted, level), "seconds": seconds})
    return fits, rows


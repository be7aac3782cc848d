"""The record-level model: exact discretisation, exact likelihood, recovery of a known person, the CLI's answer."""

import inspect
import json
import re

import numpy as np
import pandas as pd
import pytest
from scipy import linalg

from smd_statespace.cli import main
from smd_statespace.errors import CycleError, SMDInputError
from smd_statespace.io import G, make_record
from smd_statespace.person import CycleTiming, RecordModel, Regressor, estimate_timing, identify_person
from smd_statespace.person.search import fit_model, information
from smd_statespace.person.system import expm2
from smd_statespace.person.results import PersonResult
from smd_statespace.person.statespace import RecordStateSpace
from smd_statespace.signals import find_cycles
from smd_statespace.simulation import simulate_bouncing

from helpers import lab_export


def true_timing(sim):
    cycles = sim.cycles
    return CycleTiming(np.append(cycles.t_start.values, cycles.t_end.values[-1]), "truth")


def acceleration(sim):
    return sim.record.force / sim.record.mass - G


@pytest.mark.parametrize("xi_h", [1e-3, 0.3, 1.0, 1.7])
def test_closed_form_exponential_equals_scipy(xi_h):
    w = 2 * np.pi * 2.5
    a = np.array([[0.0, 1.0], [-w**2, -2 * xi_h * w]])
    assert np.allclose(expm2(a, 0.01), linalg.expm(a * 0.01), rtol=1e-12, atol=1e-15)


def test_step_is_the_exact_solution_of_eq2_under_a_harmonic_force():
    """One step of [u, u'] under cos/sin of the phase equals the matrix exponential of the augmented system."""
    t = np.arange(0.0, 1.0, 0.01)
    timing = CycleTiming(np.array([-0.1, 0.45, 1.2]))
    model = RecordModel(t, np.zeros_like(t), timing, n_harmonics=2)
    params = model.start_params(2.7, 0.2)
    sys = model.system(params)
    _, theta, rate, _ = model._phase
    w = 2 * np.pi * params[0]
    for k in (3, 30, 77):
        for order in (1, 2):
            nu = order * rate[k]
            # [u, u', c, s]: c = cos(order theta), s = sin(order theta) rotate at nu; c drives a_i, s drives b_i
            a = np.zeros((4, 4))
            a[0, 1] = 1.0
            a[1, :2] = [-w**2, -2 * params[1] * w]
            a[2, 3], a[3, 2] = -nu, nu
            x0 = np.array([0.0, 0.0, np.cos(order * theta[k]), np.sin(order * theta[k])])
            for column, drive in ((2 * order - 1, 2), (2 * order, 3)):
                a[1, 2:] = 0.0
                a[1, drive] = 1.0
                exact = linalg.expm(a * 0.01) @ x0
                assert np.allclose(sys.Gam[k, :, column] / G, exact[:2], rtol=1e-9, atol=1e-15)
    # the constant a0: A^-1 (Phi - I) B
    a2 = np.array([[0.0, 1.0], [-w**2, -2 * params[1] * w]])
    big = np.zeros((3, 3))
    big[:2, :2], big[1, 2] = a2, 1.0
    assert np.allclose(sys.Gam[5, :, 0] / G, (linalg.expm(big * 0.01) @ [0, 0, 1.0])[:2], rtol=1e-9)


@pytest.mark.parametrize("options", [
    {},
    {"variation": "random_walk"},
    {"variation": "both", "drift": True},
    {"process_noise": True},
    {"phase_template": np.array([0.0, -0.2, 0.1, 0.1, 0.05, 0.03, 0.0, 0.01, 0.0])},
    {"variation": "smooth"},
    {"variation": "smooth", "drift": True,
     "phase_template": np.array([0.0, -0.2, 0.1, 0.1, 0.05, 0.03, 0.0, 0.01, 0.0])},
    {"variation": "smooth", "observed": "gaps"},
    {"observed": "gaps", "phase_template": np.array([0.0, -0.2, 0.1, 0.1, 0.05, 0.03, 0.0, 0.01, 0.0])},
])
def test_compiled_likelihood_equals_statsmodels_kalman_filter(short_sim, options):
    """The concentrated likelihood of the compiled pass is statsmodels' exact Kalman likelihood at the same point;
    with samples missing (a phone's gaps), statsmodels' with those samples NaN (its own missing-data filter)."""
    sim = short_sim
    y = acceleration(sim)
    if options.get("observed") == "gaps":
        observed = np.ones(y.size, dtype=bool)
        observed[100:130] = observed[300:303] = False
        options = dict(options, observed=observed)
        y = np.where(observed, y, 1e3)  # whatever a gap holds is not used
    regressors = (Regressor("offset", np.ones_like(y), dynamic=False), Regressor("ramp", sim.record.time / 10.0))
    model = RecordModel(sim.record.time, y, estimate_timing(sim.record.time, sim.record.force), regressors=regressors,
                        **options)
    params = model.start_params(2.3, 0.25, -2.0)
    if "phase_template" in options:
        params[-2:] = -3.0, 0.0  # phase (rad^2) and rate ((rad/s)^2) variance ratios
    out = model.filter(params)
    reference = RecordStateSpace(model, out["delta"]).loglike(params)
    assert out["loglike"] == pytest.approx(reference, rel=1e-9)  # rounding of the GLS solve: ~1e-10
    # moving delta away from its GLS value lowers statsmodels' likelihood: the concentration really maximises
    shifted = out["delta"].copy()
    shifted[2] += 0.01
    assert RecordStateSpace(model, shifted).loglike(params) < reference


@pytest.mark.parametrize("variation", ["independent", "smooth"])
def test_the_nominal_path_is_statsmodels_predicted_state(short_sim, variation):
    """``nominal_path`` (the path an effect is linearised about), kept without the filter's covariances, is the
    one-step predicted dynamic state of statsmodels' filter at the same point."""
    from smd_statespace.person.statespace import nominal_path

    y = acceleration(short_sim)
    model = RecordModel(short_sim.record.time, y, estimate_timing(short_sim.record.time, short_sim.record.force),
                        variation=variation, regressors=(Regressor("offset", np.ones_like(y), dynamic=False),))
    params = model.start_params(2.3, 0.25, -2.0)
    view = RecordStateSpace(model, model.filter(params)["delta"])
    full = view.filter(params, cov_type="none")
    path = nominal_path(model, params)
    assert path.shape == (y.size, model.n_dynamic)
    np.testing.assert_allclose(path, full.predicted_state[:model.n_dynamic, :-1].T, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("gaps", [False, True])
def test_residual_tests_are_statsmodels_own_at_the_estimate(short_sim, gaps):
    """The person's Ljung-Box, Jarque-Bera and breakvar tests, taken on the compiled pass's innovations, are the tests
    of statsmodels' results object at the same point (its own filter; with a phone's gaps, its missing samples)."""
    from smd_statespace.person.checks import RecordChecks

    y = acceleration(short_sim)
    observed = np.ones(y.size, dtype=bool)
    if gaps:
        observed[100:130] = observed[300:303] = False
    model = RecordModel(short_sim.record.time, np.where(observed, y, 1e3),
                        estimate_timing(short_sim.record.time, short_sim.record.force),
                        regressors=(Regressor("offset", np.ones_like(y), dynamic=False),), observed=observed)
    checked = RecordChecks()
    checked.record, checked.model, checked.params = short_sim.record, model, model.start_params(2.3, 0.25, -2.0)
    checked.filtered = model.filter(checked.params)
    theirs = checked.statespace_results
    assert np.all(checked.standardized_innovations()[~observed] == 0.0)  # a gap's innovation, in both
    lags = checked.default_lags()
    ours = checked.test_serial_correlation()
    assert ours.shape == (1, 2, lags)
    np.testing.assert_allclose(ours, theirs.test_serial_correlation("ljungbox", lags=lags), rtol=1e-7)
    np.testing.assert_allclose(checked.test_normality(), theirs.test_normality("jarquebera"), rtol=1e-7)
    np.testing.assert_allclose(checked.test_heteroskedasticity(), theirs.test_heteroskedasticity("breakvar"),
                               rtol=1e-7)


@pytest.mark.parametrize("variation, gaps", [("independent", False), ("random_walk", False), ("both", False),
                                             ("smooth", False), ("independent", True), ("smooth", True)])
def test_state_only_smoother_gives_statsmodels_smoothed_states(short_sim, variation, gaps):
    """``RecordStateSpace.smoothed_state`` (the compiled smoother of ``person/smoother.py``, which the re-placement
    of the cycle starts uses) is statsmodels' full smoother's state mean, with the phase template's timing states
    too and with a phone's missing samples, and leaves the model as it found it."""
    sim = short_sim
    y = acceleration(sim)
    observed = np.ones(y.size, dtype=bool)
    if gaps:
        observed[100:130] = observed[300:303] = False
    template = np.array([0.0, -0.2, 0.1, 0.1, 0.05, 0.03, 0.0, 0.01, 0.0])
    model = RecordModel(sim.record.time, np.where(observed, y, 1e3), estimate_timing(sim.record.time, sim.record.force),
                        variation=variation, regressors=(Regressor("offset", np.ones_like(y), dynamic=False),),
                        phase_template=template, observed=observed)
    params = model.start_params(2.3, 0.25, -2.0)
    params[-2:] = -3.0, 0.0
    ssm = RecordStateSpace(model, model.filter(params)["delta"])
    full = ssm.smooth(params, cov_type="none").smoothed_state
    state = ssm.smoothed_state(params)
    assert state.shape == full.shape and np.allclose(state, full, rtol=1e-10, atol=1e-12 * np.abs(full).max())
    assert ssm.ssm.filter_concentrated and ssm.loglike(params) == pytest.approx(model.loglike(params), rel=1e-9)


def test_maximum_likelihood_recovers_the_person_with_true_cycle_starts(long_sim):
    """With the true force-cycle boundaries, f_h and xi_h come back within their intervals and a few percent."""
    sim = long_sim
    y = acceleration(sim)
    model = RecordModel(sim.record.time, y, true_timing(sim), regressors=(Regressor("offset", np.ones_like(y), dynamic=False),))
    fitted = fit_model(model)
    assert fitted["converged"]
    f_h, xi_h = fitted["params"][:2]
    assert f_h == pytest.approx(2.8, rel=0.03)
    assert xi_h == pytest.approx(0.25, abs=0.03)
    # the noise level is estimated, not assumed: about 0.2 % of body weight
    sigma = np.sqrt(model.filter(fitted["params"])["sigma2"])
    assert sigma / G == pytest.approx(0.002, rel=0.25)


def test_smoother_recovers_every_cycles_load_factors(long_sim):
    """At the true person, the per-cycle BLFs from statsmodels' smoother follow the simulator's per-cycle truth."""
    sim = long_sim
    y = acceleration(sim)
    model = RecordModel(sim.record.time, y, true_timing(sim), regressors=(Regressor("offset", np.ones_like(y), dynamic=False),))
    fitted = fit_model(model)
    params = fitted["params"].copy()
    params[:2] = 2.8, 0.25  # the true person: BLF1 inherits any error of f_h (docs/benchmarks.md)
    cov, free = information(model, params)
    result = PersonResult(sim.record, model, params, cov, free, model.loglike(params), {}, "wald", 0.9, [])
    cycles = result.cycles[result.cycles.whole]
    truth = sim.cycles.set_index("cycle")
    # match each estimated cycle to the true cycle with the nearest middle
    mid_true = 0.5 * (truth.t_start + truth.t_end).values
    mid = 0.5 * (cycles.t_start + cycles.t_end).values
    nearest = np.abs(mid[:, None] - mid_true[None, :]).argmin(axis=1)
    for i in (1, 2):
        estimated = cycles[f"blf_{i}"].values
        true = truth[f"blf{i}"].values[nearest]
        assert np.corrcoef(estimated, true)[0, 1] > 0.8
        assert np.median(np.abs(estimated - true)) < 0.05 * np.mean(true)


@pytest.mark.parametrize("variation, f_h_over_f_b, xi_h, determined", [
    ("smooth", 1.02, 0.25, False), ("smooth", 1.3, 0.25, True), ("independent", 1.02, 0.25, True),
    ("independent", 1.02, 0.01, False), ("independent", 1.3, 0.01, True), ("independent", 1.96, 0.02, False),
    ("independent", 1.96, 0.25, True)])
def test_a_fit_at_the_bouncing_frequency_that_mimics_the_force_does_not_determine_f_h(long_sim, variation,
                                                                                      f_h_over_f_b, xi_h, determined):
    """A resonance at f_b imitates a smoothly drifting first harmonic, and an undamped one the first harmonic
    itself (or any other harmonic i f_b): such an f_h is not presented as determined."""
    sim = long_sim
    y = acceleration(sim)
    model = RecordModel(sim.record.time, y, true_timing(sim), variation=variation)
    f_b = float(np.median(model.timing.f_b))
    params = model.start_params(f_h_over_f_b * f_b, xi_h)
    cov = np.eye(params.size) * 1e-6  # a confident fit: sd 0.001
    result = PersonResult(sim.record, model, params, cov, np.ones(params.size, bool), 0.0, {}, "wald", 0.9, [])
    result.misfit_share = 0.0  # what the model misses is another reason (tested below)
    assert result.determined("f_h") is determined
    assert result.at_bouncing_frequency is not determined


@pytest.mark.parametrize("f_h_over_f_b, xi_h, sd, expected", [
    (1.3, 0.25, 0.001, "kept"), (1.3, 0.25, 0.5, "yardstick"), (1.02, 0.01, 0.001, "search range")])
def test_an_undetermined_f_h_gets_an_interval_as_wide_as_the_record_leaves_it(long_sim, f_h_over_f_b, xi_h, sd,
                                                                            expected):
    """A determined f_h keeps its interval; a poorly determined one gets at least the yardstick's width (the prior
    range as an sd); an artefact (an undamped resonance standing in for the force's first harmonic) the whole
    search range: never a narrow interval around a value the record does not give."""
    from scipy import stats

    from smd_statespace.person.answer import undetermined_interval
    from smd_statespace.person.results import PRIOR_SD

    sim = long_sim
    model = RecordModel(sim.record.time, acceleration(sim), true_timing(sim), variation="independent")
    params = model.start_params(f_h_over_f_b * float(np.median(model.timing.f_b)), xi_h)
    narrow = {"f_h": (params[0] - 0.01, params[0] + 0.01), "xi_h": (params[1] - 0.01, params[1] + 0.01)}
    result = PersonResult(sim.record, model, params, np.eye(params.size) * sd**2, np.ones(params.size, bool), 0.0,
                          narrow, "wald", 0.9, [])
    result.misfit_share = 0.0
    low, high = undetermined_interval(result, "f_h")
    if expected == "kept":
        assert (low, high) == narrow["f_h"]
    elif expected == "yardstick":
        half = stats.norm.ppf(0.95) * PRIOR_SD["f_h"]
        assert (low, high) == pytest.approx((params[0] - half, params[0] + half))
    else:
        assert (low, high) == tuple(model.bounds[0]) and undetermined_interval(result, "xi_h") == tuple(
            model.bounds[1])


@pytest.mark.parametrize("sd, parts", [(0.001, True), (0.5, False)])
def test_a_person_who_changes_gets_the_parts_intervals_where_they_determine_it(long_sim, sd, parts):
    """A person whose halves differ: no one value, so f_h is not determined. Where the record determines f_h apart
    from that (sd 0.001) its interval spans the whole record's and the halves' (on 13 lab exports of changing
    people, 2026-11-30: a quarter to a third of the prior's width, each holding the bout's mean f_h); where it does
    not (sd 0.5), the prior's width as for any undetermined parameter."""
    from scipy import stats

    from smd_statespace.person.answer import honest_intervals
    from smd_statespace.person.results import PRIOR_SD

    model = RecordModel(long_sim.record.time, acceleration(long_sim), true_timing(long_sim), variation="independent")
    params = model.start_params(2.8, 0.25)
    narrow = {"f_h": (2.79, 2.81), "xi_h": (0.24, 0.26)}
    cov = np.diag(np.r_[sd, np.full(params.size - 1, 0.001)] ** 2)  # the sd of f_h as given, the others small
    result = PersonResult(long_sim.record, model, params, cov, np.ones(params.size, bool), 0.0, narrow, "wald", 0.9,
                          [])
    result.misfit_share = 0.0
    halves = [{"f_h_low": 2.9, "f_h_high": 3.0}, {"f_h_low": 2.6, "f_h_high": 2.7}]
    result.change = {"changed": ["f_h"], "halves": halves}
    assert not result.determined("f_h") and result.determined_apart_from_change("f_h") is parts
    low, high = honest_intervals(result)["f_h"]
    if parts:
        assert (low, high) == (2.6, 3.0)
    else:
        half = stats.norm.ppf(0.95) * PRIOR_SD["f_h"]
        assert (low, high) == pytest.approx((2.8 - half, 2.8 + half))
    assert honest_intervals(result)["xi_h"] == narrow["xi_h"]  # not named by the halves


@pytest.mark.parametrize("other_f_h, other_aic, spans", [(3.2, 5.2, True), (3.2, 25.0, False),
                                                         (2.45, 5.2, False)])
def test_the_f_h_interval_spans_the_variation_models_the_record_cannot_rule_out(long_sim, other_f_h, other_aic,
                                                                               spans):
    """Two variation models 5.2 apart in AIC (the record cannot rule either out) that put f_h 2.4 and 3.2 Hz:
    the interval spans both and the warning says so; a model ruled out (AIC 25 worse) or one that agrees leaves
    the interval as it was (the unseen-generator record of shared/findings: 2.10-2.26 and 2.84-3.69 Hz, truth
    2.45)."""
    from smd_statespace.person.answer import honest_intervals
    from smd_statespace.person.comparison import VariationFit

    sim = long_sim
    model = RecordModel(sim.record.time, acceleration(sim), true_timing(sim), variation="independent")
    params = model.start_params(2.4, 0.3)
    common = dict(timing="re-placed", converged=True, on_bound=False, loglike=0.0, n_params=params.size)
    rows = [VariationFit(variation="independent", aic=0.0, f_h=2.4, xi_h=0.3, **common),
            VariationFit(variation="smooth", aic=other_aic, f_h=other_f_h, xi_h=0.25, **common)]
    result = PersonResult(sim.record, model, params, np.eye(params.size) * 1e-6, np.ones(params.size, bool), 0.0,
                          {"f_h": (2.3, 2.5), "xi_h": (0.25, 0.35)}, "calibrated wald", 0.9, rows)
    result.misfit_share = 0.0
    assert honest_intervals(result)["f_h"] == ((2.3, 3.2) if spans else (2.3, 2.5))
    assert honest_intervals(result)["xi_h"] == (0.25, 0.35)
    warned = [w for w in result.warnings if "variation models disagree" in w]
    assert bool(warned) is spans and all("the interval spans them" in w for w in warned)


def test_a_model_that_misfits_the_record_does_not_determine_the_person(long_sim, long_fit):
    """What the model misses goes into f_h and xi_h: when the innovations' predictable part is a visible share
    of the signal, they are not determined, their intervals take the yardstick's width and the warning says why.
    The quiet clean record itself (Ljung-Box p about 1e-23 at 0.2 % BW noise) is not a misfit."""
    import dataclasses

    from scipy import stats

    from smd_statespace.person.answer import honest_intervals
    from smd_statespace.person.results import MISFIT_SHARE, PRIOR_SD

    assert long_fit.misfit_share < 0.2 * MISFIT_SHARE and not long_fit.misfit
    assert long_fit.determined("f_h") and long_fit.intervals == long_fit.narrow_intervals
    bent = dataclasses.replace(long_fit, intervals=dict(long_fit.narrow_intervals))
    bent.misfit_share = 3 * MISFIT_SHARE
    bent.test_pvalues = lambda: {**long_fit.test_pvalues(), "ljung_box_p": 1e-30}
    assert bent.misfit and not bent.determined("f_h") and not bent.determined("xi_h")
    low, high = honest_intervals(bent)["f_h"]
    half = stats.norm.ppf(0.95) * PRIOR_SD["f_h"]
    assert low <= bent.f_h - half + 1e-12 and high >= bent.f_h + half - 1e-12
    words = " ".join(bent.warnings)
    assert "not determined (their intervals are as wide as the yardstick)" in words and "diagnose" in words
    assert "is not determined by this record" not in words  # said once, with the reason


def test_a_person_not_determined_by_its_sd_is_told_against_what(long_fit):
    """An sd over a quarter of the article's starting range's sd: the warning gives both numbers with their unit and
    where the yardstick comes from (it said "sd 0.285 against a yardstick 0.866", for a rule the reader had to
    guess)."""
    import dataclasses

    from smd_statespace.person.results import PRIOR_SD

    cov = long_fit.cov.copy()
    j = long_fit.model.position("f_h")
    cov[j, :] *= 0.3 * PRIOR_SD["f_h"] / long_fit.sd("f_h")
    cov[:, j] *= 0.3 * PRIOR_SD["f_h"] / long_fit.sd("f_h")
    wide = dataclasses.replace(long_fit, cov=cov)
    assert not wide.determined("f_h") and wide.determined("xi_h")
    said = [w for w in wide.warnings if "is not determined" in w]
    assert said == [f"f_h is not determined by this record: its sd {0.3 * PRIOR_SD['f_h']:.3g} Hz is more than 0.25 "
                    f"of {PRIOR_SD['f_h']:.3g} Hz, the sd of the article's starting range (1-4 Hz), which a record "
                    "that determines it narrows fourfold; read its interval, not its value"]


def test_the_misfit_share_measures_what_the_innovations_own_past_predicts(long_fit):
    """White innovations: share about 0; innovations with a predictable echo of known size: that size."""
    import dataclasses

    def share(innovations):
        fit = dataclasses.replace(long_fit, model=dataclasses.replace(long_fit.model))
        fit.model.innovations = lambda params, filtered=None: (innovations, innovations)
        return fit.misfit_share

    white = np.random.default_rng(3).normal(0.0, 0.1, long_fit.model.y.size)
    assert share(white) < 0.002
    echo = white.copy()
    echo[5:] += 0.8 * white[:-5]  # a part predictable from 5 samples back: variance 0.64 of 1.64
    expected = np.sqrt(0.64 / 1.64) * np.std(echo) / np.std(long_fit.model.y)
    assert share(echo) == pytest.approx(expected, rel=0.1)


@pytest.mark.slow
def test_result_reports_the_person_with_intervals_and_tests(long_sim, long_fit):
    result = long_fit
    d = result.to_dict()
    for key in ("f_h", "f_h_sd", "xi_h", "xi_h_sd", "k_h", "c_h", "blf_1", "blf_4", "blf_1_spread", "noise_sd",
                "log_likelihood", "n_cycles", "ljung_box_p", "jarque_bera_p", "offset"):
        assert key in d
    assert d["f_h_low"] < d["f_h"] < d["f_h_high"]
    assert d["k_h"] == pytest.approx(70 * (2 * np.pi * d["f_h"]) ** 2)  # Eq. 17
    assert d["n_cycles"] >= 80
    assert d["noise_bw"] >= 0.0019  # estimated, not assumed; template timing adds its misfit (docs/person-benchmark.md)
    assert "f_h" in result.summary().splitlines()[1]
    # the printout's interval line is short (the interval in Hz); how it was made is one option away
    line = result.summary().splitlines()[1]
    assert f"90 % interval {d['f_h_low']:.2f}-{d['f_h_high']:.2f} Hz" in line and "calibrated" not in line
    assert result.interval_method in result.summary(verbose=True) and d["interval_method"] == result.interval_method


def test_too_short_a_record_is_refused_in_one_line():
    sim = simulate_bouncing(mass=70, f_b=2.0, f_h=2.5, xi_h=0.3, duration=3, seed=2)
    with pytest.raises(SMDInputError, match="at least 8"):
        identify_person(sim.record)  # the bouncing check refuses it first (6 cycles in 3 s)
    with pytest.raises(CycleError, match="at least 8"):
        identify_person(sim.record, check=False)


@pytest.mark.slow
def test_cli_writes_person_json_first_and_refuses_short_records(tmp_path, long_sim, capsys):
    path = tmp_path / "rec.csv"
    long_sim.write(path)
    assert main(["identify", str(path), "--mass", "70", "--out", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    assert printed.splitlines()[1].startswith("person from")
    person = json.loads((tmp_path / "out" / "person.json").read_text())
    assert person["f_h"] == pytest.approx(2.8, rel=0.08)  # the truth of long_sim, inside the search bounds 0.5-6
    assert person["f_h_low"] < 2.8 < person["f_h_high"] and person["f_h_high"] - person["f_h_low"] < 1.0
    assert (tmp_path / "out" / "person_fit.png").stat().st_size > 10_000
    short = simulate_bouncing(mass=70, f_b=2.0, f_h=2.5, xi_h=0.3, duration=3, seed=2)
    short.write(tmp_path / "short.csv")
    assert main(["identify", str(tmp_path / "short.csv"), "--mass", "70", "--out", str(tmp_path / "s")]) == 2
    assert "at least 8" in capsys.readouterr().err
    assert not (tmp_path / "s" / "person.json").exists()


@pytest.mark.slow
def test_constant_offset_absorbs_a_wrong_body_mass():
    """A 2 % error in the mass shifts GRF/M - g by a constant; the offset regressor takes it, f_h stays."""
    sim = simulate_bouncing(mass=70, f_b=2.0, f_h=2.5, xi_h=0.3, duration=30, seed=4)
    # the check of a person who changes fits the halves again: it moves neither the offset nor f_h
    good = identify_person(sim.record, check_change=False)
    wrong = identify_person(make_record(sim.record.time, sim.record.force, 70 * 1.02), check_change=False)
    assert wrong.regressor_coefficients().loc["offset", "value"] == pytest.approx(-G * 0.02 / 1.02, rel=0.05)
    assert wrong.f_h == pytest.approx(good.f_h, rel=0.03)


@pytest.mark.slow
@pytest.mark.parametrize("effects, expected", [
    # clean: every candidate, the cubic spring too, linearised about the predicted path (about the smoothed one it
    # absorbed the variation model's misfit here and was significant)
    (None, None),
    ({"harmonics": {"blf": (0.04, 0.03)}}, "harmonics"),
    ({"floor_mode": {}}, "floor_mode"),  # with the record's floor_acc: the measured floor
])
def test_diagnose_finds_the_hidden_effect_and_nothing_on_a_clean_record(effects, expected):
    """Hidden extra harmonics and a floor with an accelerometer are ranked first among the registered effects; a
    clean record is adequate with the whole library screened."""
    from smd_statespace.person.diagnose import diagnose_person
    from smd_statespace.person.extend import fit_effects

    sim = simulate_bouncing(mass=70, f_b=2.0 if effects is None or "harmonics" in effects else 1.75, f_h=2.5,
                            xi_h=0.3, duration=30, seed=21, effects=effects)
    base = identify_person(sim.record, measured_floor=False)  # the floor left out, for diagnose to find
    # the registered effects only where one is hidden: the generic library's screening is tested where a generic
    # term is hidden (test_person_screen) and on the clean record here, its negative case
    result = diagnose_person(base, library=expected is None)
    if expected is None:
        assert result.adequate, result.table()
        return
    assert result.missing[0] == expected
    row = result.table().loc[expected]
    assert row["likelihood"] == "exact"
    fitted = result.fits[expected]
    # the effect explains part of what was noise where the test is made (the person's cycle starts); the proposal's
    # row is the fit identify --effect gives, its starts re-placed, at a higher likelihood still (there the noise may
    # trade with the force's variation: +0.015 % on the floor record)
    screened = fit_effects(base, fitted.effects, timing=False)
    assert screened.sigma < base.sigma and fitted.loglike >= screened.loglike - 1e-6
    assert screened.effect_test()["lr"] == pytest.approx(row["lr"])
    # the person with the effect: its interval holds the truth (with the 5th and 6th harmonics, f_h is 2.41 Hz,
    # 0.8 sd below 2.5, at a log-likelihood 311 above where L-BFGS-B with difference gradients had stopped with
    # 2.53 Hz: issue 21's "f_h never worse with the true effect" is missed on this record, see its note)
    low, high = fitted.intervals["f_h"]
    assert low < 2.5 < high and row["f_h"] == pytest.approx(2.5, rel=0.06)
    if expected == "harmonics":  # the 5th harmonic's amplitude comes back, with 4 template coefficients and 2 spreads
        assert row["df"] == 6
        assert fitted.template_blf().loc[5, "blf"] == pytest.approx(0.04, rel=0.15)
    else:  # the measured floor: nothing to estimate, the exact model of the leg on a moving floor
        assert row["df"] == 0 and row["lr"] > 20
        # identify's default person of a record with floor_acc is that fit: the person rides the floor measured
        default = identify_person(sim.record)
        assert [e.spec for e in default.effects] == [e.spec for e in fitted.effects]
        assert default.f_h == pytest.approx(fitted.f_h, rel=1e-9) and default.before.f_h == base.f_h
        assert any("floor_acc is in the model" in note for note in default.notes)


@pytest.mark.slow
def test_compare_puts_the_person_beside_the_per_cycle_estimators(tmp_path, long_sim, capsys):
    path = tmp_path / "rec.csv"
    truth = tmp_path / "rec_truth.json"
    long_sim.write(path, truth)
    argv = ["compare", str(path), "--mass", "70", "--estimators", "record,ekf", "--max-passes", "1", "--quiet",
            "--truth", str(truth), "--out", str(tmp_path / "c")]
    assert main(argv) == 0
    out = capsys.readouterr().out
    table = pd.read_csv(tmp_path / "c" / "compare_table.csv", index_col=0)
    assert list(table.index) == ["record", "ekf"]
    assert table.loc["record", "|err| f_h"] == pytest.approx(abs(table.loc["record", "f_h"] - 2.8))
    assert "the person from the whole record" in out
    # each row shows its estimator's measured coverage (recomputed from the benchmark's rows for the record model:
    # test_the_coverage_compare_prints_is_the_one_measured_with_the_shipped_calibration); an estimator measured
    # under COVERAGE_OK carries the warning, one above does not
    from smd_statespace.cli.compare import COVERAGE_OK, MEASURED_COVERAGE

    for name in ("record", "ekf"):
        assert table.loc[name, "f_h_cover_%"] == MEASURED_COVERAGE[name]
        assert (f"warning: {name}: intervals over-confident" in out) == (MEASURED_COVERAGE[name] < COVERAGE_OK)


def test_likelihood_ratio_of_a_regressor_absent_is_small_and_present_is_large():
    """Records drawn from the model itself (statsmodels' simulator): a regressor that is not there gives a ratio
    under chi-square(1)'s 99.9 % point; one that is there (gain 10 m/s^2 on the person, 0.6 m/s^2 in the output) a large one. (That the absent one's ratio is
    chi-square(1) over many records is benchmarks/likelihood_ratio_null.py's "regressor" study.)"""
    from scipy import stats

    t = np.arange(0.0, 8.0, 0.01)
    timing = CycleTiming(np.arange(-0.5, 8.6, 0.5))
    offset = Regressor("offset", np.ones_like(t), dynamic=False)
    absent = Regressor("absent", np.sin(2 * np.pi * 0.7 * t + 0.3))
    params = np.array([2.6, 0.3, -6.0, -1.0, -3.0])
    ratios = []
    for gain in (0.0, 10.0):
        truth = RecordModel(t, np.zeros_like(t), timing, n_harmonics=2, regressors=(offset, absent))
        delta = np.zeros(2 + truth.n_coefficients + 2)
        delta[2:2 + truth.n_coefficients] = [0.0, -0.25, 0.05, 0.1, 0.12]
        delta[-1] = gain
        simulator = RecordStateSpace(truth, delta)
        keyword = "rng" if "rng" in inspect.signature(simulator.simulate).parameters else "random_state"
        y = simulator.simulate(params, t.size, **{keyword: np.random.default_rng(np.random.SeedSequence(314))})
        without = fit_model(RecordModel(t, y, timing, n_harmonics=2, regressors=(offset,)), params)
        with_ = fit_model(RecordModel(t, y, timing, n_harmonics=2, regressors=(offset, absent)), without["params"])
        ratios.append(2.0 * (with_["loglike"] - without["loglike"]))
    assert -1e-6 < ratios[0] < stats.chi2(1).ppf(0.999)
    assert ratios[1] > 30.0


@pytest.mark.slow
@pytest.mark.parametrize("effects, warned", [
    ({"cubic_stiffness": {"beta_3": 1500.0}}, True), ({"harmonics": {"blf": (0.04, 0.03)}}, True), (None, False)])
def test_identify_warns_when_the_base_model_misses_an_effect_and_names_the_next_command(effects, warned):
    """Hidden cubic spring or extra harmonics: a warning in words with the diagnose command; a clean record: none."""
    sim = simulate_bouncing(mass=70, f_b=1.6, f_h=1.92, xi_h=0.3, duration=30, seed=1, effects=effects)
    result = identify_person(sim.record)
    said = [w for w in result.warnings if "serially correlated" in w]
    assert bool(said) is warned
    if warned:
        assert "`smd-statespace diagnose synthetic --mass 70`" in said[0]  # the record-level diagnosis, the default


def test_wald_interval_is_symmetric_inside_the_bounds_and_ends_at_a_bound_it_would_cross():
    from scipy import stats

    from smd_statespace.person.calibration import wald_interval
    from smd_statespace.person.model import XI_H_BOUNDS

    z = stats.norm.ppf(0.95)
    low, high = wald_interval(0.3, 0.05, 0.9, XI_H_BOUNDS)
    assert np.isclose(low, 0.3 - z * 0.05) and np.isclose(high, 0.3 + z * 0.05)
    low, high = wald_interval(0.05, 0.1, 0.9, XI_H_BOUNDS)  # 0.05 - 1.645 * 0.1 < 0: no negative damping
    assert low == XI_H_BOUNDS[0] and np.isclose(high, 0.05 + z * 0.1)
    assert wald_interval(5.9, 0.2, 0.9, (0.5, 6.0))[1] == 6.0


@pytest.mark.slow
def test_a_1000_hz_record_is_fitted_at_100_hz_and_says_so(tmp_path, capsys, monkeypatch):
    from smd_statespace import progress
    from smd_statespace.person import fit as fit_module
    from smd_statespace.person.fit import AUTO_VARIATIONS
    from smd_statespace.person.search import TIMING_ITERATIONS

    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.8, xi_h=0.25, duration=30, fs=1000.0, seed=11)
    capsys.readouterr()
    monkeypatch.setattr(progress, "watched", lambda stream=None: True)  # as on a terminal

    class EveryUpdate(progress.tqdm):  # drawn at every update: tqdm skips those within 0.1 s of the last drawn
        def __init__(self, *args, **kwargs):
            super().__init__(*args, mininterval=0, miniters=1, **kwargs)

    monkeypatch.setattr(fit_module, "tqdm", EveryUpdate)
    result = identify_person(sim.record, progress=True)
    # every variation model: its first fit and its own timing fits; the winner's final fit; the halves'; the
    # information
    steps = len(AUTO_VARIATIONS) * (1 + TIMING_ITERATIONS + 1) + 3
    bar = capsys.readouterr().err
    assert "identify (record)" in bar and f"{steps}/{steps}" in bar  # every search counted, none twice
    assert result.record.fs == pytest.approx(100.0) and result.model.y.size == sim.record.time.size // 10
    assert result.notes[0] == ("fitted at 100 Hz: the record (1000 Hz) was low-pass filtered and one sample in 10 "
                               "kept (the rate asked: 100 Hz; to keep every sample, rate=None in Python or --rate 0 "
                               "on the command line)")
    # decimated, 1 % BW per 1000 Hz sample is 0.32 % per fitted one (read as 0.4 %: the force's jumps at cycle
    # starts reach the band the noise is read from): below the noise floor, which says so
    assert len(result.notes) == 2 and re.search(r"white noise of 0\.9\d % BW was added", result.notes[1])
    assert "note: fitted at 100 Hz" in result.summary() and result.to_dict()["fs"] == pytest.approx(100.0)
    low, high = result.intervals["f_h"]
    assert low < 2.8 < high  # the person, from a tenth of the samples
    path = tmp_path / "fast.csv"
    sim.write(path)
    assert main(["identify", str(path), "--mass", "70", "--rate", "-1", "--out", str(tmp_path / "o")]) == 2
    assert "--rate" in capsys.readouterr().err


@pytest.mark.slow
def test_calibrated_intervals_add_the_model_error_floor_and_the_sd_stays_the_records(long_fit):
    from scipy import stats

    from smd_statespace.person.calibration import MODEL_ERROR_FLOOR

    z = stats.norm.ppf(0.95)
    floors = MODEL_ERROR_FLOOR[long_fit.model.variation]
    for which, name, floor in ((0, "f_h", floors["f_h"] * long_fit.f_h), (1, "xi_h", floors["xi_h"])):
        low, high = long_fit.intervals[name]
        half = z * np.hypot(long_fit.se[which], floor)
        assert high == pytest.approx(long_fit.params[which] + half)
        assert low == pytest.approx(max(long_fit.params[which] - half, long_fit.model.bounds[which][0]))
        assert long_fit.determined(name)  # the floor widens the interval, not what the record determines


def test_load_factor_sds_carry_the_persons_uncertainty_through_eq2(long_fit):
    """The force is read through Eq. 2, BLF_i = |acceleration harmonic i| / |H(i f_b)|: the BLFs' sds include
    dBLF_i/df_h times the sd of f_h, which matches the derivative of |H| (a uncertainty only in f_h)."""
    import dataclasses

    from smd_statespace.model import acceleration_frf

    result = long_fit
    blf = result.template_blf()
    assert (blf["sd"] >= blf["sd_given_person"]).all()
    sd_f_h = 0.05
    only_f_h = np.zeros_like(result.cov)
    only_f_h[0, 0] = sd_f_h**2
    probe = dataclasses.replace(result, cov=only_f_h, interval_method="wald")  # no model-error floor
    person_part = np.sqrt(probe.template_blf()["sd"] ** 2 - probe.template_blf()["sd_given_person"] ** 2)
    f_b, step = float(np.median(result.model.timing.f_b)), 1e-4
    for i in (1, 2):
        def blf_at(f_h):
            return blf.loc[i, "blf"] * abs(acceleration_frf(i * f_b, result.f_h, result.xi_h)) / abs(
                acceleration_frf(i * f_b, f_h, result.xi_h))
        slope = (blf_at(result.f_h + step) - blf_at(result.f_h - step)) / (2 * step)
        assert person_part[i] == pytest.approx(abs(slope) * sd_f_h, rel=0.15)
    assert result.to_dict()["blf_1_low"] < blf.loc[1, "blf"] < result.to_dict()["blf_1_high"]


def test_load_factors_read_through_an_undetermined_person_say_so(long_fit):
    """When f_h's interval is wider than its information says (not determined), the BLFs' intervals span the
    template concentrated again across the person's intervals, and a BLF whose interval is then wider than its
    value is not determined, in the table, person.json, the summary and the warnings."""
    import dataclasses

    from smd_statespace.model import acceleration_frf

    determined = long_fit.template_blf()
    assert determined["determined"].all()  # a determined person: intervals from the sds
    for plain in (long_fit, dataclasses.replace(long_fit, narrow_intervals={})):  # calibrated, and as "wald" keeps
        assert not plain.person_widened and "±" in plain.summary().splitlines()[4]
    wide = dict(long_fit.intervals, f_h=(0.6 * long_fit.f_h, 1.4 * long_fit.f_h))
    probe = dataclasses.replace(long_fit, intervals=wide, narrow_intervals=dict(long_fit.intervals))
    blf = probe.template_blf()
    f_b = float(np.median(long_fit.model.timing.f_b))
    for i in (1, 2):  # Eq. 2 at the interval's ends: the BLFs the template gives there lie inside the new interval
        gain = [abs(acceleration_frf(i * f_b, long_fit.f_h, long_fit.xi_h)) / abs(
            acceleration_frf(i * f_b, f_h, long_fit.xi_h)) for f_h in wide["f_h"]]
        for g in gain:
            assert 0.95 * blf.loc[i, "low"] <= g * determined.loc[i, "blf"] <= 1.05 * blf.loc[i, "high"], (i, g)
        assert blf.loc[i, "high"] - blf.loc[i, "low"] > determined.loc[i, "high"] - determined.loc[i, "low"]
    assert not blf["determined"].all()
    names = [f"BLF{i}" for i in blf.index[~blf["determined"]]]
    assert any(w.startswith(", ".join(names) + " not determined") for w in probe.warnings)
    assert "NOT DETERMINED" in probe.summary().splitlines()[4]
    row = probe.to_dict()
    assert [row[f"blf_{i}_determined"] for i in blf.index] == list(blf["determined"])


def test_a_bare_effect_name_is_configured_for_the_record_as_diagnose_proposes_it(long_fit):
    """``identify --effect cubic_stiffness`` searches the range diagnose's candidate has (scaled to the record's
    displacement), not the fixed default a strong spring ends on; options given are kept."""
    from smd_statespace.effects import EFFECTS
    from smd_statespace.person.effect_adapter import fitted_record
    from smd_statespace.person.extend import configured_for_record

    scaled = EFFECTS["cubic_stiffness"].propose(fitted_record(long_fit))  # what the effect reads of the fit
    bare = configured_for_record("cubic_stiffness", long_fit)
    assert bare.spec == scaled.spec and bare.beta_range[1] > 1000.0
    assert configured_for_record("cubic_stiffness:beta_range=-500/500", long_fit).beta_range == (-500.0, 500.0)
    assert configured_for_record(scaled, long_fit) is scaled


@pytest.mark.slow
def test_auto_chooses_among_the_variation_models_at_their_own_cycle_starts():
    """``variation="auto"`` re-places each model's cycle starts with its own fit and chooses there: the chosen
    model's re-placed row is its single-model fit, the other's at most its own (it stops re-placing when left
    behind by more than ``search.BEHIND``), and the AIC's choice is kept. A wandering tempo (record 27 of
    ``person_accuracy.py --seed 2027``, f_h 0.76 f_b): chosen at smooth's re-placed starts, auto took "smooth",
    f_h -33 % with an interval that missed the truth; "independent" at its own starts is 52 higher in
    log-likelihood and covers it."""
    blf = (0.32245500587261045, 0.11268219380594661, 0.05176513594021767, 0.021418757774779775)
    sim = simulate_bouncing(mass=61.11, f_b=3.3464272409903266, f_h=2.5314826062611298, xi_h=0.39824060175194365,
                            duration=30.0, fs=100.0, blf=blf, noise=0.01, seed=322228685, variation="tempo")
    auto = identify_person(sim.record)
    replaced = {row.variation: row for row in auto.comparison if row.timing == "re-placed"}
    chosen = min(replaced.values(), key=lambda row: row.aic)
    assert auto.model.variation == chosen.variation == "independent"
    for variation in ("independent", "smooth"):
        alone = identify_person(sim.record, variation=variation, check_change=False)  # (the check moves no fit)
        if variation == chosen.variation:
            assert replaced[variation].loglike == pytest.approx(alone.loglike, abs=0.05)
        else:
            in_full = next(row for row in alone.comparison if row.timing == "re-placed")
            assert replaced[variation].loglike <= alone.loglike + 0.05 and in_full.aic > chosen.aic
    low, high = auto.intervals["f_h"]
    assert low < 2.5314826062611298 < high


def test_a_grf_whose_highest_peak_jumps_between_two_humps_still_gets_one_boundary_per_force_cycle():
    """A person on a resonant floor (``person_effects.py --seed 81``, a large measured floor, ``jumps``): the GRF
    has two humps per cycle and its highest peak jumps between them, so the peaks' intervals were 0.18-0.47 s about
    a period of 0.30 s and 94 peaks stood for 100 cycles; the record-level model, given 96 cycles, found f_h 3.36 Hz
    (truth 3.07) and, with the measured floor, a likelihood 463 below the fit without it. The cycles are now counted
    by the phase of the GRF's fundamental when the peaks are irregular
    (:data:`~smd_statespace.person.timing.PEAK_TOLERANCE`)."""
    from smd_statespace.person.timing import _regular

    sim = simulate_bouncing(mass=78.4073, f_b=3.354064, f_h=3.066881, xi_h=0.47819, duration=30.0, fs=100.0,
                            blf=(0.221154, 0.184622, 0.035741, 0.022289), noise=0.01, seed=102650511,
                            variation="jumps", effects={"floor_mode": {"modal_mass": 700.0}})
    time, force = sim.record.time, sim.record.force
    peaks, _ = find_cycles(time, force)
    assert not _regular(time[peaks])  # the case: the peaks miss cycles
    boundaries = estimate_timing(time, force).boundaries
    true_starts = sim.cycles["t_start"].to_numpy()[1:]  # (the first is the record's start)
    inner = boundaries[(boundaries > 0.0) & (boundaries < time[-1])]
    period = np.median(np.diff(true_starts))
    assert abs(inner.size - true_starts.size) <= 1
    assert np.all(np.abs(np.diff(inner) / period - 1.0) < 0.15)
    # every boundary at the same place of its true cycle (a common shift is the template's phase origin)
    j = np.clip(np.searchsorted(true_starts, inner, side="right") - 1, 0, true_starts.size - 2)
    turn = np.exp(2j * np.pi * (inner - true_starts[j]) / (true_starts[j + 1] - true_starts[j]))
    assert np.sqrt(-2.0 * np.log(abs(np.mean(turn)))) / (2.0 * np.pi) < 0.03


@pytest.mark.parametrize("case", ["half-cycle peaks", "a line off half the rate"])
def test_peak_intervals_are_regrouped_only_by_a_line_at_half_their_rate(case):
    """A dominant 2nd harmonic (``f_h`` near ``2 f_b``) puts two GRF peaks in each force cycle: the line at half
    their rate regroups them. A quiet record with some other line 5 % off half the peak rate (31-33 times its
    neighbourhood on two lab records) must not: its cycles were made two force cycles long
    (:data:`~smd_statespace.person.timing.SUBHARMONIC_OFFSET`)."""
    if case == "half-cycle peaks":
        sim = simulate_bouncing(mass=70.0, f_b=1.7, f_h=3.3, xi_h=0.1, duration=30.0, fs=100.0,
                                blf=(0.1, 0.3, 0.05, 0.02), noise=0.01, seed=3, variation="jumps")
        force = sim.record.force
        peaks, _ = find_cycles(sim.record.time, force, (0.5, 10.0))
        assert peaks.size > 1.8 * len(sim.cycles)  # the case: two peaks per cycle
    else:
        sim = simulate_bouncing(mass=70.0, f_b=2.6, f_h=3.3, xi_h=0.4, duration=30.0, fs=100.0,
                                blf=(0.3, 0.15, 0.04, 0.02), noise=0.001, seed=3, variation="jumps")
        force = sim.record.force + 0.003 * 70.0 * G * np.sin(2.0 * np.pi * 1.05 * 1.3 * sim.record.time)
    assert abs(estimate_timing(sim.record.time, force).n_cycles - len(sim.cycles)) <= 1


@pytest.mark.parametrize("name, fundamental", [("humps_not_locked", 2.25), ("humps_missed", 2.87)])
def test_humps_not_locked_to_the_cycle_are_regrouped_by_a_strong_line_a_little_off_half_their_rate(name, fundamental):
    """Lab exports with two GRF humps per force cycle whose peaks' rate is not twice the fundamental's (refused as
    "median bouncing frequency ... is outside the supported range"). ``humps_not_locked`` (``--people lab``, seed
    4361, change row 12; ``f_h`` drifting towards ``2 f_b``): humps at 4.37 Hz over a fundamental at 2.25 Hz, 2958
    times its neighbourhood, 3 % off half the humps' rate; the strong line regroups them
    (:data:`~smd_statespace.person.timing.SUBHARMONIC_STRONG`). ``humps_missed`` (seed 4364, held-out row 8): 2 % of
    the humps too low to be peaks, so a rate from the count (5.39 Hz) put the fundamental (2.871 Hz, 1623 times its
    neighbourhood) 6.5 % off; from the peaks' usual intervals (5.49 Hz), 4.5 %."""
    from smd_statespace.signals import prepare_record

    lab = lab_export(name)
    record = prepare_record(lab.record).record
    timing = estimate_timing(record.time, record.force)
    assert abs(timing.n_cycles / (record.time[-1] - record.time[0]) - fundamental) < 0.1  # not the humps' rate


def test_the_first_boundary_of_a_record_that_starts_from_rest_is_not_pulled_into_the_cycle():
    """A person starting from rest (``coefficients`` generator, record 0 of ``person_accuracy.py --seed 2027``):
    the template alignment put the first inner boundary 0.14 s into a 0.43 s cycle (true start 0.00), which cost
    f_h 12 % and flagged the record as misfit. The irregular edge cycle is now replaced by one neighbouring period
    (:data:`~smd_statespace.person.timing.EDGE_TOLERANCE`); the regular ones stay where the alignment put them."""
    from smd_statespace.person.timing import EDGE_TOLERANCE, _regular_edges

    sim = simulate_bouncing(mass=70.0, f_b=2.3043, f_h=3.038, xi_h=0.202, duration=30.0, fs=100.0,
                            blf=(0.25, 0.15, 0.05, 0.02), noise=0.01, seed=1, variation="coefficients")
    boundaries = estimate_timing(sim.record.time, sim.record.force).boundaries
    true_starts = sim.cycles["t_start"].to_numpy()
    inner = boundaries[(boundaries > 0) & (boundaries < sim.record.time[-1])]
    period = np.median(np.diff(inner))
    assert abs(inner[1] - inner[0] - period) <= EDGE_TOLERANCE * period
    # every estimated boundary sits on a true cycle start (the template's phase is that of the cycle start here)
    nearest = np.min(np.abs(inner[:, None] - true_starts[None, :]), axis=1)
    assert np.median(nearest) < 0.1 * period
    regular = np.array([0.1, 0.5, 0.9, 1.3, 1.7])
    assert np.array_equal(_regular_edges(regular), regular)
    assert _regular_edges(np.array([0.3, 0.5, 0.9, 1.3, 1.7]))[0] == pytest.approx(0.1)
    assert _regular_edges(np.array([0.1, 0.5, 0.9, 1.3, 1.45]))[-1] == pytest.approx(1.7)


def test_parameters_by_name_round_trip_and_refuse_in_words(short_sim):
    """RecordModel.unpack / pack: the parameter vector by name (code outside the model reads names, not positions)."""
    from smd_statespace.errors import OptionError

    record = short_sim.record
    model = RecordModel(record.time, record.force / record.mass - G, estimate_timing(record.time, record.force), 4,
                        "smooth")
    params = model.start_params(2.7, 0.31, -2.0)
    named = model.unpack(params)
    assert list(named) == model.param_names and named["f_h"] == 2.7 and named["xi_h"] == 0.31
    assert named["log_smooth_time"] == params[model.param_names.index("log_smooth_time")]
    assert np.array_equal(model.pack({**named, "another_models_parameter": 1.0}), params)
    with pytest.raises(OptionError, match="no value for xi_h"):
        model.pack({k: v for k, v in named.items() if k != "xi_h"})
    with pytest.raises(OptionError, match=f"{len(params)} values expected"):
        model.unpack(params[:-1])


def test_the_coverage_compare_prints_is_the_one_measured_with_the_shipped_calibration():
    """``compare`` shows the record-level model's coverage as measured: it must be the share of the benchmark's rows
    (fresh records fitted with the shipped calibration) whose interval held the truth, not an older run's."""
    from pathlib import Path

    from smd_statespace.cli.compare import MEASURED_COVERAGE
    from smd_statespace.person.calibration import CALIBRATION

    rows = pd.concat([pd.read_csv(path) for path in
                      sorted((Path(__file__).parents[1] / "benchmarks" / "results").glob("person_accuracy_seed2029*.csv"))])
    fitted = rows[rows["error"].isna()]
    assert len(fitted) == 154
    assert MEASURED_COVERAGE["record"] == round(100 * fitted["f_h_covered"].mean())
    # the rows were fitted with today's factors: their sd of f_h is the raw one times the shipped factor
    for variation, group in fitted.groupby("variation"):
        factor = (group["f_h_se"] / group["f_h_raw_se"]).median()
        assert factor == pytest.approx(CALIBRATION[variation]["f_h"], rel=1e-6)

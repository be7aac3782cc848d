"""The exact gradient of the record-level log-likelihood (:mod:`smd_statespace.person.score`).

- the per-sample log-densities of the sensitivity pass are :meth:`RecordModel.sample_loglike`'s;
- the gradient is a central difference of :meth:`RecordModel.loglike` for every variation model, a phase
  template, process noise, drift, regressors, a floor mode (linear dynamics of its own) and a cubic spring
  (linearised about a path);
- the per-sample scores, innovations' and variances' derivatives are central differences of the filter's at
  fixed ``delta``, ``sigma^2``;
- the analytic derivatives of the discretisation equal central differences of ``RecordModel.system``;
- the expected information: conditional on ``delta`` far too large for ``f_h``, ``xi_h``; with ``delta`` and
  ``sigma^2`` profiled out close to the observed information of ``fit.information``.
"""

import numpy as np
import pytest

from helpers import known_disturbance
from smd_statespace.effects import make_effect
from smd_statespace.io import G
from smd_statespace.model import SMDModel
from smd_statespace.person import RecordModel, Regressor, estimate_timing
from smd_statespace.person.dynamics import PersonDynamics
from smd_statespace.person.statespace import nominal_path
from smd_statespace.person.search import fit_model, information
from smd_statespace.person.score import score, system_derivatives
from smd_statespace.simulation import simulate_bouncing

TEMPLATE = np.array([0.0, -0.2, 0.1, 0.1, 0.05, 0.03, 0.0, 0.01, 0.0])
"""A force template (g) for the phase and rate errors."""

GRADIENT_TOLERANCE = 1e-4
"""Largest difference from the central difference of ``loglike``, relative to the gradient's norm.

The central difference (step 1e-5 of each parameter's size) has a truncation error ~ h^2 |L'''| and a
rounding error ~ 1e-16 |L| / h ~ 1e-8 (|L| ~ 1e3); the exact gradient's own error is that of the
differenced continuous ``A, b`` (~1e-10) or of a differenced ``system`` (~1e-7 of the arrays). Measured
agreement: 1e-9 to 2e-7 of the norm; 1e-4 leaves room for other machines and still catches any wrong
term of the recursion (a missing term is of the order of the gradient itself).
"""


@pytest.fixture(scope="module")
def record():
    """A 10 s record (f_b 2.2 Hz, f_h 2.8 Hz, xi_h 0.3): time, y (m/s^2), template cycle timing."""
    sim = simulate_bouncing(mass=70, f_b=2.2, f_h=2.8, xi_h=0.3, duration=10, seed=7)
    rec = sim.record
    y = rec.force / rec.mass - G
    return rec.time, y, estimate_timing(rec.time, rec.force, 4, "template")


def offset(time):
    return Regressor("offset", np.ones_like(time), "m/s^2", dynamic=False)


def build(record, effects=(), nominal=None, regressors=(), **options):
    """The record-level model as identify_person builds it (offset regressor), with options and effects."""
    time, y, timing = record
    dynamics = PersonDynamics(SMDModel(n_harmonics=4, effects=list(effects)), time) if effects else None
    return RecordModel(time, y, timing, 4, regressors=(offset(time),) + tuple(regressors), dynamics=dynamics,
                       nominal=nominal, **options)


def point(model, **named):
    """Parameters near a fit, not at one (a nonzero gradient): log variances spread around -2.5."""
    params = model.start_params(2.7, 0.32, -2.5)
    params[2:] += np.linspace(-0.6, 0.6, params.size - 2)
    for name, value in named.items():
        params[model.param_names.index(name)] = value
    return params


def central_gradient(model, params, relative=1e-5):
    out = np.empty(params.size)
    for j, scale in enumerate(model.scales):
        h = relative * max(abs(params[j]), scale)
        up, down = params.copy(), params.copy()
        up[j] += h
        down[j] -= h
        out[j] = (model.loglike(up) - model.loglike(down)) / (2.0 * h)
    return out


def cubic_model(record):
    """A cubic spring linearised about the predicted path of the model without it."""
    base = build(record)
    path = nominal_path(base, point(base))
    model = build(record, effects=[make_effect("cubic_stiffness")], nominal=path)
    return model, point(model, beta_3=300.0)


def floor_model(record):
    model = build(record, effects=[make_effect("floor_mode:source=modal")])
    return model, point(model, f_f=3.5, xi_f=0.02, mass_ratio=0.01)


CASES = {
    "independent": lambda r: build(r),
    "smooth": lambda r: build(r, variation="smooth"),
    "random_walk": lambda r: build(r, variation="random_walk"),
    "both": lambda r: build(r, variation="both"),
    "phase_template": lambda r: build(r, phase_template=TEMPLATE),
    "smooth_phase_drift": lambda r: build(r, variation="smooth", phase_template=TEMPLATE, drift=True),
    "both_phase_drift": lambda r: build(r, variation="both", phase_template=TEMPLATE, drift=True),
    "process_noise": lambda r: build(r, process_noise=True),
    "drift": lambda r: build(r, drift=True),
    "regressors": lambda r: build(r, regressors=(Regressor("sway", np.sin(2 * np.pi * 0.7 * r[0])),
                                                 Regressor("floor", np.cos(2 * np.pi * 1.3 * r[0]), observed=False))),
    "missing": lambda r: build(r, variation="smooth", phase_template=TEMPLATE, observed=gaps(r[0])),
}


def gaps(time):
    """Samples missing in three bursts (a phone's gaps: 5, 25 and 40 samples)."""
    observed = np.ones(time.size, dtype=bool)
    for start, length in ((150, 5), (400, 25), (700, 40)):
        observed[start:start + length] = False
    return observed


def disturbance_model(record):
    """An effect whose term is a known function of time with an unknown gain, at gain 0 (where identify starts it):
    its known term vanishes there, its derivative does not."""
    model = build(record, effects=[known_disturbance()])
    return model, point(model, c_d=0.0)


def case(record, name):
    if name == "floor_mode":
        return floor_model(record)
    if name == "known_disturbance":
        return disturbance_model(record)
    if name == "cubic_stiffness":
        return cubic_model(record)
    model = CASES[name](record)
    return model, point(model)


@pytest.mark.parametrize("name", list(CASES) + ["floor_mode", "cubic_stiffness", "known_disturbance"])
def test_gradient_is_the_derivative_of_the_profile_loglike(record, name):
    model, params = case(record, name)
    fitted = model.filter(params)
    out = score(model, params, fitted)
    # the pass's per-sample values are sample_loglike's at the estimated delta, sigma^2; they sum to loglike
    expected = model.sample_loglike(params, fitted["delta"], fitted["sigma2"])
    np.testing.assert_allclose(out["sample_loglike"], expected, rtol=1e-10, atol=1e-10)
    assert out["loglike"] == pytest.approx(out["sample_loglike"].sum(), rel=1e-12, abs=1e-9)
    numeric = central_gradient(model, params)
    assert np.max(np.abs(out["gradient"] - numeric)) < GRADIENT_TOLERANCE * np.linalg.norm(numeric), (
        out["gradient"], numeric)
    np.testing.assert_allclose(out["per_sample"].sum(axis=0), out["gradient"])


@pytest.mark.parametrize("name", ["phase_template", "smooth_phase_drift", "floor_mode"])
def test_per_sample_derivatives_are_differences_at_fixed_delta(record, name):
    """Scores, innovations' and log variances' derivatives of every sample: central differences of the
    filter at fixed delta and sigma^2 (what fit._cluster_scores differences)."""
    model, params = case(record, name)
    fitted = model.filter(params)
    delta, sigma2 = fitted["delta"], fitted["sigma2"]
    out = score(model, params, fitted)

    def at(values):
        f = model.filter(values)
        return (model.sample_loglike(values, delta, sigma2), f["innovations_raw"] - f["innovation_regression"] @ delta,
                np.log(f["innovation_variance_unscaled"]))

    def difference(j, h):
        up, down = params.copy(), params.copy()
        up[j] += h
        down[j] -= h
        return [(plus - minus) / (2.0 * h) for plus, minus in zip(at(up), at(down))]

    for j, scale in enumerate(model.scales):
        # Richardson's extrapolation of two central differences (error ~ h^4): each sample's value carries the
        # rounding of the whole recursion (a small step is noisy: xi_f = 0.02) and the lightly damped floor
        # mode is curved in f_f; measured worst agreement 1e-6 of a column's size (xi_f), tolerance 1e-5
        h = 3e-4 * max(abs(params[j]), scale)
        for key, coarse, fine in zip(("per_sample", "d_innovations", "d_log_variances"), difference(j, h),
                                     difference(j, h / 2)):
            numeric = (4.0 * fine - coarse) / 3.0
            size = np.max(np.abs(numeric)) + 1e-12
            assert np.max(np.abs(out[key][:, j] - numeric)) < 1e-5 * size, (model.param_names[j], key)


@pytest.mark.parametrize("name", ["phase_template", "floor_mode"])
def test_analytic_derivatives_of_the_discretisation_equal_differences_of_system(record, name):
    model, params = case(record, name)
    analytic = system_derivatives(model, params, method="analytic")
    difference = system_derivatives(model, params, method="difference")
    # central differences of system carry ~1e-7..1e-4 of rounding (measured against a Richardson extrapolation;
    # the analytic ones 1e-10..1e-7): the two agree to the differences' accuracy
    for key in ("d_hx", "d_Phi", "d_Gam", "d_X_tr", "d_Qx", "d_offset", "d_y"):
        size = np.max(np.abs(difference[key]), initial=0.0)
        assert np.max(np.abs(analytic[key] - difference[key]), initial=0.0) <= 1e-5 * size + 1e-300, key
    np.testing.assert_array_equal(analytic["dyn"], difference["dyn"])
    with pytest.raises(ValueError):
        system_derivatives(*cubic_model(record), method="analytic")


def test_forward_differences_of_a_path_linearised_system_are_as_close_as_central_ones(record):
    """A path-linearised effect's derivatives (``auto``: forward differences, one system per parameter) against a
    Richardson extrapolation of central differences at large steps: as close as the central differences at
    DYNAMICS_STEP, which the rounding of the path's own differenced Jacobian bounds (measured on this record: forward
    1.4e-6..4.3e-6 of an array's size, central 3e-7..1.1e-5)."""
    model, params = cubic_model(record)
    coarse, fine = (system_derivatives(model, params, method="difference", step=h) for h in (1e-3, 5e-4))
    forward = system_derivatives(model, params)
    central = system_derivatives(model, params, method="difference")
    for key in ("d_hx", "d_Phi", "d_Gam", "d_offset", "d_y", "d_Qx"):
        reference = (4.0 * fine[key] - coarse[key]) / 3.0
        size = np.max(np.abs(reference))
        for name, got in (("forward", forward), ("central", central)):
            assert np.max(np.abs(got[key] - reference)) <= 2e-5 * size, (key, name)
    exact = score(model, params, derivatives=central)
    assert np.max(np.abs(score(model, params)["gradient"] - exact["gradient"])) < 1e-5 * np.linalg.norm(
        exact["gradient"])


def test_score_by_differenced_system_matches(record):
    model, params = case(record, "phase_template")
    exact = score(model, params)
    differenced = score(model, params, method="difference")
    assert np.max(np.abs(exact["gradient"] - differenced["gradient"])) < 1e-6 * np.linalg.norm(exact["gradient"])


def test_expected_information_conditional_and_profiled_against_the_observed(record):
    """At a fit: the information at fixed delta, sigma^2 overstates what the record says about f_h and xi_h
    (the template absorbs much of a change of the dynamics: standard errors about 0.1-0.2 of the observed
    information's); with delta and sigma^2 profiled out (Schur complement) it agrees with the observed
    information to about 15 % (measured 0.84-1.06 over six records)."""
    model = build(record)
    fitted = fit_model(model, model.start_params(2.8, 0.3, -4.0), quick=True)
    params = fitted["params"]
    cov, free = information(model, params, "oim")
    index = np.flatnonzero(free)
    out = score(model, params)
    assert np.max(np.abs(out["gradient"][:2])) < 1.0  # at the maximum (a quick fit: to its tolerance)
    se_observed = np.sqrt(np.diag(cov)[index])
    for key, low, high in (("expected_information", 0.0, 0.3), ("profile_information", 0.7, 1.4)):
        info = out[key][np.ix_(index, index)]
        np.testing.assert_allclose(info, info.T)
        assert np.all(np.linalg.eigvalsh(info) > 0)
        ratio = np.sqrt(np.diag(np.linalg.inv(info)))[:2] / se_observed[:2]
        assert np.all((low < ratio) & (ratio < high)), (key, ratio)


def test_a_forward_hessian_whose_core_is_not_curved_is_taken_again_by_central_differences(record, monkeypatch):
    """The exact gradient carries its own rounding (the template's GLS); where a forward step's share of it makes
    the (f_h, xi_h) block of the Hessian lose its curvature (seen on lab records with a dense zero-drift basis: a
    diagonal of -858 forward, +961 central), the information is taken by central differences, which cancel it,
    instead of refusing the record. Central and forward differences agree where both are curved."""
    from smd_statespace.person import search

    model = build(record)
    params = fit_model(model, model.start_params(2.8, 0.3, -4.0), quick=True)["params"]
    steps, free = search._differencing(model, params)
    index = np.flatnonzero(free)
    forward = search._hessian(model, params, index, steps[index])
    central = search._hessian(model, params, index, steps[index], central=True)
    np.testing.assert_allclose(central[:2, :2], forward[:2, :2], rtol=0.02)
    expected = information(model, params, "oim")[0]
    original, calls = search._hessian, []

    def rounded(model_, params_, index_, steps_, threads=1, central=False):
        calls.append(central)
        hess = original(model_, params_, index_, steps_, threads, central)
        if not central:  # as if a forward step had met the gradient's rounding
            hess[1, 1] = -hess[1, 1]
        return hess

    monkeypatch.setattr(search, "_hessian", rounded)
    cov = information(model, params, "oim")[0]
    assert calls == [False, True]
    np.testing.assert_allclose(np.sqrt(np.diag(cov)[:2]), np.sqrt(np.diag(expected)[:2]), rtol=0.02)


def test_the_cycle_clustered_sandwich_uses_the_profiled_scores(record):
    """The efficient scores (delta and sigma^2 profiled out) sum to the gradient (the projections' terms sum to
    0 at the estimates of delta and sigma^2), and the cycle-clustered sandwich built from them agrees with the
    observed information on a record the model describes (ratio of the sds 0.7-2): built from the raw scores,
    which carry what the template absorbs, it came out 5-18 times the observed information's."""
    model = build(record)
    params = fit_model(model, model.start_params(2.8, 0.3, -4.0), quick=True)["params"]
    out = score(model, params)
    np.testing.assert_allclose(out["efficient_per_sample"].sum(axis=0), out["gradient"],
                               atol=1e-6 * np.abs(out["per_sample"]).sum())
    assert not np.allclose(out["efficient_per_sample"], out["per_sample"])
    se_observed = np.sqrt(np.diag(information(model, params, "oim")[0])[:2])
    se_sandwich = np.sqrt(np.diag(information(model, params, "robust")[0])[:2])
    ratio = se_sandwich / se_observed
    assert np.all((0.7 < ratio) & (ratio < 2.0)), ratio
    # the default takes the wider of the two for f_h and xi_h, and their correlation and the rest from the oim
    wider, observed = information(model, params, "oim_or_robust")[0], information(model, params, "oim")[0]
    np.testing.assert_allclose(np.sqrt(np.diag(wider)[:2]), np.maximum(se_observed, se_sandwich), rtol=1e-9)
    np.testing.assert_allclose(wider[2:, 2:], observed[2:, 2:], rtol=1e-12)
    np.testing.assert_allclose(wider[0, 1] / np.sqrt(wider[0, 0] * wider[1, 1]),
                               observed[0, 1] / np.sqrt(observed[0, 0] * observed[1, 1]), rtol=1e-9)


def test_a_broken_pass_gives_nan(record):
    model = build(record)
    params = point(model)
    fitted = dict(model.filter(params), loglike=-np.inf)
    out = score(model, params, fitted)
    assert out["loglike"] == -np.inf and np.all(np.isnan(out["gradient"]))


@pytest.mark.parametrize("name", ["independent", "phase_template", "smooth"])
def test_scoring_reaches_the_maximum_the_difference_search_reaches(record, name):
    """Fisher scoring with the exact gradient (fit_model's default) ends at the maximum L-BFGS-B with difference
    gradients finds from the same start (or higher), with a fraction of its passes, and it is a maximum. (The
    estimates themselves are not compared: where the difference search stops short of the maximum, e.g. xi_h
    0.23 sd away with a phase template on this 10 s record, scoring is the better answer.)"""
    from smd_statespace.person.search import fit_model

    model = CASES[name](record)
    start = model.start_params(2.6, 0.3, -3.0)
    scoring = fit_model(model, start)
    reference = fit_model(model, start, method="lbfgs-difference")
    assert scoring["converged"] and scoring["loglike"] >= reference["loglike"] - 1e-3
    assert scoring["n_evaluations"] < reference["n_evaluations"] / 3
    # a maximum: off the bounds, the gain a Newton step would still promise (g' I^-1 g / 2) is negligible
    out = score(model, scoring["params"])
    inside = np.array([not model.at_bound(scoring["params"], j) for j in range(len(model.param_names))])
    g, info = out["gradient"][inside], out["profile_information"][np.ix_(inside, inside)]
    assert 0.5 * g @ np.linalg.solve(info, g) < 1e-2


def test_a_looser_stop_rule_stops_sooner_near_the_same_maximum(record):
    """identify's first fits stop at a gain of 0.1 (fit.FIRST_GAIN): on the "smooth" model, whose scoring converges
    linearly (gains falling by about 0.6 a step), that takes fewer passes than the intermediate fits' rule and
    leaves less than 1 of log-likelihood on the way (a geometric tail of 0.1 x 0.6 / 0.4), never more than there."""
    from smd_statespace.person.fit import FIRST_GAIN
    from smd_statespace.person.search import fit_model

    model = CASES["smooth"](record)
    quick, first = fit_model(model, quick=True), fit_model(model, quick=FIRST_GAIN)
    assert first["n_evaluations"] < quick["n_evaluations"]
    assert quick["loglike"] - 1.0 < first["loglike"] <= quick["loglike"] + 1e-9


def test_a_scoring_search_that_runs_out_of_steps_is_finished_by_lbfgs(record, monkeypatch):
    """Scoring allowed one step only does not converge; fit_model then finishes with L-BFGS-B (exact gradient)
    from there and reaches the maximum scoring reaches with all its steps."""
    import functools

    from smd_statespace.person import search

    model = CASES["independent"](record)
    start = model.start_params(2.6, 0.3, -3.0)
    full = search.fit_model(model, start)
    monkeypatch.setattr(search, "_scoring", functools.partial(search._scoring, max_iterations=1))
    finished = search.fit_model(model, start)
    assert finished["converged"] and "then L-BFGS-B" in finished["message"]
    assert finished["loglike"] == pytest.approx(full["loglike"], abs=1e-2)


class _Bowl:
    """A stand-in model for ``search._stretched``: log-likelihood ``-|x - top|^2`` (unit scales)."""

    def __init__(self, top):
        self.top, self.scales, self.calls = np.asarray(top, dtype=float), np.ones(2), 0

    def filter(self, params):
        self.calls += 1
        return {"loglike": -float(np.sum((params - self.top) ** 2))}


@pytest.mark.parametrize("top, high, kept, tried", [
    ((0.5, 0.05), 1.0, (0.4, 0.04), 3),     # far along the step: 2x and 4x gain, 8x overshoots -> 4x kept
    ((0.12, 0.012), 1.0, (0.1, 0.01), 1),   # the step nearly reached it: 2x loses at once -> the step as taken
    ((5.0, 0.5), 0.3, (0.3, 0.08), 3),      # 4x and 8x would leave the bound: clipped to it, 8x kept
])
def test_a_step_is_stretched_while_the_likelihood_rises_and_no_farther(top, high, kept, tried):
    from smd_statespace.person.search import _stretched

    model = _Bowl(top)
    x, trial = np.zeros(2), np.array([0.1, 0.01])
    low, high = np.array([-1.0, -1.0]), np.array([high, 1.0])
    out, filtered, count = _stretched(model, x, trial, model.filter(trial), low, high)
    np.testing.assert_allclose(out, kept, atol=1e-12)
    assert filtered["loglike"] == pytest.approx(-np.sum((np.asarray(kept) - top) ** 2))
    assert count == tried == model.calls - 1


def test_scoring_along_a_ridge_is_stretched_to_the_same_maximum_with_fewer_derivative_passes(record, monkeypatch):
    """The "smooth" model with a phase template on the 10 s record: with its steps stretched the search ends at
    the maximum it reaches without (or higher), with fewer derivative passes."""
    from smd_statespace.person import score as score_module
    from smd_statespace.person import search

    model = build(record, variation="smooth", phase_template=TEMPLATE)
    start = model.start_params(3.3, 0.25, -3.0)
    passes = []
    counted = score_module.score

    def counting(*args, **kwargs):
        passes.append(1)
        return counted(*args, **kwargs)

    monkeypatch.setattr(score_module, "score", counting)
    stretched = search.fit_model(model, start)
    with_stretch, passes[:] = len(passes), []
    monkeypatch.setattr(search, "STRETCHES", 0)
    plain = search.fit_model(model, start)
    assert stretched["converged"] and stretched["loglike"] >= plain["loglike"] - 1e-3
    assert with_stretch < len(passes), (with_stretch, len(passes))

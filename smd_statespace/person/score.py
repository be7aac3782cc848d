"""Exact gradient of the record-level log-likelihood: the Kalman filter's forward sensitivity recursion.

:func:`score` returns the gradient of the profile log-likelihood of a
:class:`~smd_statespace.person.model.RecordModel`, the per-sample scores and
the expected information (conditional on the linear unknowns, and with them
profiled out), from one compiled pass that carries, next to the filter's
state mean and covariance, their derivatives with respect to every parameter
(Harvey 1989, *Forecasting, structural time series models and the Kalman
filter*, Sect. 3.4.5).

*Envelope theorem.* The profile log-likelihood is ``L(theta) = max over
delta, sigma^2 of l(theta, delta, sigma^2)`` with ``l = sum_k l_k``,
``l_k = -0.5 [log(2 pi sigma^2 f_k) + v_k^2 / (sigma^2 f_k)]``,
``v_k = e_k - Ev_k delta`` the innovation and ``f_k`` its variance
relative to ``sigma^2``. At the maximiser ``(delta_hat, sigma2_hat)``
(:meth:`RecordModel.filter`) ``dL/dtheta = dl/dtheta`` at fixed
``delta = delta_hat`` and ``sigma^2 = sigma2_hat``; the ``dl_k/dtheta``
are the per-sample scores (their sum the gradient), the quantities
:func:`~smd_statespace.person.search._cluster_scores` builds by central
differences of :meth:`RecordModel.sample_loglike`.

*The recursion* (the filter at fixed ``delta`` and its forward derivatives, one compiled
pass) is :func:`~smd_statespace.person.sensitivity.sensitivity_pass`; its module
describes it.

(Koopman & Shephard 1992, *Biometrika* 79, 823-826, give the exact score
from one smoothing pass, whose cost does not grow with the number of
parameters; it needs the derivatives of the system arrays all the same
and the smoother of the augmented filter, and is not used here.)

*Derivatives of the system arrays* (:func:`system_derivatives`). The log
variance ratios enter as ``exp``: the derivative of ``D``, ``E``, the drift
and the process noise ``Qx`` is the value itself on the entries the
parameter sets. ``log_smooth_time`` enters through the
Matern-3/2 step (:func:`~smd_statespace.person.system.matern32_step`),
differentiated in closed form. ``f_h``, ``xi_h`` and the effects'
parameters change the dynamics (``Phi``, ``Gam``, ``offset``, ``X_tr``,
``hx``, ``y_known``, ``Qx``): with linear dynamics (the person, a floor
mode) through the discretisation (the Van Loan block exponential for
``Phi`` and ``W``, the harmonic gains' derivative; only the small
continuous ``A, b`` are differenced), else (a path-linearised effect)
by forward differences of :meth:`RecordModel.system` with a relative
step of :data:`FORWARD_STEP`: one more system per parameter, where
central differences (``method="difference"``, a step of
:data:`DYNAMICS_STEP`) take two, as accurate as they (below). The
analytic arrays are 100-1000 times closer to a Richardson extrapolation
than the differenced ones, and cheaper (3.0 against 4.9 ms below).

*Information.* :func:`score` gives Harvey's expected information at fixed
``delta`` and ``sigma^2`` (``expected_information``) and with them as nuisance
parameters (``profile_information``: the Schur complement, with
``d v / d delta = -Ev``, the augmented filter's regression). The first
is *not* usable for ``f_h`` and ``xi_h``: the template absorbs much of a
change of the dynamics, and it gives standard errors 0.1-0.2 times those
of the observed information (the Hessian of
:func:`~smd_statespace.person.search.information`). The second agrees with
the observed information: ratios of the ``f_h``, ``xi_h`` standard
errors 0.98, 0.94 on the fitted sample record (``data/sample.csv``,
"independent"), 0.84-1.06 on six simulated 12 s records, 0.75-1.16 with
variation "smooth".

*Cost* (``benchmarks/person_score.py``: 30 s at 100 Hz, variation
"independent" with a phase template and the offset, 9 parameters, one
thread, fastest of 7 runs on a shared two-core machine). ``model.loglike``
3.9 ms (``system`` 1.0, the compiled pass 2.2); :func:`score` 19 ms (5 likelihoods: ``filter`` 3.9, ``system`` 1.0,
:func:`system_derivatives` 3.0, :func:`sensitivity_pass` 10.5),
against 37 ms for the ``k + 1`` likelihoods of L-BFGS-B's forward
differences and 66 ms for ``2 k`` central ones: about half and a third.
The pass costs 1.4 ms for the filter itself, then about 0.8 ms per
variance parameter and 1.4 ms per dynamics parameter, against 2.2 +
1.7 ms per likelihood evaluation, so the saving grows slowly with the
parameters. Where it counts most (and where
:mod:`~smd_statespace.person.fit` uses it): the search, by Fisher scoring
with the exact gradient and ``profile_information`` (a handful of passes per
search where L-BFGS-B with differences needed hundreds of likelihoods); the
per-sample (per-cycle) scores of the robust covariance (exact, one pass;
73 ms by central differences before); the observed information (central
differences of the exact gradient, ``2 k`` passes; the numerical Hessian of
the likelihood took ``2 k^2`` likelihoods, 610 ms).
"""

from __future__ import annotations

import math

import numpy as np

from .model import RecordModel
from .sensitivity import sensitivity_pass
from .system import contiguous
from .threads import spare_halves

__all__ = ["DYNAMICS_STEP", "FORWARD_STEP", "SPLIT_FROM", "cycle_sums", "profile_out", "score", "system_derivatives",
           "sensitivity_pass", "sensitivities"]

DYNAMICS_STEP = 1e-6
"""Relative step of the central differences of :meth:`RecordModel.system` in ``f_h``, ``xi_h`` and the effects'
parameters (times ``max(|value|, scale)``, ``scale`` from :attr:`RecordModel.scales`)."""

FORWARD_STEP = 5e-6
"""Relative step of the forward differences of :meth:`RecordModel.system` that a path-linearised effect's
derivatives take by default (as :data:`DYNAMICS_STEP`).

A path-linearised system carries the rounding of its own differenced Jacobian (about 1e-10 of its size), so
the central differences at :data:`DYNAMICS_STEP` are rounding-bound, not truncation-bound: on a fitted person
with a ``v|v|`` term (hidden-harmonics record, 30 s at 100 Hz), against a Richardson extrapolation of central
differences at 1e-3 and 5e-4, the largest error of an array relative to its size was 3-9e-6 for central
differences at 1e-6 and 2-6e-6 for forward differences at 3e-6 to 1e-5 (2-3e-6 at this step; 1-2e-5 at
1e-6), in ``f_h``, ``xi_h`` and the term's coefficient. So half the systems, the same accuracy."""


# ------------------------------------------------------------------------------------ system derivatives
DYNAMIC_ARRAYS = ("hx", "Phi", "Gam", "offset", "X_tr", "y_known", "Qx")
"""Arrays of :meth:`RecordModel.system` that change with the person's (and the effects') dynamics."""


def _matern32_derivatives(length_scale, dt):
    """Derivatives of :func:`~smd_statespace.person.system.matern32_step`'s ``(Phi, Q, P_inf)`` w.r.t. ``log ell``.

    ``lambda = sqrt(3) / ell``, so ``d lambda / d log ell = -lambda``;
    ``Phi = exp(-lambda dt) [[1 + lambda dt, dt], [-lambda^2 dt, 1 - lambda dt]]``,
    ``P_inf = diag(1, lambda^2)``, ``Q = P_inf - Phi P_inf Phi'``.
    """
    lam = np.sqrt(3.0) / float(length_scale)
    decay = np.exp(-lam * dt)
    phi = decay * np.array([[1.0 + lam * dt, dt], [-lam * lam * dt, 1.0 - lam * dt]])
    dphi_dlam = -dt * phi + decay * np.array([[dt, 0.0], [-2.0 * lam * dt, -dt]])
    p_inf = np.diag([1.0, lam * lam])
    dp_dlam = np.diag([0.0, 2.0 * lam])
    dq_dlam = dp_dlam - dphi_dlam @ p_inf @ phi.T - phi @ dp_dlam @ phi.T - phi @ p_inf @ dphi_dlam.T
    dq_dlam = 0.5 * (dq_dlam + dq_dlam.T)
    return -lam * dphi_dlam, -lam * dq_dlam, -lam * dp_dlam


def _linearise(model: RecordModel, params):
    """``model.dynamics.linearise`` at ``params``, as :meth:`RecordModel.system` calls it."""
    named = model.unpack(params)
    return model.dynamics.linearise(named["f_h"], named["xi_h"],
                                    {name: named[name] for name in model.effect_parameters}, model.nominal)


class _Discretisation:
    """The parts of :meth:`RecordModel.system` that linear dynamics' derivatives are built from, at one point.

    ``lin`` (the continuous ``A, b, c, h_x, d``), ``integral`` (``W``,
    shape (1, n_x, n_x)), the harmonic gains' matrices ``lhs = j nu I - A``
    (J, n_h, n_x, n_x), ``gains`` (J, n_h, n_x) and the inputs' rotation
    ``exp(j nu dt) I - Phi``.
    """

    def __init__(self, model: RecordModel, params):
        from .discretisation import exponentials, harmonic_gains

        self.lin = lin = _linearise(model, params)
        dt = model.dt
        self.phi, self.integral = exponentials(lin.A, dt)
        orders = np.arange(1, model.n_harmonics + 1)
        nu = model.timing_rates()[:, None] * orders  # (J, n_h)
        eye = np.eye(lin.A.shape[-1])
        self.gains = harmonic_gains(lin.A, self.phi, lin.b, nu, dt)  # (J, n_h, n_x)
        self.lhs = 1j * nu[..., None, None] * eye - lin.A[:, None]
        self.turn = np.exp(1j * nu * dt)[..., None, None] * eye - self.phi[:, None]


def _dynamics_derivative(model: RecordModel, params, j, h, base: _Discretisation, rate) -> dict:
    """Derivatives of the dynamics' arrays of :meth:`RecordModel.system` w.r.t. parameter ``j``, linear dynamics.

    The continuous ``A, b, c, h_x, d`` of the dynamics are differenced
    centrally (step ``h``: small arrays); the rest is differentiated
    through :meth:`RecordModel.system`'s own construction:

    - ``Phi = exp(A dt)``, ``W = int_0^dt exp(A s) ds``: the derivative of
      ``exp(M)``, ``M = [[A dt, I dt], [0, 0]]``, in the direction ``dM`` is
      the upper right block of ``exp([[M, dM], [0, M]])`` (Van Loan 1978,
      *IEEE Trans. Automat. Control* 23, 395-404);
    - the harmonic gains ``g = L^-1 r``, ``L = j nu I - A``,
      ``r = (exp(j nu dt) I - Phi) b``:
      ``dg = L^-1 (dA g - dPhi b + (exp(j nu dt) I - Phi) db)``;
    - the constant force's ``g0 = W b``, the phase template's columns, the
      regressors' steps and the offset ``W c`` by the product rule;
    - the process noise (``rate`` times two small matrix exponentials) by
      central differences.
    """
    from ..io import G
    from .discretisation import expm_stack
    from .system import integrated_white_noise, regressor_steps, step_mean

    up, down = params.copy(), params.copy()
    up[j] += h
    down[j] -= h
    lin, plus, minus = base.lin, _linearise(model, up), _linearise(model, down)

    def diff(name):  # an effect's known term is None where it is zero (a gain of 0): its derivative need not be
        a, b = getattr(plus, name), getattr(minus, name)
        if a is None and b is None:
            return None
        a = np.zeros_like(b) if a is None else a
        return (a - (np.zeros_like(a) if b is None else b)) / (2.0 * h)

    A, b, dA, db = lin.A, lin.b, diff("A"), diff("b")
    n = A.shape[-1]
    dt = model.dt
    block = np.zeros((1, 4 * n, 4 * n))
    for at in (0, 2 * n):
        block[0, at:at + n, at:at + n] = A[0] * dt
        block[0, at:at + n, at + n:at + 2 * n] = np.eye(n) * dt
    block[0, :n, 2 * n:3 * n] = dA[0] * dt
    e = expm_stack(block)
    d_phi, d_integral = e[:, :n, 2 * n:3 * n], e[:, :n, 3 * n:]
    integral = base.integral
    d_g0 = np.einsum("kij,kj->ki", d_integral, b) + np.einsum("kij,kj->ki", integral, db)
    rhs = (dA[:, None] @ base.gains[..., None])[..., 0] - (d_phi[:, None] @ b[:, None, :, None])[..., 0] + (
        base.turn @ db[:, None, :, None])[..., 0]
    d_gains = np.linalg.solve(base.lhs, rhs[..., None])[..., 0]  # (J, n_h, n_x)
    per_sample = d_gains[model._phase[0]] * model._rotation[..., None]
    N = model.time.size
    gam = np.empty((N, n, model.n_coefficients))
    gam[:, :, 0] = d_g0
    gam[:, :, 1::2] = per_sample.real.transpose(0, 2, 1)
    gam[:, :, 2::2] = per_sample.imag.transpose(0, 2, 1)
    gam *= G
    if model._timing_columns is not None:
        gam = np.concatenate([gam, d_g0[:, :, None] * model._timing_columns[1][:, None, :]], axis=2)
    d_qx = np.zeros((n, n)) if rate == 0 else rate * (
        integrated_white_noise(plus.A.mean(axis=0), plus.b.mean(axis=0), dt)
        - integrated_white_noise(minus.A.mean(axis=0), minus.b.mean(axis=0), dt)) / (2.0 * h)
    dynamic = np.array([r.dynamic for r in model.all_regressors], dtype=bool)
    d_c, d_d = diff("c"), diff("d")
    d_offset = np.zeros((N, n))
    if lin.c is not None:
        d_offset += np.einsum("kij,kj->ki", d_integral, step_mean(lin.c))
    if d_c is not None:
        d_offset += np.einsum("kij,kj->ki", integral, step_mean(d_c))
    return {"hx": diff("hx"), "Phi": d_phi, "Gam": gam, "offset": d_offset,
            "X_tr": regressor_steps(d_g0, model._X * dynamic),
            "y_known": np.zeros(N) if d_d is None else d_d, "Qx": d_qx}


def _variance_entries(model: RecordModel, j):
    """Which of ``D``, ``E``, the drift (per force state) and the process noise parameter ``j`` (a log variance)
    sets: ``(which, mask)``, from :attr:`RecordModel._variance_index` (the one map :meth:`RecordModel._variances`
    fills them by)."""
    index = model._variance_index
    if index["log_var_w"] == j:
        return "w", np.zeros(model.n_force_states, dtype=bool)
    for kind, which in (("log_var_d", "D"), ("log_var_e", "E"), ("log_var_s", "drift")):
        if index[kind] is not None and np.any(index[kind] == j):
            return which, index[kind] == j
    raise ValueError(f"parameter {model.param_names[j]!r} is no log variance of the model")


def system_derivatives(model: RecordModel, params, system=None, step=None, method="auto") -> dict:
    """Derivatives of the arrays of :meth:`RecordModel.system` with respect to every parameter.

    Parameters
    ----------
    model : RecordModel
    params : ndarray, shape (k,)
    system : dict, optional
        ``model.system(params)`` when already made.
    step : float, optional
        Relative step of the differences in the dynamics' parameters (times
        ``max(|value|, scale)``, ``scale`` from :attr:`RecordModel.scales`);
        default :data:`DYNAMICS_STEP` (central), :data:`FORWARD_STEP` (forward).
    method : {"auto", "analytic", "difference", "forward"}
        How the arrays that ``f_h``, ``xi_h`` and the effects' parameters
        change are differentiated: ``"difference"``, central differences of
        :meth:`RecordModel.system` (two calls per parameter; any dynamics);
        ``"forward"``, forward differences from ``system`` (one call per
        parameter; any dynamics); ``"analytic"``, through the discretisation
        (:func:`_dynamics_derivative`: only the small continuous ``A, b, c,
        h_x, d`` are differenced; linear dynamics only); ``"auto"``
        (default), analytic when the dynamics are linear, else forward.
        Measured against Richardson-extrapolated differences: the analytic
        ``Gam`` is within 1e-9 (the person) to 1e-7 (a floor mode's damping)
        of the arrays' size, the central differences within 1e-7 to 1e-4,
        the forward ones on a path-linearised effect as close as the central
        ones (:data:`FORWARD_STEP`).

    Returns
    -------
    dict
        ``dyn`` (k,) int: each parameter's index in the stacks of the
        dynamics' derivatives (-1: not a dynamics parameter); those stacks
        ``d_hx``, ``d_Phi``, ``d_Gam``, ``d_offset``, ``d_X_tr`` and ``d_y``
        (the derivative of ``-y_known``); and for every parameter ``d_Qx``
        (k, n_x, n_x), ``d_D``, ``d_E``, ``d_drift`` (k, p), ``d_sphi``,
        ``d_sq``, ``d_sp0`` (k, 2, 2).
    """
    params = np.asarray(params, dtype=float)
    if method not in ("auto", "analytic", "difference", "forward"):
        raise ValueError(f"method {method!r} is not one of: auto, analytic, difference, forward")
    if method == "analytic" and not model.dynamics.linear:
        raise ValueError("analytic derivatives of the system need linear dynamics (a path-linearised effect: "
                         "use method='forward' or 'difference')")
    analytic = method == "analytic" or (method == "auto" and model.dynamics.linear)
    central = method == "difference"
    if step is None:
        step = DYNAMICS_STEP if central or analytic else FORWARD_STEP
    sys = model.system(params) if system is None else system
    names = model.param_names
    k = len(names)
    dynamic = ["f_h", "xi_h"] + list(model.effect_parameters)
    dyn = np.full(k, -1, dtype=np.int64)
    stacks = {name: [] for name in DYNAMIC_ARRAYS}
    p = sys.D.size
    nx = model.n_dynamic
    out = {"d_Qx": np.zeros((k, nx, nx)), "d_D": np.zeros((k, p)), "d_E": np.zeros((k, p)),
           "d_drift": np.zeros((k, p)), "d_sphi": np.zeros((k, 2, 2)), "d_sq": np.zeros((k, 2, 2)),
           "d_sp0": np.zeros((k, 2, 2))}
    scales = model.scales
    values = {"D": sys.D, "E": sys.E, "drift": sys.drift}
    rate = float(np.exp(params[names.index("log_var_w")])) if "log_var_w" in names else 0.0
    base = _Discretisation(model, params) if analytic and any(name in dynamic for name in names) else None
    for j, name in enumerate(names):
        if name in dynamic:
            h = step * max(abs(params[j]), scales[j])
            if analytic:
                derivative = _dynamics_derivative(model, params, j, h, base, rate)
                for key in DYNAMIC_ARRAYS:
                    stacks[key].append(derivative[key])
            else:  # central: (system(p + h) - system(p - h)) / 2h; forward: (system(p + h) - system(p)) / h
                up, down = params.copy(), params.copy()
                up[j] += h
                down[j] -= h if central else 0.0
                plus, minus = model.system(up), (model.system(down) if central else sys)
                for key in DYNAMIC_ARRAYS:
                    stacks[key].append((getattr(plus, key) - getattr(minus, key)) / ((2.0 if central else 1.0) * h))
            out["d_Qx"][j] = stacks["Qx"][-1]
            dyn[j] = len(stacks["hx"]) - 1
        elif name == "log_smooth_time":
            out["d_sphi"][j], out["d_sq"][j], out["d_sp0"][j] = _matern32_derivatives(np.exp(params[j]), model.dt)
        elif name.startswith("log_var_"):  # exp(log variance): the derivative is the value where it enters
            which, mask = _variance_entries(model, j)
            if which == "w":
                out["d_Qx"][j] = sys.Qx
            else:
                out[f"d_{which}"][j] = np.where(mask, values[which], 0.0)
        else:
            raise ValueError(f"no derivative of the system arrays with respect to {name!r}")
    n_dyn = len(stacks["hx"])
    K = sys.Phi.shape[0]
    N = model.time.size
    r = sys.X_tr.shape[2]

    def stack(key, shape):
        return np.ascontiguousarray(np.array(stacks[key])) if n_dyn else np.zeros((0,) + shape)

    out.update(dyn=dyn, d_hx=stack("hx", (K, nx)), d_Phi=stack("Phi", (K, nx, nx)),
               d_Gam=stack("Gam", (N, nx, p)), d_offset=stack("offset", (N, nx)),
               d_X_tr=stack("X_tr", (N, nx, r)), d_y=-stack("y_known", (N,)))
    return out


# ------------------------------------------------------------------------------------------------ score
def score(model: RecordModel, params, fitted=None, method="auto", derivatives=None) -> dict:
    """Exact gradient of the profile log-likelihood, per-sample scores and the expected information.

    One compiled pass of the Kalman filter at the estimated ``delta`` and
    ``sigma^2`` with the forward derivatives of its mean and covariance
    (the module's docstring; Harvey 1989, Sect. 3.4.5). By the envelope
    theorem the derivatives at fixed ``delta``, ``sigma^2`` are those of the
    profile log-likelihood :meth:`RecordModel.loglike`.

    Parameters
    ----------
    model : RecordModel
    params : ndarray, shape (k,)
        Parameters in the order of :attr:`RecordModel.param_names`.
    fitted : dict, optional
        ``model.filter(params)`` when already made (its ``delta``, ``sigma2``, ``loglike``,
        ``innovation_regression``, ``delta_cov_unscaled``).
    method : {"auto", "analytic", "difference", "forward"}
        How the dynamics' arrays are differentiated (:func:`system_derivatives`).
    derivatives : dict, optional
        The arrays' derivatives, as :func:`system_derivatives` returns them, when made otherwise: their
        parameters, ``k`` of them, need not be ``model``'s (the directions of
        :func:`~smd_statespace.person.breaks.step_scan`, a step at every sample); every output's ``k`` is theirs.

    Returns
    -------
    dict
        ``loglike`` (float): the profile log-likelihood;
        ``sample_loglike`` (N,): the per-sample log-densities at fixed
        ``delta``, ``sigma^2`` (:meth:`RecordModel.sample_loglike`; their sum
        is ``loglike``);
        ``gradient`` (k,): ``d loglike / d params``;
        ``per_sample`` (N, k): the per-sample scores (sum over samples: the gradient);
        ``efficient_per_sample`` (N, k): the same with ``delta`` and ``sigma^2``
        profiled out, ``s_theta - I_td I_dd^-1 s_delta - I_ts I_ss^-1 s_sigma``
        with ``s_delta = v Ev / (sigma^2 f)``, the scores a sandwich of the
        profile likelihood's information needs (the raw ones carry what the
        template absorbs: summed per cycle they gave f_h variances 4-700 times
        too large);
        ``expected_information`` (k, k): Harvey's (1989, Sect. 3.4.5) expected information
        ``sum_k [0.5 df_i df_j / f^2 + dv_i dv_j / (sigma^2 f)]`` from the
        derivatives of the innovations ``v`` and of their variances
        ``sigma^2 f``. It is *conditional* on ``delta`` and ``sigma^2``
        (held at their estimates, not profiled out): it ignores the
        information the parameters share with the template, the initial
        state, the regressors and the scale, so it is not the information of
        the profile likelihood and *not usable as the observed information*:
        on fitted records its standard errors of ``f_h`` and ``xi_h`` are
        0.1-0.2 times those of the observed information (the numerical
        Hessian of :func:`~smd_statespace.person.search.information`);
        ``profile_information`` (k, k): the same expected information of
        ``(theta, delta, sigma^2)`` with ``delta`` and ``sigma^2`` as
        nuisance parameters, ``I_tt - I_td I_dd^-1 I_dt - I_ts I_ss^-1 I_st``
        (``d v / d delta = -Ev``, ``I_dd = S / sigma^2``, ``I_ss = N / (2 sigma^4)``):
        its ``f_h``, ``xi_h`` standard errors are within about 15-25 % of the
        observed information's (0.98 and 0.94 on the fitted sample record);
        ``innovations`` (N,), ``variances`` (N,) (``sigma^2 f``),
        ``d_innovations`` (N, k), ``d_log_variances`` (N, k) (derivatives of
        ``v`` and of ``log f``); ``delta``, ``sigma2``.
    """
    params = np.asarray(params, dtype=float)
    fitted = model.filter(params) if fitted is None else fitted
    sys = model.system(params)
    k = params.size if derivatives is None else derivatives["dyn"].size
    N = model.time.size
    if not np.isfinite(fitted["loglike"]):
        nan = np.full(k, np.nan)
        return {"loglike": fitted["loglike"], "sample_loglike": np.full(N, np.nan), "gradient": nan,
                "per_sample": np.full((N, k), np.nan), "efficient_per_sample": np.full((N, k), np.nan),
                "expected_information": np.full((k, k), np.nan),
                "profile_information": np.full((k, k), np.nan),
                "innovations": np.full(N, np.nan), "variances": np.full(N, np.nan),
                "d_innovations": np.full((N, k), np.nan), "d_log_variances": np.full((N, k), np.nan),
                "delta": fitted["delta"], "sigma2": fitted["sigma2"]}
    der = system_derivatives(model, params, sys, method=method) if derivatives is None else derivatives
    delta, sigma2 = np.asarray(fitted["delta"], dtype=float), float(fitted["sigma2"])
    v, f, dv, df = sensitivities(sys.pass_arguments(model.y, model.n_coefficients), delta, der)
    variance = sigma2 * f
    standard2 = v**2 / variance
    observed, n_obs = model.observed, model.n_observed  # a missing sample adds nothing (v, dv, df are 0 there)
    with np.errstate(invalid="ignore", divide="ignore"):  # a pass that broke down (variances <= 0 where a search
        # tried unstable dynamics) gives NaN here, and the search steps back (search.fit_model)
        sample = np.where(observed, -0.5 * (np.log(2.0 * math.pi * variance) + standard2), 0.0)
    relative = df / f[:, None]  # d log f
    per_sample = -0.5 * (relative * (1.0 - standard2)[:, None]) - (v / variance)[:, None] * dv
    weighted = dv / variance[:, None]
    info = 0.5 * relative.T @ relative + weighted.T @ dv
    info = 0.5 * (info + info.T)
    # delta and sigma^2 as nuisance parameters: d v / d delta = -Ev, d log(sigma^2 f) / d sigma^2 = 1 / sigma^2
    cross = -weighted.T @ fitted["innovation_regression"]  # (k, q)
    total = relative.sum(axis=0)
    profile = info - cross @ (sigma2 * fitted["delta_cov_unscaled"]) @ cross.T - 0.5 * np.outer(total, total) / n_obs
    # the per-sample scores with delta and sigma^2 profiled out (the efficient scores): what is left of each
    # parameter's score once the template, initial state and scale have taken their share (sandwich covariances)
    delta_scores = (v / variance)[:, None] * fitted["innovation_regression"]
    efficient = (per_sample - delta_scores @ (sigma2 * fitted["delta_cov_unscaled"]) @ cross.T
                 + 0.5 * np.outer(np.where(observed, 1.0 - standard2, 0.0), total) / n_obs)
    return {"loglike": float(fitted["loglike"]), "sample_loglike": sample, "gradient": per_sample.sum(axis=0),
            "per_sample": per_sample, "efficient_per_sample": efficient, "expected_information": info,
            "profile_information": 0.5 * (profile + profile.T),
            "innovations": v, "variances": variance, "d_innovations": dv, "d_log_variances": relative,
            "delta": delta, "sigma2": sigma2}


SPLIT_FROM = 4
"""Parameters a derivative pass must have to split them with an idle thread (:func:`sensitivities`): half a pass
costs about 0.6 of a whole one (the filter itself is in both halves)."""

_PER_PARAMETER = ("dyn", "d_Qx", "d_D", "d_E", "d_drift", "d_sphi", "d_sq", "d_sp0")
"""The derivative arrays with one entry per parameter (first axis); the others are per dynamic parameter, indexed
through ``dyn``."""


def sensitivities(arguments, delta, der) -> tuple:
    """``(v, f, dv, df)`` of :func:`~smd_statespace.person.sensitivity.sensitivity_pass` with the system's
    ``arguments`` (``SystemArrays.pass_arguments``) and derivatives ``der`` (:func:`system_derivatives`).

    Where one of the record's threads is idle (:func:`~smd_statespace.person.threads.spare_halves`) and there are
    :data:`SPLIT_FROM` parameters or more, the second half of the parameters' derivatives is computed in that
    thread while this one computes the first: every column is computed as in one pass, so the numbers are the same
    to the last bit (tested), whichever way it ran.
    """
    def run(columns):
        chosen = der if columns is None else {**der, **{key: der[key][columns] for key in _PER_PARAMETER}}
        return sensitivity_pass(*arguments, *contiguous(
            delta, chosen["dyn"], chosen["d_hx"], chosen["d_Phi"], chosen["d_Gam"], chosen["d_offset"],
            chosen["d_X_tr"], chosen["d_y"], chosen["d_Qx"], chosen["d_D"], chosen["d_E"], chosen["d_drift"],
            chosen["d_sphi"], chosen["d_sq"], chosen["d_sp0"]))

    k = der["dyn"].size
    halves = None if k < SPLIT_FROM else spare_halves(lambda: run(np.arange(k // 2)), lambda: run(np.arange(k // 2, k)))
    if halves is None:
        return run(None)
    here, there = halves
    return here[0], here[1], np.hstack([here[2], there[2]]), np.hstack([here[3], there[3]])


def cycle_sums(model: RecordModel, per_sample) -> np.ndarray:
    """Sums of per-sample scores ``per_sample`` (shape (N, ...)) over each force cycle of ``model``: the clusters
    of the cycle-robust statistics (the sandwich of :mod:`~smd_statespace.person.search`, the robust score test of
    :mod:`~smd_statespace.person.screen`), shape (J, ...)."""
    per_sample = np.asarray(per_sample, dtype=float)
    cycle = model._phase[0]
    out = np.zeros((cycle.max() + 1,) + per_sample.shape[1:])
    np.add.at(out, cycle, per_sample)
    return out


def profile_out(info, scores, keep, nuisance, floor: float) -> tuple:
    """Effective information and scores of the parameters ``keep`` with those in ``nuisance`` profiled out.

    ``I* = I_kk - I_kn I_nn^-1 I_nk`` and ``s* = s_k - I_kn I_nn^-1 s_n`` (``scores``: rows of per-sample or
    per-cycle scores, columns as ``info``'s), the inverse of ``I_nn`` with its eigenvalues floored at ``floor``
    times the largest. Returns ``(I*, s*)``.
    """
    keep, nuisance = list(keep), list(nuisance)
    if not nuisance:
        return info[np.ix_(keep, keep)], scores[:, keep]
    w, v = np.linalg.eigh(info[np.ix_(nuisance, nuisance)])
    w = np.maximum(w, w.max() * floor)
    coupling = info[np.ix_(keep, nuisance)] @ ((v / w) @ v.T)
    return (info[np.ix_(keep, keep)] - coupling @ info[np.ix_(nuisance, keep)],
            scores[:, keep] - scores[:, nuisance] @ coupling.T)

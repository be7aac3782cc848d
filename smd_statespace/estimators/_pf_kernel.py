"""Compiled (numba) pass of the bootstrap particle filter on the base SMD model.

One call filters a whole cycle: for every sample it moves each particle
(RK4 or Euler on ``u``, ``u'``; parameters are random walks, Eq. 6 and
11-12), adds process noise, reflects the parameters into their prior box,
weights the particle by its observation likelihood (Eq. 13-16) and
resamples systematically when the effective sample size drops. It does
exactly what :meth:`ParticleFilter._run_numpy` does and draws the same
normal variates in the same order: the filter's generator is numpy's SFC64,
whose few lines and whose ziggurat normal sampler are inlined here (with
numpy's own tables, :mod:`._ziggurat`), bit for bit, and the generator's
state is handed back to numpy after the pass. The two paths therefore agree
to rounding (``tests/test_performance.py``).

How it is fast (docs/performance.md has the measurements): inside the pass
the cloud is laid out slot by slot (``(n_state, N)``, one contiguous row per
slot) and processed in blocks of :data:`~._pf_numba.BLOCK` particles, so that
a block is moved, jittered, reflected and weighed while it is in the core's
cache, by loops the compiler vectorises; the generator's state stays in
registers; the exponentials of the weights and the systematic resampling are
written without a libm call or a branch per particle.

Only the base model (``SMDModel`` itself, no effects) is compiled; any other
model goes through the numpy path, which calls the model's own methods.

The Fourier force ``g * sum_j c_j * basis_j(t)`` (Eq. 4) needs the basis at a
handful of times per sample; those rows are computed once per pass with
:meth:`~smd_statespace.model.SMDModel.fourier_basis` and handed in.
"""

from __future__ import annotations

import numpy as np

_COMPILED = {}


def kernel():
    """The compiled pass (compiled on first use, cached on disk by numba)."""
    if not _COMPILED:
        _COMPILED.update(_compile())
    return _COMPILED["run_pass"]


def normal_filler():
    """The compiled ``fill_normal_transposed(state, out)``: the pass's normal sampler alone (for profiles)."""
    kernel()
    return _COMPILED["fill_normal_transposed"]


def available() -> bool:
    """Whether numba can be imported."""
    try:
        import numba  # noqa: F401
    except ImportError:  # pragma: no cover - numba is a dependency
        return False
    return True


def _compile():
    from . import _pf_numba

    return {"run_pass": _pf_numba.run_pass, "fill_normal_transposed": _pf_numba.fill_normal_transposed}


def force_rows(model, data, substeps: int, rk4: bool):
    """Fourier basis rows times g (Eq. 4) at every time the pass needs.

    Returns ``(steps, move_basis, obs_basis)``: ``steps[k]`` the integration step
    from sample ``k - 1`` to ``k`` (``h = dt / substeps``); ``move_basis[k, s]``
    the rows at the stage times of substep ``s`` (``t``, ``t + h/2``, ``t + h``);
    ``obs_basis[k]`` the row at ``t_k``.
    """
    from ..io import G

    t = np.asarray(data.t, dtype=float)
    m = len(t)
    steps = np.zeros(m)
    steps[1:] = (t[1:] - t[:-1]) / substeps
    times = np.zeros((m, substeps, 3))
    starts = t[:-1, None] + np.arange(substeps) * steps[1:, None]  # t_{k-1} + s h
    times[1:] = starts[..., None] + np.array([0.0, 0.5, 1.0]) * steps[1:, None, None]
    move_basis = G * model.fourier_basis(times, data.inputs)
    obs_basis = G * model.fourier_basis(t, data.inputs)
    return steps, np.ascontiguousarray(move_basis), np.ascontiguousarray(obs_basis)

"""The numba code of the compiled particle-filter pass (imported only when a pass needs it).

Module-level functions, so that numba's on-disk cache serves every process
(a worker of a process pool or a Dask cluster loads the machine code instead
of compiling it again). See :mod:`._pf_kernel` for what the pass does.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba.np.random._constants import fi_double, ki_double, wi_double, ziggurat_nor_inv_r, ziggurat_nor_r

TWO_PI = 2.0 * math.pi


u64 = np.uint64
S1, S3, S8, S11, S24, S40 = u64(1), u64(3), u64(8), u64(11), u64(24), u64(40)
LOW8, MANTISSA = u64(0xFF), u64(0x000FFFFFFFFFFFFF)


@numba.njit(inline="always")
def next_uint64(s):
    """SFC64 (numpy's ``SFC64`` bit generator, state ``s`` of 4 words, advanced in place)."""
    out = s[0] + s[1] + s[3]
    s[3] += S1
    s[0] = s[1] ^ (s[1] >> S11)
    s[1] = s[2] + (s[2] << S3)
    s[2] = ((s[2] << S24) | (s[2] >> S40)) + out
    return out


@numba.njit(inline="always")
def next_double(s):
    """Uniform on [0, 1) as numpy's ``Generator.random``."""
    return np.int64(next_uint64(s) >> S11) * (1.0 / 9007199254740992.0)


@numba.njit(inline="always")
def standard_normal(s):
    """numpy's ziggurat ``Generator.standard_normal`` (the same tables, hence the same numbers)."""
    while True:
        bits = next_uint64(s)
        idx = np.intp(bits & LOW8)
        bits >>= S8
        rabs = (bits >> S1) & MANTISSA
        x = np.int64(rabs) * wi_double[idx]
        sign = 1.0 - 2.0 * np.float64(np.int64(bits & S1))  # +-1 without a branch (one in two would mispredict)
        if rabs < ki_double[idx]:
            return x * sign
        x = x * sign
        if idx == 0:
            while True:
                xx = -ziggurat_nor_inv_r * math.log1p(-next_double(s))
                yy = -math.log1p(-next_double(s))
                if yy + yy > xx * xx:
                    if (rabs >> S8) & S1:
                        return -(ziggurat_nor_r + xx)
                    return ziggurat_nor_r + xx
        elif (fi_double[idx - 1] - fi_double[idx]) * next_double(s) + fi_double[idx] < math.exp(-0.5 * x * x):
            return x


@numba.njit(cache=True, nogil=True, error_model="numpy")
def run_pass(particles, log_weights, y, steps, move_basis, obs_basis, c0, rk4, full, noisy, q, bounded, low,
             high, r, ess_threshold, state, mean, std, innovations, innovation_cov, ess):
    """Filter one pass in place; returns (status, sample, log_likelihood, resamples, particles, log_weights).

    ``state`` is the SFC64 state of the filter's generator, advanced in place
    exactly as numpy would. status 0: done; 1: every weight vanished at ``sample``.
    """
    n, d = particles.shape
    m, n_obs = y.shape
    nb = obs_basis.shape[1]
    substeps = move_basis.shape[1]
    log_norm = -0.5 * n_obs * math.log(TWO_PI)
    for c in range(n_obs):
        log_norm -= math.log(r[c])
    predicted = np.empty((n, n_obs))
    weights = np.empty(n)
    for i in range(n):
        weights[i] = math.exp(log_weights[i])
    spare = np.empty_like(particles)
    cumulative = np.empty(n)
    accumulator = np.empty(d)
    total_log_likelihood = 0.0
    resamples = 0
    for k in range(m):
        mean_u = mean_v = mean_acc = 0.0
        # Predict every particle (Eq. 11-12 plus noise, Eq. 6), then its observation (Eq. 13-16).
        for i in range(n):
            u = particles[i, 0]
            v = particles[i, 1]
            omega = TWO_PI * particles[i, 2]
            w2 = omega * omega
            damp = 2.0 * particles[i, 3] * omega
            if k > 0:
                h = steps[k]
                for s in range(substeps):
                    f0 = 0.0
                    fh = 0.0
                    f1 = 0.0
                    for j in range(nb):
                        cj = particles[i, c0 + j]
                        f0 += cj * move_basis[k, s, 0, j]
                        fh += cj * move_basis[k, s, 1, j]
                        f1 += cj * move_basis[k, s, 2, j]
                    k1u = v
                    k1v = -w2 * u - damp * v + f0
                    if rk4:
                        u2 = u + 0.5 * h * k1u
                        v2 = v + 0.5 * h * k1v
                        k2v = -w2 * u2 - damp * v2 + fh
                        u3 = u + 0.5 * h * v2
                        v3 = v + 0.5 * h * k2v
                        k3v = -w2 * u3 - damp * v3 + fh
                        u4 = u + h * v3
                        v4 = v + h * k3v
                        k4v = -w2 * u4 - damp * v4 + f1
                        u = u + (h / 6.0) * (k1u + 2.0 * v2 + 2.0 * v3 + v4)
                        v = v + (h / 6.0) * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
                    else:
                        u = u + h * k1u
                        v = v + h * k1v
                particles[i, 0] = u
                particles[i, 1] = v
                for j in range(noisy.size):
                    particles[i, noisy[j]] += standard_normal(state) * q[j]
                for j in range(bounded.size):
                    b = bounded[j]
                    value = particles[i, b]
                    lo = low[j]
                    hi = high[j]
                    if value < lo or value > hi:
                        width = hi - lo
                        shifted = (value - lo) % (2.0 * width)
                        particles[i, b] = lo + (2.0 * width - shifted if shifted > width else shifted)
                u = particles[i, 0]
                v = particles[i, 1]
                omega = TWO_PI * particles[i, 2]
                w2 = omega * omega
                damp = 2.0 * particles[i, 3] * omega
            force = 0.0
            for j in range(nb):
                force += particles[i, c0 + j] * obs_basis[k, j]
            acc = -w2 * u - damp * v + force
            wi = weights[i]
            if full:
                predicted[i, 0] = u
                predicted[i, 1] = v
                predicted[i, 2] = acc
                mean_u += wi * u
                mean_v += wi * v
                mean_acc += wi * acc
            else:
                predicted[i, 0] = acc
                mean_acc += wi * acc
        # Predictive covariance of the observation (weights of the previous sample), and reweighting in logs.
        # Sums in local variables (not array cells), so the compiler keeps them in registers.
        top = -np.inf
        c00 = c01 = c02 = c11 = c12 = c22 = 0.0
        y0, y1, y2 = y[k, 0], y[k, n_obs - 2], y[k, n_obs - 1]
        r0, r1, r2 = r[0], r[n_obs - 2], r[n_obs - 1]
        for i in range(n):
            wi = weights[i]
            if full:
                p0, p1, p2 = predicted[i, 0], predicted[i, 1], predicted[i, 2]
                d0, d1, d2 = p0 - mean_u, p1 - mean_v, p2 - mean_acc
                c00 += wi * d0 * d0
                c01 += wi * d0 * d1
                c02 += wi * d0 * d2
                c11 += wi * d1 * d1
                c12 += wi * d1 * d2
                c22 += wi * d2 * d2
                z0 = (y0 - p0) / r0
                z1 = (y1 - p1) / r1
                z2 = (y2 - p2) / r2
                s2 = z0 * z0 + z1 * z1 + z2 * z2
            else:
                d2 = predicted[i, 0] - mean_acc
                c22 += wi * d2 * d2
                z2 = (y2 - predicted[i, 0]) / r2
                s2 = z2 * z2
            value = log_weights[i] + (log_norm - 0.5 * s2)
            if not math.isfinite(value):
                value = -np.inf
            log_weights[i] = value
            if value > top:
                top = value
        if full:
            innovations[k, 0] = y0 - mean_u
            innovations[k, 1] = y1 - mean_v
            innovations[k, 2] = y2 - mean_acc
            innovation_cov[k, 0, 0] = c00 + r0 * r0
            innovation_cov[k, 1, 1] = c11 + r1 * r1
            innovation_cov[k, 2, 2] = c22 + r2 * r2
            innovation_cov[k, 0, 1] = innovation_cov[k, 1, 0] = c01
            innovation_cov[k, 0, 2] = innovation_cov[k, 2, 0] = c02
            innovation_cov[k, 1, 2] = innovation_cov[k, 2, 1] = c12
        else:
            innovations[k, 0] = y2 - mean_acc
            innovation_cov[k, 0, 0] = c22 + r2 * r2
        if not math.isfinite(top):
            return 1, k, total_log_likelihood, resamples, particles, log_weights
        total = 0.0
        for i in range(n):
            wi = math.exp(log_weights[i] - top)
            weights[i] = wi
            total += wi
        increment = top + math.log(total)
        total_log_likelihood += increment
        # Normalised weights (one exponential per particle), filtered mean and sd, effective sample size.
        sum_w2 = 0.0
        accumulator[:] = 0.0
        scale = 1.0 / total
        for i in range(n):
            log_weights[i] -= increment
            wi = weights[i] * scale
            weights[i] = wi
            sum_w2 += wi * wi
            for j in range(d):
                accumulator[j] += wi * particles[i, j]
        mean[k, :] = accumulator
        accumulator[:] = 0.0
        for i in range(n):
            wi = weights[i]
            for j in range(d):
                dev = particles[i, j] - mean[k, j]
                accumulator[j] += wi * dev * dev
        for j in range(d):
            std[k, j] = math.sqrt(max(accumulator[j], 0.0))
        ess[k] = 1.0 / sum_w2
        if ess[k] < ess_threshold * n and k < m - 1:
            # Systematic resampling (as systematic_resample): one uniform, N evenly spaced pointers.
            start = next_double(state)
            running = 0.0
            for i in range(n):
                running += weights[i]
                cumulative[i] = running
            cumulative[n - 1] = 1.0
            source = 0
            for i in range(n):
                position = (start + i) / n
                while source < n - 1 and cumulative[source] <= position:
                    source += 1
                for j in range(d):
                    spare[i, j] = particles[source, j]
            particles, spare = spare, particles
            uniform = -math.log(n)
            flat = math.exp(uniform)
            for i in range(n):
                log_weights[i] = uniform
                weights[i] = flat
            resamples += 1
    return 0, m, total_log_likelihood, resamples, particles, log_weights


@numba.njit(cache=True, nogil=True)
def fill_normal(state, out):
    flat = out.reshape(-1)
    for i in range(flat.size):
        flat[i] = standard_normal(state)

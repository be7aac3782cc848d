"""The numba code of the compiled particle-filter pass (imported only when a pass needs it).

Module-level functions, so that numba's on-disk cache serves every process
(a worker of a process pool or a Dask cluster loads the machine code instead
of compiling it again). See :mod:`._pf_kernel` for what the pass does and
docs/performance.md for why it is laid out as it is.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from ._ziggurat import FI, INVERSE_R, KI, R, WI

TWO_PI = 2.0 * math.pi


u64 = np.uint64
S1, S3, S8, S11, S24, S40 = u64(1), u64(3), u64(8), u64(11), u64(24), u64(40)
LOW8, MANTISSA = u64(0xFF), u64(0x000FFFFFFFFFFFFF)


@numba.njit(inline="always")
def sfc64(s0, s1, s2, s3):
    """One output of SFC64 (numpy's ``SFC64`` bit generator) and its next state.

    The state travels in four local variables, not an array, so that the
    compiler keeps it in registers (a third faster than an array in memory).
    """
    out = s0 + s1 + s3
    s3 += S1
    s0 = s1 ^ (s1 >> S11)
    s1 = s2 + (s2 << S3)
    s2 = ((s2 << S24) | (s2 >> S40)) + out
    return out, s0, s1, s2, s3


@numba.njit(inline="always")
def unit_double(bits):
    """Uniform on [0, 1) from 64 bits, as numpy's ``Generator.random``."""
    return np.int64(bits >> S11) * (1.0 / 9007199254740992.0)


@numba.njit(inline="always")
def standard_normal(s0, s1, s2, s3):
    """numpy's ziggurat ``Generator.standard_normal`` (the same tables, hence the same numbers).

    Returns ``(value, s0, s1, s2, s3)``. The fast path (about 99 % of draws)
    is inlined; the rest goes to :func:`_normal_slow`.
    """
    bits, s0, s1, s2, s3 = sfc64(s0, s1, s2, s3)
    idx = np.intp(bits & LOW8)
    rest = bits >> S8
    rabs = (rest >> S1) & MANTISSA
    if rabs < KI[idx]:
        sign = 1.0 - 2.0 * np.float64(np.int64(rest & S1))  # +-1 without a branch (one in two would mispredict)
        return np.int64(rabs) * WI[idx] * sign, s0, s1, s2, s3
    return _normal_slow(bits, s0, s1, s2, s3)


@numba.njit(cache=True, nogil=True)
def _normal_slow(bits, s0, s1, s2, s3):
    """The rest of numpy's ziggurat, from the first draw ``bits`` that missed the fast path."""
    while True:
        idx = np.intp(bits & LOW8)
        bits >>= S8
        rabs = (bits >> S1) & MANTISSA
        x = np.int64(rabs) * WI[idx]
        if bits & S1:
            x = -x
        if rabs < KI[idx]:
            return x, s0, s1, s2, s3
        if idx == 0:
            while True:
                first, s0, s1, s2, s3 = sfc64(s0, s1, s2, s3)
                second, s0, s1, s2, s3 = sfc64(s0, s1, s2, s3)
                xx = -INVERSE_R * math.log1p(-unit_double(first))
                yy = -math.log1p(-unit_double(second))
                if yy + yy > xx * xx:
                    if (rabs >> S8) & S1:
                        return -(R + xx), s0, s1, s2, s3
                    return R + xx, s0, s1, s2, s3
        uniform, s0, s1, s2, s3 = sfc64(s0, s1, s2, s3)
        if (FI[idx - 1] - FI[idx]) * unit_double(uniform) + FI[idx] < math.exp(-0.5 * x * x):
            return x, s0, s1, s2, s3
        bits, s0, s1, s2, s3 = sfc64(s0, s1, s2, s3)


@numba.njit(cache=True, nogil=True)
def fill_normal_transposed(state, out):
    """Fill ``out[j, i]`` in the order ``i`` then ``j``: the draws of ``rng.standard_normal((i, j))``, transposed."""
    s0, s1, s2, s3 = state[0], state[1], state[2], state[3]
    rows, columns = out.shape
    for i in range(columns):
        for j in range(rows):
            value, s0, s1, s2, s3 = standard_normal(s0, s1, s2, s3)
            out[j, i] = value
    state[0], state[1], state[2], state[3] = s0, s1, s2, s3


@numba.njit(cache=True, nogil=True)
def next_unit_double(state):
    """One ``Generator.random()`` from the SFC64 ``state`` (advanced in place)."""
    bits, state[0], state[1], state[2], state[3] = sfc64(state[0], state[1], state[2], state[3])
    return unit_double(bits)


@intrinsic
def bits_of(typingctx, x):
    """The 64 bits of a float64, as an int64 (a free reinterpretation, which the compiler can vectorise)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))
    return types.int64(types.float64), codegen


@intrinsic
def float_of(typingctx, x):
    """The float64 whose 64 bits are the int64 ``x``."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())
    return types.float64(types.int64), codegen


LOG2E = 1.4426950408889634
LN2_HI, LN2_LO = 6.93147180369123816490e-01, 1.90821492927058770002e-10  # ln 2 in two parts (Cody and Waite)
ROUNDER = 6755399441055744.0  # 1.5 * 2**52: adding it to a whole float puts the integer in the low bits
ROUNDER_BITS = np.int64(0x4338000000000000)
LOWEST_EXPONENT = -708.0  # exp(-708) is about 3e-308, the smallest normal float's neighbourhood
E0, E1, E2, E3, E4, E5, E6, E7, E8, E9, E10, E11, E12, E13 = (1.0 / math.factorial(k) for k in range(14))


@numba.njit(inline="always")
def exp_nonpositive(x):
    """``exp(x)`` for ``x <= 0`` within 1 ulp of ``math.exp``; 0 below -708 (and for -inf).

    ``x = k ln 2 + r`` with ``|r| <= ln 2 / 2``, a degree-13 Taylor polynomial
    for ``exp(r)`` and ``2**k`` built from its bits: arithmetic only, so a loop
    of these vectorises (libm's ``exp`` is a call per value, twice as slow).
    Below -708 numpy gives subnormals of at most 3e-308 where this gives 0:
    a relative weight that no sum can see.
    """
    y = x if x > LOWEST_EXPONENT else LOWEST_EXPONENT
    kf = np.floor(y * LOG2E + 0.5)
    r = (y - kf * LN2_HI) - kf * LN2_LO
    p = ((((((((((((E13 * r + E12) * r + E11) * r + E10) * r + E9) * r + E8) * r + E7) * r + E6) * r + E5) * r
             + E4) * r + E3) * r + E2) * r + E1) * r + E0
    k = bits_of(kf + ROUNDER) - ROUNDER_BITS
    value = p * float_of((k + 1023) << 52)
    return value if x > LOWEST_EXPONENT else 0.0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def exponentiate(log_weights, top, out):
    """``out = exp(log_weights - top)`` (no fast-math licence here: the range reduction must stay exact)."""
    for i in range(log_weights.size):
        out[i] = exp_nonpositive(log_weights[i] - top)


@numba.njit(inline="never")
def fold(value, low, high):
    """Reflect ``value`` into ``[low, high]`` (as :func:`~.particle.reflect`); out of line, it is rarely needed."""
    width = high - low
    shifted = (value - low) % (2.0 * width)
    return low + (2.0 * width - shifted if shifted > width else shifted)


@numba.njit(inline="always")
def fold_block(row, low, high, outside):
    """Fold the values of ``row`` outside ``[low, high]`` back in, if ``outside`` says there are any."""
    if outside:
        for i in range(row.size):
            if row[i] < low or row[i] > high:
                row[i] = fold(row[i], low, high)


@numba.njit(inline="always")
def reflect_block(row, low, high):
    """Fold the values of ``row`` outside ``[low, high]`` back in (a vectorised test, then the rare folds)."""
    outside = 0
    for i in range(row.size):
        outside += (row[i] < low) | (row[i] > high)
    fold_block(row, low, high, outside)


@numba.njit(inline="always")
def jitter_block(row, draws, std, low, high):
    """Add ``draws * std`` to ``row`` (process noise, Eq. 6) and reflect into ``[low, high]``, in one sweep."""
    outside = 0
    for i in range(row.size):
        value = row[i] + draws[i] * std
        row[i] = value
        outside += (value < low) | (value > high)
    fold_block(row, low, high, outside)


BLOCK = 128
"""Particles per block: a block's slice of the cloud, its forces and its draws stay in the core's cache."""

SUMS = {"reassoc", "contract"}
"""Floating-point licence of the pass: sums may be reordered (so that they vectorise) and ``a * b + c`` fused.
No assumption about NaN or infinity (a non-finite likelihood is tested for)."""


@numba.njit(inline="always")
def block_force(cloud, c0, nb, basis, start, length, out):
    """The Fourier force (Eq. 4) of particles ``start .. start + length``: ``out[i] = sum_j c_j[i] * basis[j]``."""
    coefficients = cloud[c0][start:start + length]
    b = basis[0]
    for i in range(length):
        out[i] = coefficients[i] * b
    for j in range(1, nb):
        coefficients = cloud[c0 + j][start:start + length]
        b = basis[j]
        for i in range(length):
            out[i] += coefficients[i] * b


@numba.njit(inline="always")
def block_forces(cloud, c0, nb, basis, start, length, out0, out1, out2):
    """:func:`block_force` at the three times of an RK4 step (rows of ``basis``), in one sweep over the coefficients."""
    row = cloud[c0][start:start + length]
    b0, b1, b2 = basis[0, 0], basis[1, 0], basis[2, 0]
    for i in range(length):
        c = row[i]
        out0[i] = c * b0
        out1[i] = c * b1
        out2[i] = c * b2
    for j in range(1, nb):
        row = cloud[c0 + j][start:start + length]
        b0, b1, b2 = basis[0, j], basis[1, j], basis[2, j]
        for i in range(length):
            c = row[i]
            out0[i] += c * b0
            out1[i] += c * b1
            out2[i] += c * b2


@numba.njit(inline="always")
def systematic_index(weights, scale, offset, counts, index):
    """The particles chosen by systematic resampling, without a branch per particle.

    Pointer ``i`` sits at ``(offset + i) / n`` and picks the first particle
    whose cumulative normalised weight ``C_j`` exceeds it (numpy's
    ``searchsorted(C, pointers, side="right")``, ``C_{n-1} = 1``). Pointer
    ``i`` is past ``C_j`` exactly when ``i >= A_j = ceil(n C_j - offset)``, so
    ``index[i]`` is the number of ``A_j <= i``: a histogram of the ``A_j`` and
    its running sum. (The two tests round differently only for a pointer
    within a rounding error of a ``C_j``.)
    """
    n = weights.size
    counts[:] = 0
    running = 0.0
    for j in range(n - 1):
        running += weights[j] * scale
        passed = math.ceil(n * running - offset)
        counts[min(max(passed, 0), n)] += 1
    counts[n] += 1  # C_{n-1} = 1: no pointer is past the last particle
    chosen = 0
    for i in range(n):
        chosen += counts[i]
        index[i] = min(chosen, n - 1)


@numba.njit(inline="always")
def move_block(u, v, freq, damping, f_start, f_mid, f_end, h, rk4):
    """One RK4 (or Euler) step of ``u, u'`` (Eq. 10-12) for a block of particles, in place.

    ``f_start, f_mid, f_end`` are the Fourier forces at ``t``, ``t + h/2`` and ``t + h``.
    """
    if rk4:
        for i in range(u.size):
            u1, v1 = u[i], v[i]
            omega = TWO_PI * freq[i]
            w2 = omega * omega
            damp = 2.0 * damping[i] * omega
            a1 = -w2 * u1 - damp * v1 + f_start[i]
            u2 = u1 + 0.5 * h * v1
            v2 = v1 + 0.5 * h * a1
            a2 = -w2 * u2 - damp * v2 + f_mid[i]
            u3 = u1 + 0.5 * h * v2
            v3 = v1 + 0.5 * h * a2
            a3 = -w2 * u3 - damp * v3 + f_mid[i]
            u4 = u1 + h * v3
            v4 = v1 + h * a3
            a4 = -w2 * u4 - damp * v4 + f_end[i]
            u[i] = u1 + (h / 6.0) * (v1 + 2.0 * v2 + 2.0 * v3 + v4)
            v[i] = v1 + (h / 6.0) * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
    else:
        for i in range(u.size):
            u1, v1 = u[i], v[i]
            omega = TWO_PI * freq[i]
            u[i] = u1 + h * v1
            v[i] = v1 + h * (-omega * omega * u1 - 2.0 * damping[i] * omega * v1 + f_start[i])


@numba.njit(cache=True, nogil=True, fastmath={"nnan", "nsz", "reassoc"})
def largest(values):
    """The largest of ``values``, none of them NaN (-inf allowed): a licence the compiler needs to vectorise it."""
    top = -np.inf
    for i in range(values.size):
        top = max(top, values[i])
    return top


@numba.njit(inline="always")
def weigh_block(u, v, freq, damping, force, weights, log_weights, observed, inverse_noise, log_norm, pending, full):
    """Reweight a block by the likelihood of the observation (Eq. 13-16), in logs and in place.

    ``log_weights`` become ``log_weights - pending + log p(y | particle)``
    (non-finite ones -inf). Returns the sums, with the previous ``weights``,
    of the residuals ``prediction - y`` and of their products (for the
    innovation covariance), and the largest new log-weight.
    """
    y0, y1, y2 = observed
    i0, i1, i2 = inverse_noise
    e0 = e1 = e2 = c00 = c01 = c02 = c11 = c12 = c22 = 0.0
    for i in range(u.size):
        omega = TWO_PI * freq[i]
        r2 = (-omega * omega * u[i] - 2.0 * damping[i] * omega * v[i] + force[i]) - y2
        wi = weights[i]
        e2 += wi * r2
        c22 += wi * r2 * r2
        z2 = r2 * i2
        s2 = z2 * z2
        if full:
            r0 = u[i] - y0
            r1 = v[i] - y1
            e0 += wi * r0
            e1 += wi * r1
            c00 += wi * r0 * r0
            c01 += wi * r0 * r1
            c02 += wi * r0 * r2
            c11 += wi * r1 * r1
            c12 += wi * r1 * r2
            z0 = r0 * i0
            z1 = r1 * i1
            s2 += z0 * z0 + z1 * z1
        value = (log_weights[i] - pending) + (log_norm - 0.5 * s2)
        log_weights[i] = value if math.isfinite(value) else -np.inf
    top = largest(log_weights)
    return (e0, e1, e2, c00, c01, c02, c11, c12, c22), top


@numba.njit(inline="always")
def sample_block_pass(k, cloud, weights, log_weights, steps, move_basis, obs_basis, c0, rk4, full, noisy, q,
                      noisy_low, noisy_high, quiet, quiet_low, quiet_high, state, draws, forces, observed,
                      inverse_noise, log_norm, pending):
    """One sample over every block of particles: move, jitter, reflect (``k > 0``) and weigh.

    Returns the nine sums of the weighted residuals of the predicted
    observation and their products, and the largest log-weight.
    """
    d, n = cloud.shape
    nb = obs_basis.shape[1]
    f_start, f_mid, f_end, force = forces[0], forces[1], forces[2], forces[3]
    u, v, freq, damping = cloud[0], cloud[1], cloud[2], cloud[3]
    h = steps[k]
    sums = np.zeros(9)
    top = -np.inf
    for start in range(0, n, BLOCK):
        length = min(BLOCK, n - start)
        block = slice(start, start + length)
        if k > 0:
            # Predict (Eq. 11-12): RK4 or Euler on u, u'; the parameters are random walks (Eq. 6).
            for s in range(move_basis.shape[1]):
                block_forces(cloud, c0, nb, move_basis[k, s], start, length, f_start, f_mid, f_end)
                move_block(u[block], v[block], freq[block], damping[block], f_start, f_mid, f_end, h, rk4)
            # Process noise, drawn particle by particle as rng.standard_normal((n, n_noisy)) does;
            # then the parameters that left their prior box are reflected back.
            if noisy.size:
                fill_normal_transposed(state, draws[:, :length])
            for j in range(noisy.size):
                jitter_block(cloud[noisy[j]][block], draws[j], q[j], noisy_low[j], noisy_high[j])
            for j in range(quiet.size):
                reflect_block(cloud[quiet[j]][block], quiet_low[j], quiet_high[j])
        # Predicted observation (Eq. 13-16) and reweighting by its likelihood, in logs.
        block_force(cloud, c0, nb, obs_basis[k], start, length, force)
        block_sums, block_top = weigh_block(u[block], v[block], freq[block], damping[block], force, weights[block],
                                            log_weights[block], observed, inverse_noise, log_norm, pending, full)
        for j in range(9):
            sums[j] += block_sums[j]
        top = max(top, block_top)
    return sums, top


@numba.njit(inline="always")
def record_innovation(k, sums, scale, full, variances, innovations, innovation_cov):
    """The innovation of sample ``k`` and its predicted covariance, from the previous sample's weights."""
    var0, var1, var2 = variances
    e0, e1, e2, c00, c01, c02, c11, c12, c22 = sums
    e0, e1, e2 = e0 * scale, e1 * scale, e2 * scale
    if full:
        innovations[k, 0], innovations[k, 1], innovations[k, 2] = -e0, -e1, -e2
        innovation_cov[k, 0, 0] = c00 * scale - e0 * e0 + var0
        innovation_cov[k, 1, 1] = c11 * scale - e1 * e1 + var1
        innovation_cov[k, 2, 2] = c22 * scale - e2 * e2 + var2
        innovation_cov[k, 0, 1] = innovation_cov[k, 1, 0] = c01 * scale - e0 * e1
        innovation_cov[k, 0, 2] = innovation_cov[k, 2, 0] = c02 * scale - e0 * e2
        innovation_cov[k, 1, 2] = innovation_cov[k, 2, 1] = c12 * scale - e1 * e2
    else:
        innovations[k, 0] = -e2
        innovation_cov[k, 0, 0] = c22 * scale - e2 * e2 + var2


@numba.njit(inline="always")
def block_moments(cloud, weights, log_weights, top, block_weight, block_mean, block_m2):
    """New weights (``exp(log_weights - top)``) and each block's weighted moments; returns their total and sum
    of squares.

    Each block's moments are summed in one sweep, shifted by the block's
    first particle (so a fixed slot has sd 0 and a collapsed one keeps its
    digits).
    """
    d, n = cloud.shape
    total = 0.0
    sum_squares = 0.0
    for number, start in enumerate(range(0, n, BLOCK)):
        stop = min(start + BLOCK, n)
        wb = weights[start:stop]
        exponentiate(log_weights[start:stop], top, wb)
        block_total = 0.0
        for i in range(stop - start):
            block_total += wb[i]
            sum_squares += wb[i] * wb[i]
        total += block_total
        block_weight[number] = block_total
        inverse = 1.0 / block_total if block_total > 0.0 else 0.0
        for j in range(d):
            row = cloud[j][start:stop]
            offset = row[0]
            s1 = s2 = 0.0
            for i in range(stop - start):
                x = row[i] - offset
                s1 += wb[i] * x
                s2 += wb[i] * x * x
            centre = s1 * inverse
            block_mean[number, j] = offset + centre
            block_m2[number, j] = max(s2 - centre * s1, 0.0)
    return total, sum_squares


@numba.njit(inline="always")
def combine_moments(k, scale, block_weight, block_mean, block_m2, mean, std):
    """The filtered mean and sd of sample ``k`` from the blocks' moments (Chan et al.'s parallel variance)."""
    n_blocks, d = block_mean.shape
    for j in range(d):
        centre = 0.0
        for number in range(n_blocks):
            centre += block_weight[number] * block_mean[number, j]
        centre *= scale
        spread = 0.0
        for number in range(n_blocks):
            x = block_mean[number, j] - centre
            spread += block_m2[number, j] + block_weight[number] * x * x
        mean[k, j] = centre
        std[k, j] = math.sqrt(max(spread * scale, 0.0))


@numba.njit(inline="always")
def resample(cloud, spare, weights, log_weights, scale, state, counts, index):
    """Systematic resampling into ``spare`` (as ``systematic_resample``: one uniform, N evenly spaced pointers);
    the weights become equal."""
    d, n = cloud.shape
    systematic_index(weights, scale, next_unit_double(state), counts, index)
    for j in range(d):
        row, target = cloud[j], spare[j]
        for i in range(n):
            target[i] = row[index[i]]
    uniform = -math.log(n)
    flat = math.exp(uniform)
    for i in range(n):
        log_weights[i] = uniform
        weights[i] = flat


@numba.njit(cache=True, nogil=True, error_model="numpy", fastmath=SUMS)
def run_pass(cloud, log_weights, y, steps, move_basis, obs_basis, c0, rk4, full, noisy, q, noisy_low, noisy_high,
             quiet, quiet_low, quiet_high, r, ess_threshold, state, mean, std, innovations, innovation_cov, ess):
    """Filter one pass in place; returns (status, sample, log_likelihood, resamples, cloud, log_weights).

    ``cloud`` has one row per state slot (shape ``(n_state, n_particles)``);
    ``noisy`` are the slots with process noise ``q`` and bounds
    ``noisy_low``/``noisy_high`` (infinite where unbounded); ``quiet`` the
    bounded slots without noise. ``state`` is the SFC64 state of the filter's
    generator, advanced in place exactly as numpy would. status 0: done;
    1: every weight vanished at ``sample``.
    """
    d, n = cloud.shape
    m, n_obs = y.shape
    log_norm = -0.5 * n_obs * math.log(TWO_PI)
    for c in range(n_obs):
        log_norm -= math.log(r[c])
    inverse_noise = (1.0 / r[0], 1.0 / r[n_obs - 2], 1.0 / r[n_obs - 1])
    variances = (r[0] * r[0], r[n_obs - 2] * r[n_obs - 2], r[n_obs - 1] * r[n_obs - 1])
    # Weights of the previous sample: weights * scale; log-weights: log_weights - pending.
    weights = np.empty(n)
    exponentiate(log_weights, 0.0, weights)
    scale = 1.0
    pending = 0.0
    spare = np.empty_like(cloud)
    forces = np.empty((4, BLOCK))  # the force at a step's start, middle and end, and at the sample
    draws = np.empty((noisy.size, BLOCK))
    n_blocks = (n + BLOCK - 1) // BLOCK
    block_weight = np.empty(n_blocks)
    block_mean = np.empty((n_blocks, d))
    block_m2 = np.empty((n_blocks, d))
    index = np.empty(n, np.intp)
    counts = np.empty(n + 1, np.intp)
    total_log_likelihood = 0.0
    resamples = 0
    for k in range(m):
        observed = (y[k, 0], y[k, n_obs - 2], y[k, n_obs - 1])
        sums, top = sample_block_pass(k, cloud, weights, log_weights, steps, move_basis, obs_basis, c0, rk4, full,
                                      noisy, q, noisy_low, noisy_high, quiet, quiet_low, quiet_high, state, draws,
                                      forces, observed, inverse_noise, log_norm, pending)
        record_innovation(k, sums, scale, full, variances, innovations, innovation_cov)
        if not math.isfinite(top):
            return 1, k, total_log_likelihood, resamples, cloud, log_weights
        total, sum_squares = block_moments(cloud, weights, log_weights, top, block_weight, block_mean, block_m2)
        pending = top + math.log(total)
        total_log_likelihood += pending
        scale = 1.0 / total
        combine_moments(k, scale, block_weight, block_mean, block_m2, mean, std)
        ess[k] = total * total / sum_squares
        if ess[k] < ess_threshold * n and k < m - 1:
            resample(cloud, spare, weights, log_weights, scale, state, counts, index)
            cloud, spare = spare, cloud
            scale = 1.0
            pending = 0.0
            resamples += 1
    for i in range(n):
        log_weights[i] -= pending
    return 0, m, total_log_likelihood, resamples, cloud, log_weights

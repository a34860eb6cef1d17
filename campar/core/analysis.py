"""Steady-motion analysis on the stroboscopic section σn: period, detachments, stability.

Everything here works on numbers the kernel hands over (section points, one-
revolution Jacobians, per-revolution statistics); nothing here integrates.

History layout (filled by the kernel, one row per revolution):

* ``xs[j]`` — section point (y, y') at θ = 0 after j revolutions (xs[0] = start);
* ``jac[j-1]`` — Jacobian of the one-revolution map P at xs[j-1], row-major 4;
* ``revs[j-1]`` — statistics of revolution j (columns ``REV_*``).

Transient policy ("converged"): after every revolution, for each candidate
period n ≤ n_max, the fixed point z of P^n is estimated by one Newton step
from xs[k-n] → xs[k] with M = DP^n (product of the last n Jacobians). The
cell has converged with period n when z lies within ``conv_tol`` of xs[k] and
within ``window_tol`` of xs[k-n] and M is stable. Unlike a plain repeat test
|xs[k] − xs[k−n]| < tol, this measures the distance to the cycle itself, so a
slowly converging 1-cycle (multiplier near −1) cannot pass as a 2-cycle. Where
no period has converged yet, a capped Newton jump to z of the smallest
plausible period shortens the transient: near the cycle (small residual), or
far from it when consecutive estimates of z agree (a slowly attracting cycle,
multiplier near the unit circle, which plain revolutions reach only after
thousands). The jump is only a new start, the cycle is accepted by the same
test afterwards.
"""

import math

from .codes import CHAOTIC, QUASIPERIODIC, UNCONVERGED
from .jit import hot

# Columns of the per-revolution statistics.
REV_T_FREE = 0  # time with ε < 0 (separated)
REV_DETACH = 1  # detachments (ε crossing 0 downward)
REV_EPS_MIN = 2
REV_EPS_MAX = 3
REV_PN_MAX = 4
REV_LOG_STRETCH = 5  # growth of the tangent vector (Lyapunov exponent)
REV_GRAZE = 6  # smallest |ε| at a local minimum of ε: a shallow flight or a near miss
# ε at the interior local extremum of ε (minimum or maximum) nearest 0, signed: where it
# crosses 0 the contact pattern changes (a grazing contact or flight), so a continuation
# locates grazing as a root of it (campar.continuation)
REV_TOUCH = 7
N_REV_STATS = 8

# Longest Newton jump taken on agreeing estimates (assess_revolution).
TRUSTED_JUMP_MAX = 0.2
# A jump on agreeing estimates is taken for a period whose repeat is within this factor of
# the motion's closest repeat over the periods available (assess_revolution).
EVIDENT_REPEAT = 10.0
# A stable cycle this close to the motion at the budget's end (∞-norm, the distance of its
# Newton estimate and that estimate's last step) is the cell's motion, though not
# converged to conv_tol: settled (transient.settle_at_budget, kernel.run_cell).
SETTLED_DISTANCE = 1e-4

# The largest Lyapunov exponent of a non-periodic motion (exponent_window, exponent_bounds).
# The tangent vector starts along y at every restart and needs a revolution or two to turn
# into the most expanding direction: its first stretches measure the start, not the motion.
TANGENT_SETTLE = 2
# One revolution's stretch depends on the ones just before it (the tangent turns over a
# few revolutions), so the error of the mean comes from means over batches of this many
# revolutions, which are close to independent …
BATCH_REVOLUTIONS = 4
# … and from at least this many batches: fewer leave the spread itself unknown.
MIN_BATCHES = 4


@hot
def mat2_mul(a, b):
    """Product of 2×2 matrices given as row-major 4-tuples."""
    return (
        a[0] * b[0] + a[1] * b[2],
        a[0] * b[1] + a[1] * b[3],
        a[2] * b[0] + a[3] * b[2],
        a[2] * b[1] + a[3] * b[3],
    )


@hot
def eig2(m):
    """Eigenvalues of a real 2×2 matrix: (re0, im0, re1, im1), |λ0| ≥ |λ1|."""
    tr = m[0] + m[3]
    det = m[0] * m[3] - m[1] * m[2]
    disc = 0.25 * tr * tr - det
    if disc >= 0.0:
        s = math.sqrt(disc)
        l0 = 0.5 * tr + s if tr >= 0.0 else 0.5 * tr - s
        # the smaller root from det / l0 avoids cancellation
        l1 = det / l0 if l0 != 0.0 else 0.5 * tr - s
        if abs(l1) > abs(l0):
            l0, l1 = l1, l0
        return l0, 0.0, l1, 0.0
    s = math.sqrt(-disc)
    return 0.5 * tr, s, 0.5 * tr, -s


@hot
def spectral_radius(m):
    re0, im0, _, _ = eig2(m)
    return math.hypot(re0, im0)


@hot
def unit_eigenvector(m, mu):
    """The unit eigenvector of a real 2×2 matrix M for its real eigenvalue μ, orthogonal to
    the larger row of M − μI; (0, 0) where M = μI."""
    a, b, c, d = m[0] - mu, m[1], m[2], m[3] - mu
    if abs(a) + abs(b) >= abs(c) + abs(d):
        v0, v1 = -b, a
    else:
        v0, v1 = -d, c
    norm = math.hypot(v0, v1)
    if not norm > 0.0:
        return 0.0, 0.0
    return v0 / norm, v1 / norm


@hot
def real_dominant_direction(m):
    """(λ, v0, v1): the eigenvalue of largest modulus of a real 2×2 matrix and its unit
    eigenvector (any unit vector where M = λI); (nan, 0, 0) when the eigenvalues are
    complex."""
    re0, im0, _, _ = eig2(m)
    if im0 != 0.0:
        return math.nan, 0.0, 0.0
    v0, v1 = unit_eigenvector(m, re0)
    if v0 == 0.0 and v1 == 0.0:
        return re0, 1.0, 0.0
    return re0, v0, v1


@hot
def jacobian_at(jac, j):
    """The one-revolution Jacobian stored in row j as a 4-tuple."""
    return jac[j, 0], jac[j, 1], jac[j, 2], jac[j, 3]


@hot
def section_gap(xs, i, j):
    """The ∞-norm distance between section points xs[i] and xs[j]."""
    return max(abs(xs[i, 0] - xs[j, 0]), abs(xs[i, 1] - xs[j, 1]))


@hot
def cycle_jacobian(jac, k, n):
    """DP^n at xs[k-n]: the product J_k ⋯ J_{k-n+1} of the last n revolutions."""
    m = jacobian_at(jac, k - 1)
    for j in range(k - 2, k - n - 1, -1):
        m = mat2_mul(m, jacobian_at(jac, j))
    return m


@hot
def newton_fixed_point(x_now0, x_now1, x_then0, x_then1, m):
    """Fixed point z of P^n by one Newton step, given P^n(x_then) = x_now and M = DP^n.

    Solves (I − M) δ = x_now − x_then, z = x_then + δ. Returns (z0, z1,
    |z − x_now|∞, |z − x_then|∞); infinite distances when I − M is singular.
    """
    r0 = x_now0 - x_then0
    r1 = x_now1 - x_then1
    a00 = 1.0 - m[0]
    a01 = -m[1]
    a10 = -m[2]
    a11 = 1.0 - m[3]
    det = a00 * a11 - a01 * a10
    if det == 0.0 or not math.isfinite(det):
        return x_now0, x_now1, math.inf, math.inf
    d0 = (a11 * r0 - a01 * r1) / det
    d1 = (a00 * r1 - a10 * r0) / det
    z0 = x_then0 + d0
    z1 = x_then1 + d1
    return z0, z1, max(abs(z0 - x_now0), abs(z1 - x_now1)), max(abs(d0), abs(d1))


@hot
def assess_revolution(
    xs, jac, est, k, base, n_max, conv_tol, window_tol, jump_residual, jump_cap, agree
):
    """Decide, after revolution k, whether the motion has converged to a cycle.

    Only revolutions after ``base`` (the last restart) are used. Returns
    (period, jump_period, z0, z1): period > 0 when the cycle of that period has
    converged; otherwise jump_period > 0 proposes a Newton jump to (z0, z1).

    A jump is proposed where |x_k − x_{k−n}| ≤ jump_residual and the estimate is
    within jump_cap, or (agree > 0) where the estimate agrees with the one made
    n revolutions earlier to within ``agree`` times its distance and lies
    within TRUSTED_JUMP_MAX: then the section map is linear enough around the
    path for the estimate to be trusted however far the transient still has
    to go — but only for a period at which the motion repeats within
    EVIDENT_REPEAT times its closest repeat. Just past a period doubling the motion
    alternates about the unstable cycle it left; the Jacobian along its path is
    stable, and the estimates of period 1 (and 3, …) agree on that unstable cycle, a
    jump there holding the motion for hundreds of revolutions, while it repeats far
    closer every 2. ``est`` (n_max, n_max, 3) keeps each period's estimates by
    revolution, rows (revolution, z0, z1); reset it for every cell.
    """
    jump_n = 0
    jz0 = 0.0
    jz1 = 0.0
    avail = min(n_max, k - base)
    if avail < 1:
        return 0, 0, 0.0, 0.0
    closest = math.inf  # the motion's closest repeat over the periods available
    for n in range(1, avail + 1):
        closest = min(closest, section_gap(xs, k, k - n))
    m = jacobian_at(jac, k - 1)
    for n in range(1, avail + 1):
        if n > 1:
            m = mat2_mul(m, jacobian_at(jac, k - n))
        r = section_gap(xs, k, k - n)
        near = r <= jump_residual
        evident = r <= EVIDENT_REPEAT * closest
        if not (near or (agree > 0.0 and r <= TRUSTED_JUMP_MAX)):
            continue
        if not spectral_radius(m) < 1.0:
            continue  # an unstable cycle cannot be the steady motion
        z0, z1, dist_now, dist_then = newton_fixed_point(
            xs[k, 0], xs[k, 1], xs[k - n, 0], xs[k - n, 1], m
        )
        if near and dist_now <= conv_tol and dist_then <= window_tol:
            return n, 0, z0, z1
        then = est[n - 1, k % n]  # the estimate made n revolutions ago (same cycle point)
        agreeing = (
            agree > 0.0
            and then[0] == k - n
            and k - 2 * n >= base
            and max(abs(z0 - then[1]), abs(z1 - then[2])) <= agree * dist_now
        )
        then[0] = k
        then[1] = z0
        then[2] = z1
        if jump_n == 0 and (
            (near and dist_now <= jump_cap)
            or (agreeing and evident and dist_now <= TRUSTED_JUMP_MAX)
        ):
            jump_n = n
            jz0 = z0
            jz1 = z1
    return 0, jump_n, jz0, jz1


@hot
def unstable_cycle_nearby(xs, jac, k, base, n_max, reach):
    """The unstable cycle the motion lingers at, if any: (n, z0, z1, v0, v1).

    The smallest period n ≤ n_max (using revolutions after ``base``) with
    |x_k − x_{k−n}| ≤ reach, growing since n revolutions before (the motion moves away
    from the cycle, it does not settle on it), whose one-Newton-step fixed point z of
    P^n lies within reach of x_k and has a real multiplier μ, |μ| > 1; v is μ's unit
    eigenvector (of DP^n at x_k). n = 0 when there is none. Next to a period doubling
    (μ ≈ −1) or a fold the escape from such a cycle takes hundreds of revolutions, and
    its window reads as a torus or as chaos; the kernel leaves along v instead.
    """
    avail = min(n_max, (k - base) // 2)
    if avail < 1:
        return 0, 0.0, 0.0, 0.0, 0.0
    m = jacobian_at(jac, k - 1)
    for n in range(1, avail + 1):
        if n > 1:
            m = mat2_mul(m, jacobian_at(jac, k - n))
        r = section_gap(xs, k, k - n)
        before = section_gap(xs, k - n, k - 2 * n)
        if r > reach or not r > before:
            continue
        mu, im, _, _ = eig2(m)
        if im != 0.0 or not abs(mu) > 1.0:
            continue
        z0, z1, dist_now, _ = newton_fixed_point(xs[k, 0], xs[k, 1], xs[k - n, 0], xs[k - n, 1], m)
        if not dist_now <= reach:
            continue
        v0, v1 = unit_eigenvector(m, mu)
        if v0 != 0.0 or v1 != 0.0:
            return n, z0, z1, v0, v1
    return 0, 0.0, 0.0, 0.0, 0.0


@hot
def slow_cycle_period(xs, jac, k, first, n_max, reach, margin):
    """The smallest n ≤ n_max (using the section points after ``first``) for which P^n
    has a stable fixed point within ``reach`` of xs[k] (one Newton step) with a
    multiplier within ``margin`` of the unit circle; 0 when there is none.

    Such a cycle converges too slowly for the transient's budget (a multiplier 0.998
    halves the distance in 350 periods), and Newton jumps to it stall where the
    integration's noise over 1 − |μ| exceeds the convergence tolerance. Within a wide
    reach a non-periodic verdict may be a cycle the budget did not reach; within a
    narrow one the motion has settled on it.
    """
    return stable_cycle_period(xs, jac, k, first, n_max, reach, False, margin)


@hot
def stable_cycle_period(xs, jac, k, first, n_max, reach, returning, margin):
    """The smallest n ≤ n_max (section points after ``first``) whose DP^n over the last n
    revolutions is stable and whose one-Newton-step fixed point lies within ``reach`` of
    x_k; with ``returning`` only where |x_k − x_{k−n}| ≤ reach too, and only where a
    multiplier lies within ``margin`` of the unit circle (math.inf: any); 0: none.

    The search of ``stable_cycle_nearby`` and ``slow_cycle_period``: DP^n is built one
    revolution's Jacobian at a time as n grows.
    """
    avail = min(n_max, k - first)
    if avail < 1:
        return 0
    m = jacobian_at(jac, k - 1)
    for n in range(1, avail + 1):
        if n > 1:
            m = mat2_mul(m, jacobian_at(jac, k - n))
        if returning and section_gap(xs, k, k - n) > reach:
            continue
        if not spectral_radius(m) < 1.0:
            continue
        _, _, dist_now, _ = newton_fixed_point(xs[k, 0], xs[k, 1], xs[k - n, 0], xs[k - n, 1], m)
        if dist_now <= reach and (margin == math.inf or near_unit_circle(m, margin)):
            return n
    return 0


@hot
def distinct_period(xs, k, n, tol):
    """Number of distinct points (within tol, ∞-norm) of the n-cycle xs[k-n+1..k].

    The smallest divisor m of n with xs[i] ≈ xs[i+m] around the cycle.
    """
    for m in range(1, n):
        if n % m == 0 and repeats_with(xs, k, n, m, tol):
            return m
    return n


@hot
def repeats_with(xs, k, n, d, tol):
    """True when the n-cycle xs[k-n+1..k] repeats with period d: xs[i] ≈ xs[i+d] (within
    tol, ∞-norm) around the cycle."""
    for i in range(k - n + 1, k + 1):
        j = i + d
        if j > k:
            j -= n
        if abs(xs[i, 0] - xs[j, 0]) > tol or abs(xs[i, 1] - xs[j, 1]) > tol:
            return False
    return True


@hot
def stable_subperiod(xs, jac, k, n, reach):
    """The smallest divisor d of n such that the n-cycle xs[k-n+1..k] repeats with period
    d to within ``reach`` (∞-norm) and its period-d map DP^d is stable; n if none.

    Such a cycle is the d-cycle read through the integration's noise: next to a flip,
    the period-2 map's fixed point is ill-conditioned (multiplier near +1) and its two
    points can stay farther apart than period_tol, while the period-1 cycle (multiplier
    near −1) is stable. A genuine 2-cycle born in the flip has an unstable 1-cycle there.
    """
    for d in range(1, n):
        if (
            n % d == 0
            and repeats_with(xs, k, n, d, reach)
            and spectral_radius(cycle_jacobian(jac, k, d)) < 1.0
        ):
            return d
    return n


@hot
def repeat_period(xs, first, last, n_max, tol):
    """Smallest n ≤ n_max with |xs[j] − xs[j−n]| ≤ tol for every j in (first+n … last].

    The plain repeat test of a fixed transient; needs last − first ≥ 2n so the
    pattern is seen twice. Returns 0 when no such n exists.
    """
    for n in range(1, n_max + 1):
        if last - first < 2 * n:
            break
        ok = True
        for j in range(first + n, last + 1):
            if abs(xs[j, 0] - xs[j - n, 0]) > tol or abs(xs[j, 1] - xs[j - n, 1]) > tol:
                ok = False
                break
        if ok:
            return n
    return 0


@hot
def reset_revolution_stats(row):
    row[REV_T_FREE] = 0.0
    row[REV_DETACH] = 0.0
    row[REV_EPS_MIN] = math.inf
    row[REV_EPS_MAX] = -math.inf
    row[REV_PN_MAX] = 0.0
    row[REV_LOG_STRETCH] = 0.0
    row[REV_GRAZE] = math.inf
    row[REV_TOUCH] = math.inf


@hot
def add_step_stats(row, h, free, e0, e1, dip, peak, pn_hi):
    """Fold one step into a revolution's statistics: ε at both ends, ``dip`` and ``peak``
    its interior local minimum and maximum (NaN: none), ``pn_hi`` the step's largest Pn
    (campar.core.extrema.step_extremes); ``free``: the step's time counts towards the
    duty cycle (model.released).
    """
    if free:
        row[REV_T_FREE] += h
    lo = min(e0, e1)
    hi = max(e0, e1)
    if dip == dip:  # not NaN
        lo = min(lo, dip)
        # a local minimum of ε near 0 is where a detachment can appear or vanish
        row[REV_GRAZE] = min(row[REV_GRAZE], abs(dip))
        if abs(dip) < abs(row[REV_TOUCH]):
            row[REV_TOUCH] = dip
    if peak == peak:
        hi = max(hi, peak)
        # … and a local maximum near 0, where an impact can appear or vanish
        if abs(peak) < abs(row[REV_TOUCH]):
            row[REV_TOUCH] = peak
    row[REV_EPS_MIN] = min(row[REV_EPS_MIN], lo)
    row[REV_EPS_MAX] = max(row[REV_EPS_MAX], hi)
    if not free:
        row[REV_PN_MAX] = max(row[REV_PN_MAX], pn_hi)


@hot
def window_stats(revs, first, count):
    """Combine revolutions first … first+count−1: (time separated, detachments,
    ε min, ε max, Pn max, mean log-stretch per revolution, smallest |ε| at a dip)."""
    t_free = 0.0
    detach = 0.0
    eps_min = math.inf
    eps_max = -math.inf
    pn_max = 0.0
    stretch = 0.0
    graze = math.inf
    for j in range(first, first + count):
        t_free += revs[j, REV_T_FREE]
        detach += revs[j, REV_DETACH]
        eps_min = min(eps_min, revs[j, REV_EPS_MIN])
        eps_max = max(eps_max, revs[j, REV_EPS_MAX])
        pn_max = max(pn_max, revs[j, REV_PN_MAX])
        stretch += revs[j, REV_LOG_STRETCH]
        graze = min(graze, revs[j, REV_GRAZE])
    return t_free, detach, eps_min, eps_max, pn_max, stretch / max(count, 1), graze


@hot
def exponent_window(k, base, window):
    """(first, count): the revolutions after revolution k that estimate the largest Lyapunov
    exponent, the last ``window`` (at most) since the restart at ``base`` but for the
    tangent's first TANGENT_SETTLE; all since ``base`` where that leaves fewer than
    MIN_BATCHES batches (too few to tell a motion's exponent: a budget that ends that soon
    reads the whole way from the start, its contraction included)."""
    count = min(window, k - base - TANGENT_SETTLE)
    if count < MIN_BATCHES * BATCH_REVOLUTIONS:
        count = max(min(window, k - base), 1)
    return k - count, count


@hot
def exponent_bounds(revs, first, count, z):
    """(mean, half): the mean log-stretch per revolution of revolutions first …
    first+count−1 and the half-width of its confidence interval, from the spread of the
    means of the last whole batches of BATCH_REVOLUTIONS (Student's t for their number,
    from the normal quantile z: student_quantile); half = inf with fewer than MIN_BATCHES.
    """
    total = 0.0
    for j in range(first, first + count):
        total += revs[j, REV_LOG_STRETCH]
    mean = total / max(count, 1)
    batches = count // BATCH_REVOLUTIONS
    if batches < MIN_BATCHES or not math.isfinite(mean):
        return mean, math.inf
    start = first + count - batches * BATCH_REVOLUTIONS
    s1 = 0.0
    s2 = 0.0
    for b in range(batches):
        m = 0.0
        for j in range(start + b * BATCH_REVOLUTIONS, start + (b + 1) * BATCH_REVOLUTIONS):
            m += revs[j, REV_LOG_STRETCH]
        m /= BATCH_REVOLUTIONS
        s1 += m
        s2 += m * m
    centre = s1 / batches
    variance = max(s2 - batches * centre * centre, 0.0) / (batches - 1)
    return mean, student_quantile(z, batches - 1) * math.sqrt(variance / batches)


@hot
def stable_cycle_nearby(xs, jac, k, base, n_max, reach):
    """The smallest period n ≤ n_max (section points after ``base``) with
    |x_k − x_{k−n}| ≤ reach whose DP^n over the last n revolutions is stable and whose
    one-Newton-step fixed point lies within reach of x_k: a stable cycle the motion may be
    settling on, as assess_revolution's jumps on agreeing estimates read it; 0: none."""
    return stable_cycle_period(xs, jac, k, base, n_max, reach, True, math.inf)


@hot
def student_quantile(z, dof):
    """Student's t quantile for ``dof`` degrees of freedom at the probability of the normal
    quantile z (Cornish–Fisher expansion to 1/dof⁴; for dof ≥ 3 it lies below the exact
    value by at most 0.4 % at 99 % and 3 % at 99.9 %)."""
    z2 = z * z
    g1 = (z2 + 1.0) * z / 4.0
    g2 = ((5.0 * z2 + 16.0) * z2 + 3.0) * z / 96.0
    g3 = (((3.0 * z2 + 19.0) * z2 + 17.0) * z2 - 15.0) * z / 384.0
    g4 = ((((79.0 * z2 + 776.0) * z2 + 1482.0) * z2 - 1920.0) * z2 - 945.0) * z / 92160.0
    v = float(dof)
    return z + g1 / v + g2 / v**2 + g3 / v**3 + g4 / v**4


@hot
def stretch_tangent(j, u):
    """Apply a one-revolution Jacobian to the unit tangent u; return log of the growth."""
    w0 = j[0] * u[0] + j[1] * u[1]
    w1 = j[2] * u[0] + j[3] * u[1]
    norm = math.hypot(w0, w1)
    if not (norm > 0.0 and math.isfinite(norm)):
        u[0] = 1.0
        u[1] = 0.0
        return -math.inf if norm == 0.0 else math.inf
    u[0] = w0 / norm
    u[1] = w1 / norm
    return math.log(norm)


@hot
def nonperiodic_kind(lyapunov_per_revolution, lyap_tol):
    """Kind of a motion without period ≤ n_max, from its largest Lyapunov exponent.

    > tol: chaotic; within ±tol: quasi-periodic (an invariant circle has a zero
    exponent); < −tol: a stable orbit not yet reached or of longer period.
    """
    if lyapunov_per_revolution > lyap_tol:
        return CHAOTIC
    if lyapunov_per_revolution >= -lyap_tol:
        return QUASIPERIODIC
    return UNCONVERGED


@hot
def multipliers_of(m, out):
    """Floquet multipliers (eigenvalues of DP^n) into out[0..1, re/im]."""
    re0, im0, re1, im1 = eig2(m)
    out[0, 0] = re0
    out[0, 1] = im0
    out[1, 0] = re1
    out[1, 1] = im1


@hot
def near_unit_circle(m, margin):
    """True when a multiplier of M lies within margin of the unit circle."""
    re0, im0, re1, im1 = eig2(m)
    return abs(math.hypot(re0, im0) - 1.0) < margin or abs(math.hypot(re1, im1) - 1.0) < margin

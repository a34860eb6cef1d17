"""Hermite models of a scalar over one step, from its values and derivatives at both ends.

Cubic (values and slopes): the integrator's roots of event functions between step ends,
and where Pn may peak inside a step. Quintic (with second derivatives too): where ε
may have an interior extremum, accurate to O(h⁶). campar.core.extrema locates the
extremum itself on the dense output, from the place these models give.
"""

import numpy as np

from .jit import hot

# ``want_min`` for the functions below: numpy bools, which numba types as a plain bool.
# A literal True or False would be typed as itself and compile a variant of each function
# per value (a longer cold compile, with numba 0.68).
MINIMUM = np.bool_(True)
MAXIMUM = np.bool_(False)


@hot
def hermite_extremum(g0, d0, g1, d1, want_min):
    """Interior extremum of the cubic with values g0, g1 and slopes d0, d1 on [0, 1].

    Slopes are per unit θ (time rate × h). Returns (θ, value); θ = -1 when the
    cubic has no interior minimum (want_min) or maximum (not want_min).
    """
    # g(θ) = a θ³ + b θ² + d0 θ + g0
    a = 2.0 * (g0 - g1) + d0 + d1
    b = 3.0 * (g1 - g0) - 2.0 * d0 - d1
    # g'(θ) = 3a θ² + 2b θ + d0; g'' = 6aθ + 2b
    best = -1.0
    best_val = 0.0
    if abs(a) < 1e-300:
        if abs(b) > 1e-300:
            th = -d0 / (2.0 * b)
            if 0.0 < th < 1.0 and ((b > 0.0) == want_min):
                best = th
    else:
        disc = b * b - 3.0 * a * d0
        if disc >= 0.0:
            sq = np.sqrt(disc)
            for sign in (-1.0, 1.0):
                th = (-b + sign * sq) / (3.0 * a)
                if 0.0 < th < 1.0:
                    curv = 6.0 * a * th + 2.0 * b
                    if (curv > 0.0) == want_min:
                        best = th
    if best >= 0.0:
        best_val = ((a * best + b) * best + d0) * best + g0
    return best, best_val


QUINTIC_NEWTON_ITER = 8


@hot
def quintic_extremum(g0, d0, s0, g1, d1, s1, want_min):
    """Interior extremum of the quintic with values g, slopes d and second derivatives
    s (per unit θ) at θ = 0 and 1, found by Newton's method from the cubic's.

    Returns (θ, value) as hermite_extremum; θ = -1 when the cubic through the same
    values and slopes has no such extremum.
    """
    th, _ = hermite_extremum(g0, d0, g1, d1, want_min)
    if th < 0.0:
        return th, 0.0
    # g(θ) = Σ c_k θ^k with c0 = g0, c1 = d0, c2 = s0 / 2
    dg = g1 - g0
    c2 = 0.5 * s0
    c3 = 10.0 * dg - 6.0 * d0 - 4.0 * d1 - 0.5 * (3.0 * s0 - s1)
    c4 = -15.0 * dg + 8.0 * d0 + 7.0 * d1 + 0.5 * (3.0 * s0 - 2.0 * s1)
    c5 = 6.0 * dg - 3.0 * (d0 + d1) - 0.5 * (s0 - s1)
    x = th
    for _ in range(QUINTIC_NEWTON_ITER):
        slope = (((5.0 * c5 * x + 4.0 * c4) * x + 3.0 * c3) * x + 2.0 * c2) * x + d0
        curv = ((20.0 * c5 * x + 12.0 * c4) * x + 6.0 * c3) * x + 2.0 * c2
        if curv == 0.0 or (curv > 0.0) != want_min:
            x = th  # not converging to this kind of extremum: keep the cubic's place
            break
        step = slope / curv
        x -= step
        if not 0.0 < x < 1.0:
            x = th
            break
        if abs(step) < 1e-13:
            break
    return x, ((((c5 * x + c4) * x + c3) * x + c2) * x + d0) * x + g0

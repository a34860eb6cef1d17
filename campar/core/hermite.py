"""Cubic Hermite models of a scalar over one step, from its values and slopes at both ends.

Shared by the integrator (roots of event functions between step ends) and the
analysis (extremes of ε and Pn inside a step).
"""

import numpy as np

from .jit import hot


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

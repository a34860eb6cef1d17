"""Dormand–Prince 5(4) (Dormand & Prince 1980): the tableau as data, its error estimate
and the 4th-order continuous extension of Shampine (1986), as in SciPy's rk.py.
The stages themselves are stages.rk_stages; the step control is integrator.advance's.
"""

import numpy as np

from .jit import hot

# Dormand–Prince 5(4) tableau (Butcher notation: nodes C, matrix A, weights B).
C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
A = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1 / 5, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3 / 40, 9 / 40, 0.0, 0.0, 0.0, 0.0],
        [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0, 0.0],
        [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0, 0.0],
        [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0.0],
        [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84],
    ]
)
B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0])
# Error weights: 5th-order minus embedded 4th-order solution (7 stages, FSAL).
E = np.array([-71 / 57600, 0.0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40])
# Dense output: y(t + θh) = y + h Σ_j (K^T P)_j θ^{j+1} (Shampine 1986, as in SciPy).
P = np.array(
    [
        [1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
        [0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
        [0.0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
        [0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
        [0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
    ]
)
N_STAGES = 7


@hot
def error_norm(K, h, y, y_new, rtol, atol, n_err):
    """RMS of the DP54 error estimate scaled by atol + rtol·max(|y|, |y_new|)."""
    acc = 0.0
    for i in range(n_err):
        e = 0.0
        for s in range(N_STAGES):
            e += E[s] * K[s, i]
        scale = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        r = h * e / scale
        acc += r * r
    return np.sqrt(acc / n_err)


@hot
def dopri5_dense_eval(K, y, h, theta, n, out):
    """First n components of the state at t + θh from the step's stages K."""
    for i in range(n):
        q1 = 0.0
        q2 = 0.0
        q3 = 0.0
        q4 = 0.0
        for s in range(N_STAGES):
            k = K[s, i]
            q1 += k * P[s, 0]
            q2 += k * P[s, 1]
            q3 += k * P[s, 2]
            q4 += k * P[s, 3]
        out[i] = y[i] + h * theta * (q1 + theta * (q2 + theta * (q3 + theta * q4)))

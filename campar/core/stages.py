"""One explicit Runge–Kutta step: its stages, its embedded error norm and its dense output.

The methods (Dormand–Prince 5(4), DOP853, the classical RK4; campar.core.integrator says
which is which) share one stage buffer, StepWork.K. A step's dense output is read where
the event search or the step's extremes look inside it; DOP853 needs three more stages
for it, computed once per step (``prepare_dense``), which slot CTRL_DENSE of StepWork.ctrl
records until the next step is taken.
"""

from . import dop853
from .dopri5 import N_STAGES, A, C, dopri5_dense_eval, error_norm
from .jit import hot

DP54 = 0
RK4 = 1
DOP853 = 2


def method_tag(code: int) -> tuple:
    """A method as the compiled code receives it (``SolverOptions.method``): a tuple whose
    length is the method's code. numba folds ``len()`` of a tuple argument to a constant
    before typing and prunes the branches it decides, so a job's kernel compiles its own
    stepper only (a literal integer is not pruned on); a DOP853 job compiles neither
    DP5(4) nor RK4: a one-cell run with an empty cache compiles less (benchmarks/RESULTS.md)."""
    return (0,) * code


# The slot of StepWork.ctrl (campar.core.integrator) that is 1 while StepWork.F holds the
# DOP853 dense output of the step in K.
CTRL_DENSE = 6


@hot
def rk_stages(rhs, t, y, h, p, mode, w, a, c, first, last, to_new):
    """Stages first … last of an explicit Runge–Kutta tableau (a, c) into w.K:
    K[s] = rhs(t + c[s] h, y + h Σ_j a[s, j] K[j]). With ``to_new``, stage ``last``
    is f at the new state (row ``last`` of ``a`` holds the weights), left in w.y_new."""
    n = y.shape[0]
    K = w.K
    for s in range(first, last + 1):
        out = w.y_new if to_new and s == last else w.y_stage
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += a[s, j] * K[j, i]
            out[i] = y[i] + h * acc
        rhs(t + c[s] * h, out, p, mode, K[s])
    w.counts[2] += last - first + 1


@hot
def rk_step(rhs, t, y, f, h, p, mode, w, a, c, last):
    """One step of an explicit FSAL-form tableau (DP5(4): last 6; DOP853: 12) from
    (t, y) with f = rhs(t, y): fills K[0 … last] and w.y_new."""
    for i in range(y.shape[0]):
        w.K[0, i] = f[i]
    rk_stages(rhs, t, y, h, p, mode, w, a, c, 1, last, True)


@hot
def rk4_step(rhs, t, y, f, h, p, mode, w):
    """One classical RK4 step; K[0..3] hold the stages, K[6] = rhs at the new point."""
    n = y.shape[0]
    K = w.K
    for i in range(n):
        K[0, i] = f[i]
        w.y_stage[i] = y[i] + 0.5 * h * K[0, i]
    rhs(t + 0.5 * h, w.y_stage, p, mode, K[1])
    for i in range(n):
        w.y_stage[i] = y[i] + 0.5 * h * K[1, i]
    rhs(t + 0.5 * h, w.y_stage, p, mode, K[2])
    for i in range(n):
        w.y_stage[i] = y[i] + h * K[2, i]
    rhs(t + h, w.y_stage, p, mode, K[3])
    for i in range(n):
        w.y_new[i] = y[i] + h / 6.0 * (K[0, i] + 2.0 * K[1, i] + 2.0 * K[2, i] + K[3, i])
    rhs(t + h, w.y_new, p, mode, K[6])
    w.counts[2] += 4


@hot
def step_error(method, K, h, y, y_new, rtol, atol, n_err):
    """Scaled error norm of the step in K by the method's embedded estimate (≤ 1: accept)."""
    if len(method) == DOP853:
        return dop853.dop853_error(K, h, y, y_new, rtol, atol, n_err)
    return error_norm(K, h, y, y_new, rtol, atol, n_err)


@hot
def end_row(method):
    """The row of StepWork.K that holds f at the end of the step."""
    return dop853.N_STAGES if len(method) == DOP853 else N_STAGES - 1


@hot
def prepare_dense(rhs, method, t, y, h, p, mode, w):
    """Make the dense output of the step in w readable: DOP853 needs three more
    stages (once per step, only for steps whose interior is read)."""
    if len(method) == DOP853 and w.ctrl[CTRL_DENSE] != 1.0:
        first, last = dop853.N_STAGES + 1, dop853.N_STAGES_EXTENDED - 1
        rk_stages(rhs, t, y, h, p, mode, w, dop853.A, dop853.C, first, last, False)
        dop853.dop853_dense_coefficients(y, w.y_new, h, w.K, w.F)
        w.ctrl[CTRL_DENSE] = 1.0


@hot
def dense_eval(method, w, y, y_new, h, theta, n, out):
    """First n components of the state at t + θh (0 ≤ θ ≤ 1) from the last step
    (DOP853: after prepare_dense)."""
    K = w.K
    if len(method) == DOP853:
        dop853.dop853_dense_eval(w.F, y, theta, n, out)
    elif len(method) == DP54:
        dopri5_dense_eval(K, y, h, theta, n, out)
    else:
        # cubic Hermite through (y, f) at both ends
        t2 = theta * theta
        t3 = t2 * theta
        h00 = 2.0 * t3 - 3.0 * t2 + 1.0
        h10 = t3 - 2.0 * t2 + theta
        h01 = -2.0 * t3 + 3.0 * t2
        h11 = t3 - t2
        for i in range(n):
            out[i] = h00 * y[i] + h10 * h * K[0, i] + h01 * y_new[i] + h11 * h * K[6, i]


@hot
def take_step(rhs, method, t, y, f, h, p, mode, w):
    if len(method) == DP54:
        rk_step(rhs, t, y, f, h, p, mode, w, A, C, N_STAGES - 1)
    elif len(method) == DOP853:
        rk_step(rhs, t, y, f, h, p, mode, w, dop853.A, dop853.C, dop853.N_STAGES)
    else:
        rk4_step(rhs, t, y, f, h, p, mode, w)
    w.ctrl[CTRL_DENSE] = 0.0  # K holds a new step

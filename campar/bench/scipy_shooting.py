"""An independent shooting of the model with SciPy: the peer of the continuation's checks.

Built on campar.bench.scipy_model (SciPy's DOP853, exact contact events) and nothing of
campar's kernel or continuation: every derivative is a central difference quotient of
the SciPy section map, so agreement with campar's exact (variational) Jacobians and its
located bifurcations is a check of both. Slow (a few seconds a fixed point), exact enough:
at rtol 1e-12 fixed points agree to ~1e-10 and multipliers to ~1e-7.
"""

import math

import numpy as np

from .scipy_model import Model, integrate

RTOL = 1e-12
ATOL = 1e-14
STATE_STEP = 1e-5  # central differences of the map in (y, y')
PARAMETER_STEP = 1e-6  # … and in a parameter (relative to max(1, |λ|))
NEWTON_TOL = 1e-10


def section_map(parameters: dict, x, n: int, clamp: bool = True) -> np.ndarray:
    """Pⁿ(x) by SciPy: n revolutions from (y, y') at θ = 0."""
    model = Model(clamp=clamp, **parameters)
    image, _, _ = integrate(model, np.asarray(x, dtype=float), n, rtol=RTOL, atol=ATOL)
    return np.asarray(image, dtype=float)


def jacobian(parameters: dict, x, n: int, clamp: bool = True) -> np.ndarray:
    """DPⁿ(x) by central differences of the SciPy map."""
    m = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = STATE_STEP
        m[:, j] = (
            section_map(parameters, x + e, n, clamp) - section_map(parameters, x - e, n, clamp)
        ) / (2 * STATE_STEP)
    return m


def fixed_point(
    parameters: dict, guess, n: int, clamp: bool = True, max_iterations: int = 20
) -> tuple[np.ndarray, np.ndarray]:
    """(x, DPⁿ(x)) with Pⁿ(x) = x to NEWTON_TOL, by Newton with the difference Jacobian."""
    x = np.asarray(guess, dtype=float)
    for _ in range(max_iterations):
        residual = section_map(parameters, x, n, clamp) - x
        if np.max(np.abs(residual)) <= NEWTON_TOL:
            return x, jacobian(parameters, x, n, clamp)
        x = x - np.linalg.solve(jacobian(parameters, x, n, clamp) - np.eye(2), residual)
    raise RuntimeError(f"SciPy shooting did not converge from {guess} at {parameters}")


def defining_function(kind: str):
    """ψ(DPⁿ) whose root is a bifurcation: PD det(I + M), SN det(I − M)."""
    sign = {"PD": 1.0, "SN": -1.0}[kind]
    return lambda m: float(np.linalg.det(np.eye(2) + sign * m))


def bifurcation_point(
    kind: str,
    parameters: dict,
    parameter: str,
    guess,
    n: int,
    clamp: bool = True,
    max_iterations: int = 12,
):
    """The PD or SN point near (guess, parameters[parameter]): Newton's method on the
    augmented system Pⁿ(x; λ) − x = 0, ψ(DPⁿ(x; λ)) = 0 in (y, y', λ), its Jacobian by
    central differences. Returns (λ, x)."""
    psi = defining_function(kind)

    def g(u):
        par = {**parameters, parameter: u[2]}
        image = section_map(par, u[:2], n, clamp)
        return np.array([*(image - u[:2]), psi(jacobian(par, u[:2], n, clamp))])

    u = np.array([guess[0], guess[1], parameters[parameter]], dtype=float)
    for _ in range(max_iterations):
        value = g(u)
        if np.max(np.abs(value[:2])) <= NEWTON_TOL and abs(value[2]) <= 1e-9:
            return float(u[2]), u[:2]
        jac = np.empty((3, 3))
        for j in range(3):
            h = PARAMETER_STEP * max(1.0, abs(u[j])) if j == 2 else STATE_STEP
            e = np.zeros(3)
            e[j] = h
            jac[:, j] = (g(u + e) - g(u - e)) / (2 * h)
        step = np.linalg.solve(jac, -value)
        u = u + step
        if not np.all(np.isfinite(u)):
            break
    raise RuntimeError(f"SciPy found no {kind} point near {guess} at {parameters}")


def multipliers(m: np.ndarray) -> np.ndarray:
    """Eigenvalues of a 2×2 matrix, the larger modulus first."""
    values = np.linalg.eigvals(m).astype(complex)
    return values[np.argsort(-np.abs(values), kind="stable")]


def liouville_determinant(parameters: dict, x, n: int, clamp: bool = True) -> float:
    """det DPⁿ = exp(∮ div f dt) along the orbit from x (Liouville's formula)."""
    model = Model(clamp=clamp, **parameters)
    _, _, div = integrate(
        model, np.asarray(x, float), n, rtol=RTOL, atol=ATOL, with_divergence=True
    )
    return math.exp(div)

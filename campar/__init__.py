"""campar — two-parameter bifurcation maps of the cam–follower impact oscillator.

The numerical core (``model``, ``integrator``, ``analysis``, ``kernel``) is
compiled with numba; ``simulate_point`` runs one cell from Python.
"""

__version__ = "0.1.0"

from .jitcache import ensure_fresh_cache

ensure_fresh_cache()


def __getattr__(name):
    # Lazy: importing campar for its version or CLI must not compile the kernel.
    if name in ("simulate_point", "PointResult"):
        from . import point

        return getattr(point, name)
    raise AttributeError(f"module 'campar' has no attribute {name!r}")

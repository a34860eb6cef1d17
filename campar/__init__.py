"""campar — two-parameter bifurcation maps of the cam–follower impact oscillator.

The package, layer by layer (each may import only the layers above it):

- ``campar.core``: the numerical core, compiled with numba (model, integrator,
  analysis, one revolution, the cell kernel);
- ``campar.model``: the model as one value (``Model``: everything a cell's numbers
  depend on, its schema and bounds) and one cell or chain computed from it;
- ``campar.sweep``: the sweep machinery (job, plan, tile, runner, progress, store);
- ``campar.views``: one cell, one bifurcation line, and figures;
- ``campar.paper``: the study of the source paper (claims, figure set, report);
- ``campar.api``: what the commands do, from Python (``run``, ``forecast``, ``line``);
- ``campar.bench``: ``campar bench``; ``campar.cli``: the ``campar`` command, a module
  per command family.

The public names (``dir(campar)``, docs/cli.md): ``run``, ``forecast``, ``line``,
``open``, ``committed``, ``simulate_point``, ``PointResult``, ``cell``, ``StoredCell``,
``Model``, ``find_attractors``, ``BifurcationLine``, ``Job``, ``load_job``.

Importing campar does nothing but define names: the numba cache is checked when
the kernel is first run (``campar.core.jitcache.ensure_fresh_cache``).
"""

__version__ = "0.1.0"

# Lazy: importing campar for its version or CLI must not compile the kernel.
_EXPORTS = {
    "run": "campar.api",
    "forecast": "campar.api",
    "line": "campar.api",
    "open": "campar.views.dataset",
    "committed": "campar.views.dataset",
    "simulate_point": "campar.views.point",
    "cell": "campar.views.cell",
    "StoredCell": "campar.views.cell",
    "Model": "campar.model",
    "PointResult": "campar.views.point",
    "find_attractors": "campar.views.attractors",
    "BifurcationLine": "campar.views.line",
    "Job": "campar.sweep.job",
    "load_job": "campar.sweep.job",
}
__all__ = ["__version__", *_EXPORTS]


def __getattr__(name):
    if name in _EXPORTS:
        import importlib

        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'campar' has no attribute {name!r}")


def __dir__():
    return sorted(__all__)

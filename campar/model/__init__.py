"""The model layer: everything one cell's numbers depend on, as one frozen value.

``Model`` holds the parameters (ω, f0, μkn, μcn, ζ), the force law's options, the cam and
the contact (``model``), the start (``initial``), the integrator, the transient and the
classification: every job key outside the sweep's own sections (sweep, fixed's grid,
tiles, chains, store, outputs, attractors, curves). It is built and validated in one
place (``Model.build``) from a job's sections, from command-line flags and from Python
keywords, with one error message per bad value whatever the entry.

May import: campar.core, campar.errors (core < model < sweep, continuation, views).
Importing this package loads pydantic and numpy only; ``campar.model.compute`` turns a
Model into kernel calls (numba loads there).
"""

from .model import FIELDS, Model, ModelField  # noqa: F401

__all__ = ["FIELDS", "Model", "ModelField"]

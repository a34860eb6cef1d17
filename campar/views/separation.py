"""Separation speeds of result stores, for the cam designer: one curve per store.

A store of a job with the ``separation`` output holds each row's separation speed (the
lowest ω at which the follower detaches along the row's chain) and the largest intrusion
and contact force below it (campar.sweep.separation). ``separation_curve`` reads them
with the row parameter and names the store's laws, ``describe_curves`` prints them, and
``campar.views.plot.design`` draws several stores on one plot (``campar separation``).
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import CamparError
from ..sweep.store import read_store


@dataclass
class SeparationCurve:
    store: Path
    label: str  # the laws of the store's job ("cycloidal", "rise cosine, fall cycloidal", …)
    parameter: str  # the second axis
    values: np.ndarray  # its values, one a row
    speed: np.ndarray  # separation speed of each row (NaN: none on its grid)
    eps_max: np.ndarray  # largest intrusion below it
    pn_max: np.ndarray  # largest contact force below it


def laws_label(job) -> str:
    """The store's cam and contact laws in a few words."""
    cam, contact = job.model.cam, job.model.contact
    if cam.table is not None:
        text = f"table {Path(cam.table).name}"
    elif cam.rise == cam.fall:
        text = cam.rise
    else:
        text = f"rise {cam.rise}, fall {cam.fall}"
    if contact.law != "hunt-crossley" or contact.n != 1.5:
        text += f"; {contact.law} n = {contact.n:g}"
    return text


def separation_curve(path: str | Path) -> SeparationCurve:
    """The separation speeds of a store's rows (CamparError where it has none)."""
    with read_store(path) as reader:
        job = reader.job
        if not job.wants("separation"):
            raise CamparError(
                f"{path}: its job has no separation output; add separation to "
                "its outputs and run it"
            )
        if job.chains.direction == "both":
            raise CamparError(
                f"{path}: a both-direction store; separation curves are drawn for one direction"
            )
        rows = {
            name: reader.read(name)[:, 0]
            for name in ("separation_omega", "separation_eps_max", "separation_pn_max")
        }
    return SeparationCurve(
        Path(path),
        laws_label(job),
        job.second,
        job.second_values,
        rows["separation_omega"],
        rows["separation_eps_max"],
        rows["separation_pn_max"],
    )


def describe_curves(curves: list[SeparationCurve]) -> str:
    """Per store: the separation speed's range over its rows and where it is lowest."""
    lines = []
    for c in curves:
        found = np.isfinite(c.speed)
        if not found.any():
            lines.append(f"{c.label}: no separation speed on the grid ({c.store})")
            continue
        low = int(np.nanargmin(c.speed))
        lines.append(
            f"{c.label}: separation speed {np.nanmin(c.speed):.6f} … {np.nanmax(c.speed):.6f} "
            f"over {c.parameter} {c.values[0]:g} … {c.values[-1]:g} ({found.sum()} of "
            f"{len(c.speed)} rows), lowest at {c.parameter} = {c.values[low]:g}; largest "
            f"contact force below it {np.nanmax(c.pn_max):.4g} ({c.store})"
        )
    return "\n".join(lines)

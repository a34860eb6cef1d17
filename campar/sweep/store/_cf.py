"""The store in the ecosystem's own language: CF-1.10 attributes of every variable and the file.

Numbers carry ``long_name``, ``units`` ("1": the model is dimensionless) and a
``comment`` naming the scaling; codes carry ``flag_values``/``flag_masks`` and
``flag_meanings`` taken from ``campar.core.codes`` (cf_xarray decodes them);
uncomputed cells are ``_FillValue``. The global attributes name the model, its
force law, how chains start and run, the job and the software (``Conventions``,
``title``, ``source``, ``history``, ``comment``), besides campar's own ``job``,
``job_hash``, ``versions``, ``runs`` and ``campar_store``.
"""

import numpy as np

from ... import __version__
from ...core.codes import KIND_NAMES, STATUS_MESSAGES, Flag, Status
from ..arrays import ARRAY_DOCS
from ..curves_job import CURVE_ARRAY_DOCS
from ..job import Job

CONVENTIONS = "CF-1.10"

# The model's parameters (docs/model.md): what each is, and its scaling.
PARAMETER_DOCS = {
    "omega": (
        "cam angular speed",
        "cam angular speed / natural frequency ωn; the cam angle is θ = ω t with t in "
        "units of 1/ωn; the continuation axis of every chain",
    ),
    "f0": ("preload", "preload / (K1 h), the paper's pressure"),
    "mu_kn": ("contact stiffness parameter", "contact stiffness k = μkn / (1 − μkn)"),
    "mu_cn": ("contact damping parameter", "contact damping c = 2 ζ μcn / (1 − μcn)"),
    "zeta": ("spring damping ratio", "ζ in y'' + 2 ζ y' + y = Pn − f0"),
    "y0": (
        "initial displacement",
        "y at θ = 0, where the cell's run starts, in units of the stroke h (basin jobs)",
    ),
    "phi1": ("cam rise angle", "Φ1 in radians; the near dwell Φ4 takes up the difference"),
    "phi2": ("cam far-dwell angle", "Φ2 in radians; the near dwell Φ4 takes up the difference"),
    "phi3": ("cam fall angle", "Φ3 in radians; the near dwell Φ4 takes up the difference"),
    "phi4": ("cam near-dwell angle", "Φ4 in radians; the far dwell Φ2 takes up the difference"),
    "n": ("contact force exponent", "n in Pn = k ε^n (1 + c ε'); 1.5: Hertz point contact"),
    "restitution": (
        "coefficient of restitution",
        "e of the contact law (Lankarani–Nikravesh, Flores et al.): damping c from e and the "
        "impact velocity",
    ),
    "ydot0": (
        "initial velocity",
        "dy/dt at θ = 0, where the cell's run starts, t in units of 1/ωn (basin jobs)",
    ),
}

SCALING = (
    "dimensionless model (campar docs/model.md): y'' + 2 ζ y' + y = Pn − f0 with lengths in "
    "units of the stroke h, time t in units of 1/ωn (ωn the natural frequency), forces in "
    "units of K1 h; the cam angle is θ = ω t"
)
FORCE_LAWS = {
    "clamp": "Hunt–Crossley Pn = max(0, k ε^1.5 (1 + c ε')): contact cannot pull",
    "allow": "Hunt–Crossley Pn = k ε^1.5 (1 + c ε') for ε > 0, as printed in the paper",
}

DUTY_CYCLES = {
    "separation": "duty cycle dc: fraction of the steady window's time with ε < 0 (separated)",
    "force": "duty cycle dc: fraction of the steady window's time with Pn = 0 (separated, "
    "or in contact with the force clamped to zero)",
}
CAM_VELOCITIES = {
    "chain": "cam velocity in the force's ε': ẏc = ω dyc/dθ (chain rule)",
    "literal": "cam velocity in the force's ε': ẏc = dyc/dθ, the paper's eq. 6 as printed "
    "(without the factor ω; ε itself is yc(ω t) − y)",
}


def words(name: str) -> str:
    """A CF flag meaning: one word of letters, digits, '_', '-', '.', '+', '@'."""
    return name.lower().replace(" ", "_")


def flag_attrs(name: str, dtype: np.dtype) -> dict:
    """flag_values/flag_masks and flag_meanings of a code array (typed as the array)."""
    if name in ("kind", "attractor_kind"):
        codes = {int(k): words(text) for k, text in KIND_NAMES.items()}
    elif name == "status":
        codes = {int(s): words(s.name) for s in Status}
    elif name == "flags":
        masks = [f for f in Flag if f.value]
        return {
            "flag_masks": np.array([f.value for f in masks], dtype),
            "flag_meanings": " ".join(words(f.name) for f in masks),
        }
    elif name == "done":
        codes = {0: "pending", 1: "committed"}
    else:
        return {}
    return {
        "flag_values": np.array(list(codes), dtype),
        "flag_meanings": " ".join(codes.values()),
    }


def cell_attrs(job: Job, name: str, dtype: np.dtype, fill) -> dict:
    """CF attributes of a per-cell array (``_FillValue``: the value of uncomputed cells)."""
    long_name, units, comment = ARRAY_DOCS[name] if name in ARRAY_DOCS else CURVE_ARRAY_DOCS[name]
    attrs = {"long_name": long_name}
    if units is not None:
        attrs["units"] = units
    attrs["comment"] = comment
    if name == "status":
        attrs["comment"] += "; " + "; ".join(
            f"{words(s.name)}: {text}" for s, text in STATUS_MESSAGES.items() if s
        )
    attrs.update(flag_attrs(name, dtype))
    attrs["_FillValue"] = fill
    attrs["coordinates"] = " ".join(sorted(job.fixed))  # the fixed parameters, as scalars
    return attrs


def coordinate_attrs(job: Job, name: str) -> dict:
    """CF attributes of a coordinate: a model parameter, or a label along a dimension."""
    if name in PARAMETER_DOCS:
        long_name, comment = PARAMETER_DOCS[name]
        return {"long_name": long_name, "units": "1", "comment": comment}
    rows = f"index along {job.second}, the second axis"
    return {
        "component": {"long_name": "state component", "comment": "y: displacement, ydot: velocity"},
        "part": {"long_name": "part of a complex number"},
        "multiplier": {"long_name": "Floquet multiplier", "comment": "by modulus, largest first"},
        "attractor": {
            "long_name": "attractor of the cell",
            "comment": "rank by basin fraction, 1 the most frequent (job key attractors)",
        },
        "section_point": {"long_name": "section point", "comment": "in revolution order"},
        "tile": {
            "long_name": "tile",
            "comment": f"tiles.rows = {job.tiles.rows} consecutive chains: a unit of work, "
            "of storage (one chunk of every array) and of commit (done)",
        },
        "direction": {
            "long_name": "sweep direction of the chains",
            "comment": "down: every chain ran omega decreasing (the paper's direction); up: "
            "omega increasing; each from the job's chain start (chain_start), the same way",
        },
        "tile_direction": {"long_name": "sweep direction of the tile's chains"},
        "tile_row_start": {"long_name": "first chain of the tile", "comment": rows},
        "tile_row_stop": {"long_name": "one past the last chain of the tile", "comment": rows},
        "point": {
            "long_name": "point of the task's curves",
            "comment": "curves_per_task slots of curves.points points, in curve order",
        },
        "task": {"long_name": "task", "comment": "a group of seeds from the map's typed edges"},
        "plane_axis": {
            "long_name": "axis of the map's plane",
            "comment": "omega, then the map's second parameter (the curves job's curves.plane)",
        },
    }[name]


def done_attrs(dtype: np.dtype) -> dict:
    return {
        "long_name": "tile committed",
        "comment": "set only after the tile's arrays are in the store (a resumed run "
        "computes the pending tiles)",
        **flag_attrs("done", dtype),
        "coordinates": "tile_row_start tile_row_stop",
    }


def checksum_attrs(dtype: np.dtype) -> dict:
    return {
        "long_name": "checksum of the tile's arrays",
        "comment": "BLAKE2b digest (8 bytes, little-endian) of every per-cell array over the "
        "tile's rows, in the store's order, each with its name, dtype and shape; written "
        "before the tile's done flag; 0: none (campar verify checks it)",
        "coordinates": "tile_row_start tile_row_stop",
    }


def global_attrs(job: Job, created: str) -> dict:
    """The file's CF and campar attributes, besides campar's own (job, runs, …)."""
    return {
        "Conventions": CONVENTIONS,
        "title": title(job),
        "source": f"campar {__version__}: cam–follower impact oscillator, "
        f"{job.integrator.method} integrator (rtol {job.integrator.rtol:g}, "
        f"atol {job.integrator.atol:g}), {job.transient.mode} transient",
        "history": history(job, created, __version__, []),
        "comment": SCALING,
        "model": "cam–follower impact oscillator: flat-faced follower on a cosine-acceleration "
        "cam, one degree of freedom, nonlinear (Hunt–Crossley) contact",
        "force_law": FORCE_LAWS[job.model.tensile],
        **law_attrs(job),
        "tensile": job.model.tensile,
        "duty_cycle": job.model.duty_cycle,
        "duty_cycle_definition": DUTY_CYCLES[job.model.duty_cycle],
        "cam_velocity": job.model.cam_velocity,
        "cam_velocity_definition": CAM_VELOCITIES[job.model.cam_velocity],
        **chain_attrs(job),
        "campar_version": __version__,
        "date_created": created,
    }


def title(job: Job) -> str:
    if job.kind == "curves":
        return (
            f"campar curves {job.name}: bifurcation curves in the "
            f"({', '.join(job.curves.plane)}) plane of {job.curves.map}"
        )
    return f"campar {job.kind} {job.name}: steady motions over ({job.first}, {job.second})" + (
        f" at omega = {job.parameter('omega'):g}" if job.kind == "basin" else ""
    )


def law_attrs(job: Job) -> dict:
    """The cam and contact laws where they are not the paper's (its stores' attributes
    name them in ``model`` and ``force_law``)."""
    cam, contact = job.model.cam, job.model.contact
    attrs = {}
    if cam != type(cam)():
        attrs["cam"] = (
            f"table {cam.table} (sha256 {cam.table_sha256}, joins {cam.table_joins})"
            if cam.table
            else f"rise {cam.rise}, fall {cam.fall}"
        )
        attrs["cam_angles"] = "phi1 … phi4 = " + ", ".join(f"{a:.12g}" for a in cam.angles)
    if contact != type(contact)():
        attrs["contact_law"] = f"{contact.law}, n = {contact.n:g}" + (
            f", restitution {contact.restitution}, impact floor {contact.impact_floor}"
            if contact.law != "hunt-crossley"
            else ""
        )
    return attrs


def chain_attrs(job: Job) -> dict:
    """Where the runs start and which way they go: a map's chains, or a basin's cells."""
    if job.kind == "curves":
        return {
            "chain_start": "seeds",
            "chain_start_state": "each task from its seeds' "
            "stored states on the map (curves.tasks)",
            "sweep_direction": "none",
        }
    if job.kind == "basin":
        return {
            "chain_start": "grid",
            "chain_start_state": "each cell from its own (y0, ydot0) at θ = 0, chaos called "
            "only at the end of the transient budget (as campar point --attractors)",
            "sweep_direction": "none",
        }
    start = job.initial
    state = f"y = {start.y:g}, ydot = {start.v:g} at θ = 0"
    if job.chains.start == "continue":
        state += f", {job.second} = {job.second_values[0]:g} (first column)"
    return {
        "chain_start": job.chains.start,
        "chain_start_state": state,
        "sweep_direction": job.chains.direction,
    }


def history_line(when: str, version: str, what: str) -> str:
    return f"{when} campar {version}: {what}"


def history(job: Job, created: str, version: str, runs: list[dict]) -> str:
    """CF history: when and by which campar the store was created, then one line per run."""
    lines = [history_line(created, version, f"created for job {job.name}")]
    for run in runs:
        what = f"run {run.get('outcome', '?')}, {run.get('tiles', '?')} tiles"
        if "ranks" in run:
            what += f" on {run['ranks']} rank" + ("s" if run["ranks"] != 1 else "")
        lines.append(history_line(run.get("end", "?"), run.get("campar", "?"), what))
    return "\n".join(lines)

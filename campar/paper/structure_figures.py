"""The gallery's figures of attractor structure: hysteresis, multistability, curves with zooms.

Called by ``campar.paper.gallery.make_gallery`` for each force law it draws, after the
paper's own figures:

- per plane, a hysteresis map (``structure.hysteresis_job``: both sweep directions along
  the paper's path) and a multistability map (``structure.census_job``: the number of
  distinct attractors the census finds per cell);
- the basin of the bistable cell (``structure.basin_job``, a basin store);
- for the (ω, f0) and (ω, μkn) planes, the map with its typed bifurcation curves (the
  plane's own store: ω down along the paper's path, ``campar plot --bifurcations
  --trace``) and three zoom panels (``structure.ZOOMS``), each its own finer job
  (``structure.zoom_job``) drawn over its window with its own curves.

Each figure is saved through ``Gallery.save`` (its .yaml sidecar, an index entry), and
every job behind it is written next to it as a runnable job file.
"""

import time

from ..views.cycles import settled_cycles
from . import setups, structure
from .figure_files import MAP_FIGURES, PLANE_SYMBOLS, write_yaml
from .structure_stats import jump_summary, load_both, load_census

PAIRS_SHOWN = 4  # label pairs a caption names
BASIN_STEM = "bistable_basin"  # the job file beside it is basin_bistable.yaml


def draw_structure(g) -> None:
    """Every figure of this module for the gallery ``g`` (one force law)."""
    for plane in setups.PLANES:
        draw_hysteresis(g, plane)
        draw_multistability(g, plane)
    for plane in structure.ZOOM_PLANES:
        draw_zooms(g, plane)
    draw_basin(g)


def draw_basin(g) -> None:
    """The basin of the bistable cell: every start coloured by the attractor it reached."""
    from ..views.dataset import open as open_store
    from ..views.plot.basin import plot_basin

    job = structure.basin_job(g.size, g.tensile)
    store = compute(g, job)
    with open_store(store) as ds:
        figure = plot_basin(ds)
        found = [
            f"{label} {100 * fraction:.1f} %"
            for label, fraction in zip(
                ds["attractor_label"].values, ds["attractor_fraction"].values, strict=True
            )
        ]
    rows, cols = job.shape
    caption = (
        f"basin of attraction at ω = {job.parameter('omega'):g}, μkn = "
        f"{job.parameter('mu_kn'):g} (job {job.name}.yaml): {cols} × {rows} starts (y0, ẏ0) "
        f"at θ = 0, each run to its steady motion and coloured by the attractor it reached "
        f"(attractors matched by their cycles' section points, not their labels): "
        f"{', '.join(found) or 'none settled'}; each attractor's own σn points drawn on it"
    )
    recipe = {
        "job": f"{job.name}.yaml",
        "store": str(store),
        "view": "basin",
        "command": f"campar run {job.name}.yaml; campar plot {store}",
        "attractors": found,
    }
    g.save(figure, BASIN_STEM, caption, recipe, start="grid", direction="none")


def axes_text(job) -> str:
    return ", ".join(PLANE_SYMBOLS[name] for name in job.sweep)


def compute(g, job):
    """Run (or reuse) ``job`` into the gallery's stores, write its job file beside the
    figures, and count the seconds as plane time."""
    clock = time.perf_counter()
    store = structure.run(job, g.stores)
    g.plane_seconds += time.perf_counter() - clock
    data = job.to_dict()
    data["store"] = str(store)
    write_yaml(g.outdir / f"{job.name}.yaml", data)
    return store


def pairs_text(pairs, limit: int = PAIRS_SHOWN) -> str:
    shown = ", ".join(f"{a} / {b} ({n})" for (a, b), n in pairs[:limit])
    more = sum(n for _, n in pairs[limit:])
    return shown + (f", others {more}" if more else "")


def draw_hysteresis(g, plane: str) -> None:
    from ..views.dataset import open as open_store
    from ..views.plot import plot_map

    job = structure.hysteresis_job(plane, g.size, g.tensile)
    store = compute(g, job)
    with open_store(store) as ds:
        layers = [
            {k: ds[k].isel(direction=d).values for k in ("kind", "status", "n", "sections")}
            for d in (0, 1)
        ]
        arrays = {
            "hysteresis": ds["hysteresis"].values,
            "computed": (ds["kind"].values >= 0).all(axis=0),
        }
    arrays["compared"] = settled_cycles(**layers[0]) & settled_cycles(**layers[1])
    jumps = jump_summary(load_both(store, typed=False))
    rows, cols = job.shape
    low = min(job.omega)
    caption = (
        f"hysteresis on the ({axes_text(job)}) plane, {rows} × {cols} cells, job "
        f"{job.name}.yaml: every chain swept ω down along the paper's path (the plane's 2-D "
        f"continuation from its corner) and ω up from the mirror start (first column at "
        f"ω = {low:g}, each row from there); red: the two sweeps end on different converged "
        f"cycles ({jumps.cells} of {jumps.compared} cells where both are periodic; down / up "
        f"labels there: {pairs_text(jumps.pairs) or 'none'}); white: a sweep not periodic "
        f"({jumps.uncompared_differ} of these cells carry different labels)"
    )
    recipe = {
        "job": f"{job.name}.yaml",
        "store": str(store),
        "view": "hysteresis",
        "command": f"campar run {job.name}.yaml; campar plot {store} --what hysteresis",
        "hysteretic_cells": jumps.cells,
        "compared_cells": jumps.compared,
    }
    g.save(
        plot_map(job, arrays, "hysteresis"),
        f"{plane}_hysteresis",
        caption,
        recipe,
        start="continue",
        direction="both",
    )


def draw_multistability(g, plane: str) -> None:
    from ..views.plot import plot_map

    job = structure.census_job(plane, g.size, g.tensile)
    store = compute(g, job)
    census = load_census(store)
    n = census.n_attractors
    arrays = {"n_attractors": n, "computed": n >= 0}
    rows, cols = job.shape
    multi = int((n >= 2).sum())
    caption = (
        f"multistability on the ({axes_text(job)}) plane, {rows} × {cols} cells, job "
        f"{job.name}.yaml: distinct attractors per cell found by a census of "
        f"{job.attractors.starts} starts (rest, then Halton points over y ∈ [−1, 2] h, ẏ ∈ "
        f"±1.5 ω h at θ = 0) and the chain's own state (ω down along the paper's path); "
        f"{multi} of {int((n >= 0).sum())} cells hold ≥ 2 attractors, "
        f"{int(census.unsettled.sum())} starts settled on none"
    )
    recipe = {
        "job": f"{job.name}.yaml",
        "store": str(store),
        "view": "multistability",
        "command": f"campar run {job.name}.yaml; campar plot {store} --what multistability",
        "multistable_cells": multi,
    }
    g.save(
        plot_map(job, arrays, "multistability"),
        f"{plane}_multistability",
        caption,
        recipe,
        start="continue",
        direction="down",
    )


def store_labels(store):
    """(job, arrays kind/n/p/computed) of a store's map."""
    from ..sweep.store import read_store
    from ..views.plot import computed_mask

    with read_store(store) as reader:
        arrays = {name: reader.read(name) for name in ("kind", "n", "p")}
        arrays["computed"] = computed_mask(reader.job, reader.done)
        return reader.job, arrays


def counts_text(found) -> str:
    counts = {k: v for k, v in found.counts().items() if v}
    return ", ".join(f"{k} {v}" for k, v in counts.items()) or "none"


def draw_zooms(g, plane: str) -> None:
    from ..views.boundaries import store_boundaries
    from ..views.map_curves import curves_beside, describe_curves
    from ..views.plot.maps import MapGrid
    from ..views.plot.zooms import Panel, plot_zoom_set

    job = setups.plane_job(plane, g.size, g.tensile)
    clock = time.perf_counter()
    store = setups.run_plane(job, g.stores)
    g.plane_seconds += time.perf_counter() - clock
    parent, arrays = store_labels(store)
    curves = store_boundaries(store, trace=True)
    zooms = structure.ZOOMS[plane]
    symbol = PLANE_SYMBOLS[job.second]
    main = Panel(
        MapGrid.from_job(parent),
        arrays,
        curves,
        f"(a) {job.shape[0]} × {job.shape[1]} cells, Δω = "
        f"{structure.spacing(parent)[0]:.3g}, Δ{symbol} = "
        f"{structure.spacing(parent)[1]:.3g}",
        windows=tuple((z.key, z.omega, z.second) for z in zooms),
    )
    panels, recipes, texts = [], [], []
    for zoom in zooms:
        zjob = structure.zoom_job(plane, zoom.key, g.size, g.tensile)
        zstore = compute(g, zjob)
        zparent, zarrays = store_labels(zstore)
        found = store_boundaries(zstore, omega=zoom.omega, trace=True)
        continued = curves_beside(zstore, shoot=setups.SIZES[g.size].shoot)
        dw, ds = structure.spacing(zjob)
        panels.append(
            Panel(
                MapGrid.from_job(zparent),
                zarrays,
                found,
                f"({zoom.key}) as the paper's {zoom.paper}: recomputed, "
                f"Δω = {dw:.3g}, Δ{symbol} = {ds:.3g}",
                zoom.omega,
                zoom.second,
                zoom.key,
                continued=continued,
            )
        )
        texts.append(
            f"({zoom.key}) ω {zoom.omega[0]:g}–{zoom.omega[1]:g}, {symbol} "
            f"{zoom.second[0]:g}–{zoom.second[1]:g}: {zoom.shows}; recomputed as "
            f"job {zjob.name}.yaml (Δω = {dw:.3g}, Δ{symbol} = {ds:.3g}); typed "
            f"edges {counts_text(found)}; continued curves "
            f"{describe_curves(continued)}"
        )
        recipes.append(
            {
                "key": zoom.key,
                "paper": zoom.paper,
                "omega": list(zoom.omega),
                "second": list(zoom.second),
                "job": f"{zjob.name}.yaml",
                "store": str(zstore),
                "spacing": [dw, ds],
                "curves": found.counts(),
                "command": f"campar run {zjob.name}.yaml; campar plot {zstore} "
                f"--bifurcations --trace --omega {zoom.omega[0]:g}:"
                f"{zoom.omega[1]:g}",
            }
        )
    caption = (
        f"bifurcation curves (as the paper's {MAP_FIGURES[plane].replace('fig', 'Fig. ')}a, "
        f"c–e) on the ({axes_text(job)}) plane: (a) the n-p map of job {job.name}.yaml with "
        f"every edge between different labels typed from the stored multipliers and traced "
        f"orbits (PD, SN, NS = the paper's Hopf, G grazing, chaos, jump; unknown edges "
        f"counted, not drawn; curves {counts_text(curves)}); (c)–(e) each recomputed on its "
        f"own finer grid along the paper's path (its first column the chain along {symbol} "
        f"at ω = {parent.omega[0]:g} from the state the plane's path reaches at the window's "
        f"starting edge, its rows ω down from {parent.omega[0]:g} at the window's spacing), "
        "drawn over its window only, its edges typed on its own cells and its PD, SN and G "
        "curves continued from them (campar curves, lines): " + "; ".join(texts)
    )
    recipe = {
        "job": f"{job.name}.yaml",
        "store": str(store),
        "command": f"campar plot {store} --bifurcations --trace",
        "curves": curves.counts(),
        "zooms": recipes,
    }
    figure = plot_zoom_set(main, panels)
    g.save(
        figure,
        f"{MAP_FIGURES[plane]}_{plane}_curves_zooms",
        caption,
        recipe,
        start="continue",
        direction="down",
    )

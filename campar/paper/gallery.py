"""``campar gallery``: the paper's whole figure set from one command, under both force laws.

Computes what each figure needs (``campar.paper.setups``), draws it (``campar.views.plot``)
and writes, next to every PNG, a .yaml of the same name: the figure's caption,
its force law (``tensile``), where its chains start (``start``: rest or
continue) and which way ω is swept (``direction``: down, up, or none for single
points), the title and units of every axis drawn, and the job file or recipe it
came from (the ``campar`` command that redraws it, the normalised jobs and point
parameters behind it). Every figure's title states the same force law, start
and direction. An ``index.md`` lists the figures with their captions.

``tensile``: "both" (the default) draws the set twice, once under the product's
force law ``clamp`` (Pn = max(0, …), plain file names) and once under the
paper's literal ``allow`` (the same names with "-allow"); "clamp" or "allow"
draws one.

Size "small" (48 × 48 planes, 1000-cell lines) takes about a minute on two
cores and is what CI runs; "full" uses the job files' own 400 × 400 grids (tens
of seconds per plane here; the stores are reused by later runs and by ``campar
report`` of the same size).

After the paper's figures come those of attractor structure
(``campar.paper.structure_figures``): per plane a hysteresis map (both sweep
directions along the paper's path) and a multistability map (an attractor census
on ``Size.census`` points per axis), and for the (ω, f0) and (ω, μkn) planes the map
with its typed bifurcation curves and three zoom panels, each recomputed on its own
finer job (``Size.zoom`` points across its window), as the paper's Figs 2c–e, 4c–e.
"""

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..model import Model
from ..sweep.job import PAPER_VALUES
from . import setups
from .figure_files import MAP_FIGURES, PLANE_SYMBOLS, write_yaml
from .structure_figures import draw_structure

# Views drawn per plane, with their captions.
PLANE_MAPS = {
    "labels": "n-p labels",
    "dc": "duty cycle DC",
    "lyapunov": "largest Lyapunov exponent λ1 (diverging colours, white at 0: λ1 < 0 stable "
    "cycles, ≈ 0 quasi-periodic, > 0 chaos)",
}
PNG_DPI = 200
BOTH = "both"
LAW_TEXT = {
    "clamp": "force law clamp (Pn = max(0, …), no tensile force)",
    "allow": "force law allow (the paper's literal Pn, tensile force allowed)",
}
START_TEXT = {
    "continue": "chains start continue (the plane's 2-D continuation from its corner)",
    "rest": "start rest ((y, ẏ) = (0, 0) at θ = 0)",
    "grid": "every start of a grid of initial states (y, ẏ) at θ = 0 (a basin)",
}
DIRECTION_TEXT = {
    "down": "ω swept down",
    "up": "ω swept up",
    "both": "ω swept down and up (both sweeps compared)",
    "none": "no sweep (single points)",
}


def provenance(tensile: str, start: str, direction: str, *, short: bool = False) -> str:
    """What a figure's title and caption state: force law, chain start, sweep direction."""
    if short:
        sweep = "single points" if direction == "none" else f"ω {direction}"
        return f"tensile: {tensile}   start: {start}   sweep: {sweep}"
    return f"{LAW_TEXT[tensile]}; {START_TEXT[start]}; {DIRECTION_TEXT[direction]}"


@dataclass
class Gallery:
    """Where the figures of one force law go and what has been written so far."""

    outdir: Path
    size: str
    tensile: str
    stores: Path
    entries: list = field(default_factory=list)  # (file, caption)
    log: object = print
    plane_seconds: float = 0.0  # spent in run_plane (0 when every store was complete)

    def name(self, stem: str) -> str:
        return stem if self.tensile == setups.LAW else f"{stem}-{self.tensile}"

    def save(
        self, figure, stem: str, caption: str, recipe: dict, *, start: str, direction: str
    ) -> Path:
        """Write the PNG (its title stating force law, start and direction) and its .yaml."""
        from ..views.plot import save_figure

        line = provenance(self.tensile, start, direction, short=True)
        head = figure.get_suptitle()
        figure.suptitle(f"{head}\n{line}" if head else line, x=0.01, ha="left", fontsize=8)
        path = save_figure(figure, self.outdir / f"{self.name(stem)}.png", dpi=PNG_DPI)
        caption = f"{caption}. {provenance(self.tensile, start, direction)}"
        meta = {
            "figure": path.name,
            "caption": caption,
            "tensile": self.tensile,
            "start": start,
            "direction": direction,
            "axes": axes_labels(figure),
        }
        write_yaml(self.outdir / f"{self.name(stem)}.yaml", {**meta, **recipe})
        self.entries.append((path.name, caption))
        self.log(f"wrote {path}")
        return path


def axes_labels(figure) -> list[dict]:
    """The titles of every visible, labelled axis of a figure (colour bars included)."""
    found = []
    for ax in figure.axes:
        if not ax.get_visible():
            continue
        labels = {k: v for k, v in (("x", ax.get_xlabel()), ("y", ax.get_ylabel())) if v}
        if labels:
            found.append(labels)
    return found


def default_stores(size: str) -> Path:
    """Where gallery and report keep their plane stores (reused between runs)."""
    return Path("results") / f"paper-{size}"


def laws_of(tensile: str) -> tuple[str, ...]:
    """The force laws a gallery draws: both, or the one named."""
    if tensile == BOTH:
        return setups.TENSILE
    if tensile not in setups.TENSILE:
        raise ValueError(f"tensile must be {BOTH} or one of {', '.join(setups.TENSILE)}")
    return (tensile,)


def make_gallery(
    outdir, size: str = "small", tensile: str = BOTH, stores=None, log=print
) -> list[Path]:
    """Compute and draw every figure into ``outdir`` under each force law of ``tensile``
    ("both", "clamp" or "allow"); returns the PNG paths."""
    if size not in setups.SIZES:
        raise ValueError(f"size must be one of {', '.join(setups.SIZES)}, got {size!r}")
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    galleries = []
    for law in laws_of(tensile):
        g = Gallery(outdir, size, law, Path(stores or default_stores(size)), log=log)
        for plane in setups.PLANES:
            draw_plane(g, plane)
        draw_lines(g)
        draw_phase_portraits(g)
        draw_penetration(g)
        draw_forces(g)
        draw_orbit_example(g)
        draw_structure(g)  # hysteresis, multistability, curves with zooms
        galleries.append(g)
    write_index(outdir, size, tensile, galleries, time.perf_counter() - start)
    return [outdir / name for g in galleries for name, _ in g.entries]


def draw_plane(g: Gallery, plane: str) -> None:
    from matplotlib.colors import to_hex

    from ..sweep.store import read_store
    from ..views.plot import computed_mask, plot_map
    from ..views.plot.labels import OTHER, distinct_categories, map_labels
    from ..views.plot.maps import LEGEND_MAX

    job = setups.plane_job(plane, g.size, g.tensile)
    clock = time.perf_counter()
    store = setups.run_plane(job, g.stores)
    g.plane_seconds += time.perf_counter() - clock
    with read_store(store) as reader:
        names = [n for n in ("kind", "n", "p", "dc", "lyapunov") if n in reader.names]
        arrays = {name: reader.read(name) for name in names}
        arrays["computed"] = computed_mask(reader.job, reader.done)
    data = job.to_dict()
    data["store"] = str(store)
    write_yaml(g.outdir / f"{job.name}.yaml", data)
    rows, cols = job.shape
    axes = ", ".join(PLANE_SYMBOLS[name] for name in job.sweep)
    for what, text in PLANE_MAPS.items():
        if what != "labels" and what not in arrays:
            continue
        figure = plot_map(job, arrays, what)
        caption = f"{text} on the ({axes}) plane, {rows} × {cols} cells, job {job.name}.yaml"
        recipe = {
            "job": f"{job.name}.yaml",
            "store": str(store),
            "view": what,
            "command": f"campar plot {store} --what {what}",
        }
        if what == "labels":
            cells = distinct_categories(map_labels(arrays, job.classify.chatter_p), LEGEND_MAX)
            recipe["palette"] = {e.label: to_hex(e.colour) for e in cells.entries}
            other = [e for e in cells.entries if e.label == OTHER]
            if other:
                members = other[0].members
                recipe["other"] = list(members)
                listed = ", ".join(plain_label(m) for m in members)
                caption += (
                    f"; the {len(members)} rarest labels ({other[0].count} cells) share "
                    f"the hatched class “other”: {listed}"
                )
        g.save(
            figure,
            f"{MAP_FIGURES[plane]}_{plane}_{what}",
            caption,
            recipe,
            start=job.chains.start,
            direction=job.chains.direction,
        )


def plain_label(category: str) -> str:
    """A category as caption text: "1-p~" → "1-p̃"."""
    return category.replace("p~", "p\u0303")


def draw_lines(g: Gallery) -> None:
    from ..views.plot.bifurcation import plot_lines

    lines = setups.paper_lines(g.size, g.tensile)
    titles = [
        rf"$\mu_{{\mathrm{{kn}}}}$ = {max(f'{mu:.2f}', f'{mu:g}', key=len)}"
        for mu in setups.FIG5_MU_KN
    ]
    points = setups.SIZES[g.size].line
    mu_list = " ".join(f"{mu:g}" for mu in setups.FIG5_MU_KN)
    recipe = {
        "command": f"campar line --omega 6:0.02 --points {points} --mu-kn {mu_list} "
        f"--tensile {g.tensile} -o {g.name('fig5_lines')}.png",
        "lines": [
            setups.paper_line_job(mu, g.size, g.tensile).to_dict() for mu in setups.FIG5_MU_KN
        ],
    }
    caption = (
        f"bifurcation lines (Fig. 5): σn points y and detachments p against ω, "
        f"{points} ω values from 6.0 down, each chain from rest at ω = 6.0, "
        f"μkn = {mu_list}"
    )
    g.save(plot_lines(lines, titles), "fig5_lines", caption, recipe, start="rest", direction="down")


def draw_phase_portraits(g: Gallery) -> None:
    from ..views.plot.figures import plot_phase_grid

    panels, cells, multistable = [], [], []
    for omega, claim in setups.FIG6_CLAIMS:
        cell = setups.path_cell(omega, setups.FIG6_MU_KN, g.tensile)
        cells.append(cell_recipe(cell))
        if len(cell.portraits) > 1:
            multistable.append(f"ω = {omega:.10g}: {len(cell.portraits)} attractors")
        for portrait in cell.portraits:
            r = portrait.result
            share = "" if math.isnan(portrait.fraction) else f" ({portrait.fraction:.0%} of starts)"
            if portrait.on_path:
                head = f"$\\omega$ = {omega:.10g}, paper: {claim}\npath → {r.label}{share}"
            else:
                head = f"$\\omega$ = {omega:.10g}, also found:\n{r.label}{share}"
            panels.append({"kind": "phase", "result": r, "heading": head})
            if r.kind != "periodic":
                head = f"$\\sigma_n$ at $\\omega$ = {omega:.10g}: {r.label}"
                panels.append(
                    {"kind": "section", "result": r, "cloud": portrait.cloud, "heading": head}
                )
    starts = setups.FIG6_STARTS
    found = "; ".join(multistable) or (
        f"every cell monostable: all {starts} starts reached the path's attractor or none"
    )
    caption = (
        f"phase portraits (Fig. 6) at μkn = {setups.FIG6_MU_KN:g}, ω = "
        f"{', '.join(f'{w:.10g}' for w, _ in setups.FIG6_CLAIMS)}: each cell reached along the "
        f"paper's path, the (ω, μkn) plane's 2-D continuation from its corner (6.0, 0.95) at "
        f"the full plane's grid spacing (down μkn at ω = 6.0, then down ω at μkn = "
        f"{setups.FIG6_MU_KN:g}), ending exactly at the cell; the orbit traced from the state "
        f"reached ('path →'); then an attractor census of {starts} starts (rest, the path's "
        f"state, Halton points over y ∈ [−1, 2] h, ẏ ∈ ±1.5 ω h at θ = 0) at the cell, every "
        f"other attractor drawn too ({found}); σn points blue, detachment points red; the "
        f"paper's label and campar's in each title; σn clouds of 1500 revolutions for "
        f"non-periodic attractors"
    )
    recipe = {
        "path": "campar.paper.setups.plane_path_job: the plane's job cut to end at the "
        "cell, its last row's last state",
        "cells": cells,
    }
    g.save(
        plot_phase_grid(panels),
        "fig6_phase_portraits",
        caption,
        recipe,
        start="continue",
        direction="down",
    )


def cell_recipe(cell) -> dict:
    """What a Fig. 6 cell's .yaml entry records: the path, its state and the census."""
    return {
        "omega": cell.omega,
        "path_job": cell.job.to_dict(),
        "path_state": [float(cell.state[0]), float(cell.state[1])],
        "census_starts": cell.starts,
        "census_unsettled": cell.unsettled,
        "attractors": [
            {
                "label": p.result.label,
                "kind": p.result.kind,
                "on_path": p.on_path,
                "fraction": None if math.isnan(p.fraction) else float(p.fraction),
                "state": [float(x) for x in p.result.state],
            }
            for p in cell.portraits
        ],
    }


def point_recipe(omega: float, tensile: str, params: dict) -> dict:
    model = Model.build(omega=omega, tensile=tensile, **params)
    flags = " ".join(f"--{k.replace('_', '-')} {v:g}" for k, v in params.items())
    return {
        "command": f"campar point --omega {omega:g} {flags} --tensile {tensile}",
        "model": model.to_dict(),
    }


def draw_penetration(g: Gallery) -> None:
    from ..views.plot.figures import plot_gap_family

    for stem, f0, varied, caption in (
        (
            "fig3_gap_preload",
            None,
            (("f0", setups.FIG3_F0),),
            "penetration ε(t) over the steady orbit (Fig. 3) for three preloads f0 at ω = 1, 3, 5",
        ),
        (
            "fig8_gap_stiffness_damping",
            setups.FIG8_F0,
            (("mu_kn", setups.FIG8_RATIOS), ("mu_cn", setups.FIG8_RATIOS)),
            "penetration ε(t) (Fig. 8) at f0 = 2.5 for three μkn (top) and three μcn (bottom), "
            "ω = 1, 3, 5",
        ),
    ):
        rows, recipes = [], []
        for name, values in varied:
            by_speed = []
            for omega in setups.SPEEDS:
                results = []
                for value in values:
                    params = {**PAPER_VALUES, **({"f0": f0} if f0 is not None else {}), name: value}
                    results.append(setups.steady_point(omega, g.tensile, **params))
                    recipes.append(point_recipe(omega, g.tensile, params))
                by_speed.append(results)
            rows.append((name, values, by_speed))
        caption += "; cam rise and fall shaded (R rise, FD far dwell, F fall, ND near dwell)"
        g.save(
            plot_gap_family(rows),
            stem,
            caption,
            {"points": recipes},
            start="rest",
            direction="none",
        )


def draw_forces(g: Gallery) -> None:
    from ..views.plot.figures import plot_force_row
    from ..views.plot.orbit import clamped_intervals

    params = {**PAPER_VALUES, "f0": setups.FIG9_F0}
    results = [setups.steady_point(omega, g.tensile, **params) for omega in setups.SPEEDS]
    recipe = {"points": [point_recipe(w, g.tensile, params) for w in setups.SPEEDS]}
    clamped = [sum(b - a for a, b in clamped_intervals(r.trace)) / r.trace.period for r in results]
    recipe["clamped_fraction_of_revolution"] = {
        f"{w:g}": round(c, 4) for w, c in zip(setups.SPEEDS, clamped, strict=True)
    }
    caption = (
        "contact force Pn(t) (red) with the cam input yc(t) (blue), impacts ○ and "
        "detachments ★ (Fig. 9), f0 = 0.5, ω = 1, 3, 5"
    )
    if g.tensile == "clamp":
        caption += (
            "; shaded orange: the clamp holds Pn = 0 while ε > 0 (follower ahead of the "
            "cam without force), "
            + ", ".join(
                f"{c:.1%} of a revolution at ω = {w:g}"
                for w, c in zip(setups.SPEEDS, clamped, strict=True)
            )
        )
    else:
        caption += "; Pn < 0 is the literal law's tensile force (no clamp, nothing shaded)"
    g.save(plot_force_row(results), "fig9_force", caption, recipe, start="rest", direction="none")


def draw_orbit_example(g: Gallery) -> None:
    from ..views.plot import plot_orbit

    params = {**PAPER_VALUES, "mu_kn": setups.FIG6_MU_KN}
    result = setups.steady_point(3.0, g.tensile, **params)
    caption = (
        "one point's orbit as `campar point --plot` draws it: phase portrait, ε(t), "
        "Pn(t) with yc(t); ω = 3, μkn = 0.91, from rest"
    )
    g.save(
        plot_orbit(result),
        "orbit_point",
        caption,
        point_recipe(3.0, g.tensile, params),
        start="rest",
        direction="none",
    )


def write_index(outdir: Path, size: str, tensile: str, galleries, seconds: float) -> None:
    lines = [
        f"# campar gallery ({size} size, tensile: {tensile})",
        "",
        f"Generated by `campar gallery {outdir} --size {size} --tensile {tensile}` in "
        f"{seconds:.0f} s, of which {sum(g.plane_seconds for g in galleries):.0f} s in the "
        f"planes' runs (a complete store under {galleries[0].stores} is reused). Each "
        "figure's caption, force law (`tensile`), chain start (`start`), sweep direction "
        "(`direction`), axis titles with units, and job file or recipe are in the .yaml of "
        "the same name; its title states the first three.",
        "",
        "Colours: any two categories shown on one label map differ by CIEDE2000 ΔE00 ≥ 10 "
        "(tests/test_palette.py); labels the legend has no room for are grouped in one "
        "hatched class “other”, listed in the legend and the caption. Units: the model is "
        "dimensionless; ω in units of ωn; y, yc, ε in strokes h; ẏ in h·ωn; t in 1/ωn; "
        "Pn and f0 in K1·h; λ1 in ωn; μkn, μcn, ζ, DC and p are pure numbers.",
        "",
    ]
    for g in galleries:
        lines += [
            f"## {LAW_TEXT[g.tensile]}",
            "",
            "| figure | shows |",
            "|---|---|",
            *(f"| [{name}]({name}) | {caption} |" for name, caption in g.entries),
            "",
        ]
    (outdir / "index.md").write_text("\n".join(lines))

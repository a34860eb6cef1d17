"""``campar gallery``: the paper's whole figure set from one command.

Computes what each figure needs (``campar.paper.setups``), draws it (``campar.views.plot``)
and writes, next to every PNG, the file it came from: the plane's job file
(runnable with ``campar run``) or a recipe (the ``campar`` command that
redraws the figure and the normalised jobs and point parameters behind it).
An ``index.md`` lists the figures with what each shows.

Size "small" (48 × 48 planes, 1000-cell lines) takes well under a minute on
two cores and is what CI runs; "full" uses the job files' own 400 × 400 grids
(minutes per plane; the stores are reused by later runs and by
``campar report`` of the same size).
"""

import time
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from ..sweep.job import PAPER_VALUES
from ..views.point import point_job
from . import setups

MAP_FIGURES = {"omega_f0": "fig2", "mu_kn": "fig4", "mu_cn": "fig7"}
PLANE_MAPS = {"labels": "n-p labels", "dc": "duty cycle DC"}  # views drawn per plane, captions
PNG_DPI = 200
PLANE_SYMBOLS = {"omega": "ω", "f0": "f0", "mu_kn": "μkn", "mu_cn": "μcn", "zeta": "ζ"}


@dataclass
class Gallery:
    """Where the figures go and what has been written so far."""

    outdir: Path
    size: str
    tensile: str
    stores: Path
    entries: list = field(default_factory=list)  # (file, caption)
    log: object = print

    def name(self, stem: str) -> str:
        return stem if self.tensile == setups.LAW else f"{stem}-{self.tensile}"

    def save(self, figure, stem: str, caption: str, recipe: dict | None = None) -> Path:
        from ..views.plot import save_figure

        path = save_figure(figure, self.outdir / f"{self.name(stem)}.png", dpi=PNG_DPI)
        if recipe is not None:
            write_yaml(self.outdir / f"{self.name(stem)}.yaml", recipe)
        self.entries.append((path.name, caption))
        self.log(f"wrote {path}")
        return path


def write_yaml(path: Path, data: dict) -> None:
    path.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True, width=100))


def default_stores(size: str) -> Path:
    """Where gallery and report keep their plane stores (reused between runs)."""
    return Path("results") / f"paper-{size}"


def make_gallery(outdir, size: str = "small", tensile: str = setups.LAW, stores=None,
                 log=print) -> list[Path]:  # fmt: skip
    """Compute and draw every figure into ``outdir``; returns the PNG paths."""
    if size not in setups.SIZES:
        raise ValueError(f"size must be one of {', '.join(setups.SIZES)}, got {size!r}")
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    g = Gallery(outdir, size, tensile, Path(stores or default_stores(size)), log=log)
    start = time.perf_counter()
    for plane in setups.PLANES:
        draw_plane(g, plane)
    draw_lines(g)
    draw_phase_portraits(g)
    draw_penetration(g)
    draw_forces(g)
    draw_orbit_example(g)
    write_index(g, time.perf_counter() - start)
    return [outdir / name for name, _ in g.entries]


def draw_plane(g: Gallery, plane: str) -> None:
    from ..sweep.store import read_store
    from ..views.plot import computed_mask, plot_map

    job = setups.plane_job(plane, g.size, g.tensile)
    store = setups.run_plane(job, g.stores)
    with read_store(store) as reader:
        arrays = {name: reader.read(name) for name in ("kind", "n", "p", "dc")}
        arrays["computed"] = computed_mask(reader.job, reader.done)
    data = job.to_dict()
    data["store"] = str(store)
    write_yaml(g.outdir / f"{job.name}.yaml", data)
    rows, cols = job.shape
    for what, text in PLANE_MAPS.items():
        figure = plot_map(job, arrays, what)
        axes = ", ".join(PLANE_SYMBOLS[name] for name in job.sweep)
        caption = (f"{text} on the ({axes}) plane, {rows} × {cols} cells, "
                   f"job {job.name}.yaml")  # fmt: skip
        g.save(figure, f"{MAP_FIGURES[plane]}_{plane}_{what}", caption)


def draw_lines(g: Gallery) -> None:
    from ..views.plot.bifurcation import plot_lines

    lines = setups.paper_lines(g.size, g.tensile)
    titles = [rf"$\mu_{{\mathrm{{kn}}}}$ = {max(f'{mu:.2f}', f'{mu:g}', key=len)}"
              for mu in setups.FIG5_MU_KN]  # fmt: skip
    points = setups.SIZES[g.size].line
    mu_list = " ".join(f"{mu:g}" for mu in setups.FIG5_MU_KN)
    recipe = {
        "figure": "the paper's Fig. 5: σn points y and detachments p against ω",
        "command": f"campar line --omega 6:0.02 --points {points} --mu-kn {mu_list} "
        f"--tensile {g.tensile} -o fig5_lines.png",
        "jobs": [
            setups.paper_line_job(mu, g.size, g.tensile).to_dict() for mu in setups.FIG5_MU_KN
        ],
    }
    caption = (f"bifurcation lines (Fig. 5): σn points y and detachments p against ω, "
               f"{points} ω values from 6.0 down (continuation), μkn = {mu_list}")  # fmt: skip
    g.save(plot_lines(lines, titles), "fig5_lines", caption, recipe)


def continuation_recipe(omega: float, tensile: str, params: dict) -> dict:
    from ..views.line import CONTINUATION_STEP, PAPER_START, continuation_points, line_job

    job = line_job((PAPER_START, omega), continuation_points(omega), tensile=tensile,
                   sections=1, **params)  # fmt: skip
    return {"omega": omega, "continuation": job.to_dict(), "step": CONTINUATION_STEP,
            "then": "simulate_point from the chain's last state, with trace"}  # fmt: skip


def draw_phase_portraits(g: Gallery) -> None:
    from ..views.plot.figures import plot_phase_grid

    params = {**PAPER_VALUES, "mu_kn": setups.FIG6_MU_KN}
    panels, recipes = [], []
    for omega, claim in setups.FIG6_CLAIMS:
        found = setups.continued_point(omega, g.tensile, **params)
        r = found.result
        head = f"paper {claim}, campar {r.label}"
        panels.append({"kind": "phase", "result": r, "heading": f"$\\omega$ = {omega}\n{head}"})
        if claim in ("chaos", "QP"):
            panels.append({"kind": "section", "result": r, "cloud": found.cloud,
                           "heading": f"$\\sigma_n$ at $\\omega$ = {omega}\n{head}"})  # fmt: skip
        recipes.append(continuation_recipe(omega, g.tensile, params))
    recipe = {"figure": "the paper's Fig. 6: phase portraits along μkn = 0.91, each orbit "
              "reached by continuation from ω = 6.0", "points": recipes}  # fmt: skip
    caption = ("phase portraits (Fig. 6) at μkn = 0.91, reached by continuation from ω = 6.0: "
               "σn points blue, detachment points red; the paper's label and campar's in each "
               "title; Poincaré sections (c, h) where the paper reports chaos and QP")  # fmt: skip
    g.save(plot_phase_grid(panels), "fig6_phase_portraits", caption, recipe)


def point_recipe(omega: float, tensile: str, params: dict) -> dict:
    job = point_job(omega=omega, tensile=tensile, **params)
    flags = " ".join(f"--{k.replace('_', '-')} {v:g}" for k, v in params.items())
    return {"command": f"campar point --omega {omega:g} {flags} --tensile {tensile}",
            "job": job.to_dict()}  # fmt: skip


def draw_penetration(g: Gallery) -> None:
    from ..views.plot.figures import plot_gap_family

    for stem, f0, varied, caption in (
        ("fig3_gap_preload", None, (("f0", setups.FIG3_F0),),
         "penetration ε(t) over the steady orbit (Fig. 3) for three preloads f0 at ω = 1, 3, 5"),
        ("fig8_gap_stiffness_damping", setups.FIG8_F0,
         (("mu_kn", setups.FIG8_RATIOS), ("mu_cn", setups.FIG8_RATIOS)),
         "penetration ε(t) (Fig. 8) at f0 = 2.5 for three μkn (top) and three μcn (bottom), "
         "ω = 1, 3, 5"),
    ):  # fmt: skip
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
        recipe = {"figure": caption, "start": "rest, (y, y') = (0, 0) at θ = 0",
                  "points": recipes}  # fmt: skip
        g.save(
            plot_gap_family(rows),
            stem,
            caption + "; cam rise and fall shaded (R rise, FD far dwell, F fall, ND near dwell)",
            recipe,
        )


def draw_forces(g: Gallery) -> None:
    from ..views.plot.figures import plot_force_row

    params = {**PAPER_VALUES, "f0": setups.FIG9_F0}
    results = [setups.steady_point(omega, g.tensile, **params) for omega in setups.SPEEDS]
    recipe = {"figure": "the paper's Fig. 9", "start": "rest, (y, y') = (0, 0) at θ = 0",
              "points": [point_recipe(w, g.tensile, params) for w in setups.SPEEDS]}  # fmt: skip
    caption = ("contact force Pn(t) (red) with the cam input yc(t) (blue), impacts ○ and "
               "detachments ★ (Fig. 9), f0 = 0.5, ω = 1, 3, 5")  # fmt: skip
    g.save(plot_force_row(results), "fig9_force", caption, recipe)


def draw_orbit_example(g: Gallery) -> None:
    from ..views.plot import plot_orbit

    params = {**PAPER_VALUES, "mu_kn": setups.FIG6_MU_KN}
    result = setups.steady_point(3.0, g.tensile, **params)
    caption = ("one point's orbit as `campar point --plot` draws it: phase portrait, ε(t), "
               "Pn(t) with yc(t); ω = 3, μkn = 0.91, from rest")  # fmt: skip
    g.save(plot_orbit(result), "orbit_point", caption, point_recipe(3.0, g.tensile, params))


def write_index(g: Gallery, seconds: float) -> None:
    lines = [
        f"# campar gallery ({g.size} size, tensile: {g.tensile})",
        "",
        f"Generated by `campar gallery {g.outdir} --size {g.size} --tensile {g.tensile}` "
        f"in {seconds:.0f} s. Each figure's job file or recipe is the .yaml of the same name.",
        "",
        "| figure | shows |",
        "|---|---|",
        *(f"| [{name}]({name}) | {caption} |" for name, caption in g.entries),
        "",
    ]
    (g.outdir / "index.md").write_text("\n".join(lines))

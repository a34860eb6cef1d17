"""The report's section on jumps, tongues and irreversible transitions, computed.

For each plane and force law: the plane swept both ways along the paper's path
(``structure.hysteresis_job``) and its attractor census (``structure.census_job``), at
the report's size, counted by ``campar.paper.structure_stats``. The text states the
numbers and what they say about the paper's statements (its Figs. 2c–e and 4c–e: jumps
at grazing, "lingual" tongues bounded by PD and G, irreversible transitions as their
cause); it never decides a number to agree with the paper.
"""

from statistics import median

from . import setups, structure
from . import structure_stats as st

SYMBOLS = {"f0": "f0", "mu_kn": "μkn", "mu_cn": "μcn", "zeta": "ζ"}
PLANE_TEXT = {"omega_f0": "(ω, f0)", "mu_kn": "(ω, μkn)", "mu_cn": "(ω, μcn)"}
SHOWN = 3  # label pairs, intervals and regions named per table cell
PAPER_PAIR = ("1-2", "1-3")  # the paper's reversible jump (Fig. 4c, 5a: grazing of 1-2)


def cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def num(x: float) -> str:
    return f"{x:.3g}".replace("-", "−")


def share(part: int, whole: int) -> str:
    return f"{part} of {whole} ({100 * part / whole:.1f} %)" if whole else f"{part} of 0"


def pairs_text(pairs, limit: int = SHOWN, arrow: str = " / ") -> str:
    if not pairs:
        return "none"
    shown = ", ".join(f"{a}{arrow}{b} ({n})" for (a, b), n in pairs[:limit])
    rest, more = sum(n for _, n in pairs[limit:]), len(pairs) - limit
    return shown + (f", {more} other pair{'s' * (more > 1)} ({rest})" if rest else "")


def intervals_text(runs) -> str:
    if not runs:
        return "–"
    shown = ", ".join(f"{num(lo)}–{num(hi)} ({n})" for lo, hi, n in runs[:SHOWN])
    return shown + (f", {len(runs) - SHOWN} more" if len(runs) > SHOWN else "")


def region_text(r: st.Region, name: str) -> str:
    name = SYMBOLS.get(name, name)
    shape = (
        f"tongue, tip at {name} = {num(r.tip)}"
        if r.tongue
        else f"no tip (end widths {r.ends[0]}, {r.ends[1]})"
    )
    return (
        f"{r.cells} cells, ω {num(r.omega[0])}–{num(r.omega[1])}, {name} "
        f"{num(r.second[0])}–{num(r.second[1])}, widest {r.widest}: {shape}"
    )


def bounds_text(r: st.Region) -> str:
    if not r.bounds:
        return "–"
    total = sum(r.bounds.values())
    both = sum(
        n
        for (hi, lo), n in r.bounds.items()
        if sweeps(hi) ^ sweeps(lo) == {"down", "up"} and sweeps(hi) and sweeps(lo)
    )
    top = ", ".join(f"[{hi}] … [{lo}] ({n})" for (hi, lo), n in r.bounds.most_common(2))
    return f"{both} of {total} rows bounded by one sweep's change at each end; {top}"


def sweeps(end: str) -> set:
    return {word for word in ("down", "up") if word in end.split()}


class Plane:
    """One plane under one force law: its ``both`` map and its census, loaded once."""

    def __init__(self, plane: str, size: str, tensile: str, stores):
        self.plane, self.tensile = plane, tensile
        self.both_job = structure.hysteresis_job(plane, size, tensile)
        self.census_job = structure.census_job(plane, size, tensile)
        self.both = st.load_both(structure.run(self.both_job, stores))
        self.census = st.load_census(structure.run(self.census_job, stores))
        self.jumps = st.jump_summary(self.both)
        self.regions = st.regions(
            self.both.hysteresis, self.both.omega, self.both.second, self.both
        )
        multi = self.census.n_attractors >= 2
        self.census_regions = st.regions(multi, self.census.omega, self.census.second)
        self.sets = st.attractor_sets(self.census, multi)
        self.check = st.census_versus_hysteresis(self.census, self.both)
        self.crossings = {s: st.irreversibility(self.both, s) for s in ("down", "up")}
        self.labels = st.label_regions(self.both, "down")

    @property
    def head(self) -> str:
        return f"| {PLANE_TEXT[self.plane]} | {self.tensile} |"


def jumps_table(planes) -> list[str]:
    lines = [
        "| plane | law | hysteretic cells (of cells where both sweeps are periodic) | ω range "
        "| ω intervals (cells) | down / up labels there (cells) | same n-p, other cycle | "
        "labels differ, a sweep not periodic (pairs) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for p in planes:
        j = p.jumps
        w = f"{num(j.omega_range[0])}–{num(j.omega_range[1])}" if j.omega_range else "–"
        lines.append(
            p.head
            + " | ".join(
                cell(x)
                for x in (
                    f" {share(j.cells, j.compared)}",
                    w,
                    intervals_text(j.intervals),
                    pairs_text(j.pairs),
                    j.same_label,
                    f"{j.uncompared_differ}: {pairs_text(j.uncompared_pairs)}",
                )
            )
            + " |"
        )
    return lines


def tongues_table(planes) -> list[str]:
    lines = [
        f"| plane | law | hysteresis regions ≥ {st.MIN_REGION} cells (tongue-shaped) | "
        "largest regions | their ends along ω: which sweep changes label, and the type "
        "of its boundary |",
        "|---|---|---|---|---|",
    ]
    for p in planes:
        name = p.both.name
        tongues = sum(r.tongue for r in p.regions)
        largest = "; ".join(region_text(r, name) for r in p.regions[:SHOWN]) or "–"
        bounds = (
            "; ".join(f"region {k + 1}: {bounds_text(r)}" for k, r in enumerate(p.regions[:SHOWN]))
            or "–"
        )
        lines.append(
            p.head
            + " | ".join(cell(x) for x in (f" {len(p.regions)} ({tongues})", largest, bounds))
            + " |"
        )
    return lines


def labels_table(planes) -> list[str]:
    lines = [
        f"| plane | law | regions ≥ {st.MIN_REGION} cells (tongue-shaped; PD and G bound "
        "them) | largest regions: label, extent, shape, typed edges on the boundary |",
        "|---|---|---|---|",
    ]
    for p in planes:
        regions = p.labels
        largest = "; ".join(
            f"{r.label}: {region_text(r.region, p.both.name)}; edges "
            + ", ".join(f"{t} {n}" for t, n in r.types.most_common())
            for r in regions[:SHOWN]
        )
        counts = (
            f" {len(regions)} ({sum(r.region.tongue for r in regions)}; "
            f"{sum(r.pd_and_g for r in regions)})"
        )
        lines.append(p.head + " | ".join(cell(x) for x in (counts, largest or "–")) + " |")
    return lines


def census_table(planes) -> list[str]:
    lines = [
        "| plane | law | census grid (starts) | multistable cells (≥ 2 attractors) | "
        f"regions ≥ {st.MIN_REGION} cells (tongue-shaped): largest | attractor sets "
        "(cells) | hysteretic cells at census cells: found multistable | multistable "
        "census cells the two sweeps show as hysteresis |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for p in planes:
        c, k = p.census, p.check
        rows, cols = c.n_attractors.shape
        computed = int((c.n_attractors >= 0).sum())
        regions = p.census_regions
        largest = region_text(regions[0], c.name) if regions else "–"
        where = "the same cells" if k["exact"] else "nearest cells"
        lines.append(
            p.head
            + " | ".join(
                cell(x)
                for x in (
                    f" {rows} × {cols} ({c.starts})",
                    share(k["multistable"], computed),
                    f"{len(regions)} ({sum(r.tongue for r in regions)}): {largest}",
                    pairs_sets(p.sets),
                    f"{k['confirmed']} of {k['hysteretic']} ({where})",
                    share(k["multistable_hysteretic"], k["multistable"]),
                )
            )
            + " |"
        )
    return lines


def pairs_sets(sets) -> str:
    if not sets:
        return "none"
    shown = ", ".join(f"{{{', '.join(s)}}} ({n})" for s, n in sets[:SHOWN])
    return shown + (f", {len(sets) - SHOWN} other sets" if len(sets) > SHOWN else "")


def crossings_table(planes) -> list[str]:
    lines = [
        "| plane | law | sweep | label changes along ω | crossed back at the same edge | "
        f"within {st.NEAR} edges | farther (median \\|Δω\\|) | not in the row | "
        "most frequent not crossed back (from → to, in the sweep's direction: edges) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for p in planes:
        for sweep, c in p.crossings.items():
            far = f"{c.far} ({num(median(c.far_omega))})" if c.far_omega else "0"
            lines.append(
                p.head
                + " | ".join(
                    cell(x)
                    for x in (
                        f" {sweep}",
                        c.total,
                        share(c.same, c.total),
                        c.near,
                        far,
                        c.never,
                        pairs_text(c.irreversible, arrow=" → "),
                    )
                )
                + " |"
            )
    return lines


def pair_crossings(p: Plane, pair=PAPER_PAIR) -> tuple[int, int]:
    """Down-sweep changes between the two labels of ``pair`` (either order) and how many of
    them the up sweep crosses back at the same edge."""
    m = p.both
    a, b = m.down[:, :-1], m.down[:, 1:]
    hit = ((a == pair[0]) & (b == pair[1])) | ((a == pair[1]) & (b == pair[0]))
    back = hit & (m.up[:, :-1] == a) & (m.up[:, 1:] == b)
    return int(hit.sum()), int(back.sum())


def first_column(p: Plane) -> list[tuple[float, str, str]]:
    """Label changes of the paper's path along its first column (the chain along the second
    axis at the plane's first ω, from its corner): (second between the rows, from, to)."""
    m = p.both
    labels = m.down[:, int(m.omega.argmax())]
    return [
        (float((m.second[i] + m.second[i + 1]) / 2), str(labels[i]), str(labels[i + 1]))
        for i in range(len(labels) - 1)
        if labels[i] != labels[i + 1]
    ]


def path_edges(p: Plane) -> str:
    """The first column's changes, and the hysteresis regions with a straight end there."""
    changes = first_column(p)
    if not changes:
        return ""
    m = p.both
    step = float(abs(m.second[1] - m.second[0])) if len(m.second) > 1 else 0.0
    at = [x for x, _, _ in changes]
    cut = sum(any(abs(end - x) <= step for x in at for end in r.second) for r in p.regions)
    name = SYMBOLS.get(m.name, m.name)
    shown = ", ".join(f"{name} {num(x)} ({a} → {b})" for x, a, b in changes[:SHOWN])
    more = f" and {len(changes) - SHOWN} more" if len(changes) > SHOWN else ""
    text = f"; the path's first column (ω = {num(m.omega.max())}) changes label at {shown}{more}"
    if not cut:
        return text + f", where none of the {len(p.regions)} hysteresis regions ends"
    return (
        text + f", and {cut} of the {len(p.regions)} hysteresis regions end{'s' * (cut == 1)} "
        "within a cell of such a change: there its straight edge along ω is the path's "
        "history, every row on one side starting on one branch and every row on the other "
        "on another"
    )


def summary(planes) -> list[str]:
    lines = []
    for p in planes:
        j, c = p.jumps, p.crossings["down"]
        tongues = [r for r in p.regions if r.tongue]
        hits, back = pair_crossings(p)
        text = (
            f"- {PLANE_TEXT[p.plane]}, {p.tensile}: {j.cells} hysteretic "
            f"cell{'s' * (j.cells != 1)}"
            + (
                f", ω {num(j.omega_range[0])}–{num(j.omega_range[1])}, mostly "
                f"{pairs_text(j.pairs, 2)} (down / up)"
                if j.cells
                else ""
            )
            + f"; {len(tongues)} of {len(p.regions)} hysteresis regions tongue-shaped; "
            f"{sum(r.region.tongue for r in p.labels)} of {len(p.labels)} subharmonic "
            f"label regions of the paper's path tongue-shaped, "
            f"{sum(r.pd_and_g for r in p.labels)} bounded by PD and G; "
            f"{share(p.check['multistable'], int((p.census.n_attractors >= 0).sum()))} "
            f"census cells multistable; of the down sweep's {c.total} label changes "
            f"{c.same} are crossed back at the same edge, {c.never} nowhere in their "
            f"row"
        )
        if p.regions:
            text += path_edges(p)
        if hits:
            text += (
                f"; {PAPER_PAIR[0]} ↔ {PAPER_PAIR[1]} changes (the paper's reversible "
                f"grazing jump): {back} of {hits} crossed back at the same edge"
            )
        lines.append(text + ".")
    lingual = [
        f"{r.label} on {PLANE_TEXT[p.plane]}, {p.tensile}"
        for p in planes
        for r in p.labels
        if r.region.tongue and r.pd_and_g
    ]
    rows = sum(sum(r.bounds.values()) for p in planes for r in p.regions)
    pd_g = sum(
        n
        for p in planes
        for r in p.regions
        for (hi, lo), n in r.bounds.items()
        if {"PD", "G"} <= set(hi.split()) | set(lo.split())
    )
    lines += [
        "- Against the paper's lingual domains (a tongue of subharmonic motion bounded by PD "
        "and G, which it ascribes to irreversible PD and G transitions): tongue-shaped "
        f"subharmonic regions bounded by PD and G: {', '.join(lingual) or 'none'}; rows of "
        f"the hysteresis regions (all planes and laws) with PD and G at their ends: {pd_g} of "
        f"{rows}.",
    ]
    return lines


def structure_section(size: str, stores=None, log=print) -> list[str]:
    """The section's Markdown lines (computes or reuses every store it reads)."""
    import time

    from .gallery import default_stores

    clock = time.perf_counter()
    stores = stores or default_stores(size)
    planes = [Plane(name, size, law, stores) for name in setups.PLANES for law in setups.TENSILE]
    log(f"report: jumps, tongues and irreversibility in {time.perf_counter() - clock:.1f} s")
    both, census = planes[0].both_job, planes[0].census_job
    return [
        "## Jumps, tongues and irreversible transitions (computed)",
        "",
        f"Each plane swept both ways on its {both.shape[0]} × {both.shape[1]} grid "
        "(`chains: {start: continue, direction: both}`, job `<plane>_both`): *down* is the "
        "paper's path (its 2-D continuation from the starting corner), *up* its mirror (the "
        "first column at the lowest ω, each row up from there). A cell is *hysteretic* when "
        "both sweeps end on converged cycles that differ (σn points not equal within 1e-5 "
        "after any cyclic shift; `campar.open`'s `hysteresis`). Besides, an attractor census "
        f"on {census.shape[0]} × {census.shape[1]} cells (job `<plane>_census`, "
        f"{census.attractors.starts} starts per cell and the chain's own state: rest, then "
        "Halton points over y ∈ [−1, 2] h, ẏ ∈ ±1.5 ω h at θ = 0). Commands: `campar gallery "
        f"docs/figures --size {size}` writes the jobs and draws the maps (`*_hysteresis.png`, "
        "`*_multistability.png`); `campar run <job>.yaml`, then `campar plot <store> --what "
        "hysteresis|multistability` or `campar.open(<store>)`. Every number below is counted "
        "from those stores by `campar.paper.structure_stats`.",
        "",
        "### (a) Jumps: hysteresis between the two sweep directions",
        "",
        *jumps_table(planes),
        "",
        f"### (b) Tongues: connected regions (4-neighbours) of at least {st.MIN_REGION} cells",
        "",
        "A region is *tongue-shaped* when it spans ≥ "
        f"{st.MIN_TONGUE_ROWS} rows, its widest row has ≥ 4 cells, and its row at one end "
        f"of the second parameter is ≤ {st.TIP_SHARE:g} × as wide as its widest (it narrows to "
        "a tip). For each row of a hysteresis region, its two ends along ω are read: which "
        "sweep changes label across that cell edge (down, up, both, none, or the map's edge) "
        "and the type of that sweep's boundary there (`campar plot --bifurcations` rules "
        "from the stored multipliers, grazing from orbits traced from the stored states, as "
        "`--trace`: PD, SN, NS, G, chaos, jump, unknown). The paper's lingual domain is a "
        "region of subharmonic motion bounded by PD of n-p and G of (n+1)-(p+1). Every row is "
        "its own chain along ω, so an edge of a region at a constant second parameter (a "
        "straight line along ω) is where chains on neighbouring rows arrive on different "
        "branches: a property of the two paths, not a bifurcation curve.",
        "",
        *tongues_table(planes),
        "",
        "The regions of each subharmonic label (n ≥ 2) of the paper's path (the down sweep), "
        "with the typed edges on their boundary (edges along both axes); *PD and G bound "
        "them* when both types occur there and together make at least half of its typed "
        "(not unknown) edges, as the paper's lingual domains:",
        "",
        *labels_table(planes),
        "",
        "Multistable cells of the census (the sweeps see at most two attractors a cell; "
        "the census sees those its starts reach):",
        "",
        *census_table(planes),
        "",
        "### (c) Irreversible transitions",
        "",
        "Every label change of one sweep between neighbouring cells along ω (a cell edge "
        "with its label pair) is *crossed back at the same edge* when the other sweep has "
        "the same two labels on the same two cells (it crosses the same edge the other way); "
        f"else the reverse change is looked for along the same row (within {st.NEAR} edges, "
        "farther, or not at all: a transition crossed in one direction and not crossed back "
        "at any ω of the row in the other).",
        "",
        *crossings_table(planes),
        "",
        "### What the model gives",
        "",
        *summary(planes),
        "",
    ]

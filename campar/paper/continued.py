"""The paper's claims about what lies between the attractors, decided by continuation.

The paper reads a Neimark–Sacker point (P7), a period-doubling cascade (N4), tongues
bounded by PD and G curves (N2) and routes of typed transitions (N1) from its maps and
diagrams. campar decides them on the cycles themselves, stable and unstable
(campar.continuation):

- the branch structure at μkn = 0.91 along ω from 6 down to 2 (``Evidence.structure``):
  every periodic attractor met on the paper's path and by a census of starts at nine
  speeds, each continued both ways with branch switching, up to cycles of 16 revolutions;
- the PD and G curves of the (ω, μkn) and (ω, μcn) planes, seeded from the maps' typed
  edges (``Evidence.map_curves``).
"""

import numpy as np

from . import setups
from .claims import Evidence, Verdict, fmt

STRUCTURE_WINDOW = (2.0, 6.0)
STRUCTURE_POINTS = 400  # the line's cells over the window (its seeds)
SWITCH_DEPTH = 4
MAX_PERIOD = 16  # the cascade's first four doublings: enough to see Feigenbaum's ratio
CENSUS_STARTS = 8
NS_WINDOW = (3.1, 3.3)  # where the paper places its Hopf point (ω = 3.208583)


def structure_command(ev: Evidence, law: str) -> str:
    return (
        f"campar continue --omega 6:2 --mu-kn {setups.FIG6_MU_KN:g} --switch "
        f"{SWITCH_DEPTH} -o branches.png --line {STRUCTURE_POINTS}{law} (the branch of "
        "the attractor at ω = 6; --omega 4.4:2 and 4.4:6 for the 1-1 branch)"
    )


def structure(ev: Evidence):
    """The branch structure at the paper's μkn over STRUCTURE_WINDOW (kept per evidence)."""
    model = {"tensile": ev.tensile, **ev.options}
    return ev._keep(("structure", setups.FIG6_MU_KN), lambda: compute_structure(model))


def compute_structure(model: dict | None = None):
    """The LineStructure at the paper's μkn over STRUCTURE_WINDOW: every periodic attractor
    of the path from ω = 6 down and of a census, continued both ways with switching (its
    account, campar.views.branch_account, is docs/continuation.md's at μkn = 0.91)."""
    from ..views.continuation import line_structure

    return line_structure(
        STRUCTURE_WINDOW,
        STRUCTURE_POINTS,
        {"mu_kn": setups.FIG6_MU_KN},
        switch=SWITCH_DEPTH,
        census=CENSUS_STARTS,
        max_period=MAX_PERIOD,
        model=model or {},
    )


def ns_claim(ev: Evidence) -> Verdict:
    """P7: a Neimark–Sacker point between ω 3.1 and 3.3 on any branch at μkn = 0.91."""
    found = structure(ev)
    lo, hi = NS_WINDOW
    ns = [sp for _, sp in found.special_points() if sp.type == "NS" and lo <= sp.value <= hi]
    dets, labels = [], set()
    for root in found.branches:
        for branch in root.walk():
            inside = (branch.values >= lo) & (branch.values <= hi)
            if inside.any():
                dets.append(np.abs(branch.multipliers[inside].prod(axis=1)).max())
                labels.update(
                    f"{lab}{'' if st else ' (unstable)'}"
                    for lab, st in zip(
                        np.array(branch.labels)[inside], branch.stable[inside], strict=True
                    )
                )
    if ns:
        return Verdict(f"NS at ω = {', '.join(fmt(sp.value, 6) for sp in ns)}", True)
    det = max(dets) if dets else float("nan")
    text = (
        f"no NS point on the {len(dets)} branches crossing ω ∈ [{lo:g}, {hi:g}] "
        f"({', '.join(sorted(labels))}): det DPⁿ ≤ {fmt(det, 4)} < 1 there (Liouville: "
        "no complex pair reaches the unit circle)"
    )
    return Verdict(text, False)


def cascade_claim(ev: Evidence) -> Verdict:
    """N4: a cascade 1 → 2 → 4 of PD points at μkn = 0.91 (a branch of period 4 switched
    from a branch of period 2 switched from one of period 1)."""
    found = structure(ev)
    pds = sorted({(b.n, round(sp.value, 6)) for b, sp in found.special_points() if sp.type == "PD"})
    depth = 0
    for root in found.branches:
        for branch in root.walk():
            chain, node = [branch.n], branch
            while node.origin is not None:
                parent = next(b for r in found.branches for b in r.walk() if node in b.children)
                chain.append(parent.n)
                node = parent
            if chain[-1] == 1 and all(a == 2 * b for a, b in zip(chain, chain[1:], strict=False)):
                depth = max(depth, len(chain) - 1)
    listed = "; ".join(f"{n}-cycles at ω = {value:.6f}" for n, value in pds) or "none"
    bubbles = [b for root in found.branches for b in root.walk() if b.returned]
    text = f"PD points: {listed}; doublings in a row from the 1-cycles: {depth}" + (
        f"; {len(bubbles)} doubled branch(es) return onto the cycles they left "
        "(period-doubling bubbles)"
        if bubbles
        else ""
    )
    return Verdict(text, depth >= 2)


TONGUES = ("2-2", "2-1")  # the subharmonic domains the paper's Figs 4c–e name
TONGUE_PLANES = ("mu_kn", "mu_cn")
BOUNDED_SHARE = 0.8  # of a tongue's boundary on PD and G curves for N2 to hold


def map_curves(ev: Evidence, plane: str) -> list:
    """The PD, SN and G curves of a plane's map (``campar curves`` beside its store; kept
    per evidence)."""

    def compute():
        from ..views.map_curves import curves_beside

        job = ev.job(setups.plane_job(plane, ev.size, ev.tensile))
        shoot = setups.SIZES[ev.size].shoot
        return curves_beside(setups.run_plane(job, ev.stores), shoot=shoot)

    return ev._keep(("map_curves", plane), compute)


def tongue_boundaries(ev: Evidence, plane: str, label: str) -> dict[str, float]:
    """Shares of the boundary of the cells labelled ``label`` on ``plane`` that lie within
    one cell of a continued curve, by the curve's "type n" ("none": of no curve)."""
    from ..continuation.mapscale import distances_to, in_plane

    grid = ev.plane(plane)
    kind, n, p = (np.asarray(grid.arrays[k]) for k in ("kind", "n", "p"))
    inside = (kind == 0) & (n == int(label.split("-")[0])) & (p == int(label.split("-")[1]))
    computed = kind >= 0
    omega, second = np.asarray(grid.omega, float), np.asarray(grid.second, float)
    spacing = np.array([np.abs(np.diff(omega)).mean(), np.abs(np.diff(second)).mean()])
    centres = []
    for axis in (0, 1):
        a, b = (inside[:-1], inside[1:]) if axis == 0 else (inside[:, :-1], inside[:, 1:])
        ca, cb = (computed[:-1], computed[1:]) if axis == 0 else (computed[:, :-1], computed[:, 1:])
        for i, j in zip(*np.nonzero((a != b) & ca & cb), strict=True):
            if axis == 0:
                centres.append((omega[j], 0.5 * (second[i] + second[i + 1])))
            else:
                centres.append((0.5 * (omega[j] + omega[j + 1]), second[i]))
    if not centres:
        return {}
    centres = np.array(centres) / spacing
    nearest = np.full(len(centres), np.inf)
    names = np.full(len(centres), "none", dtype=object)
    for curve in map_curves(ev, plane):
        d = distances_to(centres, in_plane(curve, ("omega", grid.name)) / spacing)
        better = (d < nearest) & (d <= 1.5)
        nearest[better] = d[better]
        names[better] = f"{curve.type} {curve.n}"
    kinds, counts = np.unique(names.astype(str), return_counts=True)
    return {k: c / len(names) for k, c in zip(kinds, counts, strict=True)}


def tongue_claim(ev: Evidence) -> Verdict:
    """N2: the 2-2 and 2-1 tongues of the (ω, μkn) and (ω, μcn) planes bounded by PD and G
    curves (≥ BOUNDED_SHARE of each tongue's boundary within a cell of them)."""
    parts, holds = [], []
    for plane in TONGUE_PLANES:
        for label in TONGUES:
            shares = tongue_boundaries(ev, plane, label)
            if not shares:
                continue
            pd = sum(v for k, v in shares.items() if k.startswith("PD"))
            g = sum(v for k, v in shares.items() if k.startswith("G"))
            holds.append(pd + g >= BOUNDED_SHARE and pd > 0 and g > 0)
            top = ", ".join(
                f"{k} {100 * v:.0f} %" for k, v in sorted(shares.items(), key=lambda kv: -kv[1])[:4]
            )
            parts.append(f"{label} on (ω, {plane}): {top}")
    if not parts:
        return Verdict("no 2-2 or 2-1 cells on the planes", None)
    return Verdict(
        "; ".join(parts) + " (of each tongue's boundary: within a cell of a "
        "continued curve of that type and period)",
        all(holds),
    )


def tongue_command(ev: Evidence, law: str) -> str:
    return (
        "campar run jobs/mu_kn.yaml and jobs/mu_cn.yaml"
        + (" (allow: model.tensile: allow in a copy)" if law else "")
        + ", then campar curves results/mu_kn.zarr "
        "and results/mu_cn.zarr; campar plot results/mu_kn.zarr --curves"
    )

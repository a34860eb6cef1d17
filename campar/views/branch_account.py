"""A branch structure told in words, generated from the computed branches (``account``).

A family is the branches continued from one seed (``line_structure``): both ways from it,
or once round where the branch is a closed loop. Each is told as the path along it — the
n-p label and stability of every stretch, the special point between two stretches, where
it ends — then the branches switched at its PD points, each under the point it was born
at, and, for a chain of doublings, the PD points of each period in turn with the ratios of
their successive intervals (Feigenbaum's δ = 4.669… in the limit of a cascade). A last
line gives the largest |det DPⁿ| met: below 1, no Neimark–Sacker point can exist.
docs/continuation.md's account of μkn = 0.91 is this text, checked by a test.
"""

import numpy as np

from ..continuation.branch_result import Branch

# Decimals of a special point's parameter: it is located to 1e-10, so the text is the same
# on every platform; five tell the points of a cascade apart.
DIGITS = 5
SYMBOL = {"omega": "ω", "f0": "f0", "mu_kn": "μkn", "mu_cn": "μcn", "zeta": "ζ"}


def families(found) -> list[tuple[tuple, list[Branch]]]:
    """(seed, its root branches) of a LineStructure: two roots a seed (down, then up), one
    where the first is a closed loop."""
    out, k = [], 0
    for seed in found.seeds:
        roots = [found.branches[k]]
        k += 1
        if not roots[0].closed:
            roots.append(found.branches[k])
            k += 1
        out.append((seed, roots))
    return out


def side(label: str, stable: bool) -> str:
    return f"{label} {'stable' if stable else 'unstable'}"


def value(branch: Branch, x: float) -> str:
    return f"{SYMBOL.get(branch.parameter, branch.parameter)} = {x:.{DIGITS}f}"


def path(roots: list[Branch]) -> str:
    """The stretches and special points along a family's roots: from the far end of the
    second (walked backwards) through the seed to the far end of the first."""
    steps = []  # (special point, the side before it, the side after it) in path order
    if len(roots) == 2:
        for sp in reversed(roots[1].special):
            steps.append((sp, side(sp.labels[1], sp.stable[1]), side(sp.labels[0], sp.stable[0])))
    for sp in roots[0].special:
        steps.append((sp, side(sp.labels[0], sp.stable[0]), side(sp.labels[1], sp.stable[1])))
    first = roots[0]
    parts = [steps[0][1] if steps else side(first.labels[0], first.stable[0])]
    for sp, _, after in steps:
        parts += [f"{sp.type} at {value(first, sp.value)}", after]
    return ", ".join(parts)


def ends(roots: list[Branch]) -> str:
    if roots[0].closed:
        return "a closed loop (an isola)"
    return f"ends: {roots[1].end}; {roots[0].end}"


def switched(branch: Branch, depth: int) -> list[str]:
    """A sub-item per branch switched from ``branch``, recursively."""
    lines = []
    for child in branch.children:
        lines.append(
            f"{'  ' * depth}- {child.n}-cycles switched at the PD point "
            f"{value(child, child.origin.value)}: {path([child])}; {child.end}"
        )
        lines.extend(switched(child, depth + 1))
    return lines


def doublings(roots: list[Branch]) -> str:
    """The PD points of each period of a chain of doublings in turn, and the ratios of the
    successive intervals at either end; "" unless each of at least three periods has two
    PD points (a cascade from both ends of a bubble)."""
    level, pds = list(roots), []
    while level:
        points = sorted({round(sp.value, 12) for b in level for sp in b.special if sp.type == "PD"})
        if len(points) != 2:
            break
        pds.append((level[0].n, points))
        level = [child for b in level for child in b.children]
    if len(pds) < 3:
        return ""
    ratios = []
    for end in (1, 0):  # from above, from below
        x = [points[end] for _, points in pds]
        ratios.append(
            ", ".join(f"{(x[k] - x[k + 1]) / (x[k + 1] - x[k + 2]):.2f}" for k in range(len(x) - 2))
        )
    listed = "; ".join(f"{n}-cycles at {a:.{DIGITS}f} and {b:.{DIGITS}f}" for n, (a, b) in pds)
    return (
        f"  - PD points of each period in turn: {listed}; ratios of successive intervals "
        f"{ratios[0]} from above, {ratios[1]} from below (Feigenbaum's δ = 4.669 in the limit)"
    )


def account(found) -> list[str]:
    """The structure of a LineStructure as Markdown list items, one family after another."""
    lines = []
    for (omega, label, source), roots in families(found):
        where = "the path's cell" if source == "path" else "the census"
        lines.append(
            f"- **{label.split('-')[0]}-cycles** from {where} at "
            f"{SYMBOL.get(roots[0].parameter, roots[0].parameter)} = {omega:.6g} "
            f"({label}): {path(roots)}; {ends(roots)}"
        )
        for root in roots:
            lines.extend(switched(root, 1))
        cascade = doublings(roots)
        if cascade:
            lines.append(cascade)
    dets = [
        float(np.abs(b.multipliers.prod(axis=1)).max())
        for root in found.branches
        for b in root.walk()
        if len(b.values)
    ]
    ns = sum(sp.type == "NS" for root in found.branches for b in root.walk() for sp in b.special)
    lines.append(
        f"- {ns} Neimark–Sacker points: |det DPⁿ| ≤ {max(dets):.4f} on every branch"
        if ns == 0
        else f"- {ns} Neimark–Sacker points"
    )
    return lines

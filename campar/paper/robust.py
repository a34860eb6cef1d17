"""Label claims (the paper's Fig. 6) tested for robustness, not for one lucky cell.

A label the paper gives at one ω counts as reproduced only if

- it holds at every cell of a neighbourhood of that ω, ``NEIGHBOURS`` cells of
  ``STEP`` on either side (ω ± WIDTH), both along the paper's path (the (ω, μkn)
  plane's 2-D continuation from its corner, ``chains: {start: continue}``, to
  ω + WIDTH, then on along ω in steps of STEP) and from rest at each of those ω;
- a quasi-periodic or chaotic label also survives a long run (``LONG_RUN``
  revolutions as a fixed transient, then the read window) from the path's state;
- and it is specific: at the paper's other Fig. 6 speeds outside the
  neighbourhood, where the paper claims a different label, campar's label
  differs from it. A label that never changes over the whole range matches
  "2-2 at 3.0" as well as it would match "2-2 at 2.83", where the paper says 4-4.

``judge_label`` is the rule on plain data (so it can be tested on synthetic
labels); ``label_claim`` gathers the data from ``Evidence``.
"""

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import setups
from .claims import LONG_RUN, Evidence, Verdict

NEIGHBOURS = 2  # cells on either side of the claimed ω
STEP = 0.005  # their spacing in ω
WIDTH = NEIGHBOURS * STEP  # the neighbourhood: ω ± 0.01
NONPERIODIC = ("chaos", "QP")


@dataclass(frozen=True)
class Neighbourhood:
    """Labels at ω0 + k STEP (k = NEIGHBOURS … −NEIGHBOURS, ω decreasing) along the paper's
    path and from rest, the path's states there, and long-run labels where computed."""

    omega0: float
    omega: tuple[float, ...]
    path: tuple[str, ...]
    rest: tuple[str, ...]
    states: tuple[tuple[float, float], ...]
    long: tuple[str, ...] = ()  # LONG_RUN revolutions from the path's states (NaN: none)

    @property
    def centre(self) -> int:
        return len(self.omega) // 2


def judge_label(
    expected: str, hood: Neighbourhood, rivals: list[tuple[float, str, str]]
) -> tuple[bool, list[str]]:
    """Whether the claim "``expected`` at hood.omega0" is reproduced robustly, and why not.

    ``rivals``: (ω, the paper's label there, campar's path label there) of the paper's other
    claims whose label differs from ``expected``; those within WIDTH of ω0 are ignored
    (they fall inside the neighbourhood, which must hold ``expected`` throughout).
    """
    reasons = []
    for name, labels in (("path", hood.path), ("rest", hood.rest)):
        wrong = [(w, lab) for w, lab in zip(hood.omega, labels, strict=True) if lab != expected]
        if wrong or len(labels) != 2 * NEIGHBOURS + 1:
            cells = ", ".join(f"{lab} at {w:.4g}" for w, lab in wrong)
            reasons.append(
                f"{name}: {len(labels) - len(wrong)}/{len(labels)} cells {expected}"
                + (f" ({cells})" if cells else "")
            )
    # (a path that fails already has its reason; its long runs are context only)
    path_holds = all(lab == expected for lab in hood.path)
    long_holds = len(hood.long) == len(hood.omega) and all(lab == expected for lab in hood.long)
    if expected in NONPERIODIC and path_holds and not long_holds:
        found = ", ".join(hood.long) or "not run"
        reasons.append(f"{LONG_RUN} revolutions from the path's states: {found}")
    same = [
        (w, claimed)
        for w, claimed, ours in rivals
        if abs(w - hood.omega0) > WIDTH + 1e-12 and ours == expected
    ]
    if same:
        where = ", ".join(f"ω = {w:g} (paper: {claimed})" for w, claimed in same)
        reasons.append(f"not specific: campar's path gives {expected} also at {where}")
    return not reasons, reasons


def neighbourhood(
    ev: Evidence, omega0: float, expected: str, second: float = setups.FIG6_MU_KN
) -> Neighbourhood:
    """The labels around ω0 along the paper's path and from rest (see the module doc)."""

    def compute():
        top = omega0 + WIDTH
        row = ev.path_row(second, top)
        start = (float(row.state[-1, 0]), float(row.state[-1, 1]))
        line = ev.line(
            (top, omega0 - WIDTH), 2 * NEIGHBOURS + 1, initial=start, sections=1, mu_kn=second
        )
        omegas = tuple(float(w) for w in line.omega)
        states = tuple((float(y), float(v)) for y, v in line.state)
        rest = tuple(ev.rest(w, mu_kn=second).label for w in omegas)
        path = tuple(line.labels)
        long = ()
        if expected in NONPERIODIC:
            cells = range(len(omegas)) if all(lab == expected for lab in path) else [NEIGHBOURS]
            long = tuple(ev.long_run(omegas[i], states[i], mu_kn=second).label for i in cells)
        return Neighbourhood(omega0, omegas, path, rest, states, long)

    return ev._keep(("hood", omega0, expected, second), compute)


def label_claim(omega: float, expected: str) -> Callable:
    """The Fig. 6 claim "``expected`` at ω" (μkn = 0.91), judged by ``judge_label``."""

    def evaluate(ev: Evidence) -> Verdict:
        hood = neighbourhood(ev, omega, expected)
        rivals = []
        for w, claimed in setups.FIG6_CLAIMS:
            if claimed != expected and abs(w - omega) > WIDTH + 1e-12:
                other = neighbourhood(ev, w, claimed)
                rivals.append((w, claimed, other.path[other.centre]))
        match, reasons = judge_label(expected, hood, rivals)
        centre = hood.centre
        text = (
            f"path {hood.path[centre]}, rest {hood.rest[centre]}; ω ± {WIDTH:g}: path "
            f"{summary(hood.path)}, rest {summary(hood.rest)}"
        )
        if hood.long:
            where = "the path's states" if len(hood.long) > 1 else "the path's state at ω"
            text += f"; {LONG_RUN} revolutions from {where}: {summary(hood.long)}"
        if expected in NONPERIODIC:
            text += "; " + nonperiodic_context(ev, expected, omega)
        if reasons:
            text += ". Not robust: " + "; ".join(reasons)
        y, v = hood.states[centre]
        law = law_flags_text(ev)
        command = (
            f"campar point --omega {omega:g} --mu-kn {setups.FIG6_MU_KN:g} --y0 {y:.9g} "
            f"--v0 {v:.9g}{law} (the path's state); campar point --omega {omega:g} "
            f"--mu-kn {setups.FIG6_MU_KN:g}{law} (from rest)"
        )
        return Verdict(text, match, command)

    return evaluate


def summary(labels) -> str:
    """ "2-2 ×5" or "2-2 ×3, 1-1 ×2" (in order of first appearance)."""
    counts = {}
    for lab in labels:
        counts[lab] = counts.get(lab, 0) + 1
    return ", ".join(f"{lab} ×{c}" for lab, c in counts.items()) or "–"


def law_flags_text(ev: Evidence) -> str:
    """The ``campar point`` flags of the evidence's force law and options."""
    text = "" if ev.tensile == "clamp" else f" --tensile {ev.tensile}"
    for key, value in sorted(ev.options.items()):
        text += f" --{key.replace('_', '-')} {value}"
    return text


def nonperiodic_context(ev: Evidence, label: str, omega: float) -> str:
    """Where the fine line (ω-continuation from rest at 6.0, step 0.001) has ``label`` cells,
    and what the nearest one is when run from rest and for LONG_RUN revolutions."""
    line = ev.fine_line(setups.FIG6_MU_KN)
    labels = np.array(line.labels)
    cells = np.flatnonzero(labels == label)
    where = f"the line ω {line.omega[0]:g} → {line.omega[-1]:g} (step 0.001, from rest at 6)"
    if not cells.size:
        return f"no {label} cell on {where}"
    i = int(cells[np.argmin(np.abs(line.omega[cells] - omega))])
    w = float(line.omega[i])
    long = ev.long_run(w, line.state[i], mu_kn=setups.FIG6_MU_KN)
    rest = ev.rest(w, mu_kn=setups.FIG6_MU_KN)
    text = (
        f"{cells.size} {label} cells on {where}, the nearest at ω = {w:.4g}: "
        f"{LONG_RUN} revolutions from the line's state there give {long.label}, "
        f"from rest {rest.label}"
    )
    if rest.kind == "periodic" and rest.multipliers:
        text += " (stable, |λ| = " + ", ".join(f"{abs(m):.2g}" for m in rest.multipliers) + ")"
    return text

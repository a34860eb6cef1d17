"""Every step's dense output keeps its contact mode's sign of ε: no event stepped over.

    python benchmarks/step_signs.py STORE [STORE …] [--cells 500] [--seed 0]

For a random sample of a map store's periodic cells, the cell's steady orbit (its period,
at most 8 revolutions, from its stored final state) is traced with the job's model and
solver, and each step's dense output is read at SAMPLES − 1 interior points. A step in
free flight must keep ε ≤ 0 inside, one in contact (pushing, or slack under the clamp)
ε ≥ 0: a sample beyond EPS_NOISE on the wrong side is a contact, or a flight, that began
and ended inside one step without its events. The check reads ε exactly (the cam's S at
the sample's angle) against the integrator's own interpolant, so it tests the event
search, not the integration. Prints, per store, the steps and violations by mode and the
first few violating steps (row, column, label, mode, the step's index, ε's range).
"""

import argparse
import time

import numpy as np

import campar
from campar.core.codes import PERIODIC
from campar.core.model import FREE, PUSH, SLACK
from campar.views import dataset as campar_dataset
from campar.views.point import trace_steady

SAMPLES = 48  # dense samples a step, its end included
EPS_NOISE = 1e-9  # ε's rounding near an event, well above the event tolerance's 1e-11
MAX_REVOLUTIONS = 8
MODES = {FREE: "free", PUSH: "push", SLACK: "slack"}


def steady_steps(cell) -> tuple[np.ndarray, np.ndarray]:
    """ε at the SAMPLES samples of each step of the cell's steady orbit, (steps, SAMPLES),
    and each step's contact mode."""
    revolutions = int(min(max(int(cell.stored["n"]), 1), MAX_REVOLUTIONS))
    steps = int(cell.stored["steps"])
    trace = trace_steady(cell.model, cell.state, revolutions, steps, per_step=SAMPLES)
    if trace is None:
        raise RuntimeError(f"the trace of {cell.coordinates} failed")
    return trace.by_step(trace.eps), trace.by_step(trace.contact)[:, -1]


def scan(path: str, cells: int, seed: int) -> None:
    ds = campar_dataset.open(path)
    second = ds["kind"].dims[0]  # (second parameter, ω)
    omega, values = ds["omega"].values, ds[second].values
    labels = ds["label"].values
    rows, cols = np.nonzero(ds["kind"].values == PERIODIC)
    pick = np.random.default_rng(seed).choice(len(rows), min(cells, len(rows)), replace=False)
    steps = dict.fromkeys(MODES, 0)
    wrong = dict.fromkeys(MODES, 0)
    examples = []
    start = time.perf_counter()
    for i in pick:
        row, col = int(rows[i]), int(cols[i])
        cell = campar.cell(path, omega=float(omega[col]), **{second: float(values[row])})
        eps, mode = steady_steps(cell)
        inner = eps[:, :-1]
        off = np.where(mode == FREE, inner.max(axis=1) > EPS_NOISE, inner.min(axis=1) < -EPS_NOISE)
        for m in MODES:
            steps[m] += int(np.sum(mode == m))
            wrong[m] += int(np.sum(off & (mode == m)))
        for j in np.flatnonzero(off)[: max(0, 5 - len(examples))]:
            examples.append(
                f"  ({row}, {col}) {labels[row, col]} {MODES[mode[j]]} step {j}, "
                f"ε {eps[j].min():.3g} … {eps[j].max():.3g}"
            )
    elapsed = time.perf_counter() - start
    counts = ", ".join(f"{MODES[m]} {steps[m]} ({wrong[m]} wrong)" for m in MODES)
    print(f"{path}: {len(pick)} cells, steps {counts}; {elapsed:.0f} s", flush=True)
    for line in examples:
        print(line)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("stores", nargs="+")
    parser.add_argument("--cells", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    for path in args.stores:
        scan(path, args.cells, args.seed)


if __name__ == "__main__":
    main()

"""Every periodic cell of a chain against SciPy with a bounded step: its p and its cycle.

    python benchmarks/contact_count.py [--laws …] [--contact MU_KN MU_CN …] [--points 241]

For each motion law (rise and fall alike) and each (μkn, μcn), the chain ω 6 → 1 (f0 0.5,
ζ 0.2) is computed by campar (``run_cells``, labels only); from each periodic cell's final
state, n revolutions are integrated by SciPy (campar.bench.scipy_model: DOP853 rtol 1e-11,
exact contact events) with its step bounded to 0.005, so that no contact shorter than
that is stepped over. A cell is "off" where SciPy's detachments over the n revolutions
are not campar's p, or its state after them is over 1e-5 from the start (campar's cycle
is not SciPy's). Prints one line a chain, with the off cells (index, ω, label, SciPy's
detachments, the distance). Slow: ~30–60 s a chain on one core.
"""

import argparse
import time

import numpy as np

from campar.bench.scipy_model import Model as ScipyModel
from campar.bench.scipy_model import integrate
from campar.model.compute import run_cells
from campar.model.model import Model
from campar.views.dataset import cell_labels

LAWS = ("cycloidal", "polynomial-345", "modified-trapezoid", "modified-sine", "cosine")
CONTACTS = ((0.8, 0.8), (0.95, 0.8), (0.95, 0.95))
MAX_STEP = 0.005
OFF = 1e-5


def chain(law: str, mu_kn: float, mu_cn: float, points: int) -> tuple[int, list]:
    omega = np.linspace(6.0, 1.0, points)
    cam = {"rise": law, "fall": law}
    model = Model.build(
        {"omega": 6.0, "f0": 0.5, "mu_kn": mu_kn, "mu_cn": mu_cn, "model": {"cam": cam}}
    )
    out = run_cells(model, omega=omega, outputs=("label",))
    labels = cell_labels(out.kind, out.n, out.p)
    checked, off = 0, []
    for i, w in enumerate(omega):
        n = int(out.n[i])
        if n < 1:
            continue
        scipy = ScipyModel(omega=w, f0=0.5, mu_kn=mu_kn, mu_cn=mu_cn, rise=law, fall=law)
        end, events, _ = integrate(
            scipy, np.array(out.state[i]), n, rtol=1e-11, atol=1e-13, max_step=MAX_STEP
        )
        detachments = sum(kind == "detachment" for _, kind in events)
        distance = float(np.abs(np.asarray(end) - out.state[i]).max())
        checked += 1
        if detachments != out.p[i] or distance > OFF:
            off.append((i, round(float(w), 4), str(labels[i]), detachments, f"{distance:.1e}"))
    return checked, off


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--laws", nargs="+", default=LAWS, choices=LAWS)
    parser.add_argument(
        "--contact", nargs=2, type=float, action="append", metavar=("MU_KN", "MU_CN")
    )
    parser.add_argument("--points", type=int, default=241)
    args = parser.parse_args()
    for mu_kn, mu_cn in args.contact or CONTACTS:
        for law in args.laws:
            start = time.perf_counter()
            checked, off = chain(law, mu_kn, mu_cn, args.points)
            print(
                f"{law} μkn {mu_kn} μcn {mu_cn}: {checked} periodic cells, {len(off)} off "
                f"({time.perf_counter() - start:.0f} s) {off}",
                flush=True,
            )


if __name__ == "__main__":
    main()

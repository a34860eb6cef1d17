"""Map edges typed by shooting (campar.continuation.edges), against SciPy."""

import numpy as np
import pytest
from support.jobs import SHOT_CORNER

from campar.continuation.edges import Cell, type_edge
from campar.continuation.section_map import SectionMap

# An edge of the (ω, μkn) plane (jobs/mu_kn.yaml at 400²) between a 1-1 cell and the 1-2
# cell after it along ω, with the cells' stored final states: a new flight appears
# between them (a grazing), which the stored ε extrema cannot show.
FIXED = {"zeta": 0.2, "mu_cn": 0.8, "f0": 0.5, "mu_kn": 0.95}
BEFORE = Cell({**FIXED, "omega": 1.4737844611528823}, (-0.008265748117109561, 0.26294188315912), 1)
AFTER = Cell({**FIXED, "omega": 1.4587969924812025}, (0.0022705935799745536, 0.23689884074162), 1)


def scipy_detachments(omega: float, guess) -> tuple[int, np.ndarray]:
    """Detachments per revolution of the 1-cycle at ω by SciPy shooting (DOP853, exact
    contact events, steps ≤ 1e-3 so that a short flight is not stepped over)."""
    from campar.bench.scipy_model import Model, integrate
    from campar.bench.scipy_shooting import fixed_point, section_map

    parameters = {**FIXED, "omega": omega}
    try:
        x, _ = fixed_point(parameters, guess, 1)
    except RuntimeError:  # within ~1e-5 of the grazing its difference Jacobian spans the kink
        x = np.asarray(guess, float)  # the cycle is stable there: iterate the map onto it
        for _ in range(200):
            x, last = section_map(parameters, x, 1), x
            if np.max(np.abs(x - last)) <= 1e-10:
                break
    _, events, _ = integrate(Model(omega=omega, **FIXED), x, 1, max_step=1e-3)
    return sum(kind == "detachment" for _, kind in events), x


@pytest.mark.slow
def test_grazing_edge_is_located_where_scipy_sees_the_new_flight():
    change = type_edge(BEFORE, AFTER, SectionMap())
    assert change.type == "G" and change.side == "before"
    assert abs(change.value) < 1e-4  # the ε extremum nearest 0, at the located point
    w0, w1 = BEFORE.parameters["omega"], AFTER.parameters["omega"]
    located = w0 + change.at * (w1 - w0)
    # SciPy's 1-cycle has one detachment a revolution just before the located point and
    # two just after it: the new flight appears within 0.5 % of the edge of it.
    margin = 5e-3 * (w1 - w0)
    before, x = scipy_detachments(located - margin, BEFORE.state)
    after, _ = scipy_detachments(located + margin, x)
    assert (before, after) == (1, 2)


def orbit(n=1, p=1, touch=-0.1, multipliers=(0.5, 0.1), state=(0.0, 0.0)):
    """A PeriodicOrbit with what change_between reads; the rest placeholders."""
    from campar.continuation.orbit import PeriodicOrbit

    sections = np.array([state] * n, float)
    return PeriodicOrbit(
        parameters={},
        model={},
        n=n,
        p=p,
        state=state,
        sections=sections,
        multipliers=tuple(complex(m) for m in multipliers),
        residual=0.0,
        iterations=0,
        dc=0.5,
        eps_min=-1.0,
        eps_max=1.0,
        pn_max=1.0,
        touch=touch,
    )


@pytest.mark.parametrize(
    ("a", "b", "expected"),
    [
        (orbit(), orbit(), None),  # nothing changes along the branch
        (orbit(), orbit(p=2), "G"),  # a new flight: detachments per period change
        (orbit(touch=-1e-3), orbit(touch=2e-3), "G"),  # the ε extremum nearest 0 crosses it
        (orbit(multipliers=(-0.9, 0.1)), orbit(multipliers=(-1.1, 0.1)), "PD"),
        (orbit(multipliers=(0.9, 0.1)), orbit(multipliers=(1.2, 0.1)), "SN"),
        (orbit(multipliers=(0.9j, -0.9j)), orbit(multipliers=(1.1j, -1.1j)), "NS"),
        (orbit(n=2), orbit(n=1), "PD"),  # the doubled cycle meets the one it doubled
        (orbit(multipliers=(-1.2, 0.1)), orbit(multipliers=(-1.3, 0.1)), None),  # unstable both
    ],
)
def test_change_between_two_orbits_of_a_branch(a, b, expected):
    from campar.continuation.edges import change_between

    assert change_between(a, b) == expected


def test_same_cycle_at_any_phase_but_not_another_period():
    from campar.continuation.edges import same_cycle

    two = orbit(n=2, state=(0.1, 0.2))
    two = type(two)(**{**two.__dict__, "sections": np.array([[0.1, 0.2], [0.3, 0.4]])})
    assert same_cycle(orbit(n=2, state=(0.3, 0.4)), two)  # the other point of the 2-cycle
    assert not same_cycle(orbit(n=2, state=(0.3, 0.41)), two)
    assert not same_cycle(orbit(n=1, state=(0.1, 0.2)), two)


def test_plot_bifurcations_shoot_types_the_unknown_edges(tmp_path, capsys):
    import json

    from campar.cli import main
    from campar.sweep.job import Job
    from campar.sweep.runner import run_job

    store = tmp_path / "corner.zarr"
    run_job(Job.from_dict(SHOT_CORNER), store)
    assert (
        main(["plot", str(store), "--bifurcations", "--json", "-o", str(tmp_path / "a.png")]) == 0
    )
    plain = json.loads(capsys.readouterr().out)
    args = [
        "plot",
        str(store),
        "--bifurcations",
        "--shoot",
        "--json",
        "-o",
        str(tmp_path / "b.png"),
    ]
    assert main(args) == 0
    shot = json.loads(capsys.readouterr().out)
    assert plain["counts"]["unknown"] >= 2  # the stored ε extrema cannot tell these
    assert shot["counts"]["unknown"] == 0
    assert shot["counts"]["G"] == plain["counts"]["G"] + plain["counts"]["unknown"]
    for segment in shot["segments"]:
        assert {segment["from"], segment["to"]} <= {"1-1", "1-2", "1-3"}  # flights added
        assert segment["evidence"]["critical"] == "graze" and segment["evidence"]["side"]

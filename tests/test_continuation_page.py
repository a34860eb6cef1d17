"""docs/continuation.md does what it says: every command line on the page is run here, as
written, and the claim its text makes is checked — against SciPy's shooting
(campar.bench.scipy_shooting) where it is a number; its account of the branches at
μkn = 0.91 is what the computed branches give."""

import re
import shlex
import shutil
from pathlib import Path

import numpy as np
import pytest

from campar.bench import scipy_shooting
from campar.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "continuation.md"
MU_KN = 0.91
# The 1-cycle's PD points at μkn = 0.91 that the page names ("near 3.5426 and 2.3664").
PD_NEAR = (3.5426, 2.3664)


def page_commands() -> set[str]:
    """The command lines of the page: those of its code blocks, and those written inline
    with options (``campar point --omega …``; placeholders such as MAP or N excluded)."""
    text = PAGE.read_text()
    found = set()
    for block in re.findall(r"```(?:sh|console)\n(.*?)```", text, re.S):
        for line in block.splitlines():
            line = line.removeprefix("$ ").strip()
            if line.startswith("campar "):
                found.add(line)
    for inline in re.findall(r"`(campar (?:point|continue) --[^`]*)`", text):
        if not any(word.isupper() for word in inline.split()):  # MAP, N: a placeholder
            found.add(" ".join(inline.split()))
    return found


def run(command: str, capsys) -> tuple[str, str]:
    argv = shlex.split(command)[1:]
    assert main(argv) == 0, capsys.readouterr().err
    return capsys.readouterr()


def scipy_cycle(parameters: dict, state, n: int):
    """(x, multipliers larger first) of the n-cycle through ``state`` by SciPy's shooting."""
    x, jac = scipy_shooting.fixed_point(parameters, state, n)
    return x, scipy_shooting.multipliers(jac)


def pd_points(out: str) -> list[float]:
    return [float(v) for v in re.findall(r"PD at omega=([0-9.]+)", out)]


def check_unstable_cycle(command, capsys, tmp_path):
    """The 1-1 cycle at ω = 3.54, past the PD point: unstable, a multiplier below −1."""
    out, _ = run(command, capsys)
    assert out.startswith("1-1 cycle (unstable) at omega=3.54")
    y, v = (float(c) for c in re.search(r"section points: \(([^,]+), ([^)]+)\)", out).groups())
    x, mult = scipy_cycle({"omega": 3.54, "mu_kn": MU_KN}, (y, v), 1)
    assert np.abs(x - [y, v]).max() <= 1e-8
    shown = float(re.search(r"multipliers: ([-0-9.]+)", out).group(1))
    assert abs(mult[0].real - shown) <= 1e-6 and mult[0].real < -1.0


def check_first_example(command, capsys, tmp_path):
    """The 1-cycle's branch: PD points near 3.5426 and 2.3664 (SciPy's to 1e-6); the
    2-cycles born at the first return onto the 1-cycles at the second, with no doubling
    of their own; the figure written."""
    out, _ = run(command, capsys)
    assert out.splitlines()[0].startswith("start: 1-1 cycle (stable) at omega=6")
    branch_lines = [line for line in out.splitlines() if line.startswith("branch of period")]
    assert [line.split(":")[0] for line in branch_lines] == [
        "branch of period 1",
        "branch of period 2",
    ]
    first = out.split("branch of period 2")[0]
    found = pd_points(first)
    assert len(found) == 2 and np.allclose(found, PD_NEAR, atol=1e-4)
    for value in found:
        scipy_value, _ = scipy_shooting.bifurcation_point(
            "PD", {"omega": value, "mu_kn": MU_KN}, "omega", guess_on_branch(value), 1
        )
        assert abs(scipy_value - value) <= 1e-6
    assert "returned onto the 1-cycles at their PD point omega=2.3664" in out
    assert (tmp_path / "branches.png").stat().st_size > 0


def guess_on_branch(omega: float):
    """A start for SciPy's Newton: campar's 1-cycle at ω."""
    from campar.continuation.orbit import find_cycle

    return find_cycle(1, (0.6, -0.6), omega=omega, mu_kn=MU_KN).state


def check_two_parameter_example(command, capsys, tmp_path):
    """One PD curve of 1-cycles, through the branch's PD point; the curves' figure written."""
    out, err = run(command, capsys)
    assert "campar continue:" not in err  # nothing asked for is missing
    curves = [line for line in out.splitlines() if " curve of " in line]
    assert len(curves) == 1 and curves[0].startswith("PD curve of 1-cycles in (omega, mu_kn)")
    assert len(pd_points(out)) == 1 and abs(pd_points(out)[0] - PD_NEAR[0]) <= 1e-4
    assert (tmp_path / "pd.png").stat().st_size > 0
    assert (tmp_path / "pd-curves.png").stat().st_size > 0


def check_escape(command, capsys, tmp_path):
    """From next to the unstable 1-cycle: the 2-2 cycle within 20 revolutions, flagged
    escaped; SciPy's 2-cycle through its state is stable."""
    out, _ = run(command, capsys)
    assert out.startswith("2-2  (periodic; ok)")
    revolutions = int(re.search(r"(\d+) revolutions", out).group(1))
    assert revolutions <= 20 and "escaped" in out.split("flags:")[1]
    from campar.views.point import simulate_point

    cell = simulate_point(3.54, mu_kn=MU_KN, y0=0.5406, v0=-0.72436)
    _, mult = scipy_cycle({"omega": 3.54, "mu_kn": MU_KN}, cell.state, 2)
    assert np.abs(mult).max() < 1.0


def check_slow_cycle(command, capsys, tmp_path):
    """A budget ending next to a slowly attracting cycle: 2-2 after its 500 revolutions and
    Newton's method on P², flagged slow; SciPy's 2-cycle there has its multiplier 0.998."""
    out, _ = run(command, capsys)
    assert out.startswith("2-2  (periodic; ok)")
    assert "502 revolutions" in out and "slow" in out.split("flags:")[1]
    parameters = {"omega": 2.351717171717172, "mu_cn": 0.8515151515151514}
    _, mult = scipy_cycle(parameters, (0.08519105224337234, -1.0035574481119836), 2)
    assert abs(abs(mult[0]) - 0.998) <= 5e-4


def check_map_curves(commands, capsys, tmp_path):
    """The tongue's map, its curves, and the map drawn with them: a PD curve of 1-cycles
    through the 1-cycle's PD point at μkn = 0.91 (within a cell)."""
    from campar.views.map_curves import read_curves

    (tmp_path / "jobs").mkdir()
    shutil.copy(ROOT / "jobs" / "mu_kn_tongue.yaml", tmp_path / "jobs")
    for command in commands:
        run(command, capsys)
    curves = read_curves(tmp_path / "results" / "mu_kn_tongue.zarr")
    cell = np.array([2.5 / 59, 0.11 / 39])  # the map's spacing in (ω, μkn)
    near = [
        np.abs((c.values - [PD_NEAR[0], MU_KN]) / cell).max(axis=1).min()
        for c in curves
        if (c.type, c.n) == ("PD", 1)
    ]
    assert near and min(near) <= 1.0
    assert (tmp_path / "mu_kn_tongue-labels.png").stat().st_size > 0


MAP_COMMANDS = (
    "campar run jobs/mu_kn_tongue.yaml",
    "campar curves results/mu_kn_tongue.zarr",
    "campar plot results/mu_kn_tongue.zarr --curves",
)
CHECKS = {
    "campar point --omega 3.54 --mu-kn 0.91 --cycle 1": check_unstable_cycle,
    "campar continue --omega 6:2 --mu-kn 0.91 --cycle 1 --switch 4 -o branches.png "
    "--line 400": check_first_example,
    "campar continue --omega 4:3 --mu-kn 0.91 --cycle 1 --curves PD --second "
    "mu_kn:0.84:0.95 -o pd.png": check_two_parameter_example,
    "campar point --omega 3.54 --mu-kn 0.91 --y0 0.5406 --v0 -0.72436": check_escape,
    "campar point --omega 2.351717171717172 --mu-cn 0.8515151515151514 --y0 "
    "0.08519105224337234 --v0 -1.0035574481119836": check_slow_cycle,
}
SLOW = {check_first_example}


def test_every_command_line_of_the_page_has_its_check():
    assert page_commands() == set(CHECKS) | set(MAP_COMMANDS)


@pytest.mark.parametrize(
    "command",
    [pytest.param(c, marks=pytest.mark.slow) if CHECKS[c] in SLOW else c for c in CHECKS],
)
def test_a_command_of_the_page_does_what_its_text_says(command, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    CHECKS[command](command, capsys, tmp_path)


@pytest.mark.slow
def test_the_maps_curves_commands_do_what_the_page_says(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    check_map_curves(MAP_COMMANDS, capsys, tmp_path)


GENERATED = re.compile(
    r"<!-- account of the branches at μkn = 0\.91: generated, do not edit by hand -->\n"
    r"(.*?)<!-- end of the generated account -->",
    re.S,
)


@pytest.mark.slow
def test_the_account_at_mu_kn_091_is_what_the_computed_branches_give():
    from campar.paper.continued import compute_structure
    from campar.views.branch_account import account

    written = GENERATED.search(PAGE.read_text()).group(1)
    generated = "\n".join(account(compute_structure())) + "\n"
    assert written == generated, f"the page's account is out of date; it is now:\n{generated}"

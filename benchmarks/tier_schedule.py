"""How the tiers plugin's xdist workers share the machine, on a synthetic suite of tests
that sleep (no CPU: the machine's load hardly moves it).

    python benchmarks/tier_schedule.py [--baseline TREE] [--rounds 3]

The suite has the real one's shape: 6 modules, each of 12 shared tests (10 of 0.1 s, 2 of
4 s) with an ``mpi`` test (0.5 s, exclusive) after every third: 54 s of shared tests, 12 s
of exclusive ones. On 2 workers at best 12 + 54 / 2 = 39 s. It runs under this tree's
tests/support/tiers.py and, with ``--baseline``, another checkout's, alternately, and
prints each run's wall time.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TREE = Path(__file__).resolve().parents[1]
INI = "[pytest]\nmarkers =\n    process\n    mpi\n    slurm\n    browser\n    slow\n"


def write_suite(folder: Path) -> None:
    for m in range(6):
        body = ["import time", "import pytest", ""]
        for i in range(12):
            seconds = 4.0 if i in (4, 9) else 0.1
            body += [f"def test_shared_{i}():", f"    time.sleep({seconds})", ""]
            if i % 3 == 2:
                body += ["@pytest.mark.mpi", f"def test_exclusive_{i}():", "    time.sleep(0.5)"]
                body += [""]
        (folder / f"test_m{m}.py").write_text("\n".join(body))
    (folder / "pytest.ini").write_text(INI)


def timed(tree: Path, folder: Path) -> float:
    env = {**os.environ, "PYTHONPATH": str(tree / "tests")}
    command = [sys.executable, "-m", "pytest", "-p", "support.tiers", "-p", "no:cacheprovider"]
    start = time.monotonic()
    done = subprocess.run(
        [*command, "--all-tiers", "-n", "2", "-q", "."],
        cwd=folder,
        env=env,
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        sys.exit(f"tier_schedule: the synthetic suite failed under {tree}:\n{done.stdout}")
    return time.monotonic() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", type=Path, help="another checkout to compare with")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    if args.baseline is not None and not (args.baseline / "tests/support/tiers.py").is_file():
        print(f"tier_schedule: {args.baseline}: no tests/support/tiers.py there", file=sys.stderr)
        sys.exit(2)
    trees = {"this": TREE, **({"baseline": args.baseline} if args.baseline else {})}
    with tempfile.TemporaryDirectory(prefix="campar-tier-schedule-") as folder:
        write_suite(Path(folder))
        for round_ in range(args.rounds):
            for name, tree in trees.items():
                print(f"round {round_ + 1}  {name:8s}  {timed(tree, Path(folder)):6.1f} s wall")


if __name__ == "__main__":
    main()

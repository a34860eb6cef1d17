"""The share of a test run's time that today's plain tier holds, measured inside that run.

    python benchmarks/tier_share.py RUN.log

RUN.log: the output of ``pytest --durations=0 -q`` (every test's setup, call and teardown
durations). Each test is summed under the tier it has now (``pytest --collect-only -q``
lists the plain tier's tests); the file-wide checks that are one test each now (the
present-tense and layering checks) count as plain. Prints the totals and the 25 slowest.
"""

import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

MERGED = (
    "tests/test_present_tense.py::test_the_file_describes_the_present",
    "tests/test_architecture.py::test_imports_point_down_the_layers",
)


def plain_tests() -> set[str]:
    listing = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider"],
        capture_output=True,
        text=True,
    ).stdout
    return {line for line in listing.splitlines() if "::" in line}


def main(log_path: str) -> None:
    log = Path(log_path).read_text()
    seconds: dict[str, float] = defaultdict(float)
    for match in re.finditer(r"^([\d.]+)s (?:setup|call|teardown)\s+(\S.*)$", log, re.M):
        seconds[match.group(2)] += float(match.group(1))
    plain = plain_tests()

    def tier(test: str) -> str:
        return "plain" if test in plain or test.startswith(MERGED) else "other tiers"

    total = sum(seconds.values())
    by, count = defaultdict(float), defaultdict(int)
    for test, s in seconds.items():
        by[tier(test)] += s
        count[tier(test)] += 1
    print(f"{len(seconds)} tests with durations, {total:.0f} s in all")
    for name in sorted(by):
        print(f"  {name}: {count[name]} tests, {by[name]:.0f} s ({by[name] / total:.1%})")
    for test, s in sorted(seconds.items(), key=lambda kv: -kv[1])[:25]:
        print(f"{s:8.1f}  {tier(test):11s}  {test}")


if __name__ == "__main__":
    main(sys.argv[1])

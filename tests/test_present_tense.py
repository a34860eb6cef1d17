"""Code and documentation describe the present: what campar does now and why.

History — how the code used to be, old timings, who measured what in which session —
belongs in commit messages, CHANGELOG.md and benchmarks/RESULTS.md. This test fails on
the phrases that narrate it in README.md, campar/ (comments and docstrings) and docs/.
"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

HISTORY = {
    "the tree before": re.compile(r"\btree\s+before\b|\bon the (?:code|tree) of [0-9a-f]{7}", re.I),
    "was … now": re.compile(r"\bwas\b[^.\n]{0,80}\bnow\b", re.I),
    "(was …)": re.compile(r"\(was\b", re.I),
    "session": re.compile(r"\bsessions?\b", re.I),
    "N → M s": re.compile(
        r"\d[\d.,]*\s*(?:ms|µs|s|%)?\s*→\s*\d[\d.,–]*\s*(?:CPU\s+)?(?:ms|µs|s|tiles/s)\b"
    ),
    "N s before": re.compile(r"\d\s*(?:CPU\s+)?(?:ms|µs|s)\s+before\b"),
    "dated diary heading": re.compile(r"^#+ .*\b20\d\d-\d\d-\d\d", re.M),
    "clock time": re.compile(r"\b\d\d:\d\d(?:–\d\d:\d\d)?\s+UTC\b"),
}


def narrating(text: str) -> list[str]:
    """Each history phrase in ``text``, as 'line N: name: the match'."""
    found = []
    for name, pattern in HISTORY.items():
        for match in pattern.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            found.append(f"line {line}: {name}: {match.group(0)!r}")
    return found


def checked_files() -> list[Path]:
    code, docs = sorted((ROOT / "campar").rglob("*.py")), sorted((ROOT / "docs").rglob("*.md"))
    return [ROOT / "README.md", *code, *docs]


def test_every_file_describes_the_present():
    found = [
        f"{path.relative_to(ROOT)} {phrase}"
        for path in checked_files()
        for phrase in narrating(path.read_text())
    ]
    assert not found, "narrating history:\n" + "\n".join(found)


@pytest.mark.parametrize(
    "text",
    [
        "8.74–8.95 s at 05:28 on the tree before",
        "the master was the only writer; now every worker writes",
        "(89 → 57 tiles/s)",
        "22.7 → 17.9 CPU s of compilation",
        "1.93–1.95× in five runs of the sixth session",
        "## Session of 2026-11-25: the CPU beside the kernel",
        "a capacity of 559 (was 421)",
        "21.1 CPU s before, 21.9 after",
    ],
)
def test_each_phrase_is_caught(text):
    assert narrating(text)


@pytest.mark.parametrize(
    "text",
    [
        "ω 6.0 → 0.02 and μcn 0.99 → 0.50",
        "the cell computed first, before the jump",
        "a lock whose pid no longer exists",
        "1-1 → PD → 2-2 → 4-4",
    ],
)
def test_the_present_passes(text):
    assert not narrating(text)

"""How xdist's workers share the machine (tests/support/tiers.py): the order a worker runs
its tests in, and the lock an mpi or slurm test holds alone, kept from one such test to
the next."""

import fcntl
from pathlib import Path

import pytest
from support.tiers import SharedLock, run_order


class Item:
    """What run_order reads of a collected test: its module's path and its markers."""

    def __init__(self, name: str, *markers: str) -> None:
        module, _, self.name = name.partition("::")
        self.path = Path(module)
        self.marks = [getattr(pytest.mark, m).mark for m in markers]

    def iter_markers(self):
        return iter(self.marks)

    def get_closest_marker(self, name: str):
        return next((m for m in self.marks if m.name == name), None)

    def __repr__(self) -> str:
        return f"{self.path}::{self.name}"


def names(items) -> list[str]:
    return [repr(item) for item in items]


def test_exclusive_tests_first_then_modules_with_long_tests_then_the_unit_modules():
    items = [
        Item("a.py::unit"),
        Item("b.py::unit1"),
        Item("b.py::mpi", "mpi", "process"),
        Item("b.py::unit2"),
        Item("c.py::slow", "slow"),
        Item("c.py::unit"),
        Item("d.py::slurm", "slurm", "process"),
        Item("e.py::unit"),
        Item("f.py::serial", "process"),
        Item("f.py::mpi", "mpi", "process"),
    ]
    assert names(run_order(items)) == [
        "b.py::mpi",
        "d.py::slurm",
        "f.py::mpi",
        "c.py::slow",  # a module with a long test: whole, in its order
        "c.py::unit",
        "f.py::serial",
        "a.py::unit",  # the unit modules, in their order; b's others stay together
        "b.py::unit1",
        "b.py::unit2",
        "e.py::unit",
    ]


def free(lock: SharedLock, mode: int) -> bool:
    """Whether another worker would get the room now (``mode``: LOCK_SH or LOCK_EX)."""
    try:
        fcntl.flock(lock.room, mode | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    fcntl.flock(lock.room, fcntl.LOCK_UN)
    return True


def test_an_exclusive_hold_is_kept_between_two_exclusive_tests_and_then_released(tmp_path):
    mine, other = SharedLock(tmp_path), SharedLock(tmp_path)  # two workers' locks
    with mine.hold(True, keep=True):
        assert not free(other, fcntl.LOCK_SH)
    assert mine.kept and not free(other, fcntl.LOCK_SH)  # between the two tests
    with mine.hold(True, keep=False):
        assert not free(other, fcntl.LOCK_SH)
    assert not mine.kept and free(other, fcntl.LOCK_EX)


def test_a_kept_hold_gives_way_to_a_shared_one_and_a_shared_hold_is_never_kept(tmp_path):
    mine, other = SharedLock(tmp_path), SharedLock(tmp_path)
    with mine.hold(True, keep=True):
        pass
    with mine.hold(False, keep=True):  # the next test was not exclusive after all
        assert free(other, fcntl.LOCK_SH) and not free(other, fcntl.LOCK_EX)
    assert not mine.kept and free(other, fcntl.LOCK_EX)

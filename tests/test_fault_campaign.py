"""The fault campaign (full tier): stores of both layouts damaged many times at random — any
file of the store, deleted, truncated, a bit flipped, a block zeroed, or one of the damage
suite's edits (values, coordinates, decoding attributes, metadata documents) — and after
each fault every reader: ``verify``, ``status``, ``plot``, ``campar.open``, then a resume.

Counted, and printed on a line starting ``CAMPAIGN`` (run with ``-s``): faults, detected,
repaired bitwise, refused (named, left for a person: which job a store holds is unknown),
tracebacks and silently wrong values — the last two must be 0. Detected: ``verify`` did not
say intact (65 naming the damage; 3 where the store's one file was deleted: no store). A
value is silently wrong when ``campar.open`` returns, without refusing or warning, a
coordinate, an attribute or a cell that differs from the store as written.

    pytest tests/test_fault_campaign.py -m slow -s | grep CAMPAIGN

``CAMPAR_FAULT_ROUNDS`` scales it (default 1: 16 Zarr and 4 HDF5 faults).
"""

import contextlib
import io
import os
import shutil
import warnings

import numpy as np
import pytest
from support.damage import DAMAGE, assert_synthetic, damage_file, finish, synthetic_store
from test_damage import HDF5_DAMAGE, ZARR_DAMAGE
from test_faults import short_watchdog  # noqa: F401 (fixture: rescues give up after 3 s)
from test_store import make_job

import campar
from campar.cli import main
from campar.errors import CamparError, StoreDamageWarning

ROUNDS = int(os.environ.get("CAMPAR_FAULT_ROUNDS", "1"))
# Faults per layout in the full tier (~1 s a Zarr fault, ~6 s an HDF5 one: each reader of a
# damaged HDF5 file rescues it in a child process); the figures in benchmarks/RESULTS.md
# come from CAMPAR_FAULT_ROUNDS=10.
FAULTS = {".zarr": 16, ".h5": 4}


def _quiet(*args) -> tuple[int | None, str]:
    """``campar ARGS`` in this process: (exit code, everything it printed)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in args])
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue() + err.getvalue()


def _files(path):
    return [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())


def _silently_wrong(ds, reference) -> list[str]:
    """What ``ds`` (opened without refusal) holds that the intact store does not: cells of
    tiles it calls done, coordinates, variables' attributes."""
    volatile = ("runs", "history", "date_created", "campar_version", "versions")
    keys = (set(ds.attrs) | set(reference.attrs)) - set(volatile)
    wrong = [f"attribute {k}" for k in keys if str(ds.attrs.get(k)) != str(reference.attrs.get(k))]
    done = ds["done"].values.astype(bool)
    tiles = ds["tile"].values
    rows = list(zip(ds["tile_row_start"].values, ds["tile_row_stop"].values, strict=True))
    for name, var in reference.variables.items():
        if name not in ds.variables:
            wrong.append(f"{name} missing")
            continue
        got = ds[name]
        if not _same_attrs(got.attrs, var.attrs):
            wrong.append(f"{name} attributes")
        if name in reference.coords or "tile" in var.dims or name == "label":
            derived = name in ("done", "checksum", "label")  # of damaged tiles: 0, ""
            same = np.array_equal(got.values, var.values, equal_nan=var.dtype.kind == "f")
            if not derived and not same:
                wrong.append(f"{name} values")
            continue
        for index in tiles[done]:
            start, stop = rows[index]
            a, b = got.values[start:stop], var.values[start:stop]
            if not np.array_equal(a, b, equal_nan=var.dtype.kind == "f"):
                wrong.append(f"{name} in tile {index}")
    return wrong


def _same_attrs(a, b) -> bool:
    return a.keys() == b.keys() and all(
        np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in a
    )


@pytest.mark.slow
@pytest.mark.process  # HDF5: a damaged sealed file is rescued in the guard's child process
@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_fault_campaign(tmp_path, suffix):
    rng = np.random.default_rng(len(suffix))
    job = make_job()
    pristine = tmp_path / f"pristine{suffix}"
    synthetic_store(pristine, job)
    reference = campar.open(pristine).load()
    table = ZARR_DAMAGE if suffix == ".zarr" else HDF5_DAMAGE
    counts = dict(
        faults=0,
        detected=0,
        repaired_bitwise=0,
        refused=0,
        tracebacks=0,
        silently_wrong=0,
        unchanged=0,
    )
    wrong_cases = []
    path = tmp_path / f"s{suffix}"
    for _ in range(FAULTS[suffix] * ROUNDS):
        shutil.rmtree(path, ignore_errors=True) if path.is_dir() else path.unlink(missing_ok=True)
        shutil.copytree(pristine, path) if pristine.is_dir() else shutil.copy(pristine, path)
        if rng.random() < 0.3:  # one of the damage suite's edits
            what, damage = table[int(rng.integers(len(table)))][:2]
            damage(path)
        else:  # a failing disk: any file of the store
            target = _files(path)[int(rng.integers(len(_files(path))))]
            what = damage_file(target, DAMAGE[int(rng.integers(len(DAMAGE)))], rng)
            if what is None:
                counts["unchanged"] += 1
                continue
        counts["faults"] += 1

        code, said = _quiet("verify", path)
        counts["tracebacks"] += "Traceback" in said
        detected = code != 0  # 65 naming the damage, or 3: no store there at all
        counts["detected"] += detected
        for args in (("status", path), ("plot", path, "-o", tmp_path / "map.png")):
            code, said = _quiet(*args)
            counts["tracebacks"] += "Traceback" in said or code not in (0, 3, 65, 74)

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                ds = campar.open(path)
            except CamparError:
                ds = None
            except Exception:
                counts["tracebacks"] += 1
                ds = None
        if ds is not None:
            warned = any(issubclass(w.category, StoreDamageWarning) for w in caught)
            wrong = _silently_wrong(ds.load(), reference)
            ds.close()
            if wrong and not warned or (wrong and any("tile" not in w for w in wrong)):
                counts["silently_wrong"] += 1
                wrong_cases.append((what, wrong[:3]))
            if not detected and (wrong or warned):
                counts["silently_wrong"] += 1  # verify said intact, open saw otherwise
                wrong_cases.append((what, ["verify missed it"]))

        try:
            finish(path, job)
        except CamparError:
            counts["refused"] += 1  # said in one line; campar never guesses which job
            continue
        except Exception:
            counts["tracebacks"] += 1
            continue
        assert_synthetic(path, job)
        with warnings.catch_warnings():
            warnings.simplefilter("error", StoreDamageWarning)
            assert not _silently_wrong(campar.open(path).load(), reference)
        counts["repaired_bitwise"] += 1
    print(
        "CAMPAIGN layout="
        + suffix.lstrip(".")
        + " "
        + " ".join(f"{k}={v}" for k, v in counts.items()),
        flush=True,
    )
    assert counts["tracebacks"] == 0 and counts["silently_wrong"] == 0, wrong_cases
    assert counts["faults"] > 0.8 * FAULTS[suffix] * ROUNDS
    assert counts["repaired_bitwise"] + counts["refused"] == counts["faults"]

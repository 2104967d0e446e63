"""Shared helpers of the Python package's tests: the command line as the reference, CSV
files read back as the numbers they hold, bit-for-bit comparisons."""

import csv
import json
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
#: The command line built by `cargo build --release` (scripts/python-test.sh builds it).
CLI = Path(os.environ.get("VISCOBAR_CLI", ROOT / "target" / "release" / "viscobar"))
#: summary.json's fields measured on the clock: they differ between any two runs.
CLOCK_FIELDS = ("wall_time_s", "ns_per_unknown_step", "time_shares")


def cli(*args):
    """Runs the command line; its completed process (text output)."""
    assert CLI.exists(), f"{CLI} is missing: build it with `cargo build --release`"
    return subprocess.run([str(CLI), *args], capture_output=True, text=True)


def set_args(overrides):
    """`--set KEY=VALUE` arguments for a dict whose values are --set's text."""
    return [a for k, v in overrides.items() for a in ("--set", f"{k}={v}")]


def read_csv(path):
    """A CSV file's columns as float64 arrays (an empty cell is NaN), in file order."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    names, body = rows[0], rows[1:]
    return {
        name: np.array([float(r[i]) if r[i] != "" else math.nan for r in body])
        for i, name in enumerate(names)
    }


def without_clock(summary):
    """A summary without its clock fields (each must be there)."""
    summary = dict(summary)
    for field in CLOCK_FIELDS:
        del summary[field]
    return summary


def read_summary(path):
    with open(path) as f:
        return json.load(f)


def same_bits(a, b):
    """Whether two float64 arrays hold the same bits (NaN where the other has NaN)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


@pytest.fixture
def out(tmp_path):
    return tmp_path

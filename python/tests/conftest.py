"""What the tests share: the repository's paths, the built CLI (the parity tests run
it on the same scenes) and summary.json read into arrays."""

import json
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
CLI = ROOT / "target" / "release" / "luxtally"


@pytest.fixture(scope="session")
def cli():
    """Runs the CLI binary (built by `cargo build --release`: scripts/test.sh builds
    it before the pytest suite); returns the finished process."""
    if not CLI.exists():
        pytest.fail(f"{CLI} is missing: run `cargo build --release` first")

    def run(*args, check=True):
        return subprocess.run(
            [str(CLI), *map(str, args)], capture_output=True, text=True, check=check
        )

    return run


def summary_arrays(out_dir, receiver, key):
    """A receiver's per-cell list from a CLI run's summary.json, shaped like the grid
    (null → NaN)."""
    s = json.loads((pathlib.Path(out_dir) / "summary.json").read_text())
    r = s["receivers"][receiver]
    values = [np.nan if x is None else x for x in r[key]]
    return np.array(values).reshape(r["cells"][1], r["cells"][0])


def assert_same_bits(a, b):
    """Equal arrays, NaN where NaN, bit for bit."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype
    assert a.tobytes() == b.tobytes()

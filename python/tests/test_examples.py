"""The examples run (fewer photons than their defaults)."""

import pathlib
import subprocess
import sys

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


def run(name, *args):
    return subprocess.run(
        [sys.executable, str(EXAMPLES / name), *args], capture_output=True, text=True, timeout=300
    )


def test_parametric_study_prints_illuminance_rising_with_reflectance():
    out = run("parametric_study.py", "--photons", "60000")
    assert out.returncode == 0, out.stderr
    means = [float(line.split()[1]) for line in out.stdout.splitlines()[1:6]]
    assert means == sorted(means)


def test_backend_parity_agrees():
    out = run("backend_parity.py", "--photons", "100000")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "agree" in out.stdout

"""BENCHMARKS.md, "Python (issue 30)": the office scene from Python against the CLI,
same photons and seed, measured alternately in one session; and the transfer time of a
10⁶-cell receiver (the summary's statistics, then its arrays into a luxtally.Result).

    target/py-venv/bin/python python/bench/python_vs_cli.py [--rounds 5]"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import luxtally

ROOT = pathlib.Path(__file__).resolve().parents[2]
OFFICE = ROOT / "scenes" / "office.toml"
CLI = ROOT / "target" / "release" / "luxtally"
PHOTONS = 1_000_000


def python_run():
    began = time.perf_counter()
    result = luxtally.Scene.load(OFFICE).run(photons=PHOTONS, seed=1)
    wall = time.perf_counter() - began
    return wall, result.summary["elapsed_s"]


def cli_run(out):
    began = time.perf_counter()
    subprocess.run(
        [CLI, "run", OFFICE, "--photons", str(PHOTONS), "--seed", "1", "--out", out,
         "--quiet", "--outputs", "none"],
        check=True,
    )
    wall = time.perf_counter() - began
    return wall, json.loads((pathlib.Path(out) / "summary.json").read_text())["elapsed_s"]


def big_receiver_scene():
    document = {
        "materials": {"wall": {"reflectance": 0.5}},
        "objects": [{"shape": "box", "min": [0, 0, 0], "max": [6, 5, 3], "material": "wall"}],
        "lights": [{"type": "point", "position": [3, 2.5, 2.8], "intensity_cd": 1000}],
        "receivers": [{"name": "floor", "corner": [0.01, 0.01, 0.01], "u": [5.98, 0, 0],
                       "v": [0, 4.98, 0], "cells": [1000, 1000]}],
    }
    return luxtally.Scene.from_dict(document, origin="big.toml")


def main():
    args = argparse.ArgumentParser()
    args.add_argument("--rounds", type=int, default=5)
    rounds = args.parse_args().rounds
    times = {"python": [], "cli": []}
    with tempfile.TemporaryDirectory() as out:
        for _ in range(rounds):
            times["python"].append(python_run())
            times["cli"].append(cli_run(out))
    for who, runs in times.items():
        wall = [w for w, _ in runs]
        passes = [p for _, p in runs]
        print(f"{who}: wall {statistics.median(wall):.3f} s (min {min(wall):.3f}, max "
              f"{max(wall):.3f}); photon pass {statistics.median(passes):.3f} s "
              f"(min {min(passes):.3f}, max {max(passes):.3f}) over {rounds} rounds")
    scene = big_receiver_scene()
    transfers, stats = [], []
    for _ in range(rounds):
        r = scene.run(photons=100_000, seed=1)
        assert r.receivers["floor"].values.shape == (1000, 1000)
        transfers.append(r.transfer_s)
        stats.append(r.summary_s)
    with tempfile.TemporaryDirectory() as out:
        r.save(out, outputs="none")
        t0 = time.perf_counter()
        luxtally.Result.load(out)
        load_s = time.perf_counter() - t0
    print(f"10^6-cell receiver: arrays and dict {statistics.median(transfers):.3f} s "
          f"(min {min(transfers):.3f}, max {max(transfers):.3f}); the summary's statistics "
          f"before them {statistics.median(stats):.3f} s (min {min(stats):.3f}, max "
          f"{max(stats):.3f}); Result.load of its summary.json {load_s:.3f} s")
    print(sys.version.split()[0], luxtally.__version__)


if __name__ == "__main__":
    main()

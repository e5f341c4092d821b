"""Embree against obvhs on the same scene and seed: the two backends cast the same
rays to within rounding, so their receiver means must agree within a few σ (their
bits differ: docs/architecture.md, "Bit identity"). Needs the package built with the
obvhs feature (scripts/test.sh builds it so).

    python python/examples/backend_parity.py [SCENE] [--photons N]"""

import argparse
import pathlib
import sys

import luxtally

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args.add_argument("scene", nargs="?", default=ROOT / "scenes" / "cornell.toml")
    args.add_argument("--photons", type=int, default=500_000)
    a = args.parse_args()
    if "obvhs" not in luxtally.backends():
        sys.exit("this package was built without the obvhs backend (maturin ... --features obvhs)")
    scene = luxtally.Scene.load(a.scene)
    runs = {b: scene.run(photons=a.photons, seed=1, backend=b) for b in ("embree", "obvhs")}
    worst = 0.0
    for name in runs["embree"].receivers:
        e, o = (runs[b].receivers[name] for b in ("embree", "obvhs"))
        sigma = (e.mean_sigma**2 + o.mean_sigma**2) ** 0.5
        if not sigma > 0:
            print(f"{name}: no error to compare by (embree {e.mean}, obvhs {o.mean})")
            continue
        z = abs(e.mean - o.mean) / sigma
        worst = max(worst, z)
        print(f"{name}: embree {e.mean:.4f}, obvhs {o.mean:.4f} {e.unit}, difference {z:.2f}σ")
    print("agree" if worst < 4 else "DISAGREE", f"(largest difference {worst:.2f}σ)")
    sys.exit(0 if worst < 4 else 1)


if __name__ == "__main__":
    main()

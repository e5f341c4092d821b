"""Desk illuminance against wall reflectance, with error bars: one scene loaded once,
its walls changed by Scene.set (the ray casters are built once), one run per value.

    python python/examples/parametric_study.py [--photons N] [--plot study.png]

Prints a table; with matplotlib installed and --plot, draws it too."""

import argparse
import pathlib

import luxtally

SCENE = pathlib.Path(__file__).resolve().parents[2] / "scenes" / "office.toml"


def study(photons, reflectances, seed=1):
    scene = luxtally.Scene.load(SCENE)
    rows = []
    for rho in reflectances:
        scene.set("materials.wall.reflectance", rho)
        desk = scene.run(photons=photons, seed=seed).receivers["desk"]
        rows.append((rho, desk.mean, desk.mean_sigma))
    return rows


def plot(rows, path):
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot")
        return
    rho, mean, sigma = zip(*rows)
    fig, ax = plt.subplots()
    ax.errorbar(rho, mean, yerr=[2 * s for s in sigma], fmt="o-", capsize=3)
    ax.set_xlabel("wall reflectance ρ")
    ax.set_ylabel("mean desk illuminance (lx), ±2σ")
    fig.savefig(path, dpi=120)
    print(f"plot: {path}")


def main():
    args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args.add_argument("--photons", type=int, default=300_000)
    args.add_argument("--plot", type=pathlib.Path)
    a = args.parse_args()
    rows = study(a.photons, [0.1, 0.3, 0.5, 0.7, 0.9])
    print("wall ρ   desk Ē (lx)   σ (lx)")
    for rho, mean, sigma in rows:
        print(f"{rho:6.2f}   {mean:11.2f}   {sigma:6.2f}")
    if a.plot:
        plot(rows, a.plot)


if __name__ == "__main__":
    main()

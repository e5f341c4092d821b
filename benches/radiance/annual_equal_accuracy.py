#!/usr/bin/env python3
"""Radiance's 2-phase at luxtally's accuracy, measured (not extrapolated).

Run after annual.py (reuses its work directory: office.rad, sky.rad, luxtally's CSV for
the sensors). For each -ad of --ads (in order) it runs the whole 2-phase twice,
independently (-u+): `gendaymtx -m 2 -g 0.2 x3 -O0 -of EPW`, `rfluxmtx -I+ -ab 6 -ad AD
-lw 1e-5 -aa 0 -lr 0 -u+ -n 2 -faf - sky.rad office.rad`, `dctimestep -of dc sky`; each
step timed (wall) with the 1-minute load average before it. Radiance's noise per run is
RMS(a - b)/sqrt(2) / RMS((a + b)/2) over the sensors' annual means (occupied records,
dark ones 0). It stops at the first -ad whose noise is at most --target. Before each
Radiance run it times `luxtally annual SCENE --photons N --sda-halfwidth 0.5 --threads
2 --seed S` (one round; alternated with Radiance; --lux-runs of them, seeds 1, 2, ...),
whose accuracy is its RMS mean_sigma_lx / mean_lx (and, from two seeds, the observed
RMS(a - b)/sqrt(2) / RMS(value) as for Radiance). Standard library; see benches/radiance/README.md.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import annual  # noqa: E402
import annual_5phase  # noqa: E402  (read_any, lux_cols)
import compare  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
log = compare.log


def timed(cmd, cwd, stdin=None, stdout_path=None):
    l0 = annual.load_avg()
    _, dt, _ = annual.run(cmd, cwd, stdin=stdin, stdout_path=stdout_path)
    return dict(cmd=[Path(cmd[0]).name, *cmd[1:]], wall_s=dt, load_before=l0)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--workdir", type=Path, default=REPO / "target" / "radiance-annual")
    ap.add_argument("--scene", type=Path, default=REPO / "scenes" / "daylit_office_annual.toml")
    ap.add_argument("--venv", type=Path, default=REPO / "target" / "radiance-compare" / "venv")
    ap.add_argument("--luxtally", type=Path, default=REPO / "target" / "release" / "luxtally")
    ap.add_argument("--ads", default="12288,16384,24576")
    ap.add_argument("--target", type=float, default=0.0094)
    ap.add_argument("--photons", default="80000000")
    ap.add_argument("--lux-runs", type=int, default=2)
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    work = a.workdir.resolve()
    import tomllib
    scene = tomllib.loads(a.scene.read_text())
    ann = scene["annual"]
    epw = (a.scene.resolve().parent / ann["weather"]).resolve()
    occ = [float(x) for x in ann.get("occupied_hours", [8.0, 18.0])]
    rho = f"{float(ann.get('ground_reflectance', 0.2)):g}"
    binpath, raypath, version = compare.setup_radiance(a.venv)
    os.environ["RAYPATH"] = "." + os.pathsep + raypath
    tools = annual.tools_in(binpath)
    os.environ["PATH"] = str(Path(tools["rcontrib"]).parent) + os.pathsep + os.environ.get("PATH", "")
    cells = annual.read_csv(work / "lux" / "annual_df_grid.csv")
    sensors = "".join(f"{float(c['x']):.4f} {float(c['y']):.4f} {float(c['z']):.4f} 0 0 1\n" for c in cells).encode()
    n = len(cells)
    stamps = annual.epw_stamps(epw)
    occupied = [k for k, s in enumerate(stamps) if occ[0] <= s[2] - 0.5 < occ[1]]

    lux_runs = []

    def lux_run():
        out = work / f"lux_eq_{len(lux_runs)}"
        cmd = [str(a.luxtally), "annual", str(a.scene.resolve()), "--out", str(out), "--threads", "2", "--photons", a.photons,
               "--sda-halfwidth", "0.5", "--seed", str(1 + len(lux_runs))]
        l0 = annual.load_avg()
        t0 = time.perf_counter()
        r = subprocess.run(["nice", "-n", "19", *cmd], capture_output=True, text=True)
        dt = time.perf_counter() - t0
        if r.returncode != 0:
            annual.die(r.stderr[-2000:])
        cc = annual.read_csv(out / "annual_df_grid.csv")
        m = [float(c["mean_lx"]) for c in cc]
        s = [float(c["mean_sigma_lx"]) for c in cc]
        js = json.loads((out / "annual.json").read_text())
        rec = dict(cmd=["luxtally", *cmd[1:]], wall_s=dt, load_before=l0, photons=js["photons"],
                   elapsed_s=js["elapsed_s"], sky_matrix_s=js.get("sky_matrix_s"),
                   sigma_rms_rel=compare.rms([x / y for x, y in zip(s, m)]), grid_mean=sum(m) / n,
                   sda=js["receivers"][0]["sda_300_50"], summary=r.stdout.strip().split("\n")[0])
        lux_runs.append(rec)
        log(f"luxtally {a.photons}: {dt:.1f} s (load {l0[0]:.2f}), σ {rec['sigma_rms_rel']:.2%}")

    rad = []
    done = False
    for ad in [int(x) for x in a.ads.split(",")]:
        means = []
        for tag in ("a", "b"):
            if len(lux_runs) < a.lux_runs:
                lux_run()
            steps = {}
            steps["gendaymtx"] = timed([tools["gendaymtx"], "-m", "2", "-g", rho, rho, rho, "-O0", "-of", str(epw)], work,
                                       stdout_path=work / "eq_sky.mtx")
            steps["rfluxmtx"] = timed([tools["rfluxmtx"], "-I+", "-ab", "6", "-ad", str(ad), "-lw", "1e-5", "-aa", "0",
                                       "-lr", "0", "-u+", "-n", "2", "-faf", "-", "sky.rad", "office.rad"], work,
                                      stdin=sensors, stdout_path=work / f"eq_dc_{ad}_{tag}.mtx")
            steps["dctimestep"] = timed([tools["dctimestep"], "-of", f"eq_dc_{ad}_{tag}.mtx", "eq_sky.mtx"], work,
                                        stdout_path=work / "eq_E.mtx")
            arr, nr, nc = annual_5phase.read_any(work / "eq_E.mtx")
            rows = annual_5phase.lux_cols(arr, nr, nc, occupied)
            del arr
            (work / "eq_E.mtx").unlink()
            m = [sum(r) / len(occupied) for r in rows]
            means.append(m)
            total = sum(s["wall_s"] for s in steps.values())
            rad.append(dict(ad=ad, tag=tag, steps=steps, wall_s=total, grid_mean=sum(m) / n))
            log(f"2-phase -ad {ad} ({tag}): {total:.1f} s (rfluxmtx {steps['rfluxmtx']['wall_s']:.1f} s, "
                f"load {steps['rfluxmtx']['load_before'][0]:.2f}), grid mean {sum(m) / n:.1f}")
        d = [x - y for x, y in zip(*means)]
        mm = [(x + y) / 2 for x, y in zip(*means)]
        noise = compare.rms(d) / math.sqrt(2) / compare.rms(mm)
        rad[-1]["noise_per_run"] = rad[-2]["noise_per_run"] = noise
        log(f"-ad {ad}: noise per run {noise:.2%}")
        if noise <= a.target:
            done = True
            break
    lux_noise = None
    if len(lux_runs) >= 2:
        m0 = [float(c["mean_lx"]) for c in annual.read_csv(work / "lux_eq_0" / "annual_df_grid.csv")]
        m1 = [float(c["mean_lx"]) for c in annual.read_csv(work / "lux_eq_1" / "annual_df_grid.csv")]
        lux_noise = compare.rms([x - y for x, y in zip(m0, m1)]) / math.sqrt(2) / compare.rms(
            [(x + y) / 2 for x, y in zip(m0, m1)])
        log(f"luxtally observed noise per run (seeds 1, 2): {lux_noise:.2%}")
    out = dict(radiance=version, luxtally_observed_noise_per_run=lux_noise, target=a.target, reached=done, radiance_runs=rad, luxtally_runs=lux_runs)
    print(json.dumps(dict(rad=[(r["ad"], r["tag"], round(r["wall_s"], 1), r.get("noise_per_run")) for r in rad],
                          lux=[(round(r["wall_s"], 1), r["load_before"][0], r["sigma_rms_rel"]) for r in lux_runs])))
    if a.json:
        a.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()

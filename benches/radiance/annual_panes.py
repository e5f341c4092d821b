#!/usr/bin/env python3
"""One pane against two: does the polarised pane stacking explain luxtally's offset from
Radiance's 5-phase? And Radiance's bounce ladder (-ab 6 / 10 / 16) at the back of the room.

Run after nothing (it works in its own directory, target/radiance-annual/panes/). Two
versions of scenes/daylit_office_annual.toml: the bundled one (`glazing = [0.88, 0.88]`)
and a copy written here with `glazing = [0.88]` (one pane; nothing under scenes/ is
touched). For one pane luxtally's per-polarisation stacking and Radiance's unpolarised
`glass` surfaces give the same transmittance (both sum the pane's internal reflections
per polarisation and average the two: Radiance's glass.c does so within one surface), so
the polarisation term of ANNUAL_RESULTS.md's budget (estimated × 1.0184 for two panes)
vanishes, and luxtally / Radiance on one pane over the same on two should be ≈ 1/1.0184.

Stages (`--stages lux,rad,report`, default all; each skips what its outputs already hold;
`glass` checks Radiance's two `glass` polygons against the pane formulas with rtrace):

lux    `luxtally annual SCENE --out DIR --threads 2 --photons N --sda-halfwidth 0.5
       --seed S` for both scenes and seeds 1, 2 (one round of N photons, default 80 M):
       a per-sensor σ from the two seeds' difference pooled by rows (as annual.py does
       for Radiance), and luxtally's own `mean_sigma_lx` (÷ √2 for the two-seed mean).
rad    per scene, Radiance 5-phase with luxtally's suns (annual_5phase.py's method):
       mean = [DC·(Σ sky + ground + MF 2 sun) − DC_d·(Σ MF 2 sun) + Σ C_ds] / T over the
       occupied records (the annual mean is linear in the sky vectors: no dctimestep), DC
       = `rfluxmtx -I+ -ab AB -ad 8192 -lw LW -aa 0 -lr 0 -u+ -n 2` (the ladder
       `--ladder`, once each, on the two-pane scene only, and the deep setting `--deep`
       twice, -u+, on both: Radiance's σ), DC_d = the same at `-ab 1 -ad 65536` on the
       scene with every plastic black (twice), C_ds = `rcontrib -ab 0 ... -M suns.mod` of
       luxtally's suns (its hours CSV: position and direct normal illuminance, a 0.533°
       `light` per occupied record), averaged over K × K points per cell (`--sub`).
report per-sensor comparison (annual.compare_cells: ratio of the means, RMS relative
       difference, RMS z with σ = √(σ_lux² + σ_rad²), within 2σ, the same after scaling
       Radiance by the ratio of the means) for both scenes, the ratio of the two scenes'
       ratios per sensor and by depth band, and Radiance's ladder by band.

Needs numpy: it re-runs itself with the pyradiance venv's Python (which has it). See
benches/radiance/README.md.
"""

import argparse
import json
import math
import os
import re
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))
import compare  # noqa: E402

try:
    import numpy as np
except ImportError:  # the pyradiance venv has numpy
    venv = REPO / "target" / "radiance-compare" / "venv"
    compare.setup_radiance(venv)
    os.execv(str(venv / "bin" / "python"), [str(venv / "bin" / "python"), __file__, *sys.argv[1:]])

import tomllib  # noqa: E402

import annual  # noqa: E402
import daylight  # noqa: E402

log = compare.log
W = np.array([compare.LM_PER_W * x for x in compare.PHOTOMETRIC])
SUN_R = math.radians(0.533 / 2)
SUN_SA = math.pi * SUN_R * SUN_R


def read_mtx(path):
    """A Radiance matrix (header + float/double), as an array [rows, cols, comps]."""
    data = Path(path).read_bytes()
    end = data.find(b"\n\n")
    info = {}
    for line in data[:end].decode(errors="replace").split("\n"):
        if "=" in line:
            k, v = line.split("=", 1)
            info[k.strip()] = v.strip()
    dt = {"float": np.float32, "double": np.float64}[info["FORMAT"]]
    arr = np.frombuffer(data[end + 2:], dtype=dt)
    nc, ncomp = int(info["NCOLS"]), int(info.get("NCOMP", "3"))
    nr = int(info.get("NROWS", arr.size // (nc * ncomp)))
    assert nr * nc * ncomp == arr.size, (path, nr, nc, ncomp, arr.size)
    return arr.reshape(nr, nc, ncomp).astype(np.float64)


def timed(cmd, cwd, stdin=None, stdout_path=None):
    l0 = annual.load_avg()
    _, dt, _ = annual.run(cmd, cwd, stdin=stdin, stdout_path=stdout_path)
    return dict(cmd=[Path(str(cmd[0])).name, *map(str, cmd[1:])], wall_s=dt, load_before=l0, load_after=annual.load_avg())


def scene_variant(src: Path, panes, dst: Path, extra=None):
    """The scene's text with `glazing = [..]` of `panes` panes and an absolute weather path
    (and `[annual]` overrides), written to dst."""
    text = src.read_text()
    text = re.sub(r"glazing = \[[^\]]*\]", "glazing = [" + ", ".join(["0.88"] * panes) + "]", text)
    scene = tomllib.loads(src.read_text())
    epw = (src.resolve().parent / scene["annual"]["weather"]).resolve()
    text = re.sub(r'weather = "[^"]*"', f'weather = "{epw}"', text)
    text = text.replace('name = "daylit_office_annual"', f'name = "daylit_office_annual_{panes}pane"')
    head, tail = text.split("[annual]\n", 1)  # overrides go to the [annual] table (the scene's last)
    for k, v in (extra or {}).items():
        if re.search(rf"^{k} = ", tail, re.M):
            tail = re.sub(rf"^{k} = .*$", f"{k} = {v}", tail, flags=re.M)
        else:
            tail = f"{k} = {v}\n" + tail
    text = head + "[annual]\n" + tail
    dst.write_text(text)
    assert tomllib.loads(text)["materials"]["window"]["glazing"] == [0.88] * panes
    return dst


def glazing_factor(cos_i, tns):
    """luxtally's transmittance of the panes (per polarisation, their inter-reflections
    summed: daylight.stack_T) over what Radiance's `glass` polygons give a ray from a light
    source (its shadow ray through each pane in turn, unpolarised, no reflections between
    the panes: the product of the panes' transmittances; checked with rtrace -ab 0 through
    one and two panes). 1 for a single pane."""
    if cos_i <= 1e-9:
        return 1.0
    prod = 1.0
    for tn in tns:
        (ts, _), (tp, _) = daylight.pane_TR(cos_i, tn)
        prod *= (ts + tp) / 2
    return daylight.stack_T(cos_i, tns)[0] / prod


def check_glass(tools, tns, workdir, angles=(0, 20, 40, 55, 65, 70)):
    """Radiance's `glass` polygons (12 mm apart) against the pane formulas, by rtrace -ab 0:
    a view ray through them at a glow of radiance 1 (what backward rays see), and the
    illuminance from a distant 0.533 deg light of radiance 1000 at a point behind them, over
    the same without glass (what a light source's shadow ray gets). Per incidence angle:
    rtrace's two ratios, the product of the panes' unpolarised T, the unpolarised adding
    formula (the panes' inter-reflections summed) and luxtally's polarised stack."""
    import subprocess
    out = []
    for th in angles:
        t = math.radians(th)
        d = (0.0, -math.cos(t), math.sin(t))
        row = dict(angle=th)
        for kind in ("view", "source"):
            vals = []
            for npn in (0, len(tns)):
                txt = ["void glass g 0 0 3 " + " ".join([f"{tns[0]:.9f}"] * 3)] if npn else []
                for k in range(npn):
                    y = -0.012 * k
                    txt.append(f"g polygon p{k} 0 0 12 -50 {y} -50  50 {y} -50  50 {y} 50  -50 {y} 50")
                if kind == "view":
                    txt += ["void glow gl 0 0 4 1 1 1 0", "gl polygon big 0 0 12 -500 -100 500  500 -100 500  500 -100 -500  -500 -100 -500"]
                    ray, opts = f"0 1 0 {d[0]} {d[1]} {d[2]}\n", ["-ov"]
                else:
                    txt += ["void light sunl 0 0 3 1000 1000 1000", f"sunl source sun 0 0 4 {d[0]} {d[1]} {d[2]} 0.533"]
                    ray, opts = f"0 1 0 {d[0]} {d[1]} {d[2]}\n", ["-I+", "-dj", "0", "-dc", "1", "-dt", "0"]
                (workdir / "glass_check.rad").write_text("\n".join(txt) + "\n")
                annual.run([tools["oconv"], "glass_check.rad"], workdir, stdout_path=workdir / "glass_check.oct")
                r = subprocess.run([tools["rtrace"], "-h", "-ab", "0", "-lw", "1e-9", "-lr", "-10", *opts, "glass_check.oct"],
                                   input=ray.encode(), capture_output=True, cwd=workdir)
                vals.append(float(r.stdout.split()[0]))
            row[kind] = vals[1] / vals[0]
        c = math.cos(t)
        per = [daylight.pane_TR(c, tn) for tn in tns]
        prod = 1.0
        for (ts, _), (tp, _) in per:
            prod *= (ts + tp) / 2
        pol, unpol = daylight.stack_T(c, tns)
        row.update(product=prod, adding_unpolarised=unpol, luxtally_polarised=pol)
        out.append(row)
    return out


def rows_sigma(a, b, nu, nv):
    m, s, noise = annual.rows_sigma(list(a), list(b), nu, nv)
    return np.array(m), np.array(s), noise


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", type=Path, default=REPO / "scenes" / "daylit_office_annual.toml")
    ap.add_argument("--workdir", type=Path, default=REPO / "target" / "radiance-annual" / "panes")
    ap.add_argument("--venv", type=Path, default=REPO / "target" / "radiance-compare" / "venv")
    ap.add_argument("--luxtally", type=Path, default=Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "release" / "luxtally")
    ap.add_argument("--stages", default="lux,rad,report")
    ap.add_argument("--panes", default="2,1")
    ap.add_argument("--photons", default="80000000")
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--ad", type=int, default=8192)
    ap.add_argument("--ladder", default="6:1e-5,10:1e-6", help="AB:LW settings run once on the two-pane scene")
    ap.add_argument("--deep", default="16:1e-7", help="AB:LW run twice (-u+) on every scene: Radiance's σ")
    ap.add_argument("--ad-direct", type=int, default=65536)
    ap.add_argument("--sub", type=int, default=4, help="K x K points per cell for the direct sun")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--md", type=Path, default=None, help="write the report's Markdown here (default: stdout)")
    a = ap.parse_args()
    work = a.workdir.resolve()
    work.mkdir(parents=True, exist_ok=True)
    stages = set(a.stages.split(","))
    panes = [int(x) for x in a.panes.split(",")]
    seeds = [int(x) for x in a.seeds.split(",")]
    scene0 = tomllib.loads(a.scene.read_text())
    ann = scene0["annual"]
    epw = (a.scene.resolve().parent / ann["weather"]).resolve()
    occ = [float(x) for x in ann.get("occupied_hours", [8.0, 18.0])]
    mf = int(ann.get("mf", 2))
    rho = f"{float(ann.get('ground_reflectance', 0.2)):g}"
    rec = [r for r in scene0["receivers"] if r["name"] == "df_grid"][0]
    pts, normal, (nu, nv) = daylight.cell_points(rec)
    n = len(pts)
    centre = tuple(sum(p[k] for p in pts) / n for k in range(3))
    stamps = annual.epw_stamps(epw)
    occupied = [k for k, s in enumerate(stamps) if occ[0] <= s[2] - 0.5 < occ[1]]
    n_occ = len(occupied)
    runs_file = work / "runs.json"
    runs = json.loads(runs_file.read_text()) if runs_file.exists() else {}

    def save_runs():
        runs_file.write_text(json.dumps(runs, indent=1))

    scenes = {p: scene_variant(a.scene, p, work / f"daylit_office_annual_{p}pane.toml") for p in panes}

    # --- luxtally -------------------------------------------------------------------------
    if "lux" in stages:
        for p in panes:
            for s in seeds:
                out = work / f"lux_{p}pane_seed{s}"
                if (out / "annual.json").exists():
                    continue
                log(f"luxtally annual, {p} pane(s), seed {s}, {a.photons} photons")
                r = annual.run_luxtally(a.luxtally, scenes[p], out,
                                        ["--photons", a.photons, "--sda-halfwidth", "0.5", "--seed", str(s)], 2)
                r["cmd"] = [Path(r["cmd"][0]).name, *r["cmd"][1:]]
                runs[f"lux {p} seed {s}"] = dict(cmd=r["cmd"], wall_s=r["wall_s"], load_before=r["load_before"],
                                                 load_after=r["load_after"], elapsed_s=r["summary"].get("elapsed_s"),
                                                 photons=r["summary"].get("photons"), stderr_tail=r["stderr_tail"])
                save_runs()
                log(f"  {r['wall_s']:.1f} s wall (load before {r['load_before']})")

    # --- Radiance ---------------------------------------------------------------------------
    binpath, raypath, version = compare.setup_radiance(a.venv)
    os.environ["RAYPATH"] = "." + os.pathsep + raypath
    tools = annual.tools_in(binpath)
    os.environ["PATH"] = str(Path(tools["rcontrib"]).parent) + os.pathsep + os.environ.get("PATH", "")
    sensors = "".join(f"{x:.4f} {y:.4f} {z:.4f} 0 0 1\n" for x, y, z in pts).encode()
    ladder = [(int(x.split(":")[0]), x.split(":")[1]) for x in a.ladder.split(",") if x]
    deep_ab, deep_lw = int(a.deep.split(":")[0]), a.deep.split(":")[1]

    def dc_name(ab, lw, tag):
        return f"dc_ab{ab}_lw{lw}_{tag}.mtx"

    if "rad" in stages:
        g = rho
        for name, cmd in (("sky.mtx", [tools["gendaymtx"], "-m", str(mf), "-g", g, g, g, "-O0", "-of", str(epw)]),
                          ("sky_only.mtx", [tools["gendaymtx"], "-m", str(mf), "-s", "-g", g, g, g, "-O0", "-of", str(epw)]),
                          ("sun_m2.mtx", [tools["gendaymtx"], "-m", str(mf), "-d", "-O0", "-of", str(epw)])):
            if not (work / name).exists():
                runs[f"gendaymtx {name}"] = timed(cmd, work, stdout_path=work / name)
        (work / "sky.rad").write_text(annual.SKY_RAD.format(mf=mf))
        for p in panes:
            wd = work / f"rad_{p}pane"
            wd.mkdir(exist_ok=True)
            scene = tomllib.loads(scenes[p].read_text())
            text, glass = daylight.radiance_scene(scene, centre, 0.012)
            (wd / "office.rad").write_text(text)
            runs[f"glass {p}"] = glass
            black = re.sub(r"(void plastic \S+\n0\n0\n5) \S+ \S+ \S+ 0 0\n", r"\1 0 0 0 0 0\n", text)
            assert black.count("5 0 0 0 0 0") == text.count("void plastic")
            (wd / "office_black.rad").write_text(black)
            (wd / "sky.rad").write_text(annual.SKY_RAD.format(mf=mf))
            todo = [(ab, lw, "a") for ab, lw in ladder] if p == 2 else []
            todo += [(deep_ab, deep_lw, "a"), (deep_ab, deep_lw, "b")]
            for ab, lw, tag in todo:
                f = wd / dc_name(ab, lw, tag)
                if f.exists():
                    continue
                cmd = [tools["rfluxmtx"], "-I+", "-ab", str(ab), "-ad", str(a.ad), "-lw", lw, "-aa", "0", "-lr", "0",
                       "-u+", "-n", "2", "-faf", "-", "sky.rad", "office.rad"]
                log(f"{p} pane(s): rfluxmtx -ab {ab} -lw {lw} ({tag})")
                runs[f"rad {p} {f.name}"] = timed(cmd, wd, stdin=sensors, stdout_path=f)
                save_runs()
                log(f"  {runs[f'rad {p} {f.name}']['wall_s']:.1f} s")
            for tag in ("a", "b"):
                f = wd / f"dcd_{tag}.mtx"
                if f.exists():
                    continue
                cmd = [tools["rfluxmtx"], "-I+", "-ab", "1", "-ad", str(a.ad_direct), "-lw", "1e-5", "-aa", "0", "-lr",
                       "0", "-u+", "-n", "2", "-faf", "-", "sky.rad", "office_black.rad"]
                runs[f"rad {p} {f.name}"] = timed(cmd, wd, stdin=sensors, stdout_path=f)
                save_runs()
            # luxtally's suns (its hours CSV, the same in every run), one per occupied record
            f_cds = wd / f"cds_sum_{a.sub}x{a.sub}.npy"
            if not f_cds.exists():
                hours = annual.read_csv(work / f"lux_{p}pane_seed{seeds[0]}" / "annual_df_grid_hours.csv")
                occ_set = set(occupied)
                with open(wd / "suns_lux.rad", "w") as fr, open(wd / "suns_lux.mod", "w") as fm:
                    for k, h in enumerate(hours):
                        if k not in occ_set or h["sun_altitude_deg"] == "" or float(h["direct_normal_lx"]) <= 0:
                            continue
                        al, az = math.radians(float(h["sun_altitude_deg"])), math.radians(float(h["sun_azimuth_deg"]))
                        v = (math.cos(al) * math.sin(az), math.cos(al) * math.cos(az), math.sin(al))
                        L = float(h["direct_normal_lx"]) / (179.0 * SUN_SA)
                        fr.write(f"\nvoid light lsolar{k}\n0\n0\n3 {L:.6e} {L:.6e} {L:.6e}\n\nlsolar{k} source lsun{k}\n"
                                 f"0\n0\n4 {v[0]:.7f} {v[1]:.7f} {v[2]:.7f} 0.5330\n")
                        fm.write(f"lsolar{k}\n")
                annual.run([tools["oconv"], "office.rad", "suns_lux.rad"], wd, stdout_path=wd / "suns_lux.oct")
                K = a.sub
                du, dv = 3.0 / nu, 5.0 / nv
                recs = [int(x[6:]) for x in (wd / "suns_lux.mod").read_text().split()]
                acc = np.zeros((n, len(recs)))
                t = 0.0
                l0 = annual.load_avg()
                for q in range(K):
                    for pp in range(K):
                        fu, fv = (pp + 0.5) / K - 0.5, (q + 0.5) / K - 0.5
                        txt = "".join(f"{x + fu * du:.5f} {y + fv * dv:.5f} {z:.4f} 0 0 1\n" for x, y, z in pts).encode()
                        cmd = [tools["rcontrib"], "-V+", "-I+", "-ab", "0", "-dj", "0", "-dt", "0", "-dc", "1", "-dr", "0",
                               "-n", "2", "-faf", "-M", "suns_lux.mod", "suns_lux.oct"]
                        _, dt, _ = annual.run(cmd, wd, stdin=txt, stdout_path=wd / "cds_tmp.mtx")
                        t += dt
                        acc += read_mtx(wd / "cds_tmp.mtx") @ W
                        (wd / "cds_tmp.mtx").unlink()
                runs[f"rad {p} rcontrib C_ds {K}x{K}"] = dict(cmd=[Path(cmd[0]).name, *cmd[1:]], wall_s=t, load_before=l0)
                np.save(wd / f"cds_hourly_{K}x{K}.npy", (acc / (K * K)).astype(np.float32))  # [cell, sun]
                np.save(wd / "cds_records.npy", np.array(recs))
                np.save(f_cds, acc.sum(axis=1) / (K * K))
                save_runs()
                log(f"{p} pane(s): rcontrib C_ds on {K}x{K} points per cell: {t:.1f} s")
        save_runs()

    if "glass" in stages:
        rows = check_glass(tools, [daylight.tn_from_Tn(0.88)] * 2, work)
        runs["glass check (2 panes)"] = rows
        save_runs()
        print("| incidence | rtrace view ray (glow) | rtrace light source (shadow ray) | Π pane T | adding, unpolarised | luxtally, polarised |")
        print("|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['angle']}° | {r['view']:.6f} | {r['source']:.6f} | {r['product']:.6f} | {r['adding_unpolarised']:.6f} | "
                  f"{r['luxtally_polarised']:.6f} |")

    if "report" not in stages:
        return
    # --- report -------------------------------------------------------------------------
    sky = read_mtx(work / "sky.mtx")[:, occupied, :].sum(axis=1)  # [patch, comp]
    sun2 = read_mtx(work / "sun_m2.mtx")[:, occupied, :].sum(axis=1)
    skyo = read_mtx(work / "sky_only.mtx")[:, occupied, :].sum(axis=1)

    def mean_of(dc_file, wd, dcd_tag):
        dc = read_mtx(wd / dc_file)
        dcd = read_mtx(wd / f"dcd_{dcd_tag}.mtx")
        cds = np.load(wd / f"cds_sum_{a.sub}x{a.sub}.npy")
        full = np.einsum("ijc,jc->ic", dc, sky) @ W
        dpatch = np.einsum("ijc,jc->ic", dcd, sun2) @ W
        return (full - dpatch + cds) / n_occ, full / n_occ

    res = dict(radiance=version, photons=a.photons, seeds=seeds, ad=a.ad, sub=a.sub, occupied_records=n_occ,
               runs=runs, scenes={})
    lux, rad = {}, {}
    for p in panes:
        wd = work / f"rad_{p}pane"
        cells = [annual.read_csv(work / f"lux_{p}pane_seed{s}" / "annual_df_grid.csv") for s in seeds]
        lpts = [(float(c["x"]), float(c["y"]), float(c["z"])) for c in cells[0]]
        assert max(max(abs(u - v) for u, v in zip(q, r)) for q, r in zip(pts, lpts)) < 1e-3
        m = [np.array([float(c["mean_lx"]) for c in cc]) for cc in cells]
        sg = [np.array([float(c["mean_sigma_lx"]) for c in cc]) for cc in cells]
        lm, ls, lnoise = rows_sigma(m[0], m[1], nu, nv)
        own = np.sqrt(sg[0] ** 2 + sg[1] ** 2) / 2  # σ of the two-seed mean from mean_sigma_lx
        zseed = (m[0] - m[1]) / np.sqrt(sg[0] ** 2 + sg[1] ** 2)
        lux[p] = dict(mean=lm, sigma_pooled=ls, sigma_own=own, seeds=m)
        dl = {}
        for ab, lw in ([(x, y) for x, y in ladder] if p == 2 else []):
            dl[f"-ab {ab} -lw {lw}"], _ = mean_of(dc_name(ab, lw, "a"), wd, "a")
        ma, fa = mean_of(dc_name(deep_ab, deep_lw, "a"), wd, "a")
        mb, fb = mean_of(dc_name(deep_ab, deep_lw, "b"), wd, "b")
        rm, rs, rnoise = rows_sigma(ma, mb, nu, nv)
        dl[f"-ab {deep_ab} -lw {deep_lw} (a+b)"] = rm
        rad[p] = dict(mean=rm, sigma=rs, ladder=dl)
        cmp = {}
        for label, lsig in (("σ_lux pooled from the two seeds", ls), ("σ_lux = luxtally's mean_sigma_lx (÷√2)", own)):
            c = annual.compare_cells(list(lm), list(lsig), list(rm), list(rs))
            cmp[label] = c
        # The direct sun through luxtally's glazing model (exact per hour at the sun's incidence
        # on the window: glazing_factor), everything else as Radiance traced it.
        fh = wd / f"cds_hourly_{a.sub}x{a.sub}.npy"
        pol_term = None
        if fh.exists():
            ch = np.load(fh).astype(np.float64)
            hrs = annual.read_csv(work / f"lux_{p}pane_seed{seeds[0]}" / "annual_df_grid_hours.csv")
            tns = [daylight.tn_from_Tn(float(t)) for t in tomllib.loads(scenes[p].read_text())["materials"]["window"]["glazing"]]
            fac = []
            for k in np.load(wd / "cds_records.npy"):
                al, az = math.radians(float(hrs[k]["sun_altitude_deg"])), math.radians(float(hrs[k]["sun_azimuth_deg"]))
                cos_i = -math.cos(al) * math.cos(az)  # -(direction . y): the window faces -y
                fac.append(glazing_factor(cos_i, tns))
            fac = np.array(fac)
            rm_pol = rm + ch @ (fac - 1) / n_occ
            rad[p]["mean_pol"] = rm_pol
            direct_share = float((ch.sum(axis=1) / n_occ).mean() / rm.mean())
            pol_term = dict(grid=float(rm_pol.mean() / rm.mean()), direct_sun_share_of_mean=direct_share,
                            direct_sun_factor=float((ch @ fac).sum() / ch.sum()))
            for label, lsig in (("σ_lux pooled from the two seeds", ls), ("σ_lux = luxtally's mean_sigma_lx (÷√2)", own)):
                cmp[f"{label}; Radiance's direct sun × luxtally's glazing / Radiance's"] = annual.compare_cells(
                    list(lm), list(lsig), list(rm_pol), list(rs))
        # Radiance's diffuse part (everything but C_ds, which is already a 4 x 4 cell average) at the
        # cell centres moved to cell averages by daylight.centre_to_average (its curvature term)
        cds_mean = np.load(wd / f"cds_sum_{a.sub}x{a.sub}.npy") / n_occ
        c2a = np.array(daylight.centre_to_average(list(rm - cds_mean), nu, nv))
        variants = {"Radiance's diffuse part at cell averages": rm + c2a}
        if "mean_pol" in rad[p]:
            variants["both"] = rad[p]["mean_pol"] + c2a
        for vk, vm in variants.items():
            cmp[f"σ_lux pooled from the two seeds; {vk}"] = annual.compare_cells(list(lm), list(ls), list(vm), list(rs))
        res["scenes"][p] = dict(
            centre_to_average_grid=float((rm + c2a).mean() / rm.mean()),
            direct_sun_polarisation=pol_term,
            lux_grid_mean=float(lm.mean()), lux_seed_means=[float(x.mean()) for x in m],
            lux_observed_noise_per_run=lnoise,
            lux_stated_noise_per_run=float(np.sqrt((sg[0] ** 2 + sg[1] ** 2).mean() / 2) / np.sqrt((lm ** 2).mean())),
            lux_seed_z_rms=float(np.sqrt((zseed ** 2).mean())), lux_seed_within_2sigma=float((abs(zseed) <= 2).mean()),
            rad_grid_mean=float(rm.mean()), rad_runs=[float(ma.mean()), float(mb.mean())], rad_noise_per_run=rnoise,
            ladder={k: float(v.mean()) for k, v in dl.items()}, compare=cmp,
            glass=runs.get(f"glass {p}"))
        log(f"{p} pane(s): luxtally {lm.mean():.1f} lx, Radiance {rm.mean():.1f} lx, ratio {lm.mean() / rm.mean():.4f}")
    # the two scenes' ratios
    bands = []
    for b in range(5):
        idx = np.array([j * nu + i for j in range(b * 6, b * 6 + 6) for i in range(nu)])
        row = dict(rows=f"{b * 6}-{b * 6 + 5}")
        for p in panes:
            row[f"lux {p}"] = float(lux[p]["mean"][idx].mean())
            for k, v in rad[p]["ladder"].items():
                row[f"rad {p} {k}"] = float(v[idx].mean())
            row[f"ratio {p}"] = row[f"lux {p}"] / float(rad[p]["mean"][idx].mean())
            if "mean_pol" in rad[p] and p > 1:
                row[f"ratio {p}, rad direct sun × glazing f."] = row[f"lux {p}"] / float(rad[p]["mean_pol"][idx].mean())
        if len(panes) == 2:
            row["ratio 1 / ratio 2"] = row["ratio 1"] / row["ratio 2"]
        bands.append(row)
    res["bands"] = bands
    if 1 in lux and 2 in lux:
        r1 = lux[1]["mean"] / rad[1]["mean"]
        r2 = lux[2]["mean"] / rad[2]["mean"]
        rel = lambda p: np.sqrt((lux[p]["sigma_pooled"] / lux[p]["mean"]) ** 2 + (rad[p]["sigma"] / rad[p]["mean"]) ** 2)  # noqa: E731
        dr = r1 / r2
        sd = dr * np.sqrt(rel(1) ** 2 + rel(2) ** 2)
        gm = (lux[1]["mean"].mean() / rad[1]["mean"].mean()) / (lux[2]["mean"].mean() / rad[2]["mean"].mean())
        res["double_ratio"] = dict(grid=float(gm), per_sensor_mean=float(dr.mean()),
                                   per_sensor_rms_sigma=float(np.sqrt((sd ** 2).mean())),
                                   z_rms_vs_grid=float(np.sqrt((((dr - gm) / sd) ** 2).mean())))
        # the polarisation term of the two-pane scene, as annual.py estimates it (light let in)
        s_all, s_sky = sky[1:] @ W, skyo[1:] @ W
        pol = annual.light_in_polarisation(tomllib.loads(scenes[2].read_text()), mf, list(s_sky), list(s_all - s_sky),
                                           float(sky[0] @ W))
        pol1 = annual.light_in_polarisation(tomllib.loads(scenes[1].read_text()), mf, list(s_sky), list(s_all - s_sky),
                                            float(sky[0] @ W))
        res["polarisation_estimate"] = {2: pol, 1: pol1}
        lux_ratio = lux[1]["mean"].mean() / lux[2]["mean"].mean()
        rad_ratio = rad[1]["mean"].mean() / rad[2]["mean"].mean()
        res["one_over_two_panes"] = dict(luxtally=float(lux_ratio), radiance=float(rad_ratio))
    md = markdown(res, panes)
    if a.md:
        a.md.write_text(md)
    print(md)
    out = a.json or work / "panes_results.json"
    out.write_text(json.dumps(res, indent=1, default=lambda x: x.tolist() if hasattr(x, "tolist") else str(x)))


def markdown(r, panes):
    o = []
    o.append("| scene | luxtally (2 seeds) | Radiance 5-phase (a+b) | ratio of the means | luxtally noise per run, observed / stated | "
             "Radiance noise per run | luxtally seed z RMS (own σ) |")
    o.append("|---|---|---|---|---|---|---|")
    for p in panes:
        s = r["scenes"][p]
        o.append(f"| {p} pane(s) | {s['lux_grid_mean']:.1f} | {s['rad_grid_mean']:.1f} | "
                 f"{s['lux_grid_mean'] / s['rad_grid_mean']:.4f} | {s['lux_observed_noise_per_run']:.2%} / "
                 f"{s['lux_stated_noise_per_run']:.2%} | {s['rad_noise_per_run']:.2%} | {s['lux_seed_z_rms']:.2f} "
                 f"({s['lux_seed_within_2sigma']:.1%} within 2σ) |")
    o.append("")
    o.append("| scene, σ_lux | mean ratio | ratio of the means | RMS rel. diff. | RMS z | within 2σ | RMS z scaled | within 2σ scaled |")
    o.append("|---|---|---|---|---|---|---|---|")
    for p in panes:
        for k, c in r["scenes"][p]["compare"].items():
            o.append(f"| {p} pane(s), {k} | {c['mean_ratio']:.4f} | {c['ratio_of_means']:.4f} | {c['rms_rel_diff']:.2%} | "
                     f"{c['z_rms']:.2f} | {c['within_2sigma']:.1%} | {c['z_rms_scaled']:.2f} | {c['within_2sigma_scaled']:.1%} |")
    o.append("")
    keys = [k for k in r["bands"][0] if k != "rows"]
    o.append("| rows | " + " | ".join(keys) + " |")
    o.append("|---|" + "---|" * len(keys))
    for b in r["bands"]:
        o.append(f"| {b['rows']} | " + " | ".join(f"{b[k]:.4f}" if "ratio" in k else f"{b[k]:.1f}" for k in keys) + " |")
    o.append("")
    for p in panes:
        o.append(f"Radiance ladder, {p} pane(s): " + ", ".join(f"{k}: {v:.1f} lx" for k, v in r["scenes"][p]["ladder"].items()))
        if r["scenes"][p].get("direct_sun_polarisation"):
            d = r["scenes"][p]["direct_sun_polarisation"]
            o.append(f"  direct sun (4 × 4 per cell) share of Radiance's mean {d['direct_sun_share_of_mean']:.1%}; luxtally's/Radiance's glazing "
                     f"factor {d['direct_sun_factor']:.4f}; Radiance's mean with it × {d['grid']:.4f}")
    if "double_ratio" in r:
        d = r["double_ratio"]
        o.append("")
        o.append(f"(lux/rad, 1 pane) / (lux/rad, 2 panes): grid {d['grid']:.4f}, per sensor mean {d['per_sensor_mean']:.4f} "
                 f"(RMS σ {d['per_sensor_rms_sigma']:.4f}, z RMS about the grid value {d['z_rms_vs_grid']:.2f}); "
                 f"1 pane / 2 panes: luxtally {r['one_over_two_panes']['luxtally']:.4f}, Radiance "
                 f"{r['one_over_two_panes']['radiance']:.4f}; polarisation estimate (light let in, polarised / unpolarised): "
                 f"2 panes {r['polarisation_estimate'][2]['all']['ratio']:.4f}, 1 pane {r['polarisation_estimate'][1]['all']['ratio']:.4f}")
    o.append("")
    o.append("| run | wall s | load (1 min) before |")
    o.append("|---|---|---|")
    for k, v in r["runs"].items():
        if isinstance(v, dict) and "wall_s" in v:
            lb = v.get("load_before")
            o.append(f"| {k}: `{' '.join(map(str, v['cmd']))}` | {v['wall_s']:.1f} | {lb[0] if lb else '–'} |")
    return "\n".join(o) + "\n"


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The sun as a true 0.533-degree disc on the Radiance side (5-phase style), and ASE /
sDA with the 2 % blinds rule, against `luxtally annual`.

Run after annual.py and annual_sun_trace.py (reuses their work directory: office.rad,
sky.rad, sky.mtx, dc_a.mtx, dc_b.mtx, dc_deep.mtx, suns.rad / suns.mod, luxtally's outputs).

Per sensor and occupied record, as the 5-phase method:

    E = DC (sky + ground + sun in MF 2 patches)            [annual.py's 2-phase, -ab 6]
      - DC_d (sun in MF 2 patches)                         [direct only: -ab 1, black scene]
      + C_ds (the hour's sun as a 0.533 deg `light`)       [direct only: rcontrib -ab 0]

DC_d: `rfluxmtx -I+ -ab 1 -ad AD_D ... sky.rad office_black.rad` (every plastic's
reflectance 0, the glass kept; twice, -u+, for the noise), times `gendaymtx -m 2 -d`'s sun.
C_ds: `rcontrib -V+ -I+ -ab 0 -dj 0 -dt 0 -dc 1 -M suns.mod` on `oconv office.rad suns.rad`:
one source per record, deterministic (no ambient). Two sun files: gendaymtx's own (-D,
its positions and radiance) and one written from luxtally's hours CSV (its sun position
and direct normal illuminance per record, the same 0.533 deg light), which takes the
position and efficacy differences (annual_sun_trace.py) out.

The direct part alone is what luxtally's ASE and blinds use (src/annual/metrics.rs:
the sun's direct part), so the metrics follow docs/daylight.md's conventions: ASE hours
= occupied records with direct sun > 1000 lx (no blinds), ASE1000,250 = share of cells
with more than 250; an hour closes the blinds when more than 2 % of the cells get direct
sun > 1000 lx, closed blinds scale all of the hour's light by 0.05; DA300 with blinds
per cell; sDA300/50 % = share of cells with DA >= 50 %. Standard library; see
benches/radiance/README.md.
"""

import argparse
import json
import math
import os
import re
import sys
import time
from array import array
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import annual  # noqa: E402
import compare  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
SUN_R = math.radians(0.533 / 2)
SUN_SA = math.pi * SUN_R * SUN_R
W = [compare.LM_PER_W * x for x in compare.PHOTOMETRIC]
log = compare.log


def read_any(path):
    """Header + float data; NROWS may be missing (rcontrib): inferred."""
    data = Path(path).read_bytes()
    end = data.find(b"\n\n")
    info = {}
    for line in data[:end].decode(errors="replace").split("\n"):
        if "=" in line:
            k, v = line.split("=", 1)
            info[k.strip()] = v.strip()
    arr = array({"float": "f", "double": "d"}[info["FORMAT"]])
    arr.frombytes(data[end + 2:])
    ncomp = int(info.get("NCOMP", "3"))
    nc = int(info["NCOLS"])
    nr = int(info.get("NROWS", len(arr) // (nc * ncomp)))
    assert nr * nc * ncomp == len(arr), (path, nr, nc, ncomp, len(arr))
    return arr, nr, nc


def lux_cols(arr, nr, nc, cols):
    """Per row, 179 (0.265 R + 0.670 G + 0.065 B) at the columns `cols` (array 'f')."""
    out = []
    for i in range(nr):
        base = i * nc * 3
        out.append(array("f", (W[0] * arr[base + 3 * k] + W[1] * arr[base + 3 * k + 1] + W[2] * arr[base + 3 * k + 2]
                               for k in cols)))
    return out


def metrics(total, direct, n_cells, n_occ, shade=0.05, share=0.02, ase_lx=1000.0, ase_hours=250, da_lx=300.0):
    """total, direct: per cell, per occupied record (array). Blinds, DA300 with blinds, sDA,
    ASE, mean, as docs/daylight.md."""
    nk = len(total[0])
    closed = []
    for k in range(nk):
        c = sum(1 for i in range(n_cells) if direct[i][k] > ase_lx)
        closed.append(c > share * n_cells)
    da_b, da, ase_h, means = [], [], [], []
    for i in range(n_cells):
        t, d = total[i], direct[i]
        da_b.append(sum(1 for k in range(nk) if (t[k] * shade if closed[k] else t[k]) >= da_lx) / n_occ)
        da.append(sum(1 for k in range(nk) if t[k] >= da_lx) / n_occ)
        ase_h.append(sum(1 for k in range(nk) if d[k] > ase_lx))
        means.append(sum(t) / n_occ)
    return dict(blinds_closed_fraction=sum(closed) / n_occ, sda_blinds=sum(1 for x in da_b if x >= 0.5) / n_cells,
                sda_no_blinds=sum(1 for x in da if x >= 0.5) / n_cells,
                ase=sum(1 for h in ase_h if h > ase_hours) / n_cells, da300_blinds=da_b, da300=da, ase_hours=ase_h,
                mean=means, closed=closed)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--workdir", type=Path, default=REPO / "target" / "radiance-annual")
    ap.add_argument("--scene", type=Path, default=REPO / "scenes" / "daylit_office_annual.toml")
    ap.add_argument("--venv", type=Path, default=REPO / "target" / "radiance-compare" / "venv")
    ap.add_argument("--ad-direct", type=int, default=65536, help="-ad of the direct-only patch coefficients")
    ap.add_argument("--lux", default="lux", help="luxtally sun_mf 6 output (in WORKDIR)")
    ap.add_argument("--lux0", default="lux_sun_mf_0", help="luxtally sun_mf 0 output (in WORKDIR)")
    ap.add_argument("--lux-seeds", default="lux_eq_0,lux_eq_1",
                    help="two luxtally runs of the scene with different seeds (in WORKDIR; annual_equal_accuracy.py's "
                         "80 M photon runs): their mean, with a σ from their difference pooled by rows as Radiance's")
    ap.add_argument("--sub", type=int, default=4, help="K: K x K points per cell for the cell-averaged direct sun")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    work = a.workdir.resolve()
    t_all = time.perf_counter()
    import tomllib
    scene = tomllib.loads(a.scene.read_text())
    ann = scene["annual"]
    epw = (a.scene.resolve().parent / ann["weather"]).resolve()
    occ = [float(x) for x in ann.get("occupied_hours", [8.0, 18.0])]
    shade = float(ann.get("shade_transmittance", 0.05))
    binpath, raypath, version = compare.setup_radiance(a.venv)
    os.environ["RAYPATH"] = "." + os.pathsep + raypath
    tools = annual.tools_in(binpath)
    os.environ["PATH"] = str(Path(tools["rcontrib"]).parent) + os.pathsep + os.environ.get("PATH", "")
    res_main = json.loads((work / "annual_results.json").read_text())
    cells = annual.read_csv(work / a.lux / "annual_df_grid.csv")
    pts = [(float(c["x"]), float(c["y"]), float(c["z"])) for c in cells]
    n = len(pts)
    nu, nv = 20, 30
    sensors = "".join(f"{x:.4f} {y:.4f} {z:.4f} 0 0 1\n" for x, y, z in pts).encode()
    stamps = annual.epw_stamps(epw)
    occupied = [k for k, s in enumerate(stamps) if occ[0] <= s[2] - 0.5 < occ[1]]
    n_occ = len(occupied)
    hours = annual.read_csv(work / a.lux / "annual_df_grid_hours.csv")
    timing = {}

    # --- the black scene and the direct-only patch coefficients -----------------------
    text = (work / "office.rad").read_text()
    black = re.sub(r"(void plastic \S+\n0\n0\n5) \S+ \S+ \S+ 0 0\n", r"\1 0 0 0 0 0\n", text)
    assert black.count("5 0 0 0 0 0") == text.count("void plastic"), "not every plastic blackened"
    (work / "office_black.rad").write_text(black)
    g = "0"
    sun_cmd = [tools["gendaymtx"], "-m", str(res_main["mf"]), "-d", "-O0", "-of", str(epw)]
    annual.run(sun_cmd, work, stdout_path=work / "sun_m2.mtx")
    dcd_flags = ["-I+", "-ab", "1", "-ad", str(a.ad_direct), "-lw", "1e-5", "-aa", "0", "-lr", "0", "-u+", "-n", "2",
                 "-faf"]
    dcd_runs = []
    for tag in ("a", "b"):
        f = work / f"dcd_{tag}.mtx"
        cmd = [tools["rfluxmtx"], *dcd_flags, "-", "sky.rad", "office_black.rad"]
        l0 = annual.load_avg()
        _, dt, _ = annual.run(cmd, work, stdin=sensors, stdout_path=f)
        dcd_runs.append(dict(tag=tag, cmd=cmd, wall_s=dt, load_before=l0))
        log(f"rfluxmtx direct-only {tag}: {dt:.1f} s")

    # --- the suns as 0.533 deg light sources -------------------------------------------
    def sun_id(k):
        mo, da, hr = stamps[k][:3]
        jd = sum([31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31][:mo - 1]) + da
        return 1440 * (jd - 1) + int((hr - 0.5) * 60 + 0.5)

    lux_suns = []
    for k, h in enumerate(hours):
        if h["sun_altitude_deg"] == "" or float(h["direct_normal_lx"]) <= 0:
            continue
        al, az = math.radians(float(h["sun_altitude_deg"])), math.radians(float(h["sun_azimuth_deg"]))
        v = (math.cos(al) * math.sin(az), math.cos(al) * math.cos(az), math.sin(al))
        L = float(h["direct_normal_lx"]) / (179.0 * SUN_SA)
        lux_suns.append((k, v, L))
    with open(work / "suns_lux.rad", "w") as f, open(work / "suns_lux.mod", "w") as fm:
        for k, v, L in lux_suns:
            f.write(f"\nvoid light lsolar{k}\n0\n0\n3 {L:.6e} {L:.6e} {L:.6e}\n\nlsolar{k} source lsun{k}\n0\n0\n"
                    f"4 {v[0]:.7f} {v[1]:.7f} {v[2]:.7f} 0.5330\n")
            fm.write(f"lsolar{k}\n")
    rc_flags = ["-V+", "-I+", "-ab", "0", "-dj", "0", "-dt", "0", "-dc", "1", "-dr", "0", "-n", "2", "-faf"]
    direct, direct_avg = {}, {}
    # Sub-points of each cell (K x K) for the cell-averaged direct sun (luxtally's cells
    # are areas: ASE and the blinds count a cell's mean direct sun, not its centre's).
    du, dv = (3.0 / nu, 0.0, 0.0), (0.0, 5.0 / nv, 0.0)  # the receiver's u / 20, v / 30 (this scene)
    K = a.sub
    offsets = [((p + 0.5) / K - 0.5, (q + 0.5) / K - 0.5) for q in range(K) for p in range(K)]
    for tag, sunrad, sunmod in (("gendaymtx suns", "suns.rad", "suns.mod"), ("luxtally suns", "suns_lux.rad", "suns_lux.mod")):
        oct_ = work / f"{Path(sunrad).stem}.oct"
        annual.run([tools["oconv"], "office.rad", sunrad], work, stdout_path=oct_)
        cmd = [tools["rcontrib"], *rc_flags, "-M", sunmod, oct_.name]
        mods = (work / sunmod).read_text().split()
        col_of = {}
        for j, m in enumerate(mods):
            col_of[int(m[6:]) if m.startswith("lsolar") else int(m[5:])] = j
        cols = []
        for k in occupied:
            key = k if tag == "luxtally suns" else sun_id(k)
            j = col_of.get(key)
            cols.append(j if j is not None else -1)

        def trace(sens_text, label):
            l0 = annual.load_avg()
            _, dt, _ = annual.run(cmd, work, stdin=sens_text, stdout_path=work / "Cds_tmp.mtx")
            arr, nr, nc = read_any(work / "Cds_tmp.mtx")
            assert nr == n and nc == len(mods), (nr, nc, len(mods))
            rows = []
            for i in range(n):
                base = i * nc * 3
                rows.append(array("f", ((W[0] * arr[base + 3 * j] + W[1] * arr[base + 3 * j + 1]
                                         + W[2] * arr[base + 3 * j + 2]) if j >= 0 else 0.0 for j in cols)))
            (work / "Cds_tmp.mtx").unlink()
            return rows, dict(cmd=cmd, wall_s=dt, load_before=l0, points=label)

        direct[tag], timing[f"rcontrib {tag}"] = trace(sensors, "cell centres")
        log(f"rcontrib direct sun ({tag}): {timing[f'rcontrib {tag}']['wall_s']:.1f} s")
        if K > 1:
            acc = [array("f", [0.0] * n_occ) for _ in range(n)]
            t_sub = 0.0
            for (fu, fv) in offsets:
                txt = "".join(f"{x + fu * du[0]:.4f} {y + fv * dv[1]:.4f} {z:.4f} 0 0 1\n" for x, y, z in pts).encode()
                rows, info = trace(txt, "sub")
                t_sub += info["wall_s"]
                for i in range(n):
                    acc[i] = array("f", (x + y for x, y in zip(acc[i], rows[i])))
            direct_avg[tag] = [array("f", (x / len(offsets) for x in row)) for row in acc]
            timing[f"rcontrib {tag}, {K}x{K} points per cell"] = dict(cmd=cmd, wall_s=t_sub)
            log(f"rcontrib direct sun ({tag}) on {K}x{K} points per cell: {t_sub:.1f} s")

    # --- hourly totals: dctimestep ------------------------------------------------------
    def hourly(dc, sky):
        out = work / "E_tmp.mtx"
        cmd = [tools["dctimestep"], "-of", dc, sky]
        _, dt, _ = annual.run(cmd, work, stdout_path=out)
        arr, nr, nc = read_any(out)
        assert nr == n and nc == len(stamps)
        rows = lux_cols(arr, nr, nc, occupied)
        out.unlink()
        log(f"dctimestep {dc} {sky}: {dt:.1f} s")
        return rows

    full = {t: hourly(f"dc_{t}.mtx", "sky.mtx") for t in ("a", "b", "deep") if (work / f"dc_{t}.mtx").exists()}
    dpatch = {t: hourly(f"dcd_{t}.mtx", "sun_m2.mtx") for t in ("a", "b")}

    def combine(f, d, s):
        return [array("f", (x - y + z for x, y, z in zip(f[i], d[i], s[i]))) for i in range(n)]

    variants = {}
    for sun in ("gendaymtx suns", "luxtally suns"):
        for t in ("a", "b"):
            variants[f"5-phase {t}, {sun}"] = (combine(full[t], dpatch[t], direct[sun]), direct[sun])
        if "deep" in full:
            variants[f"5-phase deep, {sun}"] = (combine(full["deep"], dpatch["a"], direct[sun]), direct[sun])
    for sun, rows_avg in direct_avg.items():
        for t in ("a", "b"):
            variants[f"5-phase {t}, {sun}, direct sun averaged over {a.sub}x{a.sub} points per cell"] = (
                combine(full[t], dpatch[t], rows_avg), rows_avg)
    for t in ("a", "b"):
        variants[f"2-phase {t} (direct sun: MF 2 patches' direct part)"] = (full[t], dpatch[t])
    met = {}
    for k, (tot, dr) in variants.items():
        m = metrics(tot, dr, n, n_occ, shade=shade)
        met[k] = m
        log(f"{k}: mean {sum(m['mean']) / n:.1f} lx, sDA(blinds) {m['sda_blinds']:.3f}, ASE {m['ase']:.3f}, "
            f"blinds {m['blinds_closed_fraction']:.4f}")

    # Sensitivity of ASE and the blinds to the direct sun's level (e.g. the +1.7 % annual.py
    # estimates for polarised over unpolarised pane stacking of the sun): direct x s.
    sens = {}
    for s in (1.0168, 1.03, 1.05):
        tot, dr = variants["5-phase a, luxtally suns"]
        m = metrics(tot, [array("f", (x * s for x in row)) for row in dr], n, n_occ, shade=shade)
        sens[f"{s:g}"] = dict(ase=m["ase"], blinds_closed_fraction=m["blinds_closed_fraction"], sda_blinds=m["sda_blinds"])
        log(f"direct x {s:g}: ASE {m['ase']:.3f}, blinds {m['blinds_closed_fraction']:.4f}")

    # --- against luxtally ---------------------------------------------------------------
    lux = {}
    for name, d in (("sun_mf 6", a.lux), ("sun_mf 0", a.lux0)):
        cc = annual.read_csv(work / d / "annual_df_grid.csv")
        js = json.loads((work / d / "annual.json").read_text())["receivers"][0]
        lux[name] = dict(mean=[float(c["mean_lx"]) for c in cc], sigma=[float(c["mean_sigma_lx"]) for c in cc],
                         da_b=[float(c["da300_blinds"]) for c in cc], da_b_lo=[float(c["da300_blinds_low"]) for c in cc],
                         da_b_hi=[float(c["da300_blinds_high"]) for c in cc],
                         ase_h=[float(c["ase_hours"]) for c in cc], ase_lo=[float(c["ase_hours_low"]) for c in cc],
                         ase_hi=[float(c["ase_hours_high"]) for c in cc],
                         sda=js["sda_300_50"], ase=js["ase_1000_250"], blinds=js["blinds_closed_hours_fraction"])
    agreement = {}
    for sun in ("gendaymtx suns", "luxtally suns"):
        ma, mb = met[f"5-phase a, {sun}"]["mean"], met[f"5-phase b, {sun}"]["mean"]
        rm, rs, noise = annual.rows_sigma(ma, mb, nu, nv)
        for ln, L in lux.items():
            c = annual.compare_cells(L["mean"], L["sigma"], rm, rs)
            c["radiance_noise_per_run"] = noise
            c["radiance_mean"] = sum(rm) / n
            c["lux_mean"] = sum(L["mean"]) / n
            agreement[f"{ln} vs 5-phase (a+b), {sun}"] = c
            if f"5-phase deep, {sun}" in met:
                md = met[f"5-phase deep, {sun}"]["mean"]
                c2 = annual.compare_cells(L["mean"], L["sigma"], md, [s * math.sqrt(2) for s in rs])
                c2["radiance_mean"] = sum(md) / n
                c2["lux_mean"] = sum(L["mean"]) / n
                agreement[f"{ln} vs 5-phase deep (-ab 10), {sun}"] = c2
    # luxtally's two seeds: a measured σ (its mean_sigma_lx carries the rule-of-three bounds of
    # the sources that reached no cell, which make it far wider than its observed spread)
    seeds = [work / d for d in a.lux_seeds.split(",") if d]
    if len(seeds) == 2 and all((d / "annual_df_grid.csv").exists() for d in seeds):
        s0, s1 = ([float(c["mean_lx"]) for c in annual.read_csv(d / "annual_df_grid.csv")] for d in seeds)
        lm, ls, lnoise = annual.rows_sigma(s0, s1, nu, nv)
        for sun in ("gendaymtx suns", "luxtally suns"):
            ma, mb = met[f"5-phase a, {sun}"]["mean"], met[f"5-phase b, {sun}"]["mean"]
            rm, rs, _ = annual.rows_sigma(ma, mb, nu, nv)
            for tag, (rmean, rsig) in (("5-phase (a+b)", (rm, rs)),
                                       ("5-phase deep (-ab 10)", (met[f"5-phase deep, {sun}"]["mean"],
                                                                  [x * math.sqrt(2) for x in rs]))):
                c = annual.compare_cells(lm, ls, rmean, rsig)
                c["radiance_mean"] = sum(rmean) / n
                c["lux_mean"] = sum(lm) / n
                c["lux_observed_noise_per_run"] = lnoise
                agreement[f"luxtally sun_mf 6, 2 seeds ({seeds[0].name}, {seeds[1].name}; σ from them) vs {tag}, {sun}"] = c
    # the 2-phase as run, for reference
    rm2, rs2, _ = annual.rows_sigma(met["2-phase a (direct sun: MF 2 patches' direct part)"]["mean"],
                                    met["2-phase b (direct sun: MF 2 patches' direct part)"]["mean"], nu, nv)
    for ln, L in lux.items():
        c = annual.compare_cells(L["mean"], L["sigma"], rm2, rs2)
        c["radiance_mean"] = sum(rm2) / n
        c["lux_mean"] = sum(L["mean"]) / n
        agreement[f"{ln} vs 2-phase (a+b) as run"] = c
    bands = []
    for b in range(5):
        idx = [j * nu + i for j in range(b * 6, b * 6 + 6) for i in range(nu)]
        mm = lambda v: sum(v[i] for i in idx) / len(idx)  # noqa: E731
        row = dict(rows=f"{b * 6}-{b * 6 + 5}", lux6=mm(lux["sun_mf 6"]["mean"]), lux0=mm(lux["sun_mf 0"]["mean"]),
                   two_phase=mm(rm2))
        for sun in ("gendaymtx suns", "luxtally suns"):
            ma, mb = met[f"5-phase a, {sun}"]["mean"], met[f"5-phase b, {sun}"]["mean"]
            row[f"five_{sun}"] = (mm(ma) + mm(mb)) / 2
            if f"5-phase deep, {sun}" in met:
                row[f"five_deep_{sun}"] = mm(met[f"5-phase deep, {sun}"]["mean"])
        bands.append(row)
    # per-cell DA with blinds and ASE hours: Radiance inside luxtally's per-cell intervals?
    percell = {}
    for k in [q for q in met if q.startswith("5-phase a,")]:
        m = met[k]
        for ln, L in lux.items():
            inside_da = sum(1 for i in range(n) if L["da_b_lo"][i] - 1e-9 <= m["da300_blinds"][i] <= L["da_b_hi"][i] + 1e-9)
            inside_ase = sum(1 for i in range(n) if L["ase_lo"][i] - 1e-9 <= m["ase_hours"][i] <= L["ase_hi"][i] + 1e-9)
            percell[f"{ln} vs {k}"] = dict(
                da300_blinds_inside=inside_da / n, ase_hours_inside=inside_ase / n,
                da300_blinds_mean_diff=sum(L["da_b"][i] - m["da300_blinds"][i] for i in range(n)) / n,
                ase_hours_mean_diff=sum(L["ase_h"][i] - m["ase_hours"][i] for i in range(n)) / n)
    out = dict(radiance=version, sun_matrix_cmd=sun_cmd, dcd_runs=dcd_runs, rcontrib=timing,
               n_lux_suns=len(lux_suns), occupied_records=n_occ, shade_transmittance=shade,
               metrics={k: {q: v for q, v in m.items() if q not in ("closed",)} for k, m in met.items()},
               luxtally={k: dict(sda=v["sda"], ase=v["ase"], blinds=v["blinds"], mean=sum(v["mean"]) / n)
                         for k, v in lux.items()},
               agreement=agreement, bands=bands, direct_scale_sensitivity=sens, percell=percell, wall_s=time.perf_counter() - t_all)
    print(markdown(out))
    if a.json:
        a.json.write_text(json.dumps(out, indent=1))


def markdown(r):
    o = []
    o.append("| agreement, per sensor annual mean | luxtally | Radiance | ratio of the means | mean ratio | "
             "RMS rel. diff. | RMS z | within 2σ | RMS z scaled | within 2σ scaled |")
    o.append("|---|---|---|---|---|---|---|---|---|---|")
    for k, c in r["agreement"].items():
        o.append(f"| {k} | {c['lux_mean']:.1f} | {c['radiance_mean']:.1f} | {c['ratio_of_means']:.4f} | "
                 f"{c['mean_ratio']:.4f} | {c['rms_rel_diff']:.2%} | {c['z_rms']:.2f} | {c['within_2sigma']:.1%} | "
                 f"{c['z_rms_scaled']:.2f} | {c['within_2sigma_scaled']:.1%} |")
    o.append("")
    keys = [k for k in r["bands"][0] if k != "rows"]
    o.append("| rows | " + " | ".join(keys) + " |")
    o.append("|---|" + "---|" * len(keys))
    for b in r["bands"]:
        o.append(f"| {b['rows']} | " + " | ".join(f"{b[k]:.1f}" for k in keys) + " |")
    o.append("")
    o.append("| metric | " + " | ".join(f"luxtally {k} (95 %)" for k in r["luxtally"]) + " |")
    o.append("|---|" + "---|" * len(r["luxtally"]))
    for lab, k in (("sDA300/50 % with blinds", "sda"), ("ASE1000,250", "ase"), ("blinds closed, share of occupied hours", "blinds")):
        o.append(f"| {lab} | " + " | ".join(f"{v[k]['value']:.1%} ({v[k]['low']:.1%}–{v[k]['high']:.1%})"
                                             for v in r["luxtally"].values()) + " |")
    o.append("")
    o.append("| Radiance | mean lx | sDA300/50 % with blinds | sDA no blinds | ASE1000,250 | blinds closed |")
    o.append("|---|---|---|---|---|---|")
    for k, m in r["metrics"].items():
        o.append(f"| {k} | {sum(m['mean']) / len(m['mean']):.1f} | {m['sda_blinds']:.1%} | {m['sda_no_blinds']:.1%} | "
                 f"{m['ase']:.1%} | {m['blinds_closed_fraction']:.2%} |")
    o.append("")
    o.append("| 5-phase a, luxtally suns, direct sun × s (ASE and blinds only) | ASE1000,250 | blinds closed | "
             "sDA with blinds |")
    o.append("|---|---|---|---|")
    for k, v in r["direct_scale_sensitivity"].items():
        o.append(f"| × {k} | {v['ase']:.1%} | {v['blinds_closed_fraction']:.2%} | {v['sda_blinds']:.1%} |")
    o.append("")
    o.append("| per cell | DA300 with blinds inside luxtally's interval | mean DA diff (lux − rad) | ASE hours inside | "
             "mean ASE-hours diff |")
    o.append("|---|---|---|---|---|")
    for k, p in r["percell"].items():
        o.append(f"| {k} | {p['da300_blinds_inside']:.1%} | {p['da300_blinds_mean_diff']:+.4f} | "
                 f"{p['ase_hours_inside']:.1%} | {p['ase_hours_mean_diff']:+.1f} |")
    return "\n".join(o) + "\n"


if __name__ == "__main__":
    main()

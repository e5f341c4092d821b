#!/usr/bin/env python3
"""ASE1000,250 and the 2 % blinds rule from Radiance's direct sun averaged over K × K
points per cell (K = 1, 4, 8, 16 ...), against `luxtally annual` with each hour its own
sun (sun_mf = 0), whose cells are areas (its direct sun is a stratified estimate of the
cell's mean, src/trace/direct.rs).

Works in target/radiance-annual/ase/. Stages (`--stages lux,rad,report`):

lux    `luxtally annual SCENE0 --out lux_sun_mf_0 --threads 2 --sda-halfwidth 0.5` (one
       round) on a copy of scenes/daylit_office_annual.toml written here with
       `sun_mf = 0` and the EPW's absolute path (nothing under scenes/ is touched).
rad    luxtally's suns (its hours CSV: position, direct normal illuminance; a 0.533°
       `light` per occupied record with the sun up) in `oconv office.rad suns_lux.rad`,
       `rcontrib -V+ -I+ -ab 0 -dj 0 -dt 0 -dc 1 -dr 0 -n 2 -faf -M suns_lux.mod` (no
       ambient: deterministic) at the K × K midpoints of every cell (several offsets per
       rcontrib call), averaged: per cell and occupied record the direct sun, lx, saved
       as direct_K.npy.
report per K: ASE hours per cell (direct sun > 1000 lx), ASE1000,250 (share of cells
       with more than 250), the blinds (closed when more than 2 % of the cells get direct
       sun > 1000 lx); the same with Radiance's direct sun multiplied per hour by
       luxtally's polarised over Radiance's unpolarised two-pane transmittance at that
       sun's incidence on the window (daylight.stack_T: the only modelling difference in
       the direct sun left once the suns are the same); against luxtally's figures and
       intervals (annual.json) and per cell its ASE hours and their interval; the cells
       whose ASE verdict differs, with their hours on both sides. Optionally (--trace)
       per hour of those cells: luxtally's total (its hourly binary) against Radiance's
       direct sun plus the 5-phase diffuse of annual_panes.py's `-ab 16` run.

Needs numpy: re-runs itself with the pyradiance venv's Python. See README.md.
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
except ImportError:
    venv = REPO / "target" / "radiance-compare" / "venv"
    compare.setup_radiance(venv)
    os.execv(str(venv / "bin" / "python"), [str(venv / "bin" / "python"), __file__, *sys.argv[1:]])

import tomllib  # noqa: E402

import annual  # noqa: E402
import annual_panes  # noqa: E402
import daylight  # noqa: E402

log = compare.log
W = np.array([compare.LM_PER_W * x for x in compare.PHOTOMETRIC], dtype=np.float32)
SUN_SA = math.pi * math.radians(0.533 / 2) ** 2


def hourly_lx(dc, sky):
    """dc [cell, patch, 3] times sky [patch, record, 3]: lx [cell, record] (a matmul per channel)."""
    return sum(float(W[c]) * (dc[:, :, c] @ sky[:, :, c]) for c in range(3))


def metrics(direct, n_cells, share=0.02, ase_lx=1000.0, ase_hours=250):
    over = direct > ase_lx  # [cell, record]
    hours = over.sum(axis=1)
    closed = over.sum(axis=0) > share * n_cells
    return dict(ase=float((hours > ase_hours).mean()), ase_hours=hours, closed=closed,
                blinds=float(closed.sum()))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", type=Path, default=REPO / "scenes" / "daylit_office_annual.toml")
    ap.add_argument("--workdir", type=Path, default=REPO / "target" / "radiance-annual" / "ase")
    ap.add_argument("--venv", type=Path, default=REPO / "target" / "radiance-compare" / "venv")
    ap.add_argument("--luxtally", type=Path, default=Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "release" / "luxtally")
    ap.add_argument("--stages", default="lux,rad,report")
    ap.add_argument("--panes", type=int, default=2, help="panes of the scene (2: as bundled)")
    ap.add_argument("--ks", default="1,4,8,16")
    ap.add_argument("--batch", type=int, default=4, help="offsets per rcontrib call")
    ap.add_argument("--dj", default="0", help="rcontrib -dj: 0 shadows at the sun's centre; 1 at a random point of its "
                    "disc per ray (one ray per point: the K x K points then also sample the disc)")
    ap.add_argument("--trace", type=Path,
                    help="annual_panes.py's work directory (sky.mtx, sky_only.mtx, rad_2pane/dcd_a.mtx): trace the direct "
                         "light hour by hour against a luxtally run of the scene with every surface black")
    ap.add_argument("--penumbra", type=int, default=0,
                    help="with --trace: C > 0 re-traces the records that differ most with rcontrib -dj 1 -c C (the sun's disc)")
    ap.add_argument("--sda", type=Path,
                    help="annual_panes.py's work directory: sDA300/50 % with the blinds from its 5-phase (-ab 16 runs a, "
                         "b; the direct sun = this script's finest K, -dj 1 if present, x the glazing factor)")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    work = a.workdir.resolve()
    work.mkdir(parents=True, exist_ok=True)
    stages = set(a.stages.split(","))
    ks = [int(x) for x in a.ks.split(",")]
    scene_file = annual_panes.scene_variant(a.scene, a.panes, work / f"scene_{a.panes}pane_sun_mf_0.toml", {"sun_mf": 0})
    scene = tomllib.loads(scene_file.read_text())
    ann = scene["annual"]
    epw = Path(ann["weather"])
    occ = [float(x) for x in ann.get("occupied_hours", [8.0, 18.0])]
    rec = [r for r in scene["receivers"] if r["name"] == "df_grid"][0]
    pts, _, (nu, nv) = daylight.cell_points(rec)
    n = len(pts)
    centre = tuple(sum(p[k] for p in pts) / n for k in range(3))
    stamps = annual.epw_stamps(epw)
    occupied = [k for k, s in enumerate(stamps) if occ[0] <= s[2] - 0.5 < occ[1]]
    n_occ = len(occupied)
    runs_file = work / "runs.json"
    runs = json.loads(runs_file.read_text()) if runs_file.exists() else {}
    lux_dir = work / f"lux_{a.panes}pane_sun_mf_0"
    dj_tag = "" if a.dj == "0" else f"_dj{a.dj}"

    if "lux" in stages and not (lux_dir / "annual.json").exists():
        log(f"luxtally annual {scene_file.name} (one round)")
        r = annual.run_luxtally(a.luxtally, scene_file, lux_dir, ["--sda-halfwidth", "0.5"], 2)
        runs["luxtally sun_mf 0"] = dict(cmd=[Path(r["cmd"][0]).name, *r["cmd"][1:]], wall_s=r["wall_s"],
                                         load_before=r["load_before"], load_after=r["load_after"],
                                         elapsed_s=r["summary"].get("elapsed_s"), photons=r["summary"].get("photons"))
        runs_file.write_text(json.dumps(runs, indent=1))
        log(f"  {r['wall_s']:.1f} s")

    black_dir = work / f"lux_{a.panes}pane_black_sun_mf_0"
    if a.trace and "lux" in stages and not (black_dir / "annual.json").exists():
        bfile = annual_panes.scene_variant(a.scene, a.panes, work / f"scene_{a.panes}pane_black_sun_mf_0.toml",
                                           {"sun_mf": 0})
        bfile.write_text(re.sub(r"^reflectance = .*$", "reflectance = 0.0", bfile.read_text(), flags=re.M))
        log(f"luxtally annual {bfile.name} (one round)")
        r = annual.run_luxtally(a.luxtally, bfile, black_dir, ["--sda-halfwidth", "0.5"], 2)
        runs["luxtally sun_mf 0, black"] = dict(cmd=[Path(r["cmd"][0]).name, *r["cmd"][1:]], wall_s=r["wall_s"],
                                                load_before=r["load_before"], load_after=r["load_after"],
                                                elapsed_s=r["summary"].get("elapsed_s"), photons=r["summary"].get("photons"))
        runs_file.write_text(json.dumps(runs, indent=1))
        log(f"  {r['wall_s']:.1f} s")

    hours = annual.read_csv(lux_dir / "annual_df_grid_hours.csv")
    occ_set = set(occupied)
    suns = []  # (record, direction, E_dn)
    for k, h in enumerate(hours):
        if k in occ_set and h["sun_altitude_deg"] != "" and float(h["direct_normal_lx"]) > 0:
            al, az = math.radians(float(h["sun_altitude_deg"])), math.radians(float(h["sun_azimuth_deg"]))
            suns.append((k, (math.cos(al) * math.sin(az), math.cos(al) * math.cos(az), math.sin(al)),
                         float(h["direct_normal_lx"])))
    col_of_rec = {k: j for j, k in enumerate(occupied)}

    if "rad" in stages:
        binpath, raypath, version = compare.setup_radiance(a.venv)
        os.environ["RAYPATH"] = "." + os.pathsep + raypath
        tools = annual.tools_in(binpath)
        text, _ = daylight.radiance_scene(scene, centre, 0.012)
        (work / "office.rad").write_text(text)
        with open(work / "suns_lux.rad", "w") as fr, open(work / "suns_lux.mod", "w") as fm:
            for k, v, edn in suns:
                L = edn / (179.0 * SUN_SA)
                fr.write(f"\nvoid light lsolar{k}\n0\n0\n3 {L:.6e} {L:.6e} {L:.6e}\n\nlsolar{k} source lsun{k}\n0\n0\n"
                         f"4 {v[0]:.7f} {v[1]:.7f} {v[2]:.7f} 0.5330\n")
                fm.write(f"lsolar{k}\n")
        annual.run([tools["oconv"], "office.rad", "suns_lux.rad"], work, stdout_path=work / "suns_lux.oct")
        cols = np.array([col_of_rec[k] for k, _, _ in suns])
        du, dv = 3.0 / nu, 5.0 / nv
        cmd = [tools["rcontrib"], "-V+", "-I+", "-ab", "0", "-dj", a.dj, "-dt", "0", "-dc", "1", "-dr", "0", "-n", "2",
               "-faf", "-M", "suns_lux.mod", "suns_lux.oct"]
        for K in ks:
            f = work / f"direct_{K}{dj_tag}.npy"
            if f.exists():
                continue
            offs = [((p + 0.5) / K - 0.5, (q + 0.5) / K - 0.5) for q in range(K) for p in range(K)]
            acc = np.zeros((n, n_occ), dtype=np.float64)
            t, l0 = 0.0, annual.load_avg()
            for b0 in range(0, len(offs), a.batch):
                batch = offs[b0:b0 + a.batch]
                txt = "".join(f"{x + fu * du:.5f} {y + fv * dv:.5f} {z:.4f} 0 0 1\n"
                              for fu, fv in batch for x, y, z in pts).encode()
                _, dt, _ = annual.run(cmd, work, stdin=txt, stdout_path=work / "cds_tmp.mtx")
                t += dt
                m = annual_panes.read_mtx(work / "cds_tmp.mtx").astype(np.float32)  # [pts, suns, 3]
                lx = (m @ W).reshape(len(batch), n, len(suns)).sum(axis=0)
                acc[:, cols] += lx
            (work / "cds_tmp.mtx").unlink()
            np.save(f, (acc / len(offs)).astype(np.float32))
            runs[f"rcontrib {K}x{K}{dj_tag}"] = dict(cmd=[Path(cmd[0]).name, *cmd[1:]], points=n * K * K, wall_s=t,
                                            load_before=l0, load_after=annual.load_avg())
            runs_file.write_text(json.dumps(runs, indent=1))
            log(f"rcontrib direct sun, {K}x{K} points per cell: {t:.1f} s (load before {l0})")

    if "report" not in stages:
        return
    js = json.loads((lux_dir / "annual.json").read_text())["receivers"][0]
    cells = annual.read_csv(lux_dir / "annual_df_grid.csv")
    lux_h = np.array([float(c["ase_hours"]) for c in cells])
    lux_lo = np.array([float(c["ase_hours_low"]) for c in cells])
    lux_hi = np.array([float(c["ase_hours_high"]) for c in cells])
    # per-hour factor: luxtally's glazing over Radiance's for a light source's ray, at the sun's incidence
    glz = [float(x) for x in scene["materials"]["window"]["glazing"]]
    tns = [daylight.tn_from_Tn(t) for t in glz]
    pol = np.ones(n_occ)
    for k, v, _ in suns:
        pol[col_of_rec[k]] = annual_panes.glazing_factor(-v[1], tns)  # the window faces -y (south)
    res = dict(luxtally=dict(ase=js["ase_1000_250"], blinds=js["blinds_closed_hours_fraction"],
                             sda=js["sda_300_50"], mean_ase_hours=float(lux_h.mean())),
               occupied_records=n_occ, suns=len(suns), runs=runs, radiance={})
    lux_ase_cells = lux_h > 250
    per_k = {}
    for K, djt in [(K, t) for K in ks for t in ("", "_dj1")]:
        f = work / f"direct_{K}{djt}.npy"
        if not f.exists():
            continue
        d = np.load(f)
        for tag, dd in (("as traced", d), ("× luxtally's / Radiance's glazing per hour", d * pol[None, :])):
            if djt:
                tag = f"-dj 1, {tag}"
            m = metrics(dd, n)
            ase_cells = m["ase_hours"] > 250
            inside = (m["ase_hours"] >= lux_lo - 1e-9) & (m["ase_hours"] <= lux_hi + 1e-9)
            diff = np.nonzero(ase_cells != lux_ase_cells)[0]
            res["radiance"][f"{K}x{K}, {tag}"] = dict(
                ase=m["ase"], blinds=m["blinds"] / n_occ, blinds_hours=m["blinds"],
                mean_ase_hours=float(m["ase_hours"].mean()),
                mean_ase_hours_diff_lux_minus_rad=float((lux_h - m["ase_hours"]).mean()),
                cells_inside_lux_interval=float(inside.mean()),
                cells_verdict_differs=[dict(cell=int(i), row=int(i // nu), col=int(i % nu), lux=float(lux_h[i]),
                                            lux_lo=float(lux_lo[i]), lux_hi=float(lux_hi[i]),
                                            rad=int(m["ase_hours"][i])) for i in diff])
            if not djt:
                per_k[(K, tag)] = m
        if djt:
            continue
        log(f"K={K}: ASE {res['radiance'][f'{K}x{K}, as traced']['ase']:.4f}, blinds "
            f"{res['radiance'][f'{K}x{K}, as traced']['blinds']:.4f}")
    # per cell: the ASE hours' convergence in K (largest K as the reference)
    kk = [K for K in ks if (K, "as traced") in per_k]
    if len(kk) > 1:
        ref = per_k[(kk[-1], "as traced")]["ase_hours"]
        res["convergence"] = {f"{K}x{K}": dict(rms_hours_vs_finest=float(np.sqrt(((per_k[(K, 'as traced')]['ase_hours'] - ref) ** 2).mean())),
                                               max_abs_hours_vs_finest=int(abs(per_k[(K, 'as traced')]['ase_hours'] - ref).max()))
                              for K in kk}
        # blinds: hours closed in one and not the other
        cl = per_k[(kk[-1], "as traced")]["closed"]
        res["blinds_hours_vs_finest"] = {f"{K}x{K}": [int((per_k[(K, 'as traced')]['closed'] & ~cl).sum()),
                                                      int((~per_k[(K, 'as traced')]['closed'] & cl).sum())] for K in kk}
    if a.trace and kk and (black_dir / "annual.json").exists():
        # luxtally's direct light hour by hour: its run with every surface black gives the sun's,
        # the sky patches' and the ground's (rho 0.2, a source) direct light only; the patches' and
        # the ground's part is taken out with Radiance's (DC_d x the sky without the sun, and
        # gendaymtx's ground row), leaving luxtally's direct sun.
        K = kk[-1]
        d = np.load(work / f"direct_{K}.npy") * pol[None, :]
        direct_label = f"{K}x{K} -dj 0"
        if (work / f"direct_{K}_dj1.npy").exists():  # the sun's disc sampled
            d = np.load(work / f"direct_{K}_dj1.npy") * pol[None, :]
            direct_label = f"{K}x{K} -dj 1"
        hb = (black_dir / "annual_df_grid_hourly.bin").read_bytes()
        body = 8 * n * 8760
        ncell, nrec = np.frombuffer(hb[len(hb) - body - 8:len(hb) - body], dtype="<u4")
        assert ncell == n and nrec == 8760, (ncell, nrec)
        e = np.frombuffer(hb[len(hb) - body:], dtype="<f4").reshape(8760, 2, n)
        e_occ, s_occ = e[occupied, 0, :].T.astype(np.float64), e[occupied, 1, :].T.astype(np.float64)
        skyo = annual_panes.read_mtx(a.trace / "sky_only.mtx")[:, occupied, :]
        skyo[0] = annual_panes.read_mtx(a.trace / "sky.mtx")[0, occupied, :]  # the ground row with the sun's light
        dcd = annual_panes.read_mtx(a.trace / f"rad_{a.panes}pane" / "dcd_a.mtx")
        sky_direct = hourly_lx(dcd, skyo)  # [cell, occ]
        lux_sun = e_occ - sky_direct
        over_l, over_r = lux_sun > 1000, d > 1000
        closed_l, closed_r = over_l.sum(axis=0) > 0.02 * n, over_r.sum(axis=0) > 0.02 * n
        lit = d > 0
        tr = dict(K=K, direct=direct_label, lux_ase_hours_mean=float(over_l.sum(axis=1).mean()), rad_ase_hours_mean=float(over_r.sum(axis=1).mean()),
                  lux_ase=float((over_l.sum(axis=1) > 250).mean()), rad_ase=float((over_r.sum(axis=1) > 250).mean()),
                  lux_blinds_hours=int(closed_l.sum()), rad_blinds_hours=int(closed_r.sum()),
                  blinds_only_lux=int((closed_l & ~closed_r).sum()), blinds_only_rad=int((~closed_l & closed_r).sum()),
                  cell_hours_only_lux=int((over_l & ~over_r).sum()), cell_hours_only_rad=int((~over_l & over_r).sum()),
                  direct_sum_ratio_lux_over_rad=float(lux_sun[lit].sum() / d[lit].sum()),
                  sky_direct_mean_lx=float(sky_direct.mean()))
        # relative difference of the direct sun where Radiance's is over 5000 lx (cells fully sunlit)
        full = d > 5000
        tr["fully_sunlit_ratio_lux_over_rad"] = float(lux_sun[full].sum() / d[full].sum())
        # the cell-hours that differ: how far from 1000 lx, how partly lit
        diff = np.nonzero(over_l != over_r)
        tr["differing_cell_hours"] = [dict(cell=int(i), row=int(i // nu), col=int(i % nu), record=int(occupied[j]),
                                           month=stamps[occupied[j]][0], day=stamps[occupied[j]][1],
                                           stamp=stamps[occupied[j]][2], lux_direct=float(lux_sun[i, j]),
                                           lux_sigma=float(s_occ[i, j]), rad_direct=float(d[i, j]))
                                      for i, j in zip(*diff)][:400]
        z = (lux_sun[diff] - d[diff]) / np.maximum(s_occ[diff], 1e-9)
        tr["differing_z"] = dict(mean=float(z.mean()) if z.size else None, rms=float(np.sqrt((z ** 2).mean())) if z.size else None)
        zall = (lux_sun[lit] - d[lit]) / np.maximum(s_occ[lit], 1e-9)
        tr["lit_cell_hours_z"] = dict(n=int(lit.sum()), mean=float(zall.mean()), rms=float(np.sqrt((zall ** 2).mean())))
        # the blinds hours that differ, with the cells over 1000 lx on each side
        tr["blinds_hours_differing"] = [dict(record=int(occupied[j]), month=stamps[occupied[j]][0], day=stamps[occupied[j]][1],
                                             stamp=stamps[occupied[j]][2], lux_cells=int(over_l[:, j].sum()),
                                             rad_cells=int(over_r[:, j].sum()))
                                        for j in np.nonzero(closed_l != closed_r)[0]]
        # The sun's disc: luxtally samples the 0.533 deg disc, rcontrib -dj 0 shadows at its centre.
        # For the blinds hours that differ and the records of the cell-hours that differ most, the
        # direct sun again with -dj 1 (points over the disc) and -c C samples per point, 8 x 8 per cell.
        if a.penumbra:
            recs = sorted({h["record"] for h in tr["blinds_hours_differing"]}
                          | {c["record"] for c in sorted(tr["differing_cell_hours"],
                                                          key=lambda c: -abs(c["lux_direct"] - c["rad_direct"]))[:40]})
            sel = [x for x in suns if x[0] in set(recs)]
            binpath, raypath, _ = compare.setup_radiance(a.venv)
            os.environ["RAYPATH"] = "." + os.pathsep + raypath
            tools = annual.tools_in(binpath)
            with open(work / "suns_sel.rad", "w") as fr, open(work / "suns_sel.mod", "w") as fm:
                for k, v, edn in sel:
                    L = edn / (179.0 * SUN_SA)
                    fr.write(f"\nvoid light lsolar{k}\n0\n0\n3 {L:.6e} {L:.6e} {L:.6e}\n\nlsolar{k} source lsun{k}\n0\n0\n"
                             f"4 {v[0]:.7f} {v[1]:.7f} {v[2]:.7f} 0.5330\n")
                    fm.write(f"lsolar{k}\n")
            annual.run([tools["oconv"], "office.rad", "suns_sel.rad"], work, stdout_path=work / "suns_sel.oct")
            Kp, C = 8, a.penumbra
            offs = [((p_ + 0.5) / Kp - 0.5, (q + 0.5) / Kp - 0.5) for q in range(Kp) for p_ in range(Kp)]
            txt = "".join(f"{x + fu * 3.0 / nu:.5f} {y + fv * 5.0 / nv:.5f} {z:.4f} 0 0 1\n"
                          for fu, fv in offs for x, y, z in pts).encode()
            out_p = {}
            for dj in ("0", "1"):
                cmd = [tools["rcontrib"], "-V+", "-I+", "-ab", "0", "-dj", dj, "-dt", "0", "-dc", "1", "-dr", "0", "-n", "2",
                       "-faf", "-c", str(C if dj == "1" else 1), "-M", "suns_sel.mod", "suns_sel.oct"]
                l0 = annual.load_avg()
                # -c C averages C input rays per record: each point given C times (-dj 1 jitters each over the disc)
                src = txt if dj == "0" else b"".join(line + b"\n" for line in txt.split(b"\n")[:-1] for _ in range(C))
                _, dt, _ = annual.run(cmd, work, stdin=src, stdout_path=work / "sel_tmp.mtx")
                m = annual_panes.read_mtx(work / "sel_tmp.mtx").astype(np.float32) @ W
                out_p[dj] = m.reshape(len(offs), n, len(sel)).mean(axis=0)  # [cell, sun] (rcontrib -c averages)
                runs[f"rcontrib penumbra -dj {dj}"] = dict(cmd=[Path(cmd[0]).name, *cmd[1:]], points=n * Kp * Kp,
                                                          suns=len(sel), wall_s=dt, load_before=l0)
            (work / "sel_tmp.mtx").unlink()
            rows = []
            for q, (k, _, _) in enumerate(sel):
                j = col_of_rec[k]
                fj = pol[j]
                r0, r1 = out_p["0"][:, q] * fj, out_p["1"][:, q] * fj
                rows.append(dict(record=int(k), month=stamps[k][0], day=stamps[k][1], stamp=stamps[k][2],
                                 altitude=float(hours[k]["sun_altitude_deg"]), azimuth=float(hours[k]["sun_azimuth_deg"]),
                                 lux_cells=int(over_l[:, j].sum()), rad_dj0_cells=int((r0 > 1000).sum()),
                                 rad_dj1_cells=int((r1 > 1000).sum()), lux_sum=float(lux_sun[:, j].sum()),
                                 rad_dj0_sum=float(r0.sum()), rad_dj1_sum=float(r1.sum()),
                                 cells_disagree_dj0=int(((r0 > 1000) != over_l[:, j]).sum()),
                                 cells_disagree_dj1=int(((r1 > 1000) != over_l[:, j]).sum())))
            tr["penumbra"] = dict(samples_per_point=C, points_per_cell=Kp * Kp, records=rows)
        res["trace"] = tr
        log(f"trace: {json.dumps({k: v for k, v in tr.items() if not isinstance(v, list)})}")
    if a.sda and kk:
        K = kk[-1]
        fd = work / f"direct_{K}_dj1.npy"
        d = np.load(fd if fd.exists() else work / f"direct_{K}.npy").astype(np.float64) * pol[None, :]
        sky = annual_panes.read_mtx(a.sda / "sky.mtx")[:, occupied, :]
        sun2 = annual_panes.read_mtx(a.sda / "sun_m2.mtx")[:, occupied, :]
        closed = (d > 1000).sum(axis=0) > 0.02 * n
        shade = float(ann.get("shade_transmittance", 0.05))
        out_s = dict(direct=fd.name if fd.exists() else f"direct_{K}.npy", blinds=float(closed.mean()), runs={})
        for tag in ("a", "b"):
            dc = sorted((a.sda / f"rad_{a.panes}pane").glob(f"dc_ab16_*_{tag}.mtx"))[0]
            dcm = annual_panes.read_mtx(dc)
            dcd = annual_panes.read_mtx(a.sda / f"rad_{a.panes}pane" / f"dcd_{tag}.mtx")
            e = hourly_lx(dcm, sky) - hourly_lx(dcd, sun2) + d  # [cell, occ]
            da_b = ((np.where(closed[None, :], e * shade, e)) >= 300).sum(axis=1) / n_occ
            da = (e >= 300).sum(axis=1) / n_occ
            out_s["runs"][tag] = dict(dc=dc.name, mean=float(e.mean()), sda_blinds=float((da_b >= 0.5).mean()),
                                      sda_no_blinds=float((da >= 0.5).mean()), da300_blinds=da_b.tolist())
            log(f"sDA with blinds, Radiance 5-phase {dc.name}: {(da_b >= 0.5).mean():.4f} (mean {e.mean():.1f} lx)")
        # per cell: inside luxtally's DA300-with-blinds interval?
        lda = np.array([float(c["da300_blinds"]) for c in cells])
        llo = np.array([float(c["da300_blinds_low"]) for c in cells])
        lhi = np.array([float(c["da300_blinds_high"]) for c in cells])
        for tag, r_ in out_s["runs"].items():
            dab = np.array(r_["da300_blinds"])
            r_["cells_inside_lux_da_interval"] = float(((dab >= llo - 1e-9) & (dab <= lhi + 1e-9)).mean())
            r_["mean_da_diff_lux_minus_rad"] = float((lda - dab).mean())
            del r_["da300_blinds"]
        out_s["luxtally"] = dict(sda=js["sda_300_50"], run=str(lux_dir.name))
        res["sda"] = out_s
        log(f"sDA: {json.dumps(out_s)}")
    out = a.json or work / "ase_results.json"
    out.write_text(json.dumps(res, indent=1))
    print(markdown(res))


def markdown(r):
    L = r["luxtally"]
    o = [f"luxtally sun_mf 0: ASE {L['ase']['value']:.2%} ({L['ase']['low']:.2%}–{L['ase']['high']:.2%}), blinds closed "
         f"{L['blinds']['value']:.2%} ({L['blinds']['low']:.2%}–{L['blinds']['high']:.2%}), mean ASE hours per cell "
         f"{L['mean_ase_hours']:.1f}", "",
         "| Radiance direct sun | ASE1000,250 | blinds closed | mean ASE hours | lux − rad ASE hours | cells inside lux's interval | "
         "cells whose verdict differs (row, col: lux [lo–hi] / rad) |", "|---|---|---|---|---|---|---|"]
    for k, v in r["radiance"].items():
        cd = "; ".join(f"{c['row']},{c['col']}: {c['lux']:.0f} [{c['lux_lo']:.0f}–{c['lux_hi']:.0f}] / {c['rad']}"
                       for c in v["cells_verdict_differs"][:12])
        more = len(v["cells_verdict_differs"])
        o.append(f"| {k} | {v['ase']:.2%} | {v['blinds']:.2%} ({v['blinds_hours']:.0f} h) | {v['mean_ase_hours']:.1f} | "
                 f"{v['mean_ase_hours_diff_lux_minus_rad']:+.1f} | {v['cells_inside_lux_interval']:.1%} | {more}: {cd} |")
    if "convergence" in r:
        o.append("")
        o.append("per cell ASE hours against the finest K: " + ", ".join(
            f"{k}: RMS {v['rms_hours_vs_finest']:.1f} h, max {v['max_abs_hours_vs_finest']} h" for k, v in r["convergence"].items()))
        o.append("blinds hours (closed only in K, only in the finest): " + ", ".join(
            f"{k}: {v[0]}/{v[1]}" for k, v in r["blinds_hours_vs_finest"].items()))
    o.append("")
    for k, v in r["runs"].items():
        o.append(f"- {k}: `{' '.join(map(str, v['cmd']))}` {v['wall_s']:.1f} s, load before {v['load_before']}")
    return "\n".join(o) + "\n"


if __name__ == "__main__":
    main()

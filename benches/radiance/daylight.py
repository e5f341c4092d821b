#!/usr/bin/env python3
"""Radiance (rtrace) against luxtally on the daylit office's daylight-factor grid.

Converts scenes/daylit_office.toml to Radiance (plastic polygons, the double glazing as
two `glass` polygons 12 mm apart, the CIE traditional overcast sky, type 16, by its own
.cal file), checks the sky's calibration (10000 lx on an open horizontal plane), then
traces the 240 DF cell centres with

    rtrace -h -I+ -ab 8 -aa 0 -ad N -as 0 -lr 0 -lw 1e-5 -u+ -n 2

doubling N from 256 (two independent runs each) until Radiance's per-point noise is
<= 2 % or its time budget is spent; runs luxtally (next_event) for a photon budget and
compares the mean, the row means and the cells. Plain Python 3.11 standard library;
reuses compare.py's pyradiance venv. See benches/radiance/README.md.
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
import tomllib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import compare  # noqa: E402  (setup_radiance, find_tools, poly, rtrace, rms)

REPO = Path(__file__).resolve().parents[2]
E_OUT = 10000.0  # overridden by the scene's horizontal_illuminance_lx
LM_PER_W = compare.LM_PER_W


def die(msg, code=1):
    print(f"daylight.py: {msg}", file=sys.stderr)
    sys.exit(code)


log = compare.log


def add(a, b):
    return tuple(p + q for p, q in zip(a, b))


def sub(a, b):
    return tuple(p - q for p, q in zip(a, b))


def scale(a, k):
    return tuple(p * k for p in a)


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(p * q for p, q in zip(a, b))


def tn_from_Tn(Tn):
    """Radiance's transmissivity tn from the normal transmittance Tn (n = 1.52)."""
    return (math.sqrt(0.8402528435 + 0.0072522239 * Tn * Tn) - 0.9166530661) / 0.0036261119 / Tn


def Tn_from_tn(tn, n=1.52):
    """Tn = (1-r)^2 tn / (1 - r^2 tn^2), r = ((n-1)/(n+1))^2: the round trip."""
    r = ((n - 1) / (n + 1)) ** 2
    return (1 - r) ** 2 * tn / (1 - r * r * tn * tn)


# --- the scene ------------------------------------------------------------------
def sky_of(scene):
    skies = [l for l in scene.get("lights", []) if l.get("type") == "sky"]
    if len(scene.get("lights", [])) != 1 or len(skies) != 1:
        die("the scene must have exactly one light, a sky")
    sky = skies[0]
    if sky.get("cie_type") != 16:
        die(f"only CIE type 16 is converted, not {sky.get('cie_type')}")
    if "horizontal_illuminance_lx" in sky:
        eh = float(sky["horizontal_illuminance_lx"])
        lz = eh * 9 / (7 * math.pi)
    else:
        lz = float(sky["zenith_luminance_cdm2"])
        eh = 7 * math.pi / 9 * lz
    rho_g = float(sky.get("ground_reflectance", 0.2))
    return eh, lz, rho_g


def df_receiver(scene):
    recs = [r for r in scene.get("receivers", []) if r.get("daylight_factor")]
    if len(recs) != 1:
        die("the scene must have exactly one daylight_factor receiver")
    return recs[0]


def cell_points(rec):
    c, u, v = (tuple(map(float, rec[k])) for k in ("corner", "u", "v"))
    nu, nv = rec["cells"]
    n = cross(u, v)
    nn = math.sqrt(dot(n, n))
    normal = scale(n, 1 / nn)
    pts = []
    for j in range(nv):
        for i in range(nu):
            pts.append(add(add(c, scale(u, (i + 0.5) / nu)), scale(v, (j + 0.5) / nv)))
    return pts, normal, (nu, nv)  # index j * nu + i


def radiance_scene(scene, interior_point, pane_gap):
    """The scene's objects as Radiance polygons. Glazing panes stack from the rect's
    plane towards interior_point (the outer pane in the plane, the next pane_gap in)."""
    out = ["# scenes/daylit_office.toml for Radiance (benches/radiance/daylight.py)\n"]
    mats = scene["materials"]
    kinds = {}
    glass_info = {}
    for name, m in mats.items():
        if "glazing" in m:
            if set(m) - {"glazing"}:
                die(f"material {name}: only a plain `glazing` list is converted")
            panes = [float(t) for t in m["glazing"]]
            tns = [tn_from_Tn(t) for t in panes]
            for k, tn in enumerate(tns):
                out.append(f"void glass {name}_pane{k}\n0\n0\n3 {tn:.6f} {tn:.6f} {tn:.6f}\n")
            kinds[name] = ("glass", len(panes))
            glass_info[name] = dict(Tn=panes, tn=tns, Tn_round_trip=[Tn_from_tn(t) for t in tns])
        else:
            extra = set(m) - {"reflectance"}
            if extra:
                die(f"material {name}: only `reflectance` is converted, not {sorted(extra)}")
            rho = float(m.get("reflectance", 0.0))
            out.append(f"void plastic {name}\n0\n0\n5 {rho:g} {rho:g} {rho:g} 0 0\n")
            kinds[name] = ("plastic", 1)
    for k, obj in enumerate(scene["objects"]):
        mat = obj["material"]
        if obj["shape"] == "rect":
            c, u, v = (tuple(map(float, obj[q])) for q in ("corner", "u", "v"))
            quad = [c, add(c, u), add(add(c, u), v), add(c, v)]
            if kinds[mat][0] == "glass":
                n = cross(u, v)
                n = scale(n, 1 / math.sqrt(dot(n, n)))
                if dot(sub(interior_point, c), n) < 0:
                    n = scale(n, -1)
                for p in range(kinds[mat][1]):
                    off = scale(n, p * pane_gap)
                    out.append(compare.poly(f"{mat}_pane{p}", f"o{k}_pane{p}", [add(q, off) for q in quad]))
            else:
                out.append(compare.poly(mat, f"o{k}", quad))
        elif obj["shape"] == "box":
            if kinds[mat][0] != "plastic":
                die("a glazed box is not converted")
            (x0, y0, z0), (x1, y1, z1) = tuple(map(float, obj["min"])), tuple(map(float, obj["max"]))
            faces = [
                [(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)],
                [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],
                [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)],
                [(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)],
                [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)],
                [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)],
            ]
            for f, quad in enumerate(faces):
                out.append(compare.poly(mat, f"o{k}_f{f}", quad))
        else:
            die(f"object {k}: shape {obj['shape']} is not converted")
    return "".join(out), glass_info


def sky_files(workdir, lz, rho_g, eh):
    """CIE type 16 exactly: L = Lz (1 + 2 sin g)/3 above the horizon, rho_g E_h / pi below;
    Radiance radiance = luminance / 179 (equal RGB)."""
    lz_r = lz / LM_PER_W
    lg_r = rho_g * eh / math.pi / LM_PER_W
    cal = (
        "{ CIE traditional overcast sky (type 16), benches/radiance/daylight.py }\n"
        f"Lz = {lz_r:.9g};\n"
        f"ground = {lg_r:.9g};\n"
        "skybright = if(Dz, Lz*(1+2*Dz)/3, ground);\n"
    )
    (workdir / "sky16.cal").write_text(cal)
    rad = (
        "void brightfunc skyfunc\n2 skybright sky16.cal\n0\n0\n"
        "skyfunc glow skyglow\n0\n0\n4 1 1 1 0\n"
        "skyglow source sky\n0\n0\n4 0 0 1 180\n"
        "skyglow source ground\n0\n0\n4 0 0 -1 180\n"
    )
    (workdir / "sky16.rad").write_text(rad)
    return lz_r, lg_r


def oconv(tools, files, octree, cwd):
    with open(octree, "wb") as f:
        r = subprocess.run([tools["oconv"], *map(str, files)], stdout=f, stderr=subprocess.PIPE, cwd=cwd)
    if r.returncode != 0:
        die(f"oconv failed: {r.stderr.decode()}")


def rtrace(tools, octree, text, args, cwd):
    old = os.getcwd()
    os.chdir(cwd)  # sky16.cal is found through RAYPATH, which starts with "."
    try:
        return compare.rtrace(tools, octree, text, args)
    finally:
        os.chdir(old)


def rtrace_version(tools):
    r = subprocess.run([tools["rtrace"], "-version"], capture_output=True, text=True)
    return (r.stdout or r.stderr).strip()


# --- statistics -----------------------------------------------------------------
def mean(xs):
    return sum(xs) / len(xs)


def rad_stats(va, vb, nu, nv):
    """Radiance's two runs: per-point noise RMS(a-b)/sqrt2 / RMS(value); the two-run mean
    per cell; the mean over cells with its sigma from the differences (independent
    points: -aa 0, no ambient cache); row means with sigma from each row's differences;
    per-cell sigma of the two-run mean from each row's relative noise (12 dof)."""
    m = [(x + y) / 2 for x, y in zip(va, vb)]
    d = [x - y for x, y in zip(va, vb)]
    noise = compare.rms(d) / math.sqrt(2) / compare.rms(m)
    n = len(m)
    mean_all = mean(m)
    sig_mean = math.sqrt(sum(x * x for x in d) / 4) / n
    rows, rows_sig, cell_sig = [], [], [0.0] * n
    for j in range(nv):
        idx = [j * nu + i for i in range(nu)]
        rows.append(mean([m[i] for i in idx]))
        rows_sig.append(math.sqrt(sum(d[i] ** 2 for i in idx) / 4) / nu)
        # relative sigma of a two-run mean in this row
        rel = math.sqrt(sum(d[i] ** 2 for i in idx) / 4 / sum(m[i] ** 2 for i in idx))
        for i in idx:
            cell_sig[i] = rel * m[i]
    return dict(values=m, noise=noise, mean=mean_all, mean_sigma=sig_mean, rows=rows,
                rows_sigma=rows_sig, cell_sigma=cell_sig)


def time_to(search, target, key="noise"):
    """Wall time (faster run) at exactly `target`, log-log between (or beyond) the last two."""
    if len(search) < 2:
        return None
    p1, p2 = search[-2], search[-1]
    t1, t2 = min(p1["times_s"]), min(p2["times_s"])
    if p1[key] <= p2[key]:
        return None
    slope = math.log(t2 / t1) / math.log(p1[key] / p2[key])
    return t2 * (p2[key] / target) ** slope, slope


# --- luxtally -------------------------------------------------------------------
def run_luxtally(bin_path, scene, photons, threads, outdir, seed=None):
    cmd = [str(bin_path), "run", str(scene), "--photons", str(photons), "--threads", str(threads),
           "--estimator", "next_event", "--quiet", "--out", str(outdir)]
    if seed is not None:
        cmd += ["--seed", str(seed)]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        die(f"luxtally failed ({' '.join(cmd)}):\n{r.stdout}\n{r.stderr}")
    s = json.loads((Path(outdir) / "summary.json").read_text())
    return s, wall, cmd


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", type=Path, default=REPO / "scenes" / "daylit_office.toml")
    ap.add_argument("--target", type=float, default=0.02, help="per-point noise (default 0.02)")
    ap.add_argument("--ab", type=int, default=8)
    ap.add_argument("--lw", default="1e-5")
    ap.add_argument("--ad-start", type=int, default=256)
    ap.add_argument("--ad-max", type=int, default=1 << 20)
    ap.add_argument("--rad-budget", type=float, default=480, help="s of Radiance tracing in all (default 480)")
    ap.add_argument("--pane-gap", type=float, default=0.012, help="m between the glass polygons")
    ap.add_argument("--procs", type=int, default=2, help="rtrace -n and luxtally --threads")
    ap.add_argument("--workdir", type=Path, default=REPO / "target" / "radiance-daylight")
    ap.add_argument("--venv", type=Path, default=REPO / "target" / "radiance-compare" / "venv",
                    help="pyradiance venv (compare.py's, created if missing)")
    ap.add_argument("--radiance-bin", type=Path, help="use this Radiance bin/ instead of pyradiance")
    ap.add_argument("--raypath", help="RAYPATH with --radiance-bin (its lib/)")
    ap.add_argument("--luxtally", type=Path, default=REPO / "target" / "release" / "luxtally",
                    help="luxtally binary (build it first: cargo build --release [--features obvhs])")
    ap.add_argument("--lux-seconds", type=float, default=100, help="photon-pass budget for luxtally (s)")
    ap.add_argument("--lux-photons", type=int, help="photons for luxtally (overrides --lux-seconds)")
    ap.add_argument("--lux-max-photons", type=int, default=400_000_000)
    ap.add_argument("--json", type=Path, help="also write all numbers here")
    a = ap.parse_args()

    work = a.workdir.resolve()
    work.mkdir(parents=True, exist_ok=True)
    scene = tomllib.loads(a.scene.read_text())
    eh, lz, rho_g = sky_of(scene)
    rec = df_receiver(scene)
    pts, normal, (nu, nv) = cell_points(rec)
    centre = mean([p[0] for p in pts]), mean([p[1] for p in pts]), mean([p[2] for p in pts])

    # Radiance
    if a.radiance_bin:
        binpath, raypath, rad_version = a.radiance_bin, a.raypath or os.environ.get("RAYPATH", "."), "local"
    else:
        binpath, raypath, rad_version = compare.setup_radiance(a.venv)
    os.environ["RAYPATH"] = raypath if "." in raypath.split(os.pathsep) else "." + os.pathsep + raypath
    tools = compare.find_tools(binpath)
    rt_version = rtrace_version(tools)
    log(f"Radiance: {tools['rtrace']} ({rad_version}; {rt_version})")

    lz_r, lg_r = sky_files(work, lz, rho_g, eh)
    text, glass_info = radiance_scene(scene, centre, a.pane_gap)
    (work / "daylit_office.rad").write_text(text)
    oconv(tools, [work / "sky16.rad"], work / "sky.oct", work)
    oconv(tools, [work / "sky16.rad", work / "daylit_office.rad"], work / "daylit_office.oct", work)
    for name, g in glass_info.items():
        log(f"glazing {name}: Tn {g['Tn']} -> tn {[round(t, 6) for t in g['tn']]} "
            f"(round trip Tn {[round(t, 6) for t in g['Tn_round_trip']]})")

    # Calibration: the sky alone, an open horizontal plane facing up (E_h) and down
    # (the ground: rho_g E_h). -ab 1 with no geometry: one bounce reaches the sky.
    cal_args = ["-ab", "1", "-aa", "0", "-ad", "16384", "-as", "0", "-lr", "0", "-lw", "1e-6"]
    (e_up,), _, _ = rtrace(tools, work / "sky.oct", "0 0 0 0 0 1\n", cal_args, work)
    (e_dn,), _, _ = rtrace(tools, work / "sky.oct", "0 0 0 0 0 -1\n", cal_args, work)
    calib = dict(up_lx=e_up, up_expected_lx=eh, down_lx=e_dn, down_expected_lx=rho_g * eh,
                 args=cal_args, Lz_cdm2=lz, ground_cdm2=rho_g * eh / math.pi,
                 Lz_radiance=lz_r, ground_radiance=lg_r)
    log(f"sky: Lz {lz:.2f} cd/m2 ({lz_r:.6g} W/sr/m2), ground {rho_g * eh / math.pi:.2f} cd/m2; "
        f"up {e_up:.1f} lx vs {eh:.1f} ({e_up / eh - 1:+.3%}), down {e_dn:.1f} lx vs "
        f"{rho_g * eh:.1f} ({e_dn / (rho_g * eh) - 1:+.3%})")
    if abs(e_up / eh - 1) > 0.01 or (rho_g > 0 and abs(e_dn / (rho_g * eh) - 1) > 0.01):
        die("the sky's calibration is off by more than 1 %")

    nx, ny, nz = normal
    points_text = "".join(f"{x:.6f} {y:.6f} {z:.6f} {nx:g} {ny:g} {nz:g}\n" for x, y, z in pts)
    search, final = [], None
    ad, spent = a.ad_start, 0.0
    while ad <= a.ad_max:
        args = ["-ab", str(a.ab), "-aa", "0", "-ad", str(ad), "-as", "0", "-lr", "0", "-lw", a.lw,
                "-u+", "-n", str(a.procs)]
        va, ta, cmd = rtrace(tools, work / "daylit_office.oct", points_text, args, work)
        vb, tb, _ = rtrace(tools, work / "daylit_office.oct", points_text, args, work)
        spent += ta + tb
        if len(va) != len(pts) or len(vb) != len(pts):
            die(f"rtrace returned {len(va)}/{len(vb)} values for {len(pts)} points")
        dfa = [100 * x / eh for x in va]
        dfb = [100 * x / eh for x in vb]
        st = rad_stats(dfa, dfb, nu, nv)
        row = dict(ad=ad, times_s=[ta, tb], noise=st["noise"], mean_df=st["mean"],
                   mean_df_sigma=st["mean_sigma"])
        search.append(row)
        final = dict(row, a=dfa, b=dfb, stats=st, cmd=cmd)
        log(f"rtrace -ad {ad:6d}: {ta:7.2f} s, {tb:7.2f} s; noise {st['noise']:.3%}; "
            f"mean DF {st['mean']:.4f} ± {st['mean_sigma']:.4f} % (spent {spent:.0f} s)")
        if st["noise"] <= a.target:
            break
        if spent + 2 * (ta + tb) > a.rad_budget:
            log(f"Radiance's budget ({a.rad_budget:.0f} s) would be exceeded at -ad {2 * ad}: stop")
            break
        ad *= 2
    rad = final["stats"]
    t_rad = time_to(search, a.target)

    # luxtally
    lux_bin = a.luxtally
    if not lux_bin.exists():
        die(f"{lux_bin} not found: cargo build --release [--features obvhs] first")
    probe_n = 8_000_000
    sp, wp, _ = run_luxtally(lux_bin, a.scene, probe_n, a.procs, work / "lux-probe")
    rate = probe_n / sp["elapsed_s"]
    n_lux = a.lux_photons or min(a.lux_max_photons, int(rate * a.lux_seconds / 1e6) * 1_000_000)
    log(f"luxtally probe: {probe_n} photons in {sp['elapsed_s']:.2f} s ({rate / 1e6:.2f} M/s); "
        f"running {n_lux:,}")
    s, lux_wall, lux_cmd = run_luxtally(lux_bin, a.scene, n_lux, a.procs, work / "lux")
    r = s["receivers"][rec["name"]]
    df = r["daylight_factor"]
    lv, ls = df["values"], df["sigma"]
    sky, refl = df["sky_component"], df["reflected"]
    sky_sig = [x / eh * 100 if x is not None else None for x in r["direct_sigma"]]
    ok = [i for i in range(len(lv)) if ls[i] is not None and ls[i] > 0]
    lux_rel = [ls[i] / lv[i] for i in ok]
    lux_median_rel = statistics.median(lux_rel)
    lux_quadratic = compare.rms([ls[i] for i in ok]) / compare.rms([lv[i] for i in ok])
    sky_ok = [i for i in range(len(sky)) if sky[i] > 0 and sky_sig[i] is not None and sky_sig[i] > 0]
    sky_median_rel = statistics.median([sky_sig[i] / sky[i] for i in sky_ok]) if sky_ok else None
    t_lux_run = s["elapsed_s"] + s["setup_s"]
    t_lux_median = t_lux_run * (lux_median_rel / a.target) ** 2
    t_lux_quadratic = t_lux_run * (lux_quadratic / a.target) ** 2
    t_sky = t_lux_run * (sky_median_rel / a.target) ** 2 if sky_median_rel else None

    # (a) the mean over the cells
    lm = df["mean"]
    lux_mean_sig = (lm["high"] - lm["low"]) / (2 * 1.959964)
    z_mean = (lm["value"] - rad["mean"]) / math.hypot(lux_mean_sig, rad["mean_sigma"])
    # (b) row means; luxtally's sigma from its cells as if independent
    rows = []
    for j in range(nv):
        idx = [j * nu + i for i in range(nu)]
        lrow = mean([lv[i] for i in idx])
        lsig = math.sqrt(sum((ls[i] or 0.0) ** 2 for i in idx)) / nu
        srow = mean([sky[i] for i in idx])
        rrow = mean([refl[i] for i in idx])
        y = pts[j * nu][1]
        z = (lrow - rad["rows"][j]) / math.hypot(lsig, rad["rows_sigma"][j])
        rows.append(dict(j=j, y=y, lux=lrow, lux_sigma=lsig, lux_sky=srow, lux_reflected=rrow,
                         rad=rad["rows"][j], rad_sigma=rad["rows_sigma"][j], z=z))
    z_rows_rms = compare.rms([row["z"] for row in rows])
    # (c) cells
    zc = [(lv[i] - rad["values"][i]) / math.hypot(ls[i], rad["cell_sigma"][i]) for i in ok]
    z_cells_rms = compare.rms(zc)
    rel_mean = lm["value"] / rad["mean"] - 1

    settings = "rtrace " + " ".join(final["cmd"][1:-1])
    print()
    print(f"Daylight factor grid `{rec['name']}`, {nu}×{nv} = {nu * nv} cells, CIE type 16, "
          f"E_out {eh:.0f} lx; {a.procs} processes/threads; {rad_version} ({rt_version})")
    print()
    print("| tool | settings | run | per-point noise | mean DF | time to 2 % per point |")
    print("|---|---|---|---:|---:|---:|")
    tr = f"{t_rad[0]:.0f} s (log-log, slope {t_rad[1]:.2f})" if t_rad else "–"
    print(f"| Radiance | `{settings}`, cell centres | {final['times_s'][0]:.1f}, {final['times_s'][1]:.1f} s "
          f"| {rad['noise']:.2%} (RMS(a−b)/√2 / RMS) | {rad['mean']:.3f} ± {rad['mean_sigma']:.3f} % | {tr} |")
    print(f"| luxtally | `run --photons {n_lux} --threads {a.procs} --estimator next_event`, cell averages "
          f"| {s['elapsed_s']:.1f} s photons + {s['setup_s']:.1f} s setup ({lux_wall:.1f} s process) "
          f"| median σ/value {lux_median_rel:.2%}; RMS σ / RMS {lux_quadratic:.2%} "
          f"| {lm['value']:.3f} % (95 % {lm['low']:.3f}–{lm['high']:.3f}) "
          f"| {t_lux_median:.0f} s (median), {t_lux_quadratic:.0f} s (RMS); sky component alone "
          + (f"{t_sky:.0f} s |" if t_sky else "– |"))
    print()
    print(f"Mean DF: luxtally − Radiance = {lm['value'] - rad['mean']:+.4f} % ({rel_mean:+.2%}), "
          f"z = {z_mean:+.2f} (σ_lux {lux_mean_sig:.4f} from its interval, σ_rad {rad['mean_sigma']:.4f}); "
          f"row-mean z RMS {z_rows_rms:.2f} over {nv} rows; cell z RMS {z_cells_rms:.2f} over {len(ok)} cells.")
    print()
    print("| row j | y (m) | Radiance DF (%) | luxtally DF (%) | luxtally sky / reflected | z |")
    print("|---:|---:|---:|---:|---:|---:|")
    for row in rows:
        print(f"| {row['j']} | {row['y']:.3f} | {row['rad']:.3f} ± {row['rad_sigma']:.3f} | "
              f"{row['lux']:.3f} ± {row['lux_sigma']:.3f} | {row['lux_sky']:.3f} / {row['lux_reflected']:.3f} | "
              f"{row['z']:+.2f} |")
    print()
    print("| -ad | run times (s) | noise | mean DF (%) |")
    print("|---:|---|---:|---:|")
    for row in search:
        print(f"| {row['ad']} | {row['times_s'][0]:.1f}, {row['times_s'][1]:.1f} | {row['noise']:.2%} | "
              f"{row['mean_df']:.4f} ± {row['mean_df_sigma']:.4f} |")
    print()
    print(f"Sky check (`rtrace -I+ {' '.join(cal_args)}`, sky only): up {e_up:.1f} lx "
          f"({e_up / eh - 1:+.3%}), down {e_dn:.1f} lx ({e_dn / (rho_g * eh) - 1:+.3%}). "
          + "; ".join(f"glazing {k}: Tn {g['Tn']} → tn {', '.join(f'{t:.6f}' for t in g['tn'])}"
                      for k, g in glass_info.items()))

    if a.json:
        a.json.write_text(json.dumps(dict(
            radiance=dict(version=rad_version, rtrace_version=rt_version, cmd=final["cmd"], search=search,
                          time_to_target_s=t_rad[0] if t_rad else None, calibration=calib, glass=glass_info,
                          pane_gap_m=a.pane_gap, values_a=final["a"], values_b=final["b"], mean=rad["mean"],
                          mean_sigma=rad["mean_sigma"], noise=rad["noise"]),
            luxtally=dict(cmd=lux_cmd, photons=s["photons_emitted"], elapsed_s=s["elapsed_s"],
                          setup_s=s["setup_s"], direct_s=s.get("direct_s"), process_s=lux_wall,
                          probe_rate_per_s=rate, mean=lm, mean_sigma=lux_mean_sig,
                          median_rel_sigma=lux_median_rel, quadratic_rel_sigma=lux_quadratic,
                          sky_median_rel_sigma=sky_median_rel, time_to_target_median_s=t_lux_median,
                          time_to_target_quadratic_s=t_lux_quadratic, sky_time_to_target_s=t_sky,
                          values=lv, sigma=ls, sky_component=sky, reflected=refl, sky_sigma=sky_sig),
            agreement=dict(mean_diff=lm["value"] - rad["mean"], mean_rel=rel_mean, z_mean=z_mean,
                           rows=rows, z_rows_rms=z_rows_rms, z_cells_rms=z_cells_rms, cells_compared=len(ok)),
            target=a.target,
        ), indent=1))


if __name__ == "__main__":
    main()

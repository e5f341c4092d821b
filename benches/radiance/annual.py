#!/usr/bin/env python3
"""Radiance's 2-phase method (rfluxmtx + gendaymtx + dctimestep) against `luxtally annual`.

Converts scenes/daylit_office_annual.toml to Radiance with daylight.py's functions (plastic
polygons, the double glazing as two `glass` polygons, no sky of the scene's own), then

    rfluxmtx -I+ -ab 6 -ad 4096 -lw 1e-5 -aa 0 -u+ -n 2 - sky.rad office.rad < sensors
    gendaymtx -m 2 -g 0.2 0.2 0.2 EPW                 (visible radiance, -O0)
    dctimestep dc.mtx sky.mtx                          (W/m2 per sensor and record)

over the receiver's cell centres (normal +z, luxtally's CSV x, y, z), illuminance =
179 (0.265 R + 0.670 G + 0.065 B); two independent rfluxmtx runs (-u+) for Radiance's
noise, one more with a deeper bounce limit (mean only). The per-sensor mean over the
occupied records (dark records count 0), DA300 and sDA300/50 % (no blinds), against
`luxtally annual` on the same scene. Plain Python 3.11 standard library; reuses
compare.py's pyradiance venv. See benches/radiance/README.md.
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time
import tomllib
from array import array
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import compare  # noqa: E402  (setup_radiance, rms, log)
import daylight  # noqa: E402  (radiance_scene, cell_points)

REPO = Path(__file__).resolve().parents[2]
LM_PER_W = compare.LM_PER_W
PHOT = compare.PHOTOMETRIC
log = compare.log


def die(msg, code=1):
    print(f"annual.py: {msg}", file=sys.stderr)
    sys.exit(code)


def mean(xs):
    return sum(xs) / len(xs) if xs else float("nan")


def load_avg():
    try:
        return [float(x) for x in Path("/proc/loadavg").read_text().split()[:3]]
    except OSError:
        return None


# --- Radiance tools and matrices -------------------------------------------------
def tools_in(binpath):
    out = {}
    for name in ("rfluxmtx", "rcontrib", "gendaymtx", "dctimestep", "oconv", "rtrace"):
        p = Path(binpath) / name
        if not p.exists():
            w = shutil.which(name)
            if w is None:
                die(f"{name} not found in {binpath} nor on PATH")
            p = Path(w)
        out[name] = str(p)
    return out


def run(cmd, cwd, stdin=None, stdout_path=None):
    """Runs cmd; its stdout to stdout_path (binary) or returned; wall time."""
    t0 = time.perf_counter()
    if stdout_path is not None:
        with open(stdout_path, "wb") as f:
            r = subprocess.run(cmd, cwd=cwd, input=stdin, stdout=f, stderr=subprocess.PIPE)
        out = None
    else:
        r = subprocess.run(cmd, cwd=cwd, input=stdin, capture_output=True)
        out = r.stdout
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        die(f"{' '.join(map(str, cmd))} failed:\n{r.stderr.decode(errors='replace')[-2000:]}")
    return out, dt, r.stderr.decode(errors="replace")


def read_matrix(path):
    """A Radiance matrix file with a header and binary float/double data (-of/-od)."""
    data = Path(path).read_bytes()
    end = data.find(b"\n\n")
    if end < 0:
        die(f"{path}: no header end")
    head = data[:end].decode(errors="replace").split("\n")
    info = {}
    for line in head:
        if "=" in line:
            k, v = line.split("=", 1)
            info[k.strip()] = v.strip()
    fmt = info.get("FORMAT", "")
    if info.get("BigEndian", "0") != "0" and sys.byteorder == "little":
        die(f"{path}: big-endian data")
    code = {"float": "f", "double": "d"}.get(fmt)
    if code is None:
        die(f"{path}: format {fmt!r} (write -of or -od)")
    arr = array(code)
    arr.frombytes(data[end + 2:])
    nr, nc, ncomp = int(info["NROWS"]), int(info["NCOLS"]), int(info.get("NCOMP", "3"))
    if len(arr) != nr * nc * ncomp:
        die(f"{path}: {len(arr)} numbers for {nr} x {nc} x {ncomp}")
    return arr, nr, nc, ncomp, head


def lux_of(arr, nr, nc):
    """179 (0.265 R + 0.670 G + 0.065 B) per row and column: list of rows."""
    wr, wg, wb = (LM_PER_W * w for w in PHOT)
    rows = []
    for i in range(nr):
        base = i * nc * 3
        r_ = arr[base:base + 3 * nc:3]
        g_ = arr[base + 1:base + 3 * nc:3]
        b_ = arr[base + 2:base + 3 * nc:3]
        rows.append([wr * a + wg * b + wb * c for a, b, c in zip(r_, g_, b_)])
    return rows


def reinhart_solid_angles(mf):
    """Solid angle of each Reinhart MF sky patch (gendaymtx order)."""
    tregenza = [30, 30, 24, 24, 18, 12, 6]
    alpha = math.radians(90.0 / (7 * mf + 0.5))
    out, row = [], 0
    for n in tregenza:
        for _ in range(mf):
            k = n * mf
            out += [(2 * math.pi / k) * (math.sin((row + 1) * alpha) - math.sin(row * alpha))] * k
            row += 1
    out.append(2 * math.pi * (1 - math.cos(alpha / 2)))
    return out


def sun_disc_in_patch(work, mf, disc_deg):
    """`gendaymtx -5 D` writes the sun's patch with the radiance of a D-degree disc (for a
    sun source of that size, 5-phase). For patch coefficients spread it over its patch:
    sky + (sun1 - sky) * omega_disc / omega_patch. Writes sky_sun1p.mtx (float)."""
    s1, nr, nc, ncomp, head = read_matrix(work / "sky_sun1.mtx")
    so, *_ = read_matrix(work / "sky_only.mtx")
    om = [None] + reinhart_solid_angles(mf)
    od = 2 * math.pi * (1 - math.cos(math.radians(disc_deg / 2)))
    out = array("f", so)
    step = nc * ncomp
    for j in range(1, nr):
        f = od / om[j]
        base = j * step
        for q in range(base, base + step):
            d = s1[q] - so[q]
            if d != 0.0:
                out[q] = so[q] + d * f
    with open(work / "sky_sun1p.mtx", "wb") as fh:
        fh.write(("\n".join(["#?RADIANCE", "annual.py: gendaymtx -5 sun spread over its patch",
                              f"NROWS={nr}", f"NCOLS={nc}", f"NCOMP={ncomp}", "BigEndian=0",
                              "FORMAT=float"]) + "\n\n").encode())
        out.tofile(fh)


def reinhart_directions(mf):
    """Centre direction of each Reinhart MF sky patch (x east, y north, z up): rows from
    the horizon, patch 1 of a row due north, then towards the east (reinhartb.cal)."""
    tregenza = [30, 30, 24, 24, 18, 12, 6]
    alpha = math.radians(90.0 / (7 * mf + 0.5))
    out, row = [], 0
    for n in tregenza:
        for _ in range(mf):
            k = n * mf
            alt = (row + 0.5) * alpha
            for q in range(k):
                az = 2 * math.pi * q / k
                out.append((math.sin(az) * math.cos(alt), math.cos(az) * math.cos(alt), math.sin(alt)))
            row += 1
    out.append((0.0, 0.0, 1.0))
    return out


def ray_hits_box(o, d, lo, hi):
    t0, t1 = 1e-9, float("inf")
    for k in range(3):
        if abs(d[k]) < 1e-15:
            if not lo[k] <= o[k] <= hi[k]:
                return False
            continue
        a, b = (lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]
        if a > b:
            a, b = b, a
        t0, t1 = max(t0, a), min(t1, b)
        if t0 > t1:
            return False
    return True


def light_in_polarisation(scene, mf, s_sky, s_sun, s_ground, n_win=(12, 6)):
    """Flux let in through the glazed rects, polarised (luxtally) over unpolarised
    (Radiance's glass) pane stacking, from each patch centre direction weighted by its
    occupied-hours luminance sum x solid angle x cos(incidence) x the fraction of the
    window the direction reaches unobstructed (overhang, building: every other rect and
    box of the scene that is outside). The ground (below the horizon, uniform) by the
    same patches mirrored. An estimate of what the polarised stacking adds to the light
    entering the room; the room's response to each direction is not weighed."""
    mats = scene["materials"]
    glazed = [o for o in scene["objects"] if o["shape"] == "rect" and "glazing" in mats[o["material"]]]
    if len(glazed) != 1:
        return None
    g = glazed[0]
    tns = [daylight.tn_from_Tn(float(t)) for t in mats[g["material"]]["glazing"]]
    c, u, v = (tuple(map(float, g[q])) for q in ("corner", "u", "v"))
    n = daylight.cross(u, v)
    n = daylight.scale(n, 1 / math.sqrt(daylight.dot(n, n)))
    if n[1] > 0:
        n = daylight.scale(n, -1)  # outwards: the room is at y > 0 (this scene)
    blockers = []
    for o in scene["objects"]:
        if o is g:
            continue
        if o["shape"] == "rect":
            oc, ou, ov = (tuple(map(float, o[q])) for q in ("corner", "u", "v"))
            quad = [oc, daylight.add(oc, ou), daylight.add(daylight.add(oc, ou), ov), daylight.add(oc, ov)]
            if min(q[1] for q in quad) < -1e-6:  # outside the wall plane y = 0
                blockers.append(("quad", quad))
        elif o["shape"] == "box":
            blockers.append(("box", tuple(map(float, o["min"])), tuple(map(float, o["max"]))))
    wpts = [daylight.add(daylight.add(c, daylight.scale(u, (i + 0.5) / n_win[0])), daylight.scale(v, (j + 0.5) / n_win[1]))
            for j in range(n_win[1]) for i in range(n_win[0])]
    wpts = [daylight.add(p, daylight.scale(n, 1e-6)) for p in wpts]

    cache = {}

    def free(d):
        if d in cache:
            return cache[d]
        k = 0
        for p in wpts:
            hit = False
            for b in blockers:
                if b[0] == "quad":
                    hit = daylight.hits_quad(p, d, b[1])
                else:
                    hit = ray_hits_box(p, d, b[1], b[2])
                if hit:
                    break
            k += not hit
        cache[d] = k / len(wpts)
        return cache[d]

    dirs = reinhart_directions(mf)
    om = reinhart_solid_angles(mf)
    sums = {"sky": [0.0, 0.0], "sun": [0.0, 0.0], "ground": [0.0, 0.0]}
    for j, d in enumerate(dirs):
        for part, dd, w in (("sky", d, s_sky[j]), ("sun", d, s_sun[j]),
                            ("ground", (d[0], d[1], -d[2]), s_ground)):
            cos_i = daylight.dot(dd, n)
            if cos_i <= 1e-9 or w <= 0:
                continue
            f = free(dd)
            if f == 0:
                continue
            tp, tu = daylight.stack_T(cos_i, tns)
            sums[part][0] += w * om[j] * cos_i * f * tp
            sums[part][1] += w * om[j] * cos_i * f * tu
    out = {k: dict(polarised=v[0], unpolarised=v[1], ratio=v[0] / v[1] if v[1] else None) for k, v in sums.items()}
    tot_p = sum(v[0] for v in sums.values())
    tot_u = sum(v[1] for v in sums.values())
    out["all"] = dict(polarised=tot_p, unpolarised=tot_u, ratio=tot_p / tot_u)
    return out


def reinhart_projected(mf):
    """Exact projected solid angle (the horizontal illuminance per unit radiance) of each
    Reinhart MF sky patch, in gendaymtx / reinhartb.cal order (rows from the horizon,
    Tregenza's 30 30 24 24 18 12 6 patches per band times MF per row, the zenith cap)."""
    tregenza = [30, 30, 24, 24, 18, 12, 6]
    alpha = math.radians(90.0 / (7 * mf + 0.5))
    out = []
    row = 0
    for n in tregenza:
        for _ in range(mf):
            a1, a2 = row * alpha, (row + 1) * alpha
            k = n * mf
            p = (2 * math.pi / k) * (math.sin(a2) ** 2 - math.sin(a1) ** 2) / 2
            out += [p] * k
            row += 1
    out.append(math.pi * math.sin(alpha / 2) ** 2)
    return out


SKY_RAD = """#@rfluxmtx h=u u=Y
void glow ground_glow
0
0
4 1 1 1 0

ground_glow source ground
0
0
4 0 0 -1 180

#@rfluxmtx h=r{mf} u=Y
void glow skyglow
0
0
4 1 1 1 0

skyglow source sky
0
0
4 0 0 1 180
"""


# --- the weather file's stamps ---------------------------------------------------
def epw_stamps(path):
    rows = []
    with open(path, newline="") as f:
        for k, line in enumerate(f):
            if k < 8:
                continue
            p = line.split(",")
            if len(p) < 20:
                continue
            rows.append((int(p[1]), int(p[2]), int(p[3]), float(p[14]), float(p[15]), float(p[18])))
    return rows  # month, day, hour, DNI W/m2, DHI W/m2, DHI lx


# --- luxtally --------------------------------------------------------------------
def read_csv(path):
    with open(path) as f:
        head = f.readline().strip().split(",")
        rows = [dict(zip(head, line.strip().split(","))) for line in f if line.strip()]
    return rows


def run_luxtally(bin_path, scene, out, extra, threads):
    cmd = [str(bin_path), "annual", str(scene), "--out", str(out), "--threads", str(threads), *extra]
    load0 = load_avg()
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        die(f"{' '.join(cmd)} failed:\n{r.stderr[-3000:]}")
    summary = json.loads((Path(out) / "annual.json").read_text())
    return dict(cmd=cmd, wall_s=dt, load_before=load0, load_after=load_avg(), summary=summary,
                stderr_tail=r.stderr.strip().split("\n")[-8:])


def lux_results(out, rec_name):
    cells = read_csv(Path(out) / f"annual_{rec_name}.csv")
    hours = read_csv(Path(out) / f"annual_{rec_name}_hours.csv")
    return cells, hours


# --- statistics ------------------------------------------------------------------
def sda(da_list):
    return sum(1 for d in da_list if d >= 0.5) / len(da_list)


def compare_cells(lux_mean, lux_sig, rad_mean, rad_sig):
    ratios = [l / r for l, r in zip(lux_mean, rad_mean) if r > 0]
    rel = [(l - r) / r for l, r in zip(lux_mean, rad_mean) if r > 0]
    z = [(l - r) / math.sqrt(s1 * s1 + s2 * s2) for l, r, s1, s2 in zip(lux_mean, rad_mean, lux_sig, rad_sig)
         if s1 > 0 or s2 > 0]
    k = mean(lux_mean) / mean(rad_mean)
    zs = [(l - k * r) / math.sqrt(s1 * s1 + (k * s2) ** 2) for l, r, s1, s2 in zip(lux_mean, rad_mean, lux_sig, rad_sig)
          if s1 > 0 or s2 > 0]
    return dict(
        mean_ratio=mean(ratios),
        ratio_of_means=k,
        rms_rel_diff=compare.rms(rel),
        z_rms=compare.rms(z),
        within_2sigma=sum(1 for x in z if abs(x) <= 2) / len(z),
        z_rms_scaled=compare.rms(zs),
        within_2sigma_scaled=sum(1 for x in zs if abs(x) <= 2) / len(zs),
        min_ratio=min(ratios), max_ratio=max(ratios),
    )


def rows_sigma(a, b, nu, nv):
    """Per-sensor sigma of the two-run mean from each row's pooled relative noise
    (nu sensors a row, as daylight.py); and the overall per-run relative noise."""
    m = [(x + y) / 2 for x, y in zip(a, b)]
    d = [x - y for x, y in zip(a, b)]
    sig = [0.0] * len(m)
    for j in range(nv):
        idx = range(j * nu, (j + 1) * nu)
        m2 = sum(m[i] ** 2 for i in idx)
        rel = math.sqrt(sum(d[i] ** 2 for i in idx) / 4 / m2) if m2 > 0 else 0.0
        for i in idx:
            sig[i] = rel * m[i]
    noise = compare.rms(d) / math.sqrt(2) / compare.rms(m)
    return m, sig, noise


# --- main ------------------------------------------------------------------------
def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", type=Path, default=REPO / "scenes" / "daylit_office_annual.toml")
    ap.add_argument("--receiver", default="df_grid")
    ap.add_argument("--ab", type=int, default=6)
    ap.add_argument("--ad", type=int, default=8192)
    ap.add_argument("--lw", default="1e-5")
    ap.add_argument("--bias-ab", type=int, default=10,
                    help="one more rfluxmtx run with this -ab and -lw 1e-6 (mean only; 0: skip)")
    ap.add_argument("--pane-gap", type=float, default=0.012)
    ap.add_argument("--procs", type=int, default=2, help="rcontrib -n and luxtally --threads")
    ap.add_argument("--workdir", type=Path, default=REPO / "target" / "radiance-annual")
    ap.add_argument("--venv", type=Path, default=REPO / "target" / "radiance-compare" / "venv")
    ap.add_argument("--radiance-bin", type=Path)
    ap.add_argument("--raypath")
    ap.add_argument("--luxtally", type=Path, default=REPO / "target" / "release" / "luxtally")
    ap.add_argument("--lux-args", default="--sda-halfwidth 0.5",
                    help="extra luxtally annual options (default: one round, '--sda-halfwidth 0.5')")
    ap.add_argument("--lux-out", type=Path, help="use this finished luxtally annual output instead of running it")
    ap.add_argument("--lux-variants", default="seed=2,sun_mf=2,sun_mf=0",
                    help="comma-separated [annual] overrides run as extra luxtally variants, seed=N: "
                         "the scene with --seed N ('' = none)")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--md", type=Path, default=REPO / "benches" / "radiance" / "ANNUAL_RESULTS.md")
    a = ap.parse_args()

    t_start = time.perf_counter()
    work = a.workdir.resolve()
    work.mkdir(parents=True, exist_ok=True)
    scene_path = a.scene.resolve()
    scene = tomllib.loads(scene_path.read_text())
    ann = scene.get("annual")
    if ann is None:
        die("the scene has no [annual] table")
    mf = int(ann.get("mf", 1))
    sun_mf = int(ann.get("sun_mf", 0))
    rho_g = float(ann.get("ground_reflectance", 0.2))
    occ = [float(x) for x in ann.get("occupied_hours", [8.0, 18.0])]
    epw = (scene_path.parent / ann["weather"]).resolve()
    if epw.suffix.lower() != ".epw":
        die("only an EPW weather file is read here")
    recs = [r for r in scene["receivers"] if r["name"] == a.receiver]
    if len(recs) != 1:
        die(f"no receiver {a.receiver}")
    rec = recs[0]
    pts, normal, (nu, nv) = daylight.cell_points(rec)
    if normal != (0.0, 0.0, 1.0):
        die(f"the receiver's normal is {normal}, not +z")
    centre = tuple(mean([p[k] for p in pts]) for k in range(3))

    # --- luxtally first (its CSV's x, y, z are the sensors) -----------------------
    lux_runs = {}
    if a.lux_out:
        lux_out = a.lux_out.resolve()
        lux_runs["scene"] = dict(cmd=None, wall_s=None, summary=json.loads((lux_out / "annual.json").read_text()))
    else:
        if not a.luxtally.exists():
            die(f"{a.luxtally} not found: cargo build --release --features obvhs first")
        lux_out = work / "lux"
        log(f"luxtally annual {scene_path.name} ({a.lux_args})")
        lux_runs["scene"] = run_luxtally(a.luxtally, scene_path, lux_out, a.lux_args.split(), a.procs)
        log(f"  {lux_runs['scene']['wall_s']:.1f} s wall, photon pass {lux_runs['scene']['summary']['elapsed_s']:.1f} s")
    lux_runs["scene"]["out"] = str(lux_out)
    cells, hours = lux_results(lux_out, a.receiver)
    lux_pts = [(float(c["x"]), float(c["y"]), float(c["z"])) for c in cells]
    if len(lux_pts) != len(pts) or max(max(abs(p - q) for p, q in zip(u, v)) for u, v in zip(pts, lux_pts)) > 1e-3:
        die("luxtally's CSV cells are not the receiver's cell centres in j * nu + i order")
    variants = {}
    for spec in [s for s in a.lux_variants.split(",") if s.strip()]:
        key, val = (x.strip() for x in spec.split("="))
        if key == "seed":  # the scene as it is, another seed: luxtally's own spread
            vout = work / f"lux_seed_{val}"
            log(f"luxtally annual, --seed {val}")
            r = run_luxtally(a.luxtally, scene_path, vout, [*a.lux_args.split(), "--seed", val], a.procs)
            r["out"] = str(vout)
            variants[f"seed={val}"] = (r, lux_results(vout, a.receiver))
            log(f"  {r['wall_s']:.1f} s wall")
            continue
        text = scene_path.read_text()
        if f"\n{key} =" in text:
            lines = [f"{key} = {val}" if ln.startswith(f"{key} =") else ln for ln in text.split("\n")]
            text = "\n".join(lines)
        else:
            text = text.replace("[annual]\n", f"[annual]\n{key} = {val}\n")
        vscene = scene_path.parent / f".annual_py_{key}_{val}.toml"  # beside the scene: the EPW path is relative
        vscene.write_text(text)
        try:
            vout = work / f"lux_{key}_{val}"
            log(f"luxtally annual variant {key} = {val}")
            r = run_luxtally(a.luxtally, vscene, vout, a.lux_args.split(), a.procs)
        finally:
            vscene.unlink()
        r["out"] = str(vout)
        variants[f"{key}={val}"] = (r, lux_results(vout, a.receiver))
        log(f"  {r['wall_s']:.1f} s wall")

    # --- Radiance ----------------------------------------------------------------
    if a.radiance_bin:
        binpath, raypath, rad_version = a.radiance_bin, a.raypath or os.environ.get("RAYPATH", "."), "local"
    else:
        binpath, raypath, rad_version = compare.setup_radiance(a.venv)
    os.environ["RAYPATH"] = raypath if "." in raypath.split(os.pathsep) else "." + os.pathsep + raypath
    tools = tools_in(binpath)
    # rfluxmtx runs rcontrib and oconv from PATH
    os.environ["PATH"] = str(Path(tools["rcontrib"]).parent) + os.pathsep + os.environ.get("PATH", "")
    text, glass_info = daylight.radiance_scene(scene, centre, a.pane_gap)
    (work / "office.rad").write_text(text)
    (work / "sky.rad").write_text(SKY_RAD.format(mf=mf))
    sensors = "".join(f"{x:.4f} {y:.4f} {z:.4f} 0 0 1\n" for x, y, z in lux_pts).encode()

    # Sky matrices: the default sun (4 nearest patches) and the sun as a 0.533 deg disc in one patch.
    g = f"{rho_g:g}"
    gd_cmd = [tools["gendaymtx"], "-m", str(mf), "-g", g, g, g, "-O0", "-of", str(epw)]
    _, t_gd, gd_err = run(gd_cmd, work, stdout_path=work / "sky.mtx")
    gd5_cmd = [tools["gendaymtx"], "-m", str(mf), "-5", "0.533", "-g", g, g, g, "-O0", "-of", str(epw)]
    _, t_gd5, _ = run(gd5_cmd, work, stdout_path=work / "sky_sun1.mtx")
    gds_cmd = [tools["gendaymtx"], "-m", str(mf), "-s", "-g", g, g, g, "-O0", "-of", str(epw)]
    _, _, _ = run(gds_cmd, work, stdout_path=work / "sky_only.mtx")
    n_bright = gd_err.count("unusually bright")
    log(f"gendaymtx: {t_gd:.2f} s ({n_bright} 'unusually bright' warnings)")

    base = ["-I+", "-ab", str(a.ab), "-ad", str(a.ad), "-lw", a.lw, "-aa", "0", "-lr", "0", "-u+", "-n", str(a.procs), "-faf"]
    settings = {"ab": a.ab, "ad": a.ad, "lw": a.lw, "aa": 0, "lr": 0, "u": "+", "n": a.procs}
    dc_runs = []
    for tag in ("a", "b"):
        cmd = [tools["rfluxmtx"], *base, "-", "sky.rad", "office.rad"]
        l0 = load_avg()
        _, dt, _ = run(cmd, work, stdin=sensors, stdout_path=work / f"dc_{tag}.mtx")
        dc_runs.append(dict(tag=tag, cmd=cmd, wall_s=dt, load_before=l0, load_after=load_avg(), file=f"dc_{tag}.mtx"))
        log(f"rfluxmtx run {tag}: {dt:.1f} s")
    if a.bias_ab:
        deep = ["-I+", "-ab", str(a.bias_ab), "-ad", str(a.ad), "-lw", "1e-6", "-aa", "0", "-lr", "0", "-u+", "-n", str(a.procs), "-faf"]
        cmd = [tools["rfluxmtx"], *deep, "-", "sky.rad", "office.rad"]
        l0 = load_avg()
        _, dt, _ = run(cmd, work, stdin=sensors, stdout_path=work / "dc_deep.mtx")
        dc_runs.append(dict(tag="deep", cmd=cmd, wall_s=dt, load_before=l0, load_after=load_avg(), file="dc_deep.mtx"))
        log(f"rfluxmtx deep run (-ab {a.bias_ab} -lw 1e-6): {dt:.1f} s")

    stamps = epw_stamps(epw)
    # A record stamped h covers (h-1, h]; its sun is at h - 0.5 (gendaymtx's loadEPW too).
    occupied = [k for k, s in enumerate(stamps) if occ[0] <= s[2] - 0.5 < occ[1]]
    n_occ = len(occupied)

    def hourly(dc_file, sky_file):
        out = work / f"E_{Path(dc_file).stem}_{Path(sky_file).stem}.mtx"
        cmd = [tools["dctimestep"], "-of", dc_file, sky_file]
        _, dt, _ = run(cmd, work, stdout_path=out)
        arr, nr, nc, _, _ = read_matrix(out)
        if nr != len(lux_pts) or nc != len(stamps):
            die(f"dctimestep gave {nr} x {nc}, not {len(lux_pts)} sensors x {len(stamps)} records")
        rows = lux_of(arr, nr, nc)
        out.unlink()  # 63 MB
        return rows, dt, cmd

    def annual_stats(rows):
        means, das = [], []
        for r in rows:
            e = [r[k] for k in occupied]
            means.append(sum(e) / n_occ)
            das.append(sum(1 for x in e if x >= 300.0) / n_occ)
        return means, das

    rad = {}
    t_dct = []
    for run_ in dc_runs:
        rows, dt, dct_cmd = hourly(run_["file"], "sky.mtx")
        t_dct.append(dt)
        m, da = annual_stats(rows)
        rad[run_["tag"]] = dict(mean=m, da=da)
        if run_["tag"] == "a":
            rows_a = rows
        log(f"dctimestep {run_['tag']}: {dt:.1f} s; mean over sensors {mean(m):.1f} lx, sDA {sda(da):.3f}")
    # The sun as a disc in one patch and the sky alone (run a's coefficients).
    sun_disc_in_patch(work, mf, 0.533)
    rows, _, _ = hourly("dc_a.mtx", "sky_sun1p.mtx")
    m, da = annual_stats(rows)
    rad["a_sun1"] = dict(mean=m, da=da)
    rows, _, _ = hourly("dc_a.mtx", "sky_only.mtx")
    m, da = annual_stats(rows)
    rad["a_sky_only"] = dict(mean=m, da=da)
    rad_mean, rad_sig, rad_noise = rows_sigma(rad["a"]["mean"], rad["b"]["mean"], nu, nv)
    rad_da = [(x + y) / 2 for x, y in zip(rad["a"]["da"], rad["b"]["da"])]

    # --- the skies themselves: gendaymtx's global horizontal against luxtally's --------
    sky, nr, nc, _, _ = read_matrix(work / "sky.mtx")
    sky_rows = lux_of(sky, nr, nc)  # [patch][record], cd/m2 / 179 * 179 = cd/m2
    proj = reinhart_projected(mf)
    if len(proj) + 1 != nr:
        die(f"sky.mtx has {nr} rows, MF {mf} gives {len(proj) + 1}")
    lux_hours = {int(h["record"]): h for h in hours}
    gh_rad, gh_lux, gh_patch, dhi_rad, dhi_epw = [], [], [], [], []
    skyo, _, _, _, _ = read_matrix(work / "sky_only.mtx")
    skyo_rows = lux_of(skyo, nr, nc)
    s1p, _, _, _, _ = read_matrix(work / "sky_sun1p.mtx")
    s1p_rows = lux_of(s1p, nr, nc)
    gh_sun1p = []
    rad_dark_lux_lit, lux_dark_rad_lit = 0, 0
    for k in occupied:
        g_r = sky_rows[0][k] * math.pi / rho_g  # ground row = rho (Ed + Edn sin h) / pi
        g_l = float(lux_hours[k]["global_horizontal_lx"])
        if g_r > 0 and g_l == 0:
            rad_dark_lux_lit += 1
        if g_l > 0 and g_r == 0:
            lux_dark_rad_lit += 1
        if g_r > 0 and g_l > 0:
            gh_rad.append(g_r)
            gh_lux.append(g_l)
            gh_patch.append(sum(sky_rows[j + 1][k] * proj[j] for j in range(len(proj))))
            dhi_rad.append(sum(skyo_rows[j + 1][k] * proj[j] for j in range(len(proj))))
            dhi_epw.append(stamps[k][5])
            gh_sun1p.append(sum(s1p_rows[j + 1][k] * proj[j] for j in range(len(proj))))
    skies = dict(
        occupied_records=n_occ,
        both_lit=len(gh_rad),
        radiance_lit_luxtally_dark=rad_dark_lux_lit,
        luxtally_lit_radiance_dark=lux_dark_rad_lit,
        global_horizontal_sum_ratio_radiance_ground_row_over_luxtally=sum(gh_rad) / sum(gh_lux),
        global_horizontal_sum_ratio_patches_over_ground_row=sum(gh_patch) / sum(gh_rad),
        diffuse_horizontal_sum_radiance_sky_only_over_epw_field19=sum(dhi_rad) / sum(dhi_epw),
        global_horizontal_sum_ratio_sun_one_patch_over_default=sum(gh_sun1p) / sum(gh_patch),
        mean_global_horizontal_lx_radiance=mean(gh_rad),
        mean_global_horizontal_lx_luxtally=mean(gh_lux),
    )
    log(f"skies over occupied records: {json.dumps(skies)}")

    # --- expected differences, term by term ---------------------------------------------
    s_all = [sum(sky_rows[j + 1][k] for k in occupied) for j in range(len(proj))]
    s_sky = [sum(skyo_rows[j + 1][k] for k in occupied) for j in range(len(proj))]
    s_sun = [x - y for x, y in zip(s_all, s_sky)]
    s_ground = sum(sky_rows[0][k] for k in occupied)
    pol = light_in_polarisation(scene, mf, s_sky, s_sun, s_ground)
    c2a = daylight.centre_to_average(rad_mean, nu, nv)
    terms = dict(
        sky_input=1 / skies["global_horizontal_sum_ratio_radiance_ground_row_over_luxtally"],
        sky_patches=1 / skies["global_horizontal_sum_ratio_patches_over_ground_row"],
        polarisation=pol["all"]["ratio"] if pol else 1.0,
        centre_to_average=1 + mean(c2a) / mean(rad_mean),
    )
    if "deep" in rad:
        terms["bounces"] = mean(rad["deep"]["mean"]) / mean(rad["a"]["mean"])
    expected = 1.0
    for x in terms.values():
        expected *= x
    budget = dict(terms=terms, expected_ratio=expected, light_in=pol,
                  sun_share_radiance=1 - mean(rad["a_sky_only"]["mean"]) / mean(rad["a"]["mean"]))
    log(f"budget: {json.dumps(budget)}")

    # --- luxtally's cells -------------------------------------------------------------
    lux_mean = [float(c["mean_lx"]) for c in cells]
    lux_sig = [float(c["mean_sigma_lx"]) for c in cells]
    lux_da = [float(c["da300"]) for c in cells]
    cmp_main = compare_cells(lux_mean, lux_sig, rad_mean, rad_sig)
    cmp_variants = {}
    for key, (r, (vcells, _)) in variants.items():
        vm = [float(c["mean_lx"]) for c in vcells]
        vs = [float(c["mean_sigma_lx"]) for c in vcells]
        vd = [float(c["da300"]) for c in vcells]
        cmp_variants[key] = dict(cmp=compare_cells(vm, vs, rad_mean, rad_sig), mean_lx=mean(vm),
                                 sda=sda(vd), wall_s=r["wall_s"], photons=r["summary"]["photons"],
                                 sun_bins=r["summary"]["sun_bins"], mean_sigma_rms_rel=compare.rms(
                                     [s / x for s, x in zip(vs, vm)]))
    seed_check = None
    for key, (r, (vcells, _)) in variants.items():
        if key.startswith("seed="):
            vm = [float(c["mean_lx"]) for c in vcells]
            vs = [float(c["mean_sigma_lx"]) for c in vcells]
            zz = [(x - y) / math.sqrt(s1 * s1 + s2 * s2) for x, y, s1, s2 in zip(lux_mean, vm, lux_sig, vs)]
            seed_check = dict(variant=key, grid_mean=[mean(lux_mean), mean(vm)],
                              grid_mean_rel_diff=mean(lux_mean) / mean(vm) - 1,
                              z_rms=compare.rms(zz), within_2sigma=sum(1 for x in zz if abs(x) <= 2) / len(zz),
                              observed_rel_noise_per_run=compare.rms([x - y for x, y in zip(lux_mean, vm)])
                              / math.sqrt(2) / compare.rms([(x + y) / 2 for x, y in zip(lux_mean, vm)]))
            log(f"luxtally seed check: {json.dumps(seed_check)}")
    # Radiance's sun in one patch, compared the same way (noise of run a alone ~ sqrt2 x).
    cmp_sun1 = compare_cells(lux_mean, lux_sig, rad["a_sun1"]["mean"], [s * math.sqrt(2) for s in rad_sig])
    cmp_deep = None
    if "deep" in rad:
        cmp_deep = compare_cells(lux_mean, lux_sig, rad["deep"]["mean"], [x * math.sqrt(2) for x in rad_sig])
    deep = None
    if "deep" in rad:
        deep = dict(mean_lx=mean(rad["deep"]["mean"]), ratio_to_ab=mean(rad["deep"]["mean"]) / mean(rad_mean),
                    sda=sda(rad["deep"]["da"]))

    # Rows from the window (j = 0) to the back, 5 bands of 6 rows.
    bands = []
    for b in range(5):
        idx = [j * nu + i for j in range(b * nv // 5, (b + 1) * nv // 5) for i in range(nu)]
        bands.append(dict(rows=f"{b * nv // 5}-{(b + 1) * nv // 5 - 1}",
                          lux=mean([lux_mean[i] for i in idx]), rad=mean([rad_mean[i] for i in idx]),
                          rad_sun1=mean([rad["a_sun1"]["mean"][i] for i in idx]),
                          rad_sky_only=mean([rad["a_sky_only"]["mean"][i] for i in idx]),
                          rad_deep=mean([rad["deep"]["mean"][i] for i in idx]) if "deep" in rad else None,
                          lux_variants={k: mean([float(vc[i]["mean_lx"]) for i in idx])
                                        for k, (_, (vc, _)) in variants.items()}))

    res = dict(
        scene=str(scene_path.relative_to(REPO)) if scene_path.is_relative_to(REPO) else str(scene_path),
        receiver=a.receiver, sensors=len(lux_pts), mf=mf, sun_mf=sun_mf, ground_reflectance=rho_g,
        occupied_hours=occ, occupied_records=n_occ, epw=str(epw.name),
        machine=dict(cores=os.cpu_count(), load_at_end=load_avg()),
        radiance=dict(version=rad_version, settings=settings, glass=glass_info,
                      gendaymtx=dict(cmd=gd_cmd, wall_s=t_gd, unusually_bright_warnings=n_bright,
                                     sun_disc_cmd=gd5_cmd, sky_only_cmd=gds_cmd),
                      rfluxmtx=dc_runs, dctimestep_wall_s=t_dct,
                      wall_s_one_run=dc_runs[0]["wall_s"] + t_gd + t_dct[0],
                      noise_per_run_rms_rel=rad_noise,
                      mean_lx=mean(rad_mean), mean_lx_runs=[mean(rad["a"]["mean"]), mean(rad["b"]["mean"])],
                      mean_sigma_rms_rel=compare.rms([s / x for s, x in zip(rad_sig, rad_mean)]),
                      sda=sda(rad_da), sda_runs=[sda(rad["a"]["da"]), sda(rad["b"]["da"])],
                      sun_disc_one_patch=dict(mean_lx=mean(rad["a_sun1"]["mean"]), sda=sda(rad["a_sun1"]["da"]),
                                              ratio_to_run_a=mean(rad["a_sun1"]["mean"]) / mean(rad["a"]["mean"])),
                      sky_only_mean_lx=mean(rad["a_sky_only"]["mean"]),
                      deep=deep,
                      per_sensor=dict(mean_a=rad["a"]["mean"], mean_b=rad["b"]["mean"], da_a=rad["a"]["da"],
                                      da_b=rad["b"]["da"], mean_deep=rad.get("deep", {}).get("mean"),
                                      mean_sun_one_patch=rad["a_sun1"]["mean"],
                                      mean_sky_only=rad["a_sky_only"]["mean"])),
        luxtally=dict(per_sensor=dict(mean_lx=lux_mean, mean_sigma_lx=lux_sig, da300=lux_da),
                      run={k: v for k, v in lux_runs["scene"].items() if k != "summary"},
                      photons=lux_runs["scene"]["summary"]["photons"],
                      elapsed_s=lux_runs["scene"]["summary"]["elapsed_s"],
                      sun_bins=lux_runs["scene"]["summary"]["sun_bins"],
                      mean_lx=mean(lux_mean), mean_sigma_rms_rel=compare.rms([s / x for s, x in zip(lux_sig, lux_mean)]),
                      sda=sda(lux_da), variants=cmp_variants),
        comparison=cmp_main, comparison_radiance_sun_disc=cmp_sun1, comparison_radiance_deep=cmp_deep, luxtally_seed_check=seed_check, skies=skies, budget=budget, depth_bands=bands,
        wall_s_script=time.perf_counter() - t_start,
    )
    jpath = a.json or (work / "annual_results.json")
    jpath.write_text(json.dumps(res, indent=1))
    md = markdown(res)
    a.md.write_text(md)
    print(md)
    log(f"wrote {jpath} and {a.md}")


def markdown(r):
    R, L, C = r["radiance"], r["luxtally"], r["comparison"]
    s = R["settings"]
    runs = R["rfluxmtx"]
    lr = L["run"]
    load = lambda x: "–" if not x else f"{x[0]:.2f}"  # noqa: E731
    out = []
    out.append(f"# Annual daylight: Radiance 2-phase against `luxtally annual`\n")
    out.append(f"Scene `{r['scene']}`, receiver `{r['receiver']}` ({r['sensors']} cell centres, normal +z), "
               f"{r['epw']}, sky MF {r['mf']} (+ ground), luxtally sun_mf {r['sun_mf']} ({L['sun_bins']} sun bins), "
               f"ground ρ {r['ground_reflectance']}, occupied [{r['occupied_hours'][0]:g}, {r['occupied_hours'][1]:g}) h "
               f"({r['occupied_records']} records, EPW stamps 9–18; dark records count 0). "
               f"Machine: {r['machine']['cores']} cores, shared (load averages shown).\n")
    out.append("## Settings and wall times\n")
    out.append("| tool | command / settings | wall time | load (1 min) before |")
    out.append("|---|---|---|---|")
    out.append(f"| gendaymtx | `gendaymtx -m {r['mf']} -g {r['ground_reflectance']:g} ×3 -O0 -of EPW` | "
               f"{R['gendaymtx']['wall_s']:.2f} s | – |")
    for run in runs:
        flags = " ".join(run["cmd"][1:run["cmd"].index("-")])
        out.append(f"| rfluxmtx ({run['tag']}) | `rfluxmtx {flags} - sky.rad office.rad` | {run['wall_s']:.1f} s | "
                   f"{load(run['load_before'])} |")
    out.append(f"| dctimestep | `dctimestep -of dc.mtx sky.mtx` (600 × 8760) | {R['dctimestep_wall_s'][0]:.1f} s | – |")
    out.append(f"| Radiance total, one run | gendaymtx + rfluxmtx (a) + dctimestep | **{R['wall_s_one_run']:.1f} s** | – |")
    out.append(f"| luxtally annual | `{' '.join(Path(x).name if k == 0 else x for k, x in enumerate(lr['cmd'] or []))}` | "
               f"**{lr['wall_s'] or float('nan'):.1f} s** (photon pass {L['elapsed_s']:.1f} s, {L['photons'] / 1e6:.2f} M photons) | "
               f"{load(lr.get('load_before'))} |")
    for k, v in L["variants"].items():
        out.append(f"| luxtally annual, {k} | same, `[annual] {k.replace('=', ' = ')}` ({v['sun_bins']} sun bins) | "
                   f"{v['wall_s']:.1f} s ({v['photons'] / 1e6:.2f} M photons) | – |")
    out.append("")
    out.append("## Per-sensor annual mean (occupied hours) and sDA300/50 % without blinds\n")
    out.append("| quantity | Radiance 2-phase | luxtally |")
    out.append("|---|---|---|")
    out.append(f"| mean over sensors of the annual mean | {R['mean_lx']:.1f} lx (runs {R['mean_lx_runs'][0]:.1f}, "
               f"{R['mean_lx_runs'][1]:.1f}) | {L['mean_lx']:.1f} lx |")
    out.append(f"| σ of a sensor's annual mean: RMS over sensors of σ/value | {R['mean_sigma_rms_rel']:.2%} (two-run mean, "
               f"from each row's pooled run difference) | {L['mean_sigma_rms_rel']:.2%} (`mean_sigma_lx`) |")
    out.append(f"| Radiance's noise per run, RMS(a − b)/√2 / RMS(value) | {R['noise_per_run_rms_rel']:.2%} | – |")
    out.append(f"| sDA300/50 % (no blinds) | {R['sda']:.1%} (runs {R['sda_runs'][0]:.1%}, {R['sda_runs'][1]:.1%}) | "
               f"{L['sda']:.1%} (from `da300`) |")
    if R["deep"]:
        out.append(f"| deeper bounces (`-ab {runs[-1]['cmd'][runs[-1]['cmd'].index('-ab') + 1]} -lw 1e-6`, one run) | "
                   f"{R['deep']['mean_lx']:.1f} lx (× {R['deep']['ratio_to_ab']:.4f}), sDA {R['deep']['sda']:.1%} | – |")
    sd = R["sun_disc_one_patch"]
    out.append(f"| sun as a 0.533° disc in one patch (`gendaymtx -5 0.533`, run a) | {sd['mean_lx']:.1f} lx "
               f"(× {sd['ratio_to_run_a']:.4f} of run a), sDA {sd['sda']:.1%} | – |")
    out.append(f"| sky and ground only (`gendaymtx -s`, run a) | {R['sky_only_mean_lx']:.1f} lx | – |")
    for k, v in L["variants"].items():
        out.append(f"| luxtally, `{k}` | – | {v['mean_lx']:.1f} lx, sDA {v['sda']:.1%}, σ {v['mean_sigma_rms_rel']:.2%} |")
    out.append("")
    out.append("| agreement (luxtally / Radiance, per sensor) | scene (sun_mf " + str(r["sun_mf"]) + ") | "
               + " | ".join(f"luxtally {k}" for k in L["variants"]) + " | Radiance sun in one patch (run a) |"
               + (" Radiance -ab 10 (deep run) |" if r.get("comparison_radiance_deep") else ""))
    out.append("|---|---|" + "---|" * len(L["variants"]) + "---|" + ("---|" if r.get("comparison_radiance_deep") else ""))
    rows = [("mean ratio", "mean_ratio", "{:.4f}"), ("ratio of the means", "ratio_of_means", "{:.4f}"),
            ("min – max ratio", None, None),
            ("RMS relative difference", "rms_rel_diff", "{:.2%}"),
            ("RMS z, σ = √(σ_lux² + σ_rad²)", "z_rms", "{:.2f}"),
            ("fraction within 2σ", "within_2sigma", "{:.1%}"),
            ("RMS z after scaling Radiance by the ratio of the means", "z_rms_scaled", "{:.2f}"),
            ("fraction within 2σ after that scaling", "within_2sigma_scaled", "{:.1%}")]
    cols = [C] + [v["cmp"] for v in L["variants"].values()] + [r["comparison_radiance_sun_disc"]]
    if r.get("comparison_radiance_deep"):
        cols.append(r["comparison_radiance_deep"])
    for label, key, fmt in rows:
        if key is None:
            cells = [f"{c['min_ratio']:.3f} – {c['max_ratio']:.3f}" for c in cols]
        else:
            cells = [fmt.format(c[key]) for c in cols]
        out.append(f"| {label} | " + " | ".join(cells) + " |")
    out.append("")
    sc = r.get("luxtally_seed_check")
    if sc:
        out.append(f"luxtally against itself ({sc['variant']}): grid means {sc['grid_mean'][0]:.1f} and {sc['grid_mean'][1]:.1f} lx "
                   f"({sc['grid_mean_rel_diff']:+.2%}); per sensor z = (a − b)/√(σ_a² + σ_b²) from `mean_sigma_lx`: "
                   f"RMS {sc['z_rms']:.2f}, {sc['within_2sigma']:.1%} within 2σ; observed noise per run "
                   f"RMS(a − b)/√2 / RMS(value) {sc['observed_rel_noise_per_run']:.2%}.\n")
    out.append("## By depth (mean annual illuminance of 6 rows of 20 sensors, lx)\n")
    vk = list(L["variants"])
    out.append("| rows (0 = window) | luxtally | " + "".join(f"luxtally {k} | " for k in vk)
               + "Radiance | ratio | Radiance -ab 10 | ratio | Radiance, sun in one patch | Radiance, sky + ground only |")
    out.append("|---|---|" + "---|" * len(vk) + "---|---|---|---|---|---|")
    for b in r["depth_bands"]:
        dp = b["rad_deep"] or float("nan")
        out.append(f"| {b['rows']} | {b['lux']:.1f} | " + "".join(f"{b['lux_variants'][k]:.1f} | " for k in vk)
                   + f"{b['rad']:.1f} | {b['lux'] / b['rad']:.4f} | {dp:.1f} | {b['lux'] / dp:.4f} | {b['rad_sun1']:.1f} | "
                   f"{b['rad_sky_only']:.1f} |")
    out.append("")
    sk = r["skies"]
    out.append("## The skies (occupied records)\n")
    out.append(f"- records lit in both: {sk['both_lit']}; lit in gendaymtx but dark in luxtally: "
               f"{sk['radiance_lit_luxtally_dark']}; lit in luxtally but dark in gendaymtx: {sk['luxtally_lit_radiance_dark']}.")
    out.append(f"- global horizontal illuminance, summed: gendaymtx's ground row (ρ(E_d + E_n sin h)/π) × π/ρ over "
               f"luxtally's `global_horizontal_lx`: {sk['global_horizontal_sum_ratio_radiance_ground_row_over_luxtally']:.4f} "
               f"(means {sk['mean_global_horizontal_lx_radiance']:.0f} and {sk['mean_global_horizontal_lx_luxtally']:.0f} lx).")
    out.append(f"- gendaymtx's patches (sky + sun spread over 4 patches) integrated with the patches' exact projected solid "
               f"angles, over its own global horizontal: {sk['global_horizontal_sum_ratio_patches_over_ground_row']:.4f}.")
    out.append(f"- the same with the sun in one patch (`-5 0.533`, its disc radiance spread over the patch) over the "
               f"default 4-patch sun: {sk['global_horizontal_sum_ratio_sun_one_patch_over_default']:.4f}.")
    out.append(f"- its sky alone (`-s`) so integrated, over the EPW's diffuse horizontal illuminance (field 19): "
               f"{sk['diffuse_horizontal_sum_radiance_sky_only_over_epw_field19']:.4f}.")
    out.append(f"- gendaymtx warned 'unusually bright' {R['gendaymtx']['unusually_bright_warnings']} times.")
    out.append("")
    b = r["budget"]
    out.append("## Expected luxtally / Radiance, term by term (ratio of the means)\n")
    out.append("| term | factor |")
    out.append("|---|---|")
    names = dict(sky_input="sky input: luxtally's global horizontal over gendaymtx's (ground row)",
                 sky_patches="gendaymtx's patches integrate to less than its own global horizontal",
                 polarisation="polarised pane stacking (luxtally) over unpolarised (Radiance), light let in",
                 centre_to_average="cell averages (luxtally) over centres (Radiance), from Radiance's curvature",
                 bounces="Radiance's deeper run over run a (-ab limit)")
    for k, x in b["terms"].items():
        out.append(f"| {names.get(k, k)} | {x:.4f} |")
    out.append(f"| **product (expected)** | **{b['expected_ratio']:.4f}** |")
    out.append(f"| measured ratio of the means | {C['ratio_of_means']:.4f} |")
    if b["light_in"]:
        li = b["light_in"]
        out.append("")
        out.append("Polarised / unpolarised light let in by part (patch centres, window obstructions by 12 × 6 points): "
                   + ", ".join(f"{k} {v['ratio']:.4f}" for k, v in li.items() if v["ratio"])
                   + f"; the sun's share of Radiance's annual mean (run a) {b['sun_share_radiance']:.1%}.")
    out.append("")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()

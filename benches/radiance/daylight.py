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


def blacken(rad_text):
    """The same scene with every plastic black: with -ab 1, Radiance's sky component."""
    out, lines = [], rad_text.split("\n")
    for k, line in enumerate(lines):
        if k >= 3 and lines[k - 3].startswith("void plastic ") and line.startswith("5 "):
            line = "5 0 0 0 0 0"
        out.append(line)
    return "\n".join(out)


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


# --- the sky component by quadrature ----------------------------------------------
def pane_TR(cos_i, tn, n=1.52):
    """One pane of transmissivity tn at incidence cos_i: [(T, R) for s, p], the internal
    reflections summed (docs/daylight.md, *Glazing*; Radiance's glass does the same)."""
    sin_t = math.sqrt(max(0.0, 1 - cos_i * cos_i)) / n
    cos_t = math.sqrt(1 - sin_t * sin_t)
    rs = ((cos_i - n * cos_t) / (cos_i + n * cos_t)) ** 2
    rp = ((n * cos_i - cos_t) / (n * cos_i + cos_t)) ** 2
    tau = tn ** (1 / cos_t)
    return [((1 - r) ** 2 * tau / (1 - r * r * tau * tau),
             r + r * (1 - r) ** 2 * tau * tau / (1 - r * r * tau * tau)) for r in (rs, rp)]


def stack_T(cos_i, tns):
    """Transmittance of panes in series: (polarised, unpolarised). Polarised: the adding
    formula per polarisation, then the mean (luxtally). Unpolarised: each pane's mean T
    and R combined by the same formula, as rays without a polarisation state (Radiance's
    glass polygons one behind the other) see them."""
    per = [pane_TR(cos_i, tn) for tn in tns]
    pol = []
    for k in (0, 1):
        T, R = per[0][k]
        for q in per[1:]:
            Tb, Rb = q[k]
            T, R = T * Tb / (1 - R * Rb), R + T * T * Rb / (1 - R * Rb)
        pol.append(T)
    T, R = (per[0][0][0] + per[0][1][0]) / 2, (per[0][0][1] + per[0][1][1]) / 2
    for q in per[1:]:
        Tb, Rb = (q[0][0] + q[1][0]) / 2, (q[0][1] + q[1][1]) / 2
        T, R = T * Tb / (1 - R * Rb), R + T * T * Rb / (1 - R * Rb)
    return (pol[0] + pol[1]) / 2, T


def window_flux_ratio(lz, lg, tns, n_th=400, n_ph=400):
    """Flux through a vertical glazed opening from the unobstructed sky (type 16, above
    the horizon) and ground (below): polarised over unpolarised stacking, and the
    polarised flux over the unglazed flux (the mean transmittance). Midpoint rule in the
    angle from the window normal and the azimuth about it."""
    fp = fu = f0 = 0.0
    for a in range(n_th):
        th = (a + 0.5) * (math.pi / 2) / n_th
        tp, tu = stack_T(math.cos(th), tns)
        for b in range(n_ph):
            ph = (b + 0.5) * 2 * math.pi / n_ph
            dz = math.sin(th) * math.sin(ph)  # the direction's vertical component
            lum = lz * (1 + 2 * dz) / 3 if dz > 0 else lg
            w = lum * math.cos(th) * math.sin(th)
            fp += w * tp
            fu += w * tu
            f0 += w
    return fp / fu, fp / f0, fu / f0


def hits_quad(o, d, quad):
    c = quad[0]
    u, v = sub(quad[1], c), sub(quad[3], c)
    n = cross(u, v)
    den = dot(n, d)
    if abs(den) < 1e-15:
        return False
    t = dot(n, sub(c, o)) / den
    if t <= 1e-9:
        return False
    p = sub(add(o, scale(d, t)), c)
    su, sv = dot(p, u) / dot(u, u), dot(p, v) / dot(v, v)
    return 0 <= su <= 1 and 0 <= sv <= 1


def sky_component_quadrature(scene, rec, lz, eh, tns_by_mat, nw=(48, 24), sub_pts=2):
    """DF sky component of each cell (its average, sub_pts x sub_pts points) through the
    glazed rects by the midpoint rule over each window (nw points), the sky's type 16
    luminance, the panes' T at the window, blocked by every quad outside the window's
    plane. Returns (polarised, unpolarised) lists, in %. Receiver points must see the
    window from below its sill or through it only upwards (true here: z 0.8, sill 0.9)."""
    quads = []
    for obj in scene["objects"]:
        if obj["material"] in tns_by_mat:
            continue
        if obj["shape"] == "rect":
            c, u, v = (tuple(map(float, obj[q])) for q in ("corner", "u", "v"))
            quads.append([c, add(c, u), add(add(c, u), v), add(c, v)])
        else:
            (x0, y0, z0), (x1, y1, z1) = tuple(map(float, obj["min"])), tuple(map(float, obj["max"]))
            for q in ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)],
                      [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],
                      [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)],
                      [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)],
                      [(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)],
                      [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)]):
                quads.append(q)
    rc, ru, rv = (tuple(map(float, rec[k])) for k in ("corner", "u", "v"))
    nu, nv = rec["cells"]
    rn = cross(ru, rv)
    rn = scale(rn, 1 / math.sqrt(dot(rn, rn)))
    pol_out, unp_out = [0.0] * (nu * nv), [0.0] * (nu * nv)
    for obj in scene["objects"]:
        if obj["material"] not in tns_by_mat or obj["shape"] != "rect":
            continue
        tns = tns_by_mat[obj["material"]]
        wc, wu, wv = (tuple(map(float, obj[q])) for q in ("corner", "u", "v"))
        wn = cross(wu, wv)
        warea = math.sqrt(dot(wn, wn))
        wn = scale(wn, 1 / warea)
        centre = add(rc, scale(add(ru, rv), 0.5))
        if dot(sub(centre, wc), wn) > 0:
            wn = scale(wn, -1)  # wn points outwards
        outside = [q for q in quads
                   if any(dot(sub(p, wc), wn) > 1e-9 for p in q)]
        wpts = [add(add(wc, scale(wu, (a + 0.5) / nw[0])), scale(wv, (b + 0.5) / nw[1]))
                for b in range(nw[1]) for a in range(nw[0])]
        da = warea / (nw[0] * nw[1])
        cache = {}
        for j in range(nv):
            for i in range(nu):
                ep = eu = 0.0
                for sj in range(sub_pts):
                    for si in range(sub_pts):
                        p = add(add(rc, scale(ru, (i + (si + 0.5) / sub_pts) / nu)),
                                scale(rv, (j + (sj + 0.5) / sub_pts) / nv))
                        for w in wpts:
                            d = sub(w, p)
                            r2 = dot(d, d)
                            d = scale(d, 1 / math.sqrt(r2))
                            cos_w = dot(d, wn)
                            cos_p = dot(d, rn)
                            if cos_w <= 0 or cos_p <= 0:
                                continue
                            if any(hits_quad(w, d, q) for q in outside):
                                continue
                            lum = lz * (1 + 2 * d[2]) / 3 if d[2] > 0 else None
                            if lum is None:
                                continue  # (not met here: the window is above the plane)
                            key = round(cos_w, 5)
                            if key not in cache:
                                cache[key] = stack_T(cos_w, tns)
                            tp, tu = cache[key]
                            g = lum * cos_p * cos_w / r2 * da
                            ep += g * tp
                            eu += g * tu
                k = sub_pts * sub_pts
                pol_out[j * nu + i] += 100 * ep / k / eh
                unp_out[j * nu + i] += 100 * eu / k / eh
    return pol_out, unp_out


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
        m2 = sum(m[i] ** 2 for i in idx)
        rel = math.sqrt(sum(d[i] ** 2 for i in idx) / 4 / m2) if m2 > 0 else 0.0
        for i in idx:
            cell_sig[i] = rel * m[i]
    return dict(values=m, noise=noise, mean=mean_all, mean_sigma=sig_mean, rows=rows,
                rows_sigma=rows_sig, cell_sigma=cell_sig)


def centre_to_average(values, nu, nv):
    """Estimated cell average minus cell centre value of a smooth field sampled at the
    centres: (hu^2 f_uu + hv^2 f_vv)/24, the second differences from the neighbours
    (the edge cells take their inner neighbour's). luxtally scores cell averages,
    Radiance the centres; this is the leading term of the difference."""
    f = lambda i, j: values[j * nu + i]  # noqa: E731
    out = [0.0] * (nu * nv)
    for j in range(nv):
        for i in range(nu):
            ic = min(max(i, 1), nu - 2)
            jc = min(max(j, 1), nv - 2)
            duu = f(ic - 1, j) - 2 * f(ic, j) + f(ic + 1, j)  # = hu^2 f_uu
            dvv = f(i, jc - 1) - 2 * f(i, jc) + f(i, jc + 1)
            out[j * nu + i] = (duu + dvv) / 24
    return out


def runs_stats(runs, st, nu, nv):
    """Several independent runs (-u+): the mean over runs per point, and the sigmas of the
    mean and the row means from the spread of the runs' own means (so correlations
    between points within a run count)."""
    n = len(runs)
    vals = [sum(r[c] for r in runs) / n for c in range(nu * nv)]
    means = [mean(r) for r in runs]
    st = dict(st, values=vals, mean=mean(means), mean_sigma=statistics.stdev(means) / math.sqrt(n),
              mean_sigma_independent=st["mean_sigma"], run_means=means)
    rows, rows_sig = [], []
    for j in range(nv):
        rm = [mean(r[j * nu:(j + 1) * nu]) for r in runs]
        rows.append(mean(rm))
        rows_sig.append(statistics.stdev(rm) / math.sqrt(n))
    st["rows"], st["rows_sigma"] = rows, rows_sig
    return st


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
def run_luxtally(bin_path, scene, photons, threads, outdir):
    """A next-event run of `photons` (compare.py's runner)."""
    stop = ["--photons", str(photons), "--estimator", "next_event"]
    return compare.run_luxtally(bin_path, scene, stop, threads, outdir)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", type=Path, default=REPO / "scenes" / "daylit_office.toml")
    ap.add_argument("--target", type=float, default=0.02, help="per-point noise (default 0.02)")
    ap.add_argument("--ab", type=int, default=8)
    ap.add_argument("--lw", default="1e-5")
    ap.add_argument("--ad-start", type=int, default=256)
    ap.add_argument("--ad-max", type=int, default=1 << 20)
    ap.add_argument("--rad-budget", type=float, default=480, help="s of Radiance tracing in all (default 480)")
    ap.add_argument("--bias-ab", type=int, default=16,
                    help="one more run at the final -ad with this -ab, mean only (0: skip)")
    ap.add_argument("--sc-ad", type=int, default=8192, help="-ad of the black-scene sky-component run")
    ap.add_argument("--sc-runs", type=int, default=4, help="independent runs of the sky-component traces")
    ap.add_argument("--sc-sub", type=int, default=4, help="points per cell side for the sky component's cell averages")
    ap.add_argument("--quad-nw", type=int, default=48, help="window points across (half as many up)")
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
                   mean_df_sigma=st["mean_sigma"], run_means=[mean(dfa), mean(dfb)],
                   run_rows=[[mean(v[j * nu:(j + 1) * nu]) for j in range(nv)] for v in (dfa, dfb)],
                   rows_sigma_independent=st["rows_sigma"])
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
    # Radiance's points are not independent within a run (the same sampling pattern at
    # every point, it seems): the run means differ by more than the points' noise/sqrt n
    # says. Inflation factors pooled over the whole -ad search (one pair per -ad):
    # |mean_a - mean_b|/2 against the independent-points sigma of the two-run mean.
    f_mean = compare.rms([abs(r["run_means"][0] - r["run_means"][1]) / 2 / r["mean_df_sigma"] for r in search])
    f_rows = compare.rms([abs(r["run_rows"][0][j] - r["run_rows"][1][j]) / 2 / r["rows_sigma_independent"][j]
                          for r in search for j in range(nv) if r["rows_sigma_independent"][j] > 0])
    rad["mean_sigma_independent"] = rad["mean_sigma"]
    rad["rows_sigma_independent"] = list(rad["rows_sigma"])
    rad["mean_sigma"] = rad["mean_sigma"] * max(1.0, f_mean)
    rad["rows_sigma"] = [x * max(1.0, f_rows) for x in rad["rows_sigma"]]
    log(f"Radiance run-to-run: the mean's sigma is {f_mean:.2f}x, the rows' {f_rows:.2f}x the "
        f"independent-points figure ({len(search)} pairs); using max(1, factor)")

    # How much light -ab leaves out: one run at the final -ad with more ambient bounces
    # (-lr 0: beyond -lw, Russian roulette, so -ab is the only truncation). Its mean only.
    bias = None
    if a.bias_ab:
        args = ["-ab", str(a.bias_ab), "-aa", "0", "-ad", str(final["ad"]), "-as", "0", "-lr", "0",
                "-lw", a.lw, "-u+", "-n", str(a.procs)]
        vc, tc, ccmd = rtrace(tools, work / "daylit_office.oct", points_text, args, work)
        dfc = [100 * x / eh for x in vc]
        mc = mean(dfc)
        # its sigma: one run's noise is sqrt 2 times the two-run mean's
        sc = rad["mean_sigma"] * math.sqrt(2)
        bias = dict(cmd=ccmd, time_s=tc, mean_df=mc, mean_df_sigma=sc, diff=mc - rad["mean"],
                    diff_sigma=math.hypot(sc, rad["mean_sigma"]))
        log(f"rtrace -ab {a.bias_ab}: {tc:.1f} s; mean DF {mc:.4f} ± {sc:.4f} % "
            f"({mc - rad['mean']:+.4f} ± {bias['diff_sigma']:.4f} against -ab {a.ab})")

    # Radiance's sky component: the same scene with black plastics, -ab 1, two runs.
    (work / "daylit_office_black.rad").write_text(blacken(text))
    oconv(tools, [work / "sky16.rad", work / "daylit_office_black.rad"], work / "black.oct", work)
    sc_args = ["-ab", "1", "-aa", "0", "-ad", str(a.sc_ad), "-as", "0", "-lr", "0", "-lw", "1e-6",
               "-u+", "-n", str(a.procs)]
    sc_runs = [rtrace(tools, work / "black.oct", points_text, sc_args, work) for _ in range(a.sc_runs)]
    (sa, tsa, sc_cmd), (sb, tsb, _) = sc_runs[0], sc_runs[1]
    sc_st = rad_stats([100 * x / eh for x in sa], [100 * x / eh for x in sb], nu, nv)
    sc_st = runs_stats([[100 * x / eh for x in r[0]] for r in sc_runs], sc_st, nu, nv)
    log(f"Radiance sky component (black plastics, -ab 1 -ad {a.sc_ad}): {tsa:.1f}, {tsb:.1f} s; "
        f"noise {sc_st['noise']:.3%}; mean {sc_st['mean']:.4f} ± {sc_st['mean_sigma']:.4f} %")
    # ... and as cell averages, like luxtally's: k x k points per cell, -ad halved
    k = a.sc_sub
    rc, ru, rv = (tuple(map(float, rec[q])) for q in ("corner", "u", "v"))
    sub_pts = [add(add(rc, scale(ru, (i + (si + 0.5) / k) / nu)), scale(rv, (j + (sj + 0.5) / k) / nv))
               for j in range(nv) for i in range(nu) for sj in range(k) for si in range(k)]
    sub_text = "".join(f"{x:.6f} {y:.6f} {z:.6f} {nx:g} {ny:g} {nz:g}\n" for x, y, z in sub_pts)
    avg_args = list(sc_args)
    avg_args[avg_args.index("-ad") + 1] = str(max(256, a.sc_ad // 4))
    avg_runs = [rtrace(tools, work / "black.oct", sub_text, avg_args, work) for _ in range(a.sc_runs)]
    (ua, tua, _), (ub, tub, _) = avg_runs[0], avg_runs[1]
    cell_avg = lambda v: [100 * sum(v[c * k * k:(c + 1) * k * k]) / (k * k) / eh for c in range(nu * nv)]  # noqa: E731
    sc_avg = rad_stats(cell_avg(ua), cell_avg(ub), nu, nv)
    sc_avg = runs_stats([cell_avg(r[0]) for r in avg_runs], sc_avg, nu, nv)
    log(f"Radiance sky component, cell averages ({k}x{k} points, -ad {avg_args[avg_args.index('-ad') + 1]}): "
        f"{tua:.1f}, {tub:.1f} s; noise {sc_avg['noise']:.3%}; mean {sc_avg['mean']:.4f} ± {sc_avg['mean_sigma']:.4f} %")

    # Polarisation: luxtally stacks panes per polarisation, Radiance's rays have none.
    tns_by_mat = {k: g["tn"] for k, g in glass_info.items()}
    t0 = time.perf_counter()
    q_pol, q_unp = sky_component_quadrature(scene, rec, lz, eh, tns_by_mat, nw=(a.quad_nw, a.quad_nw // 2),
                                            sub_pts=1)
    pol_ratio = [p / u if u > 0 else None for p, u in zip(q_pol, q_unp)]
    pol_ratio_mean = sum(q_pol) / sum(q_unp)
    tns0 = next(iter(tns_by_mat.values()))
    wf = window_flux_ratio(lz, rho_g * eh / math.pi, tns0)
    log(f"quadrature ({time.perf_counter() - t0:.1f} s): sky component polarised/unpolarised "
        f"{pol_ratio_mean - 1:+.3%} over the mean (midpoint {a.quad_nw}x{a.quad_nw // 2} over the window); "
        f"window flux, unobstructed: polarised/unpolarised {wf[0] - 1:+.3%}, mean T {wf[1]:.4f} / {wf[2]:.4f}")

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
        ssig = math.sqrt(sum((sky_sig[i] or 0.0) ** 2 for i in idx)) / nu
        rad_sc = sc_st["rows"][j]
        pr = sum(q_pol[i] for i in idx) / sum(q_unp[i] for i in idx) if sum(q_unp[i] for i in idx) > 0 else 1.0
        exp_sc = sc_avg["rows"][j] * pr
        exp_sc_sig = sc_avg["rows_sigma"][j] * pr
        z_sc = (srow - exp_sc) / math.hypot(ssig, exp_sc_sig) if math.hypot(ssig, exp_sc_sig) > 0 else 0.0
        rows.append(dict(j=j, y=y, lux=lrow, lux_sigma=lsig, lux_sky=srow, lux_sky_sigma=ssig,
                         lux_reflected=rrow, rad=rad["rows"][j], rad_sigma=rad["rows_sigma"][j], z=z,
                         rad_sky=rad_sc, rad_sky_sigma=sc_st["rows_sigma"][j], pol_ratio=pr,
                         rad_sky_avg=sc_avg["rows"][j], rad_sky_avg_sigma=sc_avg["rows_sigma"][j],
                         sky_expected=exp_sc, sky_expected_sigma=exp_sc_sig, z_sky=z_sc,
                         rad_reflected=rad["rows"][j] - rad_sc,
                         rad_reflected_sigma=math.hypot(rad["rows_sigma"][j], sc_st["rows_sigma"][j])))
    z_rows_rms = compare.rms([row["z"] for row in rows])
    # (c) cells
    zc = [(lv[i] - rad["values"][i]) / math.hypot(ls[i], rad["cell_sigma"][i]) for i in ok]
    z_cells_rms = compare.rms(zc)
    rel_mean = lm["value"] / rad["mean"] - 1
    # components over all cells
    lux_sky_mean = mean(sky)
    lux_sky_mean_sig = math.sqrt(sum((x or 0.0) ** 2 for x in sky_sig)) / len(sky)  # as if independent
    lux_refl_mean = mean(refl)
    rad_sky_mean, rad_sky_sig = sc_st["mean"], sc_st["mean_sigma"]
    rad_refl_mean = rad["mean"] - rad_sky_mean
    z_sky_rows_rms = compare.rms([row["z_sky"] for row in rows])
    sky_avg_pol = sc_avg["mean"] * pol_ratio_mean
    z_sky_mean = (lux_sky_mean - sky_avg_pol) / math.hypot(lux_sky_mean_sig, sc_avg["mean_sigma"] * pol_ratio_mean)
    # The expected difference, term by term (approximate: see README)
    budget = dict(
        polarisation_sky=sc_avg["mean"] * (pol_ratio_mean - 1),
        centre_to_average_sky=sc_avg["mean"] - sc_st["mean"],
        polarisation_reflected_unobstructed=rad_refl_mean * (wf[0] - 1),
        more_bounces=bias["diff"] if bias else 0.0,
        more_bounces_sigma=bias["diff_sigma"] if bias else 0.0,
    )
    budget["total"] = (budget["polarisation_sky"] + budget["centre_to_average_sky"]
                       + budget["polarisation_reflected_unobstructed"] + budget["more_bounces"])
    z_budget = (lm["value"] - rad["mean"] - budget["total"]) / math.sqrt(
        lux_mean_sig ** 2 + rad["mean_sigma"] ** 2 + budget["more_bounces_sigma"] ** 2)
    rad_refl_sig = math.hypot(rad["mean_sigma"], rad_sky_sig)
    lux_refl_sig = math.sqrt(max(0.0, lux_mean_sig ** 2 - lux_sky_mean_sig ** 2))
    # Centres against averages: Radiance's centres shifted by the estimated difference
    # (second differences of its own two-run mean; its noise enters them, not counted).
    corr = centre_to_average(rad["values"], nu, nv)
    corr_mean = mean(corr)
    z_mean_c = (lm["value"] - rad["mean"] - corr_mean) / math.hypot(lux_mean_sig, rad["mean_sigma"])
    for j, row in enumerate(rows):
        row["rad_centre_to_average"] = mean(corr[j * nu:(j + 1) * nu])
        row["z_corrected"] = (row["lux"] - row["rad"] - row["rad_centre_to_average"]) / math.hypot(
            row["lux_sigma"], row["rad_sigma"])
    z_rows_rms_c = compare.rms([row["z_corrected"] for row in rows])
    zc_c = [(lv[i] - rad["values"][i] - corr[i]) / math.hypot(ls[i], rad["cell_sigma"][i]) for i in ok]
    z_cells_rms_c = compare.rms(zc_c)

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
          f"z = {z_mean:+.2f} (σ_lux {lux_mean_sig:.4f} from its interval, σ_rad {rad['mean_sigma']:.4f}: "
          f"{max(1.0, f_mean):.2f} × {rad['mean_sigma_independent']:.4f}, the independent-points figure, by the "
          f"run-to-run spread over the -ad search; rows × {max(1.0, f_rows):.2f}); "
          f"row-mean z RMS {z_rows_rms:.2f} over {nv} rows; cell z RMS {z_cells_rms:.2f} over {len(ok)} cells.")
    print(f"Components over the cells: sky component luxtally {lux_sky_mean:.4f} ± {lux_sky_mean_sig:.4f} % "
          f"(cells as independent), Radiance {rad_sky_mean:.4f} ± {rad_sky_sig:.4f} % "
          f"(black plastics, `-ab 1 -ad {a.sc_ad}`): {lux_sky_mean / rad_sky_mean - 1:+.2%}, of which the "
          f"polarisation accounts for {pol_ratio_mean - 1:+.2%} (quadrature); reflected luxtally "
          f"{lux_refl_mean:.4f} ± {lux_refl_sig:.4f} %, Radiance (total − sky component) {rad_refl_mean:.4f} ± "
          f"{rad_refl_sig:.4f} %: {lux_refl_mean / rad_refl_mean - 1:+.2%}; unobstructed window flux "
          f"polarised/unpolarised {wf[0] - 1:+.2%}.")
    print(f"Sky component against Radiance's cell averages ({k}×{k} points) × the polarisation ratio: "
          f"mean luxtally {lux_sky_mean:.4f} vs {sky_avg_pol:.4f} % (z {z_sky_mean:+.2f}, luxtally's cells as "
          f"independent); row z RMS {z_sky_rows_rms:.2f}.")
    print(f"Expected luxtally − Radiance (-ab {a.ab}) on the mean, term by term: polarisation, sky component "
          f"{budget['polarisation_sky']:+.4f}; centres→averages, sky component {budget['centre_to_average_sky']:+.4f}; "
          f"polarisation of the light let in (reflected × unobstructed window-flux ratio) "
          f"{budget['polarisation_reflected_unobstructed']:+.4f}; -ab {a.bias_ab} over -ab {a.ab} "
          f"{budget['more_bounces']:+.4f} ± {budget['more_bounces_sigma']:.4f}; total {budget['total']:+.4f} %, "
          f"against {lm['value'] - rad['mean']:+.4f} % measured: z {z_budget:+.2f}.")
    print(f"With Radiance's centres moved to cell averages (estimated, mean {corr_mean:+.4f} %): "
          f"mean z = {z_mean_c:+.2f}, row-mean z RMS {z_rows_rms_c:.2f}, cell z RMS {z_cells_rms_c:.2f}.")
    print()
    print("| row j | y (m) | Radiance DF (%) | luxtally DF (%) | z | centre→average | z, corrected "
          "| sky comp. Radiance | sky comp. luxtally | pol. ratio | reflected Radiance | reflected luxtally |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for row in rows:
        print(f"| {row['j']} | {row['y']:.3f} | {row['rad']:.3f} ± {row['rad_sigma']:.3f} | "
              f"{row['lux']:.3f} ± {row['lux_sigma']:.3f} | {row['z']:+.2f} | "
              f"{row['rad_centre_to_average']:+.4f} | {row['z_corrected']:+.2f} | "
              f"{row['rad_sky']:.4f} ± {row['rad_sky_sigma']:.4f} | {row['lux_sky']:.4f} ± {row['lux_sky_sigma']:.4f} | "
              f"{row['pol_ratio']:.4f} | {row['rad_reflected']:.3f} ± {row['rad_reflected_sigma']:.3f} | "
              f"{row['lux_reflected']:.3f} |")
    print()
    print("| row j | sky comp. Radiance, cell averages | × pol. ratio | luxtally | z |")
    print("|---:|---:|---:|---:|---:|")
    for row in rows:
        if row["rad_sky_avg"] > 0 or row["lux_sky"] > 0:
            print(f"| {row['j']} | {row['rad_sky_avg']:.4f} ± {row['rad_sky_avg_sigma']:.4f} | "
                  f"{row['sky_expected']:.4f} | {row['lux_sky']:.4f} ± {row['lux_sky_sigma']:.4f} | {row['z_sky']:+.2f} |")
    print()
    print("| -ad | run times (s) | noise | mean DF (%) |")
    print("|---:|---|---:|---:|")
    for row in search:
        print(f"| {row['ad']} | {row['times_s'][0]:.1f}, {row['times_s'][1]:.1f} | {row['noise']:.2%} | "
              f"{row['mean_df']:.4f} ± {row['mean_df_sigma']:.4f} |")
    print()
    if bias:
        print(f"More bounces (`rtrace {' '.join(bias['cmd'][1:-1])}`, {bias['time_s']:.1f} s, one run): "
              f"mean DF {bias['mean_df']:.4f} ± {bias['mean_df_sigma']:.4f} %, "
              f"{bias['diff']:+.4f} ± {bias['diff_sigma']:.4f} % against -ab {a.ab}.")
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
                          mean_sigma=rad["mean_sigma"], mean_sigma_independent=rad["mean_sigma_independent"],
                          sigma_inflation=dict(mean=f_mean, rows=f_rows), noise=rad["noise"], more_bounces=bias,
                          sky_component=dict(cmd=sc_cmd, times_s=[tsa, tsb], noise=sc_st["noise"],
                                             mean=rad_sky_mean, mean_sigma=rad_sky_sig, values=sc_st["values"],
                                             cell_average=dict(points_per_side=k, args=avg_args, times_s=[tua, tub],
                                                               noise=sc_avg["noise"], mean=sc_avg["mean"],
                                                               mean_sigma=sc_avg["mean_sigma"],
                                                               values=sc_avg["values"]))),
            quadrature=dict(sky_polarised=q_pol, sky_unpolarised=q_unp, ratio_mean=pol_ratio_mean,
                            window_flux=dict(pol_over_unpol=wf[0], mean_T_pol=wf[1], mean_T_unpol=wf[2])),
            luxtally=dict(cmd=lux_cmd, photons=s["photons_emitted"], elapsed_s=s["elapsed_s"],
                          setup_s=s["setup_s"], direct_s=s.get("direct_s"), process_s=lux_wall,
                          probe_rate_per_s=rate, mean=lm, mean_sigma=lux_mean_sig,
                          median_rel_sigma=lux_median_rel, quadratic_rel_sigma=lux_quadratic,
                          sky_median_rel_sigma=sky_median_rel, time_to_target_median_s=t_lux_median,
                          time_to_target_quadratic_s=t_lux_quadratic, sky_time_to_target_s=t_sky,
                          values=lv, sigma=ls, sky_component=sky, reflected=refl, sky_sigma=sky_sig),
            components=dict(lux_sky=lux_sky_mean, lux_sky_sigma=lux_sky_mean_sig, rad_sky=rad_sky_mean,
                            rad_sky_sigma=rad_sky_sig, lux_reflected=lux_refl_mean, lux_reflected_sigma=lux_refl_sig,
                            rad_reflected=rad_refl_mean, rad_reflected_sigma=rad_refl_sig,
                            z_sky_mean=z_sky_mean, z_sky_rows_rms=z_sky_rows_rms, budget=budget, z_budget=z_budget),
            agreement=dict(mean_diff=lm["value"] - rad["mean"], mean_rel=rel_mean, z_mean=z_mean,
                           rows=rows, z_rows_rms=z_rows_rms, z_cells_rms=z_cells_rms, cells_compared=len(ok),
                           centre_to_average=corr, centre_to_average_mean=corr_mean, z_mean_corrected=z_mean_c,
                           z_rows_rms_corrected=z_rows_rms_c, z_cells_rms_corrected=z_cells_rms_c),
            target=a.target,
        ), indent=1))


if __name__ == "__main__":
    main()

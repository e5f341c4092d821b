#!/usr/bin/env python3
"""gendaymtx's sun, hour by hour, against `luxtally annual`'s hours CSV.

Runs `gendaymtx -D suns.rad -M suns.mod -d -O0 -of EPW` (Radiance's 5-phase sun file: one
0.533-degree `light` source per record with the sun up, id = solar minute 1440(jd - 1) +
round(60 hr), radiance dir_illum / (179 pi r^2), r = 0.2665 deg) and the ground row of
`gendaymtx -m 1 -O0` (rho (E_d + E_n sin h) / pi), and compares per record with luxtally's
`annual_<rec>_hours.csv` (sun_altitude_deg, sun_azimuth_deg, direct_normal_lx,
diffuse_horizontal_lx, global_horizontal_lx): the angle between the sun directions, the
direct normal illuminance, E_dn sin h and the diffuse; sums by month and by altitude band.

Then it re-computes both tools' Perez efficacies in Python (gendaymtx.c's ComputeSky:
Kasten 1966 air mass, the dew point averaged over the record and the two before it,
clearness clamped to [1, 11.9], brightness to [0.01, 0.6]; luxtally's src/light/perez.rs:
Kasten & Young 1989, the hour's own dew point, brightness >= 0.01 only) and swaps the
ingredients one at a time from gendaymtx's to luxtally's, to say which of them makes the
difference. Standard library; see benches/radiance/README.md.
"""

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import annual  # noqa: E402
import compare  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
WHTEFFICACY = 179.0
SUN_R = math.radians(0.533 / 2)
SUN_SA = math.pi * SUN_R * SUN_R  # gendaymtx's OutputSun: pi r^2

CLEAR_BOUNDS = [1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200]
DIFF_EFF = [(97.24, -0.46, 12.00, -8.91), (107.22, 1.15, 0.59, -3.95), (104.97, 2.96, -5.53, -8.77),
            (102.39, 5.59, -13.95, -13.90), (100.71, 5.94, -22.75, -23.74), (106.42, 3.83, -36.15, -28.83),
            (141.88, 1.90, -53.24, -14.03), (152.23, 0.35, -45.27, -7.98)]
DIR_EFF = [(57.20, -4.55, -2.98, 117.12), (98.99, -3.46, -1.21, 12.38), (109.83, -4.90, -1.71, -8.81),
           (110.34, -5.84, -1.99, -4.56), (106.36, -3.97, -1.75, -6.16), (107.19, -1.25, -1.51, -26.73),
           (105.75, 0.77, -1.26, -34.44), (101.18, 1.58, -1.10, -8.29)]
MONTH_DAYS = [31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31]


def jdate(mo, da):
    return sum(MONTH_DAYS[:mo - 1]) + da


def eccentricity(jd):
    g = (jd - 1.0) * 2 * math.pi / 365.0
    return 1.00011 + 0.034221 * math.cos(g) + 0.00128 * math.sin(g) + 0.000719 * math.cos(2 * g) + 0.000077 * math.sin(2 * g)


def air_mass(z, model):
    zd = math.degrees(z)
    if model == "kasten1966":  # gendaymtx.c CalcAirMass
        return 1.0 / (math.cos(z) + 0.15 * (93.885 - zd) ** -1.253)
    return 1.0 / (math.cos(z) + 0.50572 * (96.07995 - zd) ** -1.6364)  # luxtally: Kasten & Young 1989


def efficacies(dni, dhi, z, jd, dew, airmass, clamps):
    """(K_d, K_b) in lm/W. clamps 'gendaymtx': eps in [1, 11.9], delta in [0.01, 0.6] (both
    efficacies); 'luxtally': delta >= 0.01 for the efficacies, eps as is."""
    k = 1.041 * z ** 3
    eps = ((dhi + dni) / dhi + k) / (1 + k)
    delta = dhi * air_mass(z, airmass) / (1367.0 * eccentricity(jd))
    if clamps == "gendaymtx":
        eps = min(max(eps, 1.0), 11.9)
        delta = min(max(delta, 0.01), 0.6)
    else:
        delta = max(delta, 0.01)
    cat = sum(1 for b in CLEAR_BOUNDS if eps >= b)
    w = math.exp(0.07 * dew - 0.075)
    a, b, c, d = DIFF_EFF[cat]
    kd = a + b * w + c * math.cos(z) + d * math.log(delta)
    a, b, c, d = DIR_EFF[cat]
    kb = max(a + b * w + c * math.exp(5.73 * z - 5.0) + d * delta, 0.0)
    return kd, kb


def read_epw(path):
    recs = []
    with open(path, newline="") as f:
        for k, line in enumerate(f):
            if k < 8:
                continue
            p = line.split(",")
            if len(p) < 20:
                continue
            recs.append(dict(month=int(p[1]), day=int(p[2]), hour=int(p[3]), dew=float(p[7]),
                             dni=float(p[14]), dhi=float(p[15])))
    return recs


def gendaymtx_dew(recs):
    """gendaymtx.c: dew_point = (d[-2] + d[-1] + d[0]) / 3, the first record's history = itself."""
    out, hist = [], None
    for r in recs:
        d = r["dew"]
        if d >= 99.9:  # missing: loadEPW leaves it unset; gendaymtx resets the history
            out.append(11.0)
            hist = None
            continue
        if hist is None:
            hist = [d, d]
        out.append((hist[0] + hist[1] + d) / 3)
        hist = [hist[1], d]
    return out


def read_suns(path):
    """{solar minute id: (unit vector (x east, y north, z up), radiance)}."""
    toks = Path(path).read_text().split()
    suns, rad = {}, {}
    i = 0
    while i < len(toks):
        if toks[i] == "light":
            name = toks[i + 1]
            rad[name] = float(toks[i + 5])
            i += 9
        elif toks[i] == "source":
            mod, name = toks[i - 1], toks[i + 1]
            v = tuple(float(x) for x in toks[i + 5:i + 8])
            suns[int(mod[5:])] = (v, rad[mod])
            i += 9
        else:
            i += 1
    return suns


def vec(alt_deg, az_deg):
    a, z = math.radians(alt_deg), math.radians(az_deg)
    return (math.cos(a) * math.sin(z), math.cos(a) * math.cos(z), math.sin(a))


def angle_deg(u, v):
    d = sum(x * y for x, y in zip(u, v))
    n = math.sqrt(sum(x * x for x in u) * sum(x * x for x in v))
    return math.degrees(math.acos(max(-1.0, min(1.0, d / n))))


def almanac_sun(year, month, day, hour_lst, lat, lon_east, tz_h):
    """The Astronomical Almanac's low-precision sun (about 0.01 deg, 1950-2050), no
    refraction: (x east, y north, z up). A third opinion between the two tools."""
    y, m = (year - 1, month + 12) if month <= 2 else (year, month)
    jd0 = int(365.25 * (y + 4716)) + int(30.6001 * (m + 1)) + day - 1524.5 + 2 - y // 100 + y // 400
    jd = jd0 + (hour_lst - tz_h) / 24.0
    n = jd - 2451545.0
    L = math.radians((280.460 + 0.9856474 * n) % 360)
    g = math.radians((357.528 + 0.9856003 * n) % 360)
    lam = L + math.radians(1.915) * math.sin(g) + math.radians(0.020) * math.sin(2 * g)
    eps = math.radians(23.439 - 4e-7 * n)
    ra = math.atan2(math.cos(eps) * math.sin(lam), math.cos(lam))
    dec = math.asin(math.sin(eps) * math.sin(lam))
    gmst = (18.697374558 + 24.06570982441908 * n) % 24
    ha = math.radians(gmst * 15 + lon_east) - ra
    phi = math.radians(lat)
    z = math.sin(phi) * math.sin(dec) + math.cos(phi) * math.cos(dec) * math.cos(ha)
    x = -math.cos(dec) * math.sin(ha)  # east
    yv = math.cos(phi) * math.sin(dec) - math.sin(phi) * math.cos(dec) * math.cos(ha)  # north
    return (x, yv, z)


def radiance_sun(jd, hr, lat, lon_east, tz_h):
    """Radiance's sun.c as gendaymtx calls it (sdec, stadj, salt, sazi from the day of
    the year; 6.0a's sdec has 365, not 368): (x east, y north, z up)."""
    s_lat, s_lon, s_mer = math.radians(lat), math.radians(-lon_east), math.radians(-15.0 * tz_h)
    sd = 0.4093 * math.sin((2 * math.pi / 365) * (jd - 81))
    st = hr + 0.170 * math.sin((4 * math.pi / 373) * (jd - 80)) - 0.129 * math.sin((2 * math.pi / 355) * (jd - 8)) \
        + 12 * (s_mer - s_lon) / math.pi
    alt = math.asin(math.sin(s_lat) * math.sin(sd) - math.cos(s_lat) * math.cos(sd) * math.cos(st * math.pi / 12))
    azi = -math.atan2(math.cos(sd) * math.sin(st * math.pi / 12),
                      -math.cos(s_lat) * math.sin(sd) - math.sin(s_lat) * math.cos(sd) * math.cos(st * math.pi / 12)) + math.pi
    return (math.cos(alt) * math.sin(azi), math.cos(alt) * math.cos(azi), math.sin(alt))


def epw_location(path):
    with open(path) as f:
        p = f.readline().split(",")
    return float(p[6]), float(p[7]), float(p[8])


def pct(xs, q):
    s = sorted(xs)
    if not s:
        return float("nan")
    return s[min(len(s) - 1, int(q * len(s)))]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", type=Path, default=REPO / "scenes" / "daylit_office_annual.toml")
    ap.add_argument("--workdir", type=Path, default=REPO / "target" / "radiance-annual")
    ap.add_argument("--lux-out", type=Path, help="luxtally annual output (default WORKDIR/lux)")
    ap.add_argument("--receiver", default="df_grid")
    ap.add_argument("--venv", type=Path, default=REPO / "target" / "radiance-compare" / "venv")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    import tomllib
    scene = tomllib.loads(a.scene.read_text())
    ann = scene["annual"]
    epw = (a.scene.resolve().parent / ann["weather"]).resolve()
    occ = [float(x) for x in ann.get("occupied_hours", [8.0, 18.0])]
    rho = float(ann.get("ground_reflectance", 0.2))
    work = a.workdir.resolve()
    work.mkdir(parents=True, exist_ok=True)
    lux_out = (a.lux_out or work / "lux").resolve()
    binpath, raypath, version = compare.setup_radiance(a.venv)
    os.environ["RAYPATH"] = "." + os.pathsep + raypath
    tools = annual.tools_in(binpath)
    g = f"{rho:g}"
    sun_cmd = [tools["gendaymtx"], "-D", "suns.rad", "-M", "suns.mod", "-d", "-O0", "-of", str(epw)]
    annual.run(sun_cmd, work, stdout_path=work / "sun_d_m1.mtx")
    gr_cmd = [tools["gendaymtx"], "-m", "1", "-g", g, g, g, "-O0", "-of", str(epw)]
    annual.run(gr_cmd, work, stdout_path=work / "sky_m1.mtx")
    ground, nr, nc, _, _ = annual.read_matrix(work / "sky_m1.mtx")
    suns = read_suns(work / "suns.rad")
    recs = read_epw(epw)
    assert nc == len(recs), (nc, len(recs))
    dew3 = gendaymtx_dew(recs)
    hours = annual.read_csv(lux_out / f"annual_{a.receiver}_hours.csv")
    lat, lon, tz = epw_location(epw)
    minutes = sorted({sid % 60 for sid in suns})
    replica_sun_max_deg = max(angle_deg(radiance_sun(sid // 1440 + 1, (sid % 1440) / 60, lat, lon, tz), v)
                              for sid, (v, _) in suns.items())
    assert len(hours) == len(recs)

    rows = []
    sets = dict(both=0, rad_only=0, lux_only=0, rad_sun_lux_dark=[], lux_sun_rad_dark=[])
    for k, (r, h) in enumerate(zip(recs, hours)):
        assert int(h["month"]) == r["month"] and int(h["day"]) == r["day"] and int(h["hour"]) == r["hour"]
        if not occ[0] <= r["hour"] - 0.5 < occ[1]:
            continue
        jd = jdate(r["month"], r["day"])
        sid = 1440 * (jd - 1) + int((r["hour"] - 0.5) * 60 + 0.5)
        s = suns.get(sid)
        e_rad_gh = ground[3 * k + 1] * math.pi / rho * WHTEFFICACY  # the ground row (grey)
        lux_lit = h["sun_altitude_deg"] != "" and float(h["global_horizontal_lx"]) > 0
        rad_lit = e_rad_gh > 0
        if lux_lit and rad_lit:
            sets["both"] += 1
        elif rad_lit:
            sets["rad_only"] += 1
        elif lux_lit:
            sets["lux_only"] += 1
        if not (lux_lit or rad_lit):
            continue
        row = dict(record=k, month=r["month"], day=r["day"], hour=r["hour"], jd=jd, dni=r["dni"], dhi=r["dhi"],
                   dew=r["dew"], dew3=dew3[k], lux_lit=lux_lit, rad_lit=rad_lit)
        if s is not None:
            v, L = s
            row["rad_vec"] = v
            row["rad_alt"] = math.degrees(math.asin(max(-1.0, min(1.0, v[2]))))
            row["rad_edn"] = L * SUN_SA * WHTEFFICACY  # grey: 0.265 + 0.670 + 0.065 = 1
        else:
            row["rad_vec"], row["rad_alt"], row["rad_edn"] = None, None, 0.0
        row["rad_gh"] = e_rad_gh
        row["rad_dir_h"] = row["rad_edn"] * max(row["rad_vec"][2], 0.0) if row["rad_vec"] else 0.0
        row["rad_dif"] = e_rad_gh - row["rad_dir_h"]
        if lux_lit:
            row["lux_alt"] = float(h["sun_altitude_deg"])
            row["lux_vec"] = vec(row["lux_alt"], float(h["sun_azimuth_deg"]))
            row["lux_edn"] = float(h["direct_normal_lx"])
            row["lux_dif"] = float(h["diffuse_horizontal_lx"])
            row["lux_gh"] = float(h["global_horizontal_lx"])
            row["lux_dir_h"] = row["lux_edn"] * row["lux_vec"][2]
        else:
            row["lux_alt"], row["lux_vec"] = None, None
            row["lux_edn"] = row["lux_dif"] = row["lux_gh"] = row["lux_dir_h"] = 0.0
            if rad_lit:
                sets["rad_sun_lux_dark"].append(dict(record=k, month=r["month"], day=r["day"], hour=r["hour"],
                                                     rad_alt=row["rad_alt"], rad_gh=e_rad_gh))
        if row["rad_vec"] and row["lux_vec"]:
            row["angle"] = angle_deg(row["rad_vec"], row["lux_vec"])
            alm = almanac_sun(2023, r["month"], r["day"], r["hour"] - 0.5, lat, lon, tz)
            row["angle_alm_lux"] = angle_deg(alm, row["lux_vec"])
            row["angle_alm_rad"] = angle_deg(alm, row["rad_vec"])
        rows.append(row)

    # --- the efficacy chain, gendaymtx -> luxtally, one ingredient at a time ----------
    steps = [("gendaymtx (replica)", dict(pos="rad", am="kasten1966", dew="dew3", cl="gendaymtx")),
             ("+ luxtally's sun position", dict(pos="lux", am="kasten1966", dew="dew3", cl="gendaymtx")),
             ("+ Kasten & Young air mass", dict(pos="lux", am="ky1989", dew="dew3", cl="gendaymtx")),
             ("+ the hour's own dew point", dict(pos="lux", am="ky1989", dew="dew", cl="gendaymtx")),
             ("+ luxtally's clamps (= luxtally)", dict(pos="lux", am="ky1989", dew="dew", cl="luxtally"))]
    both = [r for r in rows if r["lux_lit"] and r["rad_lit"] and r["rad_vec"] and r["dhi"] > 0]

    def model(r, st):
        v = r["rad_vec"] if st["pos"] == "rad" else r["lux_vec"]
        alt = math.asin(v[2])
        if st["pos"] == "rad":  # gendaymtx.c: zenith 90 below the horizon, 3 above 87 deg
            z = math.pi / 2 if alt <= 0 else (math.radians(3) if alt >= math.radians(87) else math.pi / 2 - alt)
        else:
            z = math.acos(min(v[2], 1.0))
        kd, kb = efficacies(r["dni"], r["dhi"], z, r["jd"], r[st["dew"]], st["am"], st["cl"])
        edn = kb * r["dni"]
        return edn, edn * max(v[2], 0.0), kd * r["dhi"]

    chain = []
    for name, st in steps:
        s_dn = s_dh = s_dif = 0.0
        for r in both:
            edn, edh, dif = model(r, st)
            s_dn += edn
            s_dh += edh
            s_dif += dif
        chain.append(dict(step=name, sum_edn=s_dn, sum_edn_sinh=s_dh, sum_diffuse=s_dif))
    # checks of the replicas
    rep_rad = [model(r, steps[0][1]) for r in both]
    rep_lux = [model(r, steps[-1][1]) for r in both]
    chk = dict(
        replica_rad_edn_max_rel=max(abs(m[0] - r["rad_edn"]) / r["rad_edn"] for m, r in zip(rep_rad, both) if r["rad_edn"] > 1),
        replica_rad_dif_max_rel=max(abs(m[2] - r["rad_dif"]) / r["rad_dif"] for m, r in zip(rep_rad, both) if r["rad_dif"] > 1),
        replica_lux_edn_max_rel=max(abs(m[0] - r["lux_edn"]) / r["lux_edn"] for m, r in zip(rep_lux, both) if r["lux_edn"] > 1),
        replica_lux_dif_max_rel=max(abs(m[2] - r["lux_dif"]) / r["lux_dif"] for m, r in zip(rep_lux, both) if r["lux_dif"] > 1),
        replica_rad_sum_edn_sinh_over_actual=chain[0]["sum_edn_sinh"] / sum(r["rad_dir_h"] for r in both),
        replica_lux_sum_edn_sinh_over_actual=chain[-1]["sum_edn_sinh"] / sum(r["lux_dir_h"] for r in both))

    # --- sums ------------------------------------------------------------------------
    def sums(sel):
        return dict(n=len(sel), rad_dir_h=sum(r["rad_dir_h"] for r in sel), lux_dir_h=sum(r["lux_dir_h"] for r in sel),
                    rad_edn=sum(r["rad_edn"] for r in sel), lux_edn=sum(r["lux_edn"] for r in sel),
                    rad_dif=sum(r["rad_dif"] for r in sel), lux_dif=sum(r["lux_dif"] for r in sel),
                    rad_gh=sum(r["rad_gh"] for r in sel), lux_gh=sum(r["lux_gh"] for r in sel))

    total = sums(rows)
    total_both = sums(both)
    by_month = {m: sums([r for r in rows if r["month"] == m]) for m in range(1, 13)}
    bands = [(-1, 5), (5, 10), (10, 20), (20, 30), (30, 45), (45, 60), (60, 90)]

    def alt_of(r):
        if r["lux_alt"] is not None:
            return r["lux_alt"]
        return r["rad_alt"] if r["rad_alt"] is not None else -0.9  # no sun in either: the lowest band

    by_alt = {f"{lo}-{hi}": sums([r for r in rows if lo <= alt_of(r) < hi]) for lo, hi in bands}
    ang = [r["angle"] for r in rows if "angle" in r]
    ang_w = [(r["angle"], r["lux_dir_h"]) for r in rows if "angle" in r]
    wsum = sum(w for _, w in ang_w)
    dalt = [r["lux_alt"] - r["rad_alt"] for r in rows if "angle" in r]
    top = sorted(rows, key=lambda r: -abs(r["lux_dir_h"] - r["rad_dir_h"]))[:12]
    edn_ratio = [r["lux_edn"] / r["rad_edn"] for r in both if r["rad_edn"] > 100]
    res = dict(
        radiance=version, commands=dict(suns=sun_cmd, ground_row=gr_cmd), epw=epw.name, occupied_hours=occ,
        record_sets={k: v for k, v in sets.items()}, total=total, total_both_lit=total_both,
        by_month=by_month, by_altitude_deg=by_alt, chain=chain, replica_checks=chk,
        angle_deg=dict(n=len(ang), mean=sum(ang) / len(ang), median=pct(ang, 0.5), p90=pct(ang, 0.9), p99=pct(ang, 0.99),
                       max=max(ang), weighted_by_lux_edn_sinh=sum(x * w for x, w in ang_w) / wsum),
        sun_minutes_past_the_hour=minutes, replica_sun_c_max_angle_deg=replica_sun_max_deg,
        almanac_angle_deg=dict(to_luxtally_mean=sum(r["angle_alm_lux"] for r in rows if "angle" in r) / len(ang),
                               to_luxtally_max=max(r["angle_alm_lux"] for r in rows if "angle" in r),
                               to_gendaymtx_mean=sum(r["angle_alm_rad"] for r in rows if "angle" in r) / len(ang),
                               to_gendaymtx_max=max(r["angle_alm_rad"] for r in rows if "angle" in r)),
        altitude_diff_deg=dict(mean=sum(dalt) / len(dalt), min=min(dalt), max=max(dalt)),
        edn_ratio_per_record=dict(n=len(edn_ratio), median=pct(edn_ratio, 0.5), p5=pct(edn_ratio, 0.05),
                                  p95=pct(edn_ratio, 0.95), min=min(edn_ratio), max=max(edn_ratio)),
        top_records=[{k: r[k] for k in ("record", "month", "day", "hour", "dni", "dhi", "dew", "dew3", "rad_alt", "lux_alt",
                                         "rad_edn", "lux_edn", "rad_dir_h", "lux_dir_h", "rad_dif", "lux_dif")}
                     | dict(angle=r.get("angle")) for r in top])
    print(markdown(res))
    if a.json:
        a.json.write_text(json.dumps(res, indent=1))


def markdown(r):
    out = []
    t, tb = r["total"], r["total_both_lit"]
    rs = r["record_sets"]
    out.append(f"Occupied records lit in both {rs['both']}, in gendaymtx only {rs['rad_only']}, in luxtally only "
               f"{rs['lux_only']}.\n")
    out.append("| sum over occupied records | gendaymtx | luxtally | luxtally / gendaymtx |")
    out.append("|---|---|---|---|")
    for lab, k in (("E_dn sin h (direct on the horizontal)", "dir_h"), ("E_dn", "edn"), ("diffuse horizontal", "dif"),
                   ("global horizontal", "gh")):
        out.append(f"| {lab}, all records | {t['rad_' + k] / 1e6:.3f} Mlx·h | {t['lux_' + k] / 1e6:.3f} Mlx·h | "
                   f"{t['lux_' + k] / t['rad_' + k]:.4f} |")
    for lab, k in (("E_dn sin h", "dir_h"), ("global horizontal", "gh")):
        out.append(f"| {lab}, records lit in both | {tb['rad_' + k] / 1e6:.3f} | {tb['lux_' + k] / 1e6:.3f} | "
                   f"{tb['lux_' + k] / tb['rad_' + k]:.4f} |")
    out.append("")
    out.append("| month | records | Σ E_dn sin h luxtally / gendaymtx | Σ diffuse ratio | Σ global ratio | "
               "share of the year's Δ(E_dn sin h) |")
    out.append("|---|---|---|---|---|---|")
    dtot = t["lux_dir_h"] - t["rad_dir_h"]
    for m, s in r["by_month"].items():
        out.append(f"| {m} | {s['n']} | {s['lux_dir_h'] / s['rad_dir_h']:.4f} | {s['lux_dif'] / s['rad_dif']:.4f} | "
                   f"{s['lux_gh'] / s['rad_gh']:.4f} | {(s['lux_dir_h'] - s['rad_dir_h']) / dtot:+.1%} |")
    out.append("")
    out.append("| sun altitude (°, luxtally's) | records | Σ E_dn sin h luxtally / gendaymtx | Σ E_dn ratio | "
               "share of the year's Δ(E_dn sin h) |")
    out.append("|---|---|---|---|---|")
    for b, s in r["by_altitude_deg"].items():
        rr = s["lux_dir_h"] / s["rad_dir_h"] if s["rad_dir_h"] else float("nan")
        re_ = s["lux_edn"] / s["rad_edn"] if s["rad_edn"] else float("nan")
        out.append(f"| {b} | {s['n']} | {rr:.4f} | {re_:.4f} | {(s['lux_dir_h'] - s['rad_dir_h']) / dtot:+.1%} |")
    out.append("")
    a = r["angle_deg"]
    out.append(f"Angle between the two suns (records with both): mean {a['mean']:.3f}°, median {a['median']:.3f}°, "
               f"90 % {a['p90']:.3f}°, 99 % {a['p99']:.3f}°, max {a['max']:.3f}°; weighted by E_dn sin h "
               f"{a['weighted_by_lux_edn_sinh']:.3f}°. Altitude luxtally − gendaymtx: mean "
               f"{r['altitude_diff_deg']['mean']:+.3f}°, {r['altitude_diff_deg']['min']:+.3f}° … "
               f"{r['altitude_diff_deg']['max']:+.3f}°.")
    al = r["almanac_angle_deg"]
    out.append(f"A third sun (the Astronomical Almanac's low-precision formula, ≈ 0.01°, year 2023 as luxtally, no "
               f"refraction): to luxtally's mean {al['to_luxtally_mean']:.3f}°, max {al['to_luxtally_max']:.3f}°; to "
               f"gendaymtx's mean {al['to_gendaymtx_mean']:.3f}°, max {al['to_gendaymtx_max']:.3f}°. gendaymtx's suns "
               f"sit at {r['sun_minutes_past_the_hour']} min past the hour (its loadEPW: stamp − 0.5 h, as luxtally's "
               f"mid-hour). Radiance's sun.c (sdec = 0.4093 sin(2π(jd − 81)/365), stadj's two-term equation of "
               f"time, from the day of the year), re-computed here, gives gendaymtx's suns within "
               f"{r['replica_sun_c_max_angle_deg']:.5f}°.")
    e = r["edn_ratio_per_record"]
    out.append(f"E_dn luxtally / gendaymtx per record (E_dn > 100 lx in gendaymtx, {e['n']}): median {e['median']:.4f}, "
               f"5–95 % {e['p5']:.4f}–{e['p95']:.4f}, min {e['min']:.4f}, max {e['max']:.4f}.\n")
    out.append("| efficacy chain (records lit in both), gendaymtx → luxtally | Σ E_dn sin h | step | Σ E_dn | "
               "Σ diffuse | step |")
    out.append("|---|---|---|---|---|---|")
    prev = None
    for c in r["chain"]:
        s1 = "–" if prev is None else f"× {c['sum_edn_sinh'] / prev['sum_edn_sinh']:.4f}"
        s2 = "–" if prev is None else f"× {c['sum_diffuse'] / prev['sum_diffuse']:.4f}"
        out.append(f"| {c['step']} | {c['sum_edn_sinh'] / 1e6:.3f} Mlx·h | {s1} | {c['sum_edn'] / 1e6:.3f} | "
                   f"{c['sum_diffuse'] / 1e6:.3f} | {s2} |")
        prev = c
    c0, c1 = r["chain"][0], r["chain"][-1]
    out.append(f"| **all steps** | | **× {c1['sum_edn_sinh'] / c0['sum_edn_sinh']:.4f}** | | | "
               f"**× {c1['sum_diffuse'] / c0['sum_diffuse']:.4f}** |")
    ck = r["replica_checks"]
    out.append(f"\nReplica checks: gendaymtx's E_dn per record within {ck['replica_rad_edn_max_rel']:.2%} (its sun "
               f"file prints 4 digits), its diffuse within {ck['replica_rad_dif_max_rel']:.2%}; luxtally's E_dn within "
               f"{ck['replica_lux_edn_max_rel']:.2%}, diffuse within {ck['replica_lux_dif_max_rel']:.2%}; Σ E_dn sin h "
               f"replica / actual: gendaymtx {ck['replica_rad_sum_edn_sinh_over_actual']:.5f}, luxtally "
               f"{ck['replica_lux_sum_edn_sinh_over_actual']:.5f}.\n")
    out.append("| record | date, EPW hour | DNI W/m² | dew point (3-rec. mean) °C | altitude gendaymtx / luxtally ° | "
               "angle ° | E_dn gendaymtx / luxtally lx | E_dn sin h gendaymtx / luxtally lx |")
    out.append("|---|---|---|---|---|---|---|---|")
    for x in r["top_records"]:
        ra = "–" if x["rad_alt"] is None else f"{x['rad_alt']:.3f}"
        la = "–" if x["lux_alt"] is None else f"{x['lux_alt']:.3f}"
        an = "–" if x["angle"] is None else f"{x['angle']:.3f}"
        out.append(f"| {x['record']} | {x['month']}-{x['day']} {x['hour']} | {x['dni']:.0f} | {x['dew']:.1f} "
                   f"({x['dew3']:.1f}) | {ra} / {la} | {an} | {x['rad_edn']:.0f} / {x['lux_edn']:.0f} | "
                   f"{x['rad_dir_h']:.0f} / {x['lux_dir_h']:.0f} |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()

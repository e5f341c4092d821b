#!/usr/bin/env python3
"""Radiance (rtrace) against luxtally on the office desk receiver (issue 7).

Installs pyradiance (whose wheel bundles the Radiance binaries) into a venv under
target/, writes scenes/office.toml as a Radiance scene, and runs

    rtrace -h -I+ -ab 5 -aa 0 -ad N -as N/2 -lw 1e-4 -u+ -n 2

over the 2048 desk cell centres, doubling N until Radiance's per-cell noise is <= 1 %,
then runs luxtally to the same target and prints a Markdown table. Plain Python 3.11
standard library; see benches/radiance/README.md.
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

# --- the office (scenes/office.toml), restated -----------------------------------
ROOM_MIN = (0.0, 0.0, 0.0)
ROOM_MAX = (6.0, 5.0, 3.0)
RHO_WALL = 0.5
TABLE = ((2.2, 2.1, 0.75), (1.6, 0.0, 0.0), (0.0, 0.8, 0.0))  # corner, u, v
RHO_TABLE = 0.3
LIGHT_POS = (3.0, 2.5, 2.8)
LIGHT_CD = 1000.0
DESK = ((2.5, 2.25, 0.7501), (1.0, 0.0, 0.0), (0.0, 0.5, 0.0))  # corner, u, v
CELLS = (64, 32)

LM_PER_W = 179.0  # Radiance's luminous efficacy of its "white" watt
PHOTOMETRIC = (0.265, 0.670, 0.065)  # Radiance's RGB -> luminance weights


def die(msg, code=1):
    print(f"compare.py: {msg}", file=sys.stderr)
    sys.exit(code)


def log(msg):
    print(msg, file=sys.stderr, flush=True)


# --- pyradiance in a venv --------------------------------------------------------
def setup_radiance(venv: Path):
    py = venv / "bin" / "python"
    if not py.exists():
        log(f"creating venv {venv}")
        r = subprocess.run([sys.executable, "-m", "venv", str(venv)])
        if r.returncode != 0:
            die(f"could not create a venv in {venv}")
    probe = (
        "import os, pyradiance, pyradiance.anci as a;"
        "print(a.BINPATH); print(os.environ['RAYPATH']); print(pyradiance.__version__)"
    )
    r = subprocess.run([str(py), "-c", probe], capture_output=True, text=True)
    if r.returncode != 0:
        log("pip install pyradiance (into the venv)")
        inst = subprocess.run([str(py), "-m", "pip", "install", "-q", "pyradiance"])
        if inst.returncode != 0:
            die(
                "`pip install pyradiance` failed: no wheel for this platform/Python or no "
                "access to PyPI. Install Radiance (rtrace, oconv) and pass --radiance-bin."
            )
        r = subprocess.run([str(py), "-c", probe], capture_output=True, text=True)
        if r.returncode != 0:
            die(f"pyradiance installed but does not import:\n{r.stderr}")
    binpath, raypath, version = r.stdout.strip().splitlines()[:3]
    return Path(binpath), raypath, f"pyradiance {version}"


def find_tools(binpath: Path):
    tools = {}
    for name in ("rtrace", "oconv"):
        p = binpath / name
        if not p.exists():
            w = shutil.which(name)
            if w is None:
                die(f"{name} not found in {binpath} nor on PATH")
            p = Path(w)
        tools[name] = str(p)
    return tools


# --- the Radiance scene ----------------------------------------------------------
def poly(mat, name, pts):
    coords = "  ".join(" ".join(f"{c:g}" for c in p) for p in pts)
    return f"{mat} polygon {name}\n0\n0\n{3 * len(pts)} {coords}\n"


def radiance_scene(light_radius):
    (x0, y0, z0), (x1, y1, z1) = ROOM_MIN, ROOM_MAX
    # Vertices counter-clockwise seen from inside the room: normals point inwards.
    faces = {
        "floor": [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)],
        "ceiling": [(x0, y0, z1), (x0, y1, z1), (x1, y1, z1), (x1, y0, z1)],
        "wall_y0": [(x0, y0, z0), (x0, y0, z1), (x1, y0, z1), (x1, y0, z0)],
        "wall_y1": [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)],
        "wall_x0": [(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)],
        "wall_x1": [(x1, y0, z0), (x1, y0, z1), (x1, y1, z1), (x1, y1, z0)],
    }
    c, u, v = TABLE
    add = lambda a, b: tuple(p + q for p, q in zip(a, b))  # noqa: E731
    table = [c, add(c, u), add(add(c, u), v), add(c, v)]
    # A sphere of radius r seen from afar has projected area pi r^2: I = L pi r^2 W/sr
    # per channel, times 179 lm/W (equal RGB: luminance weights sum to 1).
    L = LIGHT_CD / (LM_PER_W * math.pi * light_radius**2)
    out = [
        "# scenes/office.toml for Radiance (benches/radiance/compare.py)\n",
        f"void plastic wall\n0\n0\n5 {RHO_WALL} {RHO_WALL} {RHO_WALL} 0 0\n",
        f"void plastic table\n0\n0\n5 {RHO_TABLE} {RHO_TABLE} {RHO_TABLE} 0 0\n",
        f"void light lamp\n0\n0\n3 {L:.6g} {L:.6g} {L:.6g}\n",
    ]
    out += [poly("wall", n, p) for n, p in faces.items()]
    out.append(poly("table", "table_top", table))
    lx, ly, lz = LIGHT_POS
    out.append(f"lamp sphere bulb\n0\n0\n4 {lx:g} {ly:g} {lz:g} {light_radius:g}\n")
    return "".join(out), L


def desk_points():
    (cx, cy, cz), (ux, _, _), (_, vy, _) = DESK
    nx, ny = CELLS
    pts = []
    for j in range(ny):
        for i in range(nx):
            pts.append((cx + (i + 0.5) * ux / nx, cy + (j + 0.5) * vy / ny, cz))
    return pts  # index j * nx + i


def rtrace(tools, octree, points_text, args):
    cmd = [tools["rtrace"], "-h", "-I+", *args, str(octree)]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, input=points_text, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        die(f"rtrace failed ({' '.join(cmd)}):\n{r.stderr}")
    vals = []
    for line in r.stdout.split("\n"):
        f = line.split()
        if len(f) >= 3:
            rgb = [float(x) for x in f[:3]]
            vals.append(LM_PER_W * sum(w * c for w, c in zip(PHOTOMETRIC, rgb)))
    return vals, dt, cmd


def rms(xs):
    return math.sqrt(sum(x * x for x in xs) / len(xs))


def pair_noise(a, b):
    """Per-run noise of two independent runs: RMS(a - b)/sqrt 2 over cells, relative
    to the RMS value of the cells (as luxtally's eq. 9 quadratic: RMS sigma/RMS value),
    and relative to the arithmetic mean too."""
    sig = rms([x - y for x, y in zip(a, b)]) / math.sqrt(2)
    m = [(x + y) / 2 for x, y in zip(a, b)]
    return sig / rms(m), sig / (sum(m) / len(m))


# --- luxtally --------------------------------------------------------------------
def run_luxtally(bin_path, scene, stop_args, threads, outdir):
    """Runs `luxtally run SCENE STOP_ARGS…` on `threads`; its summary, wall time, command."""
    cmd = [
        str(bin_path), "run", str(scene), *stop_args,
        "--threads", str(threads), "--quiet", "--out", str(outdir),
    ]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        die(f"luxtally failed ({' '.join(cmd)}):\n{r.stdout}\n{r.stderr}")
    s = json.loads((Path(outdir) / "summary.json").read_text())
    return s, wall, cmd


def luxtally_binary(a):
    """--luxtally BIN, or `cargo build --release` (honouring CARGO_TARGET_DIR)."""
    if a.luxtally:
        return a.luxtally
    tdir = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    log(f"cargo build --release (CARGO_TARGET_DIR={tdir})")
    r = subprocess.run(["cargo", "build", "--release"], cwd=REPO,
                       env=dict(os.environ, CARGO_TARGET_DIR=str(tdir)))
    if r.returncode != 0:
        die("cargo build --release failed")
    return tdir / "release" / "luxtally"


def radiance_setup(a, work):
    """pyradiance (or --radiance-bin), office.rad and office.oct in WORK, and the check of the
    light's calibration (-ab 0 at the desk centre against I/d^2; stops beyond 1 %)."""
    if a.radiance_bin:
        binpath, raypath, rad_version = a.radiance_bin, a.raypath or os.environ.get("RAYPATH", "."), "local"
    else:
        binpath, raypath, rad_version = setup_radiance(work / "venv")
    os.environ["RAYPATH"] = raypath if "." in raypath.split(os.pathsep) else "." + os.pathsep + raypath
    tools = find_tools(binpath)
    log(f"Radiance: {tools['rtrace']} ({rad_version})")

    scene_text, L = radiance_scene(a.light_radius)
    rad_file = work / "office.rad"
    rad_file.write_text(scene_text)
    octree = work / "office.oct"
    with open(octree, "wb") as f:
        r = subprocess.run([tools["oconv"], str(rad_file)], stdout=f, stderr=subprocess.PIPE, text=False)
    if r.returncode != 0:
        die(f"oconv failed: {r.stderr.decode()}")

    # Check of the source's calibration: direct light only (-ab 0) at the desk centre,
    # straight below the light, against I/d^2.
    (cx, cy, cz), (ux, _, _), (_, vy, _) = DESK
    centre = (cx + ux / 2, cy + vy / 2, cz)
    d = LIGHT_POS[2] - centre[2]
    e_expect = LIGHT_CD / d**2
    (e_ab0,), _, _ = rtrace(tools, octree, "%g %g %g 0 0 1\n" % centre, ["-ab", "0"])
    calib = e_ab0 / e_expect - 1
    log(f"light: L = {L:.6g} W/sr/m2 per channel; -ab 0 at desk centre {e_ab0:.3f} lx, "
        f"I/d^2 = {e_expect:.3f} lx ({calib:+.4%})")
    if abs(calib) > 0.01:
        die("the light's calibration is off by more than 1 %")

    return tools, octree, rad_version, L, e_ab0, e_expect, calib



# --- --cached: Radiance's ambient cache against luxtally at equal per-cell RMS error ---
# (issue 31). With -aa > 0 Radiance interpolates between cached irradiances, so its error
# is not run-to-run noise alone: it is measured against a high-precision luxtally
# reference, the same quadratic measure for both tools.
CACHED_LADDER = ",".join([  # -ab/-ad/-as/-aa/-ar
    "5/512/256/0.2/128", "5/1024/512/0.2/128", "5/1024/512/0.1/256", "6/1024/512/0.1/256",
    "7/1024/512/0.1/256", "5/2048/1024/0.1/256", "6/4096/2048/0.1/256", "7/2048/1024/0.05/512",
])


def parse_rtrace_values(text):
    vals = []
    for line in text.split("\n"):
        f = line.split()
        if len(f) >= 3:
            rgb = [float(x) for x in f[:3]]
            vals.append(LM_PER_W * sum(w * c for w, c in zip(PHOTOMETRIC, rgb)))
    return vals


def rtrace_cached(tools, octree, points_text, setting, procs, runs_dir, reuse):
    """One rtrace with the ambient cache: a fresh ambient file (shared by the -n processes,
    as users run rtrace -n with -af), deleted afterwards. Each run is saved as
    RUNS_DIR/KEY.json (command, wall time, load averages, output); with REUSE an existing
    file for the same settings is read instead of running again (it says so)."""
    ab, ad, as_, aa, ar = setting.split("/")
    args = ["-ab", ab, "-ad", ad, "-as", as_, "-aa", aa, "-ar", ar]
    key = "_".join(x.lstrip("-") for x in args)
    saved = runs_dir / f"{key}.json"
    if reuse and saved.exists():
        d = json.loads(saved.read_text())
        log(f"rtrace {' '.join(args)}: reusing {saved} ({d['wall_s']:.1f} s, load {d['load_before'][0]:.2f})")
        d["reused"] = True
    else:
        amb = runs_dir / f"{key}.amb"
        if amb.exists():
            amb.unlink()
        cmd = [tools["rtrace"], "-h", "-I+", *args, "-af", str(amb), "-n", str(procs), str(octree)]
        l0 = os.getloadavg()
        t0 = time.perf_counter()
        r = subprocess.run(cmd, input=points_text, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        l1 = os.getloadavg()
        if r.returncode != 0:
            die(f"rtrace failed ({' '.join(cmd)}):\n{r.stderr}")
        amb_bytes = amb.stat().st_size if amb.exists() else 0
        if amb.exists():
            amb.unlink()
        d = dict(args=args, cmd=cmd, wall_s=wall, load_before=list(l0), load_after=list(l1),
                 ambient_file_bytes=amb_bytes, stdout=r.stdout, stderr=r.stderr, rc=r.returncode,
                 when=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()))
        saved.write_text(json.dumps(d))
        d["reused"] = False
    d["values"] = parse_rtrace_values(d.pop("stdout"))
    d["setting"] = setting
    return d


def error_vs_ref(vals, ref, ref_var_q):
    """Per-cell RMS error against the reference, RMS(v - ref)/RMS(ref) (luxtally's eq. 9,
    quadratic), with the reference's own variance subtracted (measured^2 = true^2 +
    sigma_ref^2); the mean offset mean(v)/mean(ref) - 1; and the error after dividing v by
    (1 + offset). Returns (raw, corrected, offset, raw_offset_removed, corrected_offset_removed);
    a corrected value is negative (-sqrt|.|) if the measured error is below the reference's."""
    n = len(ref)
    rr = rms(ref)
    raw2 = sum((v - r) ** 2 for v, r in zip(vals, ref)) / n / rr**2
    off = (sum(vals) / n) / (sum(ref) / n) - 1
    raw02 = sum((v / (1 + off) - r) ** 2 for v, r in zip(vals, ref)) / n / rr**2
    sq = lambda x: math.copysign(math.sqrt(abs(x)), x)  # noqa: E731
    return math.sqrt(raw2), sq(raw2 - ref_var_q), off, math.sqrt(raw02), sq(raw02 - ref_var_q)


def loglog_time_at(err, levels):
    """luxtally's wall time at per-cell error ERR: log-log interpolation between the two
    bracketing levels [(error, time)], or extrapolation from the nearest two (flagged)."""
    # Levels that stopped at the same error ran the same photons (a QMC run's 32-block
    # minimum meets several loose targets at once): one point, their mean time.
    same = {}
    for e, t in levels:
        if e > 0:
            same.setdefault(e, []).append(t)
    pts = sorted((e, sum(ts) / len(ts)) for e, ts in same.items())
    if err <= 0 or len(pts) < 2:
        return None, "n/a"
    if err < pts[0][0]:
        (e1, t1), (e2, t2), how = pts[0], pts[1], "extrapolated below the smallest luxtally error"
    elif err > pts[-1][0]:
        (e1, t1), (e2, t2), how = pts[-2], pts[-1], "extrapolated above the largest luxtally error"
    else:
        i = max(k for k in range(len(pts) - 1) if pts[k][0] <= err)
        (e1, t1), (e2, t2), how = pts[i], pts[i + 1], "interpolated"
    slope = math.log(t2 / t1) / math.log(e2 / e1)
    return t1 * (err / e1) ** slope, how


def centre_vs_average(tools, octree, ref, k):
    """Radiance scores cell centres, luxtally cell averages. (a) The direct light, the
    part with the curvature (rtrace -ab 0, deterministic), at the centres against the mean
    of K x K points per cell; (b) h^2 (f_xx + f_yy)/24 from the reference's second
    differences (interior cells; includes the reference's noise, so an upper bound)."""
    (cx, cy, cz), (ux, _, _), (_, vy, _) = DESK
    nx, ny = CELLS
    hx, hy = ux / nx, vy / ny
    centres = desk_points()
    sub = []
    for x, y, z in centres:
        for q in range(k):
            for p in range(k):
                sub.append((x - hx / 2 + (p + 0.5) * hx / k, y - hy / 2 + (q + 0.5) * hy / k, z))
    txt = lambda pts: "".join(f"{x:.6f} {y:.6f} {z:.6f} 0 0 1\n" for x, y, z in pts)  # noqa: E731
    vc, _, _ = rtrace(tools, octree, txt(centres), ["-ab", "0"])
    vs, _, _ = rtrace(tools, octree, txt(sub), ["-ab", "0"])
    va = [sum(vs[i * k * k:(i + 1) * k * k]) / (k * k) for i in range(len(centres))]
    d_direct = rms([c - m for c, m in zip(vc, va)]) / rms(ref)
    mean_direct = (sum(vc) - sum(va)) / len(vc) / (sum(ref) / len(ref))
    corr = []
    for j in range(1, ny - 1):
        for i in range(1, nx - 1):
            f = lambda ii, jj: ref[jj * nx + ii]  # noqa: E731
            fxx = (f(i + 1, j) - 2 * f(i, j) + f(i - 1, j)) / hx**2
            fyy = (f(i, j + 1) - 2 * f(i, j) + f(i, j - 1)) / hy**2
            corr.append((hx**2 * fxx + hy**2 * fyy) / 24)
    d_ref = rms(corr) / rms(ref)
    return dict(direct_centre_minus_average_rms=d_direct, direct_centre_minus_average_mean=mean_direct,
                ref_second_difference_rms=d_ref, sub_points=k,
                direct_centre_mean_lx=sum(vc) / len(vc), direct_average_mean_lx=sum(va) / len(va))


def cached_main(a):
    work = a.workdir
    work.mkdir(parents=True, exist_ok=True)
    runs_dir = work / "runs"
    runs_dir.mkdir(exist_ok=True)
    cpu = subprocess.run("lscpu | grep 'Model name'", shell=True, capture_output=True, text=True).stdout.strip()
    cpu = cpu.split(":", 1)[-1].strip() or "unknown"
    uptime = lambda: subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()  # noqa: E731
    up_start = uptime()
    log(f"machine: {cpu}, {os.cpu_count()} cores; {up_start}")

    tools, octree, rad_version, L, e_ab0, e_expect, calib = radiance_setup(a, work)
    lux_bin = luxtally_binary(a)
    scene = REPO / "scenes" / "office.toml"
    pts = desk_points()
    points_text = "".join(f"{x:.6f} {y:.6f} {z:.6f} 0 0 1\n" for x, y, z in pts)

    def lux(err, seed):
        out = Path(tempfile.mkdtemp(prefix="luxtally-", dir=work))
        l0 = os.getloadavg()
        qmc = ["--qmc"] if a.lux_qmc and err != a.ref_error else []
        s, wall, cmd = run_luxtally(lux_bin, scene, ["--target-error", str(err), "--photons", "1000000000",
                                                     "--seed", str(seed), *qmc], a.procs, out)
        l1 = os.getloadavg()
        shutil.rmtree(out, ignore_errors=True)
        d = s["receivers"]["desk"]
        return dict(target=err, seed=seed, cmd=cmd, wall_s=wall, elapsed_s=s["elapsed_s"], setup_s=s["setup_s"],
                    photons=s["photons_emitted"], values=d["values"], sigma=d["sigma"],
                    stated_error=rms(d["sigma"]) / rms(d["values"]), mean_lx=d["mean"],
                    load_before=list(l0), load_after=list(l1))

    # 1. the reference
    log(f"reference: luxtally --target-error {a.ref_error} --seed {a.ref_seed} …")
    ref_run = lux(a.ref_error, a.ref_seed)
    ref, ref_sig = ref_run["values"], ref_run["sigma"]
    ref_q = ref_run["stated_error"]
    ref_var_q = sum(s * s for s in ref_sig) / sum(v * v for v in ref)  # = ref_q^2
    log(f"reference: {ref_run['wall_s']:.1f} s, {ref_run['photons']:,} photons, stated error {ref_q:.4%}, "
        f"mean {ref_run['mean_lx']:.3f} lx")

    cva = centre_vs_average(tools, octree, ref, a.sub_points)
    log(f"centre vs cell average: direct light {cva['direct_centre_minus_average_rms']:.4%} RMS "
        f"(mean {cva['direct_centre_minus_average_mean']:+.4%}); from the reference's second differences "
        f"{cva['ref_second_difference_rms']:.4%} RMS")

    # 2. Radiance's ladder and luxtally's levels, alternated
    settings = [s for s in a.settings.split(",") if s]
    # luxtally runs in the order of the levels (the seeds inner), spread evenly over the
    # n + 1 gaps before, between and after the n Radiance runs (both grow costlier along
    # their lists, so the long runs of each meet similar loads)
    lux_jobs = [(float(e), int(sd)) for e in a.lux_errors.split(",") for sd in a.lux_seeds.split(",")]
    rad_runs, lux_runs = [], []
    slots = len(settings) + 1
    slot_of = [k * slots // len(lux_jobs) for k in range(len(lux_jobs))] if lux_jobs else []
    queue = list(zip(slot_of, lux_jobs))
    for n_st, st in enumerate(settings):
        while queue and queue[0][0] <= n_st:
            _, (e, sd) = queue.pop(0)
            r = lux(e, sd)
            r["err"] = error_vs_ref(r["values"], ref, ref_var_q)
            lux_runs.append(r)
            log(f"luxtally target {e} seed {sd}: {r['wall_s']:.2f} s, stated {r['stated_error']:.3%}, "
                f"vs ref {r['err'][1]:.3%} (raw {r['err'][0]:.3%}), offset {r['err'][2]:+.3%}, "
                f"load {r['load_before'][0]:.2f}")
        d = rtrace_cached(tools, octree, points_text, st, a.procs, runs_dir, a.reuse_rtrace)
        if len(d["values"]) != len(pts):
            die(f"rtrace returned {len(d['values'])} values for {len(pts)} points")
        d["err"] = error_vs_ref(d["values"], ref, ref_var_q)
        rad_runs.append(d)
        log(f"rtrace {st}: {d['wall_s']:.1f} s; vs ref {d['err'][1]:.3%} (raw {d['err'][0]:.3%}), "
            f"offset {d['err'][2]:+.3%}, offset removed {d['err'][4]:.3%}; load {d['load_before'][0]:.2f}")
    for _, (e, sd) in queue:
        r = lux(e, sd)
        r["err"] = error_vs_ref(r["values"], ref, ref_var_q)
        lux_runs.append(r)
        log(f"luxtally target {e} seed {sd}: {r['wall_s']:.2f} s, vs ref {r['err'][1]:.3%}")
    up_end = uptime()

    # 3. luxtally's time against its measured error, per target level (seeds pooled:
    # RMS of the errors, mean of the wall times)
    def levels(idx):
        out = []
        for e in sorted({r["target"] for r in lux_runs}):
            rs = [r for r in lux_runs if r["target"] == e]
            m2 = sum(math.copysign(r["err"][idx] ** 2, r["err"][idx]) for r in rs) / len(rs)
            out.append((math.copysign(math.sqrt(abs(m2)), m2), sum(r["wall_s"] for r in rs) / len(rs), e, len(rs)))
        return out
    lv_as_is = levels(1)
    lv_off = levels(4)
    for d in rad_runs:
        t, how = loglog_time_at(d["err"][1], [(e, t) for e, t, _, _ in lv_as_is])
        t0, how0 = loglog_time_at(d["err"][4], [(e, t) for e, t, _, _ in lv_off])
        d.update(lux_time=t, lux_how=how, lux_time_off=t0, lux_how_off=how0)

    # 4. tables
    fmt_load = lambda r: f"{r['load_before'][0]:.2f}→{r['load_after'][0]:.2f}"  # noqa: E731
    lines = []
    P = lines.append
    P(f"Machine: {cpu}, {os.cpu_count()} cores; {rad_version}; rtrace `-n {a.procs}`, luxtally `--threads {a.procs}`.")
    P(f"Start: `{up_start}`; end: `{up_end}`.")
    P("")
    P(f"Reference: `luxtally run scenes/office.toml --target-error {a.ref_error} --seed {a.ref_seed} "
      f"--photons 1000000000 --threads {a.procs}`: {ref_run['photons']:,} photons, {ref_run['wall_s']:.1f} s, "
      f"its stated per-cell error (RMS σ / RMS value) {ref_q:.3%}, mean {ref_run['mean_lx']:.3f} lx. "
      f"Measured errors below have its variance subtracted (error² = measured² − {ref_q:.3%}²).")
    P(f"Centre vs cell average (Radiance scores centres, luxtally averages): the direct light "
      f"(`rtrace -ab 0`, centre against {a.sub_points}×{a.sub_points} points per cell) differs by "
      f"{cva['direct_centre_minus_average_rms']:.3%} RMS (mean {cva['direct_centre_minus_average_mean']:+.3%}); "
      f"h²(f_xx + f_yy)/24 from the reference's second differences {cva['ref_second_difference_rms']:.3%} RMS "
      f"(mostly the reference's own noise: an upper bound).")
    P(f"Light calibration: `-ab 0` at the desk centre {e_ab0:.3f} lx vs I/d² = {e_expect:.3f} lx ({calib:+.3%}).")
    P("")
    P("| Radiance `rtrace -I+ -af (fresh) -n 2` settings | wall (s) | load | mean offset vs ref | error vs ref | "
      "error, offset removed | luxtally at equal error | ratio | luxtally at equal error, offset removed | ratio |")
    P("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    for d in rad_runs:
        raw, cor, off, raw0, cor0 = d["err"]
        f = lambda t, how: ("–" if t is None else f"{t:.2f} s" + ("" if how == "interpolated" else " (extrap.)"))  # noqa: E731
        ratio = lambda t: "–" if t is None else f"{d['wall_s'] / t:.1f}×"  # noqa: E731
        P(f"| `{' '.join(d['args'])}` | {d['wall_s']:.1f} | {fmt_load(d)} | {off:+.2%} | {cor:.2%} | {cor0:.2%} | "
          f"{f(d['lux_time'], d['lux_how'])} | {ratio(d['lux_time'])} | {f(d['lux_time_off'], d['lux_how_off'])} | "
          f"{ratio(d['lux_time_off'])} |")
    P("")
    qmc = " --qmc" if a.lux_qmc else ""
    P(f"luxtally runs (`run scenes/office.toml --target-error E --photons 1000000000 --threads 2 --quiet --seed S{qmc}`):")
    P("")
    P("| target E | seed | wall (s) | photons | stated error | error vs ref | mean offset vs ref | error, offset removed | load |")
    P("|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in sorted(lux_runs, key=lambda r: (-r["target"], r["seed"])):
        raw, cor, off, raw0, cor0 = r["err"]
        P(f"| {r['target']} | {r['seed']} | {r['wall_s']:.2f} | {r['photons']:,} | {r['stated_error']:.3%} | "
          f"{cor:.3%} | {off:+.3%} | {cor0:.3%} | {fmt_load(r)} |")
    P("")
    P("Per level (seeds pooled; used for the interpolation): "
      + "; ".join(f"E = {e}: {err:.3%} in {t:.2f} s" for err, t, e, _ in lv_as_is) + ".")
    table = "\n".join(lines)
    print(table)
    if a.md:
        a.md.write_text(table + "\n")
    if a.json:
        strip = lambda r: {k: v for k, v in r.items() if k not in ("values", "sigma")}  # noqa: E731
        a.json.write_text(json.dumps(dict(
            machine=dict(cpu=cpu, cores=os.cpu_count(), uptime_start=up_start, uptime_end=up_end),
            radiance=dict(version=rad_version, calibration=dict(ab0_lx=e_ab0, expected_lx=e_expect),
                          runs=[dict(d) for d in rad_runs]),
            reference=dict(strip(ref_run), values=ref, sigma=ref_sig),
            centre_vs_average=cva,
            luxtally=[strip(r) for r in lux_runs],
            levels_as_is=lv_as_is, levels_offset_removed=lv_off,
        ), indent=1))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--target", type=float, default=0.01, help="relative per-cell noise (default 0.01)")
    ap.add_argument("--ab", type=int, default=5)
    ap.add_argument("--ad-start", type=int, default=64)
    ap.add_argument("--ad-max", type=int, default=65536)
    ap.add_argument("--procs", type=int, default=2, help="rtrace -n and luxtally --threads")
    ap.add_argument("--light-radius", type=float, default=0.01, help="m")
    ap.add_argument("--workdir", type=Path, default=REPO / "target" / "radiance-compare")
    ap.add_argument("--radiance-bin", type=Path, help="use this Radiance bin/ instead of pyradiance")
    ap.add_argument("--raypath", help="RAYPATH with --radiance-bin (its lib/)")
    ap.add_argument("--luxtally", type=Path, help="luxtally binary (default: cargo build --release)")
    ap.add_argument("--luxtally-repeats", type=int, default=3, help="luxtally runs timed (default 3)")
    ap.add_argument("--no-bias-check", action="store_true",
                    help="skip the run without -ab 5 truncation (-ab 20 -lw 1e-7 -lr 0 -ad 256)")
    ap.add_argument("--json", type=Path, help="also write all numbers here")
    g = ap.add_argument_group("--cached: Radiance's ambient cache at equal per-cell RMS error (issue 31)")
    g.add_argument("--cached", action="store_true",
                   help="instead of the -aa 0 search: rtrace with the ambient cache against a luxtally reference")
    g.add_argument("--settings", default=CACHED_LADDER,
                   help="comma-separated -ab/-ad/-as/-aa/-ar (default: the ladder in CACHED_LADDER)")
    g.add_argument("--ref-error", type=float, default=0.0007, help="the reference's --target-error (default 0.0007)")
    g.add_argument("--ref-seed", type=int, default=1000)
    g.add_argument("--lux-errors", default="0.02,0.014,0.01,0.007,0.005,0.0035,0.0025,0.0018,0.0013,0.001",
                   help="luxtally --target-error levels, comma-separated")
    g.add_argument("--lux-seeds", default="1,2", help="luxtally seeds at each level")
    g.add_argument("--sub-points", type=int, default=4, help="K x K points per cell for the centre/average check")
    g.add_argument("--reuse-rtrace", action="store_true",
                   help="reuse WORKDIR/runs/KEY.json of an earlier run with the same settings")
    g.add_argument("--md", type=Path, help="--cached: also write the tables here")
    g.add_argument("--lux-qmc", action="store_true",
                   help="luxtally's timed runs with --qmc (the reference stays an ordinary run)")
    a = ap.parse_args()
    if a.cached:
        if a.workdir == REPO / "target" / "radiance-compare":
            a.workdir = REPO / "target" / "radiance-cached"
        return cached_main(a)

    work = a.workdir
    work.mkdir(parents=True, exist_ok=True)

    tools, octree, rad_version, L, e_ab0, e_expect, calib = radiance_setup(a, work)

    pts = desk_points()
    points_text = "".join(f"{x:.6f} {y:.6f} {z:.6f} 0 0 1\n" for x, y, z in pts)

    search = []
    ad = a.ad_start
    final = None
    while ad <= a.ad_max:
        args = ["-ab", str(a.ab), "-aa", "0", "-ad", str(ad), "-as", str(ad // 2),
                "-lw", "1e-4", "-u+", "-n", str(a.procs)]
        va, ta, cmd = rtrace(tools, octree, points_text, args)
        vb, tb, _ = rtrace(tools, octree, points_text, args)
        if len(va) != len(pts) or len(vb) != len(pts):
            die(f"rtrace returned {len(va)}/{len(vb)} values for {len(pts)} points")
        q, ar = pair_noise(va, vb)
        mean = sum(va + vb) / (2 * len(pts))
        row = dict(ad=ad, times_s=[ta, tb], noise_quadratic=q, noise_arithmetic=ar, mean_lx=mean)
        search.append(row)
        log(f"rtrace -ad {ad:6d}: {ta:7.2f} s, {tb:7.2f} s; noise {q:.3%} (RMS sigma/RMS value), "
            f"{ar:.3%} (/mean); mean {mean:.2f} lx")
        if q <= a.target:
            final = dict(row, values_a=va, values_b=vb, cmd=cmd)
            break
        ad *= 2
    if final is None:
        die(f"Radiance did not reach {a.target:.1%} by -ad {a.ad_max}")

    # How much of the desk's light -ab 5 -lw 1e-4 leaves out: one run with (practically)
    # no bounce limit. Only its mean over the 2048 cells is used (noise ~0.04 %).
    bias = None
    if not a.no_bias_check:
        args = ["-ab", "20", "-aa", "0", "-ad", "256", "-as", "128", "-lw", "1e-7", "-lr", "0",
                "-u+", "-n", str(a.procs)]
        vc, tc, ccmd = rtrace(tools, octree, points_text, args)
        bias = dict(cmd=ccmd, time_s=tc, mean_lx=sum(vc) / len(vc))
        log(f"rtrace {' '.join(args)}: {tc:.2f} s; mean {bias['mean_lx']:.2f} lx")

    # luxtally
    lux_bin = luxtally_binary(a)
    lux_out = Path(tempfile.mkdtemp(prefix="luxtally-", dir=work))
    stop = ["--target-error", str(a.target), "--photons", "1000000000"]
    s, lux_wall, lux_cmd = run_luxtally(lux_bin, REPO / "scenes" / "office.toml", stop, a.procs, lux_out)
    lux_times = [(s["elapsed_s"], s["setup_s"], lux_wall)]
    for _ in range(a.luxtally_repeats - 1):  # timing only; the first run's cells are compared
        s2, w2, _ = run_luxtally(lux_bin, REPO / "scenes" / "office.toml", stop, a.procs,
                                 Path(tempfile.mkdtemp(prefix="luxtally-", dir=work)))
        lux_times.append((s2["elapsed_s"], s2["setup_s"], w2))
    log("luxtally runs (photon pass, setup, process): "
        + "; ".join(f"{e:.3f}, {st:.3f}, {w:.2f} s" for e, st, w in lux_times))
    desk = s["receivers"]["desk"]
    lv, ls = desk["values"], desk["sigma"]
    lux_q = rms(ls) / rms(lv)
    log(f"luxtally: {s['elapsed_s']:.3f} s photon pass + {s['setup_s']:.3f} s setup, "
        f"{lux_wall:.2f} s process; {s['photons_emitted']} photons; error {lux_q:.3%}; mean {desk['mean']:.2f} lx")

    # Agreement, cell by cell, against the mean of Radiance's two runs
    va, vb = final["values_a"], final["values_b"]
    rv = [(x + y) / 2 for x, y in zip(va, vb)]
    rad_rel_sigma = final["noise_quadratic"] / math.sqrt(2)  # of the two-run mean
    rel = [(x - y) / y for x, y in zip(lv, rv)]
    mean_rel = sum(rel) / len(rel)
    z = [(x - y) / math.hypot(sx, rad_rel_sigma * y) for x, y, sx in zip(lv, rv, ls)]
    z_rms = rms(z)
    # the same after removing the mean ratio: does the shape agree?
    k = 1 + mean_rel
    z0 = [(x - k * y) / math.hypot(sx, rad_rel_sigma * k * y) for x, y, sx in zip(lv, rv, ls)]
    z0_rms = rms(z0)
    rad_mean = sum(rv) / len(rv)

    t_rad = min(final["times_s"])
    # Time at exactly the target, interpolated log-log between the last two -ad settings
    # (noise falls about as 1/N here, not 1/sqrt N: see the search table).
    t_rad_scaled = None
    if len(search) >= 2:
        p1, p2 = search[-2], search[-1]
        t1, t2 = min(p1["times_s"]), min(p2["times_s"])
        slope = math.log(t2 / t1) / math.log(p1["noise_quadratic"] / p2["noise_quadratic"])
        t_rad_scaled = t2 * (p2["noise_quadratic"] / a.target) ** slope
    rad_settings = "rtrace " + " ".join(final["cmd"][1:-1])
    print()
    print(f"Desk receiver, 2048 cells, target {a.target:.0%} (RMS σ / RMS value); "
          f"{a.procs} processes/threads; {rad_version}")
    print()
    print("| tool | settings | wall time to 1 % | error reached | mean desk illuminance |")
    print("|---|---|---:|---:|---:|")
    print(f"| Radiance rtrace | `{rad_settings}` | {t_rad:.2f} s (best of 2: "
          f"{final['times_s'][0]:.2f}, {final['times_s'][1]:.2f} s"
          + (f"; at exactly {a.target:.0%}, interpolated: {t_rad_scaled:.2f} s" if t_rad_scaled else "") + ") "
          f"| {final['noise_quadratic']:.2%} | {rad_mean:.2f} lx |")
    best = min(lux_times, key=lambda t: t[2])
    print(f"| luxtally | `run --target-error {a.target} --threads {a.procs}` (next_event) | "
          f"{best[2]:.2f} s process: {best[0]:.3f} s photon pass + {best[1]:.3f} s setup (best of "
          f"{len(lux_times)}; photon pass {min(t[0] for t in lux_times):.3f}–{max(t[0] for t in lux_times):.3f} s, "
          f"process {min(t[2] for t in lux_times):.2f}–{max(t[2] for t in lux_times):.2f} s) "
          f"| {lux_q:.2%} ({s['photons_emitted']:,} photons) | {desk['mean']:.2f} lx |")
    print()
    print(f"Agreement (luxtally − Radiance)/Radiance, cell by cell against the mean of Radiance's two runs: "
          f"mean {mean_rel:+.2%}; z-score RMS {z_rms:.2f} "
          f"(σ² = σ_luxtally² + σ_Radiance², σ_Radiance = {rad_rel_sigma:.2%} × value); "
          f"z RMS after scaling Radiance by the mean ratio {z0_rms:.2f}.")
    if bias:
        print(f"Without the bounce limit (`rtrace {' '.join(bias['cmd'][1:-1])}`, {bias['time_s']:.1f} s): "
              f"Radiance's mean {bias['mean_lx']:.2f} lx, {bias['mean_lx'] / rad_mean - 1:+.2%} over -ab 5; "
              f"luxtally's mean is {desk['mean'] / bias['mean_lx'] - 1:+.2%} over it.")
    print(f"Light: radius {a.light_radius} m, L = {L:.6g} W/sr/m²; -ab 0 at the desk centre "
          f"{e_ab0:.3f} lx vs I/d² = {e_expect:.3f} lx ({calib:+.3%}).")
    print()
    print("-ad search (two independent runs each):")
    print()
    print("| -ad | -as | run times (s) | noise (RMS σ / RMS value) | noise (/ mean) | mean (lx) |")
    print("|---:|---:|---|---:|---:|---:|")
    for r in search:
        print(f"| {r['ad']} | {r['ad'] // 2} | {r['times_s'][0]:.2f}, {r['times_s'][1]:.2f} | "
              f"{r['noise_quadratic']:.2%} | {r['noise_arithmetic']:.2%} | {r['mean_lx']:.2f} |")

    if a.json:
        a.json.write_text(json.dumps(dict(
            radiance=dict(version=rad_version, search=search, time_at_target_interpolated_s=t_rad_scaled, cmd=final["cmd"], mean_lx=rad_mean,
                          calibration=dict(ab0_lx=e_ab0, expected_lx=e_expect), no_bounce_limit=bias),
            luxtally=dict(cmd=lux_cmd, elapsed_s=s["elapsed_s"], setup_s=s["setup_s"], process_s=lux_wall,
                          photons=s["photons_emitted"], error_quadratic=lux_q, runs=lux_times, mean_lx=desk["mean"]),
            agreement=dict(mean_rel=mean_rel, z_rms=z_rms, z_rms_scaled=z0_rms),
        ), indent=1))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""How much of annual.py's difference is the 2-phase sun in MF 2 patches?

Run after annual.py (it reuses its work directory: office.rad, dc_a.mtx, sky.mtx,
sky_only.mtx and luxtally's CSVs). Traces one more coefficient matrix, the sky alone on
Reinhart MF N patches (default 6, 5185 patches, ~2.1 degrees), with the same rfluxmtx
settings as run a, and takes the sun from `gendaymtx -m N -d` (the sun alone, over the 4
nearest MF N patches); the sky and the ground stay on run a's MF 2 coefficients. The
annual mean is linear in the sky vectors, so it is DC x (the occupied records' summed
sky vector): no dctimestep. Prints the mean by depth band against annual.py's run a and
luxtally (sun_mf 6 and 0). Standard library; see benches/radiance/README.md.
"""

import argparse
import json
import math
import os
import sys
import time
from array import array
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import annual  # noqa: E402
import compare  # noqa: E402

REPO = Path(__file__).resolve().parents[2]


def read_any(path, ncols_expected=None):
    data = Path(path).read_bytes()
    end = data.find(b"\n\n")
    info = {}
    for line in data[:end].decode(errors="replace").split("\n"):
        if "=" in line:
            k, v = line.split("=", 1)
            info[k.strip()] = v.strip()
    arr = array({"float": "f", "double": "d"}[info["FORMAT"]])
    arr.frombytes(data[end + 2:])
    nc, ncomp = int(info["NCOLS"]), int(info.get("NCOMP", "3"))
    nr = int(info.get("NROWS", len(arr) // (nc * ncomp)))
    return arr, nr, nc, ncomp


def summed(sky, nr, nc, cols):
    """Per row and component the sum over the columns `cols`."""
    out = []
    for j in range(nr):
        base = j * nc * 3
        out.append([sum(sky[base + 3 * k + c] for k in cols) for c in range(3)])
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--workdir", type=Path, default=REPO / "target" / "radiance-annual")
    ap.add_argument("--mf", type=int, default=6)
    ap.add_argument("--scene", type=Path, default=REPO / "scenes" / "daylit_office_annual.toml")
    ap.add_argument("--venv", type=Path, default=REPO / "target" / "radiance-compare" / "venv")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    work = a.workdir.resolve()
    res_main = json.loads((REPO / "benches" / "radiance" / "annual_results.json").read_text())
    binpath, raypath, _ = compare.setup_radiance(a.venv)
    os.environ["RAYPATH"] = "." + os.pathsep + raypath
    tools = annual.tools_in(binpath)
    os.environ["PATH"] = str(Path(tools["rcontrib"]).parent) + os.pathsep + os.environ.get("PATH", "")
    import tomllib
    scene = tomllib.loads(a.scene.read_text())
    epw = (a.scene.resolve().parent / scene["annual"]["weather"]).resolve()
    cells = annual.read_csv(work / "lux" / "annual_df_grid.csv")
    pts = [(float(c["x"]), float(c["y"]), float(c["z"])) for c in cells]
    sensors = "".join(f"{x:.4f} {y:.4f} {z:.4f} 0 0 1\n" for x, y, z in pts).encode()
    (work / f"sky{a.mf}.rad").write_text(
        f"#@rfluxmtx h=r{a.mf} u=Y\nvoid glow skyglow\n0\n0\n4 1 1 1 0\n\nskyglow source sky\n0\n0\n4 0 0 1 180\n")
    run_a = [x for x in res_main["radiance"]["rfluxmtx"] if x["tag"] == "a"][0]["cmd"]
    flags = run_a[1:run_a.index("-")]
    cmd = [tools["rfluxmtx"], *flags, "-", f"sky{a.mf}.rad", "office.rad"]
    _, t_dc, _ = annual.run(cmd, work, stdin=sensors, stdout_path=work / f"dc_sun{a.mf}.mtx")
    compare.log(f"rfluxmtx MF {a.mf}: {t_dc:.1f} s")
    g = f"{res_main['ground_reflectance']:g}"
    annual.run([tools["gendaymtx"], "-m", str(a.mf), "-d", "-g", g, g, g, "-O0", "-of", str(epw)], work,
               stdout_path=work / f"sun{a.mf}.mtx")

    stamps = annual.epw_stamps(epw)
    occ = res_main["occupied_hours"]
    occupied = [k for k, s in enumerate(stamps) if occ[0] <= s[2] - 0.5 < occ[1]]
    n = len(occupied)
    sky, nr2, nc, _ = read_any(work / "sky.mtx")
    skyo, _, _, _ = read_any(work / "sky_only.mtx")
    sun6, nr6, _, _ = read_any(work / f"sun{a.mf}.mtx")
    S_def = summed(sky, nr2, nc, occupied)
    S_sky = summed(skyo, nr2, nc, occupied)
    S_sun6 = summed(sun6, nr6, nc, occupied)
    dc2, ns, nc2, _ = read_any(work / "dc_a.mtx")
    dc6, ns6, nc6, _ = read_any(work / f"dc_sun{a.mf}.mtx")
    assert nc2 == nr2 and nc6 == nr6 - 1 and ns == ns6 == len(pts), (nc2, nr2, nc6, nr6, ns, ns6)
    w = [compare.LM_PER_W * x for x in compare.PHOTOMETRIC]

    def dot(dc, ncols, i, S, offset):
        base = i * ncols * 3
        return sum(w[c] * sum(dc[base + 3 * j + c] * S[j + offset][c] for j in range(ncols)) for c in range(3))

    mean_default, mean_mf = [], []
    for i in range(ns):
        e_def = dot(dc2, nc2, i, S_def, 0) / n
        e_sky = dot(dc2, nc2, i, S_sky, 0) / n  # ground (row 0: the same in every mode) + sky
        e_sun = dot(dc6, nc6, i, S_sun6, 1) / n  # MF N patches: rows 1.. of the -d matrix
        mean_default.append(e_def)
        mean_mf.append(e_sky + e_sun)
    lux = {k: [float(c["mean_lx"]) for c in annual.read_csv(work / d / "annual_df_grid.csv")]
           for k, d in (("sun_mf 6", "lux"), ("sun_mf 0", "lux_sun_mf_0"))}
    nu, nv = 20, 30
    print(f"| rows (0 = window) | Radiance, sun on MF 2 (run a) | Radiance, sun on MF {a.mf} | ratio | "
          "luxtally sun_mf 6 | luxtally sun_mf 0 | luxtally sun_mf 0 / Radiance MF " + str(a.mf) + " |")
    print("|---|---|---|---|---|---|---|")
    bands = []
    for b in list(range(5)) + [None]:
        rows = range(30) if b is None else range(b * 6, b * 6 + 6)
        idx = [j * nu + i for j in rows for i in range(nu)]
        m = lambda v: sum(v[i] for i in idx) / len(idx)  # noqa: E731
        row = dict(rows="all" if b is None else f"{b * 6}-{b * 6 + 5}", rad_mf2=m(mean_default), rad_mf=m(mean_mf),
                   lux6=m(lux["sun_mf 6"]), lux0=m(lux["sun_mf 0"]))
        bands.append(row)
        print(f"| {row['rows']} | {row['rad_mf2']:.1f} | {row['rad_mf']:.1f} | {row['rad_mf'] / row['rad_mf2']:.4f} | "
              f"{row['lux6']:.1f} | {row['lux0']:.1f} | {row['lux0'] / row['rad_mf']:.4f} |")
    out = dict(mf=a.mf, rfluxmtx_cmd=cmd, rfluxmtx_wall_s=t_dc, bands=bands,
               check_run_a_mean=sum(mean_default) / ns, annual_py_run_a_mean=res_main["radiance"]["mean_lx_runs"][0],
               per_sensor_sun_mf=mean_mf)
    print(f"\ncheck: run a's mean from the summed sky vector {out['check_run_a_mean']:.2f} lx, annual.py (dctimestep) "
          f"{out['annual_py_run_a_mean']:.2f} lx")
    if a.json:
        a.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()

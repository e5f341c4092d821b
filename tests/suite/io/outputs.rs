//! The files a run writes read back to the numbers of summary.json: receiver EXR (with
//! the exr crate) and CSV, the scene map PLY (with a minimal PLY reader written here,
//! independent of the writer), the PNG previews, a self-contained report.html and the
//! skies' fisheye plots.

use crate::common;

use common::*;
use luxtally::accel::Backend;
use luxtally::light::sun::direction;
use luxtally::output::{summary, write_all, Finished, Outputs};
use luxtally::run::run;
use luxtally::stats::{relative_error, triangle_illuminance_lx, MapKind};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

const SCENE: &str = r#"
name = "outputs"
[materials.wall]
reflectance = 0.5
[[objects]]
shape = "box"
min = [0, 0, 0]
max = [4, 3, 2.5]
material = "wall"
[[objects]]
shape = "sphere"
center = [2, 1.5, 0.6]
radius = 0.4
subdivisions = 2
material = "wall"
[[lights]]
type = "point"
position = [2, 1.5, 2.3]
intensity_cd = 500
[[receivers]]
name = "desk"
corner = [0.5, 0.5, 0.8]
u = [3, 0, 0]
v = [0, 2, 0]
cells = [12, 7]
[[receivers]]
name = "wall meter"
corner = [0.001, 0.2, 0.2]
u = [0, 2.6, 0]
v = [0, 0, 2]
cells = [5, 3]
"#;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("luxtally-outputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Runs the scene and writes every output into a fresh directory; hands the directory,
/// the scene and the run's state to `check`.
fn with_outputs(name: &str, check: impl FnOnce(&Path, &luxtally::run::RunState<'_>)) {
    let scene = scene(SCENE);
    let opts = options(&scene, 200_000, 2, Backend::Embree);
    let result = run(&scene, &opts, &AtomicBool::new(false), &mut ()).expect("run succeeds");
    let state = result.state(&scene, &opts);
    let dir = temp_dir(name);
    let finished = Finished {
        run: Some(&state),
        image: None,
    };
    write_all(&dir, finished, Outputs::ALL).expect("outputs written");
    check(&dir, &state);
}

#[test]
fn receiver_exr_holds_summary_numbers_rounded_to_f32() {
    use exr::prelude::*;
    with_outputs("exr", |dir, state| {
        let s = summary::build(state);
        for (name, file) in [("desk", "desk"), ("wall meter", "wall_meter")] {
            let r = &s.receivers[name];
            let image = read()
                .no_deep_data()
                .largest_resolution_level()
                .all_channels()
                .first_valid_layer()
                .all_attributes()
                .from_file(dir.join(format!("receivers/{file}.exr")))
                .expect("EXR reads back");
            let layer = &image.layer_data;
            assert_eq!(
                (layer.size.width(), layer.size.height()),
                (r.cells[0] as usize, r.cells[1] as usize),
                "{name}: data window = cells"
            );
            let channel = |c: &str| -> Vec<f32> {
                let ch = layer
                    .channel_data
                    .list
                    .iter()
                    .find(|ch| ch.name == *c)
                    .unwrap_or_else(|| panic!("{name}: channel {c}"));
                ch.sample_data.values_as_f32().collect()
            };
            let (value, sigma, rel, hits) = (
                channel("value"),
                channel("sigma"),
                channel("rel_error"),
                channel("hits"),
            );
            assert_eq!(value.len(), r.values.len());
            for k in 0..r.values.len() {
                assert_eq!(
                    value[k].to_bits(),
                    (r.values[k] as f32).to_bits(),
                    "{name} value {k}"
                );
                assert_eq!(
                    sigma[k].to_bits(),
                    (r.sigma[k] as f32).to_bits(),
                    "{name} sigma {k}"
                );
                let expected_rel = relative_error(r.values[k], r.sigma[k]) as f32;
                assert_eq!(
                    rel[k].to_bits(),
                    expected_rel.to_bits(),
                    "{name} rel_error {k}"
                );
                assert_eq!(hits[k], r.hits[k] as f32, "{name} hits {k}");
            }
            assert!(r.hits.iter().any(|&h| h > 0), "{name}: some light arrived");
        }
    });
}

#[test]
fn receiver_csv_parses_back_to_summary_numbers_and_cell_centres() {
    with_outputs("csv", |dir, state| {
        let s = summary::build(state);
        for r in &state.scene.receivers {
            let rs = &s.receivers[&r.name];
            let file = r.name.replace(' ', "_");
            let text = std::fs::read_to_string(dir.join(format!("receivers/{file}.csv")))
                .expect("CSV exists");
            let mut lines = text.lines();
            assert_eq!(
                lines.next(),
                Some(
                    "i,j,x_m,y_m,z_m,value,sigma,rel_error,hits,scoring_histories,vov,dof,\
                     status,upper_bound"
                )
            );
            let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
            assert_eq!(rows.len(), rs.values.len());
            let nu = r.cells[0] as usize;
            for (k, row) in rows.iter().enumerate() {
                let f = |c: usize| row[c].parse::<f64>().expect("a number");
                let (i, j) = (
                    row[0].parse::<usize>().unwrap(),
                    row[1].parse::<usize>().unwrap(),
                );
                assert_eq!((i, j), (k % nu, k / nu));
                let centre = r.corner
                    + r.u * ((i as f64 + 0.5) / r.cells[0] as f64)
                    + r.v * ((j as f64 + 0.5) / r.cells[1] as f64);
                assert_eq!([f(2), f(3), f(4)], centre.to_array());
                // Unknown errors are written `NaN`.
                let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || a.is_nan() && b.is_nan();
                assert_eq!(f(5).to_bits(), rs.values[k].to_bits());
                assert!(same(f(6), rs.sigma[k]), "{} vs {}", row[6], rs.sigma[k]);
                assert!(same(f(7), relative_error(rs.values[k], rs.sigma[k])));
                assert_eq!(row[8].parse::<u64>().unwrap(), rs.hits[k]);
                assert_eq!(row[9].parse::<u64>().unwrap(), rs.scoring_histories[k]);
                assert!(same(f(10), rs.vov[k]) && same(f(11), rs.dof[k]));
                assert_eq!(row[12], rs.status[k].as_str());
                assert!(same(f(13), rs.upper_bound[k]));
            }
        }
    });
}

/// A PLY file read by a minimal reader of its own: the header's elements and properties,
/// then binary little-endian records.
struct Ply {
    /// element name → (property names, rows of values; lists flattened, count first).
    elements: Vec<(String, Vec<String>, Vec<Vec<f64>>)>,
}

fn read_ply(bytes: &[u8]) -> Ply {
    let end = b"end_header\n";
    let header_len = bytes
        .windows(end.len())
        .position(|w| w == end)
        .expect("end_header")
        + end.len();
    let header = std::str::from_utf8(&bytes[..header_len]).expect("ASCII header");
    let mut lines = header.lines();
    assert_eq!(lines.next(), Some("ply"));
    assert_eq!(lines.next(), Some("format binary_little_endian 1.0"));
    // (name, count, [(property, type, list count type)])
    type Prop = (String, String, Option<String>);
    let mut decl: Vec<(String, usize, Vec<Prop>)> = Vec::new();
    for line in lines {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["element", name, n] => decl.push((name.to_string(), n.parse().unwrap(), vec![])),
            ["property", "list", ct, t, name] => decl.last_mut().unwrap().2.push((
                name.to_string(),
                t.to_string(),
                Some(ct.to_string()),
            )),
            ["property", t, name] => {
                decl.last_mut()
                    .unwrap()
                    .2
                    .push((name.to_string(), t.to_string(), None))
            }
            _ => {}
        }
    }
    let mut at = header_len;
    let mut take = |t: &str| -> f64 {
        let size = match t {
            "uchar" | "char" => 1,
            "short" | "ushort" => 2,
            "int" | "uint" | "float" => 4,
            "double" => 8,
            other => panic!("type {other}"),
        };
        let b = &bytes[at..at + size];
        at += size;
        match t {
            "uchar" => b[0] as f64,
            "int" => i32::from_le_bytes(b.try_into().unwrap()) as f64,
            "uint" => u32::from_le_bytes(b.try_into().unwrap()) as f64,
            "float" => f32::from_le_bytes(b.try_into().unwrap()) as f64,
            "double" => f64::from_le_bytes(b.try_into().unwrap()),
            other => panic!("type {other}"),
        }
    };
    let mut elements = Vec::new();
    for (name, n, props) in decl {
        let mut rows = Vec::with_capacity(n);
        for _ in 0..n {
            let mut row = Vec::new();
            for (_, t, list) in &props {
                if let Some(ct) = list {
                    let count = take(ct);
                    row.push(count);
                    for _ in 0..count as usize {
                        row.push(take(t));
                    }
                } else {
                    row.push(take(t));
                }
            }
            rows.push(row);
        }
        elements.push((name, props.into_iter().map(|p| p.0).collect(), rows));
    }
    assert_eq!(at, bytes.len(), "no trailing bytes");
    Ply { elements }
}

#[test]
fn scene_map_ply_reads_back_to_the_triangle_map() {
    with_outputs("ply", |dir, state| {
        let bytes = std::fs::read(dir.join("scene_map.ply")).expect("PLY exists");
        let ply = read_ply(&bytes);
        let g = &state.scene.geometry;
        let (vname, vprops, vertices) = &ply.elements[0];
        let (fname, fprops, faces) = &ply.elements[1];
        assert_eq!((vname.as_str(), fname.as_str()), ("vertex", "face"));
        assert_eq!(
            vprops,
            &["x", "y", "z", "illuminance", "red", "green", "blue"]
        );
        assert_eq!(
            fprops,
            &["vertex_indices", "illuminance", "indirect", "rel_error"]
        );
        assert_eq!(vertices.len(), g.vertices.len());
        assert_eq!(faces.len(), g.triangle_count());
        let t = &state.progress.tallies;
        let flux = state.setup.total_flux_lm;
        let adjacent =
            luxtally::scene::adjacency::VertexFaces::by_position(&g.triangles, &g.vertices);
        let rel_errors =
            luxtally::stats::triangle_rel_errors(t, &g.triangles, &adjacent, |k| g.area_m2(k));
        let mut weight = vec![0.0; g.vertices.len()];
        let mut sum = vec![0.0; g.vertices.len()];
        for (k, face) in faces.iter().enumerate() {
            let a = g.area_m2(k);
            let tri = g.triangles[k];
            assert_eq!(
                face[..4],
                [3.0, tri[0] as f64, tri[1] as f64, tri[2] as f64]
            );
            let e = triangle_illuminance_lx(t, MapKind::Total, k, a, flux, None);
            let ind = triangle_illuminance_lx(t, MapKind::Indirect, k, a, flux, None);
            // The triangle's own error (docs/method.md); 1 where it is unknown.
            let rel = if rel_errors[k].is_nan() {
                1.0
            } else {
                rel_errors[k]
            };
            assert_eq!(face[4], e as f32 as f64, "face {k} illuminance");
            assert_eq!(face[5], ind as f32 as f64, "face {k} indirect");
            assert_eq!(face[6], rel as f32 as f64, "face {k} rel_error");
            for &v in &tri {
                weight[v as usize] += a;
                sum[v as usize] += a * e;
            }
        }
        assert!(faces.iter().any(|f| f[4] > 0.0), "the map is lit");
        for (n, v) in vertices.iter().enumerate() {
            let world = g.origin + g.vertices[n].as_dvec3();
            assert_eq!(
                v[..3],
                world.to_array().map(|x| x as f32 as f64),
                "vertex {n}"
            );
            let mean = if weight[n] > 0.0 {
                sum[n] / weight[n]
            } else {
                0.0
            };
            assert!(
                (v[3] - mean).abs() <= 1e-6 * mean.abs().max(1.0),
                "vertex {n}: {} vs area-weighted {mean}",
                v[3]
            );
        }
        // Colours vary with illuminance: more than one colour on a lit room.
        let colours: std::collections::BTreeSet<[u8; 3]> = vertices
            .iter()
            .map(|v| [v[4] as u8, v[5] as u8, v[6] as u8])
            .collect();
        assert!(colours.len() > 1);
    });
}

#[test]
fn previews_and_report_are_written_and_self_contained() {
    with_outputs("report", |dir, _| {
        for name in ["desk", "desk_error", "wall_meter", "wall_meter_error"] {
            let file = std::fs::File::open(dir.join(format!("receivers/{name}.png")))
                .unwrap_or_else(|_| panic!("{name}.png exists"));
            let info = png::Decoder::new(std::io::BufReader::new(file))
                .read_info()
                .expect("a PNG")
                .info()
                .clone();
            assert!(info.width >= 256, "{name}.png is {} px wide", info.width);
        }
        let html = std::fs::read_to_string(dir.join("report.html")).expect("report exists");
        assert!(
            !html.contains("http-equiv=\"refresh\""),
            "a finished run does not reload"
        );
        for remote in [
            "<script src",
            "<link",
            "http://",
            "https://",
            "fetch(",
            "XMLHttpRequest",
        ] {
            assert!(!html.contains(remote), "report.html refers to `{remote}`");
        }
        assert!(html.contains("\"wall meter\""));
    });
}

#[test]
fn report_command_rebuilds_report_and_previews_from_summary_json() {
    with_outputs("rebuild", |dir, _| {
        for f in [
            "report.html",
            "receivers/desk.png",
            "receivers/desk_error.png",
        ] {
            std::fs::remove_file(dir.join(f)).expect("file was written");
        }
        // An unknown error (NaN, written as null) reads back typed.
        let path = dir.join("summary.json");
        let mut json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        json["receivers"]["desk"]["sigma"][0] = serde_json::Value::Null;
        std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_luxtally"))
            .args(["report", dir.to_str().unwrap()])
            .output()
            .expect("binary runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        for f in [
            "report.html",
            "receivers/desk.png",
            "receivers/desk_error.png",
        ] {
            assert!(dir.join(f).exists(), "{f} rebuilt");
        }
        let missing = temp_dir("rebuild-missing");
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_luxtally"))
            .args(["report", missing.to_str().unwrap()])
            .output()
            .expect("binary runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1));
        assert!(
            err.contains("summary.json") && err.lines().count() == 1,
            "{err}"
        );
    });
}

#[test]
fn live_report_reloads_itself_until_the_run_ends() {
    let mut s = serde_json::json!({ "scene": "x", "stop_reason": null, "receivers": {} });
    let live = luxtally::output::report::report_html(&s, 3.0).unwrap();
    assert!(live.contains("<meta http-equiv=\"refresh\" content=\"3\">"));
    s["stop_reason"] = "interrupted".into();
    let done = luxtally::output::report::report_html(&s, 3.0).unwrap();
    assert!(!done.contains("http-equiv"));
    // Data cannot close the script element.
    s["scene"] = "</script><script>alert(1)</script>".into();
    let html = luxtally::output::report::report_html(&s, 3.0).unwrap();
    assert_eq!(html.matches("</script>").count(), 1);
}

#[test]
fn report_rebuilds_from_an_older_summary_missing_newer_keys() {
    // An older summary.json: no direct light, luminaires, unknown-cell or merge keys.
    let dir = std::env::temp_dir().join(format!("luxtally-old-summary-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let old = r#"{"scene": "office", "backend": "embree", "seed": 1, "threads": 2,
        "photons_emitted": 1000, "rays_traced": 3000, "elapsed_s": 0.1,
        "stop_reason": "photons", "total_flux_lm": 12566.4,
        "receivers": {"desk": {"quantity": "illuminance", "unit": "lx", "cells": [2, 1],
            "values": [1.0, 2.0], "sigma": [0.1, null], "hits": [3, 0], "mean": 1.5,
            "rel_error": {"arithmetic": 0.1, "quadratic": 0.1}}},
        "global": {"triangles": 12, "area_m2": 114.0, "mean_illuminance_lx": 210.0,
            "rel_error": {"arithmetic": 0.004, "quadratic": 0.0035},
            "indirect_rel_error": {"arithmetic": 0.006, "quadratic": 0.005}},
        "history": [], "forecast": null}"#;
    std::fs::write(dir.join("summary.json"), old).unwrap();
    luxtally::output::rebuild_report(&dir).expect("an older summary rebuilds");
    assert!(dir.join("report.html").is_file());
    assert!(dir.join("receivers/desk.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two skies and a sun over an open receiver: summary.json's `sky_plots` has a plot per
/// sky (none for the sun), 64 × 64 pixels, null exactly beyond the horizon circle, each
/// sky's marker (type 12 its own sun, type 16 the scene's), and ∫L cos θ dω summed over
/// the pixels gives each sky's horizontal illuminance. In the equidistant projection a
/// pixel of side h = 2/64 at radius r (zenith angle θ = r·π/2) spans h²·(π/2)·sin θ/r sr.
/// The tolerance is the midpoint rule's error bound on this grid: a pixel the horizon
/// cuts errs by at most h²·(π²/4)·L_h·√2h/(1 − √2h) (the integrand g = L cos θ·(π/2)
/// sin θ/r falls to 0 at the horizon with slope (π²/4)·L·sin θ/r, and such a pixel lies
/// within √2h of it), there are at most 8/h + 4 of them (a quarter circle, monotone,
/// crosses at most 2/h + 1 pixels), and the whole pixels add their leading error
/// (h²/24)·∮∂g/∂n = π³h²L_h/48; L_h the greatest luminance within √2h of the horizon.
#[test]
fn sky_plots_in_summary_integrate_to_each_skys_horizontal_illuminance() {
    let toml = r#"
name = "skies"
[[lights]]
type = "sky"
cie_type = 12
sun_altitude_deg = 30
sun_azimuth_deg = 200
horizontal_illuminance_lx = 10000
[[lights]]
type = "sky"
cie_type = 16
zenith_luminance_cdm2 = 3000
[[lights]]
type = "sun"
direct_normal_lx = 80000
sun_altitude_deg = 40
sun_azimuth_deg = 120
[[receivers]]
name = "open"
corner = [0, 0, 0]
u = [1, 0, 0]
v = [0, 1, 0]
cells = [2, 2]
"#;
    let scene = scene(toml);
    let opts = options(&scene, 20_000, 2, Backend::Embree);
    let result = run(&scene, &opts, &AtomicBool::new(false), &mut ()).expect("run succeeds");
    let state = result.state(&scene, &opts);
    let dir = temp_dir("sky-plots");
    let finished = Finished {
        run: Some(&state),
        image: None,
    };
    write_all(&dir, finished, Outputs::ALL).expect("outputs written");
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    let s: summary::Summary = serde_json::from_str(&text).expect("summary.json reads back");
    let labels: Vec<&str> = s.sky_plots.iter().map(|p| p.light.as_str()).collect();
    assert_eq!(
        labels,
        ["lights[0]", "lights[1]"],
        "a plot per sky, none for the sun"
    );
    let want_lx = [10_000.0, 7.0 * PI / 9.0 * 3000.0];
    let markers = [("lights[0]", 30.0, 200.0), ("lights[2]", 40.0, 120.0)];
    for ((plot, want), (from, alt, az)) in s.sky_plots.iter().zip(want_lx).zip(markers) {
        let n = plot.size;
        assert_eq!((n, plot.luminance_cdm2.len()), (64, 64 * 64));
        assert_eq!(plot.projection, "equidistant");
        assert_eq!(plot.sun_light.as_deref(), Some(from));
        assert!((plot.sun_altitude_deg.unwrap() - alt).abs() < 1e-9);
        assert!((plot.sun_azimuth_deg.unwrap() - az).abs() < 1e-9);
        let h = 2.0 / n as f64;
        let mut sum_lx = 0.0;
        for (k, &l) in plot.luminance_cdm2.iter().enumerate() {
            let x = (k % n) as f64 * h + h / 2.0 - 1.0;
            let y = 1.0 - (k / n) as f64 * h - h / 2.0;
            let r = (x * x + y * y).sqrt();
            assert_eq!(l.is_nan(), r >= 1.0, "pixel {k} at radius {r}: {l}");
            if r < 1.0 {
                let theta = r * PI / 2.0;
                sum_lx += l * libm::cos(theta) * h * h * PI / 2.0 * libm::sin(theta) / r;
            }
        }
        let light = &scene
            .lights
            .iter()
            .find(|l| l.label == plot.light)
            .unwrap()
            .kind;
        let band_deg = 2f64.sqrt() * h * 90.0;
        let l_h = (0..3600 * 8)
            .map(|k| {
                let alt = (k / 3600) as f64 / 7.0 * band_deg + 1e-6;
                let w = direction(alt, (k % 3600) as f64 / 10.0);
                light.daylight(w).unwrap().sky_luminance_cdm2.unwrap()
            })
            .fold(0.0, f64::max);
        // sin θ/r ≤ 1/r ≤ 1/(1 − √2h) in those pixels.
        let edge = l_h * 2f64.sqrt() * h / (1.0 - 2f64.sqrt() * h);
        let boundary = (8.0 / h + 4.0) * h * h * (PI * PI / 4.0) * edge;
        let tolerance = boundary + PI * PI * PI * h * h * l_h / 48.0;
        eprintln!(
            "{}: ∑L cos θ ω = {sum_lx} lx, exact {want}, tolerance {tolerance}",
            plot.light
        );
        assert!(
            (sum_lx - want).abs() <= tolerance,
            "{}: ∑L cos θ ω = {sum_lx} lx against {want} (tolerance {tolerance})",
            plot.light
        );
    }
}

//! Every key that holds a coordinate, an extent, a direction or an intensity, given a
//! value beyond f32's range (1e39; 3.4e38, the largest f32, for some): coordinates and
//! extents are refused in one line naming the key (rays reach the ray casters in f32,
//! and Embree aborts on ray origins beyond ±1.844e18), directions work at any finite
//! length, and intensities, which luxtally carries in f64, give results that scale
//! exactly with them.

use std::path::{Path, PathBuf};
use std::process::Command;

const BASE: &str = r#"
[materials.grey]
reflectance = 0.5
[[objects]]
shape = "box"
min = [-5, -5, -1]
max = [5, 5, 0]
material = "grey"
[[objects]]
shape = "rect"
corner = [-5, -5, 4]
u = [0, 10, 0]
v = [10, 0, 0]
material = "grey"
[[objects]]
shape = "sphere"
center = [1, 1, 0.5]
radius = 0.25
material = "grey"
translate = [0, 0, 0]
scale = 1
[[objects]]
shape = "box"
min = [-0.1, -0.1, 0]
max = [0.1, 0.1, 0.2]
material = "grey"
instances = [{ translate = [2, 2, 0], scale = 1 }]
grid = { count = [2, 2], spacing = [0.5, 0.5] }
[[lights]]
type = "point"
position = [0.1, 0.2, 2]
intensity_cd = 100
[[lights]]
type = "spot"
position = [-1, 0.5, 3]
direction = [0, 0, -1]
intensity_cd = 200
cone_deg = 30
[[lights]]
type = "area"
corner = [-0.5, -0.5, 3.5]
u = [1, 0, 0]
v = [0, -1, 0]
luminance_cdm2 = 50
[[lights]]
type = "directional"
direction = [0.2, 0.1, -1]
illuminance_lx = 10
[[receivers]]
name = "floor"
corner = [-2, -2, 0.001]
u = [4, 0, 0]
v = [0, 4, 0]
cells = [4, 4]
[[receivers]]
name = "meter"
corner = [-1, -1, 1]
u = [2, 0, 0]
v = [0, 2, 0]
cells = [2, 2]
quantity = "luminance"
view_direction = [0, 0, -1]
half_angle_deg = 5
[camera]
position = [0, -4, 2]
look_at = [0, 0, 0]
up = [0, 0, 1]
fov_deg = 60
resolution = [16, 12]
"#;

const LUMINAIRE: &str = r#"
[[lights]]
type = "luminaire"
file = "examp1.ies"
position = [0, 0, 2.5]
aim = [0, 0, -1]
multiplier = 1
"#;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("luxtally-f32-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::copy("scenes/photometry/examp1.ies", d.join("examp1.ies")).unwrap();
    d
}

/// `BASE` (and a luminaire) with the `nth` occurrence of `old` (after `after`) replaced.
fn edited(after: &str, old: &str, new: &str) -> String {
    let text = format!("{BASE}{LUMINAIRE}");
    let start = text.find(after).unwrap_or_else(|| panic!("no `{after}`"));
    let at = start
        + text[start..]
            .find(old)
            .unwrap_or_else(|| panic!("no `{old}`"));
    format!("{}{new}{}", &text[..at], &text[at + old.len()..])
}

struct Ran {
    code: Option<i32>,
    stderr: String,
    out: PathBuf,
}

fn run(dir: &Path, text: &str, command: &str) -> Ran {
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let out = dir.join("out");
    let _ = std::fs::remove_dir_all(&out);
    let o = Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .current_dir(dir)
        .args([
            command,
            "s.toml",
            "--out",
            "out",
            "--photons",
            "4000",
            "--quiet",
        ])
        .args(["--threads", "2", "--seed", "5"])
        .output()
        .unwrap();
    Ran {
        code: o.status.code(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
        out,
    }
}

/// (where in the file, the text there, the text beyond f32, the key the message names).
const COORDINATES: &[(&str, &str, &str, &str)] = &[
    (
        "shape = \"box\"",
        "min = [-5",
        "min = [-1e39",
        "objects[0].min",
    ),
    (
        "shape = \"box\"",
        "max = [5",
        "max = [3.4e38",
        "objects[0].max",
    ),
    (
        "shape = \"rect\"",
        "corner = [-5",
        "corner = [-1e39",
        "objects[1].corner",
    ),
    (
        "shape = \"rect\"",
        "u = [0, 10",
        "u = [0, 1e39",
        "objects[1].u",
    ),
    ("shape = \"rect\"", "v = [10", "v = [1e39", "objects[1].v"),
    (
        "shape = \"sphere\"",
        "center = [1",
        "center = [1e39",
        "objects[2].center",
    ),
    (
        "shape = \"sphere\"",
        "radius = 0.25",
        "radius = 1e39",
        "objects[2].radius",
    ),
    (
        "shape = \"sphere\"",
        "translate = [0",
        "translate = [3.4e38",
        "objects[2].translate",
    ),
    (
        "shape = \"sphere\"",
        "scale = 1",
        "scale = 1e39",
        "objects[2]",
    ),
    (
        "instances",
        "translate = [2",
        "translate = [1e39",
        "objects[3].instances[0].translate",
    ),
    ("instances", "scale = 1 }", "scale = 1e39 }", "objects[3]"),
    (
        "grid",
        "spacing = [0.5",
        "spacing = [1e39",
        "objects[3].grid.spacing[0]",
    ),
    (
        "type = \"point\"",
        "position = [0.1",
        "position = [1e39",
        "lights[0].position",
    ),
    (
        "type = \"spot\"",
        "position = [-1",
        "position = [-1e39",
        "lights[1].position",
    ),
    (
        "type = \"area\"",
        "corner = [-0.5",
        "corner = [3.4e38",
        "lights[2].corner",
    ),
    ("type = \"area\"", "u = [1", "u = [1e39", "lights[2].u"),
    (
        "type = \"area\"",
        "v = [0, -1",
        "v = [0, -1e39",
        "lights[2].v",
    ),
    (
        "type = \"luminaire\"",
        "position = [0",
        "position = [1e39",
        "lights[4].position",
    ),
    (
        "name = \"floor\"",
        "corner = [-2",
        "corner = [-1e39",
        "receivers[0].corner",
    ),
    ("name = \"floor\"", "u = [4", "u = [1e39", "receivers[0].u"),
    (
        "name = \"floor\"",
        "v = [0, 4",
        "v = [0, 3.4e38",
        "receivers[0].v",
    ),
    (
        "[camera]",
        "position = [0",
        "position = [1e39",
        "camera.position",
    ),
    (
        "[camera]",
        "look_at = [0",
        "look_at = [1e39",
        "camera.look_at",
    ),
];

#[test]
fn coordinates_and_extents_beyond_f32_are_refused_naming_the_key() {
    let d = dir("coordinates");
    for (after, old, new, key) in COORDINATES {
        let ran = run(&d, &edited(after, old, new), "run");
        let message = ran.stderr.trim();
        assert_eq!(ran.code, Some(1), "{new} at {key}: {message}");
        assert_eq!(message.lines().count(), 1, "{key}: {message}");
        assert!(
            message.contains(&format!("s.toml: {key}")) && message.contains("beyond"),
            "{key}: {message}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn luminaire_positions_beyond_f32_are_refused_naming_the_entry() {
    let d = dir("positions");
    let text = edited(
        "type = \"luminaire\"",
        "position = [0, 0, 2.5]",
        "positions = [[0, 0, 2.5], [1, 0, 2.5], [0, -1e39, 2.5]]",
    );
    let ran = run(&d, &text, "run");
    let message = ran.stderr.trim();
    assert_eq!(ran.code, Some(1), "{message}");
    assert!(
        message.contains("s.toml: lights[4].positions[2]") && message.contains("beyond"),
        "{message}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Angles (degrees) beyond f32's range: a result, or one line naming the key.
#[test]
fn angles_beyond_f32_give_a_result_or_name_the_key() {
    let d = dir("angles");
    let cases = [
        (
            "type = \"spot\"",
            "cone_deg = 30",
            "cone_deg = 1e39",
            "lights[1].cone_deg",
        ),
        (
            "shape = \"sphere\"",
            "scale = 1",
            "scale = 1\nrotate_deg = [1e39, 0, 0]",
            "",
        ),
        (
            "name = \"meter\"",
            "half_angle_deg = 5",
            "half_angle_deg = 1e39",
            "receivers[1].half_angle_deg",
        ),
        (
            "[camera]",
            "fov_deg = 60",
            "fov_deg = 1e39",
            "camera.fov_deg",
        ),
        (
            "type = \"luminaire\"",
            "multiplier = 1",
            "multiplier = 1\nrotate_deg = 1e39",
            "",
        ),
    ];
    for (after, old, new, key) in cases {
        let ran = run(&d, &edited(after, old, new), "render");
        let message = ran.stderr.trim();
        match ran.code {
            Some(0) => assert!(key.is_empty(), "{new} was accepted"),
            Some(1) => assert!(
                message.lines().count() == 1 && !key.is_empty() && message.contains(key),
                "{new}: {message}"
            ),
            other => panic!("{new}: {other:?} {message}"),
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn coordinates_up_to_the_limit_run() {
    let d = dir("limit");
    // A floor 1e16 m from the scene's centre: the largest coordinate a scene may hold.
    let ran = run(
        &d,
        &edited("shape = \"box\"", "min = [-5", "min = [-1e16"),
        "run",
    );
    assert_eq!(ran.code, Some(0), "{}", ran.stderr);
    let ran = run(
        &d,
        &edited("shape = \"box\"", "min = [-5", "min = [-1.0000001e16"),
        "run",
    );
    assert_eq!(ran.code, Some(1), "{}", ran.stderr);
    let _ = std::fs::remove_dir_all(&d);
}

/// The floor receiver's cell values and the camera's luminance from `text`.
fn floor_values(ran: &Ran) -> Vec<f64> {
    assert_eq!(ran.code, Some(0), "{}", ran.stderr);
    let summary = std::fs::read(ran.out.join("summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_slice(&summary).unwrap();
    summary["receivers"]["floor"]["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

#[test]
fn directions_of_any_finite_length_work() {
    let d = dir("directions");
    let reference = floor_values(&run(&d, &edited("", "", ""), "run"));
    let cases = [
        (
            "type = \"spot\"",
            "direction = [0, 0, -1]",
            "direction = [0, 0, -1e39]",
        ),
        (
            "type = \"spot\"",
            "direction = [0, 0, -1]",
            "direction = [0, 0, -1e-300]",
        ),
        (
            "type = \"directional\"",
            "direction = [0.2, 0.1, -1]",
            "direction = [2e300, 1e300, -1e301]",
        ),
        (
            "type = \"luminaire\"",
            "aim = [0, 0, -1]",
            "aim = [0, 0, -3.4e38]",
        ),
        (
            "name = \"meter\"",
            "view_direction = [0, 0, -1]",
            "view_direction = [0, 0, -1e39]",
        ),
        ("[camera]", "up = [0, 0, 1]", "up = [0, 0, 1e39]"),
    ];
    for (after, old, new) in cases {
        let ran = run(&d, &edited(after, old, new), "run");
        let values = floor_values(&ran);
        // A direction scaled by a power of ten normalises to the same unit vector within
        // an ulp or two: the same photons, the same cells to 1e-9.
        for (a, b) in values.iter().zip(&reference) {
            assert!(
                (a - b).abs() <= 1e-9 * b.abs().max(1e-300),
                "{new}: {a} vs {b}"
            );
        }
    }
    let ran = run(
        &d,
        &edited("[camera]", "up = [0, 0, 1]", "up = [0, 0, 1e39]"),
        "render",
    );
    assert_eq!(ran.code, Some(0), "render: {}", ran.stderr);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn intensities_beyond_f32_scale_the_results_exactly() {
    let d = dir("intensities");
    // Every light's intensity times 1e40 (the directional one and the luminaires too):
    // the same photons carry 1e40 times the flux, so every cell is 1e40 times as bright.
    let second = "[[lights]]\ntype = \"luminaire\"\nfile = \"examp1.ies\"\nposition = [1, 1, 2.5]\nflux_lm = 1000\n";
    let reference = format!("{BASE}{LUMINAIRE}{second}");
    let reference = floor_values(&run(&d, &reference, "run"));
    let mut text = format!("{BASE}{LUMINAIRE}{second}");
    for (old, new) in [
        ("intensity_cd = 100", "intensity_cd = 100e40"),
        ("intensity_cd = 200", "intensity_cd = 200e40"),
        ("luminance_cdm2 = 50", "luminance_cdm2 = 50e40"),
        ("illuminance_lx = 10", "illuminance_lx = 10e40"),
        ("multiplier = 1", "multiplier = 1e40"),
        ("flux_lm = 1000", "flux_lm = 1000e40"),
    ] {
        assert!(text.contains(old));
        text = text.replace(old, new);
    }
    let scaled = floor_values(&run(&d, &text, "run"));
    for (a, b) in scaled.iter().zip(&reference) {
        assert!(a.is_finite(), "{a}");
        assert!((a / 1e40 - b).abs() <= 1e-9 * b.abs(), "{a} vs {b} × 1e40");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `BASE` with its luminaire reading `file`, written into `d` with `text`.
fn with_photometry(d: &Path, file: &str, text: &str) -> Ran {
    std::fs::write(d.join(file), text).unwrap();
    run(
        d,
        &edited("", "file = \"examp1.ies\"", &format!("file = \"{file}\"")),
        "run",
    )
}

#[test]
fn photometry_openings_beyond_f32_are_refused_naming_the_line() {
    let d = dir("photometry");
    let ies = std::fs::read_to_string("tests/data/photometry/opening_feet.ies").unwrap();
    let line = "1 -1 1 37 1 1 1 2 4 0.5";
    assert!(ies.contains(line));
    for (bad, what) in [
        ("1 -1 1 37 1 1 1 -1e300 4 0.5", "luminous width"),
        ("1 -1 1 37 1 1 1 2 1e39 0.5", "luminous length"),
        ("1 -1 1 37 1 1 1 2 4 -3.4e38", "luminous height"),
    ] {
        let ran = with_photometry(&d, "wide.ies", &ies.replace(line, bad));
        let message = ran.stderr.trim();
        assert_eq!(ran.code, Some(1), "{bad}: {message}");
        assert_eq!(message.lines().count(), 1, "{message}");
        assert!(
            message.contains("wide.ies") && message.contains(what) && message.contains("beyond"),
            "{message}"
        );
    }
    // EULUMDAT's luminous area length (line 16) in mm.
    let ldt = std::fs::read_to_string("tests/data/photometry/cosine.ldt").unwrap();
    let mut lines: Vec<&str> = ldt.lines().collect();
    lines[15] = "1e39";
    let ran = with_photometry(&d, "wide.ldt", &lines.join("\r\n"));
    let message = ran.stderr.trim();
    assert_eq!(ran.code, Some(1), "{message}");
    assert!(
        message.contains("wide.ldt")
            && message.contains("luminous area length")
            && message.contains("beyond"),
        "{message}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn mesh_vertices_beyond_f32_are_refused_naming_the_object() {
    let d = dir("mesh");
    for vertex in ["1e39", "3.4e38", "-1e17"] {
        let obj = format!("v 0 0 0\nv 1 0 0\nv 0 {vertex} 0\nf 1 2 3\n");
        std::fs::write(d.join("far.obj"), obj).unwrap();
        let text = format!("{BASE}\n[[objects]]\nfile = \"far.obj\"\nmaterial = \"grey\"\n");
        let ran = run(&d, &text, "run");
        let message = ran.stderr.trim();
        assert_eq!(ran.code, Some(1), "{vertex}: {message}");
        assert_eq!(message.lines().count(), 1, "{message}");
        assert!(
            message.contains("objects[4]")
                && (message.contains("beyond") || message.contains("finite")),
            "{vertex}: {message}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

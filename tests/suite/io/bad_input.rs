//! Bad scene input: every case is an error (never a panic) whose message is one line that
//! names the file and the key at fault.

use luxtally::scene;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A unique path under the temp directory (tests run in parallel).
fn temp_path(name: &str) -> PathBuf {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("luxtally-bad-{}-{n}-{name}", std::process::id()))
}

fn write(name: &str, contents: &[u8]) -> PathBuf {
    let path = temp_path(name);
    std::fs::write(&path, contents).unwrap();
    path
}

/// Loads `text` as a scene file and returns its error message, checked to be one line
/// naming the file; `luxtally run` on the same file must print that line and exit 1.
fn error_of(text: &str) -> String {
    let path = write("scene.toml", text.as_bytes());
    let result = scene::load(&path);
    let cli = std::process::Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(["run", path.to_str().unwrap(), "--quiet", "--out"])
        .arg(temp_path("out"))
        .output()
        .expect("binary runs");
    let _ = std::fs::remove_file(&path);
    let message = match result {
        Ok(_) => panic!("scene loaded but should not have:\n{text}"),
        Err(e) => e.to_string(),
    };
    eprintln!("{message}");
    assert!(!message.contains('\n'), "not one line: {message:?}");
    let stderr = String::from_utf8_lossy(&cli.stderr);
    assert_eq!(
        cli.status.code(),
        Some(1),
        "exit code of `luxtally run`: {stderr}"
    );
    assert_eq!(
        stderr.trim_end(),
        format!("luxtally: {message}"),
        "the CLI prints the message as one line"
    );
    assert!(
        message.contains(&path.display().to_string()),
        "does not name the file: {message}"
    );
    message
}

fn assert_has(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(message.contains(p), "`{p}` missing from: {message}");
    }
}

const GREY: &str = "[materials.grey]\nreflectance = 0.5\n";
const RECEIVER: &str = "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\ncells = [2, 2]\n";

#[test]
fn missing_scene_file_names_the_path() {
    let path = temp_path("does-not-exist.toml");
    let message = match scene::load(&path) {
        Ok(_) => panic!("loaded a missing file"),
        Err(e) => e.to_string(),
    };
    assert!(!message.contains('\n'));
    assert_has(&message, &[&path.display().to_string()]);
}

#[test]
fn missing_mesh_file_names_the_mesh_and_the_key() {
    let m = error_of(&format!(
        "{GREY}[[objects]]\nfile = \"no-such-mesh.obj\"\nmaterial = \"grey\"\n"
    ));
    assert_has(&m, &["objects[0].file", "no-such-mesh.obj"]);
}

#[test]
fn malformed_toml_names_line_and_column() {
    let m = error_of("name = \"x\"\n[[objects]\nshape = \"box\"\n");
    assert_has(&m, &["line 2, column"]);
}

#[test]
fn malformed_obj_names_the_mesh_and_tobj_reason() {
    let obj = write("bad.obj", b"v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n");
    let m = error_of(&format!(
        "{GREY}[[objects]]\nfile = \"{}\"\nmaterial = \"grey\"\n",
        obj.display()
    ));
    let _ = std::fs::remove_file(&obj);
    assert_has(&m, &["objects[0].file", "bad.obj", "malformed OBJ"]);
}

#[test]
fn obj_face_index_out_of_range_is_an_error() {
    let obj = write("range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    let m = error_of(&format!(
        "{GREY}[[objects]]\nfile = \"{}\"\nmaterial = \"grey\"\n",
        obj.display()
    ));
    let _ = std::fs::remove_file(&obj);
    assert_has(&m, &["objects[0].file", "range.obj"]);
}

#[test]
fn obj_without_material_asks_for_an_override() {
    let obj = write("plain.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let m = error_of(&format!("[[objects]]\nfile = \"{}\"\n", obj.display()));
    let _ = std::fs::remove_file(&obj);
    assert_has(&m, &["objects[0].material", "set `material"]);
}

#[test]
fn malformed_gltf_names_the_mesh() {
    let gltf = write("bad.gltf", b"{ \"asset\": { \"version\": ");
    let m = error_of(&format!(
        "{GREY}[[objects]]\nfile = \"{}\"\nmaterial = \"grey\"\n",
        gltf.display()
    ));
    let _ = std::fs::remove_file(&gltf);
    assert_has(&m, &["objects[0].file", "bad.gltf", "malformed glTF"]);
}

#[test]
fn gltf_with_out_of_range_data_is_an_error_not_a_panic() {
    // The accessor claims 30 vertices but the buffer holds 36 bytes; indices point past
    // the end; a node is its own child.
    let cases = [
        r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
           "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
           "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
           "bufferViews":[{"buffer":0,"byteLength":36}],
           "accessors":[{"bufferView":0,"componentType":5126,"count":30,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]}"#,
        r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
           "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
           "buffers":[{"byteLength":40,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAEJAA=="}],
           "bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":4}],
           "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
                        {"bufferView":1,"componentType":5121,"count":3,"type":"SCALAR"}]}"#,
        r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"children":[0]}]}"#,
        r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":100,"uri":"data:application/octet-stream;base64,AAAA"}]}"#,
    ];
    for (k, json) in cases.iter().enumerate() {
        let gltf = write(&format!("broken{k}.gltf"), json.as_bytes());
        let m = error_of(&format!(
            "{GREY}[[objects]]\nfile = \"{}\"\nmaterial = \"grey\"\n",
            gltf.display()
        ));
        let _ = std::fs::remove_file(&gltf);
        assert_has(&m, &["objects[0].file", &format!("broken{k}.gltf")]);
    }
}

#[test]
fn nan_is_rejected_with_its_key_path() {
    let m = error_of("[[lights]]\ntype = \"point\"\nposition = [3, nan, 2.8]\nintensity_cd = 1\n");
    assert_has(&m, &["lights[0].position: value is not finite"]);
}

#[test]
fn infinity_is_rejected_with_its_key_path() {
    let m = error_of("[materials.wall]\nreflectance = inf\n");
    assert_has(&m, &["materials.wall.reflectance: value is not finite"]);
}

#[test]
fn unknown_key_is_named() {
    let m = error_of(&format!(
        "{GREY}[[objects]]\nshape = \"box\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nmaterial = \"grey\"\ncolour = \"red\"\n"
    ));
    assert_has(&m, &["objects[0]", "unknown field `colour`"]);
    let m = error_of("[simulation]\nphotns = 10\n");
    assert_has(
        &m,
        &[
            "simulation.photns",
            "unknown field `photns`",
            "`seed`",
            "`photons`",
        ],
    );
    let m = error_of("nmae = \"x\"\n");
    assert_has(&m, &["unknown field `nmae`"]);
}

#[test]
fn wrong_type_names_the_field() {
    let m = error_of(&format!(
        "{GREY}[[objects]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = \"big\"\nmaterial = \"grey\"\n"
    ));
    assert_has(&m, &["objects[0].radius"]);
}

#[test]
fn unknown_material_is_named() {
    let m = error_of(&format!(
        "{GREY}[[objects]]\nshape = \"box\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nmaterial = \"grey\"\n[[objects]]\nshape = \"rect\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\nmaterial = \"glass\"\n"
    ));
    assert_has(&m, &["objects[1].material", "unknown material `glass`"]);
}

#[test]
fn energy_creating_material_is_rejected() {
    let m = error_of("[materials.bright]\nreflectance = 0.8\nspecular_reflectance = 0.4\n");
    assert_has(
        &m,
        &[
            "materials.bright",
            "energy-creating material",
            "= 1.2",
            "> 1",
        ],
    );
    let m = error_of("[materials.neg]\nreflectance = -0.1\n");
    assert_has(&m, &["materials.neg.reflectance"]);
    let m = error_of("[materials.glass]\nspecular_transmittance = 0.9\nior = 0.9\n");
    assert_has(&m, &["materials.glass.ior"]);
}

#[test]
fn zero_area_receiver_is_rejected() {
    let m = error_of(
        "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [2, 0, 0]\ncells = [2, 2]\n",
    );
    assert_has(&m, &["receivers[0]", "zero-area receiver"]);
}

#[test]
fn zero_cells_are_rejected() {
    let m = error_of(
        "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\ncells = [0, 4]\n",
    );
    assert_has(&m, &["receivers[0].cells", "zero cells"]);
}

#[test]
fn bad_light_parameters_are_rejected() {
    let cases: &[(&str, &[&str])] = &[
        ("type = \"point\"\nposition = [0, 0, 0]\nflux_lm = -5\n", &["lights[0].flux_lm"]),
        ("type = \"point\"\nposition = [0, 0, 0]\nintensity_cd = 1\nflux_lm = 5\n", &["lights[0]", "exactly one"]),
        ("type = \"point\"\nposition = [0, 0, 0]\n", &["lights[0]", "exactly one"]),
        ("type = \"point\"\nintensity_cd = 1\n", &["lights[0].position", "missing"]),
        ("type = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 0, 0]\nintensity_cd = 1\ncone_deg = 30\n", &["lights[0].direction", "zero direction"]),
        ("type = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 0, -1]\nintensity_cd = 1\ncone_deg = 200\n", &["lights[0].cone_deg"]),
        ("type = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 0, -1]\nintensity_cd = 1\ncone_deg = 30\nfalloff_deg = 40\n", &["lights[0].falloff_deg"]),
        ("type = \"directional\"\ndirection = [0, 0, -1]\nilluminance_lx = -1\n", &["lights[0].illuminance_lx"]),
        ("type = \"area\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [1, 0, 0]\nflux_lm = 10\n", &["lights[0]", "zero-area light"]),
        ("type = \"area\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\nflux_lm = 10\nposition = [0, 0, 0]\n", &["lights[0].position", "does not apply"]),
        ("type = \"laser\"\n", &["lights[0].type", "unknown light type"]),
    ];
    for (light, parts) in cases {
        let m = error_of(&format!("[[lights]]\n{light}"));
        assert_has(&m, parts);
    }
}

#[test]
fn duplicate_receiver_name_is_rejected() {
    let m = error_of(&format!("{RECEIVER}{RECEIVER}"));
    assert_has(&m, &["receivers[1].name", "duplicate receiver name `r`"]);
}

#[test]
fn bad_shape_parameters_are_rejected() {
    let cases: &[(&str, &[&str])] = &[
        (
            "shape = \"box\"\nmin = [0, 0, 0]\nmax = [1, 0, 1]\n",
            &["objects[0].max"],
        ),
        (
            "shape = \"box\"\nmin = [0, 0, 0]\n",
            &["objects[0].max", "missing"],
        ),
        (
            "shape = \"rect\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [2, 0, 0]\n",
            &["objects[0]", "zero-area rect"],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0\n",
            &["objects[0].radius"],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nsubdivisions = 9\n",
            &["objects[0].subdivisions"],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmin = [0, 0, 0]\n",
            &["objects[0].min", "does not apply"],
        ),
        ("shape = \"cone\"\n", &["objects[0].shape", "unknown shape"]),
        (
            "shape = \"box\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nscale = -1\n",
            &["objects[0].scale"],
        ),
    ];
    for (object, parts) in cases {
        let m = error_of(&format!("{GREY}[[objects]]\n{object}material = \"grey\"\n"));
        assert_has(&m, parts);
    }
    let m = error_of("[[objects]]\nshape = \"box\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n");
    assert_has(&m, &["objects[0].material", "missing"]);
}

#[test]
fn bad_receiver_and_simulation_parameters_are_rejected() {
    let m = error_of(&format!(
        "{RECEIVER}quantity = \"luminance\"\nview_direction = [0, 0, -1]\nhalf_angle_deg = 95\n"
    ));
    assert_has(&m, &["receivers[0].half_angle_deg"]);
    let m = error_of(&format!(
        "{RECEIVER}quantity = \"luminance\"\nhalf_angle_deg = 5\n"
    ));
    assert_has(&m, &["receivers[0].view_direction", "missing"]);
    let m = error_of(&format!("{RECEIVER}estimator = \"magic\"\n"));
    assert_has(&m, &["receivers[0].estimator"]);
    let m = error_of("[[receivers]]\nname = \"\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\ncells = [2, 2]\n");
    assert_has(&m, &["receivers[0].name", "empty"]);
    let m = error_of("[simulation]\nphotons = 0\n");
    assert_has(&m, &["simulation.photons"]);
    for bad in ["0", "1", "1.5", "-0.5"] {
        let m = error_of(&format!("[simulation]\nconfidence = {bad}\n"));
        assert_has(&m, &["simulation.confidence", "between 0 and 1"]);
    }
    let m = error_of("[simulation]\nqmc = \"yes\"\n");
    assert_has(&m, &["simulation.qmc"]);
    let m = error_of("[simulation]\nqcm = true\n");
    assert_has(&m, &["qcm", "qmc"]);
    let m = error_of("[simulation]\nphotons = -3\n");
    assert_has(&m, &["simulation.photons"]);
    let m = error_of("[simulation]\ntime_limit = 0\n");
    assert_has(&m, &["simulation.time_limit"]);
}

#[test]
fn bad_cylindrical_receivers_are_rejected() {
    let semi = format!("{RECEIVER}quantity = \"semi_cylindrical\"\n");
    let m = error_of(&semi);
    assert_has(&m, &["receivers[0].facing", "missing", "semi_cylindrical"]);
    let m = error_of(&format!("{semi}facing = [0, 0, 1]\n"));
    assert_has(&m, &["receivers[0].facing", "horizontal"]);
    let m = error_of(&format!("{semi}facing = [1, 0, 0.01]\n"));
    assert_has(&m, &["receivers[0].facing", "horizontal"]);
    let m = error_of(&format!("{semi}facing = [0, 0, 0]\n"));
    assert_has(&m, &["receivers[0].facing", "zero direction"]);
    let m = error_of(&format!(
        "{semi}facing = [1, 0, 0]\nview_direction = [0, 0, -1]\n"
    ));
    assert_has(
        &m,
        &[
            "receivers[0].view_direction",
            "only to quantity = \"luminance\"",
        ],
    );
    let cylinder = format!("{RECEIVER}quantity = \"cylindrical\"\n");
    let m = error_of(&format!("{cylinder}facing = [1, 0, 0]\n"));
    assert_has(
        &m,
        &[
            "receivers[0].facing",
            "only to quantity = \"semi_cylindrical\"",
        ],
    );
    let m = error_of(&format!("{cylinder}view_direction = [0, 0, -1]\n"));
    assert_has(
        &m,
        &[
            "receivers[0].view_direction",
            "only to quantity = \"luminance\"",
        ],
    );
    let m = error_of(&format!("{cylinder}half_angle_deg = 10\n"));
    assert_has(
        &m,
        &[
            "receivers[0].half_angle_deg",
            "only to quantity = \"luminance\"",
        ],
    );
    let m = error_of(&format!("{RECEIVER}facing = [1, 0, 0]\n"));
    assert_has(
        &m,
        &[
            "receivers[0].facing",
            "only to quantity = \"semi_cylindrical\"",
        ],
    );
    let m = error_of(&format!(
        "{RECEIVER}quantity = \"luminance\"\nview_direction = [0, 0, -1]\nhalf_angle_deg = 5\nfacing = [1, 0, 0]\n"
    ));
    assert_has(
        &m,
        &[
            "receivers[0].facing",
            "only to quantity = \"semi_cylindrical\"",
        ],
    );
    let m = error_of(&format!("{RECEIVER}quantity = \"spherical\"\n"));
    assert_has(
        &m,
        &["receivers[0].quantity", "cylindrical", "semi_cylindrical"],
    );
}

/// A receiver without `cells`, for the `grid` keys.
const GRID_RECEIVER: &str =
    "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [3, 0, 0]\nv = [0, 2, 0]\n";

#[test]
fn bad_calculation_grids_are_rejected() {
    let m = error_of(&format!("{RECEIVER}grid = \"en12464\"\n"));
    assert_has(&m, &["receivers[0].grid", "not both"]);
    let m = error_of(GRID_RECEIVER);
    assert_has(&m, &["receivers[0].cells", "missing", "grid = \"en12464\""]);
    let m = error_of(&format!("{GRID_RECEIVER}grid = \"en12193\"\n"));
    assert_has(&m, &["receivers[0].grid", "en12464"]);
    let m = error_of(&format!(
        "{GRID_RECEIVER}grid = \"en12464\"\ngrid_band_m = -0.5\n"
    ));
    assert_has(&m, &["receivers[0].grid_band_m", "≥ 0", "-0.5"]);
    // 2 m wide: a 1 m band on both sides leaves nothing; so does the default 0.5 m band
    // on a 1 m side.
    let m = error_of(&format!(
        "{GRID_RECEIVER}grid = \"en12464\"\ngrid_band_m = 1\n"
    ));
    assert_has(&m, &["receivers[0].grid_band_m", "leaves no area"]);
    let m = error_of(
        "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [3, 0, 0]\nv = [0, 1, 0]\ngrid = \"en12464\"\n",
    );
    assert_has(
        &m,
        &["receivers[0].grid_band_m", "0.5 m band", "leaves no area"],
    );
    let m = error_of(&format!(
        "{GRID_RECEIVER}grid = \"en12464\"\ngrid_rounding = \"odd\"\n"
    ));
    assert_has(&m, &["receivers[0].grid_rounding", "up", "nearest"]);
    let m = error_of(&format!("{RECEIVER}grid_band_m = 0.5\n"));
    assert_has(&m, &["receivers[0].grid_band_m", "only to grid"]);
    let m = error_of(&format!("{RECEIVER}grid_rounding = \"up\"\n"));
    assert_has(&m, &["receivers[0].grid_rounding", "only to grid"]);
    // More points than a receiver holds: an error, not a wrapped count.
    let m = error_of(
        "[[receivers]]\nname = \"r\"\ncorner = [0, 0, 0]\nu = [1e12, 0, 0]\nv = [0, 1e12, 0]\ngrid = \"en12464\"\n",
    );
    assert_has(&m, &["receivers[0].grid", "points along u"]);
}

/// A small deterministic generator for the mutation test (no dependency needed).
fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

#[test]
fn mutated_scene_and_mesh_files_never_panic() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    for name in [
        "office.toml",
        "gltf/Box.gltf",
        "gltf/OrientationTest.glb",
        "meshes/cornell_box.obj",
    ] {
        let original = std::fs::read(dir.join(name)).unwrap();
        let ext = name.rsplit('.').next().unwrap_or("bin");
        for _ in 0..300 {
            let mut bytes = original.clone();
            // Overwrite a few random bytes, sometimes truncate.
            for _ in 0..1 + xorshift(&mut state) % 4 {
                let at = (xorshift(&mut state) % bytes.len() as u64) as usize;
                bytes[at] = (xorshift(&mut state) % 256) as u8;
            }
            if xorshift(&mut state).is_multiple_of(4) {
                bytes.truncate((xorshift(&mut state) % bytes.len() as u64) as usize);
            }
            if ext == "toml" {
                let text = String::from_utf8_lossy(&bytes);
                let _ = scene::load_str(&text, &dir, "mutated.toml");
            } else {
                let mesh = write(&format!("mutated.{ext}"), &bytes);
                let text = format!(
                    "{GREY}[[objects]]\nfile = \"{}\"\nmaterial = \"grey\"\n",
                    mesh.display()
                );
                let _ = scene::load_str(&text, &dir, "mutated.toml");
                let _ = std::fs::remove_file(&mesh);
            }
        }
    }
}

/// A GLB whose vertex is not finite, or whose index points past its vertices: the
/// loader's parallel path for tightly packed data names the culprit as the per-item
/// path does (the first bad vertex or index).
#[test]
fn glb_with_a_bad_vertex_or_index_names_it() {
    use glam::DVec3;
    let v = [
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::new(1.0, 1.0, f64::NAN),
    ];
    type Case<'a> = (&'a [DVec3], &'a [[u32; 3]], &'a str);
    let cases: [Case; 2] = [
        (&v, &[[0, 1, 2], [1, 3, 2]], "is not finite"),
        (
            &v[..3],
            &[[0, 1, 2], [0, 2, 7]],
            "index 7 out of range (3 vertices)",
        ),
    ];
    for (k, (vertices, triangles, what)) in cases.iter().enumerate() {
        let glb = temp_path(&format!("bad{k}.glb"));
        luxtally::fixtures::write_glb(&glb, vertices, triangles).unwrap();
        let m = error_of(&format!(
            "{GREY}[[objects]]\nfile = \"{}\"\nmaterial = \"grey\"\n",
            glb.display()
        ));
        let _ = std::fs::remove_file(&glb);
        assert_has(&m, &["objects[0].file", &format!("bad{k}.glb"), what]);
    }
}

#[test]
fn bad_requirements_are_rejected_in_one_line() {
    let req = |keys: &str| format!("{RECEIVER}[[requirements]]\n{keys}\n");
    let m = error_of(&req("receiver = \"desk\"\nem = 500"));
    assert_has(
        &m,
        &["requirements[0].receiver", "no receiver named `desk`"],
    );
    for bad in ["0", "1.2", "-0.5"] {
        let m = error_of(&req(&format!("receiver = \"r\"\nu0 = {bad}")));
        assert_has(&m, &["requirements[0].u0", "in (0, 1]"]);
    }
    let m = error_of(&req("receiver = \"r\"\ng2 = 2"));
    assert_has(&m, &["requirements[0].g2", "in (0, 1]"]);
    let m = error_of(&req("receiver = \"r\"\nem = -500"));
    assert_has(&m, &["requirements[0].em", "positive"]);
    let m = error_of(&req("receiver = \"r\""));
    assert_has(&m, &["requirements[0]", "sets no figure"]);
    let m = error_of(&req("receiver = \"r\"\nugr = 19"));
    assert_has(&m, &["requirements[0]", "ugr"]);
    // An observer's figure on a receiver, a receiver's on an observer, neither, both.
    let m = error_of(&req("receiver = \"r\"\nugr_max = 19"));
    assert_has(
        &m,
        &["requirements[0].ugr_max", "applies only to an observer"],
    );
    let m = error_of(&req("observer = \"eye\"\nugr_max = 19"));
    assert_has(&m, &["requirements[0].observer", "no observer named `eye`"]);
    let m = error_of(&req("em = 1"));
    assert_has(
        &m,
        &[
            "requirements[0]",
            "exactly one of `receiver` and `observer`",
        ],
    );
    for bad in ["0", "-3"] {
        let m = error_of(&format!(
            "{}[[observers]]\nname = \"eye\"\nposition = [0, 0, 1.2]\nlook = [1, 0, 0]\n",
            req(&format!("observer = \"eye\"\nugr_max = {bad}"))
        ));
        assert_has(&m, &["requirements[0].ugr_max", "a positive number"]);
    }
    let m = error_of(&format!(
        "{}[[observers]]\nname = \"eye\"\nposition = [0, 0, 1.2]\nlook = [1, 0, 0]\n",
        req("observer = \"eye\"\nem = 100")
    ));
    assert_has(&m, &["requirements[0].em", "applies only to a receiver"]);
    // The modelling ratio: on a cylindrical receiver with a partner, least < most.
    let m = error_of(&req("receiver = \"r\"\nmodelling = [0.3, 0.6]"));
    assert_has(&m, &["requirements[0].modelling", "modelling_with"]);
    let paired = "[[receivers]]\nname = \"z\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\n\
                  v = [0, 1, 0]\ncells = [2, 2]\nquantity = \"cylindrical\"\nmodelling_with = \"r\"\n";
    for bad in ["[0.6, 0.3]", "[0, 0.6]", "[0.3, 0.3]"] {
        let m = error_of(&format!(
            "{paired}{}",
            req(&format!("receiver = \"z\"\nmodelling = {bad}"))
        ));
        assert_has(&m, &["requirements[0].modelling", "0 < least < most"]);
    }
    let bad_partner = |with: &str| {
        error_of(&format!(
            "{RECEIVER}{}",
            paired.replace(
                "modelling_with = \"r\"",
                &format!("modelling_with = \"{with}\"")
            )
        ))
    };
    let m = bad_partner("x");
    assert_has(
        &m,
        &["receivers[1].modelling_with", "no receiver named `x`"],
    );
    let m = bad_partner("z");
    assert_has(&m, &["receivers[1].modelling_with", "another receiver"]);
    let m = error_of(&RECEIVER.replace("cells = [2, 2]", "cells = [2, 2]\nmodelling_with = \"r\""));
    assert_has(&m, &["receivers[0].modelling_with", "cylindrical"]);
    let m = error_of(&format!(
        "{}[[requirements]]\nreceiver = \"r\"\nem = 1\n",
        req("receiver = \"r\"\nem = 1")
    ));
    assert_has(
        &m,
        &["requirements[1].name", "duplicate requirement name `r`"],
    );
}

/// A named task type: unknown ids list the known ones; `area` must be one of the areas,
/// `cylindrical` exactly on a cylindrical receiver; `modified` only where the row has a
/// modified value; `area` and `modified` need a task and a receiver.
#[test]
fn bad_task_types_are_rejected_in_one_line() {
    let req = |keys: &str| format!("{RECEIVER}[[requirements]]\nreceiver = \"r\"\n{keys}\n");
    let m = error_of(&req("task = \"office.nap\""));
    assert_has(
        &m,
        &[
            "requirements[0].task",
            "unknown task type `office.nap`",
            "office.writing",
        ],
    );
    let m = error_of(&req("task = \"office.writing\"\narea = \"floor\""));
    assert_has(&m, &["requirements[0].area", "`floor`", "surrounding"]);
    let m = error_of(&req("task = \"office.writing\"\narea = \"cylindrical\""));
    assert_has(&m, &["requirements[0].area", "cylindrical receiver"]);
    let m = error_of(&req("task = \"office.archives\"\nmodified = true"));
    assert_has(
        &m,
        &[
            "requirements[0].modified",
            "`office.archives` gives no modified value",
        ],
    );
    let m = error_of(&req("area = \"walls\"\nem = 50"));
    assert_has(
        &m,
        &["requirements[0]", "`area` and `modified` need a `task`"],
    );
    let m = error_of(&format!(
        "{RECEIVER}[[observers]]\nname = \"eye\"\nposition = [0, 0, 1.2]\nlook = [1, 0, 0]\n\
         [[requirements]]\nobserver = \"eye\"\ntask = \"office.writing\"\narea = \"task\"\n"
    ));
    assert_has(&m, &["requirements[0]", "not an observer"]);
}

//! Scene loading: built-in shapes, transforms, OBJ and glTF meshes, and the bundled
//! office scene. Expected values come from geometry, computed here.

use glam::DVec3;
use luxtally::light::{Area, Point, Spot};
use luxtally::scene::{self, Estimator, Quantity, Scene};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn load(text: &str) -> Scene {
    match scene::load_str(text, &scenes_dir(), "test.toml") {
        Ok(s) => s,
        Err(e) => panic!("scene failed to load: {e}"),
    }
}

/// World positions of all vertices.
fn world_vertices(s: &Scene) -> Vec<DVec3> {
    let g = &s.geometry;
    g.vertices.iter().map(|v| g.origin + v.as_dvec3()).collect()
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol
}

/// Every triangle's normal points away from `center` (closed convex shapes).
fn assert_outward(s: &Scene, center: DVec3) {
    let g = &s.geometry;
    for (t, tri) in g.triangles.iter().enumerate() {
        let c = tri
            .iter()
            .map(|&i| g.origin + g.vertices[i as usize].as_dvec3())
            .sum::<DVec3>()
            / 3.0;
        assert!(
            g.normal(t).as_dvec3().dot(c - center) > 0.0,
            "triangle {t} faces inward"
        );
    }
}

const MATERIALS: &str = "[materials.grey]\nreflectance = 0.5\n";

#[test]
fn bundled_office_scene_loads_as_the_contract_describes() {
    let s = match scene::load(&scenes_dir().join("office.toml")) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(s.name, "office");
    assert_eq!(s.geometry.triangle_count(), 14);
    let room = 2.0 * (6.0 * 5.0 + 5.0 * 3.0 + 3.0 * 6.0);
    let table = 1.6 * 0.8;
    // Areas are those of the triangles traced, from f32 vertices (the room spans 6 m,
    // the table's edges are 0.8 m: each coordinate within 6 m · ε/2 of the file's).
    let f32_rounding = 16.0 * f64::from(f32::EPSILON) * (room + table);
    assert!((s.geometry.total_area_m2() - (room + table)).abs() < f32_rounding);
    assert_eq!(
        s.lights[0].get::<Point>(),
        Some(&Point {
            position: DVec3::new(3.0, 2.5, 2.8),
            intensity_cd: 1000.0
        })
    );
    assert_eq!(s.lights[0].label, "lights[0]");
    let desk = &s.receivers[0];
    assert_eq!((desk.name.as_str(), desk.cells), ("desk", [64, 32]));
    assert_eq!(desk.quantity, Quantity::Illuminance);
    assert_eq!(desk.estimator, Estimator::Auto);
    assert_eq!(s.simulation.stop.photons, Some(1_000_000));
    assert_eq!(s.simulation.seed, 1);
    let wall = &s.materials[s.geometry.material.get(0) as usize];
    assert_eq!((wall.name.as_str(), wall.reflectance), ("wall", 0.5));
}

#[test]
fn box_has_12_outward_triangles_and_area_2_ab_bc_ca() {
    let s = load(&format!(
        "{MATERIALS}[[objects]]\nshape = \"box\"\nmin = [1, 2, 3]\nmax = [3, 5, 7]\nmaterial = \"grey\"\n"
    ));
    let (a, b, c) = (2.0, 3.0, 4.0);
    assert_eq!(s.geometry.triangle_count(), 12);
    assert!((s.geometry.total_area_m2() - 2.0 * (a * b + b * c + c * a)).abs() < 1e-12);
    assert_outward(&s, DVec3::new(2.0, 3.5, 5.0));
    let (lo, hi) = s.geometry.world_bounds().unwrap();
    assert!(
        close(lo, DVec3::new(1.0, 2.0, 3.0), 1e-12) && close(hi, DVec3::new(3.0, 5.0, 7.0), 1e-12)
    );
}

#[test]
fn icosphere_area_converges_to_4_pi_r2_with_outward_normals() {
    let r = 2.0;
    let exact = 4.0 * PI * r * r;
    let mut previous = f64::INFINITY;
    for level in 0..=5u32 {
        let s = load(&format!(
            "{MATERIALS}[[objects]]\nshape = \"sphere\"\ncenter = [1, 1, 1]\nradius = {r}\nsubdivisions = {level}\nmaterial = \"grey\"\n"
        ));
        let g = &s.geometry;
        assert_eq!(g.triangle_count(), 20 * 4usize.pow(level));
        // Shared vertices: V = 10·4^n + 2 (Euler for a closed triangulated sphere).
        assert_eq!(g.vertices.len(), 10 * 4usize.pow(level) + 2);
        for p in world_vertices(&s) {
            assert!(((p - DVec3::ONE).length() - r).abs() < 1e-5);
        }
        assert_outward(&s, DVec3::ONE);
        let deficit = (exact - g.total_area_m2()) / exact;
        assert!(
            deficit > 0.0 && deficit < previous,
            "level {level}: deficit {deficit}"
        );
        previous = deficit;
    }
    assert!(previous < 0.002, "deficit at level 5: {previous}");
}

#[test]
fn rect_is_two_triangles_with_normal_u_cross_v() {
    let s = load(&format!(
        "{MATERIALS}[[objects]]\nshape = \"rect\"\ncorner = [1, 0, 0]\nu = [0, 2, 0]\nv = [0, 0, 3]\nmaterial = \"grey\"\n"
    ));
    let g = &s.geometry;
    assert_eq!(g.triangle_count(), 2);
    assert!((g.total_area_m2() - 6.0).abs() < 1e-12);
    for n in (0..g.triangle_count()).map(|t| g.normal(t)) {
        assert!(close(n.as_dvec3(), DVec3::X, 1e-6));
    }
}

#[test]
fn transforms_apply_scale_then_rotate_x_y_z_then_translate() {
    // corner+u = (1,0,0): scale 2 → (2,0,0); Rz 90° → (0,2,0); translate → (10,2,0).
    let s = load(&format!(
        "{MATERIALS}[[objects]]\nshape = \"rect\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\nmaterial = \"grey\"\nscale = 2\nrotate_deg = [0, 0, 90]\ntranslate = [10, 0, 0]\n"
    ));
    let v = world_vertices(&s);
    assert!(v
        .iter()
        .any(|p| close(*p, DVec3::new(10.0, 2.0, 0.0), 1e-6)));
    assert!((s.geometry.total_area_m2() - 4.0).abs() < 1e-9);

    // Rotation order: x first, then y. (0,1,0) → Rx 90° → (0,0,1) → Ry 90° → (1,0,0).
    // The other order would give (0,0,1). Per-axis scale [1,3,1] first makes it (0,3,0).
    let s = load(&format!(
        "{MATERIALS}[[objects]]\nshape = \"rect\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\nmaterial = \"grey\"\nscale = [1, 3, 1]\nrotate_deg = [90, 90, 0]\n"
    ));
    let v = world_vertices(&s);
    assert!(
        v.iter().any(|p| close(*p, DVec3::new(3.0, 0.0, 0.0), 1e-6)),
        "{v:?}"
    );
}

#[test]
fn cornell_box_obj_loads_8_models_36_triangles_with_kd_as_reflectance() {
    let s = load("[[objects]]\nfile = \"meshes/cornell_box.obj\"\n");
    let g = &s.geometry;
    assert_eq!(g.triangle_count(), 36);
    let names: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
    assert!(names.contains(&"meshes/cornell_box.obj:white"), "{names:?}");
    let red = s
        .materials
        .iter()
        .find(|m| m.name == "meshes/cornell_box.obj:red")
        .unwrap();
    // Kd 1 0 0 → luminance-weighted reflectance 0.2126.
    assert!((red.reflectance - 0.2126).abs() < 1e-9);
    let white = s
        .materials
        .iter()
        .position(|m| m.name == "meshes/cornell_box.obj:white")
        .unwrap();
    assert!(g.material.iter().any(|m| m == white as u32));
    let (lo, hi) = g.world_bounds().unwrap();
    assert!(close(lo, DVec3::ZERO, 1e-3) && close(hi, DVec3::new(556.0, 548.8, 559.2), 1e-3));
}

#[test]
fn obj_material_override_and_quad_triangulation() {
    let s = load(&format!(
        "{MATERIALS}[[objects]]\nfile = \"meshes/suzanne.obj\"\nmaterial = \"grey\"\n"
    ));
    assert_eq!(s.geometry.triangle_count(), 968);
    assert!(s
        .geometry
        .material
        .iter()
        .all(|m| s.materials[m as usize].name == "grey"));
}

#[test]
fn the_same_obj_twice_shares_its_materials() {
    let s = load(
        "[[objects]]\nfile = \"meshes/cornell_box.obj\"\n[[objects]]\nfile = \"meshes/cornell_box.obj\"\ntranslate = [1000, 0, 0]\n",
    );
    assert_eq!(s.geometry.triangle_count(), 72);
    assert_eq!(s.materials.len(), 5);
    assert_eq!(s.geometry.object.iter().filter(|&o| o == 1).count(), 36);
}

#[test]
fn gltf_box_has_12_triangles_and_its_base_color() {
    let s = load("[[objects]]\nfile = \"gltf/Box.gltf\"\n");
    assert_eq!(s.geometry.triangle_count(), 12);
    let (lo, hi) = s.geometry.world_bounds().unwrap();
    assert!(close(lo, DVec3::splat(-0.5), 1e-6) && close(hi, DVec3::splat(0.5), 1e-6));
    assert_outward(&s, DVec3::ZERO);
    let m = &s.materials[s.geometry.material.get(0) as usize];
    assert_eq!(m.name, "gltf/Box.gltf:0");
    // metallicFactor and roughnessFactor default to 1: a rough metal of albedo Y(base).
    assert!((m.glossy_reflectance - 0.2126 * 0.8).abs() < 1e-6);
    assert_eq!((m.reflectance, m.roughness), (0.0, 1.0));
}

#[test]
fn gltf_duck_glb_applies_its_node_matrix() {
    let s = load(&format!(
        "{MATERIALS}[[objects]]\nfile = \"gltf/Duck.glb\"\nmaterial = \"grey\"\n"
    ));
    assert_eq!(s.geometry.triangle_count(), 4212);
    let (lo, hi) = s.geometry.world_bounds().unwrap();
    assert!(close(lo, DVec3::new(-0.69, 0.10, -0.61), 0.01), "{lo}");
    assert!(close(hi, DVec3::new(0.96, 1.64, 0.54), 0.01), "{hi}");
}

#[test]
fn gltf_orientation_test_has_524_triangles_within_5_33() {
    let s = load("[[objects]]\nfile = \"gltf/OrientationTest.glb\"\n");
    assert_eq!(s.geometry.triangle_count(), 524);
    let (lo, hi) = s.geometry.world_bounds().unwrap();
    assert!(
        close(lo, DVec3::splat(-5.33), 0.01) && close(hi, DVec3::splat(5.33), 0.01),
        "{lo} {hi}"
    );
    assert!(s
        .materials
        .iter()
        .any(|m| m.name == "gltf/OrientationTest.glb:MatX1"));
}

/// One triangle (0,0,0), (1,0,0), (0,1,0) with u16 indices, under a parent node
/// (T = [1,2,3], R = 90° about z, S = 2) and a child (T = [1,0,0], R = 90° about x,
/// S = [1,3,1]), material baseColorFactor [0.5, 0.4, 0.3].
fn gltf_fixture_json(buffer_uri: Option<&str>) -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    for x in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bin.extend_from_slice(&x.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes()); // last index pads to 4 bytes
    }
    let uri = match buffer_uri {
        Some(u) => format!(", \"uri\": \"{u}\""),
        None => String::new(),
    };
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [
    {{"children": [1], "translation": [1, 2, 3], "rotation": [0, 0, {h}, {h}], "scale": [2, 2, 2]}},
    {{"mesh": 0, "translation": [1, 0, 0], "rotation": [{h}, 0, 0, {h}], "scale": [1, 3, 1]}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
  "materials": [{{"name": "paint", "pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.4, 0.3, 1.0]}}}}],
  "buffers": [{{"byteLength": {len}{uri}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}
  ]
}}"#,
        len = bin.len()
    );
    (json, bin)
}

fn temp_path(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("luxtally-{}-{name}", std::process::id()))
}

fn check_fixture_scene(mesh: &Path) {
    let text = format!("[[objects]]\nfile = \"{}\"\n", mesh.display());
    let s = match scene::load_str(&text, Path::new("/"), "fixture.toml") {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    };
    let g = &s.geometry;
    assert_eq!(g.triangle_count(), 1);
    let world: Vec<DVec3> = g.triangles[0]
        .iter()
        .map(|&i| g.origin + g.vertices[i as usize].as_dvec3())
        .collect();
    // p ↦ Tp·Rp·Sp·(Tc·Rc·Sc·p), worked by hand: e.g. (0,1,0) → (0,3,0) → (0,0,3)
    // → (1,0,3) → (2,0,6) → (0,2,6) → (1,4,9).
    let expected = [
        DVec3::new(1.0, 4.0, 3.0),
        DVec3::new(1.0, 6.0, 3.0),
        DVec3::new(1.0, 4.0, 9.0),
    ];
    for (w, e) in world.iter().zip(expected) {
        assert!(close(*w, e, 1e-5), "{w} ≠ {e}");
    }
    // (b − a) × (c − a) = (0,2,0) × (0,0,6) ∝ +x.
    assert!(close(g.normal(0).as_dvec3(), DVec3::X, 1e-6));
    let m = &s.materials[g.material.get(0) as usize];
    assert!(m.name.ends_with(":paint"), "{}", m.name);
    // metallicFactor defaults to 1: the base colour is the glossy (metal) albedo.
    assert!((m.glossy_reflectance - (0.2126 * 0.5 + 0.7152 * 0.4 + 0.0722 * 0.3)).abs() < 1e-6);
}

#[test]
fn gltf_node_hierarchy_with_trs_and_base_color_from_embedded_buffer() {
    use base64::Engine;
    let (_, bin) = gltf_fixture_json(None);
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let (json, _) = gltf_fixture_json(Some(&uri));
    let path = temp_path("fixture.gltf");
    std::fs::write(&path, json).unwrap();
    check_fixture_scene(&path);
    let _ = std::fs::remove_file(path);
}

#[test]
fn glb_fixture_with_binary_chunk_loads_the_same() {
    let (json, bin) = gltf_fixture_json(None);
    let mut json = json.into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    let path = temp_path("fixture.glb");
    std::fs::write(&path, glb).unwrap();
    check_fixture_scene(&path);
    let _ = std::fs::remove_file(path);
}

#[test]
fn objects_far_from_origin_keep_triangle_areas() {
    let shape = "shape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0.5\nsubdivisions = 2\nmaterial = \"grey\"\n";
    let near = load(&format!("{MATERIALS}[[objects]]\n{shape}"));
    let far = load(&format!(
        "{MATERIALS}[[objects]]\n{shape}translate = [1e5, 1e5, 1e5]\n"
    ));
    assert_eq!(
        near.geometry.triangle_count(),
        far.geometry.triangle_count()
    );
    for (a, b) in near.geometry.areas_m2().zip(far.geometry.areas_m2()) {
        assert!(((a - b) / a).abs() < 1e-9);
    }
    // The local frame is re-centred, so f32 positions stay precise.
    assert!(close(far.geometry.origin, DVec3::splat(1e5), 1e-6));
    let max_local = far
        .geometry
        .vertices
        .iter()
        .map(|v| v.abs().max_element())
        .fold(0.0, f32::max);
    assert!(max_local <= 0.5 + 1e-6);
}

#[test]
fn lights_receivers_and_simulation_keep_their_parameters() {
    let s = load(
        r#"
name = "all"
[[lights]]
type = "point"
position = [0, 0, 1]
flux_lm = 1000
[[lights]]
type = "spot"
position = [0, 0, 2]
direction = [0, 0, -2]
intensity_cd = 500
cone_deg = 30
[[lights]]
type = "directional"
direction = [0, 0, -1]
illuminance_lx = 100000
[[lights]]
type = "area"
corner = [0, 0, 3]
u = [2, 0, 0]
v = [0, 1, 0]
flux_lm = 3000
[[receivers]]
name = "meter"
corner = [0, 0, 0]
u = [1, 0, 0]
v = [0, 1, 0]
cells = [1, 1]
quantity = "luminance"
view_direction = [0, 0, 2]
half_angle_deg = 5
estimator = "next_event"
[simulation]
photons = 10
seed = 7
time_limit = 2.5
target_error = 0.01
target = "receiver:meter"
absolute = true
min_hits = 100
"#,
    );
    assert_eq!(s.name, "all");
    match s.lights[0].get::<Point>() {
        Some(&Point { intensity_cd, .. }) => {
            assert!((intensity_cd - 1000.0 / (4.0 * PI)).abs() < 1e-12)
        }
        _ => panic!("{:?}", s.lights),
    }
    match s.lights[1].get::<Spot>() {
        Some(&Spot {
            direction,
            falloff_deg,
            cone_deg,
            ..
        }) => {
            assert_eq!(direction, DVec3::NEG_Z);
            assert_eq!(falloff_deg, cone_deg);
        }
        _ => panic!("{:?}", s.lights),
    }
    match s.lights[3].get::<Area>() {
        // Φ = π L A.
        Some(&Area { luminance_cdm2, .. }) => {
            assert!((luminance_cdm2 - 3000.0 / (PI * 2.0)).abs() < 1e-9)
        }
        _ => panic!("{:?}", s.lights),
    }
    let r = &s.receivers[0];
    assert_eq!(r.estimator, Estimator::NextEvent);
    assert_eq!(
        r.quantity,
        Quantity::Luminance {
            view_direction: DVec3::Z,
            half_angle_deg: 5.0
        }
    );
    let (sim, seed) = (&s.simulation.stop, s.simulation.seed);
    assert_eq!(
        (sim.photons, seed, sim.time_limit_s, sim.target_error),
        (Some(10), 7, Some(2.5), Some(0.01))
    );
    assert_eq!(
        (sim.target.as_deref(), sim.absolute, sim.min_hits),
        (Some("receiver:meter"), true, Some(100))
    );
}

#[test]
fn name_defaults_to_the_file_stem_and_seed_to_1() {
    let s = scene::load_str("", Path::new("."), "dir/lobby.toml").unwrap();
    assert_eq!(s.name, "lobby");
    assert_eq!(s.simulation.seed, 1);
    assert_eq!(s.geometry.triangle_count(), 0);
}

/// bench-scale's `glb:N` case: the procedural mesh written by `fixtures::write_glb` loads
/// back through the scene loader as the same triangles, vertices rounded to f32 as the
/// generated scene's own are.
#[test]
fn a_written_glb_loads_back_as_the_same_mesh() {
    use luxtally::fixtures::{load_obj_geometry, procedural_geometry, procedural_mesh, write_glb};
    let (vertices, triangles) = procedural_mesh(20_000);
    let path = std::env::temp_dir().join(format!("luxtally-glb-{}.glb", std::process::id()));
    write_glb(&path, &vertices, &triangles).unwrap();
    let loaded = load_obj_geometry(&path, glam::DVec3::ZERO).unwrap();
    std::fs::remove_file(&path).unwrap();
    let generated = procedural_geometry(20_000);
    assert_eq!(loaded.triangle_count(), generated.triangle_count());
    assert_eq!(&loaded.triangles[..], &generated.triangles[..]);
    for (k, (a, b)) in loaded
        .vertices
        .iter()
        .zip(generated.vertices.iter())
        .enumerate()
    {
        let (a, b) = (
            a.as_dvec3() + loaded.origin,
            b.as_dvec3() + generated.origin,
        );
        assert!((a - b).length() < 1e-5, "vertex {k}: {a} against {b}");
    }
}

//! Instancing (`instances`, `grid`, `map = false`, glTF nodes sharing a mesh): instanced
//! copies hit, shade and light exactly like the same copies flattened, mirrored copies
//! keep their outside, both backends agree, and scenes too large to flatten are refused
//! in one line or traced without flattening.

use crate::common;

use glam::{DVec3, Vec3};
use luxtally::accel::{self, Backend, HitBatch, RayBatch, INSTANCE_HIT, NO_HIT};
use luxtally::scene::{self, Geometry, Scene};
use std::path::Path;

fn load(text: &str) -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    match scene::load_str(text, &dir, "test.toml") {
        Ok(s) => s,
        Err(e) => panic!("scene failed to load: {e}"),
    }
}

/// Boxes, suzannes and a rect under rotations, scales and mirrors, with `map = {map}`
/// on the copied objects (the floor is always mapped).
fn copies_scene(map: bool) -> String {
    format!(
        r#"
[materials]
grey = {{ reflectance = 0.5 }}
white = {{ reflectance = 0.8, transmittance = 0.1 }}

[[objects]]
shape = "rect"
corner = [-4, -4, 0]
u = [12, 0, 0]
v = [0, 12, 0]
material = "grey"

[[objects]]
shape = "box"
min = [-0.3, -0.2, 0.1]
max = [0.3, 0.4, 0.9]
material = "white"
map = {map}
instances = [
  {{ translate = [0.5, 0, 0] }},
  {{ translate = [0, 1.2, 0.5], rotate_deg = [10, 20, 30], scale = [1, -1.5, 0.7] }},
  {{ translate = [-1.9, 0.05, 1.6], scale = -1 }},
]
grid = {{ count = [3, 2], spacing = [2.5, 3] }}

[[objects]]
file = "meshes/suzanne.obj"
material = "white"
map = {map}
rotate_deg = [90, 0, 0]
scale = 0.5
translate = [1, -2, 1]
instances = [{{ translate = [0, 0, 0] }}, {{ translate = [3, 0, 0.2], rotate_deg = [0, 0, 45], scale = [-1, 1, 1.2] }}]

[[objects]]
shape = "rect"
corner = [0, 0, 0]
u = [1, 0, 0]
v = [0, 1, 0]
material = "white"
map = {map}
instances = [{{ translate = [5, 5, 2], scale = [1, 1, -1] }}, {{ translate = [4, 6, 2.5], rotate_deg = [0, 180, 0] }}]
"#
    )
}

/// `n` rays in world coordinates through the region of the copies.
fn world_rays(n: usize, seed: u64) -> Vec<(DVec3, DVec3)> {
    let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let o = DVec3::new(
                -4.0 + 12.0 * next(),
                -4.0 + 12.0 * next(),
                0.05 + 4.0 * next(),
            );
            let d = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5);
            (o, d.normalize())
        })
        .collect()
}

fn local_batch(g: &Geometry, rays: &[(DVec3, DVec3)]) -> RayBatch {
    let mut batch = RayBatch::with_capacity(rays.len());
    for (o, d) in rays {
        batch.push(
            (*o - g.origin).as_vec3().to_array(),
            d.as_vec3().to_array(),
            0.0,
            f32::INFINITY,
        );
    }
    batch
}

fn trace(backend: Backend, g: &Geometry, rays: &[(DVec3, DVec3)]) -> (HitBatch, Vec<bool>) {
    let caster = accel::build(backend, g).expect("backend builds");
    let batch = local_batch(g, rays);
    let mut hits = HitBatch::default();
    caster.intersect(&batch, &mut hits);
    // Shadow segments of half the hit distance (or 3 m on a miss).
    let mut shadow = batch.clone();
    for (k, t) in shadow.tfar.iter_mut().enumerate() {
        *t = if hits.t[k].is_finite() {
            0.5 * hits.t[k]
        } else {
            3.0
        };
    }
    let mut occluded = Vec::new();
    caster.occluded(&shadow, &mut occluded);
    (hits, occluded)
}

/// World hit point, unit normal and object of hit `k`.
fn world_surface(g: &Geometry, hits: &HitBatch, k: usize) -> Option<(DVec3, Vec3, u32)> {
    let s = hits.surface(k, g)?;
    let object = match s.mapped {
        Some(t) => g.object.get(t as usize),
        None => g.instanced.instances[hits.inst[k] as usize].object,
    };
    Some((g.origin + s.point.as_dvec3(), s.normal, object))
}

/// Instanced and flattened copies agree ray by ray: hit or miss, distance, point,
/// normal orientation (so mirrored copies keep their outside) and object.
fn assert_same_hits(backend: Backend) {
    let inst = load(&copies_scene(false));
    let flat = load(&copies_scene(true));
    let (gi, gf) = (&inst.geometry, &flat.geometry);
    let rays = world_rays(50_000, 11);
    let (hi, oi) = trace(backend, gi, &rays);
    let (hf, of) = trace(backend, gf, &rays);
    let mut instance_hits = 0;
    let mut differ = 0;
    for k in 0..rays.len() {
        if (hi.tri[k] == NO_HIT) != (hf.tri[k] == NO_HIT) || oi[k] != of[k] {
            // A ray grazing an edge may go either way in f32.
            differ += 1;
            continue;
        }
        let (Some((pi, ni, obj_i)), Some((pf, nf, obj_f))) =
            (world_surface(gi, &hi, k), world_surface(gf, &hf, k))
        else {
            continue;
        };
        if hi.tri[k] == INSTANCE_HIT {
            instance_hits += 1;
        }
        if (pi - pf).length() > 1e-4 || obj_i != obj_f {
            differ += 1;
            continue;
        }
        assert!(
            (hi.t[k] - hf.t[k]).abs() <= 1e-4 * hf.t[k].max(1.0),
            "{backend:?} ray {k}: t {} vs {}",
            hi.t[k],
            hf.t[k]
        );
        assert!(
            ni.dot(nf) > 0.999,
            "{backend:?} ray {k}: normal {ni} vs flattened {nf} (object {obj_f})"
        );
        // The backend's own normal agrees with the surface's.
        let ng = Vec3::new(hi.ngx[k], hi.ngy[k], hi.ngz[k]);
        assert!(
            ng.dot(ni) > 0.999,
            "{backend:?} ray {k}: backend normal {ng} vs {ni}"
        );
    }
    assert!(
        instance_hits > 2_000,
        "{backend:?}: only {instance_hits} rays hit instances"
    );
    assert!(
        differ <= rays.len() / 2000,
        "{backend:?}: {differ} of {} rays differ",
        rays.len()
    );
}

#[test]
fn instanced_and_flattened_copies_are_hit_alike_embree() {
    assert_same_hits(Backend::Embree);
}

#[cfg(feature = "obvhs")]
#[test]
fn instanced_and_flattened_copies_are_hit_alike_obvhs() {
    assert_same_hits(Backend::Obvhs);
}

/// Embree and obvhs report the same instance, triangle and distance.
#[cfg(feature = "obvhs")]
#[test]
fn backends_agree_on_instance_hits() {
    let s = load(&copies_scene(false));
    let g = &s.geometry;
    let rays = world_rays(50_000, 12);
    let (he, oe) = trace(Backend::Embree, g, &rays);
    let (ho, oo) = trace(Backend::Obvhs, g, &rays);
    let mut differ = 0;
    for k in 0..rays.len() {
        if he.tri[k] != ho.tri[k]
            || (he.tri[k] == INSTANCE_HIT && (he.inst[k], he.prim[k]) != (ho.inst[k], ho.prim[k]))
            || oe[k] != oo[k]
        {
            differ += 1;
            continue;
        }
        if he.tri[k] != NO_HIT {
            assert!(
                (he.t[k] - ho.t[k]).abs() <= 1e-4 * he.t[k].max(1.0),
                "ray {k}: t {} vs {}",
                he.t[k],
                ho.t[k]
            );
            let dot = he.ngx[k] * ho.ngx[k] + he.ngy[k] * ho.ngy[k] + he.ngz[k] * ho.ngz[k];
            assert!(dot > 0.999, "ray {k}: normals differ ({dot})");
        }
    }
    assert!(differ <= rays.len() / 2000, "{differ} rays differ");
}

#[test]
fn instanced_objects_hold_no_map_and_flattened_ones_do() {
    let inst = load(&copies_scene(false));
    let flat = load(&copies_scene(true));
    // Box: 3 instances × 6 grid points × 12; suzanne: 2 × 500 (some may be degenerate);
    // rect: 2 × 2.
    let (gi, gf) = (&inst.geometry, &flat.geometry);
    assert_eq!(gi.triangle_count(), 2, "only the floor is mapped");
    assert_eq!(gi.instanced.instances.len(), 18 + 2 + 2);
    assert_eq!(gi.instanced.prototypes.len(), 3);
    let suzanne = gi.instanced.prototypes[1].triangles.len() as u64;
    assert_eq!(
        gi.instanced.flattened_triangle_count(),
        18 * 12 + 2 * suzanne + 2 * 2
    );
    assert_eq!(
        gf.triangle_count() as u64,
        2 + gi.instanced.flattened_triangle_count()
    );
    assert!(gf.instanced.is_empty());
    // Same world bounds either way (instances bounded by their boxes, padded).
    let (li, hi) = gi.world_bounds().unwrap();
    let (lf, hf) = gf.world_bounds().unwrap();
    assert!((li - lf).abs().max_element() < 0.6 && (hi - hf).abs().max_element() < 0.6);
}

/// A lit scene: a point light over the copies, receivers on the floor and a wall.
fn lit(map: bool) -> String {
    format!(
        r#"{}
[[lights]]
type = "point"
position = [2, 1, 5]
intensity_cd = 1000

[[receivers]]
name = "floor"
corner = [-3, -3, 0.001]
u = [9, 0, 0]
v = [0, 9, 0]
cells = [6, 6]
estimator = "track"

[[receivers]]
name = "above"
corner = [-3, -3, 3.9]
u = [9, 0, 0]
v = [0, 9, 0]
cells = [3, 3]
estimator = "auto"
"#,
        copies_scene(map)
    )
}

/// z-scores of every cell of two runs' receivers (cells nothing reached in either run
/// must read 0 in both), and how many cells are bit-identical.
fn z_scores(
    a: &luxtally::output::summary::Summary,
    b: &luxtally::output::summary::Summary,
) -> (Vec<f64>, usize) {
    let mut z = Vec::new();
    let mut identical = 0;
    for ((name, ra), (_, rb)) in a.receivers.iter().zip(&b.receivers) {
        for k in 0..ra.values.len() {
            let (va, vb) = (ra.values[k], rb.values[k]);
            identical += (va == vb) as usize;
            let s = (ra.sigma[k].powi(2) + rb.sigma[k].powi(2)).sqrt();
            if ra.sigma[k].is_nan() && rb.sigma[k].is_nan() {
                assert_eq!((va, vb), (0.0, 0.0), "{name} cell {k}");
            } else if s > 0.0 {
                assert!(s.is_finite(), "{name} cell {k}: σ unknown in one run only");
                z.push((va - vb) / s);
            } else {
                assert_eq!(va, vb, "{name} cell {k}");
            }
        }
    }
    (z, identical)
}

fn run_seed(text: &str, photons: u64, seed: u64) -> luxtally::output::summary::Summary {
    let s = load(text);
    let options = luxtally::run::RunOptions {
        seed,
        ..common::options(&s, photons, 2, Backend::Embree)
    };
    common::run_options(&s, &options)
}

#[test]
fn instanced_and_flattened_copies_light_receivers_alike() {
    let photons = 400_000;
    let instanced = run_seed(&lit(false), photons, 1);
    // Independent runs (another seed) agree within their σ ...
    let flat_other = run_seed(&lit(true), photons, 2);
    let (z, _) = z_scores(&instanced, &flat_other);
    let worst = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mean_sq = z.iter().map(|x| x * x).sum::<f64>() / z.len() as f64;
    eprintln!(
        "independent: {} cells, worst z {worst:.2}, mean z² {mean_sq:.2}",
        z.len()
    );
    assert!(z.len() >= 40, "{} cells compared", z.len());
    assert!(worst < 5.0, "a cell differs by {worst:.1}σ");
    assert!(mean_sq < 2.0, "mean z² {mean_sq:.2}: the two differ");
    // ... and with the same seed the photons follow the same paths but for the few that
    // meet an edge or a surface within f32 precision (instanced hit points and normals
    // come from f32 transforms of the prototype, flattened ones from f64-placed
    // vertices), so the results are close but not bit-identical.
    let flat_same = run_seed(&lit(true), photons, 1);
    let (z, identical) = z_scores(&instanced, &flat_same);
    let worst = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    eprintln!("same seed: {identical} cells bit-identical, worst z {worst:.2}");
    assert!(worst < 1.0, "same seed: a cell differs by {worst:.2}σ");
}

/// A receiver under a mirrored instanced glass pane: refraction needs the pane's outside
/// (where its normal points); a mirrored copy must keep it, so the light through it is
/// the same as through the unmirrored pane and through the flattened mirrored pane.
#[test]
fn a_mirrored_instanced_pane_keeps_its_outside() {
    let scene = |map: bool, scale: &str| {
        format!(
            r#"
[materials]
glass = {{ specular_transmittance = 0.9, ior = 1.5 }}

[[objects]]
shape = "box"
min = [-1, -1, 0]
max = [1, 1, 0.2]
material = "glass"
map = {map}
instances = [{{ translate = [0, 0, 1], scale = {scale} }}]

[[lights]]
type = "directional"
direction = [0.3, 0, -1]
illuminance_lx = 1000

[[receivers]]
name = "below"
corner = [-0.5, -0.5, 0.5]
u = [1, 0, 0]
v = [0, 1, 0]
cells = [2, 2]
estimator = "track"
"#
        )
    };
    let photons = 200_000;
    let plain = run(&scene(false, "1"), photons);
    let mirrored = run(&scene(false, "[-1, 1, 1]"), photons);
    let flat = run(&scene(true, "[-1, 1, 1]"), photons);
    let total = |s: &luxtally::output::summary::Summary| {
        let r = &s.receivers["below"];
        let v: f64 = r.values.iter().sum::<f64>() / r.values.len() as f64;
        let s2: f64 = r.sigma.iter().map(|s| s * s).sum::<f64>();
        (v, s2.sqrt() / r.values.len() as f64)
    };
    let (vp, sp) = total(&plain);
    let (vm, sm) = total(&mirrored);
    let (vf, sf) = total(&flat);
    // Through the pane: well below the unobstructed 1000·cos and well above zero.
    assert!(vp > 300.0 && vp < 950.0, "{vp}");
    for (name, v, s) in [("mirrored", vm, sm), ("flattened", vf, sf)] {
        let z = (v - vp) / (s * s + sp * sp).sqrt();
        assert!(
            z.abs() < 5.0,
            "{name}: {v} ± {s} vs plain {vp} ± {sp} ({z:.1}σ)"
        );
    }
    // Its normals: every hit from above sees a front face (normal towards the light).
    let s = load(&scene(false, "[-1, 1, 1]"));
    let g = &s.geometry;
    let rays: Vec<(DVec3, DVec3)> = (0..100)
        .map(|k| {
            let x = -0.9 + 0.018 * k as f64;
            (DVec3::new(x, 0.1, 3.0), DVec3::NEG_Z)
        })
        .collect();
    for backend in backends() {
        let (hits, _) = trace(backend, g, &rays);
        for k in 0..rays.len() {
            let (_, n, _) = world_surface(g, &hits, k).expect("the pane is hit");
            assert!(
                n.z > 0.99,
                "{backend:?} ray {k}: normal {n} is not outwards"
            );
        }
    }
}

/// Runs `photons` photons through the scene (meshes under scenes/) on 2 threads.
fn run(text: &str, photons: u64) -> luxtally::output::summary::Summary {
    let s = load(text);
    common::run_options(&s, &common::options(&s, photons, 2, Backend::Embree))
}

fn backends() -> Vec<Backend> {
    let mut b = vec![Backend::Embree];
    if cfg!(feature = "obvhs") {
        b.push(Backend::Obvhs);
    }
    b
}

/// glTF nodes that share a mesh: one prototype, one instance per node, mirrored nodes
/// included (three nodes, the third mirrored in x).
#[test]
fn gltf_nodes_sharing_a_mesh_become_instances_of_one_prototype() {
    let mut bin = Vec::new();
    for x in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bin.extend_from_slice(&x.to_le_bytes());
    }
    use base64::Engine;
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1, 2]}}],
  "nodes": [
    {{"mesh": 0}},
    {{"mesh": 0, "translation": [3, 0, 0]}},
    {{"mesh": 0, "translation": [6, 0, 0], "scale": [-1, 1, 1]}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "material": 0}}]}}],
  "materials": [{{"name": "paint", "pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.5, 0.5, 1.0]}}}}],
  "buffers": [{{"byteLength": 36, "uri": "{uri}"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}}]
}}"#
    );
    let path = std::env::temp_dir().join(format!("luxtally-{}-shared.gltf", std::process::id()));
    std::fs::write(&path, json).unwrap();
    let text = |map: bool| format!("[[objects]]\nfile = \"{}\"\nmap = {map}\n", path.display());
    let inst = scene::load_str(&text(false), Path::new("/"), "t.toml").expect("loads");
    let flat = scene::load_str(&text(true), Path::new("/"), "t.toml").expect("loads");
    let _ = std::fs::remove_file(&path);
    let gi = &inst.geometry;
    assert_eq!(gi.triangle_count(), 0);
    assert_eq!(gi.instanced.prototypes.len(), 1);
    assert_eq!(gi.instanced.instances.len(), 3);
    assert_eq!(flat.geometry.triangle_count(), 3);
    // Rays straight down onto each copy: same normals as the flattened copies (+z:
    // the mirrored node's winding is reversed, glTF spec "Transformations").
    let rays: Vec<(DVec3, DVec3)> = [0.2, 3.2, 5.8]
        .iter()
        .map(|&x| (DVec3::new(x, 0.2, 1.0), DVec3::NEG_Z))
        .collect();
    for backend in backends() {
        for g in [gi, &flat.geometry] {
            let (hits, _) = trace(backend, g, &rays);
            for k in 0..rays.len() {
                let (p, n, _) = world_surface(g, &hits, k).expect("hit");
                assert!((p.z).abs() < 1e-5, "{backend:?} ray {k}: at {p}");
                assert!(n.z > 0.999, "{backend:?} ray {k}: normal {n}");
            }
        }
    }
}

#[test]
fn too_many_copies_stop_with_one_clear_line() {
    let grid = |map: bool, n: u64| {
        format!(
            "[materials]\ngrey = {{ reflectance = 0.5 }}\n[[objects]]\nfile = \"meshes/suzanne.obj\"\nmaterial = \"grey\"\nmap = {map}\ngrid = {{ count = [{n}, {n}], spacing = [1, 1] }}\n"
        )
    };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for (map, n, expect) in [
        (false, 100_000u64, "instances"),
        (true, 2_000, "mapped triangles exceed the limit"),
    ] {
        let err = match scene::load_str(&grid(map, n), &dir, "big.toml") {
            Ok(_) => panic!("map = {map}, {n}²: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(!err.contains('\n'), "not one line: {err}");
        assert!(err.contains("big.toml: objects[0]"), "{err}");
        assert!(err.contains(expect), "{err}");
    }
}

/// 10⁵ instances of a 500-triangle mesh (5 × 10⁷ triangles if flattened) load with the
/// mesh stored once, and trace.
#[test]
fn a_hundred_thousand_instances_load_and_trace_without_flattening() {
    let text = r#"
[materials]
grey = { reflectance = 0.5 }

[[objects]]
file = "meshes/suzanne.obj"
material = "grey"
scale = 0.3
grid = { count = [400, 250], spacing = [1, 1] }

[[lights]]
type = "directional"
direction = [0.2, 0.1, -1]
illuminance_lx = 100

[[receivers]]
name = "floor"
corner = [0, 0, -1]
u = [400, 0, 0]
v = [0, 250, 0]
cells = [4, 4]
estimator = "track"
"#;
    let s = load(text);
    let g = &s.geometry;
    assert_eq!(g.triangle_count(), 0);
    assert_eq!(g.instanced.instances.len(), 100_000);
    assert_eq!(g.instanced.prototypes.len(), 1);
    let per = g.instanced.stored_triangle_count() as u64;
    let one = load("[[objects]]\nfile = \"meshes/suzanne.obj\"\nmaterial = \"grey\"\n[materials]\ngrey = { reflectance = 0.5 }\n");
    assert_eq!(per, one.geometry.triangle_count() as u64);
    assert_eq!(g.instanced.flattened_triangle_count(), 100_000 * per);
    let summary = common::run_options(&s, &common::options(&s, 20_000, 2, Backend::Embree));
    let r = &summary.receivers["floor"];
    // Some light is blocked (the floor gets less than 100 lx on average) and some passes.
    let mean = r.values.iter().sum::<f64>() / r.values.len() as f64;
    assert!(mean > 5.0 && mean < 99.0, "mean {mean}");
}

fn luxtally(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("binary runs")
}

/// `--outputs receivers,report` writes summary.json, the receivers' files and the
/// report, and neither scene_map.ply nor the indirect map; a bad name is one line.
#[test]
fn outputs_choose_the_files_a_run_writes() {
    let dir = std::env::temp_dir().join(format!("luxtally-outputs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = luxtally(&[
        "run",
        "scenes/office.toml",
        "--photons",
        "20000",
        "--quiet",
        "--outputs",
        "receivers,report",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("summary.json").is_file());
    assert!(dir.join("report.html").is_file());
    let receivers: Vec<_> = std::fs::read_dir(dir.join("receivers"))
        .expect("receivers/ written")
        .collect();
    assert!(!receivers.is_empty());
    assert!(!dir.join("scene_map.ply").exists(), "scene_map.ply written");
    // Besides the run's state (checkpoint.bin, which every run keeps for --resume).
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with("checkpoint."))
        .collect();
    assert_eq!(
        names.len(),
        3,
        "only summary, report, receivers/: {names:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);

    let bad = luxtally(&["run", "scenes/office.toml", "--outputs", "receivers,maps"]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("--outputs") && err.contains("`maps`"), "{err}");
}

/// `map = false` on an ordinary object: it shadows the floor but holds no tallies, so
/// the global statistics cover the floor alone; `map = true` (the default) adds its
/// triangles and area.
#[test]
fn unmapped_objects_shadow_but_are_left_out_of_the_scene_map() {
    let scene = |map: &str| {
        format!(
            r#"
[materials]
grey = {{ reflectance = 0.5 }}

[[objects]]
shape = "rect"
corner = [-5, -5, 0]
u = [10, 0, 0]
v = [0, 10, 0]
material = "grey"

[[objects]]
shape = "box"
min = [-1, -1, 1]
max = [1, 1, 2]
material = "grey"
{map}

[[lights]]
type = "directional"
direction = [0, 0, -1]
illuminance_lx = 100
"#
        )
    };
    let unmapped = run(&scene("map = false"), 100_000);
    let mapped = run(&scene(""), 100_000);
    assert_eq!(unmapped.global.triangles, 2);
    assert!((unmapped.global.area_m2 - 100.0).abs() < 1e-9);
    assert_eq!(mapped.global.triangles, 14);
    assert!((mapped.global.area_m2 - 116.0).abs() < 1e-9);
    // The floor's mean: 96 % lit at 100 lx (plus a little light from the box's bottom);
    // without the box's shadow it would be 100 lx.
    let e = unmapped.global.mean_illuminance_lx;
    let s = unmapped.global.mean_sigma_lx;
    assert!(
        e > 96.0 - 5.0 * s && e < 100.0 - 1.0,
        "floor mean {e} ± {s}"
    );
}

/// The eye pass sees instances: the top of an instanced (mirrored) box straight under a
/// point source reads L = ρ·I/(π r²) (direct light only: it holds no indirect map).
#[test]
fn render_shades_instanced_surfaces_with_direct_light() {
    for scale in ["1", "[-1, 1, 1]"] {
        let text = format!(
            r#"
[materials]
grey = {{ reflectance = 0.5 }}

[[objects]]
shape = "rect"
corner = [-5, -5, 0]
u = [10, 0, 0]
v = [0, 10, 0]
material = "grey"

[[objects]]
shape = "box"
min = [-1, -1, 0]
max = [1, 1, 1]
material = "grey"
instances = [{{ scale = {scale} }}]

[[lights]]
type = "point"
position = [0, 0, 5]
intensity_cd = 1000

[camera]
position = [0, 0.001, 4]
look_at = [0, 0, 0]
up = [0, 1, 0]
fov_deg = 1
resolution = [3, 3]
"#
        );
        let s = load(&text);
        let options = common::options(&s, 20_000, 2, Backend::Embree);
        let result = luxtally::run::run(
            &s,
            &options,
            &std::sync::atomic::AtomicBool::new(false),
            &mut (),
        )
        .expect("runs");
        let map = luxtally::output::IndirectMap::from_tallies(
            &s,
            &result.progress.tallies,
            result.setup.total_flux_lm,
        );
        let caster = accel::build(Backend::Embree, &s.geometry).expect("builds");
        let camera = s.camera.as_ref().unwrap();
        let r = luxtally::render::render(&s, camera, &map, caster.as_ref(), 1, 2).expect("renders");
        let centre = r.image.luminance_cdm2[4];
        let exact = 0.5 * 1000.0 / (std::f64::consts::PI * 16.0);
        assert!(
            (centre - exact).abs() < 0.01 * exact,
            "scale {scale}: {centre} cd/m² vs {exact}"
        );
    }
}

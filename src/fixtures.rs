//! Test and benchmark fixtures: a procedural scene of any size, a mesh file loaded as one
//! geometry, random ray sets, a lit scene over any geometry and a GLB writer. Used by
//! tests/, benches/ and the `luxtally bench-*` commands; not part of the engine.

use crate::accel::RayBatch;
use crate::scene::{Geometry, Scene};
use crate::{Error, Result};
use glam::{DVec3, Vec3};
use rand::Rng;
use rayon::prelude::*;
use std::path::Path;

/// A deterministic scene of at least `min_triangles` triangles with real depth
/// complexity: a bumpy 100 m × 100 m heightfield under a field of overlapping spheres of
/// different sizes floating at different heights.
pub fn procedural_geometry(min_triangles: usize) -> Geometry {
    let (verts, tris) = procedural_mesh(min_triangles);
    Geometry::uniform(&verts, tris, 0, 0)
}

/// The world-space vertices and triangles of [`procedural_geometry`], generated in
/// parallel (every vertex and triangle alone, so the values do not depend on the
/// threads; the spheres' random centres and radii are drawn first, in order).
pub fn procedural_mesh(min_triangles: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    // Heightfield: about 40 % of the budget, 2·n² triangles.
    let n = (((min_triangles as f64 * 0.4) / 2.0).sqrt().ceil() as usize).max(2);
    let size = 100.0;
    let field_vertices = (n + 1) * (n + 1);
    let field_triangles = 2 * n * n;

    // Spheres (UV, 48 × 24: 2 208 triangles each) until the budget is reached.
    let (seg, rings) = (48usize, 24usize);
    let sphere_vertices = (rings + 1) * seg;
    let pattern = sphere_pattern(seg, rings);
    let spheres = min_triangles
        .saturating_sub(field_triangles)
        .div_ceil(pattern.len());
    let mut rng = crate::rng::aux_stream(0x5eed);
    let placed: Vec<(DVec3, f64)> = (0..spheres)
        .map(|_| {
            let c = DVec3::new(
                rng.random_range(-45.0..45.0),
                rng.random_range(-45.0..45.0),
                rng.random_range(0.0..12.0),
            );
            (c, rng.random_range(0.3..4.0))
        })
        .collect();

    // Trigonometry by table: the heightfield's factors depend on one coordinate each,
    // a sphere's direction and displacement on the vertex's place in the pattern only
    // (27 M sin/cos calls at 10⁷ triangles were most of the generation's time).
    let coordinate = |i: usize| -size / 2.0 + size * i as f64 / n as f64;
    let (sin_x, cos_y): (Vec<f64>, Vec<f64>) = (0..=n)
        .map(|i| {
            (
                libm::sin(0.31 * coordinate(i)),
                libm::cos(0.23 * coordinate(i)),
            )
        })
        .unzip();
    let unit_sphere = unit_sphere(seg, rings);

    let mut verts: Vec<DVec3> = Vec::new();
    (0..field_vertices + spheres * sphere_vertices)
        .into_par_iter()
        .map(|index| {
            if index < field_vertices {
                let (i, j) = (index % (n + 1), index / (n + 1));
                let (x, y) = (coordinate(i), coordinate(j));
                let z = 1.5 * sin_x[i] * cos_y[j] + 0.4 * libm::sin(1.7 * x + 0.9 * y);
                return DVec3::new(x, y, z);
            }
            let index = index - field_vertices;
            let (c, r) = placed[index / sphere_vertices];
            let (d, displacement) = unit_sphere[index % sphere_vertices];
            c + d * r * displacement
        })
        .collect_into_vec(&mut verts);

    let mut tris: Vec<[u32; 3]> = Vec::new();
    let field_at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    (0..field_triangles + spheres * pattern.len())
        .into_par_iter()
        .map(|index| {
            if index < field_triangles {
                let (i, j) = ((index / 2) % n, (index / 2) / n);
                return if index % 2 == 0 {
                    [field_at(i, j), field_at(i + 1, j), field_at(i + 1, j + 1)]
                } else {
                    [field_at(i, j), field_at(i + 1, j + 1), field_at(i, j + 1)]
                };
            }
            let index = index - field_triangles;
            let base = (field_vertices + index / pattern.len() * sphere_vertices) as u32;
            pattern[index % pattern.len()].map(|v| base + v)
        })
        .collect_into_vec(&mut tris);
    (verts, tris)
}

/// The triangles of a UV sphere of `seg` segments and `rings` rings, over vertex
/// `k * seg + s` (ring k, segment s): quads between two rings, fans at the poles.
fn sphere_pattern(seg: usize, rings: usize) -> Vec<[u32; 3]> {
    let at = |k: usize, s: usize| (k * seg + s % seg) as u32;
    let mut pattern: Vec<[u32; 3]> = Vec::new();
    for k in 0..rings {
        for s in 0..seg {
            // Skip the halves that collapse onto a pole.
            if k + 1 != rings {
                pattern.push([at(k, s), at(k + 1, s), at(k + 1, s + 1)]);
            }
            if k != 0 {
                pattern.push([at(k, s), at(k + 1, s + 1), at(k, s + 1)]);
            }
        }
    }
    pattern
}

/// Per vertex of [`sphere_pattern`]: its direction from the centre and its radius
/// factor.
fn unit_sphere(seg: usize, rings: usize) -> Vec<(DVec3, f64)> {
    (0..(rings + 1) * seg)
        .map(|index| {
            let (k, s) = (index / seg, index % seg);
            let theta = std::f64::consts::PI * k as f64 / rings as f64;
            let phi = std::f64::consts::TAU * s as f64 / seg as f64;
            let d = DVec3::new(
                libm::sin(theta) * libm::cos(phi),
                libm::sin(theta) * libm::sin(phi),
                libm::cos(theta),
            );
            // A little displacement so no two spheres are alike.
            (
                d,
                1.0 + 0.05 * libm::sin(5.0 * phi) * libm::sin(3.0 * theta),
            )
        })
        .collect()
}

/// Loads a mesh file (OBJ or glTF) through the scene loader as one `Geometry`,
/// translated by `offset` in world space.
pub fn load_obj_geometry(path: &Path, offset: DVec3) -> Result<Geometry> {
    let file = path.display().to_string().replace('\\', "/");
    let toml = format!(
        "[materials.m]\nreflectance = 0.5\n[[objects]]\nfile = \"{file}\"\nmaterial = \"m\"\ntranslate = [{}, {}, {}]\n",
        offset.x, offset.y, offset.z
    );
    Ok(crate::scene::load_str(&toml, Path::new("."), &file)?.geometry)
}

/// Local-frame bounds of the geometry (zero box when empty).
pub fn local_bounds(g: &Geometry) -> (Vec3, Vec3) {
    let mut it = g.vertices.iter();
    let Some(first) = it.next() else {
        return (Vec3::ZERO, Vec3::ZERO);
    };
    it.fold((*first, *first), |(lo, hi), v| (lo.min(*v), hi.max(*v)))
}

/// Uniform direction on the unit sphere.
fn random_dir(rng: &mut impl Rng) -> Vec3 {
    let z: f32 = rng.random_range(-1.0..1.0);
    let phi: f32 = rng.random_range(0.0..std::f32::consts::TAU);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z)
}

/// `n` incoherent rays: origins uniform in the bounds, uniform unit directions,
/// `tnear = 0`, `tfar = ∞`.
pub fn random_rays(lo: Vec3, hi: Vec3, n: usize, seed: u64) -> RayBatch {
    let mut rng = crate::rng::aux_stream(seed);
    let mut rays = RayBatch::with_capacity(n);
    for _ in 0..n {
        let o = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
        let d = random_dir(&mut rng);
        rays.push(o.to_array(), d.to_array(), 0.0, f32::INFINITY);
    }
    rays
}

/// `n` shadow rays between two uniform points of the bounds (unit direction,
/// `tfar` = their distance).
pub fn random_segments(lo: Vec3, hi: Vec3, n: usize, seed: u64) -> RayBatch {
    let mut rng = crate::rng::aux_stream(seed);
    let mut rays = RayBatch::with_capacity(n);
    while rays.len() < n {
        let a = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
        let b = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
        let len = (b - a).length();
        if len > 0.0 {
            rays.push(a.to_array(), ((b - a) / len).to_array(), 0.0, len);
        }
    }
    rays
}

/// A scene for photon benchmarks over `geometry`: one grey Lambertian material
/// (ρ = 0.5) on every triangle and a point light at the centre of the bounds' top tenth.
pub fn lit_scene(name: &str, mut geometry: Geometry) -> Scene {
    use crate::light::Point;
    use crate::scene::{Material, SceneLight};
    geometry.material = crate::scene::TriangleIds::constant(0, geometry.triangle_count());
    let (lo, hi) = geometry.world_bounds().unwrap_or((DVec3::ZERO, DVec3::ONE));
    let position = DVec3::new(
        (lo.x + hi.x) / 2.0,
        (lo.y + hi.y) / 2.0,
        hi.z - 0.1 * (hi.z - lo.z),
    );
    Scene {
        name: name.to_string(),
        materials: vec![Material::lambertian("grey", 0.5)],
        geometry,
        lights: vec![SceneLight::new(
            "lights[0]",
            Point {
                position,
                intensity_cd: 1000.0,
            },
        )],
        ..Scene::default()
    }
}

/// Writes one mesh (f32 positions, u32 indices, one node) as a binary glTF file.
pub fn write_glb(path: &Path, vertices: &[DVec3], triangles: &[[u32; 3]]) -> Result<()> {
    use std::io::Write;
    let mut bin: Vec<u8> = Vec::with_capacity(12 * (vertices.len() + triangles.len()));
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for v in vertices {
        let v = v.as_vec3();
        // The accessor's bounds must be numbers in the JSON, whatever the vertices.
        if v.is_finite() {
            (lo, hi) = (lo.min(v), hi.max(v));
        }
        for c in v.to_array() {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    if lo.cmpgt(hi).any() {
        // No finite vertex: bounds that are numbers all the same.
        (lo, hi) = (Vec3::ZERO, Vec3::ZERO);
    }
    let positions_len = bin.len();
    for i in triangles.iter().flatten() {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],"buffers":[{{"byteLength":{total}}}],"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{positions_len}}},{{"buffer":0,"byteOffset":{positions_len},"byteLength":{indices_len}}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":{vertex_count},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},{{"bufferView":1,"componentType":5125,"count":{index_count},"type":"SCALAR"}}]}}"#,
        lo.x,
        lo.y,
        lo.z,
        hi.x,
        hi.y,
        hi.z,
        total = bin.len(),
        indices_len = bin.len() - positions_len,
        vertex_count = vertices.len(),
        index_count = 3 * triangles.len(),
    );
    // Chunks are 4-byte aligned: JSON padded with spaces (the binary chunk already is).
    let mut json = json.into_bytes();
    json.resize(json.len().next_multiple_of(4), b' ');
    let length = u32::try_from(12 + 8 + json.len() + 8 + bin.len())
        .map_err(|_| Error::Unsupported(format!("{}: over 4 GiB", path.display())))?;
    let fail = |e| Error::io(path, e);
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(fail)?);
    out.write_all(b"glTF").map_err(fail)?;
    out.write_all(&2u32.to_le_bytes()).map_err(fail)?;
    out.write_all(&length.to_le_bytes()).map_err(fail)?;
    out.write_all(&(json.len() as u32).to_le_bytes())
        .map_err(fail)?;
    out.write_all(b"JSON").map_err(fail)?;
    out.write_all(&json).map_err(fail)?;
    out.write_all(&(bin.len() as u32).to_le_bytes())
        .map_err(fail)?;
    out.write_all(b"BIN\0").map_err(fail)?;
    out.write_all(&bin).map_err(fail)?;
    out.flush().map_err(fail)
}

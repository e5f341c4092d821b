//! Mesh files: Wavefront OBJ (+ MTL) through `tobj`, glTF 2.0 (`.gltf`, `.glb`) through
//! `gltf` without its `import` feature (we resolve buffers ourselves and never decode
//! images). Both return the file's meshes in their own frames with their placements,
//! and the file's own materials, already reduced to scalar diffuse and glossy
//! reflectances and a roughness (docs/scene.md). The glTF reader is `gltf_file`.

mod gltf_file;

use super::shapes::Mesh;
use crate::error::{Error, Result};
use crate::input::one_line;
use glam::{DMat4, DVec3};
use std::path::Path;

/// RGB → scalar reflectance: luminance-weighted (Rec. 709 / sRGB Y), because luxtally
/// tallies photometric quantities and the eye weighs green most.
pub fn rgb_to_reflectance(rgb: [f64; 3]) -> f64 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// A material found in a mesh file.
#[derive(Clone, Debug, PartialEq)]
pub struct FileMaterial {
    /// The material's name in the file, or its index when unnamed.
    pub name: String,
    /// Lambertian reflectance (NaN: the file gives no colour).
    pub reflectance: f64,
    /// GGX glossy reflectance (0: none).
    pub glossy_reflectance: f64,
    /// Roughness of the glossy lobe, in (0, 1].
    pub roughness: f64,
}

/// Smallest roughness a mesh file's material maps to (α = 10⁻⁶: a mirror in effect).
pub const MIN_FILE_ROUGHNESS: f64 = 1e-3;

/// MTL → (reflectance, glossy_reflectance, roughness). `Ks` (its luminance-weighted
/// scalar k_s) becomes the glossy lobe and the diffuse part keeps what it leaves,
/// Y(Kd)·(1 − k_s), so the sum never exceeds 1. The Blinn–Phong exponent `Ns` maps to
/// the equivalent Beckmann/GGX width α = √(2/(Ns + 2)) (Walter et al. 2007), and
/// roughness = √α; without `Ns` the lobe is as rough as it gets (roughness 1).
pub fn mtl_to_material(kd: [f64; 3], ks: Option<[f64; 3]>, ns: Option<f64>) -> (f64, f64, f64) {
    let diffuse = rgb_to_reflectance(kd);
    let ks = ks.map_or(0.0, rgb_to_reflectance).clamp(0.0, 1.0);
    if ks.is_nan() || ks <= 0.0 {
        return (diffuse, 0.0, 1.0);
    }
    let ns = ns.unwrap_or(0.0).max(0.0);
    let alpha = (2.0 / (ns + 2.0)).sqrt();
    let roughness = alpha.sqrt().clamp(MIN_FILE_ROUGHNESS, 1.0);
    (diffuse * (1.0 - ks), ks, roughness)
}

/// glTF metallic–roughness → (reflectance, glossy_reflectance, roughness), b = Y(base
/// colour), m = metallicFactor (default 1 as the specification says): a metal (m) is a
/// glossy lobe of albedo b; a dielectric (1 − m) has a 4 % specular glossy lobe (F0 of
/// index 1.5) over a diffuse base of 0.96·b. glTF's roughnessFactor is already the
/// perceptual roughness with α = roughness² (clamped to ≥ 10⁻³).
pub fn gltf_to_material(base: [f64; 3], metallic: f64, roughness: f64) -> (f64, f64, f64) {
    const F0: f64 = 0.04;
    let b = rgb_to_reflectance(base);
    let m = metallic.clamp(0.0, 1.0);
    (
        (1.0 - m) * (1.0 - F0) * b,
        m * b + (1.0 - m) * F0,
        roughness.clamp(MIN_FILE_ROUGHNESS, 1.0),
    )
}

/// A loaded mesh file. `material[t]` indexes `materials`, or is `None` when the file gives
/// triangle `t` no (usable) material; `missing_reason` then says why.
#[derive(Clone, Debug, Default)]
pub struct MeshFile {
    pub mesh: Mesh,
    pub material: Vec<Option<u32>>,
    pub materials: Vec<FileMaterial>,
    pub missing_reason: Option<String>,
}

/// A mesh file as shared meshes and their placements: glTF nodes that use one mesh are
/// placements of one prototype; an OBJ is one prototype placed once.
#[derive(Clone, Debug, Default)]
pub struct MeshParts {
    /// Per prototype: its mesh in its own frame and its triangles' file materials.
    pub prototypes: Vec<(Mesh, Vec<Option<u32>>)>,
    /// (prototype, file-frame transform), in the file's node order.
    pub placements: Vec<(u32, DMat4)>,
    pub materials: Vec<FileMaterial>,
    pub missing_reason: Option<String>,
}

/// Loads `path` by extension as prototypes and placements, nothing copied.
pub fn load_mesh_parts(path: &Path, origin: &str) -> Result<MeshParts> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let bytes = std::fs::read(path).map_err(|e| {
        Error::input(
            origin,
            format!("cannot read mesh file {}: {e}", path.display()),
        )
    })?;
    let at = Culprit {
        origin,
        file: path.display().to_string(),
    };
    let out = match ext.as_str() {
        "obj" => {
            let file = load_obj(&bytes, path, &at)?;
            MeshParts {
                prototypes: vec![(file.mesh, file.material)],
                placements: vec![(0, DMat4::IDENTITY)],
                materials: file.materials,
                missing_reason: file.missing_reason,
            }
        }
        "gltf" | "glb" => gltf_file::load_gltf(&bytes, path, &at)?,
        _ => return Err(at.error("unsupported mesh format (expected .obj, .gltf or .glb)")),
    };
    Ok(out)
}

/// The mesh file an error is about: the scene key that names it (`objects[2].file`) and
/// its path, so every message from the readers below is one line naming both.
struct Culprit<'a> {
    origin: &'a str,
    file: String,
}

impl Culprit<'_> {
    fn error(&self, message: impl std::fmt::Display) -> Error {
        Error::input(
            self.origin,
            format!("{}: {}", self.file, one_line(&message.to_string())),
        )
    }
}

fn check_vertex(p: DVec3, at: &Culprit) -> Result<DVec3> {
    if p.is_finite() {
        Ok(p)
    } else {
        Err(at.error(format!("vertex {p} is not finite")))
    }
}

fn load_obj(bytes: &[u8], path: &Path, at: &Culprit) -> Result<MeshFile> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        // Points and lines have no area; tobj would turn them into degenerate triangles.
        ignore_points: true,
        ignore_lines: true,
    };
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut reader = std::io::Cursor::new(bytes);
    let (models, materials) =
        tobj::load_obj_buf(&mut reader, &options, |mtl| tobj::load_mtl(dir.join(mtl)))
            .map_err(|e| at.error(format!("malformed OBJ: {e}")))?;

    let mut out = MeshFile::default();
    // MTL problems only matter when no `material` override is given, so keep the reason.
    let mtl_ok = match materials {
        Ok(mats) => {
            out.materials = mats.iter().enumerate().map(obj_material).collect();
            true
        }
        Err(e) => {
            out.missing_reason = Some(format!("its MTL file could not be loaded ({e})"));
            false
        }
    };
    for model in &models {
        add_obj_model(&mut out, model, mtl_ok, at)?;
    }
    Ok(out)
}

/// MTL material `k`; one without Kd keeps its slot (indices must stay aligned) but is
/// marked unusable (NaN reflectance).
fn obj_material((k, m): (usize, &tobj::Material)) -> FileMaterial {
    let name = if m.name.is_empty() {
        k.to_string()
    } else {
        m.name.clone()
    };
    match m.diffuse {
        Some(kd) => {
            let (reflectance, glossy_reflectance, roughness) = mtl_to_material(
                kd.map(f64::from),
                m.specular.map(|ks| ks.map(f64::from)),
                m.shininess.map(f64::from),
            );
            FileMaterial {
                name,
                reflectance,
                glossy_reflectance,
                roughness,
            }
        }
        None => FileMaterial {
            name,
            reflectance: f64::NAN,
            glossy_reflectance: 0.0,
            roughness: 1.0,
        },
    }
}

/// Appends an OBJ model's vertices and triangles to `out`, with its MTL material when
/// it has a usable one (`mtl_ok`: the MTL file loaded), else why not.
fn add_obj_model(
    out: &mut MeshFile,
    model: &tobj::Model,
    mtl_ok: bool,
    at: &Culprit,
) -> Result<()> {
    let m = &model.mesh;
    if !m.positions.len().is_multiple_of(3) || !m.indices.len().is_multiple_of(3) {
        return Err(at.error(format!(
            "malformed OBJ: model `{}` is incomplete",
            model.name
        )));
    }
    let base = out.mesh.vertices.len();
    let count = m.positions.len() / 3;
    for p in m.positions.chunks_exact(3) {
        let v = DVec3::new(p[0].into(), p[1].into(), p[2].into());
        out.mesh.vertices.push(check_vertex(v, at)?);
    }
    let material = match m.material_id {
        Some(id) if mtl_ok => match out.materials.get(id) {
            Some(fm) if fm.reflectance.is_nan() => {
                out.missing_reason = Some(format!("material `{}` has no Kd", fm.name));
                None
            }
            Some(_) => Some(id as u32),
            None => {
                out.missing_reason = Some(format!("material index {id} is not in its MTL"));
                None
            }
        },
        Some(_) => None,
        None => {
            out.missing_reason = Some(format!("object `{}` has no material", model.name));
            None
        }
    };
    for t in m.indices.chunks_exact(3) {
        let mut tri = [0u32; 3];
        for (slot, &i) in tri.iter_mut().zip(t) {
            if i as usize >= count {
                return Err(at.error(format!(
                    "malformed OBJ: face index {} out of range in `{}`",
                    i + 1,
                    model.name
                )));
            }
            *slot = u32::try_from(base + i as usize).map_err(|_| at.error("too many vertices"))?;
        }
        out.mesh.triangles.push(tri);
        out.material.push(material);
    }
    Ok(())
}

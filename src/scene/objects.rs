//! The `[[objects]]` entries into one `Geometry`: built-in shapes and mesh files, their
//! materials, transforms and instanced copies; mapped objects merged in world space,
//! unmapped ones kept as prototypes and placements. Every check names the key at fault.

// `!(x > 0.0)` is deliberate: it also rejects NaN (e.g. from an overflowing cross product).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::file::{InstanceFile, ObjectEntry, ObjectFile, ScaleFile, ShapeFile, Source};
use super::mesh_io;
use super::shapes::{self, Mesh, Transform};
use super::{Geometry, Material, Placement, PrototypeMesh};
use crate::error::{Error, Result};
use crate::input::{self, required, vec3};
use glam::{DAffine3, DVec3};
use std::path::Path;

/// Mapped triangles are tallied with 8 deposit codes each in a `u32`
/// (`tally::deposit_code`), and a map costs ~200 bytes per triangle: 2²⁹ − 1 triangles
/// is both the code space and ~100 GiB.
pub const MAX_MAPPED_TRIANGLES: u64 = (1 << 29) - 1;

/// Instances: ~0.9 KiB each measured with Embree (BENCHMARKS.md, bench-scale), so 2²⁴ is
/// ~15 GiB.
pub const MAX_INSTANCES: u64 = 1 << 24;

/// Errs when `total` `what` pass `limit` (`hint` ends the message).
fn within_limit(total: u64, limit: u64, what: &str, hint: &str, at: &str) -> Result<()> {
    if total > limit {
        return Err(Error::input(
            at,
            format!("{total} {what} exceed the limit of {limit}{hint}"),
        ));
    }
    Ok(())
}

/// Collects every mapped object's triangles in world space and every unmapped object's
/// prototypes and placements, then builds one `Geometry`.
#[derive(Default)]
pub(super) struct GeometryBuilder {
    /// Mapped objects' meshes in world space, joined once by `finish` (a large mesh is
    /// moved, not copied, when it is the only one).
    mapped: Vec<MappedPart>,
    mapped_vertices: usize,
    mapped_triangles: usize,
    prototypes: Vec<PrototypeMesh>,
    placements: Vec<Placement>,
}

struct MappedPart {
    mesh: Mesh,
    material: Vec<u32>,
    object: u32,
}

impl GeometryBuilder {
    fn add(&mut self, mesh: Mesh, material: Vec<u32>, object: u32, at: &str) -> Result<()> {
        check_reach(&mesh.vertices, at, "vertex", " (after the transforms)")?;
        // Geometry indexes vertices with u32.
        if self.mapped_vertices + mesh.vertices.len() > u32::MAX as usize {
            return Err(Error::input(
                at,
                "too many vertices in the scene (more than 2^32)",
            ));
        }
        self.mapped_vertices += mesh.vertices.len();
        self.mapped_triangles += mesh.triangles.len();
        self.mapped.push(MappedPart {
            mesh,
            material,
            object,
        });
        Ok(())
    }

    /// Errs, before anything is allocated, when `more` mapped triangles would pass
    /// [`MAX_MAPPED_TRIANGLES`].
    fn check_mapped(&self, more: u64, at: &str) -> Result<()> {
        let total = self.mapped_triangles as u64 + more;
        let hint = " (each holds a map): set `map = false` on instanced objects";
        within_limit(total, MAX_MAPPED_TRIANGLES, "mapped triangles", hint, at)
    }

    /// Errs when `more` instances would pass [`MAX_INSTANCES`].
    fn check_instances(&self, more: u64, at: &str) -> Result<()> {
        let total = self.placements.len() as u64 + more;
        within_limit(total, MAX_INSTANCES, "instances", "", at)
    }

    pub(super) fn finish(mut self) -> Result<Geometry> {
        let (vertices, triangles, material, object) = if self.mapped.len() == 1 {
            let part = self.mapped.pop().expect("one part");
            let object = vec![part.object; part.mesh.triangles.len()];
            (
                part.mesh.vertices,
                part.mesh.triangles,
                part.material,
                object,
            )
        } else {
            let (v, t) = (self.mapped_vertices, self.mapped_triangles);
            let mut vertices = Vec::with_capacity(v);
            let mut triangles = Vec::with_capacity(t);
            let mut material = Vec::with_capacity(t);
            let mut object = Vec::with_capacity(t);
            for part in self.mapped {
                let base = vertices.len() as u32;
                vertices.extend_from_slice(&part.mesh.vertices);
                triangles.extend(part.mesh.triangles.iter().map(|t| t.map(|i| i + base)));
                material.extend_from_slice(&part.material);
                object.extend(std::iter::repeat_n(part.object, part.mesh.triangles.len()));
            }
            (vertices, triangles, material, object)
        };
        Ok(Geometry::with_instances(
            &vertices,
            triangles,
            &material,
            &object,
            &self.prototypes,
            &self.placements,
        ))
    }
}

fn material_index(materials: &[Material], name: &str) -> Option<u32> {
    materials
        .iter()
        .position(|m| m.name == name)
        .map(|i| i as u32)
}

/// An object's meshes with scene materials, and where each goes in the object's frame
/// (prototype index, placement).
type Prototypes = (Vec<PrototypeMesh>, Vec<(u32, DAffine3)>);

/// One `[[objects]]` entry into the builder: its prototypes (a built-in shape, or a mesh
/// file's meshes) placed by its own transform and copies, flattened into the map or
/// kept as instances (`map = false`).
pub(super) fn load_object(
    entry: &ObjectEntry,
    i: usize,
    origin: &str,
    base_dir: &Path,
    materials: &mut Vec<Material>,
    builder: &mut GeometryBuilder,
) -> Result<()> {
    let o = &entry.object;
    let at = format!("{origin}: objects[{i}]");
    let override_material = match &o.material {
        Some(name) => Some(material_index(materials, name).ok_or_else(|| {
            Error::input(
                format!("{at}.material"),
                format!("unknown material `{name}`"),
            )
        })?),
        None => None,
    };
    let transform = transform(o, &at)?;
    let copies = copies(o, &at)?;
    let mapped = o.mapped();
    let object = Placed {
        object: i as u32,
        transform,
        copies,
        at,
    };
    let (prototypes, placements) = match &entry.source {
        Source::Shape(shape) => shape_prototype(shape, override_material, &object.at)?,
        Source::File(file) => {
            let found = (override_material, base_dir);
            file_prototypes(file, found, &object.at, materials)?
        }
    };
    if mapped {
        object.add_mapped(builder, prototypes, &placements)
    } else {
        object.add_instances(builder, prototypes, &placements)
    }
}

/// A built-in shape in the object's material, as one prototype placed once.
fn shape_prototype(shape: &ShapeFile, material: Option<u32>, at: &str) -> Result<Prototypes> {
    let material = material.ok_or_else(|| {
        Error::input(
            format!("{at}.material"),
            format!("missing (required for shape \"{}\")", shape.name()),
        )
    })?;
    let mesh = builtin_shape(shape, at)?;
    let proto = PrototypeMesh {
        material: vec![material; mesh.triangles.len()],
        vertices: mesh.vertices,
        triangles: mesh.triangles,
    };
    Ok((vec![proto], vec![(0, DAffine3::IDENTITY)]))
}

/// A mesh file's prototypes and placements, in the object's material (`found.0`) or the
/// file's own. `found.1`: the scene file's directory.
fn file_prototypes(
    file: &str,
    found: (Option<u32>, &Path),
    at: &str,
    materials: &mut Vec<Material>,
) -> Result<Prototypes> {
    let (override_material, base_dir) = found;
    let mesh_path = base_dir.join(file);
    let parts = mesh_io::load_mesh_parts(&mesh_path, &format!("{at}.file"))?;
    let mut protos = Vec::with_capacity(parts.prototypes.len());
    for (mesh, tri_material) in parts.prototypes {
        let material = match override_material {
            Some(m) => vec![m; mesh.triangles.len()],
            None => file_materials(
                &parts.materials,
                &tri_material,
                parts.missing_reason.as_deref(),
                file,
                at,
                materials,
            )?,
        };
        protos.push(PrototypeMesh {
            vertices: mesh.vertices,
            triangles: mesh.triangles,
            material,
        });
    }
    let placements = parts
        .placements
        .iter()
        .map(|(p, m)| (*p, DAffine3::from_mat4(*m)))
        .collect();
    Ok((protos, placements))
}

/// Refuses the first of `points` beyond [`input::MAX_COORDINATE_M`], naming `at`.
fn check_reach(points: &[DVec3], at: &str, what: &str, note: &str) -> Result<()> {
    match points.iter().find(|p| !input::within_reach(**p)) {
        Some(bad) => Err(Error::input(
            at,
            input::beyond_reach(format!("{what} {bad}{note}")),
        )),
        None => Ok(()),
    }
}

/// The eight corners of box `[lo, hi]`; an empty box (lo > hi) gives the origin.
fn box_corners([lo, hi]: [DVec3; 2]) -> [DVec3; 8] {
    if lo.x > hi.x {
        return [DVec3::ZERO; 8];
    }
    std::array::from_fn(|k| {
        DVec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), hi, lo)
    })
}

/// The corners of the box around `vertices` (lowest, highest).
fn bounds_of(vertices: &[DVec3]) -> [DVec3; 2] {
    vertices
        .iter()
        .fold([DVec3::INFINITY, DVec3::NEG_INFINITY], |[lo, hi], v| {
            [lo.min(*v), hi.max(*v)]
        })
}

/// How an object is placed: its index, own transform and copies; `at` names it.
struct Placed {
    object: u32,
    transform: Transform,
    copies: Vec<DAffine3>,
    at: String,
}

impl Placed {
    /// Unmapped: the prototypes stored once, an instance per copy and placement.
    fn add_instances(
        &self,
        builder: &mut GeometryBuilder,
        prototypes: Vec<PrototypeMesh>,
        placements: &[(u32, DAffine3)],
    ) -> Result<()> {
        let at = &self.at;
        let copies_total = (self.copies.len() as u64).saturating_mul(placements.len() as u64);
        builder.check_instances(copies_total, at)?;
        let object_tf = self.transform.affine();
        let base = builder.prototypes.len() as u32;
        let bounds: Vec<[DVec3; 2]> = prototypes.iter().map(|p| bounds_of(&p.vertices)).collect();
        for p in &prototypes {
            check_reach(&p.vertices, &format!("{at}.file"), "vertex", "")?;
        }
        builder.prototypes.extend(prototypes);
        for copy in &self.copies {
            for (proto, node) in placements {
                let world = *copy * object_tf * *node;
                if !world.is_finite() || world.matrix3.determinant() == 0.0 {
                    return Err(Error::input(
                        at,
                        "an instance transform is not finite or not invertible",
                    ));
                }
                let corners =
                    box_corners(bounds[*proto as usize]).map(|c| world.transform_point3(c));
                check_reach(&corners, at, "a copy's bounding-box corner", "")?;
                builder.placements.push(Placement {
                    prototype: base + proto,
                    object: self.object,
                    world,
                });
            }
        }
        Ok(())
    }

    /// Mapped: flattened in f64 into the scene's one triangle mesh; refused before
    /// the flattening allocates when its copies would pass [`MAX_MAPPED_TRIANGLES`].
    fn add_mapped(
        &self,
        builder: &mut GeometryBuilder,
        prototypes: Vec<PrototypeMesh>,
        placements: &[(u32, DAffine3)],
    ) -> Result<()> {
        let at = &self.at;
        let per_copy: u64 = placements
            .iter()
            .map(|(p, _)| prototypes[*p as usize].triangles.len() as u64)
            .sum();
        builder.check_mapped(per_copy.saturating_mul(self.copies.len() as u64), at)?;
        let (mut mesh, per_tri) = flatten(prototypes, placements);
        check_reach(&mesh.vertices, &format!("{at}.file"), "vertex", "")?;
        self.transform.apply(&mut mesh.vertices);
        if self.copies.len() == 1 && self.copies[0] == DAffine3::IDENTITY {
            return builder.add(mesh, per_tri, self.object, at);
        }
        for copy in &self.copies {
            let mut placed = Mesh::default();
            append_placed(&mut placed, (&mesh.vertices, &mesh.triangles), Some(copy));
            builder.add(placed, per_tri.clone(), self.object, at)?;
        }
        Ok(())
    }
}

/// The prototypes at their placements as one mesh in the object's frame, with each
/// triangle's material.
fn flatten(mut prototypes: Vec<PrototypeMesh>, placements: &[(u32, DAffine3)]) -> (Mesh, Vec<u32>) {
    // One prototype placed once as it is (a mesh file's usual case): taken, not copied.
    if let [(proto, node)] = placements {
        if *node == DAffine3::IDENTITY {
            let pm = prototypes.swap_remove(*proto as usize);
            let mesh = Mesh {
                vertices: pm.vertices,
                triangles: pm.triangles,
            };
            return (mesh, pm.material);
        }
    }
    let mut mesh = Mesh::default();
    let mut per_tri = Vec::new();
    for (proto, node) in placements {
        let pm = &prototypes[*proto as usize];
        // An identity node leaves the vertices' bits as the file has them (-0.0 stays).
        let moved = (*node != DAffine3::IDENTITY).then_some(node);
        append_placed(&mut mesh, (&pm.vertices, &pm.triangles), moved);
        per_tri.extend_from_slice(&pm.material);
    }
    (mesh, per_tri)
}

/// Appends `part` (vertices, triangles) to `mesh`, moved by `m` (`None`: as it is); a
/// mirroring `m` reverses the triangles' winding, so their normals keep facing out.
fn append_placed(mesh: &mut Mesh, part: (&[DVec3], &[[u32; 3]]), m: Option<&DAffine3>) {
    let (vertices, triangles) = part;
    let base = mesh.vertices.len() as u32;
    match m {
        Some(m) => mesh
            .vertices
            .extend(vertices.iter().map(|p| m.transform_point3(*p))),
        None => mesh.vertices.extend_from_slice(vertices),
    }
    let mirrored = m.is_some_and(|m| m.matrix3.determinant() < 0.0);
    mesh.triangles.extend(triangles.iter().map(|t| {
        let t = t.map(|k| k + base);
        if mirrored {
            [t[0], t[2], t[1]]
        } else {
            t
        }
    }));
}

/// The copies of an object (applied after its own transform): each `instances` entry
/// (default: one identity) at each `grid` point (default: the origin only).
fn copies(o: &ObjectFile, at: &str) -> Result<Vec<DAffine3>> {
    let list: Vec<DAffine3> = match &o.instances {
        None => vec![DAffine3::IDENTITY],
        Some(list) if list.is_empty() => {
            return Err(Error::input(format!("{at}.instances"), "is empty"));
        }
        Some(list) => list
            .iter()
            .enumerate()
            .map(|(k, inst)| instance_transform(inst, &format!("{at}.instances[{k}]")))
            .collect::<Result<_>>()?,
    };
    let Some(grid) = o.grid else {
        return Ok(list);
    };
    let [nx, ny] = grid.count;
    if nx == 0 || ny == 0 {
        return Err(Error::input(
            format!("{at}.grid.count"),
            format!("zero copies: {:?} (each must be ≥ 1)", grid.count),
        ));
    }
    let total = o.copy_count();
    if total > MAX_INSTANCES {
        return Err(Error::input(
            format!("{at}.grid.count"),
            format!("{total} copies exceed the limit of {MAX_INSTANCES} instances"),
        ));
    }
    let [dx, dy] = grid.spacing.map(|l| l.0);
    let mut out = Vec::with_capacity(total as usize);
    for j in 0..ny {
        for i in 0..nx {
            let shift = DVec3::new(i as f64 * dx, j as f64 * dy, 0.0);
            out.extend(list.iter().map(|m| DAffine3::from_translation(shift) * *m));
        }
    }
    Ok(out)
}

/// One `instances` entry: scale → rotate → translate; any non-zero scale (negative
/// mirrors).
fn instance_transform(inst: &InstanceFile, at: &str) -> Result<DAffine3> {
    let scale = match inst.scale {
        None => DVec3::ONE,
        Some(ScaleFile::Uniform(s)) => DVec3::splat(s),
        Some(ScaleFile::PerAxis(s)) => vec3(s),
    };
    if scale.cmpeq(DVec3::ZERO).any() {
        return Err(Error::input(format!("{at}.scale"), "must not be 0"));
    }
    let t = Transform {
        scale,
        rotate_deg: inst.rotate_deg.map_or(DVec3::ZERO, vec3),
        translate: inst.translate.map_or(DVec3::ZERO, vec3),
    };
    Ok(t.affine())
}

/// Turns a mesh file's own materials into scene materials named `FILE:NAME`; a scene
/// material of that exact name (defined in `[materials]` or by an earlier object) is reused.
fn file_materials(
    file_materials: &[mesh_io::FileMaterial],
    tri_material: &[Option<u32>],
    missing_reason: Option<&str>,
    file: &str,
    at: &str,
    materials: &mut Vec<Material>,
) -> Result<Vec<u32>> {
    let mut scene_index = Vec::with_capacity(file_materials.len());
    for fm in file_materials {
        let name = format!("{file}:{}", fm.name);
        let index = match material_index(materials, &name) {
            Some(k) => k,
            None => {
                // Materials the file defines without a colour (NaN) are only an error
                // if a triangle uses them, which `missing_reason` reports below.
                let material = Material {
                    glossy_reflectance: fm.glossy_reflectance,
                    roughness: fm.roughness,
                    ..Material::lambertian(&name, fm.reflectance)
                };
                if !fm.reflectance.is_nan() {
                    material.validate(&format!("{at}.file: material `{}`", fm.name))?;
                }
                materials.push(material);
                (materials.len() - 1) as u32
            }
        };
        scene_index.push(index);
    }
    tri_material
        .iter()
        .map(|m| {
            m.and_then(|k| scene_index.get(k as usize).copied()).ok_or_else(|| {
                let reason = missing_reason.unwrap_or("it has no usable material");
                Error::input(
                    format!("{at}.material"),
                    format!("`{file}` gives no material ({reason}): set `material = \"...\"` on this object"),
                )
            })
        })
        .collect()
}

fn transform(o: &ObjectFile, at: &str) -> Result<Transform> {
    let scale = match o.scale {
        None => DVec3::ONE,
        Some(ScaleFile::Uniform(s)) => DVec3::splat(s),
        Some(ScaleFile::PerAxis(s)) => vec3(s),
    };
    if !(scale.cmpgt(DVec3::ZERO).all()) {
        return Err(Error::input(format!("{at}.scale"), "must be > 0"));
    }
    Ok(Transform {
        scale,
        rotate_deg: o.rotate_deg.map_or(DVec3::ZERO, vec3),
        translate: o.translate.map_or(DVec3::ZERO, vec3),
    })
}

/// A built-in shape's mesh, its keys validated.
fn builtin_shape(shape: &ShapeFile, at: &str) -> Result<Mesh> {
    let what = format!("shape \"{}\"", shape.name());
    match shape {
        ShapeFile::Box(o) => {
            let min = vec3(required(o.min, at, "min", &what)?);
            let max = vec3(required(o.max, at, "max", &what)?);
            if !min.cmplt(max).all() {
                return Err(Error::input(
                    format!("{at}.max"),
                    format!("must exceed min on every axis (min {min}, max {max})"),
                ));
            }
            Ok(shapes::make_box(min, max))
        }
        ShapeFile::Rect(o) => {
            let corner = vec3(required(o.corner, at, "corner", &what)?);
            let u = vec3(required(o.u, at, "u", &what)?);
            let v = vec3(required(o.v, at, "v", &what)?);
            if !(u.cross(v).length() > 0.0) {
                return Err(Error::input(at, "zero-area rect: u × v = 0"));
            }
            Ok(shapes::make_rect(corner, u, v))
        }
        ShapeFile::Sphere(o) => {
            let center = vec3(required(o.center, at, "center", &what)?);
            let radius = required(o.radius, at, "radius", &what)?.0;
            if !(radius > 0.0) {
                return Err(Error::input(
                    format!("{at}.radius"),
                    format!("must be > 0, got {radius}"),
                ));
            }
            let subdivisions = o
                .subdivisions
                .unwrap_or(shapes::DEFAULT_SPHERE_SUBDIVISIONS);
            if subdivisions > shapes::MAX_SPHERE_SUBDIVISIONS {
                return Err(Error::input(
                    format!("{at}.subdivisions"),
                    format!(
                        "must be in 0..={}, got {subdivisions}",
                        shapes::MAX_SPHERE_SUBDIVISIONS
                    ),
                ));
            }
            Ok(shapes::make_sphere(center, radius, subdivisions))
        }
    }
}

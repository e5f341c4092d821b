//! glTF 2.0 (`.gltf`, `.glb`) through `gltf` without its `import` feature: buffers are
//! resolved here and images never decoded; the node tree is walked into prototypes (one
//! per glTF mesh) and their placements, tightly packed data decoded in parallel.

use super::{check_vertex, gltf_to_material, Culprit, FileMaterial, MeshParts};
use crate::error::{Error, Result};
use crate::scene::shapes::Mesh;
use glam::{DMat4, DQuat, DVec3};
use std::borrow::Cow;
use std::path::Path;

/// The bytes of a tightly packed accessor (no stride, or a stride of one element) when
/// they lie within their buffer; `None` sends the caller to `gltf`'s reader, which
/// handles every layout and reports data outside the buffer.
fn packed_bytes<'b>(accessor: &gltf::Accessor, buffers: &'b [Cow<[u8]>]) -> Option<&'b [u8]> {
    // A sparse accessor's values are substituted by the reader (refused earlier anyway).
    if accessor.sparse().is_some() {
        return None;
    }
    let view = accessor.view()?;
    if view
        .stride()
        .is_some_and(|stride| stride != accessor.size())
    {
        return None;
    }
    let len = accessor.count().checked_mul(accessor.size())?;
    if accessor.offset().checked_add(len)? > view.length() {
        return None;
    }
    let start = view.offset().checked_add(accessor.offset())?;
    buffers
        .get(view.buffer().index())?
        .get(start..start.checked_add(len)?)
}

/// Items per parallel check of a mesh file's data (a check per item in parallel, as
/// `find_first` does, took longer than reading the file).
const BLOCK: usize = 1 << 16;

/// The little-endian u32 at byte `k` of `c`.
#[inline]
fn u32_at(c: &[u8], k: usize) -> u32 {
    u32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]])
}

/// The little-endian f32 at byte `k` of `c`.
#[inline]
fn f32_at(c: &[u8], k: usize) -> f32 {
    f32::from_bits(u32_at(c, k))
}

fn whole_triangles(indices: usize, at: &Culprit) -> Result<()> {
    if indices.is_multiple_of(3) {
        Ok(())
    } else {
        Err(at.error(format!(
            "{indices} indices is not a whole number of triangles"
        )))
    }
}

/// Reads a glTF buffer's bytes: the GLB chunk, a base64 `data:` URI, or a file next to
/// the glTF file.
fn buffer_data<'a>(
    buffer: &gltf::Buffer,
    blob: Option<&'a [u8]>,
    dir: &Path,
    at: &Culprit,
) -> Result<Cow<'a, [u8]>> {
    let index = buffer.index();
    let data: Cow<[u8]> = match buffer.source() {
        gltf::buffer::Source::Bin => blob
            .ok_or_else(|| at.error(format!("buffer {index} refers to a missing GLB chunk")))?
            .into(),
        gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
            use base64::Engine;
            let (_, payload) = uri.split_once(";base64,").ok_or_else(|| {
                at.error(format!(
                    "buffer {index}: only base64 data URIs are supported"
                ))
            })?;
            base64::engine::general_purpose::STANDARD
                .decode(payload)
                .map_err(|e| at.error(format!("buffer {index}: bad base64 ({e})")))?
                .into()
        }
        gltf::buffer::Source::Uri(uri) => {
            let file = dir.join(uri);
            std::fs::read(&file)
                .map_err(|e| at.error(format!("buffer {index}: {}: {e}", file.display())))?
                .into()
        }
    };
    if data.len() < buffer.length() {
        return Err(at.error(format!(
            "buffer {index} holds {} bytes, fewer than its byteLength {}",
            data.len(),
            buffer.length()
        )));
    }
    Ok(data)
}

/// Checks what `gltf`'s reader assumes (and would otherwise debug-assert or overflow on):
/// the accessor's shape, a non-empty dense view, and a count its view can hold.
fn check_accessor(
    accessor: &gltf::Accessor,
    what: &str,
    dims: gltf::accessor::Dimensions,
    types: &[gltf::accessor::DataType],
    at: &Culprit,
) -> Result<()> {
    let id = accessor.index();
    if accessor.dimensions() != dims || !types.contains(&accessor.data_type()) {
        return Err(at.error(format!(
            "accessor {id} ({what}) has type {:?} {:?}",
            accessor.dimensions(),
            accessor.data_type()
        )));
    }
    if accessor.sparse().is_some() {
        return Err(at.error(format!(
            "accessor {id} ({what}): sparse accessors are not supported"
        )));
    }
    let view = accessor
        .view()
        .ok_or_else(|| at.error(format!("accessor {id} ({what}) has no buffer view")))?;
    if let Some(stride) = view.stride() {
        if stride < accessor.size() {
            return Err(at.error(format!("accessor {id} ({what}): stride {stride} too small")));
        }
    }
    if accessor.count() == 0 || accessor.count() > view.length() {
        return Err(at.error(format!(
            "accessor {id} ({what}): bad count {}",
            accessor.count()
        )));
    }
    Ok(())
}

/// A node's local transform in f64 (TRS composed as T·R·S, as glTF specifies).
fn node_matrix(node: &gltf::Node) -> DMat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)))
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let q = DQuat::from_array(rotation.map(f64::from));
            // Unnormalised quaternions occur in the wild; a zero one means no rotation.
            let q = if q.length_squared() > 0.0 {
                q.normalize()
            } else {
                DQuat::IDENTITY
            };
            DMat4::from_scale_rotation_translation(
                DVec3::from_array(scale.map(f64::from)),
                q,
                DVec3::from_array(translation.map(f64::from)),
            )
        }
    }
}

struct GltfWalk<'a> {
    buffers: Vec<Cow<'a, [u8]>>,
    out: MeshParts,
    /// glTF mesh index → prototype, decoded on first use.
    mesh_slot: Vec<Option<u32>>,
    /// glTF material index → index in `out.materials`.
    material_slot: Vec<Option<u32>>,
    /// Nodes on the current path from the root, to reject cycles.
    stack: Vec<usize>,
    doc: &'a gltf::Document,
    at: &'a Culprit<'a>,
}

/// The JSON and the binary chunk of a glTF file, borrowed: a GLB's two chunks, or the
/// whole file as JSON. (`gltf::Gltf::from_slice` would copy a GLB's binary chunk.)
type GltfChunks<'a> = (Cow<'a, [u8]>, Option<Cow<'a, [u8]>>);

fn gltf_chunks<'b>(bytes: &'b [u8], at: &Culprit) -> Result<GltfChunks<'b>> {
    if bytes.starts_with(b"glTF") {
        let glb =
            gltf::Glb::from_slice(bytes).map_err(|e| at.error(format!("malformed glTF: {e}")))?;
        Ok((glb.json, glb.bin))
    } else {
        Ok((bytes.into(), None))
    }
}

/// gltf-json 1.4.1's validation indexes `accessors[POSITION]` before checking that the
/// index exists, and panics on a bad one: check that first on the unvalidated JSON.
fn precheck_gltf(json: &[u8], at: &Culprit) -> Result<gltf::json::Root> {
    let root: gltf::json::Root = gltf::json::deserialize::from_slice(json)
        .map_err(|e| at.error(format!("malformed glTF: {e}")))?;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for accessor in primitive.attributes.values() {
                if accessor.value() >= root.accessors.len() {
                    return Err(at.error(format!(
                        "malformed glTF: meshes[{m}].primitives[{p}] refers to missing accessor {}",
                        accessor.value()
                    )));
                }
            }
        }
    }
    Ok(root)
}

pub(super) fn load_gltf(bytes: &[u8], path: &Path, at: &Culprit) -> Result<MeshParts> {
    let (json, blob) = gltf_chunks(bytes, at)?;
    let gltf = gltf::Document::from_json(precheck_gltf(&json, at)?)
        .map_err(|e| at.error(format!("malformed glTF: {e}")))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let buffers = gltf
        .buffers()
        .map(|b| buffer_data(&b, blob.as_deref(), dir, at))
        .collect::<Result<Vec<_>>>()?;
    let scene = gltf
        .default_scene()
        .or_else(|| gltf.scenes().next())
        .ok_or_else(|| at.error("the glTF file has no scene"))?;
    let mut walk = GltfWalk {
        buffers,
        out: MeshParts::default(),
        mesh_slot: vec![None; gltf.meshes().len()],
        material_slot: vec![None; gltf.materials().len()],
        stack: Vec::new(),
        doc: &gltf,
        at,
    };
    for node in scene.nodes() {
        walk.node(&node, DMat4::IDENTITY)?;
    }
    Ok(walk.out)
}

impl GltfWalk<'_> {
    fn node(&mut self, node: &gltf::Node, parent: DMat4) -> Result<()> {
        let at = self.at;
        if self.stack.contains(&node.index()) {
            return Err(at.error(format!("node {} is its own ancestor", node.index())));
        }
        let world = parent * node_matrix(node);
        if !world.is_finite() {
            return Err(at.error(format!("node {}: transform is not finite", node.index())));
        }
        self.stack.push(node.index());
        if let Some(mesh) = node.mesh() {
            let slot = self
                .mesh_slot
                .get(mesh.index())
                .copied()
                .ok_or_else(|| at.error(format!("mesh {} does not exist", mesh.index())))?;
            let proto = match slot {
                Some(p) => p,
                None => {
                    let p = self.out.prototypes.len() as u32;
                    self.out.prototypes.push((Mesh::default(), Vec::new()));
                    for primitive in mesh.primitives() {
                        self.primitive(&primitive, p as usize)?;
                    }
                    self.mesh_slot[mesh.index()] = Some(p);
                    p
                }
            };
            self.out.placements.push((proto, world));
        }
        for child in node.children() {
            self.node(&child, world)?;
        }
        self.stack.pop();
        Ok(())
    }

    /// Appends a triangle primitive to prototype `proto`: its vertices, its triangles
    /// and their material. Lines and points have no area: skipped.
    fn primitive(&mut self, primitive: &gltf::Primitive, proto: usize) -> Result<()> {
        use gltf::accessor::{DataType, Dimensions};
        let at = self.at;
        if primitive.mode() != gltf::mesh::Mode::Triangles {
            return Ok(());
        }
        let positions = primitive
            .get(&gltf::Semantic::Positions)
            .ok_or_else(|| at.error("a triangle primitive has no POSITION"))?;
        check_accessor(
            &positions,
            "POSITION",
            Dimensions::Vec3,
            &[DataType::F32],
            at,
        )?;
        if let Some(indices) = primitive.indices() {
            check_accessor(
                &indices,
                "indices",
                Dimensions::Scalar,
                &[DataType::U8, DataType::U16, DataType::U32],
                at,
            )?;
        }
        let material = self.material(primitive)?;
        let mesh = &mut self.out.prototypes[proto].0;
        let base = mesh.vertices.len();
        read_positions(&mut mesh.vertices, primitive, &positions, &self.buffers, at)?;
        let vertex_count = mesh.vertices.len() - base;
        let triangles_before = mesh.triangles.len();
        let corners = Corners {
            base,
            vertex_count,
            at,
        };
        read_triangles(&mut mesh.triangles, primitive, &corners, &self.buffers)?;
        let added = mesh.triangles.len() - triangles_before;
        let materials = &mut self.out.prototypes[proto].1;
        materials.resize(materials.len() + added, material);
        Ok(())
    }

    /// The primitive's material as a slot in `out.materials`, created on first use.
    fn material(&mut self, primitive: &gltf::Primitive) -> Result<Option<u32>> {
        let at = self.at;
        let Some(index) = primitive.material().index() else {
            self.out.missing_reason = Some("a primitive has no material".to_string());
            return Ok(None);
        };
        let slot = self
            .material_slot
            .get_mut(index)
            .ok_or_else(|| at.error(format!("material {index} does not exist")))?;
        if let Some(s) = slot {
            return Ok(Some(*s));
        }
        let m = self
            .doc
            .materials()
            .nth(index)
            .ok_or_else(|| at.error(format!("material {index} does not exist")))?;
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, _alpha] = pbr.base_color_factor();
        let (reflectance, glossy_reflectance, roughness) = gltf_to_material(
            [r, g, b].map(f64::from),
            pbr.metallic_factor().into(),
            pbr.roughness_factor().into(),
        );
        self.out.materials.push(FileMaterial {
            name: m.name().map_or_else(|| index.to_string(), str::to_string),
            reflectance,
            glossy_reflectance,
            roughness,
        });
        let s = (self.out.materials.len() - 1) as u32;
        *slot = Some(s);
        Ok(Some(s))
    }
}

/// Appends a primitive's POSITION accessor to `vertices`, each checked finite. Read
/// straight into the mesh, so a 10⁷-triangle file is not held three times; tightly
/// packed data (the usual layout) is decoded in parallel.
fn read_positions(
    vertices: &mut Vec<DVec3>,
    primitive: &gltf::Primitive,
    positions: &gltf::Accessor,
    buffers: &[Cow<[u8]>],
    at: &Culprit,
) -> Result<()> {
    use rayon::prelude::*;
    let base = vertices.len();
    if let Some(bytes) = packed_bytes(positions, buffers) {
        vertices.par_extend(bytes.par_chunks_exact(12).map(|c| {
            DVec3::new(
                f32_at(c, 0).into(),
                f32_at(c, 4).into(),
                f32_at(c, 8).into(),
            )
        }));
        let added = &vertices[base..];
        if !added
            .par_chunks(BLOCK)
            .all(|b| b.iter().all(|p| p.is_finite()))
        {
            added
                .iter()
                .try_for_each(|&p| check_vertex(p, at).map(drop))?;
        }
    } else {
        let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &**d));
        let read = reader.read_positions().ok_or_else(|| {
            at.error(format!(
                "accessor {}: data outside its buffer",
                positions.index()
            ))
        })?;
        vertices.reserve_exact(positions.count());
        for p in read {
            vertices.push(check_vertex(DVec3::from_array(p.map(f64::from)), at)?);
        }
    }
    Ok(())
}

/// A primitive's vertices in its prototype: `vertex_count` of them from `base` on.
struct Corners<'a> {
    base: usize,
    vertex_count: usize,
    at: &'a Culprit<'a>,
}

impl Corners<'_> {
    fn out_of_range(&self, i: u32) -> Error {
        self.at.error(format!(
            "index {i} out of range ({} vertices)",
            self.vertex_count
        ))
    }

    /// The prototype's vertex for the primitive's index `i`.
    fn corner(&self, i: u32) -> Result<u32> {
        if i as usize >= self.vertex_count {
            return Err(self.out_of_range(i));
        }
        u32::try_from(self.base + i as usize).map_err(|_| self.at.error("too many vertices"))
    }
}

/// Appends a primitive's triangles to `triangles`: from its index accessor, or from
/// consecutive vertices when it has none.
fn read_triangles(
    triangles: &mut Vec<[u32; 3]>,
    primitive: &gltf::Primitive,
    corners: &Corners,
    buffers: &[Cow<[u8]>],
) -> Result<()> {
    let at = corners.at;
    let packed_indices = primitive
        .indices()
        .filter(|acc| acc.data_type() == gltf::accessor::DataType::U32)
        .and_then(|acc| packed_bytes(&acc, buffers));
    match (primitive.indices(), packed_indices) {
        (Some(_), Some(bytes)) => packed_triangles(triangles, bytes, corners)?,
        (Some(acc), None) => {
            let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &**d));
            let mut indices = reader
                .read_indices()
                .ok_or_else(|| {
                    at.error(format!("accessor {}: data outside its buffer", acc.index()))
                })?
                .into_u32();
            whole_triangles(indices.len(), at)?;
            triangles.reserve_exact(indices.len() / 3);
            while let (Some(a), Some(b), Some(c)) = (indices.next(), indices.next(), indices.next())
            {
                triangles.push([corners.corner(a)?, corners.corner(b)?, corners.corner(c)?]);
            }
        }
        (None, _) => {
            whole_triangles(corners.vertex_count, at)?;
            triangles.reserve_exact(corners.vertex_count / 3);
            for k in (0..corners.vertex_count as u32).step_by(3) {
                triangles.push([
                    corners.corner(k)?,
                    corners.corner(k + 1)?,
                    corners.corner(k + 2)?,
                ]);
            }
        }
    }
    Ok(())
}

/// Appends the triangles of tightly packed u32 indices, checked and offset in parallel.
fn packed_triangles(triangles: &mut Vec<[u32; 3]>, bytes: &[u8], corners: &Corners) -> Result<()> {
    use rayon::prelude::*;
    let (vertex_count, at) = (corners.vertex_count, corners.at);
    whole_triangles(bytes.len() / 4, at)?;
    let index = |c: &[u8]| u32_at(c, 0);
    let in_range = |b: &[u8]| {
        b.chunks_exact(4)
            .all(|c| (index(c) as usize) < vertex_count)
    };
    if !bytes.par_chunks(4 * BLOCK).all(in_range) {
        let bad = bytes
            .chunks_exact(4)
            .map(index)
            .find(|&i| i as usize >= vertex_count);
        return Err(corners.out_of_range(bad.unwrap_or_default()));
    }
    // Every index is below vertex_count, so the last vertex bounds them all.
    let base = u32::try_from(corners.base + vertex_count.saturating_sub(1))
        .map(|_| corners.base as u32)
        .map_err(|_| at.error("too many vertices"))?;
    triangles.par_extend(
        bytes
            .par_chunks_exact(12)
            .map(|c| [0, 4, 8].map(|k| base + u32_at(c, k))),
    );
    Ok(())
}

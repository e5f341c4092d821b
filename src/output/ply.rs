//! `scene_map.ply`: the scene's illuminance map as a binary little-endian PLY mesh that
//! MeshLab, ParaView and Blender display as it is.
//!
//! Vertices: `x y z` (float: world metres, f64 rounded to f32), `illuminance` (float,
//! lx: the area-weighted mean of the adjacent faces' total illuminance) and
//! `red green blue` (uchar: viridis over 0 … the 99th percentile of the vertex
//! illuminance, brighter vertices clipped to the top colour; the scale is repeated in a
//! `comment` line). Faces: `vertex_indices` (list uchar int), `illuminance` (total, lx),
//! `indirect` (lx) and `rel_error` (σ/E from the triangle's hits, its neighbours' and the
//! scene's odd/even overdispersion, `stats::triangle_rel_errors`; 1 when unknown), all
//! float (f64 rounded to f32).

use crate::raster::palette::{normalise, viridis};
use crate::raster::{quantile, Rank};
use crate::run::RunState;
use crate::scene::adjacency::{vertex_means, VertexFaces};
use crate::stats::{triangle_illuminance_lx, triangle_rel_errors, MapKind, REL_ERROR_UNKNOWN};
use std::io::Write;

/// Per-face values of the map, f64.
pub struct FaceMap {
    pub illuminance_lx: Vec<f64>,
    pub indirect_lx: Vec<f64>,
    pub rel_error: Vec<f64>,
}

/// Total and indirect illuminance and relative error of every triangle.
pub fn face_map(state: &RunState<'_>, adjacent: &VertexFaces) -> FaceMap {
    let t = &state.progress.tallies;
    let g = &state.scene.geometry;
    let rel_errors = triangle_rel_errors(t, &g.triangles, adjacent, |k| g.area_m2(k));
    let mut m = FaceMap {
        illuminance_lx: Vec::with_capacity(g.triangle_count()),
        indirect_lx: Vec::with_capacity(g.triangle_count()),
        rel_error: Vec::with_capacity(g.triangle_count()),
    };
    for (k, a) in g.areas_m2().enumerate() {
        let e = |kind, parity| {
            triangle_illuminance_lx(t, kind, k, a, state.setup.total_flux_lm, parity)
        };
        let total = e(MapKind::Total, None);
        let rel = if rel_errors[k].is_nan() {
            REL_ERROR_UNKNOWN
        } else {
            rel_errors[k]
        };
        m.illuminance_lx.push(total);
        m.indirect_lx.push(e(MapKind::Indirect, None));
        m.rel_error.push(rel);
    }
    m
}

/// The PLY file of a run's scene map, in memory (tests; runs stream it with
/// [`write_scene_map_ply`]).
pub fn scene_map_ply(state: &RunState<'_>) -> Vec<u8> {
    let mut out = Vec::new();
    write_scene_map_ply(state, &mut out).expect("writing to memory cannot fail");
    out
}

/// Streams the PLY file of a run's scene map to `out` (wrap files in a `BufWriter`):
/// only the per-face and per-vertex values are held, never the file's bytes.
pub fn write_scene_map_ply(state: &RunState<'_>, out: &mut impl Write) -> std::io::Result<()> {
    let g = &state.scene.geometry;
    let adjacent = VertexFaces::by_position(&g.triangles, &g.vertices);
    let faces = face_map(state, &adjacent);
    let vertex_lx = vertex_means(
        &g.triangles,
        g.vertices.len(),
        |j| g.area_m2(j),
        |j| faces.illuminance_lx[j],
    );
    let scale = quantile(&vertex_lx, 0.99, Rank::Nearest, f64::is_finite);

    let header = format!(
        "ply\nformat binary_little_endian 1.0\n\
         comment luxtally scene map of {}: illuminance in lx\n\
         comment vertex colours: viridis over 0 .. {} lx (99th percentile of vertex illuminance)\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float illuminance\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {}\nproperty list uchar int vertex_indices\nproperty float illuminance\n\
         property float indirect\nproperty float rel_error\nend_header\n",
        state.scene.name.replace('\n', " "),
        scale,
        g.vertices.len(),
        g.triangle_count()
    );
    out.write_all(header.as_bytes())?;
    for (v, &e) in g.vertices.iter().zip(&vertex_lx) {
        let world = g.origin + v.as_dvec3();
        let mut record = [0u8; 19];
        for (k, x) in [world.x, world.y, world.z, e].into_iter().enumerate() {
            record[4 * k..4 * k + 4].copy_from_slice(&(x as f32).to_le_bytes());
        }
        record[16..].copy_from_slice(&viridis(normalise(e, scale)));
        out.write_all(&record)?;
    }
    for (k, tri) in g.triangles.iter().enumerate() {
        let mut record = [0u8; 25];
        record[0] = 3;
        for (j, &v) in tri.iter().enumerate() {
            record[1 + 4 * j..5 + 4 * j].copy_from_slice(&(v as i32).to_le_bytes());
        }
        let values = [
            faces.illuminance_lx[k],
            faces.indirect_lx[k],
            faces.rel_error[k],
        ];
        for (j, x) in values.into_iter().enumerate() {
            record[13 + 4 * j..17 + 4 * j].copy_from_slice(&(x as f32).to_le_bytes());
        }
        out.write_all(&record)?;
    }
    Ok(())
}

//! The indirect light at any point of a triangle face: smooth interpolation across
//! triangles of the photon pass's per-face map (`output::IndirectMap`).

use crate::output::IndirectMap;
use crate::scene::adjacency::VertexFaces;
use crate::scene::Scene;

/// Triangles whose normals differ by more than this are not smoothed together: the
/// faces of a box stay apart, a tessellated sphere is smooth.
const CREASE_COS: f32 = 0.866; // 30°

/// The indirect illuminance at any point of a triangle face: barycentric interpolation
/// of corner values, or the triangle's own value when interpolation is off.
pub struct IndirectField {
    /// Per triangle, per corner, [front, back] lx.
    corner_lx: Vec<[[f64; 2]; 3]>,
}

impl IndirectField {
    /// Corner values are the area-weighted mean of the face values of the triangles
    /// sharing the vertex and lying within the crease angle (same side of each, as the
    /// normals agree); without `interpolate` every corner holds the triangle's value.
    pub fn new(scene: &Scene, map: &IndirectMap, interpolate: bool) -> IndirectField {
        let g = &scene.geometry;
        if !interpolate {
            return IndirectField {
                corner_lx: map.face_lx.iter().map(|f| [*f; 3]).collect(),
            };
        }
        let adjacent = VertexFaces::new(&g.triangles, g.vertices.len());
        let corner_lx = g
            .triangles
            .iter()
            .enumerate()
            .map(|(k, t)| {
                t.map(|i| {
                    let normal = g.normal(k);
                    let same_side = |j: usize| !(g.normal(j).dot(normal) < CREASE_COS);
                    let area_m2 = |j: usize| g.area_m2(j);
                    adjacent
                        .area_weighted_mean(i as usize, area_m2, same_side, |j| map.face_lx[j])
                        .unwrap_or(map.face_lx[k])
                })
            })
            .collect();
        IndirectField { corner_lx }
    }

    /// Indirect illuminance (lx) on face `back` of triangle `k` at barycentrics (u, v)
    /// (weights of corners 1 and 2).
    #[inline]
    pub fn illuminance_lx(&self, k: usize, back: bool, u: f32, v: f32) -> f64 {
        let c = &self.corner_lx[k];
        let s = back as usize;
        let (u, v) = (u as f64, v as f64);
        (1.0 - u - v) * c[0][s] + u * c[1][s] + v * c[2][s]
    }
}

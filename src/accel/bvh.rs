//! Pure-Rust backend: obvhs's compressed wide BVH (CWBVH), traversed one ray at a time.
//!
//! obvhs only reports the closest primitive and distance; barycentrics come from our
//! own Möller–Trumbore test, normals from `Geometry::normal`.

use super::{HitBatch, RayApi, RayBatch, RayCaster};
use crate::scene::Geometry;
use glam::{Vec3, Vec3A};
use obvhs::cwbvh::{builder::build_cwbvh_from_tris, CwBvh};
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::time::Duration;

/// obvhs's node test clamps the entry distance to an absolute `t >= 1e-4`
/// (`cwbvh::node::EPSILON`), so boxes the ray leaves within 1e-4 direction lengths are
/// skipped and hits closer than that are lost (a photon leaving a surface next to a
/// small triangle). Tracing with the direction scaled by 2⁻¹⁶ moves that cut-off to
/// 1.5e-9 direction lengths; a power of two scales t, tnear and tfar exactly, and the
/// barycentrics not at all.
const DIR_SCALE: f32 = 1.0 / 65536.0;

/// A triangle prepared for the intersection test: a vertex and the two edges from it.
#[derive(Clone, Copy)]
struct PreTri {
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
}

/// Möller–Trumbore: `(t, u, v)` of a hit strictly inside `(tmin, tmax)`, else `None`.
#[inline(always)]
fn intersect(tri: &PreTri, o: Vec3A, d: Vec3A, tmin: f32, tmax: f32) -> Option<(f32, f32, f32)> {
    let p = d.cross(tri.e2);
    let det = tri.e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - tri.v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(tri.e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = tri.e2.dot(q) * inv;
    (t > tmin && t < tmax).then_some((t, u, v))
}

/// An obvhs CWBVH over one `Geometry`.
pub struct ObvhsScene {
    bvh: CwBvh,
    /// Triangles in the BVH's primitive order (`tris[k]` is `primitive_indices[k]`).
    tris: Vec<PreTri>,
    /// Unit normals per global triangle id.
    normals: Vec<Vec3>,
}

impl ObvhsScene {
    /// Builds the BVH (obvhs `medium_build`). Triangles referencing missing vertices get
    /// degenerate (never-hit) stand-ins rather than a panic.
    pub fn new(geometry: &Geometry) -> ObvhsScene {
        let vertex = |i: u32| -> Vec3A {
            geometry
                .vertices
                .get(i as usize)
                .map_or(Vec3A::ZERO, |v| Vec3A::from(*v))
        };
        let tris: Vec<Triangle> = geometry
            .triangles
            .iter()
            .map(|t| Triangle {
                v0: vertex(t[0]),
                v1: vertex(t[1]),
                v2: vertex(t[2]),
            })
            .collect();
        let bvh = if tris.is_empty() {
            CwBvh::default()
        } else {
            build_cwbvh_from_tris(
                &tris,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            )
        };
        let ordered = bvh
            .primitive_indices
            .iter()
            .map(|&id| {
                let t = tris[id as usize];
                PreTri {
                    v0: t.v0,
                    e1: t.v1 - t.v0,
                    e2: t.v2 - t.v0,
                }
            })
            .collect();
        ObvhsScene {
            bvh,
            tris: ordered,
            normals: geometry.normal.clone(),
        }
    }

    /// The obvhs ray for ray `i`, its direction shortened by `DIR_SCALE` (see there).
    #[inline(always)]
    fn ray(rays: &RayBatch, i: usize) -> Ray {
        let o = Vec3A::new(rays.ox[i], rays.oy[i], rays.oz[i]);
        let d = Vec3A::new(rays.dx[i], rays.dy[i], rays.dz[i]) * DIR_SCALE;
        // Not `Ray::new`: its `safe_inverse` clamps components below f32::EPSILON,
        // which the scaled direction has plenty of. Ours clamps far lower, and keeps the
        // slab products in the node test finite.
        let inv = |x: f32| {
            if x.abs() <= 1e-20 {
                if x.is_sign_negative() {
                    -1e20
                } else {
                    1e20
                }
            } else {
                1.0 / x
            }
        };
        Ray {
            origin: o,
            direction: d,
            inv_direction: Vec3A::new(inv(d.x), inv(d.y), inv(d.z)),
            tmin: rays.tnear[i] / DIR_SCALE,
            tmax: rays.tfar[i] / DIR_SCALE,
        }
    }
}

impl RayCaster for ObvhsScene {
    fn name(&self) -> &'static str {
        "obvhs"
    }

    fn intersect_with(&self, _api: RayApi, rays: &RayBatch, hits: &mut HitBatch) {
        hits.reset(rays.len());
        if self.tris.is_empty() {
            return;
        }
        for i in 0..rays.len() {
            let ray = Self::ray(rays, i);
            let mut hit = RayHit::none();
            let found = self.bvh.ray_traverse(ray, &mut hit, |r, k| {
                intersect(&self.tris[k], r.origin, r.direction, r.tmin, r.tmax)
                    .map_or(f32::INFINITY, |(t, _, _)| t)
            });
            if !found {
                continue;
            }
            let k = hit.primitive_id as usize;
            // Re-run the winning test for its barycentrics (tmax just above the hit).
            let (t, u, v) = intersect(
                &self.tris[k],
                ray.origin,
                ray.direction,
                ray.tmin,
                f32::INFINITY,
            )
            .unwrap_or((hit.t, 0.0, 0.0));
            let id = self.bvh.primitive_indices[k];
            let n = self.normals.get(id as usize).copied().unwrap_or(Vec3::ZERO);
            hits.t[i] = t * DIR_SCALE;
            hits.tri[i] = id;
            hits.u[i] = u;
            hits.v[i] = v;
            hits.ngx[i] = n.x;
            hits.ngy[i] = n.y;
            hits.ngz[i] = n.z;
        }
    }

    fn occluded_with(&self, _api: RayApi, rays: &RayBatch, occluded: &mut Vec<bool>) {
        occluded.clear();
        occluded.resize(rays.len(), false);
        if self.tris.is_empty() {
            return;
        }
        for (i, out) in occluded.iter_mut().enumerate() {
            let ray = Self::ray(rays, i);
            *out = !self.bvh.ray_traverse_miss(ray, |r, k| {
                intersect(&self.tris[k], r.origin, r.direction, r.tmin, r.tmax)
                    .map_or(f32::INFINITY, |(t, _, _)| t)
            });
        }
    }

    fn default_intersect_api(&self) -> RayApi {
        RayApi::Single
    }

    fn default_occluded_api(&self) -> RayApi {
        RayApi::Single
    }
}

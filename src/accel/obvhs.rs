//! Pure-Rust backend: obvhs's compressed wide BVH (CWBVH), traversed one ray at a time.
//!
//! obvhs only reports the closest primitive and distance; barycentrics come from our
//! own Möller–Trumbore test, normals from `Geometry::normal`.
//!
//! Unmapped objects are two-level, as in the Embree backend: one BVH per prototype and a
//! top-level BVH over the instances' bounds; a ray reaching an instance's box is
//! transformed into the prototype's frame (the same t, as the direction is transformed
//! without normalising) and traverses the prototype's BVH.

use super::{HitBatch, RayApi, RayBatch, RayCaster, INSTANCE_HIT};
use crate::scene::{Geometry, Shared};
use glam::{Affine3A, DAffine3, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::{
    builder::{build_cwbvh, build_cwbvh_from_tris},
    CwBvh,
};
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

/// A CWBVH over one triangle mesh, with its triangles in the BVH's primitive order.
#[derive(Default)]
struct Blas {
    bvh: CwBvh,
    /// Triangles in the BVH's primitive order (`tris[k]` is `primitive_indices[k]`).
    tris: Vec<PreTri>,
}

impl Blas {
    /// Builds the BVH (obvhs `medium_build`). Triangles referencing missing vertices get
    /// degenerate (never-hit) stand-ins rather than a panic.
    fn new(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Blas {
        let vertex = |i: u32| -> Vec3A {
            vertices
                .get(i as usize)
                .map_or(Vec3A::ZERO, |v| Vec3A::from(*v))
        };
        let tris: Vec<Triangle> = triangles
            .iter()
            .map(|t| Triangle {
                v0: vertex(t[0]),
                v1: vertex(t[1]),
                v2: vertex(t[2]),
            })
            .collect();
        if tris.is_empty() {
            return Blas::default();
        }
        let bvh = build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
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
        Blas { bvh, tris: ordered }
    }

    /// Closest hit (BVH slot, t) strictly inside the ray's (tmin, tmax).
    #[inline]
    fn closest(&self, ray: Ray) -> Option<(usize, f32)> {
        if self.tris.is_empty() {
            return None;
        }
        let mut hit = RayHit::none();
        self.bvh
            .ray_traverse(ray, &mut hit, |r, k| {
                intersect(&self.tris[k], r.origin, r.direction, r.tmin, r.tmax)
                    .map_or(f32::INFINITY, |(t, _, _)| t)
            })
            .then_some((hit.primitive_id as usize, hit.t))
    }

    /// Some hit strictly inside (tmin, tmax), if any.
    #[inline]
    fn any(&self, ray: Ray) -> Option<f32> {
        if self.tris.is_empty() {
            return None;
        }
        let mut found = None;
        self.bvh.ray_traverse_miss(ray, |r, k| {
            let t = intersect(&self.tris[k], r.origin, r.direction, r.tmin, r.tmax)
                .map_or(f32::INFINITY, |(t, _, _)| t);
            if t < r.tmax {
                found = Some(t);
            }
            t
        });
        found
    }

    /// Barycentrics of the hit in slot `k`: the winning test re-run (tmax open above).
    #[inline]
    fn barycentrics(&self, k: usize, ray: &Ray, t_hit: f32) -> (f32, f32, f32) {
        intersect(
            &self.tris[k],
            ray.origin,
            ray.direction,
            ray.tmin,
            f32::INFINITY,
        )
        .unwrap_or((t_hit, 0.0, 0.0))
    }
}

/// One instance as the obvhs backend traces it.
struct InstanceData {
    /// Local frame → prototype frame.
    to_prototype: Affine3A,
    /// `Instance::normal_matrix`.
    normal: [Vec3; 3],
    prototype: u32,
}

/// Prototypes, instances and the top-level BVH over the instances' bounds.
#[derive(Default)]
struct TwoLevel {
    prototypes: Vec<Blas>,
    /// Unit normals per prototype triangle, per prototype.
    prototype_normals: Vec<Vec<Vec3>>,
    instances: Vec<InstanceData>,
    tlas: CwBvh,
}

/// An obvhs CWBVH over one `Geometry`.
pub struct ObvhsScene {
    flat: Blas,
    /// The geometry's vertices and triangles (shared, not copied): hits' normals come
    /// from them, as `Geometry::normal`'s do.
    vertices: Shared<Vec3>,
    triangles: Shared<[u32; 3]>,
    two_level: TwoLevel,
}

impl ObvhsScene {
    /// Builds the BVHs (obvhs `medium_build`).
    pub fn new(geometry: &Geometry) -> ObvhsScene {
        let scene = ObvhsScene {
            flat: Blas::new(&geometry.vertices, &geometry.triangles),
            vertices: geometry.vertices.clone(),
            triangles: geometry.triangles.clone(),
            two_level: TwoLevel::new(geometry),
        };
        // What every ray reads, in huge pages (collapsed in the background) as Embree's
        // BVH is: in 4 KiB pages a large BVH's rays lose to TLB misses.
        if geometry.triangles.len() >= super::huge_pages::DEFER_FROM_TRIANGLES {
            super::huge_pages::advise(&[
                address_range(&scene.flat.bvh.nodes),
                address_range(&scene.flat.tris),
                address_range(&scene.vertices),
                address_range(&scene.triangles),
            ]);
        }
        scene
    }

    /// The obvhs ray for ray `i`, its direction shortened by `DIR_SCALE` (see there).
    #[inline(always)]
    fn ray(rays: &RayBatch, i: usize) -> Ray {
        let o = Vec3A::new(rays.ox[i], rays.oy[i], rays.oz[i]);
        let d = Vec3A::new(rays.dx[i], rays.dy[i], rays.dz[i]) * DIR_SCALE;
        make_ray(o, d, rays.tnear[i] / DIR_SCALE, rays.tfar[i] / DIR_SCALE)
    }
}

/// An obvhs ray. Not `Ray::new`: its `safe_inverse` clamps components below
/// f32::EPSILON, which the scaled direction has plenty of. Ours clamps far lower, and
/// keeps the slab products in the node test finite.
#[inline(always)]
fn make_ray(origin: Vec3A, direction: Vec3A, tmin: f32, tmax: f32) -> Ray {
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
        origin,
        direction,
        inv_direction: Vec3A::new(inv(direction.x), inv(direction.y), inv(direction.z)),
        tmin,
        tmax,
    }
}

impl TwoLevel {
    fn new(geometry: &Geometry) -> TwoLevel {
        let inst = &geometry.instanced;
        if inst.is_empty() {
            return TwoLevel::default();
        }
        let prototypes = inst
            .prototypes
            .iter()
            .map(|p| Blas::new(&p.vertices, &p.triangles))
            .collect();
        let prototype_normals = inst.prototypes.iter().map(|p| p.normal.clone()).collect();
        let mut boxes = Vec::with_capacity(inst.instances.len());
        let instances = inst
            .instances
            .iter()
            .map(|i| {
                let (lo, hi) = inst.prototypes[i.prototype as usize].bounds;
                let mut min = Vec3A::splat(f32::INFINITY);
                let mut max = Vec3A::splat(f32::NEG_INFINITY);
                for k in 0..8 {
                    let c = Vec3::new(
                        if k & 1 == 0 { lo.x } else { hi.x },
                        if k & 2 == 0 { lo.y } else { hi.y },
                        if k & 4 == 0 { lo.z } else { hi.z },
                    );
                    let p = Vec3A::from(i.point(c));
                    min = min.min(p);
                    max = max.max(p);
                }
                // Padded: the box must hold every f32-transformed vertex.
                let pad = Vec3A::splat(1e-5 * min.abs().max(max.abs()).max_element() + 1e-30);
                boxes.push(Aabb::new(min - pad, max + pad));
                let to_local = DAffine3::from_cols_array(&i.to_local.map(f64::from));
                let inverse = to_local.inverse().to_cols_array().map(|x| x as f32);
                InstanceData {
                    to_prototype: Affine3A::from_cols_array(&inverse),
                    normal: i.normal_matrix(),
                    prototype: i.prototype,
                }
            })
            .collect();
        let tlas = build_cwbvh(
            &boxes,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        TwoLevel {
            prototypes,
            prototype_normals,
            instances,
            tlas,
        }
    }

    /// The ray in instance `id`'s prototype frame (same t).
    #[inline(always)]
    fn ray_in(&self, id: usize, r: &Ray) -> Ray {
        let d = &self.instances[id];
        make_ray(
            d.to_prototype.transform_point3a(r.origin),
            d.to_prototype.transform_vector3a(r.direction),
            r.tmin,
            r.tmax,
        )
    }

    /// Closest instance hit before `ray.tmax`: (instance, prototype triangle, t, u, v,
    /// unit normal in the local frame).
    fn closest(&self, ray: Ray) -> Option<(u32, u32, f32, f32, f32, Vec3)> {
        if self.instances.is_empty() {
            return None;
        }
        let mut best: Option<(usize, usize, Ray)> = None;
        let mut hit = RayHit::none();
        self.tlas.ray_traverse(ray, &mut hit, |r, slot| {
            let id = self.tlas.primitive_indices[slot] as usize;
            let local = self.ray_in(id, r);
            let blas = &self.prototypes[self.instances[id].prototype as usize];
            match blas.closest(local) {
                Some((k, t)) => {
                    best = Some((id, k, local));
                    t
                }
                None => f32::INFINITY,
            }
        });
        let (id, k, local) = best?;
        let d = &self.instances[id];
        let blas = &self.prototypes[d.prototype as usize];
        let (t, u, v) = blas.barycentrics(k, &local, hit.t);
        let prim = blas.bvh.primitive_indices[k];
        let n = self.prototype_normals[d.prototype as usize]
            .get(prim as usize)
            .copied()
            .unwrap_or(Vec3::ZERO);
        let [c0, c1, c2] = d.normal;
        let normal = (c0 * n.x + c1 * n.y + c2 * n.z).normalize_or_zero();
        Some((id as u32, prim, t, u, v, normal))
    }

    /// Whether any instance blocks the ray inside (tmin, tmax).
    fn occluded(&self, ray: Ray) -> bool {
        if self.instances.is_empty() {
            return false;
        }
        !self.tlas.ray_traverse_miss(ray, |r, slot| {
            let id = self.tlas.primitive_indices[slot] as usize;
            let local = self.ray_in(id, r);
            self.prototypes[self.instances[id].prototype as usize]
                .any(local)
                .unwrap_or(f32::INFINITY)
        })
    }
}

impl RayCaster for ObvhsScene {
    fn name(&self) -> &'static str {
        "obvhs"
    }

    fn intersect_with(&self, _api: RayApi, rays: &RayBatch, hits: &mut HitBatch) {
        hits.reset(rays.len());
        if self.flat.tris.is_empty() && self.two_level.instances.is_empty() {
            return;
        }
        for i in 0..rays.len() {
            let mut ray = Self::ray(rays, i);
            if let Some((k, t_hit)) = self.flat.closest(ray) {
                let (t, u, v) = self.flat.barycentrics(k, &ray, t_hit);
                let id = self.flat.bvh.primitive_indices[k];
                let [a, b, c] = self.triangles[id as usize].map(|k| self.vertices[k as usize]);
                let n = crate::scene::triangle_normal(a, b, c);
                hits.tri[i] = id;
                hits.set_surface(i, t * DIR_SCALE, u, v, n.to_array());
                ray.tmax = t_hit;
            }
            if let Some((inst, prim, t, u, v, n)) = self.two_level.closest(ray) {
                hits.tri[i] = INSTANCE_HIT;
                hits.inst[i] = inst;
                hits.prim[i] = prim;
                hits.set_surface(i, t * DIR_SCALE, u, v, n.to_array());
            }
        }
    }

    fn occluded_with(&self, _api: RayApi, rays: &RayBatch, occluded: &mut Vec<bool>) {
        occluded.clear();
        occluded.resize(rays.len(), false);
        if self.flat.tris.is_empty() && self.two_level.instances.is_empty() {
            return;
        }
        for (i, out) in occluded.iter_mut().enumerate() {
            let ray = Self::ray(rays, i);
            *out = self.flat.any(ray).is_some() || self.two_level.occluded(ray);
        }
    }

    fn default_intersect_api(&self) -> RayApi {
        RayApi::Single
    }

    fn default_occluded_api(&self) -> RayApi {
        RayApi::Single
    }
}

/// Where a slice lies in memory: (start address, bytes).
fn address_range<T>(items: &[T]) -> (usize, usize) {
    (items.as_ptr() as usize, std::mem::size_of_val(items))
}

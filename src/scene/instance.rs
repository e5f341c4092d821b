//! Instancing, the two-level part of the scene: prototypes (a mesh in its own frame,
//! shared) and their placed copies, as loaded (f64, `PrototypeMesh`, `Placement`) and as
//! traced (f32, `Prototype`, `Instance`, `Instanced`).

use super::Bounds;
use glam::{DAffine3, DVec3, Vec3};

/// A mesh shared by instances, in its own frame (centred on its bounds, so f32 keeps
/// full precision whatever the instance transforms are).
#[derive(Clone, Debug, Default)]
pub struct Prototype {
    pub vertices: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Material index (into `Scene::materials`) per triangle.
    pub material: Vec<u32>,
    /// Unit normal per triangle in the prototype frame, (v1 − v0) × (v2 − v0).
    pub normal: Vec<Vec3>,
    /// Bounds of the vertices (min, max), prototype frame.
    pub bounds: (Vec3, Vec3),
}

/// One placed copy of a prototype.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    pub prototype: u32,
    /// Index of the `[[objects]]` entry it came from.
    pub object: u32,
    /// Prototype frame → scene local frame, 3 × 4 column-major (columns: images of x, y,
    /// z, then the translation): Embree's `RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR`. Composed in
    /// f64 (file, object, instance transforms and the re-centring) before rounding.
    pub to_local: [f32; 12],
    /// [`Instance::normal_matrix`], computed once: every instance hit needs it.
    normal_cols: [Vec3; 3],
}

impl Instance {
    pub fn new(prototype: u32, object: u32, to_local: [f32; 12]) -> Instance {
        let mut instance = Instance {
            prototype,
            object,
            to_local,
            normal_cols: [Vec3::ZERO; 3],
        };
        instance.normal_cols = instance.cofactor_columns();
        instance
    }

    /// Column `k` of the linear part.
    #[inline(always)]
    pub fn column(&self, k: usize) -> Vec3 {
        Vec3::new(
            self.to_local[3 * k],
            self.to_local[3 * k + 1],
            self.to_local[3 * k + 2],
        )
    }

    /// A prototype-frame point in the local frame.
    #[inline(always)]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.column(0) * p.x + self.column(1) * p.y + self.column(2) * p.z + self.column(3)
    }

    /// The matrix taking prototype-frame normals to the local frame (up to length),
    /// columns first: sign(det A)·cof(A) = |det A|·A⁻ᵀ. The cofactor cof(A) = det(A)·A⁻ᵀ
    /// (columns a1 × a2, a2 × a0, a0 × a1) maps e1 × e2 to (A e1) × (A e2); under a
    /// mirroring transform the placed triangle's winding is taken as reversed, as glTF
    /// and the flattened path do, so a normal that pointed outwards still does.
    #[inline(always)]
    pub fn normal_matrix(&self) -> [Vec3; 3] {
        self.normal_cols
    }

    fn cofactor_columns(&self) -> [Vec3; 3] {
        let (a0, a1, a2) = (self.column(0), self.column(1), self.column(2));
        let sign = if a0.dot(a1.cross(a2)) < 0.0 {
            -1.0
        } else {
            1.0
        };
        [
            a1.cross(a2) * sign,
            a2.cross(a0) * sign,
            a0.cross(a1) * sign,
        ]
    }

    /// A prototype-frame unit normal in the local frame, unit (see `normal_matrix`).
    #[inline(always)]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        let [c0, c1, c2] = self.normal_matrix();
        (c0 * n.x + c1 * n.y + c2 * n.z).normalize_or_zero()
    }
}

/// The two-level part of the scene: prototypes and their instances.
#[derive(Clone, Debug, Default)]
pub struct Instanced {
    pub prototypes: Vec<Prototype>,
    pub instances: Vec<Instance>,
    /// Bounds (min, max) of every instance, local frame; meaningless without instances.
    pub bounds: (Vec3, Vec3),
}

impl Instanced {
    pub fn is_empty(&self) -> bool {
        self.instances.is_empty()
    }

    /// Triangles the instances would have if flattened.
    pub fn flattened_triangle_count(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.prototypes[i.prototype as usize].triangles.len() as u64)
            .sum()
    }

    /// Triangles stored (once per prototype).
    pub fn stored_triangle_count(&self) -> usize {
        self.prototypes.iter().map(|p| p.triangles.len()).sum()
    }

    /// Hit point (local frame), unit normal (local frame) and material of prototype
    /// triangle `prim` of instance `inst` at barycentrics `u`, `v`.
    #[inline]
    pub fn surface(&self, inst: u32, prim: u32, u: f32, v: f32) -> (Vec3, Vec3, u32) {
        let i = &self.instances[inst as usize];
        let proto = &self.prototypes[i.prototype as usize];
        let [a, b, c] = proto.triangles[prim as usize].map(|k| proto.vertices[k as usize]);
        let p = i.point(a + (b - a) * u + (c - a) * v);
        (
            p,
            i.normal(proto.normal[prim as usize]),
            proto.material[prim as usize],
        )
    }
}

impl Instanced {
    /// The instances of `placed` (placement, prototype frame → world) over `prototypes`,
    /// their transforms made relative to the local frame at `origin` in f64 before
    /// rounding, and the bounds of all of them from `world_bounds` (theirs in world
    /// space). Shifting the box equals shifting every corner: x ↦ x − origin is monotone
    /// in floating point too, so min and max are kept.
    pub(super) fn place(
        prototypes: Vec<Prototype>,
        placed: &[(&Placement, DAffine3)],
        origin: DVec3,
        world_bounds: &Bounds,
    ) -> Instanced {
        let mut instanced = Instanced {
            prototypes,
            instances: Vec::with_capacity(placed.len()),
            bounds: (Vec3::ZERO, Vec3::ZERO),
        };
        for (pl, full) in placed {
            let m = full.matrix3;
            let t = full.translation - origin;
            let cols = [m.x_axis, m.y_axis, m.z_axis, t];
            let mut to_local = [0f32; 12];
            for (k, c) in cols.iter().enumerate() {
                to_local[3 * k..3 * k + 3].copy_from_slice(&c.as_vec3().to_array());
            }
            instanced
                .instances
                .push(Instance::new(pl.prototype, pl.object, to_local));
        }
        if let Some((lo, hi)) = world_bounds.0 {
            let (ilo, ihi) = (lo - origin, hi - origin);
            // Rounded outwards so that f32 bounds still hold every instance.
            let pad = |x: DVec3| x.abs().max_element() * 1e-6 + f32::MIN_POSITIVE as f64;
            instanced.bounds = (
                (ilo - DVec3::splat(pad(ilo))).as_vec3(),
                (ihi + DVec3::splat(pad(ihi))).as_vec3(),
            );
        }
        instanced
    }
}

/// A prototype as loaded: f64 vertices in its own (file or object) frame.
#[derive(Clone, Debug, Default)]
pub struct PrototypeMesh {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Material index per triangle.
    pub material: Vec<u32>,
}

/// Where one copy of a prototype goes: world = `world` · prototype point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub prototype: u32,
    pub object: u32,
    pub world: DAffine3,
}

impl Prototype {
    /// Centres `mesh` on its bounds (returning the centre, in the mesh's frame) and
    /// drops triangles of zero area.
    pub(super) fn centred(mesh: &PrototypeMesh) -> (Prototype, DVec3) {
        let centre = match mesh.vertices.split_first() {
            None => DVec3::ZERO,
            Some((first, rest)) => {
                let (lo, hi) = rest
                    .iter()
                    .fold((*first, *first), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
                (lo + hi) * 0.5
            }
        };
        let vertices: Vec<Vec3> = mesh
            .vertices
            .iter()
            .map(|v| (*v - centre).as_vec3())
            .collect();
        let mut p = Prototype::default();
        for (k, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| mesh.vertices[i as usize]);
            let cross = (b - a).cross(c - a);
            let len = cross.length();
            if len.is_nan() || len <= 0.0 {
                continue;
            }
            p.triangles.push(*tri);
            p.material.push(mesh.material[k]);
            p.normal.push((cross / len).as_vec3());
        }
        let (lo, hi) = vertices.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        p.bounds = if vertices.is_empty() {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (lo, hi)
        };
        p.vertices = vertices;
        (p, centre)
    }
}

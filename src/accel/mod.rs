//! Ray casting: the one interface the tracer uses, with two backends behind it —
//! Debian's Embree over FFI (`embree`) and pure-Rust obvhs (`obvhs`, feature `obvhs`).
//!
//! Rays and hits travel as structures of arrays (SoA) so batches map straight onto
//! Embree's packets and streams. Coordinates are the scene's re-centred local frame (f32).

pub mod embree;
pub mod huge_pages;
#[cfg(feature = "obvhs")]
pub mod obvhs;

use crate::scene::Geometry;
use crate::{Error, Result};
use glam::Vec3;

/// Triangle id of a ray that hit nothing.
pub const NO_HIT: u32 = u32::MAX;

/// Triangle id of a hit on an instance (an unmapped object): `inst` and `prim` say which
/// instance and which triangle of its prototype.
pub const INSTANCE_HIT: u32 = u32::MAX - 1;

/// A batch of rays, structure of arrays. All vectors have the same length.
#[derive(Clone, Debug, Default)]
pub struct RayBatch {
    pub ox: Vec<f32>,
    pub oy: Vec<f32>,
    pub oz: Vec<f32>,
    pub dx: Vec<f32>,
    pub dy: Vec<f32>,
    pub dz: Vec<f32>,
    pub tnear: Vec<f32>,
    pub tfar: Vec<f32>,
}

impl RayBatch {
    pub fn with_capacity(n: usize) -> Self {
        let v = || Vec::with_capacity(n);
        RayBatch {
            ox: v(),
            oy: v(),
            oz: v(),
            dx: v(),
            dy: v(),
            dz: v(),
            tnear: v(),
            tfar: v(),
        }
    }

    pub fn len(&self) -> usize {
        self.ox.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ox.is_empty()
    }

    pub fn clear(&mut self) {
        self.truncate(0);
    }

    /// Keeps the first `n` rays.
    pub fn truncate(&mut self, n: usize) {
        for v in self.arrays() {
            v.truncate(n);
        }
    }

    /// `n` closest-hit rays from t = 0 to ∞, origins and directions zero (to be set).
    pub fn reset_closest_hit(&mut self, n: usize) {
        self.truncate(0);
        for v in self.arrays() {
            v.resize(n, 0.0);
        }
        self.tfar.fill(f32::INFINITY);
    }

    fn arrays(&mut self) -> [&mut Vec<f32>; 8] {
        [
            &mut self.ox,
            &mut self.oy,
            &mut self.oz,
            &mut self.dx,
            &mut self.dy,
            &mut self.dz,
            &mut self.tnear,
            &mut self.tfar,
        ]
    }

    /// Appends one ray; `dir` need not be normalised (distances are then in its units).
    #[inline]
    pub fn push(&mut self, origin: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32) {
        self.ox.push(origin[0]);
        self.oy.push(origin[1]);
        self.oz.push(origin[2]);
        self.dx.push(dir[0]);
        self.dy.push(dir[1]);
        self.dz.push(dir[2]);
        self.tnear.push(tnear);
        self.tfar.push(tfar);
    }
}

/// Closest hits of a batch, structure of arrays, one entry per ray.
#[derive(Clone, Debug, Default)]
pub struct HitBatch {
    /// Distance along the ray (in units of its direction's length); `f32::INFINITY` on a miss.
    pub t: Vec<f32>,
    /// Global triangle id (index into `Geometry::triangles`), [`NO_HIT`] or
    /// [`INSTANCE_HIT`].
    pub tri: Vec<u32>,
    /// Instance index (into `Instanced::instances`) where `tri` is [`INSTANCE_HIT`];
    /// unspecified elsewhere.
    pub inst: Vec<u32>,
    /// Triangle of the instance's prototype where `tri` is [`INSTANCE_HIT`].
    pub prim: Vec<u32>,
    /// Barycentric coordinates of the hit (weights of vertices 1 and 2).
    pub u: Vec<f32>,
    pub v: Vec<f32>,
    /// Unit geometric normal of the hit triangle in the local frame, (v1 − v0) × (v2 − v0)
    /// orientation, from the f32 vertices as traced (Embree's `Ng`; obvhs computes
    /// `Geometry::normal`): the normal [`HitBatch::surface`] gives mapped triangles.
    /// On instances that of the prototype carried by `Instance::normal` (a mirrored
    /// copy keeps its outside, as a flattened mirrored copy does).
    pub ngx: Vec<f32>,
    pub ngy: Vec<f32>,
    pub ngz: Vec<f32>,
}

impl HitBatch {
    /// Records where ray `i` hit: distance `t`, barycentrics `u`, `v`, unit normal `n`
    /// (which triangle is the caller's: `tri`, `inst`, `prim`).
    #[inline(always)]
    pub fn set_surface(&mut self, i: usize, t: f32, u: f32, v: f32, n: [f32; 3]) {
        self.t[i] = t;
        self.u[i] = u;
        self.v[i] = v;
        self.ngx[i] = n[0];
        self.ngy[i] = n[1];
        self.ngz[i] = n[2];
    }

    /// Resizes every array to `n` entries, marked as misses.
    pub fn reset(&mut self, n: usize) {
        self.t.clear();
        self.t.resize(n, f32::INFINITY);
        self.tri.clear();
        self.tri.resize(n, NO_HIT);
        // Read only where `tri` says so: sized, not cleared.
        self.inst.resize(n, 0);
        self.prim.resize(n, 0);
        for v in [
            &mut self.u,
            &mut self.v,
            &mut self.ngx,
            &mut self.ngy,
            &mut self.ngz,
        ] {
            v.clear();
            v.resize(n, 0.0);
        }
    }

    pub fn len(&self) -> usize {
        self.t.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// What the tracer needs of hit `k`: point, normal, material and, for mapped
    /// triangles, the triangle id; `None` on a miss.
    #[inline(always)]
    pub fn surface(&self, k: usize, g: &Geometry) -> Option<Surface> {
        let tri = self.tri[k];
        let (u, v) = (self.u[k], self.v[k]);
        if tri == NO_HIT {
            return None;
        }
        if tri == INSTANCE_HIT {
            let (point, normal, material) = g.instanced.surface(self.inst[k], self.prim[k], u, v);
            return Some(Surface {
                point,
                normal,
                material,
                mapped: None,
            });
        }
        let t = tri as usize;
        // Hit point from barycentrics: its error scales with the vertices, which the
        // ray-origin offset is sized for. The normal is the backend's (normals are not
        // stored per triangle: see `Geometry`).
        let [a, b, c] = g.triangles[t].map(|i| g.vertices[i as usize]);
        let normal = Vec3::new(self.ngx[k], self.ngy[k], self.ngz[k]);
        Some(Surface::mapped(
            tri,
            [a, b - a, c - a],
            g.material.get(t),
            (u, v),
            normal,
        ))
    }
}

/// A surface point hit by a ray, local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    pub point: Vec3,
    /// Unit geometric normal, (v1 − v0) × (v2 − v0) orientation of the placed triangle.
    pub normal: Vec3,
    /// Index into `Scene::materials`.
    pub material: u32,
    /// The global triangle id if the triangle holds a map.
    pub mapped: Option<u32>,
}

impl Surface {
    /// Mapped triangle `tri` hit at barycentrics (u, v), from its first vertex and its
    /// two edges from it (`[a, b − a, c − a]`): the one formula for the hit point, whether
    /// the vertices come from the geometry or from the tracer's per-triangle table.
    #[inline(always)]
    pub fn mapped(
        tri: u32,
        [a, e1, e2]: [Vec3; 3],
        material: u32,
        (u, v): (f32, f32),
        normal: Vec3,
    ) -> Surface {
        Surface {
            point: a + e1 * u + e2 * v,
            normal,
            material,
            mapped: Some(tri),
        }
    }
}

/// How a batch is handed to the backend. Embree implements all; obvhs traces one ray
/// at a time whatever is asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RayApi {
    /// `rtcIntersect1` / `rtcOccluded1`, one call per ray.
    Single,
    /// `rtcIntersect8` / `rtcOccluded8`.
    Packet8,
    /// `rtcIntersect16` / `rtcOccluded16`.
    Packet16,
    /// `rtcIntersect1M` / `rtcOccluded1M` with the incoherent flag.
    Stream,
}

impl RayApi {
    pub const ALL: [RayApi; 4] = [
        RayApi::Single,
        RayApi::Packet8,
        RayApi::Packet16,
        RayApi::Stream,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RayApi::Single => "single",
            RayApi::Packet8 => "packet8",
            RayApi::Packet16 => "packet16",
            RayApi::Stream => "stream",
        }
    }
}

/// A ray-casting backend built over a scene's triangles.
pub trait RayCaster: Send + Sync {
    /// Backend name as on the command line (`embree`, `obvhs`).
    fn name(&self) -> &'static str;

    /// Closest hits of `rays` into `hits` (resized to the batch), through the
    /// backend's fastest measured path for closest-hit rays.
    fn intersect(&self, rays: &RayBatch, hits: &mut HitBatch) {
        self.intersect_with(self.default_intersect_api(), rays, hits)
    }

    /// Occlusion of `rays` between `tnear` and `tfar` into `occluded` (resized), through
    /// the backend's fastest measured path for shadow rays.
    fn occluded(&self, rays: &RayBatch, occluded: &mut Vec<bool>) {
        self.occluded_with(self.default_occluded_api(), rays, occluded)
    }

    /// Closest hits through a chosen API.
    fn intersect_with(&self, api: RayApi, rays: &RayBatch, hits: &mut HitBatch);

    /// Occlusion through a chosen API.
    fn occluded_with(&self, api: RayApi, rays: &RayBatch, occluded: &mut Vec<bool>);

    /// The API `intersect` uses.
    fn default_intersect_api(&self) -> RayApi;

    /// The API `occluded` uses.
    fn default_occluded_api(&self) -> RayApi;
}

/// Which backend to build (`--backend`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Backend {
    #[default]
    Embree,
    Obvhs,
}

impl std::str::FromStr for Backend {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "embree" => Ok(Backend::Embree),
            "obvhs" => Ok(Backend::Obvhs),
            other => Err(Error::input(
                "--backend",
                format!("unknown backend `{other}` (expected `embree` or `obvhs`)"),
            )),
        }
    }
}

impl Backend {
    pub fn name(self) -> &'static str {
        match self {
            Backend::Embree => "embree",
            Backend::Obvhs => "obvhs",
        }
    }
}

/// Which BVH a backend builds. Embree's compact BVH holds vertex indices in its leaves
/// instead of vertex copies: about half the bytes per triangle (83 against 145 with the
/// geometry at 10⁷ triangles), rays ≈ 35 % slower (BENCHMARKS.md, "Scale"). obvhs has
/// one layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Bvh {
    /// The fast BVH when the run fits its memory budget with it, else the compact one
    /// (`limits::check_run` decides; built without a decision, the fast one).
    #[default]
    Auto,
    Fast,
    Compact,
}

impl std::str::FromStr for Bvh {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(Bvh::Auto),
            "fast" => Ok(Bvh::Fast),
            "compact" => Ok(Bvh::Compact),
            other => Err(Error::input(
                "--bvh",
                format!("unknown BVH `{other}` (expected `auto`, `fast` or `compact`)"),
            )),
        }
    }
}

impl Bvh {
    /// The layout a backend builds for this choice (`Auto` undecided: the fast one).
    pub fn built(self) -> Bvh {
        match self {
            Bvh::Compact => Bvh::Compact,
            Bvh::Auto | Bvh::Fast => Bvh::Fast,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Bvh::Auto => "auto",
            Bvh::Fast => "fast",
            Bvh::Compact => "compact",
        }
    }
}

/// Builds the chosen backend over `geometry` with its fast BVH.
pub fn build(backend: Backend, geometry: &Geometry) -> Result<Box<dyn RayCaster>> {
    build_with(backend, Bvh::Fast, geometry)
}

/// Builds the chosen backend over `geometry` with the `layout` BVH.
pub fn build_with(
    backend: Backend,
    layout: Bvh,
    geometry: &Geometry,
) -> Result<Box<dyn RayCaster>> {
    match backend {
        Backend::Embree => Ok(Box::new(embree::EmbreeScene::with_bvh(geometry, layout)?)),
        Backend::Obvhs if layout == Bvh::Compact => Err(Error::input(
            "--bvh",
            "compact: only the embree backend has a compact BVH",
        )),
        #[cfg(feature = "obvhs")]
        Backend::Obvhs => Ok(Box::new(self::obvhs::ObvhsScene::new(geometry))),
        #[cfg(not(feature = "obvhs"))]
        Backend::Obvhs => Err(Error::Unsupported(
            "--backend obvhs: this build lacks the `obvhs` feature (cargo build --features obvhs)"
                .into(),
        )),
    }
}

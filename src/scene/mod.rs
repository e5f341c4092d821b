//! The scene: the TOML file of the contract, parsed, validated and loaded into the
//! structures the tracer uses. Geometry is re-centred in f64 before it becomes f32.
//!
//! Every other position in `Scene` (lights, receivers) stays in world coordinates (f64);
//! `Geometry::origin` maps between the two frames: world = origin + local.

use crate::criteria::StopCriteria;
use glam::{DAffine3, DVec3, Vec3};
use std::path::PathBuf;
use std::sync::Arc;

pub mod adjacency;
pub mod annual;
pub mod file;
pub mod fingerprint;
pub mod grid;
mod instance;
mod load;
pub mod mesh_io;
mod objects;
pub mod observers;
pub mod requirements;
pub mod shapes;
pub mod tasks;
mod triangle_ids;

pub use crate::light::Luminaire;
pub use crate::surface::{Material, MaterialFile};
pub use instance::{Instance, Instanced, Placement, Prototype, PrototypeMesh};
pub use load::{load, load_str, POINTS_NEED_NEXT_EVENT};
pub use observers::Observer;
pub use requirements::{Check, FigureName, Limit, ModellingPair, Requirement, Subject};
pub use triangle_ids::TriangleIds;

/// All triangles of the scene in one indexed mesh, in the re-centred local frame.
///
/// Per triangle only what cannot be recomputed is stored (indices, and material and
/// object compactly): areas and normals come from the f32 vertices, those of the
/// triangle actually traced ([`Geometry::area_m2`], [`Geometry::normal`]).
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// World position of the local frame's origin (centre of the scene's bounds).
    pub origin: DVec3,
    /// Vertex positions, local frame (shared with Embree, which reads them in place).
    pub vertices: Shared<Vec3>,
    /// Triangles as vertex indices (shared with Embree).
    pub triangles: Shared<[u32; 3]>,
    /// Material index (into `Scene::materials`) per triangle.
    pub material: TriangleIds,
    /// Index of the `[[objects]]` entry each triangle came from.
    pub object: TriangleIds,
    /// [`Geometry::total_area_m2`], once asked: the vertices and triangles do not
    /// change after loading (a backend reads them in place).
    total_area_m2: std::sync::OnceLock<f64>,
    /// Objects without a map (`map = false`): shared meshes placed by transforms, traced
    /// but never tallied. Empty for scenes that map everything.
    pub instanced: Instanced,
}

/// A read-only array that a ray-casting backend may hold without copying it (Embree
/// reads the scene's vertices and triangles in place): clones share the array, and
/// writing through one first copies the array if anything else still holds it, so what
/// a backend holds never changes under it.
#[derive(Clone, Debug, PartialEq)]
pub struct Shared<T>(Arc<Vec<T>>);

impl<T> Shared<T> {
    /// Holds `items` with room for one more element after the last: Embree reads vertex
    /// buffers with 16-byte loads, 4 bytes past the last 12-byte vertex.
    pub fn padded(mut items: Vec<T>) -> Shared<T> {
        items.reserve_exact(1);
        Shared(Arc::new(items))
    }

    /// The array, for a backend to keep alive while it reads it in place.
    pub fn arc(&self) -> &Arc<Vec<T>> {
        &self.0
    }
}

impl<T> Default for Shared<T> {
    fn default() -> Self {
        Shared(Arc::new(Vec::new()))
    }
}

impl<T> From<Vec<T>> for Shared<T> {
    fn from(items: Vec<T>) -> Self {
        Shared(Arc::new(items))
    }
}

impl<T> std::ops::Deref for Shared<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        &self.0
    }
}

impl<T: Clone> std::ops::DerefMut for Shared<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        Arc::make_mut(&mut self.0).as_mut_slice()
    }
}

impl<'a, T> IntoIterator for &'a Shared<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

impl Geometry {
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Total geometric area S (one side per triangle), summed in triangle order;
    /// computed once (the statistics ask after every epoch).
    pub fn total_area_m2(&self) -> f64 {
        *self.total_area_m2.get_or_init(|| self.areas_m2().sum())
    }

    /// Largest coordinate of the local frame (at least the smallest positive f32): the
    /// scale ray-origin offsets are sized by.
    pub fn local_scale(&self) -> f32 {
        let flat = self
            .vertices
            .iter()
            .map(|v| v.abs().max_element())
            .fold(f32::MIN_POSITIVE, f32::max);
        if self.instanced.is_empty() {
            return flat;
        }
        let (lo, hi) = self.instanced.bounds;
        flat.max(lo.abs().max_element()).max(hi.abs().max_element())
    }

    /// World-space bounds (min, max) of all vertices, or `None` without geometry.
    pub fn world_bounds(&self) -> Option<(DVec3, DVec3)> {
        let (ilo, ihi) = self.instanced.bounds;
        let extra = if self.instanced.is_empty() { 0 } else { 2 };
        let mut it = (self.vertices.iter().copied())
            .chain([ilo, ihi].into_iter().take(extra))
            .map(|v| v.as_dvec3());
        let first = it.next()?;
        let (lo, hi) = it.fold((first, first), |(lo, hi), v| (lo.min(v), hi.max(v)));
        Some((lo + self.origin, hi + self.origin))
    }
}

/// A light of the scene, as `crate::light` validated it (world coordinates).
#[derive(Clone)]
pub struct SceneLight {
    /// `lights[i]` as in the scene file, for messages.
    pub label: String,
    /// The source: one of `crate::light`'s kinds, or any other implementation.
    pub kind: Arc<dyn crate::light::Light>,
}

/// Printed as `Light { label, kind }`: the print is part of the scene fingerprint
/// (`fingerprint::light_transport`) that indirect_map.bin files carry, and the golden
/// hashes of those files (tests/data/golden_outputs.txt) hold it.
impl std::fmt::Debug for SceneLight {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Light")
            .field("label", &self.label)
            .field("kind", &self.kind)
            .finish()
    }
}

impl SceneLight {
    pub fn new(label: impl Into<String>, kind: impl crate::light::Light) -> SceneLight {
        SceneLight {
            label: label.into(),
            kind: Arc::new(kind),
        }
    }

    /// The source as kind `T`, if it is one (`light.get::<light::Point>()`).
    pub fn get<T: crate::light::Light>(&self) -> Option<&T> {
        let any: &dyn std::any::Any = self.kind.as_ref();
        any.downcast_ref::<T>()
    }
}

/// What a receiver measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Quantity {
    /// Incident flux on the face whose normal is u × v, per cell area (lx).
    Illuminance,
    /// Flux crossing the cell towards the meter within its cone (cd/m²).
    Luminance {
        /// Unit vector: where the meter looks (light travels against it).
        view_direction: DVec3,
        half_angle_deg: f64,
    },
    /// Cylindrical illuminance Ez (lx): the mean illuminance on the curved surface of
    /// an infinitesimal vertical cylinder (axis world z) at the cell's points,
    /// (1/π)∫ L sin θ dω with θ from the vertical; light from either side of the
    /// receiver's plane counts.
    Cylindrical,
    /// Semi-cylindrical illuminance (lx): the same on the half of the cylinder facing
    /// `facing`, (1/π)∫ L (|s_h| + s_h·f) dω, s_h the horizontal part of the unit
    /// vector towards where the light comes from.
    SemiCylindrical {
        /// Horizontal unit vector (z = 0): the normal of the half-cylinder's middle.
        facing: DVec3,
    },
}

impl Quantity {
    /// As in the scene file and summary.json.
    pub fn name(&self) -> &'static str {
        match self {
            Quantity::Illuminance => "illuminance",
            Quantity::Luminance { .. } => "luminance",
            Quantity::Cylindrical => "cylindrical",
            Quantity::SemiCylindrical { .. } => "semi_cylindrical",
        }
    }

    /// The unit of its values, as summary.json writes it.
    pub fn unit(&self) -> &'static str {
        match self {
            Quantity::Luminance { .. } => "cd/m2",
            _ => "lx",
        }
    }
}

/// How a receiver is scored (`estimator = "track" | "next_event" | "auto"`): its name
/// (scene file, `--estimator`, summary.json) and what it does, in one place. The photon
/// pass (`trace`), the direct light's schedule (`run`) and the summary only ask the
/// methods below, so an estimator that combines these behaviours differently is a
/// variant, its name and its answers here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum Estimator {
    /// Analog: a cell scores when a photon crosses it.
    #[default]
    Track,
    NextEvent,
    Auto,
}

impl Estimator {
    /// Every estimator, in the order messages list them.
    pub const ALL: [Estimator; 3] = [Estimator::Track, Estimator::NextEvent, Estimator::Auto];

    /// What a receiver is scored by: `auto` is next-event estimation (sampled direct
    /// light wherever a source reaches, connections where diffuse paths exist, crossings
    /// for what neither can score).
    pub fn resolved(self) -> Estimator {
        match self {
            Estimator::Auto => Estimator::NextEvent,
            e => e,
        }
    }

    /// As in the scene file and summary.json (serde reads the same snake_case names).
    pub fn name(self) -> &'static str {
        match self {
            Estimator::Track => "track",
            Estimator::NextEvent => "next_event",
            Estimator::Auto => "auto",
        }
    }

    /// The estimator called `name` (`--estimator`).
    pub fn from_name(name: &str) -> Option<Estimator> {
        Estimator::ALL.into_iter().find(|e| e.name() == name)
    }

    /// The names, for messages: "track, next_event or auto".
    pub fn expected() -> String {
        crate::input::or_list(Estimator::ALL.iter().map(|e| e.name()))
    }

    /// The direct light (photons' first segments) is sampled as independent replicates
    /// (`trace::direct`, scheduled by `run`) instead of scored by crossing.
    pub fn direct_by_replicates(self) -> bool {
        matches!(self, Estimator::NextEvent)
    }

    /// Diffuse and connectable glossy vertices are connected to the receiver by shadow
    /// rays beyond its near zone, and their segments do not score by crossing there.
    /// Segments leaving specular vertices always score by crossing.
    pub fn connects(self) -> bool {
        matches!(self, Estimator::NextEvent)
    }

    /// summary.json's `direct_estimator`.
    pub fn direct_name(self) -> &'static str {
        if self.direct_by_replicates() {
            "sampled"
        } else {
            "track"
        }
    }

    /// summary.json's `indirect_estimator`.
    pub fn indirect_name(self) -> &'static str {
        if self.connects() {
            "next_event"
        } else {
            "track"
        }
    }
}

/// A virtual detector: a grid of cells on a parallelogram; it never blocks light.
#[derive(Clone, Debug, PartialEq)]
pub struct Receiver {
    pub name: String,
    pub corner: DVec3,
    pub u: DVec3,
    pub v: DVec3,
    /// Cells along u, along v.
    pub cells: [u32; 2],
    pub quantity: Quantity,
    pub estimator: Estimator,
    /// `Some` when the cells (and the area, after its edge band) were made by the
    /// EN 12464-1 rule (`grid = "en12464"`, [`grid`]); corner, u, v and cells above are
    /// then the rule's result.
    pub grid: Option<grid::GridRule>,
    /// `values = "point"`: each cell scores the value at its centre (next-event only),
    /// not its mean over the cell.
    pub points: bool,
    /// `exclude`: the receivers (indices) whose areas its mean and figures leave out
    /// ([`Receiver::excluded_cells`]).
    pub exclude: Vec<usize>,
}

impl Receiver {
    /// Area of one cell in m².
    pub fn cell_area_m2(&self) -> f64 {
        self.u.cross(self.v).length() / (self.cells[0] as f64 * self.cells[1] as f64)
    }

    pub fn cell_count(&self) -> usize {
        self.cells[0] as usize * self.cells[1] as usize
    }

    /// The receiver's (a, b) ∈ [0, 1)² coordinates of world point `p` projected onto
    /// its plane along its normal, or None outside its area.
    pub fn coordinates_of(&self, p: DVec3) -> Option<(f64, f64)> {
        let n = self.u.cross(self.v);
        let area = n.length();
        let n = n / area;
        let rel = p - self.corner;
        let a = rel.dot(self.v.cross(n) / area);
        let b = rel.dot(n.cross(self.u) / area);
        ((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b)).then_some((a, b))
    }

    /// Per cell (j·nu + i), whether its centre lies within one of the `exclude`d
    /// receivers' areas (projected onto each along its normal); empty when it excludes
    /// none.
    pub fn excluded_cells(&self, receivers: &[Receiver]) -> Vec<bool> {
        self.cells_within(&self.exclude, receivers)
    }

    /// Per cell, whether its centre lies within one of `others`' areas; empty when
    /// `others` is.
    pub fn cells_within(&self, others: &[usize], receivers: &[Receiver]) -> Vec<bool> {
        if others.is_empty() {
            return Vec::new();
        }
        let [nu, nv] = self.cells;
        (0..nu * nv)
            .map(|k| {
                let (i, j) = ((k % nu) as f64 + 0.5, (k / nu) as f64 + 0.5);
                let centre = self.corner + self.u * (i / nu as f64) + self.v * (j / nv as f64);
                (others.iter()).any(|&e| receivers[e].coordinates_of(centre).is_some())
            })
            .collect()
    }

    /// The cells its mean and figures are over (local indices): all but the excluded;
    /// None for all.
    pub fn included_cells(&self, receivers: &[Receiver]) -> Option<Vec<usize>> {
        let excluded = self.excluded_cells(receivers);
        (!excluded.is_empty()).then(|| (0..excluded.len()).filter(|&k| !excluded[k]).collect())
    }
}

/// Receivers reported as daylight factors DF = 100·E/E_out (docs/daylight.md).
#[derive(Clone, Debug, PartialEq)]
pub struct DaylightFactor {
    /// Indices into the scene's receivers.
    pub receivers: Vec<usize>,
    /// E_out: the sky's illuminance on an unobstructed horizontal plane, exact, lx.
    pub outside_lx: f64,
    /// Which sky it is under (its description).
    pub sky: String,
}

/// Confidence of the receivers' figures' intervals unless the scene says otherwise.
pub const DEFAULT_CONFIDENCE: f64 = 0.95;

/// The scene's `[simulation]` table: when to stop (the command line overrides it key
/// by key) and the seed.
#[derive(Clone, Debug, PartialEq)]
pub struct Simulation {
    pub stop: StopCriteria,
    pub seed: u64,
    /// Two-sided confidence of the receivers' figures' intervals (`confidence`, 0.95 by
    /// default). It changes no photon's numbers, so a checkpoint resumes under another.
    pub confidence: f64,
    /// Randomised quasi-Monte Carlo emission, connection points and direct-light
    /// replicates (`qmc`; `run --qmc`): see `trace::Tracer::with_qmc`.
    pub qmc: bool,
}

impl Default for Simulation {
    fn default() -> Self {
        Simulation {
            stop: StopCriteria::default(),
            seed: 0,
            confidence: DEFAULT_CONFIDENCE,
            qmc: false,
        }
    }
}

/// A loaded, validated scene.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub name: String,
    /// The scene file, for messages.
    pub path: PathBuf,
    pub materials: Vec<Material>,
    pub geometry: Geometry,
    pub lights: Vec<SceneLight>,
    pub receivers: Vec<Receiver>,
    /// What the receivers' and observers' figures must reach (`[[requirements]]`).
    pub requirements: Vec<Requirement>,
    /// The cylindrical receivers with `modelling_with`: their modelling ratio Ēz/Ēh.
    pub modelling: Vec<ModellingPair>,
    /// The receivers with `daylight_factor = true` and the unobstructed horizontal
    /// illuminance of the scene's overcast sky their daylight factor divides by.
    pub daylight_factor: Option<DaylightFactor>,
    pub simulation: Simulation,
    /// The `[camera]` of `luxtally render`, if the file has one.
    pub camera: Option<Camera>,
    /// The `[[observers]]` whose UGR the run reports (docs/ugr.md); each has a hidden
    /// receiver `observer:NAME` at the end of `receivers`.
    pub observers: Vec<Observer>,
    /// The `[[portals]]` (world), which skies and suns made for the scene take too.
    pub portals: Vec<crate::light::distant::Portal>,
    /// The `[annual]` table, if any: what `luxtally annual` runs.
    pub annual: Option<annual::Annual>,
}

/// The eye of `luxtally render` (world coordinates). Validated: `look_at` differs from
/// `position` and `up` is not along the view.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    pub look_at: DVec3,
    /// Unit up vector.
    pub up: DVec3,
    /// Vertical field of view, degrees.
    pub fov_deg: f64,
    /// Width, height in pixels.
    pub resolution: [u32; 2],
    /// Eye rays per pixel (jittered on a grid).
    pub samples: u32,
    /// Indirect light interpolated across triangles (false: the raw per-triangle map).
    pub interpolate: bool,
    /// n: an area source is sampled on an n × n jittered grid per shading point.
    pub area_light_samples: u32,
    /// Specular and glossy bounces an eye ray may take.
    pub max_depth: u32,
}

impl Geometry {
    /// Builds the scene mesh from world-space vertices and triangles: re-centres on the
    /// centre of the bounds in f64, then stores f32 local positions, so geometry far from
    /// the world origin keeps full f32 precision. Triangles of zero area (they can never
    /// be hit and have no illuminance) are dropped. `material` and `object` are per
    /// input triangle.
    pub fn from_world(
        vertices: &[DVec3],
        triangles: &[[u32; 3]],
        material: &[u32],
        object: &[u32],
    ) -> Geometry {
        Self::with_instances(vertices, triangles.to_vec(), material, object, &[], &[])
    }

    /// As [`Geometry::from_world`], plus unmapped prototypes placed by `placements`
    /// (world = placement · prototype point). The local frame is centred on the bounds
    /// of both. Placements of prototypes without triangles are dropped.
    pub fn with_instances(
        vertices: &[DVec3],
        triangles: Vec<[u32; 3]>,
        material: &[u32],
        object: &[u32],
        prototypes: &[PrototypeMesh],
        placements: &[Placement],
    ) -> Geometry {
        // Each prototype centred on its own bounds (f32 vertices), and its centre.
        let (protos, centres): (Vec<Prototype>, Vec<DVec3>) =
            prototypes.iter().map(Prototype::centred).unzip();
        // The world box of every instance's prototype box corners, transformed once here:
        // it grows the scene's bounds and, shifted to the local frame, is the instances'.
        let mut instance_bounds = Bounds::default();
        let placed: Vec<(&Placement, DAffine3)> = placements
            .iter()
            .filter(|pl| !protos[pl.prototype as usize].triangles.is_empty())
            .map(|pl| {
                let full = pl.world * DAffine3::from_translation(centres[pl.prototype as usize]);
                for corner in box_corners(protos[pl.prototype as usize].bounds) {
                    instance_bounds.grow(full.transform_point3(corner));
                }
                (pl, full)
            })
            .collect();
        let mut bounds = Bounds::of(vertices);
        if let Some((lo, hi)) = instance_bounds.0 {
            bounds.grow(lo);
            bounds.grow(hi);
        }
        let origin = bounds.centre();
        let mut g = Geometry {
            origin,
            vertices: Shared::padded(local_vertices(vertices, origin)),
            instanced: Instanced::place(protos, &placed, origin, &instance_bounds),
            ..Geometry::default()
        };
        g.set_mapped_triangles(triangles, material, object);
        g
    }

    /// As [`Geometry::from_world`] with one material and one object for every triangle,
    /// `triangles` taken rather than copied (the procedural benchmark scenes: 10⁷
    /// triangles set up without a second 120 MB array).
    pub fn uniform(
        vertices: &[DVec3],
        triangles: Vec<[u32; 3]>,
        material: u32,
        object: u32,
    ) -> Geometry {
        use rayon::prelude::*;
        let origin = Bounds::of(vertices).centre();
        let mut g = Geometry {
            origin,
            vertices: Shared::padded(local_vertices(vertices, origin)),
            ..Geometry::default()
        };
        let keep = |t: &[u32; 3]| g.cross_f64(*t).length() > 0.0;
        let triangles = if triangles.par_iter().all(keep) {
            triangles
        } else {
            // Triangles of zero (or NaN) area can never be hit and have no illuminance.
            triangles.into_par_iter().filter(keep).collect()
        };
        g.material = TriangleIds::constant(material, triangles.len());
        g.object = TriangleIds::constant(object, triangles.len());
        g.triangles = triangles.into();
        g
    }

    /// Stores the triangles of nonzero area (as traced: from the f32 local vertices)
    /// with their material and object.
    fn set_mapped_triangles(
        &mut self,
        mut triangles: Vec<[u32; 3]>,
        material: &[u32],
        object: &[u32],
    ) {
        use rayon::prelude::*;
        let keep = |t: &[u32; 3]| self.cross_f64(*t).length() > 0.0;
        if triangles.par_iter().all(keep) {
            triangles.shrink_to_fit();
            self.triangles = triangles.into();
            self.material = TriangleIds::new(material);
            self.object = TriangleIds::new(object);
            return;
        }
        // Triangles of zero (or NaN) area can never be hit and have no illuminance.
        let kept: Vec<usize> = (0..triangles.len())
            .into_par_iter()
            .filter(|&k| keep(&triangles[k]))
            .collect();
        self.triangles = kept
            .iter()
            .map(|&k| triangles[k])
            .collect::<Vec<_>>()
            .into();
        self.material = kept.iter().map(|&k| material[k]).collect();
        self.object = kept.iter().map(|&k| object[k]).collect();
    }

    /// (v1 − v0) × (v2 − v0) of the triangle with vertex indices `tri`, in f64 from the
    /// stored f32 vertices: twice its area along its normal.
    #[inline(always)]
    fn cross_f64(&self, tri: [u32; 3]) -> DVec3 {
        let [a, b, c] = tri.map(|i| self.vertices[i as usize].as_dvec3());
        (b - a).cross(c - a)
    }

    /// Area in m² of triangle `t` as traced (its f32 local vertices, computed in f64).
    /// Not stored: 8 bytes per triangle at 10⁷ triangles are worth more than the few
    /// passes over every triangle (statistics, outputs) that recompute it.
    #[inline]
    pub fn area_m2(&self, t: usize) -> f64 {
        0.5 * self.cross_f64(self.triangles[t]).length()
    }

    /// Every triangle's area in m² ([`Geometry::area_m2`]), in triangle order.
    pub fn areas_m2(&self) -> impl ExactSizeIterator<Item = f64> + Clone + '_ {
        (0..self.triangles.len()).map(|t| self.area_m2(t))
    }

    /// Unit geometric normal of triangle `t`, (v1 − v0) × (v2 − v0) orientation
    /// ([`triangle_normal`] of its stored vertices).
    #[inline]
    pub fn normal(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.triangles[t].map(|i| self.vertices[i as usize]);
        triangle_normal(a, b, c)
    }
}

/// The unit normal of the triangle a, b, c, (b − a) × (c − a) orientation, computed in
/// f64 (so that every triangle of nonzero area as traced has one) and rounded to f32.
/// Not stored per triangle: a hit computes it from the vertices it reads anyway.
#[inline(always)]
pub fn triangle_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let n = (b - a).cross(c - a);
    (n / n.length()).as_vec3()
}

/// World-space vertices in the local frame at `origin`, with room for one more (see
/// [`Shared::padded`]: no reallocation there).
fn local_vertices(vertices: &[DVec3], origin: DVec3) -> Vec<Vec3> {
    use rayon::prelude::*;
    let mut local = Vec::with_capacity(vertices.len() + 1);
    vertices
        .par_iter()
        .map(|v| (*v - origin).as_vec3())
        .collect_into_vec(&mut local);
    local
}

/// A growing axis-aligned box (empty until the first point).
#[derive(Default)]
struct Bounds(Option<(DVec3, DVec3)>);

impl Bounds {
    /// The box of `points`, found in parallel (min and max do not depend on the order).
    fn of(points: &[DVec3]) -> Bounds {
        use rayon::prelude::*;
        let inf = DVec3::splat(f64::INFINITY);
        let (lo, hi) = points
            .par_iter()
            .fold(|| (inf, -inf), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
            .reduce(|| (inf, -inf), |(a, b), (c, d)| (a.min(c), b.max(d)));
        Bounds((!points.is_empty()).then_some((lo, hi)))
    }

    fn grow(&mut self, p: DVec3) {
        self.0 = Some(match self.0 {
            None => (p, p),
            Some((lo, hi)) => (lo.min(p), hi.max(p)),
        });
    }

    /// The centre of the box (the origin when empty).
    fn centre(&self) -> DVec3 {
        self.0.map_or(DVec3::ZERO, |(lo, hi)| (lo + hi) * 0.5)
    }
}

/// The 8 corners of an f32 box, in f64.
fn box_corners((lo, hi): (Vec3, Vec3)) -> impl Iterator<Item = DVec3> {
    (0..8).map(move |k| {
        DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x } as f64,
            if k & 2 == 0 { lo.y } else { hi.y } as f64,
            if k & 4 == 0 { lo.z } else { hi.z } as f64,
        )
    })
}

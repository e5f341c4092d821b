//! The scene: the TOML file of the contract, parsed, validated and loaded into the
//! structures the tracer uses. Geometry is re-centred in f64 before it becomes f32.
//!
//! Every other position in `Scene` (lights, receivers) stays in world coordinates (f64);
//! `Geometry::origin` maps between the two frames: world = origin + local.

use crate::photometry::Photometry;
use glam::{DMat3, DVec3, Vec3};
use std::path::PathBuf;
use std::sync::Arc;

pub mod adjacency;
pub mod file;
mod load;
pub mod mesh_io;
pub mod shapes;

pub use load::{load, load_str};

/// A material: any mix of Lambertian reflection/transmission, ideal specular
/// reflection/refraction and glossy (GGX microfacet) reflection/refraction
/// (`trace::bsdf`). The fractions sum to at most 1; the rest is absorbed.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse (Lambertian) reflectance ρ.
    pub reflectance: f64,
    /// Diffuse (Lambertian) transmittance τ.
    pub transmittance: f64,
    /// Ideal mirror reflectance.
    pub specular_reflectance: f64,
    /// Ideal refraction (dielectric of index `ior`, with Fresnel reflection at its face).
    pub specular_transmittance: f64,
    /// Index of refraction of the dielectric lobes (ideal and rough).
    pub ior: f64,
    /// Glossy reflector: a GGX lobe of this albedo weight (Fresnel factor 1).
    pub glossy_reflectance: f64,
    /// Rough dielectric (index `ior`, Fresnel reflection and refraction through GGX
    /// microfacets) of this albedo weight.
    pub glossy_transmittance: f64,
    /// Perceptual roughness of the glossy lobes, in (0, 1]; GGX α = roughness².
    pub roughness: f64,
}

impl Material {
    /// A Lambertian reflector of reflectance `rho`.
    pub fn lambertian(name: &str, rho: f64) -> Self {
        Material {
            name: name.to_string(),
            reflectance: rho,
            transmittance: 0.0,
            specular_reflectance: 0.0,
            specular_transmittance: 0.0,
            ior: 1.5,
            glossy_reflectance: 0.0,
            glossy_transmittance: 0.0,
            roughness: 1.0,
        }
    }

    /// Total albedo: the fraction of incident flux that is not absorbed.
    pub fn albedo(&self) -> f64 {
        self.reflectance
            + self.transmittance
            + self.specular_reflectance
            + self.specular_transmittance
            + self.glossy_reflectance
            + self.glossy_transmittance
    }
}

/// All triangles of the scene in one indexed mesh, in the re-centred local frame.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// World position of the local frame's origin (centre of the scene's bounds).
    pub origin: DVec3,
    /// Vertex positions, local frame.
    pub vertices: Vec<Vec3>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Material index (into `Scene::materials`) per triangle.
    pub material: Vec<u32>,
    /// Triangle area in m², computed in f64 from world coordinates.
    pub area_m2: Vec<f64>,
    /// Unit geometric normal per triangle, (v1 − v0) × (v2 − v0) orientation.
    pub normal: Vec<Vec3>,
    /// Index of the `[[objects]]` entry each triangle came from.
    pub object: Vec<u32>,
}

impl Geometry {
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Total geometric area S (one side per triangle).
    pub fn total_area_m2(&self) -> f64 {
        self.area_m2.iter().sum()
    }

    /// Largest coordinate of the local frame (at least the smallest positive f32): the
    /// scale ray-origin offsets are sized by.
    pub fn local_scale(&self) -> f32 {
        self.vertices
            .iter()
            .map(|v| v.abs().max_element())
            .fold(f32::MIN_POSITIVE, f32::max)
    }

    /// World-space bounds (min, max) of all vertices, or `None` without geometry.
    pub fn world_bounds(&self) -> Option<(DVec3, DVec3)> {
        let mut it = self.vertices.iter();
        let first = it.next()?.as_dvec3();
        let (lo, hi) = it.fold((first, first), |(lo, hi), v| {
            let v = v.as_dvec3();
            (lo.min(v), hi.max(v))
        });
        Some((lo + self.origin, hi + self.origin))
    }
}

/// A light source, world coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum LightKind {
    /// Isotropic point source.
    Point { position: DVec3, intensity_cd: f64 },
    /// Spot: intensity `intensity_cd` on axis up to `falloff_deg` off axis, then a smooth
    /// (smoothstep in cos θ) fall to zero at `cone_deg`.
    Spot {
        position: DVec3,
        direction: DVec3,
        intensity_cd: f64,
        cone_deg: f64,
        falloff_deg: f64,
    },
    /// Parallel source: `illuminance_lx` on a plane normal to `direction` (unit, the way
    /// the light travels).
    Directional {
        direction: DVec3,
        illuminance_lx: f64,
    },
    /// One-sided Lambertian parallelogram emitting on the side of u × v.
    Area {
        corner: DVec3,
        u: DVec3,
        v: DVec3,
        luminance_cdm2: f64,
    },
    /// A luminaire from a photometric file (docs/photometry.md).
    Luminaire(Luminaire),
}

/// A luminaire placed in the scene: its photometry (shared by every luminaire of the
/// same file), where it is and how it is turned.
#[derive(Clone, Debug, PartialEq)]
pub struct Luminaire {
    pub photometry: Arc<Photometry>,
    /// World position of the centre of its luminous opening.
    pub position: DVec3,
    /// Luminaire frame (x = C0, y = C90, z = up, nadir −z) → world.
    pub frame: DMat3,
    /// Factor on the file's intensities: `multiplier`, times the `flux_lm` rescaling,
    /// times the file's tilt factor at the luminaire's tilt (relative to tilt 0).
    pub scale: f64,
}

impl Luminaire {
    /// The frame that turns the nadir (−z) to `aim` (unit) by the shortest rotation (a
    /// half turn about x when `aim` is straight up), then turns C0 about `aim` by
    /// `rotate_deg` (counter-clockwise seen from where the light goes).
    pub fn frame(aim: DVec3, rotate_deg: f64) -> DMat3 {
        let nadir = -DVec3::Z;
        let turn = if aim.dot(nadir) < -1.0 + 1e-12 {
            DMat3::from_rotation_x(std::f64::consts::PI)
        } else {
            DMat3::from_quat(glam::DQuat::from_rotation_arc(nadir, aim))
        };
        DMat3::from_axis_angle(-aim, rotate_deg.to_radians()) * turn
    }

    /// Flux of the luminaire as placed, lm.
    pub fn flux_lm(&self) -> f64 {
        self.photometry.flux_lm() * self.scale
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// `lights[i]` as in the scene file, for messages.
    pub label: String,
    pub kind: LightKind,
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
}

/// How a receiver is scored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Estimator {
    /// Analog: a cell scores when a photon crosses it.
    #[default]
    Track,
    NextEvent,
    Auto,
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
}

impl Receiver {
    /// Area of one cell in m².
    pub fn cell_area_m2(&self) -> f64 {
        self.u.cross(self.v).length() / (self.cells[0] as f64 * self.cells[1] as f64)
    }

    pub fn cell_count(&self) -> usize {
        self.cells[0] as usize * self.cells[1] as usize
    }
}

/// What to stop on, from the scene's `[simulation]` table (the command line overrides it).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Simulation {
    pub photons: Option<u64>,
    pub seed: u64,
    pub time_limit_s: Option<f64>,
    pub target_error: Option<f64>,
    pub target: Option<String>,
    pub absolute: bool,
    pub min_hits: Option<u64>,
}

/// A loaded, validated scene.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub name: String,
    /// The scene file, for messages.
    pub path: PathBuf,
    pub materials: Vec<Material>,
    pub geometry: Geometry,
    pub lights: Vec<Light>,
    pub receivers: Vec<Receiver>,
    pub simulation: Simulation,
    /// The `[camera]` of `luxtally render`, if the file has one.
    pub camera: Option<Camera>,
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
        let origin = match vertices.split_first() {
            None => DVec3::ZERO,
            Some((first, rest)) => {
                let (lo, hi) = rest
                    .iter()
                    .fold((*first, *first), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
                (lo + hi) * 0.5
            }
        };
        let mut g = Geometry {
            origin,
            vertices: vertices.iter().map(|v| (*v - origin).as_vec3()).collect(),
            ..Geometry::default()
        };
        for (k, tri) in triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| vertices[i as usize]);
            let cross = (b - a).cross(c - a);
            let area = 0.5 * cross.length();
            if !(area > 0.0) {
                continue;
            }
            g.triangles.push(*tri);
            g.material.push(material[k]);
            g.object.push(object[k]);
            g.area_m2.push(area);
            g.normal.push((cross / (2.0 * area)).as_vec3());
        }
        g
    }
}

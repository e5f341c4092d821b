//! The eye pass as a wavefront over SoA batches (pbrt-v4's stages): generate eye rays →
//! intersect → at each hit add the indirect term and queue shadow rays for the direct
//! term (method.md eqs. 1–2) and the specular and glossy continuations → trace the
//! shadow rays → repeat on the continuations until none is left or the depth limit is
//! reached. Glossy surfaces take their direct light through the BSDF (`surface`) by
//! the same shadow rays, and continue through one sampled direction per glossy lobe.

use super::map::IndirectField;
use crate::accel::{HitBatch, RayBatch, RayCaster};
use crate::rng;
use crate::sampling::uniform;
use crate::scene::{Camera, Scene};
use crate::surface::{Bsdf, Incidence, LobeKind};
use crate::trace::emit::Emitters;
use crate::trace::reflected::reflected_direct;
use crate::trace::scatter::offset_origin;
use crate::trace::shadow::{ShadowCaster, ShadowScratch};
use glam::{DVec3, Vec3};
use rand_pcg::Pcg32;

/// Pixels per work item: enough rays per batch for Embree's streams, small enough to
/// share the image among threads.
pub const TILE_PIXELS: usize = 256;

/// Continuations whose weight falls below this are dropped (their luminance is at most
/// this fraction of what they would show).
const MIN_WEIGHT: f64 = 1e-5;

/// Rays the eye pass cast.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayCounts {
    /// Primary and specular (closest-hit) rays.
    pub eye: u64,
    /// Shadow (occlusion) rays.
    pub shadow: u64,
}

/// The pinhole camera in the local frame.
#[derive(Clone, Copy, Debug)]
struct Pinhole {
    eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half: f64,
    aspect: f64,
}

impl Pinhole {
    fn new(c: &Camera, origin: DVec3) -> Pinhole {
        let forward = (c.look_at - c.position).normalize();
        let right = forward.cross(c.up).normalize();
        Pinhole {
            eye: c.position - origin,
            forward,
            right,
            up: right.cross(forward),
            tan_half: libm::tan(0.5 * c.fov_deg.to_radians()),
            aspect: c.resolution[0] as f64 / c.resolution[1] as f64,
        }
    }

    /// Unit direction through image position (x, y) in pixels from the top-left corner.
    fn direction(&self, x: f64, y: f64, width: f64, height: f64) -> DVec3 {
        let sx = (2.0 * x / width - 1.0) * self.tan_half * self.aspect;
        let sy = (1.0 - 2.0 * y / height) * self.tan_half;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }
}

/// Most samples per side of an area source at one shading point (48² shadow rays).
pub const MAX_AREA_SAMPLES: usize = 48;

/// Samples per side n of an area source of diagonal `diagonal_m` seen from `distance_m`
/// (to its centre): the camera's `area_light_samples` n₀ from a diagonal's distance on,
/// growing as n₀·diagonal/distance nearer, up to [`MAX_AREA_SAMPLES`]. Jittered strata
/// make the noise fall as 1/n² and grow about as (diagonal/distance)^1.5, so this keeps
/// the direct term's noise per shading point near its far-field value (≈ 0.25 % for
/// n₀ = 8; docs/render.md).
pub fn area_samples_per_side(n0: u32, diagonal_m: f64, distance_m: f64) -> usize {
    let n0 = n0 as usize;
    let grown = (n0 as f64 * diagonal_m / distance_m.max(1e-9)).ceil();
    if grown.is_finite() && grown > n0 as f64 {
        (grown as usize).min(MAX_AREA_SAMPLES.max(n0))
    } else {
        n0
    }
}

/// Everything the eye pass reads, prepared once.
pub struct EyePass<'a> {
    caster: &'a dyn RayCaster,
    /// The direct term's shadow rays (through glazing).
    shadows: ShadowCaster<'a>,
    scene: &'a Scene,
    camera: &'a Camera,
    field: &'a IndirectField,
    lights: Emitters,
    pinhole: Pinhole,
    scene_scale: f32,
    seed: u64,
    /// Per material.
    bsdfs: Vec<Bsdf>,
}

/// An eye path's state besides its ray.
#[derive(Clone, Copy, Debug)]
struct Path {
    /// Sample within the tile.
    sample: u32,
    /// Throughput: the luminance the path's end adds is scaled by it.
    weight: f64,
    /// The segment leaves a glossy vertex, whose shadow rays already took the light of
    /// the sources it sees: sources met along it are not counted again.
    lights_counted: bool,
}

/// Where an eye path meets a surface, as the eye sees it.
struct Vertex<'a> {
    p: Vec3,
    /// The ray's direction, the normals, the side the eye sees.
    inc: Incidence,
    bsdf: &'a Bsdf,
    path: Path,
    /// The random stream of (tile, depth, ray) for what is sampled here.
    stream: u64,
}

/// Reused buffers of one worker.
#[derive(Default)]
pub struct Scratch {
    rays: RayBatch,
    hits: HitBatch,
    /// Per ray.
    paths: Vec<Path>,
    next_rays: RayBatch,
    next_paths: Vec<Path>,
    shadow: RayBatch,
    /// Per shadow ray: (sample within tile, luminance it adds if unoccluded).
    shadow_gain: Vec<(u32, f64)>,
    /// Per shadow ray, the fraction of its light that arrives.
    through: Vec<f64>,
    shadow_scratch: ShadowScratch,
}

impl<'a> EyePass<'a> {
    pub fn new(
        scene: &'a Scene,
        camera: &'a Camera,
        field: &'a IndirectField,
        caster: &'a dyn RayCaster,
        seed: u64,
    ) -> EyePass<'a> {
        let origin = scene.geometry.origin;
        let lights = Emitters::new(scene);
        let scene_scale = scene.geometry.local_scale();
        EyePass {
            caster,
            shadows: ShadowCaster::new(scene, caster),
            scene,
            camera,
            field,
            lights,
            pinhole: Pinhole::new(camera, origin),
            scene_scale,
            seed,
            bsdfs: scene.materials.iter().map(Bsdf::new).collect(),
        }
    }

    pub fn pixel_count(&self) -> usize {
        self.camera.resolution[0] as usize * self.camera.resolution[1] as usize
    }

    /// Luminance of the pixels `first..first + count` (raster order) and the rays cast.
    pub fn render_tile(
        &self,
        first: usize,
        count: usize,
        s: &mut Scratch,
    ) -> (Vec<f64>, RayCounts) {
        let spp = self.camera.samples as usize;
        let mut sample_l = vec![0.0f64; count * spp];
        let mut counts = RayCounts::default();
        self.generate(first, count, s);
        for depth in 0..=self.camera.max_depth {
            if s.rays.is_empty() {
                break;
            }
            self.caster.intersect(&s.rays, &mut s.hits);
            counts.eye += s.rays.len() as u64;
            s.next_rays.clear();
            s.next_paths.clear();
            s.shadow.clear();
            s.shadow_gain.clear();
            for k in 0..s.rays.len() {
                // (tile, ray in the queue, depth): unique below 2²⁷ tiles, 2³⁰ rays a
                // queue and depths 0..=127 (max_depth ≤ 64 needs 7 bits); `rng::stream`
                // mixes it.
                let tile = (first / TILE_PIXELS) as u64;
                let stream = tile << 37 | (k as u64 & ((1 << 30) - 1)) << 7 | depth as u64;
                self.shade(k, depth < self.camera.max_depth, stream, s, &mut sample_l);
            }
            if !s.shadow.is_empty() {
                self.shadows
                    .transmitted(&s.shadow, &mut s.through, &mut s.shadow_scratch);
                counts.shadow += s.shadow.len() as u64;
                for (&(sample, gain), &through) in s.shadow_gain.iter().zip(&s.through) {
                    if through > 0.0 {
                        sample_l[sample as usize] += gain * through;
                    }
                }
            }
            std::mem::swap(&mut s.rays, &mut s.next_rays);
            std::mem::swap(&mut s.paths, &mut s.next_paths);
        }
        let pixels = sample_l
            .chunks_exact(spp)
            .map(|c| c.iter().sum::<f64>() / spp as f64)
            .collect();
        (pixels, counts)
    }

    /// Primary rays: one through the pixel centre with one sample per pixel, else
    /// jittered on a grid of ⌈√n⌉ columns (stratified), from the pixel's own stream.
    fn generate(&self, first: usize, count: usize, s: &mut Scratch) {
        let [w, h] = self.camera.resolution.map(|x| x as f64);
        let spp = self.camera.samples as usize;
        let cols = (spp as f64).sqrt().ceil() as usize;
        let rows = spp.div_ceil(cols);
        s.rays.clear();
        s.paths.clear();
        let eye = self.pinhole.eye.as_vec3().to_array();
        for p in 0..count {
            let pixel = first + p;
            let (px, py) = ((pixel % w as usize) as f64, (pixel / w as usize) as f64);
            let mut rng: Pcg32 = rng::stream(self.seed, pixel as u64);
            for k in 0..spp {
                let (jx, jy) = if spp == 1 {
                    (0.5, 0.5)
                } else {
                    (
                        ((k % cols) as f64 + uniform(&mut rng)) / cols as f64,
                        ((k / cols) as f64 + uniform(&mut rng)) / rows as f64,
                    )
                };
                let d = self.pinhole.direction(px + jx, py + jy, w, h);
                s.rays.push(eye, d.as_vec3().to_array(), 0.0, f32::INFINITY);
                s.paths.push(Path {
                    sample: (p * spp + k) as u32,
                    weight: 1.0,
                    lights_counted: false,
                });
            }
        }
    }

    /// One eye ray's hit: emitters seen directly, the diffuse and glossy parts (indirect
    /// now, direct through queued shadow rays), and the specular and glossy
    /// continuations.
    fn shade(
        &self,
        k: usize,
        may_continue: bool,
        stream: u64,
        s: &mut Scratch,
        sample_l: &mut [f64],
    ) {
        let path = s.paths[k];
        let o = DVec3::new(
            s.rays.ox[k] as f64,
            s.rays.oy[k] as f64,
            s.rays.oz[k] as f64,
        );
        let dir = DVec3::new(
            s.rays.dx[k] as f64,
            s.rays.dy[k] as f64,
            s.rays.dz[k] as f64,
        )
        .normalize();
        let t_hit = s.hits.t[k] as f64;
        let l = &mut sample_l[path.sample as usize];
        if !path.lights_counted {
            *l += path.weight * self.area_light_seen(o, dir, t_hit);
        }
        let Some(surface) = s.hits.surface(k, &self.scene.geometry) else {
            return;
        };
        let at = Vertex {
            p: surface.point,
            inc: Incidence::new(dir, surface.normal.as_dvec3()),
            bsdf: &self.bsdfs[surface.material as usize],
            path,
            stream,
        };
        if let Some(t) = surface.mapped {
            let uv = (s.hits.u[k], s.hits.v[k]);
            self.add_map_light(&at, t as usize, uv, may_continue, l);
        }
        if at.bsdf.has(LobeKind::Diffuse) || at.bsdf.has(LobeKind::Glossy) {
            self.queue_direct(&at, s);
        }
        if may_continue {
            self.continue_path(&at, s);
        }
    }

    /// Adds the indirect light read from the map at triangle `t` (unmapped, instanced
    /// objects have none: direct light only), through the lobes' `eye_indirect`: the
    /// Lambertian parts', and at the depth limit the glossy lobes'.
    fn add_map_light(
        &self,
        at: &Vertex,
        t: usize,
        (u, v): (f32, f32),
        may_continue: bool,
        l: &mut f64,
    ) {
        let back = at.inc.back;
        let e_seen = || self.field.illuminance_lx(t, back, u, v);
        let e_other = || self.field.illuminance_lx(t, !back, u, v);
        at.bsdf
            .eye_indirect(l, at.path.weight, &at.inc, &e_seen, &e_other, !may_continue);
    }

    /// Queues the rays that go on from `at`, as its lobes continue them
    /// (`Lobe::eye_continue`: mirror reflection, Fresnel glass's reflection and
    /// refraction, one sampled direction per glossy lobe, from a stream of (tile, depth,
    /// ray) like the area-source pattern).
    fn continue_path(&self, at: &Vertex, s: &mut Scratch) {
        let facing = at.inc.facing;
        let new_rng = || rng::stream(self.seed ^ 0x5a5a_0000_5a5a_0000, at.stream);
        at.bsdf
            .eye_continue(at.path.weight, &at.inc, &new_rng, &mut |c| {
                if c.weight < MIN_WEIGHT {
                    return;
                }
                let leave = if c.transmitted { -facing } else { facing };
                let origin = offset_origin(at.p, leave.as_vec3(), self.scene_scale);
                s.next_rays.push(
                    origin.to_array(),
                    c.dir.as_vec3().to_array(),
                    0.0,
                    f32::INFINITY,
                );
                s.next_paths.push(Path {
                    sample: at.path.sample,
                    weight: c.weight,
                    // Straight through a pane, the shadow rays behind it went on too.
                    lights_counted: c.lights_counted || (c.see_through && at.path.lights_counted),
                });
            });
    }

    /// Queues the shadow rays of the direct term at `at` (eqs. 1–2): each carries the
    /// luminance it adds, f(wo, ω_light)·|cos|·E summed over the finite lobes (ρ/π·E on
    /// the eye's side or τ/π·E from the other side for a Lambertian one; `wo` towards
    /// the eye).
    fn queue_direct(&self, at: &Vertex, s: &mut Scratch) {
        let (weight, sample, stream) = (at.path.weight, at.path.sample, at.stream);
        let pd = at.p.as_dvec3();
        let mut area_pattern = Vec::new();
        for light in 0..self.lights.emitters.len() {
            // n × n jittered strata over sources with an extent (area sources,
            // luminaires' openings), from a stream of (tile, depth, ray): the same
            // whatever the threads or the backend.
            let (centre, diagonal) = self.lights.extent(light);
            area_pattern.clear();
            if diagonal > 0.0 {
                let n = area_samples_per_side(
                    self.camera.area_light_samples,
                    diagonal,
                    (centre - pd).length(),
                );
                let mut rng = rng::stream(self.seed ^ 0xa5a5_a5a5_0000_0000, stream);
                for k in 0..n * n {
                    let (i, j) = ((k / n) as f64, (k % n) as f64);
                    area_pattern.push((
                        (i + uniform(&mut rng)) / n as f64,
                        (j + uniform(&mut rng)) / n as f64,
                    ));
                }
            } else {
                area_pattern.push((0.5, 0.5));
            }
            let surface = (at.p, &at.inc, at.bsdf);
            let scale = self.scene_scale;
            reflected_direct(
                &self.lights,
                light,
                surface,
                weight,
                &area_pattern,
                false,
                scale,
                |o, to, t_far, l| {
                    s.shadow.push(o.to_array(), to.to_array(), 0.0, t_far);
                    s.shadow_gain.push((sample, l));
                },
            );
        }
    }

    /// Luminance of the sources the ray meets from their emitting side before `t_hit`
    /// (area sources: they are not scene geometry; the eye still sees them).
    fn area_light_seen(&self, o: DVec3, dir: DVec3, t_hit: f64) -> f64 {
        let mut l = 0.0;
        for emitter in &self.lights.emitters {
            if let Some(luminance_cdm2) = emitter.luminance_seen(o, dir, t_hit) {
                l += luminance_cdm2;
            }
        }
        l
    }
}

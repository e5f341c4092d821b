//! Luminance meters' reflected direct light, sampled with its own error: part of each
//! direct-light replicate of a luminance cell ([`super::direct`]). Each of a
//! replicate's samples takes a jittered point of the cell and a direction of the
//! meter's cone (uniform in solid angle, its band of cos θ stratified), follows it back
//! through any panes to the first surface, and if that surface connects (diffuse, or a
//! glossy lobe broad enough, [`crate::surface::Bsdf::connectable`]) adds the light of
//! every source reaching it, reflected towards the meter: f(wo, wi)·|cos θ_i|·E⊥ through
//! the connectable lobes, behind a shadow ray — the eye pass's direct term at a pixel.
//!
//! The photons leave that light to these samples: a vertex lit straight from its
//! source does not connect to such a meter (`Tracer::connect`). What a sample does not
//! take stays the photons': surfaces nearer the meter (first hit within its near zone,
//! measured from the nearest pane as the photons' crossings are), lobes too sharp to
//! connect, and light that came by another surface.

use super::direct::DirectLight;
use super::emit::Emitters;
use super::scatter::offset_origin;
use super::shadow::SeenThrough;
use crate::accel::RayBatch;
use crate::rng::direct_stream;
use crate::sampling::{cone_band_direction, uniform};
use crate::scene::Scene;
use crate::surface::{Bsdf, Incidence, Transport};
use crate::tally::receiver_grid::Kind;
use crate::tally::ReceiverGrid;
use glam::{DVec3, Vec3};

/// Per material, the BSDF a meter's samples reflect the sources' light through.
pub struct Reflectors {
    bsdfs: Vec<Bsdf>,
    scene_scale: f32,
}

impl Reflectors {
    pub fn new(scene: &Scene) -> Reflectors {
        Reflectors {
            bsdfs: scene.materials.iter().map(Bsdf::new).collect(),
            scene_scale: scene.geometry.local_scale(),
        }
    }
}

/// The next event of a surface point seen along `at.dir`: for each piece of source
/// `light` (`pattern` of an area source) reaching `x`, the luminance w·f(wo, ωᵢ)·|cos θᵢ|·E⊥
/// its lobes send back towards where the ray came from (the finite lobes, or the
/// connectable ones only), handed to `push` with the shadow ray that must be clear for
/// it (origin offset off the side it leaves, direction to the source, t_far short of a
/// source point). The eye pass's direct term and the meters' reflected light both.
#[allow(clippy::too_many_arguments)]
pub fn reflected_direct(
    emitters: &Emitters,
    light: usize,
    (x, at, bsdf): (Vec3, &Incidence, &Bsdf),
    w: f64,
    pattern: &[(f64, f64)],
    connectable_only: bool,
    scene_scale: f32,
    mut push: impl FnMut(Vec3, Vec3, f32, f64),
) {
    // Shadow rays towards a point stop just short of it: a source sitting on a
    // surface is not shadowed by that surface.
    const SHORT: f32 = 1.0 - 1e-5;
    let wo = -at.dir;
    emitters.incoming(light, x.as_dvec3(), pattern, |inc| {
        let wi = inc.direction();
        let cos = wi.dot(at.facing);
        let side = if cos >= 0.0 { at.facing } else { -at.facing };
        let g = bsdf.f_cos(w, wo, wi, at.n, cos, Transport::Radiance, connectable_only);
        let l = g * inc.normal_lx;
        if !(l > 0.0) {
            return;
        }
        let t_far = if inc.distance.is_finite() {
            SHORT
        } else {
            f32::INFINITY
        };
        let origin = offset_origin(x, side.as_vec3(), scene_scale);
        push(origin, inc.to_source.as_vec3(), t_far, l);
    });
}

/// Reused buffers of one worker.
#[derive(Default)]
pub(super) struct Scratch {
    view: RayBatch,
    /// Per view ray: (replicate within the block, its sample's weight, its direction).
    view_meta: Vec<(u32, f64, DVec3)>,
    seen: Vec<Option<SeenThrough>>,
    /// Per view ray, the source point each light is paired with.
    source_points: Vec<(f64, f64)>,
    shadow: RayBatch,
    /// Per shadow ray: (replicate within the block, luminance if unoccluded).
    gain: Vec<(u32, f64)>,
    through: Vec<f64>,
    permutation: Vec<u32>,
}

/// Streams of the reflected samples: apart from the direct light's own, so adding
/// them leaves every other receiver's bits as they were.
const STREAM: u64 = 0x5be0_cd19_137e_2179;

impl DirectLight<'_> {
    /// Adds to `totals[r]` (replicates `first + r` of local cell `(i, j)`, global
    /// index `cell`, `m` points per side) the reflected direct light of a luminance
    /// meter's cell; returns the rays cast. Nothing for other receivers.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn add_reflected(
        &self,
        grid: &ReceiverGrid,
        (i, j): (u32, u32),
        m: u32,
        cell: u64,
        first: u64,
        totals: &mut [f64],
        s: &mut Scratch,
        shadow: &mut super::shadow::ShadowScratch,
    ) -> u64 {
        let (
            Some(reflectors),
            Kind::Luminance {
                towards_meter,
                cos_half_angle,
                ..
            },
        ) = (self.reflectors, grid.kind)
        else {
            return 0;
        };
        let samples = m * m;
        s.view.clear();
        s.view_meta.clear();
        s.source_points.clear();
        let lights = self.emitters.emitters.len();
        for r in 0..totals.len() as u32 {
            let mut rng = direct_stream(self.seed ^ STREAM, cell, first + r as u64);
            super::direct::shuffle(&mut s.permutation, samples, &mut rng);
            for sample in 0..samples {
                let p = grid.cell_point(
                    (i, j),
                    ((sample % m) as f64 + uniform(&mut rng)) / m as f64,
                    ((sample / m) as f64 + uniform(&mut rng)) / m as f64,
                );
                // The band of cos θ of stratum π(sample), uniform within it.
                let band = s.permutation[sample as usize] as f64;
                let w = cone_band_direction(
                    &mut rng,
                    towards_meter,
                    cos_half_angle,
                    band,
                    samples as f64,
                );
                for _ in 0..lights {
                    s.source_points.push((uniform(&mut rng), uniform(&mut rng)));
                }
                // Start just off the receiver, which may lie on a surface.
                let t_near = (2.0 * self.slack) as f32;
                s.view.push(
                    p.as_vec3().into(),
                    (-w).as_vec3().into(),
                    t_near,
                    f32::INFINITY,
                );
                s.view_meta.push((r, 1.0 / samples as f64, w));
            }
        }
        let mut rays = self.shadows.first_opaque(&s.view, &mut s.seen, shadow);
        s.shadow.clear();
        s.gain.clear();
        for (k, seen) in s.seen.iter().enumerate() {
            let Some(seen) = seen else {
                continue;
            };
            let bsdf = &reflectors.bsdfs[seen.surface.material as usize];
            if (seen.first_hit as f64) < grid.near_zone_m || !bsdf.connectable() {
                continue;
            }
            let (r, weight, w) = s.view_meta[k];
            let at = Incidence::new(-w, seen.surface.normal.as_dvec3());
            let points = &s.source_points[k * lights..(k + 1) * lights];
            for (light, point) in points.iter().enumerate() {
                let surface = (seen.surface.point, &at, bsdf);
                let scale = reflectors.scene_scale;
                let pattern = std::slice::from_ref(point);
                reflected_direct(
                    self.emitters,
                    light,
                    surface,
                    1.0,
                    pattern,
                    true,
                    scale,
                    |o, to, t_far, l| {
                        s.shadow.push(o.to_array(), to.to_array(), 0.0, t_far);
                        s.gain.push((r, l * seen.through * weight));
                    },
                );
            }
        }
        rays += self.shadows.transmitted(&s.shadow, &mut s.through, shadow);
        for (&(r, l), &through) in s.gain.iter().zip(&s.through) {
            totals[r as usize] += l * through;
        }
        rays
    }
}

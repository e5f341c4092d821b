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
use super::scatter::offset_origin;
use super::shadow::SeenThrough;
use crate::accel::RayBatch;
use crate::rng::direct_stream;
use crate::sampling::{uniform, uniform_cone_band};
use crate::scene::Scene;
use crate::surface::{Bsdf, Incidence, Transport};
use crate::tally::receiver_grid::Kind;
use crate::tally::ReceiverGrid;
use glam::DVec3;

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
                let cos_hi = 1.0 - (1.0 - cos_half_angle) * band / samples as f64;
                let cos_lo = 1.0 - (1.0 - cos_half_angle) * (band + 1.0) / samples as f64;
                let w = uniform_cone_band(&mut rng, towards_meter, cos_lo, cos_hi);
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
            let x = seen.surface.point;
            let at = Incidence::new(-w, seen.surface.normal.as_dvec3());
            let points = &s.source_points[k * lights..(k + 1) * lights];
            for (light, &point) in points.iter().enumerate() {
                self.emitters
                    .incoming(light, x.as_dvec3(), &[point], |inc| {
                        let wi = inc.direction();
                        let cos = wi.dot(at.facing);
                        let g = bsdf.f_cos(1.0, w, wi, at.n, cos, Transport::Radiance, true);
                        let l = g * inc.normal_lx * seen.through * weight;
                        if !(l > 0.0) {
                            return;
                        }
                        let leave = if cos >= 0.0 { at.facing } else { -at.facing };
                        let origin = offset_origin(x, leave.as_vec3(), reflectors.scene_scale);
                        // Stop just short of a source point: a source on a surface is not
                        // shadowed by it.
                        let t_far = if inc.distance.is_finite() {
                            1.0 - 1e-5
                        } else {
                            f32::INFINITY
                        };
                        let to = inc.to_source.as_vec3();
                        s.shadow.push(origin.to_array(), to.to_array(), 0.0, t_far);
                        s.gain.push((r, l));
                    });
            }
        }
        rays += self.shadows.transmitted(&s.shadow, &mut s.through, shadow);
        for (&(r, l), &through) in s.gain.iter().zip(&s.through) {
            totals[r as usize] += l * through;
        }
        rays
    }
}

//! The photon pass: photons emitted from the lights travel in SoA batches, one bounce
//! per step for the whole batch, through the backend's batched ray calls:
//! emit → intersect → score receivers → deposit on triangles → connect diffuse vertices
//! to next-event receivers → scatter or absorb → shadow rays → compact survivors →
//! repeat.
//!
//! Receivers are scored in one of two ways, never both for the same path:
//! - *track* (analog): a segment scores the cell it crosses;
//! - *next event*: direct light is deterministic ([`direct`]); every diffuse vertex of
//!   every history sends shadow rays to sampled points of the receiver and scores its
//!   expected contribution there; segments that leave a specular interaction (mirror,
//!   glass: not connectable) still score by crossing, and so do diffuse segments that
//!   cross the receiver within its near zone (one cell diagonal from their vertex),
//!   where connections would have unbounded variance.

pub mod bsdf;
pub mod direct;
pub mod emit;
pub mod receiver;
pub mod scatter;

use crate::accel::{HitBatch, RayBatch, RayCaster};
use crate::rng::photon_stream;
use crate::scene::{Estimator, Geometry, Scene};
use crate::tally::{deposit_code, CellPartial, ChunkTally, ReceiverGrid, Tallies};
use bsdf::{Bsdf, LobeKind};
use direct::DirectLight;
use emit::Emitters;
use glam::{DVec3, Vec3};
use rand_pcg::Pcg32;
use scatter::{offset_origin, scatter};

/// Photons traced together as one batch and tallied as one chunk. Chunks are fixed
/// ranges of photon indices, which keeps the merge order independent of threads.
pub const CHUNK_PHOTONS: u64 = 4096;

/// Hard bounce cap for lossless materials (albedo 1), where roulette never ends a path.
pub const MAX_BOUNCES_LOSSLESS: u32 = 100_000;

/// The bounce cap: the number of bounces a photon survives with probability below
/// 1e-12 at the scene's highest albedo, so the cap cannot bias a result visibly
/// (ρ = 0.95 gives 539); never below 64, never above [`MAX_BOUNCES_LOSSLESS`].
pub fn bounce_cap(max_albedo: f64) -> u32 {
    if max_albedo < 1.0 {
        let n = (1e-12f64.ln() / max_albedo.max(1e-300).ln()).ceil();
        n.clamp(64.0, MAX_BOUNCES_LOSSLESS as f64) as u32
    } else {
        MAX_BOUNCES_LOSSLESS
    }
}

/// Everything a worker needs to trace photons; shared read-only by all workers.
pub struct Tracer<'a> {
    caster: &'a dyn RayCaster,
    geometry: &'a Geometry,
    /// BSDF per material.
    bsdfs: Vec<Bsdf>,
    pub emitters: Emitters,
    pub receivers: Vec<ReceiverGrid>,
    seed: u64,
    pub max_bounces: u32,
    /// Largest local coordinate: sizes the ray-origin offset near the frame's origin.
    scene_scale: f32,
    /// How far past a hit a receiver still counts as on the surface hit (m): 10 ppm of
    /// the scene's size, well above f32 hit-distance errors.
    pub receiver_slack: f64,
}

/// Per-worker buffers, reused from chunk to chunk (their contents never affect results).
#[derive(Default)]
pub struct Scratch {
    rays: RayBatch,
    next_rays: RayBatch,
    hits: HitBatch,
    lanes: Vec<Lane>,
    next_lanes: Vec<Lane>,
    /// (photon offset in chunk, cell, score) before folding per history.
    pending: Vec<(u32, u32, f64)>,
    /// Per-cell sums of the chunk's histories while folding.
    cell_acc: Vec<CellPartial>,
    /// Next-event shadow rays of this bounce and what each scores if unoccluded.
    shadow_rays: RayBatch,
    shadow_scores: Vec<(u32, u32, f64)>,
    occluded: Vec<bool>,
}

/// Where a photon's current segment started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Segment {
    /// At a light: its light on next-event receivers is the deterministic direct light.
    Emitted,
    /// At a diffuse or connectable glossy scattering: connected to next-event receivers
    /// beyond their near zone.
    Diffuse,
    /// At a mirror, a refraction or a glossy lobe too sharp to connect.
    Specular,
}

/// A live photon's state besides its ray.
#[derive(Clone)]
struct Lane {
    /// Photon index within the chunk.
    offset: u32,
    /// Surface hits so far (the first is direct light, the rest indirect).
    bounces: u32,
    odd: bool,
    /// Where the current segment started.
    segment: Segment,
    rng: Pcg32,
}

impl<'a> Tracer<'a> {
    /// Prepares the scene; `estimator` overrides every receiver's own choice.
    pub fn new(
        scene: &'a Scene,
        caster: &'a dyn RayCaster,
        seed: u64,
        estimator: Option<Estimator>,
    ) -> Tracer<'a> {
        let g = &scene.geometry;
        let mut first_cell = 0u32;
        let receivers = scene
            .receivers
            .iter()
            .map(|r| {
                let scoring = estimator.unwrap_or(r.estimator).resolved();
                let grid = ReceiverGrid::new(r, g.origin, first_cell, scoring);
                first_cell += grid.cell_count() as u32;
                grid
            })
            .collect();
        let scene_scale = g.local_scale();
        let max_albedo = scene
            .materials
            .iter()
            .map(|m| m.albedo())
            .fold(0.0, f64::max);
        Tracer {
            caster,
            geometry: g,
            bsdfs: scene.materials.iter().map(Bsdf::new).collect(),
            emitters: Emitters::new(scene),
            receivers,
            seed,
            max_bounces: bounce_cap(max_albedo),
            scene_scale,
            receiver_slack: 1e-5 * scene_scale as f64,
        }
    }

    /// Empty tallies for this scene's triangles and receiver cells.
    pub fn new_tallies(&self) -> Tallies {
        let mut t = Tallies::new(self.geometry.triangle_count(), self.cell_count());
        t.dark = !(self.emitters.total_flux_lm > 0.0);
        t
    }

    /// The next-event receivers' direct light, over this tracer's lights and caster.
    pub fn direct_light(&self) -> DirectLight<'_> {
        DirectLight {
            emitters: &self.emitters,
            caster: self.caster,
            slack: self.receiver_slack,
            seed: self.seed,
        }
    }

    /// Total number of receiver cells.
    pub fn cell_count(&self) -> usize {
        self.receivers.iter().map(|r| r.cell_count()).sum()
    }

    /// Traces photons `first .. first + count` to the end of their histories into
    /// `tally` (cleared first; reused from epoch to epoch, so that epochs after the first
    /// allocate nothing).
    pub fn trace_chunk_into(
        &self,
        first: u64,
        count: u32,
        scratch: &mut Scratch,
        tally: &mut ChunkTally,
    ) {
        tally.clear();
        let flux = self.emitters.total_flux_lm;
        scratch.rays.clear();
        scratch.lanes.clear();
        scratch.pending.clear();
        if flux > 0.0 {
            for offset in 0..count {
                let index = first + offset as u64;
                let mut rng = photon_stream(self.seed, index);
                let (o, d) = self
                    .emitters
                    .sample(self.emitters.light_of(index), &mut rng);
                scratch
                    .rays
                    .push(o.as_vec3().into(), d.as_vec3().into(), 0.0, f32::INFINITY);
                scratch.lanes.push(Lane {
                    offset,
                    bounces: 0,
                    odd: index % 2 == 1,
                    segment: Segment::Emitted,
                    rng,
                });
            }
        }
        while !scratch.rays.is_empty() {
            self.caster.intersect(&scratch.rays, &mut scratch.hits);
            tally.rays += scratch.rays.len() as u64;
            self.step(scratch, tally, flux);
            std::mem::swap(&mut scratch.rays, &mut scratch.next_rays);
            std::mem::swap(&mut scratch.lanes, &mut scratch.next_lanes);
        }
        fold_histories(
            &mut scratch.pending,
            &mut scratch.cell_acc,
            &mut tally.scores,
        );
    }

    /// One bounce of every live photon: score, deposit, connect, scatter, compact.
    fn step(&self, s: &mut Scratch, tally: &mut ChunkTally, flux: f64) {
        s.next_rays.clear();
        s.next_lanes.clear();
        s.shadow_rays.clear();
        s.shadow_scores.clear();
        let (rays, hits) = (&s.rays, &s.hits);
        for (k, lane) in s.lanes.iter_mut().enumerate() {
            let origin = DVec3::new(rays.ox[k] as f64, rays.oy[k] as f64, rays.oz[k] as f64);
            let dir = DVec3::new(rays.dx[k] as f64, rays.dy[k] as f64, rays.dz[k] as f64);
            // A receiver lying on a surface (within f32 precision) counts the photons
            // that hit the surface and those that leave it: one placed on a floor
            // measures the floor's illuminance, or its luminance.
            let t_reach = hits.t[k] as f64 + self.receiver_slack;
            for r in &self.receivers {
                let Some(c) = r.crossing(origin, dir, -self.receiver_slack, t_reach) else {
                    continue;
                };
                // Next-event receivers take by crossing only what they do not connect:
                // light from specular interactions, and diffuse light from vertices in
                // their near zone.
                let scores = !r.next_event()
                    || match lane.segment {
                        Segment::Emitted => false,
                        Segment::Specular => true,
                        Segment::Diffuse => c.distance < r.near_zone_m,
                    };
                if scores {
                    s.pending.push((lane.offset, c.cell, c.score_per_lm * flux));
                }
            }
            let Some(surface) = hits.surface(k, self.geometry) else {
                tally.record_history_hits(lane.bounces);
                continue;
            };
            let normal = surface.normal;
            let back_face = dir.dot(normal.as_dvec3()) > 0.0;
            // Unmapped (instanced) objects scatter and occlude but hold no tallies.
            if let Some(tri) = surface.mapped {
                tally
                    .deposits
                    .push(deposit_code(tri, back_face, lane.bounces > 0, lane.odd));
            }
            let p = surface.point;
            let facing = if back_face { -normal } else { normal };
            let material = surface.material as usize;
            let bsdf = &self.bsdfs[material];
            if bsdf.connectable() {
                self.connect(
                    p,
                    normal,
                    -dir,
                    bsdf,
                    lane,
                    flux,
                    &mut s.shadow_rays,
                    &mut s.shadow_scores,
                );
            }
            if lane.bounces >= self.max_bounces {
                tally.killed_by_bounce_cap += 1;
                tally.record_history_hits(lane.bounces + 1);
                continue;
            }
            let Some(sample) = scatter(bsdf, dir, normal.as_dvec3(), &mut lane.rng) else {
                tally.record_history_hits(lane.bounces + 1);
                continue;
            };
            let (new_dir, transmitted) = (sample.dir, sample.transmitted);
            let connected = match sample.kind {
                LobeKind::Diffuse => true,
                LobeKind::Glossy => bsdf.glossy_connectable(),
                LobeKind::Specular => false,
            };
            let o = offset_origin(
                p,
                if transmitted { -facing } else { facing },
                self.scene_scale,
            );
            s.next_rays
                .push(o.into(), new_dir.as_vec3().into(), 0.0, f32::INFINITY);
            s.next_lanes.push(Lane {
                bounces: lane.bounces + 1,
                segment: if connected {
                    Segment::Diffuse
                } else {
                    Segment::Specular
                },
                ..lane.clone()
            });
        }
        if !s.shadow_rays.is_empty() {
            self.caster.occluded(&s.shadow_rays, &mut s.occluded);
            tally.rays += s.shadow_rays.len() as u64;
            for (score, blocked) in s.shadow_scores.iter().zip(&s.occluded) {
                if !blocked {
                    s.pending.push(*score);
                }
            }
        }
    }

    /// Next-event estimation from a diffuse or glossy vertex at `p` (unit geometric
    /// normal `normal`, `wo` towards where the photon came from) to every next-event
    /// receiver: one sampled receiver point ([`ReceiverGrid::connect`]) and its expected
    /// score, w·f(wo, wi)·|cos θ_i| times the connection's factor (w·ρ·cos θ/π for a
    /// Lambertian surface), queued behind a shadow ray. It does not depend on what the
    /// roulette then picks.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn connect(
        &self,
        p: Vec3,
        normal: Vec3,
        wo: DVec3,
        bsdf: &Bsdf,
        lane: &mut Lane,
        flux: f64,
        shadow_rays: &mut RayBatch,
        shadow_scores: &mut Vec<(u32, u32, f64)>,
    ) {
        let n = normal.as_dvec3();
        let facing = if wo.dot(n) >= 0.0 { normal } else { -normal };
        for (r, stratum) in self
            .receivers
            .iter()
            .filter(|r| r.next_event())
            .flat_map(|r| (0..r.connections).map(move |s| (r, s)))
        {
            let Some(c) = r.connect(p.as_dvec3(), stratum, &mut lane.rng) else {
                continue;
            };
            // Near the receiver the connection's 1/d² makes the variance infinite: the
            // photons score those paths by crossing instead (see `step`).
            if c.distance < r.near_zone_m {
                continue;
            }
            let cos_s = c.dir.dot(facing.as_dvec3());
            let side = if cos_s > 0.0 { facing } else { -facing };
            // Intensity of the scattered photon towards the receiver point: Lambertian
            // (written as ever, so diffuse scenes keep their bits) plus glossy.
            let (rho, tau) = bsdf.diffuse();
            let coefficient = if cos_s > 0.0 { rho } else { tau };
            let mut intensity = flux * coefficient * cos_s.abs() * std::f64::consts::FRAC_1_PI;
            if bsdf.glossy_connectable() {
                intensity += flux * bsdf.f_glossy(wo, c.dir, n) * cos_s.abs();
            }
            if intensity.is_nan() || intensity <= 0.0 {
                continue;
            }
            let score = intensity * c.factor / r.connections as f64;
            let o = offset_origin(p, side, self.scene_scale);
            let to_q = (c.point - o.as_dvec3()).as_vec3();
            // Stop just short of the receiver point, which may lie on a surface.
            let t_far = (1.0 - (2.0 * self.receiver_slack / c.distance) as f32).max(0.5);
            shadow_rays.push(o.into(), to_q.into(), 0.0, t_far);
            shadow_scores.push((lane.offset, c.cell, score));
        }
    }
}

/// Sums each photon history's scores per cell (a photon crossing a cell twice scores
/// once, with the sum), so Σx² is over histories as eqs. 6–8 require, then adds the
/// histories of the chunk per cell (in the worker, so the epoch's merge handles one
/// entry per touched cell, not one per history). `acc` is scratch indexed by cell.
fn fold_histories(
    pending: &mut [(u32, u32, f64)],
    acc: &mut Vec<CellPartial>,
    out: &mut Vec<CellPartial>,
) {
    pending.sort_by_key(|&(offset, cell, _)| (offset, cell));
    let mut k = 0;
    while k < pending.len() {
        let (offset, cell, mut x) = pending[k];
        let mut hits = 1;
        k += 1;
        while k < pending.len() && (pending[k].0, pending[k].1) == (offset, cell) {
            x += pending[k].2;
            hits += 1;
            k += 1;
        }
        if acc.len() <= cell as usize {
            acc.resize(cell as usize + 1, CellPartial::default());
        }
        let slot = &mut acc[cell as usize];
        if slot.hits == 0 {
            slot.cell = cell;
            out.push(CellPartial {
                cell,
                ..CellPartial::default()
            });
        }
        slot.add_history(x, hits);
    }
    out.sort_by_key(|p| p.cell);
    for p in out.iter_mut() {
        *p = std::mem::take(&mut acc[p.cell as usize]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounce_cap_cannot_bias_a_bright_room() {
        assert_eq!(bounce_cap(0.95), 539);
        assert!(0.95f64.powi(bounce_cap(0.95) as i32) < 1e-12);
        assert_eq!(bounce_cap(0.0), 64);
        assert_eq!(bounce_cap(1.0), MAX_BOUNCES_LOSSLESS);
    }

    #[test]
    fn histories_fold_per_photon_and_cell() {
        // Photon 1 crosses cell 5 twice (one history score of 4) and cell 2 once.
        let mut pending = vec![(1, 5, 1.0), (0, 5, 2.0), (1, 5, 3.0), (1, 2, 4.0)];
        let (mut acc, mut out) = (Vec::new(), Vec::new());
        fold_histories(&mut pending, &mut acc, &mut out);
        let cell = |cell, hits, m: [f64; 4]| CellPartial {
            cell,
            hits,
            moments: m,
        };
        assert_eq!(
            out,
            vec![
                cell(2, 1, [4.0, 16.0, 64.0, 256.0]),
                cell(5, 3, [6.0, 20.0, 72.0, 272.0])
            ]
        );
        assert!(acc.iter().all(|p| p.hits == 0), "scratch left clean");
    }
}

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
//!   where connections would have unbounded variance. Next events and connections
//!   see through glazing ([`shadow`]: times the panes' T(θ)), so a segment a pane
//!   passes on unbent stays what it was: straight from its source, direct; from a
//!   connected vertex, connected, with its near zone measured from the last pane
//!   (where a connection past a pane then lands within it, the photon scores by
//!   crossing instead).

mod batch;
pub mod bounce_cap;
pub mod direct;
pub mod emit;
pub mod endless;
mod hits;
mod portal_photons;
pub mod receiver_reach;
pub mod reflected;
pub mod scatter;
pub mod shadow;

use crate::accel::{RayBatch, RayCaster};
use crate::rng::{qmc_square, qmc_square_ranked, PhotonStreams, QmcDraw};
use crate::sampling::{cosine_from_square, uniform_f32};
use crate::scene::{Estimator, Geometry, Scene};
use crate::surface::Transport;
use crate::tally::{CellPartial, ChunkTally, ReceiverGrid, Tallies};
pub use batch::Scratch;
use batch::{Lanes, Pass, PortalRule, Segment};
pub use bounce_cap::{
    bounce_cap, bounce_cap_a_priori_bound, bounce_cap_bias_bound, BOUNCE_CAP_BIAS, MAX_BOUNCE_CAP,
};
use direct::DirectLight;
use emit::Emitters;
use glam::{DVec3, Vec3};
use hits::{survival_threshold, Surfacing, TriangleSurface};
pub use hits::{SURFACE_TABLE_BYTES_PER_TRIANGLE, SURFACE_TABLE_MAX_TRIANGLES};
use rand_pcg::Pcg32;
use scatter::{offset_origin, offset_origins};

/// Photons traced together as one batch and tallied as one chunk. Chunks are fixed
/// ranges of photon indices, which keeps the merge order independent of threads.
pub const CHUNK_PHOTONS: u64 = 4096;
const _: () = assert!(CHUNK_PHOTONS.is_multiple_of(1 << crate::rng::QMC_LOG2_BLOCK));

/// Everything a worker needs to trace photons; shared read-only by all workers.
pub struct Tracer<'a> {
    caster: &'a dyn RayCaster,
    /// The next-event receivers' shadow rays (through glazing).
    shadows: shadow::ShadowCaster<'a>,
    geometry: &'a Geometry,
    /// Per mapped triangle, what a hit on it needs ([`TriangleSurface`]); empty for
    /// scenes above [`SURFACE_TABLE_MAX_TRIANGLES`].
    surface_table: Vec<TriangleSurface>,
    /// BSDF and its bounce flags per material.
    surfacings: Vec<Surfacing>,
    /// What luminance meters' reflected direct light reads ([`reflected`]).
    reflectors: reflected::Reflectors,
    pub emitters: Emitters,
    pub receivers: Vec<ReceiverGrid>,
    seed: u64,
    pub max_bounces: u32,
    /// [`bounce_cap_a_priori_bound`] of the scene's highest albedo and the cap.
    pub bounce_cap_a_priori: Option<f64>,
    /// Largest local coordinate: sizes the ray-origin offset near the frame's origin.
    scene_scale: f32,
    /// How far past a hit a receiver still counts as on the surface hit (m): 10 ppm of
    /// the scene's size, well above f32 hit-distance errors.
    pub receiver_slack: f64,
    /// Some receiver connects scattering vertices to itself.
    any_connects: bool,
    /// No receiver connects and every material is a grey Lambertian reflector (the
    /// office, the procedural scene): the hit pass runs its loop without the
    /// connection and the general scattering, a loop small enough to keep its state in
    /// registers.
    lambert_track: bool,
    /// Where each receiver's per-history mean is tallied.
    total_spans: Vec<TotalSpan>,
    /// Some light comes in by portals: each photon index also traces a portal photon,
    /// and exterior vertices spawn photons through them ([`portal_photons`]).
    portals_on: bool,
    /// The scene's portals (local frame), and the outsides of those that have one.
    portals: Vec<crate::light::distant::Portal>,
    exteriors: Vec<portal_photons::Exterior>,
    /// [`Tracer::with_qmc`].
    qmc: bool,
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
        let receivers: Vec<ReceiverGrid> = scene
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
        let surfacings: Vec<Surfacing> = (scene.materials.iter()).map(Surfacing::new).collect();
        let any_connects = receivers.iter().any(|r| r.estimator.connects());
        // The slim loop keeps no segment lane: every bounced photon stays `Emitted`, which
        // only receivers whose direct light is not sampled score by crossing.
        let any_samples_direct = receivers.iter().any(|r| r.estimator.direct_by_replicates());
        let emitters = Emitters::new(scene);
        let portals = (emitters.emitters.iter())
            .map(|e| e.portals().to_vec())
            .find(|p| !p.is_empty())
            .unwrap_or_default();
        let portals_on = !scene.receivers.is_empty() && !portals.is_empty();
        let exteriors = if portals_on {
            portal_photons::exteriors(&portals, caster, scene_scale)
        } else {
            Vec::new()
        };
        // The slim loop's photons all score receivers alike: no portal weights.
        let lambert_track = !any_connects
            && !any_samples_direct
            && !portals_on
            && surfacings.iter().all(|s| s.lambert_only);
        let max_albedo = scene
            .materials
            .iter()
            .map(|m| m.max_albedo())
            .fold(0.0, f64::max);
        // The roulette keeps a photon when a 32-bit draw x < ⌈ρ·2³²⌉: its survival
        // chance, ⌈ρ·2³²⌉·2⁻³² ≥ ρ, is what the cap's bound is taken over (1 for every
        // ρ > 1 − 2⁻³²).
        let survival = survival_threshold(max_albedo) as f64 / 4_294_967_296.0;
        let cap = bounce_cap(survival);
        Tracer {
            caster,
            shadows: shadow::ShadowCaster::new(scene, caster),
            geometry: g,
            surface_table: TriangleSurface::table(g),
            surfacings,
            reflectors: reflected::Reflectors::new(scene),
            emitters,
            seed,
            max_bounces: cap,
            bounce_cap_a_priori: bounce_cap_a_priori_bound(survival, cap),
            scene_scale,
            receiver_slack: 1e-5 * scene_scale as f64,
            any_connects,
            lambert_track,
            total_spans: TotalSpan::of(
                &receivers,
                (scene.receivers.iter())
                    .map(|r| r.excluded_cells(&scene.receivers))
                    .collect(),
            ),
            receivers,
            portals_on,
            portals,
            exteriors,
            qmc: false,
        }
    }

    /// With `qmc`, the emission's directions and the receivers' next-event connection
    /// points are randomised QMC over each block of 2^[`crate::rng::QMC_LOG2_BLOCK`]
    /// photons ([`qmc_square`]; a chunk holds whole blocks): the direction and the first
    /// vertex's connections of a photon are two pairs of one Sobol' point, stratified
    /// together, every later connection a pair of its own. Each block's scores are one
    /// history of the cells' moments ([`Tallies::set_qmc_blocks`]): only blocks are
    /// independent. Receivers whose connection points are QMC's (not the luminance
    /// meters', drawn in their cones) take
    /// [`crate::tally::receiver_grid::qmc_connections_for`] of them. The direct light's
    /// replicates take scrambled Sobol' patterns too ([`Self::direct_light`]).
    pub fn with_qmc(mut self, qmc: bool) -> Self {
        self.qmc = qmc;
        self.emitters = self.emitters.with_qmc(qmc.then_some(self.seed));
        if qmc {
            // Mirrors or glass (not glazing: shadow rays see through it).
            let caustics =
                (self.surfacings.iter()).any(|s| !s.see_through && s.bsdf.scatters_unconnected());
            let stratified = self.emitters.emission_from_square();
            for r in self.receivers.iter_mut().filter(|r| !r.is_luminance()) {
                r.connections = crate::tally::receiver_grid::qmc_connections_for(
                    r.cell_count(),
                    stratified,
                    caustics,
                );
            }
        }
        self
    }

    /// Empty tallies for this scene's triangles and receiver cells.
    pub fn new_tallies(&self) -> Tallies {
        let unit = self.emitters.score_unit;
        let mut t = Tallies::new(self.geometry.triangle_count(), self.tally_slots(), unit);
        t.set_qmc_blocks(self.qmc);
        t.dark = !(self.emitters.total_flux_lm > 0.0);
        t
    }

    /// The next-event receivers' direct light, over this tracer's lights and caster.
    pub fn direct_light(&self) -> DirectLight<'_> {
        DirectLight {
            emitters: &self.emitters,
            shadows: &self.shadows,
            slack: self.receiver_slack,
            seed: self.seed,
            reflectors: Some(&self.reflectors),
            qmc: self.qmc,
        }
    }

    /// Total number of receiver cells.
    pub fn cell_count(&self) -> usize {
        self.receivers.iter().map(|r| r.cell_count()).sum()
    }

    /// The receivers' cells and, after them, one total slot per receiver.
    pub fn tally_slots(&self) -> usize {
        self.cell_count() + self.receivers.len()
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
        // Scores come out in the tallies' score unit: the flux divided by it (a power of
        // two, so every score is the same bits as in lm, scaled exactly).
        let flux = self.emitters.total_flux_lm / self.emitters.score_unit;
        let live = if flux > 0.0 { count as usize } else { 0 };
        self.emit(first, live, scratch);
        // The parity of a photon's index is that of its chunk offset, flipped when the
        // chunk starts at an odd index.
        let odd_first = first % 2 == 1;
        let chunk = (flux, odd_first);
        self.trace_batch(scratch, tally, chunk, Pass::Map);
        if self.portals_on && live > 0 {
            self.emit_portal_photons(first, live, scratch);
            self.trace_batch(scratch, tally, chunk, Pass::Receivers);
            // Spawned photons may spawn others (out through the window, back off the
            // building): rounds of them, as many as a photon's bounces at most.
            for _ in 0..self.max_bounces {
                if !self.load_spawns(scratch) {
                    break;
                }
                self.trace_batch(scratch, tally, chunk, Pass::Receivers);
            }
            scratch.next_spawns.clear();
        }
        if self.qmc {
            // The block is the history: its photons' points are stratified together, so
            // only blocks are independent. Its score is the mean over its photons (a
            // chunk holds whole blocks, and QMC runs trace whole chunks).
            debug_assert!(first.is_multiple_of(CHUNK_PHOTONS) && count as u64 == CHUNK_PHOTONS);
            for (offset, _, x) in scratch.pending.iter_mut() {
                *offset >>= crate::rng::QMC_LOG2_BLOCK;
                *x /= (1u64 << crate::rng::QMC_LOG2_BLOCK) as f64;
            }
        }
        fold_histories(
            &mut scratch.pending,
            &self.total_spans,
            &mut scratch.cell_acc,
            &mut tally.scores,
        );
    }

    /// The batch of the chunk's `live` photons from `first`, as the lights emit them;
    /// with portals, each with its receiver weight 1 until its first segment is known.
    fn emit(&self, first: u64, live: usize, scratch: &mut Scratch) {
        // Every photon ray is a closest-hit ray from t = 0 to ∞: `tnear` and `tfar` are
        // set once here and never change while the batch shrinks.
        let rays = &mut scratch.rays;
        rays.reset_closest_hit(live);
        let lanes = &mut scratch.lanes;
        lanes.truncate(0);
        lanes.bounces = 0;
        lanes.segment.resize(live, Segment::Emitted);
        scratch.pending.clear();
        if self.portals_on {
            lanes.weight.resize(live, 1.0);
            lanes.rule.extend((0..live as u64).map(|k| {
                let light = self.emitters.light_of(first + k);
                if self.emitters.emitters[light].portals().is_empty() {
                    PortalRule::Free
                } else {
                    PortalRule::FromSky
                }
            }));
        }
        lanes.offset.extend(0..live as u32);
        lanes.first = first;
        // Each photon's stream is seeded where its emission draws from it.
        lanes.rng.resize(live, Pcg32::new(0, 0));
        let streams = PhotonStreams::new(self.seed, first);
        let o: [&mut [f32]; 3] = [&mut rays.ox, &mut rays.oy, &mut rays.oz];
        let d: [&mut [f32]; 3] = [&mut rays.dx, &mut rays.dy, &mut rays.dz];
        if self.qmc {
            (self.emitters).sample_lanes_qmc(streams, &mut lanes.rng, o, d);
        } else {
            self.emitters.sample_lanes(streams, &mut lanes.rng, o, d);
        }
        // An emitter that forgot to write a photon's stream back would leave every photon
        // on the placeholder's one stream: plausible results, all correlated.
        debug_assert!(lanes.rng.iter().all(|r| *r != Pcg32::new(0, 0)));
    }

    /// Traces the batch to the end of its histories. `(flux, odd_first)`: the flux a
    /// photon carries, and the parity of the chunk's first photon index.
    fn trace_batch(
        &self,
        scratch: &mut Scratch,
        tally: &mut ChunkTally,
        (flux, odd_first): (f64, bool),
        pass: Pass,
    ) {
        while !scratch.rays.is_empty() {
            self.caster.intersect(&scratch.rays, &mut scratch.hits);
            tally.rays += scratch.rays.len() as u64;
            if self.portals_on {
                self.apply_portal_rules(scratch, pass);
            }
            self.step(scratch, tally, flux, odd_first, pass);
        }
    }

    /// One bounce of every live photon, in short passes over the batch, each a loop the
    /// processor overlaps from lane to lane: score the receivers the segments cross;
    /// look up the surfaces hit; then deposit, connect and play the roulette at each
    /// hit, compacting the survivors in place (lane order kept); then sample the diffuse
    /// survivors' new directions. Each photon draws its random numbers in the order its
    /// own history asks for them, whatever the batch around it.
    fn step(
        &self,
        s: &mut Scratch,
        tally: &mut ChunkTally,
        flux: f64,
        odd_first: bool,
        pass: Pass,
    ) {
        s.shadow_rays.clear();
        s.shadow_scores.clear();
        let n = s.rays.len();
        let t_hit = &s.hits.t[..n];
        for r in &self.receivers {
            self.score_crossings(
                r,
                &s.rays,
                t_hit,
                &s.lanes,
                flux,
                &mut s.marks,
                &mut s.pending,
            );
        }
        s.size_bounce_arrays(n);
        let (survivors, diffuse) = if self.lambert_track {
            self.hits_pass::<true>(s, tally, flux, odd_first, pass)
        } else {
            self.hits_pass::<false>(s, tally, flux, odd_first, pass)
        };
        self.end_bounce(s, tally, survivors, diffuse);
    }

    /// Pass 3 of [`Self::step`]: the `survivors` leave their surfaces, the `diffuse` ones
    /// in new directions; then the bounce's shadow rays are cast and score if unblocked.
    fn end_bounce(
        &self,
        s: &mut Scratch,
        tally: &mut ChunkTally,
        survivors: usize,
        diffuse: usize,
    ) {
        let j = survivors;
        let rays = &mut s.rays;
        let [sx, sy, sz] = &s.side;
        let rngs = &mut s.lanes.rng;
        // In f32 lanes (the directions go straight to the ray caster, which takes f32):
        // each photon's two draws from its own stream, then the branch-free map about
        // the normal of the side it leaves on, which vectorises, then the directions
        // into their slots.
        let m = diffuse;
        let [du, dv] = &mut s.diffuse_draws;
        let (du, dv) = (&mut du[..m], &mut dv[..m]);
        if m == j {
            // Every survivor scatters diffusely (survivor i is in slot i): no gather.
            for ((rng, u), v) in rngs[..m].iter_mut().zip(&mut *du).zip(&mut *dv) {
                *u = uniform_f32(rng);
                *v = uniform_f32(rng);
            }
            let (dx, dy, dz) = (&mut rays.dx[..m], &mut rays.dy[..m], &mut rays.dz[..m]);
            let (sx, sy, sz) = (&sx[..m], &sy[..m], &sz[..m]);
            for i in 0..m {
                let d = cosine_from_square(du[i], dv[i], Vec3::new(sx[i], sy[i], sz[i]));
                (dx[i], dy[i], dz[i]) = (d.x, d.y, d.z);
            }
        } else {
            let [ex, ey, ez] = &mut s.diffuse_dir;
            let (ex, ey, ez) = (&mut ex[..m], &mut ey[..m], &mut ez[..m]);
            for (i, &slot) in s.diffuse_slot[..m].iter().enumerate() {
                let slot = slot as usize;
                let rng = &mut rngs[slot];
                du[i] = uniform_f32(rng);
                dv[i] = uniform_f32(rng);
                // The normal, gathered here, where the map's loop reads it.
                (ex[i], ey[i], ez[i]) = (sx[slot], sy[slot], sz[slot]);
            }
            for i in 0..m {
                let d = cosine_from_square(du[i], dv[i], Vec3::new(ex[i], ey[i], ez[i]));
                (ex[i], ey[i], ez[i]) = (d.x, d.y, d.z);
            }
            for (i, &slot) in s.diffuse_slot[..m].iter().enumerate() {
                let slot = slot as usize;
                (rays.dx[slot], rays.dy[slot], rays.dz[slot]) = (ex[i], ey[i], ez[i]);
            }
        }
        offset_origins(
            [&mut rays.ox[..j], &mut rays.oy[..j], &mut rays.oz[..j]],
            [&sx[..j], &sy[..j], &sz[..j]],
            self.scene_scale,
        );
        rays.truncate(j);
        s.lanes.truncate(j);
        s.lanes.bounces += 1;
        if s.shadow_rays.is_empty() {
            return;
        }
        if !self.shadows.sees_through_glazing() {
            tally.rays += s.shadow_rays.len() as u64;
            self.caster.occluded(&s.shadow_rays, &mut s.occluded);
            for (score, blocked) in s.shadow_scores.iter().zip(&s.occluded) {
                if !blocked {
                    s.pending.push(*score);
                }
            }
            return;
        }
        tally.rays += self
            .shadows
            .transmitted(&s.shadow_rays, &mut s.through, &mut s.shadow);
        let rays = &s.shadow_rays;
        for (k, (&(offset, cell, score), &t)) in s.shadow_scores.iter().zip(&s.through).enumerate()
        {
            // Within the near zone of the last pane's side, the photon's own segment
            // past the pane scores by crossing (`score_crossings`), so this must not.
            let length = Vec3::new(rays.dx[k], rays.dy[k], rays.dz[k]).length();
            let past_pane = (s.shadow.past_last_pane[k] * length) as f64;
            if t > 0.0 && past_pane >= self.receiver_of(cell).near_zone_m {
                s.pending.push((offset, cell, score * t));
            }
        }
    }

    /// The receiver global cell `cell` belongs to.
    fn receiver_of(&self, cell: u32) -> &ReceiverGrid {
        let k = (self.receivers).partition_point(|r| r.first_cell + r.cell_count() as u32 <= cell);
        &self.receivers[k]
    }

    /// Scores receiver `r` for every segment of the batch that crosses it (before the
    /// hits are processed: compaction overwrites the rays). A receiver lying on a
    /// surface (within f32 precision) counts the photons that hit the surface and those
    /// that leave it: one placed on a floor measures the floor's illuminance, or its
    /// luminance. Next-event receivers take by crossing only what they do not connect:
    /// light from specular interactions, and diffuse light from vertices in their near
    /// zone. Each photon's score carries its receiver weight ([`Lanes::weight`]).
    #[allow(clippy::too_many_arguments)]
    fn score_crossings(
        &self,
        r: &ReceiverGrid,
        rays: &RayBatch,
        t_hit: &[f32],
        lanes: &Lanes,
        flux: f64,
        marks: &mut Vec<bool>,
        pending: &mut Vec<(u32, u32, f64)>,
    ) {
        let n = t_hit.len();
        let (ox, oy, oz) = (&rays.ox[..n], &rays.oy[..n], &rays.oz[..n]);
        let (dx, dy, dz) = (&rays.dx[..n], &rays.dy[..n], &rays.dz[..n]);
        let slack = self.receiver_slack;
        r.mark_crossings([ox, oy, oz], [dx, dy, dz], t_hit, slack, marks);
        let (offsets, segments) = (&lanes.offset[..n], &lanes.segment[..n]);
        let (replicates, connects) = (r.estimator.direct_by_replicates(), r.estimator.connects());
        for k in marks.iter().enumerate().filter(|m| *m.1).map(|m| m.0) {
            let origin = DVec3::new(ox[k] as f64, oy[k] as f64, oz[k] as f64);
            let dir = DVec3::new(dx[k] as f64, dy[k] as f64, dz[k] as f64);
            let t_reach = t_hit[k] as f64 + slack;
            let Some(c) = r.crossing(origin, dir, -slack, t_reach) else {
                continue;
            };
            let scores = match segments[k] {
                Segment::Emitted => !replicates,
                Segment::Specular => true,
                Segment::Connectable => !connects || c.distance < r.near_zone_m,
            };
            let w = lanes.weight(k);
            if scores && w > 0.0 {
                pending.push((offsets[k], c.cell, c.score_per_lm * flux * w));
            }
        }
    }

    /// Next-event estimation from a diffuse or glossy vertex at `p` (unit geometric
    /// normal `normal`, `wo` towards where the photon came from) to every next-event
    /// receiver: one sampled receiver point ([`ReceiverGrid::connect`]) and its expected
    /// score, w·f(wo, wi)·|cos θ_i| times the connection's factor (w·ρ·cos θ/π for a
    /// Lambertian surface), queued behind a shadow ray. It does not depend on what the
    /// roulette then picks. `lane` is the photon's offset in the chunk and its stream.
    /// A vertex `lit_directly` (its photon came straight from its source) leaves the
    /// meters that sample reflected direct light to them ([`reflected`]).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn connect(
        &self,
        p: Vec3,
        normal: Vec3,
        wo: DVec3,
        surfacing: &Surfacing,
        (offset, rng): (u32, &mut Pcg32),
        (photon, depth, spawned, rank): (u64, u32, bool, Option<u32>),
        (flux, lit_directly): (f64, bool),
        shadow_rays: &mut RayBatch,
        shadow_scores: &mut Vec<(u32, u32, f64)>,
    ) {
        let bsdf = &surfacing.bsdf;
        let n = normal.as_dvec3();
        let facing = if wo.dot(n) >= 0.0 { normal } else { -normal };
        // A QMC run's first vertex: one point for all its connections, each shifted into
        // its stratum (the point's pair with the emission's direction).
        let first_vertex = depth == 0 && !spawned;
        let mut first_square = None;
        for (k, r, stratum) in self
            .receivers
            .iter()
            .enumerate()
            .filter(|(_, r)| {
                r.estimator.connects() && !(lit_directly && r.samples_reflected_direct())
            })
            .flat_map(|(k, r)| (0..r.connections).map(move |s| (k, r, s)))
        {
            // Luminance meters draw their directions in their cones, not from the points.
            let square = (self.qmc && !r.is_luminance()).then(|| {
                if first_vertex {
                    return *first_square.get_or_insert_with(|| {
                        qmc_square(self.seed, photon, QmcDraw::FirstConnection)
                    });
                }
                let pair = ((depth as u64) << 40) ^ ((k as u64) << 20) ^ stratum as u64;
                let draw = QmcDraw::Padded(pair ^ ((spawned as u64) << 60));
                match rank {
                    Some(rank) => qmc_square_ranked(self.seed, photon, rank, draw),
                    None => qmc_square(self.seed, photon, draw),
                }
            });
            let Some(c) = r.connect(p.as_dvec3(), stratum, square, rng) else {
                continue;
            };
            // Near the receiver the connection's 1/d² makes the variance infinite: the
            // photons score those paths by crossing instead (see `step`).
            if c.distance < r.near_zone_m {
                continue;
            }
            let cos_s = c.dir.dot(facing.as_dvec3());
            let side = if cos_s > 0.0 { facing } else { -facing };
            // Intensity of the scattered photon towards the receiver point: its
            // connectable lobes' flux·f·|cos θ|.
            let intensity = bsdf.f_cos(flux, wo, c.dir, n, cos_s, Transport::Importance, true);
            if intensity.is_nan() || intensity <= 0.0 {
                continue;
            }
            let score = intensity * c.factor / r.connections as f64;
            let o = offset_origin(p, side, self.scene_scale);
            let to_q = (c.point - o.as_dvec3()).as_vec3();
            // Stop just short of the receiver point, which may lie on a surface.
            let t_far = (1.0 - (2.0 * self.receiver_slack / c.distance) as f32).max(0.5);
            shadow_rays.push(o.into(), to_q.into(), 0.0, t_far);
            shadow_scores.push((offset, c.cell, score));
        }
    }
}

/// Where a receiver's per-history total is tallied: its cells `first..end` and the slot
/// after every receiver's cells that holds the histories of its mean over them.
#[derive(Clone, Debug)]
pub struct TotalSpan {
    pub first: u32,
    pub end: u32,
    pub slot: u32,
    /// 1 / cells counted: a history's contribution to the mean over them.
    pub per_cell: f64,
    /// Per cell, whether the mean leaves it out (`exclude`); empty: none.
    pub excluded: std::sync::Arc<[bool]>,
}

impl TotalSpan {
    /// The spans of `receivers`, whose total slots follow all their cells in order;
    /// `excluded` per receiver as [`crate::scene::Receiver::excluded_cells`].
    pub fn of(receivers: &[ReceiverGrid], excluded: Vec<Vec<bool>>) -> Vec<TotalSpan> {
        let cells: u32 = receivers.iter().map(|r| r.cell_count() as u32).sum();
        (receivers.iter().zip(excluded).enumerate())
            .map(|(k, (r, excluded))| {
                let counted = r.cell_count() - excluded.iter().filter(|&&x| x).count();
                TotalSpan {
                    first: r.first_cell,
                    end: r.first_cell + r.cell_count() as u32,
                    slot: cells + k as u32,
                    per_cell: 1.0 / counted as f64,
                    excluded: excluded.into(),
                }
            })
            .collect()
    }

    /// Whether global cell `cell` of this span counts in its mean.
    #[inline]
    fn counts(&self, cell: u32) -> bool {
        self.excluded.is_empty() || !self.excluded[(cell - self.first) as usize]
    }
}

/// Sums each photon history's scores per cell (a photon crossing a cell twice scores
/// once, with the sum), so Σx² is over histories as eqs. 6–8 require, then adds the
/// histories of the chunk per cell (in the worker, so the epoch's merge handles one
/// entry per touched cell, not one per history). Each history's mean over a receiver's
/// cells goes to the receiver's total slot (`spans`), so the receiver mean's variance
/// carries the covariance between its cells. `acc` is scratch indexed by cell.
fn fold_histories(
    pending: &mut [(u32, u32, f64)],
    spans: &[TotalSpan],
    acc: &mut Vec<CellPartial>,
    out: &mut Vec<CellPartial>,
) {
    pending.sort_by_key(|&(offset, cell, _)| (offset, cell));
    // The history being summed over a receiver: (photon offset, span, sum, hits).
    let mut total: Option<(u32, usize, f64, u64)> = None;
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
        add_history(acc, out, cell, x, hits);
        let span = spans.partition_point(|s| s.end <= cell);
        // An excluded cell adds nothing to its receiver's mean.
        let (x, hits) = match spans.get(span) {
            Some(s) if !s.counts(cell) => (0.0, 0),
            _ => (x, hits),
        };
        match &mut total {
            Some((o, s, sum, h)) if *o == offset && *s == span => {
                *sum += x;
                *h += hits;
            }
            _ => {
                if let Some((_, s, sum, h)) = total {
                    add_total(acc, out, &spans[s], sum, h);
                }
                total = (span < spans.len()).then_some((offset, span, x, hits));
            }
        }
    }
    if let Some((_, s, sum, h)) = total {
        add_total(acc, out, &spans[s], sum, h);
    }
    out.sort_by_key(|p| p.cell);
    for p in out.iter_mut() {
        *p = std::mem::take(&mut acc[p.cell as usize]);
    }
}

/// One history's mean over a receiver's counted cells, `sum` from `hits` scores (none
/// when all its scores fell in excluded cells).
#[inline]
fn add_total(
    acc: &mut Vec<CellPartial>,
    out: &mut Vec<CellPartial>,
    span: &TotalSpan,
    sum: f64,
    hits: u64,
) {
    if hits > 0 {
        add_history(acc, out, span.slot, sum * span.per_cell, hits);
    }
}

/// One history's score `x` (from `hits` scores) for `cell`, in the scratch `acc`; a
/// cell's first history lists it in `out`.
#[inline]
fn add_history(
    acc: &mut Vec<CellPartial>,
    out: &mut Vec<CellPartial>,
    cell: u32,
    x: f64,
    hits: u64,
) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The next-event receivers' connections per vertex under QMC, for a bundled scene.
    fn qmc_connections(scene_file: &str) -> (u32, u32, u32) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(scene_file);
        let scene = crate::scene::load(&path).unwrap();
        let caster = crate::accel::build(crate::accel::Backend::Embree, &scene.geometry).unwrap();
        let tracer = Tracer::new(&scene, caster.as_ref(), 1, None).with_qmc(true);
        let r = &tracer.receivers[0];
        let ordinary = crate::tally::receiver_grid::connections_for(r.cell_count());
        let stratified = tracer.emitters.emission_from_square();
        let qmc =
            crate::tally::receiver_grid::qmc_connections_for(r.cell_count(), stratified, false);
        (r.connections, ordinary, qmc)
    }

    #[test]
    fn qmc_adds_connections_unless_mirrors_or_glass_carry_light_to_receivers() {
        let (glass, ordinary, qmc) = qmc_connections("scenes/glass.toml");
        assert!(qmc > ordinary, "the glass floor would otherwise take more");
        assert_eq!(glass, ordinary);
        let (luminaires, ordinary, qmc) = qmc_connections("scenes/luminaires.toml");
        assert!(qmc > ordinary);
        assert_eq!(luminaires, qmc);
    }

    #[test]
    fn histories_fold_per_photon_and_cell() {
        // Photon 1 crosses cell 5 twice (one history score of 4) and cell 2 once.
        let mut pending = vec![(1, 5, 1.0), (0, 5, 2.0), (1, 5, 3.0), (1, 2, 4.0)];
        let (mut acc, mut out) = (Vec::new(), Vec::new());
        fold_histories(&mut pending, &[], &mut acc, &mut out);
        // Cell 2: one history of 4; cell 5: histories of 2 and 4 (mean 3, M₂ = 2, M₃ = 0,
        // M₄ = 2).
        let moments = |n, mean, m2, m4| crate::tally::Moments {
            n,
            mean,
            m2,
            m3: 0.0,
            m4,
        };
        let cell = |cell, hits, moments| CellPartial {
            cell,
            hits,
            moments,
        };
        assert_eq!(
            out,
            vec![
                cell(2, 1, moments(1, 4.0, 0.0, 0.0)),
                cell(5, 3, moments(2, 3.0, 2.0, 2.0))
            ]
        );
        assert!(acc.iter().all(|p| p.hits == 0), "scratch left clean");
    }

    #[test]
    fn each_history_adds_its_mean_over_the_receiver_to_its_total_slot() {
        // Receiver A: cells 0..4 (total slot 6); receiver B: cells 4..6 (slot 7).
        let spans = [
            TotalSpan {
                first: 0,
                end: 4,
                slot: 6,
                per_cell: 0.25,
                excluded: Default::default(),
            },
            TotalSpan {
                first: 4,
                end: 6,
                slot: 7,
                per_cell: 0.5,
                excluded: Default::default(),
            },
        ];
        // Photon 0 scores A twice (cells 1, 3) and B once; photon 1 scores A once.
        let mut pending = vec![(0, 3, 2.0), (1, 2, 8.0), (0, 1, 6.0), (0, 5, 4.0)];
        let (mut acc, mut out) = (Vec::new(), Vec::new());
        fold_histories(&mut pending, &spans, &mut acc, &mut out);
        let slot = |cell| out.iter().find(|p: &&CellPartial| p.cell == cell).unwrap();
        // A's histories: (6 + 2)/4 = 2 and 8/4 = 2; B's: 4/2 = 2.
        assert_eq!(
            (slot(6).moments.n, slot(6).moments.mean, slot(6).hits),
            (2, 2.0, 3)
        );
        assert_eq!(
            (slot(7).moments.n, slot(7).moments.mean, slot(7).hits),
            (1, 2.0, 1)
        );
        assert_eq!(out.len(), 6, "four cells and two totals");
        assert!(acc.iter().all(|p| p.hits == 0), "scratch left clean");
    }
}

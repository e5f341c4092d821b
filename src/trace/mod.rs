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

pub mod direct;
pub mod emit;
pub mod endless;
pub mod receiver_reach;
pub mod scatter;

use crate::accel::{HitBatch, RayBatch, RayCaster, Surface};
use crate::rng::PhotonStreams;
use crate::sampling::{cosine_from_square, uniform_f32};
use crate::scene::{Estimator, Geometry, Scene};
use crate::surface::{Bsdf, LobeKind, Transport};
use crate::tally::{deposit_code, CellPartial, ChunkTally, ReceiverGrid, Tallies};
use direct::DirectLight;
use emit::Emitters;
use glam::{DVec3, Vec3};
use rand::RngCore;
use rand_pcg::Pcg32;
use scatter::{offset_origin, offset_origins, scatter};

/// Photons traced together as one batch and tallied as one chunk. Chunks are fixed
/// ranges of photon indices, which keeps the merge order independent of threads.
pub const CHUNK_PHOTONS: u64 = 4096;

/// The bias the bounce cap is chosen to stay below: ρ_max^cap ≤ 1e-12.
pub const BOUNCE_CAP_BIAS: f64 = 1e-12;

/// The largest bounce cap, used for lossless materials (albedo 1), where roulette never
/// ends a path, and wherever ρ_max is so near 1 that the 1e-12 rule asks for more
/// (ρ_max > 1 − 1.3·10⁻⁵). 2²¹ keeps every history-hit moment exact: a history's hit
/// count k ≤ cap + 1, so Σk⁴ ≤ (cap + 1)³·Σk < 2⁶³·⁰⁰¹·2⁶⁴ < 2¹²⁸ (Σk ≤ the rays cast, a
/// u64), and k³ < 2⁶⁴.
pub const MAX_BOUNCE_CAP: u32 = 1 << 21;

/// The bounce cap: the number of bounces a photon survives with probability at most
/// [`BOUNCE_CAP_BIAS`] at the scene's highest albedo ρ_max, ⌈ln 10⁻¹² / ln ρ_max⌉
/// (ρ = 0.95 gives 539, ρ = 0.99995 gives 552,607); never below 64, never above
/// [`MAX_BOUNCE_CAP`] (the cap for ρ_max = 1).
pub fn bounce_cap(max_albedo: f64) -> u32 {
    if max_albedo < 1.0 {
        let n = (libm::log(BOUNCE_CAP_BIAS) / libm::log(max_albedo.max(1e-300))).ceil();
        n.clamp(64.0, MAX_BOUNCE_CAP as f64) as u32
    } else {
        MAX_BOUNCE_CAP
    }
}

/// The a-priori bound on the share of the light a cap of `cap` bounces drops at the
/// scene's highest albedo ρ_max < 1: ρ_max^cap (docs/method.md, *Bounce cap*); `None`
/// for lossless materials (ρ_max ≥ 1), where no a-priori bound exists.
pub fn bounce_cap_a_priori_bound(max_albedo: f64, cap: u32) -> Option<f64> {
    (max_albedo < 1.0).then(|| libm::exp(cap as f64 * libm::log(max_albedo.max(0.0))))
}

/// −ln 0.05: no photon of N stopped by the cap bounds the chance that one is by
/// −ln(0.05)/N ≈ 3/N at 95 % confidence (1 − 0.05^(1/N) ≤ −ln(0.05)/N).
const NONE_IN_N_95: f64 = 2.995_732_273_553_991;

/// `bounce_cap_bias_bound` of summary.json: the largest share of the light the cap can
/// have dropped, from the a-priori bound ρ_max^cap (`a_priori`, see
/// [`bounce_cap_a_priori_bound`]) and, when no photon of `photons` was stopped by the
/// cap (`killed` = 0), the 95 % bound −ln(0.05)/N on the share of the emitted flux it
/// stops; the smaller of the two. `None` (unknown) for lossless materials once a photon
/// was stopped, or before any photon.
pub fn bounce_cap_bias_bound(a_priori: Option<f64>, killed: u64, photons: u64) -> Option<f64> {
    let observed = (killed == 0 && photons > 0).then(|| NONE_IN_N_95 / photons as f64);
    match (a_priori, observed) {
        (Some(a), Some(o)) => Some(a.min(o)),
        (a, o) => a.or(o),
    }
}

/// Everything a worker needs to trace photons; shared read-only by all workers.
pub struct Tracer<'a> {
    caster: &'a dyn RayCaster,
    geometry: &'a Geometry,
    /// Per mapped triangle, what a hit on it needs ([`TriangleSurface`]); empty for
    /// scenes above [`SURFACE_TABLE_MAX_TRIANGLES`].
    surface_table: Vec<TriangleSurface>,
    /// BSDF and its bounce flags per material.
    surfacings: Vec<Surfacing>,
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
}

/// Per-worker buffers, reused from chunk to chunk (their contents never affect results).
#[derive(Default)]
pub struct Scratch {
    /// The live photons' rays: survivors are compacted in place after every bounce, in
    /// lane order, so the batch never changes order and nothing is copied twice.
    rays: RayBatch,
    hits: HitBatch,
    lanes: Lanes,
    /// (photon offset in chunk, cell, score) before folding per history.
    pending: Vec<(u32, u32, f64)>,
    /// Per-cell sums of the chunk's histories while folding.
    cell_acc: Vec<CellPartial>,
    /// Next-event shadow rays of this bounce and what each scores if unoccluded.
    shadow_rays: RayBatch,
    shadow_scores: Vec<(u32, u32, f64)>,
    occluded: Vec<bool>,
    /// Diffuse survivors of a bounce, whose directions are sampled in a pass of their
    /// own (f32 lanes): their slots in the batch (each scatters into the hemisphere of
    /// its `side`), their two random numbers and their new directions.
    diffuse_slot: Vec<u32>,
    diffuse_draws: [Vec<f32>; 2],
    diffuse_dir: [Vec<f32>; 3],
    /// Which segments of the batch cross the receiver being scored.
    marks: Vec<bool>,
    /// Per survivor, the normal of the side it leaves its surface on.
    side: [Vec<f32>; 3],
}

impl Scratch {
    /// Sizes the per-bounce arrays of pass 2 and 3 for `n` lanes.
    fn size_bounce_arrays(&mut self, n: usize) {
        if self.diffuse_slot.len() < n {
            self.diffuse_slot.resize(n, 0);
        }
        for v in (self.side.iter_mut())
            .chain(&mut self.diffuse_draws)
            .chain(&mut self.diffuse_dir)
        {
            if v.len() < n {
                v.resize(n, 0.0);
            }
        }
    }
}

/// Where a photon's current segment started.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
enum Segment {
    /// At a light: its light on next-event receivers is the deterministic direct light.
    #[default]
    Emitted,
    /// At a diffuse or connectable glossy scattering: connected to next-event receivers
    /// beyond their near zone.
    Connectable,
    /// At a mirror, a refraction or a glossy lobe too sharp to connect.
    Specular,
}

impl Segment {
    /// The segment a scattering of `kind` starts: connected (diffuse, or glossy where
    /// the material's glossy lobe connects) or specular.
    fn after(kind: LobeKind, glossy_connectable: bool) -> Segment {
        let connected = match kind {
            LobeKind::Diffuse => true,
            LobeKind::Glossy => glossy_connectable,
            LobeKind::Specular => false,
        };
        if connected {
            Segment::Connectable
        } else {
            Segment::Specular
        }
    }
}

/// The live photons' state besides their rays, structure of arrays in ray order.
#[derive(Default)]
struct Lanes {
    /// Photon index within the chunk.
    offset: Vec<u32>,
    /// Surface hits so far (the first is direct light, the rest indirect): the same for
    /// every live photon, since all start together and each bounce ends or advances
    /// every one of them.
    bounces: u32,
    /// Where the current segment started.
    segment: Vec<Segment>,
    rng: Vec<Pcg32>,
}

impl Lanes {
    fn truncate(&mut self, n: usize) {
        self.offset.truncate(n);
        self.segment.truncate(n);
        self.rng.truncate(n);
    }
}

/// The lanes a bounce's survivors are compacted into, in place: survivor `j` is written
/// from lane `k ≥ j`, so a lane is read before anything overwrites it.
struct SurvivorLanes<'a> {
    origin: [&'a mut [f32]; 3],
    /// The normal of the side the survivor leaves its surface on.
    side: [&'a mut [f32]; 3],
    offset: &'a mut [u32],
    segment: &'a mut [Segment],
    rng: &'a mut [Pcg32],
}

impl<'a> SurvivorLanes<'a> {
    /// The first `n` lanes of a batch's origins, survivors' sides and photon lanes.
    fn of(
        n: usize,
        (ox, oy, oz): (&'a mut [f32], &'a mut [f32], &'a mut [f32]),
        [sx, sy, sz]: &'a mut [Vec<f32>; 3],
        lanes: &'a mut Lanes,
    ) -> Self {
        SurvivorLanes {
            origin: [&mut ox[..n], &mut oy[..n], &mut oz[..n]],
            side: [&mut sx[..n], &mut sy[..n], &mut sz[..n]],
            offset: &mut lanes.offset[..n],
            segment: &mut lanes.segment[..n],
            rng: &mut lanes.rng[..n],
        }
    }

    /// Survivor `j`: it leaves `point` on the `side` of its surface.
    #[inline(always)]
    fn write(
        &mut self,
        j: usize,
        point: Vec3,
        side: Vec3,
        offset: u32,
        segment: Segment,
        rng: Pcg32,
    ) {
        self.write_unsegmented(j, point, side, offset, rng);
        self.segment[j] = segment;
    }

    /// [`Self::write`] leaving the segment lane as it is: for a pass whose segments no
    /// receiver reads ([`Tracer::lambert_track`]).
    #[inline(always)]
    fn write_unsegmented(&mut self, j: usize, point: Vec3, side: Vec3, offset: u32, rng: Pcg32) {
        let [ox, oy, oz] = &mut self.origin;
        (ox[j], oy[j], oz[j]) = (point.x, point.y, point.z);
        let [sx, sy, sz] = &mut self.side;
        (sx[j], sy[j], sz[j]) = (side.x, side.y, side.z);
        self.offset[j] = offset;
        self.rng[j] = rng;
    }
}

/// A photon's hit as pass 2's kernels read it.
struct Hit<'s> {
    /// Its lane in the batch.
    k: usize,
    /// Photon index within the chunk.
    offset: u32,
    point: Vec3,
    /// The geometric normal on the side the photon arrived from.
    facing: Vec3,
    /// The photon's unit direction and the surface's unit geometric normal.
    dir: DVec3,
    normal: DVec3,
    surfacing: &'s Surfacing,
}

/// How far pass 2 has written each of its outputs: histories that end at this bounce
/// (rays that left the scene; photons absorbed or stopped by the bounce cap),
/// survivors (lane k's successor is written at j ≤ k), diffuse survivors' slots and
/// deposits.
#[derive(Clone, Copy, Default)]
struct HitCursors {
    escaped: u64,
    ended: u64,
    survivors: usize,
    diffuse: usize,
    deposits: usize,
}

/// What pass 2 writes: the survivors compacted in place with their new directions (the
/// general kernel's; the diffuse ones' come in pass 3), the slots of the diffuse
/// survivors, the hits' deposits, and how far each is written.
struct HitsOut<'a> {
    survivors: SurvivorLanes<'a>,
    dir: [&'a mut [f32]; 3],
    /// Written for every hit and kept by advancing the cursor where the triangle holds
    /// a map: no branch.
    deposits: &'a mut [u32],
    /// Written for every Lambertian hit and kept by advancing the cursor, so the
    /// roulette is no branch.
    diffuse_slot: &'a mut [u32],
    cursors: HitCursors,
}

impl HitsOut<'_> {
    #[inline(always)]
    fn deposit(&mut self, code: u32, kept: bool) {
        self.deposits[self.cursors.deposits] = code;
        self.cursors.deposits += kept as usize;
    }

    /// The kernel of a grey Lambertian reflector in a pass no receiver reads segments
    /// of ([`Tracer::lambert_track`]): the [`Self::lambertian`] roulette with less to
    /// keep: every survivor scatters diffusely (so survivor j is diffuse survivor j,
    /// and pass 3 reads no slots), a hit that is not kept ended (counted after the
    /// loop), and the segment lane is left as it is: with no receiver connecting,
    /// every segment scores by crossing whatever it started at.
    #[inline(always)]
    fn lambert_track(&mut self, hit: &Hit) {
        let j = self.cursors.survivors;
        let mut rng = self.survivors.rng[hit.k].clone();
        let survives = (rng.next_u32() as u64) < hit.surfacing.survives_below;
        self.survivors
            .write_unsegmented(j, hit.point, hit.facing, hit.offset, rng);
        self.cursors.survivors += survives as usize;
    }

    /// The kernel of a material whose only lobe is diffuse reflection: `Bsdf::sample`'s
    /// roulette and diffuse lobe, the same draws (the direction's in f32 in pass 3,
    /// into the hemisphere the photon arrived from). The slot is written whatever the
    /// roulette says and kept if the photon survives. The stream is copied before its
    /// draw: a 16-byte load of what the draw just stored 8 bytes of would wait for it.
    #[inline(always)]
    fn lambertian(&mut self, hit: &Hit) {
        let c = &mut self.cursors;
        let j = c.survivors;
        let mut rng = self.survivors.rng[hit.k].clone();
        let survives = (rng.next_u32() as u64) < hit.surfacing.survives_below;
        let (point, facing) = (hit.point, hit.facing);
        self.survivors
            .write(j, point, facing, hit.offset, Segment::Connectable, rng);
        self.diffuse_slot[c.diffuse] = j as u32;
        let kept = survives as usize;
        c.ended += !survives as u64;
        c.survivors += kept;
        c.diffuse += kept;
    }

    /// The kernel of any other material: the BSDF's roulette over its lobes
    /// ([`scatter`]), the new direction written here.
    #[inline(always)]
    fn general(&mut self, hit: &Hit) {
        let mut rng = self.survivors.rng[hit.k].clone();
        let Some(sample) = scatter(&hit.surfacing.bsdf, hit.dir, hit.normal, &mut rng) else {
            self.cursors.ended += 1;
            return;
        };
        let j = self.cursors.survivors;
        let side = if sample.transmitted {
            -hit.facing
        } else {
            hit.facing
        };
        let w = sample.dir.as_vec3();
        let [dx, dy, dz] = &mut self.dir;
        (dx[j], dy[j], dz[j]) = (w.x, w.y, w.z);
        let segment = Segment::after(sample.kind, hit.surfacing.glossy_connectable);
        self.survivors
            .write(j, hit.point, side, hit.offset, segment, rng);
        self.cursors.survivors += 1;
    }
}

/// Scenes up to this many triangles get a [`TriangleSurface`] table (≤ 2.6 MB): on a
/// small scene the hit's surface lookup is a chain of dependent loads (triangle →
/// vertex indices → vertices) that dominates the tracer's own work; on a large one the
/// table would cost 40 B per triangle, against the memory goal, where cache misses in
/// the ray caster dominate anyway.
pub const SURFACE_TABLE_MAX_TRIANGLES: usize = 1 << 16;

/// Bytes per triangle of that table (`limits` counts it in a run's memory).
pub const SURFACE_TABLE_BYTES_PER_TRIANGLE: usize = std::mem::size_of::<TriangleSurface>();

/// A triangle's first vertex, its two edges from it and its material, for
/// [`Surface::mapped`] (as [`crate::accel::HitBatch::surface`] calls it: the same bits),
/// one load from the triangle id instead of two dependent ones.
#[derive(Clone, Copy, Debug)]
struct TriangleSurface {
    a: Vec3,
    e1: Vec3,
    e2: Vec3,
    material: u32,
}

impl TriangleSurface {
    /// The table for `g`, or an empty one above [`SURFACE_TABLE_MAX_TRIANGLES`].
    fn table(g: &Geometry) -> Vec<TriangleSurface> {
        if g.triangle_count() > SURFACE_TABLE_MAX_TRIANGLES {
            return Vec::new();
        }
        (g.triangles.iter().enumerate())
            .map(|(t, tri)| {
                let [a, b, c] = tri.map(|i| g.vertices[i as usize]);
                TriangleSurface {
                    a,
                    e1: b - a,
                    e2: c - a,
                    material: g.material.get(t),
                }
            })
            .collect()
    }
}

/// What the photon pass needs of a material, looked up once per hit: the BSDF and the
/// flags that decide its path through a bounce, so the common case (a grey Lambertian
/// reflector) skips the general lobe roulette.
#[derive(Clone, Debug)]
struct Surfacing {
    bsdf: Bsdf,
    /// Connected to next-event receivers ([`Bsdf::connectable`]).
    connectable: bool,
    /// Its glossy lobes are connected ([`Bsdf::glossy_connectable`]).
    glossy_connectable: bool,
    /// Diffuse reflection is its only lobe: the roulette is one comparison with ρ
    /// (the same number [`Bsdf::sample`] draws and compares, so the same path).
    lambert_only: bool,
    /// A photon survives that roulette when its 32-bit draw x is below this:
    /// x < ⌈ρ·2³²⌉ ⇔ x·2⁻³² < ρ, [`crate::sampling::uniform`]'s comparison, in integers.
    survives_below: u64,
}

impl Surfacing {
    fn new(bsdf: Bsdf) -> Surfacing {
        Surfacing {
            connectable: bsdf.connectable(),
            glossy_connectable: bsdf.glossy_connectable(),
            lambert_only: bsdf.lambert_only(),
            survives_below: survival_threshold(bsdf.diffuse().0),
            bsdf,
        }
    }
}

/// ⌈ρ·2³²⌉: for every 32-bit x, x < it exactly when x·2⁻³² < ρ (both sides exact in
/// f64: ρ·2³² is ρ scaled by a power of two, x·2⁻³² a 32-bit integer scaled).
fn survival_threshold(rho: f64) -> u64 {
    (rho.clamp(0.0, 1.0) * 4_294_967_296.0).ceil() as u64
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
        let surfacings: Vec<Surfacing> = (scene.materials.iter())
            .map(|m| Surfacing::new(Bsdf::new(m)))
            .collect();
        let any_connects = receivers.iter().any(|r| r.estimator.connects());
        // The slim loop keeps no segment lane: every bounced photon stays `Emitted`, which
        // only receivers whose direct light is not sampled score by crossing.
        let any_samples_direct = receivers.iter().any(|r| r.estimator.direct_by_replicates());
        let lambert_track =
            !any_connects && !any_samples_direct && surfacings.iter().all(|s| s.lambert_only);
        let max_albedo = scene
            .materials
            .iter()
            .map(|m| m.albedo())
            .fold(0.0, f64::max);
        // The roulette keeps a photon when a 32-bit draw x < ⌈ρ·2³²⌉: its survival
        // chance, ⌈ρ·2³²⌉·2⁻³² ≥ ρ, is what the cap's bound is taken over (1 for every
        // ρ > 1 − 2⁻³²).
        let survival = survival_threshold(max_albedo) as f64 / 4_294_967_296.0;
        let cap = bounce_cap(survival);
        Tracer {
            caster,
            geometry: g,
            surface_table: TriangleSurface::table(g),
            surfacings,
            emitters: Emitters::new(scene),
            seed,
            max_bounces: cap,
            bounce_cap_a_priori: bounce_cap_a_priori_bound(survival, cap),
            scene_scale,
            receiver_slack: 1e-5 * scene_scale as f64,
            any_connects,
            lambert_track,
            receivers,
        }
    }

    /// Empty tallies for this scene's triangles and receiver cells.
    pub fn new_tallies(&self) -> Tallies {
        let unit = self.emitters.score_unit;
        let mut t = Tallies::new(self.geometry.triangle_count(), self.cell_count(), unit);
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
        // Scores come out in the tallies' score unit: the flux divided by it (a power of
        // two, so every score is the same bits as in lm, scaled exactly).
        let flux = self.emitters.total_flux_lm / self.emitters.score_unit;
        let live = if flux > 0.0 { count as usize } else { 0 };
        // Every photon ray is a closest-hit ray from t = 0 to ∞: `tnear` and `tfar` are
        // set once here and never change while the batch shrinks.
        let rays = &mut scratch.rays;
        rays.reset_closest_hit(live);
        let lanes = &mut scratch.lanes;
        lanes.truncate(0);
        lanes.bounces = 0;
        lanes.segment.resize(live, Segment::Emitted);
        scratch.pending.clear();
        lanes.offset.extend(0..live as u32);
        // Each photon's stream is seeded where its emission draws from it.
        lanes.rng.resize(live, Pcg32::new(0, 0));
        let streams = PhotonStreams::new(self.seed, first);
        self.emitters.sample_lanes(
            streams,
            &mut lanes.rng,
            [&mut rays.ox, &mut rays.oy, &mut rays.oz],
            [&mut rays.dx, &mut rays.dy, &mut rays.dz],
        );
        // An emitter that forgot to write a photon's stream back would leave every photon
        // on the placeholder's one stream: plausible results, all correlated.
        debug_assert!(lanes.rng.iter().all(|r| *r != Pcg32::new(0, 0)));
        // The parity of a photon's index is that of its chunk offset, flipped when the
        // chunk starts at an odd index.
        let odd_first = first % 2 == 1;
        while !scratch.rays.is_empty() {
            self.caster.intersect(&scratch.rays, &mut scratch.hits);
            tally.rays += scratch.rays.len() as u64;
            self.step(scratch, tally, flux, odd_first);
        }
        fold_histories(
            &mut scratch.pending,
            &mut scratch.cell_acc,
            &mut tally.scores,
        );
    }

    /// One bounce of every live photon, in short passes over the batch, each a loop the
    /// processor overlaps from lane to lane: score the receivers the segments cross;
    /// look up the surfaces hit; then deposit, connect and play the roulette at each
    /// hit, compacting the survivors in place (lane order kept); then sample the diffuse
    /// survivors' new directions. Each photon draws its random numbers in the order its
    /// own history asks for them, whatever the batch around it.
    fn step(&self, s: &mut Scratch, tally: &mut ChunkTally, flux: f64, odd_first: bool) {
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
            self.hits_pass::<true>(s, tally, flux, odd_first)
        } else {
            self.hits_pass::<false>(s, tally, flux, odd_first)
        };
        self.end_bounce(s, tally, survivors, diffuse);
    }

    /// Pass 2 of [`Self::step`]: deposit, connect and play the roulette at each hit,
    /// compacting the survivors in place. Returns how many survive and how many of them
    /// scatter diffusely (their slots in `s.diffuse_slot`). Each hit goes to the kernel
    /// of its surface class ([`HitsOut::lambert_track`], [`HitsOut::lambertian`],
    /// [`HitsOut::general`]), as pbrt's wavefront integrator gives each material its own.
    /// `LAMBERT_TRACK`: [`Tracer::lambert_track`], which removes the connection and
    /// the other kernels from the loop at compile time (the same numbers).
    fn hits_pass<const LAMBERT_TRACK: bool>(
        &self,
        s: &mut Scratch,
        tally: &mut ChunkTally,
        flux: f64,
        odd_first: bool,
    ) -> (usize, usize) {
        let (n, hits, rays) = (s.rays.len(), &s.hits, &mut s.rays);
        // Every live photon has hit as often: the first hit is direct light.
        let hit_bounces = s.lanes.bounces;
        let (indirect, capped) = (hit_bounces > 0, hit_bounces >= self.max_bounces);
        let first_deposit = tally.deposits.len();
        tally.deposits.resize(first_deposit + n, 0);
        let mut out = HitsOut {
            survivors: SurvivorLanes::of(
                n,
                (&mut rays.ox, &mut rays.oy, &mut rays.oz),
                &mut s.side,
                &mut s.lanes,
            ),
            dir: [&mut rays.dx[..n], &mut rays.dy[..n], &mut rays.dz[..n]],
            deposits: &mut tally.deposits[first_deposit..],
            diffuse_slot: &mut s.diffuse_slot[..n],
            cursors: HitCursors::default(),
        };
        // The hits, sliced to the batch: no bounds check in the loop.
        let (hit_tri, hit_u, hit_v) = (&hits.tri[..n], &hits.u[..n], &hits.v[..n]);
        let (ngx, ngy, ngz) = (&hits.ngx[..n], &hits.ngy[..n], &hits.ngz[..n]);
        for k in 0..n {
            let tri = hit_tri[k];
            let surface = if let Some(row) = self.surface_table.get(tri as usize) {
                let normal = Vec3::new(ngx[k], ngy[k], ngz[k]);
                let (corner, uv) = ([row.a, row.e1, row.e2], (hit_u[k], hit_v[k]));
                Surface::mapped(tri, corner, row.material, uv, normal)
            } else if let Some(surface) = hits.surface(k, self.geometry) {
                surface
            } else {
                out.cursors.escaped += 1;
                continue;
            };
            let [dx, dy, dz] = &out.dir;
            let dir = DVec3::new(dx[k] as f64, dy[k] as f64, dz[k] as f64);
            let offset = out.survivors.offset[k];
            let normal = surface.normal;
            let back_face = dir.dot(normal.as_dvec3()) > 0.0;
            // Unmapped (instanced) objects scatter and occlude but hold no tallies.
            let (tri, has_map) = (surface.mapped.unwrap_or(0), surface.mapped.is_some());
            let odd = (offset % 2 == 1) != odd_first;
            out.deposit(deposit_code(tri, back_face, indirect, odd), has_map);
            let surfacing = &self.surfacings[surface.material as usize];
            if !LAMBERT_TRACK && self.any_connects && surfacing.connectable {
                self.connect(
                    surface.point,
                    normal,
                    -dir,
                    surfacing,
                    (offset, &mut out.survivors.rng[k]),
                    flux,
                    &mut s.shadow_rays,
                    &mut s.shadow_scores,
                );
            }
            if capped {
                tally.killed_by_bounce_cap += 1;
                out.cursors.ended += 1;
                continue;
            }
            let hit = Hit {
                k,
                offset,
                point: surface.point,
                facing: if back_face { -normal } else { normal },
                dir,
                normal: normal.as_dvec3(),
                surfacing,
            };
            if LAMBERT_TRACK {
                out.lambert_track(&hit);
            } else if surfacing.lambert_only {
                out.lambertian(&hit);
            } else {
                out.general(&hit);
            }
        }
        let c = out.cursors;
        let (survivors, diffuse, ended) = if LAMBERT_TRACK && !capped {
            // Each hit escaped, survived or ended; every survivor scatters diffusely.
            let ended = (n - c.survivors) as u64 - c.escaped;
            (c.survivors, c.survivors, ended)
        } else {
            (c.survivors, c.diffuse, c.ended)
        };
        tally.deposits.truncate(first_deposit + c.deposits);
        tally.record_histories(hit_bounces, c.escaped);
        tally.record_histories(hit_bounces + 1, ended);
        (survivors, diffuse)
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

    /// Scores receiver `r` for every segment of the batch that crosses it (before the
    /// hits are processed: compaction overwrites the rays). A receiver lying on a
    /// surface (within f32 precision) counts the photons that hit the surface and those
    /// that leave it: one placed on a floor measures the floor's illuminance, or its
    /// luminance. Next-event receivers take by crossing only what they do not connect:
    /// light from specular interactions, and diffuse light from vertices in their near
    /// zone.
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
            if scores {
                pending.push((offsets[k], c.cell, c.score_per_lm * flux));
            }
        }
    }

    /// Next-event estimation from a diffuse or glossy vertex at `p` (unit geometric
    /// normal `normal`, `wo` towards where the photon came from) to every next-event
    /// receiver: one sampled receiver point ([`ReceiverGrid::connect`]) and its expected
    /// score, w·f(wo, wi)·|cos θ_i| times the connection's factor (w·ρ·cos θ/π for a
    /// Lambertian surface), queued behind a shadow ray. It does not depend on what the
    /// roulette then picks. `lane` is the photon's offset in the chunk and its stream.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn connect(
        &self,
        p: Vec3,
        normal: Vec3,
        wo: DVec3,
        surfacing: &Surfacing,
        (offset, rng): (u32, &mut Pcg32),
        flux: f64,
        shadow_rays: &mut RayBatch,
        shadow_scores: &mut Vec<(u32, u32, f64)>,
    ) {
        let bsdf = &surfacing.bsdf;
        let n = normal.as_dvec3();
        let facing = if wo.dot(n) >= 0.0 { normal } else { -normal };
        for (r, stratum) in self
            .receivers
            .iter()
            .filter(|r| r.estimator.connects())
            .flat_map(|r| (0..r.connections).map(move |s| (r, s)))
        {
            let Some(c) = r.connect(p.as_dvec3(), stratum, rng) else {
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
        assert_eq!(bounce_cap(1.0), MAX_BOUNCE_CAP);
        assert_eq!(bounce_cap_a_priori_bound(1.0, MAX_BOUNCE_CAP), None);
        assert_eq!(bounce_cap_a_priori_bound(0.0, 64), Some(0.0));
    }

    #[test]
    fn bounce_cap_follows_the_albedo_past_the_old_ceiling() {
        // ρ = 0.99995: 1/(1 − ρ) = 20,000 bounces on average; the old ceiling of 100,000
        // dropped e⁻⁵ ≈ 0.67 % of the light. The cap is the least n with ρⁿ ≤ 1e-12.
        for rho in [0.99995f64, 0.9999, 0.999] {
            let cap = bounce_cap(rho);
            let bound = bounce_cap_a_priori_bound(rho, cap).unwrap();
            assert!(bound <= BOUNCE_CAP_BIAS * (1.0 + 1e-9), "ρ {rho}: {bound}");
            assert!(
                libm::pow(rho, cap as f64 - 1.0) > BOUNCE_CAP_BIAS,
                "ρ {rho}: not the least"
            );
            assert!((bound - libm::pow(rho, cap as f64)).abs() <= 1e-9 * bound);
        }
        assert_eq!(bounce_cap(0.99995), 552_607);
        assert!(bounce_cap(0.99995) > 100_000);
        // Past what the moments hold: the largest cap, its bound ρ^cap no longer tiny.
        let rho = 1.0 - 1e-7;
        assert_eq!(bounce_cap(rho), MAX_BOUNCE_CAP);
        let b = bounce_cap_a_priori_bound(rho, MAX_BOUNCE_CAP).unwrap();
        assert!((b - libm::exp(-0.2097152f64)).abs() < 1e-6, "{b}");
    }

    #[test]
    fn bias_bound_is_a_priori_or_from_no_photon_capped() {
        // Lossless: unknown once a photon was capped (or before any photon) …
        assert_eq!(bounce_cap_bias_bound(None, 1, 1000), None);
        assert_eq!(bounce_cap_bias_bound(None, 0, 0), None);
        // … else −ln(0.05)/N, which bounds 1 − 0.05^(1/N), the exact 95 % bound.
        let b = bounce_cap_bias_bound(None, 0, 1000).unwrap();
        assert!((b - 2.995_732_273_553_991e-3).abs() < 1e-15);
        assert!(1.0 - libm::pow(0.05f64, 1.0 / 1000.0) <= b);
        // A priori: kept whatever was capped; the smaller one when none was.
        assert_eq!(bounce_cap_bias_bound(Some(1e-12), 3, 1000), Some(1e-12));
        assert_eq!(bounce_cap_bias_bound(Some(0.5), 0, 1000), Some(b));
        assert_eq!(bounce_cap_bias_bound(Some(0.5), 2, 1000), Some(0.5));
    }

    #[test]
    fn integer_roulette_is_the_float_comparison() {
        // x < ⌈ρ·2³²⌉ ⇔ x·2⁻³² < ρ for every 32-bit x: checked at the threshold and its
        // neighbours, for ρ at the ends, at powers of two and at odd values.
        for rho in [0.0, 1e-12, 0.3, 0.5, 0.7, 0.95, 1.0 - 1e-12, 1.0] {
            let t = survival_threshold(rho);
            let mid = t.min(u32::MAX as u64) as i64;
            for x in (mid - 3..=mid + 3).filter(|x| (0..=u32::MAX as i64).contains(x)) {
                let float = x as f64 * (1.0 / 4_294_967_296.0) < rho;
                assert_eq!((x as u64) < t, float, "ρ {rho}, x {x}");
            }
            assert_eq!(0 < t, rho > 0.0);
        }
        assert_eq!(
            survival_threshold(1.0),
            1 << 32,
            "ρ = 1: every photon survives"
        );
    }

    #[test]
    fn histories_fold_per_photon_and_cell() {
        // Photon 1 crosses cell 5 twice (one history score of 4) and cell 2 once.
        let mut pending = vec![(1, 5, 1.0), (0, 5, 2.0), (1, 5, 3.0), (1, 2, 4.0)];
        let (mut acc, mut out) = (Vec::new(), Vec::new());
        fold_histories(&mut pending, &mut acc, &mut out);
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
}

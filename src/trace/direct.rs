//! Direct light on next-event receivers (method.md eqs. 1–2), estimated without bias and
//! with its own error: each *replicate* of a cell is a randomised stratified estimate of
//! the cell's mean direct illuminance (or luminance) — an m × m jittered pattern over the
//! cell, each point paired with one light (chosen per cell in proportion to its expected
//! share, stratified) and, for area sources, with a point of an m × m jittered pattern
//! over the source (strata paired by a random permutation), with shadow rays that thin
//! glazing lets through attenuated ([`super::shadow`]). Replicates are independent, so their Σy, Σy² give the direct
//! part's mean and σ by eqs. 6–7, like photon histories; σ sees every error of the
//! pattern (shadow edges, cone edges, grazing angles) and shrinks as replicates are
//! added during the run ([`DirectSchedule`]).
//!
//! Under `--qmc` a replicate's samples are instead the points of a scrambled Sobol'
//! pattern ([`DirectLight::queue_qmc_replicate`]): still independent replicates, each
//! unbiased, so the same statistics hold.
//!
//! Replicate r of cell c draws from `rng::direct_stream(seed, c, r)` and cells add their
//! replicates in order, so the sums depend only on the seed and the replicate count, not
//! on threads or epochs.

use super::emit::Emitters;
use super::shadow::{ShadowCaster, ShadowScratch};
use crate::accel::RayBatch;
use crate::rng::{direct_qmc_point, direct_stream};
use crate::sampling::{invert_cdf, uniform};
use crate::tally::{CellSums, ReceiverGrid};
use glam::DVec3;
use rand::RngCore;
use rand_pcg::Pcg32;
use rayon::prelude::*;

/// Replicates computed before the photons: enough for a σ of the direct part that can
/// be trusted from the start (its z-scores follow Student's t with 15 degrees of
/// freedom, RMS 1.08).
pub const PILOT_REPLICATES: u64 = 16;

/// Sample points per side of a cell in one replicate: 4 × 4, fewer on receivers with
/// very many cells so that a replicate stays affordable.
pub fn points_per_side(cells: usize) -> u32 {
    match cells {
        0..=65_536 => 4,
        65_537..=1_048_576 => 2,
        _ => 1,
    }
}

/// Points per side are this many times more in a cell that a light's edge crosses
/// ([`crosses_light_edge`]): 4× the samples per replicate there. On the cone-edge
/// calibration test (10,000 photons) this brings the fewest effective replicates of a
/// cell from ~3 to ≥ 10 and the worst z from −9.6 to −3.6 (docs/method.md); 4× per side
/// (16× the samples) costs so many rays that the replicates of every cell drop from
/// 84 to 22 under the schedule's cap (z-scores t-tailed again).
pub const EDGE_REFINEMENT: u32 = 2;

/// Probes per side of a cell where [`crosses_light_edge`] looks for a light's edge.
const EDGE_PROBES_PER_SIDE: u32 = 8;

/// A light's edge refines a cell only where that light gives at least this share of the
/// cell's brightest unoccluded light (over the probes): a minor light's skewed samples
/// hardly move the cell's value or σ, and in scenes of many luminaires with cut-offs
/// (scenes/luminaires.toml) refining for every light's edge doubled the direct rays.
const EDGE_MIN_SHARE: f64 = 0.1;

/// Cells per tile of [`DirectLight::cell_sides`]: tiles run in parallel, each casting
/// the shadow rays of its own corners (shared by its cells; a tile's border is cast
/// again by its neighbour) and holding their light, one byte per light and corner, only
/// while it runs.
const TILE_CELLS: u32 = 16_384;

/// What one light gives a corner of a receiver's cells, ordered so that the most light
/// wins where a light reaches a corner along several paths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum CornerLight {
    /// No unoccluded light (outside a cone, behind the source, or beyond the receiver's
    /// acceptance).
    Unlit,
    /// Light that an occluder blocks.
    Shadowed,
    Lit,
}

/// Whether the unoccluded light of some light is zero at some probes of the cell and
/// positive at others (a spot's cone edge, a source's plane, a receiver's acceptance
/// cone crossing the cell), probed on the cell's border and at its centre, or
/// `shadow_edge(light)` (an occluder's shadow crosses the cell: [`CornerLight`]), and
/// that light gives at least [`EDGE_MIN_SHARE`] of the cell's light. There few of a
/// replicate's points see light, and those deepest into the lit part carry most of it:
/// with 4 × 4 points per replicate a barely grazed cell's replicates are so skewed that
/// a run of a few dozen of them reads low with a small σ (docs/method.md, "Cells few
/// photons reach"). The decision comes from the geometry and the lights alone, never
/// from the cell's sampled values, so the refined replicates stay unbiased and the run
/// deterministic.
fn crosses_light_edge(
    emitters: &Emitters,
    grid: &ReceiverGrid,
    cell_point: impl Fn(f64, f64) -> DVec3,
    shadow_edge: impl Fn(usize) -> bool,
) -> bool {
    const N: u32 = EDGE_PROBES_PER_SIDE;
    let probe = |k: u32| {
        if k == 4 * N {
            return (0.5, 0.5);
        }
        let t = (k % N) as f64 / N as f64;
        match k / N {
            0 => (t, 0.0),
            1 => (1.0, t),
            2 => (1.0 - t, 1.0),
            _ => (0.0, 1.0 - t),
        }
    };
    let mut totals = [0.0; 4 * N as usize + 1];
    // Per light crossing the cell: its brightest probe.
    let mut crossing: Vec<f64> = Vec::new();
    for light in 0..emitters.emitters.len() {
        let (mut lit, mut dark, mut max) = (false, false, 0.0f64);
        for (k, total) in totals.iter_mut().enumerate() {
            let (a, b) = probe(k as u32);
            let mut e = 0.0;
            emitters.incoming(light, cell_point(a, b), &[(0.5, 0.5)], |inc| {
                if let Some(f) = grid.arrival_factor(-inc.direction()) {
                    e += inc.normal_lx * f;
                }
            });
            if e > 0.0 {
                lit = true;
                max = max.max(e);
                *total += e;
            } else {
                dark = true;
            }
        }
        if lit && (dark || shadow_edge(light)) {
            crossing.push(max);
        }
    }
    let brightest = totals.iter().fold(0.0f64, |m, &t| m.max(t));
    crossing
        .iter()
        .any(|&max| max >= EDGE_MIN_SHARE * brightest)
}

/// The light of one replicate's sample: weight of the light chosen, and for area sources
/// the point of the source it is paired with.
struct LightChoice {
    /// Per light: probability of being chosen for a sample of this cell.
    pmf: Vec<f64>,
    cdf: Vec<f64>,
}

impl LightChoice {
    /// Chooses lights for cell `cell` in proportion to their unoccluded light at its
    /// centre, mixed with 10 % uniform so a light the centre does not see (a cone or a
    /// source plane crossing the cell) is still sampled: any positive pmf is unbiased.
    fn for_cell(emitters: &Emitters, grid: &ReceiverGrid, centre: DVec3) -> LightChoice {
        let n = emitters.emitters.len();
        let mut share = vec![0.0; n];
        for (light, s) in share.iter_mut().enumerate() {
            emitters.incoming(light, centre, &[(0.5, 0.5)], |inc| {
                if let Some(f) = grid.arrival_factor(-inc.direction()) {
                    *s += inc.normal_lx * f;
                }
            });
        }
        let total: f64 = share.iter().sum();
        let pmf: Vec<f64> = share
            .iter()
            .map(|s| {
                if total > 0.0 {
                    0.9 * s / total + 0.1 / n as f64
                } else {
                    1.0 / n as f64
                }
            })
            .collect();
        let mut acc = 0.0;
        let cdf = pmf
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        LightChoice { pmf, cdf }
    }

    #[inline]
    fn pick(&self, u: f64) -> usize {
        self.cdf
            .iter()
            .position(|&c| u < c)
            .unwrap_or(self.cdf.len() - 1)
    }
}

/// Reused buffers of one worker.
#[derive(Default)]
struct Scratch {
    rays: RayBatch,
    /// Per shadow ray: (replicate within the call, weight if unoccluded).
    weights: Vec<(u32, f64)>,
    /// Per shadow ray, the fraction of its light that arrives.
    through: Vec<f64>,
    shadow: ShadowScratch,
    permutation: Vec<u32>,
    light_permutation: Vec<u32>,
    /// Per replicate of a block: the sum of its unoccluded weights.
    totals: Vec<f64>,
    reflected: super::reflected::Scratch,
}

/// Replicates of one cell whose shadow rays are cast together.
const REPLICATES_PER_BATCH: u64 = 64;

/// Everything a replicate reads.
pub struct DirectLight<'a> {
    pub emitters: &'a Emitters,
    pub shadows: &'a ShadowCaster<'a>,
    /// How far from a surface (m) a receiver still counts as lying on it.
    pub slack: f64,
    pub seed: u64,
    /// The surfaces luminance meters see the sources' light reflected by
    /// ([`super::reflected`]); `None`: meters take only the sources they see directly.
    pub reflectors: Option<&'a super::reflected::Reflectors>,
    /// Replicates from scrambled Sobol' patterns ([`DirectLight::queue_qmc_replicate`])
    /// instead of jittered ones (`run --qmc`).
    pub qmc: bool,
}

impl DirectLight<'_> {
    /// Points per side of each cell of `grid` in a replicate: `points` or
    /// [`points_per_side`], times [`EDGE_REFINEMENT`] where [`crosses_light_edge`]. The
    /// lights and the geometry alone decide it, so a run computes it once (in parallel
    /// over tiles of cells).
    pub fn cell_sides(&self, grid: &ReceiverGrid, points: Option<u32>) -> Vec<u32> {
        let m = points
            .unwrap_or_else(|| points_per_side(grid.cell_count()))
            .max(1);
        let [nu, nv] = grid.cells;
        let tile_cols = nu.min(TILE_CELLS);
        let tile_rows = (TILE_CELLS / tile_cols).clamp(1, nv);
        let tiles: Vec<(u32, u32)> = (0..nv)
            .step_by(tile_rows as usize)
            .flat_map(|j0| (0..nu).step_by(tile_cols as usize).map(move |i0| (i0, j0)))
            .collect();
        let tile_sides: Vec<Vec<u32>> = tiles
            .par_iter()
            .map_init(Scratch::default, |s, &(i0, j0)| {
                let cols = i0..(i0 + tile_cols).min(nu);
                let rows = j0..(j0 + tile_rows).min(nv);
                let corners = self.corner_lights(grid, cols.clone(), rows.clone(), s);
                let width = cols.len() + 1;
                let per_light = width * (rows.len() + 1);
                let cells = rows.clone().flat_map(|j| cols.clone().map(move |i| (i, j)));
                cells
                    .map(|(i, j)| {
                        let cell_point = |a, b| grid.cell_point((i, j), a, b);
                        let first = (j - j0) as usize * width + (i - i0) as usize;
                        let shadow_edge = |light: usize| {
                            let of = |c: usize| corners[light * per_light + c];
                            let four = [
                                of(first),
                                of(first + 1),
                                of(first + width),
                                of(first + width + 1),
                            ];
                            four.contains(&CornerLight::Lit)
                                && four.contains(&CornerLight::Shadowed)
                        };
                        if crosses_light_edge(self.emitters, grid, cell_point, shadow_edge) {
                            EDGE_REFINEMENT * m
                        } else {
                            m
                        }
                    })
                    .collect()
            })
            .collect();
        // The tiles' cells back in the grid's row-major order.
        let mut sides = vec![0; grid.cell_count()];
        for (&(i0, j0), tile) in tiles.iter().zip(tile_sides) {
            let width = tile_cols.min(nu - i0) as usize;
            for (k, side) in tile.into_iter().enumerate() {
                sides[(j0 as usize + k / width) * nu as usize + i0 as usize + k % width] = side;
            }
        }
        sides
    }

    /// What reaches each corner of the cells of columns `cols` and rows `rows` of the
    /// grid from each light's centre, by [`ShadowCaster::transmitted`]: light by
    /// light, (cols + 1) × (rows + 1) corners row by row. A straight shadow edge crossing
    /// a cell leaves at least one of its corners on each side, so a lit and a shadowed
    /// corner find every such cell (one shadow ray per corner and light, shared by the
    /// cells around it).
    fn corner_lights(
        &self,
        grid: &ReceiverGrid,
        cols: std::ops::Range<u32>,
        rows: std::ops::Range<u32>,
        s: &mut Scratch,
    ) -> Vec<CornerLight> {
        const BATCH: usize = 4096;
        let width = cols.len() + 1;
        let per_light = width * (rows.len() + 1);
        let corner_point = |c: usize| {
            let (i, j) = (
                cols.start + (c % width) as u32,
                rows.start + (c / width) as u32,
            );
            grid.cell_point((i, j), 0.0, 0.0)
        };
        let mut states = vec![CornerLight::Unlit; per_light * self.emitters.emitters.len()];
        for (light, states) in states.chunks_mut(per_light).enumerate() {
            for first in (0..per_light).step_by(BATCH) {
                s.rays.clear();
                s.weights.clear();
                for c in first..(first + BATCH).min(per_light) {
                    self.queue(grid, light, corner_point(c), (0.5, 0.5), 1.0, c as u32, s);
                }
                self.shadows
                    .transmitted(&s.rays, &mut s.through, &mut s.shadow);
                for (&(c, w), &through) in s.weights.iter().zip(&s.through) {
                    let state = match (w > 0.0, through > 0.0) {
                        (false, _) => CornerLight::Unlit,
                        (true, false) => CornerLight::Shadowed,
                        (true, true) => CornerLight::Lit,
                    };
                    let corner = &mut states[c as usize];
                    *corner = (*corner).max(state);
                }
            }
        }
        states
    }

    /// Adds replicates `first .. first + count` to every cell of `grid` (`cells` are the
    /// grid's own sums, `sides` its [`Self::cell_sides`]), in parallel over cells;
    /// returns the shadow rays cast.
    pub fn add_replicates(
        &self,
        grid: &ReceiverGrid,
        sides: &[u32],
        cells: &mut [CellSums],
        first: u64,
        count: u64,
    ) -> u64 {
        if self.emitters.emitters.is_empty() || count == 0 {
            return 0;
        }
        cells
            .par_iter_mut()
            .zip(sides)
            .enumerate()
            .map_init(Scratch::default, |s, (k, (sums, &m))| {
                let cell = grid.first_cell as u64 + k as u64;
                self.cell_replicates(grid, k as u32, m, cell, first, count, s, sums)
            })
            .sum()
    }

    /// Replicates of local cell `k` (global index `cell`, `m` points per side) into
    /// `sums`, in order, their
    /// shadow rays cast in blocks of [`REPLICATES_PER_BATCH`].
    #[allow(clippy::too_many_arguments)]
    fn cell_replicates(
        &self,
        grid: &ReceiverGrid,
        k: u32,
        m: u32,
        cell: u64,
        first: u64,
        count: u64,
        s: &mut Scratch,
        sums: &mut CellSums,
    ) -> u64 {
        let (i, j) = (k % grid.cells[0], k / grid.cells[0]);
        let cell_point = |a, b| grid.cell_point((i, j), a, b);
        let choice = LightChoice::for_cell(self.emitters, grid, cell_point(0.5, 0.5));
        let samples = m * m;
        let mut rays = 0;
        let mut block_start = first;
        while block_start < first + count {
            let block = REPLICATES_PER_BATCH.min(first + count - block_start);
            s.rays.clear();
            s.weights.clear();
            for r in 0..block {
                if self.qmc {
                    self.queue_qmc_replicate(
                        grid,
                        &choice,
                        (i, j),
                        cell,
                        block_start + r,
                        r as u32,
                        m,
                        s,
                    );
                    continue;
                }
                let mut rng = direct_stream(self.seed, cell, block_start + r);
                shuffle(&mut s.permutation, samples, &mut rng);
                shuffle(&mut s.light_permutation, samples, &mut rng);
                for sample in 0..samples {
                    // Jittered point of the cell's stratum `sample`.
                    let p = cell_point(
                        ((sample % m) as f64 + uniform(&mut rng)) / m as f64,
                        ((sample / m) as f64 + uniform(&mut rng)) / m as f64,
                    );
                    // The light, from stratum π(sample) of its cumulative distribution.
                    let u = (s.light_permutation[sample as usize] as f64 + uniform(&mut rng))
                        / samples as f64;
                    let light = choice.pick(u);
                    // The source point (area sources), from stratum π'(sample) of the source.
                    let stratum = s.permutation[sample as usize];
                    let source_point = (
                        ((stratum % m) as f64 + uniform(&mut rng)) / m as f64,
                        ((stratum / m) as f64 + uniform(&mut rng)) / m as f64,
                    );
                    let weight = 1.0 / (choice.pmf[light] * samples as f64);
                    self.queue(grid, light, p, source_point, weight, r as u32, s);
                }
            }
            rays += self
                .shadows
                .transmitted(&s.rays, &mut s.through, &mut s.shadow);
            s.totals.clear();
            s.totals.resize(block as usize, 0.0);
            for (&(r, w), &through) in s.weights.iter().zip(&s.through) {
                if through > 0.0 {
                    s.totals[r as usize] += w * through;
                }
            }
            rays += self.add_reflected(
                grid,
                (i, j),
                m,
                cell,
                block_start,
                &mut s.totals,
                &mut s.reflected,
                &mut s.shadow,
            );
            for &y in &s.totals {
                // In the run's score unit (exact: a power of two).
                sums.add_direct(y / self.emitters.score_unit);
            }
            block_start += block;
        }
        rays
    }

    /// Queues the samples of replicate `replicate` (number `r` in its batch) of cell `cell`
    /// under `--qmc`: the points of a scrambled Sobol' pattern ([`direct_qmc_point`]),
    /// whose first dimension picks the light by inverting the cell's light distribution
    /// and whose remainder, stratified among the samples that picked that light, places
    /// the point along the source's length (C0; dimension 1 across it), so each light's
    /// own samples are stratified over its opening. On the luminaires' work plane the
    /// opening's point carried three quarters of a jittered replicate's variance (fixed
    /// at the centre, the variance fell 3.9×): the jittered pattern pairs source strata
    /// with lights at random, leaving each light a random subset of them. Dimensions
    /// 2–3 place the cell's point.
    #[allow(clippy::too_many_arguments)]
    fn queue_qmc_replicate(
        &self,
        grid: &ReceiverGrid,
        choice: &LightChoice,
        (i, j): (u32, u32),
        cell: u64,
        replicate: u64,
        r: u32,
        m: u32,
        s: &mut Scratch,
    ) {
        let samples = m * m;
        let total = choice.cdf.last().copied().unwrap_or(1.0);
        for sample in 0..samples {
            let [light_u, across, a, b] = direct_qmc_point(self.seed, cell, replicate, sample);
            let (light, along) = invert_cdf(&choice.cdf, |&c| c, light_u);
            let weight = total / (choice.pmf[light] * samples as f64);
            let p = grid.cell_point((i, j), a, b);
            self.queue(grid, light, p, (along, across), weight, r, s);
        }
    }

    /// Queues the shadow ray from receiver point `p` to `light` (at `source_point` of an
    /// area source) and what it adds to replicate `r` if unoccluded.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn queue(
        &self,
        grid: &ReceiverGrid,
        light: usize,
        p: DVec3,
        source_point: (f64, f64),
        weight: f64,
        r: u32,
        s: &mut Scratch,
    ) {
        let slack = self.slack;
        self.emitters.incoming(light, p, &[source_point], |inc| {
            if inc.distance <= 4.0 * slack {
                return;
            }
            let Some(factor) = grid.arrival_factor(-inc.direction()) else {
                return;
            };
            // Stop just short of the source, and start just off the receiver, which may
            // lie on a surface. (So a ray from a point within 2·slack of a wall the
            // receiver's edge touches passes through it: docs/daylight.md, *Openings*.)
            let (t_near, t_far) = if inc.distance.is_finite() {
                let eps = (2.0 * slack / inc.distance) as f32;
                (eps, 1.0 - eps)
            } else {
                ((2.0 * slack) as f32, f32::INFINITY)
            };
            s.rays.push(
                p.as_vec3().into(),
                inc.to_source.as_vec3().into(),
                t_near,
                t_far,
            );
            s.weights.push((r, inc.normal_lx * factor * weight));
        });
    }
}

/// A uniformly random permutation of 0..n into `out` (Fisher–Yates).
pub(super) fn shuffle(out: &mut Vec<u32>, n: u32, rng: &mut Pcg32) {
    out.clear();
    out.extend(0..n);
    for k in (1..n as usize).rev() {
        let j = (rng.next_u64() % (k as u64 + 1)) as usize;
        out.swap(k, j);
    }
}

/// Samples one replicate draws over a receiver whose cells take `sides` points per side
/// ([`DirectLight::cell_sides`]): each evaluates a light (and, for an area source, draws
/// a point of it in the solid angle it subtends), whether or not it then casts a shadow
/// ray. Drawing the samples, not tracing their rays, is most of a replicate's time:
/// under a narrow luminance meter 100 % of its samples are drawn and < 1 % cast a ray,
/// and on the spot's cone-edge test tracing takes under 10 % of the direct light's time.
pub fn samples_per_replicate(sides: &[u32]) -> u64 {
    sides.iter().map(|&m| m as u64 * m as u64).sum()
}

/// How many direct-light replicates a run has after N photons: a number of replicates
/// per photon, ρ, chosen to minimise the time to a given error of the next-event
/// receivers (σ² = a/R + b/N at costs c_d·R + c_p·N is lowest at
/// R/N = sqrt(a·c_p / (b·c_d))), with c_d a replicate's samples plus its shadow rays
/// and c_p a photon's rays, at most [`MAX_DIRECT_WORK_SHARE`] times the photons' work;
/// re-estimated only at photon counts every run passes through (`CHUNK_PHOTONS`·2^k:
/// epochs are cut there), where [`replicate_floor`] may also add replicates, so the
/// replicate count, like every tally, depends on the photon count alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectSchedule {
    /// Replicates per photon.
    pub per_photon: f64,
}

/// At most this much direct work per unit of photon work (work: samples drawn plus rays
/// cast, [`DirectSchedule::from_variances`]): the direct light never takes more than
/// 16/17 of a run's work, even when photons add nothing to a receiver (a black room),
/// and the photons still build the scene map. Costed by rays alone, a replicate whose
/// samples rarely cast one (a narrow luminance meter: 1,600 samples, 7 rays) looked
/// almost free and was drawn 2 times per photon.
pub const MAX_DIRECT_WORK_SHARE: f64 = 16.0;

impl DirectSchedule {
    /// Replicates wanted after `photons` photons (never fewer than `done`).
    pub fn wanted(&self, photons: u64, done: u64) -> u64 {
        let r = (self.per_photon * photons as f64).ceil();
        (if r.is_finite() { r as u64 } else { done }).max(done)
    }

    /// The ratio re-estimated from the tallies: `a`, `b` are the receivers' direct
    /// variance per replicate and photon variance per history, each relative to the
    /// cells' values and summed over cells; `work_per_replicate` (a replicate's samples
    /// plus its shadow rays) and `rays_per_photon` the costs.
    pub fn from_variances(
        a: f64,
        b: f64,
        work_per_replicate: f64,
        rays_per_photon: f64,
    ) -> DirectSchedule {
        let cap = MAX_DIRECT_WORK_SHARE * rays_per_photon / work_per_replicate.max(1.0);
        let optimum = if b > 0.0 {
            (a * rays_per_photon / (b * work_per_replicate.max(1.0))).sqrt()
        } else {
            cap
        };
        DirectSchedule {
            per_photon: if optimum.is_finite() {
                optimum.min(cap)
            } else {
                cap
            },
        }
    }
}

/// The direct light's floor ([`replicate_floor`]): at every schedule point each lit
/// cell is given at least this many effective replicates (Σy)²/Σy². Below about 10 a
/// cell whose replicates are skewed (few of its points see light: a cone's or a
/// shadow's edge) reads low with too small a σ (docs/method.md, "Cells few photons
/// reach"); a smooth cell has about as many as its replicates, so the pilot's 16
/// already give it more and the floor adds none.
pub const FLOOR_EFFECTIVE: f64 = 10.0;

/// The floor never asks for more than this many replicates, 4 × the pilot's: it costs
/// at most 3 pilots more, once in a run, whatever the photons. A cell that would need
/// more (a light's sliver that one replicate in 16 sees) gets these.
pub const FLOOR_MAX: u64 = 4 * PILOT_REPLICATES;

/// The replicates at which every lit cell of `cells` (`replicates` of them so far) has
/// [`FLOOR_EFFECTIVE`] effective replicates (Σy)²/Σy², each further replicate adding
/// as many as the cell's replicates so far did on average; at most [`FLOOR_MAX`]. Read
/// from the tallies at a schedule point, like the schedule itself, so the replicates
/// stay a function of the photon count (their values decide how many are drawn, never
/// which, so each stays unbiased).
pub fn replicate_floor(cells: &[CellSums], replicates: u64) -> u64 {
    let mut floor = 0.0f64;
    for c in cells {
        let effective = c.direct.over(replicates).effective_count();
        if effective > 0.0 {
            floor = floor.max(FLOOR_EFFECTIVE * replicates as f64 / effective);
        }
    }
    (floor.ceil() as u64).min(FLOOR_MAX)
}

/// Σ over cells of the relative variances of one direct replicate (a) and of one photon
/// (b: N times the variance of the photons' mean), for [`DirectSchedule::from_variances`];
/// the cells' photon moments are over `histories` (the photons, or a QMC run's blocks).
/// Cells without a value are left out.
pub fn relative_variances(
    cells: &[CellSums],
    (photons, histories): (u64, u64),
    replicates: u64,
) -> (f64, f64) {
    let (mut a, mut b) = (0.0, 0.0);
    for c in cells {
        // Per replicate and per photon: n times the variance of the mean.
        let (direct, direct_var) = c.direct.over(replicates).mean_and_variance();
        let (photon, photon_var) = c.photons.over(histories).mean_and_variance();
        let value = direct + photon;
        if !(value > 0.0) {
            continue;
        }
        if direct_var >= 0.0 {
            a += direct_var * replicates as f64 / (value * value);
        }
        if photon_var >= 0.0 {
            b += photon_var * photons as f64 / (value * value);
        }
    }
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shuffle_is_a_permutation() {
        let mut rng = crate::rng::aux_stream(9);
        let mut p = Vec::new();
        shuffle(&mut p, 16, &mut rng);
        let mut sorted = p.clone();
        sorted.sort();
        assert_eq!(sorted, (0..16).collect::<Vec<_>>());
    }

    #[test]
    fn schedule_balances_variance_per_cost_and_caps_the_share() {
        // Equal variances, direct replicate 4× a photon's work: R/N = sqrt(1/4) = 1/2.
        let s = DirectSchedule::from_variances(1.0, 1.0, 40.0, 10.0);
        assert!((s.per_photon - 0.5).abs() < 1e-12);
        // Photons add nothing: the cap, 16 units of direct work per unit of photon work.
        let s = DirectSchedule::from_variances(1.0, 0.0, 40.0, 10.0);
        assert!((s.per_photon - 4.0).abs() < 1e-12);
        assert_eq!(s.wanted(1000, 3), 4000);
        assert_eq!(s.wanted(1, 16), 16, "never fewer than done");
    }

    #[test]
    fn samples_of_a_replicate_count_every_point_of_every_cell() {
        assert_eq!(samples_per_replicate(&[4, 4, 8]), 16 + 16 + 64);
    }

    /// Cells whose replicates are `values` (in order).
    fn cells(values: &[&[f64]]) -> Vec<CellSums> {
        values
            .iter()
            .map(|ys| {
                let mut c = CellSums::default();
                ys.iter().for_each(|&y| c.add_direct(y));
                c
            })
            .collect()
    }

    #[test]
    fn the_floor_gives_skewed_cells_ten_effective_replicates_and_smooth_ones_nothing() {
        // 16 equal replicates: 16 effective, more than the floor's 10 (11 replicates).
        let smooth = [1.0; 16];
        assert!(replicate_floor(&cells(&[&smooth]), 16) < 16);
        // 4 of 16 replicates saw light, equally: 4 effective, 2.5 times too few.
        let mut skewed = [0.0; 16];
        skewed[..4].fill(1.0);
        assert_eq!(replicate_floor(&cells(&[&smooth, &skewed]), 16), 40);
        // One of 16: 160 wanted, the floor's most given.
        let mut sliver = [0.0; 16];
        sliver[3] = 1.0;
        assert_eq!(replicate_floor(&cells(&[&sliver, &skewed]), 16), FLOOR_MAX);
        // Unlit cells ask for nothing.
        assert_eq!(replicate_floor(&cells(&[&[0.0; 16]]), 16), 0);
    }
}

//! Tallies: *where* light scores (receiver cells, triangle faces) and *what* it scores
//! (Σx, Σx², Σx³, Σx⁴ and hits per cell; photon counts per triangle face).
//!
//! Workers fill a [`ChunkTally`] per fixed range of photons; [`Tallies::accumulate`] folds
//! the chunks in photon order once per epoch, so the sums do not depend on the number of
//! threads or on scheduling.

pub(crate) mod receiver_grid;
mod triangle_counts;

pub use receiver_grid::ReceiverGrid;
pub use triangle_counts::TriangleCounts;

/// What one fixed range of photons scored.
#[derive(Clone, Debug, Default)]
pub struct ChunkTally {
    /// Triangle-face deposits, one per photon hit: see [`deposit_code`].
    pub deposits: Vec<u32>,
    /// Receiver scores per touched cell, in cell order.
    pub scores: Vec<CellPartial>,
    /// Rays cast (closest-hit and shadow).
    pub rays: u64,
    /// Photons stopped by the bounce cap.
    pub killed_by_bounce_cap: u64,
    /// Σk, Σk², Σk³, Σk⁴ of k, the surface hits of each photon history: the moments of
    /// the whole map's total, for the error of the scene's mean illuminance. u128: k⁴
    /// alone passes u64 beyond 65,536 hits, and a chunk's Σk⁴ long before; with k ≤
    /// `trace::MAX_BOUNCE_CAP` + 1 no sum of a run can pass u128 (see there).
    pub history_hits: [u128; 4],
}

impl ChunkTally {
    /// A photon's hit on triangle `tri`: see [`deposit_code`].
    #[inline]
    pub fn deposit(&mut self, tri: u32, back_face: bool, indirect: bool, odd: bool) {
        self.deposits
            .push(deposit_code(tri, back_face, indirect, odd));
    }

    /// Empties the tally, keeping its buffers.
    pub fn clear(&mut self) {
        self.deposits.clear();
        self.scores.clear();
        self.rays = 0;
        self.killed_by_bounce_cap = 0;
        self.history_hits = [0; 4];
    }

    /// A photon history ended after `hits` surface hits.
    #[inline]
    pub fn record_history_hits(&mut self, hits: u32) {
        self.record_histories(hits, 1);
    }

    /// `count` histories (0 or 1 in the photon pass's branch-free roulette) that ended
    /// after `hits` surface hits.
    #[inline]
    pub fn record_histories(&mut self, hits: u32, count: u64) {
        let (k, count) = (hits as u128, count as u128);
        let k2 = k * k;
        let h = &mut self.history_hits;
        h[0] += count * k;
        h[1] += count * k2;
        h[2] += count * k2 * k;
        h[3] += count * k2 * k2;
    }
}

/// One chunk's scores in one receiver cell: the count, mean and central moments of the
/// chunk's histories that scored there ([`Moments`]; each history's scores in the cell
/// summed first, so eqs. 6–8 see per-history scores) and the crossings or
/// contributions counted. The chunk's other histories scored 0: [`CellSums::add`] adds
/// them. Serialised as is by checkpoints (a shard's chunks) and MPI (a worker's chunks).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CellPartial {
    /// Global cell index over all receivers (see [`ReceiverGrid::first_cell`]).
    pub cell: u32,
    pub hits: u64,
    pub moments: Moments,
}

impl CellPartial {
    /// Adds one history's score `x` made of `hits` contributions.
    #[inline]
    pub fn add_history(&mut self, x: f64, hits: u64) {
        self.moments.push(x);
        self.hits += hits;
    }
}

/// Count, mean and central moments M₂, M₃, M₄ (sums of (x − x̄)ᵖ) of a set of scores,
/// updated and merged by Pébay's pairwise formulas (Pébay 2008; Terriberry). Raw power
/// sums Σxᵖ lose every digit of the fourth central moment to cancellation where σ/x̄ is
/// small (a sampled direct light at σ/x̄ = 10⁻⁴), and overflow where the scores are
/// large; these never subtract large numbers and stay finite for any score whose fourth
/// power about the mean is finite. Merged in a fixed order, so the same bits follow from
/// the same scores on any number of threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Moments {
    pub n: u64,
    pub mean: f64,
    pub m2: f64,
    pub m3: f64,
    pub m4: f64,
}

impl Moments {
    /// Adds one score.
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.merge(&Moments {
            n: 1,
            mean: x,
            ..Moments::default()
        });
    }

    /// Adds `count` scores of 0 (the histories that did not score).
    #[inline]
    pub fn push_zeros(&mut self, count: u64) {
        self.merge(&Moments {
            n: count,
            ..Moments::default()
        });
    }

    /// Merges the scores of `b` in (Pébay's formulas for two sets).
    #[inline]
    pub fn merge(&mut self, b: &Moments) {
        if b.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *b;
            return;
        }
        let (na, nb) = (self.n as f64, b.n as f64);
        let n = na + nb;
        let delta = b.mean - self.mean;
        let d_n = delta / n;
        let d_n2 = d_n * d_n;
        let term = delta * d_n * na * nb;
        let a = *self;
        self.n += b.n;
        // Anchored at the larger set: a few scores merged with many zeros would lose
        // digits to 1 − nb/n in the other form.
        self.mean = if na >= nb {
            a.mean + d_n * nb
        } else {
            b.mean - d_n * na
        };
        self.m2 = a.m2 + b.m2 + term;
        self.m3 = a.m3 + b.m3 + term * d_n * (na - nb) + 3.0 * d_n * (na * b.m2 - nb * a.m2);
        self.m4 = a.m4
            + b.m4
            + term * d_n2 * (na * na - na * nb + nb * nb)
            + 6.0 * d_n2 * (na * na * b.m2 + nb * nb * a.m2)
            + 4.0 * d_n * (na * b.m3 - nb * a.m3);
    }

    /// These moments with zeros added up to `n` scores (the histories since the last
    /// score): what they are over all `n` histories of a run.
    #[inline]
    pub fn over(&self, n: u64) -> Moments {
        let mut m = *self;
        m.push_zeros(n.saturating_sub(self.n));
        m
    }

    /// Effective number of equal scores, (Σx)²/Σx² (0 for none): the histories that
    /// really stand behind the mean.
    pub fn effective_count(&self) -> f64 {
        let sq = self.sum_sq();
        if sq > 0.0 {
            let s = self.sum();
            s * s / sq
        } else {
            0.0
        }
    }

    /// Σx.
    pub fn sum(&self) -> f64 {
        self.mean * self.n as f64
    }

    /// Σx² (M₂ + n·x̄²).
    pub fn sum_sq(&self) -> f64 {
        self.m2 + self.mean * self.mean * self.n as f64
    }

    /// The mean and its variance, eq. 7 squared with the unbiased n/(n − 1) variance:
    /// M₂/(n(n − 1)); NaN below 2 scores.
    pub fn mean_and_variance(&self) -> (f64, f64) {
        match self.n {
            0 => (0.0, f64::NAN),
            1 => (self.mean, f64::NAN),
            n => {
                let n = n as f64;
                (self.mean, self.m2.max(0.0) / (n * (n - 1.0)))
            }
        }
    }

    /// Relative variance of the variance of the mean (MCNP's VOV):
    /// M₄/M₂² − 1/n; 1 while nothing is known (fewer than 2 scores, or all equal).
    pub fn vov(&self) -> f64 {
        if self.n < 2 || !(self.m2 > 0.0) {
            return 1.0;
        }
        (self.m4 / (self.m2 * self.m2) - 1.0 / self.n as f64).max(0.0)
    }
}

/// Faces, light kinds and photon parities a triangle keeps apart.
pub const CODES_PER_TRIANGLE: usize = 8;

/// The slot of a photon's hit in the triangle map: triangle, face (back when the photon
/// arrives from behind the normal), indirect (the photon scattered before) and the
/// photon index's parity (the odd/even maps of method.md §3).
#[inline]
pub fn deposit_code(triangle: u32, back_face: bool, indirect: bool, odd_photon: bool) -> u32 {
    triangle * CODES_PER_TRIANGLE as u32
        + ((back_face as u32) << 2)
        + ((indirect as u32) << 1)
        + odd_photon as u32
}

/// What one slot of a triangle's [`CODES_PER_TRIANGLE`] counts: the decoding of
/// [`deposit_code`], so the bit layout lives here alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slot {
    pub back_face: bool,
    pub indirect: bool,
    pub odd_photon: bool,
}

impl Slot {
    /// The slot at offset `slot` (0..CODES_PER_TRIANGLE) of a triangle's counts.
    #[inline]
    pub fn of(slot: usize) -> Slot {
        Slot {
            back_face: slot & 4 != 0,
            indirect: slot & 2 != 0,
            odd_photon: slot & 1 != 0,
        }
    }
}

impl Tallies {
    /// Triangle `k`'s photon counts, one per [`Slot`].
    #[inline]
    pub fn triangle_slots(&self, k: usize) -> [u64; CODES_PER_TRIANGLE] {
        self.triangle_hits.slots(k)
    }
}

/// Per-cell moments of the history scores, and of the cell's sampled direct light, in
/// the run's score unit ([`score_unit`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellSums {
    /// The photon histories' scores: [`Moments`] over `photons.n` histories (those up to
    /// the last chunk that scored here: its first photon plus its scoring histories; the
    /// rest scored 0 and are added by [`Moments::over`]).
    pub photons: Moments,
    /// Contributions scored: photon crossings and connections, and direct-light
    /// replicates that saw light.
    pub hits: u64,
    /// Scoring histories: those with a non-zero score in the cell.
    pub scoring_histories: u64,
    /// The direct-light replicates (next-event receivers; see `trace::direct`), all
    /// `Tallies::direct_replicates` of them.
    pub direct: Moments,
}

impl CellSums {
    /// Adds a chunk's partial whose first history is `first` (call in history order):
    /// the histories since the cell's last score scored 0 here.
    #[inline]
    fn add(&mut self, partial: &CellPartial, first: u64) {
        self.photons
            .push_zeros(first.saturating_sub(self.photons.n));
        self.photons.merge(&partial.moments);
        self.hits += partial.hits;
        self.scoring_histories += partial.moments.n;
    }

    /// Adds one direct-light replicate `y` (call in replicate order); a replicate that
    /// saw light counts as a hit.
    #[inline]
    pub fn add_direct(&mut self, y: f64) {
        self.direct.push(y);
        self.hits += (y != 0.0) as u64;
    }

    /// The photon histories' moments over all of `counts`' histories.
    pub fn photon_moments(&self, counts: Counts) -> Moments {
        self.photons.over(counts.histories)
    }

    /// The direct light's moments over all of `counts`' replicates.
    pub fn direct_moments(&self, counts: Counts) -> Moments {
        self.direct.over(counts.direct_replicates)
    }
}

/// The unit scores are tallied in, for a scene of total flux `total_flux_lm`: the power
/// of two nearest the flux (1 for a scene without light). Scores scale with the flux, so
/// in this unit their moments neither overflow nor underflow whatever the light's level
/// (Σx⁴ of a 10⁸⁰ cd source would), and dividing by a power of two is exact: relative
/// errors and VOVs agree to rounding at any level (to the bit between levels a power of
/// two apart). Clamped to normal numbers, so that its inverse is finite too.
pub fn score_unit(total_flux_lm: f64) -> f64 {
    if total_flux_lm > 0.0 && total_flux_lm.is_finite() {
        2f64.powi(
            (libm::log2(total_flux_lm).round() as i32).clamp(f64::MIN_EXP - 1, f64::MAX_EXP - 1),
        )
    } else {
        1.0
    }
}

/// Everything accumulated so far in a run.
#[derive(Clone, Debug, Default)]
pub struct Tallies {
    /// Photons emitted (indices 0..photons).
    pub photons: u64,
    pub rays: u64,
    pub killed_by_bounce_cap: u64,
    /// Moments of surface hits per history (see [`ChunkTally::history_hits`]); u128
    /// keeps Σk⁴ exact over any run.
    pub history_hits: [u128; 4],
    /// Photon hits per triangle and [`deposit_code`] slot.
    pub triangle_hits: TriangleCounts,
    /// One entry per cell of every receiver, receivers in scene order, then one per
    /// receiver for its mean ([`Tallies::receiver_total`]).
    pub cells: Vec<CellSums>,
    /// Direct-light replicates added to every next-event receiver's cells so far, and
    /// the shadow rays they took.
    pub direct_replicates: u64,
    pub direct_rays: u64,
    /// The scene emits no light: every value is exactly 0, with no error.
    pub dark: bool,
    /// The unit of the cells' scores ([`score_unit`]), in the receivers' units.
    pub score_unit: f64,
    /// Photons per history of the cells' moments: 1, or a QMC run's block of
    /// 2^[`crate::rng::QMC_LOG2_BLOCK`] photons, whose points are not independent but
    /// whose blocks are ([`Tallies::set_qmc_blocks`]).
    pub photons_per_history: u64,
}

/// What a cell's sums were accumulated over.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counts {
    pub photons: u64,
    /// The histories of the cells' photon moments: the photons, or a QMC run's blocks.
    pub histories: u64,
    pub direct_replicates: u64,
    /// No light at all: nothing scored means exactly 0.
    pub dark: bool,
    /// The unit of the cells' scores ([`score_unit`]).
    pub unit: f64,
}

/// Blocks a QMC run's photons' variance needs before it is reported: 31 degrees of
/// freedom, where a cell's σ is judged reliable (`stats::cell_status`); below, every
/// σ that the photons' part enters is unknown.
pub const MIN_QMC_BLOCKS: u64 = 32;

impl Counts {
    /// Whether the photons' variance is known: always for histories of one photon
    /// (a cell that nothing reached is the stats' concern), for a QMC run's blocks
    /// from [`MIN_QMC_BLOCKS`] of them.
    pub fn photon_variance_known(&self) -> bool {
        self.histories == self.photons || self.histories >= MIN_QMC_BLOCKS
    }
}

impl Tallies {
    /// Empty tallies whose scores are in `score_unit` ([`score_unit`]).
    pub fn new(triangles: usize, cells: usize, score_unit: f64) -> Tallies {
        Tallies {
            triangle_hits: TriangleCounts::zeros(triangles * CODES_PER_TRIANGLE),
            cells: vec![CellSums::default(); cells],
            score_unit,
            photons_per_history: 1,
            ..Tallies::default()
        }
    }

    /// Makes every history of the cells' moments a block of a QMC run
    /// (`blocks`), or one photon. Only on empty tallies: their moments are over one or
    /// the other.
    pub fn set_qmc_blocks(&mut self, blocks: bool) {
        debug_assert_eq!(self.photons, 0);
        self.photons_per_history = if blocks {
            1 << crate::rng::QMC_LOG2_BLOCK
        } else {
            1
        };
    }

    /// Folds one chunk of `photons` photons in (call in photon order).
    pub fn accumulate(&mut self, chunk: &ChunkTally, photons: u64) {
        // A QMC run's chunks are whole blocks (`trace::Tracer::trace_chunk_into`).
        let first = self.photons / self.photons_per_history.max(1);
        self.photons += photons;
        self.rays += chunk.rays;
        self.killed_by_bounce_cap += chunk.killed_by_bounce_cap;
        for (total, part) in self.history_hits.iter_mut().zip(chunk.history_hits) {
            *total += part;
        }
        self.triangle_hits.increment_each(&chunk.deposits);
        for p in &chunk.scores {
            self.cells[p.cell as usize].add(p, first);
        }
    }

    /// What the cells' sums were accumulated over.
    pub fn counts(&self) -> Counts {
        Counts {
            photons: self.photons,
            histories: self.photons / self.photons_per_history.max(1),
            direct_replicates: self.direct_replicates,
            dark: self.dark,
            unit: self.score_unit,
        }
    }

    /// The cells of receiver `r` of `receivers` (all receivers' cells lie back to back).
    pub fn receiver_cells(&self, receivers: &[crate::scene::Receiver], r: usize) -> &[CellSums] {
        let first: usize = receivers[..r].iter().map(|x| x.cell_count()).sum();
        &self.cells[first..first + receivers[r].cell_count()]
    }

    /// The histories of receiver `r`'s mean over its cells (photons only: its sampled
    /// direct light stays in the cells). One such slot per receiver follows all the
    /// receivers' cells, in order.
    pub fn receiver_total(&self, receivers: &[crate::scene::Receiver], r: usize) -> &CellSums {
        let cells: usize = receivers.iter().map(|x| x.cell_count()).sum();
        &self.cells[cells + r]
    }

    /// Photons of odd and of even index among the first `photons`.
    pub fn odd_even_photons(&self) -> (u64, u64) {
        (self.photons / 2, self.photons - self.photons / 2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central moments of `x` by two passes in f64 (mean, then Σ(x − x̄)ᵖ): accurate
    /// where the scores' spread is not tiny against their mean.
    fn two_pass(x: &[f64]) -> [f64; 4] {
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let m = |p: i32| x.iter().map(|v| (v - mean).powi(p)).sum::<f64>();
        [mean, m(2), m(3), m(4)]
    }

    fn moments_of(x: &[f64]) -> Moments {
        let mut m = Moments::default();
        x.iter().for_each(|&v| m.push(v));
        m
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn moments_merge_in_any_split_to_the_two_pass_values() {
        let mut rng = crate::rng::aux_stream(11);
        let x: Vec<f64> = (0..5000)
            .map(|k| match k % 7 {
                0 => 0.0,
                _ => crate::sampling::uniform(&mut rng).powi(3) * 40.0,
            })
            .collect();
        let [mean, m2, m3, m4] = two_pass(&x);
        for split in [1, 17, 2500, 4999] {
            let mut m = moments_of(&x[..split]);
            m.merge(&moments_of(&x[split..]));
            assert_eq!(m.n, 5000);
            for (got, want) in [(m.mean, mean), (m.m2, m2), (m.m3, m3), (m.m4, m4)] {
                assert!(close(got, want, 1e-12), "split {split}: {got} vs {want}");
            }
        }
        // Zeros added in bulk are zeros pushed one by one.
        let mut bulk = moments_of(&x);
        bulk.push_zeros(300);
        let mut one_by_one = moments_of(&x);
        (0..300).for_each(|_| one_by_one.push(0.0));
        assert!(close(bulk.m4, one_by_one.m4, 1e-12) && close(bulk.mean, one_by_one.mean, 1e-13));
        assert_eq!(moments_of(&x).over(5300).n, 5300);
    }

    #[test]
    fn moments_keep_their_digits_where_sigma_is_a_millionth_of_the_mean() {
        // Replicates 1 + d with d ~ 10⁻⁶·(uniform³ − ½), dyadic so that 1 + d − 1 = d
        // exactly: the central moments of y are those of d, which two passes give to
        // ~1e-15 (d's spread is not small against its mean). Raw power sums lose the
        // fourth central moment entirely here (Σy⁴ ≈ n, M₄ ≈ n·10⁻²⁴).
        let mut rng = crate::rng::aux_stream(12);
        let d: Vec<f64> = (0..20_000)
            .map(|_| {
                let u = crate::sampling::uniform(&mut rng).powi(3) - 0.5;
                (u * 2f64.powi(32)).round() * 2f64.powi(-52)
            })
            .collect();
        let y: Vec<f64> = d.iter().map(|v| 1.0 + v).collect();
        assert!(y.iter().zip(&d).all(|(y, d)| y - 1.0 == *d));
        let [_, m2, m3, m4] = two_pass(&d);
        let m = moments_of(&y);
        assert!(close(m.m2, m2, 1e-9), "M₂ {} vs {m2}", m.m2);
        assert!(close(m.m3, m3, 1e-6), "M₃ {} vs {m3}", m.m3);
        assert!(close(m.m4, m4, 1e-8), "M₄ {} vs {m4}", m.m4);
        let vov = m4 / (m2 * m2) - 1.0 / d.len() as f64;
        assert!(close(m.vov(), vov, 1e-8), "VOV {} vs {vov}", m.vov());
        // The same scores at another level: relative σ and VOV to rounding.
        for scale in [1e-10, 1e30, 2f64.powi(40)] {
            let ys: Vec<f64> = y.iter().map(|v| v * scale).collect();
            let s = moments_of(&ys);
            let rel = |m: &Moments| m.mean_and_variance().1.sqrt() / m.mean;
            assert!(close(rel(&s), rel(&m), 1e-9) && close(s.vov(), m.vov(), 1e-8));
        }
    }

    #[test]
    fn a_cell_merged_chunk_by_chunk_keeps_its_mean_within_the_rounding_bound() {
        // One score of 0.1 (not representable) in each of 250,000 chunks of 4096
        // histories, merged as a run merges them (zeros, then the chunk): each merge
        // rounds its mean by a few ulps, so K merges stay within 4Kε of the exact mean
        // (the compensated power sums this replaced kept 12 digits over 10⁹ terms).
        let (chunks, per_chunk) = (250_000u64, 4096u64);
        let mut cell = CellSums::default();
        for k in 0..chunks {
            let mut partial = CellPartial::default();
            partial.add_history(0.1, 1);
            cell.add(&partial, k * per_chunk);
        }
        let m = cell.photons.over(chunks * per_chunk);
        let exact = 0.1 / per_chunk as f64;
        let bound = 4.0 * chunks as f64 * f64::EPSILON;
        let rel = ((m.mean - exact) / exact).abs();
        assert!(rel <= bound, "relative error {rel:e} above {bound:e}");
        assert_eq!(cell.scoring_histories, chunks);
    }

    #[test]
    fn the_score_unit_is_a_power_of_two_near_the_flux() {
        assert_eq!(score_unit(1.0), 1.0);
        assert_eq!(score_unit(1000.0), 1024.0);
        assert_eq!(score_unit(0.0), 1.0);
        assert_eq!(score_unit(f64::MAX), 2f64.powi(1023));
        let flux = 4.0 * std::f64::consts::PI * 1e200;
        let unit = score_unit(flux);
        assert!(unit.is_finite() && (flux / unit) > 0.7 && (flux / unit) < 1.5);
        assert_eq!(libm::log2(unit).fract(), 0.0);
        assert!(score_unit(1e-300) > 0.0);
    }

    #[test]
    fn history_hit_moments_are_exact_at_a_hundred_thousand_bounces() {
        // k⁴ = 10²⁰ > u64::MAX already for one history; seven histories of 100,000 hits
        // (one recorded as a count of 4, as the photon pass records them) and one of 3.
        let mut c = ChunkTally::default();
        c.record_history_hits(100_000);
        c.record_histories(100_000, 4);
        c.record_history_hits(3);
        c.record_histories(100_000, 2);
        c.record_histories(7, 0);
        let k = 100_000u128;
        let exact = [
            7 * k + 3,
            7 * k * k + 9,
            7 * k.pow(3) + 27,
            7 * k.pow(4) + 81,
        ];
        assert_eq!(c.history_hits, exact);
        assert_eq!(exact[3], 700_000_000_000_000_000_081);
        // Carried exactly into the run's tallies, chunk after chunk.
        let mut t = Tallies::new(0, 0, 1.0);
        t.accumulate(&c, 8);
        t.accumulate(&c, 8);
        assert_eq!(t.history_hits, exact.map(|m| 2 * m));
        // At the largest cap the terms stay exact too.
        let mut d = ChunkTally::default();
        let big = crate::trace::MAX_BOUNCE_CAP + 1;
        d.record_histories(big, 4096);
        assert_eq!(d.history_hits[3], 4096 * (big as u128).pow(4));
    }

    #[test]
    fn counting_a_run_of_codes_widens_where_one_code_would_overflow() {
        // Code 1 reaches u32::MAX at the run's second code and passes it at its fourth:
        // the codes before are counted narrow, the rest wide, each once.
        let mut c = TriangleCounts::Narrow(vec![0, u32::MAX - 1, 5]);
        c.increment_each(&[2, 1, 0, 1, 2, 1]);
        assert!(matches!(c, TriangleCounts::Wide(_)));
        assert_eq!(c.to_vec(), vec![1, u32::MAX as u64 + 2, 7]);
        let mut d = TriangleCounts::zeros(3);
        d.increment_each(&[0, 2, 2]);
        assert_eq!(d, TriangleCounts::Narrow(vec![1, 0, 2]));
        c.increment_each(&[0]);
        assert_eq!(c.get(0), 2);
    }

    #[test]
    fn triangle_counts_widen_exactly_past_u32() {
        let mut c = TriangleCounts::zeros(3);
        c.add_at(1, u32::MAX as u64 - 1);
        c.increment(1);
        assert!(matches!(c, TriangleCounts::Narrow(_)));
        c.increment(1);
        c.increment(2);
        assert!(matches!(c, TriangleCounts::Wide(_)));
        assert_eq!(c.to_vec(), vec![0, u32::MAX as u64 + 1, 1]);
        let mut d = TriangleCounts::zeros(3);
        d.add(&c);
        d.add(&c);
        assert_eq!(d.to_vec(), vec![0, 2 * (u32::MAX as u64 + 1), 2]);
        assert_eq!(TriangleCounts::from(d.to_vec()), d);
        // Two narrow arrays whose sum passes u32 in the middle: every count is added once.
        let mut e = TriangleCounts::Narrow(vec![1, u32::MAX, 3]);
        e.add(&TriangleCounts::Narrow(vec![1, 1, 1]));
        assert_eq!(e, TriangleCounts::Wide(vec![2, u32::MAX as u64 + 1, 4]));
        assert_eq!(
            TriangleCounts::from(vec![5, 6]),
            TriangleCounts::Narrow(vec![5, 6])
        );
    }

    #[test]
    fn deposit_codes_are_distinct_per_slot() {
        let mut codes = std::collections::HashSet::new();
        for tri in 0..3 {
            for b in 0..8u32 {
                codes.insert(deposit_code(tri, b & 4 != 0, b & 2 != 0, b & 1 != 0));
            }
        }
        assert_eq!(codes.len(), 24);
        assert_eq!(deposit_code(2, true, true, true), 23);
        for b in 0..8u32 {
            let slot = Slot::of(deposit_code(0, b & 4 != 0, b & 2 != 0, b & 1 != 0) as usize);
            assert_eq!(
                (slot.back_face, slot.indirect, slot.odd_photon),
                (b & 4 != 0, b & 2 != 0, b & 1 != 0)
            );
        }
    }
}

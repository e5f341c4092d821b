//! Tallies: *where* light scores (receiver cells, triangle faces) and *what* it scores
//! (Σx, Σx², Σx³, Σx⁴ and hits per cell; photon counts per triangle face).
//!
//! Workers fill a [`ChunkTally`] per fixed range of photons; [`Tallies::accumulate`] folds
//! the chunks in photon order once per epoch, so the sums do not depend on the number of
//! threads or on scheduling.

pub(crate) mod receiver;

pub use receiver::ReceiverGrid;

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

/// One chunk's scores in one receiver cell: the moments Σx, Σx², Σx³, Σx⁴ over the
/// chunk's histories (each history's scores in the cell summed first, so eqs. 6–8 see
/// per-history scores) and the crossings or contributions counted.
/// Serialised as is by checkpoints (a shard's chunks) and MPI (a worker's chunks).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CellPartial {
    /// Global cell index over all receivers (see [`ReceiverGrid::first_cell`]).
    pub cell: u32,
    pub hits: u64,
    pub moments: [f64; 4],
}

impl CellPartial {
    /// Adds one history's score `x` made of `hits` contributions.
    #[inline]
    pub fn add_history(&mut self, x: f64, hits: u64) {
        let x2 = x * x;
        for (m, v) in self.moments.iter_mut().zip([x, x2, x2 * x, x2 * x2]) {
            *m += v;
        }
        self.hits += hits;
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

/// Photon counts per triangle slot, held as u32 (half the memory of the triangle maps,
/// which dominate it in large scenes) until one count would pass u32::MAX, then as u64
/// from that moment on: exact either way.
#[derive(Clone, Debug, PartialEq)]
pub enum TriangleCounts {
    Narrow(Vec<u32>),
    Wide(Vec<u64>),
}

impl Default for TriangleCounts {
    fn default() -> Self {
        TriangleCounts::Narrow(Vec::new())
    }
}

impl TriangleCounts {
    /// `n` zero counts (the zeroed pages are only touched where photons land).
    pub fn zeros(n: usize) -> TriangleCounts {
        TriangleCounts::Narrow(vec![0; n])
    }

    pub fn len(&self) -> usize {
        match self {
            TriangleCounts::Narrow(v) => v.len(),
            TriangleCounts::Wide(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Count `i`.
    #[inline]
    pub fn get(&self, i: usize) -> u64 {
        match self {
            TriangleCounts::Narrow(v) => v[i] as u64,
            TriangleCounts::Wide(v) => v[i],
        }
    }

    /// Adds one to count `i`.
    #[inline]
    pub fn increment(&mut self, i: usize) {
        self.add_at(i, 1);
    }

    /// Adds one to count `code` for each of `codes` ([`Self::increment`] for each, the
    /// same counts), with the width matched once rather than per code: a chunk's
    /// deposits, folded into the run's tallies (0.5 ns per ray of the office's photon
    /// pass).
    pub fn increment_each(&mut self, mut codes: &[u32]) {
        if let TriangleCounts::Narrow(v) = self {
            let mut done = codes.len();
            for (k, &code) in codes.iter().enumerate() {
                let c = &mut v[code as usize];
                if *c == u32::MAX {
                    done = k;
                    break;
                }
                *c += 1;
            }
            if done == codes.len() {
                return;
            }
            self.widen();
            codes = &codes[done..];
        }
        if let TriangleCounts::Wide(v) = self {
            for &code in codes {
                v[code as usize] += 1;
            }
        }
    }

    /// Adds `n` to count `i`, widening every count first if it would not fit in u32.
    #[inline]
    pub fn add_at(&mut self, i: usize, n: u64) {
        if let TriangleCounts::Narrow(v) = self {
            match u32::try_from(v[i] as u64 + n) {
                Ok(sum) => {
                    v[i] = sum;
                    return;
                }
                Err(_) => self.widen(),
            }
        }
        if let TriangleCounts::Wide(v) = self {
            v[i] += n;
        }
    }

    /// Switches to u64 counts.
    #[cold]
    fn widen(&mut self) {
        if let TriangleCounts::Narrow(v) = self {
            *self = TriangleCounts::Wide(v.iter().map(|&c| c as u64).collect());
        }
    }

    /// Adds `other` count by count (integers: any order gives the same sums), widening
    /// at the first sum past u32.
    pub fn add(&mut self, other: &TriangleCounts) {
        use TriangleCounts::{Narrow, Wide};
        let done = match (&mut *self, other) {
            (Narrow(a), Narrow(b)) => add_narrow(a, b),
            (Narrow(a), Wide(b)) => add_narrow(a, b),
            (Wide(_), _) => 0,
        };
        if done == self.len().min(other.len()) {
            return;
        }
        self.widen();
        let Wide(a) = self else {
            unreachable!("widened above")
        };
        match other {
            Narrow(b) => add_wide(&mut a[done..], &b[done..]),
            Wide(b) => add_wide(&mut a[done..], &b[done..]),
        }
    }

    /// Triangle `k`'s [`CODES_PER_TRIANGLE`] counts.
    #[inline]
    pub fn slots(&self, k: usize) -> [u64; CODES_PER_TRIANGLE] {
        let range = k * CODES_PER_TRIANGLE..(k + 1) * CODES_PER_TRIANGLE;
        match self {
            TriangleCounts::Narrow(v) => {
                let s = &v[range];
                std::array::from_fn(|i| s[i] as u64)
            }
            TriangleCounts::Wide(v) => {
                let s = &v[range];
                std::array::from_fn(|i| s[i])
            }
        }
    }

    /// Every count as u64 (checkpoints).
    pub fn to_vec(&self) -> Vec<u64> {
        (0..self.len()).map(|i| self.get(i)).collect()
    }
}

/// Adds `b` to `a` while the sums fit in u32; returns how many counts were added.
/// Zero counts are skipped: `a`'s zeroed pages stay untouched.
fn add_narrow<T: Copy + Into<u64>>(a: &mut [u32], b: &[T]) -> usize {
    for (i, (x, &y)) in a.iter_mut().zip(b).enumerate() {
        let y = y.into();
        if y > 0 {
            match u32::try_from(*x as u64 + y) {
                Ok(sum) => *x = sum,
                Err(_) => return i,
            }
        }
    }
    a.len().min(b.len())
}

/// Adds `b` to `a`, skipping zeros as [`add_narrow`] does.
fn add_wide<T: Copy + Into<u64>>(a: &mut [u64], b: &[T]) {
    for (x, &y) in a.iter_mut().zip(b) {
        let y = y.into();
        if y > 0 {
            *x += y;
        }
    }
}

/// Saved as the sequence of u64 counts, so the bytes are those of a `Vec<u64>`
/// whichever width the counts are held in.
impl serde::Serialize for TriangleCounts {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq((0..self.len()).map(|i| self.get(i)))
    }
}

impl<'de> serde::Deserialize<'de> for TriangleCounts {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        Vec::<u64>::deserialize(deserializer).map(TriangleCounts::from)
    }
}

impl From<Vec<u64>> for TriangleCounts {
    /// Narrow when every count fits in u32.
    fn from(counts: Vec<u64>) -> Self {
        if counts.iter().all(|&c| c <= u32::MAX as u64) {
            TriangleCounts::Narrow(counts.iter().map(|&c| c as u32).collect())
        } else {
            TriangleCounts::Wide(counts)
        }
    }
}

/// Neumaier-compensated f64 sum: stays exact to ~1 ulp over billions of terms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompensatedSum {
    sum: f64,
    compensation: f64,
}

impl CompensatedSum {
    #[inline]
    pub fn add(&mut self, x: f64) {
        let t = self.sum + x;
        if self.sum.abs() >= x.abs() {
            self.compensation += (self.sum - t) + x;
        } else {
            self.compensation += (x - t) + self.sum;
        }
        self.sum = t;
    }

    #[inline]
    pub fn value(&self) -> f64 {
        self.sum + self.compensation
    }

    /// The running sum and its compensation term, bit for bit (checkpoints).
    pub fn parts(&self) -> (f64, f64) {
        (self.sum, self.compensation)
    }

    /// The sum whose [`parts`](Self::parts) are these.
    pub fn from_parts(sum: f64, compensation: f64) -> CompensatedSum {
        CompensatedSum { sum, compensation }
    }
}

/// Per-cell moments of the history scores, and of the cell's sampled direct light.
#[derive(Clone, Copy, Debug, Default)]
pub struct CellSums {
    /// Σx, Σx², Σx³, Σx⁴ of the photon histories' scores.
    pub moments: [CompensatedSum; 4],
    /// Contributions scored: photon crossings and connections, and direct-light
    /// replicates that saw light.
    pub hits: u64,
    /// Σy, Σy², Σy³, Σy⁴ of the direct-light replicates (next-event receivers; see
    /// `trace::direct`), in the receiver's unit; `Tallies::direct_replicates` of them.
    pub direct: [CompensatedSum; 4],
}

impl CellSums {
    #[inline]
    fn add(&mut self, partial: &CellPartial) {
        for (total, part) in self.moments.iter_mut().zip(partial.moments) {
            total.add(part);
        }
        self.hits += partial.hits;
    }

    /// Adds one direct-light replicate `y` (call in replicate order); a replicate that
    /// saw light counts as a hit.
    #[inline]
    pub fn add_direct(&mut self, y: f64) {
        let y2 = y * y;
        for (m, v) in self.direct.iter_mut().zip([y, y2, y2 * y, y2 * y2]) {
            m.add(v);
        }
        self.hits += (y != 0.0) as u64;
    }

    pub fn sum(&self) -> f64 {
        self.moments[0].value()
    }

    pub fn sum_sq(&self) -> f64 {
        self.moments[1].value()
    }

    /// Σy and Σy² of the direct-light replicates.
    pub fn direct_sums(&self) -> (f64, f64) {
        (self.direct[0].value(), self.direct[1].value())
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
    /// One entry per cell of every receiver, receivers in scene order.
    pub cells: Vec<CellSums>,
    /// Direct-light replicates added to every next-event receiver's cells so far, and
    /// the shadow rays they took.
    pub direct_replicates: u64,
    pub direct_rays: u64,
    /// The scene emits no light: every value is exactly 0, with no error.
    pub dark: bool,
}

/// What a cell's sums were accumulated over.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counts {
    pub photons: u64,
    pub direct_replicates: u64,
    /// No light at all: nothing scored means exactly 0.
    pub dark: bool,
}

impl Tallies {
    pub fn new(triangles: usize, cells: usize) -> Tallies {
        Tallies {
            triangle_hits: TriangleCounts::zeros(triangles * CODES_PER_TRIANGLE),
            cells: vec![CellSums::default(); cells],
            ..Tallies::default()
        }
    }

    /// Folds one chunk of `photons` photons in (call in photon order).
    pub fn accumulate(&mut self, chunk: &ChunkTally, photons: u64) {
        self.photons += photons;
        self.rays += chunk.rays;
        self.killed_by_bounce_cap += chunk.killed_by_bounce_cap;
        for (total, part) in self.history_hits.iter_mut().zip(chunk.history_hits) {
            *total += part;
        }
        self.triangle_hits.increment_each(&chunk.deposits);
        for p in &chunk.scores {
            self.cells[p.cell as usize].add(p);
        }
    }

    /// What the cells' sums were accumulated over.
    pub fn counts(&self) -> Counts {
        Counts {
            photons: self.photons,
            direct_replicates: self.direct_replicates,
            dark: self.dark,
        }
    }

    /// The cells of receiver `r` of `receivers` (all receivers' cells lie back to back).
    pub fn receiver_cells(&self, receivers: &[crate::scene::Receiver], r: usize) -> &[CellSums] {
        let first: usize = receivers[..r].iter().map(|x| x.cell_count()).sum();
        &self.cells[first..first + receivers[r].cell_count()]
    }

    /// Photons of odd and of even index among the first `photons`.
    pub fn odd_even_photons(&self) -> (u64, u64) {
        (self.photons / 2, self.photons - self.photons / 2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compensated_sum_keeps_twelve_digits_over_a_billion_terms() {
        // 10⁹ increments of 0.1 (not representable): a naive f64 sum drifts in the 8th
        // digit; the compensated one must keep 12 significant digits.
        let mut s = CompensatedSum::default();
        let n = 1_000_000_000u64;
        for _ in 0..n {
            s.add(0.1);
        }
        let exact = 0.1 * n as f64;
        assert!(((s.value() - exact) / exact).abs() < 1e-12, "{}", s.value());
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
        let mut t = Tallies::new(0, 0);
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

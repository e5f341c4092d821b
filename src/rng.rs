//! Random numbers: photon `i` of a run gets its own stream derived from (seed, i) alone
//! ([`PhotonStreams`]), so results never depend on threads or scheduling; so do the eye
//! pass's pixels and the direct light's replicates ([`stream`]).

use rand::SeedableRng;
use rand_pcg::Pcg32;

/// SplitMix64 finaliser: a bijective 64-bit mix.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The seed of part `index` of a run seeded with `seed` (an annual run's sources): two
/// SplitMix finalisers deep, so neighbouring parts' seeds share nothing.
pub fn sub_seed(seed: u64, index: u64) -> u64 {
    mix64(mix64(seed ^ 0x243f_6a88_85a3_08d3) ^ index.wrapping_mul(GOLDEN_GAMMA))
}

/// Random stream `index` of a run seeded with `seed`, three SplitMix finalisers deep: an
/// eye-pass pixel's, a direct-light replicate's ([`direct_stream`]). The photon pass
/// seeds its photons more cheaply ([`PhotonStreams`]).
#[inline]
pub fn stream(seed: u64, index: u64) -> Pcg32 {
    let state = mix64(seed ^ mix64(index.wrapping_add(GOLDEN_GAMMA)));
    let stream = mix64(state ^ 0x5851_f42d_4c95_7f2d);
    Pcg32::new(state, stream)
}

/// The streams of photons `first`, `first + 1`, … of a run seeded with `seed`, handed to
/// the emitters: each photon's stream is seeded in the loop that takes its emission
/// draws (one pass over the batch, not a seeding pass whose streams the emission then
/// reads back).
///
/// Photon i's PCG32 has stream (increment) i and a state hashed from (seed, i): output i
/// of SplitMix64 started at a key hashed from the seed. Distinct increments keep every
/// photon's sequence apart from every other's; the hashed state scatters where each one
/// starts. Four 64-bit multiplies per photon, against seven for [`stream`]
/// (three SplitMix finalisers), whose chain of multiplies was the costliest part of
/// emitting a photon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PhotonStreams {
    /// SplitMix64's start for this run, from the seed.
    key: u64,
    /// Index of the batch's first photon.
    pub first: u64,
    /// Set apart from the photons' the increments of other streams of a photon index.
    tag: u64,
}

impl PhotonStreams {
    pub fn new(seed: u64, first: u64) -> Self {
        PhotonStreams {
            key: mix64(seed ^ 0x5851_f42d_4c95_7f2d),
            first,
            tag: 0,
        }
    }

    /// The streams of the portal photons of photon indices `first`, `first + 1`, …:
    /// their own keys and increments (bit 62 set: no photon index reaches it), so
    /// independent of every photon's.
    pub fn portal(seed: u64, first: u64) -> Self {
        PhotonStreams {
            key: mix64(seed ^ 0x3c6e_f372_fe94_f82b),
            first,
            tag: 1 << 62,
        }
    }

    /// The stream of photon `first + k`.
    #[inline(always)]
    pub fn get(&self, k: usize) -> Pcg32 {
        let index = self.first + k as u64;
        let state = mix64(self.key.wrapping_add(index.wrapping_mul(GOLDEN_GAMMA)));
        Pcg32::new(state, index ^ self.tag)
    }
}

/// SplitMix64's increment, 2⁶⁴/φ rounded to odd.
const GOLDEN_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// A stream for a purpose other than photons (tests, benchmarks), seeded from `seed`.
pub fn aux_stream(seed: u64) -> Pcg32 {
    Pcg32::seed_from_u64(mix64(seed ^ 0xdead_beef_cafe_f00d))
}

/// The random stream of direct-light replicate `replicate` of receiver cell `cell` (a
/// global cell index) in a run seeded with `seed`: disjoint from the photons' streams,
/// so the direct light never depends on threads, epochs or photons. Distinct for cells
/// and replicates below 2³².
#[inline]
pub fn direct_stream(seed: u64, cell: u64, replicate: u64) -> Pcg32 {
    stream(
        mix64(seed ^ 0x6a09_e667_f3bc_c909),
        (cell << 32) ^ replicate,
    )
}

/// Photons per block of a randomised quasi-Monte Carlo (QMC) run, 2^11: each block of
/// photon indices (`i >> QMC_LOG2_BLOCK`) is scrambled on its own, so blocks are
/// independent replicates and the statistics take each block as one history.
pub const QMC_LOG2_BLOCK: u32 = 11;

/// What a QMC draw of a photon takes: two dimensions of its joint Sobol' point (the
/// emission's direction, dimensions 0 and 1, its first vertex's connection points, 2
/// and 3, and the point of the source it leaves, 4 and 5, stratified together), or a
/// pair of its own (every later draw, identified by `pair`: padded, as pbrt-v4's
/// PaddedSobolSampler pads dimensions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QmcDraw {
    Emission,
    FirstConnection,
    Origin,
    Padded(u64),
}

/// Photon `photon`'s point of `draw` in a run seeded with `seed`, in [0, 1)²: the
/// photon's point of its block's 2^[`QMC_LOG2_BLOCK`]-point Sobol' net, its index
/// shuffled and each dimension Owen-scrambled by hashes of (seed, block, pair) (Burley
/// 2020, "Practical Hash-based Owen Scrambling"). Every point is uniform on [0, 1)²
/// (so each estimate stays unbiased), and a block's points of a pair are a
/// (0, 11, 2)-net (the emission's and the padded pairs; the first connection's and the
/// origin's, Sobol's dimensions 2 and 3 and 4 and 5, (2, 11, 2)-nets): a block stratifies
/// what they pick.
#[inline]
pub fn qmc_square(seed: u64, photon: u64, draw: QmcDraw) -> (f64, f64) {
    block_square(seed, photon, None, draw)
}

/// [`qmc_square`]'s point number `rank` of photon `photon`'s block, its index not
/// shuffled, for draws made by only some of a block's photons (those still travelling
/// at a depth), numbered in photon order: the first `count` points of a scrambled Sobol'
/// sequence are evenly spread for any `count`, where the points of a random subset of
/// the photons' indices would not be. Every point is still uniform on [0, 1)², whatever
/// picked the rank, so every estimate stays unbiased.
#[inline]
pub fn qmc_square_ranked(seed: u64, photon: u64, rank: u32, draw: QmcDraw) -> (f64, f64) {
    block_square(seed, photon, Some(rank), draw)
}

#[inline]
fn block_square(seed: u64, photon: u64, rank: Option<u32>, draw: QmcDraw) -> (f64, f64) {
    QmcBlock::new(seed, photon, draw).square(photon, rank)
}

/// The scrambles of one draw over one block of photons ([`qmc_square`]): computed once,
/// they serve every photon of the block (an emission loop's photons run in blocks).
#[derive(Clone, Copy, Debug)]
pub struct QmcBlock {
    block: u64,
    index_key: u32,
    dimension_keys: [u32; 2],
    first_dimension: usize,
}

impl QmcBlock {
    /// The scrambles of `draw` over the block that holds photon `photon`.
    #[inline]
    pub fn new(seed: u64, photon: u64, draw: QmcDraw) -> QmcBlock {
        let (pair, first_dimension) = match draw {
            QmcDraw::Emission => (u64::MAX, 0),
            QmcDraw::FirstConnection => (u64::MAX, 2),
            QmcDraw::Origin => (u64::MAX, 4),
            QmcDraw::Padded(pair) => (pair, 0),
        };
        let block = photon >> QMC_LOG2_BLOCK;
        let scramble = mix64(mix64(seed ^ 0x1f83_d9ab_fb41_bd6b) ^ block);
        let scramble = mix64(scramble ^ pair.wrapping_mul(GOLDEN_GAMMA));
        let key = |d: usize| mix64(scramble ^ (d as u64 + 1)) as u32;
        QmcBlock {
            block,
            index_key: scramble as u32,
            dimension_keys: [key(first_dimension), key(first_dimension + 1)],
            first_dimension,
        }
    }

    /// Whether photon `photon` is in this block.
    #[inline]
    pub fn holds(&self, photon: u64) -> bool {
        photon >> QMC_LOG2_BLOCK == self.block
    }

    /// Photon `photon`'s point (the block's point number `rank` when given).
    #[inline]
    pub fn square(&self, photon: u64, rank: Option<u32>) -> (f64, f64) {
        debug_assert!(self.holds(photon));
        let mask = (1u32 << QMC_LOG2_BLOCK) - 1;
        let index = match rank {
            Some(rank) => rank & mask,
            None => nested_uniform_scramble(photon as u32 & mask, self.index_key) & mask,
        };
        let coordinate = |k: usize| {
            let x = sobol(index, self.first_dimension + k);
            nested_uniform_scramble(x, self.dimension_keys[k]) as f64 * (1.0 / 4_294_967_296.0)
        };
        (coordinate(0), coordinate(1))
    }
}

/// Point `sample` of replicate `replicate` of direct-light cell `cell`'s QMC pattern in a
/// run seeded with `seed` (`run --qmc`), in [0, 1)⁴: point `sample` of the Sobol'
/// sequence's dimensions 0–3, each Owen-scrambled by hashes of (seed, cell, replicate).
/// Every point is uniform on [0, 1)⁴, so each sample stays unbiased, and replicates are
/// independent scrambles, so their spread is their mean's σ as for ordinary replicates;
/// a replicate's 2^k points are a (0, k, 2)-net in dimensions 0–1 and a (t, k, 2)-net
/// (t ≤ 2) in dimensions 2–3.
#[inline]
pub fn direct_qmc_point(seed: u64, cell: u64, replicate: u64, sample: u32) -> [f64; 4] {
    let scramble = mix64(mix64(seed ^ 0x5be0_cd19_137e_2179) ^ cell.wrapping_mul(GOLDEN_GAMMA));
    let scramble = mix64(scramble ^ replicate);
    std::array::from_fn(|d| {
        let x = nested_uniform_scramble(sobol(sample, d), mix64(scramble ^ (d as u64 + 1)) as u32);
        x as f64 * (1.0 / 4_294_967_296.0)
    })
}

/// Sobol's first six dimensions' direction numbers (Joe & Kuo's new-joe-kuo-6.21201: the
/// van der Corput sequence, then the primitive polynomials x + 1, x² + x + 1,
/// x³ + x + 1, x³ + x² + 1 and x⁴ + x + 1 with m = (1), (1, 3), (1, 3, 1), (1, 1, 1),
/// (1, 1, 3, 3)).
const SOBOL_DIRECTIONS: [[u32; 32]; 6] = [
    sobol_directions(0, 0, &[]),
    sobol_directions(1, 0, &[1]),
    sobol_directions(2, 1, &[1, 3]),
    sobol_directions(3, 1, &[1, 3, 1]),
    sobol_directions(3, 2, &[1, 1, 1]),
    sobol_directions(4, 1, &[1, 1, 3, 3]),
];

/// Direction numbers of a dimension of degree `s` polynomial coefficients `a` and initial
/// numbers `m` (Joe & Kuo's recurrence; degree 0: the van der Corput sequence).
const fn sobol_directions(s: usize, a: u32, m: &[u32]) -> [u32; 32] {
    let mut v = [0u32; 32];
    let mut i = 0;
    while i < 32 {
        v[i] = if s == 0 {
            1 << (31 - i)
        } else if i < s {
            m[i] << (31 - i)
        } else {
            let mut x = v[i - s] ^ (v[i - s] >> s);
            let mut k = 1;
            while k < s {
                x ^= ((a >> (s - 1 - k)) & 1) * v[i - k];
                k += 1;
            }
            x
        };
        i += 1;
    }
    v
}

/// Coordinate `dimension` (0–5) of point `index` of the Sobol' sequence, as 32 bits.
#[inline]
fn sobol(mut index: u32, dimension: usize) -> u32 {
    let directions = &SOBOL_DIRECTIONS[dimension];
    let mut x = 0;
    while index != 0 {
        x ^= directions[index.trailing_zeros() as usize];
        index &= index - 1;
    }
    x
}

/// Owen's nested uniform scramble of the binary fraction `x`: each bit flips by a hash of
/// the bits above it (Vegdahl's hash in Laine–Karras form, on the reversed bits, where
/// each bit depends on the bits below it only).
#[inline]
fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    let mut y = x.reverse_bits();
    y ^= y.wrapping_mul(0x3d20_adea);
    y = y.wrapping_add(seed);
    y = y.wrapping_mul((seed >> 16) | 1);
    y ^= y.wrapping_mul(0x0552_6c56);
    y ^= y.wrapping_mul(0x53a2_2864);
    y.reverse_bits()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngCore;

    const M: u32 = QMC_LOG2_BLOCK;

    /// Points of `draw` of the block of photons from `first`, on a 2^M × 2^M grid.
    fn block_points(seed: u64, first: u64, draw: QmcDraw) -> Vec<(u32, u32)> {
        let side = (1u64 << M) as f64;
        (first..first + (1 << M))
            .map(|i| {
                let (u, v) = qmc_square(seed, i, draw);
                assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
                ((u * side) as u32, (v * side) as u32)
            })
            .collect()
    }

    /// Whether every box of 2^a × 2^(M−t−a) cells, for every a, holds exactly 2^t
    /// points: a (t, M, 2)-net.
    fn is_a_net(points: &[(u32, u32)], t: u32) -> bool {
        is_a_net_of(points, M, t)
    }

    /// [`is_a_net`] for 2^`log2_points` points (on the same 2^M × 2^M grid): a
    /// (t, log2_points, 2)-net.
    fn is_a_net_of(points: &[(u32, u32)], log2_points: u32, t: u32) -> bool {
        let m = log2_points - t;
        (0..=m).all(|a| {
            let mut count = vec![0u32; 1 << m];
            for &(u, v) in points {
                count[(((u >> (M - a)) << (m - a)) | (v >> (M - m + a))) as usize] += 1;
            }
            count.iter().all(|&c| c == 1 << t)
        })
    }

    #[test]
    fn a_qmc_block_is_a_net_and_blocks_are_scrambled_apart() {
        // Sobol's dimensions 2 and 3, and 4 and 5, together are (2, M, 2)-nets, each
        // alone a (0, M, 1)-net (the boxes of one row or one column).
        let draws = [
            (QmcDraw::Emission, 0),
            (QmcDraw::Padded(7), 0),
            (QmcDraw::FirstConnection, 2),
            (QmcDraw::Origin, 2),
        ];
        for (draw, t) in draws {
            let block = block_points(3, 8192, draw);
            assert!(is_a_net(&block, t), "{draw:?}");
            assert!(t == 0 || !is_a_net(&block, t - 1), "{draw:?}");
            let mut rows: Vec<u32> = block.iter().map(|p| p.0).collect();
            rows.sort_unstable();
            assert!(
                rows.iter().enumerate().all(|(k, &r)| r == k as u32),
                "{draw:?}"
            );
            // Another block, seed or pair: another scramble of the net.
            assert_ne!(block, block_points(3, 12288, draw), "{draw:?}");
            assert_ne!(block, block_points(4, 8192, draw), "{draw:?}");
        }
        assert_ne!(
            block_points(3, 0, QmcDraw::Padded(1)),
            block_points(3, 0, QmcDraw::Padded(2))
        );
    }

    /// Ranked draws take the block's points in sequence order, so those of the first
    /// 2^k ranks are a (0, k, 2)-net whatever photons drew them; every block has its own
    /// scramble, and a rank's point is uniform over blocks.
    #[test]
    fn ranked_draws_are_nets_by_prefix_and_uniform_over_blocks() {
        let draw = QmcDraw::Padded(5);
        for k in [6, 9, 10] {
            let prefix: Vec<(u32, u32)> = (0..1u32 << k)
                .map(|rank| {
                    // Any photon of the block: only its block counts.
                    let photon = 8192 + (3 * rank as u64) % 2048;
                    let (u, v) = qmc_square_ranked(3, photon, rank, draw);
                    (
                        (u * (1u64 << M) as f64) as u32,
                        (v * (1u64 << M) as f64) as u32,
                    )
                })
                .collect();
            assert!(
                is_a_net_of(&prefix, k, 0),
                "the first 2^{k} ranks are not a (0, {k}, 2)-net"
            );
        }
        assert_ne!(
            qmc_square_ranked(3, 0, 17, draw),
            qmc_square_ranked(3, 2048, 17, draw)
        );
        let mut bins = [0u32; 256];
        for block in 0..16_384u64 {
            let (u, v) = qmc_square_ranked(11, block << QMC_LOG2_BLOCK, 77, draw);
            bins[(u * 16.0) as usize * 16 + (v * 16.0) as usize] += 1;
        }
        let chi2: f64 = bins.iter().map(|&b| (b as f64 - 64.0).powi(2) / 64.0).sum();
        assert!(chi2 < 340.0, "χ² = {chi2}");
    }

    #[test]
    fn a_photons_qmc_point_is_uniform_over_blocks() {
        // One photon slot of 16,384 blocks: 16 × 16 bins, each expected 64 times; a
        // χ² of 255 dof above 340 has probability below 3·10⁻⁴.
        for draw in [
            QmcDraw::Emission,
            QmcDraw::FirstConnection,
            QmcDraw::Origin,
            QmcDraw::Padded(3),
        ] {
            let mut bins = [0u32; 256];
            for block in 0..16_384u64 {
                let (u, v) = qmc_square(11, (block << QMC_LOG2_BLOCK) + 77, draw);
                bins[(u * 16.0) as usize * 16 + (v * 16.0) as usize] += 1;
            }
            let chi2: f64 = bins.iter().map(|&b| (b as f64 - 64.0).powi(2) / 64.0).sum();
            assert!(chi2 < 340.0, "{draw:?}: χ² = {chi2}");
        }
    }

    /// A direct-light replicate's 2^k points are a (0, k, 2)-net in dimensions 0–1 and a
    /// (t ≤ 2, k, 2)-net in 2–3, for the 4, 16 and 64 points of 2, 4 and 8 per side;
    /// cells and replicates have their own scrambles, and a sample's point is uniform
    /// over replicates.
    #[test]
    fn a_direct_replicates_points_are_nets_and_uniform_over_replicates() {
        let grid = |x: f64| (x * (1u64 << M) as f64) as u32;
        for k in [2, 4, 6] {
            let points: Vec<[f64; 4]> = (0..1u32 << k)
                .map(|sample| direct_qmc_point(3, 40, 7, sample))
                .collect();
            let pair = |d: usize| -> Vec<(u32, u32)> {
                points
                    .iter()
                    .map(|p| (grid(p[d]), grid(p[d + 1])))
                    .collect()
            };
            assert!(is_a_net_of(&pair(0), k, 0), "dimensions 0–1, 2^{k} points");
            assert!(
                is_a_net_of(&pair(2), k, 2.min(k)),
                "dimensions 2–3, 2^{k} points"
            );
        }
        let point = direct_qmc_point(3, 40, 7, 5);
        assert_ne!(point, direct_qmc_point(3, 41, 7, 5));
        assert_ne!(point, direct_qmc_point(3, 40, 8, 5));
        assert_ne!(point, direct_qmc_point(4, 40, 7, 5));
        for d in [0, 2] {
            let mut bins = [0u32; 256];
            for replicate in 0..16_384u64 {
                let p = direct_qmc_point(11, 9, replicate, 13);
                bins[(p[d] * 16.0) as usize * 16 + (p[d + 1] * 16.0) as usize] += 1;
            }
            let chi2: f64 = bins.iter().map(|&b| (b as f64 - 64.0).powi(2) / 64.0).sum();
            assert!(chi2 < 340.0, "dimensions {d}–{}: χ² = {chi2}", d + 1);
        }
    }

    #[test]
    fn a_photons_stream_depends_on_the_seed_and_its_index_alone() {
        // Whatever batch a photon falls in (chunks of other sizes, other threads), it
        // draws the same numbers; other photons and other seeds draw others.
        let draws = |mut rng: Pcg32| [rng.next_u32(), rng.next_u32(), rng.next_u32()];
        let photon = |seed, first, k| draws(PhotonStreams::new(seed, first).get(k));
        for index in [0, 1, 4095, 4096, 1 << 40] {
            let d = photon(7, index, 0);
            assert_eq!(d, photon(7, 0, index as usize));
            assert_eq!(d, photon(7, index - index / 2, (index / 2) as usize));
            assert_ne!(d, photon(7, index + 1, 0));
            assert_ne!(d, photon(8, index, 0));
        }
    }
}

//! Random numbers: photon `i` of a run gets its own stream derived from (seed, i), so
//! results never depend on threads or scheduling.

use rand::SeedableRng;
use rand_pcg::Pcg32;

/// SplitMix64 finaliser: a bijective 64-bit mix.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The random stream of photon `index` in a run seeded with `seed`.
#[inline]
pub fn photon_stream(seed: u64, index: u64) -> Pcg32 {
    let state = mix64(seed ^ mix64(index.wrapping_add(0x9e37_79b9_7f4a_7c15)));
    let stream = mix64(state ^ 0x5851_f42d_4c95_7f2d);
    Pcg32::new(state, stream)
}

/// The streams of photons `first`, `first + 1`, … of a run seeded with `seed`, handed to
/// the emitters: each photon's stream is seeded in the loop that takes its emission
/// draws (one pass over the batch, not a seeding pass whose streams the emission then
/// reads back).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PhotonStreams {
    seed: u64,
    /// Index of the batch's first photon.
    pub first: u64,
}

impl PhotonStreams {
    pub fn new(seed: u64, first: u64) -> Self {
        PhotonStreams { seed, first }
    }

    /// The stream of photon `first + k`.
    #[inline(always)]
    pub fn get(&self, k: usize) -> Pcg32 {
        photon_stream(self.seed, self.first + k as u64)
    }
}

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
    photon_stream(
        mix64(seed ^ 0x6a09_e667_f3bc_c909),
        (cell << 32) ^ replicate,
    )
}

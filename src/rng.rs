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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngCore;

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

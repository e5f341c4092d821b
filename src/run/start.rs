//! Where a run starts and which photons it traces: from scratch or from a checkpoint's
//! state, the whole photon range or one shard's, on this process or shared with others.

use crate::distributed::Distributor;
use crate::tally::{CellPartial, ChunkTally};
use crate::trace::CHUNK_PHOTONS;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Shard `index` of `count`: the photons `first_photon .. end_photon`, whole chunks of
/// the run's chunk sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardRange {
    pub index: u32,
    pub count: u32,
    pub first_photon: u64,
    pub end_photon: u64,
}

impl ShardRange {
    /// Shard `index` (from 0) of `count` over `total` photons: chunks split as evenly as
    /// whole chunks allow.
    pub fn new(index: u32, count: u32, total: u64) -> Result<ShardRange> {
        if count == 0 || index >= count {
            return Err(Error::input(
                "--shard",
                format!("{index}/{count}: expected I/N with 0 ≤ I < N"),
            ));
        }
        let chunks = total.div_ceil(CHUNK_PHOTONS);
        if chunks < count as u64 {
            return Err(Error::input(
                "--shard",
                format!(
                    "{count} shards need at least {count} chunks of {CHUNK_PHOTONS} photons; \
                     --photons is {total}"
                ),
            ));
        }
        let chunk_of = |i: u64| (chunks as u128 * i as u128 / count as u128) as u64;
        Ok(ShardRange {
            index,
            count,
            first_photon: (chunk_of(index as u64) * CHUNK_PHOTONS).min(total),
            end_photon: (chunk_of(index as u64 + 1) * CHUNK_PHOTONS).min(total),
        })
    }

    /// `I/N` of the command line.
    pub fn parse(text: &str, total: u64) -> Result<ShardRange> {
        let bad = || Error::input("--shard", format!("`{text}`: expected I/N, e.g. 0/4"));
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let i: u32 = i.trim().parse().map_err(|_| bad())?;
        let n: u32 = n.trim().parse().map_err(|_| bad())?;
        ShardRange::new(i, n, total)
    }
}

/// What the merge needs of one chunk of a shard: its photons, photon rays and receiver
/// partials (the integer counters are added as shard totals).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChunkRecord {
    pub photons: u32,
    pub rays: u64,
    pub cells: Vec<CellPartial>,
}

impl ChunkRecord {
    pub fn of(chunk: &ChunkTally, photons: u32) -> ChunkRecord {
        ChunkRecord {
            photons,
            rays: chunk.rays,
            cells: chunk.scores.clone(),
        }
    }

    /// The chunk as a tally to fold (no deposits: the triangle map is added as totals).
    pub(crate) fn to_chunk(&self, chunk: &mut ChunkTally) {
        chunk.clear();
        chunk.rays = self.rays;
        chunk.scores.extend_from_slice(&self.cells);
    }
}

/// Where a run starts, which photons it traces and who traces them (see
/// [`run_from`](super::run_from)).
#[derive(Default)]
pub struct Start {
    /// A checkpoint's record to go on from.
    pub resumed: Option<super::Progress>,
    pub shard: Option<ShardRange>,
    /// Other processes sharing the chunks (MPI).
    pub distributor: Option<Box<dyn Distributor>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_the_chunks_without_gap_or_overlap() {
        let total = 10 * CHUNK_PHOTONS + 17;
        let mut next = 0;
        for i in 0..3 {
            let s = ShardRange::new(i, 3, total).unwrap();
            assert_eq!(s.first_photon, next);
            assert_eq!(s.first_photon % CHUNK_PHOTONS, 0);
            next = s.end_photon;
        }
        assert_eq!(next, total);
        assert!(ShardRange::new(3, 3, total).is_err());
        assert!(ShardRange::new(0, 12, total).is_err());
        assert!(ShardRange::parse("1/x", total).is_err());
    }
}

//! Several processes on one run (docs/distributed.md): the run's process (rank 0)
//! hands each epoch's chunks out, the others trace their share and send each chunk's
//! tally back; rank 0 folds them in chunk order, so the result is bit-identical to one
//! process. Everything else (statistics, stop, direct light, outputs, checkpoints)
//! stays on rank 0.

use crate::tally::{CellPartial, ChunkTally};
use serde::{Deserialize, Serialize};

/// Traces chunks (first photon, photons) into their tallies, in this process.
pub type LocalTracer<'a> = dyn FnMut(&[(u64, u32)], &mut [ChunkTally]) + 'a;

/// Traces an epoch's chunks, some here (`local`), some elsewhere.
pub trait Distributor {
    /// Fills `results[k]` with chunk `chunks[k]`'s tally; `local` traces chunks here.
    fn trace(
        &mut self,
        chunks: &[(u64, u32)],
        results: &mut [ChunkTally],
        local: &mut LocalTracer<'_>,
    );

    /// Processes sharing the chunks (for epoch sizing).
    fn processes(&self) -> usize;
}

/// What rank 0 tells a worker before each epoch.
#[derive(Serialize, Deserialize)]
pub enum Order {
    /// Trace these chunks (first photon, photons) and send their tallies back.
    Trace(Vec<(u64, u32)>),
    Stop,
}

/// A chunk's tally as sent to rank 0.
#[derive(Serialize, Deserialize)]
pub struct WireChunk {
    deposits: Vec<u32>,
    scores: Vec<CellPartial>,
    rays: u64,
    killed_by_bounce_cap: u64,
    history_hits: [u128; 4],
}

impl WireChunk {
    pub fn of(c: &ChunkTally) -> WireChunk {
        WireChunk {
            deposits: c.deposits.clone(),
            scores: c.scores.clone(),
            rays: c.rays,
            killed_by_bounce_cap: c.killed_by_bounce_cap,
            history_hits: c.history_hits,
        }
    }

    pub fn into_chunk(self, c: &mut ChunkTally) {
        c.clear();
        c.deposits = self.deposits;
        c.scores = self.scores;
        c.rays = self.rays;
        c.killed_by_bounce_cap = self.killed_by_bounce_cap;
        c.history_hits = self.history_hits;
    }
}

/// Chunks `lo..hi` of `count` that process `rank` of `size` traces: contiguous blocks.
pub fn share(count: usize, rank: usize, size: usize) -> std::ops::Range<usize> {
    count * rank / size..count * (rank + 1) / size
}

#[cfg(feature = "mpi")]
pub mod mpi {
    //! The [`Distributor`] over MPI (cargo feature `mpi`).

    use super::*;
    use crate::trace::{Scratch, Tracer};
    use ::mpi::topology::{Communicator, SimpleCommunicator};
    use ::mpi::traits::{Destination, Source};
    use rayon::prelude::*;

    fn encode<T: Serialize>(value: &T) -> Vec<u8> {
        postcard::to_stdvec(value).expect("in-memory encoding cannot fail")
    }

    /// Rank 0's side.
    pub struct Root {
        pub world: SimpleCommunicator,
        /// Bytes received from the workers, and epochs, in all.
        pub bytes_received: u64,
        pub epochs: u64,
        /// Print the traffic at the end.
        pub report: bool,
    }

    impl Distributor for Root {
        fn trace(
            &mut self,
            chunks: &[(u64, u32)],
            results: &mut [ChunkTally],
            local: &mut LocalTracer<'_>,
        ) {
            let size = self.world.size() as usize;
            self.epochs += 1;
            for rank in 1..size {
                let order = Order::Trace(chunks[share(chunks.len(), rank, size)].to_vec());
                self.world
                    .process_at_rank(rank as i32)
                    .send(&encode(&order)[..]);
            }
            let mine = share(chunks.len(), 0, size);
            local(&chunks[mine.clone()], &mut results[mine]);
            for rank in 1..size {
                let (bytes, _) = self.world.process_at_rank(rank as i32).receive_vec::<u8>();
                self.bytes_received += bytes.len() as u64;
                let wire: Vec<WireChunk> =
                    postcard::from_bytes(&bytes).expect("a worker sent its chunks");
                let theirs = share(chunks.len(), rank, size);
                assert_eq!(wire.len(), theirs.len(), "rank {rank} sent its chunks");
                for (w, slot) in wire.into_iter().zip(&mut results[theirs]) {
                    w.into_chunk(slot);
                }
            }
        }

        fn processes(&self) -> usize {
            self.world.size() as usize
        }
    }

    impl Drop for Root {
        /// Ends the workers, whatever ended the run.
        fn drop(&mut self) {
            if self.report {
                eprintln!(
                    "mpi: {} ranks, {:.1} MB of chunk tallies received in {} epochs ({:.1} kB per epoch)",
                    self.world.size(),
                    self.bytes_received as f64 / 1e6,
                    self.epochs,
                    self.bytes_received as f64 / 1e3 / self.epochs.max(1) as f64
                );
            }
            for rank in 1..self.world.size() {
                self.world
                    .process_at_rank(rank)
                    .send(&encode(&Order::Stop)[..]);
            }
        }
    }

    /// A worker's loop: traces the chunks rank 0 orders until it says stop.
    pub fn serve(world: &SimpleCommunicator, tracer: &Tracer<'_>, pool: &rayon::ThreadPool) {
        let root = world.process_at_rank(0);
        let mut results: Vec<ChunkTally> = Vec::new();
        loop {
            let (bytes, _) = root.receive_vec::<u8>();
            let chunks = match postcard::from_bytes(&bytes).expect("rank 0 sent an order") {
                Order::Stop => return,
                Order::Trace(chunks) => chunks,
            };
            if results.len() < chunks.len() {
                results.resize_with(chunks.len(), ChunkTally::default);
            }
            let out = &mut results[..chunks.len()];
            pool.install(|| {
                chunks.par_iter().zip(out.par_iter_mut()).for_each_init(
                    Scratch::default,
                    |scratch, (&(first, n), tally)| {
                        tracer.trace_chunk_into(first, n, scratch, tally)
                    },
                )
            });
            let wire: Vec<WireChunk> = out.iter().map(WireChunk::of).collect();
            root.send(&encode(&wire)[..]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chunk_travels_with_its_history_moments_exact() {
        // Σk⁴ of three 100,000-hit histories is 3·10²⁰, past u64: sent and received exactly.
        let mut c = ChunkTally::default();
        c.record_histories(100_000, 3);
        c.rays = 300_003;
        c.killed_by_bounce_cap = 1;
        let bytes = postcard::to_stdvec(&vec![WireChunk::of(&c)]).unwrap();
        let wire: Vec<WireChunk> = postcard::from_bytes(&bytes).unwrap();
        let mut back = ChunkTally::default();
        wire.into_iter().next().unwrap().into_chunk(&mut back);
        assert_eq!(back.history_hits, c.history_hits);
        assert_eq!(back.history_hits[3], 300_000_000_000_000_000_000);
        assert_eq!((back.rays, back.killed_by_bounce_cap), (300_003, 1));
    }
}

//! The `bench-*` commands: ray throughput, photon throughput, time to accuracy and scale.

pub mod accuracy;
mod chart;
pub mod photons;
pub mod rays;
pub mod scale;
mod timing;

/// Threads when `--threads` is not given.
fn all_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

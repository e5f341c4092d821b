//! luxtally: forward Monte Carlo photon tracing that tallies light on scene surfaces and
//! virtual receivers, and reports, forecasts and controls its own statistical error.
//!
//! Data path: `scene` (load and validate; `light` holds each light kind — its entry,
//! validation and emission — and `photometry` reads luminaires' files for it)
//! → `accel` (ray casting backends) → `tally` (receivers and triangle maps: where and
//! what scores) → `trace` (emission, BSDFs, photon batches, direct light) → `stats`
//! (equations of method.md, forecast, stop criteria) → `run` (epochs) → `output`
//! (summary.json and files) → `render` (the eye pass). `rng` and `sampling` serve them
//! all; `limits` sizes a run before it allocates; `checkpoint` and `distributed` save,
//! resume, shard and spread runs. Each module uses the ones before it, except
//! `checkpoint`, which `run` calls back.
//! `input` (deserialising entries with their key path, value checks) serves `scene` and
//! `light`. `raster` (bitmap font, PNG encoder, palettes, quantile) uses nothing of the
//! crate but its error type; `photometry`, `output` and `render` draw with it.
//! docs/architecture.md has the whole data path.

// `!(x > 0.0)` is deliberate throughout: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod bench;
pub mod checkpoint;
pub mod distributed;
pub mod error;
pub mod input;
pub mod light;
pub mod limits;
pub mod output;
pub mod photometry;
pub mod raster;
pub mod render;
pub mod rng;
pub mod run;
pub mod sampling;
pub mod scene;
pub mod stats;
pub mod tally;
pub mod trace;

pub use error::{Error, Result};

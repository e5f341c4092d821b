//! luxtally: forward Monte Carlo photon tracing that tallies light on scene surfaces and
//! virtual receivers, and reports, forecasts and controls its own statistical error.
//!
//! Data path (each module only uses the ones above it):
//! `scene` (load and validate) → `accel` (ray casting backends) → `trace` (photon
//! batches, epochs) → `tally` (receivers and triangle maps) → `stats` (equations of
//! method.md, forecast, stop criteria) → `output` (summary.json and files) → `render`
//! (the eye pass: images from a camera). `photometry` reads luminaires' photometric
//! files (IES LM-63, EULUMDAT) for the scene's lights; `limits` sizes a run from all of
//! them before it allocates. `raster` (bitmap font, PNG encoder, palettes, quantile) uses
//! nothing of the crate but its error type; `photometry`, `output` and `render` draw with
//! it. docs/architecture.md has the whole data path.

// `!(x > 0.0)` is deliberate throughout: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod bench;
pub mod checkpoint;
pub mod distributed;
pub mod error;
pub mod limits;
pub mod output;
pub mod photometry;
pub mod raster;
pub mod render;
pub mod rng;
pub mod run;
pub mod scene;
pub mod stats;
pub mod tally;
pub mod trace;

pub use error::{Error, Result};

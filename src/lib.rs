//! luxtally: forward Monte Carlo photon tracing that tallies light on scene surfaces and
//! virtual receivers, and reports, forecasts and controls its own statistical error.
//!
//! Data path (each module only uses the ones above it):
//! `scene` (load and validate) → `accel` (ray casting backends) → `trace` (photon
//! batches, epochs) → `tally` (receivers and triangle maps) → `stats` (equations of
//! method.md, forecast, stop criteria) → `output` (summary.json and files) → `render`
//! (the eye pass: images from a camera). `photometry` reads luminaires' photometric
//! files (IES LM-63, EULUMDAT) for the scene's lights.

pub mod accel;
pub mod bench;
pub mod checkpoint;
pub mod distributed;
pub mod error;
pub mod output;
pub mod photometry;
pub mod render;
pub mod rng;
pub mod run;
pub mod scene;
pub mod stats;
pub mod tally;
pub mod trace;

pub use error::{Error, Result};

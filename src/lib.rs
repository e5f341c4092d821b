//! luxtally: forward Monte Carlo photon tracing that tallies light on scene surfaces and
//! virtual receivers, and reports, forecasts and controls its own statistical error.
//!
//! Data path: `scene` (load and validate; `light` holds each light kind — its entry,
//! validation and emission — and `photometry` reads luminaires' files for it;
//! `surface` the materials and their BSDFs: the `Lobe`/`Bsdf` interface, one file per
//! lobe, microfacet and Fresnel maths) → `accel` (ray casting backends) → `tally` (receivers and triangle
//! maps: where and what scores) → `trace` (emission, photon batches, direct light)
//! → `stats`
//! (equations of method.md, forecast, stop criteria) → `run` (validate, set up, epochs;
//! `distributed` shares its chunks among processes) → `checkpoint` (save, resume, merge
//! shards) → `annual` (a year of daylight: daylight coefficients, hourly illuminance,
//! annual metrics) → `output` (summary.json and files) → `render` (the eye pass) → `limits`
//! (sizes a run or render before it allocates). The `luxtally` binary (src/bin/luxtally/:
//! one module per command, the benchmarks among them) is over all of them; `fixtures`
//! (test scenes and rays, hidden from the docs) serves tests/, benches/ and the
//! benchmarks.
//!
//! Layering: each module uses only modules before it in this order, never one after
//! it (no import cycles): `error`, `rng`, `sampling`, `raster` (bitmap font, canvas, PNG
//! encoder, palettes, quantile), `criteria` (the stop criteria of the scene file, the
//! command line and the run), `input` (scene-file entries read with their key path,
//! value checks), `weather` (EPW and WEA weather files) → `photometry` → `light` → `surface` → `scene` → `accel` → `tally` →
//! `trace` → `stats` → `distributed` → `run` → `checkpoint` → `annual` → `output` → `render` →
//! `limits` → `fixtures`. docs/architecture.md has the whole data path.

// `!(x > 0.0)` is deliberate throughout: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod annual;
pub mod checkpoint;
pub mod criteria;
pub mod distributed;
pub mod error;
// Scenes and rays for tests/, benches/ and the bench commands: not part of the engine.
#[doc(hidden)]
pub mod fixtures;
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
pub mod surface;
pub mod tally;
pub mod trace;
pub mod weather;

pub use error::{Error, Result};

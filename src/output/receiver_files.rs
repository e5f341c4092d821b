//! Per-receiver files: `receivers/NAME.exr` and `receivers/NAME.csv`, the numbers of
//! summary.json's receiver entry laid out as an image and as a table.
//!
//! EXR: one layer named after the receiver, data window cells[0] × cells[1] at (0, 0),
//! x = i along u, y = j along v, so row y = 0 (the top row in image viewers) is j = 0,
//! the edge through `corner`. Six 32-bit float channels, no compression loss (ZIP):
//! `value` (lx or cd/m²), `sigma` (same unit), `rel_error` (σ/value, 1 where nothing
//! scored), `hits`, `vov` and `reliable` (1 for a reliable cell, 0 for an unreliable,
//! dark or unknown one); the layer's comment counts the unreliable and dark cells.
//! summary.json's f64 numbers are rounded to the nearest f32 (`as f32`); hits are exact
//! up to 2^24 = 16,777,216 per cell.
//!
//! CSV: a header line, then one row per cell in index order j * cells[0] + i:
//! `i,j,x_m,y_m,z_m,value,sigma,rel_error,hits,scoring_histories,vov,dof,status,upper_bound`,
//! the cell centre in world metres and f64 numbers printed in full round-trip precision
//! (`NaN` where unknown; `upper_bound` only for dark and unreliable cells).
//!
//! Figures CSV (`receivers/NAME_figures.csv`): the receiver's designer figures
//! (summary.json's `figures`), one row each of `mean`, `min`, `max`, `u0`, `g2`:
//! `figure,value,low,high,confidence,cell,point,reliable`, `cell` the extreme cell's
//! index (empty for the others), `point` how the value was formed (`plug_in` for the
//! minimum and maximum, `mean` for the mean, `ratio` for U0 and g2).

use crate::output::summary::ReceiverSummary;
use crate::scene::Receiver;
use crate::stats::{relative_error, CellStatus};
use crate::{Error, Result};
use exr::prelude::*;
use std::fmt::Write as _;

/// The EXR of a receiver, as bytes.
pub fn receiver_exr(name: &str, r: &ReceiverSummary) -> Result<Vec<u8>> {
    let size = (r.cells[0] as usize, r.cells[1] as usize);
    let f32s = |v: &[f64]| FlatSamples::F32(v.iter().map(|&x| x as f32).collect());
    let rel: Vec<f64> = r
        .values
        .iter()
        .zip(&r.sigma)
        .map(|(&v, &s)| relative_error(v, s))
        .collect();
    let hits: Vec<f64> = r.hits.iter().map(|&h| h as f64).collect();
    let reliable: Vec<f64> = (0..r.values.len())
        .map(|k| (status_of(r, k) == CellStatus::Reliable) as u8 as f64)
        .collect();
    let vov: Vec<f64> = (0..r.values.len())
        .map(|k| r.vov.get(k).copied().unwrap_or(f64::NAN))
        .collect();
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![
        AnyChannel::new("value", f32s(&r.values)),
        AnyChannel::new("sigma", f32s(&r.sigma)),
        AnyChannel::new("rel_error", f32s(&rel)),
        AnyChannel::new("hits", f32s(&hits)),
        AnyChannel::new("vov", f32s(&vov)),
        AnyChannel::new("reliable", f32s(&reliable)),
    ]));
    let mut attributes = LayerAttributes::named(name);
    attributes.comments = Some(Text::from(
        format!(
            "luxtally receiver {name}: {} in {}; x = i along u, y = j along v; \
             {} unreliable cells, {} dark cells (value at most {} {})",
            r.quantity, r.unit, r.unreliable_cells, r.dark_cells, r.dark_upper_bound, r.unit
        )
        .as_str(),
    ));
    let layer = Layer::new(size, attributes, Encoding::SMALL_LOSSLESS, channels);
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        // Chunks in file order: the same values give the same bytes.
        .non_parallel()
        .to_buffered(&mut bytes)
        .map_err(|e| Error::Unsupported(format!("receivers/{name}.exr: {e}")))?;
    Ok(bytes.into_inner())
}

/// The figures CSV of a receiver.
pub fn figures_csv(r: &ReceiverSummary) -> String {
    let f = &r.figures;
    let mut s = String::from("figure,value,low,high,confidence,cell,point,reliable\n");
    let cell = |k: usize| k.to_string();
    for (name, figure, cell, point) in [
        ("mean", &f.mean, String::new(), "mean"),
        ("min", &f.min, cell(f.min_cell), f.min_point.as_str()),
        ("max", &f.max, cell(f.max_cell), "plug_in"),
        ("u0", &f.u0, String::new(), "ratio"),
        ("g2", &f.g2, String::new(), "ratio"),
    ] {
        let _ = writeln!(
            s,
            "{name},{},{},{},{},{cell},{point},{}",
            figure.value, figure.low, figure.high, f.confidence, f.reliable
        );
    }
    s
}

/// The CSV of a receiver, with cell centres from its geometry.
pub fn receiver_csv(receiver: &Receiver, r: &ReceiverSummary) -> String {
    let [nu, nv] = [r.cells[0] as usize, r.cells[1] as usize];
    let mut s = String::from(
        "i,j,x_m,y_m,z_m,value,sigma,rel_error,hits,scoring_histories,vov,dof,status,upper_bound\n",
    );
    let at = |v: &[f64], k: usize| v.get(k).copied().unwrap_or(f64::NAN);
    for j in 0..nv {
        for i in 0..nu {
            let k = j * nu + i;
            let c = receiver.corner
                + receiver.u * ((i as f64 + 0.5) / nu as f64)
                + receiver.v * ((j as f64 + 0.5) / nv as f64);
            let _ = writeln!(
                s,
                "{i},{j},{},{},{},{},{},{},{},{},{},{},{},{}",
                c.x,
                c.y,
                c.z,
                r.values[k],
                r.sigma[k],
                relative_error(r.values[k], r.sigma[k]),
                r.hits[k],
                r.scoring_histories.get(k).copied().unwrap_or(0),
                at(&r.vov, k),
                at(&r.dof, k),
                status_of(r, k).as_str(),
                at(&r.upper_bound, k),
            );
        }
    }
    s
}

/// Cell `k`'s status. A summary written before statuses existed has none: its cells read
/// as reliable where their σ is known, unknown where it is not.
pub fn status_of(r: &ReceiverSummary, k: usize) -> CellStatus {
    r.status.get(k).copied().unwrap_or_else(|| {
        if r.sigma.get(k).is_some_and(|s| !s.is_nan()) {
            CellStatus::Reliable
        } else {
            CellStatus::Unknown
        }
    })
}

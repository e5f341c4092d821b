//! An annual run's files (docs/daylight.md, *Annual outputs*): annual.json (settings,
//! warnings, rounds and every receiver's figures with their intervals and verdicts),
//! per receiver a CSV of its cells' figures, a CSV of its hours and the hourly
//! illuminance of every cell as a compact binary, streamed record by record (each file
//! written atomically, as every output is: `write_atomic`); annual.html
//! with the verdicts, the day × hour maps of each receiver's mean and the metric maps.

use super::{file_stem, write_atomic};
use crate::annual::metrics::{Hourly, Interval, ReceiverFigures};
use crate::annual::AnnualResult;
use crate::error::{Error, Result};
use crate::light::sun::altitude_azimuth_deg;
use crate::scene::Scene;
use serde_json::{json, Value};
use std::io::Write;
use std::path::Path;

/// The hourly file's first bytes; then u32 cells, u32 records, and per record the
/// cells' illuminance then their σ (f32, little-endian; dark records hold zeros).
pub const HOURLY_MAGIC: &[u8; 8] = b"LXHOUR01";

fn interval(i: &Interval) -> Value {
    json!({ "value": i.value, "low": i.low, "high": i.high })
}

fn receiver_json(f: &ReceiverFigures, unreached_sources: usize) -> Value {
    let levels: Vec<Value> = (f.en17037.iter())
        .map(|(name, fraction, verdict)| json!({ "level": name, "daylight_hours_fraction": interval(fraction), "verdict": verdict }))
        .collect();
    let mean = f.cells.iter().map(|c| c.mean_lx).sum::<f64>() / f.cells.len().max(1) as f64;
    json!({
        "name": f.name,
        "cells": f.shape,
        "mean_occupied_lx": mean,
        "sda_300_50": interval(&f.sda),
        "ase_1000_250": interval(&f.ase),
        "blinds_closed_hours_fraction": interval(&f.blinds_hours),
        "leed_v4_1_sda_points": { "low": f.leed_points[0], "high": f.leed_points[1] },
        "ase_over_10_percent": f.ase_over_10_percent(),
        "en17037": levels,
        "unreached_sources": unreached_sources,
    })
}

/// Writes every file of `result` into `out`.
pub fn write_annual(out: &Path, scene: &Scene, result: &AnnualResult) -> Result<()> {
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let annual = scene
        .annual
        .as_ref()
        .expect("an annual run's scene has [annual]");
    let m = &result.matrix;
    let untraced = result.coefficients.iter().filter(|c| c.is_empty()).count();
    let summary = json!({
        "scene": scene.name,
        "weather": annual.weather.display().to_string(),
        "mf": annual.mf,
        "sky_patches": m.patches.len(),
        "sun_mf": annual.sun_mf,
        "sun_bins": m.suns.len(),
        "records": m.records,
        "lit_records": m.hours.len(),
        "occupied_records": m.occupied_records,
        "occupied_hours": annual.occupied_hours,
        "shade_transmittance": annual.shade_transmittance,
        "ground_reflectance": annual.ground_reflectance,
        "warnings": m.warnings,
        "sources": result.sources.len(),
        "untraced_sources": untraced,
        "photons": result.photons,
        "rays": result.rays,
        "direct_rays": result.direct_rays,
        "sky_matrix_s": result.matrix_s,
        "elapsed_s": result.elapsed_s,
        "stop_reason": result.stop_reason,
        "rounds": result.rounds.iter().map(|r| json!({ "photons": r.photons, "elapsed_s": r.elapsed_s, "sda_halfwidth": r.sda_halfwidth })).collect::<Vec<_>>(),
        "receivers": (result.figures.receivers.iter().zip(&result.unreached_sources))
            .map(|(f, u)| receiver_json(f, u.len()))
            .collect::<Vec<_>>(),
    });
    let path = out.join("annual.json");
    let text = serde_json::to_string_pretty(&summary).expect("plain JSON values");
    write_atomic(&path, |w| w.write_all((text + "\n").as_bytes()))?;
    write_html(&out.join("annual.html"), scene, result)?;
    for (k, (f, h)) in result
        .figures
        .receivers
        .iter()
        .zip(&result.hourly)
        .enumerate()
    {
        let receiver = &scene.receivers[annual.receivers[k]];
        let stem = format!("annual_{}", file_stem(&f.name));
        write_cells(&out.join(format!("{stem}.csv")), receiver, f)?;
        write_hours(&out.join(format!("{stem}_hours.csv")), result, h)?;
        write_hourly(&out.join(format!("{stem}_hourly.bin")), result, h)?;
    }
    Ok(())
}

fn write_cells(path: &Path, receiver: &crate::scene::Receiver, f: &ReceiverFigures) -> Result<()> {
    let mut text = String::from(
        "i,j,x,y,z,mean_lx,mean_sigma_lx,da300,da300_low,da300_high,cda300,cda300_low,cda300_high,\
         da300_blinds,da300_blinds_low,da300_blinds_high,sda_probability,ase_hours,ase_hours_low,\
         ase_hours_high,ase_probability,udi_below_100,udi_below_100_low,udi_below_100_high,udi_100_300,udi_100_300_low,\
         udi_100_300_high,udi_300_3000,udi_300_3000_low,udi_300_3000_high,udi_above_3000,\
         udi_above_3000_low,udi_above_3000_high\n",
    );
    let [nu, nv] = receiver.cells;
    for (k, c) in f.cells.iter().enumerate() {
        let (i, j) = (k as u32 % nu, k as u32 / nu);
        let p = receiver.corner
            + receiver.u * ((i as f64 + 0.5) / nu as f64)
            + receiver.v * ((j as f64 + 0.5) / nv as f64);
        let iv = |x: &Interval| format!("{:.6},{:.6},{:.6}", x.value, x.low, x.high);
        text += &format!(
            "{i},{j},{:.4},{:.4},{:.4},{:.4},{:.4},{},{},{},{:.6},{},{:.6},{},{},{},{}\n",
            p.x,
            p.y,
            p.z,
            c.mean_lx,
            c.mean_sigma_lx,
            iv(&c.da),
            iv(&c.cda),
            iv(&c.da_blinds),
            c.sda_probability,
            iv(&c.ase_hours),
            c.ase_probability,
            iv(&c.udi[0]),
            iv(&c.udi[1]),
            iv(&c.udi[2]),
            iv(&c.udi[3])
        );
    }
    write_atomic(path, |w| w.write_all(text.as_bytes()))
}

/// Each record's lit hour (its index among the sky matrix's hours), or None if dark.
fn lit_hours(result: &AnnualResult) -> Vec<Option<usize>> {
    let mut out = vec![None; result.matrix.records];
    for (t, hour) in result.matrix.hours.iter().enumerate() {
        out[hour.record] = Some(t);
    }
    out
}

/// Per record: its stamp, whether occupied, the hour's own sun position, the sky's
/// direct normal, diffuse and global horizontal illuminance, and the receiver's mean
/// illuminance with an upper bound of its σ ([`Hourly::receiver_mean`]).
fn write_hours(path: &Path, result: &AnnualResult, h: &Hourly) -> Result<()> {
    let lit = lit_hours(result);
    write_atomic(path, |w| {
        writeln!(
            w,
            "record,month,day,hour,occupied,sun_altitude_deg,sun_azimuth_deg,direct_normal_lx,\
             diffuse_horizontal_lx,global_horizontal_lx,mean_lx,mean_sigma_bound_lx"
        )?;
        for (record, &[month, day, hour, occupied]) in result.matrix.stamps.iter().enumerate() {
            let Some(t) = lit[record] else {
                writeln!(w, "{record},{month},{day},{hour},{occupied},,,0,0,0,0,0")?;
                continue;
            };
            let sky = &result.matrix.hours[t];
            let (mean, sd) = h.receiver_mean(t);
            let (altitude, azimuth) = altitude_azimuth_deg(sky.sun_position);
            let direct = sky.sun.map_or(0.0, |s| s.1);
            let (diffuse, global) = (sky.diffuse_horizontal_lx, sky.global_horizontal_lx);
            writeln!(
                w,
                "{record},{month},{day},{hour},{occupied},{altitude:.4},{azimuth:.4},{direct:.2},\
                 {diffuse:.2},{global:.2},{mean:.4},{sd:.4}"
            )?;
        }
        Ok(())
    })
}

/// The hourly binary ([`HOURLY_MAGIC`]), written record by record.
fn write_hourly(path: &Path, result: &AnnualResult, h: &Hourly) -> Result<()> {
    let lit = lit_hours(result);
    write_atomic(path, |w| {
        w.write_all(HOURLY_MAGIC)?;
        w.write_all(&(h.cells as u32).to_le_bytes())?;
        w.write_all(&(result.matrix.records as u32).to_le_bytes())?;
        let zeros = vec![0u8; 8 * h.cells];
        for t in &lit {
            match *t {
                Some(t) => {
                    let range = t * h.cells..(t + 1) * h.cells;
                    for x in h.e[range.clone()].iter().chain(&h.sigma[range]) {
                        w.write_all(&x.to_le_bytes())?;
                    }
                }
                None => w.write_all(&zeros)?,
            }
        }
        Ok(())
    })
}

/// A grid of `cols` × `rows` values (row-major, row 0 drawn at the top) as a viridis map
/// of `px` pixels per value, 0 to `max`, with a colour bar labelled `0` and `max_label`
/// beneath (NaN values drawn grey).
pub fn map_png(
    values: &[f64],
    cols: usize,
    rows: usize,
    px: [usize; 2],
    max: f64,
    max_label: &str,
) -> Result<Vec<u8>> {
    use crate::raster::canvas::Canvas;
    use crate::raster::palette::{normalise, viridis};
    let (w, h) = (cols * px[0], rows * px[1]);
    let (width, bar) = (w.max(160) + 20, 14);
    let mut canvas = Canvas::new(width, h + bar + 40);
    for (k, &v) in values.iter().enumerate() {
        let (i, j) = (k % cols, k / cols);
        let colour = if v.is_nan() {
            [160, 160, 160]
        } else {
            viridis(normalise(v, max))
        };
        for y in j * px[1]..(j + 1) * px[1] {
            let row = 3 * ((10 + y) * width + 10);
            for x in i * px[0]..(i + 1) * px[0] {
                canvas.rgb[row + 3 * x..row + 3 * x + 3].copy_from_slice(&colour);
            }
        }
    }
    let bar_width = width - 20;
    for x in 0..bar_width {
        let colour = viridis(x as f64 / (bar_width - 1) as f64);
        for y in h + 16..h + 16 + bar {
            let at = 3 * (y * width + 10 + x);
            canvas.rgb[at..at + 3].copy_from_slice(&colour);
        }
    }
    canvas.text(10.0, (h + 18 + bar) as f64, "0", [0, 0, 0]);
    let label_x = width as f64 - 10.0 - crate::raster::font::text_width(max_label, 2) as f64;
    canvas.text(label_x, (h + 18 + bar) as f64, max_label, [0, 0, 0]);
    crate::raster::encode_rgb_png(width, canvas.height, &canvas.rgb)
}

/// A receiver's per-cell values as rows top-down (its v axis drawn upwards).
fn receiver_rows(values: &[f64], shape: [u32; 2]) -> Vec<f64> {
    let (nu, nv) = (shape[0] as usize, shape[1] as usize);
    (0..nv)
        .rev()
        .flat_map(|j| (0..nu).map(move |i| values[j * nu + i]))
        .collect()
}

/// An illuminance and its σ per lit hour `t` (`at(t)`) as a day (columns) by hour
/// stamp (rows, hour 1 at the top) map, and the σ relative to it (NaN where dark).
fn temporal(
    result: &AnnualResult,
    at: impl Fn(usize) -> (f64, f64),
) -> (Vec<f64>, Vec<f64>, usize) {
    let days = result.matrix.records.div_ceil(24);
    let (mut mean, mut rel) = (vec![0.0; days * 24], vec![f64::NAN; days * 24]);
    for (t, hour) in result.matrix.hours.iter().enumerate() {
        let (day, row) = (hour.record / 24, hour.record % 24);
        let (e, s) = at(t);
        mean[row * days + day] = e;
        rel[row * days + day] = if e > 0.0 { s / e } else { f64::NAN };
    }
    (mean, rel, days)
}

/// A data URI of PNG bytes.
fn png_uri(bytes: &[u8]) -> String {
    use base64::Engine;
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

/// Scale top: the largest finite value rounded up to 1, 2 or 5 × 10ⁿ.
fn nice_max(values: &[f64]) -> f64 {
    let m = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    if !(m > 0.0) {
        return 1.0;
    }
    let p = libm::pow(10.0, libm::log10(m).floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|k| k * p)
        .find(|&x| x >= m)
        .unwrap_or(10.0 * p)
}

/// One receiver's part of annual.html: its verdicts, its temporal maps and its metric maps.
fn receiver_html(result: &AnnualResult, f: &ReceiverFigures, h: &Hourly) -> Result<String> {
    let pct = |i: &Interval| {
        format!(
            "{:.1} % (95 %: {:.1}–{:.1} %)",
            100.0 * i.value,
            100.0 * i.low,
            100.0 * i.high
        )
    };
    let mut html = format!("<h2>Receiver {}</h2>\n<table>\n", escape(&f.name));
    let ase_note = f.ase_over_10_percent();
    let rows = [
        ("sDA300/50 % (2 % blinds rule)".to_string(), pct(&f.sda)),
        (
            "LEED v4.1 sDA points".into(),
            format!("{}–{}", f.leed_points[0], f.leed_points[1]),
        ),
        ("ASE1000,250".into(), pct(&f.ase)),
        ("ASE over 10 % (glare note needed)".into(), ase_note.into()),
        (
            "Blinds closed (occupied hours)".into(),
            pct(&f.blinds_hours),
        ),
    ];
    for (k, v) in rows.iter().chain(
        &f.en17037
            .iter()
            .map(|(n, x, v)| (format!("EN 17037 {n} level"), format!("{v}: {}", pct(x))))
            .collect::<Vec<_>>(),
    ) {
        html += &format!("<tr><th>{}</th><td>{}</td></tr>\n", escape(k), escape(v));
    }
    html += "</table>\n";
    // The least-lit cell: where the annual figures are decided.
    let darkest = (0..f.cells.len())
        .min_by(|&a, &b| f.cells[a].mean_lx.total_cmp(&f.cells[b].mean_lx))
        .unwrap_or(0);
    let (i, j) = (darkest % f.shape[0] as usize, darkest / f.shape[0] as usize);
    let of_cell = |t: usize| {
        let k = t * h.cells + darkest;
        (h.e[k] as f64, h.sigma[k] as f64)
    };
    let mut images = Vec::new();
    for (what, (mean, rel, days)) in [
        (
            "Receiver mean illuminance".to_string(),
            temporal(result, |t| h.receiver_mean(t)),
        ),
        (
            format!("Illuminance of the least-lit cell ({i}, {j})"),
            temporal(result, of_cell),
        ),
    ] {
        // The top of the scale at the 99th percentile of the lit hours: a few sunny
        // hours would leave the rest of the year dark.
        let p99 = crate::raster::quantile(&mean, 0.99, crate::raster::Rank::Nearest, |x| x > 0.0);
        let top = nice_max(&[p99]);
        images.push((
            format!("{what}, day of the year (across) by hour (down); the scale tops at the lit hours' 99th percentile"),
            map_png(&mean, days, 24, [2, 8], top, &format!("{top} lx"))?,
        ));
        images.push((
            "Its relative σ (for the mean, a bound: the mean of the cells' σ)".to_string(),
            map_png(&rel, days, 24, [2, 8], 0.2, "20 %")?,
        ));
    }
    let cell = |g: &dyn Fn(&crate::annual::metrics::CellFigures) -> f64| {
        receiver_rows(&f.cells.iter().map(g).collect::<Vec<_>>(), f.shape)
    };
    let (nu, nv) = (f.shape[0] as usize, f.shape[1] as usize);
    let px = (400 / nu.max(nv)).clamp(4, 40);
    let mean_cells = cell(&|c| c.mean_lx);
    let mean_top = nice_max(&mean_cells);
    let maps = [
        (
            "Mean illuminance, occupied hours",
            map_png(
                &mean_cells,
                nu,
                nv,
                [px, px],
                mean_top,
                &format!("{mean_top} lx"),
            )?,
        ),
        (
            "Its relative σ",
            map_png(
                &cell(&|c| c.mean_sigma_lx / c.mean_lx),
                nu,
                nv,
                [px, px],
                0.05,
                "5 %",
            )?,
        ),
        (
            "DA300 with blinds",
            map_png(
                &cell(&|c| c.da_blinds.value),
                nu,
                nv,
                [px, px],
                1.0,
                "100 %",
            )?,
        ),
        (
            "Probability the cell counts for sDA",
            map_png(&cell(&|c| c.sda_probability), nu, nv, [px, px], 1.0, "1")?,
        ),
        (
            "Direct-sun hours over 1000 lx",
            map_png(
                &cell(&|c| c.ase_hours.value),
                nu,
                nv,
                [px, px],
                1000.0,
                "1000",
            )?,
        ),
        (
            "Probability the cell counts for ASE",
            map_png(&cell(&|c| c.ase_probability), nu, nv, [px, px], 1.0, "1")?,
        ),
    ];
    let maps = maps.into_iter().map(|(t, png)| (t.to_string(), png));
    for (title, png) in images.into_iter().chain(maps) {
        html += &format!(
            "<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n",
            png_uri(&png),
            escape(&title),
            escape(&title)
        );
    }
    Ok(html)
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// annual.html: the run's settings and warnings, then each receiver's verdicts and maps.
fn write_html(path: &Path, scene: &Scene, result: &AnnualResult) -> Result<()> {
    let m = &result.matrix;
    let mut html = format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{0}: annual daylight</title>\n\
         <style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}\
         th,td{{border:1px solid #ccc;padding:4px 8px;text-align:left}}figure{{display:inline-block;margin:1em}}</style>\n\
         </head><body>\n<h1>{0}: annual daylight</h1>\n<p>{1} records ({2} lit, {3} occupied); Reinhart MF:{4} \
         ({5} patches + ground), {6} sun bins; {7} photons in {8:.1} s, stopped on {9}. Intervals are 95 % \
         under the comonotone error model (docs/daylight.md, <i>Annual daylight</i>).</p>\n",
        escape(&scene.name),
        m.records,
        m.hours.len(),
        m.occupied_records,
        m.patches.mf,
        m.patches.len(),
        m.suns.len(),
        result.photons,
        result.elapsed_s,
        result.stop_reason
    );
    for w in &m.warnings {
        html += &format!("<p>Warning: {}</p>\n", escape(w));
    }
    for (f, h) in result.figures.receivers.iter().zip(&result.hourly) {
        html += &receiver_html(result, f, h)?;
    }
    html += "</body></html>\n";
    write_atomic(path, |w| w.write_all(html.as_bytes()))
}

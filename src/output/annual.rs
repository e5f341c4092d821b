//! An annual run's files (docs/daylight.md, *Annual outputs*): annual.json (settings,
//! warnings, rounds and every receiver's figures with their intervals and verdicts),
//! per receiver a CSV of its cells' figures, a CSV of its hours and the hourly
//! illuminance of every cell as a compact binary, streamed record by record.

use crate::annual::metrics::{Hourly, Interval, ReceiverFigures};
use crate::annual::AnnualResult;
use crate::error::{Error, Result};
use crate::scene::Scene;
use serde_json::{json, Value};
use std::io::{BufWriter, Write};
use std::path::Path;

/// The hourly file's first bytes; then u32 cells, u32 records, and per record the
/// cells' illuminance then their σ (f32, little-endian; dark records hold zeros).
pub const HOURLY_MAGIC: &[u8; 8] = b"LXHOUR01";

fn interval(i: &Interval) -> Value {
    json!({ "value": i.value, "low": i.low, "high": i.high })
}

fn receiver_json(f: &ReceiverFigures) -> Value {
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
        "ase_over_10_percent": crate::annual::metrics::verdict(f.ase.low > 0.1, f.ase.value > 0.1, f.ase.high > 0.1),
        "en17037": levels,
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
        "elapsed_s": result.elapsed_s,
        "stop_reason": result.stop_reason,
        "rounds": result.rounds.iter().map(|r| json!({ "photons": r.photons, "elapsed_s": r.elapsed_s, "sda_halfwidth": r.sda_halfwidth })).collect::<Vec<_>>(),
        "receivers": result.figures.receivers.iter().map(receiver_json).collect::<Vec<_>>(),
    });
    let path = out.join("annual.json");
    let text = serde_json::to_string_pretty(&summary).expect("plain JSON values");
    std::fs::write(&path, text + "\n").map_err(|e| Error::io(&path, e))?;
    for (k, (f, h)) in result
        .figures
        .receivers
        .iter()
        .zip(&result.hourly)
        .enumerate()
    {
        let receiver = &scene.receivers[annual.receivers[k]];
        write_cells(&out.join(format!("annual_{}.csv", f.name)), receiver, f)?;
        write_hours(&out.join(format!("annual_{}_hours.csv", f.name)), result, h)?;
        write_hourly(
            &out.join(format!("annual_{}_hourly.bin", f.name)),
            result,
            h,
        )?;
    }
    Ok(())
}

fn create(path: &Path) -> Result<BufWriter<std::fs::File>> {
    Ok(BufWriter::new(
        std::fs::File::create(path).map_err(|e| Error::io(path, e))?,
    ))
}

fn write_cells(path: &Path, receiver: &crate::scene::Receiver, f: &ReceiverFigures) -> Result<()> {
    let mut w = create(path)?;
    let mut text = String::from(
        "i,j,x,y,z,mean_lx,mean_sigma_lx,da300,da300_low,da300_high,cda300,cda300_low,cda300_high,\
         da300_blinds,da300_blinds_low,da300_blinds_high,sda_probability,ase_hours,ase_hours_low,\
         ase_hours_high,ase_probability,udi_below_100,udi_100_300,udi_300_3000,udi_above_3000\n",
    );
    let [nu, nv] = receiver.cells;
    for (k, c) in f.cells.iter().enumerate() {
        let (i, j) = (k as u32 % nu, k as u32 / nu);
        let p = receiver.corner
            + receiver.u * ((i as f64 + 0.5) / nu as f64)
            + receiver.v * ((j as f64 + 0.5) / nv as f64);
        let iv = |x: &Interval| format!("{:.6},{:.6},{:.6}", x.value, x.low, x.high);
        text += &format!(
            "{i},{j},{:.4},{:.4},{:.4},{:.4},{:.4},{},{},{},{:.6},{},{:.6},{:.6},{:.6},{:.6},{:.6}\n",
            p.x, p.y, p.z, c.mean_lx, c.mean_sigma_lx, iv(&c.da), iv(&c.cda), iv(&c.da_blinds),
            c.sda_probability, iv(&c.ase_hours), c.ase_probability, c.udi[0], c.udi[1], c.udi[2], c.udi[3]
        );
    }
    w.write_all(text.as_bytes())
        .and_then(|_| w.flush())
        .map_err(|e| Error::io(path, e))
}

/// Per record: its stamp, whether occupied, the receiver's mean illuminance and an upper
/// bound of its σ (the mean of the cells' σ: the cells' errors correlate at most fully).
fn write_hours(path: &Path, result: &AnnualResult, h: &Hourly) -> Result<()> {
    let mut lit = result.matrix.hours.iter().enumerate().peekable();
    let mut w = create(path)?;
    let io = |e| Error::io(path, e);
    writeln!(
        w,
        "record,month,day,hour,occupied,global_horizontal_lx,mean_lx,mean_sigma_bound_lx"
    )
    .map_err(io)?;
    for (record, &[month, day, hour, occupied]) in result.matrix.stamps.iter().enumerate() {
        let (mut gh, mut mean, mut sd) = (0.0, 0.0, 0.0);
        if let Some(&(t, sky)) = lit.peek().filter(|(_, s)| s.record == record) {
            lit.next();
            let n = h.cells.max(1) as f64;
            let range = t * h.cells..(t + 1) * h.cells;
            mean = h.e[range.clone()].iter().map(|&x| x as f64).sum::<f64>() / n;
            sd = h.sigma[range].iter().map(|&x| x as f64).sum::<f64>() / n;
            gh = sky.global_horizontal_lx;
        }
        writeln!(
            w,
            "{record},{month},{day},{hour},{occupied},{gh:.2},{mean:.4},{sd:.4}"
        )
        .map_err(io)?;
    }
    w.flush().map_err(io)
}

fn write_hourly(path: &Path, result: &AnnualResult, h: &Hourly) -> Result<()> {
    let mut w = create(path)?;
    let io = |e| Error::io(path, e);
    w.write_all(HOURLY_MAGIC).map_err(io)?;
    w.write_all(&(h.cells as u32).to_le_bytes()).map_err(io)?;
    w.write_all(&(result.matrix.records as u32).to_le_bytes())
        .map_err(io)?;
    let zeros = vec![0u8; 8 * h.cells];
    let mut lit = result.matrix.hours.iter().enumerate().peekable();
    for record in 0..result.matrix.records {
        match lit.peek().filter(|(_, s)| s.record == record) {
            Some(&(t, _)) => {
                lit.next();
                let range = t * h.cells..(t + 1) * h.cells;
                for x in h.e[range.clone()].iter().chain(&h.sigma[range]) {
                    w.write_all(&x.to_le_bytes()).map_err(io)?;
                }
            }
            None => w.write_all(&zeros).map_err(io)?,
        }
    }
    w.flush().map_err(io)
}

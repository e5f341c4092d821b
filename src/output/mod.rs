//! Outputs of a run: summary.json (the contract's keys and more), the receivers' EXR,
//! CSV and PNG files, the scene map (PLY) and report.html (docs/outputs.md).

pub mod ply;
pub mod preview;
pub mod receiver_files;
pub mod report;
pub mod summary;

use crate::run::RunState;
use crate::{Error, Result};
use serde_json::Value;
use std::path::Path;

/// Writes `bytes` to `path` atomically (temporary file, then rename), so a reader or an
/// interrupted run never sees half a file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}

/// A receiver's name as a file name: characters other than ASCII letters, digits, `-`,
/// `_` and `.` become `_` (receivers/NAME.* never leave the directory).
pub fn file_stem(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.chars().all(|c| c == '.') {
        format!("_{s}")
    } else {
        s
    }
}

/// summary.json's document of a state, as JSON data.
pub fn summary_value(state: &RunState<'_>) -> Result<Value> {
    serde_json::to_value(summary::build(state))
        .map_err(|e| Error::Unsupported(format!("summary.json: {e}")))
}

/// Every file besides summary.json: `receivers/NAME.{exr,csv,png}`,
/// `receivers/NAME_error.png`, `scene_map.ply` and `report.html`.
pub fn write_run_files(out: &Path, state: &RunState<'_>) -> Result<()> {
    let s = summary::build(state);
    let dir = out.join("receivers");
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    for r in &state.scene.receivers {
        if let Some(rs) = s.receivers.get(&r.name) {
            let exr = receiver_files::receiver_exr(&r.name, rs)?;
            write_atomic(&dir.join(format!("{}.exr", file_stem(&r.name))), &exr)?;
            let csv = receiver_files::receiver_csv(r, rs);
            write_atomic(
                &dir.join(format!("{}.csv", file_stem(&r.name))),
                csv.as_bytes(),
            )?;
        }
    }
    write_atomic(&out.join("scene_map.ply"), &ply::scene_map_ply(state))?;
    write_report(out, &s, report::DEFAULT_REFRESH_S)
}

/// report.html and the receivers' PNG previews from summary.json's document.
pub fn write_report(out: &Path, summary: &summary::Summary, refresh_s: f64) -> Result<()> {
    let origin = out.join("summary.json").display().to_string();
    let receivers = preview::ReceiverData::from_summary(summary, &origin)?;
    let dir = out.join("receivers");
    if !receivers.is_empty() {
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    }
    for r in &receivers {
        let (value, error) = preview::receiver_pngs(r)?;
        write_atomic(&dir.join(format!("{}.png", file_stem(&r.name))), &value)?;
        write_atomic(
            &dir.join(format!("{}_error.png", file_stem(&r.name))),
            &error,
        )?;
    }
    let value = serde_json::to_value(summary)
        .map_err(|e| Error::Unsupported(format!("summary.json: {e}")))?;
    write_live_report(out, &value, refresh_s)
}

/// report.html alone (during a run: the PNGs wait for the end).
pub fn write_live_report(out: &Path, summary: &Value, refresh_s: f64) -> Result<()> {
    let html = report::report_html(summary, refresh_s)?;
    write_atomic(&out.join("report.html"), html.as_bytes())
}

/// `luxtally report OUT_DIR`: report.html and the PNGs again from OUT_DIR/summary.json.
pub fn rebuild_report(out: &Path) -> Result<()> {
    let path = out.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let summary: summary::Summary = serde_json::from_str(&text)
        .map_err(|e| Error::input(path.display().to_string(), format!("not a summary: {e}")))?;
    write_report(out, &summary, report::DEFAULT_REFRESH_S)
}

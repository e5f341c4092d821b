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

/// Which files a run writes besides summary.json (`--outputs LIST`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Outputs {
    /// `receivers/NAME.{exr,csv,png}` and `receivers/NAME_error.png`.
    pub receivers: bool,
    /// `scene_map.ply`.
    pub map: bool,
    /// `report.html`.
    pub report: bool,
    /// The indirect map `luxtally render --from` reuses.
    pub indirect: bool,
    /// `render.{exr,png}` and `render_false_colour.png` (`render` only).
    pub render: bool,
}

impl Default for Outputs {
    fn default() -> Self {
        Outputs::ALL
    }
}

impl Outputs {
    pub const ALL: Outputs = Outputs {
        receivers: true,
        map: true,
        report: true,
        indirect: true,
        render: true,
    };
    pub const NAMES: &'static str = "receivers, map, report, indirect, render";

    /// Parses `receivers,report` (comma-separated; `all` for everything, `none` for
    /// summary.json alone).
    pub fn parse(list: &str) -> Result<Outputs> {
        let mut o = Outputs {
            receivers: false,
            map: false,
            report: false,
            indirect: false,
            render: false,
        };
        for name in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            match name {
                "receivers" => o.receivers = true,
                "map" | "scene_map" => o.map = true,
                "report" => o.report = true,
                "indirect" => o.indirect = true,
                "render" => o.render = true,
                "all" => o = Outputs::ALL,
                "none" | "summary" => {}
                other => {
                    return Err(Error::input(
                        "--outputs",
                        format!(
                            "unknown output `{other}` (expected a comma-separated list of {}, or all or none)",
                            Outputs::NAMES
                        ),
                    ))
                }
            }
        }
        Ok(o)
    }
}

/// summary.json of `s` in `out` (pretty JSON, written atomically).
pub fn save_summary(out: &Path, s: &summary::Summary) -> Result<()> {
    let json = serde_json::to_vec_pretty(s)
        .map_err(|e| Error::Unsupported(format!("summary.json: {e}")))?;
    write_atomic(&out.join("summary.json"), &json)
}

/// Every file besides summary.json: `receivers/NAME.{exr,csv,png}`,
/// `receivers/NAME_error.png`, `scene_map.ply` and `report.html`.
pub fn write_run_files(out: &Path, state: &RunState<'_>) -> Result<()> {
    write_run_files_with(out, state, &summary::build(state), Outputs::ALL)
}

/// The files of `outputs` besides summary.json; `s` is the state's summary.
pub fn write_run_files_with(
    out: &Path,
    state: &RunState<'_>,
    s: &summary::Summary,
    outputs: Outputs,
) -> Result<()> {
    let dir = out.join("receivers");
    if outputs.receivers {
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    }
    for r in state.scene.receivers.iter().filter(|_| outputs.receivers) {
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
    if outputs.map {
        write_atomic_with(&out.join("scene_map.ply"), |w| {
            ply::write_scene_map_ply(state, w)
        })?;
    }
    if outputs.receivers {
        write_receiver_pngs(out, s)?;
    }
    if outputs.report {
        write_live_report(out, &summary_json(s)?, report::DEFAULT_REFRESH_S)?;
    }
    Ok(())
}

/// As [`write_atomic`], streaming through a `BufWriter` instead of a byte buffer.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<()> {
    use std::io::Write;
    let tmp = path.with_extension("tmp");
    let file = std::fs::File::create(&tmp).map_err(|e| Error::io(&tmp, e))?;
    let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
    write(&mut w)
        .and_then(|()| w.flush())
        .map_err(|e| Error::io(&tmp, e))?;
    drop(w);
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}

/// summary.json's document as JSON data.
fn summary_json(summary: &summary::Summary) -> Result<Value> {
    serde_json::to_value(summary).map_err(|e| Error::Unsupported(format!("summary.json: {e}")))
}

/// report.html and the receivers' PNG previews from a summary.
pub fn write_report(out: &Path, summary: &summary::Summary, refresh_s: f64) -> Result<()> {
    write_receiver_pngs(out, summary)?;
    write_live_report(out, &summary_json(summary)?, refresh_s)
}

/// The receivers' PNG previews from a summary.
fn write_receiver_pngs(out: &Path, summary: &summary::Summary) -> Result<()> {
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
    Ok(())
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

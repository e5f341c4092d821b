//! Outputs of a run: summary.json (the contract's keys and more), the receivers' EXR,
//! CSV and PNG files, the scene map (PLY), report.html, the indirect map and the
//! rendered images (docs/outputs.md). A finished command writes them all through
//! [`write_all`]; every file goes through [`write_atomic`].

pub mod annual;
pub mod image;
pub mod indirect_map;
pub mod observers;
pub mod ply;
pub mod preview;
pub mod receiver_files;
pub mod report;
pub mod sky_plot;
pub mod summary;

pub use image::Image;
pub use indirect_map::{IndirectMap, MAP_FILE};

use crate::run::RunState;
use crate::{Error, Result};
use serde_json::Value;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes `path` atomically and durably: `write` fills a temporary file beside it
/// (`NAME.tmp`, same directory, so the rename cannot cross file systems), the file is
/// synced, renamed over `path`, and the directory synced. A reader, an interrupted run
/// or a crash sees the old file or the whole new one, never a short or empty one (a
/// rename without the sync may reach the disk before the data). The directory sync
/// makes the new name itself survive a crash; it is best effort (skipped where a
/// directory cannot be opened or synced, as on Windows).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<()> {
    let mut tmp_name = path.file_name().unwrap_or_default().to_os_string();
    tmp_name.push(".tmp");
    let tmp = path.with_file_name(tmp_name);
    let written = File::create(&tmp).and_then(|file| {
        let mut w = BufWriter::with_capacity(1 << 20, file);
        write(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()
    });
    if let Err(e) = written {
        // A partial file would only take room (the disk may be full).
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::io(&tmp, e));
    }
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))?;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    if let Ok(d) = File::open(dir.unwrap_or(Path::new("."))) {
        // Best effort: some file systems refuse to sync a directory.
        let _ = d.sync_all();
    }
    Ok(())
}

/// [`write_atomic`] of bytes in memory.
fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
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

/// What a command has finished: a photon pass (its state) and/or a rendered image.
#[derive(Clone, Copy)]
pub struct Finished<'a> {
    pub run: Option<&'a RunState<'a>>,
    pub image: Option<&'a Image>,
}

/// Every output of what a command finished, into `out`: summary.json and the files of
/// `outputs` (receivers, scene map, report, indirect map) for a run, the files of
/// `outputs.render` for an image. Returns the run's summary.
pub fn write_all(
    out: &Path,
    finished: Finished<'_>,
    outputs: Outputs,
) -> Result<Option<summary::Summary>> {
    let summary = match finished.run {
        Some(state) => Some(write_run(out, state, outputs)?),
        None => None,
    };
    if let Some(image) = finished.image.filter(|_| outputs.render) {
        write_bytes(&out.join("render.exr"), &image::render_exr(image)?)?;
        write_bytes(&out.join("render.png"), &image::tone_mapped_png(image)?)?;
        write_bytes(
            &out.join("render_false_colour.png"),
            &image::false_colour_png(image)?,
        )?;
    }
    Ok(summary)
}

/// summary.json and the run files of `outputs`; returns the summary.
fn write_run(out: &Path, state: &RunState<'_>, outputs: Outputs) -> Result<summary::Summary> {
    let s = summary::build(state);
    save_summary(out, &s)?;
    if outputs.receivers {
        write_receiver_files(out, state, &s)?;
    }
    if outputs.map {
        write_atomic(&out.join("scene_map.ply"), |w| {
            ply::write_scene_map_ply(state, w)
        })?;
    }
    if outputs.receivers {
        write_receiver_pngs(out, &s)?;
    }
    if outputs.report {
        write_report_html(out, &summary_json(&s)?, report::DEFAULT_REFRESH_S)?;
    }
    if outputs.indirect {
        IndirectMap::save_from_tallies(
            &out.join(MAP_FILE),
            state.scene,
            &state.progress.tallies,
            state.setup.total_flux_lm,
        )?;
    }
    Ok(s)
}

/// summary.json of `s` in `out` (pretty JSON); also saved during a run.
pub fn save_summary(out: &Path, s: &summary::Summary) -> Result<()> {
    let json = serde_json::to_vec_pretty(s)
        .map_err(|e| Error::Unsupported(format!("summary.json: {e}")))?;
    write_bytes(&out.join("summary.json"), &json)
}

/// report.html during a run, refreshing every `refresh_s` (the PNGs wait for the end).
pub fn write_live_report(out: &Path, state: &RunState<'_>, refresh_s: f64) -> Result<()> {
    write_report_html(out, &summary_json(&summary::build(state))?, refresh_s)
}

/// `luxtally report OUT_DIR`: report.html and the PNGs again from OUT_DIR/summary.json.
pub fn rebuild_report(out: &Path) -> Result<()> {
    let summary = read_summary(out)?;
    write_receiver_pngs(out, &summary)?;
    write_report_html(out, &summary_json(&summary)?, report::DEFAULT_REFRESH_S)
}

/// The summary.json of the run in `out`, read back (NaN where the file has null).
pub fn read_summary(out: &Path) -> Result<summary::Summary> {
    let path = out.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    serde_json::from_str(&text)
        .map_err(|e| Error::input(path.display().to_string(), format!("not a summary: {e}")))
}

/// `receivers/NAME.{exr,csv}` and `receivers/NAME_figures.csv`.
fn write_receiver_files(out: &Path, state: &RunState<'_>, s: &summary::Summary) -> Result<()> {
    let dir = out.join("receivers");
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    for r in &state.scene.receivers {
        if let Some(rs) = s.receivers.get(&r.name) {
            let stem = file_stem(&r.name);
            let exr = receiver_files::receiver_exr(&r.name, rs)?;
            write_bytes(&dir.join(format!("{stem}.exr")), &exr)?;
            let csv = receiver_files::receiver_csv(r, rs);
            write_bytes(&dir.join(format!("{stem}.csv")), csv.as_bytes())?;
            let figures = receiver_files::figures_csv(rs);
            write_bytes(&dir.join(format!("{stem}_figures.csv")), figures.as_bytes())?;
        }
    }
    Ok(())
}

/// summary.json's document as JSON data.
fn summary_json(summary: &summary::Summary) -> Result<Value> {
    serde_json::to_value(summary).map_err(|e| Error::Unsupported(format!("summary.json: {e}")))
}

/// The receivers' PNG previews (`receivers/NAME.png`, `NAME_error.png`) from a summary.
fn write_receiver_pngs(out: &Path, summary: &summary::Summary) -> Result<()> {
    let origin = out.join("summary.json").display().to_string();
    let receivers = preview::ReceiverData::from_summary(summary, &origin)?;
    let dir = out.join("receivers");
    if !receivers.is_empty() {
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    }
    for r in &receivers {
        let (value, error) = preview::receiver_pngs(r)?;
        let stem = file_stem(&r.name);
        write_bytes(&dir.join(format!("{stem}.png")), &value)?;
        write_bytes(&dir.join(format!("{stem}_error.png")), &error)?;
    }
    Ok(())
}

/// report.html from summary.json's document.
fn write_report_html(out: &Path, summary: &Value, refresh_s: f64) -> Result<()> {
    let html = report::report_html(summary, refresh_s)?;
    write_bytes(&out.join("report.html"), html.as_bytes())
}

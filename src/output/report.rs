//! `report.html`: one self-contained page (inline CSS and JS, no fetch of any kind) with
//! the plots of method.md §6, drawn on canvases by a small hand-written script from the
//! summary.json data embedded in the page as a JS object. No chart library: the images
//! and colour bars need per-cell canvas drawing anyway, and the rest is a few line
//! charts, so ~20 KB of our own code beats vendoring one.
//!
//! While the run is live (`stop_reason` null) the page carries
//! `<meta http-equiv="refresh">` and reloads itself; the final page has none.

use crate::raster::palette::anchors_js;
use crate::{Error, Result};
use serde_json::Value;

/// Reload period of a live report rebuilt by `luxtally report` (the run's own
/// `--report-every` sets it otherwise), s.
pub const DEFAULT_REFRESH_S: f64 = 10.0;

const TEMPLATE: &str = include_str!("report.html");

/// The page for a summary.json document. `refresh_s`: reload period while the run is
/// live (ignored once `stop_reason` is set).
pub fn report_html(summary: &Value, refresh_s: f64) -> Result<String> {
    let json = serde_json::to_string(summary)
        .map_err(|e| Error::Unsupported(format!("report.html: {e}")))?
        // Inside <script>, "</script>" or "<!--" in a string would end or upset it.
        .replace("</", "<\\/")
        .replace("<!--", "<\\!--");
    let live = summary.get("stop_reason").is_none_or(Value::is_null);
    let refresh = if live {
        format!(
            "<meta http-equiv=\"refresh\" content=\"{}\">",
            refresh_s.max(1.0).round()
        )
    } else {
        String::new()
    };
    Ok(TEMPLATE
        .replacen("<!--@REFRESH@-->", &refresh, 1)
        .replacen("/*@VIRIDIS@*/[]", &anchors_js(), 1)
        .replacen("/*@SUMMARY@*/null", &json, 1))
}

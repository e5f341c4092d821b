//! PNG previews of the receivers, for people who will not open an EXR:
//! `receivers/NAME.png` (value) and `receivers/NAME_error.png` (relative error), false
//! colour (viridis) with a colour bar and its numeric scale, drawn with the crate's 3×5
//! bitmap font (`raster::font`). Built from summary.json's data alone, so `luxtally
//! report` can redo them.
//!
//! Orientation: u to the right, v up (cell j = 0 is the bottom row), as on a plan seen
//! from the side u × v points to. Scales: value 0 … the largest cell value; relative
//! error 0 … the largest cell error, capped at 100 %. Cells without a value (nothing
//! scored: error unknown) are grey in the error image.

use super::summary::Summary;
use crate::raster::encode_rgb_png;
use crate::raster::font::{advance, draw_text};
use crate::raster::palette::{normalise, viridis};
use crate::stats::{relative_error, CellStatus};
use crate::{Error, Result};

/// A receiver's per-cell data as summary.json holds it (index j * cells[0] + i).
#[derive(Clone, Debug, PartialEq)]
pub struct ReceiverData {
    pub name: String,
    pub unit: String,
    pub cells: [usize; 2],
    pub values: Vec<f64>,
    pub sigma: Vec<f64>,
    pub hits: Vec<u64>,
    /// Cells whose σ is not to be trusted (`unreliable`): hatched in both images.
    pub unreliable: Vec<bool>,
}

impl ReceiverData {
    /// Every receiver of a summary; `origin` names its file in errors.
    pub fn from_summary(summary: &Summary, origin: &str) -> Result<Vec<ReceiverData>> {
        let mut out = Vec::new();
        for (name, r) in &summary.receivers {
            let cells = r.cells.map(|c| c as usize);
            let n = cells[0] * cells[1];
            if r.values.len() != n || r.sigma.len() != n || r.hits.len() != n {
                return Err(Error::input(
                    format!("{origin}: receivers.{name}.values"),
                    "values, sigma and hits must have cells[0] × cells[1] entries",
                ));
            }
            out.push(ReceiverData {
                name: name.clone(),
                unit: r.unit.clone(),
                cells,
                values: r.values.clone(),
                sigma: r.sigma.clone(),
                hits: r.hits.clone(),
                unreliable: (0..n)
                    .map(|k| super::receiver_files::status_of(r, k) == CellStatus::Unreliable)
                    .collect(),
            });
        }
        Ok(out)
    }

    /// Per-cell relative error σ/value (eq. 8; 1 where nothing scored).
    pub fn rel_error(&self) -> Vec<f64> {
        self.values
            .iter()
            .zip(&self.sigma)
            .map(|(&v, &s)| relative_error(v, s))
            .collect()
    }
}

/// The two previews of a receiver, PNG-encoded: (value image, error image).
pub fn receiver_pngs(r: &ReceiverData) -> Result<(Vec<u8>, Vec<u8>)> {
    let max_value = r
        .values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let value_px = |k: usize| viridis(normalise(r.values[k], max_value));
    let hatched = |k: usize| r.unreliable.get(k).copied().unwrap_or(false);
    let value = false_colour(r.cells, &value_px, &hatched, max_value, 1.0, &r.unit)?;

    let errors = r.rel_error();
    let max_error = errors
        .iter()
        .zip(&r.values)
        .filter(|(e, &v)| v > 0.0 && e.is_finite())
        .map(|(e, _)| *e)
        .fold(0.0, f64::max)
        .min(1.0);
    let error_px = |k: usize| {
        if r.values[k] > 0.0 {
            viridis(normalise(errors[k], max_error))
        } else {
            [160, 160, 160]
        }
    };
    let error = false_colour(r.cells, &error_px, &hatched, max_error, 100.0, "%")?;
    Ok((value, error))
}

const MARGIN: usize = 8;
const BAR_W: usize = 16;
const GLYPH_SCALE: usize = 2;
const TICKS: usize = 5;
/// From the bar's edge to its labels, past the 3 px tick marks.
const LABEL_GAP: usize = 10;

/// Hatching of an unreliable cell: every third pixel diagonal, white.
const HATCH: [u8; 3] = [255, 255, 255];

/// An RGB canvas: the image scaled up to ≥ 256 px wide, a colour bar 0 … `scale` and
/// its labels (`scale · label_factor`, then `unit`); `hatched` cells are crossed by
/// diagonal stripes.
fn false_colour(
    cells: [usize; 2],
    colour: &dyn Fn(usize) -> [u8; 3],
    hatched: &dyn Fn(usize) -> bool,
    scale: f64,
    label_factor: f64,
    unit: &str,
) -> Result<Vec<u8>> {
    let [w, h] = cells;
    if w == 0 || h == 0 {
        return Err(Error::Unsupported(
            "a receiver without cells has no image".into(),
        ));
    }
    // At least 256 px wide, but no taller than 2048 px for the sake of a tall receiver.
    let s = 256usize.div_ceil(w).min((2048 / h).max(1)).max(1);
    let (img_w, img_h) = (w * s, h * s);
    let top = MARGIN + 5 * GLYPH_SCALE + 6;
    let bar_h = img_h.max(128);
    let labels: Vec<String> = (0..TICKS)
        .map(|t| {
            let v = scale * label_factor * t as f64 / (TICKS - 1) as f64;
            format_number(v)
        })
        .collect();
    let label_w = labels.iter().map(|l| l.len()).max().unwrap_or(1) * advance(GLYPH_SCALE);
    let bar_x = MARGIN + img_w + 12;
    let width = bar_x + BAR_W + LABEL_GAP + label_w.max(unit.len() * advance(GLYPH_SCALE)) + MARGIN;
    let height = top + bar_h + MARGIN + 5 * GLYPH_SCALE;
    let mut c = Canvas::new(width, height);

    for py in 0..img_h {
        let j = h - 1 - py / s;
        for px in 0..img_w {
            let k = j * w + px / s;
            let stripe = hatched(k) && (px + py) % 3 == 0;
            c.set(
                MARGIN + px,
                top + py,
                if stripe { HATCH } else { colour(k) },
            );
        }
    }
    for y in 0..bar_h {
        let t = 1.0 - y as f64 / (bar_h - 1).max(1) as f64;
        for x in 0..BAR_W {
            c.set(bar_x + x, top + y, viridis(t));
        }
    }
    c.text(bar_x, MARGIN, unit);
    // A scale of 0 (nothing scored) gets its one label.
    let shown = if scale > 0.0 { TICKS } else { 1 };
    for (t, label) in labels.iter().enumerate().take(shown) {
        let y = top + (bar_h - 1) * (TICKS - 1 - t) / (TICKS - 1);
        for x in 0..3 {
            c.set(bar_x + BAR_W + x, y, [0, 0, 0]);
        }
        let ty = y
            .saturating_sub(5 * GLYPH_SCALE / 2)
            .max(top.saturating_sub(2));
        c.text(bar_x + BAR_W + LABEL_GAP, ty, label);
    }
    c.encode()
}

/// A short label: 3 significant digits, exponent form outside [1e-3, 1e5).
pub fn format_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.2e}");
    }
    let decimals = (2 - libm::log10(a).floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

struct Canvas {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
}

impl Canvas {
    fn new(width: usize, height: usize) -> Canvas {
        Canvas {
            width,
            height,
            rgb: vec![255; width * height * 3],
        }
    }

    fn set(&mut self, x: usize, y: usize, c: [u8; 3]) {
        if x < self.width && y < self.height {
            let k = 3 * (y * self.width + x);
            self.rgb[k..k + 3].copy_from_slice(&c);
        }
    }

    fn text(&mut self, x: usize, y: usize, s: &str) {
        draw_text(&mut self.rgb, self.width, x, y, s, GLYPH_SCALE, [0, 0, 0]);
    }

    fn encode(&self) -> Result<Vec<u8>> {
        encode_rgb_png(self.width, self.height, &self.rgb)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unreliable_cells_are_hatched_and_the_others_are_not() {
        // Two cells of one colour, the second hatched: only its pixels carry stripes.
        let colour = |_: usize| [10, 20, 30];
        let png = false_colour([2, 1], &colour, &|k| k == 1, 1.0, 1.0, "lx").unwrap();
        let img = image_of(&png);
        let (s, top) = (128, MARGIN + 5 * GLYPH_SCALE + 6);
        let count = |x0: usize| {
            let mut white = 0;
            for y in top..top + s {
                for x in MARGIN + x0..MARGIN + x0 + s {
                    white += (img.2[3 * (y * img.0 + x)..][..3] == HATCH) as usize;
                }
            }
            white
        };
        assert_eq!(count(0), 0, "a reliable cell has no stripes");
        assert!(count(s) > s * s / 4, "an unreliable cell is hatched");
    }

    /// (width, height, RGB) of an 8-bit RGB PNG.
    fn image_of(png: &[u8]) -> (usize, usize, Vec<u8>) {
        let decoder = png::Decoder::new(std::io::Cursor::new(png));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        (info.width as usize, info.height as usize, buf)
    }

    #[test]
    fn labels_are_short_and_round_trip_their_digits() {
        assert_eq!(format_number(0.0), "0");
        assert_eq!(format_number(312.6), "313");
        assert_eq!(format_number(12.5), "12.5");
        assert_eq!(format_number(0.25), "0.25");
        assert_eq!(format_number(123456.0), "1.23e5");
    }
}

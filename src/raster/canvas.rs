//! An RGB drawing surface for line diagrams (the photometric polar diagram, the UGR
//! table's plot): square dots, solid or dashed polylines, bitmap-font text.

use super::font::{draw_text, text_width};

/// Text is drawn at this scale of the 3 × 5 font.
pub const SCALE: usize = 2;

/// A white `width` × `height` RGB image, row by row.
pub struct Canvas {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

impl Canvas {
    pub fn new(width: usize, height: usize) -> Canvas {
        Canvas {
            width,
            height,
            rgb: vec![255; 3 * width * height],
        }
    }

    /// A `thick` square centred on (x, y); pixels outside are skipped.
    pub fn dot(&mut self, x: f64, y: f64, colour: [u8; 3], thick: f64) {
        let h = thick / 2.0;
        let (x0, x1) = ((x - h).round() as i64, (x + h).round() as i64 - 1);
        let (y0, y1) = ((y - h).round() as i64, (y + h).round() as i64 - 1);
        for py in y0..=y1.max(y0) {
            for px in x0..=x1.max(x0) {
                if (0..self.width as i64).contains(&px) && (0..self.height as i64).contains(&py) {
                    let at = 3 * (py as usize * self.width + px as usize);
                    self.rgb[at..at + 3].copy_from_slice(&colour);
                }
            }
        }
    }

    /// A polyline; dashed: `Some((on, period))` in pixels of length.
    pub fn path(
        &mut self,
        pts: &[(f64, f64)],
        colour: [u8; 3],
        thick: f64,
        dash: Option<(f64, f64)>,
    ) {
        let mut run = 0.0;
        for w in pts.windows(2) {
            let ((x0, y0), (x1, y1)) = (w[0], w[1]);
            let len = ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
            let steps = (len * 4.0).ceil().max(1.0) as usize;
            for s in 0..=steps {
                let t = s as f64 / steps as f64;
                let on = dash.is_none_or(|(on, period)| (run + t * len) % period < on);
                if on {
                    self.dot(x0 + t * (x1 - x0), y0 + t * (y1 - y0), colour, thick);
                }
            }
            run += len;
        }
    }

    /// Text with its top-left at (x, y).
    pub fn text(&mut self, x: f64, y: f64, s: &str, colour: [u8; 3]) {
        let (x, y) = (x.max(0.0) as usize, y.max(0.0) as usize);
        draw_text(&mut self.rgb, self.width, x, y, s, SCALE, colour);
    }

    /// Text centred on (x, y).
    pub fn text_centred(&mut self, x: f64, y: f64, s: &str, colour: [u8; 3]) {
        let w = text_width(s, SCALE) as f64;
        self.text(x - w / 2.0, y - (5 * SCALE) as f64 / 2.0, s, colour);
    }
}

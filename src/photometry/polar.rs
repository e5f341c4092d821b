//! The polar diagram lighting designers read: intensity in cd/klm in the C0–C180 plane
//! (red, solid) and the C90–C270 plane (blue, dashed), nadir down, γ = 180° up; C0 and
//! C90 on the right half, C180 and C270 on the left. Rings at round cd/klm values,
//! labelled along the upward axis; spokes every 30°, labelled at the rim. Curves follow
//! the interpolant (every 0.5°), not just the table's nodes.

use super::Photometry;
use crate::raster::canvas::{Canvas, SCALE};
use crate::raster::encode_rgb_png;
use crate::raster::font::text_width;
use crate::Result;

/// Curves in cd/klm at `gamma_deg`, one per half-plane.
#[derive(Clone, Debug, PartialEq)]
pub struct PolarCurves {
    pub gamma_deg: Vec<f64>,
    pub c0: Vec<f64>,
    pub c180: Vec<f64>,
    pub c90: Vec<f64>,
    pub c270: Vec<f64>,
}

impl PolarCurves {
    /// The four half-planes of `p`, every `step_deg` of γ from 0 to 180.
    pub fn of(p: &Photometry, step_deg: f64) -> PolarCurves {
        let n = (180.0 / step_deg).round().max(1.0) as usize;
        let gamma_deg: Vec<f64> = (0..=n).map(|k| 180.0 * k as f64 / n as f64).collect();
        let k = p.cd_to_cd_per_klm();
        let curve = |c: f64| {
            gamma_deg
                .iter()
                .map(|&g| k * p.intensity_cd(c, g))
                .collect()
        };
        PolarCurves {
            c0: curve(0.0),
            c180: curve(180.0),
            c90: curve(90.0),
            c270: curve(270.0),
            gamma_deg,
        }
    }

    pub fn max(&self) -> f64 {
        [&self.c0, &self.c180, &self.c90, &self.c270]
            .iter()
            .flat_map(|c| c.iter())
            .copied()
            .fold(0.0, f64::max)
    }
}

/// An 8-bit RGB image, row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct PolarImage {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

const WIDTH: usize = 480;
const HEIGHT: usize = 510;
const RADIUS: f64 = 200.0;
const CENTRE: (f64, f64) = (240.0, 265.0);
const RED: [u8; 3] = [200, 30, 30];
const BLUE: [u8; 3] = [30, 70, 210];
const GRID: [u8; 3] = [200, 200, 200];
const INK: [u8; 3] = [0, 0, 0];

/// Ring spacing: the 1-2-2.5-5 value at or above a quarter of `max`.
pub fn ring_step(max: f64) -> f64 {
    if !(max > 0.0 && max.is_finite()) {
        return 1.0;
    }
    let raw = max / 4.0;
    let decade = libm::pow(10f64, libm::log10(raw).floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * decade)
        .find(|&s| s >= raw * (1.0 - 1e-12))
        .unwrap_or(10.0 * decade)
}

/// Screen point of intensity `r` (fraction of the outer ring) at γ, right or left half.
fn point(r: f64, gamma_deg: f64, right: bool) -> (f64, f64) {
    let (s, c) = libm::sincos(gamma_deg.to_radians());
    let side = if right { 1.0 } else { -1.0 };
    (CENTRE.0 + side * RADIUS * r * s, CENTRE.1 + RADIUS * r * c)
}

/// A ring value as a label: no trailing zeros.
fn label(v: f64) -> String {
    let s = format!("{v:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The polar diagram of `p` as an RGB image.
pub fn polar_diagram(p: &Photometry) -> PolarImage {
    let curves = PolarCurves::of(p, 0.5);
    let step = ring_step(curves.max());
    let rings = ((curves.max() / step).ceil() as usize).max(1);
    let outer = step * rings as f64;
    let mut c = Canvas::new(WIDTH, HEIGHT);

    // Rings and spokes.
    for k in 1..=rings {
        let r = k as f64 / rings as f64;
        let pts: Vec<(f64, f64)> = (0..=360).map(|a| point(r, a as f64, true)).collect();
        c.path(&pts, GRID, 1.0, None);
    }
    for a in (0..=180).step_by(30) {
        for right in [true, false] {
            c.path(
                &[point(0.0, a as f64, right), point(1.0, a as f64, right)],
                GRID,
                1.0,
                None,
            );
            let (x, y) = point(1.0 + 28.0 / RADIUS, a as f64, right);
            if right || (a != 0 && a != 180) {
                c.text_centred(x, y, &a.to_string(), INK);
            }
        }
    }
    for k in 1..=rings {
        let (x, y) = point(k as f64 / rings as f64, 180.0, true);
        c.text(x + 4.0, y + 2.0, &label(step * k as f64), [90, 90, 90]);
    }

    // Curves: C0–C180 solid red, C90–C270 dashed blue.
    let half = |values: &[f64], right: bool| -> Vec<(f64, f64)> {
        curves
            .gamma_deg
            .iter()
            .zip(values)
            .map(|(&g, &v)| point(v / outer, g, right))
            .collect()
    };
    let join = |right_half: &[f64], left_half: &[f64]| -> Vec<(f64, f64)> {
        let mut pts = half(right_half, true);
        let mut left = half(left_half, false);
        left.reverse();
        pts.extend(left);
        pts
    };
    c.path(
        &join(&curves.c90, &curves.c270),
        BLUE,
        2.0,
        Some((7.0, 11.0)),
    );
    c.path(&join(&curves.c0, &curves.c180), RED, 2.0, None);

    // Legend and unit.
    c.text(10.0, 10.0, "cd/klm", INK);
    c.path(&[(330.0, 15.0), (360.0, 15.0)], RED, 2.0, None);
    c.text(368.0, 10.0, "C0-C180", INK);
    c.path(
        &[(330.0, 35.0), (360.0, 35.0)],
        BLUE,
        2.0,
        Some((7.0, 11.0)),
    );
    c.text(368.0, 30.0, "C90-C270", INK);
    c.text(10.0, (HEIGHT - 20) as f64, "C180 C270", [90, 90, 90]);
    let right_label = "C0 C90";
    c.text(
        (WIDTH - 10 - text_width(right_label, SCALE)) as f64,
        (HEIGHT - 20) as f64,
        right_label,
        [90, 90, 90],
    );
    PolarImage {
        width: WIDTH,
        height: HEIGHT,
        rgb: c.rgb,
    }
}

/// The polar diagram of `p` as PNG bytes (for report.html to embed).
pub fn polar_diagram_png(p: &Photometry) -> Result<Vec<u8>> {
    let img = polar_diagram(p);
    encode_rgb_png(img.width, img.height, &img.rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ring_steps_are_round() {
        assert_eq!(ring_step(400.0), 100.0);
        assert_eq!(ring_step(350.0), 100.0);
        assert_eq!(ring_step(190.0), 50.0);
        assert_eq!(ring_step(9.0), 2.5);
        assert_eq!(ring_step(0.0), 1.0);
    }
}

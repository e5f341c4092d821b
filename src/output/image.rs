//! The rendered image and its files: `render.exr` (luminance, cd/m², f32), `render.png`
//! (tone-mapped) and `render_false_colour.png` (log-scale pseudo-colour with a scale).

use crate::raster::font::{draw_text, text_width};
use crate::raster::palette::false_colour;
use crate::raster::{encode_png, quantile, Rank};
use crate::{Error, Result};

/// Luminance image, row-major from the top-left pixel, cd/m².
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub luminance_cdm2: Vec<f64>,
}

/// Reinhard's key value: the log-average luminance maps to this display value.
pub const KEY: f64 = 0.18;
/// Scaled luminances at or above this percentile burn to white (Reinhard's L_white).
pub const WHITE_PERCENTILE: f64 = 0.999;

/// The luminance as a one-channel (`Y`) f32 EXR, as bytes.
pub fn render_exr(image: &Image) -> Result<Vec<u8>> {
    use exr::prelude::{SpecificChannels, Vec2, WritableImage};
    let (w, l) = (image.width, &image.luminance_cdm2);
    let channels = SpecificChannels::build()
        .with_channel("Y")
        .with_pixel_fn(|p: Vec2<usize>| (l[p.1 * w + p.0] as f32,));
    let mut bytes = std::io::Cursor::new(Vec::new());
    exr::prelude::Image::from_channels((image.width, image.height), channels)
        .write()
        // Chunks in file order: the same image gives the same bytes.
        .non_parallel()
        .to_buffered(&mut bytes)
        .map_err(|e| Error::Unsupported(format!("render.exr: {e}")))?;
    Ok(bytes.into_inner())
}

/// Log-average luminance of the lit pixels (Reinhard's L̄w), cd/m²; 0 if none is lit.
pub fn log_average_cdm2(l: &[f64]) -> f64 {
    let lit: Vec<f64> = l.iter().copied().filter(|x| *x > 0.0).collect();
    if lit.is_empty() {
        return 0.0;
    }
    libm::exp(lit.iter().map(|x| libm::log(1e-4 + x)).sum::<f64>() / lit.len() as f64)
}

/// The `q` quantile of the positive (lit) luminances, 0 if none.
fn lit_quantile(l: &[f64], q: f64) -> f64 {
    quantile(l, q, Rank::Rounded, |x| x > 0.0)
}

/// sRGB transfer function of a linear value in [0, 1].
fn srgb(c: f64) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let v = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * libm::pow(c, 1.0 / 2.4) - 0.055
    };
    (v * 255.0).round() as u8
}

/// Reinhard et al. 2002 global operator: Ls = KEY·L/L̄w, Ld = Ls(1 + Ls/Lwhite²)/(1 + Ls)
/// with Lwhite the 99.9th percentile of Ls, then sRGB; grey (luminance only).
pub fn tone_map(image: &Image) -> Vec<u8> {
    let l = &image.luminance_cdm2;
    let avg = log_average_cdm2(l);
    if avg <= 0.0 {
        return vec![0; l.len()];
    }
    let scale = KEY / avg;
    let white = (lit_quantile(l, WHITE_PERCENTILE) * scale).max(1e-9);
    l.iter()
        .map(|&x| {
            let s = x * scale;
            srgb(s * (1.0 + s / (white * white)) / (1.0 + s))
        })
        .collect()
}

/// An 8-bit PNG file's bytes; `name` is for the error.
fn png_bytes(
    name: &str,
    width: usize,
    height: usize,
    colour: png::ColorType,
    data: &[u8],
) -> Result<Vec<u8>> {
    encode_png(width, height, colour, data).map_err(|e| Error::Unsupported(format!("{name}: {e}")))
}

/// The tone-mapped image (8-bit grey, sRGB) as a PNG.
pub fn tone_mapped_png(image: &Image) -> Result<Vec<u8>> {
    png_bytes(
        "render.png",
        image.width,
        image.height,
        png::ColorType::Grayscale,
        &tone_map(image),
    )
}

/// Scale values: 1, 2 and 5 times a power of ten.
fn nice(k: i32) -> f64 {
    [1.0, 2.0, 5.0][k.rem_euclid(3) as usize] * 10f64.powi(k.div_euclid(3))
}

/// The false-colour scale, as indices of [`nice`] values (bottom, top): the top is the
/// first 1-2-5 value at or above the 99.9th percentile, the bottom the last at or below
/// the 1st percentile, at least one and at most four decades below the top.
pub fn false_colour_range(l: &[f64]) -> (i32, i32) {
    let top = lit_quantile(l, 0.999);
    if top <= 0.0 {
        return (-3, 0);
    }
    let mut hi = (libm::log10(top).floor() as i32) * 3;
    while nice(hi) < top {
        hi += 1;
    }
    let bottom = lit_quantile(l, 0.01);
    let mut lo = hi - 3;
    while lo > hi - 12 && nice(lo) > bottom {
        lo -= 1;
    }
    (lo, hi)
}

fn scale_label(v: f64) -> String {
    if (1.0..1e6).contains(&v) {
        format!("{v:.0}")
    } else if (1e-3..1.0).contains(&v) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').to_string()
    } else {
        format!("{v:e}")
    }
}

/// The log-scale pseudo-colour image as a PNG, with a scale bar and labels at its
/// right, labelled at 1-2-5 values (cd/m²); pixels that see nothing (L = 0) are black.
pub fn false_colour_png(image: &Image) -> Result<Vec<u8>> {
    const PANEL: usize = 96;
    const SCALE: usize = 2;
    let (w, h) = (image.width, image.height);
    let width = w + PANEL;
    let height = h.max(160);
    let mut rgb = vec![0u8; 3 * width * height];
    let (lo, hi) = false_colour_range(&image.luminance_cdm2);
    let (log_lo, log_hi) = (libm::log10(nice(lo)), libm::log10(nice(hi)));
    let position = |l: f64| (libm::log10(l) - log_lo) / (log_hi - log_lo);
    for y in 0..h {
        for x in 0..w {
            let l = image.luminance_cdm2[y * w + x];
            if l > 0.0 {
                let at = 3 * (y * width + x);
                rgb[at..at + 3].copy_from_slice(&false_colour(position(l)));
            }
        }
    }
    // The bar: from `top` (10^hi) down to `bottom` (10^lo).
    let (bar_x, bar_w) = (w + 10, 16);
    let (top, bottom) = (24, height - 12);
    let white = [255, 255, 255];
    draw_text(&mut rgb, width, w + 10, 6, "cd/m2", SCALE, white);
    for y in top..=bottom {
        let f = (bottom - y) as f64 / (bottom - top) as f64;
        for x in bar_x..bar_x + bar_w {
            let at = 3 * (y * width + x);
            rgb[at..at + 3].copy_from_slice(&false_colour(f));
        }
    }
    for k in lo..=hi {
        let f = position(nice(k));
        let y = bottom - (f * (bottom - top) as f64).round() as usize;
        // Ticks across the bar (a tick beside a label would read as a minus sign).
        for x in bar_x..bar_x + bar_w {
            let at = 3 * (y * width + x);
            rgb[at..at + 3].copy_from_slice(&[0, 0, 0]);
        }
        let label = scale_label(nice(k));
        let x = (bar_x + bar_w + 6).min(width.saturating_sub(text_width(&label, SCALE)));
        draw_text(
            &mut rgb,
            width,
            x,
            y.saturating_sub(5 * SCALE / 2),
            &label,
            SCALE,
            white,
        );
    }
    png_bytes(
        "render_false_colour.png",
        width,
        height,
        png::ColorType::Rgb,
        &rgb,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn false_colour_scale_brackets_the_image_on_1_2_5_values() {
        let l: Vec<f64> = (0..1000).map(|i| 8.0 + 52.0 * i as f64 / 999.0).collect();
        let (lo, hi) = false_colour_range(&l);
        assert_eq!((nice(lo), nice(hi)), (5.0, 100.0));
        assert_eq!(scale_label(0.05), "0.05");
        assert_eq!(scale_label(200.0), "200");
        assert_eq!(scale_label(2e-5), "2e-5");
    }

    #[test]
    fn tone_map_sends_the_log_average_to_the_key() {
        // A uniform image: every pixel is the log-average, Ls = KEY, Lwhite = KEY.
        let image = Image {
            width: 2,
            height: 1,
            luminance_cdm2: vec![40.0, 40.0],
        };
        let ls = KEY * 40.0 / log_average_cdm2(&image.luminance_cdm2);
        let expected = srgb(ls * (1.0 + ls / (ls * ls)) / (1.0 + ls));
        assert_eq!(tone_map(&image), vec![expected; 2]);
    }
}

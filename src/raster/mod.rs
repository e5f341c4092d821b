//! Raster helpers every image output shares (receiver previews, the render's PNGs, the
//! photometric polar diagram, the scene map's vertex colours): one bitmap font, one
//! PNG encoder, one palette module and one quantile function. Depends on nothing of the
//! crate but its error type, so `photometry`, `output` and `render` may all use it.

pub mod canvas;
pub mod font;
pub mod palette;

use crate::{Error, Result};

/// An 8-bit image (`data` row by row; 1 byte a pixel for grey, 3 for RGB) as PNG bytes.
pub fn encode_png(
    width: usize,
    height: usize,
    colour: png::ColorType,
    data: &[u8],
) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    let err = |e: png::EncodingError| Error::Unsupported(format!("PNG encoding: {e}"));
    {
        let mut enc = png::Encoder::new(&mut bytes, width as u32, height as u32);
        enc.set_color(colour);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(err)?;
        writer.write_image_data(data).map_err(err)?;
        writer.finish().map_err(err)?;
    }
    Ok(bytes)
}

/// An 8-bit RGB image (3 bytes a pixel) as PNG bytes.
pub fn encode_rgb_png(width: usize, height: usize, rgb: &[u8]) -> Result<Vec<u8>> {
    encode_png(width, height, png::ColorType::Rgb, rgb)
}

/// Which element of the sorted values a quantile `q` picks. Two rules remain because
/// each is part of an output's bytes (docs/outputs.md, docs/render.md): changing one
/// would change the scene map's colours or the render's tone mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rank {
    /// Nearest rank: the ⌈q·n⌉-th value (scene map colour scale).
    Nearest,
    /// The value at position round(q·(n − 1)) (render tone mapping, false-colour scale).
    Rounded,
}

/// The `q` quantile of the values `keep` accepts, by `rank`; 0 when none is kept.
pub fn quantile(values: &[f64], q: f64, rank: Rank, keep: impl Fn(f64) -> bool) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|&x| keep(x)).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let at = match rank {
        Rank::Nearest => ((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1,
        Rank::Rounded => ((v.len() - 1) as f64 * q).round() as usize,
    };
    v[at]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantile_rules_pick_their_ranks() {
        let v: Vec<f64> = (1..=70).map(f64::from).collect();
        // ⌈0.99 · 70⌉ = 70th value; round(0.99 · 69) = 68 → 69th value.
        assert_eq!(quantile(&v, 0.99, Rank::Nearest, f64::is_finite), 70.0);
        assert_eq!(quantile(&v, 0.99, Rank::Rounded, f64::is_finite), 69.0);
        assert_eq!(quantile(&[0.0, -1.0], 0.5, Rank::Rounded, |x| x > 0.0), 0.0);
    }
}

//! The palettes of the false-colour outputs. Maps (PLY vertex colours, receiver PNG
//! previews, report.html) use viridis: 10 anchors of matplotlib's table, interpolated
//! linearly in sRGB; report.html carries the same anchors (`VIRIDIS` in `COLORMAP_JS`).
//! The render's log-scale false-colour image uses the classic luminance scale
//! ([`false_colour`]: dark blue, blue, cyan, green, yellow, red), as lighting tools do.

/// viridis(k / 9), k = 0..=9, 8-bit sRGB.
pub const VIRIDIS: [[u8; 3]; 10] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x28, 0x78],
    [0x3e, 0x4a, 0x89],
    [0x31, 0x68, 0x8e],
    [0x26, 0x82, 0x8e],
    [0x1f, 0x9e, 0x89],
    [0x35, 0xb7, 0x79],
    [0x6d, 0xcd, 0x59],
    [0xb4, 0xde, 0x2c],
    [0xfd, 0xe7, 0x25],
];

/// Colour of `t` in [0, 1] (clamped; NaN maps to 0).
pub fn viridis(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let k = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - k as f64;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    std::array::from_fn(|c| (a[c] as f64 + f * (b[c] as f64 - a[c] as f64)).round() as u8)
}

/// The render's false-colour stops from the bottom of the scale to the top.
const STOPS: [[f64; 3]; 6] = [
    [0.0, 0.0, 0.5],
    [0.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [0.0, 1.0, 0.0],
    [1.0, 1.0, 0.0],
    [1.0, 0.0, 0.0],
];

/// Colour of `f` in [0, 1] (clamped) on the render's false-colour scale.
pub fn false_colour(f: f64) -> [u8; 3] {
    let x = f.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let t = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [0, 1, 2].map(|c| ((a[c] + (b[c] - a[c]) * t) * 255.0).round() as u8)
}

/// `t` = value / scale, 0 when the scale is not positive.
pub fn normalise(value: f64, scale: f64) -> f64 {
    if scale > 0.0 && scale.is_finite() {
        value / scale
    } else {
        0.0
    }
}

/// The anchors as a JS array, for report.html.
pub fn anchors_js() -> String {
    let items: Vec<String> = VIRIDIS
        .iter()
        .map(|c| format!("[{},{},{}]", c[0], c[1], c[2]))
        .collect();
    format!("[{}]", items.join(","))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_ends_are_the_table_ends_and_clamps() {
        assert_eq!(viridis(0.0), VIRIDIS[0]);
        assert_eq!(viridis(1.0), VIRIDIS[9]);
        assert_eq!(viridis(2.0), VIRIDIS[9]);
        assert_eq!(viridis(f64::NAN), VIRIDIS[0]);
        assert_eq!(viridis(4.0 / 9.0), VIRIDIS[4]);
    }
}

//! The crate's one 3 × 5 pixel bitmap font, for the labels of the render's false-colour
//! scale, the receivers' PNG previews and the photometric polar diagram: digits, `.`,
//! `-`, `+`, `e`, `%`, `/`, `=`, the letters of `cd/m2`, `cd/klm`, `lx` and `C`, and the
//! capitals of the UGR plot's labels (`UGR`, `X`, `Y`, `H`, `CROSSWISE`, `ENDWISE`).

/// Rows of a glyph, top first; bit 2 is the left column.
fn glyph(c: char) -> Option<[u8; 5]> {
    Some(match c {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b010, 0b010, 0b010],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        '.' => [0b000, 0b000, 0b000, 0b000, 0b010],
        '-' => [0b000, 0b000, 0b111, 0b000, 0b000],
        'e' => [0b000, 0b111, 0b111, 0b100, 0b111],
        'c' => [0b000, 0b111, 0b100, 0b100, 0b111],
        'd' => [0b001, 0b111, 0b101, 0b101, 0b111],
        'm' => [0b000, 0b110, 0b111, 0b101, 0b101],
        'k' => [0b100, 0b101, 0b110, 0b101, 0b101],
        'l' => [0b110, 0b010, 0b010, 0b010, 0b111],
        'C' => [0b111, 0b100, 0b100, 0b100, 0b111],
        '/' => [0b001, 0b001, 0b010, 0b100, 0b100],
        '+' => [0b000, 0b010, 0b111, 0b010, 0b000],
        '%' => [0b101, 0b001, 0b010, 0b100, 0b101],
        'x' => [0b000, 0b000, 0b101, 0b010, 0b101],
        '=' => [0b000, 0b111, 0b000, 0b111, 0b000],
        'U' => [0b101, 0b101, 0b101, 0b101, 0b111],
        'G' => [0b111, 0b100, 0b101, 0b101, 0b111],
        'R' => [0b110, 0b101, 0b110, 0b101, 0b101],
        'X' => [0b101, 0b101, 0b010, 0b101, 0b101],
        'Y' => [0b101, 0b101, 0b010, 0b010, 0b010],
        'H' => [0b101, 0b101, 0b111, 0b101, 0b101],
        'O' => [0b010, 0b101, 0b101, 0b101, 0b010],
        'S' => [0b011, 0b100, 0b010, 0b001, 0b110],
        'W' => [0b101, 0b101, 0b101, 0b111, 0b101],
        'I' => [0b111, 0b010, 0b010, 0b010, 0b111],
        'E' => [0b111, 0b100, 0b111, 0b100, 0b111],
        'N' => [0b110, 0b101, 0b101, 0b101, 0b101],
        'D' => [0b110, 0b101, 0b101, 0b101, 0b110],
        ' ' => [0; 5],
        _ => return None,
    })
}

/// Horizontal advance of one character drawn at `scale`, pixels (3 columns and a gap).
pub fn advance(scale: usize) -> usize {
    4 * scale
}

/// Width of `text` drawn at `scale`, pixels.
pub fn text_width(text: &str, scale: usize) -> usize {
    text.chars().count() * advance(scale)
}

/// Draws `text` into an RGB buffer of width `width` with its top-left at (x, y);
/// pixels outside the buffer are skipped.
pub fn draw_text(
    rgb: &mut [u8],
    width: usize,
    x: usize,
    y: usize,
    text: &str,
    scale: usize,
    colour: [u8; 3],
) {
    let height = rgb.len() / (3 * width);
    for (i, c) in text.chars().enumerate() {
        let Some(rows) = glyph(c) else { continue };
        for (r, bits) in rows.iter().enumerate() {
            for col in 0..3 {
                if bits & (0b100 >> col) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let px = x + (i * 4 + col) * scale + dx;
                        let py = y + r * scale + dy;
                        if px < width && py < height {
                            let at = 3 * (py * width + px);
                            rgb[at..at + 3].copy_from_slice(&colour);
                        }
                    }
                }
            }
        }
    }
}

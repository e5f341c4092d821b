//! IES LM-63 (1986, 1991, 1995, 2002, 2019): the header line (or its absence), keyword
//! lines up to `TILT=`, the tilt table (NONE, INCLUDE or a file), then the photometric
//! records as numbers separated by blanks or commas across any line breaks.

use super::expand::{c_planes, mirror_about_zero};
use super::grid::{Grid, TYPE_A, TYPE_B, TYPE_C};
use super::sample::Sampler;
use super::text::{self, at, check_increasing, check_range, Tokens, MAX_ANGLES, MAX_VALUES};
use super::{Format, Opening, PhotometricType, Photometry, Symmetry, Tilt};
use crate::input::{beyond_reach, MAX_COORDINATE_M};
use crate::Result;
use std::path::Path;

/// Feet to metres (units type 1).
const FOOT_M: f64 = 0.3048;

/// Whether a file of unknown extension reads as LM-63: an `IES…` first line or a
/// `TILT=` line.
pub fn looks_like_ies(text: &str) -> bool {
    let lines = text::lines(text);
    let first = lines.iter().find(|l| !l.trim().is_empty());
    first.is_some_and(|l| l.trim().to_ascii_uppercase().starts_with("IES"))
        || lines.iter().any(|l| tilt_spec(l).is_some())
}

/// The LM-63 edition a first line declares; None for a 1986 file (no header line).
fn version(first: &str) -> std::result::Result<Option<u16>, String> {
    let up = first.trim().to_ascii_uppercase();
    let year = if let Some(y) = up.strip_prefix("IESNA:LM-63-") {
        y.trim().parse::<u16>().ok()
    } else if let Some(y) = up.strip_prefix("IES:LM-63-") {
        y.trim().parse::<u16>().ok()
    } else if let Some(y) = up.strip_prefix("IESNA") {
        // IESNA91, and IESNA95 as files of 1995 (examp1.ies among them) wrote it.
        match y.trim() {
            "91" => Some(1991),
            "95" => Some(1995),
            _ => None,
        }
    } else if up.starts_with("IES:") {
        None
    } else {
        return Ok(None);
    };
    match year {
        Some(y @ (1991 | 1995 | 2002 | 2019)) => Ok(Some(y)),
        _ => Err(format!(
            "unknown LM-63 header `{}` (expected IESNA91, IESNA:LM-63-1995, \
             IESNA:LM-63-2002 or IES:LM-63-2019)",
            first.trim()
        )),
    }
}

/// What follows `TILT=` on a line that starts with it.
fn tilt_spec(line: &str) -> Option<&str> {
    let t = line.trim_start();
    let head = t.get(..4)?;
    if !head.eq_ignore_ascii_case("TILT") {
        return None;
    }
    t[4..].trim_start().strip_prefix('=').map(str::trim)
}

/// A tilt table's four records: geometry, count, angles, factors.
fn read_tilt(t: &mut Tokens) -> Result<Tilt> {
    let origin = t.origin();
    let (geometry, _) = t.integer("the tilt's lamp-to-luminaire geometry", 1, 3)?;
    let (n, _) = t.integer("the number of tilt angles", 1, MAX_ANGLES as i64)?;
    let (angles_deg, angle_lines) = t.numbers(n as usize, "tilt angle")?;
    check_increasing(origin, &angles_deg, &angle_lines, "tilt angle")?;
    let (factors, factor_lines) = t.numbers(n as usize, "tilt factor")?;
    for (k, &f) in factors.iter().enumerate() {
        if f < 0.0 {
            return Err(at(
                origin,
                factor_lines[k],
                format!("tilt factor {} is negative ({f})", k + 1),
            ));
        }
    }
    Ok(Tilt {
        geometry: geometry as u8,
        angles_deg,
        factors,
    })
}

/// Parses LM-63 text; `origin` names the file in errors, `dir` is where a `TILT=<file>`
/// is looked for.
pub(crate) fn parse(text: &str, origin: &str, dir: &Path) -> Result<Photometry> {
    let lines = text::lines(text);
    let year = version(lines[0]).map_err(|m| at(origin, 1, m))?;
    let label_start = usize::from(year.is_some());
    let Some(tilt_index) = lines.iter().position(|l| tilt_spec(l).is_some()) else {
        return Err(at(
            origin,
            text::last_content(&lines),
            "no `TILT=` line: not an LM-63 file, or one cut short in its keywords",
        ));
    };
    let keywords = keywords(&lines[label_start.min(tilt_index)..tilt_index], year);
    let spec = tilt_spec(lines[tilt_index]).unwrap_or_default();
    let mut t = Tokens::new(origin, &lines[tilt_index + 1..], tilt_index + 2);
    let tilt = tilt(spec, &mut t, dir, tilt_index + 1)?;
    let r = Records::read(&mut t, year)?;
    let (nv, nh) = (r.vertical_angles, r.horizontal_angles);
    let (vertical, v_lines) = t.numbers(nv, "vertical angle")?;
    let (horizontal, h_lines) = t.numbers(nh, "horizontal angle")?;
    let (mut rows, table_line) = candela_rows(&mut t, &vertical, &horizontal)?;
    t.finish(&format!("({nv} vertical × {nh} horizontal angles)"))?;

    check_increasing(origin, &vertical, &v_lines, "vertical angle")?;
    check_increasing(origin, &horizontal, &h_lines, "horizontal angle")?;
    let tilt_factor = tilt.as_ref().map_or(1.0, |t| t.factor(0.0));
    let lamp_output_factor = r.ballast * r.lamp_factor * tilt_factor;
    let scale = r.multiplier * lamp_output_factor;
    for row in &mut rows {
        for v in row.iter_mut() {
            *v *= scale;
        }
    }
    let angles = Angles {
        vertical,
        v_lines,
        horizontal,
        h_lines,
    };
    let (symmetry, grid) = grid(origin, r.kind, angles, rows)?;

    Photometry::build(
        Photometry {
            file: origin.to_string(),
            format: Format::Ies(year.unwrap_or(1986)),
            photometric_type: r.kind,
            symmetry,
            grid,
            opening: opening(r.width * r.unit_m, r.length * r.unit_m),
            height_m: r.height.abs() * r.unit_m,
            lamp_flux_lm: (r.lumens > 0.0).then_some(r.lamps as f64 * r.lumens),
            lamp_output_factor,
            input_watts: Some(r.watts),
            stated_light_output_ratio: None,
            stated_downward_fraction: None,
            tilt,
            keywords,
            lamp_sets: Vec::new(),
            sampler: Sampler::default(),
            flux_lm: 0.0,
        },
        table_line,
    )
}

/// The tilt table `TILT=<spec>` (line `line`) names: none, the one that follows in
/// `t`, or a file in `dir`.
fn tilt(spec: &str, t: &mut Tokens, dir: &Path, line: usize) -> Result<Option<Tilt>> {
    let origin = t.origin();
    if spec.eq_ignore_ascii_case("NONE") {
        Ok(None)
    } else if spec.eq_ignore_ascii_case("INCLUDE") {
        Ok(Some(read_tilt(t)?))
    } else if spec.is_empty() {
        Err(at(
            origin,
            line,
            "`TILT=` names neither NONE, INCLUDE nor a file",
        ))
    } else {
        let path = dir.join(spec);
        let tilt_text =
            text::read(&path).map_err(|e| at(origin, line, format!("TILT file: {e}")))?;
        let tilt_origin = path.display().to_string();
        let tilt_lines = text::lines(&tilt_text);
        let mut tt = Tokens::new(&tilt_origin, &tilt_lines, 1);
        let tilt = read_tilt(&mut tt)?;
        tt.finish("of the tilt table")?;
        Ok(Some(tilt))
    }
}

/// Records 1 (ten values) and 2 (three values) of an LM-63 file, checked.
struct Records {
    lamps: i64,
    /// Lumens per lamp; −1 for absolute photometry.
    lumens: f64,
    multiplier: f64,
    vertical_angles: usize,
    horizontal_angles: usize,
    kind: PhotometricType,
    /// Metres per unit of the dimensions.
    unit_m: f64,
    width: f64,
    length: f64,
    height: f64,
    ballast: f64,
    lamp_factor: f64,
    watts: f64,
}

impl Records {
    fn read(t: &mut Tokens, year: Option<u16>) -> Result<Records> {
        let origin = t.origin();
        let (lamps, _) = t.integer("the number of lamps", 1, 1_000_000)?;
        let (lumens, lumens_line) = t.number("the lumens per lamp")?;
        if !(lumens > 0.0 || lumens == -1.0) {
            return Err(at(
                origin,
                lumens_line,
                format!(
                    "lumens per lamp {lumens}: must be positive, or −1 for absolute photometry"
                ),
            ));
        }
        let (multiplier, multiplier_line) = t.number("the candela multiplier")?;
        positive(origin, multiplier_line, "candela multiplier", multiplier)?;
        let (nv, _) = t.integer("the number of vertical angles", 2, MAX_ANGLES as i64)?;
        let (nh, nh_line) = t.integer("the number of horizontal angles", 1, MAX_ANGLES as i64)?;
        let (nv, nh) = (nv as usize, nh as usize);
        if nv * nh > MAX_VALUES {
            return Err(at(
                origin,
                nh_line,
                format!("{nv} × {nh} candela values: more than {MAX_VALUES}"),
            ));
        }
        let kind = Self::photometric_type(t)?;
        let unit_m = Self::unit_m(t)?;
        let mut dimension = |what: &str| -> Result<f64> {
            let (v, line) = t.number(what)?;
            if (v * unit_m).abs() > MAX_COORDINATE_M {
                let metres = format!("{:e} m", v * unit_m);
                return Err(at(
                    origin,
                    line,
                    format!("{what}: {}", beyond_reach(metres)),
                ));
            }
            Ok(v)
        };
        let width = dimension("the luminous width")?;
        let length = dimension("the luminous length")?;
        let height = dimension("the luminous height")?;
        let (ballast, lamp_factor, watts) = Self::record_2(t, year)?;
        Ok(Records {
            lamps,
            lumens,
            multiplier,
            vertical_angles: nv,
            horizontal_angles: nh,
            kind,
            unit_m,
            width,
            length,
            height,
            ballast,
            lamp_factor,
            watts,
        })
    }

    /// Record 1's photometric type: 1 = C, 2 = B, 3 = A.
    fn photometric_type(t: &mut Tokens) -> Result<PhotometricType> {
        let (kind, kind_line) = t.number("the photometric type")?;
        match kind {
            1.0 => Ok(PhotometricType::C),
            2.0 => Ok(PhotometricType::B),
            3.0 => Ok(PhotometricType::A),
            _ => Err(at(
                t.origin(),
                kind_line,
                format!("unknown photometric type {kind} (1 = C, 2 = B, 3 = A)"),
            )),
        }
    }

    /// Record 1's units type as metres per unit: 1 = feet, 2 = metres.
    fn unit_m(t: &mut Tokens) -> Result<f64> {
        let (units, units_line) = t.number("the units type")?;
        match units {
            1.0 => Ok(FOOT_M),
            2.0 => Ok(1.0),
            _ => Err(at(
                t.origin(),
                units_line,
                format!("unknown units type {units} (1 = feet, 2 = metres)"),
            )),
        }
    }

    /// Record 2: the ballast factor, the ballast-lamp photometric factor and the input
    /// watts.
    fn record_2(t: &mut Tokens, year: Option<u16>) -> Result<(f64, f64, f64)> {
        let origin = t.origin();
        let (ballast, ballast_line) = t.number("the ballast factor")?;
        positive(origin, ballast_line, "ballast factor", ballast)?;
        let (third, third_line) = t.number(if year == Some(2019) {
            "the file generation type"
        } else {
            "the ballast-lamp photometric factor"
        })?;
        // LM-63-2019 reuses the field for how the file was made: not a factor.
        let lamp_factor = if year == Some(2019) {
            1.0
        } else {
            positive(origin, third_line, "ballast-lamp photometric factor", third)?;
            third
        };
        let (watts, watts_line) = t.number("the input watts")?;
        if watts < 0.0 {
            return Err(at(
                origin,
                watts_line,
                format!("input watts {watts} is negative"),
            ));
        }
        Ok((ballast, lamp_factor, watts))
    }
}

/// The candela table: a row of `vertical.len()` values per horizontal angle, none
/// negative; also the line the table starts on.
fn candela_rows(
    t: &mut Tokens,
    vertical: &[f64],
    horizontal: &[f64],
) -> Result<(Vec<Vec<f64>>, usize)> {
    let origin = t.origin();
    let mut rows = Vec::new();
    let mut table_line = 0;
    for &h in horizontal {
        let (row, row_lines) = t.numbers(
            vertical.len(),
            &format!("candela value at horizontal angle {h}°:"),
        )?;
        if table_line == 0 {
            table_line = row_lines[0];
        }
        for (k, &cd) in row.iter().enumerate() {
            if cd < 0.0 {
                return Err(at(
                    origin,
                    row_lines[k],
                    format!(
                        "candela value {cd} at horizontal {h}°, vertical {}° is negative",
                        vertical[k]
                    ),
                ));
            }
        }
        rows.push(row);
    }
    Ok((rows, table_line))
}

/// The file's angles and the lines they stand on.
struct Angles {
    vertical: Vec<f64>,
    v_lines: Vec<usize>,
    horizontal: Vec<f64>,
    h_lines: Vec<usize>,
}

/// The candela `rows` (one per horizontal angle) on the grid of photometric type
/// `kind`, with the symmetry the angles imply.
fn grid(
    origin: &str,
    kind: PhotometricType,
    angles: Angles,
    rows: Vec<Vec<f64>>,
) -> Result<(Symmetry, Grid)> {
    let Angles {
        vertical,
        v_lines,
        horizontal,
        h_lines,
    } = angles;
    let (nv, nh) = (vertical.len(), horizontal.len());
    // Vertical and horizontal angles within their type's ranges (degrees).
    let in_ranges = |(v0, v1), (h0, h1)| -> Result<()> {
        check_range(origin, &vertical, &v_lines, "vertical angle", v0, v1)?;
        check_range(origin, &horizontal, &h_lines, "horizontal angle", h0, h1)
    };
    match kind {
        PhotometricType::C => {
            in_ranges((0.0, 180.0), (0.0, 360.0))?;
            let symmetry = c_symmetry(&horizontal).ok_or_else(|| {
                at(
                    origin,
                    h_lines[0],
                    format!(
                        "horizontal angles {}–{}°: type C stores 0, 0–90, 0–180, 90–270 or 0–360",
                        horizontal[0],
                        horizontal[nh - 1]
                    ),
                )
            })?;
            let (phi, planes) = c_planes(&horizontal, &rows, symmetry);
            Ok((symmetry, grid_of(TYPE_C, phi, vertical, &planes)))
        }
        PhotometricType::A | PhotometricType::B => {
            in_ranges((-90.0, 90.0), (-90.0, 90.0))?;
            if nh < 2 {
                return Err(at(
                    origin,
                    h_lines[0],
                    "types A and B need at least two horizontal angles",
                ));
            }
            let (symmetry, (h, rows)) = if horizontal[0] == 0.0 {
                (Symmetry::LateralH, mirror_about_zero(&horizontal, &rows))
            } else {
                (Symmetry::None, (horizontal, rows))
            };
            let lat = |a: &[f64]| a.iter().map(|x| 90.0 + x).collect::<Vec<_>>();
            let grid = if kind == PhotometricType::A {
                // Planes are H, the latitude is V.
                grid_of(TYPE_A, h, lat(&vertical), &rows)
            } else {
                // Planes are V, the latitude is H: the rows transpose.
                let planes: Vec<Vec<f64>> = (0..nv)
                    .map(|v| rows.iter().map(|r| r[v]).collect())
                    .collect();
                grid_of(TYPE_B, vertical, lat(&h), &planes)
            };
            Ok((symmetry, grid))
        }
    }
}

fn positive(origin: &str, line: usize, what: &str, v: f64) -> Result<()> {
    if v > 0.0 {
        Ok(())
    } else {
        Err(at(origin, line, format!("{what} {v} must be positive")))
    }
}

/// Type C's symmetry from its stored horizontal angles (increasing, within 0 … 360).
fn c_symmetry(h: &[f64]) -> Option<Symmetry> {
    let (first, last) = (h[0], h[h.len() - 1]);
    match (h.len(), first, last) {
        (1, _, _) => Some(Symmetry::Rotational),
        (_, 0.0, 90.0) => Some(Symmetry::Quadrant),
        (_, 0.0, 180.0) => Some(Symmetry::BilateralC0C180),
        (_, 90.0, 270.0) => Some(Symmetry::BilateralC90C270),
        // Full circle; a last plane short of 360 wraps to C = 0.
        (_, 0.0, l) if l > 180.0 => Some(Symmetry::None),
        _ => None,
    }
}

/// A grid from planes (rows of values at `theta`).
fn grid_of(axes: super::grid::Axes, phi: Vec<f64>, theta: Vec<f64>, planes: &[Vec<f64>]) -> Grid {
    Grid {
        axes,
        phi_deg: phi,
        theta_deg: theta,
        cd: planes.concat(),
    }
}

/// The opening of LM-63's width (along C90, y) and length (along C0, x), metres: both 0
/// a point, both ≥ 0 a rectangle, a negative one round (a disc whose diameter is the
/// non-zero one, or an ellipse if both differ).
fn opening(width_m: f64, length_m: f64) -> Opening {
    if width_m == 0.0 && length_m == 0.0 {
        Opening::Point
    } else if width_m >= 0.0 && length_m >= 0.0 {
        Opening::Rectangle { length_m, width_m }
    } else {
        let (l, w) = (length_m.abs(), width_m.abs());
        if l == 0.0 || w == 0.0 || l == w {
            Opening::Disc {
                diameter_m: l.max(w),
            }
        } else {
            Opening::Ellipse {
                length_m: l,
                width_m: w,
            }
        }
    }
}

/// `[KEY] value` lines (`[MORE]` continues the previous one); other lines — all of a
/// 1986 file's label — under `LABEL`.
fn keywords(lines: &[&str], year: Option<u16>) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for line in lines {
        let l = line.trim();
        if l.is_empty() {
            continue;
        }
        let parsed = if year.is_some() {
            l.strip_prefix('[')
                .and_then(|r| r.split_once(']'))
                .map(|(k, v)| (k.trim().to_ascii_uppercase(), v.trim().to_string()))
        } else {
            None
        };
        match parsed {
            Some((k, v)) if k == "MORE" && !out.is_empty() => {
                let last = out.len() - 1;
                out[last].1.push('\n');
                out[last].1.push_str(&v);
            }
            Some(kv) => out.push(kv),
            None => out.push(("LABEL".into(), l.to_string())),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_lines_name_their_edition() {
        assert_eq!(version("IESNA:LM-63-1995"), Ok(Some(1995)));
        assert_eq!(version("IESNA:LM-63-2002 "), Ok(Some(2002)));
        assert_eq!(version("IES:LM-63-2019"), Ok(Some(2019)));
        assert_eq!(version("IESNA91"), Ok(Some(1991)));
        assert_eq!(version("IESNA95"), Ok(Some(1995)));
        assert_eq!(version("Some manufacturer"), Ok(None));
        assert!(version("IESNA:LM-63-2031").is_err());
    }

    #[test]
    fn tilt_lines_are_found_in_any_case_and_spacing() {
        assert_eq!(tilt_spec("TILT=NONE"), Some("NONE"));
        assert_eq!(tilt_spec("tilt = include "), Some("include"));
        assert_eq!(tilt_spec("TILT=lamp.tlt"), Some("lamp.tlt"));
        assert_eq!(tilt_spec("[TILTED] x"), None);
    }
}

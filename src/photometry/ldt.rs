//! EULUMDAT (.ldt): one field per line at a fixed place (Stockmar 1990). Intensities are
//! in cd per 1000 lm of lamp flux, already the luminaire's (so LORL is not applied):
//! cd = value × (lamp set 1's flux / 1000) × the conversion factor.

use super::expand::c_planes;
use super::grid::{Grid, TYPE_C};
use super::sample::Sampler;
use super::text::{self, at, check_increasing, check_range, MAX_ANGLES, MAX_VALUES};
use super::{Format, LampSet, Opening, PhotometricType, Photometry, Symmetry};
use crate::input::{beyond_reach, MAX_COORDINATE_M};
use crate::Result;

/// Largest number of lamp sets accepted (the format allows 20; some writers more).
const MAX_SETS: i64 = 1000;

/// The file's lines, read by 1-based line number.
struct Lines<'a> {
    origin: &'a str,
    lines: Vec<&'a str>,
    /// The last line with content: blank lines after it are the end of the file.
    end: usize,
}

impl<'a> Lines<'a> {
    fn text(&self, n: usize, what: &str) -> Result<&'a str> {
        match self.lines.get(n - 1).filter(|_| n <= self.end) {
            Some(l) => Ok(l.trim()),
            None => Err(at(
                self.origin,
                self.end,
                format!("the file ends before line {n} ({what})"),
            )),
        }
    }

    /// A number; a decimal comma (German writers) is read as a point.
    fn number(&self, n: usize, what: &str) -> Result<f64> {
        let s = self.text(n, what)?;
        let owned;
        let s = if s.contains(',') && !s.contains('.') {
            owned = s.replace(',', ".");
            owned.as_str()
        } else {
            s
        };
        text::number(s).map_err(|m| at(self.origin, n, format!("{what}: {m}")))
    }

    fn integer(&self, n: usize, what: &str, lo: i64, hi: i64) -> Result<i64> {
        let s = self.text(n, what)?;
        text::integer(s, lo, hi).map_err(|m| at(self.origin, n, format!("{what}: {m}")))
    }

    fn numbers(&self, first: usize, count: usize, what: &str) -> Result<Vec<f64>> {
        (0..count)
            .map(|k| self.number(first + k, &format!("{what} {} of {count}", k + 1)))
            .collect()
    }
}

/// Parses EULUMDAT text; `origin` names the file in errors.
pub(crate) fn parse(text_in: &str, origin: &str) -> Result<Photometry> {
    let lines = text::lines(text_in);
    let f = Lines {
        origin,
        end: text::last_content(&lines),
        lines,
    };
    let (h, keywords) = Header::read(&f)?;
    let (mc, ng) = (h.c_planes, h.gamma_angles);
    let lamp_sets = lamp_sets(&f, h.lamp_sets)?;
    // 26a–26f take six lines per lamp set; ten direct ratios follow.
    let ratios_line = 27 + 6 * h.lamp_sets;
    let _direct_ratios = f.numbers(ratios_line, 10, "direct ratio")?;
    let c_line = ratios_line + 10;
    let c_all = f.numbers(c_line, mc, "C angle")?;
    let g_line = c_line + mc;
    let gamma = f.numbers(g_line, ng, "γ angle")?;
    let c_lines: Vec<usize> = (c_line..c_line + mc).collect();
    let g_lines: Vec<usize> = (g_line..g_line + ng).collect();
    check_increasing(origin, &c_all, &c_lines, "C angle")?;
    check_range(origin, &c_all, &c_lines, "C angle", 0.0, 360.0)?;
    check_increasing(origin, &gamma, &g_lines, "γ angle")?;
    check_range(origin, &gamma, &g_lines, "γ angle", 0.0, 180.0)?;
    if c_all[0] != 0.0 || c_all[mc - 1] >= 360.0 {
        return Err(at(
            origin,
            c_line,
            format!(
                "C angles {}–{}°: EULUMDAT lists Mc planes from 0 up to below 360",
                c_all[0],
                c_all[mc - 1]
            ),
        ));
    }
    let (symmetry, stored_deg) = stored_planes(origin, h.isym, &c_all, c_line)?;
    let stored = stored_deg.len();
    if stored * ng > MAX_VALUES {
        return Err(at(
            origin,
            6,
            format!("{stored} × {ng} intensities: more than {MAX_VALUES}"),
        ));
    }
    let table_line = g_line + ng;
    let scale = lamp_sets[0].flux_lm / 1000.0 * h.cfli;
    let rows = intensities(&f, table_line, &stored_deg, &gamma, scale)?;

    let (phi, planes) = c_planes(&stored_deg, &rows, symmetry);
    let grid = Grid {
        axes: TYPE_C,
        phi_deg: phi,
        theta_deg: gamma,
        cd: planes.concat(),
    };
    let absolute = lamp_sets[0].lamps < 0;
    Photometry::build(
        Photometry {
            file: origin.to_string(),
            format: Format::Eulumdat,
            photometric_type: PhotometricType::C,
            symmetry,
            grid,
            opening: opening(h.area_length_m, h.area_width_m),
            height_m: h.height_m,
            lamp_flux_lm: (!absolute).then_some(lamp_sets[0].flux_lm),
            lamp_output_factor: 1.0,
            input_watts: Some(lamp_sets[0].watts),
            stated_light_output_ratio: Some(h.lorl / 100.0),
            stated_downward_fraction: Some(h.dff / 100.0),
            tilt: None,
            keywords,
            lamp_sets,
            sampler: Sampler::default(),
            flux_lm: 0.0,
        },
        table_line,
    )
}

/// Lines 1–26: what the file is, its counts and the luminaire's dimensions.
struct Header {
    isym: i64,
    /// Mc and Ng.
    c_planes: usize,
    gamma_angles: usize,
    area_length_m: f64,
    area_width_m: f64,
    /// The largest of the four luminous heights.
    height_m: f64,
    /// Downward flux fraction and light output ratio, %.
    dff: f64,
    lorl: f64,
    /// Intensity conversion factor (0 read as 1).
    cfli: f64,
    lamp_sets: usize,
}

impl Header {
    /// The header and the file's keywords (company, type, report, luminaire, …).
    fn read(f: &Lines) -> Result<(Header, Vec<(String, String)>)> {
        let origin = f.origin;
        let mut keywords = vec![("COMPANY".to_string(), f.text(1, "company")?.to_string())];
        let ityp = f.integer(2, "type indicator Ityp", 0, 3)?;
        keywords.push(("ITYP".into(), ityp.to_string()));
        let isym = f.integer(3, "symmetry indicator Isym", 0, 4)?;
        let mc = f.integer(4, "number of C-planes Mc", 1, MAX_ANGLES as i64)? as usize;
        let divisor = match isym {
            2 => 2,
            3 | 4 => 4,
            _ => 1,
        };
        if !mc.is_multiple_of(divisor) {
            return Err(at(
                origin,
                4,
                format!("Isym {isym} needs Mc divisible by {divisor}, not {mc}"),
            ));
        }
        let _dc = f.number(5, "C-plane distance Dc")?;
        let ng = f.integer(6, "number of γ angles Ng", 2, MAX_ANGLES as i64)? as usize;
        let _dg = f.number(7, "γ distance Dg")?;
        for (n, key) in [
            (8, "REPORT"),
            (9, "LUMINAIRE"),
            (10, "NUMBER"),
            (11, "FILENAME"),
            (12, "DATE"),
        ] {
            keywords.push((key.into(), f.text(n, key)?.to_string()));
        }
        let mm = |n: usize, what: &str| -> Result<f64> {
            let v = f.number(n, what)?;
            if v < 0.0 {
                return Err(at(origin, n, format!("{what} {v} mm is negative")));
            }
            if v / 1000.0 > MAX_COORDINATE_M {
                return Err(at(
                    origin,
                    n,
                    format!("{what}: {}", beyond_reach(format!("{v} mm"))),
                ));
            }
            Ok(v / 1000.0)
        };
        let _luminaire_length = mm(13, "luminaire length/diameter")?;
        let _luminaire_width = mm(14, "luminaire width")?;
        let _luminaire_height = mm(15, "luminaire height")?;
        let area_length_m = mm(16, "luminous area length/diameter")?;
        let area_width_m = mm(17, "luminous area width")?;
        let mut height_m: f64 = 0.0;
        for (n, what) in [
            (18, "luminous height C0"),
            (19, "luminous height C90"),
            (20, "luminous height C180"),
            (21, "luminous height C270"),
        ] {
            height_m = height_m.max(mm(n, what)?);
        }
        let dff = f.number(22, "downward flux fraction DFF")?;
        let lorl = f.number(23, "light output ratio LORL")?;
        let cfli = f.number(24, "intensity conversion factor")?;
        if cfli < 0.0 {
            return Err(at(
                origin,
                24,
                format!("intensity conversion factor {cfli} is negative"),
            ));
        }
        let _tilt_deg = f.number(25, "tilt during measurement")?;
        let lamp_sets = f.integer(26, "number of lamp sets", 1, MAX_SETS)? as usize;
        let header = Header {
            isym,
            c_planes: mc,
            gamma_angles: ng,
            area_length_m,
            area_width_m,
            height_m,
            dff,
            lorl,
            // Some writers leave 0 for "no conversion".
            cfli: if cfli == 0.0 { 1.0 } else { cfli },
            lamp_sets,
        };
        Ok((header, keywords))
    }
}

/// Lines 26a–26f: each field's `n_sets` lines in turn (all the sets' lamp counts, then
/// their types…).
fn lamp_sets(f: &Lines, n_sets: usize) -> Result<Vec<LampSet>> {
    let field = |k: usize, set: usize| 27 + k * n_sets + set;
    let mut lamp_sets = Vec::new();
    for s in 0..n_sets {
        let lamps = f.integer(field(0, s), "number of lamps", -1_000_000, 1_000_000)?;
        let flux_lm = f.number(field(2, s), "lamp set flux")?;
        if flux_lm <= 0.0 {
            return Err(at(
                f.origin,
                field(2, s),
                format!("lamp set {} flux {flux_lm} lm must be positive", s + 1),
            ));
        }
        lamp_sets.push(LampSet {
            lamps,
            lamp_type: f.text(field(1, s), "lamp type")?.to_string(),
            flux_lm,
            colour: f.text(field(3, s), "colour appearance")?.to_string(),
            colour_rendering: f.text(field(4, s), "colour rendering")?.to_string(),
            watts: f.number(field(5, s), "lamp set watts")?,
        });
    }
    Ok(lamp_sets)
}

/// The planes symmetry `isym` stores (EULUMDAT's Mc1 … Mc2, wrapping past C360) and
/// their angles, increasing through the wrap (C270 … C450 for Isym 3); `c_all` are the
/// Mc angles on lines from `c_line`.
fn stored_planes(
    origin: &str,
    isym: i64,
    c_all: &[f64],
    c_line: usize,
) -> Result<(Symmetry, Vec<f64>)> {
    let mc = c_all.len();
    let (symmetry, first, stored) = match isym {
        0 => (Symmetry::None, 0, mc),
        1 => (Symmetry::Rotational, 0, 1),
        2 => (Symmetry::BilateralC0C180, 0, mc / 2 + 1),
        3 => (Symmetry::BilateralC90C270, 3 * mc / 4, mc / 2 + 1),
        _ => (Symmetry::Quadrant, 0, mc / 4 + 1),
    };
    let stored_deg: Vec<f64> = (0..stored)
        .map(|k| {
            let idx = first + k;
            c_all[idx % mc] + if idx >= mc { 360.0 } else { 0.0 }
        })
        .collect();
    let expected: Option<(f64, f64)> = match isym {
        2 => Some((0.0, 180.0)),
        3 => Some((270.0, 450.0)),
        4 => Some((0.0, 90.0)),
        _ => None,
    };
    if let Some((lo, hi)) = expected {
        if stored_deg[0] != lo || stored_deg[stored - 1] != hi {
            return Err(at(
                origin,
                c_line,
                format!(
                    "Isym {isym} stores planes C{lo}–C{}, but the C angles give C{}–C{}",
                    hi % 360.0,
                    stored_deg[0] % 360.0,
                    stored_deg[stored - 1] % 360.0
                ),
            ));
        }
    }
    Ok((symmetry, stored_deg))
}

/// The intensity table from `table_line`: a row per stored plane, none negative, in
/// cd/klm scaled by `scale`; nothing may follow it.
fn intensities(
    f: &Lines,
    table_line: usize,
    stored_deg: &[f64],
    gamma: &[f64],
    scale: f64,
) -> Result<Vec<Vec<f64>>> {
    let (stored, ng) = (stored_deg.len(), gamma.len());
    let mut rows = Vec::new();
    for (k, &c) in stored_deg.iter().enumerate() {
        let first_line = table_line + k * ng;
        let c = c % 360.0;
        let row = f.numbers(first_line, ng, &format!("intensity of plane C{c}:"))?;
        for (j, &v) in row.iter().enumerate() {
            if v < 0.0 {
                return Err(at(
                    f.origin,
                    first_line + j,
                    format!("intensity {v} cd/klm at C{c}, γ {}° is negative", gamma[j]),
                ));
            }
        }
        rows.push(row.iter().map(|v| v * scale).collect::<Vec<f64>>());
    }
    let end = table_line + stored * ng;
    if let Some(k) = (end..=f.lines.len()).find(|&n| !f.lines[n - 1].trim().is_empty()) {
        return Err(at(
            f.origin,
            k,
            format!(
                "`{}` after the last intensity ({stored} planes × {ng} angles): \
                 the counts do not match the data",
                f.lines[k - 1].trim()
            ),
        ));
    }
    Ok(rows)
}

/// EULUMDAT's luminous area: length (along C0, x) and width (along C90, y); width 0 means
/// a circle whose diameter is the length; both 0 a point.
fn opening(length_m: f64, width_m: f64) -> Opening {
    match (length_m > 0.0, width_m > 0.0) {
        (false, false) => Opening::Point,
        (true, false) => Opening::Disc {
            diameter_m: length_m,
        },
        _ => Opening::Rectangle { length_m, width_m },
    }
}

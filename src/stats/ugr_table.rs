//! CIE 190:2010 tabular UGR of a luminaire (docs/ugr.md, "CIE 190 table"): the UGR of
//! a regular array of the luminaire in 19 standard rooms, seen crosswise and endwise,
//! for 5 reflectance sets, at 1000 lm of lamp flux.
//!
//! Observer at the middle of one wall, eye on the reference plane, looking horizontally
//! along the room (+y); luminaire plane H = 2 m above the eye. Lᵢ, ωᵢ and pᵢ are exact
//! (the file's interpolant, its flat opening, [`position_index`]); the background
//! luminance is CIE 190's flux-transfer formula Lb = E_WID/π, with the transfer factors
//! derived from the three-surface enclosure (floor plane, walls, luminaire plane) with
//! exact form factors, and the direct flux on the floor integrated exactly for the array.

use super::ugr::{position_index, ugr, MAX_H_OVER_R, MAX_T_OVER_R};
use crate::photometry::{Opening, Photometry};
use crate::raster::canvas::Canvas;
use crate::raster::encode_rgb_png;
use crate::{Error, Result};
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI};

/// Height of the luminaire plane above the eye, m (CIE 190 §4.2).
pub const H_M: f64 = 2.0;

/// The lamp flux the uncorrected table is computed for, lm.
pub const REFERENCE_FLUX_LM: f64 = 1000.0;

/// Luminaires seen more than 85° from their nadir are left out of the sum (CIE 117's
/// tabular method; eulumdat-ugr's `GAMMA_MAX`).
pub const MAX_GAMMA_DEG: f64 = 85.0;

/// The 19 rooms (X across, Y along the line of sight, in units of H), CIE 190 Table 3.
pub const ROOMS: [(f64, f64); 19] = [
    (2.0, 2.0),
    (2.0, 3.0),
    (2.0, 4.0),
    (2.0, 6.0),
    (2.0, 8.0),
    (2.0, 12.0),
    (4.0, 2.0),
    (4.0, 3.0),
    (4.0, 4.0),
    (4.0, 6.0),
    (4.0, 8.0),
    (4.0, 12.0),
    (8.0, 4.0),
    (8.0, 6.0),
    (8.0, 8.0),
    (8.0, 12.0),
    (12.0, 4.0),
    (12.0, 6.0),
    (12.0, 8.0),
];

/// The room of the "UGR reference value": 4H × 8H.
pub const REFERENCE_ROOM: usize = 10;

/// Reflectances of the ceiling (luminaire plane), the walls and the floor (reference plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reflectances {
    pub ceiling: f64,
    pub walls: f64,
    pub floor: f64,
}

impl Reflectances {
    /// `70/50/20`, as datasheets head their columns.
    pub fn label(&self) -> String {
        let pc = |r: f64| (r * 100.0).round() as i64;
        format!("{}/{}/{}", pc(self.ceiling), pc(self.walls), pc(self.floor))
    }
}

const fn refl(ceiling: f64, walls: f64, floor: f64) -> Reflectances {
    Reflectances {
        ceiling,
        walls,
        floor,
    }
}

/// CIE 190's five reflectance sets, in datasheet order.
pub const REFLECTANCES: [Reflectances; 5] = [
    refl(0.7, 0.5, 0.2),
    refl(0.7, 0.3, 0.2),
    refl(0.5, 0.5, 0.2),
    refl(0.5, 0.3, 0.2),
    refl(0.3, 0.3, 0.2),
];

/// How the luminaires are turned against the line of sight.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// The C0 plane along the line of sight, towards the observer: C = atan(T/R).
    Crosswise,
    /// The C90 plane along the line of sight: C = 90° − atan(T/R).
    Endwise,
}

impl View {
    pub const BOTH: [View; 2] = [View::Crosswise, View::Endwise];

    pub fn as_str(self) -> &'static str {
        match self {
            View::Crosswise => "crosswise",
            View::Endwise => "endwise",
        }
    }

    /// A world direction (x across, y along the line of sight, z up) in the luminaire
    /// frame. Both are rotations about z (not mirrors), so an asymmetric luminaire keeps
    /// its handedness; the array is symmetric in x, so its sum equals CIE's with |T|.
    pub fn to_luminaire(self, d: DVec3) -> DVec3 {
        match self {
            View::Crosswise => DVec3::new(-d.y, d.x, d.z),
            View::Endwise => DVec3::new(-d.x, -d.y, d.z),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Form factors and transfer factors

/// Form factor between two equal, directly opposed a × b rectangles c apart (Hottel).
pub fn parallel_rectangles(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    2.0 / (PI * x * y)
        * (0.5 * libm::log((1.0 + x * x) * (1.0 + y * y) / (1.0 + x * x + y * y))
            + x * sy * libm::atan(x / sy)
            + y * sx * libm::atan(y / sx)
            - x * libm::atan(x)
            - y * libm::atan(y))
}

/// Form factor from a rectangle of `width` to a perpendicular one of `height`, sharing
/// an edge of length `common`.
pub fn perpendicular_rectangles(common: f64, width: f64, height: f64) -> f64 {
    let (w, h) = (width / common, height / common);
    let (w2, h2) = (w * w, h * h);
    let s = (w2 + h2).sqrt();
    let log = libm::log((1.0 + w2) * (1.0 + h2) / (1.0 + w2 + h2))
        + w2 * libm::log(w2 * (1.0 + w2 + h2) / ((1.0 + w2) * (w2 + h2)))
        + h2 * libm::log(h2 * (1.0 + h2 + w2) / ((1.0 + h2) * (h2 + w2)));
    (w * libm::atan(1.0 / w) + h * libm::atan(1.0 / h) - s * libm::atan(1.0 / s) + 0.25 * log)
        / (PI * w)
}

/// Surfaces of the enclosure, in this order.
pub const FLOOR: usize = 0;
pub const WALLS: usize = 1;
pub const CEILING: usize = 2;

/// The X × Y × H box as three surfaces: areas (m²) and form factors `f[i][j]` from i to j.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Enclosure {
    pub area_m2: [f64; 3],
    pub f: [[f64; 3]; 3],
}

/// The box's enclosure: floor–ceiling exactly, the rest by summation and reciprocity
/// (the tests check them against the perpendicular-rectangle form factors).
pub fn enclosure(x_m: f64, y_m: f64, h_m: f64) -> Enclosure {
    let plane = x_m * y_m;
    let walls = 2.0 * h_m * (x_m + y_m);
    let fcf = parallel_rectangles(x_m, y_m, h_m);
    let fwc = plane * (1.0 - fcf) / walls;
    Enclosure {
        area_m2: [plane, walls, plane],
        f: [
            [0.0, 1.0 - fcf, fcf],
            [fwc, 1.0 - 2.0 * fwc, fwc],
            [fcf, 1.0 - fcf, 0.0],
        ],
    }
}

/// CIE 190's transfer factors to the walls: the flux finally arriving on the walls per
/// unit of flux first arriving on the floor, on the walls (less that first unit) and
/// on the ceiling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransferFactors {
    pub floor_walls: f64,
    pub walls_walls_minus_1: f64,
    pub ceiling_walls: f64,
}

/// The flux finally arriving on each surface of `e` (reflectances `r`) when a unit first
/// arrives on surface `first`: Φ = Φ₀ + Φ·diag(ρ)·F (Φ a row), so Φ solves
/// (I − diag(ρ)F)ᵀ·Φ = e_first.
pub fn incident_flux(e: &Enclosure, r: Reflectances, first: usize) -> [f64; 3] {
    let rho = [r.floor, r.walls, r.ceiling];
    let m: [[f64; 3]; 3] = std::array::from_fn(|j| {
        std::array::from_fn(|i| f64::from(u8::from(i == j)) - rho[i] * e.f[i][j])
    });
    solve3(m, std::array::from_fn(|k| f64::from(u8::from(k == first))))
}

/// The transfer factors of `e` for reflectances `r` ([`incident_flux`]'s wall share).
pub fn transfer_factors(e: &Enclosure, r: Reflectances) -> TransferFactors {
    let to_walls = |first| incident_flux(e, r, first)[WALLS];
    TransferFactors {
        floor_walls: to_walls(FLOOR),
        walls_walls_minus_1: to_walls(WALLS) - 1.0,
        ceiling_walls: to_walls(CEILING),
    }
}

/// m·x = b by Cramer's rule (m is diagonally dominant: ρ < 1, rows of F sum to 1).
fn solve3(m: [[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    std::array::from_fn(|k| {
        let mut mk = m;
        for (row, &bi) in mk.iter_mut().zip(&b) {
            row[k] = bi;
        }
        det(&mk) / d
    })
}

// ---------------------------------------------------------------------------------------
// The array and its direct flux

/// Luminaire positions (T across, R along the line of sight), m, spacing SHR·H: across
/// at ±S/2, ±3S/2, …, along at S/2, 3S/2, … (CIE 190; eulumdat-ugr's `UgrGrid`).
pub fn array(x_h: f64, y_h: f64, shr: f64) -> Vec<(f64, f64)> {
    let s = shr * H_M;
    let half = (x_h * H_M / s / 2.0).round() as i64;
    let rows = (y_h * H_M / s).round() as i64;
    let mut out = Vec::with_capacity((2 * half * rows).max(0) as usize);
    for r in 0..rows {
        for t in -half..half {
            out.push(((t as f64 + 0.5) * s, (r as f64 + 0.5) * s));
        }
    }
    out
}

/// Cells per axis of [`FloorTable`]: 0.25° in each of its angles.
const FLOOR_CELLS: usize = 720;

/// The luminaire's downward flux as a summed-area table over the plane H below it,
/// in angles a = atan(x/H), b = atan(y/H) ∈ (−90°, 90°): every luminaire of the array
/// sees the floor as one rectangle in (a, b), so one table, built once per view, gives
/// each luminaire's direct flux on the floor by four look-ups.
pub struct FloorTable {
    /// (FLOOR_CELLS + 1)², row-major in a: the flux fraction below (a, b).
    sum: Vec<f64>,
}

impl FloorTable {
    /// `p` turned by `view`, as fractions of `rated_lm`: each cell's intensity at its
    /// centre times its exact solid angle ([`corner_solid_angle`]), so a uniform source
    /// is integrated exactly.
    pub fn new(p: &Photometry, view: View, rated_lm: f64) -> FloorTable {
        let n = FLOOR_CELLS;
        let step = PI / n as f64;
        let node = |k: usize| -FRAC_PI_2 + k as f64 * step;
        let corner: Vec<f64> = (0..=n)
            .flat_map(|i| (0..=n).map(move |j| corner_solid_angle(node(i), node(j))))
            .collect();
        let c = |i: usize, j: usize| corner[i * (n + 1) + j];
        let mut sum = vec![0.0; (n + 1) * (n + 1)];
        for i in 0..n {
            let ta = libm::tan(node(i) + step / 2.0);
            let mut row = 0.0;
            for j in 0..n {
                let tb = libm::tan(node(j) + step / 2.0);
                let omega = c(i + 1, j + 1) - c(i, j + 1) - c(i + 1, j) + c(i, j);
                let dir = view.to_luminaire(DVec3::new(ta, tb, -1.0));
                row += p.intensity_toward_cd(dir) * omega / rated_lm;
                sum[(i + 1) * (n + 1) + j + 1] = sum[i * (n + 1) + j + 1] + row;
            }
        }
        FloorTable { sum }
    }

    /// The fraction below angles (a, b) in radians, bilinear between nodes (exact for
    /// the table's piecewise-constant density).
    fn below(&self, a: f64, b: f64) -> f64 {
        let n = FLOOR_CELLS;
        let at = |v: f64| ((v + FRAC_PI_2) / PI * n as f64).clamp(0.0, n as f64);
        let (u, v) = (at(a), at(b));
        let (i, j) = ((u as usize).min(n - 1), (v as usize).min(n - 1));
        let (fu, fv) = (u - i as f64, v - j as f64);
        let s = |i: usize, j: usize| self.sum[i * (n + 1) + j];
        (1.0 - fu) * ((1.0 - fv) * s(i, j) + fv * s(i, j + 1))
            + fu * ((1.0 - fv) * s(i + 1, j) + fv * s(i + 1, j + 1))
    }

    /// The downward flux fraction (the whole plane).
    pub fn downward(&self) -> f64 {
        *self.sum.last().unwrap_or(&0.0)
    }

    /// The fraction on the floor rectangle x ∈ [x0, x1], y ∈ [y0, y1] (m, relative to the
    /// luminaire's foot, H_M below it).
    pub fn on(&self, [x0, x1]: [f64; 2], [y0, y1]: [f64; 2]) -> f64 {
        let (a0, a1) = (libm::atan(x0 / H_M), libm::atan(x1 / H_M));
        let (b0, b1) = (libm::atan(y0 / H_M), libm::atan(y1 / H_M));
        self.below(a1, b1) - self.below(a0, b1) - self.below(a1, b0) + self.below(a0, b0)
    }
}

/// Solid angle of the plane's rectangle between the foot and the point at angles
/// (a, b) (x = H·tan a, y = H·tan b), signed: atan(xy/(H·√(H² + x² + y²))), in the form
/// that stays finite at a or b = ±90°.
fn corner_solid_angle(a: f64, b: f64) -> f64 {
    let ((sa, ca), (sb, cb)) = (libm::sincos(a), libm::sincos(b));
    let den = (ca * ca * cb * cb + sa * sa * cb * cb + ca * ca * sb * sb).sqrt();
    libm::atan2(sa * sb, den)
}

/// Direct flux on floor, walls and ceiling per luminaire, as fractions of the rated lamp
/// flux (CIE 190's F_DF, F_DW, F_DC; they sum to the light output ratio).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectFractions {
    pub floor: f64,
    pub walls: f64,
    pub ceiling: f64,
}

/// The array's mean direct fractions in the X × Y room (m): F_DF exactly over the
/// floor rectangle, F_DW the rest of the downward flux, F_DC the upward flux.
pub fn direct_fractions(
    table: &FloorTable,
    lor: f64,
    positions: &[(f64, f64)],
    x_m: f64,
    y_m: f64,
) -> DirectFractions {
    let floor = positions
        .iter()
        .map(|&(t, r)| table.on([-x_m / 2.0 - t, x_m / 2.0 - t], [-r, y_m - r]))
        .sum::<f64>()
        / positions.len().max(1) as f64;
    let down = table.downward();
    DirectFractions {
        floor,
        walls: (down - floor).max(0.0),
        ceiling: (lor - down).max(0.0),
    }
}

// ---------------------------------------------------------------------------------------
// The table

/// The lamp flux the file's intensities are for: its rated lamp flux × lamp output
/// factor (LOR = flux / that), or the luminaire's flux for absolute photometry.
pub fn rated_flux_lm(p: &Photometry) -> f64 {
    p.flux_lm() / p.light_output_ratio().unwrap_or(1.0)
}

/// What turns the 1000 lm table into the file's: 8·log10(Φ/1000) (CIE 190 eq. 2).
pub fn flux_correction(flux_lm: f64) -> f64 {
    8.0 * libm::log10(flux_lm / REFERENCE_FLUX_LM)
}

/// The luminous area seen from unit direction `u` (luminaire frame, towards the eye), m²:
/// the opening (facing −z) times cos γ, plus its luminous sides of height `height_m`
/// (a box's two visible faces; a disc's or ellipse's cylinder by its silhouette), as
/// CIE 117 and EULUMDAT's luminous-area heights mean it (the largest of EULUMDAT's four).
pub fn projected_area_m2(opening: Opening, height_m: f64, u: DVec3) -> f64 {
    let bottom = opening.area_m2() * (-u.z).max(0.0);
    let sides = match opening {
        Opening::Point => 0.0,
        Opening::Rectangle { length_m, width_m } => width_m * u.x.abs() + length_m * u.y.abs(),
        Opening::Disc { diameter_m } => diameter_m * libm::hypot(u.x, u.y),
        Opening::Ellipse { length_m, width_m } => libm::hypot(length_m * u.y, width_m * u.x),
    };
    bottom + height_m.max(0.0) * sides
}

/// Σ L²ω/p² of the array seen by `view`, intensities scaled by `scale`: L = I/A_proj
/// and ω = A_proj/r², so L²ω = I²/(A_proj·r²) ([`projected_area_m2`]). Luminaires
/// outside the position index's field or beyond [`MAX_GAMMA_DEG`] count 0.
pub fn glare_sum(p: &Photometry, view: View, positions: &[(f64, f64)], scale: f64) -> f64 {
    let max_tan_gamma = libm::tan(MAX_GAMMA_DEG.to_radians());
    let (look, up) = (DVec3::Y, DVec3::Z);
    positions
        .iter()
        .filter(|&&(t, r)| {
            H_M / r <= MAX_H_OVER_R
                && t.abs() / r <= MAX_T_OVER_R
                && libm::hypot(t, r) / H_M <= max_tan_gamma
        })
        .map(|&(t, r)| {
            let to_lum = DVec3::new(t, r, H_M);
            let d = to_lum.length();
            let towards_eye = view.to_luminaire(-to_lum / d);
            let i = scale * p.intensity_toward_cd(towards_eye);
            let a_proj = projected_area_m2(p.opening, p.height_m, towards_eye);
            let pi = position_index(to_lum / d, look, up);
            i * i / (a_proj * d * d * pi * pi)
        })
        .sum()
}

/// One room of the table.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// X, Y in units of H.
    pub x_h: f64,
    pub y_h: f64,
    pub luminaires: usize,
    /// Per reflectance set of [`REFLECTANCES`].
    pub transfer: [TransferFactors; 5],
    /// Per view of [`View::BOTH`].
    pub direct: [DirectFractions; 2],
    /// UGR per view, per reflectance set (None where no luminaire counts).
    pub ugr: [[Option<f64>; 5]; 2],
}

/// The table of a luminaire at one lamp flux and spacing.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub shr: f64,
    /// The lamp flux the values are for, lm.
    pub flux_lm: f64,
    pub rows: Vec<Row>,
}

impl Table {
    /// The "UGR reference value": 4H × 8H, 70/50/20, (crosswise, endwise).
    pub fn reference(&self) -> [Option<f64>; 2] {
        let row = &self.rows[REFERENCE_ROOM];
        [row.ugr[0][0], row.ugr[1][0]]
    }
}

/// The CIE 190 table of `p` with luminaires spaced `shr`·H, for a lamp flux `flux_lm`
/// (CIE's uncorrected table: [`REFERENCE_FLUX_LM`]). A point opening has no luminance
/// and cannot be rated.
pub fn table(p: &Photometry, shr: f64, flux_lm: f64) -> Result<Table> {
    if !(p.opening.area_m2() > 0.0) || p.opening == Opening::Point {
        return Err(Error::input(
            &p.file,
            "a point opening (no luminous area) cannot be rated: the UGR table needs the \
             luminous opening's dimensions",
        ));
    }
    if !(shr > 0.0 && shr.is_finite()) {
        return Err(Error::input(
            &p.file,
            format!("spacing-to-height ratio {shr} must be > 0"),
        ));
    }
    let rated = rated_flux_lm(p);
    let lor = p.flux_lm() / rated;
    let floors = View::BOTH.map(|v| FloorTable::new(p, v, rated));
    let rows = ROOMS
        .iter()
        .map(|&(x_h, y_h)| room_row(p, &floors, lor, (x_h, y_h), shr, flux_lm / rated))
        .collect();
    Ok(Table { shr, flux_lm, rows })
}

/// One room: E_WID = B·F_UWID with B = Φ·N/A_w and F_UWID = F_DF·F_T,FW +
/// F_DW·(F_T,WW − 1) + F_DC·F_T,CW (CIE 190 eq. 7–8), Lb = E_WID/π.
fn room_row(
    p: &Photometry,
    floors: &[FloorTable; 2],
    lor: f64,
    (x_h, y_h): (f64, f64),
    shr: f64,
    scale: f64,
) -> Row {
    let (x_m, y_m) = (x_h * H_M, y_h * H_M);
    let positions = array(x_h, y_h, shr);
    let enc = enclosure(x_m, y_m, H_M);
    let transfer = REFLECTANCES.map(|r| transfer_factors(&enc, r));
    let direct = [0, 1].map(|v| direct_fractions(&floors[v], lor, &positions, x_m, y_m));
    let b = scale * rated_flux_lm(p) * positions.len() as f64 / enc.area_m2[WALLS];
    let ugr_of = |v: usize| {
        let sum = glare_sum(p, View::BOTH[v], &positions, scale);
        let d = direct[v];
        transfer.map(|t| {
            let f_uwid = d.floor * t.floor_walls
                + d.walls * t.walls_walls_minus_1
                + d.ceiling * t.ceiling_walls;
            ugr(sum, b * f_uwid)
        })
    };
    Row {
        x_h,
        y_h,
        luminaires: positions.len(),
        transfer,
        direct,
        ugr: [ugr_of(0), ugr_of(1)],
    }
}

// ---------------------------------------------------------------------------------------
// The plot

const PANEL: (f64, f64) = (420.0, 320.0);
/// Plot area inside a panel: left, top, right, bottom margins (room for labels).
const MARGIN: [f64; 4] = [52.0, 40.0, 16.0, 44.0];
const COLOURS: [[u8; 3]; 4] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [148, 103, 189],
];
const INK: [u8; 3] = [0, 0, 0];
const GRID: [u8; 3] = [210, 210, 210];

/// The plot of `t`: UGR (70/50/20) against Y/H, one line per X, crosswise on the left,
/// endwise on the right, as PNG bytes.
pub fn plot_png(t: &Table) -> Result<Vec<u8>> {
    let values = t
        .rows
        .iter()
        .flat_map(|r| [r.ugr[0][0], r.ugr[1][0]])
        .flatten();
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let (lo, hi) = if lo <= hi {
        (lo.floor(), hi.ceil().max(lo.floor() + 1.0))
    } else {
        (0.0, 1.0)
    };
    let mut c = Canvas::new((2.0 * PANEL.0) as usize, PANEL.1 as usize);
    for (v, view) in View::BOTH.iter().enumerate() {
        plot_panel(&mut c, t, v, *view, (lo, hi));
    }
    encode_rgb_png(c.width, c.height, &c.rgb)
}

/// One view's panel at its place in `c`, UGR axis `lo`…`hi`.
fn plot_panel(c: &mut Canvas, t: &Table, v: usize, view: View, (lo, hi): (f64, f64)) {
    let left = v as f64 * PANEL.0;
    let [ml, mt, mr, mb] = MARGIN;
    let (x0, x1) = (left + ml, left + PANEL.0 - mr);
    let (y0, y1) = (PANEL.1 - mb, mt);
    let sx = |y_h: f64| x0 + (y_h - 2.0) / 10.0 * (x1 - x0);
    let sy = |u: f64| y0 + (u - lo) / (hi - lo) * (y1 - y0);
    let step = if hi - lo > 8.0 { 2.0 } else { 1.0 };
    let mut u = lo;
    while u <= hi + 1e-9 {
        c.path(&[(x0, sy(u)), (x1, sy(u))], GRID, 1.0, None);
        c.text(left + 8.0, sy(u) - 5.0, &format!("{u}"), INK);
        u += step;
    }
    for y_h in [2.0, 3.0, 4.0, 6.0, 8.0, 12.0] {
        c.path(&[(sx(y_h), y0), (sx(y_h), y1)], GRID, 1.0, None);
        c.text_centred(sx(y_h), y0 + 12.0, &format!("{y_h}"), INK);
    }
    c.path(&[(x0, y1), (x0, y0), (x1, y0)], INK, 1.0, None);
    c.text_centred((x0 + x1) / 2.0, y0 + 30.0, "Y/H", INK);
    let title = format!("UGR {} 70/50/20", view.as_str().to_uppercase());
    c.text(x0, 12.0, &title, INK);
    for (k, x_h) in [2.0, 4.0, 8.0, 12.0].into_iter().enumerate() {
        let pts: Vec<(f64, f64)> = (t.rows.iter())
            .filter(|r| r.x_h == x_h)
            .filter_map(|r| r.ugr[v][0].map(|u| (sx(r.y_h), sy(u))))
            .collect();
        c.path(&pts, COLOURS[k], 2.0, None);
        for &(x, y) in &pts {
            c.dot(x, y, COLOURS[k], 6.0);
        }
        let lx = x1 - 70.0;
        let ly = y0 - 20.0 - 16.0 * (3 - k) as f64;
        c.path(
            &[(lx, ly + 5.0), (lx + 16.0, ly + 5.0)],
            COLOURS[k],
            2.0,
            None,
        );
        c.text(lx + 22.0, ly, &format!("X={x_h}H"), INK);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_have_cie_190s_luminaire_counts() {
        // CIE 190 Table 3: 4H × 8H holds 32 at SHR 1; the catalogue's 0.25 gives 16 × 32.
        assert_eq!(array(4.0, 8.0, 1.0).len(), 32);
        assert_eq!(array(4.0, 8.0, 0.25).len(), 512);
        assert_eq!(
            array(2.0, 2.0, 1.0),
            [(-1.0, 1.0), (1.0, 1.0), (-1.0, 3.0), (1.0, 3.0)]
        );
    }

    #[test]
    fn projected_area_adds_the_visible_luminous_sides() {
        let box_ = Opening::Rectangle {
            length_m: 1.0,
            width_m: 0.5,
        };
        let down = DVec3::new(0.0, 0.0, -1.0);
        assert_eq!(projected_area_m2(box_, 0.1, down), 0.5);
        // Horizontally along x: the 0.5 × 0.1 end face only.
        assert!((projected_area_m2(box_, 0.1, DVec3::X) - 0.05).abs() < 1e-15);
        let disc = Opening::Disc { diameter_m: 0.2 };
        let u = DVec3::new(0.6, 0.0, -0.8);
        let expected = disc.area_m2() * 0.8 + 0.1 * 0.2 * 0.6;
        assert!((projected_area_m2(disc, 0.1, u) - expected).abs() < 1e-15);
        assert_eq!(projected_area_m2(Opening::Point, 0.1, u), 0.0);
    }

    #[test]
    fn corner_solid_angles_are_finite_at_the_horizon() {
        // A quadrant of the plane below subtends π/2; the form at ±90° stays exact.
        let quadrant = corner_solid_angle(FRAC_PI_2, FRAC_PI_2);
        assert!((quadrant - FRAC_PI_2).abs() < 1e-15);
        let (x, y) = (0.7f64, 1.3f64);
        let direct = libm::atan(x * y / (1.0 + x * x + y * y).sqrt());
        assert!((corner_solid_angle(libm::atan(x), libm::atan(y)) - direct).abs() < 1e-15);
    }

    #[test]
    fn labels_and_the_flux_correction() {
        assert_eq!(REFLECTANCES[0].label(), "70/50/20");
        assert_eq!(REFLECTANCES[4].label(), "30/30/20");
        assert_eq!(flux_correction(1000.0), 0.0);
        assert!((flux_correction(10_000.0) - 8.0).abs() < 1e-12);
    }
}

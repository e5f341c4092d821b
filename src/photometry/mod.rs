//! Photometric files of real luminaires — IES LM-63 (1986 … 2019) and EULUMDAT — read
//! into one normalised candela table whose bilinear interpolant is *the* luminaire: its
//! intensity toward any direction, its exact flux, and emission directions sampled from
//! it exactly. Conventions (frames, types A and B, symmetries, factors): docs/photometry.md.
//!
//! Luminaire frame: x = the C = 0° direction, y = C = 90°, z = up; γ = 0 is the nadir
//! (−z). Placed with `aim = [0, 0, −1]` and `rotate_deg = 0`, that frame is the world's.
//!
//! ```no_run
//! let p = luxtally::photometry::load(std::path::Path::new("scenes/photometry/examp1.ies"))?;
//! println!("{:.2} lm, {:.1} cd toward the nadir", p.flux_lm(), p.intensity_cd(0.0, 0.0));
//! let mut rng = rand_pcg::Pcg32::new(1, 1);
//! let dir = p.sample_direction(&mut rng); // unit vector, luminaire frame
//! # Ok::<(), luxtally::Error>(())
//! ```

mod expand;
mod grid;
pub mod ies;
pub mod ldt;
pub mod polar;
mod sample;
mod text;

use crate::sampling::uniform;
use crate::Result;
use glam::DVec3;
use grid::Grid;
use rand_pcg::Pcg32;
use sample::Sampler;
use std::path::Path;

/// Which file format, and which edition of LM-63.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// IES LM-63 of the given year (1986 = no header line).
    Ies(u16),
    Eulumdat,
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Format::Ies(year) => write!(f, "IES LM-63-{year}"),
            Format::Eulumdat => write!(f, "EULUMDAT"),
        }
    }
}

/// The goniometer's coordinate system (LM-63's photometric type 1, 2, 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotometricType {
    /// C-planes about the vertical axis, γ from the nadir (type 1; EULUMDAT always).
    C,
    /// Floodlights: V-planes about a horizontal axis, H the latitude (type 2).
    B,
    /// Automotive: H-planes about the up axis, V the latitude (type 3).
    A,
}

/// The symmetry the file declares (by its stored angle range, or EULUMDAT's Isym).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symmetry {
    /// One plane for all C (LM-63 horizontal angle 0 only; Isym 1).
    Rotational,
    /// C 0–90 mirrored into every quadrant (Isym 4).
    Quadrant,
    /// C 0–180, mirror image about the C0–C180 plane (Isym 2).
    BilateralC0C180,
    /// C 90–270, mirror image about the C90–C270 plane (Isym 3).
    BilateralC90C270,
    /// Every plane stored (C 0–360, Isym 0; types A/B: H −90–90).
    None,
    /// Types A and B: H 0–90, mirrored to −H.
    LateralH,
}

impl Symmetry {
    /// A short description for people: `quadrant (C 0–90)`.
    pub fn describe(self) -> &'static str {
        match self {
            Symmetry::Rotational => "rotationally symmetric (one C-plane)",
            Symmetry::Quadrant => "quadrant (C 0–90 mirrored)",
            Symmetry::BilateralC0C180 => "bilateral about C0–C180 (C 0–180)",
            Symmetry::BilateralC90C270 => "bilateral about C90–C270 (C 90–270)",
            Symmetry::None => "none (every plane)",
            Symmetry::LateralH => "lateral about H = 0 (H 0–90 mirrored)",
        }
    }
}

/// The luminous opening photons leave from, in the luminaire frame's z = 0 plane:
/// `length` along x (the C0–C180 axis), `width` along y (C90–C270).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Opening {
    Point,
    Rectangle { length_m: f64, width_m: f64 },
    Disc { diameter_m: f64 },
    Ellipse { length_m: f64, width_m: f64 },
}

impl Opening {
    pub fn area_m2(&self) -> f64 {
        match *self {
            Opening::Point => 0.0,
            Opening::Rectangle { length_m, width_m } => length_m * width_m,
            Opening::Disc { diameter_m } => std::f64::consts::PI * diameter_m * diameter_m / 4.0,
            Opening::Ellipse { length_m, width_m } => {
                std::f64::consts::PI * length_m * width_m / 4.0
            }
        }
    }

    /// A point uniformly distributed over the opening (z = 0), metres. A rectangle's is
    /// [`Opening::point_at`] of two draws; a point draws nothing; discs and ellipses keep
    /// their rejection sampling (not `point_at`'s concentric map): the same distribution,
    /// but other points from the same stream, and emission's bits are recorded.
    pub fn sample_point_m(&self, rng: &mut Pcg32) -> DVec3 {
        match *self {
            Opening::Point => DVec3::ZERO,
            // Arguments are evaluated left to right: a is drawn first (the bits depend on it).
            Opening::Rectangle { .. } => self.point_at(uniform(rng), uniform(rng)),
            Opening::Disc { diameter_m } => disc_point(rng, diameter_m, diameter_m),
            Opening::Ellipse { length_m, width_m } => disc_point(rng, length_m, width_m),
        }
    }

    /// The opening's largest extent, m (0 for a point).
    pub fn diagonal_m(&self) -> f64 {
        match *self {
            Opening::Point => 0.0,
            Opening::Rectangle { length_m, width_m } => libm::hypot(length_m, width_m),
            Opening::Disc { diameter_m } => diameter_m,
            Opening::Ellipse { length_m, width_m } => length_m.max(width_m),
        }
    }

    /// The point of the opening at (a, b) ∈ [0, 1)² (z = 0), metres: uniform (a, b) give
    /// uniform points, and strata of (a, b) strata of the opening (discs and ellipses by
    /// Shirley and Chiu's concentric map).
    pub fn point_at(&self, a: f64, b: f64) -> DVec3 {
        match *self {
            Opening::Point => DVec3::ZERO,
            Opening::Rectangle { length_m, width_m } => {
                DVec3::new((a - 0.5) * length_m, (b - 0.5) * width_m, 0.0)
            }
            Opening::Disc { diameter_m } => concentric(a, b, diameter_m, diameter_m),
            Opening::Ellipse { length_m, width_m } => concentric(a, b, length_m, width_m),
        }
    }

    /// `rectangle 1.231 × 0.259 m` and the like.
    pub fn describe(&self) -> String {
        match *self {
            Opening::Point => "point (no luminous dimensions)".into(),
            Opening::Rectangle { length_m, width_m } => {
                format!("rectangle {length_m:.3} m (along C0, x) × {width_m:.3} m (along C90, y)")
            }
            Opening::Disc { diameter_m } => format!("disc of diameter {diameter_m:.3} m"),
            Opening::Ellipse { length_m, width_m } => {
                format!("ellipse {length_m:.3} m (along C0, x) × {width_m:.3} m (along C90, y)")
            }
        }
    }
}

/// The concentric map of (u, v) ∈ [0, 1)² onto the ellipse of axes `a` (x) and `b` (y).
fn concentric(u: f64, v: f64, a: f64, b: f64) -> DVec3 {
    let (x, y) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if x == 0.0 && y == 0.0 {
        return DVec3::ZERO;
    }
    let (r, phi) = if x.abs() > y.abs() {
        (x, std::f64::consts::FRAC_PI_4 * (y / x))
    } else {
        (
            y,
            std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (x / y),
        )
    };
    DVec3::new(
        0.5 * a * r * libm::cos(phi),
        0.5 * b * r * libm::sin(phi),
        0.0,
    )
}

/// Uniform in the ellipse of axes `a` (x) and `b` (y), by rejection from the square.
fn disc_point(rng: &mut Pcg32, a: f64, b: f64) -> DVec3 {
    loop {
        let x = 2.0 * uniform(rng) - 1.0;
        let y = 2.0 * uniform(rng) - 1.0;
        if x * x + y * y < 1.0 {
            return DVec3::new(0.5 * a * x, 0.5 * b * y, 0.0);
        }
    }
}

/// A tilt table (LM-63 `TILT=INCLUDE` or `TILT=<file>`): candela multiplying factors of
/// the lamp against the luminaire's tilt from its photometered position.
#[derive(Clone, Debug, PartialEq)]
pub struct Tilt {
    /// Lamp-to-luminaire geometry: 1 vertical base-up/down, 2 horizontal and stays
    /// horizontal when tilted about the 0° axis, 3 horizontal and tilts with the
    /// luminaire (LM-63).
    pub geometry: u8,
    pub angles_deg: Vec<f64>,
    pub factors: Vec<f64>,
}

impl Tilt {
    /// The factor at `tilt_deg`, linear between the table's angles, the end values
    /// beyond them.
    pub fn factor(&self, tilt_deg: f64) -> f64 {
        let a = &self.angles_deg;
        let n = a.len();
        if n == 1 || tilt_deg <= a[0] {
            return self.factors[0];
        }
        if tilt_deg >= a[n - 1] {
            return self.factors[n - 1];
        }
        let k = a.partition_point(|&v| v <= tilt_deg) - 1;
        let t = (tilt_deg - a[k]) / (a[k + 1] - a[k]);
        self.factors[k] + t * (self.factors[k + 1] - self.factors[k])
    }
}

/// The largest intensity of the table and where it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    pub intensity_cd: f64,
    pub c_deg: f64,
    pub gamma_deg: f64,
}

/// One EULUMDAT lamp set (lines 26a–26f).
#[derive(Clone, Debug, PartialEq)]
pub struct LampSet {
    /// Negative: absolute photometry (the flux is then the luminaire's).
    pub lamps: i64,
    pub lamp_type: String,
    pub flux_lm: f64,
    pub colour: String,
    pub colour_rendering: String,
    pub watts: f64,
}

/// A photometric file, normalised. The candela table includes every factor the file
/// gives (multiplier, ballast factors, tilt at the photometered position, EULUMDAT's
/// lamp-set flux and conversion factor); the scene's own `multiplier`/`flux_lm` are not.
#[derive(Clone, Debug, PartialEq)]
pub struct Photometry {
    /// The file as the caller named it.
    pub file: String,
    pub format: Format,
    pub photometric_type: PhotometricType,
    pub symmetry: Symmetry,
    pub opening: Opening,
    /// Luminous height (LM-63 height, EULUMDAT's largest luminous-area height), metres:
    /// kept for information; photons leave the flat opening.
    pub height_m: f64,
    /// Rated flux of the lamps (LM-63 lamps × lumens per lamp; EULUMDAT lamp set 1);
    /// None for absolute photometry.
    pub lamp_flux_lm: Option<f64>,
    /// What scales the lamps' output in the table besides the candela multiplier:
    /// ballast factor × ballast-lamp photometric factor × tilt factor (LM-63); 1 for
    /// EULUMDAT. The light output ratio divides it out.
    pub lamp_output_factor: f64,
    pub input_watts: Option<f64>,
    /// EULUMDAT's stated LORL as a fraction (not used in the table).
    pub stated_light_output_ratio: Option<f64>,
    /// EULUMDAT's stated downward flux fraction (DFF), as a fraction.
    pub stated_downward_fraction: Option<f64>,
    pub tilt: Option<Tilt>,
    /// LM-63 keywords (`[MANUFAC]` → `MANUFAC`; label lines of 1986 files under
    /// `LABEL`) or EULUMDAT's text lines (`COMPANY`, `LUMINAIRE`, ...), in file order.
    pub keywords: Vec<(String, String)>,
    /// EULUMDAT's lamp sets (empty for LM-63).
    pub lamp_sets: Vec<LampSet>,
    grid: Grid,
    sampler: Sampler,
    flux_lm: f64,
}

/// Reads a photometric file: `.ies` as LM-63, `.ldt` as EULUMDAT; another extension by
/// its content (LM-63 if it has an `IES…` header or a `TILT=` line). Relative TILT files
/// are read from the file's directory. Errors name the file and line.
pub fn load(path: &Path) -> Result<Photometry> {
    let text = text::read(path)?;
    let origin = path.display().to_string();
    let dir = path.parent().unwrap_or(Path::new("."));
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let is_ies = match ext.as_deref() {
        Some("ies") => true,
        Some("ldt") => false,
        _ => ies::looks_like_ies(&text),
    };
    if is_ies {
        parse_ies(&text, &origin, dir)
    } else {
        parse_ldt(&text, &origin)
    }
}

/// Parses LM-63 text; `origin` names it in errors, `dir` is where `TILT=<file>` is read.
pub fn parse_ies(text: &str, origin: &str, dir: &Path) -> Result<Photometry> {
    ies::parse(text, origin, dir)
}

/// Parses EULUMDAT text; `origin` names it in errors.
pub fn parse_ldt(text: &str, origin: &str) -> Result<Photometry> {
    ldt::parse(text, origin)
}

impl Photometry {
    /// A parsed file `p` (its `sampler` and `flux_lm` placeholders) made whole: the
    /// interpolant's flux and sampler, once the table is known to emit light; errors
    /// name the table's first line `table_line`.
    pub(crate) fn build(mut p: Photometry, table_line: usize) -> Result<Photometry> {
        p.flux_lm = p.grid.flux_lm();
        let table_error = |m: &str| text::at(&p.file, table_line, m);
        if !p.flux_lm.is_finite() {
            return Err(table_error(
                "the candela values are too large: their flux is not finite",
            ));
        }
        p.sampler = match Sampler::new(&p.grid) {
            Some(s) if p.flux_lm > 0.0 => s,
            _ => {
                return Err(table_error(
                    "every candela value is 0 (after the file's factors): it emits no light",
                ))
            }
        };
        Ok(p)
    }

    /// The interpolant's intensity in plane `c_deg` at `gamma_deg` from the nadir, cd
    /// (bilinear in (C, γ) for type C; types A and B interpolate in their own angles).
    pub fn intensity_cd(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        if self.photometric_type == PhotometricType::C {
            self.grid.value(c_deg, gamma_deg)
        } else {
            self.grid.value_toward(direction(c_deg, gamma_deg))
        }
    }

    /// The intensity toward `dir` (luminaire frame, any length > 0), cd.
    pub fn intensity_toward_cd(&self, dir: DVec3) -> f64 {
        self.grid.value_toward(dir)
    }

    /// The luminaire's flux: the exact integral of the interpolant over the sphere, lm.
    pub fn flux_lm(&self) -> f64 {
        self.flux_lm
    }

    /// Flux / (rated lamp flux × lamp output factor); None for absolute photometry.
    pub fn light_output_ratio(&self) -> Option<f64> {
        self.lamp_flux_lm
            .map(|lamps| self.flux_lm / (lamps * self.lamp_output_factor))
    }

    /// The table's largest intensity, at (C, γ) of the luminaire frame.
    pub fn peak(&self) -> Peak {
        let (cd, phi, theta) = self.grid.peak();
        let (c_deg, gamma_deg) = if self.photometric_type == PhotometricType::C {
            (phi, theta)
        } else {
            c_gamma_deg(self.grid.axes.direction(phi, theta))
        };
        Peak {
            intensity_cd: cd,
            c_deg,
            gamma_deg,
        }
    }

    pub fn peak_cd(&self) -> f64 {
        self.peak().intensity_cd
    }

    /// Candela → cd/klm as lighting designers read them: per 1000 lm of rated lamp flux,
    /// or of the luminaire's flux for absolute photometry.
    pub fn cd_to_cd_per_klm(&self) -> f64 {
        1000.0 / self.lamp_flux_lm.unwrap_or(self.flux_lm)
    }

    /// An emission direction (unit vector, luminaire frame) with density
    /// I(direction)/Φ: the interpolant reproduced exactly.
    #[inline]
    pub fn sample_direction(&self, rng: &mut Pcg32) -> DVec3 {
        let cell = (uniform(rng), uniform(rng));
        self.sampler.sample_direction(&self.grid, cell, rng)
    }

    /// [`Photometry::sample_direction`] from a QMC run's point of [0, 1)²: it picks the
    /// grid cell by inversion and places the first proposal in it.
    pub fn sample_direction_from(&self, square: (f64, f64), rng: &mut Pcg32) -> DVec3 {
        (self.sampler).sample_direction_from_square(&self.grid, square, rng)
    }

    /// [`Photometry::sample_direction`] as (C, γ) in degrees.
    pub fn sample_c_gamma_deg(&self, rng: &mut Pcg32) -> (f64, f64) {
        if self.photometric_type == PhotometricType::C {
            let (phi, theta, _, _) = self.sampler.sample_rad(rng);
            (phi.to_degrees(), theta.to_degrees())
        } else {
            c_gamma_deg(self.sample_direction(rng))
        }
    }

    /// The keyword's value (LM-63 `MANUFAC`, EULUMDAT `LUMINAIRE`, ...), if any.
    pub fn keyword(&self, key: &str) -> Option<&str> {
        self.keywords
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
    }

    /// What `luxtally photometry` prints: one fact per line.
    pub fn summary_lines(&self) -> Vec<String> {
        let type_name = match self.photometric_type {
            PhotometricType::C => "C",
            PhotometricType::B => "B",
            PhotometricType::A => "A",
        };
        let mut lines = vec![
            format!("file: {}", self.file),
            format!("format: {}, photometric type {type_name}", self.format),
            format!("symmetry: {}", self.symmetry.describe()),
            format!("flux of the interpolant: {:.2} lm", self.flux_lm),
        ];
        match self.lamp_flux_lm {
            Some(lamps) => {
                lines.push(format!("lamp lumens: {lamps:.1} lm"));
                if let Some(lor) = self.light_output_ratio() {
                    let stated = self
                        .stated_light_output_ratio
                        .map(|s| format!(" (file states {s:.3})"))
                        .unwrap_or_default();
                    lines.push(format!("light output ratio: {lor:.3}{stated}"));
                }
            }
            None => lines.push("lamp lumens: none (absolute photometry)".into()),
        }
        let peak = self.peak();
        lines.push(format!(
            "peak intensity: {:.1} cd ({:.1} cd/klm) at C {:.1}°, γ {:.1}°",
            peak.intensity_cd,
            peak.intensity_cd * self.cd_to_cd_per_klm(),
            peak.c_deg,
            peak.gamma_deg
        ));
        lines.push(format!("opening: {}", self.opening.describe()));
        if let Some(t) = &self.tilt {
            lines.push(format!(
                "tilt: geometry {}, {} angles, factor {:.4} at 0° (applied)",
                t.geometry,
                t.angles_deg.len(),
                t.factor(0.0)
            ));
        }
        lines
    }
}

/// The unit direction of (C, γ) in the luminaire frame: (sin γ cos C, sin γ sin C, −cos γ).
pub fn direction(c_deg: f64, gamma_deg: f64) -> DVec3 {
    grid::TYPE_C.direction(c_deg, gamma_deg)
}

/// (C in [0, 360), γ in [0, 180]) of a direction of the luminaire frame, degrees.
pub fn c_gamma_deg(dir: DVec3) -> (f64, f64) {
    grid::TYPE_C.angles_deg(dir)
}

#[doc(hidden)]
impl Photometry {
    /// The normalised table, for tests: (φ angles, θ angles, cd per φ then θ).
    pub fn table(&self) -> (&[f64], &[f64], &[f64]) {
        (&self.grid.phi_deg, &self.grid.theta_deg, &self.grid.cd)
    }
}

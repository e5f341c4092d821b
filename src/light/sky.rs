//! Skies: `type = "sky"`, the 15 CIE standard general skies (ISO 15469:2004 / CIE S
//! 011/E:2003), the CIE traditional overcast sky (Moon & Spencer, `cie_type = 16`) and
//! the uniform sky, at a zenith luminance or a diffuse horizontal illuminance, and the
//! Perez all-weather sky from an hour's irradiance (`perez.rs`), with the
//! ground below the horizon as a Lambertian emitter of ρ·E_h/π (docs/daylight.md). The
//! sky excludes the sun's disc: that is `type = "sun"`.

use super::distant::{angle_range, hemisphere_bands, DistantEmitter, DistantTable, Portal, Region};
use super::perez::{PerezInput, PerezSky, DEFAULT_DEW_POINT_C};
use super::sun::{altitude_azimuth_deg, ground_reflectance, SunPositionFile};
use super::{single, BoundingSphere, Emitter, Labelled, Light, LightFile, LoadContext};
use crate::error::{Error, Result};
use crate::input::amount;
use glam::DVec3;
use serde::Deserialize;
use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::Arc;

/// Gradation a, b and indicatrix c, d, e of the 15 CIE standard general skies.
pub const CIE_SKIES: [[f64; 5]; 15] = [
    [4.0, -0.70, 0.0, -1.0, 0.00],
    [4.0, -0.70, 2.0, -1.5, 0.15],
    [1.1, -0.80, 0.0, -1.0, 0.00],
    [1.1, -0.80, 2.0, -1.5, 0.15],
    [0.0, -1.00, 0.0, -1.0, 0.00],
    [0.0, -1.00, 2.0, -1.5, 0.15],
    [0.0, -1.00, 5.0, -2.5, 0.30],
    [0.0, -1.00, 10.0, -3.0, 0.45],
    [-1.0, -0.55, 2.0, -1.5, 0.15],
    [-1.0, -0.55, 5.0, -2.5, 0.30],
    [-1.0, -0.55, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 16.0, -3.0, 0.30],
    [-1.0, -0.15, 16.0, -3.0, 0.30],
    [-1.0, -0.15, 24.0, -2.8, 0.15],
];

/// The sky's relative luminance distribution L/Lz.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SkyModel {
    /// CIE standard general sky `kind` (1–15) with the sun towards `sun` (unit, world).
    Cie { kind: u8, sun: DVec3 },
    /// CIE traditional overcast: (1 + 2 sin γ)/3.
    TraditionalOvercast,
    /// The Perez all-weather sky (`light::perez`).
    Perez(PerezSky),
    Uniform,
}

impl SkyModel {
    /// Gradation φ(Z) at cos Z = `z` (> 0).
    fn gradation(a: f64, b: f64, z: f64) -> f64 {
        if z > 0.0 {
            1.0 + a * libm::exp(b / z)
        } else {
            1.0
        }
    }

    /// Indicatrix f(χ).
    fn indicatrix(c: f64, d: f64, e: f64, chi: f64) -> f64 {
        let cos = libm::cos(chi);
        1.0 + c * (libm::exp(d * chi) - libm::exp(d * FRAC_PI_2)) + e * cos * cos
    }

    /// L/Lz towards unit `w` (0 below the horizon).
    pub fn relative(&self, w: DVec3) -> f64 {
        self.unscaled(w) / self.zenith_value()
    }

    /// The distribution before its division by its zenith value: f(χ)·φ(Z) for a CIE
    /// sky (0 below the horizon).
    fn unscaled(&self, w: DVec3) -> f64 {
        if !(w.z > 0.0) {
            return 0.0;
        }
        match *self {
            SkyModel::Cie { kind, sun } => {
                let [a, b, c, d, e] = CIE_SKIES[kind as usize - 1];
                let chi = libm::acos(w.dot(sun).clamp(-1.0, 1.0));
                Self::indicatrix(c, d, e, chi) * Self::gradation(a, b, w.z)
            }
            SkyModel::TraditionalOvercast => (1.0 + 2.0 * w.z) / 3.0,
            SkyModel::Perez(p) => p.relative(w),
            SkyModel::Uniform => 1.0,
        }
    }

    /// The sun its luminance follows: a CIE type whose indicatrix depends on it (all but
    /// 1, 3 and 5), or a Perez sky's.
    pub fn sun(&self) -> Option<DVec3> {
        match *self {
            SkyModel::Cie { kind, sun } if CIE_SKIES[kind as usize - 1][2] != 0.0 => Some(sun),
            SkyModel::Perez(p) => Some(p.sun),
            _ => None,
        }
    }

    /// [`SkyModel::unscaled`] at the zenith: f(Zs)·φ(0) for a CIE sky (the zenith sits
    /// at χ = Zs), lv there for a Perez sky, 1 for the others. Some Perez hours give a
    /// dark zenith (lv ≤ 0, cut to 0): their sky is scaled by lv itself (1), and their
    /// "Lz" is the luminance per unit lv.
    fn zenith_value(&self) -> f64 {
        match *self {
            SkyModel::Cie { kind, sun } => {
                let [a, b, c, d, e] = CIE_SKIES[kind as usize - 1];
                let zs = libm::acos(sun.z.clamp(-1.0, 1.0));
                Self::indicatrix(c, d, e, zs) * Self::gradation(a, b, 1.0)
            }
            SkyModel::Perez(p) => Some(p.relative(DVec3::Z)).filter(|&l| l > 0.0).unwrap_or(1.0),
            _ => 1.0,
        }
    }

    /// An upper bound of L/Lz over `band` (upper hemisphere): the gradation is monotone
    /// in z, so its largest value sits on a z edge; the indicatrix falls with χ up to
    /// 90° and its cos² term rises again beyond, so it is bounded by its exponential
    /// part at the least χ plus the cos² part at the χ farthest from 90°.
    pub fn bound(&self, band: &Region) -> f64 {
        let Region::Band { z, .. } = *band else {
            return f64::INFINITY;
        };
        match *self {
            SkyModel::Cie { kind, sun } => {
                let [a, b, c, d, e] = CIE_SKIES[kind as usize - 1];
                let g = Self::gradation(a, b, z[0]).max(Self::gradation(a, b, z[1]));
                let (lo, hi) = angle_range(band, sun);
                let (cos_lo, cos_hi) = (libm::cos(lo), libm::cos(hi));
                let cos2 = (cos_lo * cos_lo).max(cos_hi * cos_hi);
                let f = 1.0 + c * (libm::exp(d * lo) - libm::exp(d * FRAC_PI_2)) + e * cos2;
                f * g / self.zenith_value()
            }
            SkyModel::Perez(p) => p.bound(z, angle_range(band, p.sun)) / self.zenith_value(),
            SkyModel::TraditionalOvercast => (1.0 + 2.0 * z[1]) / 3.0,
            SkyModel::Uniform => 1.0,
        }
    }

    /// ∫ (L/Lz) dω and ∫ (L/Lz)·cos Z dω over the upper hemisphere (the latter the
    /// horizontal illuminance per Lz), by 4-point Gauss–Legendre on 256 × 512 z–φ
    /// cells: the integrand is smooth, so this is exact to far below any photon noise
    /// (tests/suite/physics/daylight.rs checks it against closed forms and a finer rule).
    pub fn integrals(&self) -> (f64, f64) {
        self.integrals_on(256, 512)
    }

    /// [`SkyModel::integrals`] on `nz` × `nphi` cells.
    pub fn integrals_on(&self, nz: usize, nphi: usize) -> (f64, f64) {
        let gl = [
            (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
            (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
            (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
            (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
        ];
        let (dz, dphi) = (1.0 / nz as f64, 2.0 * PI / nphi as f64);
        let (mut solid, mut horizontal) = (0.0, 0.0);
        for i in 0..nz {
            for &(xz, wz) in &gl {
                let z = (i as f64 + 0.5 + 0.5 * xz) * dz;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let mut ring = 0.0;
                for j in 0..nphi {
                    for &(xp, wp) in &gl {
                        let phi = (j as f64 + 0.5 + 0.5 * xp) * dphi;
                        let w = DVec3::new(r * libm::cos(phi), r * libm::sin(phi), z);
                        ring += wp * self.relative(w);
                    }
                }
                solid += wz * ring;
                horizontal += wz * ring * z;
            }
        }
        let cell = 0.25 * dz * dphi;
        (solid * cell, horizontal * cell)
    }
}

/// The `[[lights]]` entry.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SkyFile {
    /// 1–15: the CIE standard general skies; 16: the CIE traditional overcast sky.
    pub cie_type: Option<i64>,
    /// `"uniform"` or `"perez"` instead of a CIE type.
    pub model: Option<String>,
    pub zenith_luminance_cdm2: Option<f64>,
    /// The sky's illuminance on an unobstructed horizontal plane (the diffuse
    /// horizontal illuminance), lx.
    pub horizontal_illuminance_lx: Option<f64>,
    pub ground_reflectance: Option<f64>,
    pub sun_altitude_deg: Option<f64>,
    pub sun_azimuth_deg: Option<f64>,
    pub latitude_deg: Option<f64>,
    pub longitude_deg: Option<f64>,
    pub timezone_h: Option<f64>,
    pub date: Option<String>,
    pub time: Option<String>,
    /// `model = "perez"`: direct normal irradiance, W/m².
    pub direct_normal_irradiance_wm2: Option<f64>,
    /// `model = "perez"`: diffuse horizontal irradiance, W/m².
    pub diffuse_horizontal_irradiance_wm2: Option<f64>,
    /// `model = "perez"`: 1–366, for the extraterrestrial irradiance; derived from
    /// `date` when the sun is placed by site and time, required otherwise.
    pub day_of_year: Option<f64>,
    /// `model = "perez"`: dew point, °C, for the efficacies' precipitable water
    /// (default [`DEFAULT_DEW_POINT_C`]).
    pub dew_point_c: Option<f64>,
}

impl SkyFile {
    /// The Perez sky of the entry's irradiance, day and dew point with the sun at `sun`.
    fn perez(&self, at: &str, sun: Option<DVec3>) -> Result<SkyModel> {
        let what = "model = \"perez\"";
        let sun = sun.ok_or_else(|| {
            Error::input(at, "a Perez sky needs the sun's position (altitude/azimuth or site, date and time)")
        })?;
        let dni = crate::input::required(self.direct_normal_irradiance_wm2, at, "direct_normal_irradiance_wm2", what)?;
        let dhi = crate::input::required(
            self.diffuse_horizontal_irradiance_wm2,
            at,
            "diffuse_horizontal_irradiance_wm2",
            what,
        )?;
        let day = match (self.day_of_year, self.date.as_deref()) {
            (Some(_), Some(_)) => {
                return Err(Error::input(
                    format!("{at}.day_of_year"),
                    "give `day_of_year` or `date`, not both (the date fixes the day)",
                ))
            }
            (Some(day), None) => day,
            (None, Some(date)) => super::perez::day_of_year(date).ok_or_else(|| {
                Error::input(format!("{at}.date"), format!("`{date}` is not YYYY-MM-DD"))
            })?,
            (None, None) => {
                return Err(Error::input(
                    format!("{at}.day_of_year"),
                    "missing (required for a Perez sky whose sun is given by angles: the \
                     extraterrestrial irradiance varies ±3.3 % over the year)",
                ))
            }
        };
        let input = PerezInput {
            direct_normal_wm2: dni,
            diffuse_horizontal_wm2: dhi,
            sun,
            day_of_year: day,
            dew_point_c: self.dew_point_c.unwrap_or(DEFAULT_DEW_POINT_C),
        };
        PerezSky::new(&input).map(SkyModel::Perez).map_err(|e| Error::input(at, e))
    }

    /// The Perez-only keys this entry gives.
    fn perez_keys(&self) -> Vec<&'static str> {
        [
            ("direct_normal_irradiance_wm2", self.direct_normal_irradiance_wm2.is_some()),
            ("diffuse_horizontal_irradiance_wm2", self.diffuse_horizontal_irradiance_wm2.is_some()),
            ("day_of_year", self.day_of_year.is_some()),
            ("dew_point_c", self.dew_point_c.is_some()),
        ]
        .into_iter()
        .filter_map(|(k, given)| given.then_some(k))
        .collect()
    }

    fn model(&self, at: &str) -> Result<SkyModel> {
        let position = SunPositionFile {
            sun_altitude_deg: self.sun_altitude_deg,
            sun_azimuth_deg: self.sun_azimuth_deg,
            latitude_deg: self.latitude_deg,
            longitude_deg: self.longitude_deg,
            timezone_h: self.timezone_h,
            date: self.date.clone(),
            time: self.time.clone(),
        };
        let sun = position.resolve(at)?;
        let perez = self.model.as_deref() == Some("perez");
        if let (false, Some(key)) = (perez, self.perez_keys().first()) {
            return Err(Error::input(format!("{at}.{key}"), "applies only to model = \"perez\""));
        }
        let model = match (self.cie_type, self.model.as_deref()) {
            (Some(16), None) => SkyModel::TraditionalOvercast,
            (Some(k @ 1..=15), None) => {
                let needs_sun = CIE_SKIES[k as usize - 1][2] != 0.0;
                match sun {
                    Some(s) if s.z >= 0.0 => SkyModel::Cie { kind: k as u8, sun: s },
                    Some(s) => {
                        return Err(Error::input(
                            at,
                            format!(
                                "the sun is below the horizon (altitude {:.3}°): the CIE \
                                 skies are defined for a sun at or above it",
                                libm::asin(s.z).to_degrees()
                            ),
                        ))
                    }
                    // Azimuthally uniform types do not depend on the sun.
                    None if !needs_sun => SkyModel::Cie { kind: k as u8, sun: DVec3::Z },
                    None => {
                        return Err(Error::input(
                            at,
                            format!("CIE sky type {k} needs the sun's position (its indicatrix)"),
                        ))
                    }
                }
            }
            (Some(k), None) => {
                return Err(Error::input(
                    format!("{at}.cie_type"),
                    format!("must be 1–15 (CIE standard general skies) or 16 (traditional overcast), got {k}"),
                ))
            }
            (None, Some("uniform")) => SkyModel::Uniform,
            (None, Some("perez")) => self.perez(at, sun)?,
            (None, Some(other)) => {
                return Err(Error::input(
                    format!("{at}.model"),
                    format!("unknown sky model `{other}` (expected \"uniform\" or \"perez\", or a cie_type)"),
                ))
            }
            _ => {
                return Err(Error::input(
                    at,
                    "give exactly one of `cie_type` (1–16) and `model` (\"uniform\" or \"perez\")",
                ))
            }
        };
        Ok(model)
    }
}

impl LightFile for SkyFile {
    const TYPE: &'static str = "sky";

    fn into_lights(self, label: &str, at: &str, cx: &mut LoadContext) -> Result<Vec<Labelled>> {
        let model = self.model(at)?;
        let (solid_per_lz, per_lz) = model.integrals();
        let level = (self.zenith_luminance_cdm2, self.horizontal_illuminance_lx);
        let zenith_luminance_cdm2 = match (level, model) {
            // Lz = E_dh / ∫(L/Lz) cos Z dω: the exact integral, not 145 patches.
            ((None, None), SkyModel::Perez(p)) if per_lz > 0.0 => p.diffuse_horizontal_lx / per_lz,
            ((None, None), SkyModel::Perez(p)) => {
                return Err(Error::input(
                    at,
                    format!(
                        "ε {:.4}, Δ {:.4}: the Perez luminance is 0 everywhere above the horizon",
                        p.clearness, p.brightness
                    ),
                ))
            }
            (_, SkyModel::Perez(_)) => {
                return Err(Error::input(
                    at,
                    "a Perez sky's level comes from its irradiance (the efficacy model): give \
                     neither `zenith_luminance_cdm2` nor `horizontal_illuminance_lx`",
                ))
            }
            ((Some(lz), None), _) => amount(lz, at, "zenith_luminance_cdm2")?,
            ((None, Some(e)), _) => amount(e, at, "horizontal_illuminance_lx")? / per_lz,
            _ => {
                return Err(Error::input(
                    at,
                    "give exactly one of `zenith_luminance_cdm2` and `horizontal_illuminance_lx`",
                ))
            }
        };
        single(
            label,
            Sky {
                model,
                zenith_luminance_cdm2,
                horizontal_lx: zenith_luminance_cdm2 * per_lz,
                radiant_integral: zenith_luminance_cdm2 * solid_per_lz,
                ground_reflectance: ground_reflectance(self.ground_reflectance, at)?,
                portals: cx.portals.clone(),
            },
        )
    }
}

/// A sky: its model, zenith luminance, and the integrals that fix its flux.
#[derive(Clone, Debug, PartialEq)]
pub struct Sky {
    pub model: SkyModel,
    /// Lz, the scale of [`SkyModel::relative`] (the zenith's luminance, but for a Perez
    /// sky with a dark zenith: see [`SkyModel::zenith_value`]).
    pub zenith_luminance_cdm2: f64,
    /// Its illuminance on an unobstructed horizontal plane, lx.
    pub horizontal_lx: f64,
    /// ∫ L dω over the upper hemisphere, cd/m²·sr.
    pub radiant_integral: f64,
    pub ground_reflectance: f64,
    /// The scene's `[[portals]]`: photons come in by them, next events aim at them too.
    pub portals: Vec<Portal>,
}

/// Bands the sky is tabulated on for sampling: z × azimuth.
const BANDS: (usize, usize) = (64, 128);

impl Sky {
    /// Luminance of the ground it lights, cd/m².
    pub fn ground_luminance_cdm2(&self) -> f64 {
        self.ground_reflectance * self.horizontal_lx / PI
    }

    /// Luminance towards unit `w`: the sky above the horizon, the ground below.
    pub fn luminance(&self, w: DVec3) -> f64 {
        self.luminance_fn()(w)
    }

    /// [`Sky::luminance`] with its constants (Lz over the zenith value, the ground's
    /// luminance) worked out once: what photons and next events call.
    fn luminance_fn(&self) -> impl Fn(DVec3) -> f64 + Send + Sync + 'static {
        let model = self.model;
        let scale = self.zenith_luminance_cdm2 / model.zenith_value();
        let ground = self.ground_luminance_cdm2();
        move |w: DVec3| {
            if w.z > 0.0 {
                scale * model.unscaled(w)
            } else {
                ground
            }
        }
    }

    fn table(&self) -> DistantTable {
        let lz = self.zenith_luminance_cdm2;
        let mut parts: Vec<(Region, f64)> = hemisphere_bands(BANDS.0, BANDS.1)
            .map(|band| (band, lz * self.model.bound(&band)))
            .collect();
        parts.push((Region::ground(), self.ground_luminance_cdm2()));
        DistantTable::new(parts, Arc::new(self.luminance_fn())).with_grid(BANDS.0, BANDS.1)
    }
}

impl Sky {
    /// [`Light::describe`] and the luminance at the zenith, the horizon and towards the
    /// sun (where its indicatrix depends on it), for `luxtally sky`.
    pub fn describe_full(&self) -> String {
        let mut text = self.describe();
        let horizon = self.luminance(DVec3::new(0.0, 1.0, 1e-9).normalize());
        text += &format!("; L at the horizon (north) {horizon:.2} cd/m²");
        if let Some(sun) = self.model.sun().filter(|s| s.z > 0.0) {
            text += &format!(", next to the sun {:.2} cd/m²", self.luminance(sun));
        }
        if let SkyModel::Perez(p) = self.model {
            text += &format!(
                "; Perez ε {:.4}, Δ {:.4}, category {}, a b c d e \
                 {:.4} {:.4} {:.4} {:.4} {:.4}; the sun's direct normal illuminance {:.1} lx \
                 (a `type = \"sun\"` with `direct_normal_lx = {:.1}` and the same position)",
                p.clearness,
                p.brightness,
                p.category,
                p.coefficients[0],
                p.coefficients[1],
                p.coefficients[2],
                p.coefficients[3],
                p.coefficients[4],
                p.direct_normal_lx,
                p.direct_normal_lx,
            );
        }
        text
    }
}

impl Light for Sky {
    /// Photons cross a disk of the scene's radius R normal to each direction: Φ =
    /// πR²·∫L dω over the sky and the ground.
    fn flux_lm(&self, sphere: &BoundingSphere) -> f64 {
        let total = self.radiant_integral + 2.0 * PI * self.ground_luminance_cdm2();
        PI * sphere.radius * sphere.radius * total
    }

    fn emitter(&self, origin: DVec3, sphere: &BoundingSphere) -> Arc<dyn Emitter> {
        DistantEmitter::of(self.table(), origin, sphere, &self.portals, true)
    }

    fn describe(&self) -> String {
        let model = match self.model {
            SkyModel::Cie { kind, sun } => {
                let (altitude, azimuth) = altitude_azimuth_deg(sun);
                format!(
                    "CIE standard general sky type {kind}, sun at altitude {altitude:.3}°, \
                     azimuth {azimuth:.3}°"
                )
            }
            SkyModel::TraditionalOvercast => "CIE traditional overcast sky (type 16)".into(),
            SkyModel::Perez(p) => {
                let (altitude, azimuth) = altitude_azimuth_deg(p.sun);
                format!(
                    "Perez all-weather sky (ε {:.4}, Δ {:.4}), sun at altitude {altitude:.3}°, \
                     azimuth {azimuth:.3}°",
                    p.clearness, p.brightness
                )
            }
            SkyModel::Uniform => "uniform sky".into(),
        };
        format!(
            "{model}: Lz {:.2} cd/m², horizontal illuminance {:.1} lx; ground ρ {} (L {:.2} cd/m²)",
            self.luminance(DVec3::Z),
            self.horizontal_lx,
            self.ground_reflectance,
            self.ground_luminance_cdm2()
        )
    }

    /// Its luminance towards `w` ([`Sky::luminance`]), and its sun where its indicatrix
    /// follows one (types 1, 3 and 5 and the others have none that matters).
    fn daylight(&self, w: DVec3) -> Option<super::Daylight> {
        Some(super::Daylight {
            sky_luminance_cdm2: Some(self.luminance(w)),
            sun: self.model.sun(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::sun::direction;

    /// The rejection sampler is exact only if every band's bound holds: L/Lz at points
    /// spread over each band (its corners and edges included) never exceeds it, for
    /// every CIE type with the sun low, high, at the zenith and on a band's corner.
    #[test]
    fn band_bounds_hold_everywhere_in_their_band() {
        let suns = [direction(2.0, 10.0), direction(45.0, 123.0), DVec3::Z, direction(87.1875, 0.0)];
        for kind in 1..=15u8 {
            for &sun in &suns {
                let sky = SkyModel::Cie { kind, sun };
                for band in hemisphere_bands(BANDS.0, BANDS.1) {
                    let bound = sky.bound(&band);
                    for k in 0..25 {
                        let (a, b) = ((k % 5) as f64 / 4.0, (k / 5) as f64 / 4.0);
                        let l = sky.relative(band.direction(a.min(1.0 - 1e-12), b));
                        assert!(l <= bound * (1.0 + 1e-12), "type {kind}: {l} > {bound} in {band:?}");
                    }
                }
            }
        }
        for model in [SkyModel::TraditionalOvercast, SkyModel::Uniform] {
            for band in hemisphere_bands(BANDS.0, BANDS.1) {
                let l = model.relative(band.direction(0.999_999, 0.5));
                assert!(l <= model.bound(&band) * (1.0 + 1e-12));
            }
        }
    }

    /// Next-event pieces carry L(ω)/p(ω): their mean over a fine stratified pattern is
    /// ∫ L dω (here with the ground, ρ 0.2).
    #[test]
    fn pieces_integrate_the_luminance() {
        let model = SkyModel::Cie { kind: 12, sun: direction(30.0, 200.0) };
        let (solid, horizontal) = model.integrals();
        let sky = Sky {
            model,
            zenith_luminance_cdm2: 1.0,
            horizontal_lx: horizontal,
            radiant_integral: solid,
            ground_reflectance: 0.2,
            portals: Vec::new(),
        };
        let table = sky.table();
        let n = 400;
        let mut sum = 0.0;
        for k in 0..n * n {
            let (a, b) = (((k % n) as f64 + 0.5) / n as f64, ((k / n) as f64 + 0.5) / n as f64);
            sum += table.piece(a, b).1;
        }
        let want = solid + 2.0 * PI * sky.ground_luminance_cdm2();
        assert!((sum / (n * n) as f64 - want).abs() < 1e-3 * want, "{} against {want}", sum / (n * n) as f64);
    }
}

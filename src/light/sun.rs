//! The sun: `type = "sun"`, a disc of 0.533° (uniform luminance in its cone) giving
//! `direct_normal_lx` on a plane normal to it, placed by altitude and azimuth or by site
//! and local time (NREL SPA, Reda & Andreas 2004, through the `solar-positioning`
//! crate), and the ground it lights (docs/daylight.md).

use super::distant::{DistantEmitter, DistantTable, Portal, Region};
use super::{single, BoundingSphere, Emitter, Labelled, Light, LightFile, LoadContext};
use crate::error::{Error, Result};
use crate::input::{amount, required};
use glam::DVec3;
use serde::Deserialize;
use std::f64::consts::PI;
use std::sync::Arc;

/// Half the sun's angular diameter, 0.533°/2.
pub const SUN_HALF_ANGLE_DEG: f64 = 0.2665;

/// Ground reflectance where an entry gives none.
pub const DEFAULT_GROUND_REFLECTANCE: f64 = 0.2;

/// Where the sun is: altitude and azimuth, or a site and its local standard time.
#[derive(Deserialize, Debug, Default, Clone)]
#[serde(deny_unknown_fields)]
pub struct SunPositionFile {
    pub sun_altitude_deg: Option<f64>,
    /// From north (+y) towards east (+x).
    pub sun_azimuth_deg: Option<f64>,
    pub latitude_deg: Option<f64>,
    /// Positive east.
    pub longitude_deg: Option<f64>,
    /// Hours ahead of UTC (positive east), standard time.
    pub timezone_h: Option<f64>,
    /// "YYYY-MM-DD".
    pub date: Option<String>,
    /// "HH:MM" or "HH:MM:SS", local standard time.
    pub time: Option<String>,
}

impl SunPositionFile {
    /// The unit direction towards the sun (world: +z up, +y north, +x east), or None
    /// when no key of either way is given.
    pub fn resolve(&self, at: &str) -> Result<Option<DVec3>> {
        let angles = self.sun_altitude_deg.is_some() || self.sun_azimuth_deg.is_some();
        let site = self.latitude_deg.is_some()
            || self.longitude_deg.is_some()
            || self.timezone_h.is_some()
            || self.date.is_some()
            || self.time.is_some();
        let (altitude, azimuth) = match (angles, site) {
            (false, false) => return Ok(None),
            (true, true) => {
                return Err(Error::input(
                    at,
                    "give the sun's altitude and azimuth or its site and time, not both",
                ))
            }
            (true, false) => {
                let what = "a sun given by angles";
                let alt = required(self.sun_altitude_deg, at, "sun_altitude_deg", what)?;
                let az = required(self.sun_azimuth_deg, at, "sun_azimuth_deg", what)?;
                if !(-90.0..=90.0).contains(&alt) || !az.is_finite() {
                    return Err(Error::input(
                        format!("{at}.sun_altitude_deg"),
                        format!("must be within −90…90°, got {alt} (azimuth {az})"),
                    ));
                }
                (alt, az)
            }
            (false, true) => self.site_position(at)?,
        };
        Ok(Some(direction(altitude, azimuth)))
    }

    /// Altitude and azimuth (degrees) at the site and local standard time, by SPA
    /// (geometric: no refraction; ΔT estimated from the date).
    fn site_position(&self, at: &str) -> Result<(f64, f64)> {
        let what = "a sun placed by site and time";
        let lat = required(self.latitude_deg, at, "latitude_deg", what)?;
        let lon = required(self.longitude_deg, at, "longitude_deg", what)?;
        let tz = required(self.timezone_h, at, "timezone_h", what)?;
        let date = required(self.date.clone(), at, "date", what)?;
        let time = required(self.time.clone(), at, "time", what)?;
        if !(-90.0..=90.0).contains(&lat) {
            return Err(Error::input(
                format!("{at}.latitude_deg"),
                format!("must be within −90…90°, got {lat}"),
            ));
        }
        if !(-180.0..=180.0).contains(&lon) {
            return Err(Error::input(
                format!("{at}.longitude_deg"),
                format!("must be within −180…180°, got {lon}"),
            ));
        }
        if !(-14.0..=14.0).contains(&tz) {
            return Err(Error::input(
                format!("{at}.timezone_h"),
                format!("must be within −14…14 h, got {tz}"),
            ));
        }
        let [y, m, d] = parse_fields::<3>(&date, '-')
            .ok_or_else(|| Error::input(format!("{at}.date"), format!("`{date}` is not YYYY-MM-DD")))?;
        let hms = parse_fields::<3>(&time, ':').or_else(|| {
            parse_fields::<2>(&time, ':').map(|[h, mi]| [h, mi, 0.0])
        });
        let [h, mi, s] = hms
            .ok_or_else(|| Error::input(format!("{at}.time"), format!("`{time}` is not HH:MM[:SS]")))?;
        solar_position(lat, lon, tz, [y, m, d], [h, mi, s])
            .map_err(|e| Error::input(at, format!("solar position: {e}")))
    }
}

/// "2026-06-21" → [2026, 6, 21].
fn parse_fields<const N: usize>(text: &str, sep: char) -> Option<[f64; N]> {
    let parts: Vec<f64> = (text.trim().split(sep))
        .map(|p| p.trim().parse::<f64>().ok())
        .collect::<Option<_>>()?;
    parts.try_into().ok()
}

/// The sun's altitude and azimuth (degrees, azimuth from north towards east) at
/// latitude/longitude (degrees, east positive) at local standard time `date`/`hms`
/// in time zone `tz_h` (hours ahead of UTC), by NREL SPA without refraction.
pub fn solar_position(lat: f64, lon: f64, tz_h: f64, date: [f64; 3], hms: [f64; 3]) -> std::result::Result<(f64, f64), String> {
    use solar_positioning::time::JulianDate;
    use solar_positioning::{delta_t, Location, SolarPositions};
    let [y, m, d] = date;
    let [h, mi, s] = hms;
    let whole = |x: f64, lo: f64, hi: f64| x.fract() == 0.0 && (lo..=hi).contains(&x);
    let valid = whole(y, -2000.0, 6000.0)
        && whole(m, 1.0, 12.0)
        && whole(d, 1.0, 31.0)
        && whole(h, 0.0, 23.0)
        && whole(mi, 0.0, 59.0)
        && (0.0..60.0).contains(&s);
    if !valid {
        return Err(format!("no such date and time: {y}-{m}-{d} {h}:{mi}:{s}"));
    }
    let dt = delta_t::estimate_from_date(y as i32, m as u32).map_err(|e| e.to_string())?;
    let local = JulianDate::from_utc(y as i32, m as u32, d as u32, h as u32, mi as u32, s, dt)
        .map_err(|e| e.to_string())?;
    let utc = JulianDate::new(local.julian_date() - tz_h / 24.0, dt).map_err(|e| e.to_string())?;
    let p = SolarPositions::new()
        .at_from_julian(utc, Location { latitude: lat, longitude: lon }, 0.0, None)
        .map_err(|e| e.to_string())?;
    Ok((p.elevation_angle(), p.azimuth()))
}

/// Unit vector towards altitude/azimuth (degrees; azimuth from +y towards +x).
pub fn direction(altitude_deg: f64, azimuth_deg: f64) -> DVec3 {
    direction_rad(altitude_deg.to_radians(), azimuth_deg.to_radians())
}

/// [`direction`] of an altitude and azimuth in radians.
pub fn direction_rad(altitude: f64, azimuth: f64) -> DVec3 {
    let c = libm::cos(altitude);
    DVec3::new(c * libm::sin(azimuth), c * libm::cos(azimuth), libm::sin(altitude))
}

/// Altitude and azimuth (degrees, azimuth from north towards east) of unit `w`: the
/// inverse of [`direction`].
pub fn altitude_azimuth_deg(w: DVec3) -> (f64, f64) {
    let altitude = libm::asin(w.z.clamp(-1.0, 1.0)).to_degrees();
    let azimuth = libm::atan2(w.x, w.y).to_degrees().rem_euclid(360.0);
    (altitude, azimuth)
}

/// The `[[lights]]` entry.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SunFile {
    pub direct_normal_lx: Option<f64>,
    pub ground_reflectance: Option<f64>,
    pub sun_altitude_deg: Option<f64>,
    pub sun_azimuth_deg: Option<f64>,
    pub latitude_deg: Option<f64>,
    pub longitude_deg: Option<f64>,
    pub timezone_h: Option<f64>,
    pub date: Option<String>,
    pub time: Option<String>,
}

/// A ground reflectance key, validated (default [`DEFAULT_GROUND_REFLECTANCE`]).
pub fn ground_reflectance(x: Option<f64>, at: &str) -> Result<f64> {
    let rho = x.unwrap_or(DEFAULT_GROUND_REFLECTANCE);
    if !(0.0..=1.0).contains(&rho) {
        return Err(Error::input(
            format!("{at}.ground_reflectance"),
            format!("must be within 0…1 (0: the scene models its ground), got {rho}"),
        ));
    }
    Ok(rho)
}

impl LightFile for SunFile {
    const TYPE: &'static str = "sun";

    fn into_lights(self, label: &str, at: &str, cx: &mut LoadContext) -> Result<Vec<Labelled>> {
        let what = "type \"sun\" lights";
        let e = required(self.direct_normal_lx, at, "direct_normal_lx", what)?;
        let direct_normal_lx = amount(e, at, "direct_normal_lx")?;
        let position = SunPositionFile {
            sun_altitude_deg: self.sun_altitude_deg,
            sun_azimuth_deg: self.sun_azimuth_deg,
            latitude_deg: self.latitude_deg,
            longitude_deg: self.longitude_deg,
            timezone_h: self.timezone_h,
            date: self.date,
            time: self.time,
        };
        let towards = position.resolve(at)?.ok_or_else(|| {
            Error::input(
                at,
                "needs the sun's position: sun_altitude_deg and sun_azimuth_deg, or \
                 latitude_deg, longitude_deg, timezone_h, date and time",
            )
        })?;
        if !(towards.z > 0.0) {
            return Err(Error::input(
                at,
                format!(
                    "the sun is below the horizon (altitude {:.3}°): no sun light then",
                    libm::asin(towards.z).to_degrees()
                ),
            ));
        }
        single(
            label,
            Sun {
                towards,
                direct_normal_lx,
                ground_reflectance: ground_reflectance(self.ground_reflectance, at)?,
                portals: cx.portals.clone(),
            },
        )
    }
}

/// The sun: unit `towards` it (world), E on a plane normal to it, and the reflectance
/// of the ground its light reaches (a Lambertian lower hemisphere of ρ·E_h/π).
#[derive(Clone, Debug, PartialEq)]
pub struct Sun {
    pub towards: DVec3,
    pub direct_normal_lx: f64,
    pub ground_reflectance: f64,
    /// The scene's `[[portals]]`: photons come in by them (next events do not aim at
    /// them: the sun's cone is sampled directly).
    pub portals: Vec<Portal>,
}

impl Sun {
    /// cos of the sun's half angle.
    pub fn cos_half_angle() -> f64 {
        libm::cos(SUN_HALF_ANGLE_DEG.to_radians())
    }

    /// Luminance of the disc: E_n = L·π sin²α exactly on a plane normal to the sun.
    pub fn disc_luminance_cdm2(&self) -> f64 {
        let s = libm::sin(SUN_HALF_ANGLE_DEG.to_radians());
        self.direct_normal_lx / (PI * s * s)
    }

    /// Horizontal illuminance of the disc, lx: ∫cone ω dω = axis·π sin²α, so
    /// L ∫cone ω_z dω = E_n·sin γs exactly (the whole disc above the horizon).
    pub fn horizontal_lx(&self) -> f64 {
        self.direct_normal_lx * self.towards.z
    }

    /// Luminance of the ground it lights, cd/m².
    pub fn ground_luminance_cdm2(&self) -> f64 {
        self.ground_reflectance * self.horizontal_lx() / PI
    }

    fn table(&self) -> DistantTable {
        let (axis, cos_max) = (self.towards, Sun::cos_half_angle());
        let (l_disc, l_ground) = (self.disc_luminance_cdm2(), self.ground_luminance_cdm2());
        let luminance = Arc::new(move |w: DVec3| {
            if w.dot(axis) >= cos_max {
                l_disc
            } else if w.z < 0.0 {
                l_ground
            } else {
                0.0
            }
        });
        DistantTable::new(
            vec![
                (Region::Cone { axis, cos_max }, l_disc),
                (Region::ground(), l_ground),
            ],
            luminance,
        )
    }

    /// ∫ L dω over the sphere: the disc and the ground.
    fn radiant_integral(&self) -> f64 {
        let disc = self.disc_luminance_cdm2() * 2.0 * PI * (1.0 - Sun::cos_half_angle());
        disc + self.ground_luminance_cdm2() * 2.0 * PI
    }
}

impl Light for Sun {
    /// Photons cross a disk of the scene's radius R normal to each direction: Φ =
    /// πR²·∫L dω.
    fn flux_lm(&self, sphere: &BoundingSphere) -> f64 {
        PI * sphere.radius * sphere.radius * self.radiant_integral()
    }

    fn emitter(&self, origin: DVec3, sphere: &BoundingSphere) -> Arc<dyn Emitter> {
        DistantEmitter::of(self.table(), origin, sphere, &self.portals, false)
    }

    fn describe(&self) -> String {
        let (altitude, azimuth) = altitude_azimuth_deg(self.towards);
        format!(
            "sun at altitude {altitude:.3}°, azimuth {azimuth:.3}° (from north, +y, towards \
             east, +x), {} lx normal, {:.1} lx horizontal; ground ρ {} (L {:.2} cd/m²)",
            self.direct_normal_lx,
            self.horizontal_lx(),
            self.ground_reflectance,
            self.ground_luminance_cdm2()
        )
    }

    /// Where it is, for the sky plots' marker.
    fn daylight(&self, _w: DVec3) -> Option<super::Daylight> {
        Some(super::Daylight {
            sky_luminance_cdm2: None,
            sun: Some(self.towards),
        })
    }
}

//! The year's skies as daylight-coefficient weights: for every hour of the weather file,
//! the Perez sky's mean luminance over each Reinhart patch (normalised to the hour's
//! diffuse horizontal illuminance by the sky's own integral: each patch's ∫L cos dω
//! from the same Gauss–Legendre points as its mean, summed), the ground's luminance,
//! and the sun's direct normal illuminance with the bin its position falls in.

use crate::error::{Error, Result};
use crate::light::patches::SkyPatches;
use crate::light::perez::{PerezInput, PerezSky, DEFAULT_DEW_POINT_C};
use crate::light::sky::{Sky, SkyModel};
use crate::light::sun::{direction, solar_position};
use crate::scene::annual::Annual;
use crate::weather::{day_of_year, Weather, WeatherHour};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// The year suns are placed in: a weather file's records come from several years (a
/// typical year), so one fixed non-leap year is used for every record.
pub const SOLAR_YEAR: f64 = 2023.0;

/// One hour with daylight.
#[derive(Clone, Debug)]
pub struct SkyHour {
    /// Index of its record in the weather file (0 = the first).
    pub record: usize,
    pub occupied: bool,
    /// Mean luminance per sky patch, cd/m².
    pub patches: Vec<f32>,
    /// The ground's luminance ρ·E_gh/π, cd/m².
    pub ground_cdm2: f64,
    /// The sun's bin (index into [`SkyMatrix::suns`]) and its direct normal illuminance.
    pub sun: Option<(usize, f64)>,
    /// The hour's own sun position (unit, towards the sun), before binning.
    pub sun_position: DVec3,
    /// Diffuse horizontal illuminance of the Perez sky, lx.
    pub diffuse_horizontal_lx: f64,
    /// Unobstructed global horizontal illuminance (sky and sun), lx.
    pub global_horizontal_lx: f64,
}

/// Every hour's source weights.
#[derive(Clone, Debug)]
pub struct SkyMatrix {
    pub patches: SkyPatches,
    /// Hours with daylight, in record order.
    pub hours: Vec<SkyHour>,
    /// Records in the file, and those of them occupied.
    pub records: usize,
    /// Per record: month, day, hour stamp and whether occupied (0 or 1).
    pub stamps: Vec<[u32; 4]>,
    pub occupied_records: usize,
    /// The sun bins' positions (unit, towards the sun): each the direct-normal-weighted
    /// mean of its hours' positions.
    pub suns: Vec<DVec3>,
    /// Counted warnings, one line each.
    pub warnings: Vec<String>,
}

/// What one record gives before the suns are binned.
enum RecordSky {
    Dark,
    /// Light reported while the sun is below the horizon at mid-interval (counted).
    SunBelowHorizon,
    /// No Perez sky (the reason, counted).
    Refused(String),
    Lit(SkyHour, Option<DVec3>),
}

impl SkyMatrix {
    pub fn new(weather: &Weather, annual: &Annual) -> Result<SkyMatrix> {
        let patches = SkyPatches::reinhart(annual.mf, "annual.mf")?;
        let records: Vec<RecordSky> = (weather.hours.par_iter().enumerate())
            .map(|(i, h)| record_sky(weather, h, i, &patches, annual))
            .collect::<Result<_>>()?;
        let occupied_records = (weather.hours.iter())
            .filter(|h| occupied(h, annual))
            .count();
        let mut warnings = weather.warnings.clone();
        let (mut below, mut refused, mut hours, mut positions) =
            (0, Vec::new(), Vec::new(), Vec::new());
        for r in records {
            match r {
                RecordSky::Dark => {}
                RecordSky::SunBelowHorizon => below += 1,
                RecordSky::Refused(why) => refused.push(why),
                RecordSky::Lit(hour, sun) => {
                    hours.push(hour);
                    positions.push(sun);
                }
            }
        }
        if below > 0 {
            warnings.push(format!(
                "{below} hours report diffuse light with the sun below the horizon at mid-hour: counted as dark"
            ));
        }
        if let Some(first) = refused.first() {
            warnings.push(format!(
                "{} hours have no Perez sky and count as dark (the first: {first})",
                refused.len()
            ));
        }
        let suns = bin_suns(&mut hours, &positions, annual.sun_mf)?;
        Ok(SkyMatrix {
            patches,
            hours,
            records: weather.hours.len(),
            stamps: (weather.hours.iter())
                .map(|h| [h.month, h.day, h.hour, occupied(h, annual) as u32])
                .collect(),
            occupied_records,
            suns,
            warnings,
        })
    }
}

fn occupied(h: &WeatherHour, annual: &Annual) -> bool {
    let t = h.sun_time_h();
    annual.occupied_hours[0] <= t && t < annual.occupied_hours[1]
}

/// The sun's unit direction at a record's sun time.
fn sun_of(weather: &Weather, h: &WeatherHour) -> Result<DVec3> {
    let t = h.sun_time_h();
    let (hour, rest) = (t.floor(), (t - t.floor()) * 60.0);
    let (minute, second) = (rest.floor(), (rest - rest.floor()) * 60.0);
    let l = &weather.location;
    let date = [SOLAR_YEAR, h.month as f64, h.day as f64];
    let (altitude, azimuth) = solar_position(
        l.latitude_deg,
        l.longitude_deg,
        l.timezone_h,
        date,
        [hour, minute, second],
    )
    .map_err(|e| Error::input(format!("weather line {}", h.line), e))?;
    Ok(direction(altitude, azimuth))
}

fn record_sky(
    weather: &Weather,
    h: &WeatherHour,
    record: usize,
    patches: &SkyPatches,
    annual: &Annual,
) -> Result<RecordSky> {
    let (Some(dni), Some(dhi)) = (h.direct_normal_wm2, h.diffuse_horizontal_wm2) else {
        return Ok(RecordSky::Dark);
    };
    if !(dhi > 0.0) {
        return Ok(RecordSky::Dark);
    }
    let sun = sun_of(weather, h)?;
    if !(sun.z > 0.0) {
        return Ok(RecordSky::SunBelowHorizon);
    }
    let (m, d) = (h.month as usize, h.day as usize);
    let day = day_of_year(m, d, false)
        .or_else(|| day_of_year(m, d, true))
        .unwrap_or(1) as f64;
    let input = PerezInput {
        direct_normal_wm2: dni,
        diffuse_horizontal_wm2: dhi,
        sun,
        day_of_year: day,
        dew_point_c: h.dew_point_c.unwrap_or(DEFAULT_DEW_POINT_C),
    };
    let perez = match PerezSky::new(&input) {
        Ok(p) => p,
        Err(why) => return Ok(RecordSky::Refused(format!("line {}: {why}", h.line))),
    };
    // The sky at unit scale, then scaled to the hour's diffuse horizontal illuminance
    // by its own integral, summed over the patches from the points their means take.
    let sky = Sky {
        model: SkyModel::Perez(perez),
        zenith_luminance_cdm2: 1.0,
        horizontal_lx: 0.0,
        radiant_integral: 0.0,
        ground_reflectance: 0.0,
        portals: Vec::new(),
    };
    let luminance = |w: DVec3| sky.luminance(w);
    let parts: Vec<(f64, f64)> = (0..patches.len())
        .map(|k| patches.integrals_over(k, &luminance))
        .collect();
    let horizontal: f64 = parts.iter().map(|p| p.1).sum();
    if !(horizontal > 0.0) {
        return Ok(RecordSky::Refused(format!(
            "line {}: the Perez luminance is 0 everywhere",
            h.line
        )));
    }
    let scale = perez.diffuse_horizontal_lx / horizontal;
    let means: Vec<f32> = parts.iter().map(|p| (p.0 * scale) as f32).collect();
    let direct_normal = perez.direct_normal_lx;
    let global = perez.diffuse_horizontal_lx + direct_normal * sun.z;
    let lit_sun = (direct_normal > 0.0).then_some(sun);
    Ok(RecordSky::Lit(
        SkyHour {
            record,
            occupied: occupied(h, annual),
            patches: means,
            ground_cdm2: annual.ground_reflectance * global / PI,
            sun: lit_sun.map(|_| (usize::MAX, direct_normal)),
            sun_position: sun,
            diffuse_horizontal_lx: perez.diffuse_horizontal_lx,
            global_horizontal_lx: global,
        },
        lit_sun,
    ))
}

/// Bins the hours' suns: on Reinhart MF:`sun_mf` patches (each bin at the direct-
/// normal-weighted mean position of its hours), or each hour its own (`sun_mf` 0).
fn bin_suns(hours: &mut [SkyHour], positions: &[Option<DVec3>], sun_mf: u32) -> Result<Vec<DVec3>> {
    let grid = match sun_mf {
        0 => None,
        mf => Some(SkyPatches::reinhart(mf, "annual.sun_mf")?),
    };
    let mut bin_of_patch = std::collections::BTreeMap::new();
    let mut sums: Vec<DVec3> = Vec::new();
    for (hour, position) in hours.iter_mut().zip(positions) {
        let (Some(w), Some((bin, e))) = (position, hour.sun.as_mut()) else {
            continue;
        };
        let key = match &grid {
            Some(g) => g.index(*w).unwrap_or(0),
            None => sums.len(),
        };
        let next = sums.len();
        let b = *bin_of_patch.entry(key).or_insert(next);
        if b == sums.len() {
            sums.push(DVec3::ZERO);
        }
        sums[b] += *w * *e;
        *bin = b;
    }
    Ok(sums.into_iter().map(DVec3::normalize).collect())
}

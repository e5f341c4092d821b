//! The `[annual]` table: a year of daylight from a weather file (docs/daylight.md,
//! *Annual daylight*), validated into [`Annual`]; the annual run (`luxtally annual`) runs it.

use super::Receiver;
use crate::error::{Error, Result};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The table as written.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct AnnualFile {
    /// EPW (or WEA) file, relative to the scene file.
    pub weather: String,
    /// Reinhart MF of the sky patches (1 = Tregenza's 145).
    pub mf: Option<u32>,
    /// Reinhart MF of the grid the year's suns are binned on; 0: every hour its own sun.
    pub sun_mf: Option<u32>,
    pub ground_reflectance: Option<f64>,
    /// Analysis hours, local standard time: [start, end), hours after midnight.
    pub occupied_hours: Option<[f64; 2]>,
    /// The receivers analysed (default: every illuminance receiver).
    pub receivers: Option<Vec<String>>,
    /// Transmittance of the blinds the 2 % rule closes (LM-83's sDA).
    pub shade_transmittance: Option<f64>,
    /// Photons of the first round, over all sources.
    pub photons: Option<u64>,
    /// At most this many photons over all sources.
    pub max_photons: Option<u64>,
    /// Stop once every analysed receiver's sDA300/50 % interval is at most ± this
    /// (fraction of the area).
    pub sda_halfwidth: Option<f64>,
}

/// A validated `[annual]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct Annual {
    pub weather: PathBuf,
    pub mf: u32,
    pub sun_mf: u32,
    pub ground_reflectance: f64,
    pub occupied_hours: [f64; 2],
    /// Indices into the scene's receivers.
    pub receivers: Vec<usize>,
    pub shade_transmittance: f64,
    pub photons: u64,
    pub max_photons: u64,
    pub sda_halfwidth: Option<f64>,
}

/// Sky patches by default: MF 2 (577 patches), as Radiance's 2-phase method is often run.
pub const DEFAULT_MF: u32 = 2;
/// Sun bins by default: MF 6 (5185 positions, Radiance's 5-phase suns; only the bins the
/// year's sun passes through are traced).
pub const DEFAULT_SUN_MF: u32 = 6;
/// LEED v4's analysis hours, 08:00–18:00.
pub const DEFAULT_OCCUPIED: [f64; 2] = [8.0, 18.0];
/// Honeybee's default for the blinds of the 2 % rule.
pub const DEFAULT_SHADE_TRANSMITTANCE: f64 = 0.05;
pub const DEFAULT_PHOTONS: u64 = 1 << 20;
pub const DEFAULT_MAX_PHOTONS: u64 = 1 << 26;

impl AnnualFile {
    /// Validates the table (`at` names it) against the scene's receivers.
    pub fn validate(self, at: &str, base_dir: &Path, receivers: &[Receiver]) -> Result<Annual> {
        let key = |k: &str| format!("{at}.{k}");
        let mf = self.mf.unwrap_or(DEFAULT_MF);
        crate::light::patches::SkyPatches::reinhart(mf, &key("mf"))?;
        let sun_mf = self.sun_mf.unwrap_or(DEFAULT_SUN_MF);
        if sun_mf != 0 {
            crate::light::patches::SkyPatches::reinhart(sun_mf, &key("sun_mf"))?;
        }
        let fraction = |x: Option<f64>, k: &str, default: f64| match x {
            Some(v) if (0.0..=1.0).contains(&v) => Ok(v),
            Some(v) => Err(Error::input(key(k), format!("must be within 0…1, got {v}"))),
            None => Ok(default),
        };
        let ground_reflectance = fraction(self.ground_reflectance, "ground_reflectance", 0.2)?;
        let shade_transmittance = fraction(
            self.shade_transmittance,
            "shade_transmittance",
            DEFAULT_SHADE_TRANSMITTANCE,
        )?;
        let occupied_hours = self.occupied_hours.unwrap_or(DEFAULT_OCCUPIED);
        let [a, b] = occupied_hours;
        if !(0.0 <= a && a < b && b <= 24.0) {
            return Err(Error::input(
                key("occupied_hours"),
                format!("must be [start, end) with 0 ≤ start < end ≤ 24, got [{a}, {b}]"),
            ));
        }
        let receivers = self.chosen_receivers(&key("receivers"), receivers)?;
        let photons = self.photons.unwrap_or(DEFAULT_PHOTONS);
        let max_photons = self.max_photons.unwrap_or(DEFAULT_MAX_PHOTONS.max(photons));
        if photons == 0 || max_photons < photons {
            return Err(Error::input(
                key("photons"),
                format!("must be > 0 and at most max_photons ({max_photons}), got {photons}"),
            ));
        }
        if let Some(h) = self.sda_halfwidth.filter(|h| !(*h > 0.0 && *h < 1.0)) {
            return Err(Error::input(
                key("sda_halfwidth"),
                format!("must be within (0, 1), got {h}"),
            ));
        }
        Ok(Annual {
            weather: base_dir.join(&self.weather),
            mf,
            sun_mf,
            ground_reflectance,
            occupied_hours,
            receivers,
            shade_transmittance,
            photons,
            max_photons,
            sda_halfwidth: self.sda_halfwidth,
        })
    }

    fn chosen_receivers(&self, at: &str, receivers: &[Receiver]) -> Result<Vec<usize>> {
        let illuminance = |r: &Receiver| {
            !r.name.starts_with("observer:") && r.quantity == super::Quantity::Illuminance
        };
        let chosen: Vec<usize> = match &self.receivers {
            None => (0..receivers.len())
                .filter(|&i| illuminance(&receivers[i]))
                .collect(),
            Some(names) => names
                .iter()
                .map(|n| match receivers.iter().position(|r| &r.name == n) {
                    Some(i) if illuminance(&receivers[i]) => Ok(i),
                    Some(_) => Err(Error::input(
                        at,
                        format!("`{n}` is not an illuminance receiver"),
                    )),
                    None => Err(Error::input(at, format!("no receiver is named `{n}`"))),
                })
                .collect::<Result<_>>()?,
        };
        if chosen.is_empty() {
            return Err(Error::input(
                at,
                "the scene has no illuminance receiver to analyse",
            ));
        }
        Ok(chosen)
    }
}

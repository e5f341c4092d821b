//! Weather files: EnergyPlus EPW (8 header lines, then one record per hour), read into
//! the site and the hourly irradiance, illuminance and dew point the Perez sky needs
//! (docs/daylight.md, *Weather files*). Not yet wired into runs: the annual run will
//! make one sky per record. `luxtally weather FILE` prints its summary.
//!
//! Time: a record stamped hour h (1–24) covers the interval (h − 1, h] of local
//! standard time; its sun is evaluated at the midpoint, h − 0.5 ([`WeatherHour::sun_time_h`]).

use crate::error::{Error, Result};
use std::path::Path;

/// The site of LOCATION.
#[derive(Clone, Debug, PartialEq)]
pub struct Location {
    pub city: String,
    pub latitude_deg: f64,
    /// Positive east.
    pub longitude_deg: f64,
    /// Hours ahead of UTC, positive east (standard time).
    pub timezone_h: f64,
    pub elevation_m: f64,
}

/// One hourly record; `None` where the file holds its missing-value code.
#[derive(Clone, Debug, PartialEq)]
pub struct WeatherHour {
    /// 1-based line of the file.
    pub line: usize,
    pub month: u32,
    pub day: u32,
    /// 1–24: the interval (hour − 1, hour].
    pub hour: u32,
    pub dew_point_c: Option<f64>,
    pub global_horizontal_wm2: Option<f64>,
    pub direct_normal_wm2: Option<f64>,
    pub diffuse_horizontal_wm2: Option<f64>,
    pub global_horizontal_lx: Option<f64>,
    pub direct_normal_lx: Option<f64>,
    pub diffuse_horizontal_lx: Option<f64>,
}

impl WeatherHour {
    /// The local standard time its sun is evaluated at, hours after midnight: the
    /// interval's midpoint, hour − 0.5 (as Radiance's loadEPW for hourly files).
    pub fn sun_time_h(&self) -> f64 {
        self.hour as f64 - 0.5
    }

    /// Whether the Perez inputs (direct normal and diffuse horizontal irradiance) are
    /// both present.
    pub fn has_irradiance(&self) -> bool {
        self.direct_normal_wm2.is_some() && self.diffuse_horizontal_wm2.is_some()
    }
}

/// A read weather file.
#[derive(Clone, Debug, PartialEq)]
pub struct Weather {
    pub location: Location,
    pub hours: Vec<WeatherHour>,
    /// Records missing direct normal or diffuse horizontal irradiance.
    pub missing_hours: usize,
    /// One line each: missing-value hours counted, a time zone far from the longitude.
    pub warnings: Vec<String>,
}

/// Fields of an EPW record.
const FIELDS: usize = 35;

/// Reads an EPW file.
pub fn read_epw(path: &Path) -> Result<Weather> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_epw(&text, &path.display().to_string())
}

/// Parses EPW `text`; errors are one line naming `origin` and the line.
pub fn parse_epw(text: &str, origin: &str) -> Result<Weather> {
    let lines: Vec<&str> = text.lines().collect();
    if lines.len() < 8 {
        return Err(Error::input(
            origin,
            format!(
                "{} lines: an EPW file has 8 header lines before its records (truncated?)",
                lines.len()
            ),
        ));
    }
    let location = location(lines[0], origin)?;
    let expected = expected_records(lines[4], lines[7], origin)?;
    let mut hours = Vec::with_capacity(expected);
    for (i, line) in lines.iter().enumerate().skip(8) {
        if line.trim().is_empty() {
            continue;
        }
        hours.push(record(line, i + 1, origin)?);
    }
    if hours.len() != expected {
        return Err(Error::input(
            origin,
            format!(
                "{} hourly records, but DATA PERIODS (line 8) makes {expected} (a truncated file?)",
                hours.len()
            ),
        ));
    }
    let missing: Vec<&WeatherHour> = hours.iter().filter(|h| !h.has_irradiance()).collect();
    let mut warnings = Vec::new();
    if let Some(first) = missing.first() {
        warnings.push(format!(
            "{origin}: {} of {} hours miss direct normal or diffuse horizontal irradiance \
             (9999), the first at line {}: they will have no sky",
            missing.len(),
            hours.len(),
            first.line
        ));
    }
    let solar_h = location.longitude_deg / 15.0;
    if (location.timezone_h - solar_h).abs() > 2.0 {
        warnings.push(format!(
            "{origin}: line 1: time zone {:+} h is {:.1} h from the longitude's {:+.2} h \
             ({}°): EPW counts both positive east (WEA and Radiance count west)",
            location.timezone_h,
            (location.timezone_h - solar_h).abs(),
            solar_h,
            location.longitude_deg
        ));
    }
    Ok(Weather {
        location,
        missing_hours: missing.len(),
        hours,
        warnings,
    })
}

/// LOCATION,city,state,country,source,WMO,lat,lon,tz,elev.
fn location(line: &str, origin: &str) -> Result<Location> {
    let at = format!("{origin}: line 1");
    let f: Vec<&str> = line.split(',').map(str::trim).collect();
    if f.first().map(|s| s.to_ascii_uppercase()) != Some("LOCATION".into()) || f.len() < 10 {
        return Err(Error::input(
            at,
            "expected LOCATION,city,state,country,source,WMO,latitude,longitude,time zone,elevation",
        ));
    }
    let number = |k: usize, what: &str, lo: f64, hi: f64| -> Result<f64> {
        match f[k].parse::<f64>() {
            Ok(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
            _ => Err(Error::input(
                at.clone(),
                format!(
                    "field {}: {what} `{}` is not a number within {lo}…{hi}",
                    k + 1,
                    f[k]
                ),
            )),
        }
    };
    Ok(Location {
        city: f[1].to_string(),
        latitude_deg: number(6, "latitude", -90.0, 90.0)?,
        longitude_deg: number(7, "longitude", -180.0, 180.0)?,
        timezone_h: number(8, "time zone", -14.0, 14.0)?,
        elevation_m: number(9, "elevation", -1000.0, 9000.0)?,
    })
}

/// The records DATA PERIODS announces: one period of 1 record per hour from M/D to
/// M/D, a leap day included when HOLIDAYS/DAYLIGHT SAVINGS says the year has one.
fn expected_records(holidays: &str, periods: &str, origin: &str) -> Result<usize> {
    let at = format!("{origin}: line 8");
    let f: Vec<&str> = periods.split(',').map(str::trim).collect();
    let bad = || {
        Error::input(
            at.clone(),
            "expected DATA PERIODS,1,1,name,start weekday,M/D,M/D (one hourly period)",
        )
    };
    if f.first().map(|s| s.to_ascii_uppercase()) != Some("DATA PERIODS".into()) || f.len() < 7 {
        return Err(bad());
    }
    if f[1] != "1" || f[2] != "1" {
        return Err(Error::input(
            at,
            format!(
                "{} periods of {} records per hour: only one hourly period is supported",
                f[1], f[2]
            ),
        ));
    }
    let leap = holidays
        .split(',')
        .nth(1)
        .map(|s| s.trim().eq_ignore_ascii_case("yes"))
        == Some(true);
    let day = |s: &str| -> Option<usize> {
        let (m, d) = s.split_once('/')?;
        day_of_year(m.trim().parse().ok()?, d.trim().parse().ok()?, leap)
    };
    match (day(f[5]), day(f[6])) {
        (Some(a), Some(b)) if b >= a => Ok((b - a + 1) * 24),
        _ => Err(bad()),
    }
}

/// The day of the year (1 January = 1) of month `m`, day `d`, or None if there is no
/// such day.
pub fn day_of_year(m: usize, d: usize, leap: bool) -> Option<usize> {
    let lengths = [
        31,
        28 + leap as usize,
        31,
        30,
        31,
        30,
        31,
        31,
        30,
        31,
        30,
        31,
    ];
    ((1..=12).contains(&m) && (1..=lengths[m - 1]).contains(&d))
        .then(|| lengths[..m - 1].iter().sum::<usize>() + d)
}

/// One record (line `n`, 1-based).
fn record(line: &str, n: usize, origin: &str) -> Result<WeatherHour> {
    let at = format!("{origin}: line {n}");
    let f: Vec<&str> = line.split(',').map(str::trim).collect();
    if f.len() < FIELDS {
        return Err(Error::input(
            at,
            format!(
                "{} fields, an EPW record has {FIELDS} (a truncated line?)",
                f.len()
            ),
        ));
    }
    let value = |k: usize, what: &str| -> Result<f64> {
        match f[k - 1].parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(Error::input(
                at.clone(),
                format!("field {k} ({what}): `{}` is not a number", f[k - 1]),
            )),
        }
    };
    // Radiation's missing code is 9999, illuminance's 999999 (≥ 999900, as loadEPW),
    // the dew point's 99.9; a negative flux is an error, not a missing value.
    let flux = |k: usize, what: &str, missing: f64| -> Result<Option<f64>> {
        let x = value(k, what)?;
        if x >= missing {
            Ok(None)
        } else if x < 0.0 {
            Err(Error::input(
                at.clone(),
                format!("field {k} ({what}): {x} is negative"),
            ))
        } else {
            Ok(Some(x))
        }
    };
    let whole = |k: usize, what: &str, lo: u32, hi: u32| -> Result<u32> {
        match f[k - 1].parse::<u32>() {
            Ok(x) if (lo..=hi).contains(&x) => Ok(x),
            _ => Err(Error::input(
                at.clone(),
                format!(
                    "field {k} ({what}): `{}` is not a whole number within {lo}…{hi}",
                    f[k - 1]
                ),
            )),
        }
    };
    let dew = value(8, "dew point")?;
    Ok(WeatherHour {
        line: n,
        month: whole(2, "month", 1, 12)?,
        day: whole(3, "day", 1, 31)?,
        hour: whole(4, "hour", 1, 24)?,
        dew_point_c: (dew < 99.9).then_some(dew),
        global_horizontal_wm2: flux(14, "global horizontal radiation", 9999.0)?,
        direct_normal_wm2: flux(15, "direct normal radiation", 9999.0)?,
        diffuse_horizontal_wm2: flux(16, "diffuse horizontal radiation", 9999.0)?,
        global_horizontal_lx: flux(17, "global horizontal illuminance", 999_900.0)?,
        direct_normal_lx: flux(18, "direct normal illuminance", 999_900.0)?,
        diffuse_horizontal_lx: flux(19, "diffuse horizontal illuminance", 999_900.0)?,
    })
}

impl Weather {
    /// Annual sums of global horizontal, direct normal and diffuse horizontal
    /// radiation over the records that hold them, kWh/m² (each record is 1 h).
    pub fn radiation_sums_kwh_m2(&self) -> [f64; 3] {
        let sum = |f: fn(&WeatherHour) -> Option<f64>| {
            self.hours.iter().filter_map(f).sum::<f64>() / 1000.0
        };
        [
            sum(|h| h.global_horizontal_wm2),
            sum(|h| h.direct_normal_wm2),
            sum(|h| h.diffuse_horizontal_wm2),
        ]
    }

    /// What `luxtally weather` prints: the site, the records, the missing hours, the
    /// sums, the warnings.
    pub fn summary(&self) -> String {
        let l = &self.location;
        let [g, b, d] = self.radiation_sums_kwh_m2();
        let mut text = format!(
            "{}: latitude {}°, longitude {}° (east positive), time zone UTC{:+} h, elevation {} m\n\
             {} hourly records (hour h = the interval (h−1, h] of local standard time, its sun at h − 0.5), \
             {} missing direct normal or diffuse horizontal irradiance\n\
             radiation sums: global horizontal {g:.1}, direct normal {b:.1}, diffuse horizontal {d:.1} kWh/m²\n",
            l.city, l.latitude_deg, l.longitude_deg, l.timezone_h, l.elevation_m, self.hours.len(), self.missing_hours
        );
        for w in &self.warnings {
            text += &format!("warning: {w}\n");
        }
        text
    }
}

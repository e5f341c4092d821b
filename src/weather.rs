//! Weather files: EnergyPlus EPW (8 header lines, then one record per hour) and
//! DAYSIM/Radiance WEA (6 `key value` header lines, then `month day hour direct diffuse`
//! rows), read into the site and the hourly irradiance, illuminance and dew point the
//! Perez sky needs (docs/daylight.md, *Weather files*). [`read_weather`] picks the reader
//! by the file's extension. The annual run (`luxtally annual`) makes one Perez sky per
//! record. `luxtally weather FILE` prints its summary.
//!
//! Time: a record stamped hour h (1–24) covers the interval (h − 1, h] of local
//! standard time; its sun is evaluated at the midpoint, h − 0.5 ([`WeatherHour::sun_time_h`]).
//! A WEA row's decimal time t is stamped with the interval holding it, h = ⌈t⌉ (t = 0
//! in the first, h = 1); a t other than h − 0.5 is kept and its sun evaluated at t.
//!
//! Signs: [`Location`] counts longitude and time zone positive east, as EPW does; a
//! WEA's `longitude` and `time_zone` (the standard meridian, degrees) count west and
//! are converted: longitude_deg = −longitude, timezone_h = −time_zone/15.

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
    /// The local standard time the file states when it is not the interval's midpoint
    /// (a WEA row's decimal hour other than hour − 0.5); None for EPW records.
    pub stated_time_h: Option<f64>,
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
    /// interval's midpoint, hour − 0.5 (as Radiance's loadEPW for hourly files), or the
    /// time a WEA row states when that is not the midpoint.
    pub fn sun_time_h(&self) -> f64 {
        self.stated_time_h.unwrap_or(self.hour as f64 - 0.5)
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
    let missing = hours.iter().filter(|h| !h.has_irradiance()).count();
    let mut warnings: Vec<String> = missing_warning(&hours, origin).into_iter().collect();
    warnings.extend(timezone_warning(
        &location,
        origin,
        1,
        "EPW counts both positive east (WEA and Radiance count west)",
    ));
    Ok(Weather {
        location,
        missing_hours: missing,
        hours,
        warnings,
    })
}

/// One line counting the hours without direct normal or diffuse horizontal irradiance
/// (their missing-value code, 9999), naming the first; None if there are none.
fn missing_warning(hours: &[WeatherHour], origin: &str) -> Option<String> {
    let missing: Vec<&WeatherHour> = hours.iter().filter(|h| !h.has_irradiance()).collect();
    missing.first().map(|first| {
        format!(
            "{origin}: {} of {} hours miss direct normal or diffuse horizontal irradiance \
             (9999), the first at line {}: they will have no sky",
            missing.len(),
            hours.len(),
            first.line
        )
    })
}

/// One line if the time zone is more than 2 h from longitude/15 (line `line` of the
/// file states it; `note` says how the format counts them), else None.
fn timezone_warning(location: &Location, origin: &str, line: usize, note: &str) -> Option<String> {
    let solar_h = location.longitude_deg / 15.0;
    ((location.timezone_h - solar_h).abs() > 2.0).then(|| {
        format!(
            "{origin}: line {line}: time zone {:+} h is {:.1} h from the longitude's {:+.2} h \
             ({}°): {note}",
            location.timezone_h,
            (location.timezone_h - solar_h).abs(),
            solar_h,
            location.longitude_deg
        )
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
        stated_time_h: None,
        dew_point_c: (dew < 99.9).then_some(dew),
        global_horizontal_wm2: flux(14, "global horizontal radiation", 9999.0)?,
        direct_normal_wm2: flux(15, "direct normal radiation", 9999.0)?,
        diffuse_horizontal_wm2: flux(16, "diffuse horizontal radiation", 9999.0)?,
        global_horizontal_lx: flux(17, "global horizontal illuminance", 999_900.0)?,
        direct_normal_lx: flux(18, "direct normal illuminance", 999_900.0)?,
        diffuse_horizontal_lx: flux(19, "diffuse horizontal illuminance", 999_900.0)?,
    })
}

/// Reads a weather file by its extension, in any case: `.epw` (EnergyPlus) or `.wea`
/// (DAYSIM/Radiance).
pub fn read_weather(path: &Path) -> Result<Weather> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("epw") => read_epw(path),
        Some("wea") => read_wea(path),
        _ => Err(Error::input(
            path.display().to_string(),
            "not a known weather file: expected the extension .epw (EnergyPlus) or .wea (DAYSIM/Radiance)",
        )),
    }
}

/// Reads a WEA file.
pub fn read_wea(path: &Path) -> Result<Weather> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_wea(&text, &path.display().to_string())
}

/// What a WEA row's two values are (`weather_data_file_units`).
#[derive(Clone, Copy, Debug, PartialEq)]
enum WeaUnits {
    /// 1: direct normal and diffuse horizontal irradiance, W/m².
    Irradiance,
    /// 3: direct normal and diffuse horizontal illuminance, lx.
    Illuminance,
}

/// A WEA header: the site, the units and the lines stating them.
struct WeaHeader {
    location: Location,
    units: WeaUnits,
    units_line: usize,
    timezone_line: usize,
    /// `time_zone` as written: the standard meridian, degrees, +west.
    meridian_deg: f64,
    /// 0-based index of the first row.
    first_row: usize,
}

/// The WEA header's keys, in the order Radiance's epw2wea writes them.
const WEA_KEYS: [&str; 6] = [
    "place",
    "latitude",
    "longitude",
    "time_zone",
    "site_elevation",
    "weather_data_file_units",
];

/// Parses WEA `text`; errors are one line naming `origin` and the line.
///
/// The header's keys may come in any order, each once; the rows follow from the first
/// line that starts with a number. Values ≥ 9999 (irradiance) or ≥ 999900
/// (illuminance) read as missing, as EPW's codes; a negative value is an error.
pub fn parse_wea(text: &str, origin: &str) -> Result<Weather> {
    let lines: Vec<&str> = text.lines().collect();
    let header = wea_header(&lines, origin)?;
    let mut hours = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(header.first_row) {
        if line.trim().is_empty() {
            continue;
        }
        hours.push(wea_row(line, i + 1, header.units, origin)?);
    }
    if hours.is_empty() {
        return Err(Error::input(
            origin,
            format!(
                "{} lines: no data rows after the WEA header (truncated?)",
                lines.len()
            ),
        ));
    }
    let missing = hours.iter().filter(|h| !h.has_irradiance()).count();
    let mut warnings = Vec::new();
    match header.units {
        WeaUnits::Irradiance => warnings.extend(missing_warning(&hours, origin)),
        WeaUnits::Illuminance => warnings.push(format!(
            "{origin}: line {}: weather_data_file_units 3: the rows are direct normal and \
             diffuse horizontal illuminance (lx), read as such, with no irradiance: no hour \
             can make a Perez sky",
            header.units_line
        )),
    }
    // Every standard meridian is a whole quarter hour, 3.75°: another time_zone is
    // likely hours written for degrees (−1 for UTC+1, which should be −15).
    let meridian = header.meridian_deg;
    if (meridian / 3.75).fract().abs() > 1e-9 {
        warnings.push(format!(
            "{origin}: line {}: time_zone {meridian}° is no whole quarter hour (3.75°): \
             hours given for degrees? (WEA's time_zone is the standard meridian, +west, \
             −15 × the hours ahead of UTC)",
            header.timezone_line
        ));
    }
    warnings.extend(timezone_warning(
        &header.location,
        origin,
        header.timezone_line,
        "WEA counts longitude and time_zone (the standard meridian, degrees) positive west",
    ));
    Ok(Weather {
        location: header.location,
        missing_hours: missing,
        hours,
        warnings,
    })
}

/// The header lines up to the first row: each of [`WEA_KEYS`] once, with its value.
fn wea_header(lines: &[&str], origin: &str) -> Result<WeaHeader> {
    let mut values: [Option<(usize, &str)>; 6] = [None; 6];
    let mut first_row = lines.len();
    for (i, line) in lines.iter().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if line.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+' || c == '.') {
            first_row = i;
            break;
        }
        let (key, value) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let at = format!("{origin}: line {}", i + 1);
        let Some(k) = WEA_KEYS.iter().position(|w| w.eq_ignore_ascii_case(key)) else {
            return Err(Error::input(
                at,
                format!("`{key}` is not a WEA header key ({})", WEA_KEYS.join(", ")),
            ));
        };
        if let Some((before, _)) = values[k] {
            return Err(Error::input(
                at,
                format!("`{key}` again (line {before} states it already)"),
            ));
        }
        values[k] = Some((i + 1, value.trim()));
    }
    if let Some(k) = values.iter().position(Option::is_none) {
        return Err(Error::input(
            format!("{origin}: line {}", first_row + 1),
            format!(
                "the WEA header lacks `{}` (it needs {})",
                WEA_KEYS[k],
                WEA_KEYS.join(", ")
            ),
        ));
    }
    let value = |k: usize| values[k].expect("checked above");
    let number = |k: usize, lo: f64, hi: f64| -> Result<f64> {
        let (n, v) = value(k);
        match v.parse::<f64>() {
            Ok(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
            _ => Err(Error::input(
                format!("{origin}: line {n}"),
                format!("{}: `{v}` is not a number within {lo}…{hi}", WEA_KEYS[k]),
            )),
        }
    };
    let (units_line, units) = value(5);
    let units = wea_units(units, &format!("{origin}: line {units_line}"))?;
    // WEA counts west: longitude +W, time_zone the standard meridian in degrees +W.
    let meridian_deg = number(3, -210.0, 210.0)?;
    let location = Location {
        city: value(0).1.to_string(),
        latitude_deg: number(1, -90.0, 90.0)?,
        longitude_deg: 0.0 - number(2, -180.0, 180.0)?,
        timezone_h: 0.0 - meridian_deg / 15.0,
        elevation_m: number(4, -1000.0, 9000.0)?,
    };
    Ok(WeaHeader {
        location,
        units,
        units_line,
        timezone_line: value(3).0,
        meridian_deg,
        first_row,
    })
}

/// `weather_data_file_units`: 1 and 3 are read, 2 is refused (`at` names the line).
fn wea_units(value: &str, at: &str) -> Result<WeaUnits> {
    match value {
        "1" => Ok(WeaUnits::Irradiance),
        "3" => Ok(WeaUnits::Illuminance),
        "2" => Err(Error::input(
            at,
            "weather_data_file_units 2 (direct horizontal irradiance) is not supported: \
             its direct normal needs the sun's altitude per row; write the file with \
             units 1 (direct normal, as epw2wea does)",
        )),
        other => Err(Error::input(
            at,
            format!("weather_data_file_units `{other}` is not 1, 2 or 3"),
        )),
    }
}

/// One WEA row (line `n`, 1-based): month, day, decimal local standard time, then the
/// direct normal and diffuse horizontal values in `units`.
fn wea_row(line: &str, n: usize, units: WeaUnits, origin: &str) -> Result<WeatherHour> {
    let at = format!("{origin}: line {n}");
    let f: Vec<&str> = line.split_whitespace().collect();
    if f.len() != 5 {
        return Err(Error::input(
            at,
            format!(
                "{} fields, a WEA row has 5: month day hour direct diffuse (a truncated line?)",
                f.len()
            ),
        ));
    }
    let whole = |k: usize, what: &str, hi: u32| -> Result<u32> {
        match f[k - 1].parse::<u32>() {
            Ok(x) if (1..=hi).contains(&x) => Ok(x),
            _ => Err(Error::input(
                at.clone(),
                format!(
                    "field {k} ({what}): `{}` is not a whole number within 1…{hi}",
                    f[k - 1]
                ),
            )),
        }
    };
    let month = whole(1, "month", 12)?;
    let day = whole(2, "day", 31)?;
    if day_of_year(month as usize, day as usize, true).is_none() {
        return Err(Error::input(at, format!("month {month} has no day {day}")));
    }
    let t = match f[2].parse::<f64>() {
        Ok(t) if (0.0..=24.0).contains(&t) => t,
        _ => {
            return Err(Error::input(
                at,
                format!(
                    "field 3 (hour): `{}` is not a decimal hour within 0…24 (local standard time)",
                    f[2]
                ),
            ))
        }
    };
    // The interval (h − 1, h] holding t; t = 0 belongs to the first.
    let hour = (libm::ceil(t) as u32).max(1);
    let (missing, what) = match units {
        WeaUnits::Irradiance => (9999.0, "irradiance"),
        WeaUnits::Illuminance => (999_900.0, "illuminance"),
    };
    let value = |k: usize, name: &str| -> Result<Option<f64>> {
        let what = format!("{name} {what}");
        match f[k - 1].parse::<f64>() {
            Ok(x) if x.is_finite() && x >= missing => Ok(None),
            Ok(x) if x.is_finite() && x >= 0.0 => Ok(Some(x)),
            Ok(x) if x < 0.0 => Err(Error::input(
                at.clone(),
                format!("field {k} ({what}): {x} is negative"),
            )),
            _ => Err(Error::input(
                at.clone(),
                format!("field {k} ({what}): `{}` is not a number", f[k - 1]),
            )),
        }
    };
    let direct = value(4, "direct normal")?;
    let diffuse = value(5, "diffuse horizontal")?;
    let (wm2, lx) = match units {
        WeaUnits::Irradiance => ((direct, diffuse), (None, None)),
        WeaUnits::Illuminance => ((None, None), (direct, diffuse)),
    };
    Ok(WeatherHour {
        line: n,
        month,
        day,
        hour,
        stated_time_h: (t != hour as f64 - 0.5).then_some(t),
        dew_point_c: None,
        global_horizontal_wm2: None,
        direct_normal_wm2: wm2.0,
        diffuse_horizontal_wm2: wm2.1,
        global_horizontal_lx: None,
        direct_normal_lx: lx.0,
        diffuse_horizontal_lx: lx.1,
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
    /// sums (— for a quantity no record holds: WEA has no global horizontal), the
    /// warnings.
    pub fn summary(&self) -> String {
        let l = &self.location;
        let sums = self.radiation_sums_kwh_m2();
        let held: [fn(&WeatherHour) -> bool; 3] = [
            |h| h.global_horizontal_wm2.is_some(),
            |h| h.direct_normal_wm2.is_some(),
            |h| h.diffuse_horizontal_wm2.is_some(),
        ];
        let [g, b, d] = std::array::from_fn(|k| {
            if self.hours.iter().any(held[k]) {
                format!("{:.1}", sums[k])
            } else {
                "—".to_string()
            }
        });
        let stated = self
            .hours
            .iter()
            .filter(|h| h.stated_time_h.is_some())
            .count();
        let sun = if stated == 0 {
            "its sun at h − 0.5".to_string()
        } else {
            format!("its sun at h − 0.5, or at the file's stated time for {stated}")
        };
        let mut text = format!(
            "{}: latitude {}°, longitude {}° (east positive), time zone UTC{:+} h, elevation {} m\n\
             {} hourly records (hour h = the interval (h−1, h] of local standard time, {sun}), \
             {} missing direct normal or diffuse horizontal irradiance\n\
             radiation sums: global horizontal {g}, direct normal {b}, diffuse horizontal {d} kWh/m²\n",
            l.city, l.latitude_deg, l.longitude_deg, l.timezone_h, l.elevation_m, self.hours.len(), self.missing_hours
        );
        for w in &self.warnings {
            text += &format!("warning: {w}\n");
        }
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(text: &str) -> WeatherHour {
        wea_row(text, 7, WeaUnits::Irradiance, "t.wea").unwrap()
    }

    /// t → the interval (h − 1, h] holding it, t = 0 in the first; the midpoint is
    /// EPW's convention (no stated time), any other t is kept for the sun.
    #[test]
    fn wea_times_map_to_their_interval() {
        for (t, hour, stated) in [
            ("0", 1, Some(0.0)),
            ("0.5", 1, None),
            ("1", 1, Some(1.0)),
            ("1.0001", 2, Some(1.0001)),
            ("11.5", 12, None),
            ("23.99", 24, Some(23.99)),
            ("24", 24, Some(24.0)),
        ] {
            let h = row(&format!("6 21 {t} 800 100"));
            assert_eq!((h.hour, h.stated_time_h), (hour, stated), "t = {t}");
            assert_eq!(h.sun_time_h(), stated.unwrap_or(hour as f64 - 0.5));
        }
        assert_eq!(
            row("2 29 12.5 0 0").day,
            29,
            "a WEA has no year: 29 February is a day"
        );
    }

    #[test]
    fn wea_signs_become_east_positive() {
        let text = "place X\nlatitude -33.9\nlongitude -151.2\ntime_zone -150\n\
                    site_elevation 3\nweather_data_file_units 1\n1 1 12.5 800 100\n";
        let l = parse_wea(text, "t.wea").unwrap().location;
        assert_eq!(
            (l.latitude_deg, l.longitude_deg, l.timezone_h),
            (-33.9, 151.2, 10.0)
        );
    }
}

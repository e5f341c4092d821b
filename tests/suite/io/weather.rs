//! Weather files beyond EPW's own tests (physics::perez): the WEA reader against an EPW
//! of the same hours (signs converted, same stamps and values), its time convention,
//! illuminance files, its warnings and one-line errors, `read_weather`'s choice by
//! extension, and the bundled EPW (scenes/weather/) read whole.

use crate::common;

use common::{epw, BERLIN};
use luxtally::light::sun::solar_position;
use luxtally::weather::{parse_epw, parse_wea, read_weather, WeatherHour};
use std::path::{Path, PathBuf};

/// Berlin's WEA header: 13.40° E is longitude −13.40 in WEA, UTC+1 the meridian −15°.
const BERLIN_WEA: &str = "place Berlin\nlatitude 52.47\nlongitude -13.40\ntime_zone -15\n\
                          site_elevation 49.0\nweather_data_file_units 1\n";

/// The WEA of an EPW's records: `month day h−0.5 DNI DHI` per record (fields 2, 3, 4,
/// 15, 16), as Radiance's epw2wea writes them, after `header`.
fn wea_of(epw_text: &str, header: &str) -> String {
    let mut t = header.to_string();
    for line in epw_text.lines().skip(8) {
        let f: Vec<&str> = line.split(',').collect();
        let h: f64 = f[3].parse().unwrap();
        t += &format!("{} {} {:.3} {} {}\n", f[1], f[2], h - 0.5, f[14], f[15]);
    }
    t
}

fn wea(text: &str) -> luxtally::weather::Weather {
    parse_wea(text, "b.wea").unwrap_or_else(|e| panic!("{e}"))
}

/// What an hour says about the sky: its stamp, sun time and Perez inputs.
fn sky_inputs(h: &WeatherHour) -> (u32, u32, u32, f64, Option<f64>, Option<f64>) {
    (
        h.month,
        h.day,
        h.hour,
        h.sun_time_h(),
        h.direct_normal_wm2,
        h.diffuse_horizontal_wm2,
    )
}

#[test]
fn a_wea_reads_as_the_epw_of_the_same_hours() {
    let e = parse_epw(&epw(BERLIN, 2), "b.epw").unwrap();
    let w = wea(&wea_of(&epw(BERLIN, 2), BERLIN_WEA));
    assert_eq!(w.location, e.location, "signs converted to +east");
    assert_eq!(
        (w.location.longitude_deg, w.location.timezone_h),
        (13.4, 1.0)
    );
    assert_eq!((w.hours.len(), w.missing_hours), (48, 0));
    assert!(w.warnings.is_empty(), "{:?}", w.warnings);
    for (a, b) in w.hours.iter().zip(&e.hours) {
        assert_eq!(sky_inputs(a), sky_inputs(b));
        assert_eq!(
            a.stated_time_h, None,
            "mid-interval times are the EPW convention"
        );
        assert_eq!(a.line, b.line - 2, "6 header lines against EPW's 8");
        assert_eq!((a.dew_point_c, a.global_horizontal_wm2), (None, None));
    }
    let [_, b, d] = w.radiation_sums_kwh_m2();
    let [_, eb, ed] = e.radiation_sums_kwh_m2();
    assert_eq!((b, d), (eb, ed));
    assert!(
        w.summary().contains("global horizontal —"),
        "{}",
        w.summary()
    );
    // The far west: 105.18° W in UTC−7 is longitude 105.18, meridian 105 in WEA.
    let golden = "LOCATION,Golden,CO,USA,test,724666,39.74,-105.18,-7.0,1829.0";
    let header = "place Golden\nlatitude 39.74\nlongitude 105.18\ntime_zone 105\n\
                  site_elevation 1829\nweather_data_file_units 1\n";
    let e = parse_epw(&epw(golden, 1), "g.epw").unwrap();
    let w = wea(&wea_of(&epw(golden, 1), header));
    assert_eq!(w.location, e.location);
    assert!(w.warnings.is_empty(), "{:?}", w.warnings);
}

/// A WEA time t is stamped with the interval (h − 1, h] holding it (t = 0 in the first);
/// one that is not h − 0.5 is kept, and the sun is evaluated there.
#[test]
fn wea_times_off_the_midpoint_are_kept() {
    let rows =
        "1 1 0 0 0\n1 1 0.5 0 0\n1 1 12 500 62\n1 1 12.25 500 62\n1 1 23.5 0 0\n1 1 24 0 0\n";
    let w = wea(&format!("{BERLIN_WEA}{rows}"));
    let got: Vec<(u32, Option<f64>, f64)> = w
        .hours
        .iter()
        .map(|h| (h.hour, h.stated_time_h, h.sun_time_h()))
        .collect();
    assert_eq!(
        got,
        [
            (1, Some(0.0), 0.0),
            (1, None, 0.5),
            (12, Some(12.0), 12.0),
            (13, Some(12.25), 12.25),
            (24, None, 23.5),
            (24, Some(24.0), 24.0),
        ]
    );
    assert!(
        w.summary().contains("at the file's stated time for 4"),
        "{}",
        w.summary()
    );
}

/// Units 3: the values are illuminance, read into the illuminance fields; irradiance is
/// none, every hour counts as missing it, and one warning says why.
#[test]
fn an_illuminance_wea_fills_the_illuminance_fields() {
    let text = format!("{BERLIN_WEA}1 1 12.5 50000 6820\n1 1 13.5 999999 6000\n")
        .replace("units 1", "units 3");
    let w = wea(&text);
    let h = &w.hours[0];
    assert_eq!(
        (h.direct_normal_lx, h.diffuse_horizontal_lx),
        (Some(50_000.0), Some(6820.0))
    );
    assert_eq!(
        (h.direct_normal_wm2, h.diffuse_horizontal_wm2),
        (None, None)
    );
    assert_eq!(w.hours[1].direct_normal_lx, None, "999999 is missing");
    assert_eq!(w.missing_hours, 2);
    assert_eq!(
        w.warnings,
        [
            "b.wea: line 6: weather_data_file_units 3: the rows are direct normal and diffuse \
          horizontal illuminance (lx), read as such, with no irradiance: no hour can make a \
          Perez sky"
        ]
    );
}

#[test]
fn wea_missing_hours_and_time_zones_are_counted_warnings() {
    let text = wea_of(&epw(BERLIN, 2), BERLIN_WEA).replacen(" 500 62", " 9999 62", 2);
    let w = wea(&text);
    assert_eq!((w.missing_hours, w.hours[11].direct_normal_wm2), (2, None));
    assert_eq!(w.warnings, ["b.wea: 2 of 48 hours miss direct normal or diffuse horizontal irradiance (9999), the first at line 18: they will have no sky"]);
    // A site west of Greenwich in a western zone, both +west: no warning.
    let one_row = |header: String| wea(&(header + "1 1 12.5 500 62\n"));
    let w = one_row(BERLIN_WEA.replace("-13.40", "13.40").replace("-15", "15"));
    assert!(w.warnings.is_empty(), "{:?}", w.warnings);
    // 13.40° E kept in UTC−2 (meridian 30° W): 2.9 h apart.
    let w = one_row(BERLIN_WEA.replace("-15", "30"));
    assert_eq!(w.warnings, ["b.wea: line 4: time zone -2 h is 2.9 h from the longitude's +0.89 h (13.4°): WEA counts longitude and time_zone (the standard meridian, degrees) positive west"]);
    // Hours written for degrees: −1 for UTC+1.
    let w = one_row(BERLIN_WEA.replace("-15", "-1"));
    assert_eq!(w.warnings, ["b.wea: line 4: time_zone -1° is no whole quarter hour (3.75°): hours given for degrees? (WEA's time_zone is the standard meridian, +west, −15 × the hours ahead of UTC)"]);
}

#[test]
fn bad_wea_files_are_refused_in_one_line() {
    let good = wea_of(&epw(BERLIN, 1), BERLIN_WEA);
    let lines: Vec<&str> = good.lines().collect();
    let with = |k: usize, row: &str| {
        let mut l = lines.clone();
        l[k] = row;
        l.join("\n")
    };
    let cases = [
        (
            lines[..19].join("\n") + "\n" + &lines[19][..8],
            "b.wea: line 20: 3 fields, a WEA row has 5: month day hour direct diffuse (a truncated line?)",
        ),
        (
            with(18, "1 1 12.5 5OO 62"),
            "b.wea: line 19: field 4 (direct normal irradiance): `5OO` is not a number",
        ),
        (
            with(18, "1 1 12.5 500 NaN"),
            "b.wea: line 19: field 5 (diffuse horizontal irradiance): `NaN` is not a number",
        ),
        (
            with(18, "1 1 12.5 -3 62"),
            "b.wea: line 19: field 4 (direct normal irradiance): -3 is negative",
        ),
        (
            with(18, "1 1 24.5 500 62"),
            "b.wea: line 19: field 3 (hour): `24.5` is not a decimal hour within 0…24 (local standard time)",
        ),
        (
            with(18, "13 1 12.5 500 62"),
            "b.wea: line 19: field 1 (month): `13` is not a whole number within 1…12",
        ),
        (with(18, "2 30 12.5 500 62"), "b.wea: line 19: month 2 has no day 30"),
        (
            with(3, "site_elevation 49.0"),
            "b.wea: line 5: `site_elevation` again (line 4 states it already)",
        ),
        (
            good.replace("time_zone -15\n", ""),
            "b.wea: line 6: the WEA header lacks `time_zone` (it needs place, latitude, longitude, time_zone, site_elevation, weather_data_file_units)",
        ),
        (
            good.replace("time_zone", "timezone"),
            "b.wea: line 4: `timezone` is not a WEA header key (place, latitude, longitude, time_zone, site_elevation, weather_data_file_units)",
        ),
        (
            good.replace("latitude 52.47", "latitude north"),
            "b.wea: line 2: latitude: `north` is not a number within -90…90",
        ),
        (
            good.replace("units 1", "units 2"),
            "b.wea: line 6: weather_data_file_units 2 (direct horizontal irradiance) is not supported: its direct normal needs the sun's altitude per row; write the file with units 1 (direct normal, as epw2wea does)",
        ),
        (
            good.replace("units 1", "units 4"),
            "b.wea: line 6: weather_data_file_units `4` is not 1, 2 or 3",
        ),
        (
            BERLIN_WEA.to_string(),
            "b.wea: 6 lines: no data rows after the WEA header (truncated?)",
        ),
    ];
    for (text, want) in cases {
        match parse_wea(&text, "b.wea") {
            Ok(_) => panic!("read: {want}"),
            Err(e) => assert_eq!(e.to_string(), want),
        }
    }
}

fn temp_file(name: &str, text: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("io-weather");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// `.epw` and `.wea` in any case pick their reader; another extension is refused.
#[test]
fn read_weather_goes_by_the_extension() {
    let e = read_weather(&temp_file("b.Epw", &epw(BERLIN, 1))).unwrap();
    let text = wea_of(&epw(BERLIN, 1), BERLIN_WEA);
    let w = read_weather(&temp_file("b.WEA", &text)).unwrap();
    assert_eq!((e.hours.len(), w.hours.len()), (24, 24));
    assert_eq!(w.location, e.location);
    for (name, text) in [("b.csv", text.as_str()), ("b", text.as_str())] {
        let path = temp_file(name, text);
        let err = read_weather(&path).unwrap_err().to_string();
        assert_eq!(
            err,
            format!(
                "{}: not a known weather file: expected the extension .epw (EnergyPlus) or .wea (DAYSIM/Radiance)",
                path.display()
            )
        );
    }
    // A WEA named .epw is read as EPW and refused as such, in one line.
    let err = read_weather(&temp_file("w.epw", &text))
        .unwrap_err()
        .to_string();
    assert!(err.ends_with("line 1: expected LOCATION,city,state,country,source,WMO,latitude,longitude,time zone,elevation"), "{err}");
}

/// The bundled TMY3 EPW (scenes/weather/README.md) reads whole, with no warning: the
/// site LOCATION states, 8760 hours of 1/1–12/31, and annual sums that agree with the
/// file's own columns, summed here from the raw text. Plausibility from its records:
/// global horizontal lies between 40 % and 75 % of the extraterrestrial horizontal
/// (field 11; an annual clearness outside that range is found on no real site), and it
/// closes with DHI + DNI·sin(altitude), the sun from NREL SPA at each record's
/// midpoint h − 0.5, within 1 % over the year (0.06 % measured) — which also checks the
/// time convention.
#[test]
fn the_bundled_epw_reads_whole_and_closes() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/weather/USA_CO_Golden-NREL.724666_TMY3.epw");
    let w = read_weather(&path).unwrap_or_else(|e| panic!("{e}"));
    let l = &w.location;
    assert_eq!(
        (l.latitude_deg, l.longitude_deg, l.timezone_h, l.elevation_m),
        (39.74, -105.18, -7.0, 1829.0)
    );
    assert_eq!((w.hours.len(), w.missing_hours), (8760, 0));
    assert!(w.warnings.is_empty(), "{:?}", w.warnings);
    let (first, last) = (&w.hours[0], &w.hours[8759]);
    assert_eq!((first.month, first.day, first.hour), (1, 1, 1));
    assert_eq!((last.month, last.day, last.hour), (12, 31, 24));
    let text = std::fs::read_to_string(&path).unwrap();
    let rows: Vec<Vec<f64>> = (text.lines().skip(8))
        .map(|r| {
            let f: Vec<&str> = r.split(',').collect();
            [0, 10, 13, 14, 15]
                .map(|k| f[k].parse::<f64>().unwrap())
                .to_vec()
        })
        .collect();
    let column = |k: usize| rows.iter().map(|r| r[k]).sum::<f64>() / 1000.0;
    let [g, b, d] = w.radiation_sums_kwh_m2();
    for (got, want) in [(g, column(2)), (b, column(3)), (d, column(4))] {
        assert!((got - want).abs() < 1e-9, "{got} against {want}");
    }
    let clearness = g / column(1);
    assert!(
        (0.4..0.75).contains(&clearness),
        "annual clearness {clearness}"
    );
    let mut closed = 0.0;
    for (h, r) in w.hours.iter().zip(&rows) {
        let date = [r[0], h.month as f64, h.day as f64];
        let (alt, _) = solar_position(
            l.latitude_deg,
            l.longitude_deg,
            l.timezone_h,
            date,
            [h.hour as f64 - 1.0, 30.0, 0.0],
        )
        .unwrap();
        let up = libm::sin(alt.max(0.0).to_radians());
        closed += h.diffuse_horizontal_wm2.unwrap() + h.direct_normal_wm2.unwrap() * up;
    }
    let closed = closed / 1000.0;
    assert!(
        (closed / g - 1.0).abs() < 0.01,
        "DHI + DNI sin(alt) {closed} against GHI {g} kWh/m²"
    );
}

//! The Perez all-weather sky (docs/daylight.md, *Perez*): ε, Δ, the air mass and the
//! coefficient interpolation against hand-computed values, the luminous efficacies, the
//! sky's level against an independent quadrature, its band bounds, next events on an
//! open receiver against E_dh, bad input; and the EPW reader (`luxtally::weather`).

use crate::common;

use super::daylight::run_with;
use common::*;
use luxtally::light::distant::hemisphere_bands;
use luxtally::light::perez::*;
use luxtally::light::sky::SkyModel;
use luxtally::light::sun::direction;
use luxtally::light::Sky;
use luxtally::scene::Estimator;
use std::f64::consts::PI;

fn close(got: f64, want: f64, rel: f64, what: &str) {
    assert!(
        (got - want).abs() <= rel * want.abs(),
        "{what}: {got} against {want}"
    );
}

/// ε = ((Dh + I)/Dh + 1.041Z³)/(1 + 1.041Z³), Kasten & Young's air mass, Spencer's E0 and
/// Δ = Dh·m/(1367·E0), at Z = 30°, I = 700, Dh = 100 W/m², 21 June (day 172), against
/// values worked out by hand (a separate script of the same formulas).
#[test]
fn clearness_brightness_and_air_mass_match_hand_values() {
    let z = 30f64.to_radians();
    close(clearness(700.0, 100.0, z), 7.089958988607769, 1e-13, "ε");
    close(clearness(700.0, 100.0, 0.0), 8.0, 1e-15, "ε at the zenith");
    close(clearness(0.0, 100.0, 1.2), 1.0, 1e-15, "ε without a beam");
    close(air_mass(z), 1.1539922333636758, 1e-13, "m(30°)");
    close(air_mass(0.0), 0.9997119918558381, 1e-13, "m(0°)");
    close(air_mass(PI / 2.0), 37.9196083778363, 1e-12, "m(90°)");
    close(eccentricity(172.0), 0.967442787915536, 1e-13, "E0");
    close(brightness(100.0, z, 172.0), 0.08725876861221171, 1e-12, "Δ");
    close(precipitable_water_cm(10.97), 1.9995056999733052, 1e-13, "W");
    assert_eq!(day_of_year("2026-06-21"), Some(172.0));
    assert_eq!(day_of_year("2024-12-31"), Some(366.0));
    assert_eq!(day_of_year("2026-02-29"), None);
    let bins = [
        (1.0, 1),
        (1.0649, 1),
        (1.065, 2),
        (1.3, 3),
        (1.95, 5),
        (4.4, 6),
        (6.19, 7),
        (6.2, 8),
        (40.0, 8),
    ];
    for (eps, cat) in bins {
        assert_eq!(category(eps), cat, "ε {eps}");
    }
}

/// a…e of every category at Z = 0.7 rad, Δ = 0.25: x1 + x2·Z + Δ(x3 + x4·Z), and category
/// 1's c = exp((Δ(c1 + c2Z))^c3) − c4, d = −exp(Δ(d1 + d2Z)) + d3 + Δ·d4, by hand.
#[test]
fn coefficients_interpolate_per_category() {
    let want = [
        [
            0.853525,
            -0.4697375,
            1.148266720371,
            -0.739421093070,
            -0.020655,
        ],
        [-1.21652, -0.99768, 8.6894225, -2.36187, 0.1797025],
        [-1.04952, -0.767735, 12.237725, -3.412585, 0.10383],
        [-0.9564325, -0.6720325, 14.0800675, -3.19337, 0.2075225],
        [-1.067745, -0.7696175, 13.53504, -3.18744, 0.017775],
        [-0.7746575, -0.457335, 12.8356275, -3.469425, 0.204575],
        [-0.9491875, -0.2754325, 15.476805, -3.83992, 0.425195],
        [-0.860445, -0.0491175, 19.074425, -3.501105, 1.61291],
    ];
    for (cat, w) in want.iter().enumerate() {
        let got = coefficients(cat + 1, 0.7, 0.25);
        for k in 0..5 {
            assert!(
                (got[k] - w[k]).abs() < 1e-11,
                "category {}: {:?} against {w:?}",
                cat + 1,
                got
            );
        }
    }
}

fn perez(dni: f64, dhi: f64, altitude: f64, azimuth: f64, day: f64) -> Result<PerezSky, String> {
    PerezSky::new(&PerezInput {
        direct_normal_wm2: dni,
        diffuse_horizontal_wm2: dhi,
        sun: direction(altitude, azimuth),
        day_of_year: day,
        dew_point_c: DEFAULT_DEW_POINT_C,
    })
}

/// Perez 1990's efficacies for the clear sky above (category 8, W from Td = 10.97 °C):
/// K_d = 152.23 + 0.35W − 45.27 cos Z − 7.98 ln Δ = 133.187 lm/W, K_b = 101.18 + 1.58W −
/// 1.10 exp(5.73Z − 5) − 8.29Δ = 103.467 lm/W, by hand; E_dh = K_d·Dh, E_dn = K_b·I.
#[test]
fn efficacies_give_the_hand_computed_illuminances() {
    let sky = perez(700.0, 100.0, 60.0, 180.0, 172.0).unwrap();
    assert_eq!(sky.category, 8);
    close(sky.diffuse_horizontal_lx, 13318.709720597471, 1e-12, "E_dh");
    close(sky.direct_normal_lx, 72426.8594709206, 1e-12, "E_dn");
    close(
        diffuse_efficacy(
            8,
            1.9995056999733052,
            30f64.to_radians(),
            0.08725876861221171,
        ),
        133.1870972059747,
        1e-13,
        "K_d",
    );
}

/// Skies over the range: overcast (ε ≈ 1), intermediate, clear, a low sun, a dark sky.
fn sample_skies() -> Vec<(&'static str, PerezSky)> {
    [
        ("overcast", 0.0, 150.0, 30.0, 170.0, 350.0),
        ("thin overcast", 20.0, 250.0, 50.0, 120.0, 100.0),
        ("intermediate", 250.0, 200.0, 40.0, 200.0, 80.0),
        ("partly cloudy", 450.0, 160.0, 25.0, 240.0, 300.0),
        ("clear", 850.0, 90.0, 60.0, 180.0, 172.0),
        ("clear, low sun", 400.0, 40.0, 6.0, 100.0, 15.0),
        ("very clear, high sun", 950.0, 60.0, 85.0, 10.0, 200.0),
    ]
    .into_iter()
    .map(|(name, dni, dhi, alt, az, day)| (name, perez(dni, dhi, alt, az, day).unwrap()))
    .collect()
}

/// The sky's level: Lz = E_dh/∫(L/Lz) cos Z dω by the sky's own exact rule, so a sky
/// loaded from the scene file has horizontal illuminance E_dh; an independent midpoint
/// rule in (θ, φ), 3000 × 6000, integrates its L·cos to E_dh within 10⁻⁴.
#[test]
fn the_sky_integrates_to_its_diffuse_illuminance() {
    let keys = "model = \"perez\"\ndirect_normal_irradiance_wm2 = 850\ndiffuse_horizontal_irradiance_wm2 = 90\n\
                sun_altitude_deg = 60\nsun_azimuth_deg = 180\nday_of_year = 172";
    let loaded = scene(&format!("[[lights]]\ntype = \"sky\"\n{keys}\n"));
    let sky = loaded.lights[0].get::<Sky>().unwrap();
    let SkyModel::Perez(p) = sky.model else {
        panic!("{:?}", sky.model)
    };
    close(
        sky.horizontal_lx,
        p.diffuse_horizontal_lx,
        1e-12,
        "loaded sky",
    );
    for (name, p) in sample_skies() {
        let model = SkyModel::Perez(p);
        let lz = p.diffuse_horizontal_lx / model.integrals().1;
        let (nt, np) = (3000, 6000);
        let (dt, dp) = (PI / 2.0 / nt as f64, 2.0 * PI / np as f64);
        let mut sum = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) * dt;
            let (st, ct) = (libm::sin(t), libm::cos(t));
            let mut ring = 0.0;
            for j in 0..np {
                let f = (j as f64 + 0.5) * dp;
                ring += model.relative(glam::DVec3::new(st * libm::cos(f), st * libm::sin(f), ct));
            }
            sum += ring * ct * st;
        }
        close(lz * sum * dt * dp, p.diffuse_horizontal_lx, 1e-4, name);
    }
}

/// The rejection sampler is exact only if each band's bound holds: lv at 25 points of
/// every band (corners and edges included) never exceeds it, over a grid of irradiance
/// and suns spanning the eight categories, Δ from the guards' floor to their cap, and
/// suns from 2° to the zenith.
#[test]
fn perez_band_bounds_hold_everywhere_in_their_band() {
    let (mut skies, mut cats) = (0, [0usize; 8]);
    for dhi in [15.0, 60.0, 150.0, 400.0, 600.0] {
        for dni in [0.0, 30.0, 150.0, 400.0, 1000.0] {
            for (alt, az) in [
                (2.0, 10.0),
                (12.0, 123.0),
                (35.0, 250.0),
                (70.0, 300.0),
                (89.9, 0.0),
            ] {
                let p = match perez(dni, dhi, alt, az, 100.0) {
                    Ok(p) => p,
                    Err(e) => {
                        eprintln!("refused: I {dni}, Dh {dhi}, altitude {alt}: {e}");
                        continue;
                    }
                };
                skies += 1;
                cats[p.category - 1] += 1;
                let model = SkyModel::Perez(p);
                for band in hemisphere_bands(64, 128) {
                    let bound = model.bound(&band);
                    for k in 0..25 {
                        let (a, b) = ((k % 5) as f64 / 4.0, (k / 5) as f64 / 4.0);
                        let l = model.relative(band.direction(a.min(1.0 - 1e-12), b));
                        assert!(
                            l <= bound * (1.0 + 1e-12),
                            "{p:?}: {l} > {bound} in {band:?}"
                        );
                    }
                }
            }
        }
    }
    eprintln!("bounds checked on {skies} skies, per category {cats:?}");
    assert!(
        skies >= 100 && cats.iter().all(|&n| n > 0),
        "{skies} skies, categories {cats:?}"
    );
}

/// Next events on an open horizontal receiver give E_dh within σ, over overcast to very
/// clear skies and a low sun, and photons do for the clear one (z-calibrated).
#[test]
fn every_perez_sky_gives_its_diffuse_illuminance() {
    let mut z = Vec::new();
    let cases = [
        (0.0, 150.0, 30.0, 170.0),
        (250.0, 200.0, 40.0, 200.0),
        (850.0, 90.0, 60.0, 180.0),
        (400.0, 40.0, 6.0, 100.0),
        (950.0, 60.0, 85.0, 10.0),
    ];
    for (i, (dni, dhi, alt, az)) in cases.into_iter().enumerate() {
        let text = format!(
            "[[lights]]\ntype = \"sky\"\nmodel = \"perez\"\ndirect_normal_irradiance_wm2 = {dni}\n\
             diffuse_horizontal_irradiance_wm2 = {dhi}\nsun_altitude_deg = {alt}\nsun_azimuth_deg = {az}\n\
             day_of_year = 80\n[[receivers]]\nname = \"open\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\n\
             v = [0, 1, 0]\ncells = [4, 4]\n[simulation]\nphotons = 1000\n"
        );
        let scene = scene(&text);
        let want = perez(dni, dhi, alt, az, 80.0)
            .unwrap()
            .diffuse_horizontal_lx;
        let s = run_with(&scene, 50_000, Estimator::NextEvent, i as u64 + 1);
        z.extend(z_scores(&s.receivers["open"], |_, _| want));
        if i == 2 {
            // Photons: the emission's rejection sampling against the bounds.
            let s = run_with(&scene, 300_000, Estimator::Track, 7);
            z.extend(z_scores(&s.receivers["open"], |_, _| want));
        }
    }
    assert_calibrated(&z, "Perez skies' diffuse horizontal illuminance");
}

/// An hour whose Perez luminance is 0 at the zenith (category 6, a low Δ, the sun 70°
/// high: the coefficients cut the zenith's lv to 0) is a sky like any other, scaled by
/// lv itself: dark at the zenith, and next events on an open receiver give its E_dh.
#[test]
fn a_perez_sky_with_a_dark_zenith_still_gives_its_diffuse_illuminance() {
    let p = perez(150.0, 60.0, 70.0, 180.0, 100.0).expect("a Perez sky");
    assert_eq!(p.relative(glam::DVec3::Z), 0.0, "the zenith is dark: {p:?}");
    let text = "[[lights]]\ntype = \"sky\"\nmodel = \"perez\"\ndirect_normal_irradiance_wm2 = 150\n\
                diffuse_horizontal_irradiance_wm2 = 60\nsun_altitude_deg = 70\nsun_azimuth_deg = 180\n\
                day_of_year = 100\n[[receivers]]\nname = \"open\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\n\
                v = [0, 1, 0]\ncells = [4, 4]\n";
    let scene = scene(text);
    let sky = scene.lights[0].get::<Sky>().expect("a sky");
    assert_eq!(sky.luminance(glam::DVec3::Z), 0.0);
    let s = run_with(&scene, 50_000, Estimator::NextEvent, 3);
    let z = z_scores(&s.receivers["open"], |_, _| p.diffuse_horizontal_lx);
    assert!(z.iter().all(|z| z.abs() < 4.0), "{z:?}");
}

/// Bad Perez entries, each refused in one line naming the entry and the key.
#[test]
fn bad_perez_skies_are_rejected_in_one_line() {
    let base = "model = \"perez\"\ndirect_normal_irradiance_wm2 = 500\ndiffuse_horizontal_irradiance_wm2 = 100\n";
    let angles = "sun_altitude_deg = 40\nsun_azimuth_deg = 180\n";
    let cases = [
        (format!("{base}{angles}"), "day.toml: lights[0].day_of_year: missing (required for a Perez sky whose sun is given by angles: the extraterrestrial irradiance varies ±3.3 % over the year)"),
        (format!("{base}{angles}day_of_year = 100\nhorizontal_illuminance_lx = 1000"), "day.toml: lights[0]: a Perez sky's level comes from its irradiance (the efficacy model): give neither `zenith_luminance_cdm2` nor `horizontal_illuminance_lx`"),
        (format!("{base}day_of_year = 100"), "day.toml: lights[0]: a Perez sky needs the sun's position (altitude/azimuth or site, date and time)"),
        (format!("{base}sun_altitude_deg = -2\nsun_azimuth_deg = 180\nday_of_year = 100"), "day.toml: lights[0]: the sun is at or below the horizon (altitude -2.000°): the Perez sky needs it above"),
        (format!("model = \"perez\"\ndirect_normal_irradiance_wm2 = 500\ndiffuse_horizontal_irradiance_wm2 = 0\n{angles}day_of_year = 100"), "day.toml: lights[0]: diffuse_horizontal_irradiance_wm2 must be > 0 for a Perez sky (ε divides by it), got 0"),
        (format!("model = \"perez\"\ndiffuse_horizontal_irradiance_wm2 = 100\n{angles}day_of_year = 100"), "day.toml: lights[0].direct_normal_irradiance_wm2: missing (required for model = \"perez\")"),
        (format!("{base}latitude_deg = 52\nlongitude_deg = 13\ntimezone_h = 1\ndate = \"2026-06-21\"\ntime = \"12:00\"\nday_of_year = 172"), "day.toml: lights[0].day_of_year: give `day_of_year` or `date`, not both (the date fixes the day)"),
        (format!("{base}{angles}day_of_year = 400"), "day.toml: lights[0]: day_of_year must be within 1…366, got 400"),
        ("cie_type = 12\nsun_altitude_deg = 40\nsun_azimuth_deg = 0\nhorizontal_illuminance_lx = 1\ndew_point_c = 5".to_string(), "day.toml: lights[0].dew_point_c: applies only to model = \"perez\""),
    ];
    for (keys, want) in cases {
        let text = format!("[[lights]]\ntype = \"sky\"\n{keys}\n");
        match luxtally::scene::load_str(&text, std::path::Path::new("."), "day.toml") {
            Ok(_) => panic!("loaded: {text}"),
            Err(e) => assert_eq!(e.to_string(), want),
        }
    }
}

/// A sun placed by site and date takes its day from the date: the same sky as one given
/// by angles and `day_of_year`.
#[test]
fn the_date_fixes_the_day_of_year() {
    let keys = "model = \"perez\"\ndirect_normal_irradiance_wm2 = 500\ndiffuse_horizontal_irradiance_wm2 = 100\n\
                latitude_deg = 52.52\nlongitude_deg = 13.4\ntimezone_h = 1\ndate = \"2026-06-21\"\ntime = \"13:00\"";
    let loaded = scene(&format!("[[lights]]\ntype = \"sky\"\n{keys}\n"));
    let SkyModel::Perez(p) = loaded.lights[0].get::<Sky>().unwrap().model else {
        panic!()
    };
    let by_day = PerezSky::new(&PerezInput {
        direct_normal_wm2: 500.0,
        diffuse_horizontal_wm2: 100.0,
        sun: p.sun,
        day_of_year: 172.0,
        dew_point_c: DEFAULT_DEW_POINT_C,
    })
    .unwrap();
    assert_eq!(p, by_day);
}

// ---- EPW -------------------------------------------------------------------------

// `epw` and `BERLIN` (a small EPW's text) are in `common`, shared with io::weather's
// WEA tests.

#[test]
fn a_small_epw_is_read_with_its_site_and_hours() {
    let w = luxtally::weather::parse_epw(&epw(BERLIN, 2), "b.epw").unwrap();
    let l = &w.location;
    assert_eq!(
        (
            l.city.as_str(),
            l.latitude_deg,
            l.longitude_deg,
            l.timezone_h,
            l.elevation_m
        ),
        ("Berlin", 52.47, 13.40, 1.0, 49.0)
    );
    assert_eq!((w.hours.len(), w.missing_hours), (48, 0));
    assert!(w.warnings.is_empty(), "{:?}", w.warnings);
    let noon = &w.hours[24 + 11];
    assert_eq!(
        (noon.month, noon.day, noon.hour, noon.line),
        (1, 2, 12, 8 + 24 + 12)
    );
    assert_eq!(noon.sun_time_h(), 11.5);
    assert_eq!(
        (
            noon.direct_normal_wm2,
            noon.diffuse_horizontal_wm2,
            noon.dew_point_c
        ),
        (Some(500.0), Some(62.0), Some(-1.5))
    );
    assert_eq!(
        (noon.direct_normal_lx, noon.diffuse_horizontal_lx),
        (Some(50_000.0), Some(6820.0))
    );
    // DNI over a day: 100·(1 + … + 9) W/m² for 1 h each.
    let dni_day: f64 = (1..=9).map(|k| 100.0 * k as f64).sum();
    let dhi_day: f64 = (8..=16).map(|h| 50.0 + h as f64).sum();
    let [_, b, d] = w.radiation_sums_kwh_m2();
    assert_eq!((b, d), (2.0 * dni_day / 1000.0, 2.0 * dhi_day / 1000.0));
    assert!(w.summary().contains("48 hourly records"), "{}", w.summary());
}

#[test]
fn bad_epw_files_are_refused_in_one_line() {
    let good = epw(BERLIN, 2);
    let lines: Vec<&str> = good.lines().collect();
    let truncated = lines[..40].join("\n");
    let cut_line = lines[..21].join("\n") + "\n" + &lines[21][..40];
    let nan = good.replacen(",500,62,", ",NaN,62,", 1);
    let bad_lat = good.replacen("52.47", "north", 1);
    let cases = [
        (
            truncated,
            "b.epw: 32 hourly records, but DATA PERIODS (line 8) makes 48 (a truncated file?)"
                .to_string(),
        ),
        (
            cut_line,
            format!(
                "b.epw: line 22: {} fields, an EPW record has 35 (a truncated line?)",
                lines[21][..40].split(',').count()
            ),
        ),
        (
            nan,
            "b.epw: line 20: field 15 (direct normal radiation): `NaN` is not a number".to_string(),
        ),
        (
            bad_lat,
            "b.epw: line 1: field 7: latitude `north` is not a number within -90…90".to_string(),
        ),
        (
            lines[..5].join("\n"),
            "b.epw: 5 lines: an EPW file has 8 header lines before its records (truncated?)"
                .to_string(),
        ),
    ];
    for (text, want) in cases {
        match luxtally::weather::parse_epw(&text, "b.epw") {
            Ok(_) => panic!("read: {want}"),
            Err(e) => assert_eq!(e.to_string(), want),
        }
    }
}

/// Missing-value hours (9999) and a time zone more than 2 h from the longitude are
/// counted warnings, each one line; the missing values read as None, never 0.
#[test]
fn missing_hours_and_a_far_time_zone_are_counted_warnings() {
    let text = epw(BERLIN, 2).replacen(",500,62,", ",9999,62,", 2);
    let w = luxtally::weather::parse_epw(&text, "b.epw").unwrap();
    assert_eq!(w.missing_hours, 2);
    assert_eq!(w.hours[11].direct_normal_wm2, None);
    assert_eq!(w.warnings, ["b.epw: 2 of 48 hours miss direct normal or diffuse horizontal irradiance (9999), the first at line 20: they will have no sky"]);
    let west = epw(
        "LOCATION,Berlin,BE,DEU,test,103840,52.47,13.40,-1.0,49.0",
        1,
    );
    let w = luxtally::weather::parse_epw(&west, "w.epw").unwrap();
    assert!(
        w.warnings.is_empty(),
        "1.9 h is within 2 h: {:?}",
        w.warnings
    );
    let west = epw(
        "LOCATION,Berlin,BE,DEU,test,103840,52.47,13.40,-2.0,49.0",
        1,
    );
    let w = luxtally::weather::parse_epw(&west, "w.epw").unwrap();
    assert_eq!(w.warnings, ["w.epw: line 1: time zone -2 h is 2.9 h from the longitude's +0.89 h (13.4°): EPW counts both positive east (WEA and Radiance count west)"]);
}

/// A leap year's file (HOLIDAYS/DAYLIGHT SAVINGS says Yes) from 28 February to 1 March
/// holds 72 records; a sub-hourly file is refused in one line.
#[test]
fn leap_days_and_sub_hourly_periods() {
    let leap = epw(BERLIN, 3)
        .replace(
            "HOLIDAYS/DAYLIGHT SAVINGS,No",
            "HOLIDAYS/DAYLIGHT SAVINGS,Yes",
        )
        .replace("Sunday, 1/ 1, 1/ 3", "Sunday, 2/28, 3/ 1");
    let w = luxtally::weather::parse_epw(&leap, "l.epw").unwrap();
    assert_eq!(w.hours.len(), 72);
    let no_leap = leap.replace(
        "HOLIDAYS/DAYLIGHT SAVINGS,Yes",
        "HOLIDAYS/DAYLIGHT SAVINGS,No",
    );
    let e = luxtally::weather::parse_epw(&no_leap, "l.epw")
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "l.epw: 72 hourly records, but DATA PERIODS (line 8) makes 48 (a truncated file?)"
    );
    let sub = epw(BERLIN, 1).replace("DATA PERIODS,1,1,", "DATA PERIODS,1,4,");
    let e = luxtally::weather::parse_epw(&sub, "s.epw")
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "s.epw: line 8: 1 periods of 4 records per hour: only one hourly period is supported"
    );
}

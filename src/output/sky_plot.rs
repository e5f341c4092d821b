//! summary.json's `sky_plots`: each sky's luminance on a fisheye grid, for report.html's
//! sky charts (docs/daylight.md, *Sky plots*). The values come from the sky's own
//! luminance function ([`Light::daylight`]), the one its photons and next events
//! sample, not from the tallies: a plot shows what the scene asked for.
//!
//! The grid is the **equidistant** (angular) fisheye looking up at the zenith as seen
//! from below: north at the top, **east on the left**, west on the right; the distance
//! from the centre is proportional to the zenith angle, the horizon the circle of
//! radius 1. Pixel (i, j), stored at `j * size + i`, has column i from the left (east)
//! edge and row j from the top (north) edge; its centre sits at plot coordinates
//! x = 2(i + ½)/size − 1 (towards west), y = 1 − 2(j + ½)/size (towards north).

use crate::light::sun::altitude_azimuth_deg;
use crate::light::{Daylight, Light};
use crate::scene::Scene;
use crate::stats::null_as_nan;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

/// Pixels along each side of a sky plot.
pub const SKY_PLOT_SIZE: usize = 64;

/// One sky's fisheye plot (module docs: projection and pixel order).
#[derive(Serialize, Deserialize, Default, Clone, Debug)]
#[serde(default)]
pub struct SkyPlot {
    /// The sky's label (`lights[i]`).
    pub light: String,
    /// `equidistant`: radius ∝ zenith angle, north up, east on the left.
    pub projection: String,
    /// Pixels along each side; `luminance_cdm2` has size² of them.
    pub size: usize,
    /// Per pixel, row by row from the top (north) edge, each row from the left (east)
    /// edge: the sky's luminance towards the pixel's centre, cd/m²; null outside the
    /// horizon circle.
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub luminance_cdm2: Vec<f64>,
    /// The luminance at the zenith and the least and greatest over the pixels, cd/m².
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub zenith_cdm2: f64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub min_cdm2: f64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub max_cdm2: f64,
    /// The sun's position for the plot's marker (azimuth from north towards east), and
    /// the light it comes from: the sky's own sun where its indicatrix follows one,
    /// else the scene's first `sun`; null without either.
    pub sun_altitude_deg: Option<f64>,
    pub sun_azimuth_deg: Option<f64>,
    pub sun_light: Option<String>,
}

/// The unit world direction (z up, +y north, +x east) at the centre of pixel (i, j) of a
/// `size` × `size` plot, or None outside the horizon circle.
pub fn pixel_direction(size: usize, i: usize, j: usize) -> Option<DVec3> {
    let n = size as f64;
    let x = 2.0 * (i as f64 + 0.5) / n - 1.0;
    let y = 1.0 - 2.0 * (j as f64 + 0.5) / n;
    let r = libm::hypot(x, y);
    if !(r < 1.0) {
        return None;
    }
    let theta = FRAC_PI_2 * r;
    // sin θ / r, which tends to π/2 at the centre (no pixel centre sits there for an
    // even size; r > 0 for any size above 1 but odd ones).
    let s = if r > 0.0 {
        libm::sin(theta) / r
    } else {
        FRAC_PI_2
    };
    // East on the left: x grows towards west, −x.
    Some(DVec3::new(-x * s, y * s, libm::cos(theta)).normalize())
}

/// The plots of the scene's skies, in the order of its lights (empty without skies).
pub fn sky_plots(scene: &Scene) -> Vec<SkyPlot> {
    let probe = |l: &dyn Light| l.daylight(DVec3::Z);
    // The marker of a sky without a sun of its own: the scene's first sun.
    let scene_sun = scene
        .lights
        .iter()
        .find_map(|l| match probe(l.kind.as_ref()) {
            Some(Daylight {
                sky_luminance_cdm2: None,
                sun: Some(s),
            }) => Some((l.label.clone(), s)),
            _ => None,
        });
    scene
        .lights
        .iter()
        .filter_map(|l| sky_plot(&l.label, l.kind.as_ref(), scene_sun.clone(), SKY_PLOT_SIZE))
        .collect()
}

/// Light `light`'s plot on `size` × `size` pixels, if it is a sky; `scene_sun` (a label
/// and a direction) marks the sun when the sky has none of its own.
pub fn sky_plot(
    label: &str,
    light: &dyn Light,
    scene_sun: Option<(String, DVec3)>,
    size: usize,
) -> Option<SkyPlot> {
    let at = |w: DVec3| light.daylight(w).and_then(|d| d.sky_luminance_cdm2);
    let zenith_cdm2 = at(DVec3::Z)?;
    let luminance_cdm2: Vec<f64> = (0..size * size)
        .map(|k| pixel_direction(size, k % size, k / size).map_or(Some(f64::NAN), at))
        .collect::<Option<_>>()?;
    let inside = || luminance_cdm2.iter().copied().filter(|l| !l.is_nan());
    let own_sun = light.daylight(DVec3::Z).and_then(|d| d.sun);
    let sun = own_sun.map(|s| (label.to_string(), s)).or(scene_sun);
    let position = sun.as_ref().map(|(_, s)| altitude_azimuth_deg(*s));
    Some(SkyPlot {
        light: label.to_string(),
        projection: "equidistant".into(),
        size,
        zenith_cdm2,
        min_cdm2: inside().fold(zenith_cdm2, f64::min),
        max_cdm2: inside().fold(zenith_cdm2, f64::max),
        luminance_cdm2,
        sun_altitude_deg: position.map(|p| p.0),
        sun_azimuth_deg: position.map(|p| p.1),
        sun_light: sun.map(|(label, _)| label),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{load_entry, LoadContext};
    use std::f64::consts::PI;
    use std::path::Path;
    use std::sync::Arc;

    /// The light of a `[[lights]]` entry written as TOML.
    fn light(entry: &str) -> Arc<dyn Light> {
        let value: toml::Value = toml::from_str(entry).expect("TOML");
        let mut cx = LoadContext::new(Path::new("."));
        let mut lights = load_entry(value, "lights[0]", "test.toml", &mut cx).expect("a light");
        lights.remove(0).1
    }

    fn clear_sky(azimuth_deg: f64) -> Arc<dyn Light> {
        light(&format!(
            "type = \"sky\"\ncie_type = 12\nsun_altitude_deg = 30\nsun_azimuth_deg = {azimuth_deg}\n\
             horizontal_illuminance_lx = 10000"
        ))
    }

    /// Each pixel holds the sky's luminance towards the direction its centre stands for,
    /// worked out here from the projection's definition (radius ∝ zenith angle, north
    /// up, east left), and null outside the horizon circle.
    #[test]
    fn pixels_hold_the_sky_luminance_of_their_directions() {
        let sky = clear_sky(200.0);
        let n = 16;
        let plot = sky_plot("lights[0]", sky.as_ref(), None, n).expect("a sky");
        assert_eq!((plot.size, plot.luminance_cdm2.len()), (n, n * n));
        let l = |w: DVec3| sky.daylight(w).unwrap().sky_luminance_cdm2.unwrap();
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (
                    (i as f64 + 0.5) / n as f64 * 2.0 - 1.0,
                    1.0 - (j as f64 + 0.5) / n as f64 * 2.0,
                );
                let r = (x * x + y * y).sqrt();
                let got = plot.luminance_cdm2[j * n + i];
                if r >= 1.0 {
                    assert!(got.is_nan(), "({i}, {j}) lies beyond the horizon");
                    continue;
                }
                // Zenith angle r·90°; azimuth from north (up) towards east (left).
                let (zenith, azimuth) = (r * PI / 2.0, libm::atan2(-x, y));
                let w = DVec3::new(
                    libm::sin(zenith) * libm::sin(azimuth),
                    libm::sin(zenith) * libm::cos(azimuth),
                    libm::cos(zenith),
                );
                assert!(
                    (got - l(w)).abs() <= 1e-12 * l(w),
                    "({i}, {j}): {got} against {}",
                    l(w)
                );
            }
        }
        assert_eq!(plot.zenith_cdm2, l(DVec3::Z));
        let (alt, az) = (
            plot.sun_altitude_deg.unwrap(),
            plot.sun_azimuth_deg.unwrap(),
        );
        assert!(
            (alt - 30.0).abs() < 1e-9 && (az - 200.0).abs() < 1e-9,
            "{alt}, {az}"
        );
        assert_eq!(plot.sun_light.as_deref(), Some("lights[0]"));
    }

    /// The projection's orientation: a sun in the east brightens the left half, one in
    /// the north the top; the centre looks at the zenith, and the horizon is the circle
    /// of radius 1 (its pixels just inside look out at the horizon, those just outside
    /// are empty).
    #[test]
    fn east_is_on_the_left_the_zenith_at_the_centre_the_horizon_at_radius_one() {
        let n = 64;
        let brightest = |azimuth: f64| {
            let plot = sky_plot("sky", clear_sky(azimuth).as_ref(), None, n).unwrap();
            let k = (0..n * n)
                .filter(|&k| !plot.luminance_cdm2[k].is_nan())
                .max_by(|&a, &b| plot.luminance_cdm2[a].total_cmp(&plot.luminance_cdm2[b]))
                .unwrap();
            (k % n, k / n)
        };
        let (i, j) = brightest(90.0);
        assert!(
            i < n / 2 && (j as f64 - n as f64 / 2.0).abs() <= 2.0,
            "east sun at ({i}, {j})"
        );
        let (i, j) = brightest(0.0);
        assert!(
            j < n / 2 && (i as f64 - n as f64 / 2.0).abs() <= 2.0,
            "north sun at ({i}, {j})"
        );
        // The four centre pixels lie half a pixel's diagonal from the zenith.
        let half = n / 2;
        for (i, j) in [
            (half - 1, half - 1),
            (half, half - 1),
            (half - 1, half),
            (half, half),
        ] {
            let w = pixel_direction(n, i, j).unwrap();
            let want = libm::cos(FRAC_PI_2 * 2f64.sqrt() / n as f64);
            assert!((w.z - want).abs() < 1e-12, "({i}, {j}): z {}", w.z);
        }
        // Along the middle row, the last pixels inside are within a pixel of the
        // horizon, and the west edge (right) looks west.
        let west = pixel_direction(n, n - 1, half).unwrap();
        assert!(
            west.z < libm::sin(PI / n as f64) && west.x < -0.99,
            "{west}"
        );
        let east = pixel_direction(n, 0, half).unwrap();
        assert!(east.x > 0.99, "{east}");
        let corner = pixel_direction(n, 0, 0);
        assert!(corner.is_none(), "the corners lie beyond the horizon");
        for k in 0..n * n {
            let (x, y) = (
                2.0 * ((k % n) as f64 + 0.5) / n as f64 - 1.0,
                1.0 - 2.0 * ((k / n) as f64 + 0.5) / n as f64,
            );
            assert_eq!(
                pixel_direction(n, k % n, k / n).is_some(),
                x * x + y * y < 1.0
            );
        }
    }

    /// A sky whose indicatrix does not follow the sun (type 16) takes the scene's sun
    /// for its marker; lights other than skies have no plot.
    #[test]
    fn a_sky_without_a_sun_of_its_own_marks_the_scenes_sun() {
        let overcast = light("type = \"sky\"\ncie_type = 16\nzenith_luminance_cdm2 = 3000");
        let sun = light("type = \"sun\"\ndirect_normal_lx = 80000\nsun_altitude_deg = 40\nsun_azimuth_deg = 120");
        let towards = sun.daylight(DVec3::Z).unwrap().sun.unwrap();
        assert!(sky_plot("sun", sun.as_ref(), None, 8).is_none());
        let plot = sky_plot("sky", overcast.as_ref(), Some(("sun".into(), towards)), 8).unwrap();
        let (alt, az) = (
            plot.sun_altitude_deg.unwrap(),
            plot.sun_azimuth_deg.unwrap(),
        );
        assert!(
            (alt - 40.0).abs() < 1e-9 && (az - 120.0).abs() < 1e-9,
            "{alt}, {az}"
        );
        assert_eq!(plot.sun_light.as_deref(), Some("sun"));
        assert_eq!(plot.zenith_cdm2, 3000.0);
        assert!(plot.min_cdm2 >= 1000.0 && plot.max_cdm2 == 3000.0);
        let bare = sky_plot("sky", overcast.as_ref(), None, 8).unwrap();
        assert!(bare.sun_altitude_deg.is_none() && bare.sun_light.is_none());
        let point = light("type = \"point\"\nposition = [0, 0, 1]\nintensity_cd = 100");
        assert!(sky_plot("lamp", point.as_ref(), None, 8).is_none());
    }
}

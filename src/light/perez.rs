//! The Perez all-weather sky (Perez, Seals & Michalsky, Solar Energy 50(3), 1993) from
//! direct normal and diffuse horizontal irradiance, with the luminous efficacies of
//! Perez et al. (Solar Energy 44(5), 1990): sky clearness ε, brightness Δ, the five
//! coefficients of the relative luminance, the diffuse horizontal illuminance E_dh and
//! the sun's direct normal illuminance. `sky.rs` turns it into a `type = "sky"` light
//! (its level set by the exact integral); docs/daylight.md has the formulas and what
//! differs from Radiance's gendaylit.

use glam::DVec3;
use std::f64::consts::PI;

/// Upper ε of categories 1–7 (category 8 is ε > 6.2).
pub const CLEARNESS_BINS: [f64; 7] = [1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200];

/// The coefficients x1 x2 x3 x4 of a, b, c, d, e per category (Perez, Seals & Michalsky
/// 1993, Table 1; as Radiance's gendaylit.c `coeff_perez[]`): x = x1 + x2·Z + Δ(x3 + x4·Z),
/// except category 1's c and d ([`coefficients`]).
pub const PEREZ_COEFFICIENTS: [[[f64; 4]; 5]; 8] = [
    [
        [1.3525, -0.2576, -0.2690, -1.4366],
        [-0.7670, 0.0007, 1.2734, -0.1233],
        [2.8000, 0.6004, 1.2375, 1.0000],
        [1.8734, 0.6297, 0.9738, 0.2809],
        [0.0356, -0.1246, -0.5718, 0.9938],
    ],
    [
        [-1.2219, -0.7730, 1.4148, 1.1016],
        [-0.2054, 0.0367, -3.9128, 0.9156],
        [6.9750, 0.1774, 6.4477, -0.1239],
        [-1.5798, -0.5081, -1.7812, 0.1080],
        [0.2624, 0.0672, -0.2190, -0.4285],
    ],
    [
        [-1.1000, -0.2515, 0.8952, 0.0156],
        [0.2782, -0.1812, -4.5000, 1.1766],
        [24.7219, -13.0812, -37.7000, 34.8438],
        [-5.0000, 1.5218, 3.9229, -2.6204],
        [-0.0156, 0.1597, 0.4199, -0.5562],
    ],
    [
        [-0.5484, -0.6654, -0.2672, 0.7117],
        [0.7234, -0.6219, -5.6812, 2.6297],
        [33.3389, -18.3000, -62.2500, 52.0781],
        [-3.5000, 0.0016, 1.1477, 0.1062],
        [0.4659, -0.3296, -0.0876, -0.0329],
    ],
    [
        [-0.6000, -0.3566, -2.5000, 2.3250],
        [0.2937, 0.0496, -5.6812, 1.8415],
        [21.0000, -4.7656, -21.5906, 7.2492],
        [-3.5000, -0.1554, 1.4062, 0.3988],
        [0.0032, 0.0766, -0.0656, -0.1294],
    ],
    [
        [-1.0156, -0.3670, 1.0078, 1.4051],
        [0.2875, -0.5328, -3.8500, 3.3750],
        [14.0000, -0.9999, -7.1406, 7.5469],
        [-3.4000, -0.1078, -1.0750, 1.5702],
        [-0.0672, 0.4016, 0.3017, -0.4844],
    ],
    [
        [-1.0000, 0.0211, 0.5025, -0.5119],
        [-0.3000, 0.1922, 0.7023, -1.6317],
        [19.0000, -5.0000, 1.2438, -1.9094],
        [-4.0000, 0.0250, 0.3844, 0.2656],
        [1.0468, -0.3788, -2.4517, 1.4656],
    ],
    [
        [-1.0500, 0.0289, 0.4260, 0.3590],
        [-0.3250, 0.1156, 0.7781, 0.0025],
        [31.0625, -14.5000, -46.1148, 55.3750],
        [-7.2312, 0.4050, 13.3500, 0.6234],
        [1.5000, -0.6426, 1.8564, 0.5636],
    ],
];

/// Diffuse luminous efficacy a b c d per category (Perez et al. 1990, Table 4), lm/W:
/// K_d = a + b·W + c·cos Z + d·ln Δ.
pub const DIFFUSE_EFFICACY: [[f64; 4]; 8] = [
    [97.24, -0.46, 12.00, -8.91],
    [107.22, 1.15, 0.59, -3.95],
    [104.97, 2.96, -5.53, -8.77],
    [102.39, 5.59, -13.95, -13.90],
    [100.71, 5.94, -22.75, -23.74],
    [106.42, 3.83, -36.15, -28.83],
    [141.88, 1.90, -53.24, -14.03],
    [152.23, 0.35, -45.27, -7.98],
];

/// Direct (beam) luminous efficacy a b c d per category (Perez et al. 1990, Table 4),
/// lm/W: K_b = max(0, a + b·W + c·exp(5.73·Z − 5) + d·Δ).
pub const DIRECT_EFFICACY: [[f64; 4]; 8] = [
    [57.20, -4.55, -2.98, 117.12],
    [98.99, -3.46, -1.21, 12.38],
    [109.83, -4.90, -1.71, -8.81],
    [110.34, -5.84, -1.99, -4.56],
    [106.36, -3.97, -1.75, -6.16],
    [107.19, -1.25, -1.51, -26.73],
    [105.75, 0.77, -1.26, -34.44],
    [101.18, 1.58, -1.10, -8.29],
];

/// The solar constant, W/m² (as Perez et al. and gendaylit).
pub const SOLAR_CONSTANT_WM2: f64 = 1367.0;

/// Dew point where an entry gives none, °C: gendaylit's `-d` default.
pub const DEFAULT_DEW_POINT_C: f64 = 10.97;

/// The least cos ζ the gradation is evaluated at: below 0.01 (0.57° altitude) it takes
/// its value at 0.01, as Radiance's perezlum.cal does, so that exp(b/cos ζ) stays finite.
pub const MIN_COS_ZENITH: f64 = 0.01;

/// Sky clearness ε = ((Dh + I)/Dh + κZ³)/(1 + κZ³), κ = 1.041, Z the solar zenith angle
/// in radians (Perez et al. 1990, eq. 1).
pub fn clearness(direct_normal_wm2: f64, diffuse_horizontal_wm2: f64, zenith_rad: f64) -> f64 {
    let k = 1.041 * zenith_rad * zenith_rad * zenith_rad;
    ((diffuse_horizontal_wm2 + direct_normal_wm2) / diffuse_horizontal_wm2 + k) / (1.0 + k)
}

/// Relative optical air mass by Kasten & Young (Applied Optics 28(22), 1989):
/// m = 1/(cos Z + 0.50572·(96.07995° − Z°)^−1.6364).
pub fn air_mass(zenith_rad: f64) -> f64 {
    let z_deg = zenith_rad.to_degrees();
    1.0 / (libm::cos(zenith_rad) + 0.50572 * libm::pow(96.07995 - z_deg, -1.6364))
}

/// The Earth–Sun distance factor E0 (Spencer 1971), Γ = 2π(day − 1)/365.
pub fn eccentricity(day_of_year: f64) -> f64 {
    let g = 2.0 * PI * (day_of_year - 1.0) / 365.0;
    1.00011
        + 0.034221 * libm::cos(g)
        + 0.00128 * libm::sin(g)
        + 0.000719 * libm::cos(2.0 * g)
        + 0.000077 * libm::sin(2.0 * g)
}

/// Sky brightness Δ = Dh·m/I0, I0 = 1367·E0 the extraterrestrial normal irradiance
/// (Perez et al. 1990, eq. 2).
pub fn brightness(diffuse_horizontal_wm2: f64, zenith_rad: f64, day_of_year: f64) -> f64 {
    diffuse_horizontal_wm2 * air_mass(zenith_rad) / (SOLAR_CONSTANT_WM2 * eccentricity(day_of_year))
}

/// Precipitable water W = exp(0.07·Td − 0.075) cm, Td the dew point in °C (Perez et al.
/// 1990, after Wright et al. 1989).
pub fn precipitable_water_cm(dew_point_c: f64) -> f64 {
    libm::exp(0.07 * dew_point_c - 0.075)
}

/// The clearness category 1–8 of ε (ε < 1.065 is 1, ε ≥ 6.2 is 8).
pub fn category(clearness: f64) -> usize {
    1 + CLEARNESS_BINS
        .iter()
        .take_while(|&&upper| clearness >= upper)
        .count()
}

/// a, b, c, d, e of category `cat` (1–8) at solar zenith `z` (radians) and brightness
/// Δ: x = x1 + x2·Z + Δ(x3 + x4·Z); category 1's c = exp((Δ(c1 + c2·Z))^c3) − c4 and
/// d = −exp(Δ(d1 + d2·Z)) + d3 + Δ·d4 (Perez, Seals & Michalsky 1993).
pub fn coefficients(cat: usize, z: f64, delta: f64) -> [f64; 5] {
    let table = &PEREZ_COEFFICIENTS[cat - 1];
    let linear = |x: &[f64; 4]| x[0] + x[1] * z + delta * (x[2] + x[3] * z);
    let mut out = [0.0; 5];
    for (o, x) in out.iter_mut().zip(table) {
        *o = linear(x);
    }
    if cat == 1 {
        let [c1, c2, c3, c4] = table[2];
        out[2] = libm::exp(libm::pow(delta * (c1 + c2 * z), c3)) - c4;
        let [d1, d2, d3, d4] = table[3];
        out[3] = -libm::exp(delta * (d1 + d2 * z)) + d3 + delta * d4;
    }
    out
}

/// Diffuse luminous efficacy K_d = a + b·W + c·cos Z + d·ln Δ, lm/W.
pub fn diffuse_efficacy(cat: usize, water_cm: f64, z: f64, delta: f64) -> f64 {
    let [a, b, c, d] = DIFFUSE_EFFICACY[cat - 1];
    a + b * water_cm + c * libm::cos(z) + d * libm::log(delta)
}

/// Direct luminous efficacy K_b = max(0, a + b·W + c·exp(5.73·Z − 5) + d·Δ), lm/W.
pub fn direct_efficacy(cat: usize, water_cm: f64, z: f64, delta: f64) -> f64 {
    let [a, b, c, d] = DIRECT_EFFICACY[cat - 1];
    (a + b * water_cm + c * libm::exp(5.73 * z - 5.0) + d * delta).max(0.0)
}

/// gendaylit's guards on the brightness that shapes the distribution (not the
/// efficacies): Δ within 0.01…0.6, and at least 0.2 for 1.065 < ε < 2.8 (categories
/// 2–5), where smaller Δ make b positive and the horizon grow without bound.
pub fn guarded_brightness(cat: usize, delta: f64) -> f64 {
    let d = delta.clamp(0.01, 0.6);
    if (2..=5).contains(&cat) {
        d.max(0.2)
    } else {
        d
    }
}

/// What a Perez sky is made of.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerezInput {
    pub direct_normal_wm2: f64,
    pub diffuse_horizontal_wm2: f64,
    /// Unit, towards the sun; above the horizon.
    pub sun: DVec3,
    /// 1–366 (fractional allowed), for the extraterrestrial irradiance.
    pub day_of_year: f64,
    pub dew_point_c: f64,
}

/// A Perez sky: its parameters, coefficients and illuminances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerezSky {
    /// a, b, c, d, e of lv (at the guarded Δ).
    pub coefficients: [f64; 5],
    /// Unit, towards the sun.
    pub sun: DVec3,
    /// ε.
    pub clearness: f64,
    /// Δ as computed from the irradiance (before gendaylit's guards).
    pub brightness: f64,
    /// 1–8.
    pub category: usize,
    /// E_dh = K_d·Dh, lx: the level the sky is normalised to.
    pub diffuse_horizontal_lx: f64,
    /// E_dn = K_b·I, lx: what a `type = "sun"` in the same position should be given.
    pub direct_normal_lx: f64,
}

impl PerezSky {
    /// ε, Δ, the category, the coefficients and both illuminances, or why not.
    pub fn new(input: &PerezInput) -> Result<PerezSky, String> {
        let PerezInput {
            direct_normal_wm2: dni,
            diffuse_horizontal_wm2: dhi,
            sun,
            ..
        } = *input;
        if !(dhi > 0.0 && dhi.is_finite()) {
            return Err(format!(
                "diffuse_horizontal_irradiance_wm2 must be > 0 for a Perez sky (ε divides by it), got {dhi}"
            ));
        }
        if !(dni >= 0.0 && dni.is_finite()) {
            return Err(format!(
                "direct_normal_irradiance_wm2 must be ≥ 0, got {dni}"
            ));
        }
        if !(sun.z > 0.0) {
            return Err(format!(
                "the sun is at or below the horizon (altitude {:.3}°): the Perez sky needs it above",
                libm::asin(sun.z.clamp(-1.0, 1.0)).to_degrees()
            ));
        }
        if !(1.0..367.0).contains(&input.day_of_year) {
            return Err(format!(
                "day_of_year must be within 1…366, got {}",
                input.day_of_year
            ));
        }
        if !(-100.0..=60.0).contains(&input.dew_point_c) {
            return Err(format!(
                "dew_point_c must be within −100…60 °C, got {}",
                input.dew_point_c
            ));
        }
        let z = libm::acos(sun.z.min(1.0));
        let eps = clearness(dni, dhi, z);
        let delta = brightness(dhi, z, input.day_of_year);
        let cat = category(eps);
        let coefficients = coefficients(cat, z, guarded_brightness(cat, delta));
        let [a, b, ..] = coefficients;
        if a > 0.0 && b > 0.0 {
            return Err(format!(
                "ε {eps:.4}, Δ {delta:.4} give a gradation a {a:.4}, b {b:.4} that grows without \
                 bound towards the horizon (gendaylit makes it an all-zero sky); no Perez sky"
            ));
        }
        let water = precipitable_water_cm(input.dew_point_c);
        // ln Δ of the efficacy model kept within the model's range.
        let efficacy_delta = delta.max(0.01);
        let sky = PerezSky {
            coefficients,
            sun,
            clearness: eps,
            brightness: delta,
            category: cat,
            diffuse_horizontal_lx: diffuse_efficacy(cat, water, z, efficacy_delta) * dhi,
            direct_normal_lx: direct_efficacy(cat, water, z, efficacy_delta) * dni,
        };
        Ok(sky)
    }

    /// lv = max(0, [1 + a·exp(b/cos ζ)]·[1 + c·exp(dγ) + e·cos²γ]) towards unit `w` (0
    /// below the horizon), cos ζ no less than [`MIN_COS_ZENITH`]; negative values (which
    /// some coefficients give) are cut to 0.
    pub fn relative(&self, w: DVec3) -> f64 {
        if !(w.z > 0.0) {
            return 0.0;
        }
        let [a, b, c, d, e] = self.coefficients;
        let cos_gamma = w.dot(self.sun).clamp(-1.0, 1.0);
        let gamma = libm::acos(cos_gamma);
        let g = gradation(a, b, w.z);
        let f = 1.0 + c * libm::exp(d * gamma) + e * cos_gamma * cos_gamma;
        (g * f).max(0.0)
    }

    /// An upper bound of lv over the directions with cos ζ in `z` and angle to the sun in
    /// [γlo, γhi]. The gradation is monotone in cos ζ whatever the signs of a and b
    /// (exp(b/z) is monotone in z, the clamp keeps it so), so its range over the band is
    /// spanned by its values at the two z edges; the indicatrix's range is bounded by
    /// that of its exponential term (monotone in γ: the γ ends) plus that of its cos²
    /// term (cos² is monotone on each side of 90°: the γ ends, and 0 if 90° lies
    /// between). lv ≤ max(0, the largest product of the two ranges' ends).
    pub fn bound(&self, z: [f64; 2], gamma: (f64, f64)) -> f64 {
        let [a, b, c, d, e] = self.coefficients;
        let (g0, g1) = (gradation(a, b, z[0]), gradation(a, b, z[1]));
        let g = (g0.min(g1), g0.max(g1));
        let (lo, hi) = gamma;
        let (x0, x1) = (c * libm::exp(d * lo), c * libm::exp(d * hi));
        let (c0, c1) = (libm::cos(lo), libm::cos(hi));
        let cos2_max = (c0 * c0).max(c1 * c1);
        let cos2_min = if lo <= PI / 2.0 && PI / 2.0 <= hi {
            0.0
        } else {
            (c0 * c0).min(c1 * c1)
        };
        let (e0, e1) = (e * cos2_min, e * cos2_max);
        let f = (1.0 + x0.min(x1) + e0.min(e1), 1.0 + x0.max(x1) + e0.max(e1));
        let products = [g.0 * f.0, g.0 * f.1, g.1 * f.0, g.1 * f.1];
        products.into_iter().fold(0.0, f64::max)
    }
}

/// 1 + a·exp(b/max(cos ζ, 0.01)).
fn gradation(a: f64, b: f64, z: f64) -> f64 {
    1.0 + a * libm::exp(b / z.max(MIN_COS_ZENITH))
}

/// The day of the year (1 January = 1) of "YYYY-MM-DD" (Gregorian), or None.
pub fn day_of_year(date: &str) -> Option<f64> {
    let parts: Vec<i64> = (date.trim().split('-'))
        .map(|p| p.trim().parse().ok())
        .collect::<Option<_>>()?;
    let [y, m, d] = parts[..] else { return None };
    let leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    let (m, d) = (usize::try_from(m).ok()?, usize::try_from(d).ok()?);
    crate::weather::day_of_year(m, d, leap).map(|n| n as f64)
}

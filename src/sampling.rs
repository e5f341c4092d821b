//! Sampling of directions and points, shared by emission, scattering, receivers,
//! photometry and the eye pass.

use glam::{DVec3, Vec3};
use rand::RngCore;
use rand_pcg::Pcg32;

/// A uniform random number in [0, 1) from one 32-bit draw: ample resolution for
/// sampling positions and directions, at half the cost of a 53-bit draw.
#[inline]
pub fn uniform(rng: &mut Pcg32) -> f64 {
    rng.next_u32() as f64 * (1.0 / 4_294_967_296.0)
}

/// Where `x` in [0, 1) falls in the cumulative sums `cdf` (non-decreasing, read through
/// `sum`): the index of the interval holding it and `x`'s fraction across that interval,
/// in [0, 1) and uniform again when `x` is. Inversion keeps neighbouring numbers in
/// neighbouring intervals, which a QMC point's strata need. Zero-width intervals are never
/// chosen (all zero: the last, with `x` as it is).
#[inline]
pub fn invert_cdf<T>(cdf: &[T], sum: impl Fn(&T) -> f64, x: f64) -> (usize, f64) {
    let last = cdf.len() - 1;
    let y = x * sum(&cdf[last]);
    let k = cdf.partition_point(|c| sum(c) <= y).min(last);
    let (lo, hi) = (if k == 0 { 0.0 } else { sum(&cdf[k - 1]) }, sum(&cdf[k]));
    let fraction = if hi > lo { (y - lo) / (hi - lo) } else { x };
    (k, fraction.clamp(0.0, 1.0 - f64::EPSILON / 2.0))
}

/// A uniform random number in [0, 1) as an f32 from one 32-bit draw (24 bits kept):
/// for directions handed to the ray caster, which takes f32 anyway.
#[inline]
pub fn uniform_f32(rng: &mut Pcg32) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// cos θ and sin θ for |θ| ≤ π/4 by their Taylor polynomials (errors below 10⁻¹¹): no
/// library call, no range reduction, no branch.
#[inline(always)]
fn cos_sin_quarter(t: f64) -> (f64, f64) {
    let t2 = t * t;
    let sin = t
        * (1.0
            + t2 * (-1.0 / 6.0
                + t2 * (1.0 / 120.0
                    + t2 * (-1.0 / 5040.0 + t2 * (1.0 / 362_880.0 - t2 / 39_916_800.0)))));
    let cos = 1.0
        + t2 * (-0.5
            + t2 * (1.0 / 24.0
                + t2 * (-1.0 / 720.0
                    + t2 * (1.0 / 40_320.0 + t2 * (-1.0 / 3_628_800.0 + t2 / 479_001_600.0)))));
    (cos, sin)
}

/// [`cos_sin_quarter`] in f32 (errors below 10⁻⁸, under f32's resolution).
#[inline(always)]
fn cos_sin_quarter_f32(t: f32) -> (f32, f32) {
    let t2 = t * t;
    let sin =
        t * (1.0 + t2 * (-1.0 / 6.0 + t2 * (1.0 / 120.0 + t2 * (-1.0 / 5040.0 + t2 / 362_880.0))));
    let cos = 1.0
        + t2 * (-0.5
            + t2 * (1.0 / 24.0 + t2 * (-1.0 / 720.0 + t2 * (1.0 / 40_320.0 - t2 / 3_628_800.0))));
    (cos, sin)
}

/// The concentric map (Shirley and Chiu 1997) of the square [-1, 1]² onto the unit disk:
/// area-preserving, so uniform (a, b) give a uniform point of the disk, in closed form
/// (no rejection loop, whose unpredictable exit cost more than the arithmetic).
#[inline(always)]
fn concentric(a: f64, b: f64) -> (f64, f64) {
    // Selects, not branches: which of |a|, |b| is larger is a coin toss.
    let wide = a.abs() > b.abs();
    let hi = if wide { a } else { b };
    let lo = if wide { b } else { a };
    let t = lo / if hi == 0.0 { 1.0 } else { hi };
    let (c, s) = cos_sin_quarter(std::f64::consts::FRAC_PI_4 * t);
    let (p, q) = (hi * c, hi * s);
    (if wide { p } else { q }, if wide { q } else { p })
}

/// [`concentric`] in f32, with the radius: (x, y, r), r = √(x² + y²) exactly (|a| or
/// |b|), so that 1 − r² can be formed as (1 − r)(1 + r) without cancellation.
#[inline(always)]
fn concentric_f32(a: f32, b: f32) -> (f32, f32, f32) {
    // Selects, not branches: which of |a|, |b| is larger is a coin toss.
    let wide = a.abs() > b.abs();
    let hi = if wide { a } else { b };
    let lo = if wide { b } else { a };
    let t = lo / if hi == 0.0 { 1.0 } else { hi };
    let (c, s) = cos_sin_quarter_f32(std::f32::consts::FRAC_PI_4 * t);
    let (p, q) = (hi * c, hi * s);
    (if wide { p } else { q }, if wide { q } else { p }, hi.abs())
}

/// A point uniformly distributed in the unit disk (two draws, concentric map).
#[inline]
pub fn unit_disk(rng: &mut Pcg32) -> (f64, f64) {
    let a = 2.0 * uniform(rng) - 1.0;
    let b = 2.0 * uniform(rng) - 1.0;
    concentric(a, b)
}

/// [`unit_disk`] in f32.
#[inline]
pub fn unit_disk_f32(rng: &mut Pcg32) -> (f32, f32) {
    let a = 2.0 * uniform_f32(rng) - 1.0;
    let b = 2.0 * uniform_f32(rng) - 1.0;
    let (x, y, _) = concentric_f32(a, b);
    (x, y)
}

/// Duff et al.'s (2017) orthonormal basis, written once for both float widths: `$n` a
/// unit vector of type `$vec` with `$float` components. Expands to the same arithmetic
/// as a hand-written copy would, so each width keeps its bits and its speed.
macro_rules! duff_basis {
    ($n:expr, $vec:ident, $float:ty) => {{
        let n = $n;
        let sign = <$float>::copysign(1.0, n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        (
            $vec::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            $vec::new(b, sign + n.y * n.y * a, -n.y),
        )
    }};
}

/// Two unit vectors completing `n` (unit) to an orthonormal basis (Duff et al. 2017).
#[inline]
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    duff_basis!(n, DVec3, f64)
}

/// [`basis`] in f32.
#[inline(always)]
pub fn basis_f32(n: Vec3) -> (Vec3, Vec3) {
    duff_basis!(n, Vec3, f32)
}

/// A direction uniformly distributed over the unit sphere: a uniform point of the unit
/// disk lifted by Marsaglia's (1972) equal-area map (z = 1 − 2r²), one square root.
#[inline]
pub fn uniform_sphere(rng: &mut Pcg32) -> DVec3 {
    let (x, y) = unit_disk(rng);
    let r2 = x * x + y * y;
    let s = 2.0 * (1.0 - r2).max(0.0).sqrt();
    DVec3::new(x * s, y * s, 1.0 - 2.0 * r2)
}

/// A direction about `n` (unit) with cos θ uniform in [cos_max, 1]: uniform over the
/// cone's solid angle.
#[inline]
pub fn uniform_cone(rng: &mut Pcg32, n: DVec3, cos_max: f64) -> DVec3 {
    uniform_cone_band(rng, n, cos_max, 1.0)
}

/// A direction uniform in solid angle within band `band` of `bands` equal bands of
/// cos θ of the cone of half-angle cos⁻¹ `cos_half` about `n` (band 0 nearest the axis):
/// stratified cone sampling, as luminance meters' connections and samples draw it.
pub fn cone_band_direction(
    rng: &mut Pcg32,
    n: DVec3,
    cos_half: f64,
    band: f64,
    bands: f64,
) -> DVec3 {
    let cos_lo = 1.0 - (1.0 - cos_half) * (band + 1.0) / bands;
    let cos_hi = 1.0 - (1.0 - cos_half) * band / bands;
    uniform_cone_band(rng, n, cos_lo, cos_hi)
}

/// A direction about `n` (unit), uniform over the solid angle of the band
/// cos_lo ≤ cos θ ≤ cos_hi.
#[inline]
pub fn uniform_cone_band(rng: &mut Pcg32, n: DVec3, cos_lo: f64, cos_hi: f64) -> DVec3 {
    let (u, v) = (uniform(rng), uniform(rng));
    cone_from_square(n, cos_lo, cos_hi, (u, v))
}

/// [`uniform_cone_band`]'s direction from the point (u, v) of [0, 1)²: u picks cos θ, v
/// the azimuth.
#[inline]
pub fn cone_from_square(n: DVec3, cos_lo: f64, cos_hi: f64, (u, v): (f64, f64)) -> DVec3 {
    around(n, cos_hi - u * (cos_hi - cos_lo), std::f64::consts::TAU * v)
}

/// A cosine-weighted (Lambertian) direction in the hemisphere about `n` (unit): a
/// uniform point of the unit disk lifted to the hemisphere (Malley's method).
#[inline]
pub fn cosine_hemisphere(rng: &mut Pcg32, n: DVec3) -> DVec3 {
    let (x, y) = unit_disk(rng);
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    let (t, b) = basis(n);
    (t * x + b * y + n * z).normalize()
}

/// [`cosine_hemisphere`] in f32, for directions that go straight to the ray caster
/// (the same two draws as [`cosine_from_square`]).
#[inline]
pub fn cosine_hemisphere_f32(rng: &mut Pcg32, n: Vec3) -> Vec3 {
    let u = uniform_f32(rng);
    let v = uniform_f32(rng);
    cosine_from_square(u, v, n)
}

/// The cosine-weighted direction about `n` (unit) at the point (u, v) of [0, 1)²: the
/// concentric disk lifted to the hemisphere (Malley), in f32 and without a branch, so
/// a loop over lanes vectorises. Its length is 1 to f32 rounding (a few 10⁻⁷): not
/// normalised.
#[inline(always)]
pub fn cosine_from_square(u: f32, v: f32, n: Vec3) -> Vec3 {
    let (x, y, r) = concentric_f32(2.0 * u - 1.0, 2.0 * v - 1.0);
    let z = ((1.0 - r) * (1.0 + r)).sqrt();
    let (t, b) = basis_f32(n);
    t * x + b * y + n * z
}

/// The uniform direction of the sphere at the point (u, v) of [0, 1)²: the concentric
/// disk lifted by Marsaglia's equal-area map, in f32 and without a branch (see
/// [`cosine_from_square`]).
#[inline(always)]
pub fn sphere_from_square(u: f32, v: f32) -> Vec3 {
    let (x, y, r) = concentric_f32(2.0 * u - 1.0, 2.0 * v - 1.0);
    // 1 − r² without cancellation near the rim (the pole z = −1).
    let one_minus_r2 = (1.0 - r) * (1.0 + r);
    let s = 2.0 * one_minus_r2.sqrt();
    Vec3::new(x * s, y * s, 2.0 * one_minus_r2 - 1.0)
}

/// The unit direction at polar angle acos(cos_t) and azimuth `phi` about `n`.
#[inline]
fn around(n: DVec3, cos_t: f64, phi: f64) -> DVec3 {
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let (t, b) = basis(n);
    (t * (sin_t * libm::cos(phi)) + b * (sin_t * libm::sin(phi)) + n * cos_t).normalize()
}

/// A point uniformly distributed on the disk of `radius` about `center`, normal `n`.
#[inline]
pub fn uniform_disk(rng: &mut Pcg32, center: DVec3, n: DVec3, radius: f64) -> DVec3 {
    let (x, y) = unit_disk(rng);
    let (t, b) = basis(n);
    center + t * (radius * x) + b * (radius * y)
}

/// A rectangle (orthogonal edges `ex`, `ey` from `corner`) as seen from a point:
/// uniform sampling of its solid angle (Ureña, Fajardo and King 2013, "An
/// area-preserving parametrization for spherical rectangles", as in pbrt-v4). Light
/// from a Lambertian rectangle of luminance L then arrives with the constant weight
/// L·Ω per sample, however close or grazing the point: no 1/d² in the estimate.
#[derive(Clone, Copy, Debug)]
pub struct SphericalRect {
    origin: DVec3,
    x: DVec3,
    y: DVec3,
    z: DVec3,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    z0: f64,
    b0: f64,
    b1: f64,
    k: f64,
    /// Solid angle subtended (sr).
    pub solid_angle_sr: f64,
}

impl SphericalRect {
    /// The rectangle as seen from `p`; `None` when it subtends no solid angle (p in its
    /// plane) or the edges are not orthogonal.
    pub fn new(p: DVec3, corner: DVec3, ex: DVec3, ey: DVec3) -> Option<SphericalRect> {
        let (exl, eyl) = (ex.length(), ey.length());
        let (x, y) = (ex / exl, ey / eyl);
        if x.dot(y).abs() > 1e-9 {
            return None;
        }
        let mut z = x.cross(y);
        let d = corner - p;
        let mut z0 = d.dot(z);
        // z points away from the rectangle.
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        let (x0, y0) = (d.dot(x), d.dot(y));
        let (x1, y1) = (x0 + exl, y0 + eyl);
        // The interior angles g0..g3 at the corners of the spherical rectangle, from the
        // normals of the planes through the eye and each edge, in closed form.
        let z2 = z0 * z0;
        let (rx0, rx1) = ((z2 + x0 * x0).sqrt(), (z2 + x1 * x1).sqrt());
        let (ry0, ry1) = ((z2 + y0 * y0).sqrt(), (z2 + y1 * y1).sqrt());
        let angle = |c: f64| libm::acos(c.clamp(-1.0, 1.0));
        let g0 = angle(x1 * y0 / (ry0 * rx1));
        let g1 = angle(-x1 * y1 / (rx1 * ry1));
        let g2 = angle(x0 * y1 / (rx0 * ry1));
        let g3 = angle(-x0 * y0 / (rx0 * ry0));
        let solid_angle_sr = g0 + g1 + g2 + g3 - std::f64::consts::TAU;
        if !(solid_angle_sr > 0.0 && z0 < 0.0) {
            return None;
        }
        Some(SphericalRect {
            origin: p,
            x,
            y,
            z,
            x0,
            x1,
            y0,
            y1,
            z0,
            b0: -y0 / ry0,
            b1: y1 / ry1,
            k: std::f64::consts::TAU - g2 - g3,
            solid_angle_sr,
        })
    }

    /// The point of the rectangle at parameters (u, v) ∈ [0, 1)²: uniform (u, v) give
    /// directions uniform over the solid angle, and strata of (u, v) strata of it.
    pub fn sample(&self, u: f64, v: f64) -> DVec3 {
        let au = u * self.solid_angle_sr + self.k;
        let fu = (libm::cos(au) * self.b0 - self.b1) / libm::sin(au);
        let cu = (1.0 / (fu * fu + self.b0 * self.b0).sqrt())
            .copysign(fu)
            .clamp(-1.0 + 1e-15, 1.0 - 1e-15);
        let xu = (-(cu * self.z0) / (1.0 - cu * cu).max(0.0).sqrt()).clamp(self.x0, self.x1);
        let d2 = xu * xu + self.z0 * self.z0;
        let d = d2.sqrt();
        let h0 = self.y0 / (d2 + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d2 + self.y1 * self.y1).sqrt();
        let hv = h0 + v * (h1 - h0);
        let hv2 = hv * hv;
        let yv = if hv2 < 1.0 - 1e-12 {
            (hv * d / (1.0 - hv2).sqrt()).clamp(self.y0, self.y1)
        } else {
            self.y1
        };
        self.origin + self.x * xu + self.y * yv + self.z * self.z0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal_for_all_octants() {
        let mut rng = crate::rng::aux_stream(3);
        for _ in 0..1000 {
            let n = uniform_sphere(&mut rng);
            let (t, b) = basis(n);
            for (x, y) in [(t, b), (t, n), (b, n)] {
                assert!(x.dot(y).abs() < 1e-12);
            }
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn uniform_sphere_has_zero_mean_and_a_third_per_axis() {
        let mut rng = crate::rng::aux_stream(5);
        let k = 200_000;
        let (mut mean, mut sq) = (DVec3::ZERO, DVec3::ZERO);
        for _ in 0..k {
            let d = uniform_sphere(&mut rng);
            assert!((d.length() - 1.0).abs() < 1e-12);
            mean += d;
            sq += d * d;
        }
        let (mean, sq) = (mean / k as f64, sq / k as f64);
        // Var(x) = 1/3, Var(x²) = 1/5 − 1/9 = 4/45 for a uniform direction.
        let (s1, s2) = (
            (1.0 / 3.0 / k as f64).sqrt(),
            (4.0 / 45.0 / k as f64).sqrt(),
        );
        for a in 0..3 {
            assert!(mean[a].abs() < 4.0 * s1, "mean {mean}");
            assert!((sq[a] - 1.0 / 3.0).abs() < 4.0 * s2, "second moment {sq}");
        }
    }

    #[test]
    fn cosine_hemisphere_has_mean_cosine_two_thirds() {
        let mut rng = crate::rng::aux_stream(4);
        let n = DVec3::new(0.3, -0.5, 0.8).normalize();
        let k = 200_000;
        let cosines: Vec<f64> = (0..k)
            .map(|_| cosine_hemisphere(&mut rng, n).dot(n))
            .collect();
        assert!(cosines.iter().all(|c| *c >= 0.0));
        let mean = cosines.iter().sum::<f64>() / k as f64;
        // Var(cos) = 1/2 − 4/9 = 1/18 for the cosine-weighted distribution.
        let sigma = (1.0 / 18.0 / k as f64).sqrt();
        assert!((mean - 2.0 / 3.0).abs() < 4.0 * sigma, "mean cos {mean}");
    }

    /// Pearson's χ² of `k` points of [0, 1)² (each sampler's coordinates mapped so that
    /// its exact density becomes uniform) over `m` × `m` equal cells, against its bound:
    /// the mean (m² − 1) plus 5 of its standard deviations √(2(m² − 1)).
    fn chi_square_is_uniform(k: usize, m: usize, mut point: impl FnMut() -> (f64, f64)) {
        let mut counts = vec![0u32; m * m];
        for _ in 0..k {
            let (u, v) = point();
            assert!(
                (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v),
                "{u} {v}"
            );
            let (i, j) = (
                ((u * m as f64) as usize).min(m - 1),
                ((v * m as f64) as usize).min(m - 1),
            );
            counts[i * m + j] += 1;
        }
        let expected = k as f64 / (m * m) as f64;
        let chi2: f64 = (counts.iter())
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        let dof = (m * m - 1) as f64;
        assert!(
            chi2 < dof + 5.0 * (2.0 * dof).sqrt(),
            "χ² {chi2} for {dof} dof"
        );
    }

    /// The azimuth of (x, y) as a fraction of a turn, in [0, 1].
    fn turn(x: f64, y: f64) -> f64 {
        libm::atan2(y, x) / std::f64::consts::TAU + 0.5
    }

    #[test]
    fn unit_disk_density_is_uniform() {
        // Uniform in the disk ⇔ r² and the azimuth uniform and independent.
        let mut rng = crate::rng::aux_stream(21);
        chi_square_is_uniform(400_000, 16, || {
            let (x, y) = unit_disk(&mut rng);
            (x * x + y * y, turn(x, y))
        });
        let mut rng = crate::rng::aux_stream(22);
        chi_square_is_uniform(400_000, 16, || {
            let (x, y) = unit_disk_f32(&mut rng);
            let (x, y) = (x as f64, y as f64);
            (x * x + y * y, turn(x, y))
        });
    }

    #[test]
    fn uniform_disk_density_is_uniform() {
        let mut rng = crate::rng::aux_stream(23);
        let (c, n) = (DVec3::new(1.0, -2.0, 3.0), DVec3::new(-0.6, 0.0, 0.8));
        let (t, b) = basis(n);
        chi_square_is_uniform(200_000, 12, || {
            let d = (uniform_disk(&mut rng, c, n, 2.5) - c) / 2.5;
            assert!(d.dot(n).abs() < 1e-12);
            let (x, y) = (d.dot(t), d.dot(b));
            (x * x + y * y, turn(x, y))
        });
    }

    #[test]
    fn uniform_sphere_density_is_uniform() {
        // Uniform on the sphere ⇔ z and the azimuth uniform and independent.
        let mut rng = crate::rng::aux_stream(24);
        chi_square_is_uniform(400_000, 16, || {
            let d = uniform_sphere(&mut rng);
            assert!((d.length() - 1.0).abs() < 1e-12);
            ((d.z + 1.0) / 2.0, turn(d.x, d.y))
        });
        let mut rng = crate::rng::aux_stream(29);
        chi_square_is_uniform(400_000, 16, || {
            let (u, v) = (uniform_f32(&mut rng), uniform_f32(&mut rng));
            let d = sphere_from_square(u, v).as_dvec3();
            assert!((d.length() - 1.0).abs() < 1e-6);
            (((d.z + 1.0) / 2.0).clamp(0.0, 1.0), turn(d.x, d.y))
        });
    }

    #[test]
    fn cosine_hemisphere_density_is_cosine() {
        // Density cos θ / π ⇔ sin²θ and the azimuth about n uniform and independent.
        let n = DVec3::new(0.3, -0.5, 0.8).normalize();
        let (t, b) = basis(n);
        let mut rng = crate::rng::aux_stream(25);
        chi_square_is_uniform(400_000, 16, || {
            let d = cosine_hemisphere(&mut rng, n);
            assert!((d.length() - 1.0).abs() < 1e-12 && d.dot(n) >= 0.0);
            let (x, y) = (d.dot(t), d.dot(b));
            (x * x + y * y, turn(x, y))
        });
        for (seed, n) in [(26, n), (27, DVec3::new(0.0, 0.0, -1.0)), (28, DVec3::X)] {
            let n32 = n.as_vec3();
            let (t, b) = basis(n);
            let mut rng = crate::rng::aux_stream(seed);
            chi_square_is_uniform(400_000, 16, || {
                let d = cosine_hemisphere_f32(&mut rng, n32).as_dvec3();
                assert!((d.length() - 1.0).abs() < 1e-6 && d.dot(n) >= -1e-7);
                let (x, y) = (d.dot(t), d.dot(b));
                ((x * x + y * y).min(1.0), turn(x, y))
            });
        }
    }

    /// The f32 maps at the edges of their domain: every corner, edge and centre of
    /// [0, 1]² (1 itself included, though `uniform_f32` stops at 1 − 2⁻²⁴), and the
    /// points next to the rim of the disk (r → 1, where 1 − r² cancels): finite, unit
    /// length to f32 rounding, in the right hemisphere.
    #[test]
    fn f32_maps_hold_at_the_domain_edges() {
        let last = 1.0 - f32::EPSILON / 2.0; // the largest `uniform_f32`
        let edge = [0.0, f32::EPSILON / 2.0, 0.25, 0.5, 0.75, last, 1.0];
        let normals = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.0, -1.0, 1e-7).normalize(),
            Vec3::new(0.3, -0.5, 0.8).normalize(),
        ];
        for &u in &edge {
            for &v in &edge {
                let w = sphere_from_square(u, v);
                assert!(w.is_finite(), "sphere ({u}, {v}) → {w}");
                assert!((w.length() - 1.0).abs() < 1e-6, "sphere ({u}, {v}) → {w}");
                assert!((-1.0..=1.0).contains(&w.z));
                for n in normals {
                    let d = cosine_from_square(u, v, n);
                    assert!(d.is_finite(), "cosine ({u}, {v}) about {n} → {d}");
                    assert!((d.length() - 1.0).abs() < 1e-6, "({u}, {v}) {n} → {d}");
                    assert!(d.dot(n) >= -1e-6, "({u}, {v}) about {n} → {d}");
                }
            }
        }
        // The rim: |a| or |b| = 1 maps to r = 1 exactly, the sphere's south pole and the
        // hemisphere's horizon; next to it, 1 − r² keeps its digits.
        let w = sphere_from_square(0.0, 0.5);
        assert_eq!(w.z, -1.0);
        let d = cosine_from_square(1.0, 0.5, Vec3::Z);
        assert_eq!(d.z, 0.0);
        let near = sphere_from_square(last, 0.5);
        let r = 2.0 * last - 1.0;
        let exact = 2.0 * (1.0 - r as f64 * r as f64) - 1.0;
        assert!((near.z as f64 - exact).abs() < 1e-6 * (1.0 + exact.abs()));
        // The centre maps to the pole (the concentric map's 0/0 is guarded).
        assert_eq!(concentric_f32(0.0, 0.0), (0.0, 0.0, 0.0));
        assert_eq!(concentric(0.0, 0.0), (0.0, 0.0));
        assert_eq!(cosine_from_square(0.5, 0.5, Vec3::Z), Vec3::Z);
    }

    /// The f32 cosine map's first moments about its normal: E[cos θ] = 2/3 and
    /// E[cos² θ] = 1/2 for the density cos θ/π, within 5σ of their sampling error.
    #[test]
    fn f32_cosine_moments_follow_the_cosine_law() {
        let n = Vec3::new(-0.2, 0.9, 0.4).normalize();
        let mut rng = crate::rng::aux_stream(31);
        let k = 200_000;
        let (mut m1, mut m2) = (0.0, 0.0);
        for _ in 0..k {
            let (u, v) = (uniform_f32(&mut rng), uniform_f32(&mut rng));
            let c = cosine_from_square(u, v, n).dot(n) as f64;
            (m1, m2) = (m1 + c, m2 + c * c);
        }
        let (m1, m2) = (m1 / k as f64, m2 / k as f64);
        // Var cos θ = 1/2 − 4/9 = 1/18; Var cos² θ = E[cos⁴] − 1/4 = 1/3 − 1/4 = 1/12.
        let (s1, s2) = (
            (1.0 / 18.0 / k as f64).sqrt(),
            (1.0 / 12.0 / k as f64).sqrt(),
        );
        assert!((m1 - 2.0 / 3.0).abs() < 5.0 * s1, "E[cos] {m1}");
        assert!((m2 - 0.5).abs() < 5.0 * s2, "E[cos²] {m2}");
    }

    #[test]
    fn quarter_polynomials_match_the_library() {
        for k in -1000..=1000 {
            let t = std::f64::consts::FRAC_PI_4 * k as f64 / 1000.0;
            let (c, s) = cos_sin_quarter(t);
            assert!(
                (c - libm::cos(t)).abs() < 1e-11 && (s - libm::sin(t)).abs() < 1e-11,
                "{t}"
            );
            let (c, s) = cos_sin_quarter_f32(t as f32);
            let (c, s) = (c as f64, s as f64);
            assert!(
                (c - libm::cos(t)).abs() < 3e-7 && (s - libm::sin(t)).abs() < 3e-7,
                "{t}"
            );
        }
    }

    #[test]
    fn spherical_rect_samples_are_uniform_in_solid_angle() {
        // A 2 × 1 rectangle 0.05 above a point near its edge: E = L∫cos θ dω, estimated
        // with Ω·mean(cos θ), must match the exact irradiance of the rectangle (the
        // polygon formula) to the sampling error of jittered strata.
        let (corner, ex, ey) = (DVec3::new(-0.1, -0.5, 0.05), DVec3::X * 2.0, DVec3::Y);
        let p = DVec3::ZERO;
        let rect = SphericalRect::new(p, corner, ex, ey).unwrap();
        let m = 64;
        let mut rng = crate::rng::aux_stream(11);
        let mut sum = 0.0;
        for k in 0..m * m {
            let u = ((k % m) as f64 + uniform(&mut rng)) / m as f64;
            let v = ((k / m) as f64 + uniform(&mut rng)) / m as f64;
            let q = rect.sample(u, v);
            assert!((q.z - 0.05).abs() < 1e-12 && q.x >= -0.1 - 1e-12 && q.x <= 1.9 + 1e-12);
            sum += (q - p).normalize().z;
        }
        let estimate = rect.solid_angle_sr * sum / (m * m) as f64;
        let corners = [corner, corner + ex, corner + ex + ey, corner + ey];
        let exact: f64 = (0..4)
            .map(|i| {
                let (a, b) = (corners[i] - p, corners[(i + 1) % 4] - p);
                let c = a.cross(b);
                libm::acos(a.normalize().dot(b.normalize())) * c.z / c.length()
            })
            .sum::<f64>()
            .abs()
            / 2.0;
        assert!(
            (estimate - exact).abs() < 1e-4 * exact,
            "{estimate} vs {exact}"
        );
    }
}

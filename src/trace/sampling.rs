//! Sampling of directions and points, shared by emission and scattering.

use glam::DVec3;
use rand::RngCore;
use rand_pcg::Pcg32;

/// A uniform random number in [0, 1) from one 32-bit draw: ample resolution for
/// sampling positions and directions, at half the cost of a 53-bit draw.
#[inline]
pub fn uniform(rng: &mut Pcg32) -> f64 {
    rng.next_u32() as f64 * (1.0 / 4_294_967_296.0)
}

/// A point uniformly distributed in the unit disk, by rejection from the square (no
/// trigonometry; 78.5 % of draws are accepted).
#[inline]
fn unit_disk(rng: &mut Pcg32) -> (f64, f64) {
    loop {
        let x = 2.0 * uniform(rng) - 1.0;
        let y = 2.0 * uniform(rng) - 1.0;
        if x * x + y * y < 1.0 {
            return (x, y);
        }
    }
}

/// Two unit vectors completing `n` (unit) to an orthonormal basis (Duff et al. 2017).
#[inline]
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0_f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A direction uniformly distributed over the unit sphere (Marsaglia 1972: from a
/// uniform point of the unit disk, no trigonometry).
#[inline]
pub fn uniform_sphere(rng: &mut Pcg32) -> DVec3 {
    let (x, y) = unit_disk(rng);
    let r2 = x * x + y * y;
    let s = 2.0 * (1.0 - r2).sqrt();
    DVec3::new(x * s, y * s, 1.0 - 2.0 * r2)
}

/// A direction about `n` (unit) with cos θ uniform in [cos_max, 1]: uniform over the
/// cone's solid angle.
#[inline]
pub fn uniform_cone(rng: &mut Pcg32, n: DVec3, cos_max: f64) -> DVec3 {
    uniform_cone_band(rng, n, cos_max, 1.0)
}

/// A direction about `n` (unit), uniform over the solid angle of the band
/// cos_lo ≤ cos θ ≤ cos_hi.
#[inline]
pub fn uniform_cone_band(rng: &mut Pcg32, n: DVec3, cos_lo: f64, cos_hi: f64) -> DVec3 {
    let cos_t = cos_hi - uniform(rng) * (cos_hi - cos_lo);
    around(n, cos_t, std::f64::consts::TAU * uniform(rng))
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

/// The unit direction at polar angle acos(cos_t) and azimuth `phi` about `n`.
#[inline]
fn around(n: DVec3, cos_t: f64, phi: f64) -> DVec3 {
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let (t, b) = basis(n);
    (t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + n * cos_t).normalize()
}

/// A point uniformly distributed on the disk of `radius` about `center`, normal `n`.
#[inline]
pub fn uniform_disk(rng: &mut Pcg32, center: DVec3, n: DVec3, radius: f64) -> DVec3 {
    let r = radius * uniform(rng).sqrt();
    let phi = std::f64::consts::TAU * uniform(rng);
    let (t, b) = basis(n);
    center + t * (r * phi.cos()) + b * (r * phi.sin())
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
}

//! Sampling of directions and points, shared by emission and scattering.

use glam::DVec3;
use rand::Rng;
use rand_pcg::Pcg32;

/// A uniform random number in [0, 1) with 53 bits.
#[inline]
pub fn uniform(rng: &mut Pcg32) -> f64 {
    rng.random::<f64>()
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

/// A direction uniformly distributed over the unit sphere.
#[inline]
pub fn uniform_sphere(rng: &mut Pcg32) -> DVec3 {
    let z = 1.0 - 2.0 * uniform(rng);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f64::consts::TAU * uniform(rng);
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A direction about `n` (unit) with cos θ uniform in [cos_max, 1]: uniform over the
/// cone's solid angle.
#[inline]
pub fn uniform_cone(rng: &mut Pcg32, n: DVec3, cos_max: f64) -> DVec3 {
    let cos_t = 1.0 - uniform(rng) * (1.0 - cos_max);
    around(n, cos_t, std::f64::consts::TAU * uniform(rng))
}

/// A cosine-weighted (Lambertian) direction in the hemisphere about `n` (unit).
#[inline]
pub fn cosine_hemisphere(rng: &mut Pcg32, n: DVec3) -> DVec3 {
    let cos_t = uniform(rng).sqrt();
    around(n, cos_t, std::f64::consts::TAU * uniform(rng))
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

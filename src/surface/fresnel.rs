//! The laws of an ideal interface: mirror reflection, Snell's refraction and the one
//! Fresnel reflectance of a dielectric, [`fresnel_from_cosines`], which the ideal glass
//! (through [`refract`]) and the rough dielectric (through [`fr_dielectric`]) share.

use glam::DVec3;

/// Mirror reflection of `dir` about the unit normal `n`.
#[inline]
pub fn reflect(dir: DVec3, n: DVec3) -> DVec3 {
    (dir - n * (2.0 * dir.dot(n))).normalize()
}

/// Refraction of unit `dir` through a surface whose unit normal `facing` points against
/// it, with relative index `eta` = n_incident / n_transmitted. Returns the refracted
/// direction and the unpolarised Fresnel reflectance, or `None` on total internal
/// reflection.
#[inline]
pub fn refract(dir: DVec3, facing: DVec3, eta: f64) -> Option<(DVec3, f64)> {
    let cos_i = -dir.dot(facing);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let refracted = (dir * eta + facing * (eta * cos_i - cos_t)).normalize();
    Some((refracted, fresnel_from_cosines(cos_i, cos_t, eta)))
}

/// Unpolarised Fresnel reflectance of a dielectric for cos θ to the normal on the side
/// of `cos_i`'s sign and `eta` = n(below)/n(above) (pbrt-v4's `FrDielectric`); 1 on
/// total internal reflection.
#[inline]
pub fn fr_dielectric(cos_i: f64, eta: f64) -> f64 {
    let (mut cos_i, mut eta) = (cos_i.clamp(-1.0, 1.0), eta);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    fresnel_from_cosines(cos_i, cos_t, eta)
}

/// The Fresnel equations: unpolarised reflectance from the cosines of the incident and
/// transmitted angles and the index ratio `eta`, either n_t/n_i or n_i/n_t (swapping
/// the ratio swaps the two polarisations' terms, whose mean is the same).
#[inline]
pub fn fresnel_from_cosines(cos_i: f64, cos_t: f64, eta: f64) -> f64 {
    let r_1 = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_2 = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_1 * r_1 + r_2 * r_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_at_normal_incidence_is_squared_index_ratio() {
        let n = 1.5f64;
        let want = ((n - 1.0) / (n + 1.0)).powi(2);
        assert!((fresnel_from_cosines(1.0, 1.0, 1.0 / n) - want).abs() < 1e-15);
        assert!((fr_dielectric(1.0, n) - want).abs() < 1e-15);
        assert!((fr_dielectric(-1.0, n) - want).abs() < 1e-15);
    }

    #[test]
    fn refract_and_fr_dielectric_agree() {
        for cos_i in [0.05f64, 0.3, 0.7, 0.99] {
            let dir = DVec3::new((1.0 - cos_i * cos_i).sqrt(), 0.0, -cos_i);
            let (_, from_refract) = refract(dir, DVec3::Z, 1.0 / 1.5).unwrap();
            assert!((from_refract - fr_dielectric(cos_i, 1.5)).abs() < 1e-14);
        }
    }

    #[test]
    fn refraction_obeys_snell_and_total_internal_reflection() {
        let dir = DVec3::new(0.6, 0.0, -0.8);
        let (t, _) = refract(dir, DVec3::Z, 1.0 / 1.5).unwrap();
        assert!((0.6 - 1.5 * t.x).abs() < 1e-12, "sin θi = n sin θt");
        // Inside glass at 60° from the normal: beyond the critical angle (41.8°).
        let inside = DVec3::new(
            libm::sin(60f64.to_radians()),
            0.0,
            libm::cos(60f64.to_radians()),
        );
        assert!(refract(inside, -DVec3::Z, 1.5).is_none());
        assert_eq!(fr_dielectric(-0.5, 1.5), 1.0);
    }
}

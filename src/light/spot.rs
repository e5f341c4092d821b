//! Spot: `type = "spot"`, intensity I (cd) on its axis up to `falloff_deg` off it, then a
//! smooth fall to zero at `cone_deg`.

use super::{
    from_point, single, BoundingSphere, EmissionSquares, Emitter, Incoming, Labelled, Light,
    LightFile, LoadContext,
};
use crate::error::{Error, Result};
use crate::input::{amount, direction, required, vec3, Coords};
use crate::sampling::{cone_from_square, uniform, uniform_cone};
use glam::DVec3;
use rand_pcg::Pcg32;
use serde::Deserialize;
use std::f64::consts::TAU;
use std::sync::Arc;

/// The `[[lights]]` entry.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SpotFile {
    pub position: Option<Coords>,
    pub direction: Option<[f64; 3]>,
    pub intensity_cd: Option<f64>,
    pub cone_deg: Option<f64>,
    /// Default: `cone_deg` (a sharp edge).
    pub falloff_deg: Option<f64>,
}

impl LightFile for SpotFile {
    const TYPE: &'static str = "spot";

    fn into_lights(self, label: &str, at: &str, _: &mut LoadContext) -> Result<Vec<Labelled>> {
        let what = "type \"spot\" lights";
        let position = vec3(required(self.position, at, "position", what)?);
        let direction = direction(
            required(self.direction, at, "direction", what)?,
            at,
            "direction",
        )?;
        let intensity_cd = amount(
            required(self.intensity_cd, at, "intensity_cd", what)?,
            at,
            "intensity_cd",
        )?;
        let cone_deg = required(self.cone_deg, at, "cone_deg", what)?;
        if !(cone_deg > 0.0 && cone_deg <= 180.0) {
            return Err(Error::input(
                format!("{at}.cone_deg"),
                format!("must be in (0, 180], got {cone_deg}"),
            ));
        }
        let falloff_deg = self.falloff_deg.unwrap_or(cone_deg);
        if !(falloff_deg >= 0.0 && falloff_deg <= cone_deg) {
            return Err(Error::input(
                format!("{at}.falloff_deg"),
                format!("must be in [0, cone_deg = {cone_deg}], got {falloff_deg}"),
            ));
        }
        single(
            label,
            Spot {
                position,
                direction,
                intensity_cd,
                cone_deg,
                falloff_deg,
            },
        )
    }
}

/// Spot: intensity `intensity_cd` on axis up to `falloff_deg` off axis, then a smooth
/// (smoothstep in cos θ) fall to zero at `cone_deg`. World coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Spot {
    pub position: DVec3,
    /// Unit axis, the way the light goes.
    pub direction: DVec3,
    pub intensity_cd: f64,
    pub cone_deg: f64,
    pub falloff_deg: f64,
}

/// The smooth spot profile: 1 inside the falloff angle, 0 outside the cone, a smoothstep
/// in cos θ between (so intensity and its slope are continuous).
#[inline]
pub fn spot_profile(cos_theta: f64, cos_cone: f64, cos_falloff: f64) -> f64 {
    if cos_theta >= cos_falloff {
        1.0
    } else if cos_theta <= cos_cone {
        0.0
    } else {
        let s = (cos_theta - cos_cone) / (cos_falloff - cos_cone);
        s * s * (3.0 - 2.0 * s)
    }
}

impl Light for Spot {
    fn flux_lm(&self, _: &BoundingSphere) -> f64 {
        let (cos_cone, cos_falloff) = (
            libm::cos(self.cone_deg.to_radians()),
            libm::cos(self.falloff_deg.to_radians()),
        );
        // ∫ I dω: full core, plus the smoothstep ramp whose mean over cos θ is 1/2.
        TAU * self.intensity_cd * ((1.0 - cos_falloff) + 0.5 * (cos_falloff - cos_cone))
    }

    fn emitter(&self, origin: DVec3, _: &BoundingSphere) -> Arc<dyn Emitter> {
        Arc::new(SpotEmitter {
            position: self.position - origin,
            axis: self.direction.normalize(),
            cos_cone: libm::cos(self.cone_deg.to_radians()),
            cos_falloff: libm::cos(self.falloff_deg.to_radians()),
            intensity_cd: self.intensity_cd,
        })
    }
}

#[derive(Clone, Debug)]
struct SpotEmitter {
    position: DVec3,
    axis: DVec3,
    /// cos of the cut-off half-angle (`cone_deg`).
    cos_cone: f64,
    /// cos of the half-angle up to which intensity is full (`falloff_deg`).
    cos_falloff: f64,
    intensity_cd: f64,
}

impl Emitter for SpotEmitter {
    #[inline]
    fn sample_emission(&self, rng: &mut Pcg32) -> (DVec3, DVec3) {
        loop {
            // Rejection from the uniform cone: exact for any profile bounded by 1.
            let dir = uniform_cone(rng, self.axis, self.cos_cone);
            if uniform(rng) < spot_profile(dir.dot(self.axis), self.cos_cone, self.cos_falloff) {
                break (self.position, dir);
            }
        }
    }

    /// The first proposal from `direction`, later ones (after a rejection) from `rng`:
    /// each proposal is uniform in the cone and independent of the test, so the
    /// density is `sample_emission`'s.
    fn direction_from_square(&self) -> bool {
        true
    }

    fn sample_emission_from(&self, squares: EmissionSquares, rng: &mut Pcg32) -> (DVec3, DVec3) {
        let dir = cone_from_square(self.axis, self.cos_cone, 1.0, squares.direction);
        if uniform(rng) < spot_profile(dir.dot(self.axis), self.cos_cone, self.cos_falloff) {
            return (self.position, dir);
        }
        self.sample_emission(rng)
    }

    fn incoming(&self, p: DVec3, _: &[(f64, f64)], each: &mut dyn FnMut(Incoming)) {
        if !(self.intensity_cd > 0.0) {
            return;
        }
        let towards_p = (p - self.position).normalize_or_zero();
        let profile = spot_profile(towards_p.dot(self.axis), self.cos_cone, self.cos_falloff);
        from_point(p, self.position, self.intensity_cd * profile, each);
    }

    fn extent(&self) -> (DVec3, f64) {
        (self.position, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_flux_matches_numeric_integral_of_profile() {
        let (cone, falloff) = (40.0_f64, 25.0_f64);
        let spot = Spot {
            position: DVec3::ZERO,
            direction: DVec3::Z,
            intensity_cd: 100.0,
            cone_deg: cone,
            falloff_deg: falloff,
        };
        let (cc, cf) = (libm::cos(cone.to_radians()), libm::cos(falloff.to_radians()));
        let n = 100_000;
        let numeric: f64 = (0..n)
            .map(|k| {
                let c = cc + (1.0 - cc) * (k as f64 + 0.5) / n as f64;
                spot_profile(c, cc, cf) * (1.0 - cc) / n as f64
            })
            .sum::<f64>()
            * TAU
            * 100.0;
        let sphere = BoundingSphere {
            center: DVec3::ZERO,
            radius: 0.0,
        };
        let exact = spot.flux_lm(&sphere);
        assert!(
            (numeric - exact).abs() < 1e-6 * exact,
            "{numeric} vs {exact}"
        );
    }
}

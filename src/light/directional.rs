//! Parallel source (sun, sky patch at infinity): `type = "directional"`, illuminance E
//! (lx) on a plane normal to its direction.

use super::{single, BoundingSphere, Emitter, Incoming, Labelled, Light, LightFile, LoadContext};
use crate::error::Result;
use crate::input::{amount, direction, required};
use crate::sampling::uniform_disk;
use glam::DVec3;
use rand_pcg::Pcg32;
use serde::Deserialize;
use std::f64::consts::PI;
use std::sync::Arc;

/// The `[[lights]]` entry.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct DirectionalFile {
    pub direction: Option<[f64; 3]>,
    pub illuminance_lx: Option<f64>,
}

impl LightFile for DirectionalFile {
    const TYPE: &'static str = "directional";

    fn into_lights(self, label: &str, at: &str, _: &mut LoadContext) -> Result<Vec<Labelled>> {
        let what = "type \"directional\" lights";
        let direction = direction(
            required(self.direction, at, "direction", what)?,
            at,
            "direction",
        )?;
        let illuminance_lx = amount(
            required(self.illuminance_lx, at, "illuminance_lx", what)?,
            at,
            "illuminance_lx",
        )?;
        single(
            label,
            Directional {
                direction,
                illuminance_lx,
            },
        )
    }
}

/// Parallel source: `illuminance_lx` on a plane normal to `direction` (unit, the way
/// the light travels).
#[derive(Clone, Debug, PartialEq)]
pub struct Directional {
    pub direction: DVec3,
    pub illuminance_lx: f64,
}

impl Light for Directional {
    /// Photons leave a disk of the scene's radius R: Φ = E·π·R².
    fn flux_lm(&self, sphere: &BoundingSphere) -> f64 {
        self.illuminance_lx * PI * sphere.radius * sphere.radius
    }

    fn emitter(&self, origin: DVec3, sphere: &BoundingSphere) -> Arc<dyn Emitter> {
        let direction = self.direction.normalize();
        Arc::new(DirectionalEmitter {
            direction,
            // Start outside the scene so every photon crosses all of it.
            disk_center: sphere.center - origin - direction * (sphere.radius * 1.01),
            disk_radius: sphere.radius,
            illuminance_lx: self.illuminance_lx,
        })
    }
}

#[derive(Clone, Debug)]
struct DirectionalEmitter {
    direction: DVec3,
    /// Centre and radius of the disk, normal to `direction`, photons start from.
    disk_center: DVec3,
    disk_radius: f64,
    illuminance_lx: f64,
}

impl Emitter for DirectionalEmitter {
    #[inline]
    fn sample_emission(&self, rng: &mut Pcg32) -> (DVec3, DVec3) {
        (
            uniform_disk(rng, self.disk_center, self.direction, self.disk_radius),
            self.direction,
        )
    }

    fn incoming(&self, _: DVec3, _: &[(f64, f64)], each: &mut dyn FnMut(Incoming)) {
        if self.illuminance_lx > 0.0 {
            each(Incoming {
                to_source: -self.direction,
                distance: f64::INFINITY,
                normal_lx: self.illuminance_lx,
            });
        }
    }

    fn extent(&self) -> (DVec3, f64) {
        (self.disk_center, 0.0)
    }
}

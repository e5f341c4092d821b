//! Isotropic point source: `type = "point"`, intensity I (cd) in every direction.

use super::{
    from_point, single, BoundingSphere, EmissionSquares, Emitter, Incoming, Labelled, Light,
    LightFile, LoadContext,
};
use crate::error::{Error, Result};
use crate::input::{amount, required, vec3, Coords};
use crate::rng::PhotonStreams;
use crate::sampling::{sphere_from_square, uniform_f32, uniform_sphere};
use glam::DVec3;
use rand_pcg::Pcg32;
use serde::Deserialize;
use std::f64::consts::PI;
use std::sync::Arc;

/// The `[[lights]]` entry: `position` and one of `intensity_cd`, `flux_lm`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct PointFile {
    pub position: Option<Coords>,
    pub intensity_cd: Option<f64>,
    pub flux_lm: Option<f64>,
}

impl LightFile for PointFile {
    const TYPE: &'static str = "point";

    fn into_lights(self, label: &str, at: &str, _: &mut LoadContext) -> Result<Vec<Labelled>> {
        let what = "type \"point\" lights";
        let position = vec3(required(self.position, at, "position", what)?);
        let intensity_cd = match (self.intensity_cd, self.flux_lm) {
            (Some(i), None) => amount(i, at, "intensity_cd")?,
            // Isotropic: Φ = 4π I.
            (None, Some(f)) => amount(f, at, "flux_lm")? / (4.0 * PI),
            _ => {
                return Err(Error::input(
                    at,
                    "give exactly one of `intensity_cd` and `flux_lm`",
                ))
            }
        };
        single(
            label,
            Point {
                position,
                intensity_cd,
            },
        )
    }
}

/// Isotropic point source (world coordinates).
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    pub position: DVec3,
    pub intensity_cd: f64,
}

impl Light for Point {
    fn flux_lm(&self, _: &BoundingSphere) -> f64 {
        4.0 * PI * self.intensity_cd
    }

    fn emitter(&self, origin: DVec3, _: &BoundingSphere) -> Arc<dyn Emitter> {
        Arc::new(PointEmitter {
            position: self.position - origin,
            intensity_cd: self.intensity_cd,
        })
    }
}

#[derive(Clone, Debug)]
struct PointEmitter {
    position: DVec3,
    intensity_cd: f64,
}

impl Emitter for PointEmitter {
    #[inline]
    fn sample_emission(&self, rng: &mut Pcg32) -> (DVec3, DVec3) {
        (self.position, uniform_sphere(rng))
    }

    fn direction_from_square(&self) -> bool {
        true
    }

    fn sample_emission_from(&self, squares: EmissionSquares, _: &mut Pcg32) -> (DVec3, DVec3) {
        let (u, v) = squares.direction;
        // As the lanes map theirs, in f32 (rounding below 1: the square is half-open).
        const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;
        let w = sphere_from_square((u as f32).min(BELOW_ONE), (v as f32).min(BELOW_ONE));
        (self.position, w.as_dvec3())
    }

    /// Uniform directions in f32 lanes: each photon's stream seeded and its two draws
    /// taken in one loop, then the branch-free concentric map and lift
    /// ([`sphere_from_square`]) in one that vectorises.
    fn sample_emission_lanes(
        &self,
        streams: PhotonStreams,
        rngs: &mut [Pcg32],
        o: [&mut [f32]; 3],
        d: [&mut [f32]; 3],
    ) {
        let p = self.position.as_vec3();
        for (o, p) in o.into_iter().zip([p.x, p.y, p.z]) {
            o[..rngs.len()].fill(p);
        }
        const LANES: usize = 64;
        let [dx, dy, dz] = d;
        let blocks = rngs.chunks_mut(LANES).zip(dx.chunks_mut(LANES));
        let blocks = blocks.zip(dy.chunks_mut(LANES).zip(dz.chunks_mut(LANES)));
        for (b, ((rngs, dx), (dy, dz))) in blocks.enumerate() {
            let (mut u, mut v) = ([0.0_f32; LANES], [0.0_f32; LANES]);
            for (i, ((slot, u), v)) in rngs.iter_mut().zip(&mut u).zip(&mut v).enumerate() {
                let mut rng = streams.get(b * LANES + i);
                *u = uniform_f32(&mut rng);
                *v = uniform_f32(&mut rng);
                *slot = rng;
            }
            let n = rngs.len();
            for k in 0..n.min(dx.len()).min(dy.len()).min(dz.len()) {
                let w = sphere_from_square(u[k], v[k]);
                (dx[k], dy[k], dz[k]) = (w.x, w.y, w.z);
            }
        }
    }

    fn incoming(&self, p: DVec3, _: &[(f64, f64)], each: &mut dyn FnMut(Incoming)) {
        if self.intensity_cd > 0.0 {
            from_point(p, self.position, self.intensity_cd, each);
        }
    }

    fn extent(&self) -> (DVec3, f64) {
        (self.position, 0.0)
    }
}

//! The light interface is open: a light kind written here, outside the crate, against
//! `luxtally::light::{Light, Emitter}` only, is put into a loaded scene and run. Its
//! illuminance on a plane must match the inverse-square cosine law within the σ the run
//! reports, by the photon pass (its emission sampling) and by next-event estimation (the
//! light it gives a point), and its flux must be what it declares.

use crate::common;

use common::*;
use glam::DVec3;
use luxtally::accel::Backend;
use luxtally::light::{BoundingSphere, Emitter, Incoming, Light};
use luxtally::run::RunOptions;
use luxtally::scene::{Estimator, SceneLight};
use rand::Rng;
use rand_pcg::Pcg32;
use std::f64::consts::PI;
use std::sync::Arc;

/// A horizontal ring of `count` isotropic point emitters of `intensity_cd` each, evenly
/// spaced on a circle of `radius_m` about `center` (world coordinates).
#[derive(Clone, Debug, PartialEq)]
struct Ring {
    center: DVec3,
    radius_m: f64,
    count: usize,
    intensity_cd: f64,
}

impl Ring {
    fn points(&self, shift: DVec3) -> Vec<DVec3> {
        (0..self.count)
            .map(|k| {
                let phi = 2.0 * PI * k as f64 / self.count as f64;
                self.center - shift
                    + self.radius_m * DVec3::new(libm::cos(phi), libm::sin(phi), 0.0)
            })
            .collect()
    }
}

impl Light for Ring {
    fn flux_lm(&self, _: &BoundingSphere) -> f64 {
        self.count as f64 * 4.0 * PI * self.intensity_cd
    }

    fn emitter(&self, origin: DVec3, _: &BoundingSphere) -> Arc<dyn Emitter> {
        Arc::new(RingEmitter {
            points: self.points(origin),
            intensity_cd: self.intensity_cd,
        })
    }
}

/// The ring in the scene's local frame.
#[derive(Debug)]
struct RingEmitter {
    points: Vec<DVec3>,
    intensity_cd: f64,
}

impl Emitter for RingEmitter {
    /// A point chosen uniformly (they are equally bright), a direction uniform on the
    /// sphere (z = 1 − 2u, φ = 2πv).
    fn sample_emission(&self, rng: &mut Pcg32) -> (DVec3, DVec3) {
        let k = rng.random_range(0..self.points.len());
        let (u, v): (f64, f64) = (rng.random(), rng.random());
        let z = 1.0 - 2.0 * u;
        let s = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * v;
        (
            self.points[k],
            DVec3::new(s * libm::cos(phi), s * libm::sin(phi), z),
        )
    }

    /// Every emitter of the ring, each as I/d² towards `p`.
    fn incoming(&self, p: DVec3, _: &[(f64, f64)], each: &mut dyn FnMut(Incoming)) {
        for q in &self.points {
            let to_source = *q - p;
            let distance = to_source.length();
            if distance > 0.0 {
                each(Incoming {
                    to_source,
                    distance,
                    normal_lx: self.intensity_cd / (distance * distance),
                });
            }
        }
    }

    fn extent(&self) -> (DVec3, f64) {
        let centre = self.points.iter().sum::<DVec3>() / self.points.len() as f64;
        (centre, 0.0)
    }
}

const RING: Ring = Ring {
    center: DVec3::new(0.2, -0.1, 1.5),
    radius_m: 0.6,
    count: 5,
    intensity_cd: 200.0,
};

/// A black floor and a receiver just above it; the scene file has no lights: the ring
/// is added after loading.
fn ring_run(estimator: Estimator, photons: u64) -> luxtally::output::summary::Summary {
    let mut s = scene(&format!("{BLACK_FLOOR}{FLOOR_RECEIVER}"));
    s.lights.push(SceneLight::new("ring", RING));
    assert_eq!(s.lights[0].get::<Ring>(), Some(&RING));
    let opts = RunOptions {
        estimator: Some(estimator),
        ..options(&s, photons, 2, Backend::Embree)
    };
    run_options(&s, &opts)
}

/// Exact mean illuminance of cell (i, j): the sum over the ring's points of the
/// inverse-square cosine law integrated over the cell.
fn ring_cell_lx(i: usize, j: usize) -> f64 {
    let h = RING.center.z - 0.0001;
    RING.points(DVec3::ZERO)
        .iter()
        .map(|q| {
            let (x0, y0) = (-1.0 + i as f64 * 0.125 - q.x, -1.0 + j as f64 * 0.125 - q.y);
            point_source_cell_lx(RING.intensity_cd, h, x0, x0 + 0.125, y0, y0 + 0.125)
        })
        .sum()
}

#[test]
fn a_light_kind_defined_outside_the_crate_is_emitted_by_its_own_sampling() {
    let s = ring_run(Estimator::Track, 400_000);
    let flux = RING.count as f64 * 4.0 * PI * RING.intensity_cd;
    assert_eq!(s.total_flux_lm, flux);
    assert_eq!(s.lights[0].label, "ring");
    assert_matches(&s.receivers["r"], ring_cell_lx, "ring light, photons");
}

#[test]
fn a_light_kind_defined_outside_the_crate_gives_next_event_its_incoming_light() {
    let s = ring_run(Estimator::NextEvent, 20_000);
    assert_matches(&s.receivers["r"], ring_cell_lx, "ring light, next event");
}

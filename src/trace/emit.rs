//! The scene's lights as the photon and eye passes use them: each prepared in the local
//! frame (`crate::light::Emitter`), their fluxes, and how photons are shared among them.
//! What each kind emits lives in `crate::light`; nothing here knows the kinds.

use crate::light::{BoundingSphere, EmissionSquares, Emitter, Incoming};
use crate::rng::{qmc_square, PhotonStreams, QmcBlock, QmcDraw};
use crate::sampling::invert_cdf;
use crate::scene::Scene;
use glam::DVec3;
use rand_pcg::Pcg32;
use std::sync::Arc;

/// The lights of a scene, with the cumulative distribution of their flux used to share
/// photons among them.
#[derive(Clone, Debug)]
pub struct Emitters {
    pub emitters: Vec<Arc<dyn Emitter>>,
    pub flux_lm: Vec<f64>,
    pub total_flux_lm: f64,
    /// The unit receiver scores are tallied in ([`crate::tally::score_unit`]).
    pub score_unit: f64,
    cdf: Vec<f64>,
    /// A QMC run's seed ([`Emitters::with_qmc`]): the light of a photon is then picked by
    /// its emission point's first number.
    qmc_seed: Option<u64>,
}

impl Emitters {
    /// Prepares the scene's lights in the local frame (world = `origin` + local). The
    /// directional sources' disk covers the bounding sphere of geometry and receivers.
    pub fn new(scene: &Scene) -> Emitters {
        let origin = scene.geometry.origin;
        let sphere = bounding_sphere(scene);
        let flux_lm: Vec<f64> = scene
            .lights
            .iter()
            .map(|l| l.kind.flux_lm(&sphere))
            .collect();
        let emitters = (scene.lights.iter())
            .map(|l| l.kind.emitter(origin, &sphere))
            .collect();
        let total_flux_lm: f64 = flux_lm.iter().sum();
        let mut acc = 0.0;
        let cdf = flux_lm
            .iter()
            .map(|f| {
                acc += f;
                if total_flux_lm > 0.0 {
                    acc / total_flux_lm
                } else {
                    0.0
                }
            })
            .collect();
        Emitters {
            emitters,
            flux_lm,
            total_flux_lm,
            score_unit: crate::tally::score_unit(total_flux_lm),
            cdf,
            qmc_seed: None,
        }
    }

    /// For a QMC run seeded with `seed`: each photon's light is picked by the first number
    /// of its emission point ([`QmcDraw::Emission`]), by inversion of the flux CDF, and
    /// what is left of that number goes on to the light's direction. A block's photons
    /// then share the lights out as evenly as the golden-ratio sequence does, and each
    /// light's photons keep a stratified set of directions (a light's share of a net).
    pub fn with_qmc(mut self, seed: Option<u64>) -> Self {
        self.qmc_seed = seed;
        self
    }

    /// The light that emits photon `index`. Photons are shared in proportion to flux by
    /// a golden-ratio sequence over the flux CDF: deterministic per index, and any run of
    /// consecutive photons follows the shares closely (no multinomial noise). In a QMC
    /// run ([`Emitters::with_qmc`]), by the photon's emission point.
    #[inline]
    pub fn light_of(&self, index: u64) -> usize {
        const GOLDEN: f64 = 0.618_033_988_749_894_8;
        if self.cdf.len() < 2 {
            return 0;
        }
        if let Some(seed) = self.qmc_seed {
            return self
                .light_of_square(qmc_square(seed, index, QmcDraw::Emission))
                .0;
        }
        let x = (index as f64 * GOLDEN).fract();
        self.cdf
            .iter()
            .position(|&c| x < c)
            .unwrap_or(self.cdf.len().saturating_sub(1))
    }

    /// Whether every source takes its emission's direction from a QMC run's point
    /// ([`Emitter::direction_from_square`]): the whole emission is then stratified.
    pub fn emission_from_square(&self) -> bool {
        self.emitters.iter().all(|e| e.direction_from_square())
    }

    /// The light whose share of the flux CDF holds `u`, and the point with `u` rescaled
    /// across that share (uniform in [0, 1) again).
    #[inline]
    fn light_of_square(&self, (u, v): (f64, f64)) -> (usize, (f64, f64)) {
        if self.cdf.is_empty() {
            return (0, (u, v));
        }
        let (light, u) = invert_cdf(&self.cdf, |&c| c, u);
        (light, (u, v))
    }

    /// Origins and directions (f32, for the ray caster) of the photons `streams.first`,
    /// `streams.first + 1`, …, one per slot of `rngs`, each drawn from its own stream,
    /// which is left in its slot: in lanes when one light emits them all
    /// ([`Emitter::sample_emission_lanes`]), else photon by photon.
    pub fn sample_lanes(
        &self,
        streams: PhotonStreams,
        rngs: &mut [Pcg32],
        o: [&mut [f32]; 3],
        d: [&mut [f32]; 3],
    ) {
        if let [emitter] = &self.emitters[..] {
            return emitter.sample_emission_lanes(streams, rngs, o, d);
        }
        crate::light::emission_lanes_one_by_one(streams, rngs, o, d, |k, rng| {
            self.sample(self.light_of(streams.first + k as u64), rng)
        });
    }

    /// [`Emitters::sample_lanes`] for a QMC run ([`Emitters::with_qmc`]): each photon's
    /// light and direction from its joint point's emission pair ([`QmcDraw::Emission`]),
    /// photon by photon; as `sample_lanes` where no source takes its direction so.
    pub fn sample_lanes_qmc(
        &self,
        streams: PhotonStreams,
        rngs: &mut [Pcg32],
        o: [&mut [f32]; 3],
        d: [&mut [f32]; 3],
    ) {
        let Some(seed) = self.qmc_seed else {
            return self.sample_lanes(streams, rngs, o, d);
        };
        if !self.emitters.iter().any(|e| e.direction_from_square()) {
            return self.sample_lanes(streams, rngs, o, d);
        }
        let blocks_of =
            |photon| [QmcDraw::Emission, QmcDraw::Origin].map(|d| QmcBlock::new(seed, photon, d));
        let mut blocks = blocks_of(streams.first);
        crate::light::emission_lanes_one_by_one(streams, rngs, o, d, |k, rng| {
            let photon = streams.first + k as u64;
            if !blocks[0].holds(photon) {
                blocks = blocks_of(photon);
            }
            let (light, direction) = self.light_of_square(blocks[0].square(photon, None));
            let origin = if self.emitters[light].origin_from_square() {
                blocks[1].square(photon, None)
            } else {
                (0.0, 0.0)
            };
            let squares = EmissionSquares { direction, origin };
            self.emitters[light].sample_emission_from(squares, rng)
        });
    }

    /// Samples the origin and unit direction of a photon of light `light`.
    #[inline]
    pub fn sample(&self, light: usize, rng: &mut Pcg32) -> (DVec3, DVec3) {
        self.emitters[light].sample_emission(rng)
    }

    /// Centre and diagonal (m) of the light's emitting extent: an area source, a
    /// luminaire's opening; diagonal 0 for point-like and directional sources.
    pub fn extent(&self, light: usize) -> (DVec3, f64) {
        self.emitters[light].extent()
    }

    /// The light of source `light` arriving at local point `p`, piece by piece
    /// ([`Emitter::incoming`]; `area_pattern` places the pieces of sources with an
    /// extent). Visibility is the caller's.
    #[inline]
    pub fn incoming(
        &self,
        light: usize,
        p: DVec3,
        area_pattern: &[(f64, f64)],
        mut each: impl FnMut(Incoming),
    ) {
        self.emitters[light].incoming(p, area_pattern, &mut each);
    }
}

/// Centre (world) and radius of a sphere holding the geometry and the receivers.
pub fn bounding_sphere(scene: &Scene) -> BoundingSphere {
    let mut points: Vec<DVec3> = Vec::new();
    if let Some((lo, hi)) = scene.geometry.world_bounds() {
        points.extend([lo, hi]);
    }
    for r in &scene.receivers {
        points.extend([
            r.corner,
            r.corner + r.u,
            r.corner + r.v,
            r.corner + r.u + r.v,
        ]);
    }
    let Some(first) = points.first().copied() else {
        return BoundingSphere {
            center: DVec3::ZERO,
            radius: 0.0,
        };
    };
    let (lo, hi) = points
        .iter()
        .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let center = (lo + hi) * 0.5;
    // Never zero: a lone flat receiver still needs a disk to catch the light.
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    BoundingSphere { center, radius }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn photons_are_shared_in_proportion_to_flux() {
        let mut scene = Scene::default();
        for intensity_cd in [1.0, 3.0] {
            scene.lights.push(crate::scene::SceneLight::new(
                "",
                crate::light::Point {
                    position: DVec3::ZERO,
                    intensity_cd,
                },
            ));
        }
        let e = Emitters::new(&scene);
        let n = 100_000;
        let first = (0..n).filter(|&i| e.light_of(i) == 0).count();
        assert!((first as f64 / n as f64 - 0.25).abs() < 1e-4);
    }

    /// In a QMC run each block's first numbers are one per 1/2048 of [0, 1), so a light
    /// with a quarter of the flux gets exactly a quarter of every block; and the light a
    /// photon is emitted from is `light_of`'s (the portal rules read that).
    #[test]
    fn qmc_photons_are_shared_exactly_per_block_and_emitted_from_their_light() {
        let mut scene = Scene::default();
        for (x, intensity_cd) in [(-1.0, 1.0), (1.0, 3.0)] {
            scene.lights.push(crate::scene::SceneLight::new(
                "",
                crate::light::Point {
                    position: DVec3::new(x, 0.0, 0.0),
                    intensity_cd,
                },
            ));
        }
        let e = Emitters::new(&scene).with_qmc(Some(7));
        let block = 1u64 << crate::rng::QMC_LOG2_BLOCK;
        for b in 0..4 {
            let first = (b * block..(b + 1) * block)
                .filter(|&i| e.light_of(i) == 0)
                .count();
            assert_eq!(first as u64, block / 4, "block {b}");
        }
        let n = 4096;
        let streams = PhotonStreams::new(7, 8192);
        let mut rngs = vec![Pcg32::new(0, 0); n];
        let (mut ox, mut oy, mut oz) = (vec![0f32; n], vec![0f32; n], vec![0f32; n]);
        let (mut dx, mut dy, mut dz) = (vec![0f32; n], vec![0f32; n], vec![0f32; n]);
        e.sample_lanes_qmc(
            streams,
            &mut rngs,
            [&mut ox, &mut oy, &mut oz],
            [&mut dx, &mut dy, &mut dz],
        );
        for (k, &x) in ox.iter().enumerate() {
            let light = e.light_of(8192 + k as u64);
            assert_eq!(x, if light == 0 { -1.0 } else { 1.0 }, "photon {k}");
        }
    }
}

//! Light sources in the local frame: their flux, and the sampling of a photon's origin
//! and direction from each source's spatial and angular emission density.

use crate::photometry::Photometry;
use crate::sampling::{
    cosine_hemisphere, uniform, uniform_cone, uniform_disk, uniform_sphere, SphericalRect,
};
use crate::scene::{LightKind, Scene};
use glam::{DMat3, DVec3};
use rand_pcg::Pcg32;
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

/// One light, prepared for sampling (positions in the scene's local frame).
#[derive(Clone, Debug)]
pub enum Emitter {
    Point {
        position: DVec3,
    },
    Spot {
        position: DVec3,
        axis: DVec3,
        /// cos of the cut-off half-angle (`cone_deg`).
        cos_cone: f64,
        /// cos of the half-angle up to which intensity is full (`falloff_deg`).
        cos_falloff: f64,
    },
    Directional {
        direction: DVec3,
        /// Centre and radius of the disk, normal to `direction`, photons start from.
        disk_center: DVec3,
        disk_radius: f64,
    },
    Area {
        corner: DVec3,
        u: DVec3,
        v: DVec3,
        normal: DVec3,
    },
    /// A luminaire: photons leave its opening (centred on `position`, luminaire frame
    /// `frame`) in directions drawn from its photometry.
    Luminaire {
        position: DVec3,
        frame: DMat3,
        photometry: Arc<Photometry>,
    },
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

/// Flux (lm) of a light. Directional sources need the disk they are emitted from, whose
/// radius `scene_radius` covers the scene: Φ = E·π·R².
pub fn light_flux_lm(kind: &LightKind, scene_radius: f64) -> f64 {
    match *kind {
        LightKind::Point { intensity_cd, .. } => 4.0 * PI * intensity_cd,
        LightKind::Spot {
            intensity_cd,
            cone_deg,
            falloff_deg,
            ..
        } => {
            let (cos_cone, cos_falloff) =
                (cone_deg.to_radians().cos(), falloff_deg.to_radians().cos());
            // ∫ I dω: full core, plus the smoothstep ramp whose mean over cos θ is 1/2.
            TAU * intensity_cd * ((1.0 - cos_falloff) + 0.5 * (cos_falloff - cos_cone))
        }
        LightKind::Directional { illuminance_lx, .. } => {
            illuminance_lx * PI * scene_radius * scene_radius
        }
        LightKind::Area {
            u,
            v,
            luminance_cdm2,
            ..
        } => PI * luminance_cdm2 * u.cross(v).length(),
        LightKind::Luminaire(ref l) => l.flux_lm(),
    }
}

/// The lights of a scene, with the cumulative distribution of their flux used to share
/// photons among them.
#[derive(Clone, Debug)]
pub struct Emitters {
    pub emitters: Vec<Emitter>,
    pub flux_lm: Vec<f64>,
    /// The amount the direct light scales with: intensity (cd) of point and spot
    /// sources, illuminance (lx) of directional ones, luminance (cd/m²) of area sources,
    /// the factor on the file's intensities of luminaires.
    pub intensity_scale: Vec<f64>,
    pub total_flux_lm: f64,
    cdf: Vec<f64>,
}

impl Emitters {
    /// Prepares the scene's lights in the local frame (world = `origin` + local). The
    /// directional sources' disk covers the bounding sphere of geometry and receivers.
    pub fn new(scene: &Scene) -> Emitters {
        let origin = scene.geometry.origin;
        let (center, radius) = bounding_sphere(scene);
        let mut emitters = Vec::new();
        let mut flux_lm = Vec::new();
        let mut intensity_scale = Vec::new();
        for light in &scene.lights {
            flux_lm.push(light_flux_lm(&light.kind, radius));
            intensity_scale.push(match light.kind {
                LightKind::Point { intensity_cd, .. } | LightKind::Spot { intensity_cd, .. } => {
                    intensity_cd
                }
                LightKind::Directional { illuminance_lx, .. } => illuminance_lx,
                LightKind::Area { luminance_cdm2, .. } => luminance_cdm2,
                LightKind::Luminaire(ref l) => l.scale,
            });
            emitters.push(match light.kind {
                LightKind::Point { position, .. } => Emitter::Point {
                    position: position - origin,
                },
                LightKind::Spot {
                    position,
                    direction,
                    cone_deg,
                    falloff_deg,
                    ..
                } => Emitter::Spot {
                    position: position - origin,
                    axis: direction.normalize(),
                    cos_cone: cone_deg.to_radians().cos(),
                    cos_falloff: falloff_deg.to_radians().cos(),
                },
                LightKind::Directional { direction, .. } => {
                    let direction = direction.normalize();
                    Emitter::Directional {
                        direction,
                        // Start outside the scene so every photon crosses all of it.
                        disk_center: center - origin - direction * (radius * 1.01),
                        disk_radius: radius,
                    }
                }
                LightKind::Area { corner, u, v, .. } => Emitter::Area {
                    corner: corner - origin,
                    u,
                    v,
                    normal: u.cross(v).normalize(),
                },
                LightKind::Luminaire(ref l) => Emitter::Luminaire {
                    position: l.position - origin,
                    frame: l.frame,
                    photometry: l.photometry.clone(),
                },
            });
        }
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
            intensity_scale,
            total_flux_lm,
            cdf,
        }
    }

    /// The light that emits photon `index`. Photons are shared in proportion to flux by
    /// a golden-ratio sequence over the flux CDF: deterministic per index, and any run of
    /// consecutive photons follows the shares closely (no multinomial noise).
    #[inline]
    pub fn light_of(&self, index: u64) -> usize {
        const GOLDEN: f64 = 0.618_033_988_749_894_8;
        let x = (index as f64 * GOLDEN).fract();
        self.cdf
            .iter()
            .position(|&c| x < c)
            .unwrap_or(self.cdf.len().saturating_sub(1))
    }

    /// Samples the origin and unit direction of a photon of light `light`.
    #[inline]
    pub fn sample(&self, light: usize, rng: &mut Pcg32) -> (DVec3, DVec3) {
        match self.emitters[light] {
            Emitter::Point { position } => (position, uniform_sphere(rng)),
            Emitter::Spot {
                position,
                axis,
                cos_cone,
                cos_falloff,
            } => loop {
                // Rejection from the uniform cone: exact for any profile bounded by 1.
                let dir = uniform_cone(rng, axis, cos_cone);
                if uniform(rng) < spot_profile(dir.dot(axis), cos_cone, cos_falloff) {
                    break (position, dir);
                }
            },
            Emitter::Directional {
                direction,
                disk_center,
                disk_radius,
            } => (
                uniform_disk(rng, disk_center, direction, disk_radius),
                direction,
            ),
            Emitter::Area {
                corner,
                u,
                v,
                normal,
            } => {
                let p = corner + u * uniform(rng) + v * uniform(rng);
                (p, cosine_hemisphere(rng, normal))
            }
            Emitter::Luminaire {
                position,
                frame,
                ref photometry,
            } => {
                let p = position + frame * photometry.opening.sample_point_m(rng);
                (p, frame * photometry.sample_direction(rng))
            }
        }
    }
}

/// Below this solid angle (sr) an area source is sampled by area, not by solid angle:
/// its light then varies little over it, and the spherical parametrisation loses
/// digits.
const MIN_SPHERICAL_SR: f64 = 1e-4;

/// Light from one source arriving at a point, as one point-like piece of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incoming {
    /// From the point towards the piece: the vector to it, or for a directional source
    /// the unit direction towards the source.
    pub to_source: DVec3,
    /// Distance to the piece; `f64::INFINITY` for a directional source.
    pub distance: f64,
    /// Illuminance the piece gives on a plane facing it (lx): I/d² for point and spot
    /// sources, E⊥ for directional ones, L·Ω/n for one of n solid-angle shares of an
    /// area source (L·cos θ_s·ΔA/d² for a patch of one, when it is sampled by area).
    pub normal_lx: f64,
}

impl Incoming {
    /// Unit direction from the point towards the piece.
    #[inline]
    pub fn direction(&self) -> DVec3 {
        if self.distance.is_finite() {
            self.to_source / self.distance
        } else {
            self.to_source
        }
    }
}

impl Emitters {
    /// Centre and diagonal (m) of the light's emitting extent: an area source, a
    /// luminaire's opening; diagonal 0 for point-like and directional sources.
    pub fn extent(&self, light: usize) -> (DVec3, f64) {
        match self.emitters[light] {
            Emitter::Area { corner, u, v, .. } => (corner + 0.5 * (u + v), (u + v).length()),
            Emitter::Luminaire {
                position,
                ref photometry,
                ..
            } => (position, photometry.opening.diagonal_m()),
            Emitter::Point { position } | Emitter::Spot { position, .. } => (position, 0.0),
            Emitter::Directional { disk_center, .. } => (disk_center, 0.0),
        }
    }

    /// The light of source `light` arriving at local point `p` (method.md eqs. 1–2),
    /// piece by piece: one piece for point, spot and directional sources; for an area
    /// source one per point of `area_pattern` ([0, 1)² coordinates), each standing for
    /// an equal share of the source's solid angle seen from `p` (of its area, for far
    /// sources and parallelograms that are not rectangles). Visibility is the caller's.
    pub fn incoming(
        &self,
        light: usize,
        p: DVec3,
        area_pattern: &[(f64, f64)],
        mut each: impl FnMut(Incoming),
    ) {
        let scale = self.intensity_scale[light];
        if !(scale > 0.0) {
            return;
        }
        let mut from_point = |q: DVec3, intensity: f64| {
            let to_source = q - p;
            let distance = to_source.length();
            if intensity > 0.0 && distance > 0.0 {
                each(Incoming {
                    to_source,
                    distance,
                    normal_lx: intensity / (distance * distance),
                });
            }
        };
        match self.emitters[light] {
            Emitter::Point { position } => from_point(position, scale),
            Emitter::Spot {
                position,
                axis,
                cos_cone,
                cos_falloff,
            } => {
                let towards_p = (p - position).normalize_or_zero();
                from_point(
                    position,
                    scale * spot_profile(towards_p.dot(axis), cos_cone, cos_falloff),
                );
            }
            Emitter::Directional { direction, .. } => each(Incoming {
                to_source: -direction,
                distance: f64::INFINITY,
                normal_lx: scale,
            }),
            // Every point of the opening emits the file's distribution, I/A per unit
            // area (as the photons leave it): one equal share of the opening per piece.
            Emitter::Luminaire {
                position,
                frame,
                ref photometry,
            } => {
                let share = scale / area_pattern.len().max(1) as f64;
                for &(a, b) in area_pattern {
                    let q = position + frame * photometry.opening.point_at(a, b);
                    let towards_p = frame.transpose() * (p - q);
                    if towards_p != DVec3::ZERO {
                        from_point(q, share * photometry.intensity_toward_cd(towards_p));
                    }
                }
            }
            Emitter::Area {
                corner,
                u,
                v,
                normal,
            } => {
                if !((p - corner).dot(normal) > 0.0) {
                    return;
                }
                let pieces = area_pattern.len().max(1) as f64;
                match SphericalRect::new(p, corner, u, v) {
                    // Equal shares of the solid angle: each piece gives L·Ω/n, bounded
                    // however near or grazing the point.
                    Some(rect) if rect.solid_angle_sr > MIN_SPHERICAL_SR => {
                        let normal_lx = scale * rect.solid_angle_sr / pieces;
                        for &(a, b) in area_pattern {
                            let to_source = rect.sample(a, b) - p;
                            let distance = to_source.length();
                            if distance > 0.0 {
                                each(Incoming {
                                    to_source,
                                    distance,
                                    normal_lx,
                                });
                            }
                        }
                    }
                    // Far (or a parallelogram): equal shares of the area,
                    // L·cos θ_s·ΔA/d² each.
                    _ => {
                        let patch_area = u.cross(v).length() / pieces;
                        for &(a, b) in area_pattern {
                            let q = corner + u * a + v * b;
                            let cos_s = (p - q).normalize_or_zero().dot(normal);
                            if cos_s > 0.0 {
                                from_point(q, scale * cos_s * patch_area);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Centre (world) and radius of a sphere holding the geometry and the receivers.
fn bounding_sphere(scene: &Scene) -> (DVec3, f64) {
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
        return (DVec3::ZERO, 0.0);
    };
    let (lo, hi) = points
        .iter()
        .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let center = (lo + hi) * 0.5;
    // Never zero: a lone flat receiver still needs a disk to catch the light.
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    (center, radius)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_flux_matches_numeric_integral_of_profile() {
        let (cone, falloff) = (40.0_f64, 25.0_f64);
        let kind = LightKind::Spot {
            position: DVec3::ZERO,
            direction: DVec3::Z,
            intensity_cd: 100.0,
            cone_deg: cone,
            falloff_deg: falloff,
        };
        let (cc, cf) = (cone.to_radians().cos(), falloff.to_radians().cos());
        let n = 100_000;
        let numeric: f64 = (0..n)
            .map(|k| {
                let c = cc + (1.0 - cc) * (k as f64 + 0.5) / n as f64;
                spot_profile(c, cc, cf) * (1.0 - cc) / n as f64
            })
            .sum::<f64>()
            * TAU
            * 100.0;
        let exact = light_flux_lm(&kind, 0.0);
        assert!(
            (numeric - exact).abs() < 1e-6 * exact,
            "{numeric} vs {exact}"
        );
    }

    #[test]
    fn photons_are_shared_in_proportion_to_flux() {
        let mut scene = Scene::default();
        for intensity_cd in [1.0, 3.0] {
            scene.lights.push(crate::scene::Light {
                label: String::new(),
                kind: LightKind::Point {
                    position: DVec3::ZERO,
                    intensity_cd,
                },
            });
        }
        let e = Emitters::new(&scene);
        let n = 100_000;
        let first = (0..n).filter(|&i| e.light_of(i) == 0).count();
        assert!((first as f64 / n as f64 - 0.25).abs() < 1e-4);
    }
}

//! Area source: `type = "area"`, a one-sided Lambertian parallelogram of luminance L
//! (cd/m²) emitting on the side of u × v. The only source the camera sees.

use super::{
    from_point, single, BoundingSphere, Emitter, Incoming, Labelled, Light, LightFile, LoadContext,
};
use crate::error::{Error, Result};
use crate::input::{amount, required, vec3, Coords};
use crate::sampling::{cosine_hemisphere, uniform, SphericalRect};
use glam::DVec3;
use rand_pcg::Pcg32;
use serde::Deserialize;
use std::f64::consts::PI;
use std::sync::Arc;

/// The `[[lights]]` entry: the parallelogram and one of `flux_lm`, `luminance_cdm2`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct AreaFile {
    pub corner: Option<Coords>,
    pub u: Option<Coords>,
    pub v: Option<Coords>,
    pub flux_lm: Option<f64>,
    pub luminance_cdm2: Option<f64>,
}

impl LightFile for AreaFile {
    const TYPE: &'static str = "area";

    fn into_lights(self, label: &str, at: &str, _: &mut LoadContext) -> Result<Vec<Labelled>> {
        let what = "type \"area\" lights";
        let corner = vec3(required(self.corner, at, "corner", what)?);
        let u = vec3(required(self.u, at, "u", what)?);
        let v = vec3(required(self.v, at, "v", what)?);
        let area = u.cross(v).length();
        if !(area > 0.0) {
            return Err(Error::input(at, "zero-area light: u × v = 0"));
        }
        let luminance_cdm2 = match (self.flux_lm, self.luminance_cdm2) {
            // One-sided Lambertian emitter: Φ = π L A.
            (Some(f), None) => amount(f, at, "flux_lm")? / (PI * area),
            (None, Some(lum)) => amount(lum, at, "luminance_cdm2")?,
            _ => {
                return Err(Error::input(
                    at,
                    "give exactly one of `flux_lm` and `luminance_cdm2`",
                ))
            }
        };
        single(
            label,
            Area {
                corner,
                u,
                v,
                luminance_cdm2,
            },
        )
    }
}

/// One-sided Lambertian parallelogram emitting on the side of u × v (world coordinates).
#[derive(Clone, Debug, PartialEq)]
pub struct Area {
    pub corner: DVec3,
    pub u: DVec3,
    pub v: DVec3,
    pub luminance_cdm2: f64,
}

impl Light for Area {
    fn flux_lm(&self, _: &BoundingSphere) -> f64 {
        PI * self.luminance_cdm2 * self.u.cross(self.v).length()
    }

    fn emitter(&self, origin: DVec3, _: &BoundingSphere) -> Arc<dyn Emitter> {
        Arc::new(AreaEmitter {
            corner: self.corner - origin,
            u: self.u,
            v: self.v,
            normal: self.u.cross(self.v).normalize(),
            luminance_cdm2: self.luminance_cdm2,
        })
    }

    /// The eye pass samples it on an n × n grid per shading point.
    fn eye_shadow_rays(&self, area_light_samples: u32) -> f64 {
        (area_light_samples as f64).powi(2)
    }
}

/// Below this solid angle (sr) an area source is sampled by area, not by solid angle:
/// its light then varies little over it, and the spherical parametrisation loses
/// digits.
const MIN_SPHERICAL_SR: f64 = 1e-4;

#[derive(Clone, Debug)]
struct AreaEmitter {
    corner: DVec3,
    u: DVec3,
    v: DVec3,
    normal: DVec3,
    luminance_cdm2: f64,
}

impl Emitter for AreaEmitter {
    #[inline]
    fn sample_emission(&self, rng: &mut Pcg32) -> (DVec3, DVec3) {
        let p = self.corner + self.u * uniform(rng) + self.v * uniform(rng);
        (p, cosine_hemisphere(rng, self.normal))
    }

    /// One piece per point of `area_pattern`, each an equal share of the solid angle the
    /// source subtends at `p` (of its area, for far sources and parallelograms that are
    /// not rectangles).
    fn incoming(&self, p: DVec3, area_pattern: &[(f64, f64)], each: &mut dyn FnMut(Incoming)) {
        let Self {
            corner,
            u,
            v,
            normal,
            luminance_cdm2: scale,
        } = *self;
        if !(scale > 0.0) || !((p - corner).dot(normal) > 0.0) {
            return;
        }
        let pieces = area_pattern.len().max(1) as f64;
        match SphericalRect::new(p, corner, u, v) {
            // Equal shares of the solid angle: each piece gives L·Ω/n, bounded however
            // near or grazing the point.
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
            // Far (or a parallelogram): equal shares of the area, L·cos θ_s·ΔA/d² each.
            _ => {
                let patch_area = u.cross(v).length() / pieces;
                for &(a, b) in area_pattern {
                    let q = corner + u * a + v * b;
                    let cos_s = (p - q).normalize_or_zero().dot(normal);
                    if cos_s > 0.0 {
                        from_point(p, q, scale * cos_s * patch_area, each);
                    }
                }
            }
        }
    }

    fn extent(&self) -> (DVec3, f64) {
        (
            self.corner + 0.5 * (self.u + self.v),
            (self.u + self.v).length(),
        )
    }

    /// Its luminance if the ray meets it from the emitting side before `t_hit`.
    fn luminance_seen(&self, o: DVec3, dir: DVec3, t_hit: f64) -> Option<f64> {
        let Self {
            corner,
            u,
            v,
            normal,
            ..
        } = *self;
        let cos = dir.dot(normal);
        if cos >= 0.0 {
            return None;
        }
        let t = (corner - o).dot(normal) / cos;
        if !(t > 0.0 && t < t_hit) {
            return None;
        }
        // Coordinates of the hit in the (u, v) parallelogram.
        let r = o + dir * t - corner;
        let uv = u.cross(v);
        let a = r.cross(v).dot(uv) / uv.length_squared();
        let b = u.cross(r).dot(uv) / uv.length_squared();
        ((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then_some(self.luminance_cdm2)
    }
}

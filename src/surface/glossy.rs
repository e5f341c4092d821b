//! The glossy lobes: a rough reflector (GGX conductor with a Fresnel factor of 1) and a
//! rough dielectric, both GGX microfacet lobes sampled by visible normals (as pbrt-v4's
//! `ConductorBxDF` and `DielectricBxDF`), in the flux form of transmission.

use super::fresnel::fr_dielectric;
use super::microfacet::{ggx_d, ggx_g, ggx_g1, ggx_sample_visible, ggx_visible_d, Frame};
use super::Material;
use super::{Bsdf, Continuation, Incidence, Lobe, LobeKind, Sample, CONNECT_MIN_ALPHA};
use crate::sampling::uniform;
use glam::DVec3;
use rand_pcg::Pcg32;
use std::f64::consts::PI;

/// The glossy lobes: a GGX reflector of weight `gr` (Fresnel factor 1) and a rough
/// dielectric of weight `gt` (index `ior`), one roughness.
#[derive(Clone, Copy, Debug)]
pub struct Glossy {
    gr: f64,
    gt: f64,
    /// Roulette threshold between the reflector and the rough dielectric.
    reflect_hi: f64,
    ior: f64,
    /// GGX α = roughness².
    alpha: f64,
}

impl Glossy {
    /// `conductor` (reflection) and `dielectric` (rough transmission) of the local
    /// directions, times their weights: f or pdf of the two lobes.
    fn weighted(
        &self,
        wo: DVec3,
        wi: DVec3,
        n: DVec3,
        conductor: fn(DVec3, DVec3, f64) -> f64,
        dielectric: fn(DVec3, DVec3, f64, f64) -> f64,
    ) -> f64 {
        let mut sum = 0.0;
        let frame = Frame::new(n);
        let (lo, li) = (frame.to_local(wo), frame.to_local(wi));
        if self.gr > 0.0 {
            sum += self.gr * conductor(lo, li, self.alpha);
        }
        if self.gt > 0.0 {
            sum += self.gt * dielectric(lo, li, self.alpha, self.ior);
        }
        sum
    }

    pub(super) fn add(b: &mut Bsdf, m: &Material) {
        let (lo, reflect_hi) = b.stack(m.glossy_reflectance);
        let (_, hi) = b.stack(m.glossy_transmittance);
        let lobe = Glossy {
            gr: reflect_hi - lo,
            gt: hi - reflect_hi,
            reflect_hi,
            ior: m.ior,
            alpha: (m.roughness * m.roughness).max(1e-7),
        };
        b.push(lobe.gr + lobe.gt > 0.0, lobe);
    }

    /// Samples the glossy reflector's lobe for `wo` (visible normals); the weight is
    /// G₂/G₁(wo). `None` when the reflected direction falls below the surface.
    pub fn sample_reflection(&self, wo: DVec3, n: DVec3, u: [f64; 2]) -> Option<Sample> {
        // Two-sided: the frame's z is on wo's side.
        let z = if wo.dot(n) >= 0.0 { n } else { -n };
        let frame = Frame::new(z);
        let lo = frame.to_local(wo);
        let (li, weight) = conductor_sample(lo, self.alpha, u)?;
        Some(Sample {
            dir: frame.to_world(li),
            transmitted: false,
            kind: LobeKind::Glossy,
            weight,
        })
    }

    /// Samples the rough dielectric for `wo`: a visible normal, then Fresnel reflection
    /// or refraction through it chosen by `u[2]`; the weight is G₂/G₁(wo).
    pub fn sample_rough_dielectric(&self, wo: DVec3, n: DVec3, u: [f64; 3]) -> Option<Sample> {
        let frame = Frame::new(n);
        let lo = frame.to_local(wo);
        let (li, weight) = dielectric_sample(lo, self.alpha, self.ior, u)?;
        Some(Sample {
            dir: frame.to_world(li),
            transmitted: li.z * lo.z < 0.0,
            kind: LobeKind::Glossy,
            weight,
        })
    }
}

impl Lobe for Glossy {
    fn kind(&self) -> LobeKind {
        LobeKind::Glossy
    }

    fn connectable(&self) -> bool {
        self.alpha >= CONNECT_MIN_ALPHA
    }

    fn sample(&self, xi: f64, dir: DVec3, normal: DVec3, rng: &mut Pcg32) -> Option<Sample> {
        if xi < self.reflect_hi {
            let u = [uniform(rng), uniform(rng)];
            self.sample_reflection(-dir, normal, u)
        } else {
            let u = [uniform(rng), uniform(rng), uniform(rng)];
            self.sample_rough_dielectric(-dir, normal, u)
        }
    }

    /// Both microfacet lobes times their weights.
    fn f(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        self.weighted(wo, wi, n, conductor_f, dielectric_f)
    }

    fn pdf(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        self.weighted(wo, wi, n, conductor_pdf, dielectric_pdf)
    }

    /// At the depth limit, as if Lambertian of the same weights (the rough dielectric
    /// split by Fresnel at the viewing angle).
    fn eye_indirect(
        &self,
        w: f64,
        at: &Incidence,
        e_seen: &dyn Fn() -> f64,
        e_other: &dyn Fn() -> f64,
        at_depth_limit: bool,
    ) -> f64 {
        if !at_depth_limit {
            return 0.0;
        }
        let (gr, gt) = (self.gr, self.gt);
        let (e_seen, e_other) = (e_seen(), e_other());
        let r = fr_dielectric(-at.dir.dot(at.n), self.ior);
        w * (gr * e_seen + gt * (r * e_seen + (1.0 - r) * e_other)) / PI
    }

    /// One sampled direction per glossy lobe, weight f·|cos|/pdf.
    fn eye_continue(
        &self,
        w: f64,
        at: &Incidence,
        new_rng: &dyn Fn() -> Pcg32,
        out: &mut dyn FnMut(Continuation),
    ) {
        let mut rng = new_rng();
        let wo = -at.dir;
        if self.gr > 0.0 {
            let u = [uniform(&mut rng), uniform(&mut rng)];
            if let Some(smp) = self.sample_reflection(wo, at.n, u) {
                out(Continuation {
                    dir: smp.dir,
                    weight: w * self.gr * smp.weight,
                    transmitted: false,
                    lights_counted: true,
                    see_through: false,
                });
            }
        }
        if self.gt > 0.0 {
            let u = [uniform(&mut rng), uniform(&mut rng), uniform(&mut rng)];
            if let Some(smp) = self.sample_rough_dielectric(wo, at.n, u) {
                out(Continuation {
                    dir: smp.dir,
                    weight: w * self.gt * smp.weight,
                    transmitted: smp.transmitted,
                    lights_counted: true,
                    see_through: false,
                });
            }
        }
    }
}

/// Unit-weight glossy reflector, local frame: D·G₂/(4|cos θo cos θi|) with a Fresnel
/// factor of 1 (the material's `glossy_reflectance` is its tint), two-sided.
#[inline]
pub fn conductor_f(wo: DVec3, wi: DVec3, alpha: f64) -> f64 {
    if wo.z * wi.z <= 0.0 {
        return 0.0;
    }
    let wm = wo + wi;
    if wm.length_squared() == 0.0 {
        return 0.0;
    }
    let mut wm = wm.normalize();
    if wm.z < 0.0 {
        wm = -wm;
    }
    ggx_d(wm, alpha) * ggx_g(wo, wi, alpha) / (4.0 * (wo.z * wi.z).abs())
}

/// Density of [`conductor_sample`]: D_wo(wm)/(4|wo·wm|).
#[inline]
pub fn conductor_pdf(wo: DVec3, wi: DVec3, alpha: f64) -> f64 {
    if wo.z * wi.z <= 0.0 {
        return 0.0;
    }
    let wm = wo + wi;
    if wm.length_squared() == 0.0 {
        return 0.0;
    }
    let wm = wm.normalize();
    // Visible normals are sampled on wo's side.
    let (wo, wm) = if wo.z < 0.0 {
        (-wo, if wm.z < 0.0 { -wm } else { wm })
    } else {
        (wo, if wm.z < 0.0 { -wm } else { wm })
    };
    ggx_visible_d(wo, wm, alpha) / (4.0 * wo.dot(wm).abs())
}

/// Samples the unit-weight reflector for `wo` (wo.z > 0): (wi, G₂/G₁(wo)).
#[inline]
pub fn conductor_sample(wo: DVec3, alpha: f64, u: [f64; 2]) -> Option<(DVec3, f64)> {
    if wo.z <= 0.0 {
        return None;
    }
    let wm = ggx_sample_visible(wo, alpha, u);
    let wi = (-wo + wm * (2.0 * wo.dot(wm))).normalize();
    if wi.z <= 0.0 {
        return None;
    }
    Some((wi, ggx_g(wo, wi, alpha) / ggx_g1(wo, alpha)))
}

/// The generalised half vector of a rough dielectric interface (upper hemisphere) and
/// the relative index η' of the crossing (1 for reflection), or `None` for degenerate
/// or back-facing configurations (pbrt-v4's `DielectricBxDF::f`).
#[inline]
fn dielectric_half(wo: DVec3, wi: DVec3, ior: f64) -> Option<(DVec3, f64, bool)> {
    let (cos_o, cos_i) = (wo.z, wi.z);
    if cos_o == 0.0 || cos_i == 0.0 {
        return None;
    }
    let reflect = cos_o * cos_i > 0.0;
    let etap = if reflect {
        1.0
    } else if cos_o > 0.0 {
        ior
    } else {
        1.0 / ior
    };
    let wm = wi * etap + wo;
    if wm.length_squared() == 0.0 {
        return None;
    }
    let mut wm = wm.normalize();
    if wm.z < 0.0 {
        wm = -wm;
    }
    // Microfacets seen from behind scatter nothing.
    if wm.dot(wi) * cos_i < 0.0 || wm.dot(wo) * cos_o < 0.0 {
        return None;
    }
    Some((wm, etap, reflect))
}

/// Unit-weight rough dielectric (outside: local +z, index `ior` inside), flux form.
#[inline]
pub fn dielectric_f(wo: DVec3, wi: DVec3, alpha: f64, ior: f64) -> f64 {
    let Some((wm, etap, reflect)) = dielectric_half(wo, wi, ior) else {
        return 0.0;
    };
    let fr = fr_dielectric(wo.dot(wm), ior);
    let d = ggx_d(wm, alpha);
    let g = ggx_g(wo, wi, alpha);
    if reflect {
        d * g * fr / (4.0 * (wo.z * wi.z).abs())
    } else {
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * wi.z * wo.z;
        d * (1.0 - fr) * g * (wi.dot(wm) * wo.dot(wm) / denom).abs()
    }
}

/// Density of [`dielectric_sample`].
#[inline]
pub fn dielectric_pdf(wo: DVec3, wi: DVec3, alpha: f64, ior: f64) -> f64 {
    let Some((wm, etap, reflect)) = dielectric_half(wo, wi, ior) else {
        return 0.0;
    };
    let r = fr_dielectric(wo.dot(wm), ior);
    // Visible normals on wo's side: the density only involves |wo·wm| and cos².
    let dv = ggx_visible_d(wo, wm, alpha);
    if reflect {
        dv / (4.0 * wo.dot(wm).abs()) * r
    } else {
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
        dv * wi.dot(wm).abs() / denom * (1.0 - r)
    }
}

/// Samples the unit-weight rough dielectric for `wo` (either side): a visible normal,
/// then reflection with probability F, else refraction: (wi, G₂/G₁(wo)).
#[inline]
pub fn dielectric_sample(wo: DVec3, alpha: f64, ior: f64, u: [f64; 3]) -> Option<(DVec3, f64)> {
    if wo.z == 0.0 {
        return None;
    }
    // Visible normals of the side wo is on, as an upper-hemisphere normal (pbrt's
    // `Sample_wm`): wo·wm < 0 below, which makes the Fresnel term see the inside.
    let wo_up = if wo.z < 0.0 { -wo } else { wo };
    let wm = ggx_sample_visible(wo_up, alpha, [u[0], u[1]]);
    let r = fr_dielectric(wo.dot(wm), ior);
    let wi = if u[2] < r {
        let wi = (-wo + wm * (2.0 * wo.dot(wm))).normalize();
        if wi.z * wo.z <= 0.0 {
            return None;
        }
        wi
    } else {
        // Refraction through wm: pbrt's `Refract` with η = n(below)/n(above).
        let (mut cos_i, mut eta, mut n) = (wm.dot(wo), ior, wm);
        if cos_i < 0.0 {
            eta = 1.0 / eta;
            cos_i = -cos_i;
            n = -n;
        }
        let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
        if sin2_t >= 1.0 {
            return None;
        }
        let cos_t = (1.0 - sin2_t).sqrt();
        let wi = (-wo / eta + n * (cos_i / eta - cos_t)).normalize();
        if wi.z * wo.z >= 0.0 {
            return None;
        }
        wi
    };
    let f = dielectric_f(wo, wi, alpha, ior);
    let pdf = dielectric_pdf(wo, wi, alpha, ior);
    if !(pdf > 0.0 && f > 0.0) {
        return None;
    }
    Some((wi, f * wi.z.abs() / pdf))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_sample_weight_is_g2_over_g1() {
        let wo = DVec3::new(0.5, 0.1, 0.7).normalize();
        for u in [[0.3, 0.6, 0.01], [0.8, 0.2, 0.99], [0.1, 0.9, 0.5]] {
            if let Some((wi, w)) = dielectric_sample(wo, 0.3, 1.5, u) {
                let expect = ggx_g(wo, wi, 0.3) / ggx_g1(wo, 0.3);
                assert!((w - expect).abs() < 1e-9, "{w} vs {expect}");
            }
        }
    }
}

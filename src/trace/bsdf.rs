//! The surface interface: one scattering function (BSDF) per material, used by the photon
//! pass, its next-event connections and the eye pass alike.
//!
//! A material is a weighted sum of lobes whose weights (albedos) sum to at most 1:
//! Lambertian reflection ρ and transmission τ, an ideal mirror, an ideal dielectric
//! (Fresnel reflection and refraction), and the two glossy lobes: a rough reflector and a
//! rough dielectric, both GGX (Trowbridge–Reitz) microfacet lobes with Smith's
//! height-correlated shadowing, sampled by visible normals (Heitz 2018, as in pbrt-v4's
//! `TrowbridgeReitzDistribution`, `ConductorBxDF` and `DielectricBxDF`).
//!
//! Directions are unit vectors pointing *away* from the surface: `wo` towards where the
//! path came from, `wi` where it goes (pbrt's convention). The shading frame is the
//! geometric normal's: there are no shading normals. Transmission is evaluated in its
//! flux form (pbrt's `TransportMode::Importance`, no 1/η² radiance scaling), as the ideal
//! glass always was; the factors cancel on any way into and out of a dielectric.

use super::scatter::{reflect, refract};
use crate::sampling::{cosine_hemisphere, uniform};
use crate::scene::Material;
use glam::DVec3;
use rand_pcg::Pcg32;
use std::f64::consts::{FRAC_1_PI, PI};

/// Glossy lobes rougher than this (α = roughness² ≥ 0.04) are connected to next-event
/// receivers like diffuse ones; sharper lobes would give connections a variance growing
/// as 1/α², so their photons score next-event receivers by crossing, as a mirror's do.
pub const CONNECT_MIN_ALPHA: f64 = 0.04;

/// Which kind of lobe scattered a path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeKind {
    Diffuse,
    /// A microfacet lobe: `f` is finite, so it can be evaluated and connected.
    Glossy,
    /// A mirror or an ideal refraction (a Dirac lobe): it can only be sampled.
    Specular,
}

/// A sampled scattering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Unit direction the path continues in.
    pub dir: DVec3,
    /// It crossed to the other side of the surface.
    pub transmitted: bool,
    pub kind: LobeKind,
    /// f·|cos θ_i|/pdf of the chosen lobe divided by the lobe's albedo weight: 1 for the
    /// Lambertian and ideal lobes, G₂/G₁(wo) ≤ 1 for a glossy lobe (the energy
    /// single-scattering microfacet models lose).
    pub weight: f64,
}

/// A material's BSDF: its lobes' albedo weights as cumulative thresholds for one uniform
/// number (Russian roulette over lobes), the dielectric's index and the GGX α.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    diffuse_reflect: f64,
    diffuse_transmit: f64,
    mirror: f64,
    dielectric: f64,
    glossy_reflect: f64,
    glossy_transmit: f64,
    ior: f64,
    /// GGX α = roughness².
    alpha: f64,
}

impl Bsdf {
    pub fn new(m: &Material) -> Bsdf {
        let diffuse_reflect = m.reflectance;
        let diffuse_transmit = diffuse_reflect + m.transmittance;
        let mirror = diffuse_transmit + m.specular_reflectance;
        let dielectric = mirror + m.specular_transmittance;
        let glossy_reflect = dielectric + m.glossy_reflectance;
        let glossy_transmit = glossy_reflect + m.glossy_transmittance;
        Bsdf {
            diffuse_reflect,
            diffuse_transmit,
            mirror,
            dielectric,
            glossy_reflect,
            glossy_transmit,
            ior: m.ior,
            alpha: (m.roughness * m.roughness).max(1e-7),
        }
    }

    /// Diffuse reflectance and diffuse transmittance.
    #[inline]
    pub fn diffuse(&self) -> (f64, f64) {
        (
            self.diffuse_reflect,
            self.diffuse_transmit - self.diffuse_reflect,
        )
    }

    /// Ideal mirror and ideal dielectric weights.
    #[inline]
    pub fn specular(&self) -> (f64, f64) {
        (
            self.mirror - self.diffuse_transmit,
            self.dielectric - self.mirror,
        )
    }

    /// Glossy reflector and rough dielectric weights.
    #[inline]
    pub fn glossy(&self) -> (f64, f64) {
        (
            self.glossy_reflect - self.dielectric,
            self.glossy_transmit - self.glossy_reflect,
        )
    }

    #[inline]
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    #[inline]
    pub fn ior(&self) -> f64 {
        self.ior
    }

    /// Its glossy lobes are connected to next-event receivers ([`CONNECT_MIN_ALPHA`]).
    #[inline]
    pub fn glossy_connectable(&self) -> bool {
        let (r, t) = self.glossy();
        r + t > 0.0 && self.alpha >= CONNECT_MIN_ALPHA
    }

    /// Some part of it is connected to next-event receivers.
    #[inline]
    pub fn connectable(&self) -> bool {
        let (rho, tau) = self.diffuse();
        rho + tau > 0.0 || self.glossy_connectable()
    }

    /// The BSDF's finite part f(wo, wi) (1/sr): Lambertian and glossy lobes; the Dirac
    /// lobes are zero almost everywhere. `n` is the unit geometric normal, whose side is
    /// the dielectrics' outside.
    #[inline]
    pub fn f(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        self.f_diffuse(wo, wi, n) + self.f_glossy(wo, wi, n)
    }

    /// What next-event connections evaluate: f without glossy lobes too sharp to
    /// connect, whose photons score by crossing instead.
    #[inline]
    pub fn f_connectable(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        let glossy = if self.glossy_connectable() {
            self.f_glossy(wo, wi, n)
        } else {
            0.0
        };
        self.f_diffuse(wo, wi, n) + glossy
    }

    /// Lambertian part: ρ/π on wo's side, τ/π across.
    #[inline]
    pub fn f_diffuse(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        let (rho, tau) = self.diffuse();
        if wo.dot(n) * wi.dot(n) > 0.0 {
            rho * FRAC_1_PI
        } else {
            tau * FRAC_1_PI
        }
    }

    /// Glossy part: both microfacet lobes times their weights.
    #[inline]
    pub fn f_glossy(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        let (gr, gt) = self.glossy();
        let mut f = 0.0;
        if gr > 0.0 || gt > 0.0 {
            let frame = Frame::new(n);
            let (lo, li) = (frame.to_local(wo), frame.to_local(wi));
            if gr > 0.0 {
                f += gr * conductor_f(lo, li, self.alpha);
            }
            if gt > 0.0 {
                f += gt * dielectric_f(lo, li, self.alpha, self.ior);
            }
        }
        f
    }

    /// Density (1/sr) with which [`Bsdf::sample`] returns `wi` through a finite lobe,
    /// lobe choice included: it integrates to the finite lobes' total weight, not 1.
    pub fn pdf(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        let (rho, tau) = self.diffuse();
        let (gr, gt) = self.glossy();
        let cos_i = wi.dot(n);
        let mut p = if wo.dot(n) * cos_i > 0.0 {
            rho * cos_i.abs() * FRAC_1_PI
        } else {
            tau * cos_i.abs() * FRAC_1_PI
        };
        if gr > 0.0 || gt > 0.0 {
            let frame = Frame::new(n);
            let (lo, li) = (frame.to_local(wo), frame.to_local(wi));
            if gr > 0.0 {
                p += gr * conductor_pdf(lo, li, self.alpha);
            }
            if gt > 0.0 {
                p += gt * dielectric_pdf(lo, li, self.alpha, self.ior);
            }
        }
        p
    }

    /// Chooses a lobe by Russian roulette on the weights and samples the new direction
    /// of a path travelling along unit `dir` onto a surface of unit geometric normal
    /// `normal` (either orientation for the lobes that do not care; the dielectrics'
    /// outside is the side `normal` points to). `None`: absorbed, or a glossy sample
    /// fell below the surface (a zero-weight sample).
    ///
    /// The random numbers drawn for the Lambertian and ideal lobes are those of the
    /// original roulette, so materials without glossy lobes trace exactly as before.
    #[inline]
    pub fn sample(&self, dir: DVec3, normal: DVec3, rng: &mut Pcg32) -> Option<Sample> {
        let xi = uniform(rng);
        let cos_in = dir.dot(normal);
        // Normal on the side the path comes from.
        let facing = if cos_in < 0.0 { normal } else { -normal };
        let ideal = |dir, transmitted, kind| {
            Some(Sample {
                dir,
                transmitted,
                kind,
                weight: 1.0,
            })
        };
        if xi < self.diffuse_reflect {
            ideal(cosine_hemisphere(rng, facing), false, LobeKind::Diffuse)
        } else if xi < self.diffuse_transmit {
            ideal(cosine_hemisphere(rng, -facing), true, LobeKind::Diffuse)
        } else if xi < self.mirror {
            ideal(reflect(dir, facing), false, LobeKind::Specular)
        } else if xi < self.dielectric {
            let eta = if cos_in < 0.0 {
                1.0 / self.ior
            } else {
                self.ior
            };
            match refract(dir, facing, eta) {
                Some((refracted, fresnel)) if uniform(rng) >= fresnel => {
                    ideal(refracted, true, LobeKind::Specular)
                }
                // Fresnel reflection, or total internal reflection.
                _ => ideal(reflect(dir, facing), false, LobeKind::Specular),
            }
        } else if xi < self.glossy_reflect {
            let u = [uniform(rng), uniform(rng)];
            self.sample_glossy_reflection(-dir, normal, u)
        } else if xi < self.glossy_transmit {
            let u = [uniform(rng), uniform(rng), uniform(rng)];
            self.sample_rough_dielectric(-dir, normal, u)
        } else {
            None
        }
    }

    /// Samples the glossy reflector's lobe for `wo` (visible normals); the weight is
    /// G₂/G₁(wo). `None` when the reflected direction falls below the surface.
    pub fn sample_glossy_reflection(&self, wo: DVec3, n: DVec3, u: [f64; 2]) -> Option<Sample> {
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

/// An orthonormal frame whose z is a given unit normal (Duff et al. 2017).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    x: DVec3,
    y: DVec3,
    z: DVec3,
}

impl Frame {
    #[inline]
    pub fn new(z: DVec3) -> Frame {
        let sign = 1f64.copysign(z.z);
        let a = -1.0 / (sign + z.z);
        let b = z.x * z.y * a;
        Frame {
            x: DVec3::new(1.0 + sign * z.x * z.x * a, sign * b, -sign * z.x),
            y: DVec3::new(b, sign + z.y * z.y * a, -z.y),
            z,
        }
    }

    #[inline]
    pub fn to_local(&self, w: DVec3) -> DVec3 {
        DVec3::new(w.dot(self.x), w.dot(self.y), w.dot(self.z))
    }

    #[inline]
    pub fn to_world(&self, w: DVec3) -> DVec3 {
        self.x * w.x + self.y * w.y + self.z * w.z
    }
}

/// GGX normal distribution D(wm) (1/sr), local frame.
#[inline]
pub fn ggx_d(wm: DVec3, alpha: f64) -> f64 {
    let cos2 = wm.z * wm.z;
    if cos2 <= 0.0 {
        return 0.0;
    }
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    let e = 1.0 + tan2 / (alpha * alpha);
    1.0 / (PI * alpha * alpha * cos2 * cos2 * e * e)
}

/// Smith's Λ(w) for GGX.
#[inline]
pub fn ggx_lambda(w: DVec3, alpha: f64) -> f64 {
    let cos2 = w.z * w.z;
    if cos2 <= 0.0 {
        return f64::INFINITY;
    }
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
}

/// Smith's masking G₁(w).
#[inline]
pub fn ggx_g1(w: DVec3, alpha: f64) -> f64 {
    1.0 / (1.0 + ggx_lambda(w, alpha))
}

/// Height-correlated masking-shadowing G₂(wo, wi).
#[inline]
pub fn ggx_g(wo: DVec3, wi: DVec3, alpha: f64) -> f64 {
    1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha))
}

/// Density of visible normals D_wo(wm) = G₁(wo)·max(0, wo·wm)·D(wm)/|cos θo|.
#[inline]
pub fn ggx_visible_d(wo: DVec3, wm: DVec3, alpha: f64) -> f64 {
    if wo.z == 0.0 {
        return 0.0;
    }
    ggx_g1(wo, alpha) / wo.z.abs() * ggx_d(wm, alpha) * wo.dot(wm).abs()
}

/// Samples a visible microfacet normal (upper hemisphere) for `wo` (Heitz 2018, in
/// pbrt-v4's form): stretch to α = 1, sample the projected hemisphere, unstretch.
#[inline]
pub fn ggx_sample_visible(wo: DVec3, alpha: f64, u: [f64; 2]) -> DVec3 {
    let mut wh = DVec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    if wh.z < 0.0 {
        wh = -wh;
    }
    let t1 = if wh.z < 0.99999 {
        DVec3::Z.cross(wh).normalize()
    } else {
        DVec3::X
    };
    let t2 = wh.cross(t1);
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let (px, mut py) = (r * phi.cos(), r * phi.sin());
    let h = (1.0 - px * px).max(0.0).sqrt();
    let s = 0.5 * (1.0 + wh.z);
    py = (1.0 - s) * h + s * py;
    let pz = (1.0 - px * px - py * py).max(0.0).sqrt();
    let nh = t1 * px + t2 * py + wh * pz;
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
}

/// Unpolarised Fresnel reflectance for cos θ to the normal on the side of `cos_i`'s
/// sign and `eta` = n(below)/n(above) (pbrt-v4's `FrDielectric`).
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
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
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
    fn frame_is_orthonormal() {
        for z in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::new(0.3, -0.4, 0.866).normalize(),
        ] {
            let f = Frame::new(z);
            let w = DVec3::new(0.2, 0.5, -0.7).normalize();
            assert!((f.to_world(f.to_local(w)) - w).length() < 1e-12);
            assert!(f.x.dot(f.y).abs() < 1e-12 && f.x.cross(f.y).dot(z) > 0.999);
        }
    }

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

//! The Lambertian lobe: diffuse reflection and diffuse transmission.

use super::{facing, ideal, Bsdf, Incidence, Lobe, LobeKind, Sample, Transport};
use crate::sampling::cosine_hemisphere;
use glam::DVec3;
use rand_pcg::Pcg32;
use std::f64::consts::{FRAC_1_PI, PI};

/// Lambertian reflection ρ (on wo's side) and transmission τ (across).
#[derive(Clone, Copy, Debug)]
pub struct Lambertian {
    rho: f64,
    tau: f64,
    /// τ as the roulette line gives it ((ρ + τ) − ρ), which f and connections use.
    tau_line: f64,
    /// Roulette threshold between reflection and transmission.
    reflect_hi: f64,
}

impl Lambertian {
    pub(super) fn add(b: &mut Bsdf, rho: f64, tau: f64) {
        let (_, reflect_hi) = b.stack(rho);
        let (_, hi) = b.stack(tau);
        let tau_line = hi - reflect_hi;
        b.diffuse = (reflect_hi, tau_line);
        let lobe = Lambertian {
            rho: reflect_hi,
            tau,
            tau_line,
            reflect_hi,
        };
        b.push(rho > 0.0 || tau > 0.0, lobe);
    }
}

impl Lobe for Lambertian {
    fn kind(&self) -> LobeKind {
        LobeKind::Diffuse
    }

    fn sample(&self, xi: f64, dir: DVec3, normal: DVec3, rng: &mut Pcg32) -> Option<Sample> {
        let facing = facing(dir, normal);
        if xi < self.reflect_hi {
            ideal(cosine_hemisphere(rng, facing), false, LobeKind::Diffuse)
        } else {
            ideal(cosine_hemisphere(rng, -facing), true, LobeKind::Diffuse)
        }
    }

    /// ρ/π on wo's side, τ/π across.
    fn f(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        if wo.dot(n) * wi.dot(n) > 0.0 {
            self.rho * FRAC_1_PI
        } else {
            self.tau_line * FRAC_1_PI
        }
    }

    fn pdf(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        let cos_i = wi.dot(n);
        if wo.dot(n) * cos_i > 0.0 {
            self.rho * cos_i.abs() * FRAC_1_PI
        } else {
            self.tau_line * cos_i.abs() * FRAC_1_PI
        }
    }

    fn f_cos(&self, w: f64, _: DVec3, _: DVec3, _: DVec3, cos_i: f64, mode: Transport) -> f64 {
        match mode {
            Transport::Importance => {
                let coefficient = if cos_i > 0.0 { self.rho } else { self.tau_line };
                w * coefficient * cos_i.abs() * FRAC_1_PI
            }
            Transport::Radiance => {
                if cos_i >= 0.0 {
                    w * self.rho * cos_i / PI
                } else {
                    w * self.tau * -cos_i / PI
                }
            }
        }
    }

    /// ρ/π times the illuminance on the eye's side, τ/π times the other side's.
    fn eye_indirect(
        &self,
        w: f64,
        _: &Incidence,
        e_seen: &dyn Fn() -> f64,
        e_other: &dyn Fn() -> f64,
        _: bool,
    ) -> f64 {
        w * (self.rho * e_seen() + self.tau * e_other()) / PI
    }
}

//! The ideal dielectric: Fresnel reflection and Snell refraction at a smooth interface.

use super::fresnel::{reflect, refract};
use super::{facing, ideal, Bsdf, Continuation, Incidence, Lobe, LobeKind, Sample};
use crate::sampling::uniform;
use glam::DVec3;
use rand_pcg::Pcg32;

/// An ideal dielectric of weight `t` and index `ior` (outside: the normal's side):
/// Fresnel reflection and refraction.
#[derive(Clone, Copy, Debug)]
pub struct Glass {
    t: f64,
    ior: f64,
}

impl Glass {
    pub(super) fn add(b: &mut Bsdf, t: f64, ior: f64) {
        b.stack(t);
        b.push(t > 0.0, Glass { t, ior });
    }
}

impl Lobe for Glass {
    fn kind(&self) -> LobeKind {
        LobeKind::Specular
    }

    fn sample(&self, _: f64, dir: DVec3, normal: DVec3, rng: &mut Pcg32) -> Option<Sample> {
        let facing = facing(dir, normal);
        let eta = if dir.dot(normal) < 0.0 {
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
    }

    /// Both the reflection and the refraction, split by Fresnel.
    fn eye_continue(
        &self,
        w: f64,
        at: &Incidence,
        _: &dyn Fn() -> Pcg32,
        out: &mut dyn FnMut(Continuation),
    ) {
        let (dir, facing) = (at.dir, at.facing);
        let eta = if at.back { self.ior } else { 1.0 / self.ior };
        let w = w * self.t;
        let go = Continuation::specular;
        match refract(dir, facing, eta) {
            Some((refracted, fresnel)) => {
                out(go(reflect(dir, facing), w * fresnel, false));
                out(go(refracted, w * (1.0 - fresnel), true));
            }
            None => out(go(reflect(dir, facing), w, false)),
        }
    }
}

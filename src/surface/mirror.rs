//! The ideal mirror.

use super::fresnel::reflect;
use super::{facing, ideal, Bsdf, Continuation, Incidence, Lobe, LobeKind, Sample};
use glam::DVec3;
use rand_pcg::Pcg32;

/// An ideal mirror of reflectance `r`.
#[derive(Clone, Copy, Debug)]
pub struct Mirror {
    r: f64,
}

impl Mirror {
    pub(super) fn add(b: &mut Bsdf, r: f64) {
        b.stack(r);
        b.push(r > 0.0, Mirror { r });
    }
}

impl Lobe for Mirror {
    fn kind(&self) -> LobeKind {
        LobeKind::Specular
    }

    fn sample(&self, _: f64, dir: DVec3, normal: DVec3, _: &mut Pcg32) -> Option<Sample> {
        ideal(reflect(dir, facing(dir, normal)), false, LobeKind::Specular)
    }

    fn eye_continue(
        &self,
        w: f64,
        at: &Incidence,
        _: &dyn Fn() -> Pcg32,
        out: &mut dyn FnMut(Continuation),
    ) {
        out(Continuation::specular(
            reflect(at.dir, at.facing),
            w * self.r,
            false,
        ));
    }
}

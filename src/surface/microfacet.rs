//! GGX (Trowbridge–Reitz) microfacet maths in a local shading frame (z: the normal):
//! the normal distribution, Smith's height-correlated masking and shadowing, and the
//! sampling of visible normals (Heitz 2018, as in pbrt-v4's
//! `TrowbridgeReitzDistribution`). The lobes built on it are in `glossy.rs`.

use glam::DVec3;
use std::f64::consts::PI;

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
    let (px, mut py) = (r * libm::cos(phi), r * libm::sin(phi));
    let h = (1.0 - px * px).max(0.0).sqrt();
    let s = 0.5 * (1.0 + wh.z);
    py = (1.0 - s) * h + s * py;
    let pz = (1.0 - px * px - py * py).max(0.0).sqrt();
    let nh = t1 * px + t2 * py + wh * pz;
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
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
}

//! What a surface does to a photon: Russian roulette over the material's lobes (the
//! photon keeps its flux, so grey materials never change a photon's weight), and the
//! offset that starts the next ray off the surface without self-intersection.

use crate::sampling::uniform;
use crate::surface::{Bsdf, Sample};
use glam::{DVec3, Vec3};
use rand_pcg::Pcg32;

/// What a surface does to a photon: the BSDF's roulette over lobes picks one and samples
/// its direction; a glossy sample's weight G₂/G₁ ≤ 1 (the energy a single-scattering
/// microfacet lobe loses) is played by a second roulette, so every photon that goes on
/// still carries the flux it was emitted with (the triangle tallies count photons).
/// `None`: absorbed. The second roulette draws only after a glossy sample (weight < 1),
/// so a material without glossy lobes draws nothing for it.
#[inline]
pub fn scatter(bsdf: &Bsdf, dir: DVec3, normal: DVec3, rng: &mut Pcg32) -> Option<Sample> {
    let s = bsdf.sample(dir, normal, rng)?;
    if s.weight < 1.0 && uniform(rng) >= s.weight {
        return None;
    }
    Some(s)
}

/// Moves a surface point `p` off the surface along `n` (unit, pointing to the side the
/// next ray leaves on) by a few ULPs of its coordinates, so the next ray cannot hit the
/// surface it starts on, whatever the coordinates' magnitude (Wächter & Binder, *Ray
/// Tracing Gems* ch. 6). Near the frame's origin, where ULPs vanish, the offset is a
/// fixed fraction of `scene_scale` (the largest local coordinate), so a 0.1 mm room and
/// a 10 km site behave alike.
#[inline]
pub fn offset_origin(p: Vec3, n: Vec3, scene_scale: f32) -> Vec3 {
    let offset = Offset::new(scene_scale);
    Vec3::new(
        offset.coordinate(p.x, n.x),
        offset.coordinate(p.y, n.y),
        offset.coordinate(p.z, n.z),
    )
}

/// [`offset_origin`] for a batch, in place: each point `p[..][k]` moves off its surface
/// along `n[..][k]`. One straight pass the compiler can vectorise; the same numbers as
/// [`offset_origin`], point by point.
pub fn offset_origins(p: [&mut [f32]; 3], n: [&[f32]; 3], scene_scale: f32) {
    let offset = Offset::new(scene_scale);
    for (p, n) in p.into_iter().zip(n) {
        for (p, &n) in p.iter_mut().zip(n) {
            *p = offset.coordinate(*p, n);
        }
    }
}

/// The two regimes of [`offset_origin`] for one scene.
#[derive(Clone, Copy)]
struct Offset {
    near_origin: f32,
    float_scale: f32,
}

impl Offset {
    #[inline(always)]
    fn new(scene_scale: f32) -> Offset {
        Offset {
            near_origin: scene_scale * (1.0 / 32.0),
            float_scale: scene_scale * (1.0 / 1_048_576.0),
        }
    }

    /// One coordinate `p` moved along the normal's component `n` (|n| ≤ 1): both
    /// regimes are computed and one is kept, without a branch.
    #[inline(always)]
    fn coordinate(self, p: f32, n: f32) -> f32 {
        const INT_SCALE: f32 = 256.0;
        let of_i = trunc_small(INT_SCALE * n);
        let ulps = f32::from_bits((p.to_bits() as i32 + if p < 0.0 { -of_i } else { of_i }) as u32);
        let fixed = p + self.float_scale * n;
        if p.abs() < self.near_origin {
            fixed
        } else {
            ulps
        }
    }
}

/// `x as i32` for |x| < 2²¹ (and NaN, which gives 0), in arithmetic the compiler
/// vectorises: `as` saturates, which it can only do one lane at a time. Adding 1.5·2²³
/// rounds x to the nearest integer r, whose value the sum's low mantissa bits hold; a
/// step back toward zero where r lies beyond x makes it the truncation.
#[inline(always)]
fn trunc_small(x: f32) -> i32 {
    const MAGIC: f32 = 12_582_912.0;
    let r = (x + MAGIC) - MAGIC;
    let back = ((x >= 0.0) & (r > x)) as i32 - ((x < 0.0) & (r < x)) as i32;
    let t = (r + MAGIC).to_bits() as i32 - MAGIC.to_bits() as i32 - back;
    if x.is_nan() {
        0
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trunc_small_is_the_cast_for_every_offset() {
        // Every f32 in [−256, 256] (the offsets 256·n of unit normals) in steps of 7
        // bit patterns, the integers and half-integers, ±0 and NaN.
        let patterns = (0..=256.0f32.to_bits()).step_by(7).map(f32::from_bits);
        let halves = (-512..=512).map(|k| k as f32 * 0.5);
        let special = [0.0, -0.0, f32::NAN, 255.99998, -255.99998];
        for x in patterns.flat_map(|x| [x, -x]).chain(halves).chain(special) {
            assert_eq!(trunc_small(x), x as i32, "{x}");
        }
    }

    #[test]
    fn offset_origin_leaves_the_surface_far_from_the_origin() {
        for (p, scale) in [
            (Vec3::new(1e5, -1e5, 3.0), 1e5),
            (Vec3::new(0.001, 0.0, -0.01), 3.0),
            (Vec3::splat(7.5), 10.0),
            (Vec3::new(1e-5, 2e-5, 0.0), 5e-5),
        ] {
            let q = offset_origin(p, Vec3::Z, scale);
            assert!(q.z > p.z && q.z - p.z < 1e-4 * scale, "{p} → {q}");
            let q = offset_origin(p, -Vec3::Z, scale);
            assert!(q.z < p.z && p.z - q.z < 1e-4 * scale, "{p} → {q}");
        }
    }
}

//! Thin glazing: one or more parallel panes of uncoated glass (index n, 1.52 by
//! default) given by their normal transmittances Tn. A pane's reflectance and
//! transmittance sum its internal reflections exactly, per polarisation (Fresnel), with
//! the absorption of a pass τ = tn^(1/cos θt), tn the pane's transmissivity (Radiance's
//! `glass`); panes combine by the adding formula, per polarisation. The light goes
//! straight through (a thin pane does not offset it) or is reflected specularly; the
//! rest is absorbed.

use super::fresnel::reflect;
use super::{facing, ideal, Bsdf, Continuation, Incidence, Lobe, LobeKind, Sample};
use crate::sampling::uniform;
use glam::DVec3;
use rand_pcg::Pcg32;

/// Index of refraction of glazing where the material gives none.
pub const DEFAULT_GLAZING_IOR: f64 = 1.52;

/// A glazing unit: its panes' transmissivities (the fraction a pass through the pane's
/// thickness keeps at normal incidence) and their index.
#[derive(Clone, Debug, PartialEq)]
pub struct Glazing {
    pub transmissivities: Vec<f64>,
    pub ior: f64,
}

/// Reflectance at normal incidence of a face of index `n`.
fn normal_reflectance(n: f64) -> f64 {
    let r = (n - 1.0) / (n + 1.0);
    r * r
}

/// One pane's (R, T) per polarisation (s, p) at incidence cos θ = `cos_i`.
fn pane(cos_i: f64, n: f64, tn: f64) -> [(f64, f64); 2] {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (n * n);
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    let rp = (cos_t - n * cos_i) / (cos_t + n * cos_i);
    let tau = libm::pow(tn, 1.0 / cos_t);
    [rs * rs, rp * rp].map(|rho| {
        let denominator = 1.0 - rho * rho * tau * tau;
        let t = (1.0 - rho) * (1.0 - rho) * tau / denominator;
        let r = rho + rho * (1.0 - rho) * (1.0 - rho) * tau * tau / denominator;
        (r, t)
    })
}

impl Glazing {
    /// The transmissivity of a pane of index `n` whose normal transmittance is `tn`
    /// (the root of ρ²·Tn·t² + (1 − ρ)²·t − Tn = 0, ρ the face's normal reflectance);
    /// None beyond the clear pane's limit (t > 1 would create energy) or for Tn ≤ 0.
    pub fn transmissivity(normal_transmittance: f64, n: f64) -> Option<f64> {
        let tn = normal_transmittance;
        if !(tn > 0.0) {
            return None;
        }
        let rho = normal_reflectance(n);
        let (a, b) = (rho * rho * tn, (1.0 - rho) * (1.0 - rho));
        let t = 2.0 * tn / (b + (b * b + 4.0 * a * tn).sqrt());
        (t <= 1.0 + 1e-12).then_some(t.min(1.0))
    }

    /// The largest normal transmittance a pane of index `n` can have (no absorption).
    pub fn clear_pane_transmittance(n: f64) -> f64 {
        let rho = normal_reflectance(n);
        (1.0 - rho) / (1.0 + rho)
    }

    /// Reflectance and transmittance of the unit at incidence cos θ = `cos_i`
    /// (unpolarised light: the mean of s and p).
    pub fn reflect_transmit(&self, cos_i: f64) -> (f64, f64) {
        let mut unit = [(0.0, 1.0); 2];
        for &tn in &self.transmissivities {
            let pane = pane(cos_i, self.ior, tn);
            for (u, (rb, tb)) in unit.iter_mut().zip(pane) {
                let (ra, ta) = *u;
                let d = 1.0 - ra * rb;
                *u = (ra + ta * ta * rb / d, ta * tb / d);
            }
        }
        (0.5 * (unit[0].0 + unit[1].0), 0.5 * (unit[0].1 + unit[1].1))
    }

    pub(super) fn add(b: &mut Bsdf, glazing: &Option<Glazing>) {
        if let Some(g) = glazing {
            b.stack(1.0);
            b.push(true, g.clone());
        }
    }
}

impl Lobe for Glazing {
    fn kind(&self) -> LobeKind {
        LobeKind::Specular
    }

    fn sample(&self, _: f64, dir: DVec3, normal: DVec3, rng: &mut Pcg32) -> Option<Sample> {
        let facing = facing(dir, normal);
        let (r, t) = self.reflect_transmit(-dir.dot(facing));
        let u = uniform(rng);
        if u < r {
            ideal(reflect(dir, facing), false, LobeKind::Specular)
        } else if u < r + t {
            ideal(dir, true, LobeKind::Specular)
        } else {
            None
        }
    }

    /// The reflection and the straight transmission, each by its share.
    fn eye_continue(
        &self,
        w: f64,
        at: &Incidence,
        _: &dyn Fn() -> Pcg32,
        out: &mut dyn FnMut(Continuation),
    ) {
        let (r, t) = self.reflect_transmit(-at.dir.dot(at.facing));
        out(Continuation::specular(
            reflect(at.dir, at.facing),
            w * r,
            false,
        ));
        out(Continuation::see_through(at.dir, w * t));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stokes' closed form for N non-absorbing panes: per polarisation, of face
    /// reflectance ρ, T = (1 − ρ)/(1 + (2N − 1)ρ); checked at 0–89° for 1 to 3 panes,
    /// ρ from Fresnel's equations written out here.
    #[test]
    fn clear_panes_match_stokes_closed_form_at_every_angle() {
        let n = 1.52;
        for panes in 1..=3usize {
            let g = Glazing {
                transmissivities: vec![1.0; panes],
                ior: n,
            };
            for k in 0..=89 {
                let ci = libm::cos((k as f64).to_radians());
                let st = (1.0 - ci * ci).sqrt() / n;
                let ct = (1.0 - st * st).sqrt();
                let (a, b) = ((ci - n * ct) / (ci + n * ct), (n * ci - ct) / (n * ci + ct));
                let (rs, rp) = (a * a, b * b);
                let m = (2 * panes - 1) as f64;
                let t = 0.5 * ((1.0 - rs) / (1.0 + m * rs) + (1.0 - rp) / (1.0 + m * rp));
                let (r, got) = g.reflect_transmit(ci);
                assert!(
                    (got - t).abs() < 1e-12,
                    "{panes} panes, {k}°: {got} against {t}"
                );
                assert!((r + got - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn normal_transmittance_round_trips_and_the_clear_pane_conserves_energy() {
        for tn in [0.05, 0.3, 0.6, 0.88, 0.9] {
            let t = Glazing::transmissivity(tn, 1.52).unwrap();
            let g = Glazing {
                transmissivities: vec![t],
                ior: 1.52,
            };
            assert!((g.reflect_transmit(1.0).1 - tn).abs() < 1e-12, "{tn}");
        }
        // Radiance's glass: tn = (sqrt(.8402528435 + .0072522239 Tn²) − .9166530661)/.0036261119/Tn.
        let tn: f64 = 0.88;
        let radiance = ((0.840_252_843_5 + 0.007_252_223_9 * tn * tn).sqrt() - 0.916_653_066_1)
            / 0.003_626_111_9
            / tn;
        assert!((Glazing::transmissivity(tn, 1.52).unwrap() - radiance).abs() < 1e-8);
        let clear = Glazing::clear_pane_transmittance(1.52);
        assert!(Glazing::transmissivity(clear + 1e-6, 1.52).is_none());
        let g = Glazing {
            transmissivities: vec![1.0, 1.0],
            ior: 1.52,
        };
        for k in 0..=89 {
            let (r, t) = g.reflect_transmit(libm::cos((k as f64).to_radians()));
            assert!((r + t - 1.0).abs() < 1e-12, "{k}°: R + T = {}", r + t);
        }
    }
}

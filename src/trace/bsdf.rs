//! The surface interface: one scattering function (BSDF) per material, used by the photon
//! pass, its next-event connections and the eye pass alike.
//!
//! A material is a weighted sum of lobes whose weights (albedos) sum to at most 1, each
//! a [`Lobe`]: [`Lambertian`] reflection ρ and transmission τ, an ideal [`Mirror`], an
//! ideal dielectric ([`Glass`]: Fresnel reflection and refraction), and [`Glossy`]: a
//! rough reflector and a rough dielectric, both GGX (Trowbridge–Reitz) microfacet lobes
//! with Smith's height-correlated shadowing, sampled by visible normals (Heitz 2018, as
//! in pbrt-v4's `TrowbridgeReitzDistribution`, `ConductorBxDF` and `DielectricBxDF`).
//! [`Bsdf::new`] is the one place that turns a `Material`'s fields into lobes; callers
//! (`trace`, `render`) evaluate and sample through [`Bsdf`] and never name a lobe.
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
use std::fmt::Debug;
use std::sync::Arc;

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

/// Who evaluates f·|cos θ_i| (pbrt's transport mode): photons (flux) connected to a
/// next-event receiver, or the eye pass (luminance). The physics is the same; the
/// Lambertian lobe keeps the two arithmetic forms each pass always used, so that every
/// output stays bit for bit what it was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    Importance,
    Radiance,
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

/// Where an eye ray meets a surface, as the eye pass's lobe methods read it.
#[derive(Clone, Copy, Debug)]
pub struct Incidence {
    /// The ray's unit direction (towards the surface).
    pub dir: DVec3,
    /// Unit geometric normal, and the normal on the eye's side.
    pub n: DVec3,
    pub facing: DVec3,
    /// The eye sees the triangle's back.
    pub back: bool,
}

impl Incidence {
    pub fn new(dir: DVec3, n: DVec3) -> Incidence {
        let back = dir.dot(n) > 0.0;
        Incidence {
            dir,
            n,
            facing: if back { -n } else { n },
            back,
        }
    }
}

/// A ray the eye pass continues along from a vertex.
#[derive(Clone, Copy, Debug)]
pub struct Continuation {
    pub dir: DVec3,
    /// The path's weight times what the lobe passes on.
    pub weight: f64,
    /// It leaves through the surface (its origin is offset to the other side).
    pub transmitted: bool,
    /// The lobe already took the light of sources it sees (by shadow rays through `f`),
    /// so sources met along it are not counted again.
    pub lights_counted: bool,
}

/// One lobe of a BSDF: its physics for the photon pass, next-event connections and the
/// eye pass. A new kind of surface implements this and adds one line to [`Bsdf::new`].
pub trait Lobe: Debug + Send + Sync {
    fn kind(&self) -> LobeKind;

    /// Connected to next-event receivers (a finite f of bounded variance).
    fn connectable(&self) -> bool {
        self.kind() == LobeKind::Diffuse
    }

    /// Samples the photon's new direction once the roulette chose this lobe with `xi`
    /// (below the lobe's upper threshold), for a path travelling along unit `dir` onto
    /// a surface of unit geometric normal `normal`.
    fn sample(&self, xi: f64, dir: DVec3, normal: DVec3, rng: &mut Pcg32) -> Option<Sample>;

    /// The lobe's finite part of f(wo, wi) (1/sr), its weight included; 0 for Dirac lobes.
    fn f(&self, _wo: DVec3, _wi: DVec3, _n: DVec3) -> f64 {
        0.0
    }

    /// Density (1/sr) with which it samples `wi`, its weight included.
    fn pdf(&self, _wo: DVec3, _wi: DVec3, _n: DVec3) -> f64 {
        0.0
    }

    /// w·f(wo, wi)·|cos θ_i|, with `cos_i` = wi · (the normal on wo's side).
    fn f_cos(&self, w: f64, wo: DVec3, wi: DVec3, n: DVec3, cos_i: f64, _: Transport) -> f64 {
        w * self.f(wo, wi, n) * cos_i.abs()
    }

    /// Eye pass: the luminance (× `w`) it shows from the indirect illuminance read from
    /// the map on the eye's side and on the other side; `at_depth_limit`: the path
    /// cannot continue, so lobes that would continue report their share here.
    fn eye_indirect(
        &self,
        _w: f64,
        _at: &Incidence,
        _e_seen: &dyn Fn() -> f64,
        _e_other: &dyn Fn() -> f64,
        _at_depth_limit: bool,
    ) -> f64 {
        0.0
    }

    /// Eye pass: the rays it continues along (`new_rng`: the vertex's random stream).
    fn eye_continue(
        &self,
        _w: f64,
        _at: &Incidence,
        _new_rng: &dyn Fn() -> Pcg32,
        _out: &mut dyn FnMut(Continuation),
    ) {
    }
}

/// A material's BSDF: its lobes, each with the upper end of its albedo interval on the
/// cumulative line one uniform number is compared with (Russian roulette over lobes).
#[derive(Clone, Debug)]
pub struct Bsdf {
    lobes: Vec<(f64, Arc<dyn Lobe>)>,
    /// Cumulative albedo so far (while building), then the total.
    total: f64,
    /// Lambertian ρ and τ (the photon pass's fast path for pure reflectors).
    diffuse: (f64, f64),
}

impl Bsdf {
    /// The material's lobes, in roulette order: the one place that maps its fields onto
    /// lobes (a new lobe adds its line here).
    pub fn new(m: &Material) -> Bsdf {
        let mut b = Bsdf {
            lobes: Vec::new(),
            total: 0.0,
            diffuse: (0.0, 0.0),
        };
        Lambertian::add(&mut b, m.reflectance, m.transmittance);
        Mirror::add(&mut b, m.specular_reflectance);
        Glass::add(&mut b, m.specular_transmittance, m.ior);
        Glossy::add(&mut b, m);
        b
    }

    /// Stacks an albedo `weight` on the roulette line; returns its interval's (lower,
    /// upper) thresholds. Summed in `Material`'s order, as the thresholds always were.
    fn stack(&mut self, weight: f64) -> (f64, f64) {
        let lo = self.total;
        self.total = lo + weight;
        (lo, self.total)
    }

    /// Adds a lobe whose interval ends at the line's current total, if `present`.
    fn push(&mut self, present: bool, lobe: impl Lobe + 'static) {
        if present {
            self.lobes.push((self.total, Arc::new(lobe)));
        }
    }

    /// Diffuse reflectance and diffuse transmittance.
    #[inline]
    pub fn diffuse(&self) -> (f64, f64) {
        self.diffuse
    }

    /// Diffuse reflection is its only lobe (or it absorbs everything): the photon
    /// pass's roulette is then one comparison with ρ.
    #[inline]
    pub fn lambert_only(&self) -> bool {
        self.total == self.diffuse.0
    }

    /// It has a lobe of this kind.
    pub fn has(&self, kind: LobeKind) -> bool {
        self.lobes.iter().any(|(_, l)| l.kind() == kind)
    }

    /// Its glossy lobes are connected to next-event receivers ([`CONNECT_MIN_ALPHA`]).
    #[inline]
    pub fn glossy_connectable(&self) -> bool {
        self.lobes
            .iter()
            .any(|(_, l)| l.kind() == LobeKind::Glossy && l.connectable())
    }

    /// Some part of it is connected to next-event receivers.
    #[inline]
    pub fn connectable(&self) -> bool {
        self.lobes.iter().any(|(_, l)| l.connectable())
    }

    /// The BSDF's finite part f(wo, wi) (1/sr); the Dirac lobes are zero almost
    /// everywhere. `n` is the unit geometric normal, whose side is the dielectrics'
    /// outside.
    pub fn f(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        self.lobes.iter().fold(0.0, |f, (_, l)| f + l.f(wo, wi, n))
    }

    /// Density (1/sr) with which [`Bsdf::sample`] returns `wi` through a finite lobe,
    /// lobe choice included: it integrates to the finite lobes' total weight, not 1.
    pub fn pdf(&self, wo: DVec3, wi: DVec3, n: DVec3) -> f64 {
        self.lobes
            .iter()
            .fold(0.0, |p, (_, l)| p + l.pdf(wo, wi, n))
    }

    /// w·f(wo, wi)·|cos θ_i| summed over the finite lobes, or over the connectable ones
    /// only (`connectable_only`: next-event connections; the other lobes' photons score
    /// by crossing). `cos_i` = wi · (the normal on wo's side).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn f_cos(
        &self,
        w: f64,
        wo: DVec3,
        wi: DVec3,
        n: DVec3,
        cos_i: f64,
        mode: Transport,
        connectable_only: bool,
    ) -> f64 {
        let mut sum = 0.0;
        for (_, l) in &self.lobes {
            let used = if connectable_only {
                l.connectable()
            } else {
                l.kind() != LobeKind::Specular
            };
            if used {
                sum += l.f_cos(w, wo, wi, n, cos_i, mode);
            }
        }
        sum
    }

    /// Eye pass: the luminance its lobes show from the map's indirect illuminance
    /// ([`Lobe::eye_indirect`]), added to `l` lobe by lobe.
    pub fn eye_indirect(
        &self,
        l: &mut f64,
        w: f64,
        at: &Incidence,
        e_seen: &dyn Fn() -> f64,
        e_other: &dyn Fn() -> f64,
        at_depth_limit: bool,
    ) {
        for (_, lobe) in &self.lobes {
            *l += lobe.eye_indirect(w, at, e_seen, e_other, at_depth_limit);
        }
    }

    /// Eye pass: the rays its lobes continue along, in lobe order.
    pub fn eye_continue(
        &self,
        w: f64,
        at: &Incidence,
        new_rng: &dyn Fn() -> Pcg32,
        out: &mut dyn FnMut(Continuation),
    ) {
        for (_, lobe) in &self.lobes {
            lobe.eye_continue(w, at, new_rng, out);
        }
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
        for (hi, lobe) in &self.lobes {
            if xi < *hi {
                return lobe.sample(xi, dir, normal, rng);
            }
        }
        None
    }
}

/// The normal on the side a path travelling along `dir` comes from.
#[inline]
fn facing(dir: DVec3, normal: DVec3) -> DVec3 {
    if dir.dot(normal) < 0.0 {
        normal
    } else {
        -normal
    }
}

fn ideal(dir: DVec3, transmitted: bool, kind: LobeKind) -> Option<Sample> {
    Some(Sample {
        dir,
        transmitted,
        kind,
        weight: 1.0,
    })
}

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
    fn add(b: &mut Bsdf, rho: f64, tau: f64) {
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

/// An ideal mirror of reflectance `r`.
#[derive(Clone, Copy, Debug)]
pub struct Mirror {
    r: f64,
}

impl Mirror {
    fn add(b: &mut Bsdf, r: f64) {
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
        out(Continuation {
            dir: reflect(at.dir, at.facing),
            weight: w * self.r,
            transmitted: false,
            lights_counted: false,
        });
    }
}

/// An ideal dielectric of weight `t` and index `ior` (outside: the normal's side):
/// Fresnel reflection and refraction.
#[derive(Clone, Copy, Debug)]
pub struct Glass {
    t: f64,
    ior: f64,
}

impl Glass {
    fn add(b: &mut Bsdf, t: f64, ior: f64) {
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
        let go = |dir, weight, transmitted| Continuation {
            dir,
            weight,
            transmitted,
            lights_counted: false,
        };
        match refract(dir, facing, eta) {
            Some((refracted, fresnel)) => {
                out(go(reflect(dir, facing), w * fresnel, false));
                out(go(refracted, w * (1.0 - fresnel), true));
            }
            None => out(go(reflect(dir, facing), w, false)),
        }
    }
}

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

    fn add(b: &mut Bsdf, m: &Material) {
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
                });
            }
        }
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
    let (px, mut py) = (r * libm::cos(phi), r * libm::sin(phi));
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

//! Surfaces: the materials of the scene file and one scattering function (BSDF) per
//! material, used by the photon pass, its next-event connections and the eye pass alike.
//!
//! [`Material`] is a `[materials.KEY]` entry ([`MaterialFile`]: the keys) validated, with
//! its description; [`Bsdf::new`] turns its fields into lobes. Both live here, so a new
//! lobe is its file and its lines in this one.
//!
//! A material is a weighted sum of lobes whose weights (albedos) sum to at most 1, each
//! a [`Lobe`], one file each: [`Lambertian`] reflection ρ and transmission τ
//! (`lambertian.rs`), an ideal [`Mirror`] (`mirror.rs`), an ideal dielectric ([`Glass`],
//! `glass.rs`: Fresnel reflection and refraction), thin [`Glazing`] (`glazing.rs`: panes
//! whose R(θ) and T(θ) sum their internal reflections), and [`Glossy`] (`glossy.rs`): a rough
//! reflector and a rough dielectric, both GGX (Trowbridge–Reitz) microfacet lobes with
//! Smith's height-correlated shadowing, sampled by visible normals (Heitz 2018, as in
//! pbrt-v4's `TrowbridgeReitzDistribution`, `ConductorBxDF` and `DielectricBxDF`), whose
//! maths is in `microfacet.rs`. `fresnel.rs` holds reflection, refraction and the one
//! Fresnel reflectance of dielectrics. [`Bsdf::new`] is the one place that turns a
//! `Material`'s fields into lobes; callers (`trace`, `render`) evaluate and sample
//! through [`Bsdf`] and never name a lobe.
//!
//! Directions are unit vectors pointing *away* from the surface: `wo` towards where the
//! path came from, `wi` where it goes (pbrt's convention). The shading frame is the
//! geometric normal's: there are no shading normals. Transmission is evaluated in its
//! flux form (pbrt's `TransportMode::Importance`, no 1/η² radiance scaling), for the
//! ideal glass and the rough dielectric alike; the factors cancel on any way into and
//! out of a dielectric.

pub mod fresnel;
mod glass;
mod glazing;
mod glossy;
mod lambertian;
pub mod microfacet;
mod mirror;

pub use glass::Glass;
pub use glazing::{Glazing, DEFAULT_GLAZING_IOR};
pub use glossy::Glossy;
pub use lambertian::Lambertian;
pub use microfacet::Frame;
pub use mirror::Mirror;

use crate::error::{Error, Result};
use crate::sampling::uniform;
use glam::DVec3;
use rand_pcg::Pcg32;
use serde::Deserialize;
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
/// Lambertian lobe computes it in a different arithmetic form for each (a different
/// rounding), and every output's bits depend on the form its pass uses.
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
    /// It goes on unbent through thin glazing, as shadow rays do: whether the sources
    /// met along it are counted is the incoming path's.
    pub see_through: bool,
}

impl Continuation {
    /// A ray continuing from a Dirac lobe (mirror, glass, glazing): the sources it meets
    /// are counted along it.
    pub fn specular(dir: DVec3, weight: f64, transmitted: bool) -> Continuation {
        Continuation {
            dir,
            weight,
            transmitted,
            lights_counted: false,
            see_through: false,
        }
    }

    /// The ray going on straight through thin glazing.
    pub fn see_through(dir: DVec3, weight: f64) -> Continuation {
        Continuation {
            see_through: true,
            ..Continuation::specular(dir, weight, true)
        }
    }
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

/// A material: any mix of Lambertian reflection/transmission, ideal specular
/// reflection/refraction and glossy (GGX microfacet) reflection/refraction
/// (the lobes below). The fractions sum to at most 1; the rest is absorbed.
///
/// Its `Debug` print is part of the scene fingerprint (`scene::fingerprint`:
/// checkpoints, indirect_map.bin).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse (Lambertian) reflectance ρ.
    pub reflectance: f64,
    /// Diffuse (Lambertian) transmittance τ.
    pub transmittance: f64,
    /// Ideal mirror reflectance.
    pub specular_reflectance: f64,
    /// Ideal refraction (dielectric of index `ior`, with Fresnel reflection at its face).
    pub specular_transmittance: f64,
    /// Index of refraction of the dielectric lobes (ideal and rough).
    pub ior: f64,
    /// Glossy reflector: a GGX lobe of this albedo weight (Fresnel factor 1).
    pub glossy_reflectance: f64,
    /// Rough dielectric (index `ior`, Fresnel reflection and refraction through GGX
    /// microfacets) of this albedo weight.
    pub glossy_transmittance: f64,
    /// Perceptual roughness of the glossy lobes, in (0, 1]; GGX α = roughness².
    pub roughness: f64,
    /// Thin glazing, the whole surface (no other part): its panes and their index.
    pub glazing: Option<Glazing>,
}

/// A `[materials.KEY]` entry as written.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct MaterialFile {
    #[serde(default)]
    pub reflectance: f64,
    #[serde(default)]
    pub transmittance: f64,
    #[serde(default)]
    pub specular_reflectance: f64,
    #[serde(default)]
    pub specular_transmittance: f64,
    #[serde(default = "default_ior")]
    pub ior: f64,
    #[serde(default)]
    pub glossy_reflectance: f64,
    #[serde(default)]
    pub glossy_transmittance: f64,
    /// Required when a glossy part is set.
    pub roughness: Option<f64>,
    /// Thin glazing: each pane's normal transmittance Tn, outermost first.
    pub glazing: Option<Vec<f64>>,
    /// The same by each pane's transmissivity tn (Radiance's `glass`).
    pub glazing_transmissivity: Option<Vec<f64>>,
    /// The panes' index of refraction (1.52 by default).
    pub glazing_ior: Option<f64>,
}

fn default_ior() -> f64 {
    1.5
}

impl Material {
    /// A Lambertian reflector of reflectance `rho`.
    pub fn lambertian(name: &str, rho: f64) -> Self {
        Material {
            name: name.to_string(),
            reflectance: rho,
            transmittance: 0.0,
            specular_reflectance: 0.0,
            specular_transmittance: 0.0,
            ior: 1.5,
            glossy_reflectance: 0.0,
            glossy_transmittance: 0.0,
            roughness: 1.0,
            glazing: None,
        }
    }

    /// `[materials.KEY]` of file `origin`, validated.
    pub fn from_entry(key: String, m: MaterialFile, origin: &str) -> Result<Material> {
        let at = format!("{origin}: materials.{key}");
        if m.roughness.is_none() && m.glossy_reflectance + m.glossy_transmittance > 0.0 {
            return Err(Error::input(
                format!("{at}.roughness"),
                "required with glossy_reflectance or glossy_transmittance",
            ));
        }
        let material = Material {
            name: key,
            reflectance: m.reflectance,
            transmittance: m.transmittance,
            specular_reflectance: m.specular_reflectance,
            specular_transmittance: m.specular_transmittance,
            ior: m.ior,
            glossy_reflectance: m.glossy_reflectance,
            glossy_transmittance: m.glossy_transmittance,
            roughness: m.roughness.unwrap_or(1.0),
            glazing: glazing(&m, &at)?,
        };
        material.validate(&at)?;
        if material.glazing.is_some() && material.albedo() > 0.0 {
            return Err(Error::input(
                &at,
                "glazing is the whole surface: no reflectance, transmittance, specular or \
                 glossy part beside it",
            ));
        }
        Ok(material)
    }

    /// The albedo weights by key, in the order the BSDF stacks its lobes.
    fn parts(&self) -> [(&'static str, f64); 6] {
        [
            ("reflectance", self.reflectance),
            ("transmittance", self.transmittance),
            ("specular_reflectance", self.specular_reflectance),
            ("specular_transmittance", self.specular_transmittance),
            ("glossy_reflectance", self.glossy_reflectance),
            ("glossy_transmittance", self.glossy_transmittance),
        ]
    }

    /// Total albedo: the fraction of incident flux that is not absorbed (glazing aside:
    /// [`Material::max_albedo`]).
    pub fn albedo(&self) -> f64 {
        // Summed left to right (the bounce cap depends on the bits).
        self.parts().iter().fold(0.0, |sum, (_, x)| sum + x)
    }

    /// The most of the incident flux it keeps at any angle: 1 for glazing (R + T
    /// reaches 1 at grazing incidence), else its albedo.
    pub fn max_albedo(&self) -> f64 {
        if self.glazing.is_some() {
            1.0
        } else {
            self.albedo()
        }
    }

    /// Every fraction finite and ≥ 0, `ior` ≥ 1, roughness in (0, 1], and no energy
    /// created; messages name `at` and the key.
    pub fn validate(&self, at: &str) -> Result<()> {
        for (key, x) in self.parts() {
            if !x.is_finite() || x < 0.0 {
                return Err(Error::input(
                    format!("{at}.{key}"),
                    format!("must be a number ≥ 0, got {x}"),
                ));
            }
        }
        if !self.ior.is_finite() || self.ior < 1.0 {
            return Err(Error::input(
                format!("{at}.ior"),
                format!("must be ≥ 1, got {}", self.ior),
            ));
        }
        if !(self.roughness > 0.0 && self.roughness <= 1.0) {
            return Err(Error::input(
                format!("{at}.roughness"),
                format!("must be in (0, 1], got {}", self.roughness),
            ));
        }
        // A little slack so that fractions written in decimal (0.7 + 0.2 + 0.1) sum to 1.
        let total = self.albedo();
        if total > 1.0 + 1e-9 {
            // Rounded so that 0.8 + 0.4 reads 1.2, not 1.2000000000000002.
            let total = (total * 1e9).round() / 1e9;
            return Err(Error::input(
                at,
                format!("energy-creating material: reflectance + transmittance + specular and glossy parts = {total} > 1"),
            ));
        }
        Ok(())
    }

    /// What `luxtally info` prints about it, one or more lines.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "ρ {} τ {} mirror {} glass {} (ior {})",
            self.reflectance,
            self.transmittance,
            self.specular_reflectance,
            self.specular_transmittance,
            self.ior
        );
        if let Some(g) = &self.glazing {
            let (r, t) = g.reflect_transmit(1.0);
            s += &format!(
                "\n    glazing: {} pane(s) of index {} (transmissivities {:?}): Tn {t:.4}, Rn {r:.4}",
                g.transmissivities.len(),
                g.ior,
                g.transmissivities
            );
        }
        if self.glossy_reflectance + self.glossy_transmittance > 0.0 {
            s += &format!(
                "\n    glossy reflector {} rough glass {} (roughness {}, α {})",
                self.glossy_reflectance,
                self.glossy_transmittance,
                self.roughness,
                self.roughness * self.roughness
            );
        }
        s
    }
}

/// The glazing of a `[materials]` entry: panes by normal transmittance or by
/// transmissivity (not both), each in (0, the clear pane's], index ≥ 1.
fn glazing(m: &MaterialFile, at: &str) -> Result<Option<Glazing>> {
    let ior = m.glazing_ior.unwrap_or(DEFAULT_GLAZING_IOR);
    if !(ior.is_finite() && ior >= 1.0) {
        return Err(Error::input(
            format!("{at}.glazing_ior"),
            format!("must be ≥ 1, got {ior}"),
        ));
    }
    let (key, panes, by_tn) = match (&m.glazing, &m.glazing_transmissivity) {
        (None, None) => return Ok(None),
        (Some(p), None) => ("glazing", p, true),
        (None, Some(p)) => ("glazing_transmissivity", p, false),
        (Some(_), Some(_)) => {
            return Err(Error::input(
                at,
                "give the panes by `glazing` (normal transmittances) or by \
                 `glazing_transmissivity`, not both",
            ))
        }
    };
    if panes.is_empty() {
        return Err(Error::input(
            format!("{at}.{key}"),
            "needs at least one pane",
        ));
    }
    let clear = Glazing::clear_pane_transmittance(ior);
    let mut transmissivities = Vec::new();
    for (i, &x) in panes.iter().enumerate() {
        let t = if by_tn {
            Glazing::transmissivity(x, ior).filter(|_| x.is_finite())
        } else {
            (x > 0.0 && x <= 1.0).then_some(x)
        };
        let Some(t) = t else {
            let what = if by_tn {
                format!("a normal transmittance in (0, {clear:.4}] (a clear pane of index {ior})")
            } else {
                "a transmissivity in (0, 1]".to_string()
            };
            return Err(Error::input(
                format!("{at}.{key}[{i}]"),
                format!("must be {what}, got {x}"),
            ));
        };
        transmissivities.push(t);
    }
    Ok(Some(Glazing {
        transmissivities,
        ior,
    }))
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
        Glazing::add(&mut b, &m.glazing);
        b
    }

    /// Stacks an albedo `weight` on the roulette line; returns its interval's (lower,
    /// upper) thresholds. Summed in `Material`'s order: the thresholds' rounding, and so
    /// every path, depends on that order.
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

    /// Some part of it (a mirror, glass, glazing, a sharp gloss) is only sampled.
    pub fn scatters_unconnected(&self) -> bool {
        self.lobes.iter().any(|(_, l)| !l.connectable())
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
    /// One uniform number chooses the lobe; the Lambertian and ideal lobes draw only
    /// what they need after it, so a material without glossy lobes draws no more.
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

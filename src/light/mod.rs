//! Light sources: one interface, and one file per kind holding everything about it — its
//! `[[lights]]` entry (serde), the entry's validation into a light, and its physics
//! (flux, emission sampling, the light it gives a point, its extent, what the eye sees of
//! it).
//!
//! A source exists at two stages. [`Light`] is the validated source in world coordinates,
//! as the scene holds it; its `Debug` print joins the scene fingerprint
//! (`scene::fingerprint`: checkpoints and indirect_map.bin carry it), so derive it. [`Emitter`] is the same source
//! prepared for the photon and eye passes in the scene's local frame (world = origin +
//! local), with whatever it precomputes.
//!
//! Adding a light kind: a file here with its entry struct (implementing [`LightFile`]),
//! its light ([`Light`]) and emitter ([`Emitter`]), and one line in `registry!`. A light
//! made by a program rather than read from a file only needs the two traits: push it into
//! `Scene::lights` (tests/suite/physics/custom_light.rs).
//!
//! Emitters are called through `dyn`: one call per photon emitted and per piece of
//! direct light, each followed by at least one ray cast, which costs far more.
//!
//! Layering: below `scene` and `trace`; uses `input`, `photometry`, `sampling`.

use crate::error::{Error, Result};
use crate::input;
use crate::photometry::Photometry;
use crate::rng::PhotonStreams;
use glam::DVec3;
use rand_pcg::Pcg32;
use serde::de::DeserializeOwned;
use std::any::Any;
use std::fmt::Debug;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use area::Area;
pub use directional::Directional;
pub use luminaire::{Luminaire, MaintenanceFile};
pub use point::Point;
pub use sky::Sky;
pub use spot::{spot_profile, Spot};
pub use sun::Sun;

/// The kinds of `[[lights]]` entry (their `type`s are the entries' `LightFile::TYPE`):
/// one line per kind, `module::EntryStruct`, declaring the module too.
macro_rules! registry {
    ($($module:ident :: $entry:ident,)*) => {
        $(pub mod $module;)*
        const KINDS: &[Kind] = &[$(Kind::of::<$module::$entry>()),*];
    };
}

registry! {
    point::PointFile,
    spot::SpotFile,
    directional::DirectionalFile,
    area::AreaFile,
    luminaire::LuminaireFile,
    sky::SkyFile,
    sun::SunFile,
}

pub mod distant;
pub mod patches;
pub mod perez;

/// A validated light source, world coordinates.
pub trait Light: Debug + Send + Sync + Any {
    /// Total flux Φ (lm). `sphere` holds the geometry and the receivers: a directional
    /// source emits through its disk.
    fn flux_lm(&self, sphere: &BoundingSphere) -> f64;

    /// The source prepared in the local frame (world = `origin` + local).
    fn emitter(&self, origin: DVec3, sphere: &BoundingSphere) -> Arc<dyn Emitter>;

    /// Shadow rays the eye pass casts towards it per shading point, for memory estimates:
    /// 1 unless it is sampled on the camera's n × n `area_light_samples` grid.
    fn eye_shadow_rays(&self, _area_light_samples: u32) -> f64 {
        1.0
    }

    /// What `luxtally info` prints after the label.
    fn describe(&self) -> String {
        format!("{self:?}")
    }

    /// The photometric file it emits by, if any (summary.json lists each once).
    fn photometry(&self) -> Option<&Arc<Photometry>> {
        None
    }

    /// The maintenance factor its flux carries (luminaires: docs/scene.md).
    fn maintenance_factor(&self) -> f64 {
        1.0
    }

    /// What a sky plot (`output::sky_plot`) shows of a daylight source: a sky's
    /// luminance towards unit world direction `w` and the sun it follows, a sun's
    /// position; None for any other light.
    fn daylight(&self, _w: DVec3) -> Option<Daylight> {
        None
    }
}

/// A daylight source as a sky plot sees it ([`Light::daylight`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Daylight {
    /// A sky's luminance towards the direction asked, cd/m² (its ground's below the
    /// horizon): the function its photons and next events sample. None for a sun.
    pub sky_luminance_cdm2: Option<f64>,
    /// Unit direction towards the sun (world), where it is known and matters: a sun's,
    /// or the one a CIE sky's indicatrix follows.
    pub sun: Option<DVec3>,
}

/// Emission lanes photon by photon: photon k's origin and direction come from
/// `sample(k, stream)`, drawing from `streams.get(k)`, which is left in `rngs[k]`; they
/// are written as f32 lanes `o` and `d`.
#[inline]
pub fn emission_lanes_one_by_one(
    streams: PhotonStreams,
    rngs: &mut [Pcg32],
    o: [&mut [f32]; 3],
    d: [&mut [f32]; 3],
    mut sample: impl FnMut(usize, &mut Pcg32) -> (DVec3, DVec3),
) {
    let ([ox, oy, oz], [dx, dy, dz]) = (o, d);
    for (k, slot) in rngs.iter_mut().enumerate() {
        let mut rng = streams.get(k);
        let (p, w) = sample(k, &mut rng);
        *slot = rng;
        let (p, w) = (p.as_vec3(), w.as_vec3());
        (ox[k], oy[k], oz[k]) = (p.x, p.y, p.z);
        (dx[k], dy[k], dz[k]) = (w.x, w.y, w.z);
    }
}

/// A QMC photon's numbers for its emission ([`Emitter::sample_emission_from`]): the
/// pair that picks its direction ([`crate::rng::QmcDraw::Emission`]) and the pair that
/// places it on the source ([`crate::rng::QmcDraw::Origin`]; (0, 0) unless
/// [`Emitter::origin_from_square`]), each in [0, 1)².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionSquares {
    pub direction: (f64, f64),
    pub origin: (f64, f64),
}

/// A light source prepared for sampling, in the scene's local frame.
pub trait Emitter: Debug + Send + Sync {
    /// The origin and unit direction of one photon, drawn from the source's emission
    /// density (the flux weight is Φ_total / N, shared by every photon).
    fn sample_emission(&self, rng: &mut Pcg32) -> (DVec3, DVec3);

    /// [`Emitter::sample_emission`] for a batch of `rngs.len()` photons: photon k draws
    /// from `streams.get(k)`, which is left in `rngs[k]` after its draws (the photon
    /// goes on drawing from it), and its origin and direction are written as f32 lanes
    /// `o` and `d` (what the ray caster takes). A source whose sampling vectorises seeds
    /// and draws in one loop and maps the numbers in another; by default, photon by
    /// photon.
    fn sample_emission_lanes(
        &self,
        streams: PhotonStreams,
        rngs: &mut [Pcg32],
        o: [&mut [f32]; 3],
        d: [&mut [f32]; 3],
    ) {
        emission_lanes_one_by_one(streams, rngs, o, d, |_, rng| self.sample_emission(rng));
    }

    /// [`Emitter::sample_emission`] with the numbers of [0, 1)² that pick the direction
    /// and the point of the source given (a QMC run's; each uniform, so the density is
    /// the same). Sources whose direction is not a map of two numbers draw it as
    /// `sample_emission` does.
    fn sample_emission_from(&self, _squares: EmissionSquares, rng: &mut Pcg32) -> (DVec3, DVec3) {
        self.sample_emission(rng)
    }

    /// Whether [`Emitter::sample_emission_from`] takes its direction from the numbers
    /// given (else a QMC run emits as an ordinary one, in lanes where it can).
    fn direction_from_square(&self) -> bool {
        false
    }

    /// Whether [`Emitter::sample_emission_from`] reads `squares.origin` (else a QMC run
    /// leaves it at (0, 0) and saves its hashing).
    fn origin_from_square(&self) -> bool {
        false
    }

    /// The light arriving at local point `p` (method.md eqs. 1–2), piece by piece: one
    /// piece for a point-like or directional source; for a source with an extent one per
    /// point of `area_pattern` ([0, 1)² coordinates), each an equal share of the source.
    /// Visibility is the caller's (shadow rays).
    fn incoming(&self, p: DVec3, area_pattern: &[(f64, f64)], each: &mut dyn FnMut(Incoming));

    /// Centre and diagonal (m) of the emitting extent: diagonal 0 for point-like and
    /// directional sources (the eye pass then takes one piece instead of a pattern).
    fn extent(&self) -> (DVec3, f64);

    /// Luminance (cd/m²) the eye sees looking along `dir` from `o`, if the ray meets the
    /// source's emitting side before `t_hit`. Sources are not scene geometry; only those
    /// the camera can see answer.
    fn luminance_seen(&self, _o: DVec3, _dir: DVec3, _t_hit: f64) -> Option<f64> {
        None
    }

    /// The openings (`[[portals]]`, local frame) its photons also come in by: a distant
    /// source's. Its photons whose first segment crosses one leave the receivers to
    /// its [`Emitter::portal_photon`]s (the photon pass; docs/daylight.md, *Photons
    /// through portals*).
    fn portals(&self) -> &[distant::Portal] {
        &[]
    }

    /// A photon of this source through its portals, drawn from `rng`, or None.
    fn portal_photon(&self, _rng: &mut Pcg32) -> Option<distant::PortalPhoton> {
        None
    }
}

/// A `[[lights]]` entry of one `type`: its keys (serde, `deny_unknown_fields`) and their
/// validation.
pub trait LightFile: DeserializeOwned {
    /// Its `type` in the scene file.
    const TYPE: &'static str;

    /// Validates the entry at `at` (`file.toml: lights[i]`, for messages) into its lights,
    /// each with its label: `label` itself for one light.
    fn into_lights(self, label: &str, at: &str, cx: &mut LoadContext) -> Result<Vec<Labelled>>;
}

/// A light with its label (`lights[i]` as in the scene file).
pub type Labelled = (String, Arc<dyn Light>);

/// The one light of an entry.
pub fn single(label: &str, light: impl Light) -> Result<Vec<Labelled>> {
    Ok(vec![(label.to_string(), Arc::new(light))])
}

/// What entries may need from the loader: the scene file's directory, and the
/// photometric files loaded so far (luminaires of one file share it).
pub struct LoadContext<'a> {
    pub base_dir: &'a Path,
    photometry: Vec<(PathBuf, Arc<Photometry>)>,
    /// The scene's `maintenance_factor`: luminaires without their own take it.
    pub maintenance_factor: f64,
    /// The scene's `[[portals]]` (world): skies aim their next events at them.
    pub portals: Vec<distant::Portal>,
}

impl<'a> LoadContext<'a> {
    pub fn new(base_dir: &'a Path) -> Self {
        LoadContext {
            base_dir,
            photometry: Vec::new(),
            maintenance_factor: 1.0,
            portals: Vec::new(),
        }
    }

    /// The photometric file at `file` (relative to the scene file), loaded once.
    pub fn photometry(&mut self, file: &str) -> Result<Arc<Photometry>> {
        let path = self.base_dir.join(file);
        if let Some((_, p)) = self.photometry.iter().find(|(q, _)| *q == path) {
            return Ok(p.clone());
        }
        let p = Arc::new(crate::photometry::load(&path)?);
        self.photometry.push((path, p.clone()));
        Ok(p)
    }
}

/// One kind of the registry.
struct Kind {
    name: &'static str,
    fields: input::Fields,
    load: fn(toml::Value, &str, &str, &mut LoadContext) -> Result<Vec<Labelled>>,
}

impl Kind {
    const fn of<T: LightFile>() -> Kind {
        Kind {
            name: T::TYPE,
            fields: input::fields_of::<T>,
            load: load_as::<T>,
        }
    }
}

fn load_as<T: LightFile>(
    value: toml::Value,
    label: &str,
    origin: &str,
    cx: &mut LoadContext,
) -> Result<Vec<Labelled>> {
    let entry: T = input::entry(value, origin, label)?;
    entry.into_lights(label, &format!("{origin}: {label}"), cx)
}

/// Loads the `[[lights]]` entry `label` (`lights[i]`) of scene file `origin` by its
/// `type`. Keys of another type are reported as not applying to this one.
pub fn load_entry(
    value: toml::Value,
    label: &str,
    origin: &str,
    cx: &mut LoadContext,
) -> Result<Vec<Labelled>> {
    let at = format!("{origin}: {label}");
    let names = || input::or_list(KINDS.iter().map(|k| format!("\"{}\"", k.name)));
    let toml::Value::Table(mut table) = value else {
        return Err(Error::input(at, "must be a table"));
    };
    let kind = match table.remove("type") {
        Some(toml::Value::String(s)) => s,
        Some(_) => return Err(Error::input(format!("{at}.type"), "must be a string")),
        None => {
            return Err(Error::input(
                format!("{at}.type"),
                format!("missing (expected {})", names()),
            ))
        }
    };
    let Some(k) = KINDS.iter().find(|k| k.name == kind) else {
        return Err(Error::input(
            format!("{at}.type"),
            format!("unknown light type `{kind}` (expected {})", names()),
        ));
    };
    let others: Vec<&[&str]> = KINDS.iter().map(|o| (o.fields)()).collect();
    let what = format!("type \"{kind}\" lights");
    input::check_keys(&table, (k.fields)(), &others, &at, &what)?;
    (k.load)(toml::Value::Table(table), label, origin, cx)
}

/// A sphere holding the scene's geometry and receivers, world coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    pub center: DVec3,
    pub radius: f64,
}

/// Light from one source arriving at a point, as one point-like piece of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incoming {
    /// From the point towards the piece: the vector to it, or for a directional source
    /// the unit direction towards the source.
    pub to_source: DVec3,
    /// Distance to the piece; `f64::INFINITY` for a directional source.
    pub distance: f64,
    /// Illuminance the piece gives on a plane facing it (lx): I/d² for point and spot
    /// sources, E⊥ for directional ones, L·Ω/n for one of n solid-angle shares of an
    /// area source (L·cos θ_s·ΔA/d² for a patch of one, when it is sampled by area).
    pub normal_lx: f64,
}

impl Incoming {
    /// Unit direction from the point towards the piece.
    #[inline]
    pub fn direction(&self) -> DVec3 {
        if self.distance.is_finite() {
            self.to_source / self.distance
        } else {
            self.to_source
        }
    }
}

/// The piece of intensity `intensity_cd` at `q` seen from `p` (inverse square law, eq. 1),
/// unless it is dark or at `p` itself.
#[inline]
pub fn from_point(p: DVec3, q: DVec3, intensity_cd: f64, each: &mut dyn FnMut(Incoming)) {
    let to_source = q - p;
    let distance = to_source.length();
    if intensity_cd > 0.0 && distance > 0.0 {
        each(Incoming {
            to_source,
            distance,
            normal_lx: intensity_cd / (distance * distance),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_has_its_own_type_and_no_type_key() {
        for (i, k) in KINDS.iter().enumerate() {
            assert!(KINDS[..i].iter().all(|o| o.name != k.name), "{}", k.name);
            assert!(!(k.fields)().is_empty() && !(k.fields)().contains(&"type"));
        }
    }
}

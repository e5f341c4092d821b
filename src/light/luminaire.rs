//! Luminaires from photometric files (docs/photometry.md): `type = "luminaire"`, one
//! light per position, emitting the file's candela distribution from its opening.

use super::{
    from_point, BoundingSphere, EmissionSquares, Emitter, Incoming, Labelled, Light, LightFile,
    LoadContext,
};
use crate::error::{Error, Result};
use crate::input::{amount, direction, required, vec3, Coords};
use crate::photometry::Photometry;
use glam::{DMat3, DVec3};
use rand_pcg::Pcg32;
use serde::Deserialize;
use std::sync::Arc;

/// The `[[lights]]` entry: the file, where (one `position` or many `positions`), how
/// turned, how scaled.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct LuminaireFile {
    pub file: Option<String>,
    pub position: Option<Coords>,
    pub positions: Option<Vec<Coords>>,
    pub aim: Option<[f64; 3]>,
    pub rotate_deg: Option<f64>,
    pub multiplier: Option<f64>,
    pub flux_lm: Option<f64>,
    /// CIE 97 maintenance factor (default: the scene's `maintenance_factor`, else 1).
    pub maintenance_factor: Option<MaintenanceFile>,
}

impl LightFile for LuminaireFile {
    const TYPE: &'static str = "luminaire";

    /// One light per position (`position`, or each of `positions`, labelled
    /// `lights[i].positions[k]`).
    fn into_lights(self, label: &str, at: &str, cx: &mut LoadContext) -> Result<Vec<Labelled>> {
        let what = "type \"luminaire\" lights";
        let file = required(self.file.as_ref(), at, "file", what)?;
        let photometry = cx.photometry(file)?;
        let positions: Vec<(String, DVec3)> = match (&self.position, &self.positions) {
            (Some(p), None) => vec![(label.to_string(), vec3(*p))],
            (None, Some(ps)) if !ps.is_empty() => ps
                .iter()
                .enumerate()
                .map(|(k, p)| (format!("{label}.positions[{k}]"), vec3(*p)))
                .collect(),
            (None, Some(_)) => return Err(Error::input(format!("{at}.positions"), "is empty")),
            _ => {
                return Err(Error::input(
                    at,
                    "give exactly one of `position` and `positions`",
                ))
            }
        };
        let aim = direction(self.aim.unwrap_or([0.0, 0.0, -1.0]), at, "aim")?;
        let multiplier = amount(self.multiplier.unwrap_or(1.0), at, "multiplier")?;
        let file_flux = photometry.flux_lm();
        let rescale = match self.flux_lm {
            None => 1.0,
            Some(f) if file_flux > 0.0 => amount(f, at, "flux_lm")? / file_flux,
            Some(_) => {
                return Err(Error::input(
                    format!("{at}.flux_lm"),
                    format!("`{file}` emits no flux: it cannot be rescaled"),
                ))
            }
        };
        // The table holds the lamp's output at the photometered position (tilt 0); a
        // luminaire tilted from it (aim away from straight down) gets the file's tilt
        // factor at that angle relative to it.
        let tilt = match &photometry.tilt {
            Some(t) if t.factor(0.0) > 0.0 => {
                t.factor(libm::acos(aim.dot(-DVec3::Z).clamp(-1.0, 1.0)).to_degrees()) / t.factor(0.0)
            }
            _ => 1.0,
        };
        let maintenance_factor = match &self.maintenance_factor {
            Some(m) => m.factor(&format!("{at}.maintenance_factor"))?,
            None => cx.maintenance_factor,
        };
        let frame = Luminaire::frame(aim, self.rotate_deg.unwrap_or(0.0));
        Ok(positions
            .into_iter()
            .map(|(label, position)| {
                let light: Arc<dyn Light> = Arc::new(Luminaire {
                    photometry: photometry.clone(),
                    position,
                    frame,
                    scale: multiplier * rescale * tilt * maintenance_factor,
                    maintenance_factor,
                });
                (label, light)
            })
            .collect())
    }
}

/// A luminaire placed in the scene: its photometry (shared by every luminaire of the
/// same file), where it is and how it is turned.
#[derive(Clone, PartialEq)]
pub struct Luminaire {
    pub photometry: Arc<Photometry>,
    /// World position of the centre of its luminous opening.
    pub position: DVec3,
    /// Luminaire frame (x = C0, y = C90, z = up, nadir −z) → world.
    pub frame: DMat3,
    /// Factor on the file's intensities: `multiplier`, times the `flux_lm` rescaling,
    /// times the file's tilt factor at the luminaire's tilt (relative to tilt 0), times
    /// the maintenance factor.
    pub scale: f64,
    /// The maintenance factor in `scale` (it prints through `scale` alone).
    pub maintenance_factor: f64,
}

/// `maintenance_factor = 0.8`, or its CIE 97:2005 parts `{llmf, lsf, lmf, rsmf}` (each
/// 1 unless given), whose product it is.
#[derive(serde::Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(untagged, expecting = "a number or a table of llmf, lsf, lmf, rsmf")]
pub enum MaintenanceFile {
    Factor(f64),
    Parts {
        llmf: Option<f64>,
        lsf: Option<f64>,
        lmf: Option<f64>,
        rsmf: Option<f64>,
    },
}

impl MaintenanceFile {
    /// The factor, each part in (0, 1]; `at` names the key in messages.
    pub fn factor(&self, at: &str) -> Result<f64> {
        let parts = match *self {
            MaintenanceFile::Factor(f) => vec![("", f)],
            MaintenanceFile::Parts {
                llmf,
                lsf,
                lmf,
                rsmf,
            } => [(".llmf", llmf), (".lsf", lsf), (".lmf", lmf), (".rsmf", rsmf)]
                .into_iter()
                .map(|(k, v)| (k, v.unwrap_or(1.0)))
                .collect(),
        };
        let mut product = 1.0;
        for (key, f) in parts {
            if !(f > 0.0 && f <= 1.0) {
                return Err(Error::input(
                    format!("{at}{key}"),
                    format!("must be in (0, 1] (a maintenance factor), got {f}"),
                ));
            }
            product *= f;
        }
        Ok(product)
    }
}

/// Printed as `Luminaire(Luminaire { .. })`: the print is part of the scene fingerprint
/// (`scene::fingerprint`) that indirect_map.bin files, and their golden hashes, carry.
impl std::fmt::Debug for Luminaire {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Luminaire(")?;
        f.debug_struct("Luminaire")
            .field("photometry", &self.photometry)
            .field("position", &self.position)
            .field("frame", &self.frame)
            .field("scale", &self.scale)
            .finish()?;
        f.write_str(")")
    }
}

impl Luminaire {
    /// The frame that turns the nadir (−z) to `aim` (unit) by the shortest rotation (a
    /// half turn about x when `aim` is straight up), then turns C0 about `aim` by
    /// `rotate_deg` (counter-clockwise seen from where the light goes).
    pub fn frame(aim: DVec3, rotate_deg: f64) -> DMat3 {
        let nadir = -DVec3::Z;
        let turn = if aim.dot(nadir) < -1.0 + 1e-12 {
            DMat3::from_rotation_x(std::f64::consts::PI)
        } else {
            DMat3::from_quat(glam::DQuat::from_rotation_arc(nadir, aim))
        };
        DMat3::from_axis_angle(-aim, rotate_deg.to_radians()) * turn
    }

    /// Flux of the luminaire as placed, lm.
    pub fn flux_lm(&self) -> f64 {
        self.photometry.flux_lm() * self.scale
    }
}

impl Light for Luminaire {
    fn flux_lm(&self, _: &BoundingSphere) -> f64 {
        Luminaire::flux_lm(self)
    }

    fn emitter(&self, origin: DVec3, _: &BoundingSphere) -> Arc<dyn Emitter> {
        Arc::new(LuminaireEmitter {
            position: self.position - origin,
            frame: self.frame,
            photometry: self.photometry.clone(),
            scale: self.scale,
        })
    }

    fn describe(&self) -> String {
        let p = &self.photometry;
        let peak = p.peak();
        format!(
            "luminaire {} at {:.3?}: {:.1} lm (file {:.1} lm × {}), light output ratio {}, peak {:.1} cd at C {:.1}° γ {:.1}°, {} symmetry, opening {}",
            p.file,
            self.position.to_array(),
            self.flux_lm(),
            p.flux_lm(),
            self.scale,
            p.light_output_ratio()
                .map_or("– (absolute photometry)".into(), |r| format!("{r:.3}")),
            peak.intensity_cd * self.scale,
            peak.c_deg,
            peak.gamma_deg,
            p.symmetry.describe(),
            p.opening.describe()
        )
    }

    fn photometry(&self) -> Option<&Arc<Photometry>> {
        Some(&self.photometry)
    }

    fn maintenance_factor(&self) -> f64 {
        self.maintenance_factor
    }
}

/// Photons leave its opening (centred on `position`, luminaire frame `frame`) in
/// directions drawn from its photometry.
#[derive(Clone, Debug)]
struct LuminaireEmitter {
    position: DVec3,
    frame: DMat3,
    photometry: Arc<Photometry>,
    scale: f64,
}

impl Emitter for LuminaireEmitter {
    #[inline]
    fn sample_emission(&self, rng: &mut Pcg32) -> (DVec3, DVec3) {
        let p = self.position + self.frame * self.photometry.opening.sample_point_m(rng);
        (p, self.frame * self.photometry.sample_direction(rng))
    }

    /// `squares.direction` picks the photometric grid's cell and the first proposal in
    /// it, `squares.origin` the point of the opening.
    fn direction_from_square(&self) -> bool {
        true
    }

    fn origin_from_square(&self) -> bool {
        true
    }

    fn sample_emission_from(&self, squares: EmissionSquares, rng: &mut Pcg32) -> (DVec3, DVec3) {
        let (a, b) = squares.origin;
        let p = self.position + self.frame * self.photometry.opening.point_at(a, b);
        let w = self.photometry.sample_direction_from(squares.direction, rng);
        (p, self.frame * w)
    }

    /// Every point of the opening emits the file's distribution, I/A per unit area (as
    /// the photons leave it): one equal share of the opening per piece.
    fn incoming(&self, p: DVec3, area_pattern: &[(f64, f64)], each: &mut dyn FnMut(Incoming)) {
        if !(self.scale > 0.0) {
            return;
        }
        let share = self.scale / area_pattern.len().max(1) as f64;
        for &(a, b) in area_pattern {
            let q = self.position + self.frame * self.photometry.opening.point_at(a, b);
            let towards_p = self.frame.transpose() * (p - q);
            if towards_p != DVec3::ZERO {
                from_point(
                    p,
                    q,
                    share * self.photometry.intensity_toward_cd(towards_p),
                    each,
                );
            }
        }
    }

    fn extent(&self) -> (DVec3, f64) {
        (self.position, self.photometry.opening.diagonal_m())
    }
}

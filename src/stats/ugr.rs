//! Unified Glare Rating (CIE 117:1995) of the scene's observers (docs/ugr.md):
//! UGR = 8·log10[(0.25/Lb)·Σ Lᵢ²ωᵢ/pᵢ²], Lb = E_ind/π. Lᵢ, ωᵢ and pᵢ come exactly from
//! the luminaires' photometry and geometry; E_ind, the indirect vertical illuminance at
//! the eye, from the observer's hidden receiver (its photons' part).

use crate::accel::{RayBatch, RayCaster};
use crate::error::{Error, Result};
use crate::light::Luminaire;
use crate::scene::{Observer, Scene, Subject};
use crate::stats::ugr_table::projected_area_m2;
use crate::tally::{CellSums, Counts, Tallies};
use glam::DVec3;

/// CIE 117's range of a source's solid angle in which UGR is valid, sr.
pub const OMEGA_RANGE_SR: (f64, f64) = (3e-4, 0.1);

/// The CIE position-index table's field (Table 4.1): H/R ≤ 1.9, T/R ≤ 3.
pub const MAX_H_OVER_R: f64 = 1.9;
pub const MAX_T_OVER_R: f64 = 3.0;

/// The Guth position index of a source in unit direction `sd` from the eye, for the
/// line of sight `vd` and view up `vu` (unit): the Luckiesh–Guth formula exactly as
/// Radiance's `src/util/glarendx.c` `posindex` computes it (NREL/Radiance, commit
/// 2fcca99): −1 behind the eye (sd·vd ≤ 0), 1 on the line of sight, else
/// exp(σ·((35.2 − 0.31889τ − 1.22·e^(−0.22222τ))·10⁻³ + σ·(21 + 0.26667τ − 0.002963τ²)·10⁻⁵)),
/// σ = angle from the line of sight and τ = acos(|sd·vu|/sin σ), both in degrees.
pub fn position_index(sd: DVec3, vd: DVec3, vu: DVec3) -> f64 {
    let d = sd.dot(vd);
    if d <= 0.0 {
        return -1.0;
    }
    if d >= 1.0 - 1e-9 {
        return 1.0;
    }
    let sigma = libm::acos(d).to_degrees();
    let c = (sd.dot(vu) / libm::sqrt(1.0 - d * d)).abs();
    let tau = libm::acos(c.min(1.0)).to_degrees();
    libm::exp(
        sigma
            * ((35.2 - tau * 0.31889 - 1.22 * libm::exp(-0.22222 * tau)) * 1e-3
                + sigma * (21.0 + tau * (0.26667 + tau * -0.002963)) * 1e-5),
    )
}

/// UGR from the sum Σ L²ω/p² and E_ind (lx); None unless both are positive.
pub fn ugr(sum: f64, e_ind_lx: f64) -> Option<f64> {
    let lb = e_ind_lx / std::f64::consts::PI;
    (sum > 0.0 && lb > 0.0 && lb.is_finite()).then(|| 8.0 * libm::log10(0.25 / lb * sum))
}

/// Whether a luminaire counts in an observer's sum, and why not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Seen {
    Counted,
    /// Its centre lies behind the eye's frontal plane.
    Behind,
    /// Its centre lies below the line of sight (H < 0).
    BelowLineOfSight,
    /// Beyond CIE Table 4.1's field (H/R > 1.9 or T/R > 3).
    OutsideField,
    /// Its opening faces away from the eye (or it has no luminous area).
    FacesAway,
    NoLuminousArea,
    Occluded,
}

impl Seen {
    pub fn as_str(self) -> &'static str {
        match self {
            Seen::Counted => "counted",
            Seen::Behind => "behind the eye",
            Seen::BelowLineOfSight => "below the line of sight",
            Seen::OutsideField => "outside the position index's field (H/R > 1.9 or T/R > 3)",
            Seen::FacesAway => "opening faces away from the eye",
            Seen::NoLuminousArea => "no luminous area (a point opening)",
            Seen::Occluded => "occluded",
        }
    }
}

/// One luminaire as an observer sees it (before occlusion).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Term {
    /// Luminance towards the eye, cd/m² (0 unless the opening faces the eye).
    pub luminance_cdm2: f64,
    /// Solid angle of the projected opening, A_proj/d², sr.
    pub omega_sr: f64,
    /// Guth position index (glarendx's; −1 behind the eye).
    pub position_index: f64,
    /// Geometry: distance along the line of sight R, height above it H, lateral T, m.
    pub r_h_t_m: [f64; 3],
    pub seen: Seen,
    /// The fraction of the opening the eye sees ([`visibility`]); ω is of that part.
    pub visible_fraction: f64,
}

impl Term {
    /// Lᵢ²ωᵢ/pᵢ² if it counts, else 0.
    pub fn contribution(&self) -> f64 {
        if self.seen == Seen::Counted {
            self.luminance_cdm2 * self.luminance_cdm2 * self.omega_sr
                / (self.position_index * self.position_index)
        } else {
            0.0
        }
    }
}

/// The observer's frame: line of sight, right (v × up) and up' (right × v); world up
/// +z (a vertical line of sight takes x as its right).
pub fn view_frame(look: DVec3) -> (DVec3, DVec3, DVec3) {
    let right = look
        .cross(DVec3::Z)
        .try_normalize()
        .unwrap_or_else(|| look.any_orthonormal_vector());
    (look, right, right.cross(look))
}

/// Luminaire `lum` as seen from `eye` looking along `look` (unit), unoccluded: L =
/// I·scale/A_proj with A_proj the luminous area seen from the eye (the opening, facing
/// the luminaire's −z, times cos θ, plus its luminous sides: the CIE 190 table's
/// [`projected_area_m2`]), ω = A_proj/d², p by [`position_index`] with view up +z.
pub fn term(lum: &Luminaire, eye: DVec3, look: DVec3) -> Term {
    let to_lum = lum.position - eye;
    let d = to_lum.length();
    let s = to_lum / d;
    let (v, right, up) = view_frame(look);
    let r_h_t = [to_lum.dot(v), to_lum.dot(up), to_lum.dot(right).abs()];
    let p = position_index(s, look, DVec3::Z);
    let towards_eye = lum.frame.transpose() * (-s);
    let cos = -towards_eye.z;
    let area = lum.photometry.opening.area_m2();
    let a_proj = projected_area_m2(lum.photometry.opening, lum.photometry.height_m, towards_eye);
    let (l, omega) = if a_proj > 0.0 {
        let i = lum.photometry.intensity_toward_cd(towards_eye) * lum.scale;
        (i / a_proj, a_proj / (d * d))
    } else {
        (0.0, 0.0)
    };
    let seen = if r_h_t[0] <= 0.0 || p <= 0.0 {
        Seen::Behind
    } else if r_h_t[1] < 0.0 {
        Seen::BelowLineOfSight
    } else if r_h_t[1] / r_h_t[0] > MAX_H_OVER_R || r_h_t[2] / r_h_t[0] > MAX_T_OVER_R {
        Seen::OutsideField
    } else if !(area > 0.0) {
        Seen::NoLuminousArea
    } else if !(cos > 0.0 && a_proj > 0.0) {
        Seen::FacesAway
    } else {
        Seen::Counted
    };
    Term {
        luminance_cdm2: l,
        omega_sr: omega,
        position_index: p,
        r_h_t_m: r_h_t,
        seen,
        visible_fraction: 1.0,
    }
}

/// The scene's luminaires: (label, luminaire), in light order.
pub fn luminaires(scene: &Scene) -> Vec<(&str, &Luminaire)> {
    scene
        .lights
        .iter()
        .filter_map(|l| l.get::<Luminaire>().map(|lum| (l.label.as_str(), lum)))
        .collect()
}

/// Points per side of the grid over a luminaire's opening that [`visibility`] casts
/// shadow rays to: 8 × 8 resolves the visible fraction to 1/64.
pub const VISIBILITY_GRID: usize = 8;

/// Per observer, per luminaire of [`luminaires`]: the fraction of its opening the eye
/// sees, from shadow rays to the centres of a [`VISIBILITY_GRID`]² grid over the
/// opening (equal-area cells; one ray to the centre of a point opening), cast in the
/// scene's local frame and stopping 1 mm short of either end. A partly hidden
/// luminaire keeps its luminance and counts with its visible solid angle.
pub fn visibility(scene: &Scene, caster: &dyn RayCaster) -> Vec<Vec<f64>> {
    let lums = luminaires(scene);
    if scene.observers.is_empty() || lums.is_empty() {
        return vec![Vec::new(); scene.observers.len()];
    }
    let targets: Vec<Vec<DVec3>> = (lums.iter()).map(|(_, lum)| opening_points(lum)).collect();
    let origin = scene.geometry.origin;
    let mut rays = RayBatch::with_capacity(scene.observers.len() * lums.len() * 64);
    for o in &scene.observers {
        for target in targets.iter().flatten() {
            let to = *target - o.position;
            let eps = (1e-3 / to.length()).min(0.25) as f32;
            rays.push(
                (o.position - origin).as_vec3().into(),
                to.as_vec3().into(),
                eps,
                1.0 - eps,
            );
        }
    }
    let mut occluded = Vec::new();
    caster.occluded(&rays, &mut occluded);
    let mut blocked = occluded.into_iter();
    (scene.observers.iter())
        .map(|_| {
            (targets.iter())
                .map(|t| {
                    let seen = blocked.by_ref().take(t.len()).filter(|&b| !b).count();
                    seen as f64 / t.len() as f64
                })
                .collect()
        })
        .collect()
}

/// World points at the centres of the equal-area cells of a luminaire's opening.
fn opening_points(lum: &Luminaire) -> Vec<DVec3> {
    let opening = lum.photometry.opening;
    if !(opening.area_m2() > 0.0) {
        return vec![lum.position];
    }
    let n = VISIBILITY_GRID;
    let at = |k: usize| (k as f64 + 0.5) / n as f64;
    (0..n * n)
        .map(|k| lum.position + lum.frame * opening.point_at(at(k % n), at(k / n)))
        .collect()
}

/// Observer `o`'s terms, one per luminaire of [`luminaires`], with `visible` (per
/// luminaire, from [`visibility`]; absent: fully visible) applied.
pub fn observer_terms(scene: &Scene, o: &Observer, visible: &[f64]) -> Vec<Term> {
    luminaires(scene)
        .iter()
        .enumerate()
        .map(|(j, (_, lum))| {
            let mut term = term(lum, o.position, o.look);
            let fraction = visible.get(j).copied().unwrap_or(1.0);
            term.visible_fraction = fraction;
            term.omega_sr *= fraction;
            if !(fraction > 0.0) && term.seen == Seen::Counted {
                term.seen = Seen::Occluded;
            }
            term
        })
        .collect()
}

/// Refuses a UGR requirement on an observer who sees (counts) a luminaire whose solid
/// angle lies outside CIE 117's range: UGR is not defined for it there (CIE 147's
/// corrections are not applied), so no verdict could ever be reached. `visible` as
/// [`visibility`] gives it. Observers without such a requirement are rated and marked
/// not valid instead.
pub fn refuse_unratable_requirements(scene: &Scene, visible: &[Vec<f64>]) -> Result<()> {
    let lums = luminaires(scene);
    let (lo, hi) = OMEGA_RANGE_SR;
    for req in &scene.requirements {
        let Subject::Observer(k) = req.subject else {
            continue;
        };
        let o = &scene.observers[k];
        let seen = visible.get(k).map_or(&[][..], Vec::as_slice);
        let terms = observer_terms(scene, o, seen);
        let outside = terms
            .iter()
            .zip(&lums)
            .find(|(t, _)| t.seen == Seen::Counted && !(t.omega_sr > lo && t.omega_sr < hi));
        if let Some((t, (label, _))) = outside {
            return Err(Error::input(
                format!("{}: requirement `{}`", scene.path.display(), req.name),
                format!(
                    "observer `{}` sees luminaire {label} under ω = {:.3e} sr, outside CIE \
                     117's {lo} < ω < {hi} sr: its UGR is not defined there, so it cannot \
                     be judged (move the observer, or drop the requirement to have the \
                     rating reported as not valid)",
                    o.name, t.omega_sr
                ),
            ));
        }
    }
    Ok(())
}

/// Observer `o`'s E_ind and its σ (lx): its hidden receiver's photon part.
pub fn e_ind(scene: &Scene, tallies: &Tallies, o: &Observer) -> (f64, f64) {
    let cells = tallies.receiver_cells(&scene.receivers, o.receiver);
    cells
        .first()
        .map_or((0.0, f64::NAN), |c| indirect_part(c, tallies.counts()))
}

/// The indirect (photons') part of a next-event cell and its σ, in the receiver's unit:
/// what the cell holds besides its sampled direct light.
pub fn indirect_part(c: &CellSums, counts: Counts) -> (f64, f64) {
    if counts.dark || counts.photons == 0 {
        return (0.0, 0.0);
    }
    let (value, var) = c.photon_moments(counts).mean_and_variance();
    let known = var >= 0.0 && counts.photon_variance_known();
    let sigma = if known { var.sqrt() } else { f64::NAN };
    (value * counts.unit, sigma * counts.unit)
}

/// One observer's rating.
#[derive(Clone, Debug, PartialEq)]
pub struct Rating {
    pub terms: Vec<Term>,
    pub sum: f64,
    pub e_ind_lx: f64,
    pub e_ind_sigma_lx: f64,
    pub ugr: Option<f64>,
    /// (8/ln 10)·σ(E_ind)/E_ind.
    pub ugr_sigma: Option<f64>,
    /// Why UGR is not valid here (None when it is).
    pub invalid: Option<String>,
}

/// An observer's rating from its terms (occlusion applied by the caller) and E_ind
/// with its σ (lx).
pub fn rate(terms: Vec<Term>, e_ind: (f64, f64)) -> Rating {
    let sum: f64 = terms.iter().map(Term::contribution).sum();
    let (e, e_sigma) = e_ind;
    let value = ugr(sum, e);
    let ugr_sigma = value.map(|_| 8.0 / std::f64::consts::LN_10 * e_sigma / e);
    let (lo, hi) = OMEGA_RANGE_SR;
    let outside = terms
        .iter()
        .filter(|t| t.seen == Seen::Counted && !(t.omega_sr > lo && t.omega_sr < hi))
        .count();
    let invalid = if !(e > 0.0) {
        Some("no indirect light at the eye (E_ind ≤ 0): UGR is undefined".to_string())
    } else if !(sum > 0.0) {
        Some("no luminaire counts (none in view, lit, unoccluded)".to_string())
    } else if outside > 0 {
        Some(format!(
            "{outside} counted luminaire(s) subtend a solid angle outside CIE 117's \
             {lo} < ω < {hi} sr"
        ))
    } else if terms.iter().any(|t| t.seen == Seen::NoLuminousArea) {
        Some("a luminaire without luminous area (point opening) cannot be rated".to_string())
    } else {
        None
    };
    Rating {
        terms,
        sum,
        e_ind_lx: e,
        e_ind_sigma_lx: e_sigma,
        ugr: value,
        ugr_sigma,
        invalid,
    }
}

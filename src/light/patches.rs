//! Sky subdivisions (docs/daylight.md, *Sky patches*): Reinhart's MF:n patches, of
//! which MF 1 is Tregenza's 145, as Radiance's reinhartb.cal and gendaymtx number them:
//! rows of width α = 90°/(7·MF + 0.5) from the horizon up, each of Tregenza's seven
//! bands (30, 30, 24, 24, 18, 12, 6 patches) split into MF rows of MF times as many
//! patches, and a zenith cap of radius α/2; in each row, patch 0 is centred due north
//! and the numbering runs towards east. Indices here start at 0 with the first sky
//! patch (Radiance's bin 1; its bin 0 is the ground).

use super::distant::{DistantEmitter, DistantTable, Portal, Region};
use super::sun::direction_rad;
use super::{BoundingSphere, Emitter, Light};
use crate::error::{Error, Result};
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;

/// Tregenza's patches per 12° band, horizon up (the zenith cap apart).
const TREGENZA_BANDS: [u32; 7] = [30, 30, 24, 24, 18, 12, 6];

/// The largest MF accepted (MF 6 is the finest Radiance's tools use: 5185 patches).
pub const MAX_MF: u32 = 12;

/// One row of patches: altitudes (radians) and how many patches share it.
#[derive(Clone, Copy, Debug)]
struct Row {
    low: f64,
    high: f64,
    patches: u32,
    first: u32,
}

/// The patches of Reinhart MF:n.
#[derive(Clone, Debug)]
pub struct SkyPatches {
    pub mf: u32,
    rows: Vec<Row>,
}

/// One patch: where it lies and its solid angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    /// Altitudes (radians) of its lower and upper edge.
    pub altitude: [f64; 2],
    /// Azimuths (radians, from north towards east) of its edges; the cap spans 0–2π.
    pub azimuth: [f64; 2],
    pub solid_angle_sr: f64,
}

impl Patch {
    /// The direction at its middle in altitude and azimuth (the zenith for the cap).
    pub fn centre(&self) -> DVec3 {
        if self.altitude[1] >= FRAC_PI_2 && self.azimuth[1] - self.azimuth[0] >= TAU {
            return DVec3::Z;
        }
        direction_rad(
            0.5 * (self.altitude[0] + self.altitude[1]),
            0.5 * (self.azimuth[0] + self.azimuth[1]),
        )
    }
}

impl SkyPatches {
    /// Reinhart MF:`mf` (1 = Tregenza), `at` naming the key for errors.
    pub fn reinhart(mf: u32, at: &str) -> Result<SkyPatches> {
        if !(1..=MAX_MF).contains(&mf) {
            return Err(Error::input(
                at,
                format!("the Reinhart subdivision MF must be 1…{MAX_MF}, got {mf}"),
            ));
        }
        let alpha = FRAC_PI_2 / (7.0 * mf as f64 + 0.5);
        let mut rows = Vec::new();
        let mut first = 0;
        for (band, &n) in TREGENZA_BANDS.iter().enumerate() {
            for r in 0..mf {
                let k = band as u32 * mf + r;
                let patches = n * mf;
                rows.push(Row {
                    low: k as f64 * alpha,
                    high: (k + 1) as f64 * alpha,
                    patches,
                    first,
                });
                first += patches;
            }
        }
        rows.push(Row {
            low: FRAC_PI_2 - 0.5 * alpha,
            high: FRAC_PI_2,
            patches: 1,
            first,
        });
        Ok(SkyPatches { mf, rows })
    }

    /// The number of sky patches, 144·MF² + 1.
    pub fn len(&self) -> usize {
        let last = self.rows[self.rows.len() - 1];
        (last.first + last.patches) as usize
    }

    pub fn is_empty(&self) -> bool {
        false
    }

    /// Patch `k` (0 ≤ k < len).
    pub fn patch(&self, k: usize) -> Patch {
        let row = self.rows[self
            .rows
            .partition_point(|r| (r.first + r.patches) as usize <= k)];
        let width = TAU / row.patches as f64;
        let j = (k - row.first as usize) as f64;
        let azimuth = if row.patches == 1 {
            [0.0, TAU]
        } else {
            [(j - 0.5) * width, (j + 0.5) * width]
        };
        Patch {
            altitude: [row.low, row.high],
            azimuth,
            solid_angle_sr: width * (libm::sin(row.high) - libm::sin(row.low)),
        }
    }

    /// The patch unit `w` falls in, None below the horizon (the ground).
    pub fn index(&self, w: DVec3) -> Option<usize> {
        if w.z < 0.0 {
            return None;
        }
        let altitude = libm::asin(w.z.min(1.0));
        let r = self
            .rows
            .partition_point(|r| r.high <= altitude)
            .min(self.rows.len() - 1);
        let row = self.rows[r];
        let width = TAU / row.patches as f64;
        let azimuth = libm::atan2(w.x, w.y).rem_euclid(TAU);
        let j = ((azimuth + 0.5 * width) / width) as u32 % row.patches;
        Some((row.first + j) as usize)
    }

    /// Σ L(centre)·∫cos Z dω over each patch: the horizontal illuminance a sky vector of
    /// centre luminances gives (Radiance's gendaymtx), lx.
    pub fn horizontal_from_centres(&self, luminance: &dyn Fn(DVec3) -> f64) -> f64 {
        (0..self.len())
            .map(|k| luminance(self.patch(k).centre()) * self.cos_integral(k))
            .sum()
    }

    /// ∫ cos Z dω over patch k: width·(sin²h₁ − sin²h₀)/2.
    pub fn cos_integral(&self, k: usize) -> f64 {
        let p = self.patch(k);
        let (s0, s1) = (libm::sin(p.altitude[0]), libm::sin(p.altitude[1]));
        0.5 * (p.azimuth[1] - p.azimuth[0]) * (s1 * s1 - s0 * s0)
    }

    /// The mean of `luminance` over patch `k`: ∫L dω / Ω by 8 × 8 Gauss–Legendre in
    /// (sin altitude, azimuth), in which the solid angle is uniform.
    pub fn mean_over(&self, k: usize, luminance: &dyn Fn(DVec3) -> f64) -> f64 {
        self.integrals_over(k, luminance).0
    }

    /// Patch `k`'s mean luminance and its ∫L cos Z dω (its horizontal illuminance), both
    /// from the same 8 × 8 Gauss–Legendre points as [`SkyPatches::mean_over`].
    pub fn integrals_over(&self, k: usize, luminance: &dyn Fn(DVec3) -> f64) -> (f64, f64) {
        let p = self.patch(k);
        let (s0, s1) = (libm::sin(p.altitude[0]), libm::sin(p.altitude[1]));
        let (mut mean, mut horizontal) = (0.0, 0.0);
        for (x, wx) in GAUSS8 {
            let s = s0 + x * (s1 - s0);
            let altitude = libm::asin(s.min(1.0));
            for (y, wy) in GAUSS8 {
                let azimuth = p.azimuth[0] + y * (p.azimuth[1] - p.azimuth[0]);
                let l = wx * wy * luminance(direction_rad(altitude, azimuth));
                mean += l;
                horizontal += l * s;
            }
        }
        (mean, horizontal * p.solid_angle_sr)
    }
}

impl SkyPatches {
    /// The sky vector's horizontal illuminance against the exact `exact_lx`: from the
    /// patches' centre luminances (as gendaymtx's vectors hold) and from their mean
    /// luminances (each patch uniform at its mean), one line.
    pub fn vector_summary(&self, luminance: &dyn Fn(DVec3) -> f64, exact_lx: f64) -> String {
        let centres = self.horizontal_from_centres(luminance);
        let means: f64 = (0..self.len())
            .map(|k| self.mean_over(k, luminance) * self.cos_integral(k))
            .sum();
        let off = |e: f64| 100.0 * (e / exact_lx - 1.0);
        format!(
            "Reinhart MF:{} ({} patches): horizontal illuminance {centres:.1} lx from the \
             patches' centres ({:+.3} %), {means:.1} lx from their means ({:+.3} %), \
             exactly {exact_lx:.1} lx",
            self.mf,
            self.len(),
            off(centres),
            off(means)
        )
    }

    /// The patches as CSV rows (no header): light label, patch, its altitude and
    /// azimuth ranges (degrees), solid angle, centre and mean luminance.
    pub fn vector_csv(&self, label: &str, luminance: &dyn Fn(DVec3) -> f64) -> String {
        let mut out = String::new();
        for k in 0..self.len() {
            let p = self.patch(k);
            let [h0, h1, a0, a1] =
                [p.altitude[0], p.altitude[1], p.azimuth[0], p.azimuth[1]].map(f64::to_degrees);
            out += &format!(
                "{label},{k},{h0:.6},{h1:.6},{a0:.6},{a1:.6},{:.9},{:.6},{:.6}\n",
                p.solid_angle_sr,
                luminance(p.centre()),
                self.mean_over(k, luminance)
            );
        }
        out
    }
}

impl SkyPatches {
    /// Patch `k` as regions of the sphere of directions (φ from +x towards +y, as
    /// [`Region::Band`]): one band, or two where it straddles φ = 0 (due east).
    pub fn regions(&self, k: usize) -> Vec<Region> {
        let p = self.patch(k);
        let z = [libm::sin(p.altitude[0]), libm::sin(p.altitude[1]).min(1.0)];
        if p.azimuth[1] - p.azimuth[0] >= TAU {
            return vec![Region::Band { z, phi: [0.0, TAU] }];
        }
        // Azimuth a (from north towards east) is φ = π/2 − a.
        let (lo, hi) = (FRAC_PI_2 - p.azimuth[1], FRAC_PI_2 - p.azimuth[0]);
        let (lo, hi) = (lo.rem_euclid(TAU), lo.rem_euclid(TAU) + (hi - lo));
        if hi <= TAU {
            vec![Region::Band { z, phi: [lo, hi] }]
        } else {
            vec![
                Region::Band { z, phi: [lo, TAU] },
                Region::Band {
                    z,
                    phi: [0.0, hi - TAU],
                },
            ]
        }
    }
}

/// A sky of constant luminance over each Reinhart patch and a uniform ground: a
/// daylight coefficient's source (one patch, or the ground, at 1 cd/m²) or a whole
/// sky vector (`annual`'s linearity checks). Its photons and next events are the
/// distant sources' (`distant.rs`), so they come through portals and glazing as a
/// sky's do.
#[derive(Clone, Debug)]
pub struct PatchSky {
    pub patches: SkyPatches,
    /// cd/m² per patch (`patches.len()` of them).
    pub luminance: Vec<f64>,
    pub ground_cdm2: f64,
    pub portals: Vec<Portal>,
    /// Whether next events aim at the portals: worth it for large sources (the ground,
    /// a whole sky); a single patch is sampled directly, as the sun's cone is.
    pub next_events_by_portals: bool,
}

impl PatchSky {
    /// Patch `k` alone at 1 cd/m².
    pub fn single(patches: &SkyPatches, k: usize, portals: &[Portal]) -> PatchSky {
        let mut luminance = vec![0.0; patches.len()];
        luminance[k] = 1.0;
        PatchSky {
            patches: patches.clone(),
            luminance,
            ground_cdm2: 0.0,
            portals: portals.to_vec(),
            next_events_by_portals: false,
        }
    }

    /// The ground alone at 1 cd/m².
    pub fn ground(patches: &SkyPatches, portals: &[Portal]) -> PatchSky {
        PatchSky {
            patches: patches.clone(),
            luminance: vec![0.0; patches.len()],
            ground_cdm2: 1.0,
            portals: portals.to_vec(),
            next_events_by_portals: true,
        }
    }

    /// ∫ L dω over the sphere, cd/m²·sr.
    fn radiant_integral(&self) -> f64 {
        let sky: f64 = (self.luminance.iter().enumerate())
            .map(|(k, l)| l * self.patches.patch(k).solid_angle_sr)
            .sum();
        sky + 2.0 * PI * self.ground_cdm2
    }

    fn table(&self) -> DistantTable {
        let mut parts = Vec::new();
        for (k, &l) in self.luminance.iter().enumerate() {
            parts.extend(self.patches.regions(k).into_iter().map(|r| (r, l)));
        }
        parts.push((Region::ground(), self.ground_cdm2));
        let (patches, luminance, ground) = (
            self.patches.clone(),
            self.luminance.clone(),
            self.ground_cdm2,
        );
        let l = move |w: DVec3| match patches.index(w) {
            Some(k) => luminance[k],
            None => ground,
        };
        DistantTable::new(parts, Arc::new(l))
    }
}

impl Light for PatchSky {
    fn flux_lm(&self, sphere: &BoundingSphere) -> f64 {
        PI * sphere.radius * sphere.radius * self.radiant_integral()
    }

    fn emitter(&self, origin: DVec3, sphere: &BoundingSphere) -> Arc<dyn Emitter> {
        DistantEmitter::of(
            self.table(),
            origin,
            sphere,
            &self.portals,
            self.next_events_by_portals,
        )
    }

    fn describe(&self) -> String {
        let lit = self.luminance.iter().filter(|&&l| l > 0.0).count();
        format!(
            "Reinhart MF:{} patch sky: {lit} of {} patches lit, ground {} cd/m²",
            self.patches.mf,
            self.patches.len(),
            self.ground_cdm2
        )
    }
}

/// Gauss–Legendre nodes and weights on [0, 1], 8 points.
const GAUSS8: [(f64, f64); 8] = {
    const X: [f64; 4] = [
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_3,
    ];
    const W: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    let mut out = [(0.0, 0.0); 8];
    let mut k = 0;
    while k < 4 {
        out[2 * k] = (0.5 - 0.5 * X[k], 0.5 * W[k]);
        out[2 * k + 1] = (0.5 + 0.5 * X[k], 0.5 * W[k]);
        k += 1;
    }
    out
};

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn patch_counts_and_solid_angles_add_up() {
        for mf in 1..=6 {
            let p = SkyPatches::reinhart(mf, "t").unwrap();
            assert_eq!(p.len(), (144 * mf * mf + 1) as usize);
            let total: f64 = (0..p.len()).map(|k| p.patch(k).solid_angle_sr).sum();
            assert!((total - TAU).abs() < 1e-12, "MF {mf}: Σ Ω = {total}");
            let cos: f64 = (0..p.len()).map(|k| p.cos_integral(k)).sum();
            assert!((cos - PI).abs() < 1e-12, "MF {mf}: Σ ∫cos = {cos}");
        }
    }

    /// Tregenza's table: 12° bands of 30, 30, 24, 24, 18, 12, 6 patches and a 6° cap
    /// (MF 1: α = 90°/7.5 = 12°), Ω = 2π(sin h₁ − sin h₀)/n.
    #[test]
    fn mf_1_is_tregenzas_145() {
        let p = SkyPatches::reinhart(1, "t").unwrap();
        let mut k = 0;
        for (band, &n) in TREGENZA_BANDS.iter().enumerate() {
            let (h0, h1) = ((12 * band) as f64, (12 * band + 12) as f64);
            for _ in 0..n {
                let patch = p.patch(k);
                let want =
                    TAU * (libm::sin(h1.to_radians()) - libm::sin(h0.to_radians())) / n as f64;
                assert!((patch.solid_angle_sr - want).abs() < 1e-14, "patch {k}");
                k += 1;
            }
        }
        let cap = p.patch(144);
        assert!((cap.solid_angle_sr - TAU * (1.0 - libm::cos(6f64.to_radians()))).abs() < 1e-14);
        assert_eq!(p.patch(144).centre(), DVec3::Z);
    }

    #[test]
    fn every_centre_falls_in_its_own_patch_numbered_from_north_towards_east() {
        for mf in [1, 2, 4] {
            let p = SkyPatches::reinhart(mf, "t").unwrap();
            for k in 0..p.len() {
                assert_eq!(p.index(p.patch(k).centre()), Some(k), "MF {mf} patch {k}");
            }
            let north = direction_rad(0.01, 0.0);
            assert_eq!(p.index(north), Some(0));
            let just_east = direction_rad(0.01, (360.0 / (30 * mf) as f64).to_radians());
            assert_eq!(p.index(just_east), Some(1));
            assert_eq!(p.index(DVec3::new(0.0, 1.0, -0.1).normalize()), None);
        }
    }

    #[test]
    fn patch_means_of_linear_luminances_are_exact() {
        let p = SkyPatches::reinhart(2, "t").unwrap();
        for k in [0, 17, 300, 576] {
            let patch = p.patch(k);
            let (s0, s1) = (libm::sin(patch.altitude[0]), libm::sin(patch.altitude[1]));
            let mean = p.mean_over(k, &|w| 2.0 + 3.0 * w.z);
            assert!((mean - (2.0 + 1.5 * (s0 + s1))).abs() < 1e-12, "patch {k}");
        }
    }

    /// Each patch's regions hold exactly the directions `index` puts in it, and their
    /// solid angles add up to the patch's.
    #[test]
    fn patch_regions_hold_their_patch() {
        for mf in [1, 2] {
            let p = SkyPatches::reinhart(mf, "t").unwrap();
            for k in 0..p.len() {
                let regions = p.regions(k);
                let solid: f64 = regions.iter().map(Region::solid_angle_sr).sum();
                assert!(
                    (solid - p.patch(k).solid_angle_sr).abs() < 1e-12,
                    "patch {k}"
                );
                for r in &regions {
                    for (a, b) in [(0.5, 0.5), (0.01, 0.02), (0.99, 0.98)] {
                        assert_eq!(p.index(r.direction(a, b)), Some(k), "MF {mf} patch {k}");
                    }
                }
            }
        }
    }

    /// A patch sky's flux is πR²·∫L dω: its lit patches' solid angles and the ground's 2π.
    #[test]
    fn a_patch_sky_emits_its_patches_flux() {
        let p = SkyPatches::reinhart(1, "t").unwrap();
        let sphere = BoundingSphere {
            center: DVec3::ZERO,
            radius: 2.0,
        };
        let one = PatchSky::single(&p, 7, &[]);
        let want = PI * 4.0 * p.patch(7).solid_angle_sr;
        assert!((one.flux_lm(&sphere) - want).abs() < 1e-12 * want);
        let ground = PatchSky::ground(&p, &[]);
        assert!((ground.flux_lm(&sphere) - PI * 4.0 * TAU).abs() < 1e-9);
    }

    #[test]
    fn an_mf_out_of_range_is_one_line_naming_the_key() {
        for mf in [0, MAX_MF + 1] {
            let e = SkyPatches::reinhart(mf, "--patches")
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("--patches") && e.contains("MF") && !e.contains('\n'),
                "{e}"
            );
        }
    }
}

//! Light from infinitely far away with a luminance L(ω) over the sphere of directions
//! (skies, the sun, the ground they light): what `sky.rs` and `sun.rs` share.
//!
//! The sphere is cut into regions (bands of z = cos θ and azimuth, cones, the lower
//! hemisphere), each with a rigorous upper bound of L over it. Photons pick a region in
//! proportion to bound × solid angle, a direction uniformly in it, and keep it with
//! probability L/bound (rejection): directions come exactly in proportion to L, so
//! every photon carries the same flux πR²·∫L dω / N through the scene's disk of radius
//! R normal to its direction. Next-event pieces use the same regions without the
//! rejection and carry L(ω)/p(ω) exactly.

use super::{Emitter, Incoming};
use crate::sampling::{basis, uniform, uniform_disk, SphericalRect};
use glam::DVec3;
use rand_pcg::Pcg32;
use std::f64::consts::PI;
use std::sync::Arc;

/// A part of the sphere of directions (towards the source).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Region {
    /// z0 ≤ z < z1 and φ0 ≤ φ < φ1 (world z up; φ from +x towards +y).
    Band { z: [f64; 2], phi: [f64; 2] },
    /// Directions within the angle whose cosine is `cos_max` of `axis` (unit).
    Cone { axis: DVec3, cos_max: f64 },
}

impl Region {
    pub fn solid_angle_sr(&self) -> f64 {
        match *self {
            Region::Band { z, phi } => (z[1] - z[0]) * (phi[1] - phi[0]),
            Region::Cone { cos_max, .. } => 2.0 * PI * (1.0 - cos_max),
        }
    }

    /// The direction at (a, b) ∈ [0, 1)², uniform in solid angle.
    pub fn direction(&self, a: f64, b: f64) -> DVec3 {
        match *self {
            Region::Band { z, phi } => {
                let z = z[0] + a * (z[1] - z[0]);
                let phi = phi[0] + b * (phi[1] - phi[0]);
                let r = (1.0 - z * z).max(0.0).sqrt();
                DVec3::new(r * libm::cos(phi), r * libm::sin(phi), z)
            }
            Region::Cone { axis, cos_max } => {
                let cos = 1.0 - a * (1.0 - cos_max);
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let phi = 2.0 * PI * b;
                let (t, s) = basis(axis);
                (t * (sin * libm::cos(phi)) + s * (sin * libm::sin(phi)) + axis * cos).normalize()
            }
        }
    }

    /// Whether unit `w` lies in it.
    pub fn contains(&self, w: DVec3) -> bool {
        match *self {
            Region::Band { z, phi } => {
                let p = libm::atan2(w.y, w.x).rem_euclid(2.0 * PI);
                w.z >= z[0] && w.z < z[1] && p >= phi[0] && p < phi[1]
            }
            Region::Cone { axis, cos_max } => w.dot(axis) >= cos_max,
        }
    }

    /// The lower hemisphere (the ground seen from above it).
    pub fn ground() -> Region {
        Region::Band {
            z: [-1.0, 0.0],
            phi: [0.0, 2.0 * PI],
        }
    }
}

/// Luminance of a distant source towards direction `w` (unit, towards the source), cd/m².
pub type LuminanceFn = Arc<dyn Fn(DVec3) -> f64 + Send + Sync>;

/// The regions, their bounds and the cumulative weights they are picked by.
#[derive(Clone)]
pub struct DistantTable {
    regions: Vec<Region>,
    bounds: Vec<f64>,
    /// Cumulative Σ bound·Ω, ending at `total`.
    cdf: Vec<f64>,
    total: f64,
    luminance: LuminanceFn,
    /// The first nz × nphi regions are [`hemisphere_bands`] (nz, nphi), in order: the
    /// density finds a direction's band directly.
    grid: Option<(usize, usize)>,
}

impl std::fmt::Debug for DistantTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DistantTable({} regions)", self.regions.len())
    }
}

impl DistantTable {
    /// `parts`: each region with an upper bound of L over it (regions of bound 0 are
    /// dropped: nothing comes from there).
    pub fn new(parts: Vec<(Region, f64)>, luminance: LuminanceFn) -> DistantTable {
        let (mut regions, mut bounds, mut cdf) = (Vec::new(), Vec::new(), Vec::new());
        let mut total = 0.0;
        for (region, bound) in parts {
            if bound > 0.0 {
                total += bound * region.solid_angle_sr();
                regions.push(region);
                bounds.push(bound);
                cdf.push(total);
            }
        }
        DistantTable {
            regions,
            bounds,
            cdf,
            total,
            luminance,
            grid: None,
        }
    }

    /// Marks the first regions as the (nz, nphi) hemisphere bands, if all were kept.
    pub fn with_grid(mut self, nz: usize, nphi: usize) -> DistantTable {
        let kept = (self.regions.iter().take(nz * nphi))
            .zip(hemisphere_bands(nz, nphi))
            .filter(|(a, b)| a == &b)
            .count();
        if kept == nz * nphi {
            self.grid = Some((nz, nphi));
        }
        self
    }

    /// The density (1/sr) with which [`DistantTable::piece`] draws unit `w`.
    pub fn density(&self, w: DVec3) -> f64 {
        if self.is_dark() {
            return 0.0;
        }
        // The grid's bands come first: the region a direction is drawn from is the
        // first that holds it, a band wherever z ≥ 0, and none of them below.
        let mut first_other = 0;
        if let Some((nz, nphi)) = self.grid {
            if w.z >= 0.0 {
                let i = ((w.z * nz as f64) as usize).min(nz - 1);
                let phi = libm::atan2(w.y, w.x).rem_euclid(2.0 * PI);
                let j = ((phi / (2.0 * PI) * nphi as f64) as usize).min(nphi - 1);
                return self.bounds[i * nphi + j] / self.total;
            }
            first_other = nz * nphi;
        }
        let (regions, bounds) = (&self.regions[first_other..], &self.bounds[first_other..]);
        (regions.iter().zip(bounds))
            .find(|(r, _)| r.contains(w))
            .map_or(0.0, |(_, b)| b / self.total)
    }

    pub fn is_dark(&self) -> bool {
        !(self.total > 0.0)
    }

    /// The region `u` ∈ [0, 1) falls in by the weights, and where in its share (∈ [0, 1)).
    fn pick(&self, u: f64) -> (usize, f64) {
        let x = u * self.total;
        let k = self
            .cdf
            .partition_point(|&c| c <= x)
            .min(self.cdf.len() - 1);
        let lo = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        let width = self.cdf[k] - lo;
        let frac = if width > 0.0 { (x - lo) / width } else { 0.5 };
        (k, frac.clamp(0.0, 1.0 - f64::EPSILON))
    }

    /// A direction drawn exactly in proportion to L (rejection against the bounds).
    pub fn sample(&self, rng: &mut Pcg32) -> DVec3 {
        loop {
            let (k, _) = self.pick(uniform(rng));
            let w = self.regions[k].direction(uniform(rng), uniform(rng));
            if uniform(rng) * self.bounds[k] < (self.luminance)(w) {
                return w;
            }
        }
    }

    /// The direction for the pattern point (a, b) and its weight L(ω)/p(ω), lx·sr/sr.
    pub fn piece(&self, a: f64, b: f64) -> (DVec3, f64) {
        let (k, frac) = self.pick(a);
        let w = self.regions[k].direction(frac, b);
        // p(ω) = bound_k / total (uniform within the region, picked by bound·Ω).
        (w, (self.luminance)(w) * self.total / self.bounds[k])
    }

    pub fn luminance(&self, w: DVec3) -> f64 {
        (self.luminance)(w)
    }
}

/// An opening the scene's daylight enters by (`[[portals]]`): a rectangle with
/// orthogonal edges `u`, `v` from `corner`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Portal {
    pub corner: DVec3,
    pub u: DVec3,
    pub v: DVec3,
}

impl Portal {
    /// The portal moved by `offset` (world to local: −origin).
    pub fn shifted(&self, offset: DVec3) -> Portal {
        Portal {
            corner: self.corner + offset,
            ..*self
        }
    }

    /// Its rectangle as seen from `p` (None from its plane).
    fn seen_from(&self, p: DVec3) -> Option<SphericalRect> {
        SphericalRect::new(p, self.corner, self.u, self.v)
    }

    /// Whether the ray from `p` along unit `w` passes through it.
    fn passes(&self, p: DVec3, w: DVec3) -> bool {
        self.crossing(p, w).is_some_and(|t| t > 0.0)
    }

    /// Where the line `p + t·w` (unit `w`) crosses the rectangle: its t, of either sign.
    pub fn crossing(&self, p: DVec3, w: DVec3) -> Option<f64> {
        let n = self.u.cross(self.v);
        let along = w.dot(n);
        if along == 0.0 {
            return None;
        }
        let t = (self.corner - p).dot(n) / along;
        let q = p + w * t - self.corner;
        let (s, r) = (
            q.dot(self.u) / self.u.length_squared(),
            q.dot(self.v) / self.v.length_squared(),
        );
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r)).then_some(t)
    }

    pub fn area_m2(&self) -> f64 {
        self.u.cross(self.v).length()
    }
}

/// A photon aimed through an opening ([`DistantEmitter::portal_photon`]): where it
/// starts on the scene's disk, its unit direction, the portal it was aimed through
/// (its first segment must cross that one first), and its flux relative to a disk
/// photon's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PortalPhoton {
    pub origin: DVec3,
    pub dir: DVec3,
    pub portal: u32,
    pub weight: f64,
}

/// With portals, the share of next-event pieces drawn from the whole sky's table (the
/// rest aim at the portals): they estimate the light that does not come through a
/// portal (sky seen beside them).
pub const SKY_TABLE_SHARE: f64 = 0.25;

/// A distant source prepared for the passes: photons start on a disk of the scene's
/// radius outside the scene, normal to their direction.
#[derive(Clone, Debug)]
pub struct DistantEmitter {
    pub table: DistantTable,
    /// Centre (local frame) and radius of the scene's bounding sphere.
    pub center: DVec3,
    pub radius: f64,
    /// The scene's openings (local frame): photons also come in by them.
    pub portals: Vec<Portal>,
    /// Whether next events aim at the portals too (a sky's do; a sun's cone is sampled
    /// directly, which aiming at a window would only make noisier).
    pub next_events_by_portals: bool,
}

impl DistantEmitter {
    /// The emitter of `table` for a scene of bounding sphere `sphere` and local frame
    /// `origin`, with the scene's `portals` (world): what every distant light's
    /// `Light::emitter` makes.
    pub fn of(
        table: DistantTable,
        origin: DVec3,
        sphere: &super::BoundingSphere,
        portals: &[Portal],
        next_events_by_portals: bool,
    ) -> Arc<dyn Emitter> {
        Arc::new(DistantEmitter {
            table,
            center: sphere.center - origin,
            radius: sphere.radius,
            portals: portals.iter().map(|o| o.shifted(-origin)).collect(),
            next_events_by_portals,
        })
    }

    /// Next-event pieces with portals. The sphere of directions seen from `p` is split
    /// in two: those through some portal, sampled by the portals' solid angles (share
    /// 1 − [`SKY_TABLE_SHARE`], split evenly, combined by their summed density where
    /// portals overlap), and all others, sampled by the sky's table (a table piece
    /// through a portal counts 0: that part is the portals'). Each part's estimate is
    /// unbiased, so their sum is, wherever the sky is seen. A partition rather than a
    /// mixture: a table piece through an opening would carry the same weight as the
    /// portals' but come rarely, and such rare scores make a cell's σ untrustworthy.
    fn incoming_through_portals(
        &self,
        p: DVec3,
        area_pattern: &[(f64, f64)],
        each: &mut dyn FnMut(Incoming),
    ) {
        let q = SKY_TABLE_SHARE;
        let per_portal = (1.0 - q) / self.portals.len() as f64;
        let pieces = area_pattern.len().max(1) as f64;
        for &(a, b) in area_pattern {
            let (w, density) = if a < q {
                let w = self.table.piece(a / q, b).0;
                if self.portals.iter().any(|o| o.passes(p, w)) {
                    continue;
                }
                (w, q * self.table.density(w))
            } else {
                let x = (a - q) / (1.0 - q) * self.portals.len() as f64;
                let k = (x as usize).min(self.portals.len() - 1);
                let Some(rect) = self.portals[k].seen_from(p) else {
                    continue;
                };
                let point = rect.sample((x - k as f64).clamp(0.0, 1.0 - f64::EPSILON), b);
                let w = (point - p).normalize();
                // Aimed at portal k, w passes it even where rounding puts the point a
                // hair outside an edge; the other portals count where w passes them.
                let density: f64 = (self.portals.iter().enumerate())
                    .filter_map(|(j, o)| {
                        if j == k {
                            Some(rect)
                        } else if o.passes(p, w) {
                            o.seen_from(p)
                        } else {
                            None
                        }
                    })
                    .map(|r| per_portal / r.solid_angle_sr)
                    .sum();
                (w, density)
            };
            let l = self.table.luminance(w);
            if l > 0.0 && density > 0.0 {
                each(Incoming {
                    to_source: w,
                    distance: f64::INFINITY,
                    normal_lx: l / density / pieces,
                });
            }
        }
    }
}

impl Emitter for DistantEmitter {
    fn sample_emission(&self, rng: &mut Pcg32) -> (DVec3, DVec3) {
        let w = self.table.sample(rng);
        let disk = self.center + w * (self.radius * 1.01);
        (uniform_disk(rng, disk, -w, self.radius), -w)
    }

    fn incoming(&self, p: DVec3, area_pattern: &[(f64, f64)], each: &mut dyn FnMut(Incoming)) {
        if self.table.is_dark() {
            return;
        }
        if self.next_events_by_portals && !self.portals.is_empty() {
            return self.incoming_through_portals(p, area_pattern, each);
        }
        let pieces = area_pattern.len().max(1) as f64;
        for &(a, b) in area_pattern {
            let (w, weight) = self.table.piece(a, b);
            if weight > 0.0 {
                each(Incoming {
                    to_source: w,
                    distance: f64::INFINITY,
                    normal_lx: weight / pieces,
                });
            }
        }
    }

    fn portals(&self) -> &[Portal] {
        &self.portals
    }

    /// A photon through the portals (docs/daylight.md, *Photons through portals*): a
    /// portal picked by area, a point uniformly on it, a direction drawn in proportion
    /// to L as a disk photon's, and the photon started where that line meets the disk.
    /// The density of such a line's point on the disk is 1/(A·|cos θ|) against the
    /// disk's 1/(πR²), so it carries A·|cos θ|/(πR²) of a disk photon's flux, A the
    /// portals' total area and θ from the portal's normal. None where the line misses
    /// the disk (no disk photon follows it). The photon pass keeps it only if its first
    /// segment crosses this portal first (nothing before it, no other portal first).
    fn portal_photon(&self, rng: &mut Pcg32) -> Option<PortalPhoton> {
        let total: f64 = self.portals.iter().map(Portal::area_m2).sum();
        if !(total > 0.0) || self.table.is_dark() {
            return None;
        }
        let mut x = uniform(rng) * total;
        let k = (self.portals.iter())
            .position(|o| {
                x -= o.area_m2();
                x < 0.0
            })
            .unwrap_or(self.portals.len() - 1);
        let portal = &self.portals[k];
        let point = portal.corner + portal.u * uniform(rng) + portal.v * uniform(rng);
        let w = self.table.sample(rng);
        let disk_center = self.center + w * (self.radius * 1.01);
        let origin = point + w * (disk_center - point).dot(w);
        if (origin - disk_center).length_squared() > self.radius * self.radius {
            return None;
        }
        let cos = w.dot(portal.u.cross(portal.v)).abs() / portal.area_m2();
        Some(PortalPhoton {
            origin,
            dir: -w,
            portal: k as u32,
            weight: total * cos / (PI * self.radius * self.radius),
        })
    }

    /// The whole sky: a pattern of the camera's largest size.
    fn extent(&self) -> (DVec3, f64) {
        (self.center, f64::INFINITY)
    }

    fn luminance_seen(&self, _o: DVec3, dir: DVec3, t_hit: f64) -> Option<f64> {
        (!t_hit.is_finite()).then(|| self.table.luminance(dir.normalize()))
    }
}

/// The upper hemisphere in `nz` bands of z and `nphi` of azimuth: the regions a sky
/// is tabulated on.
pub fn hemisphere_bands(nz: usize, nphi: usize) -> impl Iterator<Item = Region> {
    (0..nz * nphi).map(move |k| {
        let (i, j) = ((k / nphi) as f64, (k % nphi) as f64);
        let dphi = 2.0 * PI / nphi as f64;
        Region::Band {
            z: [i / nz as f64, (i + 1.0) / nz as f64],
            phi: [j * dphi, (j + 1.0) * dphi],
        }
    })
}

/// The least and greatest angle (rad) between unit `s` and the directions of `band`:
/// the farthest point of a z–φ band from any direction is one of its corners, and the
/// nearest lies no nearer than the centre's distance less the farthest corner's.
pub fn angle_range(band: &Region, s: DVec3) -> (f64, f64) {
    let Region::Band { .. } = band else {
        return (0.0, PI);
    };
    let centre = band.direction(0.5, 0.5);
    let corners =
        [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)].map(|(a, b)| band.direction(a, b));
    let angle = |p: DVec3, q: DVec3| libm::acos(p.dot(q).clamp(-1.0, 1.0));
    let radius = corners
        .iter()
        .map(|&c| angle(centre, c))
        .fold(0.0, f64::max);
    let chi = angle(centre, s);
    ((chi - radius).max(0.0), (chi + radius).min(PI))
}

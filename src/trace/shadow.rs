//! Shadow rays of next events (receivers' direct light, the eye pass's direct light):
//! what reaches a point along each. Opaque surfaces block; thin glazing
//! ([`crate::surface::Glazing`]) lets the light through unbent, times its transmittance
//! T(θ) at the ray's incidence, so windows pass the sky and the sun to next events, and
//! the photons' connections to receivers beyond a pane. A scene without glazing keeps
//! the backend's occlusion path.

use super::scatter::offset_origin;
use crate::accel::{HitBatch, RayBatch, RayCaster, Surface};
use crate::scene::{Geometry, Scene};
use crate::surface::Glazing;
use glam::Vec3;

/// Panes a shadow ray crosses at most; a ray still in glass after them counts as
/// blocked (T < 0.92^16 = 0.26 even for the clearest glass, and no real façade has so
/// many surfaces in a row).
pub const MAX_GLAZING_CROSSINGS: usize = 16;

/// Casts shadow rays for a scene: see the module.
pub struct ShadowCaster<'a> {
    caster: &'a dyn RayCaster,
    geometry: &'a Geometry,
    /// Per material, its glazing; empty when the scene has none.
    glazing: Vec<Option<Glazing>>,
    scene_scale: f32,
}

/// Buffers of one worker's shadow rays.
#[derive(Default)]
pub struct ShadowScratch {
    occluded: Vec<bool>,
    rays: RayBatch,
    next: RayBatch,
    hits: HitBatch,
    /// Per ray of `rays` (and `next`), the index of the ray it continues.
    index: Vec<u32>,
    next_index: Vec<u32>,
    /// Per ray of [`ShadowCaster::transmitted`]'s batch, how much of it lies past the
    /// last pane it crosses (∞ past none), in units of its direction's length.
    pub past_last_pane: Vec<f32>,
    /// Per ray of [`ShadowCaster::first_opaque`]'s batch: the transmittance so far, and
    /// where it first hit anything.
    gain: Vec<f64>,
    first_hit: Vec<f32>,
}

/// What a ray meets first past the panes it crosses ([`ShadowCaster::first_opaque`]).
#[derive(Clone, Copy, Debug)]
pub struct SeenThrough {
    pub surface: Surface,
    /// The product of the transmittances of the panes crossed (1 through none).
    pub through: f64,
    /// Where the ray first hit anything, pane or not, in units of its direction's length.
    pub first_hit: f32,
}

impl<'a> ShadowCaster<'a> {
    pub fn new(scene: &'a Scene, caster: &'a dyn RayCaster) -> ShadowCaster<'a> {
        let glazing: Vec<Option<Glazing>> =
            scene.materials.iter().map(|m| m.glazing.clone()).collect();
        let any = glazing.iter().any(Option::is_some);
        ShadowCaster {
            caster,
            geometry: &scene.geometry,
            glazing: if any { glazing } else { Vec::new() },
            scene_scale: scene.geometry.local_scale(),
        }
    }

    /// Whether the scene has glazing (else [`Self::transmitted`] is plain occlusion).
    pub fn sees_through_glazing(&self) -> bool {
        !self.glazing.is_empty()
    }

    /// The fraction of each ray's light that arrives, into `through` (resized): 0 where
    /// an opaque surface lies between `tnear` and `tfar`, else the product of the
    /// transmittances of the panes crossed (1 through none). Returns the rays cast: the
    /// batch's, and each one's continuation past every pane.
    pub fn transmitted(
        &self,
        rays: &RayBatch,
        through: &mut Vec<f64>,
        s: &mut ShadowScratch,
    ) -> u64 {
        through.clear();
        s.past_last_pane.clear();
        s.past_last_pane.resize(rays.len(), f32::INFINITY);
        if self.glazing.is_empty() {
            self.caster.occluded(rays, &mut s.occluded);
            through.extend(s.occluded.iter().map(|&b| if b { 0.0 } else { 1.0 }));
            return rays.len() as u64;
        }
        through.resize(rays.len(), 1.0);
        s.rays.clone_from(rays);
        s.index.clear();
        s.index.extend(0..rays.len() as u32);
        let mut cast = 0;
        for _ in 0..MAX_GLAZING_CROSSINGS {
            if s.rays.is_empty() {
                return cast;
            }
            cast += s.rays.len() as u64;
            self.caster.intersect(&s.rays, &mut s.hits);
            self.cross_panes(through, s);
            std::mem::swap(&mut s.rays, &mut s.next);
            std::mem::swap(&mut s.index, &mut s.next_index);
        }
        for &i in &s.index {
            through[i as usize] = 0.0;
        }
        cast
    }

    /// Per ray, the first surface other than glazing it meets, into `out` (resized):
    /// `None` where it escapes or is still in glass after [`MAX_GLAZING_CROSSINGS`]
    /// panes. Panes pass it on unbent, times their T(θ), exactly as [`Self::transmitted`]
    /// lets light through. Returns the rays cast.
    pub fn first_opaque(
        &self,
        rays: &RayBatch,
        out: &mut Vec<Option<SeenThrough>>,
        s: &mut ShadowScratch,
    ) -> u64 {
        out.clear();
        out.resize(rays.len(), None);
        s.gain.clear();
        s.gain.resize(rays.len(), 1.0);
        s.first_hit.clear();
        s.first_hit.resize(rays.len(), f32::INFINITY);
        s.rays.clone_from(rays);
        s.index.clear();
        s.index.extend(0..rays.len() as u32);
        let mut cast = 0;
        for round in 0..MAX_GLAZING_CROSSINGS {
            if s.rays.is_empty() {
                break;
            }
            cast += s.rays.len() as u64;
            self.caster.intersect(&s.rays, &mut s.hits);
            s.next.clear();
            s.next_index.clear();
            let r = &s.rays;
            for k in 0..r.len() {
                let i = s.index[k] as usize;
                let Some(surface) = s.hits.surface(k, self.geometry) else {
                    continue;
                };
                if round == 0 {
                    s.first_hit[i] = s.hits.t[k];
                }
                let pane = self
                    .glazing
                    .get(surface.material as usize)
                    .and_then(Option::as_ref);
                let Some(glazing) = pane else {
                    out[i] = Some(SeenThrough {
                        surface,
                        through: s.gain[i],
                        first_hit: s.first_hit[i],
                    });
                    continue;
                };
                let past = Past {
                    next: &mut s.next,
                    next_index: &mut s.next_index,
                };
                self.cross_pane(
                    glazing,
                    &surface,
                    (r, k, s.hits.t[k]),
                    (&mut s.gain[i], i),
                    past,
                );
            }
            std::mem::swap(&mut s.rays, &mut s.next);
            std::mem::swap(&mut s.index, &mut s.next_index);
        }
        cast
    }

    /// One round of [`Self::transmitted`]: each ray that hit glazing is attenuated and
    /// goes on past it (into `s.next`); one that hit anything else is blocked.
    fn cross_panes(&self, through: &mut [f64], s: &mut ShadowScratch) {
        s.next.clear();
        s.next_index.clear();
        let r = &s.rays;
        for k in 0..r.len() {
            let i = s.index[k] as usize;
            let Some(surface) = s.hits.surface(k, self.geometry) else {
                continue;
            };
            let Some(glazing) = &self.glazing[surface.material as usize] else {
                through[i] = 0.0;
                continue;
            };
            let past = Past {
                next: &mut s.next,
                next_index: &mut s.next_index,
            };
            s.past_last_pane[i] = self.cross_pane(
                glazing,
                &surface,
                (r, k, s.hits.t[k]),
                (&mut through[i], i),
                past,
            );
        }
    }

    /// Ray `k` of `r`, which hit the pane `glazing` at `surface` at distance `t`: its
    /// light `gain` times the pane's T(θ) at its incidence, and its continuation past
    /// the pane (as ray `i`) while light and length are left. Returns the length left.
    fn cross_pane(
        &self,
        glazing: &Glazing,
        surface: &Surface,
        (r, k, t): (&RayBatch, usize, f32),
        (gain, i): (&mut f64, usize),
        past: Past<'_>,
    ) -> f32 {
        let dir = Vec3::new(r.dx[k], r.dy[k], r.dz[k]);
        let along = dir.normalize().dot(surface.normal);
        *gain *= glazing.reflect_transmit(along.abs() as f64).1;
        let leave = if along > 0.0 {
            surface.normal
        } else {
            -surface.normal
        };
        let origin = offset_origin(surface.point, leave, self.scene_scale);
        let rest = r.tfar[k] - t;
        if *gain > 0.0 && rest > 0.0 {
            past.next.push(origin.to_array(), dir.to_array(), 0.0, rest);
            past.next_index.push(i as u32);
        }
        rest
    }
}

/// Where [`ShadowCaster::cross_pane`] puts the rays that go on past a pane.
struct Past<'a> {
    next: &'a mut RayBatch,
    next_index: &'a mut Vec<u32>,
}

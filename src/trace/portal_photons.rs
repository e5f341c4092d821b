//! Photons through the openings (docs/daylight.md, *Photons through portals*). A
//! distant source's disk photons cross a window in proportion to its projected area
//! over the disk's, so the light that comes in by it converges slowly. With
//! `[[portals]]` the lines through a portal are left to photons aimed at it, and each
//! such photon belongs to the history of the photon whose light it takes over, so its
//! scores add up with that history's as one sample:
//! - each photon index of a sky or a sun also traces a portal photon
//!   ([`crate::light::Emitter::portal_photon`]: from the disk along a line through a
//!   point of a portal, with its share of a disk photon's flux, kept only if that
//!   portal is the first its first segment crosses, [`PortalRule::Spawned`]), and a
//!   disk photon scores receivers only if its first segment crosses no portal
//!   ([`PortalRule::FromSky`]);
//! - at a connected vertex on a portal's outside (the building opposite, an
//!   overhang), a photon is spawned through a point of one of those portals, sampled
//!   by its solid angle and weighed by the surface's f·cos/p, and the vertex's own
//!   continuation scores receivers only if the first portal it crosses is none of
//!   them ([`PortalRule::FromExterior`]); the spawned photon only if it is the one it
//!   was aimed at ([`PortalRule::Spawned`]).
//!
//! Portal and spawned photons score receivers only: the map stays the disk photons',
//! which all carry the same flux. A portal's outside is the side from which more of a
//! fixed set of rays from it escape the scene.

use super::batch::{Pass, PortalRule, Scratch, Segment, Spawn};
use super::hits::Surfacing;
use super::scatter::offset_origin;
use super::Tracer;
use crate::accel::{RayBatch, RayCaster, NO_HIT};
use crate::light::distant::Portal;
use crate::rng::PhotonStreams;
use crate::sampling::{cosine_hemisphere, uniform, SphericalRect};
use crate::surface::Transport;
use glam::{DVec3, Vec3};
use rand::RngCore;
use rand_pcg::Pcg32;

/// Portals up to this index spawn photons at exterior vertices (one bit each).
const MAX_SPAWNING_PORTALS: usize = 32;

/// Rays cast from each side of a portal to find its outside.
const SIDE_RAYS: usize = 256;

/// A portal's outside, for spawning: its corner, edges and outward unit normal.
#[derive(Clone, Debug)]
pub struct Exterior {
    index: u32,
    portal: Portal,
    outward: DVec3,
}

/// The outsides of `portals` (local frame): for each, the side from which more of
/// [`SIDE_RAYS`] cosine-distributed rays from points of it escape; none where no ray
/// escapes on either side or as many on both.
pub fn exteriors(portals: &[Portal], caster: &dyn RayCaster, scale: f32) -> Vec<Exterior> {
    let mut rng = crate::rng::aux_stream(0x9047_a15e);
    let mut out = Vec::new();
    for (index, portal) in portals.iter().enumerate().take(MAX_SPAWNING_PORTALS) {
        let n = portal.u.cross(portal.v).normalize();
        let mut escaped = [0usize; 2];
        for (side, normal) in [n, -n].into_iter().enumerate() {
            let mut rays = RayBatch::default();
            for _ in 0..SIDE_RAYS {
                let p = portal.corner + portal.u * uniform(&mut rng) + portal.v * uniform(&mut rng);
                let o = offset_origin(p.as_vec3(), normal.as_vec3(), scale);
                let d = cosine_hemisphere(&mut rng, normal).as_vec3();
                rays.push(o.into(), d.into(), 0.0, f32::INFINITY);
            }
            let mut blocked = Vec::new();
            caster.occluded(&rays, &mut blocked);
            escaped[side] = blocked.iter().filter(|b| !**b).count();
        }
        let outward = match escaped[0].cmp(&escaped[1]) {
            std::cmp::Ordering::Greater => n,
            std::cmp::Ordering::Less => -n,
            std::cmp::Ordering::Equal => continue,
        };
        out.push(Exterior {
            index: index as u32,
            portal: *portal,
            outward,
        });
    }
    out
}

impl Tracer<'_> {
    /// The first portal the segment `o + t·d` crosses for 0 < t ≤ `reach` (the lower
    /// index where two cross at the same t).
    fn first_portal_crossed(&self, o: DVec3, d: DVec3, reach: f64) -> Option<u32> {
        let mut first: Option<(f64, u32)> = None;
        for (j, p) in self.portals.iter().enumerate() {
            if let Some(t) = p.crossing(o, d) {
                if t > 0.0 && t <= reach && first.is_none_or(|(best, _)| t < best) {
                    first = Some((t, j as u32));
                }
            }
        }
        first.map(|(_, j)| j)
    }

    /// After an intersection: each lane's segment against its [`PortalRule`] (up to its
    /// hit and the receivers' slack past it, so a pane in a portal's plane counts as
    /// crossed); a lane that fails scores receivers no more (weight 0), and in a pass
    /// that only scores receivers it ends here.
    pub(super) fn apply_portal_rules(&self, s: &mut Scratch, pass: Pass) {
        let (rays, lanes) = (&s.rays, &mut s.lanes);
        for k in 0..rays.len() {
            let rule = lanes.rule[k];
            if rule == PortalRule::Free || lanes.weight[k] == 0.0 {
                continue;
            }
            let o = DVec3::new(rays.ox[k] as f64, rays.oy[k] as f64, rays.oz[k] as f64);
            let d = DVec3::new(rays.dx[k] as f64, rays.dy[k] as f64, rays.dz[k] as f64);
            let first = self.first_portal_crossed(o, d, s.hits.t[k] as f64 + self.receiver_slack);
            let keeps = match rule {
                PortalRule::Free => true,
                PortalRule::FromSky => first.is_none(),
                PortalRule::FromExterior(mask) => first.is_none_or(|j| mask & (1 << j) == 0),
                PortalRule::Spawned(j) => first == Some(j),
            };
            if !keeps {
                lanes.weight[k] = 0.0;
                if pass == Pass::Receivers {
                    s.hits.tri[k] = NO_HIT;
                }
            }
        }
    }

    /// The portals (bits by index) whose outside `p` lies on, by more than the
    /// receivers' slack.
    #[inline]
    pub(super) fn exterior_of(&self, p: Vec3) -> u32 {
        let p = p.as_dvec3();
        (self.exteriors.iter())
            .filter(|e| (p - e.portal.corner).dot(e.outward) > self.receiver_slack)
            .fold(0, |mask, e| mask | 1 << e.index)
    }

    /// A photon spawned at exterior vertex `p` (geometric normal `normal`, `wo` back
    /// along the arriving photon) through one of the portals in `mask`, picked evenly:
    /// a direction uniform in the solid angle the portal subtends, weighed by the
    /// connected lobes' f·|cos θ| over its density. `(offset, weight, rng)`: the
    /// photon's history, its receiver weight and its stream (it draws the spawn's
    /// numbers and seeds the spawned photon's stream).
    pub(super) fn spawn(
        &self,
        (p, normal, wo): (Vec3, Vec3, DVec3),
        surfacing: &Surfacing,
        (offset, weight, rng): (u32, f64, &mut Pcg32),
        mask: u32,
        spawns: &mut Vec<Spawn>,
    ) {
        let count = mask.count_ones();
        let pick = ((uniform(rng) * count as f64) as u32).min(count - 1);
        let (a, b) = (uniform(rng), uniform(rng));
        let seed = (rng.next_u64(), rng.next_u64());
        let Some(e) = (self.exteriors.iter())
            .filter(|e| mask & (1 << e.index) != 0)
            .nth(pick as usize)
        else {
            return;
        };
        let x = p.as_dvec3();
        let Some(rect) = SphericalRect::new(x, e.portal.corner, e.portal.u, e.portal.v) else {
            return;
        };
        let dir = (rect.sample(a, b) - x).normalize();
        let n = normal.as_dvec3();
        let facing = if wo.dot(n) >= 0.0 { n } else { -n };
        let cos_s = dir.dot(facing);
        let f = (surfacing.bsdf).f_cos(1.0, wo, dir, n, cos_s, Transport::Importance, true);
        if !(f > 0.0) {
            return;
        }
        let side = if cos_s > 0.0 { facing } else { -facing };
        spawns.push(Spawn {
            offset,
            origin: offset_origin(p, side.as_vec3(), self.scene_scale),
            dir: dir.as_vec3(),
            weight: weight * f * count as f64 * rect.solid_angle_sr,
            portal: e.index,
            rng: Pcg32::new(seed.0, seed.1),
        });
    }

    /// The next round's batch: the photons spawned in this one, if any.
    pub(super) fn load_spawns(&self, s: &mut Scratch) -> bool {
        std::mem::swap(&mut s.spawns, &mut s.next_spawns);
        s.next_spawns.clear();
        let (rays, lanes) = (&mut s.rays, &mut s.lanes);
        rays.truncate(0);
        lanes.truncate(0);
        lanes.bounces = 0;
        for spawn in s.spawns.drain(..) {
            rays.push(spawn.origin.into(), spawn.dir.into(), 0.0, f32::INFINITY);
            lanes.offset.push(spawn.offset);
            lanes.segment.push(Segment::Connectable);
            lanes.rng.push(spawn.rng);
            lanes.weight.push(spawn.weight);
            lanes.rule.push(PortalRule::Spawned(spawn.portal));
        }
        !rays.is_empty()
    }

    /// The batch of the chunk's portal photons (photons `first .. first + count`, each
    /// from its own portal stream), each from the disk, with its weight, checked after
    /// its first intersection as a spawned photon is ([`PortalRule::Spawned`]).
    pub(super) fn emit_portal_photons(&self, first: u64, count: usize, s: &mut Scratch) {
        let streams = PhotonStreams::portal(self.seed, first);
        let (rays, lanes) = (&mut s.rays, &mut s.lanes);
        rays.truncate(0);
        lanes.truncate(0);
        lanes.bounces = 0;
        for k in 0..count {
            let light = self.emitters.light_of(first + k as u64);
            let emitter = &self.emitters.emitters[light];
            if emitter.portals().is_empty() {
                continue;
            }
            let mut rng = streams.get(k);
            if let Some(p) = emitter.portal_photon(&mut rng) {
                rays.push(
                    p.origin.as_vec3().into(),
                    p.dir.as_vec3().into(),
                    0.0,
                    f32::INFINITY,
                );
                lanes.offset.push(k as u32);
                lanes.segment.push(Segment::Emitted);
                lanes.rng.push(rng);
                lanes.weight.push(p.weight);
                lanes.rule.push(PortalRule::Spawned(p.portal));
            }
        }
    }
}

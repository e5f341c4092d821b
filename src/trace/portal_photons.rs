//! Photons through the openings (docs/daylight.md, *Openings*). A distant source's disk
//! photons cross a window in proportion to its projected area over the disk's, so the
//! light that comes straight in by it converges slowly. With `[[portals]]`, each photon
//! index of such a source also traces a portal photon ([`crate::light::Emitter::
//! portal_photon`]: a line through a point of a portal, carrying its share of a disk
//! photon's flux), and the two split the lines between them: the disk photon scores
//! receivers only if its first segment crosses no portal, the portal photon only if
//! nothing stands between the portal and the sky. Light that exterior geometry sends
//! in (the building opposite, an overhang) still comes by the disk photons. Both belong
//! to the photon's history, so its scores add up as one sample; the map stays the disk
//! photons' alone, which all carry the same flux.

use super::batch::{Scratch, Segment};
use super::Tracer;
use crate::rng::PhotonStreams;
use crate::tally::ChunkTally;
use glam::DVec3;

impl Tracer<'_> {
    /// After the first intersection of a chunk's disk photons: those of a source with
    /// portals whose first segment crosses one, up to its hit and the receivers'
    /// slack past it (a pane in the portal's plane is then crossed as the portal
    /// photons' occlusion test sees it), get receiver weight 0.
    pub(super) fn leave_portal_crossings(&self, first: u64, s: &mut Scratch) {
        let rays = &s.rays;
        for k in 0..rays.len() {
            let offset = s.lanes.offset[k];
            let light = self.emitters.light_of(first + offset as u64);
            let portals = self.emitters.emitters[light].portals();
            if portals.is_empty() {
                continue;
            }
            let o = DVec3::new(rays.ox[k] as f64, rays.oy[k] as f64, rays.oz[k] as f64);
            let d = DVec3::new(rays.dx[k] as f64, rays.dy[k] as f64, rays.dz[k] as f64);
            let reach = s.hits.t[k] as f64 + self.receiver_slack;
            let crosses =
                (portals.iter()).any(|p| p.crossing(o, d).is_some_and(|t| t > 0.0 && t <= reach));
            if crosses {
                s.weight[offset as usize] = 0.0;
            }
        }
    }

    /// The batch of the chunk's portal photons (photons `first .. first + count`, each
    /// from its own portal stream): those whose line reaches the sky from the portal
    /// (an occlusion ray from the point towards the source, past the receivers'
    /// slack), each starting twice the slack before its point, with its weight.
    pub(super) fn emit_portal_photons(
        &self,
        first: u64,
        count: usize,
        s: &mut Scratch,
        tally: &mut ChunkTally,
    ) {
        let streams = PhotonStreams::portal(self.seed, first);
        s.portal_photons.clear();
        for k in 0..count {
            let light = self.emitters.light_of(first + k as u64);
            let emitter = &self.emitters.emitters[light];
            if emitter.portals().is_empty() {
                continue;
            }
            let mut rng = streams.get(k);
            if let Some(photon) = emitter.portal_photon(&mut rng) {
                s.portal_photons.push((k as u32, photon, rng));
            }
        }
        let slack = self.receiver_slack;
        s.shadow_rays.clear();
        for (_, p, _) in &s.portal_photons {
            let (o, w) = (p.point.as_vec3(), (-p.dir).as_vec3());
            s.shadow_rays
                .push(o.into(), w.into(), slack as f32, f32::INFINITY);
        }
        self.caster.occluded(&s.shadow_rays, &mut s.occluded);
        tally.rays += s.shadow_rays.len() as u64;
        s.weight.clear();
        s.weight.resize(count, 0.0);
        let (rays, lanes) = (&mut s.rays, &mut s.lanes);
        rays.truncate(0);
        lanes.truncate(0);
        lanes.bounces = 0;
        for ((offset, p, rng), _) in (s.portal_photons.iter())
            .zip(&s.occluded)
            .filter(|(_, blocked)| !**blocked)
        {
            let o = (p.point - p.dir * (2.0 * slack)).as_vec3();
            rays.push(o.into(), p.dir.as_vec3().into(), 0.0, f32::INFINITY);
            lanes.offset.push(*offset);
            lanes.segment.push(Segment::Emitted);
            lanes.rng.push(rng.clone());
            s.weight[*offset as usize] = p.weight;
        }
    }
}

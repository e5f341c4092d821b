//! The photon batch's state besides its rays: the live photons' lanes (structure of
//! arrays in ray order), where each one's segment started, the compaction of a bounce's
//! survivors in place, and the per-worker scratch buffers all passes share.

use crate::accel::{HitBatch, RayBatch};
use crate::surface::LobeKind;
use crate::tally::CellPartial;
use glam::Vec3;
use rand_pcg::Pcg32;

/// Per-worker buffers, reused from chunk to chunk (their contents never affect results).
#[derive(Default)]
pub struct Scratch {
    /// The live photons' rays: survivors are compacted in place after every bounce, in
    /// lane order, so the batch never changes order and nothing is copied twice.
    pub(super) rays: RayBatch,
    pub(super) hits: HitBatch,
    pub(super) lanes: Lanes,
    /// (photon offset in chunk, cell, score) before folding per history.
    pub(super) pending: Vec<(u32, u32, f64)>,
    /// Per-cell sums of the chunk's histories while folding.
    pub(super) cell_acc: Vec<CellPartial>,
    /// Next-event shadow rays of this bounce and what each scores if unoccluded.
    pub(super) shadow_rays: RayBatch,
    pub(super) shadow_scores: Vec<(u32, u32, f64)>,
    pub(super) occluded: Vec<bool>,
    /// Through glazing: each shadow ray's transmittance, and the caster's buffers.
    pub(super) through: Vec<f64>,
    pub(super) shadow: super::shadow::ShadowScratch,
    /// Diffuse survivors of a bounce, whose directions are sampled in a pass of their
    /// own (f32 lanes): their slots in the batch (each scatters into the hemisphere of
    /// its `side`), their two random numbers and their new directions.
    pub(super) diffuse_slot: Vec<u32>,
    pub(super) diffuse_draws: [Vec<f32>; 2],
    pub(super) diffuse_dir: [Vec<f32>; 3],
    /// Which segments of the batch cross the receiver being scored.
    pub(super) marks: Vec<bool>,
    /// Per survivor, the normal of the side it leaves its surface on.
    pub(super) side: [Vec<f32>; 3],
    /// Photons spawned through portals at this round's exterior vertices, traced in the
    /// next round ([`super::portal_photons`]).
    pub(super) spawns: Vec<Spawn>,
    pub(super) next_spawns: Vec<Spawn>,
}

/// A photon spawned at an exterior vertex through a portal: its history, ray, weight
/// and the portal its first segment must cross first.
#[derive(Clone, Debug)]
pub(super) struct Spawn {
    pub(super) offset: u32,
    pub(super) origin: Vec3,
    pub(super) dir: Vec3,
    pub(super) weight: f64,
    pub(super) portal: u32,
    pub(super) rng: Pcg32,
}

impl Scratch {
    /// Sizes the per-bounce arrays of pass 2 and 3 for `n` lanes.
    pub(super) fn size_bounce_arrays(&mut self, n: usize) {
        if self.diffuse_slot.len() < n {
            self.diffuse_slot.resize(n, 0);
        }
        for v in (self.side.iter_mut())
            .chain(&mut self.diffuse_draws)
            .chain(&mut self.diffuse_dir)
        {
            if v.len() < n {
                v.resize(n, 0.0);
            }
        }
    }
}

/// Which photons a batch holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Pass {
    /// The lights' own photons: they deposit on the triangles (the scene map) and are
    /// the histories counted by bounce; they score receivers with their weights.
    Map,
    /// Portal and spawned photons: they score receivers only.
    Receivers,
}

/// Where a photon's current segment started.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(super) enum Segment {
    /// At a light: its light on next-event receivers is the deterministic direct light.
    #[default]
    Emitted,
    /// At a diffuse or connectable glossy scattering: connected to next-event receivers
    /// beyond their near zone.
    Connectable,
    /// At a mirror, a refraction or a glossy lobe too sharp to connect.
    Specular,
}

impl Segment {
    /// The segment a scattering of `kind` starts: connected (diffuse, or glossy where
    /// the material's glossy lobe connects) or specular.
    pub(super) fn after(kind: LobeKind, glossy_connectable: bool) -> Segment {
        let connected = match kind {
            LobeKind::Diffuse => true,
            LobeKind::Glossy => glossy_connectable,
            LobeKind::Specular => false,
        };
        if connected {
            Segment::Connectable
        } else {
            Segment::Specular
        }
    }
}

/// The live photons' state besides their rays, structure of arrays in ray order.
#[derive(Default)]
pub(super) struct Lanes {
    /// Photon index within the chunk.
    pub(super) offset: Vec<u32>,
    /// Surface hits so far (the first is direct light, the rest indirect): the same for
    /// every live photon, since all start together and each bounce ends or advances
    /// every one of them.
    pub(super) bounces: u32,
    /// The chunk's first photon index.
    pub(super) first: u64,
    /// Where the current segment started.
    pub(super) segment: Vec<Segment>,
    pub(super) rng: Vec<Pcg32>,
    /// With portals: the weight of each photon's receiver scores (a disk photon's 1
    /// until a portal takes its light over, a portal photon's its share), and the
    /// [`PortalRule`] its current segment is checked by. Empty without portals.
    pub(super) weight: Vec<f64>,
    pub(super) rule: Vec<PortalRule>,
}

impl Lanes {
    pub(super) fn truncate(&mut self, n: usize) {
        self.offset.truncate(n);
        self.segment.truncate(n);
        self.rng.truncate(n);
        self.weight.truncate(n);
        self.rule.truncate(n);
    }

    /// The weight of lane `k`'s receiver scores: 1 without portals.
    #[inline(always)]
    pub(super) fn weight(&self, k: usize) -> f64 {
        self.weight.get(k).copied().unwrap_or(1.0)
    }
}

/// What a segment's portal crossings decide ([`super::Tracer::apply_portal_rules`]),
/// from where it started: the light it would carry in by a portal is some other
/// photon's, so it scores receivers (weight kept) only if:
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(super) enum PortalRule {
    /// always (a lamp's photon, a segment from an interior vertex);
    #[default]
    Free,
    /// it crosses no portal (a sky's or sun's disk photon: its portal photons carry
    /// what comes in straight);
    FromSky,
    /// the first portal it crosses is none of these (bits by portal index): it left an
    /// exterior vertex, which spawned photons through them;
    FromExterior(u32),
    /// the first portal it crosses is this one (a spawned photon's first segment).
    Spawned(u32),
}

/// The lanes a bounce's survivors are compacted into, in place: survivor `j` is written
/// from lane `k ≥ j`, so a lane is read before anything overwrites it.
pub(super) struct SurvivorLanes<'a> {
    pub(super) origin: [&'a mut [f32]; 3],
    /// The normal of the side the survivor leaves its surface on.
    pub(super) side: [&'a mut [f32]; 3],
    pub(super) offset: &'a mut [u32],
    pub(super) segment: &'a mut [Segment],
    pub(super) rng: &'a mut [Pcg32],
    /// Empty without portals.
    pub(super) weight: &'a mut [f64],
    pub(super) rule: &'a mut [PortalRule],
}

impl<'a> SurvivorLanes<'a> {
    /// The first `n` lanes of a batch's origins, survivors' sides and photon lanes.
    pub(super) fn of(
        n: usize,
        (ox, oy, oz): (&'a mut [f32], &'a mut [f32], &'a mut [f32]),
        [sx, sy, sz]: &'a mut [Vec<f32>; 3],
        lanes: &'a mut Lanes,
    ) -> Self {
        let weighted = n.min(lanes.weight.len());
        SurvivorLanes {
            origin: [&mut ox[..n], &mut oy[..n], &mut oz[..n]],
            side: [&mut sx[..n], &mut sy[..n], &mut sz[..n]],
            offset: &mut lanes.offset[..n],
            segment: &mut lanes.segment[..n],
            rng: &mut lanes.rng[..n],
            weight: &mut lanes.weight[..weighted],
            rule: &mut lanes.rule[..weighted],
        }
    }

    /// The weight of lane `k`'s receiver scores: 1 without portals.
    #[inline(always)]
    pub(super) fn weight(&self, k: usize) -> f64 {
        self.weight.get(k).copied().unwrap_or(1.0)
    }

    /// Survivor `j` (written from lane `k`) keeps the lane's weight, its new segment
    /// checked by `rule`; nothing without portals.
    #[inline(always)]
    pub(super) fn carry(&mut self, j: usize, k: usize, rule: PortalRule) {
        if !self.weight.is_empty() {
            self.weight[j] = self.weight[k];
            self.rule[j] = rule;
        }
    }

    /// Survivor `j`: it leaves `point` on the `side` of its surface.
    #[inline(always)]
    pub(super) fn write(
        &mut self,
        j: usize,
        point: Vec3,
        side: Vec3,
        offset: u32,
        segment: Segment,
        rng: Pcg32,
    ) {
        self.write_unsegmented(j, point, side, offset, rng);
        self.segment[j] = segment;
    }

    /// [`Self::write`] leaving the segment lane as it is: for a pass whose segments no
    /// receiver reads ([`super::Tracer::lambert_track`]).
    #[inline(always)]
    pub(super) fn write_unsegmented(
        &mut self,
        j: usize,
        point: Vec3,
        side: Vec3,
        offset: u32,
        rng: Pcg32,
    ) {
        let [ox, oy, oz] = &mut self.origin;
        (ox[j], oy[j], oz[j]) = (point.x, point.y, point.z);
        let [sx, sy, sz] = &mut self.side;
        (sx[j], sy[j], sz[j]) = (side.x, side.y, side.z);
        self.offset[j] = offset;
        self.rng[j] = rng;
    }
}

//! Pass 2 of a bounce: what happens where the batch's photons hit. Each hit is looked up
//! (the small scenes' [`TriangleSurface`] table, else the geometry), deposits on its
//! triangle, is connected to next-event receivers, and goes to the kernel of its
//! surface class ([`Surfacing`]), which plays the roulette and compacts the survivors.

use super::batch::{Lanes, Pass, PortalRule, Scratch, Segment, SurvivorLanes};
use super::scatter::scatter;
use super::Tracer;
use crate::accel::{RayBatch, Surface};
use crate::scene::Geometry;
use crate::surface::{Bsdf, Material};
use crate::tally::{deposit_code, ChunkTally};
use glam::{DVec3, Vec3};
use rand::RngCore;

/// QMC blocks in a chunk of photons.
const BLOCKS_PER_CHUNK: usize = (super::CHUNK_PHOTONS >> crate::rng::QMC_LOG2_BLOCK) as usize;

/// The QMC block (within its chunk) of the photon at chunk offset `offset`.
#[inline]
fn block_in_chunk(offset: u32) -> usize {
    (offset >> crate::rng::QMC_LOG2_BLOCK) as usize
}

/// A photon's hit as pass 2's kernels read it.
struct Hit<'s> {
    /// Its lane in the batch.
    k: usize,
    /// Photon index within the chunk.
    offset: u32,
    point: Vec3,
    /// The geometric normal on the side the photon arrived from.
    facing: Vec3,
    /// The photon's unit direction and the surface's unit geometric normal.
    dir: DVec3,
    normal: DVec3,
    surfacing: &'s Surfacing,
    /// The portal rule of a connected segment leaving this vertex: which portals'
    /// light it leaves to the photons spawned here.
    rule_after: PortalRule,
}

/// How far pass 2 has written each of its outputs: histories that end at this bounce
/// (rays that left the scene; photons absorbed or stopped by the bounce cap),
/// survivors (lane k's successor is written at j ≤ k), diffuse survivors' slots and
/// deposits.
#[derive(Clone, Copy, Default)]
struct HitCursors {
    escaped: u64,
    ended: u64,
    survivors: usize,
    diffuse: usize,
    deposits: usize,
}

impl HitCursors {
    /// The pass's survivors, diffuse survivors and ended histories over `n` hits. In a
    /// [`Tracer::lambert_track`] pass below the cap every hit escaped, survived or
    /// ended, and every survivor scatters diffusely: the loop counted neither.
    fn totals(self, n: usize, lambert_track: bool) -> (usize, usize, u64) {
        if lambert_track {
            let ended = (n - self.survivors) as u64 - self.escaped;
            (self.survivors, self.survivors, ended)
        } else {
            (self.survivors, self.diffuse, self.ended)
        }
    }
}

/// What pass 2 writes: the survivors compacted in place with their new directions (the
/// general kernel's; the diffuse ones' come in pass 3), the slots of the diffuse
/// survivors, the hits' deposits, and how far each is written.
struct HitsOut<'a> {
    survivors: SurvivorLanes<'a>,
    dir: [&'a mut [f32]; 3],
    /// Written for every hit and kept by advancing the cursor where the triangle holds
    /// a map: no branch.
    deposits: &'a mut [u32],
    /// Written for every Lambertian hit and kept by advancing the cursor, so the
    /// roulette is no branch.
    diffuse_slot: &'a mut [u32],
    cursors: HitCursors,
}

impl<'a> HitsOut<'a> {
    /// Pass 2's outputs over the first `n` lanes of the batch, nothing written yet.
    fn new(
        n: usize,
        rays: &'a mut RayBatch,
        side: &'a mut [Vec<f32>; 3],
        lanes: &'a mut Lanes,
        deposits: &'a mut [u32],
        diffuse_slot: &'a mut [u32],
    ) -> Self {
        HitsOut {
            survivors: SurvivorLanes::of(
                n,
                (&mut rays.ox, &mut rays.oy, &mut rays.oz),
                side,
                lanes,
            ),
            dir: [&mut rays.dx[..n], &mut rays.dy[..n], &mut rays.dz[..n]],
            deposits,
            diffuse_slot: &mut diffuse_slot[..n],
            cursors: HitCursors::default(),
        }
    }

    #[inline(always)]
    fn deposit(&mut self, code: u32, kept: bool) {
        self.deposits[self.cursors.deposits] = code;
        self.cursors.deposits += kept as usize;
    }

    /// The kernel of a grey Lambertian reflector in a pass no receiver reads segments
    /// of ([`Tracer::lambert_track`]): the [`Self::lambertian`] roulette with less to
    /// keep: every survivor scatters diffusely (so survivor j is diffuse survivor j,
    /// and pass 3 reads no slots), a hit that is not kept ended (counted after the
    /// loop), and the segment lane is left as it is: with no receiver connecting,
    /// every segment scores by crossing whatever it started at.
    #[inline(always)]
    fn lambert_track(&mut self, hit: &Hit) {
        let j = self.cursors.survivors;
        let mut rng = self.survivors.rng[hit.k].clone();
        let survives = (rng.next_u32() as u64) < hit.surfacing.survives_below;
        self.survivors
            .write_unsegmented(j, hit.point, hit.facing, hit.offset, rng);
        self.cursors.survivors += survives as usize;
    }

    /// The kernel of a material whose only lobe is diffuse reflection: `Bsdf::sample`'s
    /// roulette and diffuse lobe, the same draws (the direction's in f32 in pass 3,
    /// into the hemisphere the photon arrived from). The slot is written whatever the
    /// roulette says and kept if the photon survives. The stream is copied before its
    /// draw: a 16-byte load of what the draw just stored 8 bytes of would wait for it.
    #[inline(always)]
    fn lambertian(&mut self, hit: &Hit) {
        let c = &mut self.cursors;
        let j = c.survivors;
        let mut rng = self.survivors.rng[hit.k].clone();
        let survives = (rng.next_u32() as u64) < hit.surfacing.survives_below;
        let (point, facing) = (hit.point, hit.facing);
        self.survivors
            .write(j, point, facing, hit.offset, Segment::Connectable, rng);
        self.survivors.carry(j, hit.k, hit.rule_after);
        self.diffuse_slot[c.diffuse] = j as u32;
        let kept = survives as usize;
        c.ended += !survives as u64;
        c.survivors += kept;
        c.diffuse += kept;
    }

    /// The kernel of any other material: the BSDF's roulette over its lobes
    /// ([`scatter`]), the new direction written here.
    #[inline(always)]
    fn general(&mut self, hit: &Hit) {
        let mut rng = self.survivors.rng[hit.k].clone();
        let Some(sample) = scatter(&hit.surfacing.bsdf, hit.dir, hit.normal, &mut rng) else {
            self.cursors.ended += 1;
            return;
        };
        let j = self.cursors.survivors;
        let side = if sample.transmitted {
            -hit.facing
        } else {
            hit.facing
        };
        let w = sample.dir.as_vec3();
        let [dx, dy, dz] = &mut self.dir;
        (dx[j], dy[j], dz[j]) = (w.x, w.y, w.z);
        // A pane passes light on unbent, and next events and connections see through
        // it: the segment stays what it was (emitted light still direct, light from a
        // connected vertex still connected, its near zone now from the pane).
        let through_pane = sample.transmitted && hit.surfacing.see_through;
        let (segment, rule) = if through_pane {
            (self.survivors.segment[hit.k], PortalRule::Free)
        } else {
            match Segment::after(sample.kind, hit.surfacing.glossy_connectable) {
                Segment::Connectable => (Segment::Connectable, hit.rule_after),
                other => (other, PortalRule::Free),
            }
        };
        self.survivors
            .write(j, hit.point, side, hit.offset, segment, rng);
        self.survivors.carry(j, hit.k, rule);
        self.cursors.survivors += 1;
    }
}

/// Scenes up to this many triangles get a [`TriangleSurface`] table (≤ 2.6 MB): on a
/// small scene the hit's surface lookup is a chain of dependent loads (triangle →
/// vertex indices → vertices) that dominates the tracer's own work; on a large one the
/// table would cost 40 B per triangle, against the memory goal, where cache misses in
/// the ray caster dominate anyway.
pub const SURFACE_TABLE_MAX_TRIANGLES: usize = 1 << 16;

/// Bytes per triangle of that table (`limits` counts it in a run's memory).
pub const SURFACE_TABLE_BYTES_PER_TRIANGLE: usize = std::mem::size_of::<TriangleSurface>();

/// A triangle's first vertex, its two edges from it and its material, for
/// [`Surface::mapped`] (as [`crate::accel::HitBatch::surface`] calls it: the same bits),
/// one load from the triangle id instead of two dependent ones.
#[derive(Clone, Copy, Debug)]
pub(super) struct TriangleSurface {
    pub(super) a: Vec3,
    pub(super) e1: Vec3,
    pub(super) e2: Vec3,
    pub(super) material: u32,
}

impl TriangleSurface {
    /// The table for `g`, or an empty one above [`SURFACE_TABLE_MAX_TRIANGLES`].
    pub(super) fn table(g: &Geometry) -> Vec<TriangleSurface> {
        if g.triangle_count() > SURFACE_TABLE_MAX_TRIANGLES {
            return Vec::new();
        }
        (g.triangles.iter().enumerate())
            .map(|(t, tri)| {
                let [a, b, c] = tri.map(|i| g.vertices[i as usize]);
                TriangleSurface {
                    a,
                    e1: b - a,
                    e2: c - a,
                    material: g.material.get(t),
                }
            })
            .collect()
    }
}

/// What the photon pass needs of a material, looked up once per hit: the BSDF and the
/// flags that decide its path through a bounce, so the common case (a grey Lambertian
/// reflector) skips the general lobe roulette.
#[derive(Clone, Debug)]
pub(super) struct Surfacing {
    pub(super) bsdf: Bsdf,
    /// Connected to next-event receivers ([`Bsdf::connectable`]).
    pub(super) connectable: bool,
    /// Its glossy lobes are connected ([`Bsdf::glossy_connectable`]).
    pub(super) glossy_connectable: bool,
    /// Diffuse reflection is its only lobe: the roulette is one comparison with ρ
    /// (the same number [`Bsdf::sample`] draws and compares, so the same path).
    pub(super) lambert_only: bool,
    /// A photon survives that roulette when its 32-bit draw x is below this:
    /// x < ⌈ρ·2³²⌉ ⇔ x·2⁻³² < ρ, [`crate::sampling::uniform`]'s comparison, in integers.
    pub(super) survives_below: u64,
    /// Thin glazing: light it transmits goes on unbent, as next events' shadow rays
    /// see it ([`super::shadow`]).
    pub(super) see_through: bool,
}

impl Surfacing {
    pub(super) fn new(m: &Material) -> Surfacing {
        let bsdf = Bsdf::new(m);
        Surfacing {
            see_through: m.glazing.is_some(),
            connectable: bsdf.connectable(),
            glossy_connectable: bsdf.glossy_connectable(),
            lambert_only: bsdf.lambert_only(),
            survives_below: survival_threshold(bsdf.diffuse().0),
            bsdf,
        }
    }
}

/// ⌈ρ·2³²⌉: for every 32-bit x, x < it exactly when x·2⁻³² < ρ (both sides exact in
/// f64: ρ·2³² is ρ scaled by a power of two, x·2⁻³² a 32-bit integer scaled).
pub(super) fn survival_threshold(rho: f64) -> u64 {
    (rho.clamp(0.0, 1.0) * 4_294_967_296.0).ceil() as u64
}

impl Tracer<'_> {
    /// Pass 2 of [`Tracer::step`]: deposit, connect and play the roulette at each hit,
    /// compacting the survivors in place. Returns how many survive and how many of them
    /// scatter diffusely (their slots in `s.diffuse_slot`). Each hit goes to the kernel
    /// of its surface class ([`HitsOut::lambert_track`], [`HitsOut::lambertian`],
    /// [`HitsOut::general`]), as pbrt's wavefront integrator gives each material its own.
    /// `LAMBERT_TRACK`: [`Tracer::lambert_track`], which removes the connection and
    /// the other kernels from the loop at compile time (the same numbers).
    pub(super) fn hits_pass<const LAMBERT_TRACK: bool>(
        &self,
        s: &mut Scratch,
        tally: &mut ChunkTally,
        flux: f64,
        odd_first: bool,
        pass: Pass,
    ) -> (usize, usize) {
        let (n, hits, rays) = (s.rays.len(), &s.hits, &mut s.rays);
        // Every live photon has hit as often: the first hit is direct light, and so is
        // a later one of an emitted segment (passed on straight by glazing).
        let hit_bounces = s.lanes.bounces;
        let first_photon = s.lanes.first;
        let capped = hit_bounces >= self.max_bounces;
        let map = pass == Pass::Map;
        let first_deposit = tally.deposits.len();
        tally.deposits.resize(first_deposit + n, 0);
        let mut out = HitsOut::new(
            n,
            rays,
            &mut s.side,
            &mut s.lanes,
            &mut tally.deposits[first_deposit..],
            &mut s.diffuse_slot,
        );
        // A QMC run's later connections are numbered by rank in their block: each block's
        // first lane, read before the loop compacts the lanes (they are in photon order).
        let ranked = self.qmc && map && hit_bounces > 0;
        let mut block_first_lane = [0; BLOCKS_PER_CHUNK];
        if ranked {
            let offsets = &out.survivors.offset[..n];
            for (b, first) in block_first_lane.iter_mut().enumerate() {
                *first = offsets.partition_point(|&o| block_in_chunk(o) < b);
            }
        }
        // The hits, sliced to the batch: no bounds check in the loop.
        let (hit_tri, hit_u, hit_v) = (&hits.tri[..n], &hits.u[..n], &hits.v[..n]);
        let (ngx, ngy, ngz) = (&hits.ngx[..n], &hits.ngy[..n], &hits.ngz[..n]);
        for k in 0..n {
            let tri = hit_tri[k];
            let surface = if let Some(row) = self.surface_table.get(tri as usize) {
                let normal = Vec3::new(ngx[k], ngy[k], ngz[k]);
                let (corner, uv) = ([row.a, row.e1, row.e2], (hit_u[k], hit_v[k]));
                Surface::mapped(tri, corner, row.material, uv, normal)
            } else if let Some(surface) = hits.surface(k, self.geometry) {
                surface
            } else {
                out.cursors.escaped += 1;
                continue;
            };
            let [dx, dy, dz] = &out.dir;
            let dir = DVec3::new(dx[k] as f64, dy[k] as f64, dz[k] as f64);
            let offset = out.survivors.offset[k];
            let normal = surface.normal;
            let back_face = dir.dot(normal.as_dvec3()) > 0.0;
            // Unmapped (instanced) objects scatter and occlude but hold no tallies.
            let (tri, has_map) = (surface.mapped.unwrap_or(0), surface.mapped.is_some());
            let odd = (offset % 2 == 1) != odd_first;
            let indirect = if LAMBERT_TRACK {
                hit_bounces > 0
            } else {
                out.survivors.segment[k] != Segment::Emitted
            };
            out.deposit(deposit_code(tri, back_face, indirect, odd), has_map && map);
            let surfacing = &self.surfacings[surface.material as usize];
            let weight = out.survivors.weight(k);
            if !LAMBERT_TRACK && self.any_connects && surfacing.connectable && weight > 0.0 {
                let rank = ranked.then(|| (k - block_first_lane[block_in_chunk(offset)]) as u32);
                self.connect(
                    surface.point,
                    normal,
                    -dir,
                    surfacing,
                    (offset, &mut out.survivors.rng[k]),
                    (first_photon + offset as u64, hit_bounces, !map, rank),
                    (flux * weight, !indirect),
                    &mut s.shadow_rays,
                    &mut s.shadow_scores,
                );
            }
            if capped {
                tally.killed_by_bounce_cap += map as u64;
                out.cursors.ended += 1;
                continue;
            }
            let mut rule_after = PortalRule::Free;
            if !LAMBERT_TRACK && surfacing.connectable && weight > 0.0 {
                let exterior = self.exterior_of(surface.point);
                if exterior != 0 {
                    rule_after = PortalRule::FromExterior(exterior);
                    self.spawn(
                        (surface.point, normal, -dir),
                        surfacing,
                        (offset, weight, &mut out.survivors.rng[k]),
                        exterior,
                        &mut s.next_spawns,
                    );
                }
            }
            let hit = Hit {
                k,
                offset,
                point: surface.point,
                facing: if back_face { -normal } else { normal },
                dir,
                normal: normal.as_dvec3(),
                surfacing,
                rule_after,
            };
            if LAMBERT_TRACK {
                out.lambert_track(&hit);
            } else if surfacing.lambert_only {
                out.lambertian(&hit);
            } else {
                out.general(&hit);
            }
        }
        let c = out.cursors;
        let (survivors, diffuse, ended) = c.totals(n, LAMBERT_TRACK && !capped);
        tally.deposits.truncate(first_deposit + c.deposits);
        if map {
            tally.record_histories(hit_bounces, c.escaped);
            tally.record_histories(hit_bounces + 1, ended);
        }
        (survivors, diffuse)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_roulette_is_the_float_comparison() {
        // x < ⌈ρ·2³²⌉ ⇔ x·2⁻³² < ρ for every 32-bit x: checked at the threshold and its
        // neighbours, for ρ at the ends, at powers of two and at odd values.
        for rho in [0.0, 1e-12, 0.3, 0.5, 0.7, 0.95, 1.0 - 1e-12, 1.0] {
            let t = survival_threshold(rho);
            let mid = t.min(u32::MAX as u64) as i64;
            for x in (mid - 3..=mid + 3).filter(|x| (0..=u32::MAX as i64).contains(x)) {
                let float = x as f64 * (1.0 / 4_294_967_296.0) < rho;
                assert_eq!((x as u64) < t, float, "ρ {rho}, x {x}");
            }
            assert_eq!(0 < t, rho > 0.0);
        }
        assert_eq!(
            survival_threshold(1.0),
            1 << 32,
            "ρ = 1: every photon survives"
        );
    }
}

//! Receiver geometry, the *where* of a receiver's tally: which cell a point of it lies
//! in, what light arriving in a given direction is worth to its quantity, and its
//! points. How photons reach it (crossings, connections) is `trace::receiver_reach`'s.

use crate::scene::{Estimator, Quantity, Receiver};
use glam::DVec3;
use std::f64::consts::{FRAC_1_PI, TAU};

/// A receiver prepared for scoring, in the scene's local frame.
#[derive(Clone, Debug)]
pub struct ReceiverGrid {
    pub name: String,
    pub(crate) corner: DVec3,
    pub(crate) u: DVec3,
    pub(crate) v: DVec3,
    /// Unit normal u × v / |u × v|: the illuminated face for illuminance.
    pub normal: DVec3,
    /// Dual vectors: (p − corner)·du and ·dv are p's coordinates along u and v in [0, 1).
    pub(crate) du: DVec3,
    pub(crate) dv: DVec3,
    pub cells: [u32; 2],
    pub area_m2: f64,
    pub cell_area_m2: f64,
    pub(crate) kind: Kind,
    /// Index of this receiver's first cell among all receivers' cells.
    pub first_cell: u32,
    /// How it is scored: `Track` or `NextEvent` (sampled direct light, connections),
    /// never `Auto`.
    pub estimator: Estimator,
    /// Next-event connections per diffuse vertex, in as many strata of the receiver.
    pub connections: u32,
    /// Each cell scores the value at its centre (`values = "point"`; next-event only).
    pub points: bool,
    /// Vertices closer than this (one cell diagonal) to a receiver point are not
    /// connected to it; their photons score by crossing instead. The cylinders have
    /// none: their crossing score, response/|cos θ|, is unbounded at grazing angles
    /// (infinite variance: on the bundled EN 12464-1 office some cells' VOV stayed
    /// above 0.1 after 2·10⁷ photons), while a connection's 1/d² stays bounded unless a
    /// surface comes close to the receiver (which the VOV then flags).
    pub near_zone_m: f64,
}

/// Next-event connections per vertex: one per 256 cells, 1 to 16. On the office desk
/// (2048 cells) the photons needed for a given error fall as 1/connections up to 16
/// (point sampling dominates the variance there), and time is lowest near 8.
pub fn connections_for(cells: usize) -> u32 {
    cells.div_ceil(256).clamp(1, 16) as u32
}

/// Next-event connections per vertex of a QMC run (`trace::Tracer::with_qmc`): one per
/// 64 cells, 1 to 32; one per 20 cells, 1 to 32, where every source's emission takes its
/// direction from the QMC point (`stratified_emission`: the first connections are then
/// stratified jointly with the directions). Stratified over a block, each connection buys
/// far more: the desk's error² × rays at equal photons (QMC, 6 seeds) was 400 with 8, 166
/// with 16, 115 with 32 and 114 with 64 (ordinary runs: 1183 with 8, 948 with 32);
/// Cornell's floor (1024 cells, an area light: emission not stratified) 4206 with 4, 3915
/// with 16, 4699 with 32 (blocks of 4096), and at 1 % per cell 41.8 M rays with 16
/// against 48.4 M with 32 (blocks of 2048); the luminaires' work plane (640 cells,
/// stratified emission), at 1 % per cell, 5.63 M rays with 10, 4.76 M with 20, 4.34 M
/// with 32, 6.06 M with 64 (before later connections by rank; with them, 3.97–4.18 M with
/// 32, and 3.55 M once the direct light's replicates took QMC patterns). A scene with
/// `caustics` (mirrors or glass carry light to receivers, scored by crossing, which
/// connections do not help) keeps [`connections_for`]: the glass floor (2304 cells) took
/// 29.4 M rays to 1 % per cell with 32, 12.2 M with 9.
pub fn qmc_connections_for(cells: usize, stratified_emission: bool, caustics: bool) -> u32 {
    if caustics {
        return connections_for(cells);
    }
    let cells_per_connection = if stratified_emission { 20 } else { 64 };
    cells.div_ceil(cells_per_connection).clamp(1, 32) as u32
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum Kind {
    Illuminance,
    Luminance {
        /// Direction light travels to reach the meter (−view_direction).
        towards_meter: DVec3,
        cos_half_angle: f64,
        solid_angle_sr: f64,
    },
    /// A small vertical cylinder at each point: [`cylinder_response`] without a facing.
    Cylindrical,
    /// The half of it facing `facing` (horizontal unit vector).
    SemiCylindrical {
        facing: DVec3,
    },
}

/// What light arriving from unit direction `towards_source` (from the receiver point
/// towards where the light comes from) gives an infinitesimal vertical cylinder (axis
/// world z), per unit of illuminance on a plane facing the light (I/d²):
/// (|s_h| + s_h·f)/π, s_h the horizontal part of `towards_source`, |s_h| = sin θ from
/// the vertical. `facing` is zero for the whole cylinder (cylindrical illuminance,
/// sin θ/π: the mean over the curved surface, whose projection towards the light is
/// 2rh·sin θ of its 2πrh) and the unit horizontal normal of the half's middle for the
/// semi-cylinder (sin θ·(1 + cos α)/π, α the horizontal angle between the facing and
/// the light: its lit projection over its πrh). Light from above and below counts alike.
#[inline]
pub fn cylinder_response(towards_source: DVec3, facing: DVec3) -> f64 {
    let (x, y) = (towards_source.x, towards_source.y);
    ((x * x + y * y).sqrt() + x * facing.x + y * facing.y).max(0.0) * FRAC_1_PI
}

impl ReceiverGrid {
    /// Prepares `r` for a frame whose origin is at world position `origin`.
    pub fn new(r: &Receiver, origin: DVec3, first_cell: u32, estimator: Estimator) -> ReceiverGrid {
        let cross = r.u.cross(r.v);
        let area = cross.length();
        let normal = cross / area;
        let kind = match r.quantity {
            Quantity::Illuminance => Kind::Illuminance,
            Quantity::Luminance {
                view_direction,
                half_angle_deg,
            } => {
                let cos_half_angle = libm::cos(half_angle_deg.to_radians());
                Kind::Luminance {
                    towards_meter: -view_direction.normalize(),
                    cos_half_angle,
                    solid_angle_sr: TAU * (1.0 - cos_half_angle),
                }
            }
            Quantity::Cylindrical => Kind::Cylindrical,
            Quantity::SemiCylindrical { facing } => Kind::SemiCylindrical { facing },
        };
        ReceiverGrid {
            name: r.name.clone(),
            corner: r.corner - origin,
            u: r.u,
            v: r.v,
            normal,
            du: r.v.cross(normal) / area,
            dv: normal.cross(r.u) / area,
            cells: r.cells,
            area_m2: area,
            cell_area_m2: area / (r.cells[0] as f64 * r.cells[1] as f64),
            kind,
            first_cell,
            estimator,
            connections: connections_for(r.cell_count()),
            points: r.points,
            // A point has no area to cross: every vertex connects to it.
            near_zone_m: if r.points
                || matches!(kind, Kind::Cylindrical | Kind::SemiCylindrical { .. })
            {
                0.0
            } else {
                libm::hypot(
                    r.u.length() / r.cells[0] as f64,
                    r.v.length() / r.cells[1] as f64,
                )
            },
        }
    }

    /// A luminance meter whose direct light is sampled: it samples the sources' light
    /// reflected towards it by the surfaces it sees too (`trace::reflected`).
    pub fn samples_reflected_direct(&self) -> bool {
        self.is_luminance() && self.estimator.direct_by_replicates()
    }

    /// A luminance meter (its connections are directions of its cone).
    pub fn is_luminance(&self) -> bool {
        matches!(self.kind, Kind::Luminance { .. })
    }

    pub fn cell_count(&self) -> usize {
        self.cells[0] as usize * self.cells[1] as usize
    }

    /// What light travelling in unit direction `dir` is worth at the receiver, per unit
    /// of intensity over squared distance (cd/m² → the receiver's unit): cos θ on the
    /// front face for illuminance, 1/Ω inside the meter's cone for luminance (the meter
    /// reads the mean luminance over its cone), [`cylinder_response`] of the light's
    /// origin −`dir` from either side for the cylinders. `None` when it does not count.
    /// Every estimator goes through it: crossings (over |cos θ_n| per cell area),
    /// connections and the sampled direct light (times 1/d²).
    #[inline]
    pub fn arrival_factor(&self, dir: DVec3) -> Option<f64> {
        let positive = |f: f64| (f > 0.0).then_some(f);
        match self.kind {
            Kind::Illuminance => positive(-dir.dot(self.normal)),
            Kind::Cylindrical => positive(cylinder_response(-dir, DVec3::ZERO)),
            Kind::SemiCylindrical { facing } => positive(cylinder_response(-dir, facing)),
            Kind::Luminance {
                towards_meter,
                cos_half_angle,
                solid_angle_sr,
            } => (dir.dot(towards_meter) >= cos_half_angle && dir.dot(self.normal) != 0.0)
                .then(|| 1.0 / solid_angle_sr),
        }
    }

    /// The global index of the cell at receiver coordinates (a, b) ∈ [0, 1)².
    #[inline]
    pub fn cell_at(&self, a: f64, b: f64) -> u32 {
        let i = ((a * self.cells[0] as f64) as u32).min(self.cells[0] - 1);
        let j = ((b * self.cells[1] as f64) as u32).min(self.cells[1] - 1);
        self.first_cell + j * self.cells[0] + i
    }

    /// The local-frame point at receiver coordinates (a, b).
    #[inline]
    pub fn point_at(&self, a: f64, b: f64) -> DVec3 {
        self.corner + self.u * a + self.v * b
    }

    /// The local-frame point (a, b) ∈ [0, 1]² of cell (i, j) (a corner of it at (0, 0));
    /// a point receiver's cells have only their centre.
    #[inline]
    pub fn cell_point(&self, (i, j): (u32, u32), a: f64, b: f64) -> DVec3 {
        let (a, b) = if self.points { (0.5, 0.5) } else { (a, b) };
        let (nu, nv) = (self.cells[0] as f64, self.cells[1] as f64);
        self.point_at((i as f64 + a) / nu, (j as f64 + b) / nv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Estimator;

    fn desk() -> Receiver {
        Receiver {
            name: "desk".into(),
            corner: DVec3::new(1.0, 2.0, 0.5),
            u: DVec3::new(2.0, 0.0, 0.0),
            v: DVec3::new(0.0, 1.0, 0.0),
            cells: [4, 2],
            quantity: Quantity::Illuminance,
            estimator: Estimator::Track,
            grid: None,
            points: false,
            exclude: Vec::new(),
        }
    }

    #[test]
    fn cylinder_response_is_sin_theta_over_pi_and_the_semi_cylinder_adds_its_facing() {
        let pi = std::f64::consts::PI;
        let f = DVec3::X;
        // From straight above or below: nothing. From the horizon: 1/π.
        assert_eq!(cylinder_response(DVec3::Z, DVec3::ZERO), 0.0);
        assert_eq!(cylinder_response(-DVec3::Z, f), 0.0);
        assert!((cylinder_response(DVec3::Y, DVec3::ZERO) - 1.0 / pi).abs() < 1e-15);
        // 30° from the vertical, the source 60° round from the facing:
        // sin 30°·(1 + cos 60°)/π.
        let (t, a) = (30f64.to_radians(), 60f64.to_radians());
        let s = DVec3::new(
            libm::sin(t) * libm::cos(a),
            libm::sin(t) * libm::sin(a),
            libm::cos(t),
        );
        assert!((cylinder_response(s, DVec3::ZERO) - 0.5 / pi).abs() < 1e-15);
        assert!((cylinder_response(s, f) - 0.5 * 1.5 / pi).abs() < 1e-15);
        // From behind the half-cylinder: nothing; from below as from above.
        assert_eq!(cylinder_response(DVec3::new(-1.0, 0.0, 0.3), f), 0.0);
        let below = DVec3::new(s.x, s.y, -s.z);
        assert_eq!(cylinder_response(below, f), cylinder_response(s, f));
    }

    #[test]
    fn a_cylindrical_receiver_scores_crossings_from_both_faces() {
        let mut r = desk();
        r.quantity = Quantity::Cylindrical;
        let g = ReceiverGrid::new(&r, DVec3::new(1.0, 1.0, 0.0), 10, Estimator::Track);
        // Through (0.6, 1.7, 0.5) local (cell (1, 1)) at 45° from the vertical, down
        // and then up.
        let dir = DVec3::new(1.0, 0.0, -1.0).normalize();
        let p = DVec3::new(0.6, 1.7, 0.5);
        let down = g.crossing(p - dir * 2.0, dir, 0.0, 10.0).unwrap();
        let up_dir = DVec3::new(dir.x, dir.y, -dir.z);
        let up = g.crossing(p - up_dir * 2.0, up_dir, 0.0, 10.0).unwrap();
        assert_eq!((down.cell, up.cell), (10 + 4 + 1, 10 + 4 + 1));
        // sin θ/(π·|cos θ|·A_cell) = 1/(π·0.25) at 45°.
        let expected = 1.0 / (std::f64::consts::PI * 0.25);
        assert!((down.score_per_lm - expected).abs() < 1e-12);
        assert_eq!(up.score_per_lm, down.score_per_lm);
        // Straight down: a vertical cylinder sees nothing of it.
        assert!(g.crossing(p + DVec3::Z, -DVec3::Z, 0.0, 10.0).is_none());
        // A semi-cylinder facing the light's origin gets twice as much, one facing
        // away nothing.
        r.quantity = Quantity::SemiCylindrical { facing: -DVec3::X };
        let g = ReceiverGrid::new(&r, DVec3::new(1.0, 1.0, 0.0), 10, Estimator::Track);
        let c = g.crossing(p - dir * 2.0, dir, 0.0, 10.0).unwrap();
        assert!((c.score_per_lm - 2.0 * expected).abs() < 1e-12);
        r.quantity = Quantity::SemiCylindrical { facing: DVec3::X };
        let g = ReceiverGrid::new(&r, DVec3::new(1.0, 1.0, 0.0), 10, Estimator::Track);
        assert!(g.crossing(p - dir * 2.0, dir, 0.0, 10.0).is_none());
    }

    #[test]
    fn downward_ray_scores_in_the_cell_below_it() {
        let g = ReceiverGrid::new(&desk(), DVec3::new(1.0, 1.0, 0.0), 10, Estimator::Track);
        // World (2.6, 2.7) → a = 0.8, b = 0.7 → cell (3, 1).
        let o = DVec3::new(1.6, 1.7, 3.0);
        let c = g.crossing(o, -DVec3::Z, 0.0, 10.0).unwrap();
        assert_eq!(c.cell, 10 + 4 + 3);
        assert!((c.score_per_lm - 1.0 / 0.25).abs() < 1e-12);
        assert!(
            g.crossing(o, -DVec3::Z, 0.0, 2.0).is_none(),
            "stops before the plane"
        );
        assert!(
            g.crossing(o - DVec3::Z * 4.0, DVec3::Z, 0.0, 10.0)
                .is_none(),
            "back face"
        );
        assert_eq!(g.cell_at(0.8, 0.7), c.cell);
        assert_eq!(g.point_at(0.8, 0.7), DVec3::new(1.6, 1.7, 0.5));
    }
}

//! Receiver geometry, the *where* of a receiver's tally: which cell a point of it lies
//! in, what light arriving in a given direction is worth to its quantity, and its
//! points. How photons reach it (crossings, connections) is `trace::receiver_reach`'s.

use crate::scene::{Estimator, Quantity, Receiver};
use glam::DVec3;
use std::f64::consts::TAU;

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
    /// Vertices closer than this (one cell diagonal) to a receiver point are not
    /// connected to it; their photons score by crossing instead.
    pub near_zone_m: f64,
}

/// Next-event connections per vertex: one per 256 cells, 1 to 16. On the office desk
/// (2048 cells) the photons needed for a given error fall as 1/connections up to 16
/// (point sampling dominates the variance there), and time is lowest near 8.
pub fn connections_for(cells: usize) -> u32 {
    cells.div_ceil(256).clamp(1, 16) as u32
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
            near_zone_m: libm::hypot(
                r.u.length() / r.cells[0] as f64,
                r.v.length() / r.cells[1] as f64,
            ),
        }
    }

    pub fn cell_count(&self) -> usize {
        self.cells[0] as usize * self.cells[1] as usize
    }

    /// What light travelling in unit direction `dir` is worth at the receiver, per unit
    /// of intensity over squared distance (cd/m² → the receiver's unit): cos θ on the
    /// front face for illuminance, 1/Ω inside the meter's cone for luminance (the meter
    /// reads the mean luminance over its cone). `None` when it does not count.
    #[inline]
    pub fn arrival_factor(&self, dir: DVec3) -> Option<f64> {
        match self.kind {
            Kind::Illuminance => {
                let cos = -dir.dot(self.normal);
                (cos > 0.0).then_some(cos)
            }
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

    /// The local-frame point (a, b) ∈ [0, 1]² of cell (i, j) (a corner of it at (0, 0)).
    #[inline]
    pub fn cell_point(&self, (i, j): (u32, u32), a: f64, b: f64) -> DVec3 {
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
        }
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

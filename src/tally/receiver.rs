//! Receiver geometry: which cell a ray segment crosses, and what it scores there.

use crate::scene::{Quantity, Receiver};
use glam::DVec3;
use std::f64::consts::TAU;

/// A receiver prepared for scoring, in the scene's local frame.
#[derive(Clone, Debug)]
pub struct ReceiverGrid {
    pub name: String,
    corner: DVec3,
    /// Unit normal u × v / |u × v|: the illuminated face for illuminance.
    normal: DVec3,
    /// Dual vectors: (p − corner)·du and ·dv are p's coordinates along u and v in [0, 1).
    du: DVec3,
    dv: DVec3,
    pub cells: [u32; 2],
    pub cell_area_m2: f64,
    kind: Kind,
    /// Index of this receiver's first cell among all receivers' cells.
    pub first_cell: u32,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Illuminance,
    Luminance {
        /// Direction light travels to reach the meter (−view_direction).
        towards_meter: DVec3,
        cos_half_angle: f64,
        solid_angle_sr: f64,
    },
}

/// A segment's crossing of a receiver cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Global cell index.
    pub cell: u32,
    /// Score of a photon of unit flux (lm): 1/A_cell for illuminance,
    /// 1/(A_cell·cos θ·Ω) for luminance.
    pub score_per_lm: f64,
}

impl ReceiverGrid {
    /// Prepares `r` for a frame whose origin is at world position `origin`.
    pub fn new(r: &Receiver, origin: DVec3, first_cell: u32) -> ReceiverGrid {
        let cross = r.u.cross(r.v);
        let area = cross.length();
        let normal = cross / area;
        let kind = match r.quantity {
            Quantity::Illuminance => Kind::Illuminance,
            Quantity::Luminance {
                view_direction,
                half_angle_deg,
            } => {
                let cos_half_angle = half_angle_deg.to_radians().cos();
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
            normal,
            du: r.v.cross(normal) / area,
            dv: normal.cross(r.u) / area,
            cells: r.cells,
            cell_area_m2: area / (r.cells[0] as f64 * r.cells[1] as f64),
            kind,
            first_cell,
        }
    }

    pub fn cell_count(&self) -> usize {
        self.cells[0] as usize * self.cells[1] as usize
    }

    /// The cell the segment `origin + t·dir`, `0 < t ≤ t_max` (`dir` unit), crosses and
    /// its score, if it scores: illuminance counts light arriving on the front face,
    /// luminance light travelling towards the meter within its cone.
    #[inline]
    pub fn crossing(&self, origin: DVec3, dir: DVec3, t_max: f64) -> Option<Crossing> {
        let cos_n = dir.dot(self.normal);
        let weight = match self.kind {
            Kind::Illuminance => {
                if cos_n >= 0.0 {
                    return None;
                }
                1.0
            }
            Kind::Luminance {
                towards_meter,
                cos_half_angle,
                solid_angle_sr,
            } => {
                if dir.dot(towards_meter) < cos_half_angle || cos_n == 0.0 {
                    return None;
                }
                1.0 / (cos_n.abs() * solid_angle_sr)
            }
        };
        let t = (self.corner - origin).dot(self.normal) / cos_n;
        if !(t > 0.0 && t <= t_max) {
            return None;
        }
        let rel = origin + dir * t - self.corner;
        let (a, b) = (rel.dot(self.du), rel.dot(self.dv));
        if !(0.0..1.0).contains(&a) || !(0.0..1.0).contains(&b) {
            return None;
        }
        let i = ((a * self.cells[0] as f64) as u32).min(self.cells[0] - 1);
        let j = ((b * self.cells[1] as f64) as u32).min(self.cells[1] - 1);
        Some(Crossing {
            cell: self.first_cell + j * self.cells[0] + i,
            score_per_lm: weight / self.cell_area_m2,
        })
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
        }
    }

    #[test]
    fn downward_ray_scores_in_the_cell_below_it() {
        let g = ReceiverGrid::new(&desk(), DVec3::new(1.0, 1.0, 0.0), 10);
        // World (2.6, 2.7) → a = 0.8, b = 0.7 → cell (3, 1).
        let o = DVec3::new(1.6, 1.7, 3.0);
        let c = g.crossing(o, -DVec3::Z, 10.0).unwrap();
        assert_eq!(c.cell, 10 + 4 + 3);
        assert!((c.score_per_lm - 1.0 / 0.25).abs() < 1e-12);
        assert!(
            g.crossing(o, -DVec3::Z, 2.0).is_none(),
            "stops before the plane"
        );
        assert!(
            g.crossing(o - DVec3::Z * 4.0, DVec3::Z, 10.0).is_none(),
            "back face"
        );
    }
}

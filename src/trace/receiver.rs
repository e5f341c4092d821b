//! How photons reach a receiver: the cell a ray segment crosses and its score, and the
//! next-event connection from a scattering vertex (a sampled point of the receiver, or
//! a sampled direction of a luminance meter's cone). The receiver's geometry and cells
//! are `tally::ReceiverGrid`'s.

use crate::sampling::{uniform, uniform_cone_band};
use crate::tally::receiver::Kind;
use crate::tally::ReceiverGrid;
use glam::DVec3;
use rand_pcg::Pcg32;

/// A next-event connection to a receiver (see [`ReceiverGrid::connect`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Connection {
    pub point: DVec3,
    pub cell: u32,
    /// Unit direction from the vertex to `point`, and the distance.
    pub dir: DVec3,
    pub distance: f64,
    /// Score per candela of the vertex's intensity along `dir`.
    pub factor: f64,
}

/// A segment's crossing of a receiver cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Global cell index.
    pub cell: u32,
    /// Distance from the segment's origin to the crossing (m).
    pub distance: f64,
    /// Score of a photon of unit flux (lm): 1/A_cell for illuminance,
    /// 1/(A_cell·cos θ·Ω) for luminance.
    pub score_per_lm: f64,
}

impl ReceiverGrid {
    /// The cell the segment `origin + t·dir`, `t_min < t ≤ t_max` (`dir` unit), crosses
    /// and its score, if it scores. A crossing photon carries flux, not intensity: its score
    /// is the arrival factor over |cos θ| per cell area.
    #[inline]
    pub fn crossing(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Crossing> {
        let factor = self.arrival_factor(dir)?;
        let cos_n = dir.dot(self.normal);
        let t = (self.corner - origin).dot(self.normal) / cos_n;
        if !(t > t_min && t <= t_max) {
            return None;
        }
        let rel = origin + dir * t - self.corner;
        let (a, b) = (rel.dot(self.du), rel.dot(self.dv));
        if !(0.0..1.0).contains(&a) || !(0.0..1.0).contains(&b) {
            return None;
        }
        Some(Crossing {
            cell: self.cell_at(a, b),
            distance: t,
            score_per_lm: factor / (cos_n.abs() * self.cell_area_m2),
        })
    }

    /// A next-event connection from a scattering vertex at `x`, in stratum `stratum` of
    /// [`Self::connections`]: a point of the receiver, its cell, and the factor that turns
    /// the vertex's intensity towards it (cd) into the cell's score. Illuminance samples the point uniformly over the receiver
    /// (factor = K·cos θ_r/d², K cells); luminance samples the direction uniformly in the
    /// meter's cone and follows it to the receiver (factor = 1/(A_cell·|cos θ_r|)), so
    /// every vertex a meter can see contributes, however close the meter is to it.
    #[inline]
    pub fn connect(&self, x: DVec3, stratum: u32, rng: &mut Pcg32) -> Option<Connection> {
        let strata = self.connections as f64;
        match self.kind {
            Kind::Illuminance => {
                // Stratum s of the receiver is the strip s/n ≤ a < (s+1)/n along u.
                let (a, b) = ((stratum as f64 + uniform(rng)) / strata, uniform(rng));
                let point = self.point_at(a, b);
                let d = point - x;
                let distance = d.length();
                let dir = d / distance;
                let cos = self.arrival_factor(dir)?;
                Some(Connection {
                    point,
                    cell: self.cell_at(a, b),
                    dir,
                    distance,
                    factor: self.cell_count() as f64 * cos / (distance * distance),
                })
            }
            Kind::Luminance {
                towards_meter,
                cos_half_angle,
                ..
            } => {
                // Stratum s of the cone is the band of cos θ it covers.
                let cos_lo = 1.0 - (1.0 - cos_half_angle) * (stratum as f64 + 1.0) / strata;
                let cos_hi = 1.0 - (1.0 - cos_half_angle) * stratum as f64 / strata;
                let dir = uniform_cone_band(rng, towards_meter, cos_lo, cos_hi);
                let cos_n = dir.dot(self.normal);
                let distance = (self.corner - x).dot(self.normal) / cos_n;
                if !(distance > 0.0) {
                    return None;
                }
                let point = x + dir * distance;
                let rel = point - self.corner;
                let (a, b) = (rel.dot(self.du), rel.dot(self.dv));
                if !(0.0..1.0).contains(&a) || !(0.0..1.0).contains(&b) {
                    return None;
                }
                Some(Connection {
                    point,
                    cell: self.cell_at(a, b),
                    dir,
                    distance,
                    factor: 1.0 / (self.cell_area_m2 * cos_n.abs()),
                })
            }
        }
    }
}

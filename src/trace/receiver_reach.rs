//! How photons reach a receiver: the cell a ray segment crosses and its score, and the
//! next-event connection from a scattering vertex (a sampled point of the receiver, or
//! a sampled direction of a luminance meter's cone). The receiver's geometry and cells
//! are `tally::ReceiverGrid`'s.

use crate::sampling::{cone_band_direction, uniform};
use crate::tally::receiver_grid::Kind;
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
    /// 1/(A_cell·cos θ·Ω) for luminance, response/(A_cell·|cos θ|) for the cylinders
    /// (sin θ/(π·|cos θ|) on a horizontal receiver: large at grazing crossings).
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

    /// Marks the segments of a batch (origins `o`, unit directions `d` as cast, in f32;
    /// `origin + t·dir` for −`slack` < t ≤ `t_hit` + `slack`) that cross this
    /// receiver: `marks[k]` is whether [`Self::crossing`] scores segment k. For an
    /// illuminance receiver the test is one straight pass over the batch doing
    /// `crossing`'s arithmetic, in its order, for every segment (no early exit to
    /// mispredict, and the compiler can use vector instructions), so the marks are exact;
    /// callers then call `crossing` on the few marked segments. The other quantities
    /// (a luminance meter's cone, the cylinders' two faces) call `crossing` on every
    /// segment, so their marks are exact too.
    pub fn mark_crossings(
        &self,
        o: [&[f32]; 3],
        d: [&[f32]; 3],
        t_hit: &[f32],
        slack: f64,
        marks: &mut Vec<bool>,
    ) {
        let n = t_hit.len();
        marks.clear();
        marks.resize(n, false);
        let marks = &mut marks[..n];
        let ([ox, oy, oz], [dx, dy, dz]) = (o.map(|v| &v[..n]), d.map(|v| &v[..n]));
        if !matches!(self.kind, Kind::Illuminance) {
            for (k, mark) in marks.iter_mut().enumerate() {
                let origin = DVec3::new(ox[k] as f64, oy[k] as f64, oz[k] as f64);
                let dir = DVec3::new(dx[k] as f64, dy[k] as f64, dz[k] as f64);
                *mark = self
                    .crossing(origin, dir, -slack, t_hit[k] as f64 + slack)
                    .is_some();
            }
            return;
        }
        let ([nx, ny, nz], [cx, cy, cz]) = (self.normal.to_array(), self.corner.to_array());
        let ([ux, uy, uz], [vx, vy, vz]) = (self.du.to_array(), self.dv.to_array());
        for k in 0..n {
            let (px, py, pz) = (ox[k] as f64, oy[k] as f64, oz[k] as f64);
            let (wx, wy, wz) = (dx[k] as f64, dy[k] as f64, dz[k] as f64);
            let cos_n = wx * nx + wy * ny + wz * nz;
            let t = ((cx - px) * nx + (cy - py) * ny + (cz - pz) * nz) / cos_n;
            let (rx, ry, rz) = (px + wx * t - cx, py + wy * t - cy, pz + wz * t - cz);
            let a = rx * ux + ry * uy + rz * uz;
            let b = rx * vx + ry * vy + rz * vz;
            // `&`, not `&&` or `Range::contains`: no short circuit, no branch.
            #[allow(clippy::manual_range_contains)]
            let inside = (-cos_n > 0.0)
                & (t > -slack)
                & (t <= t_hit[k] as f64 + slack)
                & (0.0 <= a)
                & (a < 1.0)
                & (0.0 <= b)
                & (b < 1.0);
            marks[k] = inside;
        }
    }

    /// A next-event connection from a scattering vertex at `x`, in stratum `stratum` of
    /// [`Self::connections`]: a point of the receiver, its cell, and the factor that turns
    /// the vertex's intensity towards it (cd) into the cell's score. Illuminance and the
    /// cylinders sample the point uniformly over the receiver (factor = K·f/d², K cells,
    /// f the [`ReceiverGrid::arrival_factor`]: cos θ_r on the front face, the cylinders'
    /// response from either side); luminance samples the direction uniformly in the
    /// meter's cone and follows it to the receiver (factor = 1/(A_cell·|cos θ_r|)), so
    /// every vertex a meter can see contributes, however close the meter is to it.
    #[inline]
    pub fn connect(
        &self,
        x: DVec3,
        stratum: u32,
        square: Option<(f64, f64)>,
        rng: &mut Pcg32,
    ) -> Option<Connection> {
        let strata = self.connections as f64;
        match self.kind {
            Kind::Illuminance | Kind::Cylindrical | Kind::SemiCylindrical { .. } => {
                // Stratum s of the receiver is the strip s/n ≤ a < (s+1)/n along u.
                let (u, v) = square.unwrap_or_else(|| (uniform(rng), uniform(rng)));
                let (a, b) = ((stratum as f64 + u) / strata, v);
                let cell = self.cell_at(a, b);
                // A point receiver's cell, picked as uniformly, scores at its centre.
                let point = if self.points {
                    let k = cell - self.first_cell;
                    self.cell_point((k % self.cells[0], k / self.cells[0]), 0.5, 0.5)
                } else {
                    self.point_at(a, b)
                };
                let d = point - x;
                let distance = d.length();
                let dir = d / distance;
                let response = self.arrival_factor(dir)?;
                Some(Connection {
                    point,
                    cell,
                    dir,
                    distance,
                    factor: self.cell_count() as f64 * response / (distance * distance),
                })
            }
            Kind::Luminance {
                towards_meter,
                cos_half_angle,
                ..
            } => {
                // Stratum s of the cone is the band of cos θ it covers.
                let dir =
                    cone_band_direction(rng, towards_meter, cos_half_angle, stratum as f64, strata);
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

#[cfg(test)]
mod tests {
    use crate::sampling::{uniform, uniform_sphere};
    use crate::scene::{Estimator, Quantity, Receiver};
    use crate::tally::ReceiverGrid;
    use glam::DVec3;

    #[test]
    fn batch_marks_are_exactly_the_crossings() {
        for quantity in [
            Quantity::Illuminance,
            Quantity::Cylindrical,
            Quantity::SemiCylindrical {
                facing: DVec3::new(0.6, 0.8, 0.0),
            },
        ] {
            batch_marks_match_crossings(quantity);
        }
    }

    /// Both faces of a cylinder count: the generic path of `mark_crossings` must mark
    /// the upward crossings too.
    fn batch_marks_match_crossings(quantity: Quantity) {
        let desk = Receiver {
            name: "desk".into(),
            corner: DVec3::new(-0.5, -0.25, -0.7),
            u: DVec3::new(1.0, 0.0, 0.0),
            v: DVec3::new(0.0, 0.5, 0.0),
            cells: [64, 32],
            quantity,
            estimator: Estimator::Track,
            grid: None,
            points: false,
            exclude: Vec::new(),
        };
        let grid = ReceiverGrid::new(&desk, DVec3::ZERO, 0, Estimator::Track);
        let mut rng = crate::rng::aux_stream(11);
        let n = 20_000;
        let mut cols: [Vec<f32>; 7] = Default::default();
        for _ in 0..n {
            // Origins in a 2 m box around the desk, some exactly on its plane.
            let mut o = DVec3::new(uniform(&mut rng), uniform(&mut rng), uniform(&mut rng));
            o = (o - 0.5) * 2.0;
            if uniform(&mut rng) < 0.1 {
                o.z = -0.7;
            }
            let d = uniform_sphere(&mut rng);
            let t = (3.0 * uniform(&mut rng)) as f32;
            for (c, x) in cols.iter_mut().zip([o.x, o.y, o.z, d.x, d.y, d.z]) {
                c.push(x as f32);
            }
            cols[6].push(t);
        }
        let slack = 1e-5;
        let mut marks = Vec::new();
        let [ox, oy, oz, dx, dy, dz, t] = &cols;
        grid.mark_crossings([ox, oy, oz], [dx, dy, dz], t, slack, &mut marks);
        let (mut crossed, mut upwards) = (0, 0);
        for k in 0..n {
            let o = DVec3::new(ox[k] as f64, oy[k] as f64, oz[k] as f64);
            let d = DVec3::new(dx[k] as f64, dy[k] as f64, dz[k] as f64);
            let exact = grid.crossing(o, d, -slack, t[k] as f64 + slack).is_some();
            assert_eq!(marks[k], exact, "{quantity:?}: segment {k}");
            crossed += exact as usize;
            upwards += (exact && d.z > 0.0) as usize;
        }
        assert!(
            crossed > 100,
            "{crossed} crossings: the test must exercise both outcomes"
        );
        match quantity {
            Quantity::Illuminance => assert_eq!(upwards, 0, "illuminance: front face only"),
            _ => assert!(upwards > 50, "{quantity:?}: {upwards} upward crossings"),
        }
    }
}

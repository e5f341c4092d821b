//! Deterministic direct light on next-event receivers (method.md eqs. 1–2): each cell's
//! direct illuminance (or luminance) is computed, not sampled, by a fixed stratified
//! pattern of points over the cell (and over the source, for area lights), with shadow
//! rays through the backend's occlusion path.
//!
//! Each cell starts with a 2 × 2 pattern and doubles it in each direction; the residual
//! error reported for an m × m pattern is the change from the (m/2) × (m/2) one, which
//! bounds the midpoint rule's error for smooth light (it is then three times the error)
//! and estimates it across shadow edges. A cell is refined until its residual is below
//! [`RESIDUAL_TOLERANCE`] of its value or the pattern reaches [`MAX_PATTERN`]. The
//! residual shrinks by refinement, never by photons.

use super::emit::{Emitter, Emitters};
use crate::accel::{RayBatch, RayCaster};
use crate::tally::ReceiverGrid;
use rayon::prelude::*;

/// Coarsest pattern: 2 × 2 points per cell (and per area source); the first value
/// reported comes from 4 × 4.
pub const FIRST_PATTERN: u32 = 2;
/// Finest pattern: 32 × 32 points per cell (and patches per area source, the pattern
/// then being capped at [`MAX_AREA_PATTERN`] since the cost grows as its fourth power).
pub const MAX_PATTERN: u32 = 32;
pub const MAX_AREA_PATTERN: u32 = 16;
/// Relative residual a cell is refined to: far below the statistical errors users ask
/// for (0.5–5 %), so the direct part never dominates a cell's error.
pub const RESIDUAL_TOLERANCE: f64 = 1e-3;

/// Direct light of one cell.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellDirect {
    pub value: f64,
    pub sigma: f64,
    /// Shadow rays cast for it.
    pub rays: u64,
}

/// A ray-casting context: the caster and the distance within which a point counts as
/// on a surface (so a receiver lying on a floor is not shadowed by the floor).
struct Shadows<'a> {
    caster: &'a dyn RayCaster,
    slack: f64,
}

/// Direct light of every cell of `grid`, in cell order. `slack` (m) is how far from a
/// surface a receiver still counts as lying on it.
pub fn direct_light(
    grid: &ReceiverGrid,
    emitters: &Emitters,
    caster: &dyn RayCaster,
    slack: f64,
) -> Vec<CellDirect> {
    let shadows = Shadows { caster, slack };
    let has_area = emitters
        .emitters
        .iter()
        .any(|e| matches!(e, Emitter::Area { .. }));
    (0..grid.cell_count() as u32)
        .into_par_iter()
        .map_init(
            || (RayBatch::default(), Vec::new(), Vec::new()),
            |(rays, weights, occluded), cell| {
                let (i, j) = (cell % grid.cells[0], cell / grid.cells[0]);
                let max_pattern = if has_area {
                    MAX_AREA_PATTERN
                } else {
                    MAX_PATTERN
                };
                let mut m = FIRST_PATTERN;
                let mut previous =
                    cell_pattern(grid, emitters, &shadows, i, j, m, rays, weights, occluded);
                let mut rays_cast = rays.len() as u64;
                loop {
                    m *= 2;
                    let value =
                        cell_pattern(grid, emitters, &shadows, i, j, m, rays, weights, occluded);
                    rays_cast += rays.len() as u64;
                    let sigma = (value - previous).abs();
                    if sigma <= RESIDUAL_TOLERANCE * value || m >= max_pattern {
                        return CellDirect {
                            value,
                            sigma,
                            rays: rays_cast,
                        };
                    }
                    previous = value;
                }
            },
        )
        .collect()
}

/// The direct light of cell (i, j) by an m × m pattern (midpoints of the sub-cells).
#[allow(clippy::too_many_arguments)]
fn cell_pattern(
    grid: &ReceiverGrid,
    emitters: &Emitters,
    shadows: &Shadows<'_>,
    i: u32,
    j: u32,
    m: u32,
    rays: &mut RayBatch,
    weights: &mut Vec<f64>,
    occluded: &mut Vec<bool>,
) -> f64 {
    rays.clear();
    weights.clear();
    let (nu, nv) = (grid.cells[0] as f64, grid.cells[1] as f64);
    // The same m × m midpoint pattern over the cell and over area sources.
    let pattern: Vec<(f64, f64)> = (0..m * m)
        .map(|k| {
            (
                ((k / m) as f64 + 0.5) / m as f64,
                ((k % m) as f64 + 0.5) / m as f64,
            )
        })
        .collect();
    for &(sa, sb) in &pattern {
        let p = grid.point_at((i as f64 + sa) / nu, (j as f64 + sb) / nv);
        for light in 0..emitters.emitters.len() {
            emitters.incoming(light, p, &pattern, |inc| {
                if inc.distance <= 4.0 * shadows.slack {
                    return;
                }
                let Some(factor) = grid.arrival_factor(-inc.direction()) else {
                    return;
                };
                // Stop just short of a source piece, and start a directional source's
                // ray just off the receiver, which may lie on a surface.
                let (t_near, t_far) = if inc.distance.is_finite() {
                    let eps = (2.0 * shadows.slack / inc.distance) as f32;
                    (eps, 1.0 - eps)
                } else {
                    ((2.0 * shadows.slack) as f32, f32::INFINITY)
                };
                rays.push(
                    p.as_vec3().into(),
                    inc.to_source.as_vec3().into(),
                    t_near,
                    t_far,
                );
                weights.push(inc.normal_lx * factor);
            });
        }
    }
    shadows.caster.occluded(rays, occluded);
    let lit: f64 = weights
        .iter()
        .zip(occluded.iter())
        .filter(|(_, blocked)| !**blocked)
        .map(|(w, _)| w)
        .sum();
    lit / (m * m) as f64
}

//! Emission directions that reproduce the bilinear interpolant exactly: a cell is chosen
//! with probability equal to its share of the exact flux (Walker's alias table), then a
//! direction uniform in solid angle inside the cell (φ uniform, cos θ uniform) is kept
//! with probability I/I_max of the cell, else redrawn in the same cell. The density is
//! then I(direction)/Φ, with no bias and unit-weight photons.
//!
//! A QMC run's point of [0, 1)² picks the cell by inversion instead (a φ column by its
//! share of the flux, then a cell of the column by its share of the column's, as pbrt's
//! piecewise-constant 2-D distribution does), and what is left of the two numbers places
//! the first proposal inside the cell: nearby points stay nearby, so the net's strata
//! become strata of directions. The alias table scatters neighbouring numbers over
//! distant cells, which is harmless for random numbers and wasteful for a net.

use super::grid::Grid;
use crate::sampling::{invert_cdf, uniform};
use glam::DVec3;
use rand_pcg::Pcg32;

/// One grid cell with non-zero flux, as the rejection step reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cell {
    phi0_rad: f64,
    dphi_rad: f64,
    theta0_rad: f64,
    dtheta_rad: f64,
    cos0: f64,
    cos1: f64,
    /// I at (φ0, θ0), (φ0, θ1), (φ1, θ0), (φ1, θ1).
    corner_cd: [f64; 4],
    max_cd: f64,
}

/// Walker's alias table over the cells (Vose's construction): O(1) per draw.
#[derive(Clone, Debug, Default, PartialEq)]
struct Alias {
    /// Probability of keeping column k rather than its alias, times 1.
    keep: Vec<f64>,
    alias: Vec<u32>,
}

impl Alias {
    /// `weights` non-negative, finite, with a positive sum.
    fn new(weights: &[f64]) -> Alias {
        let n = weights.len();
        let total: f64 = weights.iter().sum();
        let mut scaled: Vec<f64> = weights.iter().map(|w| w * n as f64 / total).collect();
        let mut keep = vec![1.0; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) =
            (0..n).partition(|&k| scaled[k] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            keep[s] = scaled[s];
            alias[s] = l as u32;
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left is 1 up to rounding: kept whole.
        Alias { keep, alias }
    }

    #[inline]
    fn sample(&self, u_column: f64, u_keep: f64) -> usize {
        let n = self.keep.len();
        let k = ((u_column * n as f64) as usize).min(n - 1);
        if u_keep < self.keep[k] {
            k
        } else {
            self.alias[k] as usize
        }
    }
}

/// The cells' flux as nested cumulative sums, for picking a cell by inversion: a φ
/// column, then a cell of that column (θ order).
#[derive(Clone, Debug, Default, PartialEq)]
struct Inversion {
    /// Cumulative flux of the φ columns that emit, with each column's cells.
    columns: Vec<(f64, Column)>,
}

#[derive(Clone, Debug, Default, PartialEq)]
struct Column {
    /// Cumulative flux of the column's emitting cells (from the column's start) and
    /// their indices in `cells`.
    cells: Vec<(f64, u32)>,
}

impl Inversion {
    /// The cell of `cells` the point picks, and the point's place inside it.
    #[inline]
    fn sample(&self, (u, v): (f64, f64)) -> (usize, (f64, f64)) {
        let (i, along) = invert_cdf(&self.columns, |c| c.0, u);
        let column = &self.columns[i].1.cells;
        let (j, across) = invert_cdf(column, |c| c.0, v);
        (column[j].1 as usize, (along, across))
    }
}

/// Samples emission directions of a [`Grid`] in proportion to its interpolant (the
/// default samples nothing: a placeholder until [`Sampler::new`] has the grid's).
#[derive(Clone, Default, PartialEq)]
pub struct Sampler {
    cells: Vec<Cell>,
    alias: Alias,
    inversion: Inversion,
}

/// The cells and the alias table only: the inversion tables are the cells' fluxes again,
/// and the scene's fingerprint (which reads the lights' `Debug`) should not change with
/// how they are indexed.
impl std::fmt::Debug for Sampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        (f.debug_struct("Sampler"))
            .field("cells", &self.cells)
            .field("alias", &self.alias)
            .finish()
    }
}

impl Sampler {
    /// None when the grid emits nothing (no cell has positive flux).
    pub fn new(grid: &Grid) -> Option<Sampler> {
        let mut cells = Vec::new();
        let mut weights = Vec::new();
        let mut inversion = Inversion::default();
        let mut total = 0.0;
        for i in 0..grid.phi_deg.len() - 1 {
            let (mut column, mut in_column) = (Column::default(), 0.0);
            for j in 0..grid.n_theta() - 1 {
                let flux = grid.cell_flux_lm(i, j);
                if flux.is_nan() || flux <= 0.0 {
                    continue;
                }
                total += flux;
                in_column += flux;
                column.cells.push((in_column, cells.len() as u32));
                let corner_cd = [
                    grid.at(i, j),
                    grid.at(i, j + 1),
                    grid.at(i + 1, j),
                    grid.at(i + 1, j + 1),
                ];
                let (t0, t1) = (
                    grid.theta_deg[j].to_radians(),
                    grid.theta_deg[j + 1].to_radians(),
                );
                cells.push(Cell {
                    phi0_rad: grid.phi_deg[i].to_radians(),
                    dphi_rad: (grid.phi_deg[i + 1] - grid.phi_deg[i]).to_radians(),
                    theta0_rad: t0,
                    dtheta_rad: t1 - t0,
                    cos0: libm::cos(t0),
                    cos1: libm::cos(t1),
                    corner_cd,
                    max_cd: corner_cd.iter().copied().fold(0.0, f64::max),
                });
                weights.push(flux);
            }
            if !column.cells.is_empty() {
                inversion.columns.push((total, column));
            }
        }
        if cells.is_empty() {
            return None;
        }
        Some(Sampler {
            alias: Alias::new(&weights),
            cells,
            inversion,
        })
    }

    /// A direction's (φ, θ) in radians, with cos θ and sin θ, distributed as I/Φ.
    #[inline]
    pub fn sample_rad(&self, rng: &mut Pcg32) -> (f64, f64, f64, f64) {
        let cell = (uniform(rng), uniform(rng));
        self.sample_rad_in(cell, rng)
    }

    /// [`Sampler::sample_rad`] with the alias table's two numbers given: `cell` picks
    /// the grid cell, `rng` the direction within it.
    #[inline]
    fn sample_rad_in(&self, cell: (f64, f64), rng: &mut Pcg32) -> (f64, f64, f64, f64) {
        let c = &self.cells[self.alias.sample(cell.0, cell.1)];
        let first = (uniform(rng), uniform(rng));
        Self::in_cell(c, first, rng)
    }

    /// A direction (as [`Sampler::sample_rad`]) in cell `c`: the proposal `first` (φ's
    /// and cos θ's fractions across the cell), kept with probability I/I_max, then
    /// proposals from `rng` until one is kept.
    #[inline]
    fn in_cell(c: &Cell, first: (f64, f64), rng: &mut Pcg32) -> (f64, f64, f64, f64) {
        let mut proposal = first;
        loop {
            let t = proposal.0;
            let cos_theta = c.cos0 - proposal.1 * (c.cos0 - c.cos1);
            let theta = libm::acos(cos_theta.clamp(-1.0, 1.0));
            let s = ((theta - c.theta0_rad) / c.dtheta_rad).clamp(0.0, 1.0);
            let [i00, i01, i10, i11] = c.corner_cd;
            let lo = i00 + s * (i01 - i00);
            let hi = i10 + s * (i11 - i10);
            let cd = lo + t * (hi - lo);
            if uniform(rng) * c.max_cd < cd {
                let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                return (c.phi0_rad + t * c.dphi_rad, theta, cos_theta, sin_theta);
            }
            proposal = (uniform(rng), uniform(rng));
        }
    }

    /// A unit direction of the luminaire frame, distributed as I/Φ.
    #[inline]
    pub fn sample_direction(&self, grid: &Grid, cell: (f64, f64), rng: &mut Pcg32) -> DVec3 {
        let (phi, _, cos_theta, sin_theta) = self.sample_rad_in(cell, rng);
        Self::direction(grid, phi, cos_theta, sin_theta)
    }

    /// [`Sampler::sample_direction`] from a QMC point of [0, 1)²: the cell by inversion,
    /// the first proposal from what is left of the point, later ones from `rng`.
    #[inline]
    pub fn sample_direction_from_square(
        &self,
        grid: &Grid,
        square: (f64, f64),
        rng: &mut Pcg32,
    ) -> DVec3 {
        let (cell, first) = self.inversion.sample(square);
        let (phi, _, cos_theta, sin_theta) = Self::in_cell(&self.cells[cell], first, rng);
        Self::direction(grid, phi, cos_theta, sin_theta)
    }

    #[inline]
    fn direction(grid: &Grid, phi: f64, cos_theta: f64, sin_theta: f64) -> DVec3 {
        let (sp, cp) = libm::sincos(phi);
        let a = &grid.axes;
        (cos_theta * a.pole + sin_theta * (cp * a.zero + sp * a.ninety)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alias_table_reproduces_its_weights() {
        let w = [1.0, 0.0, 3.0, 0.5, 5.5];
        let a = Alias::new(&w);
        // Exact probabilities from the table: (keep_k + Σ_{alias=k} (1 − keep)) / n.
        let n = w.len() as f64;
        let total: f64 = w.iter().sum();
        for k in 0..w.len() {
            let mut p = a.keep[k];
            for m in 0..w.len() {
                if a.alias[m] as usize == k && m != k {
                    p += 1.0 - a.keep[m];
                }
            }
            assert!(
                (p / n - w[k] / total).abs() < 1e-12,
                "{k}: {} vs {}",
                p / n,
                w[k] / total
            );
        }
    }
}

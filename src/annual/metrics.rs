//! Every hour's illuminance from the daylight coefficients, and the annual metrics with
//! their uncertainty (docs/daylight.md, *Annual metrics*).
//!
//! E(t) = Σₖ sₖ(t)·DCₖ and Var E(t) = Σₖ sₖ(t)²·Var DCₖ (independent sources). The
//! metrics count hours over thresholds, which no σ propagates through, so they are
//! judged under the *comonotone* error model: one standard normal z shifts every hour
//! and every cell by z·σ(t). Every hour's error is a sum of the same sources' errors with
//! weights sₖ(t) ≥ 0, so any two hours' errors correlate positively; by Slepian's
//! inequality their threshold indicators' covariances are then largest when the
//! correlation is 1, so the comonotone model gives counts (and so DA, ASE hours, sDA)
//! their widest spread: intervals err on the wide side. Cells are treated the same way
//! (their errors come from the same photons and correlate positively in practice; that
//! part is an assumption, stated in the docs). Under the model a figure is a function
//! of z: its 95 % interval is its range over |z| ≤ 1.96, a cell's pass probability the
//! normal measure of the z at which it passes.

use super::sky_matrix::SkyMatrix;
use super::{Coefficients, Source, SourceKind};
use crate::scene::annual::Annual;
use crate::scene::Scene;
use rayon::prelude::*;

/// One analysed receiver's hours: per lit hour of the sky matrix (its order), per cell
/// (`[hour * cells + cell]`): the illuminance and its σ, and the sun's direct part alone
/// (ASE's, and the blinds') and its σ, lx.
#[derive(Clone, Debug, Default)]
pub struct Hourly {
    pub cells: usize,
    pub e: Vec<f32>,
    pub sigma: Vec<f32>,
    pub sun: Vec<f32>,
    pub sun_sigma: Vec<f32>,
    /// Per cell: the mean over the occupied records (dark ones count 0) and its σ,
    /// Var = Σₖ (Σₜ sₖ(t))²·Var DCₖ / T².
    pub mean_lx: Vec<f64>,
    pub mean_sigma_lx: Vec<f64>,
}

impl Hourly {
    fn at(&self, hour: usize) -> std::ops::Range<usize> {
        hour * self.cells..(hour + 1) * self.cells
    }

    /// Lit hour `hour`'s mean over the cells and an upper bound of its σ: the mean of
    /// the cells' σ (their errors correlate at most fully).
    pub fn receiver_mean(&self, hour: usize) -> (f64, f64) {
        let n = self.cells.max(1) as f64;
        let mean = |v: &[f32]| v[self.at(hour)].iter().map(|&x| x as f64).sum::<f64>() / n;
        (mean(&self.e), mean(&self.sigma))
    }
}

/// [`Hourly`] of every analysed receiver.
pub fn hourly_all(
    matrix: &SkyMatrix,
    sources: &[Source],
    dc: &Coefficients,
    receivers: usize,
) -> Vec<Hourly> {
    (0..receivers)
        .map(|r| hourly(matrix, sources, dc, r))
        .collect()
}

/// Per source (in `sources` order), value and variance rows over receiver `r`'s cells;
/// a source not traced yet is all zeros.
fn rows(dc: &Coefficients, r: usize, cells: usize) -> [Vec<Vec<f64>>; 4] {
    let pick = |f: &dyn Fn(&crate::stats::CellEstimate) -> f64| -> Vec<Vec<f64>> {
        dc.iter()
            .map(|s| {
                s.get(r)
                    .map_or(vec![0.0; cells], |c| c.iter().map(f).collect())
            })
            .collect()
    };
    [
        pick(&|c| c.value),
        pick(&|c| c.var),
        pick(&|c| c.direct),
        pick(&|c| c.direct_var),
    ]
}

fn hourly(matrix: &SkyMatrix, sources: &[Source], dc: &Coefficients, r: usize) -> Hourly {
    let cells = dc.iter().find_map(|s| s.get(r).map(Vec::len)).unwrap_or(0);
    let [value, var, direct, direct_var] = rows(dc, r, cells);
    let patch0 = sources
        .iter()
        .position(|s| matches!(s.kind, SourceKind::Patch(_)))
        .unwrap_or(1);
    let sun0 = patch0 + matrix.patches.len();
    let per_hour: Vec<[Vec<f32>; 4]> = (matrix.hours.par_iter())
        .map(|h| {
            let (mut e, mut v) = (vec![0.0f64; cells], vec![0.0f64; cells]);
            let mut add = |k: usize, w: f64| {
                if w != 0.0 {
                    for c in 0..cells {
                        e[c] += w * value[k][c];
                        v[c] += w * w * var[k][c];
                    }
                }
            };
            add(0, h.ground_cdm2);
            for (j, &l) in h.patches.iter().enumerate() {
                add(patch0 + j, l as f64);
            }
            let (mut sun, mut sun_var) = (vec![0.0f64; cells], vec![0.0f64; cells]);
            if let Some((b, en)) = h.sun {
                add(sun0 + b, en);
                for c in 0..cells {
                    sun[c] = en * direct[sun0 + b][c];
                    sun_var[c] = en * en * direct_var[sun0 + b][c];
                }
            }
            let f = |x: &[f64]| x.iter().map(|&y| y as f32).collect::<Vec<f32>>();
            let sd = |x: &[f64]| {
                x.iter()
                    .map(|&y| y.max(0.0).sqrt() as f32)
                    .collect::<Vec<f32>>()
            };
            [f(&e), sd(&v), f(&sun), sd(&sun_var)]
        })
        .collect();
    let mut weights = vec![0.0f64; sources.len()];
    for h in matrix.hours.iter().filter(|h| h.occupied) {
        weights[0] += h.ground_cdm2;
        for (j, &l) in h.patches.iter().enumerate() {
            weights[patch0 + j] += l as f64;
        }
        if let Some((b, en)) = h.sun {
            weights[sun0 + b] += en;
        }
    }
    let t = matrix.occupied_records.max(1) as f64;
    let mean_lx = (0..cells)
        .map(|c| {
            (weights.iter().enumerate())
                .map(|(k, w)| w * value[k][c])
                .sum::<f64>()
                / t
        })
        .collect();
    let mean_sigma_lx = (0..cells)
        .map(|c| {
            (weights.iter().enumerate())
                .map(|(k, w)| w * w * var[k][c])
                .sum::<f64>()
                .sqrt()
                / t
        })
        .collect();
    let mut out = Hourly {
        cells,
        mean_lx,
        mean_sigma_lx,
        ..Hourly::default()
    };
    for [e, s, d, ds] in per_hour {
        out.e.extend(e);
        out.sigma.extend(s);
        out.sun.extend(d);
        out.sun_sigma.extend(ds);
    }
    out
}

/// The thresholds (lx and hours) of the metrics.
pub const DA_LX: f64 = 300.0;
pub const SDA_HOURS_FRACTION: f64 = 0.5;
pub const BLINDS_LX: f64 = 1000.0;
pub const BLINDS_AREA_FRACTION: f64 = 0.02;
pub const ASE_LX: f64 = 1000.0;
/// ASE counts a cell whose direct sun exceeds [`ASE_LX`] for more than this many hours.
pub const ASE_HOURS: usize = 250;
pub const UDI_EDGES_LX: [f64; 3] = [100.0, 300.0, 3000.0];
/// EN 17037's levels: name, E_T over 50 % of the plane, E_TM over 95 %.
pub const EN17037_LEVELS: [(&str, f64, f64); 3] = [
    ("minimum", 300.0, 100.0),
    ("medium", 500.0, 300.0),
    ("high", 750.0, 500.0),
];
/// EN 17037's daylight hours: the half of the year's hours with most daylight.
pub const EN17037_HOURS: usize = 4380;
/// The normal quantile of a two-sided 95 % interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// The z grid figures are evaluated on: −4…4 by 0.1.
fn z_grid() -> Vec<f64> {
    (-40..=40).map(|i| i as f64 / 10.0).collect()
}

/// Standard normal density.
fn phi(z: f64) -> f64 {
    libm::exp(-0.5 * z * z) / (2.0 * std::f64::consts::PI).sqrt()
}

/// A figure's value at z = 0 and its range over |z| ≤ 1.96.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Interval {
    pub value: f64,
    pub low: f64,
    pub high: f64,
}

impl Interval {
    fn of(grid: &[f64], values: &[f64]) -> Interval {
        let inside = grid
            .iter()
            .zip(values)
            .filter(|(z, _)| z.abs() <= Z95 + 1e-9);
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for (_, &v) in inside {
            low = low.min(v);
            high = high.max(v);
        }
        let zero = grid
            .iter()
            .position(|&z| z == 0.0)
            .expect("the grid holds 0");
        Interval {
            value: values[zero],
            low,
            high,
        }
    }

    pub fn halfwidth(&self) -> f64 {
        0.5 * (self.high - self.low)
    }
}

/// The probability, under the model, of the z at which `passes` holds (the grid's
/// points weighted by the normal density).
fn probability(grid: &[f64], passes: &[bool]) -> f64 {
    let (mut yes, mut all) = (0.0, 0.0);
    for (&z, &p) in grid.iter().zip(passes) {
        all += phi(z);
        if p {
            yes += phi(z);
        }
    }
    yes / all
}

/// A verdict under the model: met over the whole 95 % range, nowhere in it, or neither.
pub fn verdict(grid_low: bool, value: bool, grid_high: bool) -> &'static str {
    match (grid_low, value, grid_high) {
        (true, _, true) => "met",
        (false, _, false) => "not met",
        _ => "undecided",
    }
}

/// Per cell: the annual figures.
#[derive(Clone, Debug, Default)]
pub struct CellFigures {
    /// Mean illuminance over the occupied hours and its σ (exact, independent sources).
    pub mean_lx: f64,
    pub mean_sigma_lx: f64,
    /// DA300 without blinds, as a fraction of the occupied hours.
    pub da: Interval,
    pub cda: Interval,
    /// DA300 with the 2 % blinds rule (LM-83's sDA uses this).
    pub da_blinds: Interval,
    /// Probability the cell counts for sDA (DA300 with blinds ≥ 50 %).
    pub sda_probability: f64,
    /// Occupied hours of direct sun over 1000 lx, and the probability they exceed 250.
    pub ase_hours: Interval,
    pub ase_probability: f64,
    /// UDI: fractions of occupied hours below 100, 100–300, 300–3000, above 3000 lx
    /// (the middle bins are not monotone in z: their intervals are ranges).
    pub udi: [Interval; 4],
}

/// One receiver's annual figures.
#[derive(Clone, Debug, Default)]
pub struct ReceiverFigures {
    pub name: String,
    pub shape: [u32; 2],
    pub cells: Vec<CellFigures>,
    /// Area fractions.
    pub sda: Interval,
    pub ase: Interval,
    /// Fraction of occupied hours with the blinds closed.
    pub blinds_hours: Interval,
    /// Per EN 17037 level: the fraction of daylight hours meeting E_T over 50 % of the
    /// plane and E_TM over 95 % (the smaller of the two), and its verdict.
    pub en17037: Vec<(&'static str, Interval, &'static str)>,
    /// LEED v4.1 points for sDA (0–3) at the interval's ends.
    pub leed_points: [u32; 2],
}

/// Every analysed receiver's figures.
#[derive(Clone, Debug, Default)]
pub struct AnnualFigures {
    pub receivers: Vec<ReceiverFigures>,
}

impl ReceiverFigures {
    /// Whether ASE exceeds 10 % of the area (LEED then asks for a glare note).
    pub fn ase_over_10_percent(&self) -> &'static str {
        let over = |x: f64| x > 0.1;
        verdict(
            over(self.ase.low),
            over(self.ase.value),
            over(self.ase.high),
        )
    }
}

impl AnnualFigures {
    pub fn new(
        matrix: &SkyMatrix,
        hourly: &[Hourly],
        scene: &Scene,
        annual: &Annual,
    ) -> AnnualFigures {
        let receivers = (annual.receivers.iter().zip(hourly))
            .map(|(&r, h)| receiver_figures(matrix, h, &scene.receivers[r], annual))
            .collect();
        AnnualFigures { receivers }
    }

    pub fn widest_sda_halfwidth(&self) -> f64 {
        self.receivers
            .iter()
            .map(|r| r.sda.halfwidth())
            .fold(0.0, f64::max)
    }
}

/// LEED v4.1 points for an sDA area fraction.
pub fn leed_points(sda: f64) -> u32 {
    match sda {
        s if s >= 0.75 => 3,
        s if s >= 0.55 => 2,
        s if s >= 0.40 => 1,
        _ => 0,
    }
}

/// Per z of the grid: each cell's counts.
struct AtZ {
    da: Vec<u32>,
    cda: Vec<f64>,
    da_blinds: Vec<u32>,
    ase: Vec<u32>,
    /// Lit occupied hours per UDI bin.
    udi: Vec<[u32; 4]>,
    blinds_hours: u32,
    /// Per EN 17037 level: daylight hours meeting E_T over 50 % and E_TM over 95 %.
    en17037: [[u32; 2]; 3],
}

fn counts_at(matrix: &SkyMatrix, h: &Hourly, z: f64, shade: f64, daylight: &[bool]) -> AtZ {
    let n = h.cells;
    let mut a = AtZ {
        da: vec![0; n],
        cda: vec![0.0; n],
        da_blinds: vec![0; n],
        ase: vec![0; n],
        udi: vec![[0; 4]; n],
        blinds_hours: 0,
        en17037: [[0; 2]; 3],
    };
    let mut e = vec![0.0f64; n];
    for (t, hour) in matrix.hours.iter().enumerate() {
        let range = h.at(t);
        for (c, k) in range.clone().enumerate() {
            e[c] = h.e[k] as f64 + z * h.sigma[k] as f64;
        }
        if daylight[t] {
            for (level, &(_, target, minimum)) in EN17037_LEVELS.iter().enumerate() {
                let over = |lx: f64| e.iter().filter(|&&x| x >= lx).count() as f64 / n as f64;
                a.en17037[level][0] += (over(target) >= 0.5) as u32;
                a.en17037[level][1] += (over(minimum) >= 0.95) as u32;
            }
        }
        if !hour.occupied {
            continue;
        }
        let mut sunlit = 0;
        for (c, k) in range.enumerate() {
            if h.sun[k] as f64 + z * h.sun_sigma[k] as f64 > ASE_LX {
                a.ase[c] += 1;
                sunlit += 1;
            }
        }
        let blinds = sunlit as f64 > BLINDS_AREA_FRACTION * n as f64;
        a.blinds_hours += blinds as u32;
        let scale = if blinds { shade } else { 1.0 };
        for (c, &x) in e.iter().enumerate() {
            a.da[c] += (x >= DA_LX) as u32;
            a.cda[c] += (x / DA_LX).clamp(0.0, 1.0);
            a.da_blinds[c] += (scale * x >= DA_LX) as u32;
            a.udi[c][UDI_EDGES_LX.iter().filter(|&&edge| x >= edge).count()] += 1;
        }
    }
    a
}

/// The lit hours that are EN 17037 daylight hours: the [`EN17037_HOURS`] records with
/// the most global horizontal illuminance (dark records count as 0).
fn daylight_hours(matrix: &SkyMatrix) -> Vec<bool> {
    let mut order: Vec<usize> = (0..matrix.hours.len()).collect();
    order.sort_by(|&a, &b| {
        let (x, y) = (
            matrix.hours[a].global_horizontal_lx,
            matrix.hours[b].global_horizontal_lx,
        );
        y.total_cmp(&x).then(a.cmp(&b))
    });
    let mut out = vec![false; matrix.hours.len()];
    for &t in order.iter().take(EN17037_HOURS) {
        out[t] = true;
    }
    out
}

fn receiver_figures(
    matrix: &SkyMatrix,
    h: &Hourly,
    receiver: &crate::scene::Receiver,
    annual: &Annual,
) -> ReceiverFigures {
    let grid = z_grid();
    let daylight = daylight_hours(matrix);
    let at: Vec<AtZ> = (grid.par_iter())
        .map(|&z| counts_at(matrix, h, z, annual.shade_transmittance, &daylight))
        .collect();
    let occupied = matrix.occupied_records.max(1) as f64;
    let daylight_total = EN17037_HOURS.min(matrix.records).max(1) as f64;
    let n = h.cells;
    let series = |f: &dyn Fn(&AtZ) -> f64| -> Interval {
        Interval::of(&grid, &at.iter().map(f).collect::<Vec<_>>())
    };
    let cells: Vec<CellFigures> = (0..n)
        .map(|c| cell_figures(h, c, &grid, &at, occupied))
        .collect();
    let sda = series(&|a| {
        a.da_blinds
            .iter()
            .filter(|&&d| d as f64 / occupied >= SDA_HOURS_FRACTION)
            .count() as f64
            / n as f64
    });
    let ase =
        series(&|a| a.ase.iter().filter(|&&d| d as usize > ASE_HOURS).count() as f64 / n as f64);
    let en17037 = (EN17037_LEVELS.iter().enumerate())
        .map(|(level, &(name, _, _))| {
            let fraction =
                series(&|a| a.en17037[level][0].min(a.en17037[level][1]) as f64 / daylight_total);
            let met = |x: f64| x >= 0.5;
            (
                name,
                fraction,
                verdict(met(fraction.low), met(fraction.value), met(fraction.high)),
            )
        })
        .collect();
    ReceiverFigures {
        name: receiver.name.clone(),
        shape: receiver.cells,
        cells,
        sda,
        ase,
        blinds_hours: series(&|a| a.blinds_hours as f64 / occupied),
        en17037,
        leed_points: [leed_points(sda.low), leed_points(sda.high)],
    }
}

fn cell_figures(h: &Hourly, c: usize, grid: &[f64], at: &[AtZ], occupied: f64) -> CellFigures {
    let series = |f: &dyn Fn(&AtZ) -> f64| -> Interval {
        Interval::of(grid, &at.iter().map(f).collect::<Vec<_>>())
    };
    // Dark occupied records fall in the lowest bin.
    let udi_share = |a: &AtZ, bin: usize| {
        let lit: u32 = a.udi[c].iter().sum();
        let dark = if bin == 0 { occupied - lit as f64 } else { 0.0 };
        (a.udi[c][bin] as f64 + dark) / occupied
    };
    let passes_sda: Vec<bool> = at
        .iter()
        .map(|a| a.da_blinds[c] as f64 / occupied >= SDA_HOURS_FRACTION)
        .collect();
    let passes_ase: Vec<bool> = at.iter().map(|a| a.ase[c] as usize > ASE_HOURS).collect();
    CellFigures {
        mean_lx: h.mean_lx[c],
        mean_sigma_lx: h.mean_sigma_lx[c],
        da: series(&|a| a.da[c] as f64 / occupied),
        cda: series(&|a| a.cda[c] / occupied),
        da_blinds: series(&|a| a.da_blinds[c] as f64 / occupied),
        sda_probability: probability(grid, &passes_sda),
        ase_hours: series(&|a| a.ase[c] as f64),
        ase_probability: probability(grid, &passes_ase),
        udi: [0, 1, 2, 3].map(|bin| series(&|a| udi_share(a, bin))),
    }
}

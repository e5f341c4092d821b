//! Statistics of the tallies: the equations of method.md, evaluated once per epoch.
//! They only read tallies; they never touch the photon path.

pub mod forecast;
pub mod stop;

use crate::scene::Geometry;
use crate::tally::{CellSums, Counts, Slot, Tallies};

/// Relative error reported for a value of 0 whose σ is known: 100 %, so no relative
/// target can be met by a quantity nothing has reached.
pub const REL_ERROR_UNKNOWN: f64 = 1.0;

/// Estimate and standard error of one cell from its history moments, N histories
/// (eqs. 6–7, with the unbiased N/(N−1) variance). Returns (value, sigma) in the score's
/// unit: value = Σx/N, sigma = sqrt(Var(x)/N); sigma is NaN (unknown) below 2 histories.
pub fn cell_estimate(sum: f64, sum_sq: f64, n: u64) -> (f64, f64) {
    if n == 0 {
        return (0.0, f64::NAN);
    }
    let nf = n as f64;
    let mean = sum / nf;
    if n == 1 {
        return (mean, f64::NAN);
    }
    let variance = ((sum_sq / nf - mean * mean) * nf / (nf - 1.0)).max(0.0);
    (mean, (variance / nf).sqrt())
}

/// A cell's value and its σ from its own sums alone: the photons' estimate (eqs. 6–7
/// over the histories) plus the sampled direct light (the same equations over its
/// replicates); the two are independent, so their variances add. σ is NaN (unknown)
/// when nothing has scored in the cell, neither a photon nor a non-zero direct sample,
/// so its error cannot be estimated, whatever its true value (unless the scene emits no
/// light at all). Receivers report [`receiver_stats`]'s σ instead, which also looks at
/// the cell's neighbours where few photons scored.
pub fn cell_value(c: &CellSums, counts: Counts) -> (f64, f64) {
    let p = photon_part(c, counts);
    let (direct_value, direct_var) = direct_part(c, counts);
    if c.hits == 0 {
        return (0.0, if counts.dark { 0.0 } else { f64::NAN });
    }
    let unit = counts.unit;
    (
        (p.value + direct_value) * unit,
        (p.var + direct_var).sqrt() * unit,
    )
}

/// The photons' part of a cell, in the score unit (variances in it stay finite where
/// those in the receiver's unit would not): value Σx/N, its own variance estimate (eq. 7
/// squared) and the standard deviation of that variance estimate, sqrt(M₄)/N² (M₄ the
/// fourth central moment sum; nearly all histories score 0 or once, so the terms of M₂
/// are the scores' squares).
#[derive(Clone, Copy, Debug, Default)]
struct PhotonPart {
    value: f64,
    var: f64,
    var_sd: f64,
}

fn photon_part(c: &CellSums, counts: Counts) -> PhotonPart {
    let m = c.photon_moments(counts);
    let (value, var) = m.mean_and_variance();
    if !(var >= 0.0) {
        return PhotonPart {
            value,
            ..PhotonPart::default()
        };
    }
    let n = counts.photons as f64;
    PhotonPart {
        value,
        var,
        var_sd: m.m4.max(0.0).sqrt() / (n * n),
    }
}

/// The direct light's part of a cell: value and variance over its replicates, in the
/// score unit.
fn direct_part(c: &CellSums, counts: Counts) -> (f64, f64) {
    if counts.direct_replicates == 0 {
        return (0.0, 0.0);
    }
    let (value, var) = c.direct_moments(counts).mean_and_variance();
    (value, if var >= 0.0 { var } else { 0.0 })
}

/// The sampled direct part of a cell and its σ, in the receiver's unit ((0, 0) for a
/// receiver without sampled direct light; σ NaN below 2 replicates).
pub fn direct_estimate(c: &CellSums, counts: Counts) -> (f64, f64) {
    if counts.direct_replicates == 0 {
        return (0.0, 0.0);
    }
    let (value, var) = c.direct_moments(counts).mean_and_variance();
    (value * counts.unit, var.sqrt() * counts.unit)
}

/// The photons' variance of a cell that sees its own error where few photons scored.
///
/// A cell's own estimate `own` (eq. 7) comes from the same scores as its value: where a
/// cell draws k ≈ Poisson(λ) scores of similar size, both its value and `own` ∝ k, so a
/// cell that drew few scores reports a low value *and* a small σ, and z = (k − λ)/√k
/// has a heavy negative tail (k = 3 at λ = 11 reads −4.6σ). The variance it should
/// report is that of the count it should have drawn, which its neighbours see
/// independently of its own draw: `pooled` is the median of the 8 neighbours' own
/// variances (the median, not the mean, so that across a shadow or cone edge the side
/// the cell lies on decides). The cell keeps its own estimate where that is larger
/// beyond its own noise `own_sd` (a real edge, a peak, or a large score it really drew),
/// lowered by at most `pooled`:
///
/// ```text
/// var = max(pooled, own − min(own_sd, pooled))
/// ```
///
/// Where the neighbours saw nothing (pooled = 0) this is `own`; where counts are high
/// both agree and it is the pooled estimate (unbiased for a field that varies linearly
/// across the 3 × 3 cells). For Poisson counts with λ known to the neighbours, the
/// z-scores' RMS is 0.97–0.99 from λ = 2 to 100 and their tails beyond 3σ are no heavier
/// than a normal's (with `own` alone: RMS 1.13 and 12× the normal's rate below −3σ at
/// λ = 11); docs/method.md has the measurements on real receivers.
pub fn pooled_variance(own: f64, own_sd: f64, pooled: f64) -> f64 {
    pooled.max(own - own_sd.min(pooled))
}

/// Median of the photon variances of cell (i, j)'s up to 8 neighbours in a grid of
/// `nu × nv` cells (0 without neighbours). Inside the grid, a 19-comparator sorting
/// network (no branches: this runs over every cell at every epoch).
fn neighbour_median(var: &[f64], nu: usize, nv: usize, i: usize, j: usize) -> f64 {
    if i > 0 && j > 0 && i + 1 < nu && j + 1 < nv {
        let (up, down) = ((j - 1) * nu + i, (j + 1) * nu + i);
        let row = j * nu + i;
        let [mut x0, mut x1, mut x2, mut x3, mut x4, mut x5, mut x6, mut x7] = [
            var[up - 1],
            var[up],
            var[up + 1],
            var[row - 1],
            var[row + 1],
            var[down - 1],
            var[down],
            var[down + 1],
        ];
        // Compare-exchange on locals (kept in registers); variances are never NaN.
        macro_rules! cx {
            ($($a:ident $b:ident),*) => {$(
                let (lo, hi) = if $a < $b { ($a, $b) } else { ($b, $a) };
                $a = lo;
                $b = hi;
            )*};
        }
        cx!(x0 x1, x2 x3, x4 x5, x6 x7, x0 x2, x1 x3, x4 x6, x5 x7, x1 x2, x5 x6);
        cx!(x0 x4, x3 x7, x1 x5, x2 x6, x1 x4, x3 x6, x2 x4, x3 x5, x3 x4);
        let _ = (x0, x1, x2, x5, x6, x7);
        return 0.5 * (x3 + x4);
    }
    let mut nb = [0.0f64; 8];
    let mut n = 0;
    for jj in j.saturating_sub(1)..(j + 2).min(nv) {
        for ii in i.saturating_sub(1)..(i + 2).min(nu) {
            if (ii, jj) != (i, j) {
                nb[n] = var[jj * nu + ii];
                n += 1;
            }
        }
    }
    let nb = &mut nb[..n];
    if n == 0 {
        return 0.0;
    }
    nb.sort_unstable_by(f64::total_cmp);
    if n % 2 == 1 {
        nb[n / 2]
    } else {
        0.5 * (nb[n / 2 - 1] + nb[n / 2])
    }
}

/// VOV of a cell's value (photon part plus direct part): the parts are independent, so
/// the variance of its variance estimate is the sum of theirs,
/// VOV = (VOV_p·σ_p⁴ + VOV_d·σ_d⁴)/(σ_p² + σ_d²)²; 0 for a cell whose samples are all
/// equal, 1 when nothing is known. Invariant
/// to the light's level (the moments are central and in the score unit).
pub fn cell_vov(c: &CellSums, counts: Counts) -> f64 {
    let (photons, direct) = (c.photon_moments(counts), c.direct_moments(counts));
    let part = |m: &crate::tally::Moments| match m.mean_and_variance() {
        (_, var) if var > 0.0 => (m.vov(), var),
        _ => (0.0, 0.0),
    };
    let (vov_p, var_p) = part(&photons);
    let (vov_d, var_d) = part(&direct);
    let var = var_p + var_d;
    let samples = photons.n + direct.n;
    if var > 0.0 {
        (vov_p * var_p * var_p + vov_d * var_d * var_d) / (var * var)
    } else if samples >= 2 && c.hits > 0 {
        // Equal samples (a direct light every replicate sees alike): known exactly.
        0.0
    } else {
        1.0
    }
}

/// σ_rel of a value (eq. 8): NaN when σ is unknown, [`REL_ERROR_UNKNOWN`] for a zero
/// value.
pub fn relative_error(value: f64, sigma: f64) -> f64 {
    if sigma.is_nan() {
        f64::NAN
    } else if value > 0.0 {
        sigma / value
    } else {
        REL_ERROR_UNKNOWN
    }
}

/// Relative variance of the variance (MCNP's VOV) of a mean from the moments
/// [Σx, Σx², Σx³, Σx⁴] of N histories: Σ(x−x̄)⁴ / (Σ(x−x̄)²)² − 1/N. Below 0.1 the σ
/// of that mean can be trusted; 1 when nothing is known yet.
pub fn variance_of_variance(moments: [f64; 4], n: u64) -> f64 {
    if n < 2 {
        return 1.0;
    }
    let nf = n as f64;
    let [s1, s2, s3, s4] = moments;
    let m = s1 / nf;
    let c2 = s2 - s1 * m;
    if c2 <= 0.0 {
        return 1.0;
    }
    let c4 = s4 - 4.0 * m * s3 + 6.0 * m * m * s2 - 3.0 * nf * m.powi(4);
    (c4 / (c2 * c2) - 1.0 / nf).max(0.0)
}

/// Reading back numbers that serde_json wrote as null (it writes NaN and ±∞ so): NaN,
/// an unknown value, as the statistics write it.
pub mod null_as_nan {
    use serde::{Deserialize, Deserializer};

    pub fn f64<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }

    pub fn vec<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<Option<f64>>::deserialize(d)?
            .into_iter()
            .map(|x| x.unwrap_or(f64::NAN))
            .collect())
    }
}

/// Mean and mean relative error of a set of cells (eq. 9), by both averagings.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Averaged {
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub arithmetic: f64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub quadratic: f64,
}

/// Receiver (or block) summary per eq. 9: the arithmetic mean value and the RMS σ over
/// the mean by arithmetic and quadratic averaging of the values.
pub fn mean_error(values: &[f64], sigmas: &[f64]) -> (f64, Averaged) {
    let (mean, rel, _, _) = mean_error_of(values.iter().copied().zip(sigmas.iter().copied()));
    (mean, rel)
}

/// [`mean_error`] over (value, σ) pairs, with the RMS σ and the quadratic mean: one pass,
/// no arrays (a receiver of 10⁶ cells is summarised after every epoch). Each sum is
/// taken in the pairs' order.
fn mean_error_of(pairs: impl Iterator<Item = (f64, f64)>) -> (f64, Averaged, f64, f64) {
    let (mut k, mut sum, mut sum_sq, mut sigma_sq) = (0usize, -0.0f64, -0.0f64, -0.0f64);
    for (v, sigma) in pairs {
        k += 1;
        sum += v;
        sum_sq += v * v;
        sigma_sq += sigma * sigma;
    }
    if k == 0 {
        let unknown = Averaged {
            arithmetic: f64::NAN,
            quadratic: f64::NAN,
        };
        return (0.0, unknown, 0.0, 0.0);
    }
    let k = k as f64;
    let mean = sum / k;
    let quadratic_mean = (sum_sq / k).sqrt();
    let rms_sigma = (sigma_sq / k).sqrt();
    let rel = Averaged {
        arithmetic: relative_error(mean, rms_sigma),
        quadratic: relative_error(quadratic_mean, rms_sigma),
    };
    (mean, rel, rms_sigma, quadratic_mean)
}

/// One-sided 95 % quantile of the normal distribution.
const Z_95: f64 = 1.644_853_626_951_472_2;

/// No score in N trials bounds the chance of one by this over N at 95 % (−ln 0.05 =
/// 2.996, rounded up).
const NO_SCORE_95: f64 = 3.0;

/// Fewest effective samples (Welch–Satterthwaite degrees of freedom, [`cell_dof`])
/// behind a reliable cell's σ: at 30, Student's t puts 1.0 × 10⁻⁴ beyond 4.5σ (the
/// normal 6.8 × 10⁻⁶), and a cell's own variance estimate is good to about ±25 %.
pub const MIN_RELIABLE_DOF: f64 = 30.0;

/// Largest VOV of a reliable cell (MCNP's rule for a tally bin).
pub const MAX_RELIABLE_VOV: f64 = 0.1;

/// How far a cell's value and σ can be trusted (`status` of summary.json's receivers).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CellStatus {
    /// Scored, with at least [`MIN_RELIABLE_DOF`] effective samples and a VOV of at most
    /// [`MAX_RELIABLE_VOV`] behind its σ.
    #[default]
    Reliable,
    /// Scored, but by too few (or too uneven) samples for its σ to be trusted.
    Unreliable,
    /// Nothing scored in it while other cells of its receiver scored: value 0, with an
    /// upper bound (`upper_bound`) instead of a σ.
    Dark,
    /// Nothing scored, and nothing to bound it by: no cell of the receiver has scored.
    Unknown,
}

impl CellStatus {
    pub fn as_str(self) -> &'static str {
        match self {
            CellStatus::Reliable => "reliable",
            CellStatus::Unreliable => "unreliable",
            CellStatus::Dark => "dark",
            CellStatus::Unknown => "unknown",
        }
    }
}

/// Effective degrees of freedom of a cell's variance estimate, by Welch–Satterthwaite
/// over its two independent parts: the photons' (variance `var_p` from about n_p − 1
/// degrees of freedom, n_p the effective number of scoring histories (Σx)²/Σx²) and the
/// direct light's (`var_d`, n_d the effective replicates). A cell whose σ rests on a
/// handful of scores has few, whatever its σ says. A cell whose samples are all equal
/// (variance 0) has its sample count less one.
pub fn cell_dof(c: &CellSums, counts: Counts, var_p: f64, var_d: f64) -> f64 {
    // A part of a single effective sample counts as one degree of freedom: its share of
    // the variance then decides, not a vanishing n − 1.
    let term = |var: f64, n: f64| {
        if var > 0.0 {
            var * var / (n - 1.0).max(1.0)
        } else {
            0.0
        }
    };
    let n_p = c.photon_moments(counts).effective_count();
    let n_d = c.direct_moments(counts).effective_count();
    let denominator = term(var_p, n_p) + term(var_d, n_d);
    let var = var_p + var_d;
    if denominator > 0.0 {
        var * var / denominator
    } else if var > 0.0 {
        0.0
    } else {
        (n_p + n_d - 1.0).max(0.0)
    }
}

/// One-sided 95 % quantile of Student's t with `dof` degrees of freedom (at least 1): a
/// table to 10, the Cornish–Fisher expansion above (within 10⁻³ there).
pub fn student_t_95(dof: f64) -> f64 {
    const TABLE: [f64; 10] = [
        6.314, 2.920, 2.353, 2.132, 2.015, 1.943, 1.895, 1.860, 1.833, 1.812,
    ];
    let dof = dof.max(1.0);
    if dof < 10.0 {
        return TABLE[dof.floor() as usize - 1];
    }
    let z = Z_95;
    let (z3, z5) = (z.powi(3), z.powi(5));
    z + (z3 + z) / (4.0 * dof) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * dof * dof)
}

/// Upper bound (about 95 %, in the receiver's unit) on the value of a dark cell, one
/// nothing reached in `counts`' histories and replicates. No score in N histories
/// bounds the chance that a history scores there by 3/N (Poisson, zero events), so its
/// photons' part by 3/N times the score a history leaves in a typical cell of its
/// receiver; no unoccluded sample among the R replicates' S samples each bounds the
/// share of its direct light's samples that see a light by 3/(S·R), so its direct part
/// by 3/(S·R) times a typical cell's replicate mean (the mean weight of a sample that
/// sees a light). `typical` = (score per scoring history, replicate mean over S) in the
/// score unit ([`typical_scores`]); it assumes the dark cell, if it were reached, would
/// be reached like a typical cell.
pub fn dark_upper_bound(counts: Counts, typical: (f64, f64)) -> f64 {
    let part = |n: u64, typical: f64| {
        if n > 0 {
            NO_SCORE_95 / n as f64 * typical
        } else {
            0.0
        }
    };
    (part(counts.photons, typical.0) + part(counts.direct_replicates, typical.1)) * counts.unit
}

/// The σ an unreliable cell is judged by: its own σ, which it cannot vouch for, widened
/// by Student's t on its degrees of freedom ν ([`cell_dof`]) against the normal's
/// quantile, t₀.₉₅(ν)/z₀.₉₅, and by 1 + √VOV (√VOV is the relative spread of σ² itself).
pub fn widened_sigma(sigma: f64, vov: f64, dof: f64) -> f64 {
    sigma * student_t_95(dof) / Z_95 * (1.0 + vov.sqrt())
}

/// Upper bound (about 95 %) on the value of an unreliable cell: value + 1.645 times its
/// [`widened_sigma`].
pub fn unreliable_upper_bound(value: f64, sigma: f64, vov: f64, dof: f64) -> f64 {
    value + Z_95 * widened_sigma(sigma, vov, dof)
}

/// What a history and a replicate leave in a typical cell of a receiver, in the score
/// unit: the medians over the cells that scored of the mean score per scoring history
/// (Σx/k) and of the direct light's replicate mean over S, the samples of a replicate
/// (what one unoccluded sample adds): what bounds a dark cell, [`dark_upper_bound`].
fn typical_scores(cells: &[CellSums], counts: Counts) -> (f64, f64) {
    let median = |mut x: Vec<f64>| {
        if x.is_empty() {
            return 0.0;
        }
        let mid = x.len() / 2;
        *x.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    let samples = crate::trace::direct::points_per_side(cells.len()).pow(2) as f64;
    let per_history = (cells.iter())
        .filter(|c| c.scoring_histories > 0)
        .map(|c| c.photons.sum() / c.scoring_histories as f64)
        .collect();
    let per_sample = (cells.iter())
        .map(|c| c.direct_moments(counts).mean / samples)
        .filter(|&y| y > 0.0)
        .collect();
    (median(per_history), median(per_sample))
}

/// Values, errors and hits of one receiver.
#[derive(Clone, Debug, Default)]
pub struct ReceiverStats {
    pub values: Vec<f64>,
    /// NaN where the cell's error is unknown (nothing scored there).
    pub sigma: Vec<f64>,
    pub hits: Vec<u64>,
    /// Histories that scored in each cell.
    pub scoring_histories: Vec<u64>,
    /// Each cell's VOV ([`cell_vov`]; 1 where nothing is known).
    pub vov: Vec<f64>,
    /// Each cell's effective degrees of freedom ([`cell_dof`]; 0 where nothing scored).
    pub dof: Vec<f64>,
    pub status: Vec<CellStatus>,
    /// Upper bound of each dark or unreliable cell's value ([`dark_upper_bound`],
    /// [`unreliable_upper_bound`]; NaN for the others).
    pub upper_bound: Vec<f64>,
    pub mean: f64,
    /// Eq. 9 over all cells: NaN while some cell's error is unknown.
    pub rel_error: Averaged,
    /// Eq. 9 over the cells whose error is known.
    pub rel_error_known: Averaged,
    /// Cells whose error is unknown: dark and unknown cells.
    pub unknown_cells: usize,
    pub unreliable_cells: usize,
    pub dark_cells: usize,
    /// Largest upper bound of a dark cell (0 without).
    pub dark_bound: f64,
    /// RMS σ over the cells (eq. 9's numerator), in the receiver's unit; NaN while some
    /// cell's error is unknown.
    pub rms_sigma: f64,
    /// The σ a target judges each cell by: its σ if reliable, [`widened_sigma`] if
    /// unreliable, NaN for dark and unknown cells; eq. 9 (quadratic), the RMS σ and the
    /// quadratic mean value over the cells it is known for.
    pub judged_sigma: Vec<f64>,
    pub rel_error_judged: f64,
    pub rms_sigma_judged: f64,
    pub quadratic_mean_judged: f64,
}

/// Per-cell values and σ of a receiver's cells `cells`, a grid of `shape` = [nu, nv]
/// cells stored j·nu + i: the value as [`cell_value`], the σ with the photons' variance
/// from [`pooled_variance`] over the cell's neighbours. Cells where nothing scored keep
/// an unknown σ.
pub fn cell_values(cells: &[CellSums], shape: [u32; 2], counts: Counts) -> (Vec<f64>, Vec<f64>) {
    let (values, sigmas, _) = cell_values_and_parts(cells, shape, counts);
    (values, sigmas)
}

/// [`cell_values`], with each cell's photon and direct variances as reported (in the
/// score unit).
fn cell_values_and_parts(
    cells: &[CellSums],
    shape: [u32; 2],
    counts: Counts,
) -> (Vec<f64>, Vec<f64>, Vec<(f64, f64)>) {
    use rayon::prelude::*;
    // Cells are independent, each computed the same way on any thread (same bits); a
    // 10⁶-cell receiver took ≈ 100 ms per epoch on one thread. Run inside the run's pool.
    const MIN_CELLS_PER_TASK: usize = 4096;
    let (nu, nv) = (shape[0] as usize, shape[1] as usize);
    debug_assert_eq!(nu * nv, cells.len());
    let parts: Vec<PhotonPart> = cells
        .par_iter()
        .with_min_len(MIN_CELLS_PER_TASK)
        .map(|c| photon_part(c, counts))
        .collect();
    let own: Vec<f64> = parts.iter().map(|p| p.var).collect();
    let per_cell: Vec<(f64, f64, (f64, f64))> = cells
        .par_iter()
        .zip(&parts)
        .enumerate()
        .with_min_len(MIN_CELLS_PER_TASK)
        .map(|(k, (c, p))| {
            if c.hits == 0 {
                return (0.0, if counts.dark { 0.0 } else { f64::NAN }, (0.0, 0.0));
            }
            let pooled = neighbour_median(&own, nu, nv, k % nu, k / nu);
            let (direct_value, direct_var) = direct_part(c, counts);
            let photon_var = pooled_variance(p.var, p.var_sd, pooled);
            (
                (p.value + direct_value) * counts.unit,
                (photon_var + direct_var).sqrt() * counts.unit,
                (photon_var, direct_var),
            )
        })
        .collect();
    let mut values = Vec::with_capacity(cells.len());
    let mut sigmas = Vec::with_capacity(cells.len());
    let mut vars = Vec::with_capacity(cells.len());
    for (v, s, p) in per_cell {
        values.push(v);
        sigmas.push(s);
        vars.push(p);
    }
    (values, sigmas, vars)
}

/// Per-cell statistics of a receiver's cells `cells` ([`cell_values`]), a grid of
/// `shape` cells, summarised over the cells `picked` (local indices; `None`: all).
/// Each cell's VOV, degrees of freedom and [`CellStatus`] too: eq. 9 is reported over
/// all cells and over those whose error is known (not dark, not unknown).
pub fn receiver_stats(
    cells: &[CellSums],
    shape: [u32; 2],
    counts: Counts,
    picked: Option<&[usize]>,
) -> ReceiverStats {
    use rayon::prelude::*;
    let (values, sigmas, vars) = cell_values_and_parts(cells, shape, counts);
    // Local index of the `i`-th cell summarised (a whole receiver needs no list).
    let count = picked.map_or(cells.len(), <[usize]>::len);
    let index = |i: usize| picked.map_or(i, |p| p[i]);
    let receiver_scored = cells.iter().any(|c| c.hits > 0);
    // Each cell's VOV and degrees of freedom, in parallel as the values above.
    let vov_dof: Vec<(f64, f64)> = (0..count)
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| {
            let k = index(i);
            let c = &cells[k];
            if c.hits > 0 || counts.dark {
                let dof = cell_dof(c, counts, vars[k].0, vars[k].1);
                (cell_vov(c, counts), dof)
            } else {
                (1.0, 0.0)
            }
        })
        .collect();
    // The same bound for every dark cell, computed only when there is one.
    let dark_bound = std::cell::OnceCell::new();
    let mut s = ReceiverStats::default();
    for (i, &(vov, dof)) in vov_dof.iter().enumerate() {
        let k = index(i);
        let c = &cells[k];
        let status = cell_status(c, counts, receiver_scored, vov, dof);
        s.values.push(values[k]);
        s.sigma.push(sigmas[k]);
        s.hits.push(c.hits);
        s.scoring_histories.push(c.scoring_histories);
        s.vov.push(vov);
        s.dof.push(dof);
        s.status.push(status);
        s.upper_bound.push(match status {
            CellStatus::Dark => {
                *dark_bound.get_or_init(|| dark_upper_bound(counts, typical_scores(cells, counts)))
            }
            CellStatus::Unreliable => unreliable_upper_bound(values[k], sigmas[k], vov, dof),
            _ => f64::NAN,
        });
    }
    // Eq. 9 in the score unit (exact: a power of two), where squares stay finite.
    let unit = counts.unit;
    let pairs = || (s.values.iter().zip(&s.sigma)).map(|(v, sigma)| (v / unit, sigma / unit));
    let all = mean_error_of(pairs());
    (s.mean, s.rel_error, s.rms_sigma) = (all.0 * unit, all.1, all.2 * unit);
    let known = mean_error_of(pairs().filter(|(_, sigma)| !sigma.is_nan()));
    s.rel_error_known = known.1;
    // The lit cells with the σ a target judges them by: widened where unreliable.
    s.judged_sigma = (0..s.values.len())
        .map(|k| match s.status[k] {
            CellStatus::Unreliable => widened_sigma(s.sigma[k], s.vov[k], s.dof[k]),
            CellStatus::Reliable => s.sigma[k],
            _ => f64::NAN,
        })
        .collect();
    let judged = (s.values.iter().zip(&s.judged_sigma))
        .filter(|(_, sigma)| !sigma.is_nan())
        .map(|(v, sigma)| (v / unit, sigma / unit));
    let judged = mean_error_of(judged);
    s.rel_error_judged = judged.1.quadratic;
    s.rms_sigma_judged = judged.2 * unit;
    s.quadratic_mean_judged = judged.3 * unit;
    s.unknown_cells = s.sigma.iter().filter(|sigma| sigma.is_nan()).count();
    let count = |status| s.status.iter().filter(|&&x| x == status).count();
    s.unreliable_cells = count(CellStatus::Unreliable);
    s.dark_cells = count(CellStatus::Dark);
    s.dark_bound = dark_bound.get().copied().unwrap_or(0.0);
    s
}

/// A cell's [`CellStatus`] from its VOV and degrees of freedom, `receiver_scored` when
/// any cell of its receiver scored. In a scene that emits nothing every cell is an
/// exact 0 ± 0: reliable.
fn cell_status(
    c: &CellSums,
    counts: Counts,
    receiver_scored: bool,
    vov: f64,
    dof: f64,
) -> CellStatus {
    if counts.dark {
        CellStatus::Reliable
    } else if c.hits > 0 {
        if dof >= MIN_RELIABLE_DOF && vov <= MAX_RELIABLE_VOV {
            CellStatus::Reliable
        } else {
            CellStatus::Unreliable
        }
    } else if receiver_scored {
        CellStatus::Dark
    } else {
        CellStatus::Unknown
    }
}

/// The scene map's illuminance and its odd/even error (method.md §3).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MapStats {
    /// Area-weighted mean illuminance <E> (arithmetic), lx.
    pub mean_lx: f64,
    /// RMS error of the combined map, σ = d/2 (eq. 5 with the /2 correction), lx.
    pub sigma_lx: f64,
    /// σ / <E>, with <E> averaged arithmetically and quadratically (eq. 4).
    pub rel_error: Averaged,
}

/// Which photon hits a map counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Every hit: the total illumination.
    Total,
    /// Hits after at least one scattering: the secondary illumination.
    Indirect,
}

/// Photon hits of one triangle in a map, from odd and from even photons (both faces).
#[inline]
fn parity_counts(slots: &[u64], kind: MapKind) -> (u64, u64) {
    let (mut odd, mut even) = (0, 0);
    for (slot, &c) in slots.iter().enumerate() {
        let slot = Slot::of(slot);
        if kind == MapKind::Indirect && !slot.indirect {
            continue;
        }
        if slot.odd_photon {
            odd += c;
        } else {
            even += c;
        }
    }
    (odd, even)
}

/// Illuminance of triangle `k` in a map: flux of both faces over the geometric area, from
/// photons of the given parities (`None`: all), lx.
pub fn triangle_illuminance_lx(
    t: &Tallies,
    kind: MapKind,
    k: usize,
    area_m2: f64,
    total_flux_lm: f64,
    parity: Option<bool>,
) -> f64 {
    let (n_odd, n_even) = t.odd_even_photons();
    let slots = t.triangle_slots(k);
    let (odd, even) = parity_counts(&slots, kind);
    let (count, photons) = match parity {
        None => (odd + even, n_odd + n_even),
        Some(true) => (odd, n_odd),
        Some(false) => (even, n_even),
    };
    if photons == 0 {
        return 0.0;
    }
    total_flux_lm * count as f64 / (photons as f64 * area_m2)
}

/// Illuminance of one face of triangle `k` in a map (`back_face`: the face behind the
/// triangle's normal), from all photons, lx. The two faces of
/// [`triangle_illuminance_lx`] kept apart: the eye sees one of them.
pub fn triangle_face_illuminance_lx(
    t: &Tallies,
    kind: MapKind,
    k: usize,
    area_m2: f64,
    total_flux_lm: f64,
    back_face: bool,
) -> f64 {
    if t.photons == 0 || area_m2 <= 0.0 {
        return 0.0;
    }
    let slots = t.triangle_slots(k);
    let count: u64 = slots
        .iter()
        .enumerate()
        .filter(|(slot, _)| {
            let slot = Slot::of(*slot);
            slot.back_face == back_face && (kind == MapKind::Total || slot.indirect)
        })
        .map(|(_, &c)| c)
        .sum();
    total_flux_lm * count as f64 / (t.photons as f64 * area_m2)
}

/// Relative error of every triangle's total illuminance in the scene map (σ/E; NaN
/// where no photon hit it: unknown).
///
/// A triangle's illuminance counts photons of equal flux, c of them over N photons.
/// The odd/even difference of one triangle, |E_odd − E_even|/2, is an estimate of its
/// σ with one degree of freedom (z-scores against it follow Student's t with 1 degree
/// of freedom, Cauchy's tails; it is 0 where as many odd as even photons hit); eq. 5
/// averages it over the scene. Per triangle we use the count itself: Var(c) = c for
/// histories hitting it at most once, times the scene's overdispersion
/// D = Σ(o − e)²/Σc (o, e: odd and even hits; E[(o − e)²] = Var(c)), which corrects
/// for photons hitting one triangle twice (1 in a scene of small triangles, up to 2–3 on
/// the few large faces of a bright room). As for receiver cells
/// ([`pooled_variance`]), a triangle that drew few hits would report a small value and
/// a small σ; the count it should have drawn is estimated by its neighbours (triangles
/// touching one of its corners' positions — `adjacent` from
/// [`crate::scene::adjacency::VertexFaces::by_position`], so that meshes whose triangles
/// keep their own vertices have neighbours too — those sharing an edge counted twice):
/// λ = median of their hits per m² × its area, and Var = D·max(λ, c − min(√c, λ)).
pub fn triangle_rel_errors(
    t: &Tallies,
    triangles: &[[u32; 3]],
    adjacent: &crate::scene::adjacency::VertexFaces,
    area_m2: impl Fn(usize) -> f64,
) -> Vec<f64> {
    let counts: Vec<(u64, u64)> = (0..triangles.len())
        .map(|k| parity_counts(&t.triangle_slots(k), MapKind::Total))
        .collect();
    let (mut d2, mut total) = (0.0f64, 0.0f64);
    for &(o, e) in &counts {
        d2 += (o as f64 - e as f64).powi(2);
        total += (o + e) as f64;
    }
    let dispersion = if total > 0.0 { d2 / total } else { 1.0 };
    let density: Vec<f64> = counts
        .iter()
        .enumerate()
        .map(|(k, &(o, e))| match area_m2(k) {
            a if a > 0.0 => (o + e) as f64 / a,
            _ => 0.0,
        })
        .collect();
    let mut nb: Vec<f64> = Vec::new();
    let mut rel = Vec::with_capacity(triangles.len());
    for (k, (&(o, e), tri)) in counts.iter().zip(triangles).enumerate() {
        let c = (o + e) as f64;
        if c == 0.0 {
            rel.push(f64::NAN);
            continue;
        }
        // The faces of its three vertices: a neighbour across an edge appears twice
        // (it shares two vertices), which weighs it double in the median, as it should.
        nb.clear();
        for &v in tri {
            for &j in adjacent.faces(v as usize) {
                if j as usize != k {
                    nb.push(density[j as usize]);
                }
            }
        }
        let lambda = match nb.len() {
            0 => 0.0,
            n => {
                let (below, &mut upper, _) = nb.select_nth_unstable_by(n / 2, f64::total_cmp);
                let median = if n % 2 == 1 {
                    upper
                } else {
                    0.5 * (below.iter().copied().fold(f64::MIN, f64::max) + upper)
                };
                median * area_m2(k)
            }
        };
        let var = dispersion * pooled_variance(c, c.sqrt(), lambda);
        rel.push(var.sqrt() / c);
    }
    rel
}

/// Mean illuminance and odd/even error of a scene map (eqs. 4–5, σ = d/2) over the
/// triangles of `g`. Runs after every epoch: triangles no photon reached add nothing
/// (exactly 0 to each sum) and are skipped before their area is computed.
pub fn map_stats(t: &Tallies, kind: MapKind, g: &Geometry, total_flux_lm: f64) -> MapStats {
    let total_area = g.total_area_m2();
    let (n_odd, n_even) = t.odd_even_photons();
    if total_area <= 0.0 || t.photons == 0 {
        return MapStats {
            rel_error: Averaged {
                arithmetic: REL_ERROR_UNKNOWN,
                quadratic: REL_ERROR_UNKNOWN,
            },
            ..MapStats::default()
        };
    }
    // One pass over the counts: flux per photon of all photons, of odd and of even ones,
    // in the score unit (a power of two: exact), where the squares below stay finite.
    let unit = t.score_unit;
    let total_flux_lm = total_flux_lm / unit;
    let per_photon = total_flux_lm / t.photons as f64;
    let per_odd = if n_odd > 0 {
        total_flux_lm / n_odd as f64
    } else {
        0.0
    };
    let per_even = if n_even > 0 {
        total_flux_lm / n_even as f64
    } else {
        0.0
    };
    let (mut sum_e, mut sum_e2, mut sum_d2) = (0.0, 0.0, 0.0);
    for k in 0..g.triangle_count() {
        let (odd, even) = parity_counts(&t.triangle_slots(k), kind);
        if odd == 0 && even == 0 {
            continue;
        }
        let a = g.area_m2(k);
        let e = per_photon * (odd + even) as f64 / a;
        sum_e += a * e;
        sum_e2 += a * e * e;
        let d = (per_odd * odd as f64 - per_even * even as f64) / a;
        sum_d2 += a * d * d;
    }
    let mean_lx = sum_e / total_area * unit;
    let quadratic_lx = (sum_e2 / total_area).sqrt() * unit;
    let sigma_lx = if n_odd > 0 && n_even > 0 {
        0.5 * (sum_d2 / total_area).sqrt() * unit
    } else {
        0.0
    };
    let unknown = n_odd == 0 || n_even == 0;
    MapStats {
        mean_lx,
        sigma_lx,
        rel_error: if unknown {
            Averaged {
                arithmetic: REL_ERROR_UNKNOWN,
                quadratic: REL_ERROR_UNKNOWN,
            }
        } else {
            Averaged {
                arithmetic: relative_error(mean_lx, sigma_lx),
                quadratic: relative_error(quadratic_lx, sigma_lx),
            }
        },
    }
}

/// Standard error (lx) of the scene's area-weighted mean illuminance Φ·Σk/(N·S), from
/// the per-history hit counts k (eq. 7 with the whole scene as one cell).
pub fn mean_illuminance_sigma_lx(t: &Tallies, total_area_m2: f64, total_flux_lm: f64) -> f64 {
    if total_area_m2 <= 0.0 {
        return 0.0;
    }
    let (_, sigma_hits) = cell_estimate(
        t.history_hits[0] as f64,
        t.history_hits[1] as f64,
        t.photons,
    );
    total_flux_lm * sigma_hits / total_area_m2
}

/// VOV of the scene's mean illuminance (from the per-history hit counts).
pub fn mean_illuminance_vov(t: &Tallies) -> f64 {
    variance_of_variance(t.history_hits.map(|m| m as f64), t.photons)
}

/// Figure of merit 1/(σ_rel²·t) (method.md §5): constant while the run converges as
/// 1/sqrt(t); 0 before any error or time is known.
pub fn figure_of_merit(rel_error: f64, elapsed_s: f64) -> f64 {
    if rel_error > 0.0 && elapsed_s > 0.0 {
        1.0 / (rel_error * rel_error * elapsed_s)
    } else {
        0.0
    }
}

/// Reliability of the target's error, in the spirit of MCNP's tally checks.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Reliability {
    /// FOM of the target now.
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub fom: f64,
    /// FOM now against FOM at half the photons: within ±10 % once σ_rel ∝ 1/sqrt(t).
    pub fom_stable: bool,
    /// Largest variance of the variance among the target's scored cells (or of the
    /// scene mean for `global`).
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub vov: f64,
    /// The bounce cap's bias bound (`bounce_cap_bias_bound`) is unknown, or not below
    /// [`BOUNCE_CAP_BIAS_SHARE`] of the σ_rel of the target or of the scene map: the
    /// error is then not reliable, whatever the FOM and VOV say.
    #[serde(default)]
    pub bounce_cap_biased: bool,
    /// The error can be trusted: FOM stable, VOV < 0.1 and the bounce cap's bias bound
    /// below 1 % of the σ.
    pub reliable: bool,
}

/// The share of a figure's σ_rel the bounce cap's bias bound must stay below.
pub const BOUNCE_CAP_BIAS_SHARE: f64 = 0.01;

impl Reliability {
    /// Judges the bounce cap's bias bound `bound` (`None`: unknown) against the σ_rel of
    /// the figures reported: unreliable unless it is below [`BOUNCE_CAP_BIAS_SHARE`] of
    /// each (a bound of 0 passes; a σ_rel that is 0 or unknown gives nothing to compare).
    pub fn with_bounce_cap(mut self, bound: Option<f64>, sigma_rel: &[f64]) -> Reliability {
        let below = |b: f64| {
            (sigma_rel.iter())
                .filter(|s| s.is_finite() && **s > 0.0)
                .all(|s| b == 0.0 || b < BOUNCE_CAP_BIAS_SHARE * s)
        };
        self.bounce_cap_biased = !bound.is_some_and(below);
        self.reliable &= !self.bounce_cap_biased;
        self
    }
}

/// Judges the history of (elapsed, photons, error) of a target and its VOV.
pub fn reliability(history: &[forecast::HistoryPoint], vov: f64) -> Reliability {
    let fom_at = |p: &forecast::HistoryPoint| figure_of_merit(p.rel_error, p.elapsed_s);
    let fom = history.last().map_or(0.0, fom_at);
    let fom_stable = match history.last() {
        Some(last) if history.len() >= 4 && fom > 0.0 => {
            let half = history
                .iter()
                .find(|p| p.photons * 2 >= last.photons)
                .unwrap_or(last);
            let fom_half = fom_at(half);
            fom_half > 0.0 && (fom / fom_half - 1.0).abs() < 0.1
        }
        _ => false,
    };
    Reliability {
        fom,
        fom_stable,
        vov,
        bounce_cap_biased: false,
        reliable: fom_stable && vov < 0.1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_estimate_matches_textbook_standard_error() {
        // Scores 0, 2, 4 over N = 3 histories: mean 2, unbiased variance 4, σ = sqrt(4/3).
        let (m, s) = cell_estimate(6.0, 20.0, 3);
        assert_eq!(m, 2.0);
        assert!((s - (4.0f64 / 3.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn single_hit_cells_follow_one_over_root_n() {
        // n hits of equal score among N histories: σ_rel → 1/sqrt(n) (eq. 11) for n ≪ N.
        let (n_hist, n_hits) = (1_000_000u64, 400u64);
        let (m, s) = cell_estimate(n_hits as f64, n_hits as f64, n_hist);
        let rel = relative_error(m, s);
        assert!((rel - 1.0 / (n_hits as f64).sqrt()).abs() < 1e-3 * rel);
    }

    #[test]
    fn pooled_variance_follows_the_neighbours_below_and_the_cell_above() {
        // A cell that drew few scores takes its neighbours' variance ...
        assert_eq!(pooled_variance(3.0, 3f64.sqrt(), 11.0), 11.0);
        // ... one that drew more keeps its own, less one standard deviation of it ...
        assert_eq!(pooled_variance(25.0, 5.0, 11.0), 20.0);
        // ... lowered by at most the pooled variance, and all of it where the
        // neighbours saw nothing.
        assert_eq!(pooled_variance(4.0, 2.0, 1.0), 3.0);
        assert_eq!(pooled_variance(1.0, 1.0, 0.0), 1.0);
    }

    #[test]
    fn neighbour_median_reads_the_eight_neighbours_and_fewer_at_borders() {
        // 3 × 3 grid holding 0..9: the centre's neighbours are 0..9 without 4.
        let var: Vec<f64> = (0..9).map(f64::from).collect();
        assert_eq!(neighbour_median(&var, 3, 3, 1, 1), 4.0); // median of 0,1,2,3,5,6,7,8
        assert_eq!(neighbour_median(&var, 3, 3, 0, 0), 3.0); // 1, 3, 4
        assert_eq!(neighbour_median(&var, 3, 3, 2, 1), 4.0); // 1, 2, 4, 7, 8
        assert_eq!(neighbour_median(&[5.0], 1, 1, 0, 0), 0.0);
        // The sorting network against a sort, on shuffled values.
        let mut rng = crate::rng::aux_stream(3);
        for _ in 0..1000 {
            let var: Vec<f64> = (0..9)
                .map(|_| (crate::sampling::uniform(&mut rng) * 4.0).floor())
                .collect();
            let mut nb: Vec<f64> = (0..9).filter(|&k| k != 4).map(|k| var[k]).collect();
            nb.sort_by(f64::total_cmp);
            assert_eq!(neighbour_median(&var, 3, 3, 1, 1), 0.5 * (nb[3] + nb[4]));
        }
    }

    #[test]
    fn a_cell_that_drew_few_scores_reports_the_sigma_of_the_count_it_should_have() {
        // 3 × 3 cells of 10⁶ histories each scoring 1 or 0: the neighbours drew 11
        // scores, the centre 3. Its σ is that of 11 scores, not of 3.
        let n = 1_000_000u64;
        let cell = |k: u32| {
            let mut c = CellSums::default();
            for _ in 0..k {
                c.photons.push(1.0);
            }
            c.hits = k as u64;
            c
        };
        let mut cells = vec![cell(11); 9];
        cells[4] = cell(3);
        let counts = Counts {
            photons: n,
            direct_replicates: 0,
            dark: false,
            unit: 1.0,
        };
        let (values, sigmas) = cell_values(&cells, [3, 3], counts);
        let own = cell_estimate(3.0, 3.0, n).1;
        let expected = cell_estimate(11.0, 11.0, n).1;
        assert_eq!(values[4], 3.0 / n as f64);
        assert!(
            (sigmas[4] - expected).abs() < 1e-15,
            "{} vs {expected} (own {own})",
            sigmas[4]
        );
        // A cell nothing reached keeps an unknown error.
        cells[4] = CellSums::default();
        assert!(cell_values(&cells, [3, 3], counts).1[4].is_nan());
    }

    #[test]
    fn cell_statistics_are_the_same_bits_on_one_thread_and_on_two() {
        // 200 × 100 cells (several rayon tasks) of varied sums, some empty.
        let mut rng = crate::rng::aux_stream(5);
        let cells: Vec<CellSums> = (0..20_000)
            .map(|k| {
                let mut c = CellSums::default();
                if k % 7 != 0 {
                    for _ in 0..1 + k % 5 {
                        c.photons.push(crate::sampling::uniform(&mut rng));
                        c.hits += 1;
                    }
                }
                c
            })
            .collect();
        let counts = Counts {
            photons: 1000,
            direct_replicates: 0,
            dark: false,
            unit: 1.0,
        };
        let on = |threads| {
            let pool = crate::run::thread_pool(threads).unwrap();
            pool.install(|| cell_values(&cells, [200, 100], counts))
        };
        let bits = |(v, s): (Vec<f64>, Vec<f64>)| {
            v.iter()
                .chain(&s)
                .map(|x| x.to_bits())
                .collect::<Vec<u64>>()
        };
        assert_eq!(bits(on(1)), bits(on(2)));
    }

    #[test]
    fn cells_are_reliable_from_thirty_degrees_of_freedom_and_dark_cells_are_bounded() {
        // k equal photon scores of 1 among 10⁶ histories: k − 1 degrees of freedom.
        let counts = Counts {
            photons: 1_000_000,
            direct_replicates: 0,
            dark: false,
            unit: 2.0,
        };
        let cell = |k: u32| {
            let mut c = CellSums::default();
            for _ in 0..k {
                c.photons.push(1.0);
            }
            c.hits = k as u64;
            c.scoring_histories = k as u64;
            c
        };
        let c = cell(20);
        let (_, var) = c.photons.over(counts.photons).mean_and_variance();
        let dof = cell_dof(&c, counts, var, 0.0);
        assert!((dof - 19.0).abs() < 1e-6, "{dof}");
        // A 4 × 4 receiver: 14 cells of 40 scores, one of 20, one of none.
        let mut cells = vec![cell(40); 16];
        cells[5] = cell(20);
        cells[10] = CellSums::default();
        let s = receiver_stats(&cells, [4, 4], counts, None);
        assert_eq!(s.status[0], CellStatus::Reliable);
        assert_eq!(s.status[5], CellStatus::Unreliable);
        assert_eq!(s.status[10], CellStatus::Dark);
        assert_eq!(
            (s.unreliable_cells, s.dark_cells, s.unknown_cells),
            (1, 1, 1)
        );
        // No score in 10⁶ histories, a typical score per history 1 (in units of 2): 6·10⁻⁶.
        assert!((s.upper_bound[10] - 6e-6).abs() < 1e-18 && s.dark_bound == s.upper_bound[10]);
        assert!(s.upper_bound[0].is_nan() && s.sigma[10].is_nan());
        assert_eq!(s.scoring_histories[0], 40);
        // Nothing scored anywhere: unknown, not dark.
        let s = receiver_stats(&[CellSums::default(); 4], [2, 2], counts, None);
        assert!(s.status.iter().all(|&x| x == CellStatus::Unknown) && s.dark_cells == 0);
    }

    #[test]
    fn mean_error_uses_both_averagings() {
        let (mean, rel) = mean_error(&[1.0, 3.0], &[0.1, 0.1]);
        assert_eq!(mean, 2.0);
        assert!((rel.arithmetic - 0.05).abs() < 1e-15);
        assert!((rel.quadratic - 0.1 / 5f64.sqrt()).abs() < 1e-15);
    }
}

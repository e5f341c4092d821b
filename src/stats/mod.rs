//! Statistics of the tallies: the equations of method.md, evaluated once per epoch.
//! They only read tallies; they never touch the photon path.

pub mod figures;
pub mod forecast;
mod map;
mod receiver;
mod reliability;
pub mod stop;
pub mod ugr;
pub mod ugr_table;
pub mod verdict;

use crate::scene::Geometry;
use crate::tally::{CellSums, Counts, Slot, Tallies};
pub use map::{
    map_stats, mean_illuminance_sigma_lx, mean_illuminance_vov, triangle_face_illuminance_lx,
    triangle_illuminance_lx, triangle_rel_errors, MapKind, MapStats,
};
pub use receiver::{cell_estimates, cell_values, receiver_stats, CellEstimate, ReceiverStats};
pub use reliability::{figure_of_merit, reliability, Reliability, BOUNCE_CAP_BIAS_SHARE};

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
    let sigma = if counts.photon_variance_known() {
        (p.var + direct_var).sqrt() * unit
    } else {
        f64::NAN
    };
    ((p.value + direct_value) * unit, sigma)
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
    let n = counts.histories as f64;
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
    (part(counts.histories, typical.0) + part(counts.direct_replicates, typical.1)) * counts.unit
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
            histories: n,
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
            histories: 1000,
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
            histories: 1_000_000,
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
        let (_, var) = c.photons.over(counts.histories).mean_and_variance();
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

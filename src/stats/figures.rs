//! The figures a lighting designer quotes for a receiver (EN 12464-1): the mean Ē, the
//! minimum and maximum cell, the uniformity U0 = Emin/Ē and g2 = Emin/Emax, each as a
//! point value and a two-sided interval at a stated confidence.
//!
//! - Ē: the mean of the cells, its σ from the receiver's per-history totals (which carry
//!   the covariance between cells; the cells' σᵢ would not) plus the sampled direct
//!   light's variance Σσ²ᵢ/N², exact there because every cell's replicates draw from
//!   their own streams.
//! - Emin, Emax: the true minimum lies above minᵢ(Êᵢ − zσᵢ) whenever the minimum cell's
//!   own interval covers it, so the lower bound needs no correction for the number of
//!   cells; the upper bound needs every cell's interval at once (Bonferroni, valid under
//!   any correlation between cells). Emax mirrors it.
//! - U0, g2: a union bound: each part's interval at half the error rate.
//! - The plug-in minimum of noisy cells is biased low (the smallest draw wins: by about
//!   2.5σ of a cell among 100 equal ones); it is labelled `plug_in`. A parametric
//!   bootstrap of that bias over-corrected by as much as it corrected (point source over a
//!   black floor: −3.3 % plug-in, +6.2 % corrected), so none is applied: the interval,
//!   which covers, is the figure to quote.

use super::{widened_sigma, CellStatus, ReceiverStats};
use crate::scene::{Receiver, Scene};
use crate::tally::{CellSums, Counts, Tallies};
use serde::{Deserialize, Serialize};

/// A figure: its point value and its interval (NaN, null in JSON, where unknown).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Figure {
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub value: f64,
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub low: f64,
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub high: f64,
}

impl Figure {
    /// A value without a known interval.
    pub fn unbounded(value: f64) -> Figure {
        Figure {
            value,
            low: f64::NAN,
            high: f64::NAN,
        }
    }

    pub fn covers(&self, x: f64) -> bool {
        self.low <= x && x <= self.high
    }
}

/// A receiver's figures; `cell` indices are j·nu + i.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Figures {
    /// Two-sided confidence of every interval.
    pub confidence: f64,
    /// What the figures are over: `cell_average` (each cell's mean over its area) or
    /// `point` (the value at each cell's centre, `values = "point"`).
    pub values: String,
    pub mean: Figure,
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub mean_sigma: f64,
    /// `min.value` is the plug-in minimum (`min_point`), biased low under noise: the
    /// least of many noisy cells is likely one that drew low. Its interval is what to
    /// quote.
    pub min: Figure,
    pub min_point: String,
    pub min_cell: usize,
    pub max: Figure,
    pub max_cell: usize,
    pub u0: Figure,
    pub g2: Figure,
    /// Ēz/Ēh over the receiver named `modelling_with` (a cylindrical receiver that has
    /// one), its interval by a union bound of the two means' (conservative: they are
    /// positively correlated).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modelling: Option<Figure>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modelling_with: Option<String>,
    /// false when some cell's σ is unreliable (its widened σ is used) or the mean's VOV
    /// is high: the intervals are then wider but cannot vouch for their coverage.
    pub reliable: bool,
    /// Why an interval is unknown or unreliable; empty when all is well.
    pub note: String,
}

/// Φ⁻¹(p), the standard normal quantile, for 0 < p < 1: Acklam's rational
/// approximation (relative error 1.15e-9) refined by one Halley step on erfc, to
/// double precision.
pub fn normal_quantile(p: f64) -> f64 {
    if !(p > 0.0 && p < 1.0) {
        return if p == 0.0 {
            f64::NEG_INFINITY
        } else if p == 1.0 {
            f64::INFINITY
        } else {
            f64::NAN
        };
    }
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.38357751867269e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    let x = if p < 0.02425 {
        tail(libm::sqrt(-2.0 * libm::log(p)))
    } else if p > 1.0 - 0.02425 {
        -tail(libm::sqrt(-2.0 * libm::log1p(-p)))
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    };
    // Halley: e = Φ(x) − p, u = e·√(2π)·exp(x²/2).
    let e = 0.5 * libm::erfc(-x / std::f64::consts::SQRT_2) - p;
    let u = e * libm::sqrt(std::f64::consts::TAU) * libm::exp(x * x / 2.0);
    x - u / (1.0 + x * u / 2.0)
}

/// The one-sided normal quantile of each end of a two-sided interval at `confidence`
/// shared among `k` simultaneous intervals (Bonferroni).
fn z_two_sided(confidence: f64, k: usize) -> f64 {
    normal_quantile(1.0 - (1.0 - confidence) / (2.0 * k as f64))
}

/// The σ and VOV of a receiver's mean over its cells (`ReceiverStats::mean`), from its
/// total slot and its cells. The VOV is that of the photons' variance, scaled by its
/// share of the whole (the direct light's replicates are many and even).
pub fn mean_and_sigma(
    cells: &[CellSums],
    included: Option<&[usize]>,
    total: &CellSums,
    counts: Counts,
) -> (f64, f64) {
    if counts.dark {
        return (0.0, 0.0);
    }
    let counted = || -> Box<dyn Iterator<Item = &CellSums>> {
        match included {
            Some(k) => Box::new(k.iter().map(|&k| &cells[k])),
            None => Box::new(cells.iter()),
        }
    };
    if counted().all(|c| c.hits == 0) {
        // Nothing scored: the mean reads 0 with an unknown error, as its cells do.
        return (f64::NAN, 1.0);
    }
    let n = counted().count() as f64;
    let photons = total.photon_moments(counts);
    let (_, photon_var) = photons.mean_and_variance();
    if !counts.photon_variance_known() {
        return (f64::NAN, 1.0);
    }
    let direct_var: f64 = if counts.direct_replicates == 0 {
        0.0
    } else {
        counted()
            .map(|c| c.direct_moments(counts).mean_and_variance().1)
            .sum::<f64>()
            / (n * n)
    };
    let var = photon_var + direct_var;
    let share = if var > 0.0 { photon_var / var } else { 1.0 };
    (var.sqrt() * counts.unit, photons.vov() * share * share)
}

/// The figures of a receiver whose cell statistics are `stats`, its mean's σ
/// `mean_sigma` and VOV `mean_vov` (see [`mean_and_sigma`]), at `confidence`.
pub fn figures(stats: &ReceiverStats, mean_sigma: f64, mean_vov: f64, confidence: f64) -> Figures {
    let mean = stats.mean;
    let mut notes: Vec<String> = Vec::new();
    // The mean's and the extremes' intervals alone, and at half the error rate for the
    // ratios' union bounds.
    let (z, z_half) = (z_two_sided(confidence, 1), z_two_sided(confidence, 2));
    let mut f = Figures {
        confidence,
        values: "cell_average".into(),
        min_point: "plug_in".into(),
        mean: Figure {
            value: mean,
            low: mean - z * mean_sigma,
            high: mean + z * mean_sigma,
        },
        mean_sigma,
        ..Figures::default()
    };
    if mean_sigma.is_nan() {
        notes.push("Ē's error is unknown (too few photons scored)".into());
    } else if mean_vov > super::MAX_RELIABLE_VOV {
        notes.push(format!("Ē's VOV is {mean_vov:.3} (its σ not yet reliable)"));
    }
    let n = stats.values.len();
    let sigma = judged_sigmas(stats);
    let unreliable = (stats.status.iter())
        .filter(|&&s| s == CellStatus::Unreliable)
        .count();
    if unreliable > 0 {
        notes.push(format!(
            "{unreliable} of {n} cells unreliable (their σ widened)"
        ));
    }
    let unknown = sigma.iter().filter(|s| s.is_nan()).count();
    let cells = Cells {
        values: &stats.values,
        sigma: &sigma,
    };
    if n > 0 && unknown == 0 {
        (f.min, f.max) = cells.extremes(z, z_two_sided(confidence, n));
        // The ratios: each part's interval at half the error rate.
        let (min, max) = cells.extremes(z_half, z_two_sided(confidence, 2 * n));
        let mean_half = (mean - z_half * mean_sigma, mean + z_half * mean_sigma);
        f.u0 = ratio_interval(f.min.value, mean, (min.low, min.high), mean_half);
        f.g2 = ratio_interval(
            f.min.value,
            f.max.value,
            (min.low, min.high),
            (max.low, max.high),
        );
    } else if n > 0 {
        notes.push(format!(
            "{unknown} of {n} cells have no known σ (dark or unreached): Emin, Emax, U0 \
             and g2 have no interval"
        ));
        let (min, max) = (stats.values[cells.argmin()], stats.values[cells.argmax()]);
        (f.min, f.max) = (Figure::unbounded(min), Figure::unbounded(max));
        f.u0 = Figure::unbounded(ratio(min, mean));
        f.g2 = Figure::unbounded(ratio(min, max));
    }
    (f.min_cell, f.max_cell) = (cells.argmin(), cells.argmax());
    // Reliable only when every σ behind the figures is known and reliable.
    f.reliable = notes.is_empty();
    if !(mean > 0.0) {
        notes.push("Ē = 0: U0 and g2 are undefined".into());
    }
    f.note = notes.join("; ");
    f
}

/// Receiver `k`'s statistics over the cells its figures count (all but its excluded
/// cells), with its mean's σ and VOV ([`mean_and_sigma`]).
pub fn figure_stats(
    tallies: &Tallies,
    receivers: &[Receiver],
    k: usize,
) -> (ReceiverStats, f64, f64) {
    counted_stats(
        tallies,
        receivers,
        k,
        receivers[k].included_cells(receivers).as_deref(),
    )
}

/// [`figure_stats`] over the cells `included` (None: all).
fn counted_stats(
    tallies: &Tallies,
    receivers: &[Receiver],
    k: usize,
    included: Option<&[usize]>,
) -> (ReceiverStats, f64, f64) {
    let cells = tallies.receiver_cells(receivers, k);
    let total = tallies.receiver_total(receivers, k);
    let counts = tallies.counts();
    let stats = super::receiver_stats(cells, receivers[k].cells, counts, included);
    let (sigma, vov) = mean_and_sigma(cells, included, total, counts);
    (stats, sigma, vov)
}

/// Receiver `k`'s figures, at the scene's confidence: over its counted cells (the
/// cell indices are the receiver's own), labelled `point` for a point receiver, with
/// the modelling ratio where it has a `modelling_with` partner.
pub fn receiver_figures(scene: &Scene, tallies: &Tallies, k: usize) -> Figures {
    let receivers = &scene.receivers;
    let included = receivers[k].included_cells(receivers);
    let (counted, mean_sigma, mean_vov) = counted_stats(tallies, receivers, k, included.as_deref());
    let confidence = scene.simulation.confidence;
    let mut f = figures(&counted, mean_sigma, mean_vov, confidence);
    if let Some(included) = included {
        (f.min_cell, f.max_cell) = (included[f.min_cell], included[f.max_cell]);
    }
    if receivers[k].points {
        f.values = "point".into();
    }
    if let Some(p) = (scene.modelling.iter()).find(|p| p.cylindrical == k) {
        let (eh, eh_sigma, _) = figure_stats(tallies, receivers, p.horizontal);
        let ratio = modelling_ratio((counted.mean, mean_sigma), (eh.mean, eh_sigma), confidence);
        f.modelling = Some(ratio);
        f.modelling_with = Some(receivers[p.horizontal].name.clone());
    }
    f
}

/// The modelling ratio Ēz/Ēh from the two means and their σ, its interval at
/// `confidence` by a union bound (each mean's at half the error rate); no interval
/// where either σ is unknown.
pub fn modelling_ratio(ez: (f64, f64), eh: (f64, f64), confidence: f64) -> Figure {
    if ez.1.is_nan() || eh.1.is_nan() {
        return Figure::unbounded(ratio(ez.0, eh.0));
    }
    let z = z_two_sided(confidence, 2);
    let at = |(m, s): (f64, f64)| (m - z * s, m + z * s);
    unbounded_ratio_interval(ez.0, eh.0, at(ez), at(eh))
}

/// Each cell's σ as the figures judge it: its own where reliable, widened where not
/// ([`widened_sigma`]), NaN where unknown.
pub(super) fn judged_sigmas(stats: &ReceiverStats) -> Vec<f64> {
    (0..stats.values.len())
        .map(|k| match stats.status[k] {
            CellStatus::Reliable => stats.sigma[k],
            CellStatus::Unreliable => widened_sigma(stats.sigma[k], stats.vov[k], stats.dof[k]),
            CellStatus::Dark | CellStatus::Unknown => f64::NAN,
        })
        .collect()
}

/// A receiver's cell values and their judged σ.
pub(super) struct Cells<'a> {
    pub values: &'a [f64],
    pub sigma: &'a [f64],
}

impl Cells<'_> {
    pub fn argmin(&self) -> usize {
        (0..self.values.len())
            .min_by(|&a, &b| self.values[a].total_cmp(&self.values[b]))
            .unwrap_or(0)
    }

    pub fn argmax(&self) -> usize {
        (0..self.values.len())
            .max_by(|&a, &b| self.values[a].total_cmp(&self.values[b]))
            .unwrap_or(0)
    }

    /// Emin and Emax with their intervals: `z_one` for the bound one cell decides
    /// (Emin's low, Emax's high), `z_all` for the bound every cell must hold at once.
    pub fn extremes(&self, z_one: f64, z_all: f64) -> (Figure, Figure) {
        let (v, s) = (self.values, self.sigma);
        let low = |z: f64| (0..v.len()).map(move |k| v[k] - z * s[k]);
        let high = |z: f64| (0..v.len()).map(move |k| v[k] + z * s[k]);
        let min = Figure {
            value: v[self.argmin()],
            low: low(z_one).fold(f64::INFINITY, f64::min).max(0.0),
            high: high(z_all).fold(f64::INFINITY, f64::min),
        };
        let max = Figure {
            value: v[self.argmax()],
            low: low(z_all).fold(f64::NEG_INFINITY, f64::max).max(0.0),
            high: high(z_one).fold(f64::NEG_INFINITY, f64::max),
        };
        (min, max)
    }
}

/// a / b, NaN for 0 / 0.
fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else {
        f64::NAN
    }
}

/// The interval of a ratio a/b ≤ 1 of non-negative parts from theirs: [a_lo/b_hi,
/// a_hi/b_lo], within [0, 1]; its top is 1 while b's interval reaches 0.
pub(super) fn ratio_interval(a: f64, b: f64, a_range: (f64, f64), b_range: (f64, f64)) -> Figure {
    capped_ratio_interval(a, b, a_range, b_range, 1.0)
}

/// [`ratio_interval`] for a ratio that may exceed 1 (its top unbounded while b's
/// interval reaches 0), as the modelling ratio Ēz/Ēh.
pub fn unbounded_ratio_interval(
    a: f64,
    b: f64,
    a_range: (f64, f64),
    b_range: (f64, f64),
) -> Figure {
    capped_ratio_interval(a, b, a_range, b_range, f64::INFINITY)
}

fn capped_ratio_interval(
    a: f64,
    b: f64,
    (a_lo, a_hi): (f64, f64),
    (b_lo, b_hi): (f64, f64),
    cap: f64,
) -> Figure {
    let high = if b_lo > 0.0 {
        (a_hi / b_lo).min(cap)
    } else {
        cap
    };
    let low = if b_hi > 0.0 {
        (a_lo.max(0.0) / b_hi).clamp(0.0, cap)
    } else {
        0.0
    };
    Figure {
        value: ratio(a, b),
        low,
        high,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_quantile_matches_tabulated_values() {
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959_963_984_540_054),
            (0.95, 1.644_853_626_951_472_2),
            (0.999_999, 4.753_424_308_822_899),
            (1e-10, -6.361_340_902_404_056),
        ] {
            // 1e-10: 0.999999 itself is 1e-16 off, which moves its quantile by 2e-11.
            assert!(
                (normal_quantile(p) - z).abs() < 1e-10,
                "Φ⁻¹({p}) = {}",
                normal_quantile(p)
            );
        }
        assert!(normal_quantile(1.5).is_nan());
    }

    fn stats(values: &[f64], sigma: &[f64]) -> ReceiverStats {
        let n = values.len();
        ReceiverStats {
            values: values.to_vec(),
            sigma: sigma.to_vec(),
            status: vec![CellStatus::Reliable; n],
            vov: vec![0.0; n],
            dof: vec![1e6; n],
            mean: values.iter().sum::<f64>() / n as f64,
            ..ReceiverStats::default()
        }
    }

    #[test]
    fn extremes_take_their_bounds_from_the_cells() {
        let s = stats(&[100.0, 200.0, 300.0], &[10.0, 10.0, 10.0]);
        let f = figures(&s, 5.0, 0.0, 0.95);
        let z = 1.959_963_984_540_054;
        let z3 = normal_quantile(1.0 - 0.05 / 6.0);
        assert!((f.min.low - (100.0 - z * 10.0)).abs() < 1e-9);
        assert!((f.min.high - (100.0 + z3 * 10.0)).abs() < 1e-9);
        assert!((f.max.low - (300.0 - z3 * 10.0)).abs() < 1e-9);
        assert!((f.mean.high - (200.0 + z * 5.0)).abs() < 1e-9);
        assert!((f.u0.value - 0.5).abs() < 1e-12 && f.u0.low < 0.5 && f.u0.high > 0.5);
        assert!((f.g2.value - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!((f.min_cell, f.max_cell, f.reliable), (0, 2, true));
    }

    #[test]
    fn unknown_cells_leave_the_extremes_without_intervals() {
        let mut s = stats(&[100.0, 0.0], &[10.0, f64::NAN]);
        s.status[1] = CellStatus::Dark;
        let f = figures(&s, 5.0, 0.0, 0.95);
        assert!(f.min.low.is_nan() && f.u0.high.is_nan() && !f.mean.low.is_nan());
        assert!(f.note.contains("1 of 2 cells"), "{}", f.note);
        assert!(!f.reliable, "unknown intervals are not reliable ones");
    }
}

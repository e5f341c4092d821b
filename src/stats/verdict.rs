//! Verdicts on a scene's `[[requirements]]`: each check (Ē ≥ x, Emin ≥ x, U0 ≥ x,
//! g2 ≥ x) is PASS when its lower confidence bound reaches the threshold, FAIL when its
//! upper bound stays below it, UNDECIDED otherwise.
//!
//! - **Error rate.** The scene's `1 − confidence` is split evenly over all checks
//!   (Bonferroni), and each check's bounds are one-sided at its share: a check can only
//!   err one way (a passing figure can only be called FAIL), so each errs at most at its
//!   share, and the overall verdict at most at `1 − confidence`.
//! - **Anytime-valid.** A run that stops as soon as every check is decided looks at the
//!   bounds every epoch; fixed-sample bounds would then err far more often than they
//!   say. The bounds use the normal-mixture confidence sequence (Robbins; Howard,
//!   Ramdas, McAuliffe & Sekhon, Ann. Stat. 2021, eq. 14) in its asymptotic form with
//!   the estimated σ (Waudby-Smith et al. 2021): after n photons the half-width is σ̂·z_n
//!   with z_n = √((1 + 1/r)(ln(1 + r) + 2 ln(1/(2a)))), r = n/n₀ and n₀ =
//!   [`MIXTURE_PHOTONS`] fixed in advance, so the verdict holds at any stopping time —
//!   the run's end and `--until decided` alike. It is wider than a fixed-n bound
//!   (z = 2.81 against 1.64 for one check at 95 % after 10⁶ photons): the price of
//!   looking.
//! - Emin, U0 and g2 take their parts' bounds as the figures do (docs/designers.md),
//!   with these z.
//! - A check decides only when the σ behind it is reliable (Ē's VOV ≤ 0.1; for Emin, U0
//!   and g2 every cell reliable): early epochs, where few photons stand behind a cell's
//!   σ, cannot end a run on a lucky bound.

use super::figures::{judged_sigmas, mean_and_sigma, ratio_interval, Cells, Figure};
use super::{receiver_stats, CellStatus, MAX_RELIABLE_VOV};
use crate::scene::{FigureName, Scene};
use crate::tally::Tallies;
use serde::{Deserialize, Serialize};

/// The mixture's reference photon count n₀: the boundary is tightest near r = n/n₀ of a
/// few tens, where decisions on the bundled scenes fall (10⁵ to 10⁷ photons).
pub const MIXTURE_PHOTONS: f64 = 65_536.0;

/// The anytime-valid multiplier after `photons` photons for a one-sided error rate
/// `alpha` (the two-sided boundary at 2α; see the module's notes).
pub fn anytime_z(alpha: f64, photons: u64) -> f64 {
    let r = (photons as f64 / MIXTURE_PHOTONS).max(1e-9);
    libm::sqrt((1.0 + 1.0 / r) * (libm::log1p(r) + 2.0 * libm::log(1.0 / (2.0 * alpha))))
}

/// A check's outcome.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum Outcome {
    Pass,
    Fail,
    #[default]
    Undecided,
}

/// One check of one requirement.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CheckVerdict {
    pub requirement: String,
    pub receiver: String,
    /// `em`, `emin`, `u0` or `g2`.
    pub figure: String,
    pub at_least: f64,
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub value: f64,
    /// The anytime-valid one-sided bounds at this check's error rate.
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub low: f64,
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub high: f64,
    pub outcome: Outcome,
    /// (value − at_least)/σ of the figure (null where σ is unknown).
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub margin_sigma: f64,
    /// Photons by which an undecided check is expected to be decided, n·(zσ/margin)²
    /// (null once decided, or where the value sits on the threshold).
    pub decision_photons: Option<u64>,
    /// Whether the σ behind the bounds is reliable (Ē's VOV, and for Emin, U0 and g2
    /// every cell's status); an unreliable check stays UNDECIDED whatever its bounds.
    pub reliable: bool,
}

/// Every check of a scene's requirements and the overall verdict.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Verdicts {
    /// FAIL if any check fails, PASS if all pass, else UNDECIDED.
    pub overall: Outcome,
    pub confidence: f64,
    /// Each check's one-sided error rate: (1 − confidence)/checks.
    pub alpha_per_check: f64,
    pub boundary: String,
    pub checks: Vec<CheckVerdict>,
}

impl Verdicts {
    pub fn decided(&self) -> bool {
        self.checks.iter().all(|c| c.outcome != Outcome::Undecided)
    }
}

/// The verdicts on `scene`'s requirements from `tallies`.
pub fn verdicts(scene: &Scene, tallies: &Tallies) -> Verdicts {
    let confidence = scene.simulation.confidence;
    let count: usize = scene.requirements.iter().map(|r| r.checks.len()).sum();
    let alpha = (1.0 - confidence) / count.max(1) as f64;
    let counts = tallies.counts();
    let mut checks = Vec::with_capacity(count);
    for req in &scene.requirements {
        let r = &scene.receivers[req.receiver];
        let cells = tallies.receiver_cells(&scene.receivers, req.receiver);
        let stats = receiver_stats(cells, r.cells, counts, None);
        let total = tallies.receiver_total(&scene.receivers, req.receiver);
        let mean = stats.mean;
        let (mean_sigma, mean_vov) = mean_and_sigma(cells, total, counts);
        let sigma = judged_sigmas(&stats);
        let known = !mean_sigma.is_nan() && sigma.iter().all(|s| !s.is_nan());
        // A check decides only on σ it can trust: Ē's, and for the extremes every cell's.
        let mean_reliable = mean_vov <= MAX_RELIABLE_VOV;
        let cells_reliable = stats.status.iter().all(|s| *s == CellStatus::Reliable);
        let figures = Bounds {
            cells: Cells {
                values: &stats.values,
                sigma: &sigma,
            },
            mean,
            mean_sigma,
            photons: tallies.photons,
        };
        for check in &req.checks {
            let (Figure { value, low, high }, sigma) = if known && !stats.values.is_empty() {
                figures.of(check.figure, alpha)
            } else {
                (Figure::unbounded(f64::NAN), f64::NAN)
            };
            let reliable = match check.figure {
                FigureName::Mean => mean_reliable,
                FigureName::Min | FigureName::G2 => cells_reliable,
                FigureName::U0 => mean_reliable && cells_reliable,
            };
            let outcome = if !reliable {
                Outcome::Undecided
            } else if low >= check.at_least {
                Outcome::Pass
            } else if high < check.at_least {
                Outcome::Fail
            } else {
                Outcome::Undecided
            };
            let margin = value - check.at_least;
            let decision_photons = (outcome == Outcome::Undecided && margin != 0.0 && sigma > 0.0)
                .then(|| {
                    let k = anytime_z(alpha, tallies.photons) * sigma / margin.abs();
                    (tallies.photons as f64 * k * k).min(u64::MAX as f64) as u64
                });
            checks.push(CheckVerdict {
                requirement: req.name.clone(),
                receiver: r.name.clone(),
                figure: check.figure.key().into(),
                at_least: check.at_least,
                value,
                low,
                high,
                outcome,
                margin_sigma: margin / sigma,
                decision_photons,
                reliable,
            });
        }
    }
    let overall = if checks.iter().any(|c| c.outcome == Outcome::Fail) {
        Outcome::Fail
    } else if checks.iter().all(|c| c.outcome == Outcome::Pass) {
        Outcome::Pass
    } else {
        Outcome::Undecided
    };
    Verdicts {
        overall,
        confidence,
        alpha_per_check: alpha,
        boundary: "normal_mixture".into(),
        checks,
    }
}

/// A receiver's cells and mean after `photons` photons, for the checks' bounds.
struct Bounds<'a> {
    cells: Cells<'a>,
    mean: f64,
    mean_sigma: f64,
    photons: u64,
}

impl Bounds<'_> {
    /// `figure` with its bounds, each one-sided at rate `a` and anytime-valid (the ratios
    /// take their parts' bounds at a/2 each, as the figures' union bound does), and its
    /// σ (the ratios' by the delta method, for the margin only).
    fn of(&self, figure: FigureName, a: f64) -> (Figure, f64) {
        let c = &self.cells;
        let n = c.values.len() as f64;
        let z = |a: f64| anytime_z(a, self.photons);
        let (mean, mean_sigma) = (self.mean, self.mean_sigma);
        let mean_at = |a: f64| (mean - z(a) * mean_sigma, mean + z(a) * mean_sigma);
        let (min_sigma, max_sigma) = (c.sigma[c.argmin()], c.sigma[c.argmax()]);
        let ratio_sigma =
            |v: f64, (s1, v1): (f64, f64), (s2, v2): (f64, f64)| v * libm::hypot(s1 / v1, s2 / v2);
        match figure {
            FigureName::Mean => {
                let (low, high) = mean_at(a);
                (
                    Figure {
                        value: mean,
                        low,
                        high,
                    },
                    mean_sigma,
                )
            }
            FigureName::Min => (c.extremes(z(a), z(a / n)).0, min_sigma),
            FigureName::U0 => {
                let (min, _) = c.extremes(z(a / 2.0), z(a / (2.0 * n)));
                let u0 = ratio_interval(min.value, mean, (min.low, min.high), mean_at(a / 2.0));
                let s = ratio_sigma(u0.value, (min_sigma, min.value), (mean_sigma, mean));
                (u0, s)
            }
            FigureName::G2 => {
                let (min, max) = c.extremes(z(a / 2.0), z(a / (2.0 * n)));
                let g2 = ratio_interval(
                    min.value,
                    max.value,
                    (min.low, min.high),
                    (max.low, max.high),
                );
                let s = ratio_sigma(g2.value, (min_sigma, min.value), (max_sigma, max.value));
                (g2, s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::figures::normal_quantile;
    use super::*;

    /// Gaussian random walks looked at after every 4096-photon block up to 10⁶ photons
    /// (244 looks): the mixture boundary is crossed by at most its rate, which the
    /// fixed-n multiplier, looked at as often, exceeds many times over.
    #[test]
    fn the_boundary_holds_its_rate_under_continuous_monitoring() {
        use rand::Rng;
        let (walks, block, looks, a) = (4000, 4096.0, 244, 0.025);
        let mut rng = rand_pcg::Pcg32::new(7, 11);
        let mut normal = || {
            let (u1, u2): (f64, f64) = (rng.random(), rng.random());
            libm::sqrt(-2.0 * libm::log(1.0 - u1)) * libm::cos(std::f64::consts::TAU * u2)
        };
        let fixed = normal_quantile(1.0 - a);
        let (mut mixture_crossed, mut fixed_crossed) = (0, 0);
        for _ in 0..walks {
            let (mut sum, mut m, mut f) = (0.0, false, false);
            for k in 1..=looks {
                sum += normal() * libm::sqrt(block);
                let t = k as f64 * block;
                // The walk's mean in units of its standard error 1/√t.
                let z = sum / libm::sqrt(t);
                m |= z > anytime_z(a, t as u64);
                f |= z > fixed;
            }
            mixture_crossed += m as u32;
            fixed_crossed += f as u32;
        }
        let rate = |n: u32| n as f64 / walks as f64;
        let sd = libm::sqrt(a * (1.0 - a) / walks as f64);
        assert!(
            rate(mixture_crossed) <= a + 3.0 * sd,
            "mixture {}",
            rate(mixture_crossed)
        );
        assert!(
            rate(fixed_crossed) > 3.0 * a,
            "fixed {}",
            rate(fixed_crossed)
        );
    }

    #[test]
    fn the_anytime_multiplier_exceeds_the_fixed_one_and_grows_slowly() {
        let fixed = normal_quantile(1.0 - 0.025);
        let at = |n| anytime_z(0.025, n);
        assert!(at(65_536) > fixed && at(1_000_000) > fixed);
        assert!(at(100_000_000) > at(1_000_000), "√(ln r) growth");
        assert!(at(100_000_000) < 1.5 * at(1_000_000));
        // The mixture's closed form at r = 1: √(2 (ln 2 + 2 ln 20)).
        let r1 = libm::sqrt(2.0 * (libm::log(2.0) + 2.0 * libm::log(20.0)));
        assert!((at(65_536) - r1).abs() < 1e-12);
    }
}

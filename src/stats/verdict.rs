//! Verdicts on a scene's `[[requirements]]`: a check of a least value (Ē, Emin, U0,
//! g2, the modelling ratio's least) is PASS when its lower confidence bound reaches the
//! threshold, FAIL when its upper bound stays below it, UNDECIDED otherwise; a check of
//! a most value (UGR, the modelling ratio's most) the other way round.
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

use super::figures::{
    figure_stats, judged_sigmas, ratio_interval, unbounded_ratio_interval, Cells, Figure,
};
use super::{receiver_stats, ugr, CellStatus, MAX_RELIABLE_VOV};
use crate::scene::{Check, FigureName, Limit, Requirement, Scene, Subject};
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
    /// The receiver checked (an observer's hidden receiver for `ugr`).
    pub receiver: String,
    /// The observer of a `ugr` check.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observer: Option<String>,
    /// `em`, `emin`, `u0`, `g2`, `modelling` or `ugr`.
    pub figure: String,
    /// The EN 12464-1 task type and area its limits come from (`task`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub basis: Option<String>,
    /// The limit: the figure must be at least `at_least`, or at most `at_most` (the
    /// other is null).
    pub at_least: Option<f64>,
    pub at_most: Option<f64>,
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub value: f64,
    /// The anytime-valid one-sided bounds at this check's error rate.
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub low: f64,
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub high: f64,
    pub outcome: Outcome,
    /// The value's distance to the limit on the passing side over its σ (negative:
    /// failing; null where σ is unknown).
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub margin_sigma: f64,
    /// Photons by which an undecided check is expected to be decided, n·(zσ/margin)²
    /// (null once decided, or where the value sits on the threshold).
    pub decision_photons: Option<u64>,
    /// Whether the σ behind the bounds is reliable (the means' VOV, for Emin, U0 and
    /// g2 every cell's status, for UGR the eye's cell and a valid rating); an
    /// unreliable check stays UNDECIDED whatever its bounds.
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

impl CheckVerdict {
    /// "≥ 500" or "≤ 19".
    pub fn limit_text(&self) -> String {
        match (self.at_least, self.at_most) {
            (Some(x), _) => format!("≥ {x}"),
            (None, Some(x)) => format!("≤ {x}"),
            (None, None) => String::new(),
        }
    }
}

impl Verdicts {
    pub fn decided(&self) -> bool {
        self.checks.iter().all(|c| c.outcome != Outcome::Undecided)
    }

    /// How many checks pass, fail and are undecided.
    pub fn counts(&self) -> CheckCounts {
        let count = |o| self.checks.iter().filter(|c| c.outcome == o).count() as u32;
        CheckCounts {
            pass: count(Outcome::Pass),
            fail: count(Outcome::Fail),
            undecided: count(Outcome::Undecided),
        }
    }
}

/// The number of checks of each outcome at one epoch (the verdict's history).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CheckCounts {
    pub pass: u32,
    pub fail: u32,
    pub undecided: u32,
}

/// The verdicts on `scene`'s requirements from `tallies`; `observer_visible` is, per
/// observer, per luminaire, the fraction of its opening the eye sees
/// (`stats::ugr::visibility`).
pub fn verdicts(scene: &Scene, tallies: &Tallies, observer_visible: &[Vec<f64>]) -> Verdicts {
    let confidence = scene.simulation.confidence;
    let count: usize = scene.requirements.iter().map(|r| r.checks.len()).sum();
    let alpha = (1.0 - confidence) / count.max(1) as f64;
    let mut checks = Vec::with_capacity(count);
    for req in &scene.requirements {
        let subject = match req.subject {
            Subject::Receiver(k) => Judge::Receiver(ReceiverBounds::new(scene, tallies, k)),
            Subject::Observer(k) => {
                let visible = observer_visible.get(k).map_or(&[][..], Vec::as_slice);
                Judge::Observer(ObserverBounds::new(scene, tallies, k, visible))
            }
        };
        for check in &req.checks {
            let (figure, sigma, reliable) = subject.of(check.figure, alpha);
            checks.push(check_verdict(
                req,
                scene,
                check,
                (figure, sigma, reliable),
                anytime_z(alpha, tallies.photons),
                tallies.photons,
            ));
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

/// A check's verdict from its figure's one-sided bounds (each at the check's rate `z`
/// stands for), its σ and whether that σ is reliable.
fn check_verdict(
    req: &Requirement,
    scene: &Scene,
    check: &Check,
    (figure, sigma, reliable): (Figure, f64, bool),
    z: f64,
    photons: u64,
) -> CheckVerdict {
    let Figure { value, low, high } = figure;
    let x = check.limit.value();
    let (pass, fail) = match check.limit {
        Limit::AtLeast(_) => (low >= x, high < x),
        Limit::AtMost(_) => (high <= x, low > x),
    };
    let outcome = if !reliable {
        Outcome::Undecided
    } else if pass {
        Outcome::Pass
    } else if fail {
        Outcome::Fail
    } else {
        Outcome::Undecided
    };
    let margin = check.limit.margin(value);
    let decision_photons =
        (outcome == Outcome::Undecided && margin != 0.0 && sigma > 0.0).then(|| {
            let k = z * sigma / margin.abs();
            (photons as f64 * k * k).min(u64::MAX as f64) as u64
        });
    let (receiver, observer) = match req.subject {
        Subject::Receiver(k) => (scene.receivers[k].name.clone(), None),
        Subject::Observer(k) => {
            let o = &scene.observers[k];
            (
                scene.receivers[o.receiver].name.clone(),
                Some(o.name.clone()),
            )
        }
    };
    CheckVerdict {
        requirement: req.name.clone(),
        receiver,
        observer,
        figure: check.figure.key().into(),
        basis: req.basis.clone(),
        at_least: matches!(check.limit, Limit::AtLeast(_)).then_some(x),
        at_most: matches!(check.limit, Limit::AtMost(_)).then_some(x),
        value,
        low,
        high,
        outcome,
        margin_sigma: margin / sigma,
        decision_photons,
        reliable,
    }
}

/// What a requirement's checks are judged on.
enum Judge {
    Receiver(ReceiverBounds),
    Observer(ObserverBounds),
}

impl Judge {
    /// `figure` with its one-sided bounds at rate `a`, its σ (for the margin) and
    /// whether that σ is reliable.
    fn of(&self, figure: FigureName, a: f64) -> (Figure, f64, bool) {
        match self {
            Judge::Receiver(r) => r.of(figure, a),
            Judge::Observer(o) => o.of(a),
        }
    }
}

/// A receiver's mean over its cells, with its σ and whether that σ is reliable.
#[derive(Clone, Copy)]
struct Mean {
    value: f64,
    sigma: f64,
    reliable: bool,
}

impl Mean {
    fn of(scene: &Scene, tallies: &Tallies, k: usize) -> Mean {
        let (stats, sigma, vov) = figure_stats(tallies, &scene.receivers, k);
        Mean {
            value: stats.mean,
            sigma,
            reliable: vov <= MAX_RELIABLE_VOV,
        }
    }

    /// The two-sided bounds at z.
    fn at(&self, z: f64) -> (f64, f64) {
        (self.value - z * self.sigma, self.value + z * self.sigma)
    }
}

/// A receiver's cells and mean after `photons` photons, for the checks' bounds (and
/// the mean of its modelling partner, if it has one).
struct ReceiverBounds {
    values: Vec<f64>,
    sigma: Vec<f64>,
    cells_reliable: bool,
    mean: Mean,
    horizontal: Option<Mean>,
    photons: u64,
}

impl ReceiverBounds {
    fn new(scene: &Scene, tallies: &Tallies, k: usize) -> ReceiverBounds {
        let (stats, sigma, vov) = figure_stats(tallies, &scene.receivers, k);
        let horizontal = (scene.modelling.iter())
            .find(|p| p.cylindrical == k)
            .map(|p| Mean::of(scene, tallies, p.horizontal));
        ReceiverBounds {
            sigma: judged_sigmas(&stats),
            cells_reliable: stats.status.iter().all(|s| *s == CellStatus::Reliable),
            mean: Mean {
                value: stats.mean,
                sigma,
                reliable: vov <= MAX_RELIABLE_VOV,
            },
            values: stats.values,
            horizontal,
            photons: tallies.photons,
        }
    }

    /// `figure` with its bounds, each one-sided at rate `a` and anytime-valid (the
    /// ratios take their parts' bounds at a/2 each, as the figures' union bound does),
    /// its σ (the ratios' by the delta method, for the margin only) and whether the σ
    /// behind it is reliable.
    fn of(&self, figure: FigureName, a: f64) -> (Figure, f64, bool) {
        let c = Cells {
            values: &self.values,
            sigma: &self.sigma,
        };
        let known = !self.mean.sigma.is_nan() && self.sigma.iter().all(|s| !s.is_nan());
        if !known || self.values.is_empty() {
            return (Figure::unbounded(f64::NAN), f64::NAN, false);
        }
        let n = c.values.len() as f64;
        let z = |a: f64| anytime_z(a, self.photons);
        let mean = self.mean;
        let (min_sigma, max_sigma) = (c.sigma[c.argmin()], c.sigma[c.argmax()]);
        let ratio_sigma =
            |v: f64, (s1, v1): (f64, f64), (s2, v2): (f64, f64)| v * libm::hypot(s1 / v1, s2 / v2);
        let cells_reliable = self.cells_reliable;
        match figure {
            FigureName::Mean => {
                let (low, high) = mean.at(z(a));
                let value = mean.value;
                (Figure { value, low, high }, mean.sigma, mean.reliable)
            }
            FigureName::Min => (c.extremes(z(a), z(a / n)).0, min_sigma, cells_reliable),
            FigureName::U0 => {
                let (min, _) = c.extremes(z(a / 2.0), z(a / (2.0 * n)));
                let u0 = ratio_interval(
                    min.value,
                    mean.value,
                    (min.low, min.high),
                    mean.at(z(a / 2.0)),
                );
                let s = ratio_sigma(u0.value, (min_sigma, min.value), (mean.sigma, mean.value));
                (u0, s, mean.reliable && cells_reliable)
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
                (g2, s, cells_reliable)
            }
            FigureName::Modelling => {
                let Some(h) = self.horizontal.filter(|h| !h.sigma.is_nan()) else {
                    return (Figure::unbounded(f64::NAN), f64::NAN, false);
                };
                let zh = z(a / 2.0);
                let m = unbounded_ratio_interval(mean.value, h.value, mean.at(zh), h.at(zh));
                let s = ratio_sigma(m.value, (mean.sigma, mean.value), (h.sigma, h.value));
                (m, s, mean.reliable && h.reliable)
            }
            FigureName::Ugr => (Figure::unbounded(f64::NAN), f64::NAN, false),
        }
    }
}

/// An observer's glare sum and background illuminance, for a `ugr_max` check.
struct ObserverBounds {
    rating: ugr::Rating,
    cell_reliable: bool,
    photons: u64,
}

impl ObserverBounds {
    fn new(scene: &Scene, tallies: &Tallies, k: usize, visible: &[f64]) -> ObserverBounds {
        let o = &scene.observers[k];
        let terms = ugr::observer_terms(scene, o, visible);
        let cells = tallies.receiver_cells(&scene.receivers, o.receiver);
        let stats = receiver_stats(cells, [1, 1], tallies.counts(), None);
        ObserverBounds {
            rating: ugr::rate(terms, ugr::e_ind(scene, tallies, o)),
            cell_reliable: stats.status.first() == Some(&CellStatus::Reliable),
            photons: tallies.photons,
        }
    }

    /// UGR with its one-sided bounds at rate `a` (from E_ind's: UGR falls as E_ind
    /// grows), σ_UGR and whether it is reliable (a valid rating on a reliable cell).
    fn of(&self, a: f64) -> (Figure, f64, bool) {
        let r = &self.rating;
        let (Some(value), Some(sigma)) = (r.ugr, r.ugr_sigma) else {
            return (Figure::unbounded(f64::NAN), f64::NAN, false);
        };
        let (e, s) = (r.e_ind_lx, r.e_ind_sigma_lx);
        let z = anytime_z(a, self.photons);
        let low = ugr::ugr(r.sum, e + z * s).unwrap_or(f64::NAN);
        // E_ind's lower bound at or below 0: UGR has no upper bound.
        let high = ugr::ugr(r.sum, e - z * s).unwrap_or(f64::INFINITY);
        let reliable = self.cell_reliable && r.invalid.is_none() && sigma.is_finite();
        (Figure { value, low, high }, sigma, reliable)
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

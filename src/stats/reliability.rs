//! Reliability of a target's error, in the spirit of MCNP's tally checks: figure of
//! merit, its stability, the VOV and the bounce cap's bias bound (method.md §5).

use super::*;

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

//! When a run stops: one type for the scene file's `[simulation]` keys (serde), the
//! command line's flags (clap) and the run, with one validation. The command line
//! overrides the scene key by key ([`StopCriteria::overridden_by`]).

use crate::{Error, Result};
use serde::Deserialize;

/// Photons when neither the command line nor the scene says how many, and no other
/// criterion can end the run.
pub const DEFAULT_PHOTONS: u64 = 1_000_000;

/// The stop criteria (contract: `[simulation]` and `luxtally run`'s flags); the first
/// one met ends the run. `None` criteria are off. The doc comments are the flags' help.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, clap::Args)]
#[serde(deny_unknown_fields)]
pub struct StopCriteria {
    /// Photons to emit at most (default: the scene's [simulation] photons; without it and
    /// without any other stop criterion, 1,000,000).
    #[arg(long)]
    pub photons: Option<u64>,
    /// Stop after this many seconds of tracing.
    #[serde(rename = "time_limit")]
    #[arg(
        long = "time-limit",
        allow_negative_numbers = true,
        value_name = "SECONDS"
    )]
    pub time_limit_s: Option<f64>,
    /// Stop once the target's error is at most this (relative; absolute with --absolute).
    #[arg(long, allow_negative_numbers = true, value_name = "FRACTION")]
    pub target_error: Option<f64>,
    /// What the error target applies to: global, receiver:NAME or receiver:NAME[i0..i1,j0..j1].
    #[arg(long, value_name = "WHAT")]
    pub target: Option<String>,
    /// --target-error is absolute, in the quantity's unit.
    #[serde(default)]
    #[arg(long)]
    pub absolute: bool,
    /// Stop once every cell of the target received this many hits.
    #[arg(long, value_name = "N")]
    pub min_hits: Option<u64>,
    /// Stop as soon as the error target is found unreachable: nothing has reached it, or
    /// the forecast needs more photons or time than the run may take.
    #[serde(default)]
    #[arg(long)]
    pub stop_if_unreachable: bool,
    /// Stop once every [[requirements]] check is decided, PASS or FAIL, at the scene's
    /// confidence (anytime-valid: looking every epoch does not raise the error rate).
    #[arg(long, value_enum)]
    pub until: Option<Until>,
}

/// `--until decided` (`until = "decided"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Until {
    Decided,
}

impl StopCriteria {
    /// These criteria with every one `over` sets put in their place (the command line
    /// over the scene's; `absolute` can only be switched on).
    pub fn overridden_by(&self, over: &StopCriteria) -> StopCriteria {
        StopCriteria {
            photons: over.photons.or(self.photons),
            time_limit_s: over.time_limit_s.or(self.time_limit_s),
            target_error: over.target_error.or(self.target_error),
            target: over.target.clone().or_else(|| self.target.clone()),
            absolute: over.absolute || self.absolute,
            min_hits: over.min_hits.or(self.min_hits),
            stop_if_unreachable: over.stop_if_unreachable || self.stop_if_unreachable,
            until: over.until.or(self.until),
        }
    }

    /// Refuses zero photons and a time limit or error target that is not a positive
    /// number; `key` names a criterion by its scene key (`time_limit`) in the message:
    /// [`scene_key`] or [`flag`].
    pub fn validate(&self, key: impl Fn(&str) -> String) -> Result<()> {
        if self.photons == Some(0) {
            return Err(Error::input(key("photons"), "must be at least 1"));
        }
        let positive = [
            ("time_limit", self.time_limit_s, " of seconds"),
            ("target_error", self.target_error, ""),
        ];
        for (name, value, unit) in positive {
            if let Some(v) = value.filter(|v| !(*v > 0.0 && v.is_finite())) {
                return Err(Error::input(
                    key(name),
                    format!("{v} is not a positive number{unit}"),
                ));
            }
        }
        Ok(())
    }

    /// No criterion but the photon count can end the run.
    pub fn open_ended(&self) -> bool {
        self.time_limit_s.is_none() && self.target_error.is_none() && self.min_hits.is_none()
    }

    /// The photons to stop at: `photons`, else [`DEFAULT_PHOTONS`] when nothing else
    /// can end the run, else no limit.
    pub fn max_photons(&self) -> u64 {
        self.photons
            .or(self.open_ended().then_some(DEFAULT_PHOTONS))
            .unwrap_or(u64::MAX)
    }
}

/// A criterion's command-line flag: `time_limit` → `--time-limit`.
pub fn flag(key: &str) -> String {
    format!("--{}", key.replace('_', "-"))
}

/// A criterion's key in the scene file's `[simulation]` table, `at` naming the table.
pub fn scene_key(at: &str) -> impl Fn(&str) -> String + '_ {
    move |key| format!("{at}.{key}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_overrides_key_by_key() {
        let scene = StopCriteria {
            photons: Some(10),
            target_error: Some(0.1),
            target: Some("global".into()),
            ..StopCriteria::default()
        };
        let cli = StopCriteria {
            photons: Some(20),
            time_limit_s: Some(5.0),
            absolute: true,
            ..StopCriteria::default()
        };
        let both = scene.overridden_by(&cli);
        assert_eq!(both.photons, Some(20));
        assert_eq!(both.time_limit_s, Some(5.0));
        assert_eq!(both.target_error, Some(0.1));
        assert_eq!(both.target.as_deref(), Some("global"));
        assert!(both.absolute);
        assert_eq!(both.min_hits, None);
    }

    #[test]
    fn bad_values_name_their_key() {
        let zero = StopCriteria {
            photons: Some(0),
            ..StopCriteria::default()
        };
        let e = zero.validate(flag).unwrap_err().to_string();
        assert!(e.contains("--photons"), "{e}");
        let negative = StopCriteria {
            time_limit_s: Some(-1.0),
            ..StopCriteria::default()
        };
        let e = negative.validate(scene_key("s.toml: simulation"));
        let e = e.unwrap_err().to_string();
        assert!(e.contains("simulation.time_limit"), "{e}");
        let nan = StopCriteria {
            target_error: Some(f64::NAN),
            ..StopCriteria::default()
        };
        assert!(nan.validate(flag).is_err());
        assert_eq!(StopCriteria::default().max_photons(), DEFAULT_PHOTONS);
    }
}

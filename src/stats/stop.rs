//! Stop criteria (method.md §5, contract `--target`): they read statistics only, once
//! per epoch; the first one met ends the run.

use super::forecast::{Forecast, HistoryPoint};
use super::{receiver_stats, relative_error};
use crate::scene::Receiver;
use crate::tally::{CellSums, Counts};
use crate::{Error, Result};

/// What the error target (and `--min-hits`) applies to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// The scene map's odd/even error.
    Global,
    /// A receiver's mean error (eq. 9, quadratic averaging).
    Receiver { index: usize },
    /// The worst cell of a block of a receiver, half-open ranges i0..i1, j0..j1.
    Block {
        index: usize,
        i: (u32, u32),
        j: (u32, u32),
    },
}

impl Target {
    /// `text` parsed, or without it the default: the first receiver, else the scene map.
    pub fn chosen(text: Option<&str>, receivers: &[Receiver]) -> Result<Target> {
        match text {
            Some(t) => Target::parse(t, receivers),
            None if receivers.is_empty() => Ok(Target::Global),
            None => Ok(Target::Receiver { index: 0 }),
        }
    }

    /// Parses `global`, `receiver:NAME` or `receiver:NAME[i0..i1,j0..j1]`.
    pub fn parse(text: &str, receivers: &[Receiver]) -> Result<Target> {
        let bad = |msg: String| Error::input("--target", msg);
        if text == "global" {
            return Ok(Target::Global);
        }
        let Some(rest) = text.strip_prefix("receiver:") else {
            return Err(bad(format!(
                "`{text}`: expected `global`, `receiver:NAME` or `receiver:NAME[i0..i1,j0..j1]`"
            )));
        };
        let (name, block) = match rest.split_once('[') {
            Some((name, block)) => (name, Some(block)),
            None => (rest, None),
        };
        let index = receivers
            .iter()
            .position(|r| r.name == name)
            .ok_or_else(|| bad(format!("no receiver named `{name}`")))?;
        let Some(block) = block else {
            return Ok(Target::Receiver { index });
        };
        let cells = receivers[index].cells;
        let parse_range = |s: &str, n: u32| -> Result<(u32, u32)> {
            let (a, b) = s
                .split_once("..")
                .ok_or_else(|| bad(format!("`{text}`: range `{s}` is not `a..b`")))?;
            let a: u32 = a
                .trim()
                .parse()
                .map_err(|_| bad(format!("`{text}`: `{a}` is not a cell index")))?;
            let b: u32 = b
                .trim()
                .parse()
                .map_err(|_| bad(format!("`{text}`: `{b}` is not a cell index")))?;
            if a >= b || b > n {
                return Err(bad(format!(
                    "`{text}`: range {a}..{b} is empty or beyond the {n} cells"
                )));
            }
            Ok((a, b))
        };
        let inner = block
            .strip_suffix(']')
            .ok_or_else(|| bad(format!("`{text}`: missing `]`")))?;
        let (ri, rj) = inner
            .split_once(',')
            .ok_or_else(|| bad(format!("`{text}`: expected `[i0..i1,j0..j1]`")))?;
        Ok(Target::Block {
            index,
            i: parse_range(ri, cells[0])?,
            j: parse_range(rj, cells[1])?,
        })
    }

    /// The receiver the target reads, if any.
    pub fn receiver(&self) -> Option<usize> {
        match *self {
            Target::Global => None,
            Target::Receiver { index } | Target::Block { index, .. } => Some(index),
        }
    }

    /// Local cell indices (j·nu + i) of the receiver cells the target covers.
    pub fn cells(&self, receivers: &[Receiver]) -> Vec<usize> {
        match *self {
            Target::Global => Vec::new(),
            Target::Receiver { index } => (0..receivers[index].cell_count()).collect(),
            Target::Block { index, i, j } => {
                let nu = receivers[index].cells[0] as usize;
                (j.0..j.1)
                    .flat_map(|jj| (i.0..i.1).map(move |ii| jj as usize * nu + ii as usize))
                    .collect()
            }
        }
    }

    pub fn describe(&self, receivers: &[Receiver]) -> String {
        match *self {
            Target::Global => "global".into(),
            Target::Receiver { index } => format!("receiver:{}", receivers[index].name),
            Target::Block { index, i, j } => {
                format!(
                    "receiver:{}[{}..{},{}..{}]",
                    receivers[index].name, i.0, i.1, j.0, j.1
                )
            }
        }
    }
}

/// The target's current error for a receiver target: relative (eq. 9 quadratic for a
/// whole receiver, the worst cell's σ_rel for a block) or absolute (RMS σ, or the worst
/// cell's σ, in the receiver's unit), over the cells that carry light, each by the σ it
/// can vouch for ([`ReceiverStats::judged_sigma`](super::ReceiverStats): an unreliable
/// cell's σ widened by Student's t on its degrees of freedom and by its VOV). Dark cells
/// ([`super::CellStatus::Dark`]) count by their upper bound: the error is at least the largest
/// one (relative to the lit cells' mean: quadratic for a receiver, arithmetic for a
/// block), so a target is met only once
/// whatever they may hold could not change the answer by more than it. Infinite while
/// a cell it covers is unknown (nothing scored on the whole receiver).
pub fn receiver_target_error(
    target: &Target,
    receivers: &[Receiver],
    cells: &[CellSums],
    counts: Counts,
    absolute: bool,
) -> f64 {
    let Some(index) = target.receiver() else {
        return f64::INFINITY;
    };
    let picked = match target {
        Target::Receiver { .. } => None,
        _ => Some(target.cells(receivers)),
    };
    let stats = receiver_stats(cells, receivers[index].cells, counts, picked.as_deref());
    let lit =
        || (stats.values.iter().zip(&stats.judged_sigma)).filter(|(_, sigma)| !sigma.is_nan());
    if stats.unknown_cells > stats.dark_cells || lit().next().is_none() {
        return f64::INFINITY;
    }
    let bound = stats.dark_bound;
    // The dark cells' bound as an error (0 without dark cells).
    let relative_bound = |mean: f64| {
        if stats.dark_cells > 0 {
            relative_error(mean, bound)
        } else {
            0.0
        }
    };
    match (target, absolute) {
        (Target::Block { .. }, false) => {
            let (sum, n) = lit().fold((0.0, 0usize), |(s, n), (v, _)| (s + v, n + 1));
            lit()
                .map(|(v, s)| relative_error(*v, *s))
                .fold(relative_bound(sum / n as f64), f64::max)
        }
        (Target::Block { .. }, true) => lit().map(|(_, s)| *s).fold(bound, f64::max),
        (_, false) => stats
            .rel_error_judged
            .max(relative_bound(stats.quadratic_mean_judged)),
        (_, true) => stats.rms_sigma_judged.max(bound),
    }
}

/// Fewest hits among the target's cells.
pub fn min_hits(target: &Target, receivers: &[Receiver], cells: &[CellSums]) -> u64 {
    target
        .cells(receivers)
        .iter()
        .map(|&c| cells[c].hits)
        .min()
        .unwrap_or(0)
}

/// Epochs a run has before it judges whether its error target can be met: the
/// forecast's constant is a median over the later half of the history.
pub const EPOCHS_BEFORE_JUDGING: usize = 4;

/// Why the error target cannot be met, if it cannot: nothing has reached the target
/// (`nothing_scored`) after [`EPOCHS_BEFORE_JUDGING`] epochs, or the forecast needs
/// more photons than `max_photons` or more time than `time_limit_s` at this epoch and at
/// the one before (one noisy forecast does not decide). `None` while it may be met, and
/// without a target.
pub fn unreachable(
    target_error: Option<f64>,
    history: &[HistoryPoint],
    forecast: Option<Forecast>,
    nothing_scored: bool,
    max_photons: u64,
    time_limit_s: Option<f64>,
) -> Option<String> {
    target_error?;
    let last = history.last()?;
    if history.len() < EPOCHS_BEFORE_JUDGING {
        return None;
    }
    if nothing_scored {
        return Some(format!(
            "nothing has reached the target in {} photons",
            last.photons
        ));
    }
    // Why a forecast (photons, total seconds) is beyond the budget; none from a finite
    // error means the photons needed pass what can be counted.
    let beyond = |f: Option<(u64, f64)>, error: f64| match f {
        None => error.is_finite().then(|| {
            format!("the error ({error:.3e}) would need more photons than can be counted")
        }),
        Some((photons, _)) if photons > max_photons => Some(format!(
            "the forecast needs {photons} photons, more than the {max_photons} allowed"
        )),
        Some((_, total_s)) => time_limit_s.filter(|&limit| total_s > limit).map(|limit| {
            format!("the forecast needs {total_s:.1} s, more than the {limit} s time limit")
        }),
    };
    let previous = &history[history.len() - 2];
    let before = previous.forecast_photons.zip(previous.forecast_s);
    beyond(before, previous.rel_error)?;
    beyond(forecast.map(|f| (f.photons, f.total_s)), last.rel_error)
}

/// Why a run stopped (summary.json `stop_reason`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    Photons,
    Time,
    TargetError,
    MinHits,
    Interrupted,
    /// The error target was found unreachable (`--stop-if-unreachable`).
    Unreachable,
    /// Every requirement's check was decided (`--until decided`).
    Decided,
}

impl StopReason {
    pub fn as_str(self) -> &'static str {
        match self {
            StopReason::Photons => "photons",
            StopReason::Time => "time",
            StopReason::TargetError => "target_error",
            StopReason::MinHits => "min_hits",
            StopReason::Interrupted => "interrupted",
            StopReason::Unreachable => "unreachable",
            StopReason::Decided => "decided",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Estimator, Quantity};
    use glam::DVec3;

    fn receivers() -> Vec<Receiver> {
        vec![Receiver {
            name: "desk".into(),
            corner: DVec3::ZERO,
            u: DVec3::X,
            v: DVec3::Y,
            cells: [8, 4],
            quantity: Quantity::Illuminance,
            estimator: Estimator::Auto,
            grid: None,
            points: false,
            exclude: Vec::new(),
        }]
    }

    #[test]
    fn a_target_is_unreachable_once_two_forecasts_in_a_row_pass_the_budget() {
        let point = |photons: u64, forecast: Option<u64>| HistoryPoint {
            elapsed_s: photons as f64 * 1e-6,
            photons,
            rel_error: 0.1,
            forecast_s: forecast.map(|p| p as f64 * 1e-6),
            forecast_photons: forecast,
            checks: None,
        };
        let f = |photons| {
            Some(Forecast {
                total_s: photons as f64 * 1e-6,
                photons,
            })
        };
        let mut h: Vec<HistoryPoint> = (1..=4).map(|k| point(k * 1000, Some(5000))).collect();
        let judge = |h: &[HistoryPoint], now| unreachable(Some(0.01), h, now, false, 10_000, None);
        assert_eq!(judge(&h, f(5000)), None, "within the budget");
        h[3] = point(4000, Some(20_000));
        assert_eq!(
            judge(&h, f(20_000)),
            None,
            "one forecast beyond does not decide"
        );
        h.push(point(5000, Some(30_000)));
        let why = judge(&h, f(30_000)).expect("two in a row");
        assert!(
            why.contains("30000 photons, more than the 10000 allowed"),
            "{why}"
        );
        assert!(unreachable(None, &h, f(30_000), false, 10_000, None).is_none());
        // Time: the forecast's seconds beyond the limit, twice.
        let t = unreachable(Some(0.01), &h, f(30_000), false, u64::MAX, Some(0.01));
        assert!(t.expect("beyond the time limit").contains("time limit"));
        // Nothing scored: decided at once (after the first epochs).
        assert!(unreachable(Some(0.01), &h[..4], None, true, u64::MAX, None)
            .expect("nothing reached")
            .contains("nothing has reached"));
        assert!(unreachable(Some(0.01), &h[..3], None, true, u64::MAX, None).is_none());
    }

    #[test]
    fn targets_parse_and_reject_with_a_reason() {
        let r = receivers();
        assert_eq!(Target::parse("global", &r).unwrap(), Target::Global);
        assert_eq!(
            Target::parse("receiver:desk", &r).unwrap(),
            Target::Receiver { index: 0 }
        );
        let block = Target::parse("receiver:desk[2..4,1..3]", &r).unwrap();
        assert_eq!(
            block,
            Target::Block {
                index: 0,
                i: (2, 4),
                j: (1, 3)
            }
        );
        assert_eq!(block.cells(&r), vec![10, 11, 18, 19]);
        for bad in [
            "receiver:chair",
            "receiver:desk[0..9,0..1]",
            "receiver:desk[3..3,0..1]",
            "wall",
            "receiver:desk[0..1]",
        ] {
            let e = Target::parse(bad, &r).unwrap_err().to_string();
            assert!(e.starts_with("--target: "), "{e}");
        }
    }
}

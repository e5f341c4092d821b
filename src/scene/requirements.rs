//! `[[requirements]]`: the least (or most) values a receiver's or an observer's figures
//! must reach, and the modelling pairs (`modelling_with`) a requirement on the
//! modelling ratio Ēz/Ēh needs. `stats::verdict` judges them (docs/designers.md).

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::tasks::{Area, TaskType, TASK_TYPES};
use super::{Observer, Quantity, Receiver};
use crate::error::{Error, Result};
use serde::Deserialize;

/// A `[[requirements]]` entry as written: on a `receiver` (em, emin, u0, g2, modelling)
/// or on an `observer` (ugr_max).
#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
pub struct RequirementFile {
    pub name: Option<String>,
    pub receiver: Option<String>,
    pub observer: Option<String>,
    /// Ē (maintained), in the receiver's unit.
    pub em: Option<f64>,
    pub emin: Option<f64>,
    pub u0: Option<f64>,
    pub g2: Option<f64>,
    /// [least, most] of Ēz/Ēh (a cylindrical receiver with `modelling_with`).
    pub modelling: Option<[f64; 2]>,
    /// The most an observer's UGR may be.
    pub ugr_max: Option<f64>,
    /// A named EN 12464-1 task type (`scene::tasks`) whose values fill the keys left out.
    pub task: Option<String>,
    /// Which of the task's areas this receiver is (default `task`).
    pub area: Option<String>,
    /// The task's modified Ēm (2021's context modifiers) instead of the required one.
    pub modified: Option<bool>,
}

/// A figure a requirement can bound (docs/designers.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FigureName {
    /// Ē, the mean over the cells.
    Mean,
    /// Emin, the least cell.
    Min,
    /// Emin/Ē.
    U0,
    /// Emin/Emax.
    G2,
    /// Ēz/Ēh: a cylindrical receiver's mean over its `modelling_with` receiver's.
    Modelling,
    /// An observer's UGR.
    Ugr,
}

impl FigureName {
    /// The name the summary gives the check.
    pub fn key(self) -> &'static str {
        match self {
            FigureName::Mean => "em",
            FigureName::Min => "emin",
            FigureName::U0 => "u0",
            FigureName::G2 => "g2",
            FigureName::Modelling => "modelling",
            FigureName::Ugr => "ugr",
        }
    }
}

/// Which side of its limit a figure must stay.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Limit {
    AtLeast(f64),
    AtMost(f64),
}

impl Limit {
    pub fn value(self) -> f64 {
        match self {
            Limit::AtLeast(x) | Limit::AtMost(x) => x,
        }
    }

    /// How far `value` lies on the passing side of the limit (negative: failing).
    pub fn margin(self, value: f64) -> f64 {
        match self {
            Limit::AtLeast(x) => value - x,
            Limit::AtMost(x) => x - value,
        }
    }
}

/// One bound of a requirement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Check {
    pub figure: FigureName,
    pub limit: Limit,
}

/// What a requirement is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Subject {
    /// Index into the scene's receivers.
    Receiver(usize),
    /// Index into the scene's observers.
    Observer(usize),
}

/// A `[[requirements]]` entry, validated.
#[derive(Clone, Debug, PartialEq)]
pub struct Requirement {
    pub name: String,
    pub subject: Subject,
    pub checks: Vec<Check>,
    /// The task type and area the limits come from (`task`), described.
    pub basis: Option<String>,
}

/// A cylindrical receiver and the horizontal one its modelling ratio Ēz/Ēh divides by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ModellingPair {
    pub cylindrical: usize,
    pub horizontal: usize,
}

/// The modelling pairs from each receiver's `modelling_with` (in receiver order; None
/// where a receiver has none), validated: the receiver is cylindrical and names another,
/// an illuminance receiver.
pub fn modelling_pairs(
    modelling_with: &[Option<String>],
    receivers: &[Receiver],
    origin: &str,
) -> Result<Vec<ModellingPair>> {
    let mut pairs = Vec::new();
    for (i, with) in modelling_with.iter().enumerate() {
        let Some(with) = with else { continue };
        let at = format!("{origin}: receivers[{i}].modelling_with");
        if receivers[i].quantity != Quantity::Cylindrical {
            return Err(Error::input(
                at,
                "applies only to quantity = \"cylindrical\" (Ēz over Ēh)",
            ));
        }
        let horizontal = receivers
            .iter()
            .position(|r| &r.name == with)
            .ok_or_else(|| Error::input(&at, format!("no receiver named `{with}`")))?;
        if receivers[horizontal].quantity != Quantity::Illuminance || horizontal == i {
            return Err(Error::input(
                at,
                format!("`{with}` must be another receiver of quantity = \"illuminance\""),
            ));
        }
        pairs.push(ModellingPair {
            cylindrical: i,
            horizontal,
        });
    }
    Ok(pairs)
}

/// The `[[requirements]]` entries, validated against the scene's receivers, modelling
/// pairs and observers.
pub fn requirements(
    entries: Vec<RequirementFile>,
    receivers: &[Receiver],
    modelling: &[ModellingPair],
    observers: &[Observer],
    origin: &str,
) -> Result<Vec<Requirement>> {
    let mut out: Vec<Requirement> = Vec::new();
    for (i, mut r) in entries.into_iter().enumerate() {
        let at = format!("{origin}: requirements[{i}]");
        let (subject, subject_name) = subject(&r, receivers, observers, &at)?;
        let basis = apply_task(&mut r, subject, receivers, &at)?;
        let checks = checks(&r, subject, modelling, &at)?;
        let name = r.name.unwrap_or(subject_name);
        if out.iter().any(|o| o.name == name) {
            return Err(Error::input(
                format!("{at}.name"),
                format!("duplicate requirement name `{name}`"),
            ));
        }
        out.push(Requirement {
            name,
            subject,
            checks,
            basis,
        });
    }
    Ok(out)
}

/// Fills the keys a requirement leaves out from its `task` row for its `area` (an
/// observer: the row's R_UGL); returns what the limits came from.
fn apply_task(
    r: &mut RequirementFile,
    subject: Subject,
    receivers: &[Receiver],
    at: &str,
) -> Result<Option<String>> {
    let Some(id) = &r.task else {
        if r.area.is_some() || r.modified.is_some() {
            return Err(Error::input(at, "`area` and `modified` need a `task`"));
        }
        return Ok(None);
    };
    let task = TaskType::find(id).ok_or_else(|| {
        let known: Vec<&str> = TASK_TYPES.iter().map(|t| t.id).collect();
        Error::input(
            format!("{at}.task"),
            format!("unknown task type `{id}` (known: {})", known.join(", ")),
        )
    })?;
    let modified = r.modified.unwrap_or(false);
    let receiver = match subject {
        Subject::Observer(_) => {
            if r.area.is_some() || r.modified.is_some() {
                return Err(Error::input(
                    at,
                    "`area` and `modified` apply to a receiver, not an observer",
                ));
            }
            r.ugr_max = r.ugr_max.or(Some(task.ugr_max));
            return Ok(Some(format!("{}: {} (R_UGL)", task.source, task.title)));
        }
        Subject::Receiver(k) => &receivers[k],
    };
    let area = match r.area.as_deref() {
        None => match receiver.quantity {
            Quantity::Cylindrical => Area::Cylindrical,
            _ => Area::Task,
        },
        Some(name) => Area::parse(name).ok_or_else(|| {
            Error::input(
                format!("{at}.area"),
                format!("must be one of {}, got `{name}`", Area::NAMES),
            )
        })?,
    };
    if (area == Area::Cylindrical) != (receiver.quantity == Quantity::Cylindrical) {
        return Err(Error::input(
            format!("{at}.area"),
            "`cylindrical` is the area of a cylindrical receiver, and only of one",
        ));
    }
    let values = task.area_values(area, modified).ok_or_else(|| {
        Error::input(
            format!("{at}.modified"),
            format!("task type `{id}` gives no modified value here"),
        )
    })?;
    r.em = r.em.or(Some(values.em));
    r.u0 = r.u0.or(values.u0);
    Ok(Some(task.describe(area, modified)))
}

/// The receiver or observer a requirement names (exactly one), and its name.
fn subject(
    r: &RequirementFile,
    receivers: &[Receiver],
    observers: &[Observer],
    at: &str,
) -> Result<(Subject, String)> {
    match (&r.receiver, &r.observer) {
        (Some(name), None) => receivers
            .iter()
            .position(|x| &x.name == name)
            .map(|k| (Subject::Receiver(k), name.clone()))
            .ok_or_else(|| {
                Error::input(
                    format!("{at}.receiver"),
                    format!("no receiver named `{name}`"),
                )
            }),
        (None, Some(name)) => observers
            .iter()
            .position(|x| &x.name == name)
            .map(|k| (Subject::Observer(k), name.clone()))
            .ok_or_else(|| {
                Error::input(
                    format!("{at}.observer"),
                    format!("no observer named `{name}`"),
                )
            }),
        _ => Err(Error::input(
            at,
            "names exactly one of `receiver` and `observer`",
        )),
    }
}

/// A requirement's checks, each limit validated, in the order em, emin, u0, g2,
/// modelling (least, most), ugr.
fn checks(
    r: &RequirementFile,
    subject: Subject,
    modelling: &[ModellingPair],
    at: &str,
) -> Result<Vec<Check>> {
    let bad = |key: &str, what: &str, got: f64| {
        Err(Error::input(
            format!("{at}.{key}"),
            format!("must be {what}, got {got}"),
        ))
    };
    let on_receiver = [
        (FigureName::Mean, r.em),
        (FigureName::Min, r.emin),
        (FigureName::U0, r.u0),
        (FigureName::G2, r.g2),
    ];
    let mut checks = Vec::new();
    for (figure, value) in on_receiver {
        let Some(x) = value else { continue };
        let ratio = matches!(figure, FigureName::U0 | FigureName::G2);
        if ratio && !(x > 0.0 && x <= 1.0) {
            return bad(figure.key(), "in (0, 1]", x);
        }
        if !(x > 0.0 && x <= f64::MAX) {
            return bad(figure.key(), "positive", x);
        }
        checks.push(Check {
            figure,
            limit: Limit::AtLeast(x),
        });
    }
    if let Some([lo, hi]) = r.modelling {
        if !(lo > 0.0 && lo < hi && hi <= f64::MAX) {
            return Err(Error::input(
                format!("{at}.modelling"),
                format!("must be [least, most] with 0 < least < most, got [{lo}, {hi}]"),
            ));
        }
        let paired = matches!(subject, Subject::Receiver(k)
            if modelling.iter().any(|p| p.cylindrical == k));
        if !paired {
            return Err(Error::input(
                format!("{at}.modelling"),
                "needs a cylindrical receiver with `modelling_with`",
            ));
        }
        for limit in [Limit::AtLeast(lo), Limit::AtMost(hi)] {
            checks.push(Check {
                figure: FigureName::Modelling,
                limit,
            });
        }
    }
    if let Some(x) = r.ugr_max {
        if !(x.is_finite() && x > 0.0) {
            return bad("ugr_max", "a positive number", x);
        }
        checks.push(Check {
            figure: FigureName::Ugr,
            limit: Limit::AtMost(x),
        });
    }
    let wrong_subject = checks
        .iter()
        .find(|c| (c.figure == FigureName::Ugr) != matches!(subject, Subject::Observer(_)));
    if let Some(c) = wrong_subject {
        let owner = if c.figure == FigureName::Ugr {
            "an observer"
        } else {
            "a receiver"
        };
        let key = match c.figure {
            FigureName::Ugr => "ugr_max",
            other => other.key(),
        };
        return Err(Error::input(
            format!("{at}.{key}"),
            format!("applies only to {owner}"),
        ));
    }
    if checks.is_empty() {
        return Err(Error::input(
            at,
            "sets no figure to check (em, emin, u0, g2, modelling or ugr_max)",
        ));
    }
    Ok(checks)
}

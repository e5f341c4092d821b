//! `[[observers]]`: eyes whose Unified Glare Rating (CIE 117, docs/ugr.md) the run
//! reports. Each observer adds one hidden next-event receiver, `observer:NAME`, a
//! 5 cm × 5 cm single cell at the eye facing the line of sight: its indirect part is
//! the background's vertical illuminance E_ind.

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{Estimator, Quantity, Receiver, SceneLight};
use crate::error::{Error, Result};
use crate::input::{direction, vec3, Coords};
use crate::light::Luminaire;
use glam::DVec3;
use serde::Deserialize;

/// Side of an observer's hidden receiver, m.
pub const OBSERVER_RECEIVER_SIDE_M: f64 = 0.05;

/// The prefix of an observer's hidden receiver's name.
pub const OBSERVER_RECEIVER_PREFIX: &str = "observer:";

/// An `[[observers]]` entry as written.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ObserverFile {
    pub name: String,
    pub position: Coords,
    pub look: [f64; 3],
    pub grid: Option<ObserverGridFile>,
}

/// `grid = {count = [nx, ny], spacing = [dx, dy]}`: observers at (i·dx, j·dy, 0) from
/// `position`, named `NAME[i,j]`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct ObserverGridFile {
    pub count: [u32; 2],
    pub spacing: [f64; 2],
}

/// A validated observer: its eye, unit line of sight (world up is +z) and the index of
/// its hidden receiver in `Scene::receivers`.
#[derive(Clone, Debug, PartialEq)]
pub struct Observer {
    pub name: String,
    pub position: DVec3,
    pub look: DVec3,
    pub receiver: usize,
}

/// Most observers one entry's grid may make.
const MAX_GRID_OBSERVERS: u64 = 1 << 16;

/// The `[[observers]]` entries, validated against the scene's `lights`; each observer's
/// hidden receiver is appended to `receivers`.
pub fn observers(
    entries: Vec<ObserverFile>,
    lights: &[SceneLight],
    receivers: &mut Vec<Receiver>,
    origin: &str,
) -> Result<Vec<Observer>> {
    let mut out: Vec<Observer> = Vec::new();
    for (i, o) in entries.into_iter().enumerate() {
        let at = format!("{origin}: observers[{i}]");
        if o.name.trim().is_empty() {
            return Err(Error::input(format!("{at}.name"), "empty observer name"));
        }
        let look = direction(o.look, &at, "look")?;
        for (name, position) in placements(&o, &at)? {
            check_clear_of_luminaires(position, lights, &at)?;
            let receiver_name = format!("{OBSERVER_RECEIVER_PREFIX}{name}");
            if out.iter().any(|x| x.name == name)
                || receivers.iter().any(|r| r.name == receiver_name)
            {
                return Err(Error::input(
                    format!("{at}.name"),
                    format!("duplicate observer name `{name}`"),
                ));
            }
            receivers.push(hidden_receiver(receiver_name, position, look));
            out.push(Observer {
                name,
                position,
                look,
                receiver: receivers.len() - 1,
            });
        }
    }
    Ok(out)
}

/// The observers an entry places: itself, or its grid's.
fn placements(o: &ObserverFile, at: &str) -> Result<Vec<(String, DVec3)>> {
    let position = vec3(o.position);
    let Some(g) = &o.grid else {
        return Ok(vec![(o.name.clone(), position)]);
    };
    let [nx, ny] = g.count;
    if nx == 0 || ny == 0 || nx as u64 * ny as u64 > MAX_GRID_OBSERVERS {
        return Err(Error::input(
            format!("{at}.grid.count"),
            format!(
                "{:?}: each must be ≥ 1, at most {MAX_GRID_OBSERVERS} in all",
                g.count
            ),
        ));
    }
    if !g.spacing.iter().all(|s| s.is_finite() && s.abs() <= 1e16) {
        return Err(Error::input(
            format!("{at}.grid.spacing"),
            "must be finite lengths within ±1e16 m",
        ));
    }
    let mut out = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let offset = DVec3::new(i as f64 * g.spacing[0], j as f64 * g.spacing[1], 0.0);
            out.push((format!("{}[{i},{j}]", o.name), position + offset));
        }
    }
    Ok(out)
}

/// An eye within a luminaire's opening (closer to its centre than the opening's
/// largest extent) sees no luminance the formula can rate: refused.
fn check_clear_of_luminaires(eye: DVec3, lights: &[SceneLight], at: &str) -> Result<()> {
    for l in lights {
        let Some(lum) = l.get::<Luminaire>() else {
            continue;
        };
        let d = (eye - lum.position).length();
        let size = lum.photometry.opening.diagonal_m();
        if !(d > size) || d == 0.0 {
            return Err(Error::input(
                format!("{at}.position"),
                format!(
                    "the eye lies within the luminous opening of {} ({d:.3} m from its \
                     centre, opening {size:.3} m across)",
                    l.label
                ),
            ));
        }
    }
    Ok(())
}

/// The hidden receiver at `eye`: one next-event cell, `OBSERVER_RECEIVER_SIDE_M`
/// square, whose measuring face (normal u × v) is `look`: it takes the light coming
/// from the scene in front of the eye.
pub fn hidden_receiver(name: String, eye: DVec3, look: DVec3) -> Receiver {
    let u = DVec3::Z
        .cross(look)
        .try_normalize()
        .unwrap_or_else(|| look.any_orthonormal_vector());
    let v = look.cross(u);
    let s = OBSERVER_RECEIVER_SIDE_M;
    Receiver {
        name,
        corner: eye - 0.5 * s * (u + v),
        u: s * u,
        v: s * v,
        cells: [1, 1],
        quantity: Quantity::Illuminance,
        estimator: Estimator::NextEvent,
        grid: None,
        points: false,
        exclude: Vec::new(),
    }
}

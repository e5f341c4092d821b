//! summary.json's `observers`: each `[[observers]]` eye's UGR (docs/ugr.md).

use crate::run::RunState;
use crate::stats::figures::normal_quantile;
use crate::stats::ugr::{self, Seen};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One observer's rating: null numbers where UGR is undefined.
#[derive(Serialize, Deserialize, Default, Clone, Debug)]
#[serde(default)]
pub struct ObserverSummary {
    pub position: [f64; 3],
    pub look: [f64; 3],
    /// Its hidden receiver in `receivers`.
    pub receiver: String,
    pub ugr: Option<f64>,
    pub ugr_sigma: Option<f64>,
    /// The interval at `[simulation] confidence` (from E_ind's; `high` null when E_ind's
    /// lower end reaches 0).
    pub ugr_low: Option<f64>,
    pub ugr_high: Option<f64>,
    pub confidence: f64,
    pub e_ind_lx: f64,
    pub e_ind_sigma_lx: Option<f64>,
    /// Σ L²ω/p² over the counted luminaires.
    pub sum: f64,
    pub valid: bool,
    pub invalid_reason: Option<String>,
    pub luminaires: Vec<ObserverLuminaire>,
}

/// A luminaire as the observer sees it.
#[derive(Serialize, Deserialize, Default, Clone, Debug)]
#[serde(default)]
pub struct ObserverLuminaire {
    pub label: String,
    pub luminance_cdm2: f64,
    pub omega_sr: f64,
    pub position_index: f64,
    /// Along the line of sight, above it, sideways (m).
    pub r_m: f64,
    pub h_m: f64,
    pub t_m: f64,
    pub occluded: bool,
    /// The fraction of the opening the eye sees; `omega_sr` is of that part.
    pub visible_fraction: f64,
    pub counted: bool,
    /// `counted` or why not.
    pub status: String,
}

/// The observers' ratings (None for a scene without observers).
pub fn observers(state: &RunState<'_>) -> Option<BTreeMap<String, ObserverSummary>> {
    let scene = state.scene;
    if scene.observers.is_empty() {
        return None;
    }
    let t = &state.progress.tallies;
    let lums = ugr::luminaires(scene);
    let confidence = scene.simulation.confidence;
    let z = normal_quantile(1.0 - (1.0 - confidence) / 2.0);
    let mut out = BTreeMap::new();
    for (k, o) in scene.observers.iter().enumerate() {
        let visible = state
            .setup
            .observer_visible
            .get(k)
            .map_or(&[][..], Vec::as_slice);
        let terms = ugr::observer_terms(scene, o, visible);
        let rows = (lums.iter().zip(&terms))
            .map(|((label, _), term)| ObserverLuminaire {
                label: label.to_string(),
                luminance_cdm2: term.luminance_cdm2,
                omega_sr: term.omega_sr,
                position_index: term.position_index,
                r_m: term.r_h_t_m[0],
                h_m: term.r_h_t_m[1],
                t_m: term.r_h_t_m[2],
                occluded: term.visible_fraction == 0.0,
                visible_fraction: term.visible_fraction,
                counted: term.seen == Seen::Counted,
                status: term.seen.as_str().to_string(),
            })
            .collect();
        let e_ind = ugr::e_ind(scene, t, o);
        let r = ugr::rate(terms, e_ind);
        let at = |e: f64| ugr::ugr(r.sum, e);
        let (e, s) = (r.e_ind_lx, r.e_ind_sigma_lx);
        let known = r.ugr.is_some() && s.is_finite();
        out.insert(
            o.name.clone(),
            ObserverSummary {
                position: o.position.to_array(),
                look: o.look.to_array(),
                receiver: scene.receivers[o.receiver].name.clone(),
                ugr: r.ugr,
                ugr_sigma: r.ugr_sigma.filter(|x| x.is_finite()),
                ugr_low: known.then(|| at(e + z * s)).flatten(),
                ugr_high: known.then(|| at(e - z * s)).flatten(),
                confidence,
                e_ind_lx: e,
                e_ind_sigma_lx: s.is_finite().then_some(s),
                sum: r.sum,
                valid: r.invalid.is_none(),
                invalid_reason: r.invalid,
                luminaires: rows,
            },
        );
    }
    Some(out)
}

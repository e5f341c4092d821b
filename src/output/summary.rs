//! summary.json: every key of the contract, plus what a user needs to judge the run.
//! Written by serde and read back typed by `luxtally report`: numbers serde_json wrote
//! as null (NaN: an unknown error) read back as NaN.

use crate::run::RunState;
use crate::scene::Estimator;
use crate::stats::figures::{self, Figure, Figures};
use crate::stats::forecast::HistoryPoint;
use crate::stats::null_as_nan;
use crate::stats::stop::Target;
use crate::stats::ugr_table;
use crate::stats::verdict::{verdicts, Verdicts};
use crate::stats::{
    cell_vov, direct_estimate, figure_of_merit, map_stats, mean_illuminance_sigma_lx,
    mean_illuminance_vov, receiver_stats, reliability, Averaged, CellStatus, MapKind, Reliability,
};
use crate::trace::bounce_cap_bias_bound;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Keys missing from an older summary.json read as their defaults (`luxtally report`).
#[derive(Serialize, Deserialize, Default)]
#[serde(default)]
pub struct Summary {
    pub scene: String,
    pub backend: String,
    /// The BVH layout built: `fast` or `compact` (`--bvh`).
    pub bvh: String,
    pub seed: u64,
    pub threads: usize,
    pub photons_emitted: u64,
    pub rays_traced: u64,
    /// Wall time of the photon pass (s), including the direct light's replicates added
    /// during it; `setup_s` is what came before it: BVH build and the direct light's
    /// pilot replicates.
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub elapsed_s: f64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub setup_s: f64,
    /// Null while the run is still going (a summary saved mid-run).
    pub stop_reason: Option<String>,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub total_flux_lm: f64,
    pub lights: Vec<LightSummary>,
    pub luminaires: Vec<LuminaireSummary>,
    pub target: String,
    /// `history[].rel_error` and the forecast's target are absolute (`--absolute`, in
    /// the target's unit), not relative.
    pub absolute_error: bool,
    pub bounce_cap: u32,
    pub photons_killed_by_bounce_cap: u64,
    /// The largest share of the light the bounce cap can have dropped (docs/method.md,
    /// *Bounce cap*): ρ_max^cap ≤ 1e-12 below lossless materials; with them, −ln(0.05)/N
    /// (95 %) while no photon of N was capped, else null (unknown). Absent from older
    /// files (reads null).
    pub bounce_cap_bias_bound: Option<f64>,
    /// The next-event receivers' sampled direct light: replicates per cell, their
    /// shadow rays (not in `rays_traced`) and seconds (before and during the photons).
    pub direct_replicates: u64,
    pub direct_rays: u64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub direct_s: f64,
    /// Seconds of statistics, forecasts and stop checks over all epochs, and their
    /// share of `elapsed_s`.
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub stats_s: f64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub stats_share: f64,
    /// Seconds of merging the chunks' tallies at epoch ends, and their share.
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub merge_s: f64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub merge_share: f64,
    pub receivers: BTreeMap<String, ReceiverSummary>,
    pub global: GlobalSummary,
    /// How far the target's error can be trusted (FOM, its stability, VOV).
    pub reliability: Reliability,
    pub history: Vec<HistoryPoint>,
    pub forecast: Option<ForecastSummary>,
    /// Why the error target cannot be met, if it cannot: nothing has reached its cells,
    /// or the forecast is beyond the photon or time budget (`--stop-if-unreachable` ends
    /// the run then); null while it may be met, and without a target.
    pub target_unreachable: Option<String>,
    /// The verdicts on the scene's `[[requirements]]` (absent without any).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verdicts: Option<Verdicts>,
    /// The `[[observers]]`' UGR by name (absent without any; docs/ugr.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observers: Option<BTreeMap<String, super::observers::ObserverSummary>>,
    /// Each sky's luminance on a fisheye grid, for report.html (absent without skies;
    /// docs/daylight.md, *Sky plots*).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sky_plots: Vec<super::sky_plot::SkyPlot>,
}

#[derive(Serialize, Deserialize, Default)]
#[serde(default)]
pub struct LightSummary {
    pub label: String,
    /// Maintained flux: the maintenance factor applied.
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub flux_lm: f64,
    /// The maintenance factor in `flux_lm` (1 for lights without one).
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub maintenance_factor: f64,
}

/// A photometric file the scene's luminaires use (once per file).
#[derive(Serialize, Deserialize, Default)]
#[serde(default)]
pub struct LuminaireSummary {
    pub file: String,
    /// Luminaires of the scene placed from it.
    pub count: usize,
    /// Flux of the file's interpolant (before `multiplier`/`flux_lm`), lm.
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub flux_lm: f64,
    pub light_output_ratio: Option<f64>,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub peak_cd: f64,
    pub symmetry: String,
    pub opening: String,
    /// The polar diagram (C0–180, C90–270 in cd/klm), a base64 PNG.
    pub polar_png_base64: String,
    /// Its CIE 190 UGR table (SHR 0.25, 1000 lm: `luxtally ugr-table`'s plot), a base64
    /// PNG; empty where it cannot be rated (a point opening).
    #[serde(default)]
    pub ugr_table_png_base64: String,
}

#[derive(Serialize, Deserialize, Default)]
#[serde(default)]
pub struct ReceiverSummary {
    pub quantity: String,
    pub unit: String,
    /// `track` or `next_event` (what `auto` resolved to).
    pub estimator: String,
    /// How the light arriving straight from the sources is scored: `sampled` (the
    /// direct-light replicates, next_event) or `track`.
    pub direct_estimator: String,
    /// How the light arriving after scattering is scored: `next_event` (connections from
    /// diffuse vertices, crossings after specular ones and near the receiver) or `track`.
    pub indirect_estimator: String,
    /// The sampled direct part of `values` (0 for track receivers) and its σ, in the
    /// receiver's unit.
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub direct: Vec<f64>,
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub direct_sigma: Vec<f64>,
    pub cells: [u32; 2],
    /// Index j * cells[0] + i.
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub values: Vec<f64>,
    /// null where the error is unknown: nothing scored in the cell.
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub sigma: Vec<f64>,
    pub hits: Vec<u64>,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub mean: f64,
    /// Eq. 9; null while some cell's error is unknown (`unknown_cells`).
    pub rel_error: Averaged,
    /// Eq. 9 over the cells whose error is known.
    pub rel_error_known_cells: Averaged,
    pub unknown_cells: usize,
    /// Figure of merit 1/(σ_rel²·t) of the quadratic mean error.
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub fom: f64,
    /// Largest variance of the variance over the cells that scored (MCNP's check:
    /// above 0.1 the σ of that cell is not yet reliable).
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub max_vov: f64,
    /// Per cell: the photon histories that scored in it, its VOV, the effective degrees
    /// of freedom of its σ (Welch–Satterthwaite) and its status: `reliable`,
    /// `unreliable` (too few or too uneven samples behind σ), `dark` (nothing scored
    /// while other cells did: see `upper_bound`) or `unknown` (nothing scored anywhere).
    pub scoring_histories: Vec<u64>,
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub vov: Vec<f64>,
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub dof: Vec<f64>,
    pub status: Vec<CellStatus>,
    /// A dark or unreliable cell's (about) 95 % upper bound on its value (null for the
    /// other cells).
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub upper_bound: Vec<f64>,
    pub unreliable_cells: usize,
    /// Dark cells (counted in `unknown_cells` too: their σ is unknown) and the largest
    /// of their upper bounds (0 without dark cells).
    pub dark_cells: usize,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub dark_upper_bound: f64,
    /// The designer's figures over the cells: Ē, Emin, Emax, U0, g2 with intervals at
    /// `[simulation] confidence` (docs/designers.md), leaving out `excluded_cells`.
    pub figures: Figures,
    /// The cells (j·nu + i) whose centres lie in the areas of the receivers it
    /// `exclude`s: in the arrays above, not in `figures` (nor in `mean`, `rel_error`,
    /// which are over all cells).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub excluded_cells: Vec<usize>,
    /// The values as a daylight factor (`daylight_factor = true`; docs/daylight.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub daylight_factor: Option<DaylightFactorSummary>,
}

/// A receiver's illuminance as daylight factors DF = 100·E/E_out, %.
#[derive(Serialize, Deserialize, Default)]
#[serde(default)]
pub struct DaylightFactorSummary {
    /// E_out: the sky's illuminance on an unobstructed horizontal plane (exact), lx.
    pub outside_lx: f64,
    pub sky: String,
    /// Per cell, %, and σ (null where unknown): `values` × 100/E_out, exactly.
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub values: Vec<f64>,
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub sigma: Vec<f64>,
    /// The sky component (the sky seen directly through the openings: the sampled
    /// direct part) and the reflected components (externally and internally reflected
    /// together: the rest), %; empty when the direct light is not sampled apart (track).
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub sky_component: Vec<f64>,
    #[serde(deserialize_with = "null_as_nan::vec")]
    pub reflected: Vec<f64>,
    /// The mean and least DF over the included cells, with their intervals
    /// (`figures`' mean and min, scaled).
    pub mean: Figure,
    pub min: Figure,
}

#[derive(Serialize, Deserialize, Default)]
#[serde(default)]
pub struct GlobalSummary {
    pub triangles: usize,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub area_m2: f64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub mean_illuminance_lx: f64,
    /// Standard error of `mean_illuminance_lx` (from per-history hit counts).
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub mean_sigma_lx: f64,
    /// RMS error of the per-triangle map, σ = d/2 from the odd/even maps (method.md §3).
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub sigma_lx: f64,
    pub rel_error: Averaged,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub indirect_mean_illuminance_lx: f64,
    pub indirect_rel_error: Averaged,
}

#[derive(Serialize, Deserialize, Default)]
#[serde(default)]
pub struct ForecastSummary {
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub target_error: f64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub predicted_total_s: f64,
    pub predicted_photons: u64,
}

/// Builds the summary of a run's current state.
pub fn build(state: &RunState<'_>) -> Summary {
    let scene = state.scene;
    let t = &state.progress.tallies;
    let receivers = scene
        .receivers
        .iter()
        .zip(&state.setup.estimators)
        .enumerate()
        .map(|(index, (r, &estimator))| (r.name.clone(), receiver(state, index, estimator)))
        .collect();
    // A share of the run's time; 0 before any time has passed.
    let share = |part_s: f64| {
        if state.progress.times.elapsed_s > 0.0 {
            part_s / state.progress.times.elapsed_s
        } else {
            0.0
        }
    };
    let global = global(state);
    let cap_bound = bounce_cap_bias_bound(
        state.setup.bounce_cap_a_priori,
        t.killed_by_bounce_cap,
        t.photons,
    );
    // The cap's bound is judged against the relative σ of the target and of the scene
    // map's mean.
    let global_sigma_rel = global.mean_sigma_lx / global.mean_illuminance_lx;
    // The last epoch's error is the target's relative error now, unless it was absolute
    // or the tallies moved on since (a merge): then computed again.
    let target_sigma_rel = match state.progress.history.last() {
        Some(p) if !state.options.stop.absolute && p.photons == t.photons => p.rel_error,
        _ => crate::run::target_error(scene, state.target, t, state.setup.total_flux_lm, false),
    };
    Summary {
        scene: scene.name.clone(),
        backend: state.options.backend.name().to_string(),
        bvh: state.options.bvh.built().name().to_string(),
        seed: state.options.seed,
        threads: state.setup.threads,
        photons_emitted: t.photons,
        rays_traced: t.rays,
        direct_replicates: t.direct_replicates,
        elapsed_s: state.progress.times.elapsed_s,
        setup_s: state.setup.setup_s,
        stop_reason: state.stop_reason.map(|r| r.as_str().to_string()),
        total_flux_lm: state.setup.total_flux_lm,
        lights: light_summaries(state),
        luminaires: luminaires(scene),
        target: state.target.describe(&scene.receivers),
        absolute_error: state.options.stop.absolute,
        bounce_cap: state.setup.bounce_cap,
        photons_killed_by_bounce_cap: t.killed_by_bounce_cap,
        bounce_cap_bias_bound: cap_bound,
        direct_rays: t.direct_rays,
        direct_s: state.progress.times.direct_s,
        stats_s: state.progress.times.stats_s,
        merge_s: state.progress.times.merge_s,
        merge_share: share(state.progress.times.merge_s),
        stats_share: share(state.progress.times.stats_s),
        receivers,
        reliability: reliability(&state.progress.history, target_vov(state))
            .with_bounce_cap(cap_bound, &[target_sigma_rel, global_sigma_rel]),
        global,
        history: state.progress.history.to_vec(),
        target_unreachable: crate::run::target_unreachable(
            scene,
            state.options,
            state.target,
            state.progress,
        ),
        verdicts: (!scene.requirements.is_empty())
            .then(|| verdicts(scene, t, &state.setup.observer_visible)),
        forecast: forecast_summary(state),
        observers: super::observers::observers(state),
        sky_plots: super::sky_plot::sky_plots(scene),
    }
}

/// Each light's label, flux and maintenance factor.
fn light_summaries(state: &RunState<'_>) -> Vec<LightSummary> {
    (state.scene.lights.iter())
        .zip(&state.setup.light_flux_lm)
        .map(|(l, f)| LightSummary {
            label: l.label.clone(),
            flux_lm: *f,
            maintenance_factor: l.kind.maintenance_factor(),
        })
        .collect()
}

/// The forecast to the target error (None without a target or a forecast yet).
fn forecast_summary(state: &RunState<'_>) -> Option<ForecastSummary> {
    match (state.options.stop.target_error, state.progress.forecast) {
        (Some(target_error), Some(f)) => Some(ForecastSummary {
            target_error,
            predicted_total_s: f.total_s,
            predicted_photons: f.photons,
        }),
        _ => None,
    }
}

/// Receiver `index`'s summary, scored by `estimator`.
fn receiver(state: &RunState<'_>, index: usize, estimator: Estimator) -> ReceiverSummary {
    let t = &state.progress.tallies;
    let r = &state.scene.receivers[index];
    let cells = t.receiver_cells(&state.scene.receivers, index);
    let stats = receiver_stats(cells, r.cells, t.counts(), None);
    let direct: Vec<(f64, f64)> = cells
        .iter()
        .map(|c| direct_estimate(c, t.counts()))
        .collect();
    let max_vov = cells
        .iter()
        .zip(&stats.vov)
        .filter(|(c, _)| c.hits > 0)
        .map(|(_, &vov)| vov)
        .fold(0.0, f64::max);
    let receivers = &state.scene.receivers;
    let figures = figures::receiver_figures(state.scene, t, index);
    let (quantity, unit) = (r.quantity.name(), r.quantity.unit());
    let sampled = estimator.direct_by_replicates().then_some(&direct[..]);
    let daylight = daylight_factor(
        state.scene,
        index,
        &stats.values,
        &stats.sigma,
        sampled,
        &figures,
    );
    ReceiverSummary {
        quantity: quantity.into(),
        unit: unit.into(),
        estimator: estimator.name().into(),
        direct_estimator: estimator.direct_name().into(),
        indirect_estimator: estimator.indirect_name().into(),
        direct: direct.iter().map(|d| d.0).collect(),
        direct_sigma: direct.iter().map(|d| d.1).collect(),
        cells: r.cells,
        values: stats.values,
        sigma: stats.sigma,
        hits: stats.hits,
        mean: stats.mean,
        rel_error: stats.rel_error,
        rel_error_known_cells: stats.rel_error_known,
        unknown_cells: stats.unknown_cells,
        fom: figure_of_merit(stats.rel_error.quadratic, state.progress.times.elapsed_s),
        max_vov,
        scoring_histories: stats.scoring_histories,
        vov: stats.vov,
        dof: stats.dof,
        status: stats.status,
        upper_bound: stats.upper_bound,
        unreliable_cells: stats.unreliable_cells,
        dark_cells: stats.dark_cells,
        dark_upper_bound: stats.dark_bound,
        figures,
        daylight_factor: daylight,
        excluded_cells: (r.excluded_cells(receivers).iter().enumerate())
            .filter_map(|(k, &x)| x.then_some(k))
            .collect(),
    }
}

/// Receiver `index`'s daylight factors, if it asks for them: its values, σ, sampled
/// direct part (None for the track estimator) and figures (Ē, Emin) times 100/E_out.
fn daylight_factor(
    scene: &crate::scene::Scene,
    index: usize,
    values: &[f64],
    sigma: &[f64],
    direct: Option<&[(f64, f64)]>,
    figures: &Figures,
) -> Option<DaylightFactorSummary> {
    let df = scene.daylight_factor.as_ref()?;
    if !df.receivers.contains(&index) {
        return None;
    }
    let k = 100.0 / df.outside_lx;
    let scaled = |xs: &[f64]| xs.iter().map(|x| x * k).collect::<Vec<f64>>();
    let figure = |f: &Figure| Figure {
        value: f.value * k,
        low: f.low * k,
        high: f.high * k,
    };
    Some(DaylightFactorSummary {
        outside_lx: df.outside_lx,
        sky: df.sky.clone(),
        values: scaled(values),
        sigma: scaled(sigma),
        sky_component: direct.map_or_else(Vec::new, |d| d.iter().map(|d| d.0 * k).collect()),
        reflected: direct.map_or_else(Vec::new, |d| {
            values.iter().zip(d).map(|(v, d)| (v - d.0) * k).collect()
        }),
        mean: figure(&figures.mean),
        min: figure(&figures.min),
    })
}

/// The scene map's summary: total and indirect illuminance over every triangle.
fn global(state: &RunState<'_>) -> GlobalSummary {
    let (t, g) = (&state.progress.tallies, &state.scene.geometry);
    let flux_lm = state.setup.total_flux_lm;
    let total = map_stats(t, MapKind::Total, g, flux_lm);
    let indirect = map_stats(t, MapKind::Indirect, g, flux_lm);
    GlobalSummary {
        triangles: g.triangle_count(),
        area_m2: g.total_area_m2(),
        mean_illuminance_lx: total.mean_lx,
        mean_sigma_lx: mean_illuminance_sigma_lx(t, g.total_area_m2(), flux_lm),
        sigma_lx: total.sigma_lx,
        rel_error: total.rel_error,
        indirect_mean_illuminance_lx: indirect.mean_lx,
        indirect_rel_error: indirect.rel_error,
    }
}

/// One entry per photometric file of the scene's luminaires, in order of first use.
fn luminaires(scene: &crate::scene::Scene) -> Vec<LuminaireSummary> {
    use base64::Engine;
    let mut out: Vec<LuminaireSummary> = Vec::new();
    for light in &scene.lights {
        let Some(p) = light.kind.photometry() else {
            continue;
        };
        if let Some(seen) = out.iter_mut().find(|s| s.file == p.file) {
            seen.count += 1;
            continue;
        }
        out.push(LuminaireSummary {
            file: p.file.clone(),
            count: 1,
            flux_lm: p.flux_lm(),
            light_output_ratio: p.light_output_ratio(),
            peak_cd: p.peak_cd(),
            symmetry: p.symmetry.describe().to_string(),
            opening: p.opening.describe(),
            polar_png_base64: crate::photometry::polar::polar_diagram_png(p)
                .map(|png| base64::engine::general_purpose::STANDARD.encode(png))
                .unwrap_or_default(),
            ugr_table_png_base64: ugr_table::table(p, 0.25, ugr_table::REFERENCE_FLUX_LM)
                .and_then(|t| ugr_table::plot_png(&t))
                .map(|png| base64::engine::general_purpose::STANDARD.encode(png))
                .unwrap_or_default(),
        });
    }
    out
}

/// The target's VOV: for a block (whose error is its worst cell's), the largest among
/// its cells that scored; for a whole receiver (whose error is the RMS over its cells),
/// the 90th percentile, so a few sparse cells at the receiver's edge do not mark the
/// mean error unreliable; for the scene map, the VOV of its mean.
fn target_vov(state: &RunState<'_>) -> f64 {
    let t = &state.progress.tallies;
    let receivers = &state.scene.receivers;
    let Some(r) = state.target.receiver() else {
        return mean_illuminance_vov(t);
    };
    let cells = t.receiver_cells(receivers, r);
    let mut vov: Vec<f64> = state
        .target
        .cells(receivers)
        .iter()
        .map(|&c| &cells[c])
        .filter(|c| c.hits > 0)
        .map(|c| cell_vov(c, t.counts()))
        .collect();
    if vov.is_empty() {
        return 1.0;
    }
    vov.sort_by(f64::total_cmp);
    let rank = match state.target {
        Target::Block { .. } => vov.len() - 1,
        _ => (vov.len() * 9 / 10).min(vov.len() - 1),
    };
    vov[rank]
}

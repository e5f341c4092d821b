//! A year of daylight in one run (docs/daylight.md, *Annual daylight*): daylight
//! coefficients from photons, then every hour's illuminance and the annual metrics
//! with their uncertainty.
//!
//! Each source (the ground, each Reinhart patch of the sky at 1 cd/m², each sun bin at
//! 1 lx normal) is traced by its own photons, seeded from (seed, source), as a run of
//! its own over the one ray caster: the receivers' cells get each source's coefficient
//! with its σ exactly as a run reports a cell, through portals, glazing and next events.
//! Sources share no photons, so their estimates are independent and
//! Var E(t) = Σₖ sₖ(t)² Var DCₖ holds exactly (rather than up to the small negative
//! covariance that photons drawn among sources at random would leave). Photons are
//! shared among sources in proportion to the light each brings over the year (every
//! source at least one chunk), in rounds that double the total until the stop rule holds.

pub mod metrics;
pub mod sky_matrix;

use crate::accel::RayCaster;
use crate::error::{Error, Result};
use crate::light::patches::PatchSky;
use crate::light::sun::Sun;
use crate::light::Light;
use crate::run::{run_from, Progress, RunOptions, Start};
use crate::scene::{Estimator, Scene, SceneLight};
use crate::stats::{cell_estimates, CellEstimate};
use crate::trace::CHUNK_PHOTONS;
use metrics::{AnnualFigures, Hourly};
use sky_matrix::SkyMatrix;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// What lights a daylight coefficient.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SourceKind {
    Ground,
    /// A sky patch (index into the sky matrix's patches).
    Patch(usize),
    /// A sun bin (index into [`SkyMatrix::suns`]).
    Sun(usize),
}

/// One source: its light and its share of the photons.
pub struct Source {
    pub kind: SourceKind,
    pub light: Arc<dyn Light>,
    /// Its part of the year's light through the scene's disk (Σ over hours of its weight
    /// times its flux at weight 1), as a fraction of all sources'.
    pub share: f64,
}

/// The sources of `matrix`, with the scene's portals.
pub fn sources(matrix: &SkyMatrix, portals: &[crate::light::distant::Portal]) -> Vec<Source> {
    let n = matrix.patches.len();
    let mut weight = vec![0.0; 1 + n + matrix.suns.len()];
    for h in &matrix.hours {
        weight[0] += h.ground_cdm2 * 2.0 * PI;
        for (k, &l) in h.patches.iter().enumerate() {
            weight[1 + k] += l as f64 * matrix.patches.patch(k).solid_angle_sr;
        }
        if let Some((b, e)) = h.sun {
            weight[1 + n + b] += e;
        }
    }
    let total: f64 = weight.iter().sum();
    let mut out = Vec::with_capacity(weight.len());
    out.push((
        SourceKind::Ground,
        Arc::new(PatchSky::ground(&matrix.patches, portals)) as Arc<dyn Light>,
    ));
    for k in 0..n {
        out.push((
            SourceKind::Patch(k),
            Arc::new(PatchSky::single(&matrix.patches, k, portals)),
        ));
    }
    for (b, &towards) in matrix.suns.iter().enumerate() {
        let sun = Sun {
            towards,
            direct_normal_lx: 1.0,
            ground_reflectance: 0.0,
            portals: portals.to_vec(),
        };
        out.push((SourceKind::Sun(b), Arc::new(sun)));
    }
    (out.into_iter().zip(weight))
        .map(|((kind, light), w)| Source {
            kind,
            light,
            share: if total > 0.0 { w / total } else { 0.0 },
        })
        .collect()
}

/// Points per side of a cell in the direct-light replicates of the sky's patches and
/// the ground (the suns keep the receivers' own, for ASE's direct sun): the direct
/// light was 0.24 % of the hourly variance on the bundled room with 4 × 4 (and 95 % of
/// the rays), so one point (2 × 2 where a light's edge crosses the cell) suffices.
const SKY_DIRECT_POINTS_PER_SIDE: u32 = 1;

/// Photons source `share` gets of `total`: its share, and at least one chunk.
pub fn source_photons(share: f64, total: u64) -> u64 {
    ((share * total as f64).ceil() as u64).max(CHUNK_PHOTONS)
}

/// Per source, per analysed receiver, per cell: the coefficient and its variance.
pub type Coefficients = Vec<Vec<Vec<CellEstimate>>>;

/// One round's state, for the progress line.
pub struct Round {
    pub index: u32,
    pub photons: u64,
    /// Rays of the photons, and of the receivers' sampled direct light.
    pub rays: u64,
    pub direct_rays: u64,
    pub elapsed_s: f64,
    pub figures: AnnualFigures,
    /// The sDA half-width the run stops at, if any.
    pub target: Option<f64>,
}

/// What an annual run hands to the outputs.
pub struct AnnualResult {
    pub matrix: SkyMatrix,
    pub sources: Vec<SourceKind>,
    pub coefficients: Coefficients,
    pub hourly: Vec<Hourly>,
    pub figures: AnnualFigures,
    /// Per analysed receiver: the sources none of whose photons reached it, whose
    /// coefficients are bounded ([`bound_unreached`]) rather than known.
    pub unreached_sources: Vec<Vec<usize>>,
    pub rounds: Vec<RoundLine>,
    pub photons: u64,
    pub rays: u64,
    pub direct_rays: u64,
    /// Seconds to read the weather and make the sky matrix, then to trace and evaluate.
    pub matrix_s: f64,
    pub elapsed_s: f64,
    pub stop_reason: &'static str,
}

/// A round as the summary lists it.
#[derive(Clone, Debug)]
pub struct RoundLine {
    pub photons: u64,
    pub elapsed_s: f64,
    /// The widest sDA interval's half-width over the analysed receivers.
    pub sda_halfwidth: f64,
}

/// Bytes an annual run keeps per source and cell, and per source and triangle (its
/// record for the next round and its coefficients).
const BYTES_PER_SOURCE_CELL: f64 = 200.0;
const BYTES_PER_SOURCE_TRIANGLE: f64 = 64.0;

/// Bytes per analysed cell and lit hour: the hourly illuminance, the sun's part and
/// their σ (f32 each).
const BYTES_PER_CELL_HOUR: f64 = 16.0;

/// Refuses a run whose coefficients and hourly illuminance would not fit in `free`
/// bytes, one line.
fn check_memory(
    scene: &Scene,
    matrix: &SkyMatrix,
    sources: usize,
    free: Option<f64>,
) -> Result<()> {
    let cells: usize = scene.receivers.iter().map(|r| r.cell_count() + 1).sum();
    let analysed: usize = (scene.annual.iter().flat_map(|a| &a.receivers))
        .map(|&r| scene.receivers[r].cell_count())
        .sum();
    let triangles = scene.geometry.triangle_count();
    let bytes = sources as f64
        * (cells as f64 * BYTES_PER_SOURCE_CELL + triangles as f64 * BYTES_PER_SOURCE_TRIANGLE)
        + (matrix.hours.len() * analysed) as f64 * BYTES_PER_CELL_HOUR;
    match free {
        Some(free) if bytes > 0.8 * free => Err(Error::input(
            format!("{}: annual", scene.path.display()),
            format!(
                "{sources} sources × {cells} cells and {triangles} triangles, and {} lit hours of \
                 {analysed} cells, need ≈ {:.0} MB of memory, {:.0} MB is available: use a \
                 coarser mf or sun_mf, or fewer receivers",
                matrix.hours.len(),
                bytes * 1e-6,
                free * 1e-6
            ),
        )),
        _ => Ok(()),
    }
}

/// Runs the year: rounds of photons over every source until every analysed receiver's
/// sDA interval is narrow enough, the photons run out or `interrupt` is set; `each` sees
/// every round; `storage` says where it saves its work (and whether it goes on from it).
pub fn run(
    scene: &Scene,
    options: &RunOptions,
    caster: &dyn RayCaster,
    storage: &Storage<'_>,
    interrupt: &AtomicBool,
    each: &mut dyn FnMut(&Round),
) -> Result<AnnualResult> {
    let annual = scene
        .annual
        .as_ref()
        .ok_or_else(|| Error::input(scene.path.display().to_string(), "has no [annual] table"))?;
    let matrix_clock = Instant::now();
    let weather = crate::weather::read_weather(&annual.weather)?;
    let matrix = SkyMatrix::new(&weather, annual)?;
    let matrix_s = matrix_clock.elapsed().as_secs_f64();
    let sources = sources(&matrix, &scene.portals);
    check_memory(scene, &matrix, sources.len(), storage.free_bytes)?;
    let mut base = scene.clone();
    base.requirements.clear();
    base.daylight_factor = None;
    let mut options = options.clone();
    options.estimator = Some(Estimator::NextEvent);
    let sphere = crate::trace::emit::bounding_sphere(&base);
    let fluxes: Vec<f64> = sources.iter().map(|s| s.light.flux_lm(&sphere)).collect();
    let suns: Vec<bool> = (sources.iter())
        .map(|s| matches!(s.kind, SourceKind::Sun(_)))
        .collect();
    let clock = Instant::now();
    let mut records: Vec<Option<Progress>> = (0..sources.len()).map(|_| None).collect();
    let mut coefficients: Coefficients = vec![Vec::new(); sources.len()];
    let mut floors = vec![0u64; sources.len()];
    let mut rounds = Vec::new();
    let mut total = annual.photons;
    for index in 0.. {
        let wants: Vec<u64> = (sources.iter().zip(&floors))
            .map(|(s, &floor)| source_photons(s.share, total).max(floor))
            .collect();
        trace_round(
            &mut base,
            &options,
            caster,
            &sources,
            &wants,
            &mut records,
            &mut coefficients,
            storage,
            interrupt,
        )?;
        let traced: Vec<u64> = (records.iter())
            .map(|p| p.as_ref().map_or(0, |p| p.tallies.photons))
            .collect();
        let unreached = bound_unreached(&mut coefficients, &fluxes, &traced, &suns);
        // An unreached source's bound shrinks only with its own photons: double them.
        for &k in unreached.iter().flatten() {
            floors[k] = floors[k].max(2 * traced[k]);
        }
        let hourly = metrics::hourly_all(&matrix, &sources, &coefficients, annual.receivers.len());
        let figures = AnnualFigures::new(&matrix, &hourly, scene, annual);
        let photons: u64 = records.iter().flatten().map(|p| p.tallies.photons).sum();
        let rays: u64 = records.iter().flatten().map(|p| p.tallies.rays).sum();
        let direct_rays: u64 = records
            .iter()
            .flatten()
            .map(|p| p.tallies.direct_rays)
            .sum();
        let elapsed_s = clock.elapsed().as_secs_f64();
        let round = Round {
            index,
            photons,
            rays,
            direct_rays,
            elapsed_s,
            figures,
            target: annual.sda_halfwidth,
        };
        each(&round);
        rounds.push(RoundLine {
            photons,
            elapsed_s,
            sda_halfwidth: round.figures.widest_sda_halfwidth(),
        });
        let reached = annual
            .sda_halfwidth
            .is_some_and(|h| round.figures.widest_sda_halfwidth() <= h);
        let stop_reason = if interrupt.load(Ordering::Relaxed) {
            Some("interrupted")
        } else if reached {
            Some("sda_halfwidth")
        } else if annual.sda_halfwidth.is_none() || total >= annual.max_photons {
            Some("photons")
        } else {
            None
        };
        if let Some(stop_reason) = stop_reason {
            return Ok(AnnualResult {
                matrix,
                sources: sources.iter().map(|s| s.kind).collect(),
                coefficients,
                hourly,
                figures: round.figures,
                unreached_sources: unreached,
                rounds,
                photons,
                rays,
                direct_rays,
                matrix_s,
                elapsed_s,
                stop_reason,
            });
        }
        total = total.saturating_mul(2).min(annual.max_photons);
    }
    unreachable!("the rounds end by returning")
}

/// Where an annual run keeps its work and how much memory it may take.
#[derive(Clone, Copy, Debug, Default)]
pub struct Storage<'a> {
    /// The memory it may take (None: no limit).
    pub free_bytes: Option<f64>,
    /// A folder for one checkpoint per source (`NNNNN/checkpoint.bin`), saved as soon
    /// as the source is traced in a round.
    pub checkpoints: Option<&'a std::path::Path>,
    /// Go on from the checkpoints found there.
    pub resume: bool,
}

/// Source `k`'s checkpoint folder.
fn source_dir(dir: &std::path::Path, k: usize) -> std::path::PathBuf {
    dir.join(format!("{k:05}"))
}

/// Traces every source up to its `wants` photons (going on from its record, or
/// from its checkpoint when resuming), saves its checkpoint and refreshes its
/// coefficients.
#[allow(clippy::too_many_arguments)]
fn trace_round(
    base: &mut Scene,
    options: &RunOptions,
    caster: &dyn RayCaster,
    sources: &[Source],
    wants: &[u64],
    records: &mut [Option<Progress>],
    coefficients: &mut Coefficients,
    storage: &Storage<'_>,
    interrupt: &AtomicBool,
) -> Result<()> {
    let annual = base.annual.clone().expect("checked by run");
    for (k, source) in sources.iter().enumerate() {
        if interrupt.load(Ordering::Relaxed) {
            break;
        }
        base.lights = vec![SceneLight {
            label: format!("annual source {k}"),
            kind: source.light.clone(),
        }];
        let mut opts = options.clone();
        opts.seed = crate::rng::sub_seed(options.seed, k as u64);
        if !matches!(source.kind, SourceKind::Sun(_)) {
            opts.direct_points_per_side = Some(SKY_DIRECT_POINTS_PER_SIDE);
        }
        let want = wants[k];
        opts.stop = crate::criteria::StopCriteria {
            photons: Some(want),
            ..Default::default()
        };
        if let (None, Some(dir), true) = (&records[k], storage.checkpoints, storage.resume) {
            records[k] = resumed(base, &opts, &source_dir(dir, k))?;
        }
        let done = records[k].as_ref().map_or(0, |p| p.tallies.photons);
        if done < want {
            let start = Start {
                resumed: records[k].take(),
                ..Start::default()
            };
            let result = run_from(
                base,
                &opts,
                caster,
                Instant::now(),
                interrupt,
                &mut (),
                start,
            )?;
            if let Some(dir) = storage.checkpoints {
                let dir = source_dir(dir, k);
                std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
                let fingerprint = crate::scene::fingerprint::run(base);
                crate::checkpoint::Checkpoint::of(&result.state(base, &opts), fingerprint)
                    .save(&dir)?;
            }
            records[k] = Some(result.progress);
        } else if !coefficients[k].is_empty() {
            continue;
        }
        let Some(progress) = &records[k] else {
            continue;
        };
        let counts = progress.tallies.counts();
        coefficients[k] = (annual.receivers.iter())
            .map(|&r| {
                let cells = progress.tallies.receiver_cells(&base.receivers, r);
                cell_estimates(cells, base.receivers[r].cells, counts)
            })
            .collect();
    }
    Ok(())
}

/// −ln(0.025): with no history scoring among N, the two-sided 95 % upper bound of the
/// chance that one does is this over N (the rule of three's two-sided form).
const NONE_SCORED_95: f64 = 3.689;

/// Gives the receivers that none of a source's photons reached a variance instead of 0:
/// their coefficient 0 is only known to be below the 95 % bound [`NONE_SCORED_95`]/N
/// times what a scoring history carries, taken per unit flux as the median over the
/// sources of its kind (`suns`: a sun bin, or not) that reached the receiver of their
/// mean, or of all kinds if none of its kind did (the variance is that bound over
/// 1.96, squared). The tests' fortnight checks it covers: the largest coefficient a
/// 32× run found behind such a bound was 0.18 of it.
/// Sources with no light in the scene keep 0 exactly. A receiver no source reached keeps
/// its zeros: it is dark. `fluxes`, `photons` and `suns` are per source; returns per
/// receiver the sources so bounded.
pub fn bound_unreached(
    coefficients: &mut Coefficients,
    fluxes: &[f64],
    photons: &[u64],
    suns: &[bool],
) -> Vec<Vec<usize>> {
    let receivers = coefficients.iter().map(Vec::len).max().unwrap_or(0);
    let mut unreached = vec![Vec::new(); receivers];
    for (r, unreached) in unreached.iter_mut().enumerate() {
        let per_flux = |k: usize, cells: &[CellEstimate]| {
            let scored: u64 = cells.iter().map(|c| c.scoring_histories).sum();
            let value: f64 = cells.iter().map(|c| c.value - c.direct).sum();
            (scored > 0 && fluxes[k] > 0.0)
                .then(|| value.max(0.0) * photons[k] as f64 / (scored as f64 * fluxes[k]))
        };
        let typical = |sun: Option<bool>| {
            let mut scores: Vec<f64> = (coefficients.iter().enumerate())
                .filter(|&(k, _)| sun.is_none_or(|sun| suns[k] == sun))
                .filter_map(|(k, c)| c.get(r).and_then(|cells| per_flux(k, cells)))
                .collect();
            scores.sort_by(f64::total_cmp);
            scores.get(scores.len() / 2).copied().unwrap_or(0.0)
        };
        let by_kind = [typical(Some(false)), typical(Some(true))];
        let any = typical(None);
        for (k, per_receiver) in coefficients.iter_mut().enumerate() {
            let Some(cells) = per_receiver.get_mut(r) else {
                continue;
            };
            let reached = cells.iter().any(|c| c.scoring_histories > 0);
            if fluxes[k] <= 0.0 || photons[k] == 0 || reached {
                continue;
            }
            unreached.push(k);
            let per_flux = match by_kind[suns[k] as usize] {
                x if x > 0.0 => x,
                _ => any,
            };
            let bound = NONE_SCORED_95 / photons[k] as f64 * per_flux * fluxes[k];
            for c in cells {
                c.var = c.direct_var + (bound / 1.96) * (bound / 1.96);
            }
        }
    }
    unreached
}

/// Source's record from its checkpoint in `dir`, if there is one, checked against the
/// source's scene and options.
fn resumed(scene: &Scene, options: &RunOptions, dir: &std::path::Path) -> Result<Option<Progress>> {
    if !dir.join(crate::checkpoint::FILE).exists()
        && !dir.join(crate::checkpoint::PREVIOUS_FILE).exists()
    {
        return Ok(None);
    }
    let (checkpoint, path) = crate::checkpoint::Checkpoint::load(dir)?;
    checkpoint.check(&path, scene, options)?;
    checkpoint
        .into_progress(path.display().to_string())
        .map(Some)
}

/// The photons a target half-width `target` needs from a round at `photons` whose
/// widest half-width is `now`: intervals narrow as 1/√N.
pub fn forecast_photons(photons: u64, now: f64, target: f64) -> f64 {
    photons as f64 * (now / target) * (now / target)
}

/// One progress line per round.
pub fn round_line(round: &Round) -> String {
    let widest = round.figures.widest_sda_halfwidth();
    let mut line = format!(
        "round {}: {} photons, {:.1} + {:.1} Mrays (photons + direct light) in {:.1} s; widest \
         sDA interval ±{:.2} % of the area",
        round.index,
        round.photons,
        round.rays as f64 * 1e-6,
        round.direct_rays as f64 * 1e-6,
        round.elapsed_s,
        100.0 * widest
    );
    if let Some(target) = round.target.filter(|&t| widest > t) {
        let photons = forecast_photons(round.photons, widest, target);
        let seconds = round.elapsed_s / round.photons as f64 * photons;
        line += &format!(
            " (target ±{:.2} %: ≈ {photons:.3e} photons, ≈ {seconds:.0} s in all)",
            100.0 * target
        );
    }
    for r in &round.figures.receivers {
        line += &format!(
            "; {} sDA {:.1} % ({:.1}–{:.1} %)",
            r.name,
            100.0 * r.sda.value,
            100.0 * r.sda.low,
            100.0 * r.sda.high
        );
    }
    line
}

/// What `luxtally annual` prints at the end.
pub fn result_text(scene: &Scene, result: &AnnualResult, out: &std::path::Path) -> String {
    let m = &result.matrix;
    let mut text = format!(
        "{}: {} records ({} lit, {} occupied), {} sky patches + ground, {} sun bins; {} photons, {:.1} Mrays in {:.1} s (the sky matrix {:.1} s before), stopped on {}; results in {}\n",
        scene.name,
        m.records,
        m.hours.len(),
        m.occupied_records,
        m.patches.len(),
        m.suns.len(),
        result.photons,
        result.rays as f64 * 1e-6,
        result.elapsed_s,
        result.matrix_s,
        result.stop_reason,
        out.display()
    );
    for w in &m.warnings {
        text += &format!("  warning: {w}\n");
    }
    let untraced = result.coefficients.iter().filter(|c| c.is_empty()).count();
    if untraced > 0 {
        text += &format!("  incomplete: {untraced} sources were not traced (interrupted): the figures miss their light\n");
    }
    for (r, unreached) in result
        .figures
        .receivers
        .iter()
        .zip(&result.unreached_sources)
    {
        let pct = |i: &metrics::Interval| {
            format!(
                "{:.1} % (95 % {:.1}–{:.1} %)",
                100.0 * i.value,
                100.0 * i.low,
                100.0 * i.high
            )
        };
        text += &format!(
            "  receiver {}: sDA300/50 % {}, LEED v4.1 points {}–{}; ASE1000,250 {}; blinds closed {} of occupied hours\n",
            r.name,
            pct(&r.sda),
            r.leed_points[0],
            r.leed_points[1],
            pct(&r.ase),
            pct(&r.blinds_hours)
        );
        for (name, fraction, verdict) in &r.en17037 {
            text += &format!(
                "    EN 17037 {name} level: {verdict} ({} of daylight hours)\n",
                pct(fraction)
            );
        }
        if !unreached.is_empty() {
            text += &format!(
                "    {} sources reached none of its cells: their light there is bounded, not known\n",
                unreached.len()
            );
        }
    }
    text
}

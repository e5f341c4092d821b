//! Related receivers (`exclude`): a task area's immediate surrounding as a receiver
//! whose mean and figures leave out the cells inside the task area. Its Ē, by track
//! (per-history totals over the counted cells) and by next event (sampled direct
//! light), is calibrated against the exact mean over the band; bad input is refused.

use crate::common;

use common::*;
use luxtally::accel::Backend;
use luxtally::run::RunOptions;
use luxtally::scene::{load_str, Estimator};
use std::path::Path;

/// A 1000 cd point source 2 m over a black floor; the task area [−0.5, 0.5]², its
/// surrounding [−1, 1]² (8 × 8 cells of 0.25 m) with the task left out.
fn scene_text(estimator: &str) -> String {
    format!(
        r#"{BLACK_FLOOR}
        [[lights]]
        type = "point"
        position = [0, 0, 2]
        intensity_cd = 1000
        [[receivers]]
        name = "task"
        corner = [-0.5, -0.5, 0.0001]
        u = [1, 0, 0]
        v = [0, 1, 0]
        cells = [4, 4]
        estimator = "{estimator}"
        [[receivers]]
        name = "surrounding"
        corner = [-1, -1, 0.0001]
        u = [2, 0, 0]
        v = [0, 2, 0]
        cells = [8, 8]
        exclude = ["task"]
        estimator = "{estimator}"
        "#
    )
}

/// The exact cell averages of the surrounding and which cells count (the band).
fn exact_band() -> (Vec<f64>, Vec<bool>) {
    let w = 0.25;
    let (mut cells, mut band) = (Vec::new(), Vec::new());
    for k in 0..64 {
        let (i, j) = (k % 8, k / 8);
        let (x0, y0) = (-1.0 + i as f64 * w, -1.0 + j as f64 * w);
        cells.push(point_source_cell_lx(
            1000.0,
            2.0 - 0.0001,
            x0,
            x0 + w,
            y0,
            y0 + w,
        ));
        band.push(!(2..6).contains(&i) || !(2..6).contains(&j));
    }
    (cells, band)
}

fn band_mean_z_rms(estimator: Estimator, photons: u64, seeds: u64) -> f64 {
    let name = if estimator == Estimator::Track {
        "track"
    } else {
        "next_event"
    };
    let scene = scene(&scene_text(name));
    let (cells, band) = exact_band();
    let counted: Vec<f64> = (0..64).filter(|&k| band[k]).map(|k| cells[k]).collect();
    let exact = counted.iter().sum::<f64>() / counted.len() as f64;
    let mut z2 = 0.0;
    for seed in 1..=seeds {
        let o = RunOptions {
            seed,
            ..options(&scene, photons, 2, Backend::Embree)
        };
        let s = run_options(&scene, &o);
        let r = &s.receivers["surrounding"];
        let excluded: Vec<usize> = (0..64).filter(|&k| !band[k]).collect();
        assert_eq!(r.excluded_cells, excluded);
        assert!(s.receivers["task"].excluded_cells.is_empty());
        let f = &r.figures;
        let z = (f.mean.value - exact) / f.mean_sigma;
        z2 += z * z;
        // The band's least cells are its corners, not the task's.
        assert!(band[f.min_cell] && band[f.max_cell], "{f:?}");
    }
    let rms = libm::sqrt(z2 / seeds as f64);
    eprintln!("{name}: the band's Ē z RMS {rms:.3} over {seeds} seeds");
    rms
}

/// The RMS of 100 unit normals is 1 ± 0.07: within [0.8, 1.2].
#[test]
fn the_band_s_mean_leaves_the_task_out_and_is_calibrated_by_track() {
    let rms = band_mean_z_rms(Estimator::Track, 20_000, 100);
    assert!((0.8..=1.2).contains(&rms), "z RMS {rms}");
}

#[test]
fn the_band_s_mean_leaves_the_task_out_and_is_calibrated_by_next_event() {
    let rms = band_mean_z_rms(Estimator::NextEvent, 4096, 100);
    assert!((0.8..=1.2).contains(&rms), "z RMS {rms}");
}

#[test]
fn bad_exclusions_are_refused_in_one_line() {
    let error = |toml: &str| match load_str(toml, Path::new("."), "x.toml") {
        Ok(_) => panic!("loads: {toml}"),
        Err(e) => e.to_string(),
    };
    let text = scene_text("auto");
    let m = error(&text.replace("exclude = [\"task\"]", "exclude = [\"desk\"]"));
    assert!(
        m.contains("receivers[1].exclude") && m.contains("no receiver named `desk`"),
        "{m}"
    );
    let m = error(&text.replace("exclude = [\"task\"]", "exclude = [\"surrounding\"]"));
    assert!(m.contains("cannot exclude itself"), "{m}");
    // The task inside the surrounding leaves it no cell.
    let m = error(&format!(
        "{text}\n[[receivers]]\nname = \"inner\"\ncorner = [-0.4, -0.4, 0.5]\nu = [0.8, 0, 0]\nv = [0, 0.8, 0]\ncells = [1, 1]\nexclude = [\"surrounding\"]\n"
    ));
    assert!(
        m.contains("receivers[2].exclude") && m.contains("leaves no cell"),
        "{m}"
    );
}

/// By track every score is a photon's: the per-history total of the surrounding (its
/// mean over the counted cells, history by history) averages to exactly the figures'
/// Ē over the band, not to the mean over all 64 cells.
#[test]
fn the_per_history_total_counts_only_the_band() {
    let scene = scene(&scene_text("track"));
    let o = options(&scene, 20_000, 2, Backend::Embree);
    let result = luxtally::run::run(
        &scene,
        &o,
        &std::sync::atomic::AtomicBool::new(false),
        &mut (),
    )
    .expect("runs");
    let tallies = &result.progress.tallies;
    let counts = tallies.counts();
    let total = tallies.receiver_total(&scene.receivers, 1);
    let (mean, _) = total.photon_moments(counts).mean_and_variance();
    let s = luxtally::output::summary::build(&result.state(&scene, &o));
    let r = &s.receivers["surrounding"];
    let band = r.figures.mean.value;
    assert!(
        (mean * counts.unit - band).abs() <= 1e-9 * band,
        "{} against {band}",
        mean * counts.unit
    );
    let all = r.values.iter().sum::<f64>() / 64.0;
    assert!(
        (all - band).abs() > 0.05 * band,
        "the task's cells differ: {all} {band}"
    );
}

//! Coverage of the designer's figures' intervals (Ē, Emin, Emax, U0, g2) over 200
//! seeds on analytic scenes: each interval must cover the exact figure at least at its
//! nominal rate within binomial error (3σ), and Ē's, which is exact rather than a
//! bound, not much more often. Cases: a point source over a black floor scored by track
//! and by next event, and a spot whose ramp crosses the receiver (steep cells at the cone
//! edge hold the minimum).

use crate::common;

use common::*;
use luxtally::accel::Backend;
use luxtally::run::RunOptions;
use luxtally::scene::Estimator;
use luxtally::stats::figures::Figure;

const SEEDS: u64 = 200;

/// The exact figures of a receiver from its exact cells.
struct Exact {
    mean: f64,
    min: f64,
    max: f64,
}

impl Exact {
    fn of(cells: &[f64]) -> Exact {
        Exact {
            mean: cells.iter().sum::<f64>() / cells.len() as f64,
            min: cells.iter().copied().fold(f64::INFINITY, f64::min),
            max: cells.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// Covered counts of Ē, Emin, Emax, U0, g2 over the seeds, and the plug-in minimum's
/// mean bias (relative to the exact minimum).
struct Coverage {
    covered: [u64; 5],
    /// Runs whose figures say they are unreliable (some cell's σ widened).
    unreliable: u64,
    plug_in_bias: f64,
}

fn coverage(toml: &str, photons: u64, estimator: Estimator, exact_cells: &[f64]) -> Coverage {
    let scene = scene(toml);
    let exact = Exact::of(exact_cells);
    let truth = [
        exact.mean,
        exact.min,
        exact.max,
        exact.min / exact.mean,
        exact.min / exact.max,
    ];
    let mut c = Coverage {
        covered: [0; 5],
        unreliable: 0,
        plug_in_bias: 0.0,
    };
    for seed in 1..=SEEDS {
        let opts = RunOptions {
            estimator: Some(estimator),
            seed,
            ..options(&scene, photons, 2, Backend::Embree)
        };
        let summary = run_options(&scene, &opts);
        let f = &summary.receivers["r"].figures;
        c.unreliable += !f.reliable as u64;
        let figures: [&Figure; 5] = [&f.mean, &f.min, &f.max, &f.u0, &f.g2];
        for (k, (figure, &x)) in figures.iter().zip(&truth).enumerate() {
            c.covered[k] += figure.covers(x) as u64;
        }
        c.plug_in_bias += (f.min.value - exact.min) / exact.min / SEEDS as f64;
    }
    c
}

/// Every interval covers at ≥ 95 % within 3 binomial σ; Ē's (not a bound) at most 3σ
/// above 95 % too.
fn assert_covers(c: &Coverage, what: &str) {
    let n = SEEDS as f64;
    let slack = 3.0 * (0.95 * 0.05 / n).sqrt();
    let names = ["mean", "min", "max", "u0", "g2"];
    let rates: Vec<f64> = c.covered.iter().map(|&k| k as f64 / n).collect();
    eprintln!(
        "{what}: coverage {:?}, {} runs unreliable, plug-in Emin's mean bias {:+.4}",
        names.iter().zip(&rates).collect::<Vec<_>>(),
        c.unreliable,
        c.plug_in_bias,
    );
    for (name, rate) in names.iter().zip(&rates) {
        assert!(
            rate >= &(0.95 - slack),
            "{what}: {name} covered {rate} < 95 %"
        );
    }
    assert!(
        rates[0] <= 0.95 + slack,
        "{what}: mean covered {} (σ too wide)",
        rates[0]
    );
}

#[test]
fn figures_of_a_point_source_cover_by_track() {
    let (toml, exact) = point_over_small_receiver("");
    let c = coverage(&toml, 20_000, Estimator::Track, &exact);
    assert_covers(&c, "point, track");
    assert!(
        c.plug_in_bias < 0.0,
        "the plug-in minimum reads low on average"
    );
}

#[test]
fn figures_of_a_point_source_cover_by_next_event() {
    let (toml, exact) = point_over_small_receiver("");
    let c = coverage(&toml, 20_000, Estimator::NextEvent, &exact);
    assert_covers(&c, "point, next event");
}

#[test]
fn figures_cover_where_a_spot_s_cone_edge_crosses_the_receiver() {
    // The spot of `spot_over_black_floor` (falloff 15° to cone 30° at 2 m: the ramp from
    // r = 0.54 to 1.15 m) over a 6 × 6 receiver of [−0.75, 0.75]²: corner cells sit on the
    // ramp, where the minimum is.
    let toml = spot_over_black_floor()
        .replace(
            "corner = [-1.5, -1.5, 0.0001]",
            "corner = [-0.75, -0.75, 0.0001]",
        )
        .replace("u = [3, 0, 0]", "u = [1.5, 0, 0]")
        .replace("v = [0, 3, 0]", "v = [0, 1.5, 0]")
        .replace("cells = [16, 16]", "cells = [6, 6]");
    let (i0, h, cc, cf) = (
        2000.0,
        2.0 - 0.0001,
        libm::cos(30f64.to_radians()),
        libm::cos(15f64.to_radians()),
    );
    let e = |x: f64, y: f64| {
        let d2 = h * h + x * x + y * y;
        let s = ((h / d2.sqrt() - cc) / (cf - cc)).clamp(0.0, 1.0);
        i0 * s * s * (3.0 - 2.0 * s) * h / libm::pow(d2, 1.5)
    };
    let exact: Vec<f64> = (0..36)
        .map(|k| {
            subcell_average(
                e,
                -0.75 + (k % 6) as f64 * 0.25,
                -0.75 + (k / 6) as f64 * 0.25,
                0.25,
            )
        })
        .collect();
    let c = coverage(&toml, 20_000, Estimator::Track, &exact);
    assert_covers(&c, "spot ramp, track");
}

/// In a white room scored by next event, every diffuse vertex connects to several cells
/// at once (4 strata of a 1024-cell receiver) with one weight, so the cells err
/// together: the mean's σ must come from the histories' totals. Over 100 seeds Ē's
/// z-scores against a run of 100 times the photons must be calibrated, while the σ that
/// ignores the covariance, √Σσᵢ²/N, reads too small.
#[test]
fn the_mean_s_sigma_carries_the_covariance_of_the_cells() {
    let toml = r#"
        [materials.white]
        reflectance = 0.8
        [[objects]]
        shape = "box"
        min = [-1, -1, 0]
        max = [1, 1, 2]
        material = "white"
        [[lights]]
        type = "point"
        position = [0.2, 0.1, 1.5]
        intensity_cd = 100
        [[receivers]]
        name = "r"
        corner = [-0.8, -0.8, 0.0001]
        u = [1.6, 0, 0]
        v = [0, 1.6, 0]
        cells = [32, 32]
    "#;
    let scene = scene(toml);
    let run = |photons: u64, seed: u64| {
        let opts = RunOptions {
            estimator: Some(Estimator::NextEvent),
            seed,
            ..options(&scene, photons, 2, Backend::Embree)
        };
        let summary = run_options(&scene, &opts);
        let r = &summary.receivers["r"];
        let naive = r.sigma.iter().map(|s| s * s).sum::<f64>().sqrt() / r.sigma.len() as f64;
        (r.figures.mean.value, r.figures.mean_sigma, naive)
    };
    let (reference, reference_sigma, _) = run(2_000_000, 1000);
    let (mut z, mut z_naive) = (Vec::new(), Vec::new());
    for seed in 1..=100 {
        let (mean, sigma, naive) = run(20_000, seed);
        z.push((mean - reference) / (sigma * sigma + reference_sigma * reference_sigma).sqrt());
        z_naive
            .push((mean - reference) / (naive * naive + reference_sigma * reference_sigma).sqrt());
    }
    let (rms, rms_naive) = (common::rms(&z), common::rms(&z_naive));
    eprintln!("Ē z-RMS {rms:.3}; with √Σσᵢ²/N {rms_naive:.3}");
    assert!((0.8..=1.25).contains(&rms), "Ē's z-RMS {rms}");
    assert!(
        rms_naive > 1.5,
        "the covariance should matter here: naive z-RMS {rms_naive}"
    );
}

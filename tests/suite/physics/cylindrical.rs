//! Cylindrical and semi-cylindrical receivers against exact cell averages: one isotropic
//! point source above a black floor, a horizontal grid of cells beside it at 1.2 m.
//! A point at horizontal distance r, height h below the source, d² = r² + h²:
//! Ez = I·sin γ/(π d²) = I·r/(π d³), and a semi-cylinder facing f gets
//! I·sin γ·(1 + cos α)/(π d²) = I·(r + f·(−x, −y))/(π d³), (−x, −y) the horizontal way
//! to the source. The cells' exact values are the means of those over each cell (8 × 8
//! Gauss–Legendre), scored by crossing (`track`) and by sampled direct light
//! (`next_event`), and their σ checked over 50 seeds. Over a grey floor the light it
//! reflects reaches the cylinders from below: crossings and next-event connections
//! must agree.

use crate::common;

use common::*;
use glam::DVec3;
use luxtally::accel::Backend;
use luxtally::output::summary::ReceiverSummary;
use luxtally::run::RunOptions;
use luxtally::scene::{Estimator, Quantity};
use std::f64::consts::PI;

const INTENSITY_CD: f64 = 1000.0;
/// The source at (0, 0, 3), the receiver at z = 1.2.
const DROP_M: f64 = 1.8;
/// The receiver: [0.5, 2.5] × [−1, 1], 8 × 8 cells of 0.25 m.
const X0: f64 = 0.5;
const Y0: f64 = -1.0;
const SIDE_M: f64 = 2.0;
const CELLS: usize = 8;

/// The scene: `quantity` (with its keys) and the receiver's `estimator`.
fn scene_toml(quantity: &str, estimator: &str) -> String {
    format!(
        r#"{BLACK_FLOOR}
        [[lights]]
        type = "point"
        position = [0, 0, 3]
        intensity_cd = {INTENSITY_CD}
        [[receivers]]
        name = "r"
        corner = [{X0}, {Y0}, 1.2]
        u = [{SIDE_M}, 0, 0]
        v = [0, {SIDE_M}, 0]
        cells = [{CELLS}, {CELLS}]
        estimator = "{estimator}"
        {quantity}
        "#
    )
}

/// The exact value at (x, y) for a semi-cylinder facing `facing` (horizontal unit
/// vector), or the cylinder when `facing` is `None`.
fn exact_at(x: f64, y: f64, facing: Option<[f64; 2]>) -> f64 {
    let r = libm::hypot(x, y);
    let d = libm::hypot(r, DROP_M);
    let towards = facing.map_or(0.0, |f| -(f[0] * x + f[1] * y));
    INTENSITY_CD * (r + towards) / (PI * d * d * d)
}

/// The exact mean of cell (i, j).
fn exact_cell(i: usize, j: usize, facing: Option<[f64; 2]>) -> f64 {
    let w = SIDE_M / CELLS as f64;
    let (x0, y0) = (X0 + i as f64 * w, Y0 + j as f64 * w);
    cell_average(|x, y| exact_at(x, y, facing), x0, x0 + w, y0, y0 + w)
}

/// The quantity's keys in the scene file.
fn quantity_keys(facing: Option<[f64; 2]>) -> String {
    match facing {
        None => "quantity = \"cylindrical\"".into(),
        Some([x, y]) => format!("quantity = \"semi_cylindrical\"\nfacing = [{x}, {y}, 0]"),
    }
}

/// Every cell within 4σ of its exact value, the z-scores' RMS in [0.8, 1.25].
fn check(r: &ReceiverSummary, facing: Option<[f64; 2]>, what: &str) {
    assert_eq!(r.unit, "lx", "{what}");
    let z = z_scores(r, |i, j| exact_cell(i, j, facing));
    let worst = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let rel: f64 = r
        .values
        .iter()
        .zip(&r.sigma)
        .map(|(v, s)| s / v)
        .fold(0.0, f64::max);
    eprintln!(
        "{what}: z RMS {:.3}, worst {worst:.2}, largest relative σ {:.2} %",
        rms(&z),
        100.0 * rel
    );
    assert!(worst <= 4.0, "{what}: a cell is {worst:.2}σ off");
    assert!(
        (0.8..=1.25).contains(&rms(&z)),
        "{what}: z RMS {:.3}",
        rms(&z)
    );
}

/// The cylinder and the two semi-cylinders (facing the source, facing away).
const FACINGS: [Option<[f64; 2]>; 3] = [None, Some([-1.0, 0.0]), Some([1.0, 0.0])];

fn name(facing: Option<[f64; 2]>) -> String {
    match facing {
        None => "cylindrical".into(),
        Some([-1.0, 0.0]) => "semi-cylindrical facing the source".into(),
        Some([1.0, 0.0]) => "semi-cylindrical facing away".into(),
        Some([x, y]) => format!("semi-cylindrical facing [{x}, {y}, 0]"),
    }
}

#[test]
fn cylindrical_receivers_match_the_exact_cell_averages_by_crossing() {
    for facing in FACINGS {
        let s = run_scene(&scene_toml(&quantity_keys(facing), "track"), 1_000_000);
        let r = &s.receivers["r"];
        assert_eq!(r.estimator, "track");
        assert_eq!(
            r.quantity,
            if facing.is_some() {
                "semi_cylindrical"
            } else {
                "cylindrical"
            }
        );
        check(r, facing, &format!("{}, track", name(facing)));
    }
}

#[test]
fn cylindrical_receivers_match_the_exact_cell_averages_by_sampled_direct_light() {
    for facing in FACINGS {
        let s = run_scene(&scene_toml(&quantity_keys(facing), "next_event"), 100_000);
        let r = &s.receivers["r"];
        assert_eq!(r.direct_estimator, "sampled");
        check(r, facing, &format!("{}, next_event", name(facing)));
    }
}

/// The mean z² over 50 seeds: pooled over all cells, and per cell for four cells (the
/// nearest to the source, the farthest, and two between).
fn mean_z_squared_over_seeds(facing: Option<[f64; 2]>, estimator: Estimator, photons: u64) {
    let s = scene(&scene_toml(&quantity_keys(facing), estimator.name()));
    let seeds = 50;
    let mut sum = vec![0.0; CELLS * CELLS];
    for seed in 1..=seeds {
        let opts = RunOptions {
            seed,
            ..options(&s, photons, 2, Backend::Embree)
        };
        let summary = run_options(&s, &opts);
        let z = z_scores(&summary.receivers["r"], |i, j| exact_cell(i, j, facing));
        for (acc, z) in sum.iter_mut().zip(z) {
            *acc += z * z;
        }
    }
    let per_cell: Vec<f64> = sum.iter().map(|s| s / seeds as f64).collect();
    let pooled = per_cell.iter().sum::<f64>() / per_cell.len() as f64;
    let what = format!("{}, {}", name(facing), estimator.name());
    let picked = [
        CELLS * (CELLS / 2),
        CELLS * CELLS - 1,
        3 * CELLS + 4,
        6 * CELLS + 1,
    ];
    eprintln!(
        "{what}: mean z² over {seeds} seeds {pooled:.3} (all cells), {:.3?} (cells {picked:?})",
        picked.map(|k| per_cell[k])
    );
    // 3200 z² (correlated within a run): the mean of calibrated ones is 1 ± ~0.03.
    assert!(
        (0.85..=1.2).contains(&pooled),
        "{what}: mean z² {pooled:.3}"
    );
    // 50 each: 1 ± 0.2.
    for k in picked {
        assert!(
            (0.4..=1.8).contains(&per_cell[k]),
            "{what}: cell {k}: mean z² {:.3}",
            per_cell[k]
        );
    }
}

#[test]
fn cylindrical_errors_are_calibrated_over_seeds() {
    mean_z_squared_over_seeds(None, Estimator::Track, 200_000);
    mean_z_squared_over_seeds(None, Estimator::NextEvent, 20_000);
}

#[test]
fn semi_cylindrical_errors_are_calibrated_over_seeds() {
    mean_z_squared_over_seeds(Some([-1.0, 0.0]), Estimator::Track, 200_000);
    mean_z_squared_over_seeds(Some([0.6, -0.8]), Estimator::NextEvent, 20_000);
}

/// A grey floor (ρ = 0.5) reflects light that reaches the cylinders from below, through
/// the receiver's other face: scored by crossing (`track`) and by connections from the
/// floor's vertices (`next_event`), the two must agree cell by cell within their σ.
#[test]
fn light_from_below_is_scored_alike_by_crossings_and_connections() {
    for facing in [None, Some([0.0, 1.0])] {
        let toml = |estimator: &str| {
            format!(
                r#"
                [materials.grey]
                reflectance = 0.5
                [[objects]]
                shape = "rect"
                corner = [-10, -10, 0]
                u = [20, 0, 0]
                v = [0, 20, 0]
                material = "grey"
                [[lights]]
                type = "point"
                position = [0, 0, 3]
                intensity_cd = {INTENSITY_CD}
                [[receivers]]
                name = "r"
                corner = [{X0}, {Y0}, 1.2]
                u = [{SIDE_M}, 0, 0]
                v = [0, {SIDE_M}, 0]
                cells = [4, 4]
                estimator = "{estimator}"
                {}
                "#,
                quantity_keys(facing)
            )
        };
        let track = run_scene(&toml("track"), 2_000_000);
        let nee = run_scene(&toml("next_event"), 200_000);
        let (t, n) = (&track.receivers["r"], &nee.receivers["r"]);
        let what = name(facing);
        let mut z = Vec::new();
        for k in 0..t.values.len() {
            let (i, j) = (k % 4, k / 4);
            let w = SIDE_M / 4.0;
            let (x0, y0) = (X0 + i as f64 * w, Y0 + j as f64 * w);
            let direct = cell_average(|x, y| exact_at(x, y, facing), x0, x0 + w, y0, y0 + w);
            // The floor's light is a good part of every cell's.
            assert!(
                n.values[k] > 1.1 * direct,
                "{what}: cell {k}: {} with {direct} direct",
                n.values[k]
            );
            z.push((t.values[k] - n.values[k]) / libm::hypot(t.sigma[k], n.sigma[k]));
        }
        let worst = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        eprintln!(
            "{what}: track − next_event over 16 cells: z RMS {:.3}, worst {worst:.2}; cell 0: {:.3} ± {:.3} vs {:.3} ± {:.3} lx",
            rms(&z),
            t.values[0],
            t.sigma[0],
            n.values[0],
            n.sigma[0]
        );
        assert!(worst <= 4.0, "{what}: a cell differs by {worst:.2}σ");
        assert!(
            (0.5..=1.5).contains(&rms(&z)),
            "{what}: z RMS {:.3}",
            rms(&z)
        );
    }
}

#[test]
fn a_nearly_horizontal_facing_is_made_horizontal() {
    let s = scene(&scene_toml(
        "quantity = \"semi_cylindrical\"\nfacing = [2, 0, 1e-7]",
        "auto",
    ));
    assert_eq!(
        s.receivers[0].quantity,
        Quantity::SemiCylindrical { facing: DVec3::X }
    );
}

/// The modelling ratio Ēz/Ēh of the cylinder over a horizontal receiver on the same
/// cells (`modelling_with`): its interval at 95 % covers the exact ratio of the exact
/// means in at least 95 % of 200 seeds within binomial error (a union bound of the two
/// means' intervals: conservative), and `modelling = [least, most]` checks decide it.
#[test]
fn the_modelling_ratio_covers_and_its_checks_decide() {
    let horizontal = format!(
        r#"
        modelling_with = "h"
        [[receivers]]
        name = "h"
        corner = [{X0}, {Y0}, 1.2]
        u = [{SIDE_M}, 0, 0]
        v = [0, {SIDE_M}, 0]
        cells = [{CELLS}, {CELLS}]
        "#
    );
    let w = SIDE_M / CELLS as f64;
    let cells = (0..CELLS * CELLS).map(|k| (k % CELLS, k / CELLS));
    let (mut ez, mut eh) = (0.0, 0.0);
    for (i, j) in cells {
        let (x0, y0) = (X0 + i as f64 * w, Y0 + j as f64 * w);
        ez += exact_cell(i, j, None);
        eh += point_source_cell_lx(INTENSITY_CD, DROP_M, x0, x0 + w, y0, y0 + w);
    }
    let exact = ez / eh;
    let toml = scene_toml(
        &format!("quantity = \"cylindrical\"\n{horizontal}"),
        "next_event",
    );
    let scene = scene(&toml);
    let seeds = 200;
    let mut covered = 0;
    for seed in 1..=seeds {
        let o = RunOptions {
            seed,
            ..options(&scene, 4096, 2, Backend::Embree)
        };
        let s = run_options(&scene, &o);
        let f = &s.receivers["r"].figures;
        assert_eq!(f.modelling_with.as_deref(), Some("h"));
        let m = f.modelling.expect("a modelling ratio");
        assert!(m.low < m.value && m.value < m.high, "{m:?}");
        covered += m.covers(exact) as u32;
    }
    let rate = covered as f64 / seeds as f64;
    let sd = libm::sqrt(0.95 * 0.05 / seeds as f64);
    eprintln!("modelling {exact:.4}: covered in {covered} of {seeds} seeds");
    assert!(rate >= 0.95 - 3.0 * sd, "coverage {rate}");

    let checks = |lo: f64, hi: f64| {
        let toml =
            format!("{toml}\n[[requirements]]\nreceiver = \"r\"\nmodelling = [{lo}, {hi}]\n");
        let scene = crate::common::scene(&toml);
        let v = run_options(&scene, &options(&scene, 100_000, 2, Backend::Embree)).verdicts;
        let v = v.expect("verdicts");
        assert_eq!(v.checks.len(), 2);
        assert_eq!(v.checks[0].at_least, Some(lo));
        assert_eq!(v.checks[1].at_most, Some(hi));
        (v.checks[0].outcome, v.checks[1].outcome)
    };
    use luxtally::stats::verdict::Outcome::{Fail, Pass};
    assert_eq!(checks(0.5 * exact, 2.0 * exact), (Pass, Pass));
    assert_eq!(checks(1.5 * exact, 3.0 * exact), (Fail, Pass));
    assert_eq!(checks(0.2 * exact, 0.7 * exact), (Pass, Fail));
}

//! Point receivers (`values = "point"`): each cell scores the value at its centre by
//! next-event estimation — exactly for a point source's direct light, with calibrated σ
//! for an area source and for the indirect light — and the figures say so.

use crate::common;

use common::*;
use luxtally::accel::Backend;
use luxtally::run::{run, RunOptions};
use luxtally::scene::{load_str, Estimator};
use std::f64::consts::PI;
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// A 1000 cd point source 2 m above a black floor; a receiver of `cells` 0.1 mm above
/// it over [−1.5, 2.5] × [−1, 2] (`extra` keys added).
fn point_source_scene(extra: &str) -> String {
    format!(
        r#"
        [materials.black]
        reflectance = 0
        [[objects]]
        shape = "rect"
        corner = [-5, -5, 0]
        u = [10, 0, 0]
        v = [0, 10, 0]
        material = "black"
        [[lights]]
        type = "point"
        position = [0, 0, 2]
        intensity_cd = 1000
        [[receivers]]
        name = "p"
        corner = [-1.5, -1, 0.0001]
        u = [4, 0, 0]
        v = [0, 3, 0]
        values = "point"
        {extra}
        "#
    )
}

/// I·h/d³ at (x, y) of the receiver plane.
fn point_source_lx(x: f64, y: f64) -> f64 {
    let h = 2.0 - 0.0001;
    1000.0 * h / libm::pow(x * x + y * y + h * h, 1.5)
}

/// On the standard's grid the points are the cell centres and each reads I·cos γ/d²
/// exactly (σ 0: a point source's sampled direct light is the same in every replicate),
/// and so do Emin, Emax and U0, their intervals closed on them; the figures say
/// `point`.
#[test]
fn a_point_source_s_point_values_and_figures_are_exact_on_the_standard_s_grid() {
    let s = run_scene(
        &point_source_scene("grid = \"en12464\"\ngrid_band_m = 0"),
        20_000,
    );
    let r = &s.receivers["p"];
    let [nu, nv] = r.cells.map(|c| c as usize);
    // d = 4 m: p = 0.2·5^log10(4) = 0.53 m, 8 × 6 points (2011 rounding up).
    assert_eq!((nu, nv), (8, 6));
    let exact: Vec<f64> = (0..nu * nv)
        .map(|k| {
            let (i, j) = (k % nu, k / nu);
            let x = -1.5 + 4.0 * (i as f64 + 0.5) / nu as f64;
            let y = -1.0 + 3.0 * (j as f64 + 0.5) / nv as f64;
            point_source_lx(x, y)
        })
        .collect();
    for (k, (v, e)) in r.values.iter().zip(&exact).enumerate() {
        assert!((v - e).abs() <= 1e-9 * e, "point {k}: {v} against {e}");
        assert_eq!(r.sigma[k], 0.0, "point {k}");
    }
    let f = &r.figures;
    assert_eq!(f.values, "point");
    let min = exact.iter().copied().fold(f64::INFINITY, f64::min);
    let max = exact.iter().copied().fold(0.0, f64::max);
    let mean = exact.iter().sum::<f64>() / exact.len() as f64;
    for (figure, truth) in [
        (f.min, min),
        (f.max, max),
        (f.mean, mean),
        (f.u0, min / mean),
        (f.g2, min / max),
    ] {
        for x in [figure.value, figure.low, figure.high] {
            assert!(
                (x - truth).abs() <= 1e-9 * truth,
                "{figure:?} against {truth}"
            );
        }
    }
}

/// The cell averages of the same receiver differ from its point values (by ~1 % at
/// the centre, where E is curved): what a figure used matters and is labelled.
#[test]
fn cell_averages_are_not_point_values() {
    let toml = point_source_scene("cells = [4, 3]").replace("values = \"point\"", "");
    let s = run_scene(&toml, 20_000);
    let r = &s.receivers["p"];
    assert_eq!(r.figures.values, "cell_average");
    // Cell (1, 1) spans [−0.5, 0.5] × [0, 1]; its centre is (0, 0.5).
    let average = point_source_cell_lx(1000.0, 2.0 - 0.0001, -0.5, 0.5, 0.0, 1.0);
    let k = 4 + 1;
    assert!((r.values[k] - average).abs() < 1e-9 * average + 5.0 * r.sigma[k]);
    let centre = point_source_lx(0.0, 0.5);
    assert!(
        (centre - average) / average > 0.005,
        "{centre} against {average}"
    );
}

/// A Lambertian panel of luminance L over points on a table: E = π·L·F with F the
/// configuration factor from each point to the panel, sampled over the panel with a σ
/// that sees its own error (480 points).
#[test]
fn an_area_source_s_point_values_are_calibrated() {
    let toml = r#"
    [materials.black]
    reflectance = 0
    [[objects]]
    shape = "rect"
    corner = [-2, -2, 0]
    u = [12, 0, 0]
    v = [0, 12, 0]
    material = "black"
    [[lights]]
    type = "area"
    corner = [1, 1, 3]
    u = [0, 3, 0]
    v = [4, 0, 0]
    luminance_cdm2 = 1000
    [[receivers]]
    name = "table"
    corner = [0.0, 0.0, 1.5]
    u = [6, 0, 0]
    v = [0, 5, 0]
    cells = [24, 20]
    values = "point"
    "#;
    let s = run_scene(toml, 200_000);
    let r = &s.receivers["table"];
    let h = 1.5;
    let exact = |i: usize, j: usize| {
        let (x, y) = ((i as f64 + 0.5) * 0.25, (j as f64 + 0.5) * 0.25);
        let f = |a: f64, b: f64| parallel_corner_factor(a - x, b - y, h);
        let factor = f(5.0, 4.0) - f(1.0, 4.0) - f(5.0, 1.0) + f(1.0, 1.0);
        PI * 1000.0 * factor
    };
    assert!(
        r.sigma.iter().any(|s| *s > 0.0),
        "an area source is sampled"
    );
    assert_matches(r, exact, "points under a panel");
}

/// Points in an integrating sphere (ρ = 0.8) read the source's I/d² exactly plus the
/// uniform indirect ρΦ/((1 − ρ)A), the latter from connections with calibrated σ.
#[test]
fn points_in_an_integrating_sphere_read_direct_plus_uniform_indirect() {
    let (rho, intensity) = (0.8, 100.0);
    let toml = point_in_sphere("coating", "reflectance = 0.8", 4, [0.0, 0.0, 0.0])
        + r#"
        [[receivers]]
        name = "r"
        corner = [-0.2, 0.2, 0.3]
        u = [0.4, 0, 0]
        v = [0, -0.4, 0]
        cells = [16, 16]
        values = "point"
        "#;
    let s = run_scene(&toml, 300_000);
    let indirect = rho * 4.0 * PI * intensity / ((1.0 - rho) * s.global.area_m2);
    let w = 0.4 / 16.0;
    let exact = |i: usize, j: usize| {
        let (x, y) = (-0.2 + (i as f64 + 0.5) * w, 0.2 - (j as f64 + 0.5) * w);
        intensity * 0.3 / libm::pow(x * x + y * y + 0.09, 1.5) + indirect
    };
    assert_matches(&s.receivers["r"], exact, "points in an integrating sphere");
}

/// A point has no area to cross: the track estimator is refused, in the scene file
/// and from the command line's override, and so is a luminance meter at points.
#[test]
fn point_receivers_refuse_the_track_estimator_and_luminance() {
    let error = |toml: &str| match load_str(toml, Path::new("."), "p.toml") {
        Ok(_) => panic!("loads: {toml}"),
        Err(e) => e.to_string(),
    };
    let m = error(&point_source_scene("cells = [2, 2]\nestimator = \"track\""));
    assert!(
        m.contains("receivers[0].values") && m.contains("next-event"),
        "{m}"
    );
    let m = error(&point_source_scene(
        "cells = [2, 2]\nquantity = \"luminance\"\nview_direction = [0, 0, -1]\nhalf_angle_deg = 5",
    ));
    assert!(
        m.contains("receivers[0].values") && m.contains("luminance"),
        "{m}"
    );
    let scene = scene(&point_source_scene("cells = [2, 2]"));
    let o = RunOptions {
        estimator: Some(Estimator::Track),
        ..options(&scene, 1000, 2, Backend::Embree)
    };
    let Err(e) = run(&scene, &o, &AtomicBool::new(false), &mut ()) else {
        panic!("track on a point receiver ran");
    };
    let m = e.to_string();
    assert!(m.contains("--estimator track") && m.contains("`p`"), "{m}");
}

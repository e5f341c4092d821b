//! Error estimates are calibrated, forecasts come true, and every stop criterion stops
//! where it should and says why.

use crate::common;

use common::*;
use luxtally::accel::Backend;
use luxtally::criteria::StopCriteria;
use luxtally::run::{run, RunOptions};
use luxtally::scene::Scene;
use luxtally::stats::{triangle_illuminance_lx, MapKind};
use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

/// A point source 2 m over a black plane, with a receiver of `nu × nv` cells scored by
/// the analog (`track`) estimator, whose error falls with the photons alone.
fn point_over_plane(nu: u32, nv: u32) -> String {
    point_over_plane_scored(nu, nv, "track")
}

/// [`point_over_plane`] with the receiver's `estimator`.
fn point_over_plane_scored(nu: u32, nv: u32, estimator: &str) -> String {
    format!(
        r#"{BLACK_FLOOR}
        [[lights]]
        type = "point"
        position = [0, 0, 2.0]
        intensity_cd = 1000
        [[receivers]]
        name = "r"
        corner = [-1, -1, 0]
        u = [2, 0, 0]
        v = [0, 2, 0]
        cells = [{nu}, {nv}]
        estimator = "{estimator}"
        "#
    )
}

fn point_over_plane_exact(nu: u32, nv: u32) -> impl Fn(usize, usize) -> f64 {
    move |i, j| {
        let (wx, wy) = (2.0 / nu as f64, 2.0 / nv as f64);
        let (x0, y0) = (-1.0 + i as f64 * wx, -1.0 + j as f64 * wy);
        point_source_cell_lx(1000.0, 2.0, x0, x0 + wx, y0, y0 + wy)
    }
}

#[test]
fn receiver_sigma_is_calibrated_68_percent_within_one_sigma() {
    // The analog estimator, then the sampled direct light of next-event receivers.
    for (estimator, photons) in [("track", 8_000_000), ("next_event", 1_000_000)] {
        let s = run_scene(&point_over_plane_scored(32, 32, estimator), photons);
        let z = z_scores(&s.receivers["r"], point_over_plane_exact(32, 32));
        assert_calibrated(&z, &format!("32 × 32 receiver, {estimator}"));
        let inside = z.iter().filter(|x| x.abs() <= 1.0).count() as f64 / z.len() as f64;
        assert!(
            (0.62..=0.74).contains(&inside),
            "{estimator}: {:.1} % of cells within 1σ",
            100.0 * inside
        );
    }
}

/// Solid angle of the triangle (a, b, c) seen from the origin (Van Oosterom & Strackee).
fn solid_angle(a: glam::DVec3, b: glam::DVec3, c: glam::DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c)).abs();
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * libm::atan2(num, den)
}

#[test]
fn global_odd_even_error_matches_the_actual_map_error() {
    // Icosphere with a point source at its centre: per-triangle truth is direct
    // Φ·Ω_k/(4π·A_k) plus the sphere's uniform indirect ρΦ/((1−ρ)S).
    let (rho, intensity) = (0.5, 100.0);
    let scene = scene(&point_in_sphere(
        "coating",
        "reflectance = 0.5",
        3,
        [0.0, 0.0, 0.0],
    ));
    let opts = options(&scene, 2_000_000, 2, Backend::Embree);
    let result = run(&scene, &opts, &AtomicBool::new(false), &mut ()).unwrap();
    let g = &scene.geometry;
    let flux = 4.0 * PI * intensity;
    let area = g.total_area_m2();
    let indirect = rho * flux / ((1.0 - rho) * area);
    let mut sum_sq = 0.0;
    for (k, tri) in g.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| g.vertices[i as usize].as_dvec3() + g.origin);
        let exact = flux * solid_angle(a, b, c) / (4.0 * PI * g.area_m2(k)) + indirect;
        let e = triangle_illuminance_lx(
            &result.progress.tallies,
            MapKind::Total,
            k,
            g.area_m2(k),
            result.setup.total_flux_lm,
            None,
        );
        sum_sq += g.area_m2(k) * (e - exact).powi(2);
    }
    let actual = (sum_sq / area).sqrt();
    let s = luxtally::output::summary::build(&result.state(&scene, &opts));
    let ratio = s.global.sigma_lx / actual;
    eprintln!(
        "reported σ {} lx, actual RMS error {actual} lx, ratio {ratio:.3}",
        s.global.sigma_lx
    );
    assert!(
        (0.85..=1.15).contains(&ratio),
        "reported/actual = {ratio:.3}"
    );
}

fn run_until(
    scene: &Scene,
    change: impl FnOnce(&mut StopCriteria),
) -> luxtally::output::summary::Summary {
    let mut opts = options(scene, 0, 2, Backend::Embree);
    opts.stop.photons = None;
    change(&mut opts.stop);
    run_options(scene, &opts)
}

#[test]
fn forecast_at_ten_percent_predicts_the_photons_needed_within_three_percent() {
    let scene = scene(&point_over_plane(6, 6));
    let s = run_until(&scene, |o| {
        o.target_error = Some(0.01);
        o.target = Some("receiver:r".into());
    });
    assert_eq!(s.stop_reason.as_deref(), Some("target_error"));
    let needed = s.photons_emitted as f64;
    let early = s
        .history
        .iter()
        .find(|p| p.photons as f64 >= 0.1 * needed)
        .expect("a history point at 10 %");
    let predicted = early.forecast_photons.expect("forecast recorded") as f64;
    eprintln!(
        "at {} photons: forecast {predicted}, needed {needed}",
        early.photons
    );
    assert!(
        early.photons as f64 <= 0.25 * needed,
        "first point past 10 % is at {} of {needed}",
        early.photons
    );
    assert!(
        (predicted / needed - 1.0).abs() < 0.03,
        "forecast {predicted} vs {needed}"
    );
    let f = s.forecast.as_ref().expect("final forecast");
    assert_eq!(f.target_error, 0.01);
}

#[test]
fn stop_on_photons_emits_exactly_that_many() {
    let scene = scene(&point_over_plane(4, 4));
    let s = run_until(&scene, |o| o.photons = Some(123_457));
    assert_eq!(
        (s.stop_reason.as_deref(), s.photons_emitted),
        (Some("photons"), 123_457)
    );
}

#[test]
fn stop_on_time_limit_stops_at_the_first_epoch_past_it() {
    let scene = scene(&point_over_plane(4, 4));
    let s = run_until(&scene, |o| o.time_limit_s = Some(1.0));
    assert_eq!(s.stop_reason.as_deref(), Some("time"));
    // At the first epoch boundary past the limit (how long an epoch takes depends on the
    // machine's load: no wall-clock bound).
    let n = s.history.len();
    assert!(n >= 2, "{n} epochs");
    assert!(
        s.history[n - 1].elapsed_s >= 1.0 && s.history[n - 2].elapsed_s < 1.0,
        "last two epochs ended at {} s and {} s",
        s.history[n - 2].elapsed_s,
        s.history[n - 1].elapsed_s
    );
    assert!(s.elapsed_s >= 1.0, "stopped after {} s", s.elapsed_s);
}

/// The last history point meets `goal` and the one before does not.
fn assert_stopped_at_first_crossing(s: &luxtally::output::summary::Summary, goal: f64) {
    let n = s.history.len();
    assert!(n >= 2);
    assert!(
        s.history[n - 1].rel_error <= goal,
        "last error {}",
        s.history[n - 1].rel_error
    );
    assert!(
        s.history[n - 2].rel_error > goal,
        "error {} already met before",
        s.history[n - 2].rel_error
    );
}

#[test]
fn stop_on_relative_error_of_receiver_global_and_block() {
    let scene = scene(&point_over_plane(8, 8));
    for (target, goal) in [
        ("receiver:r", 0.03),
        ("global", 0.005),
        ("receiver:r[2..4,3..6]", 0.04),
    ] {
        let s = run_until(&scene, |o| {
            o.target_error = Some(goal);
            o.target = Some(target.into());
        });
        assert_eq!(s.stop_reason.as_deref(), Some("target_error"), "{target}");
        assert_eq!(s.target, target);
        assert_stopped_at_first_crossing(&s, goal);
        if target.contains('[') {
            // The worst cell of the block is at the goal: every block cell is within it.
            let r = &s.receivers["r"];
            for j in 3..6 {
                for i in 2..4 {
                    let k = j * 8 + i;
                    assert!(r.sigma[k] / r.values[k] <= goal + 1e-12);
                }
            }
        }
    }
}

#[test]
fn stop_on_absolute_error_in_lux() {
    let scene = scene(&point_over_plane(8, 8));
    let s = run_until(&scene, |o| {
        o.target_error = Some(5.0);
        o.absolute = true;
        o.target = Some("receiver:r".into());
    });
    assert_eq!(s.stop_reason.as_deref(), Some("target_error"));
    assert_stopped_at_first_crossing(&s, 5.0);
    let r = &s.receivers["r"];
    let rms_sigma = (r.sigma.iter().map(|x| x * x).sum::<f64>() / r.sigma.len() as f64).sqrt();
    assert!(rms_sigma <= 5.0 && rms_sigma > 4.0, "RMS σ {rms_sigma} lx");
}

#[test]
fn stop_on_min_hits_in_a_block() {
    let scene = scene(&point_over_plane(8, 8));
    let s = run_until(&scene, |o| {
        o.min_hits = Some(2000);
        o.target = Some("receiver:r[0..2,0..2]".into());
    });
    assert_eq!(s.stop_reason.as_deref(), Some("min_hits"));
    let hits = &s.receivers["r"].hits;
    let fewest = [0, 1, 8, 9].map(|k| hits[k]).into_iter().min().unwrap();
    assert!((2000..2100).contains(&fewest), "fewest hits {fewest}");
}

#[test]
fn combined_criteria_first_met_wins() {
    let scene = scene(&point_over_plane(8, 8));
    // 1 % needs millions of photons: the photon limit comes first.
    let s = run_until(&scene, |o| {
        o.photons = Some(50_000);
        o.target_error = Some(0.01);
    });
    assert_eq!(
        (s.stop_reason.as_deref(), s.photons_emitted),
        (Some("photons"), 50_000)
    );
    // A loose target comes before a long time limit and a large photon count.
    let s = run_until(&scene, |o| {
        o.photons = Some(1_000_000_000);
        o.time_limit_s = Some(60.0);
        o.target_error = Some(0.1);
    });
    assert_eq!(s.stop_reason.as_deref(), Some("target_error"));
}

#[test]
fn stop_criteria_are_read_from_the_scene_simulation_table() {
    let toml = point_over_plane(8, 8)
        + "[simulation]\ntarget_error = 0.05\ntarget = \"receiver:r[0..4,0..4]\"\ntime_limit = 60\nseed = 7\n";
    let scene = scene(&toml);
    let mut opts = RunOptions::from_scene(&scene);
    opts.threads = 2;
    let s = run_options(&scene, &opts);
    assert_eq!(s.stop_reason.as_deref(), Some("target_error"));
    assert_eq!(s.target, "receiver:r[0..4,0..4]");
    assert_eq!(s.seed, 7);
    assert_stopped_at_first_crossing(&s, 0.05);
}

//! The bounce cap (docs/method.md, *Bounce cap*): chosen from the scene's highest albedo
//! so the light it can drop is below 1 % of the σ, reported as `bounce_cap_bias_bound`;
//! a closed lossless scene (infinite answer) is refused; an open lossless one runs and
//! says what the cap stopped.

use crate::common;

use common::{options, run_options, scene};
use luxtally::accel::Backend;
use luxtally::output::summary::Summary;
use luxtally::run::RunOptions;
use luxtally::stats::BOUNCE_CAP_BIAS_SHARE;
use luxtally::trace::MAX_BOUNCE_CAP;
use std::f64::consts::PI;
use std::process::Command;

const INTENSITY_CD: f64 = 1000.0;

/// A closed 4 × 3 × 2.5 m room (one `box`, walls of reflectance `rho`, or `material`)
/// with a point source inside.
fn closed_room(material: &str) -> String {
    format!(
        r#"
        [materials.wall]
        {material}
        [[objects]]
        shape = "box"
        min = [0, 0, 0]
        max = [4, 3, 2.5]
        material = "wall"
        [[lights]]
        type = "point"
        position = [1.3, 1.1, 1.7]
        intensity_cd = {INTENSITY_CD}
        "#
    )
}

const ROOM_AREA_M2: f64 = 2.0 * (4.0 * 3.0 + 3.0 * 2.5 + 4.0 * 2.5);

fn run_seed(toml: &str, photons: u64, seed: u64) -> Summary {
    run_seed_on(toml, photons, seed, Backend::Embree)
}

fn run_seed_on(toml: &str, photons: u64, seed: u64, backend: Backend) -> Summary {
    let s = scene(toml);
    let opts = RunOptions {
        seed,
        ..options(&s, photons, 2, backend)
    };
    run_options(&s, &opts)
}

/// The relative σ of the scene map's mean.
fn global_sigma_rel(s: &Summary) -> f64 {
    s.global.mean_sigma_lx / s.global.mean_illuminance_lx
}

/// Closed room at ρ: the mean illuminance over all walls is exactly Φ/(S(1 − ρ)),
/// Φ = 4π·I. Over a few seeds pooled, z = Σ(Eᵢ − E)/sqrt(Σσᵢ²) within 3; each run's
/// VOV finite and < 1, no photon capped, the cap's bound reported, below 1 % of σ_rel,
/// and the error not marked biased by it.
fn closed_room_at(rho: f64, photons: u64, seeds: u64, backend: Backend) {
    let toml = closed_room(&format!("reflectance = {rho}"));
    let exact = 4.0 * PI * INTENSITY_CD / (ROOM_AREA_M2 * (1.0 - rho));
    let (mut dev, mut var) = (0.0, 0.0);
    for seed in 1..=seeds {
        let s = run_seed_on(&toml, photons, seed, backend);
        let g = &s.global;
        assert!((g.area_m2 - ROOM_AREA_M2).abs() < 1e-9);
        assert!(g.mean_sigma_lx.is_finite() && g.mean_sigma_lx > 0.0);
        dev += g.mean_illuminance_lx - exact;
        var += g.mean_sigma_lx * g.mean_sigma_lx;
        let vov = s.reliability.vov;
        assert!(
            vov.is_finite() && vov < 1.0,
            "ρ {rho} seed {seed}: VOV {vov}"
        );
        assert_eq!(s.photons_killed_by_bounce_cap, 0, "ρ {rho} seed {seed}");
        let bound = s.bounce_cap_bias_bound.expect("ρ < 1: an a-priori bound");
        assert!(
            bound < BOUNCE_CAP_BIAS_SHARE * global_sigma_rel(&s),
            "ρ {rho}: bound {bound} vs σ_rel {}",
            global_sigma_rel(&s)
        );
        assert!(!s.reliability.bounce_cap_biased);
        // ρ^cap ≤ 1e-12 (the roulette's survival chance ⌈ρ·2³²⌉/2³² ≥ ρ is what counts).
        assert!(bound <= 1e-12 * (1.0 + 1e-9), "{bound}");
        assert!(libm::pow(rho, s.bounce_cap as f64) <= bound * (1.0 + 1e-9));
        eprintln!(
            "ρ {rho} seed {seed}: cap {}, mean {} lx (exact {exact}), σ {} lx, VOV {vov}, bound {bound:e}, {} rays",
            s.bounce_cap, g.mean_illuminance_lx, g.mean_sigma_lx, s.rays_traced
        );
    }
    let z = dev / var.sqrt();
    assert!(z.abs() < 3.0, "ρ {rho}: pooled z {z}");
}

#[test]
fn closed_room_at_rho_0_99995_is_unbiased_past_the_old_cap() {
    // 20,000 bounces per photon on average: the old cap of 100,000 dropped e⁻⁵ ≈ 0.67 %.
    closed_room_at(0.99995, 1_000, 3, Backend::Embree);
}

#[cfg(feature = "obvhs")]
#[test]
fn closed_room_at_rho_0_99995_is_unbiased_on_obvhs() {
    closed_room_at(0.99995, 1_000, 3, Backend::Obvhs);
}

#[test]
fn closed_room_at_rho_0_9999_is_unbiased() {
    closed_room_at(0.9999, 2_000, 3, Backend::Embree);
}

#[test]
fn the_cap_follows_the_albedo_past_100_000() {
    let s = scene(&closed_room("reflectance = 0.99995"));
    let o = options(&s, 1, 1, Backend::Embree);
    let r = run_options(&s, &o);
    assert!(r.bounce_cap > 100_000, "{}", r.bounce_cap);
    assert_eq!(r.bounce_cap, 552_608, "⌈ln 1e-12 / ln(⌈ρ·2³²⌉/2³²)⌉");
}

/// A closed lossless room: every photon bounces forever, the exact answer is infinite:
/// refused in one line, exit 1, before any output.
#[test]
fn closed_lossless_room_is_refused_in_one_line() {
    let dir = std::env::temp_dir().join(format!("luxtally-cap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, material) in [
        ("white", "reflectance = 1.0"),
        ("mirror", "specular_reflectance = 1.0"),
        (
            "mix",
            "reflectance = 0.5\n        specular_reflectance = 0.5",
        ),
    ] {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, closed_room(material)).unwrap();
        let out = dir.join(format!("{name}-out"));
        let o = Command::new(env!("CARGO_BIN_EXE_luxtally"))
            .args([
                "run",
                path.to_str().unwrap(),
                "--photons",
                "1000",
                "--quiet",
            ])
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{name}: {stderr}");
        assert!(stderr.contains("infinite"), "{name}: {stderr}");
        assert!(!out.join("summary.json").exists(), "{name}");
    }
    // The library says the same: an input error naming the scene file.
    let s = scene(&closed_room("reflectance = 1.0"));
    let o = options(&s, 100, 1, Backend::Embree);
    let e = luxtally::run::run(&s, &o, &Default::default(), &mut ())
        .err()
        .expect("refused");
    assert!(matches!(e, luxtally::Error::Input { .. }), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A lossless floor (ρ = 1) under a point source, open to the sky: it runs with the
/// largest cap; no photon is capped, so the bound is −ln(0.05)/N (95 %), and the error
/// is marked biased exactly when that is not below 1 % of the σ_rel reported.
#[test]
fn open_lossless_scene_runs_and_bounds_the_cap_by_what_it_stopped() {
    let toml = format!(
        r#"
        [materials.white]
        reflectance = 1.0
        [[objects]]
        shape = "rect"
        corner = [-2, -2, 0]
        u = [4, 0, 0]
        v = [0, 4, 0]
        material = "white"
        [[lights]]
        type = "point"
        position = [0.2, 0.1, 1.5]
        intensity_cd = {INTENSITY_CD}
        "#
    );
    for photons in [20_000u64, 400_000] {
        let s = run_seed(&toml, photons, 1);
        assert_eq!(s.bounce_cap, MAX_BOUNCE_CAP);
        assert_eq!(s.photons_killed_by_bounce_cap, 0);
        let bound = s.bounce_cap_bias_bound.expect("none capped: a bound");
        assert!((bound - 2.995_732_273_553_991 / photons as f64).abs() < 1e-15);
        let sigma_rel = global_sigma_rel(&s);
        let biased = bound >= BOUNCE_CAP_BIAS_SHARE * sigma_rel;
        eprintln!("{photons} photons: bound {bound:e}, σ_rel {sigma_rel:e}, biased {biased}");
        assert_eq!(s.reliability.bounce_cap_biased, biased, "{photons} photons");
        if biased {
            assert!(!s.reliability.reliable);
        }
    }
}

/// A closed lossless room the refusal cannot see through (its only inner object is
/// unmapped: instanced meshes are not examined), so every photon runs to the cap: the
/// bound is unknown (null) and the error unreliable, with the reason in summary.json.
#[test]
fn lossless_photons_stopped_by_the_cap_leave_the_bound_unknown() {
    let toml = format!(
        r#"
        [materials.white]
        reflectance = 1.0
        [[objects]]
        shape = "box"
        min = [0, 0, 0]
        max = [4, 3, 2.5]
        material = "white"
        [[objects]]
        shape = "box"
        min = [2, 2, 0]
        max = [2.5, 2.5, 0.5]
        material = "white"
        map = false
        [[lights]]
        type = "point"
        position = [1.3, 1.1, 1.7]
        intensity_cd = {INTENSITY_CD}
        "#
    );
    let s = run_seed(&toml, 4, 1);
    // Nearly all: over 2²¹ bounces a photon may leak through a crack of the f32 walls.
    assert!(
        s.photons_killed_by_bounce_cap >= 1,
        "{}",
        s.photons_killed_by_bounce_cap
    );
    assert_eq!(s.bounce_cap_bias_bound, None);
    assert!(s.reliability.bounce_cap_biased && !s.reliability.reliable);
    let json = serde_json::to_value(&s).unwrap();
    assert!(json["bounce_cap_bias_bound"].is_null());
    assert_eq!(json["reliability"]["bounce_cap_biased"], true);
}

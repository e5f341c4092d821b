//! UGR of `[[observers]]` (docs/ugr.md): one luminaire's L, ω and p against the
//! geometry computed here, the UGR formula, occlusion, E_ind's calibration and that it
//! leaves out the direct light, the hidden receiver's facing, bad input.

use crate::common;

use common::*;
use luxtally::accel::Backend;
use luxtally::output::observers::ObserverSummary;
use luxtally::output::summary::Summary;
use luxtally::scene::{load_str, Scene};
use luxtally::stats::ugr;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

/// A 0.6 m × 0.6 m opening (LM-63 units 2: metres) emitting 1000 cd uniformly below the
/// horizontal (γ 0–90°; 0 at 180°), written into a folder of its own.
fn square_luminaire_dir() -> PathBuf {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("luxtally-ugr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let ies = "IESNA:LM-63-2002\n[TEST] ugr\nTILT=NONE\n1 -1 1 3 1 1 2 0.6 0.6 0\n1 1 10\n\
                   0 90 180\n0\n1000 1000 0\n";
        std::fs::write(dir.join("square.ies"), ies).unwrap();
        dir
    })
    .clone()
}

fn load(toml: &str) -> Scene {
    load_str(toml, &square_luminaire_dir(), "ugr.toml").expect("scene loads")
}

fn error_of(toml: &str) -> String {
    match load_str(toml, &square_luminaire_dir(), "ugr.toml") {
        Ok(_) => panic!("scene loads: {toml}"),
        Err(e) => e.to_string(),
    }
}

const LUMINAIRE: [f64; 3] = [3.0, 0.5, 2.8];
const EYE: [f64; 3] = [0.0, 0.0, 1.2];

/// The luminaire above a grey floor (and `extra`), an observer at `EYE` looking +x and
/// one looking −x (the luminaire behind it).
fn scene_text(extra: &str) -> String {
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
        type = "luminaire"
        file = "square.ies"
        position = {LUMINAIRE:?}
        [[observers]]
        name = "front"
        position = {EYE:?}
        look = [1, 0, 0]
        [[observers]]
        name = "back"
        position = {EYE:?}
        look = [-1, 0, 0]
        {extra}
        "#
    )
}

fn run(scene: &Scene, photons: u64, seed: u64) -> Summary {
    let mut o = options(scene, photons, 2, Backend::Embree);
    o.seed = seed;
    run_options(scene, &o)
}

fn observer<'a>(s: &'a Summary, name: &str) -> &'a ObserverSummary {
    &s.observers.as_ref().expect("observers")[name]
}

/// The Luckiesh–Guth index from the geometry: σ from the line of sight, τ the angle of
/// the plane through the line of sight and the source from the vertical (tan τ = T/H).
fn guth(r: f64, h: f64, t: f64) -> f64 {
    let sigma = libm::atan2(libm::hypot(h, t), r).to_degrees();
    let tau = libm::atan2(t, h).to_degrees();
    let a = 35.2 - 0.31889 * tau - 1.22 * libm::exp(-2.0 * tau / 9.0);
    let b = 21.0 + 0.26667 * tau - 0.002963 * tau * tau;
    libm::exp(a * 1e-3 * sigma + b * 1e-5 * sigma * sigma)
}

fn close(a: f64, b: f64, rel: f64, what: &str) {
    assert!(
        (a - b).abs() <= rel * b.abs(),
        "{what}: {a} against {b} (rel {rel})"
    );
}

#[test]
fn one_luminaire_l_omega_p_match_the_geometry() {
    let scene = load(&scene_text(""));
    let s = run(&scene, 20_000, 1);
    let o = observer(&s, "front");
    let lum = &o.luminaires[0];
    let (r, t, h) = (
        LUMINAIRE[0] - EYE[0],
        LUMINAIRE[1] - EYE[1],
        LUMINAIRE[2] - EYE[2],
    );
    let d = libm::sqrt(r * r + t * t + h * h);
    let a_proj = 0.36 * h / d; // the opening faces down: cos θ = H/d
    assert!(lum.counted && !lum.occluded, "{}", lum.status);
    close(lum.luminance_cdm2, 1000.0 / a_proj, 1e-9, "L");
    close(lum.omega_sr, a_proj / (d * d), 1e-9, "ω");
    // glarendx writes 2/9 as .22222: the two agree to ~1e-7.
    close(lum.position_index, guth(r, h, t), 1e-6, "p");
    close(lum.r_m, r, 1e-12, "R");
    close(lum.h_m, h, 1e-12, "H");
    close(lum.t_m, t, 1e-12, "T");
    // UGR from those and the run's E_ind, by the formula.
    let lb = o.e_ind_lx / std::f64::consts::PI;
    let p = lum.position_index;
    let expect = 8.0 * libm::log10(0.25 / lb * lum.luminance_cdm2.powi(2) * lum.omega_sr / (p * p));
    close(o.ugr.expect("ugr"), expect, 1e-12, "UGR");
    assert!(o.valid, "{:?}", o.invalid_reason);
    // The luminaire behind the other observer does not count.
    let back = observer(&s, "back");
    assert!(!back.luminaires[0].counted);
    assert_eq!(back.ugr, None);
    assert!(!back.valid);
}

#[test]
fn ugr_formula_and_its_sigma() {
    let (l, omega, p, e_ind): (f64, f64, f64, f64) = (5000.0, 0.01, 1.7, 150.0);
    let sum = l * l * omega / (p * p);
    let lb = e_ind / std::f64::consts::PI;
    assert_eq!(
        ugr::ugr(sum, e_ind),
        Some(8.0 * libm::log10(0.25 / lb * sum))
    );
    assert_eq!(ugr::ugr(sum, 0.0), None);
    assert_eq!(ugr::ugr(0.0, e_ind), None);
    // The flux rule: k × every luminance and E_ind raises UGR by 8·log10 k.
    let k = 2.0;
    close(
        ugr::ugr(sum * k * k, e_ind * k).unwrap(),
        ugr::ugr(sum, e_ind).unwrap() + 8.0 * libm::log10(k),
        1e-12,
        "flux rule",
    );
    // glarendx's posindex: 1 on the line of sight, −1 behind, symmetric above/below.
    use glam::DVec3;
    let (v, up) = (DVec3::X, DVec3::Z);
    assert_eq!(ugr::position_index(DVec3::X, v, up), 1.0);
    assert_eq!(ugr::position_index(-DVec3::X, v, up), -1.0);
    let s = DVec3::new(1.0, 0.3, 0.5).normalize();
    let s_below = DVec3::new(1.0, 0.3, -0.5).normalize();
    assert_eq!(
        ugr::position_index(s, v, up),
        ugr::position_index(s_below, v, up)
    );
    close(
        ugr::position_index(s, v, up),
        guth(1.0, 0.5, 0.3),
        1e-6,
        "p",
    );
}

#[test]
fn a_box_between_eye_and_luminaire_removes_it() {
    // The line from the eye to the opening's centre passes (1.5, 0.25, 2.0).
    let blocker = r#"
        [[objects]]
        shape = "box"
        min = [1.4, 0.1, 1.8]
        max = [1.6, 0.4, 2.2]
        material = "grey"
    "#;
    let s = run(&load(&scene_text(blocker)), 5_000, 1);
    let o = observer(&s, "front");
    assert!(o.luminaires[0].occluded);
    assert_eq!(o.luminaires[0].visible_fraction, 0.0);
    assert!(!o.luminaires[0].counted);
    assert_eq!(o.luminaires[0].status, "occluded");
    assert_eq!(o.ugr, None);
    assert!(!o.valid);
    let clear = run(&load(&scene_text("")), 5_000, 1);
    assert!(!observer(&clear, "front").luminaires[0].occluded);
}

/// A plate that hides exactly the half x < 3 m of the opening from the front eye: the
/// luminaire counts with half its solid angle and the same luminance, so its Σ L²ω/p²
/// halves (the visible fraction is resolved to 1/64, and this edge falls between the
/// grid's columns).
#[test]
fn a_partly_hidden_luminaire_counts_with_its_visible_solid_angle() {
    // The eye–opening rays cross z = 2.7 at 15/16 of the way: x_o = 3 maps to 2.8125.
    let plate = r#"
        [[objects]]
        shape = "rect"
        corner = [2.4, 0, 2.7]
        u = [0.4125, 0, 0]
        v = [0, 1, 0]
        material = "grey"
    "#;
    let half = run(&load(&scene_text(plate)), 5_000, 1);
    let clear = run(&load(&scene_text("")), 5_000, 1);
    let (h, c) = (observer(&half, "front"), observer(&clear, "front"));
    let (hl, cl) = (&h.luminaires[0], &c.luminaires[0]);
    assert_eq!((hl.visible_fraction, cl.visible_fraction), (0.5, 1.0));
    assert!(hl.counted && !hl.occluded);
    assert_eq!(hl.luminance_cdm2, cl.luminance_cdm2);
    close(hl.omega_sr, cl.omega_sr / 2.0, 1e-12, "visible ω");
    close(h.sum, c.sum / 2.0, 1e-12, "Σ L²ω/p²");
}

/// The luminaire in a closed box of reflectance `rho`, an observer inside.
fn boxed(rho: f64) -> String {
    format!(
        r#"
        [materials.wall]
        reflectance = {rho}
        [[objects]]
        shape = "box"
        min = [-1, -2, 0]
        max = [5, 2, 3]
        material = "wall"
        [[lights]]
        type = "luminaire"
        file = "square.ies"
        position = [3, 0.5, 2.8]
        [[observers]]
        name = "eye"
        position = [0, 0, 1.2]
        look = [1, 0, 0]
        "#
    )
}

#[test]
fn e_ind_is_calibrated_against_a_long_run() {
    let scene = load(&boxed(0.7));
    let reference = observer(&run(&scene, 400_000, 99), "eye").clone();
    let sr = reference.e_ind_sigma_lx.unwrap();
    assert!(reference.e_ind_lx > 0.0 && sr > 0.0);
    for seed in 1..=4 {
        let s = run(&scene, 20_000, seed);
        let o = observer(&s, "eye");
        let sigma = o.e_ind_sigma_lx.unwrap();
        let z = (o.e_ind_lx - reference.e_ind_lx) / libm::hypot(sigma, sr);
        assert!(z.abs() < 4.0, "seed {seed}: z = {z}");
        // σ_UGR = (8/ln 10)·σ_rel(E_ind).
        close(
            o.ugr_sigma.unwrap(),
            8.0 / std::f64::consts::LN_10 * sigma / o.e_ind_lx,
            1e-12,
            "σ_UGR",
        );
        let (lo, hi) = (o.ugr_low.unwrap(), o.ugr_high.unwrap());
        let u = o.ugr.unwrap();
        assert!(lo < u && u < hi, "{lo} {u} {hi}");
        // The hidden receiver holds direct + indirect; E_ind is the indirect part.
        let r = &s.receivers["observer:eye"];
        assert!(r.direct[0] > 0.0);
        close(
            r.values[0] - r.direct[0],
            o.e_ind_lx,
            1e-6,
            "value − direct",
        );
    }
}

#[test]
fn a_black_room_has_no_indirect_light_and_no_ugr() {
    let s = run(&load(&boxed(0.0)), 20_000, 1);
    let o = observer(&s, "eye");
    assert_eq!(o.e_ind_lx, 0.0);
    assert_eq!(o.ugr, None);
    assert!(!o.valid);
    assert!(o.invalid_reason.as_deref().unwrap().contains("E_ind"));
    // The direct light reaches the hidden receiver's face (it faces the line of
    // sight): the eye sees the luminaire in front of it.
    assert!(s.receivers["observer:eye"].direct[0] > 0.0);
}

#[test]
fn an_observer_grid_names_each_eye() {
    let grid = r#"
        [[observers]]
        name = "row"
        position = [0, -1, 1.2]
        look = [1, 0, 0]
        grid = {count = [2, 3], spacing = [0.5, 0.5]}
    "#;
    let scene = load(&scene_text(grid));
    let names: Vec<&str> = scene.observers.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names.len(), 8);
    assert!(names.contains(&"row[1,2]"));
    let o = scene
        .observers
        .iter()
        .find(|o| o.name == "row[1,2]")
        .unwrap();
    assert_eq!(o.position.to_array(), [0.5, 0.0, 1.2]);
    assert_eq!(scene.receivers[o.receiver].name, "observer:row[1,2]");
}

#[test]
fn bad_observers_are_rejected_in_one_line() {
    let base = scene_text("");
    let cases = [
        (base.replace("look = [1, 0, 0]", "look = [0, 0, 0]"), "observers[0].look"),
        (
            base.replacen(&format!("position = {EYE:?}"), "position = [3.1, 0.5, 2.75]", 2),
            "observers[0].position",
        ),
        (base.replace("name = \"back\"", "name = \"front\""), "observers[1].name"),
        (base.replace("name = \"back\"", "name = \"\""), "observers[1].name"),
        (
            format!("{base}\n[[observers]]\nname = \"x\"\nposition = [0, 0, 1]\nlook = [1, 0, 0]\ngrid = {{count = [0, 1], spacing = [1, 1]}}\n"),
            "observers[2].grid.count",
        ),
        (base.replace("look = [-1, 0, 0]", "look = [-1, 0, 0]\nup = [0, 0, 1]"), "up"),
    ];
    for (text, key) in cases {
        let e = error_of(&text);
        assert!(e.contains(key), "`{key}` not in: {e}");
        assert!(!e.contains('\n'), "one line: {e}");
    }
}

#[test]
fn scenes_without_observers_have_no_observers_entry() {
    let s = run_scene(
        r#"
        [[lights]]
        type = "point"
        position = [0, 0, 1]
        intensity_cd = 1
        "#,
        1_000,
    );
    assert!(s.observers.is_none());
}

#[test]
fn below_the_line_of_sight_and_too_large_a_source_are_flagged() {
    // The eye above the luminaire's height: the source is below the line of sight.
    let below = scene_text("").replace(&format!("position = {EYE:?}"), "position = [0, 0, 3.5]");
    let s = run(&load(&below), 5_000, 1);
    let o = observer(&s, "front");
    assert_eq!(o.luminaires[0].status, "below the line of sight");
    assert!(!o.luminaires[0].counted && o.ugr.is_none());
    // 0.86 m from a 0.6 m square: ω ≈ 0.28 sr > 0.1, rated but not valid.
    let near = scene_text("").replace(&format!("position = {EYE:?}"), "position = [2.3, 0.5, 2.3]");
    let s = run(&load(&near), 5_000, 1);
    let o = observer(&s, "front");
    assert!(o.luminaires[0].counted && o.luminaires[0].omega_sr > 0.1);
    assert!(o.ugr.is_some() && !o.valid);
    assert!(o.invalid_reason.as_deref().unwrap().contains("solid angle"));
    // A requirement on that rating could never be judged: the run is refused.
    let judged = load(&format!(
        "{near}[[requirements]]\nname = \"glare\"\nobserver = \"front\"\nugr_max = 19\n"
    ));
    let o = common::options(&judged, 1_000, 1, Backend::Embree);
    let e = match luxtally::run::run(&judged, &o, &AtomicBool::new(false), &mut ()) {
        Ok(_) => panic!("a requirement on an unratable observer ran"),
        Err(e) => e.to_string(),
    };
    for needle in [
        "requirement `glare`",
        "observer `front`",
        "ω = 2.8",
        "0.0003 < ω < 0.1",
    ] {
        assert!(e.contains(needle), "`{needle}` not in: {e}");
    }
    assert!(!e.contains('\n'), "one line: {e}");
}

#[test]
fn the_hidden_receiver_faces_the_line_of_sight() {
    let s = run(&load(&scene_text("")), 5_000, 1);
    // The luminaire is in front of `front` and behind `back`: only `front`'s receiver
    // gets its direct light.
    assert!(s.receivers["observer:front"].direct[0] > 0.0);
    assert_eq!(s.receivers["observer:back"].direct[0], 0.0);
}

/// E_ind of [`scene_text`]'s front observer, exactly: one bounce off the grey floor
/// (ρ = 0.5, nothing else to reflect), ρ·E_floor/π seen by the eye's plane facing +x,
/// ∫ L·(ω·x̂)·cos θ_floor/r² dA over the floor in front of the eye (x > 0), by 8 × 8
/// Gauss–Legendre on 0.1 m panels. E_floor = I·cos γ/d² with I = 1000 cd below the
/// luminaire.
fn front_e_ind_lx() -> f64 {
    let [lx, ly, lz] = LUMINAIRE;
    let [_, _, ez] = EYE;
    let integrand = |x: f64, y: f64| {
        let d2 = (x - lx) * (x - lx) + (y - ly) * (y - ly) + lz * lz;
        let e_floor = 1000.0 * lz / (d2 * d2.sqrt());
        let r2 = x * x + y * y + ez * ez;
        0.5 * e_floor / std::f64::consts::PI * (x * ez) / (r2 * r2)
    };
    let panel = 0.1;
    let mut sum = 0.0;
    for i in 0..100 {
        for j in 0..200 {
            let (x0, y0) = (i as f64 * panel, -10.0 + j as f64 * panel);
            sum += panel * panel * cell_average(integrand, x0, x0 + panel, y0, y0 + panel);
        }
    }
    sum
}

/// UGR's interval comes from E_ind's (UGR falls as E_ind grows, L and ω are exact):
/// over 200 seeds it covers the exact UGR at its nominal 95 % within binomial error,
/// and E_ind's z-scores against the exact value have an RMS near 1.
#[test]
fn the_ugr_interval_covers_the_exact_ugr() {
    let scene = load(&scene_text(""));
    let e_exact = front_e_ind_lx();
    let seeds = 200;
    let (mut covered, mut z2) = (0, 0.0);
    let mut exact_ugr = f64::NAN;
    for seed in 1..=seeds {
        let s = run(&scene, 20_000, seed);
        let o = observer(&s, "front");
        exact_ugr = ugr::ugr(o.sum, e_exact).expect("a rating");
        let (lo, hi) = (o.ugr_low.unwrap(), o.ugr_high.unwrap());
        covered += (lo <= exact_ugr && exact_ugr <= hi) as u32;
        let z = (o.e_ind_lx - e_exact) / o.e_ind_sigma_lx.unwrap();
        z2 += z * z;
    }
    let rate = covered as f64 / seeds as f64;
    let sd = libm::sqrt(0.95 * 0.05 / seeds as f64);
    let z_rms = libm::sqrt(z2 / seeds as f64);
    eprintln!(
        "UGR {exact_ugr:.3} (E_ind {e_exact:.4} lx): covered {covered}/{seeds}, z RMS {z_rms:.3}"
    );
    assert!((rate - 0.95).abs() <= 3.0 * sd, "coverage {rate}");
    // The RMS of 200 unit normals is 1 ± 0.05.
    assert!((0.85..=1.15).contains(&z_rms), "z RMS {z_rms}");
}

/// `ugr_max` on observers: PASS well above the exact UGR, FAIL well below, and an
/// observer who sees no luminaire (it is behind the eye) has no UGR: UNDECIDED and
/// not reliable, whatever the budget.
#[test]
fn ugr_max_checks_pass_fail_and_stay_undecided_without_a_rating() {
    let exact = {
        let s = run(&load(&scene_text("")), 1000, 1);
        ugr::ugr(observer(&s, "front").sum, front_e_ind_lx()).unwrap()
    };
    let requirement = |observer: &str, max: f64| {
        format!("[[requirements]]\nname = \"{observer} {max}\"\nobserver = \"{observer}\"\nugr_max = {max}\n")
    };
    let extra = requirement("front", exact + 2.0)
        + &requirement("front", exact - 2.0)
        + &requirement("back", 30.0);
    let s = run(&load(&scene_text(&extra)), 100_000, 5);
    let v = s.verdicts.expect("verdicts");
    let outcomes: Vec<_> = v.checks.iter().map(|c| (c.outcome, c.reliable)).collect();
    use luxtally::stats::verdict::Outcome::{Fail, Pass, Undecided};
    assert_eq!(
        outcomes,
        [(Pass, true), (Fail, true), (Undecided, false)],
        "{v:?}"
    );
    let c = &v.checks[0];
    assert_eq!(
        (c.figure.as_str(), c.at_least, c.at_most),
        ("ugr", None, Some(exact + 2.0))
    );
    assert_eq!(
        (c.observer.as_deref(), c.receiver.as_str()),
        (Some("front"), "observer:front")
    );
    assert!(
        c.low < c.value && c.value < c.high && c.margin_sigma > 3.0,
        "{c:?}"
    );
    assert_eq!(v.overall, Fail);
}

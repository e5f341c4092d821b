//! Engine properties: determinism across threads, backend parity, numerical extremes and
//! degenerate scenes, stop criteria.

use crate::common;

use common::*;
use luxtally::accel::Backend;
use std::path::Path;

fn office() -> luxtally::scene::Scene {
    luxtally::scene::load(Path::new("scenes/office.toml")).expect("office scene loads")
}

#[test]
fn same_seed_gives_bit_identical_results_on_one_and_two_threads() {
    let scene = office();
    // Not a multiple of the chunk size, so the last chunk is partial.
    let one = run_options(&scene, &options(&scene, 300_001, 1, Backend::Embree));
    let two = run_options(&scene, &options(&scene, 300_001, 2, Backend::Embree));
    let (a, b) = (&one.receivers["desk"], &two.receivers["desk"]);
    assert_eq!(a.values, b.values);
    assert_eq!(a.sigma, b.sigma);
    assert_eq!(a.hits, b.hits);
    assert_eq!(one.rays_traced, two.rays_traced);
    assert_eq!(
        one.global.mean_illuminance_lx,
        two.global.mean_illuminance_lx
    );
    assert_eq!(one.global.rel_error, two.global.rel_error);
    let reseeded = luxtally::run::RunOptions {
        seed: 2,
        ..options(&scene, 300_001, 2, Backend::Embree)
    };
    let three = run_options(&scene, &reseeded);
    assert_ne!(
        a.values, three.receivers["desk"].values,
        "another seed differs"
    );
}

#[cfg(feature = "obvhs")]
#[test]
fn embree_and_obvhs_agree_within_half_sigma_per_cell() {
    let scene = office();
    let e = run_options(&scene, &options(&scene, 400_000, 2, Backend::Embree));
    let o = run_options(&scene, &options(&scene, 400_000, 2, Backend::Obvhs));
    assert_eq!(o.backend, "obvhs");
    let (a, b) = (&e.receivers["desk"], &o.receivers["desk"]);
    for k in 0..a.values.len() {
        let tol = 0.5 * a.sigma[k].max(b.sigma[k]);
        assert!(
            (a.values[k] - b.values[k]).abs() <= tol,
            "cell {k}: {} vs {} (σ {})",
            a.values[k],
            b.values[k],
            a.sigma[k]
        );
    }
}

fn scaled_room(s: f64) -> String {
    let p = |x: f64, y: f64, z: f64| format!("[{}, {}, {}]", x * s, y * s, z * s);
    format!(
        r#"
        [materials.wall]
        reflectance = 0.5
        [[objects]]
        shape = "box"
        min = [0, 0, 0]
        max = {max}
        material = "wall"
        [[lights]]
        type = "point"
        position = {light}
        flux_lm = 1000
        [[receivers]]
        name = "floor"
        corner = {corner}
        u = {u}
        v = {v}
        cells = [8, 6]
        "#,
        max = p(4.0, 3.0, 2.5),
        light = p(1.3, 1.1, 1.7),
        corner = p(0.5, 0.5, 0.001),
        u = p(3.0, 0.0, 0.0),
        v = p(0.0, 2.0, 0.0),
    )
}

#[test]
fn tiny_and_huge_rooms_give_the_same_illuminance_after_scaling() {
    // The same room at 0.1 mm / 4 and at 10 km / 4 per metre: E scales as 1/s².
    let (small, large) = (1e-4 / 4.0, 1e4 / 4.0);
    let a = run_scene(&scaled_room(small), 200_000);
    let b = run_scene(&scaled_room(large), 200_000);
    let (ra, rb) = (&a.receivers["floor"], &b.receivers["floor"]);
    let z: Vec<f64> = (0..ra.values.len())
        .map(|k| {
            let (va, sa) = (ra.values[k] * small * small, ra.sigma[k] * small * small);
            let (vb, sb) = (rb.values[k] * large * large, rb.sigma[k] * large * large);
            (va - vb) / (sa * sa + sb * sb).sqrt()
        })
        .collect();
    // Same seed: the runs are correlated, so a sound result is well inside 1.
    assert!(rms(&z) < 1.0, "z RMS {}", rms(&z));
    let (ga, gb) = (
        a.global.mean_illuminance_lx * small * small,
        b.global.mean_illuminance_lx * large * large,
    );
    assert!(
        (ga - gb).abs() < 3.0 * a.global.mean_sigma_lx * small * small,
        "{ga} vs {gb}"
    );
    assert_eq!(
        a.photons_killed_by_bounce_cap + b.photons_killed_by_bounce_cap,
        0
    );
}

/// Every number of a summary, as JSON, is finite (serde_json writes NaN as null).
fn assert_all_finite(s: &luxtally::output::summary::Summary) {
    assert_finite_except(s, &[]);
}

/// [`assert_all_finite`], but keys whose path contains one of `unknown` may be null
/// (an unknown error); so may the keys null by design (`forecast`, `stop_reason`,
/// `target_unreachable`, the `upper_bound` of a cell that is not dark).
fn assert_finite_except(s: &luxtally::output::summary::Summary, unknown: &[&str]) {
    let json = serde_json::to_value(s).unwrap();
    walk(&json, "", unknown);
    fn walk(v: &serde_json::Value, path: &str, unknown: &[&str]) {
        match v {
            serde_json::Value::Number(n) => {
                assert!(n.as_f64().is_some_and(f64::is_finite), "{path}: {n}")
            }
            serde_json::Value::Array(a) => a
                .iter()
                .enumerate()
                .for_each(|(i, x)| walk(x, &format!("{path}[{i}]"), unknown)),
            serde_json::Value::Object(o) => o
                .iter()
                .for_each(|(k, x)| walk(x, &format!("{path}.{k}"), unknown)),
            serde_json::Value::Null
                if path != ".forecast"
                    && !path.ends_with("stop_reason")
                    && !path.ends_with("target_unreachable")
                    && !path.contains("upper_bound[")
                    && !unknown.iter().any(|u| path.contains(u)) =>
            {
                panic!("{path} is null")
            }
            _ => {}
        }
    }
}

#[test]
fn zero_flux_lights_give_zeros_not_nan() {
    let s = run_scene(
        r#"
        [materials.wall]
        reflectance = 0.5
        [[objects]]
        shape = "box"
        min = [0, 0, 0]
        max = [2, 2, 2]
        material = "wall"
        [[lights]]
        type = "point"
        position = [1, 1, 1]
        intensity_cd = 0
        [[receivers]]
        name = "r"
        corner = [0.5, 0.5, 0.5]
        u = [1, 0, 0]
        v = [0, 1, 0]
        cells = [2, 2]
        "#,
        10_000,
    );
    assert_eq!(s.total_flux_lm, 0.0);
    assert_eq!(s.receivers["r"].values, vec![0.0; 4]);
    assert_eq!(s.receivers["r"].sigma, vec![0.0; 4], "no light: exactly 0");
    assert_eq!(s.global.mean_illuminance_lx, 0.0);
    // U0 = Emin/Ē and g2 = Emin/Emax are 0/0 here: undefined, and said so.
    let f = &s.receivers["r"].figures;
    assert_eq!(
        (f.mean.value, f.mean.low, f.mean.high, f.min.high),
        (0.0, 0.0, 0.0, 0.0)
    );
    assert!(f.u0.value.is_nan() && f.g2.value.is_nan(), "{f:?}");
    assert!(f.note.contains("undefined"), "{}", f.note);
    assert_finite_except(&s, &[".figures.u0", ".figures.g2"]);
}

#[test]
fn scene_without_geometry_scores_only_its_receivers() {
    let s = run_scene(
        r#"
        [[lights]]
        type = "point"
        position = [0, 0, 1]
        intensity_cd = 100
        [[receivers]]
        name = "r"
        corner = [-0.5, -0.5, 0]
        u = [1, 0, 0]
        v = [0, 1, 0]
        cells = [2, 2]
        "#,
        100_000,
    );
    assert_eq!(s.global.triangles, 0);
    assert!(s.receivers["r"].mean > 0.0);
    assert_all_finite(&s);
}

#[test]
fn receiver_no_photon_reaches_reads_zero_with_unknown_error() {
    let s = run_scene(
        r#"
        [materials.black]
        reflectance = 0
        [[objects]]
        shape = "box"
        min = [0, 0, 0]
        max = [1, 1, 1]
        material = "black"
        [[lights]]
        type = "point"
        position = [0.5, 0.5, 0.5]
        intensity_cd = 10
        [[receivers]]
        name = "outside"
        corner = [3, 3, 3]
        u = [1, 0, 0]
        v = [0, 1, 0]
        cells = [3, 3]
        "#,
        50_000,
    );
    let r = &s.receivers["outside"];
    assert_eq!(r.values, vec![0.0; 9]);
    assert_eq!(r.hits, vec![0; 9]);
    assert!(r.sigma.iter().all(|x| x.is_nan()), "σ unknown, not 0");
    assert_eq!(r.unknown_cells, 9);
    assert!(r.rel_error.arithmetic.is_nan());
    // Only the unknown errors are null: σ, the receiver's mean error, the history of
    // the target's error and the intervals of its figures.
    assert_finite_except(
        &s,
        &[
            ".sigma",
            ".rel_error",
            ".rel_error_known_cells",
            ".history",
            "outside.figures",
        ],
    );
    let f = &s.receivers["outside"].figures;
    assert!(
        f.mean.low.is_nan() && f.min.low.is_nan() && !f.reliable,
        "{f:?}"
    );
}

#[test]
fn track_and_next_event_agree_on_every_office_desk_cell() {
    assert_estimators_agree(&office(), "desk", 10_000_000, 1_000_000);
}

#[test]
fn track_and_next_event_agree_beside_walls_and_through_glass() {
    // A floor receiver touching the walls (their lower parts are in its near zone), a
    // partly glossy wall (diffuse and mirror lobes at once) and a glass cube.
    let scene = common::scene(
        r#"
        [materials.wall]
        reflectance = 0.5
        [materials.satin]
        reflectance = 0.3
        specular_reflectance = 0.3
        [materials.glass]
        specular_transmittance = 0.95
        ior = 1.5
        [[objects]]
        shape = "box"
        min = [0, 0, 0]
        max = [2, 2, 2]
        material = "wall"
        [[objects]]
        shape = "rect"
        corner = [1.999, 0, 0]
        u = [0, 0, 2]
        v = [0, 2, 0]
        material = "satin"
        [[objects]]
        shape = "box"
        min = [0.3, 0.3, 0.4]
        max = [0.8, 0.8, 0.9]
        material = "glass"
        [[lights]]
        type = "point"
        position = [1.2, 1.1, 1.7]
        intensity_cd = 100
        [[receivers]]
        name = "floor"
        corner = [0, 0, 0.002]
        u = [2, 0, 0]
        v = [0, 2, 0]
        cells = [16, 16]
        "#,
    );
    assert_estimators_agree(&scene, "floor", 6_000_000, 1_500_000);
}

#[test]
fn auto_estimator_is_next_event_with_sampled_direct_light_everywhere() {
    let office = run_options(&office(), &options(&office(), 10_000, 2, Backend::Embree));
    assert_eq!(office.receivers["desk"].estimator, "next_event");
    let black = run_scene(
        r#"
        [materials.black]
        reflectance = 0
        [[objects]]
        shape = "rect"
        corner = [-1, -1, 0]
        u = [2, 0, 0]
        v = [0, 2, 0]
        material = "black"
        [[lights]]
        type = "point"
        position = [0, 0, 1]
        intensity_cd = 10
        [[receivers]]
        name = "r"
        corner = [-1, -1, 0.5]
        u = [2, 0, 0]
        v = [0, 2, 0]
        cells = [2, 2]
        "#,
        10_000,
    );
    // No diffuse path: the direct light is still sampled, not left to crossings.
    let r = &black.receivers["r"];
    assert_eq!(
        (
            r.estimator.as_str(),
            r.direct_estimator.as_str(),
            r.indirect_estimator.as_str()
        ),
        ("next_event", "sampled", "next_event")
    );
}

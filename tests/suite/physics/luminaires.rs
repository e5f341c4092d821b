//! Luminaires from photometric files as light sources (`type = "luminaire"`): flux,
//! illuminance against the interpolant's own intensities, orientation (aim,
//! rotate_deg), IES and EULUMDAT alike, far and near field of a large opening.

use crate::common;

use common::*;
use glam::DVec3;
use luxtally::photometry::{self, Photometry};
use luxtally::scene::{load, Estimator, Luminaire};
use std::path::{Path, PathBuf};

fn data(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/photometry")
        .join(name)
        .display()
        .to_string()
}

fn photometry_of(name: &str) -> Photometry {
    photometry::load(Path::new(&data(name))).expect("photometry loads")
}

/// A luminaire from `file` 2 m over a black plane, aimed down, with a 16 × 16 receiver
/// over [−2, 2]² lying on the plane.
fn over_black_plane(file: &str, extra: &str) -> String {
    format!(
        r#"
        [materials.black]
        reflectance = 0.0
        [[objects]]
        shape = "rect"
        corner = [-20, -20, 0]
        u = [40, 0, 0]
        v = [0, 40, 0]
        material = "black"
        [[lights]]
        type = "luminaire"
        file = "{file}"
        position = [0, 0, 2]
        {extra}
        [[receivers]]
        name = "floor"
        corner = [-2, -2, 0]
        u = [4, 0, 0]
        v = [0, 4, 0]
        cells = [16, 16]
        "#
    )
}

/// Exact cell means over the floor receiver of the point luminaire `p` at height 2 m
/// (scaled by `scale`): E = I(direction)·cos θ/d², the interpolant's own intensity.
fn point_luminaire_exact(p: &Photometry, scale: f64) -> impl Fn(usize, usize) -> f64 + '_ {
    move |i, j| {
        let w = 4.0 / 16.0;
        let (x0, y0) = (-2.0 + i as f64 * w, -2.0 + j as f64 * w);
        let e = |x: f64, y: f64| {
            let towards = DVec3::new(x, y, -2.0);
            let d2 = towards.length_squared();
            scale * p.intensity_toward_cd(towards) * 2.0 / (d2 * d2.sqrt())
        };
        // Sub-cells: the interpolant has kinks every 5°.
        subcell_average(e, x0, y0, w)
    }
}

#[test]
fn cosine_luminaire_over_a_plane_gives_its_interpolated_intensity_over_d_squared() {
    let p = photometry_of("cosine.ies");
    for estimator in [Estimator::NextEvent, Estimator::Track] {
        let photons = if estimator == Estimator::Track {
            4_000_000
        } else {
            200_000
        };
        let s = run_scene_with(
            &over_black_plane(&data("cosine.ies"), ""),
            photons,
            estimator,
        );
        assert!((s.total_flux_lm - p.flux_lm()).abs() < 1e-9 * p.flux_lm());
        assert_matches(
            &s.receivers["floor"],
            point_luminaire_exact(&p, 1.0),
            &format!("cosine luminaire, {estimator:?}"),
        );
    }
}

#[test]
fn multiplier_and_flux_rescale_the_file() {
    let p = photometry_of("cosine.ies");
    let s = run_scene(
        &over_black_plane(&data("cosine.ies"), "multiplier = 0.8"),
        100_000,
    );
    assert!((s.total_flux_lm - 0.8 * p.flux_lm()).abs() < 1e-9 * p.flux_lm());
    assert_matches(
        &s.receivers["floor"],
        point_luminaire_exact(&p, 0.8),
        "multiplier",
    );
    let s = run_scene(
        &over_black_plane(&data("cosine.ies"), "flux_lm = 1000\nmultiplier = 0.5"),
        1000,
    );
    assert!((s.total_flux_lm - 500.0).abs() < 1e-9);
}

#[test]
fn eulumdat_and_ies_of_the_same_photometry_give_the_same_illuminance() {
    let ies = run_scene(&over_black_plane(&data("cosine.ies"), ""), 100_000);
    let ldt = run_scene(&over_black_plane(&data("cosine.ldt"), ""), 100_000);
    let (a, b) = (&ies.receivers["floor"], &ldt.receivers["floor"]);
    for k in 0..a.values.len() {
        let sigma = libm::hypot(a.sigma[k], b.sigma[k]);
        assert!(
            (a.values[k] - b.values[k]).abs() <= 4.0 * sigma + 1e-9 * a.values[k],
            "cell {k}: {} vs {}",
            a.values[k],
            b.values[k]
        );
    }
}

/// A box room of black walls with a receiver on each wall, facing in, 0.1 m from it.
fn walls_room(height: f64, extra: &str) -> String {
    let wall = |name: &str, corner: [f64; 3], u: [f64; 3], v: [f64; 3]| {
        format!(
            "[[receivers]]\nname = \"{name}\"\ncorner = {corner:?}\nu = {u:?}\nv = {v:?}\ncells = [4, 4]\nestimator = \"track\"\n"
        )
    };
    format!(
        r#"
        [materials.black]
        reflectance = 0.0
        [[objects]]
        shape = "box"
        min = [-2, -2, 0]
        max = [2, 2, 4]
        material = "black"
        [[lights]]
        type = "luminaire"
        file = "{}"
        position = [0, 0, {height}]
        {extra}
        {}{}{}{}
        "#,
        data("lobe_c90.ies"),
        wall("plus_y", [-1.9, 1.9, 0.0], [3.8, 0.0, 0.0], [0.0, 0.0, 4.0]),
        wall(
            "minus_y",
            [-1.9, -1.9, 0.0],
            [0.0, 0.0, 4.0],
            [3.8, 0.0, 0.0]
        ),
        wall("plus_x", [1.9, -1.9, 0.0], [0.0, 0.0, 4.0], [0.0, 3.8, 0.0]),
        wall(
            "minus_x",
            [-1.9, -1.9, 0.0],
            [0.0, 3.8, 0.0],
            [0.0, 0.0, 4.0]
        ),
    )
}

fn lit_walls(height: f64, extra: &str) -> Vec<String> {
    let s = run_scene(&walls_room(height, extra), 50_000);
    let mut lit: Vec<String> = s
        .receivers
        .iter()
        .filter(|(_, r)| r.values.iter().any(|&v| v > 0.0))
        .map(|(name, _)| name.clone())
        .collect();
    lit.sort();
    lit
}

#[test]
fn a_lobe_in_the_c90_plane_lands_on_the_plus_y_wall_and_turns_with_rotate_deg() {
    assert_eq!(lit_walls(3.0, ""), vec!["plus_y"]);
    // C0 turned by 90° about the vertical: C90 now points to −x.
    assert_eq!(lit_walls(3.0, "rotate_deg = 90"), vec!["minus_x"]);
    // Aimed up (a half turn about x): C90 points to −y, and the lobe goes up.
    assert_eq!(lit_walls(1.0, "aim = [0, 0, 1]"), vec!["minus_y"]);
}

#[test]
fn far_from_a_large_opening_it_is_a_point_near_it_the_exact_opening_integral() {
    // opening_metres.ies: the cosine table with a 2 × 4 m rectangular opening.
    let p = photometry_of("opening_metres.ies");
    let (length, width) = match p.opening {
        photometry::Opening::Rectangle { length_m, width_m } => (length_m, width_m),
        other => panic!("{other:?}"),
    };
    // Illuminance at (x, 0, 0) of a horizontal plane under the opening at height h: the
    // mean over the opening of I(direction)·cos θ/d² (every point of the opening emits
    // the file's distribution, I/A per unit area).
    let exact_near = |x: f64, h: f64| {
        let n = 64;
        let mut sum = 0.0;
        for a in 0..n {
            for b in 0..n {
                let q = DVec3::new(
                    ((a as f64 + 0.5) / n as f64 - 0.5) * length,
                    ((b as f64 + 0.5) / n as f64 - 0.5) * width,
                    h,
                );
                let towards = DVec3::new(x, 0.0, 0.0) - q;
                let d2 = towards.length_squared();
                sum += p.intensity_toward_cd(towards) * h / (d2 * d2.sqrt());
            }
        }
        sum / (n * n) as f64
    };
    let point = |x: f64, h: f64| {
        let towards = DVec3::new(x, 0.0, -h);
        let d2 = towards.length_squared();
        p.intensity_toward_cd(towards) * h / (d2 * d2.sqrt())
    };
    for (h, far) in [(1.0, false), (50.0, true)] {
        let toml = format!(
            r#"
            [[lights]]
            type = "luminaire"
            file = "{}"
            position = [0, 0, {h}]
            [[receivers]]
            name = "spot"
            corner = [-0.01, -0.01, 0]
            u = [0.02, 0, 0]
            v = [0, 0.02, 0]
            cells = [1, 1]
            "#,
            data("opening_metres.ies")
        );
        let s = run_scene(&toml, 200_000);
        let r = &s.receivers["spot"];
        let (v, sigma) = (r.values[0], r.sigma[0]);
        let (near, pt) = (exact_near(0.0, h), point(0.0, h));
        eprintln!("h = {h}: {v} ± {sigma}, exact {near}, point {pt}");
        assert!(
            (v - near).abs() < 4.0 * sigma,
            "h = {h}: {v} vs exact {near}"
        );
        if far {
            // The inverse-square law's own error: O((size/distance)²).
            let size = libm::hypot(length, width) / h;
            assert!((near - pt).abs() < size * size * pt, "far field is a point");
        } else {
            assert!(
                (near - pt).abs() > 20.0 * sigma,
                "near field is not a point"
            );
        }
    }
}

#[test]
fn the_bundled_luminaires_scene_lights_its_workplane_from_examp1() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/luminaires.toml");
    let scene = load(&path).expect("bundled scene loads");
    assert_eq!(scene.lights.len(), 6);
    let Some(l) = scene.lights[0].get::<Luminaire>() else {
        panic!("a luminaire")
    };
    assert!((l.flux_lm() - 5296.65).abs() < 0.01);
    let opts = options(&scene, 100_000, 2, luxtally::accel::Backend::Embree);
    let s = run_options(&scene, &opts);
    assert!((s.total_flux_lm - 6.0 * l.flux_lm()).abs() < 1e-6);
    let r = &s.receivers["workplane"];
    assert_eq!(r.unknown_cells, 0);
    assert!(r.mean > 100.0, "a lit workplane: {}", r.mean);
}

#[test]
fn bad_luminaire_entries_name_the_key() {
    let cases = [
        ("", "test.toml: lights[0].file: missing"),
        (
            "file = \"nowhere.ies\"\nposition = [0, 0, 1]",
            "nowhere.ies",
        ),
        (
            &format!("file = \"{}\"", data("cosine.ies")),
            "exactly one of `position` and `positions`",
        ),
        (
            &format!(
                "file = \"{}\"\nposition = [0, 0, 1]\naim = [0, 0, 0]",
                data("cosine.ies")
            ),
            "lights[0].aim: zero direction",
        ),
        (
            &format!(
                "file = \"{}\"\nposition = [0, 0, 1]\ncone_deg = 30",
                data("cosine.ies")
            ),
            "lights[0].cone_deg: does not apply",
        ),
        (
            &format!("file = \"{}\"\npositions = []", data("cosine.ies")),
            "lights[0].positions: is empty",
        ),
    ];
    for (body, expected) in cases {
        let toml = format!("[[lights]]\ntype = \"luminaire\"\n{body}\n");
        let e = luxtally::scene::load_str(&toml, Path::new("."), "test.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains(expected), "{e}");
        assert_eq!(e.lines().count(), 1, "{e}");
    }
}

#[test]
fn a_tilted_luminaire_takes_its_files_tilt_factor() {
    // tilt_include.ies: factors 0.9, 0.85, 0.8, 0.7 at 0, 30, 60, 90°; the table holds
    // the 0° output. Aimed sideways (tilt 90°) it emits 0.7/0.9 of it; at 45°, 0.825/0.9.
    let p = photometry_of("tilt_include.ies");
    for (aim, factor) in [
        ("[0, 0, -1]", 1.0),
        ("[1, 0, 0]", 0.7 / 0.9),
        ("[1, 0, -1]", 0.825 / 0.9),
    ] {
        let s = run_scene(
            &over_black_plane(&data("tilt_include.ies"), &format!("aim = {aim}")),
            1000,
        );
        assert!(
            (s.total_flux_lm - factor * p.flux_lm()).abs() < 1e-9 * p.flux_lm(),
            "aim {aim}: {} vs {}",
            s.total_flux_lm,
            factor * p.flux_lm()
        );
    }
}

/// A maintenance factor scales a luminaire's flux and every value it gives: its own
/// (a number, or the product of CIE 97's parts) over the scene's, which applies to the
/// luminaires without one; the summary says which each light carries.
#[test]
fn maintenance_factors_give_maintained_values() {
    let file = data("cosine.ies");
    let p = photometry_of("cosine.ies");
    let initial = run_scene(&over_black_plane(&file, ""), 20_000);
    let own = run_scene(
        &over_black_plane(&file, "maintenance_factor = {llmf = 0.9, lmf = 0.8}"),
        20_000,
    );
    let scene_wide = run_scene(
        &format!("maintenance_factor = 0.72\n{}", over_black_plane(&file, "")),
        20_000,
    );
    for s in [&own, &scene_wide] {
        assert!((s.total_flux_lm - 0.72 * p.flux_lm()).abs() < 1e-9 * p.flux_lm());
        assert!((s.lights[0].maintenance_factor - 0.72).abs() < 1e-15);
        assert_matches(
            &s.receivers["floor"],
            point_luminaire_exact(&p, 0.72),
            "maintained",
        );
    }
    assert_eq!(initial.lights[0].maintenance_factor, 1.0);
    for (a, b) in initial.receivers["floor"]
        .values
        .iter()
        .zip(&own.receivers["floor"].values)
    {
        assert!((0.72 * a - b).abs() <= 1e-12 * a.abs(), "{a} × 0.72 ≠ {b}");
    }
    let bad = |extra: &str| {
        let text = over_black_plane(&file, extra);
        luxtally::scene::load_str(&text, Path::new("."), "test.toml")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    assert!(
        bad("maintenance_factor = 1.2").contains("lights[0].maintenance_factor: must be in (0, 1]")
    );
    assert!(bad("maintenance_factor = {lsf = 0}").contains("lights[0].maintenance_factor.lsf"));
    assert!(bad("maintenance_factor = \"high\"").contains("lights[0].maintenance_factor"));
    let scene_wide = luxtally::scene::load_str(
        &format!("maintenance_factor = 0\n{}", over_black_plane(&file, "")),
        Path::new("."),
        "test.toml",
    );
    let message = scene_wide.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(
        message.contains("test.toml: maintenance_factor: must be in (0, 1]"),
        "{message}"
    );
}

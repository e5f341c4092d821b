//! Statistics at the extremes (issue 24): the light's level changes no relative error,
//! VOV or verdict; the cells' central moments match a high-precision recomputation from
//! the per-replicate scores; cells nothing reaches are dark with a bound, and targets
//! that cannot be met say so.

use crate::common;

use common::*;
use luxtally::stats::CellStatus;

/// A 1 × 1 m receiver of 40 × 40 cells 0.1 mm over a grey floor, a point source of
/// `intensity` cd 2 m above it and a grey ceiling above that: sampled direct light with a
/// relative σ of about 10⁻⁴, and photon connections from the floor and ceiling.
fn plane(intensity: f64) -> String {
    format!(
        r#"
        [materials.grey]
        reflectance = 0.5
        [[objects]]
        shape = "rect"
        corner = [-5, -5, 0]
        u = [10, 0, 0]
        v = [0, 10, 0]
        material = "grey"
        [[objects]]
        shape = "rect"
        corner = [-5, -5, 3]
        u = [0, 10, 0]
        v = [10, 0, 0]
        material = "grey"
        [[lights]]
        type = "point"
        position = [0.1, 0.2, 2]
        intensity_cd = {intensity:e}
        [[receivers]]
        name = "plane"
        corner = [-0.5, -0.5, 0.0001]
        u = [1, 0, 0]
        v = [0, 1, 0]
        cells = [40, 40]
        "#
    )
}

/// Options of a run of `s` on 2 threads with an error target, and a photon budget
/// other than the scene's where `photons` says so.
fn with_target(
    s: &luxtally::scene::Scene,
    target_error: f64,
    photons: Option<u64>,
) -> luxtally::run::RunOptions {
    let mut opts = luxtally::run::RunOptions::from_scene(s);
    opts.stop.target_error = Some(target_error);
    opts.stop.photons = photons.or(opts.stop.photons);
    opts.threads = 2;
    opts
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    a == b || (a - b).abs() <= rel * a.abs().max(b.abs())
}

#[test]
fn relative_errors_vovs_and_verdicts_do_not_depend_on_the_lights_level() {
    let reference = run_scene(&plane(1.0), 20_000);
    let r0 = &reference.receivers["plane"];
    assert!(
        r0.sigma.iter().all(|s| *s > 0.0),
        "every cell's error known"
    );
    for intensity in [1e-30, 1e-10, 1e10, 1e30, 1e160, 1e200] {
        let s = run_scene(&plane(intensity), 20_000);
        let r = &s.receivers["plane"];
        for k in 0..r.values.len() {
            let what = format!("{intensity:e} cd, cell {k}");
            assert!(
                close(r.values[k] / intensity, r0.values[k], 1e-12),
                "{what}: value"
            );
            let rel = |r: &luxtally::output::summary::ReceiverSummary| r.sigma[k] / r.values[k];
            assert!(
                close(rel(r), rel(r0), 1e-9),
                "{what}: σ/value {} vs {}",
                rel(r),
                rel(r0)
            );
            assert!(
                close(r.vov[k], r0.vov[k], 1e-9),
                "{what}: VOV {} vs {}",
                r.vov[k],
                r0.vov[k]
            );
            assert!(close(r.dof[k], r0.dof[k], 1e-9), "{what}: dof");
            assert_eq!(r.status[k], r0.status[k], "{what}: status");
        }
        assert!(
            close(r.max_vov, r0.max_vov, 1e-9) && r.max_vov > 0.0,
            "max VOV"
        );
        assert!(close(r.rel_error.quadratic, r0.rel_error.quadratic, 1e-9));
        assert!(close(s.reliability.vov, reference.reliability.vov, 1e-9));
        let map = |s: &luxtally::output::summary::Summary| s.global.rel_error.quadratic;
        assert!(close(map(&s), map(&reference), 1e-9), "scene map's σ_rel");
        assert!(close(r.fom, r0.fom, 1.0) && r.fom > 0.0, "FOM known");
        let g = |s: &luxtally::output::summary::Summary| {
            s.global.mean_sigma_lx / s.global.mean_illuminance_lx
        };
        assert!(close(g(&s), g(&reference), 1e-12), "global σ_rel");
    }
}

#[test]
fn a_flux_beyond_f64_is_refused_in_one_line() {
    let dir = tempdir("extreme_flux");
    let scene = dir.join("s.toml");
    std::fs::write(&scene, plane(1e308)).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--photons",
            "1000",
            "--quiet",
        ])
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("lights") && err.contains("flux"), "{err}");
    assert!(
        err.contains(&scene.display().to_string()),
        "names the file: {err}"
    );
}

fn tempdir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("luxtally_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Double-double sums (Dekker, Knuth's two-sum): about 32 digits.
#[derive(Clone, Copy, Default)]
struct DoubleDouble(f64, f64);

impl DoubleDouble {
    fn add(self, x: f64) -> DoubleDouble {
        let s = self.0 + x;
        let v = s - self.0;
        let e = (self.0 - (s - v)) + (x - v);
        let lo = self.1 + e;
        let hi = s + lo;
        DoubleDouble(hi, lo - (hi - s))
    }
}

#[test]
fn cell_moments_match_a_high_precision_recomputation_from_the_replicates() {
    // The direct light's replicates of every cell, drawn one at a time into cells of
    // their own (the same draws: replicate r of cell c depends on (seed, c, r) alone),
    // give the per-replicate scores; their central moments in double-double against the
    // cells' moments accumulated by the run's code, at a relative σ of about 10⁻⁴.
    use luxtally::tally::{CellSums, ReceiverGrid};
    use luxtally::trace::emit::Emitters;
    let scene = scene(&plane(1000.0));
    let emitters = Emitters::new(&scene);
    let grid = ReceiverGrid::new(
        &scene.receivers[0],
        scene.geometry.origin,
        0,
        luxtally::scene::Estimator::NextEvent,
    );
    let caster = luxtally::accel::build(luxtally::accel::Backend::Embree, &scene.geometry)
        .expect("backend builds");
    let direct = luxtally::trace::direct::DirectLight {
        emitters: &emitters,
        shadows: &luxtally::trace::shadow::ShadowCaster::new(&scene, caster.as_ref()),
        slack: 1e-6,
        seed: 3,
        reflectors: None,
        qmc: false,
    };
    let sides = direct.cell_sides(&grid, None);
    let replicates = 200u64;
    let mut together = vec![CellSums::default(); grid.cell_count()];
    direct.add_replicates(&grid, &sides, &mut together, 0, replicates);
    let mut scores = vec![Vec::new(); grid.cell_count()];
    for r in 0..replicates {
        let mut one = vec![CellSums::default(); grid.cell_count()];
        direct.add_replicates(&grid, &sides, &mut one, r, 1);
        for (k, c) in one.iter().enumerate() {
            scores[k].push(c.direct.mean);
        }
    }
    let mut worst_rel = 0.0f64;
    for (k, (c, y)) in together.iter().zip(&scores).enumerate() {
        let n = y.len() as f64;
        let mean = y.iter().fold(DoubleDouble::default(), |s, &v| s.add(v));
        let (mean_hi, mean_lo) = (mean.0 / n, mean.1 / n);
        let central = |p: i32| {
            y.iter()
                .fold(DoubleDouble::default(), |s, &v| {
                    // (v − mean) to double-double precision, then its power in f64:
                    // the deviation's own rounding is 10⁻¹⁶ of a 10⁻⁴ spread.
                    let d = (v - mean_hi) - mean_lo;
                    s.add(d.powi(p))
                })
                .0
        };
        let (m2, m3, m4) = (central(2), central(3), central(4));
        assert!(
            close(c.direct.mean, mean_hi + mean_lo, 1e-14),
            "cell {k}: mean"
        );
        assert!(
            close(c.direct.m2, m2, 1e-9),
            "cell {k}: M₂ {} vs {m2}",
            c.direct.m2
        );
        assert!(
            close(c.direct.m4, m4, 1e-8),
            "cell {k}: M₄ {} vs {m4}",
            c.direct.m4
        );
        // M₃ is a small difference of signed terms: compared on the scale of M₂^1.5.
        assert!(
            (c.direct.m3 - m3).abs() <= 1e-8 * libm::pow(m2, 1.5),
            "cell {k}: M₃"
        );
        let vov = m4 / (m2 * m2) - 1.0 / n;
        assert!(close(c.direct.vov(), vov, 1e-8), "cell {k}: VOV");
        worst_rel = worst_rel.max((m2 / (n - 1.0)).sqrt() / (mean_hi));
    }
    assert!(
        worst_rel < 1e-2,
        "replicates' spread {worst_rel}: a smooth cell"
    );
}

/// Two boxes standing on a floor under a lamp, a receiver over the whole floor: the
/// cells under the boxes see nothing.
const BOXES_ON_A_FLOOR: &str = r#"
    [materials.grey]
    reflectance = 0.5
    [[objects]]
    shape = "rect"
    corner = [-2, -2, 0]
    u = [4, 0, 0]
    v = [0, 4, 0]
    material = "grey"
    [[objects]]
    shape = "box"
    min = [-1.5, -1.5, 0]
    max = [-0.5, -0.5, 1]
    material = "grey"
    [[objects]]
    shape = "box"
    min = [0.5, 0.5, 0]
    max = [1.5, 1.5, 0.5]
    material = "grey"
    [[lights]]
    type = "point"
    position = [0, 0, 3]
    intensity_cd = 1000
    [[receivers]]
    name = "floor"
    corner = [-2, -2, 0.0001]
    u = [4, 0, 0]
    v = [0, 4, 0]
    cells = [16, 16]
"#;

#[test]
fn cells_nothing_reaches_are_dark_with_a_bound_and_the_target_is_met_on_the_lit_ones() {
    let s = scene(BOXES_ON_A_FLOOR);
    let summary = run_options(&s, &with_target(&s, 0.02, Some(50_000_000)));
    let r = &summary.receivers["floor"];
    assert_eq!(summary.stop_reason.as_deref(), Some("target_error"));
    // Cells wholly under a box (cells 2–5 and 10–13 on both axes) see nothing but at
    // the box's walls: those a cell in from the walls are dark. (A cell in a box's
    // shadow that no photon has reached yet is dark too, within the same bound.)
    assert!(r.dark_cells >= 2 * 4, "{:?}", r.status);
    for (k, status) in r.status.iter().enumerate() {
        let (i, j) = (k % 16, k / 16);
        let within = |lo: usize, margin: usize| {
            let range = lo + margin..lo + 4 - margin;
            range.contains(&i) && range.contains(&j)
        };
        if within(2, 1) || within(10, 1) {
            assert_eq!(*status, CellStatus::Dark, "cell ({i}, {j})");
        }
        match status {
            CellStatus::Dark => {
                assert_eq!(r.values[k], 0.0);
                assert!(r.sigma[k].is_nan());
                assert!(r.upper_bound[k] > 0.0 && r.upper_bound[k] == r.dark_upper_bound);
            }
            CellStatus::Unreliable => assert!(r.upper_bound[k] > r.values[k]),
            _ => assert!(r.upper_bound[k].is_nan()),
        }
    }
    // The bound is no larger than the target allows.
    let lit: Vec<f64> = r
        .values
        .iter()
        .zip(&r.status)
        .filter(|(_, s)| **s != CellStatus::Dark)
        .map(|(v, _)| *v)
        .collect();
    let quadratic = (lit.iter().map(|v| v * v).sum::<f64>() / lit.len() as f64).sqrt();
    assert!(
        r.dark_upper_bound <= 0.02 * quadratic,
        "{} vs {quadratic}",
        r.dark_upper_bound
    );
    assert!(r.rel_error_known_cells.quadratic <= 0.02);
    assert!(summary.target_unreachable.is_none());
}

#[test]
fn a_target_nothing_reaches_is_reported_unreachable_and_can_end_the_run() {
    // A receiver under an opaque floor: nothing ever scores there.
    let toml = r#"
        [materials.grey]
        reflectance = 0.5
        [[objects]]
        shape = "rect"
        corner = [-2, -2, 0]
        u = [4, 0, 0]
        v = [0, 4, 0]
        material = "grey"
        [[lights]]
        type = "point"
        position = [0, 0, 1]
        intensity_cd = 100
        [[receivers]]
        name = "below"
        corner = [-1, -1, -0.5]
        u = [2, 0, 0]
        v = [0, 2, 0]
        cells = [4, 4]
    "#;
    let s = scene(toml);
    let mut opts = with_target(&s, 0.05, Some(100_000_000));
    opts.stop.stop_if_unreachable = true;
    let summary = run_options(&s, &opts);
    assert_eq!(summary.stop_reason.as_deref(), Some("unreachable"));
    assert!(summary.photons_emitted < 10_000_000, "ended early");
    let why = summary.target_unreachable.expect("said why");
    assert!(why.contains("nothing has reached"), "{why}");
    assert_eq!(summary.receivers["below"].status[0], CellStatus::Unknown);
}

#[test]
fn a_target_beyond_the_photon_budget_is_reported_unreachable() {
    // 0.01 % on the plane needs far more than 200,000 photons.
    let s = scene(&plane(1000.0));
    let mut opts = with_target(&s, 1e-6, Some(400_000));
    let summary = run_options(&s, &opts);
    assert_eq!(summary.stop_reason.as_deref(), Some("photons"));
    let why = summary.target_unreachable.expect("said why");
    assert!(why.contains("more than the 400000 allowed"), "{why}");
    opts.stop.stop_if_unreachable = true;
    let summary = run_options(&s, &opts);
    assert_eq!(summary.stop_reason.as_deref(), Some("unreachable"));
    assert!(summary.photons_emitted < 400_000);
}

#[test]
fn the_bundled_cornell_floor_meets_one_percent_with_its_dark_cells_counted() {
    // The floor receiver covers the boxes' footprints: those cells stay dark, and the
    // target is met on the cells that carry light, the dark ones within their bound.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.toml");
    let s = luxtally::scene::load(&path).expect("cornell loads");
    // `luxtally run scenes/cornell.toml --target-error 0.01`: the scene's own budget.
    let summary = run_options(&s, &with_target(&s, 0.01, None));
    assert_eq!(summary.stop_reason.as_deref(), Some("target_error"));
    let r = &summary.receivers["floor"];
    assert!(r.dark_cells > 100, "{} dark cells", r.dark_cells);
    assert!(r.dark_upper_bound > 0.0 && r.dark_upper_bound < 0.01 * r.mean);
    assert!(summary.target_unreachable.is_none());
}

//! Shared by the integration tests: run a scene given as TOML text, exact reference
//! formulas, and z-score statistics.
#![allow(dead_code)]

use luxtally::accel::Backend;
use luxtally::output::summary::{self, ReceiverSummary, Summary};
use luxtally::run::{run, RunOptions};
use luxtally::scene::{load_str, Estimator, Scene};
use std::path::Path;
use std::sync::atomic::AtomicBool;

pub fn scene(toml: &str) -> Scene {
    load_str(toml, Path::new("."), "test.toml").expect("test scene loads")
}

pub fn options(scene: &Scene, photons: u64, threads: usize, backend: Backend) -> RunOptions {
    RunOptions {
        threads,
        backend,
        ..RunOptions::with_photons(scene, photons)
    }
}

/// Runs `options` on `scene` and returns its summary.
pub fn run_options(scene: &Scene, options: &RunOptions) -> Summary {
    let result = run(scene, options, &AtomicBool::new(false), &mut ()).expect("run succeeds");
    summary::build(&result.state(scene, options))
}

/// Runs `photons` photons through the scene on 2 threads with Embree.
pub fn run_scene(toml: &str, photons: u64) -> Summary {
    let s = scene(toml);
    run_options(&s, &options(&s, photons, 2, Backend::Embree))
}

/// [`run_scene`] under randomised QMC (`run --qmc`), `photons` rounded up to whole
/// chunks as QMC runs need.
pub fn run_scene_qmc(toml: &str, photons: u64) -> Summary {
    let s = scene(toml);
    let chunk = luxtally::trace::CHUNK_PHOTONS;
    let opts = RunOptions {
        qmc: true,
        ..options(&s, photons.div_ceil(chunk) * chunk, 2, Backend::Embree)
    };
    run_options(&s, &opts)
}

/// [`run_scene`] with every receiver scored by `estimator`.
pub fn run_scene_with(toml: &str, photons: u64, estimator: Estimator) -> Summary {
    let s = scene(toml);
    let opts = RunOptions {
        estimator: Some(estimator),
        ..options(&s, photons, 2, Backend::Embree)
    };
    run_options(&s, &opts)
}

/// Checks a receiver against exact cell values: every cell's error must be known and
/// its z-scores calibrated. Cells whose σ is below 1e-9 of the value (sampled direct
/// light that is the same in every replicate, e.g. a directional source on a plane)
/// must then be exact to 1e-9 instead.
pub fn assert_matches(r: &ReceiverSummary, exact: impl Fn(usize, usize) -> f64, what: &str) {
    let nu = r.cells[0] as usize;
    let mut z = Vec::new();
    for (k, (v, s)) in r.values.iter().zip(&r.sigma).enumerate() {
        let e = exact(k % nu, k / nu);
        assert!(
            !s.is_nan(),
            "{what}: cell {k} has no error estimate (value {v})"
        );
        if *s <= 1e-9 * e.abs() {
            assert!(
                (v - e).abs() <= 1e-9 * e.abs(),
                "{what}: cell {k}: {v} vs {e} with σ {s}"
            );
        } else {
            z.push((v - e) / s);
        }
    }
    if z.len() >= 50 {
        assert_calibrated(&z, what);
    } else {
        let worst = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        eprintln!(
            "{what}: {} exact cells, worst z {worst:.2}",
            r.values.len() - z.len()
        );
        assert!(worst < 5.0, "{what}: a cell is {worst:.1}σ off");
    }
}

/// z-scores (value − exact) / σ of every cell, from `exact(i, j)`.
pub fn z_scores(r: &ReceiverSummary, exact: impl Fn(usize, usize) -> f64) -> Vec<f64> {
    let nu = r.cells[0] as usize;
    r.values
        .iter()
        .zip(&r.sigma)
        .enumerate()
        .map(|(k, (v, s))| {
            assert!(
                *s > 0.0,
                "cell {k} has no error estimate (value {v}, σ {s})"
            );
            (v - exact(k % nu, k / nu)) / s
        })
        .collect()
}

pub fn rms(z: &[f64]) -> f64 {
    (z.iter().map(|x| x * x).sum::<f64>() / z.len() as f64).sqrt()
}

/// The z-scores of a calibrated estimate: RMS within [0.85, 1.2] (the issue's bound; for
/// K ≥ 200 cells the RMS of unit normals is 1 ± 0.05) and no cell beyond 5σ.
pub fn assert_calibrated(z: &[f64], what: &str) {
    let r = rms(z);
    let worst = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    eprintln!(
        "{what}: z RMS {r:.3}, worst {worst:.2} over {} cells",
        z.len()
    );
    assert!(
        (0.85..=1.2).contains(&r),
        "{what}: z-score RMS {r:.3} over {} cells",
        z.len()
    );
    assert!(worst < 5.0, "{what}: a cell is {worst:.1}σ off");
}

/// ∫∫ h / (h² + x² + y²)^{3/2} dx dy over [0, x] × [0, y]: the solid angle of that
/// rectangle seen from height h above its corner.
pub fn corner_solid_angle(x: f64, y: f64, h: f64) -> f64 {
    libm::atan(x * y / (h * (h * h + x * x + y * y).sqrt()))
}

/// Exact mean illuminance over the rectangle [x0, x1] × [y0, y1] of a plane at distance h
/// from an isotropic point source of `intensity_cd` above the plane's origin.
pub fn point_source_cell_lx(intensity_cd: f64, h: f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let f = |x: f64, y: f64| corner_solid_angle(x, y, h);
    let omega = f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0);
    intensity_cd * omega / ((x1 - x0) * (y1 - y0))
}

/// Configuration factor from a point to a parallel a × b rectangle at distance h, one
/// of whose corners is straight above the point (signed a, b allowed).
pub fn parallel_corner_factor(a: f64, b: f64, h: f64) -> f64 {
    let (a, b) = (a / h, b / h);
    let (ra, rb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
    (a / ra * libm::atan(b / ra) + b / rb * libm::atan(a / rb)) / (2.0 * std::f64::consts::PI)
}

/// Gauss–Legendre nodes and weights on [0, 1], 8 points: exact for the smooth integrands
/// here to far below any σ.
pub fn gauss8() -> [(f64, f64); 8] {
    const X: [f64; 4] = [
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_3,
    ];
    const W: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    let mut out = [(0.0, 0.0); 8];
    for k in 0..4 {
        out[2 * k] = (0.5 - 0.5 * X[k], 0.5 * W[k]);
        out[2 * k + 1] = (0.5 + 0.5 * X[k], 0.5 * W[k]);
    }
    out
}

/// Mean of f over [x0, x1] × [y0, y1] by 8 × 8 Gauss–Legendre.
pub fn cell_average(f: impl Fn(f64, f64) -> f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let g = gauss8();
    let mut sum = 0.0;
    for (sx, wx) in g {
        for (sy, wy) in g {
            sum += wx * wy * f(x0 + sx * (x1 - x0), y0 + sy * (y1 - y0));
        }
    }
    sum
}

/// A luminance meter of 16 × 16 cells just above a 40 m grey floor (ρ = 0.6), 2 m under
/// a 1000 cd point source: L = ρE/π, cells in the near zone of the floor few photons
/// reach (tests/suite/physics/physics.rs, tests/suite/physics/calibration.rs).
pub const NEAR_ZONE_METER: &str = r#"
    [materials.floor]
    reflectance = 0.6
    [[objects]]
    shape = "rect"
    corner = [-20, -20, 0]
    u = [40, 0, 0]
    v = [0, 40, 0]
    material = "floor"
    [[lights]]
    type = "point"
    position = [0, 0, 2]
    intensity_cd = 1000
    [[receivers]]
    name = "meter"
    corner = [-0.5, -0.5, 0.0001]
    u = [1, 0, 0]
    v = [0, 1, 0]
    cells = [16, 16]
    quantity = "luminance"
    view_direction = [0, 0, -1]
    half_angle_deg = 30
"#;

/// A black 20 m × 20 m floor centred on the origin at z = 0: the start of the scenes
/// whose receivers see only the direct light of their source.
pub const BLACK_FLOOR: &str = r#"
    [materials.black]
    reflectance = 0.0
    [[objects]]
    shape = "rect"
    corner = [-10, -10, 0]
    u = [20, 0, 0]
    v = [0, 20, 0]
    material = "black"
"#;

/// A receiver "r" of 16 × 16 cells over [−1, 1]², 0.1 mm above a floor at z = 0 (it
/// reads the floor's incident light, not light the floor reflects).
pub const FLOOR_RECEIVER: &str = r#"
    [[receivers]]
    name = "r"
    corner = [-1, -1, 0.0001]
    u = [2, 0, 0]
    v = [0, 2, 0]
    cells = [16, 16]
"#;

/// A spot of 2000 cd 2 m over [`BLACK_FLOOR`], aimed down, with a smooth profile from
/// `falloff_deg` 15 to `cone_deg` 30, and a 16 × 16 receiver over [−1.5, 1.5]² 0.1 mm
/// over the floor: the cone reaches the receiver's edge, so cells see the core, the ramp
/// and the dark. Exact cells: [`spot_cell_lx`].
pub fn spot_over_black_floor() -> String {
    format!(
        r#"{BLACK_FLOOR}
    [[lights]]
    type = "spot"
    position = [0, 0, 2]
    direction = [0, 0, -1]
    intensity_cd = 2000
    cone_deg = 30
    falloff_deg = 15
    [[receivers]]
    name = "r"
    corner = [-1.5, -1.5, 0.0001]
    u = [3, 0, 0]
    v = [0, 3, 0]
    cells = [16, 16]
"#
    )
}

/// Exact mean illuminance of cell (i, j) of [`spot_over_black_floor`]'s receiver: the cell
/// average of I(θ)·h/(h² + r²)^{3/2} with the profile's smoothstep between the cosines
/// of the falloff and cone angles.
pub fn spot_cell_lx(i: usize, j: usize) -> f64 {
    let (i0, h, cone, falloff) = (2000.0, 2.0 - 0.0001, 30.0f64, 15.0f64);
    let (cc, cf) = (
        libm::cos(cone.to_radians()),
        libm::cos(falloff.to_radians()),
    );
    let e = |x: f64, y: f64| {
        let d2 = h * h + x * x + y * y;
        let cos = h / d2.sqrt();
        let s = ((cos - cc) / (cf - cc)).clamp(0.0, 1.0);
        i0 * s * s * (3.0 - 2.0 * s) * h / libm::pow(d2, 1.5)
    };
    let w = 3.0 / 16.0;
    subcell_average(e, -1.5 + i as f64 * w, -1.5 + j as f64 * w, w)
}

/// Mean of f over the square [x0, x0 + w] × [y0, y0 + w] by 4 × 4 sub-squares of 8 × 8
/// Gauss–Legendre points each: for integrands with kinks or only C¹ edges inside the cell
/// (a spot's profile, an interpolated intensity table).
pub fn subcell_average(f: impl Fn(f64, f64) -> f64, x0: f64, y0: f64, w: f64) -> f64 {
    let q = w / 4.0;
    (0..16)
        .map(|k| {
            let (a, b) = (x0 + (k % 4) as f64 * q, y0 + (k / 4) as f64 * q);
            cell_average(&f, a, a + q, b, b + q)
        })
        .sum::<f64>()
        / 16.0
}

/// A 1000 cd point source 0.5 m over a 20 m × 20 m floor of the material `material` (its
/// `[materials.mirror]` lines), and a 16 × 16 receiver 1.5 m up facing down: an ideal
/// mirror shows it the source 1 m away plus its image 2 m away ([`mirror_image_cell_lx`]).
pub fn point_over_mirror(material: &str) -> String {
    format!(
        r#"
    [materials.mirror]
    {material}
    [[objects]]
    shape = "rect"
    corner = [-10, -10, 0]
    u = [20, 0, 0]
    v = [0, 20, 0]
    material = "mirror"
    [[lights]]
    type = "point"
    position = [0, 0, 0.5]
    intensity_cd = 1000
    [[receivers]]
    name = "r"
    corner = [-1, 1, 1.5]
    u = [2, 0, 0]
    v = [0, -2, 0]
    cells = [16, 16]
"#
    )
}

/// Exact mean illuminance of cell (i, j) of [`point_over_mirror`]'s receiver under an
/// ideal mirror: the source at 1 m plus its image at 2 m.
pub fn mirror_image_cell_lx(i: usize, j: usize) -> f64 {
    let w = 2.0 / 16.0;
    let x0 = -1.0 + i as f64 * w;
    let y1 = 1.0 - j as f64 * w;
    point_source_cell_lx(1000.0, 1.0, x0, x0 + w, y1 - w, y1)
        + point_source_cell_lx(1000.0, 2.0, x0, x0 + w, y1 - w, y1)
}

/// Exact luminance of cell (i, j) of [`NEAR_ZONE_METER`]: L = ρE/π over the cell.
pub fn near_zone_meter_cdm2(i: usize, j: usize) -> f64 {
    let (x0, y0) = (-0.5 + i as f64 / 16.0, -0.5 + j as f64 / 16.0);
    0.6 / std::f64::consts::PI
        * point_source_cell_lx(1000.0, 2.0, x0, x0 + 1.0 / 16.0, y0, y0 + 1.0 / 16.0)
}

/// A 100 cd point source at `source` inside a unit sphere (icosphere of `subdivisions`)
/// made of the material `name`, whose table holds the lines `material`: the integrating
/// sphere and the furnace, where every photon stays inside.
pub fn point_in_sphere(name: &str, material: &str, subdivisions: u32, source: [f64; 3]) -> String {
    let [x, y, z] = source;
    format!(
        r#"
    [materials.{name}]
    {material}
    [[objects]]
    shape = "sphere"
    center = [0, 0, 0]
    radius = 1.0
    subdivisions = {subdivisions}
    material = "{name}"
    [[lights]]
    type = "point"
    position = [{x}, {y}, {z}]
    intensity_cd = 100
"#
    )
}

/// A point source 2 m over [`BLACK_FLOOR`], a black occluder at 1 m whose straight edge is
/// slanted at [`SHADOW_ANGLE_DEG`] to the cells of [`FLOOR_RECEIVER`] (0.1 mm over the
/// floor), which is lit where n·(x, y) ≥ [`SHADOW_C`], n = (cos, sin) of the angle.
pub const SHADOW_ANGLE_DEG: f64 = 20.0;
pub const SHADOW_C: f64 = 0.23;

pub fn shadow_scene() -> String {
    let a = SHADOW_ANGLE_DEG.to_radians();
    let (n, t) = ((libm::cos(a), libm::sin(a)), (-libm::sin(a), libm::cos(a)));
    let c_o = SHADOW_C / 1.9999;
    let p0 = (n.0 * c_o - 10.0 * t.0, n.1 * c_o - 10.0 * t.1);
    format!(
        r#"{BLACK_FLOOR}
    [[objects]]
    shape = "rect"
    corner = [{}, {}, 1.0]
    u = [{}, {}, 0]
    v = [{}, {}, 0]
    material = "black"
    [[lights]]
    type = "point"
    position = [0, 0, 2]
    intensity_cd = 1000
{FLOOR_RECEIVER}"#,
        p0.0,
        p0.1,
        20.0 * t.0,
        20.0 * t.1,
        -10.0 * n.0,
        -10.0 * n.1
    )
}

/// A 1000 cd point source at (0.3, −0.2, 1) over [`BLACK_FLOOR`], a 4 × 4 receiver "r"
/// over [−0.5, 0.5]², 0.1 mm up, and `extra` TOML after it; with the receiver's exact
/// cell averages (index j·4 + i).
pub fn point_over_small_receiver(extra: &str) -> (String, Vec<f64>) {
    let toml = format!(
        r#"{BLACK_FLOOR}
        [[lights]]
        type = "point"
        position = [0.3, -0.2, 1.0]
        intensity_cd = 1000
        [[receivers]]
        name = "r"
        corner = [-0.5, -0.5, 0.0001]
        u = [1, 0, 0]
        v = [0, 1, 0]
        cells = [4, 4]
        {extra}"#
    );
    let h = 1.0 - 0.0001;
    let exact = (0..16)
        .map(|k| {
            let (x0, y0) = (
                -0.5 + (k % 4) as f64 * 0.25 - 0.3,
                -0.5 + (k / 4) as f64 * 0.25 + 0.2,
            );
            point_source_cell_lx(1000.0, h, x0, x0 + 0.25, y0, y0 + 0.25)
        })
        .collect();
    (toml, exact)
}

/// A small EPW (physics::perez, io::weather): LOCATION, 7 more header lines, `days` × 24
/// records from 1 January with a simple daily course of DNI/DHI.
pub fn epw(location: &str, days: usize) -> String {
    let mut t = format!(
        "{location}\nDESIGN CONDITIONS,0\nTYPICAL/EXTREME PERIODS,0\nGROUND TEMPERATURES,0\n\
                         HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\nCOMMENTS 1,test\nCOMMENTS 2,test\n\
                         DATA PERIODS,1,1,Data,Sunday, 1/ 1,{:>2}/{:>2}\n",
        1, days
    );
    for d in 1..=days {
        for h in 1..=24 {
            let up = (8..=16).contains(&h);
            let (dni, dhi) = if up { (100 * (h - 7), 50 + h) } else { (0, 0) };
            t += &format!(
                "2026,1,{d},{h},60,?9?9?9?9E0?9?9?9*9*9?9*9*9*9*9*9*9*9*9*9*_*9*9*9*9*9,2.0,-1.5,80,101325,0,0,300,\
                 {},{dni},{dhi},{},{},{},9999,180,3.0,5,5,20.0,77777,9,999999999,10,0.1,0,88,0.2,0,0\n",
                dni / 2 + dhi,
                100 * (dni / 2 + dhi),
                100 * dni,
                110 * dhi
            );
        }
    }
    t
}

pub const BERLIN: &str = "LOCATION,Berlin,BE,DEU,test,103840,52.47,13.40,1.0,49.0";

/// The cross-check that no path is missed or counted twice: the analog estimator and
/// next-event estimation (deterministic direct light, connections, near-zone and
/// specular crossings) agree cell by cell within their combined σ.
pub fn assert_estimators_agree(
    scene: &luxtally::scene::Scene,
    receiver: &str,
    track_photons: u64,
    next_event_photons: u64,
) {
    let with = |estimator, photons| RunOptions {
        estimator: Some(estimator),
        ..options(scene, photons, 2, Backend::Embree)
    };
    let track = run_options(scene, &with(Estimator::Track, track_photons));
    let next = run_options(scene, &with(Estimator::NextEvent, next_event_photons));
    let (a, b) = (&track.receivers[receiver], &next.receivers[receiver]);
    assert_eq!(
        (a.estimator.as_str(), b.estimator.as_str()),
        ("track", "next_event")
    );
    let z: Vec<f64> = (0..a.values.len())
        .map(|k| (a.values[k] - b.values[k]) / libm::hypot(a.sigma[k], b.sigma[k]))
        .collect();
    let r = rms(&z);
    eprintln!(
        "{receiver}: track vs next_event: z RMS {r:.3} over {} cells",
        z.len()
    );
    assert!((0.8..=1.25).contains(&r), "z RMS {r}");
}

//! The next-event receivers' sampled direct light against exact references where it is
//! hardest: the penumbra of a large Lambertian panel partly hidden by an obstacle (the
//! reference is Lambert's polygon formula over the part of the panel each point sees),
//! points beside an area source's plane at grazing angles, a spot's hard cone edge, a
//! black room lit only by an area source (what `auto` picks), and a receiver nothing
//! reaches (σ unknown, never converged).

use crate::common;

use common::*;
use glam::DVec3;
use luxtally::output::summary::Summary;
use luxtally::scene::Estimator;

const LUMINANCE: f64 = 1000.0;

/// Illuminance at `p` (receiving face normal `n`) from a Lambertian polygon of luminance
/// L fully in front of it: E = L/2 · |Σ θ_i n·(r_i × r_{i+1})/|r_i × r_{i+1}||.
fn polygon_lx(p: DVec3, n: DVec3, polygon: &[DVec3]) -> f64 {
    if polygon.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for (k, a) in polygon.iter().enumerate() {
        let b = polygon[(k + 1) % polygon.len()];
        let (ra, rb) = (*a - p, b - p);
        let cross = ra.cross(rb);
        let len = cross.length();
        if len > 0.0 {
            let angle = libm::acos(ra.normalize().dot(rb.normalize()).clamp(-1.0, 1.0));
            sum += angle * n.dot(cross) / len;
        }
    }
    0.5 * LUMINANCE * sum.abs()
}

/// Convex hull (counter-clockwise) of points in the plane, Andrew's monotone chain.
fn convex_hull(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The convex polygon `poly` clipped to the rectangle [x0, x1] × [y0, y1]
/// (Sutherland–Hodgman).
fn clip_to_rect(poly: Vec<(f64, f64)>, x0: f64, x1: f64, y0: f64, y1: f64) -> Vec<(f64, f64)> {
    // Each edge: inside test and intersection with the boundary line.
    let edges: [(usize, f64, bool); 4] =
        [(0, x0, true), (0, x1, false), (1, y0, true), (1, y1, false)];
    let mut out = poly;
    for (axis, bound, keep_above) in edges {
        let coord = |p: (f64, f64)| if axis == 0 { p.0 } else { p.1 };
        let inside = |p: (f64, f64)| (coord(p) >= bound) == keep_above || coord(p) == bound;
        let input = std::mem::take(&mut out);
        for (k, &cur) in input.iter().enumerate() {
            let prev = input[(k + input.len() - 1) % input.len()];
            let cut = |a: (f64, f64), b: (f64, f64)| {
                let t = (bound - coord(a)) / (coord(b) - coord(a));
                (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
            };
            match (inside(prev), inside(cur)) {
                (true, true) => out.push(cur),
                (true, false) => out.push(cut(prev, cur)),
                (false, true) => {
                    out.push(cut(prev, cur));
                    out.push(cur);
                }
                (false, false) => {}
            }
        }
        if out.is_empty() {
            break;
        }
    }
    out
}

/// The panel (z = 3, x ∈ [1, 5], y ∈ [1, 4], emitting down) and the box under it.
const PANEL: (f64, f64, f64, f64, f64) = (1.0, 5.0, 1.0, 4.0, 3.0);
const OBSTACLE: ([f64; 3], [f64; 3]) = ([2.5, 2.0, 1.8], [3.5, 3.0, 2.2]);

/// Illuminance at `p` (normal `n`) from the part of the panel the obstacle leaves
/// visible: the whole panel minus the panel ∩ the obstacle's silhouette projected from
/// `p` onto the panel's plane (a convex polygon).
fn panel_past_obstacle_lx(p: DVec3, n: DVec3) -> f64 {
    let (x0, x1, y0, y1, z) = PANEL;
    let at = |(x, y): (f64, f64)| DVec3::new(x, y, z);
    let panel = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(at);
    let (lo, hi) = OBSTACLE;
    let mut shadow = Vec::new();
    for k in 0..8 {
        let v = DVec3::new(
            if k & 1 == 0 { lo[0] } else { hi[0] },
            if k & 2 == 0 { lo[1] } else { hi[1] },
            if k & 4 == 0 { lo[2] } else { hi[2] },
        );
        let t = (z - p.z) / (v.z - p.z);
        let q = p + (v - p) * t;
        shadow.push((q.x, q.y));
    }
    let hidden = clip_to_rect(convex_hull(shadow), x0, x1, y0, y1);
    let hidden: Vec<DVec3> = hidden.into_iter().map(at).collect();
    polygon_lx(p, n, &panel) - polygon_lx(p, n, &hidden)
}

/// Mean of f over a cell by 4 × 4 sub-cells of 8 × 8 Gauss points: the penumbra is
/// only piecewise smooth.
fn fine_cell_average(f: impl Fn(f64, f64) -> f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let (qx, qy) = ((x1 - x0) / 4.0, (y1 - y0) / 4.0);
    (0..16)
        .map(|k| {
            let (a, b) = (x0 + (k % 4) as f64 * qx, y0 + (k / 4) as f64 * qy);
            cell_average(&f, a, a + qx, b, b + qy)
        })
        .sum::<f64>()
        / 16.0
}

const BLACK_ROOM_PANEL: &str = r#"
    [materials.black]
    reflectance = 0.0
    [[objects]]
    shape = "rect"
    corner = [-2, -2, 0]
    u = [12, 0, 0]
    v = [0, 12, 0]
    material = "black"
    [[objects]]
    shape = "box"
    min = [2.5, 2.0, 1.8]
    max = [3.5, 3.0, 2.2]
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
    [[receivers]]
    name = "wall"
    corner = [6.0, 0.0, 0.2]
    u = [0, 0, 1.4]
    v = [0, 5, 0]
    cells = [14, 20]
"#;

#[test]
fn panel_past_an_obstacle_matches_lamberts_formula_on_its_visible_part() {
    panel_past_an_obstacle(run_scene);
}

/// The same under `--qmc`, whose replicates are scrambled Sobol' patterns.
#[test]
fn qmc_panel_past_an_obstacle_matches_lamberts_formula_on_its_visible_part() {
    panel_past_an_obstacle(run_scene_qmc);
}

fn panel_past_an_obstacle(run: fn(&str, u64) -> Summary) {
    let s = run(BLACK_ROOM_PANEL, 1_000_000);
    for (name, corner, u, v, n) in [
        (
            "table",
            DVec3::new(0.0, 0.0, 1.5),
            DVec3::X * 6.0,
            DVec3::Y * 5.0,
            DVec3::Z,
        ),
        (
            "wall",
            DVec3::new(6.0, 0.0, 0.2),
            DVec3::Z * 1.4,
            DVec3::Y * 5.0,
            -DVec3::X,
        ),
    ] {
        let r = &s.receivers[name];
        assert_eq!(
            r.estimator, "next_event",
            "auto scores direct light by sampling"
        );
        assert_eq!(r.direct_estimator, "sampled");
        let [nu, nv] = r.cells.map(|c| c as usize);
        let point = |a: f64, b: f64| corner + u * a + v * b;
        let exact = |i: usize, j: usize| {
            fine_cell_average(
                |a, b| panel_past_obstacle_lx(point(a, b), n),
                i as f64 / nu as f64,
                (i + 1) as f64 / nu as f64,
                j as f64 / nv as f64,
                (j + 1) as f64 / nv as f64,
            )
        };
        // Penumbra cells: the obstacle hides part of the panel from some corners of
        // the cell and none from others. Lit cells: from none of them.
        let (mut penumbra, mut lit) = (0, 0);
        for k in 0..r.values.len() {
            let (i, j) = (k % nu, k / nu);
            let hidden = [(0, 0), (1, 0), (0, 1), (1, 1)]
                .iter()
                .filter(|&&(di, dj)| {
                    let p = point((i + di) as f64 / nu as f64, (j + dj) as f64 / nv as f64);
                    let (x0, x1, y0, y1, z) = PANEL;
                    let whole = polygon_lx(
                        p,
                        n,
                        &[(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| DVec3::new(x, y, z)),
                    );
                    panel_past_obstacle_lx(p, n) < whole * (1.0 - 1e-9)
                })
                .count();
            match hidden {
                0 => {
                    lit += 1;
                    let e = exact(i, j);
                    assert!(
                        r.sigma[k] <= 0.01 * e,
                        "{name}: lit cell {k}: σ {} is over 1 % of {e}",
                        r.sigma[k]
                    );
                }
                4 => {}
                _ => penumbra += 1,
            }
        }
        eprintln!("{name}: {penumbra} cells where the shadow's edge crosses, {lit} lit");
        assert!(
            penumbra >= 10 && lit >= 10,
            "{name}: the test must cross shadow edges"
        );
        assert_matches(r, exact, name);
    }
}

#[test]
fn points_beside_an_area_sources_plane_at_grazing_angles_are_calibrated() {
    beside_an_area_sources_plane(run_scene);
}

#[test]
fn qmc_points_beside_an_area_sources_plane_at_grazing_angles_are_calibrated() {
    beside_an_area_sources_plane(run_scene_qmc);
}

fn beside_an_area_sources_plane(run: fn(&str, u64) -> Summary) {
    // A vertical receiver facing +x just beside the panel's edge (x = 1), from 10 cm to
    // 1 mm below the panel's plane: light arrives at up to 89.96° from the source's normal.
    let s = run(
        r#"
        [[lights]]
        type = "area"
        corner = [1, 1, 3]
        u = [0, 3, 0]
        v = [4, 0, 0]
        luminance_cdm2 = 1000
        [[receivers]]
        name = "edge"
        corner = [0.99, 0.5, 2.9]
        u = [0, 4, 0]
        v = [0, 0, 0.099]
        cells = [32, 8]
        "#,
        400_000,
    );
    let r = &s.receivers["edge"];
    let (x0, x1, y0, y1, z) = PANEL;
    let panel = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| DVec3::new(x, y, z));
    let exact = |i: usize, j: usize| {
        fine_cell_average(
            |a, b| {
                polygon_lx(
                    DVec3::new(0.99, 0.5 + 4.0 * a, 2.9 + 0.099 * b),
                    DVec3::X,
                    &panel,
                )
            },
            i as f64 / 32.0,
            (i + 1) as f64 / 32.0,
            j as f64 / 8.0,
            (j + 1) as f64 / 8.0,
        )
    };
    assert_matches(r, exact, "grazing");
}

#[test]
fn spot_cone_edge_cells_are_calibrated_and_dark_cells_unknown() {
    spot_cone_edge(run_scene);
}

#[test]
fn qmc_spot_cone_edge_cells_are_calibrated_and_dark_cells_unknown() {
    spot_cone_edge(run_scene_qmc);
}

fn spot_cone_edge(run: fn(&str, u64) -> Summary) {
    // A hard-edged spot (no falloff): the cone's edge cuts cells anywhere.
    let s = run(
        r#"
        [[lights]]
        type = "spot"
        position = [0, 0, 2]
        direction = [0, 0, -1]
        intensity_cd = 2000
        cone_deg = 30
        [[receivers]]
        name = "r"
        corner = [-1.5, -1.5, 0]
        u = [3, 0, 0]
        v = [0, 3, 0]
        cells = [20, 20]
        "#,
        400_000,
    );
    let r = &s.receivers["r"];
    let cos_cone = libm::cos(30f64.to_radians());
    let e = |x: f64, y: f64| {
        let d2 = 4.0 + x * x + y * y;
        if 2.0 / d2.sqrt() >= cos_cone {
            2000.0 * 2.0 / libm::pow(d2, 1.5)
        } else {
            0.0
        }
    };
    let w = 3.0 / 20.0;
    // Midpoints of 256 × 256 sub-cells: the edge's error cancels to far below σ.
    let exact = |i: usize, j: usize| {
        let (x0, y0) = (-1.5 + i as f64 * w, -1.5 + j as f64 * w);
        let n = 256;
        (0..n * n)
            .map(|k| {
                e(
                    x0 + ((k % n) as f64 + 0.5) * w / n as f64,
                    y0 + ((k / n) as f64 + 0.5) * w / n as f64,
                )
            })
            .sum::<f64>()
            / (n * n) as f64
    };
    let (mut z, mut edge, mut dark) = (Vec::new(), 0, 0);
    let peak = exact(10, 10);
    for k in 0..r.values.len() {
        let x = exact(k % 20, k / 20);
        if x == 0.0 {
            dark += 1;
            assert_eq!(r.values[k], 0.0);
            assert!(
                r.sigma[k].is_nan(),
                "cell {k}: nothing scored, σ must be unknown"
            );
        } else {
            if x < 0.9 * peak * 0.5 {
                edge += 1;
            }
            z.push((r.values[k] - x) / r.sigma[k]);
        }
    }
    eprintln!("{edge} cone-edge cells, {dark} dark cells");
    assert!(edge >= 20 && dark >= 20);
    assert_calibrated(&z, "spot cone edge");
    assert!(r.unknown_cells == dark && r.rel_error.quadratic.is_nan());
}

#[test]
fn auto_lights_a_black_room_from_an_area_source_by_sampled_direct_light() {
    // The classic direct-illuminance test: small receivers in a black room under an area
    // source. Track scoring needs millions of photons per percent; auto must not use it.
    let room = r#"
        [materials.black]
        reflectance = 0.0
        [[objects]]
        shape = "box"
        min = [0, 0, 0]
        max = [6, 5, 3.01]
        material = "black"
        [[lights]]
        type = "area"
        corner = [1, 1, 3]
        u = [0, 3, 0]
        v = [4, 0, 0]
        luminance_cdm2 = 1000
        [[receivers]]
        name = "small"
        corner = [2.0, 2.0, 0.8]
        u = [0.2, 0, 0]
        v = [0, 0.2, 0]
        cells = [4, 4]
    "#;
    let s = run_scene(room, 200_000);
    let r = &s.receivers["small"];
    assert_eq!(
        (r.estimator.as_str(), r.direct_estimator.as_str()),
        ("next_event", "sampled")
    );
    let (x0, x1, y0, y1, z) = PANEL;
    let panel = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| DVec3::new(x, y, z));
    let exact = |i: usize, j: usize| {
        fine_cell_average(
            |a, b| {
                polygon_lx(
                    DVec3::new(2.0 + 0.2 * a, 2.0 + 0.2 * b, 0.8),
                    DVec3::Z,
                    &panel,
                )
            },
            i as f64 / 4.0,
            (i + 1) as f64 / 4.0,
            j as f64 / 4.0,
            (j + 1) as f64 / 4.0,
        )
    };
    for k in 0..16 {
        assert!(
            r.sigma[k] < 0.005 * r.values[k],
            "cell {k}: σ {}",
            r.sigma[k]
        );
    }
    assert_matches(r, exact, "black room");
    // The analog estimator on the same photons: far noisier.
    let t = run_scene_with(room, 200_000, Estimator::Track);
    assert!(t.receivers["small"].rel_error_known_cells.quadratic > 10.0 * r.rel_error.quadratic);
}

#[test]
fn a_receiver_nothing_reaches_has_unknown_error_and_never_converges() {
    let toml = r#"
        [materials.black]
        reflectance = 0.0
        [[objects]]
        shape = "rect"
        corner = [-5, -5, 0]
        u = [10, 0, 0]
        v = [0, 10, 0]
        material = "black"
        [[lights]]
        type = "point"
        position = [0, 0, 2]
        intensity_cd = 100
        [[receivers]]
        name = "below"
        corner = [-1, -1, -1]
        u = [2, 0, 0]
        v = [0, 2, 0]
        cells = [4, 4]
        [simulation]
        photons = 300000
        target_error = 0.05
    "#;
    let scene = scene(toml);
    let summary = run_options(&scene, &luxtally::run::RunOptions::from_scene(&scene));
    let r = &summary.receivers["below"];
    assert!(r.sigma.iter().all(|s| s.is_nan()), "σ unknown, not 0");
    assert_eq!(r.unknown_cells, 16);
    assert!(r.rel_error.quadratic.is_nan() && r.rel_error.arithmetic.is_nan());
    assert_eq!(
        summary.stop_reason.as_deref(),
        Some("photons"),
        "never converged"
    );
    let json = serde_json::to_value(&summary).unwrap();
    assert!(json["receivers"]["below"]["sigma"][0].is_null());
}

/// Meters 1 m under a large panel (L = 1000 cd/m²), looking up with a 5° cone that lies
/// wholly inside the panel's solid angle: each reads L exactly. The sampled direct light
/// finds the cone in 0.5 % of the panel's solid angle only (a replicate's 1,600 samples
/// cast about 7 shadow rays), so its σ is statistical and must be calibrated.
const METER_UNDER_A_PANEL: &str = r#"
    [[lights]]
    type = "area"
    corner = [-5, -5, 1]
    u = [0, 10, 0]
    v = [10, 0, 0]
    luminance_cdm2 = 1000
    [[receivers]]
    name = "meter"
    corner = [-1, -1, 0]
    u = [2, 0, 0]
    v = [0, 2, 0]
    cells = [10, 10]
    quantity = "luminance"
    view_direction = [0, 0, 1]
    half_angle_deg = 5
"#;

#[test]
fn a_luminance_meter_looking_at_an_area_source_reads_its_luminance() {
    let s = run_scene(METER_UNDER_A_PANEL, 20_000);
    let r = &s.receivers["meter"];
    assert_eq!(r.direct_estimator, "sampled");
    assert_matches(r, |_, _| LUMINANCE, "luminance meter under a panel");
}

/// The same meter at 200,000 photons: the direct light's work stays within the
/// schedule's share of the photons' (`direct::MAX_DIRECT_WORK_SHARE`, work = samples
/// drawn plus rays cast) plus the floor's replicates. Costed by shadow rays alone, whose
/// samples here rarely cast one, it drew 430,937 replicates (93 s); then about 2,000
/// (BENCHMARKS.md); now that each sample also casts a view ray for the reflected light
/// (`trace::reflected`), about 1,000, and the luminance still matches L.
#[test]
fn a_luminance_meter_under_a_panel_draws_replicates_in_bounded_work() {
    use luxtally::trace::direct::{FLOOR_MAX, MAX_DIRECT_WORK_SHARE};
    let s = run_scene(METER_UNDER_A_PANEL, 200_000);
    let samples = 100 * 16;
    let work = (s.direct_replicates * samples + s.direct_rays) as f64;
    let bound = MAX_DIRECT_WORK_SHARE * s.rays_traced as f64 + (FLOOR_MAX * samples) as f64;
    eprintln!(
        "meter, 200,000 photons: {} replicates, {} direct rays, work {work:.3e} ≤ {bound:.3e}",
        s.direct_replicates, s.direct_rays
    );
    assert!(work <= bound, "direct work {work:.3e} beyond {bound:.3e}");
    assert!(
        s.direct_replicates >= 500,
        "{} replicates",
        s.direct_replicates
    );
    assert_matches(
        &s.receivers["meter"],
        |_, _| LUMINANCE,
        "luminance meter under a panel, 200,000 photons",
    );
}

/// Points per side of each cell of the scene's first receiver in a direct-light
/// replicate (`DirectLight::cell_sides`, next_event), and the unrefined count.
fn cell_sides(toml: &str) -> (Vec<u32>, u32) {
    use luxtally::tally::ReceiverGrid;
    use luxtally::trace::direct::{points_per_side, DirectLight};
    use luxtally::trace::emit::Emitters;
    let scene = scene(toml);
    let emitters = Emitters::new(&scene);
    let r = &scene.receivers[0];
    let grid = ReceiverGrid::new(r, scene.geometry.origin, 0, Estimator::NextEvent);
    let caster = luxtally::accel::build(luxtally::accel::Backend::Embree, &scene.geometry)
        .expect("backend builds");
    let direct = DirectLight {
        emitters: &emitters,
        shadows: &luxtally::trace::shadow::ShadowCaster::new(&scene, caster.as_ref()),
        slack: 1e-6,
        seed: 1,
        reflectors: None,
        qmc: false,
    };
    (
        direct.cell_sides(&grid, None),
        points_per_side(grid.cell_count()),
    )
}

/// The spot of [`spot_over_black_floor`] (2 m above its 3 m × 3 m receiver of 16 × 16
/// cells, lit within 30° of its axis): cells the cone's edge clearly crosses are
/// refined, cells clearly inside or outside it are not.
#[test]
fn cells_a_cone_edge_crosses_are_refined_and_no_others() {
    use luxtally::trace::direct::EDGE_REFINEMENT;
    let (sides, base) = cell_sides(&spot_over_black_floor());
    // Radius on the receiver (1.9999 m under the spot) at which the axis angle is `deg`.
    let radius = |deg: f64| (2.0 - 0.0001) * libm::tan(deg.to_radians());
    let w = 3.0 / 16.0;
    let mut refined = 0;
    for (k, &side) in sides.iter().enumerate() {
        let (x0, y0) = (-1.5 + (k % 16) as f64 * w, -1.5 + (k / 16) as f64 * w);
        let nearest = |lo: f64| (0.0f64).clamp(lo, lo + w);
        let farthest = |lo: f64| lo.abs().max((lo + w).abs());
        let r_min = libm::hypot(nearest(x0), nearest(y0));
        let r_max = libm::hypot(farthest(x0), farthest(y0));
        if r_max < radius(29.0) || r_min > radius(31.0) {
            assert_eq!(
                side, base,
                "cell {k} lies wholly inside or outside the cone"
            );
        } else if r_min < radius(29.0) && r_max > radius(31.0) {
            assert_eq!(
                side,
                EDGE_REFINEMENT * base,
                "the cone's edge crosses cell {k}"
            );
        }
        refined += (side != base) as usize;
    }
    assert!(refined > 20, "{refined} cells refined");
}

/// The cells the occluder's shadow edge crosses ([`shadow_scene`]: a point light, the
/// edge slanted at 20° to the cells) take the refined pattern and no others: the shadow
/// rays at the cells' corners find the edge however little of a cell it clips. Also on
/// grids cut into several tiles of rows and of columns (`direct::TILE_CELLS`).
#[test]
fn cells_a_shadow_edge_crosses_are_refined_and_no_others() {
    use luxtally::trace::direct::EDGE_REFINEMENT;
    for [nu, nv] in [[16, 16], [40, 500], [20_000, 2]] {
        let toml = shadow_scene().replace("cells = [16, 16]", &format!("cells = [{nu}, {nv}]"));
        let (sides, base) = cell_sides(&toml);
        assert_eq!(sides.len(), nu * nv);
        let a = SHADOW_ANGLE_DEG.to_radians();
        let (wx, wy) = (2.0 / nu as f64, 2.0 / nv as f64);
        let mut refined = 0;
        for (k, &side) in sides.iter().enumerate() {
            let (x0, y0) = (-1.0 + (k % nu) as f64 * wx, -1.0 + (k / nu) as f64 * wy);
            // Signed distance of each corner past the edge (lit where positive).
            let past: Vec<f64> = [(0.0, 0.0), (wx, 0.0), (0.0, wy), (wx, wy)]
                .iter()
                .map(|(dx, dy)| libm::cos(a) * (x0 + dx) + libm::sin(a) * (y0 + dy) - SHADOW_C)
                .collect();
            let lo = past.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = past.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if lo > 1e-6 || hi < -1e-6 {
                assert_eq!(
                    side, base,
                    "{nu} × {nv}: cell {k} lies on one side of the edge"
                );
            } else if lo < -1e-6 && hi > 1e-6 {
                assert_eq!(
                    side,
                    EDGE_REFINEMENT * base,
                    "{nu} × {nv}: the edge crosses cell {k}"
                );
            }
            refined += (side != base) as usize;
        }
        assert!(
            refined >= nu.min(nv),
            "{nu} × {nv}: {refined} cells refined"
        );
    }
}

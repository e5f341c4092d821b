//! Photons through portals (docs/daylight.md, *Openings*): with `[[portals]]`, each
//! photon index of a sky or a sun also traces a photon through a point of a portal,
//! and the disk photons whose first segment crosses a portal leave the receivers to
//! them. Checked on photon-only (track) receivers, where nothing but photons scores:
//! the sky and the sun through a roof opening against their exact integrals, far
//! tighter than without the portal; a glazed opening whose pane lies in the portal's
//! plane; light reflected in from outside; portals split in two; and the scene map,
//! which stays the disk photons' alone.

use super::daylight::{roof_opening, run_with};
use crate::common;

use common::*;
use luxtally::scene::Estimator;

/// A `[[portals]]` entry over `[x0, x1] × [y0, y1]` in the roof of [`roof_opening`].
fn portal(x: [f64; 2], y: [f64; 2]) -> String {
    format!(
        "[[portals]]\ncorner = [{}, {}, 3]\nu = [{}, 0, 0]\nv = [0, {}, 0]\n",
        x[0],
        y[0],
        x[1] - x[0],
        y[1] - y[0]
    )
}

/// The whole opening [1.5, 2.5]².
fn opening_portal() -> String {
    portal([1.5, 2.5], [1.5, 2.5])
}

const UNIFORM_SKY: &str = "[[lights]]\ntype = \"sky\"\nmodel = \"uniform\"\n\
                           zenith_luminance_cdm2 = 1000\nground_reflectance = 0\n";

/// E on floor point (x, y) of [`roof_opening`] from a uniform sky of 1000 cd/m²: π·L·F,
/// F the configuration factor to the opening.
fn uniform_sky_e(x: f64, y: f64) -> f64 {
    let h = 3.0 - 0.001;
    let f = |a: f64, b: f64| parallel_corner_factor(a - x, b - y, h);
    std::f64::consts::PI * 1000.0 * (f(2.5, 2.5) - f(1.5, 2.5) - f(2.5, 1.5) + f(1.5, 1.5))
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The uniform sky through the roof opening, by photons only: every floor cell against
/// π·L·F, z-calibrated, for two seeds; the cells' median σ at least 4 times smaller
/// than without the portal at the same photons (the disk's πR² over the opening's
/// projected area is about 60 here); and the scene map, built by the disk photons
/// alone, the same bits with and without the portal.
#[test]
fn portal_photons_bring_the_sky_through_a_roof_opening() {
    let exact = |i: usize, j: usize| {
        let (x0, y0) = (i as f64 * 0.25, j as f64 * 0.25);
        cell_average(uniform_sky_e, x0, x0 + 0.25, y0, y0 + 0.25)
    };
    let without = run_with(
        &scene(&roof_opening(UNIFORM_SKY)),
        100_000,
        Estimator::Track,
        1,
    );
    let with_portal = scene(&(roof_opening(UNIFORM_SKY) + &opening_portal()));
    for seed in [1, 2] {
        let s = run_with(&with_portal, 100_000, Estimator::Track, seed);
        let floor = &s.receivers["floor"];
        assert_matches(floor, exact, "uniform sky by portal photons");
        if seed == 1 {
            let gain = median(&without.receivers["floor"].sigma) / median(&floor.sigma);
            eprintln!("portal photons: median σ {gain:.1} times smaller");
            assert!(gain > 4.0, "σ only {gain:.2} times smaller");
            let (a, b) = (&without.global, &s.global);
            assert_eq!(
                (a.mean_illuminance_lx, a.sigma_lx),
                (b.mean_illuminance_lx, b.sigma_lx),
                "the map is the disk photons'"
            );
        }
    }
}

/// Fraction of the sun's disc (angular radius α) seen from a point `s` metres inside a
/// straight edge `h` above it (negative `s`: outside).
fn disc_fraction(s: f64, h: f64) -> f64 {
    let alpha = luxtally::light::sun::SUN_HALF_ANGLE_DEG.to_radians();
    let d = libm::atan(s / h).clamp(-alpha, alpha) / alpha;
    (std::f64::consts::PI - libm::acos(d) + d * (1.0 - d * d).sqrt()) / std::f64::consts::PI
}

/// The sun at the zenith through the roof opening by photons only, through a portal:
/// E_n inside the patch and the penumbra along its edges, every cell's average within
/// its σ over the cells that the patch or its penumbra reach (the four corner cells,
/// where the penumbra is a few photons', left out), nothing elsewhere.
#[test]
fn portal_photons_draw_the_suns_patch() {
    let e_n = 80_000.0;
    let sun = format!(
        "[[lights]]\ntype = \"sun\"\ndirect_normal_lx = {e_n}\nsun_altitude_deg = 90\n\
         sun_azimuth_deg = 0\nground_reflectance = 0\n"
    );
    let s = run_with(
        &scene(&(roof_opening(&sun) + &opening_portal())),
        50_000,
        Estimator::Track,
        7,
    );
    let h = 3.0 - 0.001;
    // Away from the patch's corners the disc's visible part is the product of its
    // fractions past each edge; the 1.4 cm penumbra needs a fine rule over a cell.
    let across = |x0: f64| {
        let n = 20_000;
        (0..n)
            .map(|k| {
                let x = x0 + 0.25 * (k as f64 + 0.5) / n as f64;
                disc_fraction((x - 1.5).min(2.5 - x), h)
            })
            .sum::<f64>()
            / n as f64
    };
    let r = &s.receivers["floor"];
    let mut z = Vec::new();
    for (k, (v, sigma)) in r.values.iter().zip(&r.sigma).enumerate() {
        let (i, j) = (k % 16, k / 16);
        let exact = e_n * across(i as f64 * 0.25) * across(j as f64 * 0.25);
        let corner = [5, 10].contains(&i) && [5, 10].contains(&j);
        if exact == 0.0 {
            assert_eq!(*v, 0.0, "cell {k} lies outside the patch");
        } else if !corner {
            assert!(sigma > &0.0, "cell {k}: {v} ± {sigma} against {exact}");
            z.push((v - exact) / sigma);
        }
    }
    assert_eq!(z.len(), 32, "the patch and its penumbra reach 6 × 6 cells");
    let worst = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let rms = (z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64).sqrt();
    eprintln!("sun patch by portal photons: z RMS {rms:.2}, worst {worst:.2}: {z:.1?}");
    assert!(worst < 4.0, "a cell is {worst:.1}σ off");
    assert!(rms < 1.5, "z RMS {rms:.2} over {} cells", z.len());
}

/// The uniform sky through a glazed roof opening whose pane lies in the portal's plane,
/// by photons only: the floor's mean against ∫L·T(θ)·cos²/r² over the opening
/// (T the pane's transmittance at the incidence), within σ; a portal photon starts
/// just outside the pane and crosses it as a disk photon would.
#[test]
fn portal_photons_cross_a_pane_in_the_portals_plane() {
    let pane = "[materials.pane]\nglazing = [0.8]\n[[objects]]\nshape = \"rect\"\n\
                corner = [1.5, 1.5, 3]\nu = [1, 0, 0]\nv = [0, 1, 0]\nmaterial = \"pane\"\n";
    let text = (roof_opening(&format!("{UNIFORM_SKY}{pane}")) + &opening_portal())
        .replace("cells = [16, 16]", "cells = [1, 1]");
    let scene = scene(&text);
    let g = (scene.materials.iter())
        .find_map(|m| m.glazing.as_ref())
        .expect("the pane")
        .clone();
    let h = 3.0 - 0.001;
    let exact = cell_average(
        |x, y| {
            let e = |a: f64, b: f64| {
                let r2 = (a - x) * (a - x) + (b - y) * (b - y) + h * h;
                let cos = h / r2.sqrt();
                1000.0 * g.reflect_transmit(cos).1 * h * h / (r2 * r2)
            };
            cell_average(e, 1.5, 2.5, 1.5, 2.5)
        },
        0.0,
        4.0,
        0.0,
        4.0,
    );
    let s = run_with(&scene, 200_000, Estimator::Track, 6);
    let r = &s.receivers["floor"];
    let z = (r.values[0] - exact) / r.sigma[0];
    eprintln!(
        "glazed opening: {} ± {} against {exact}, z {z:.2}",
        r.values[0], r.sigma[0]
    );
    assert!(z.abs() < 4.0, "z {z}");
}

/// Of the wall standing on the roof of [`roof_opening`] (x = 2.6, 1 ≤ y ≤ 3,
/// 3 ≤ z ≤ 4.5), the part floor point (x, y) sees through the opening:
/// ∫ cos θ_p·cos θ_w / r² dA, by the midpoint rule on 100 × 75 points.
fn wall_through_opening(x: f64, y: f64) -> f64 {
    let (pz, n, m) = (0.001, 100, 75);
    let mut sum = 0.0;
    for i in 0..n {
        for k in 0..m {
            let (wy, wz) = (
                1.0 + 2.0 * (i as f64 + 0.5) / n as f64,
                3.0 + 1.5 * (k as f64 + 0.5) / m as f64,
            );
            let t = (3.0 - pz) / (wz - pz);
            let (x3, y3) = (x + t * (2.6 - x), y + t * (wy - y));
            if !((1.5..=2.5).contains(&x3) && (1.5..=2.5).contains(&y3)) {
                continue;
            }
            let r2 = (2.6 - x) * (2.6 - x) + (wy - y) * (wy - y) + (wz - pz) * (wz - pz);
            sum += (wz - pz) * (2.6 - x) / (r2 * r2);
        }
    }
    sum * 3.0 / (n * m) as f64
}

/// Light a white wall outside reflects into the opening: the disk photons that hit it
/// spawn photons through the portal. Under the uniform sky (L = 1000 cd/m², a black
/// ground) the wall's face towards the opening sees the sky's upper half and black
/// below, so it shines with L_w = ρ·(πL/2)/π = 400 cd/m², and hides the sky behind it:
/// a floor point gets π·L·F − (L − L_w)·∫ cos·cos/r² over the wall it sees through the
/// opening. With no portal, one, and the opening split between two (meeting along an
/// edge), the floor's four 2 m cells match it within σ, by photons only; with the
/// portal the σ is at least 4 times smaller than without, and the wall's own light in
/// the cell that sees it is over 8 of those σ.
#[test]
fn portal_photons_keep_light_reflected_in_from_outside() {
    let wall = "[materials.white]\nreflectance = 0.8\n[[objects]]\nshape = \"rect\"\n\
                corner = [2.6, 1.0, 3.0]\nu = [0, 0, 1.5]\nv = [0, 2, 0]\nmaterial = \"white\"\n";
    let text =
        roof_opening(&format!("{UNIFORM_SKY}{wall}")).replace("cells = [16, 16]", "cells = [2, 2]");
    let exact = |i: usize, j: usize| {
        let e = |x: f64, y: f64| uniform_sky_e(x, y) - 600.0 * wall_through_opening(x, y);
        let (x0, y0) = (i as f64 * 2.0, j as f64 * 2.0);
        cell_average(e, x0, x0 + 2.0, y0, y0 + 2.0)
    };
    let halves = portal([1.5, 2.0], [1.5, 2.5]) + &portal([2.0, 2.5], [1.5, 2.5]);
    let mut sigma = Vec::new();
    for (name, portals) in [
        ("no portal", String::new()),
        ("one portal", opening_portal()),
        ("two halves", halves),
    ] {
        let s = run_with(
            &scene(&(text.clone() + &portals)),
            400_000,
            Estimator::Track,
            8,
        );
        let r = &s.receivers["floor"];
        for k in 0..4 {
            let e = exact(k % 2, k / 2);
            let z = (r.values[k] - e) / r.sigma[k];
            eprintln!(
                "{name}, cell {k}: {} ± {} against {e}, z {z:.2}",
                r.values[k], r.sigma[k]
            );
            assert!(z.abs() < 4.0, "{name}, cell {k}: z {z}");
        }
        sigma.push(r.sigma[0]);
    }
    assert!(sigma[0] > 4.0 * sigma[1], "σ {sigma:?}");
    // The wall's own light in cell 0 is far above the portal runs' σ: losing it, or
    // counting it twice, would fail.
    let reflected = cell_average(
        |x, y| 400.0 * wall_through_opening(x, y),
        0.0,
        2.0,
        0.0,
        2.0,
    );
    eprintln!("the wall's light in cell 0: {reflected} lx");
    assert!(
        reflected > 8.0 * sigma[1],
        "{reflected} against σ {sigma:?}"
    );
}

//! The photon pass against analytic truth. Every tolerance comes from the σ the run
//! reports: per-cell z-scores must be calibrated (RMS within [0.85, 1.2]).

use crate::common;

use common::*;
use luxtally::scene::Estimator;
use std::f64::consts::PI;

fn point_source_over_black_plane_matches_inverse_square_cosine_law(
    estimator: Estimator,
    photons: u64,
) {
    let s = run_scene_with(
        &format!(
            r#"{BLACK_FLOOR}
        [[lights]]
        type = "point"
        position = [0.3, -0.2, 2.0]
        intensity_cd = 1000
        {FLOOR_RECEIVER}"#
        ),
        photons,
        estimator,
    );
    let h = 2.0 - 0.0001;
    let exact = |i: usize, j: usize| {
        let (x0, y0) = (-1.0 + i as f64 * 0.125 - 0.3, -1.0 + j as f64 * 0.125 + 0.2);
        point_source_cell_lx(1000.0, h, x0, x0 + 0.125, y0, y0 + 0.125)
    };
    assert_matches(&s.receivers["r"], exact, "point source over plane");
}

fn lambertian_square_emitter_matches_view_factor(estimator: Estimator, photons: u64) {
    // A 1 m² Lambertian square 1 m above the receiver plane, emitting downwards (u × v = −z).
    let (flux, h) = (1000.0, 1.0);
    let s = run_scene_with(
        r#"
        [[lights]]
        type = "area"
        corner = [-0.5, 0.5, 1.0]
        u = [1, 0, 0]
        v = [0, -1, 0]
        flux_lm = 1000
        [[receivers]]
        name = "r"
        corner = [-1, -1, 0]
        u = [2, 0, 0]
        v = [0, 2, 0]
        cells = [16, 16]
        "#,
        photons,
        estimator,
    );
    let luminance = flux / PI;
    let point_lx = |x: f64, y: f64| {
        let f = |a: f64, b: f64| parallel_corner_factor(a, b, h);
        let (x0, x1, y0, y1) = (-0.5 - x, 0.5 - x, -0.5 - y, 0.5 - y);
        PI * luminance * (f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0))
    };
    // The formula itself: straight below the centre of a square of side 2a at height h.
    let centre = point_lx(0.0, 0.0);
    let a: f64 = 0.5;
    let exact_centre = 2.0
        * luminance
        * (a / (a * a + h * h).sqrt())
        * 2.0
        * libm::atan(a / (a * a + h * h).sqrt());
    assert!(
        (centre - exact_centre).abs() < 1e-9 * exact_centre,
        "{centre} vs {exact_centre}"
    );
    let exact = |i: usize, j: usize| {
        let (x0, y0) = (-1.0 + i as f64 * 0.125, -1.0 + j as f64 * 0.125);
        cell_average(point_lx, x0, x0 + 0.125, y0, y0 + 0.125)
    };
    assert_matches(&s.receivers["r"], exact, "area source over plane");
}

fn closed_box(rho: f64) -> String {
    format!(
        r#"
        [materials.wall]
        reflectance = {rho}
        [[objects]]
        shape = "box"
        min = [0, 0, 0]
        max = [4, 3, 2.5]
        material = "wall"
        [[lights]]
        type = "point"
        position = [1.3, 1.1, 1.7]
        intensity_cd = 100
        "#
    )
}

fn assert_closed_box_balance(rho: f64, photons: u64) {
    let s = run_scene(&closed_box(rho), photons);
    let area = 2.0 * (4.0 * 3.0 + 3.0 * 2.5 + 4.0 * 2.5);
    assert!((s.global.area_m2 - area).abs() < 1e-9);
    let exact = 4.0 * PI * 100.0 / ((1.0 - rho) * area);
    let g = &s.global;
    assert!(g.mean_sigma_lx > 0.0);
    assert!(
        (g.mean_illuminance_lx - exact).abs() < 3.0 * g.mean_sigma_lx,
        "ρ = {rho}: mean {} vs {exact} (σ {})",
        g.mean_illuminance_lx,
        g.mean_sigma_lx
    );
    assert_eq!(s.photons_killed_by_bounce_cap, 0);
}

#[test]
fn closed_box_energy_balance_rho_half() {
    assert_closed_box_balance(0.5, 1_000_000);
}

#[test]
fn closed_box_energy_balance_rho_095() {
    assert_closed_box_balance(0.95, 500_000);
}

fn integrating_sphere_receiver_reads_direct_plus_uniform_indirect(
    estimator: Estimator,
    photons: u64,
) {
    let (rho, intensity) = (0.8, 100.0);
    let s = run_scene_with(
        &(point_in_sphere("coating", "reflectance = 0.8", 4, [0.0, 0.0, 0.0])
            + r#"
        [[receivers]]
        name = "r"
        corner = [-0.2, 0.2, 0.3]
        u = [0.4, 0, 0]
        v = [0, -0.4, 0]
        cells = [16, 16]
        "#),
        photons,
        estimator,
    );
    let flux = 4.0 * PI * intensity;
    let indirect = rho * flux / ((1.0 - rho) * s.global.area_m2);
    let w = 0.4 / 16.0;
    let exact = |i: usize, j: usize| {
        let x0 = -0.2 + i as f64 * w;
        let y1 = 0.2 - j as f64 * w;
        point_source_cell_lx(intensity, 0.3, x0, x0 + w, y1 - w, y1) + indirect
    };
    assert_matches(&s.receivers["r"], exact, "integrating sphere");
}

fn luminance_receiver_over_lambertian_floor_reads_rho_e_over_pi(
    estimator: Estimator,
    photons: u64,
) {
    let s = run_scene_with(NEAR_ZONE_METER, photons, estimator);
    let r = &s.receivers["meter"];
    assert_eq!(r.unit, "cd/m2");
    assert_matches(r, near_zone_meter_cdm2, "luminance over floor");
}

fn mirror_adds_the_image_of_the_source(estimator: Estimator, photons: u64) {
    // Source 0.5 m above a perfect mirror; a downward-facing receiver 1 m above the source
    // sees the source (1 m away) and its image (2 m away).
    let s = run_scene_with(
        &point_over_mirror("reflectance = 0.0\n    specular_reflectance = 1.0"),
        photons,
        estimator,
    );
    let z = z_scores(&s.receivers["r"], mirror_image_cell_lx);
    assert_calibrated(&z, "mirror image");
}

fn glass_slab_at_normal_incidence_transmits_fresnel_series(estimator: Estimator, photons: u64) {
    let s = run_scene_with(
        r#"
        [materials.glass]
        reflectance = 0.0
        specular_transmittance = 1.0
        ior = 1.5
        [[objects]]
        shape = "box"
        min = [-3, -3, 0.5]
        max = [3, 3, 0.6]
        material = "glass"
        [[lights]]
        type = "directional"
        direction = [0, 0, -1]
        illuminance_lx = 1000
        [[receivers]]
        name = "r"
        corner = [-0.5, -0.5, 0.2]
        u = [1, 0, 0]
        v = [0, 1, 0]
        cells = [4, 4]
        "#,
        photons,
        estimator,
    );
    let r0: f64 = ((1.5 - 1.0) / (1.5 + 1.0)) * ((1.5 - 1.0) / (1.5 + 1.0));
    let exact = 1000.0 * (1.0 - r0) * (1.0 - r0) / (1.0 - r0 * r0);
    let z = z_scores(&s.receivers["r"], |_, _| exact);
    let r = rms(&z);
    assert!(
        r < 1.6,
        "glass slab: z RMS {r} (16 cells), mean {}",
        s.receivers["r"].mean
    );
}

/// Each analytic case, once per estimator, with the photons each needs: next-event
/// estimation needs far fewer where diffuse light dominates, and none at all (beyond a
/// token run) where all light is direct and computed deterministically.
macro_rules! with_each_estimator {
    ($($case:ident: $track:expr, $next_event:expr;)*) => {
        mod track {
            $(#[test]
            fn $case() {
                super::$case(super::Estimator::Track, $track);
            })*
        }
        mod next_event {
            $(#[test]
            fn $case() {
                super::$case(super::Estimator::NextEvent, $next_event);
            })*
        }
    };
}

with_each_estimator!(
    point_source_over_black_plane_matches_inverse_square_cosine_law: 4_000_000, 10_000;
    lambertian_square_emitter_matches_view_factor: 4_000_000, 10_000;
    integrating_sphere_receiver_reads_direct_plus_uniform_indirect: 6_000_000, 200_000;
    luminance_receiver_over_lambertian_floor_reads_rho_e_over_pi: 16_000_000, 1_000_000;
    mirror_adds_the_image_of_the_source: 6_000_000, 6_000_000;
    glass_slab_at_normal_incidence_transmits_fresnel_series: 2_000_000, 2_000_000;
);

/// Receivers lying exactly on a floor (no gap): the illuminance receiver reads the
/// floor's illuminance, the luminance meter looking at it reads ρE/π, with each estimator.
fn receivers_lying_on_a_floor_read_its_illuminance_and_luminance(
    estimator: Estimator,
    photons: u64,
) {
    let (rho, intensity, h) = (0.6, 1000.0, 2.0);
    let s = run_scene_with(
        r#"
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
        name = "floor"
        corner = [-0.5, -0.5, 0]
        u = [1, 0, 0]
        v = [0, 1, 0]
        cells = [8, 8]
        [[receivers]]
        name = "meter"
        corner = [-0.5, -0.5, 0]
        u = [1, 0, 0]
        v = [0, 1, 0]
        cells = [8, 8]
        quantity = "luminance"
        view_direction = [0, 0, -1]
        half_angle_deg = 30
        "#,
        photons,
        estimator,
    );
    let e = |i: usize, j: usize| {
        let (x0, y0) = (-0.5 + i as f64 / 8.0, -0.5 + j as f64 / 8.0);
        point_source_cell_lx(intensity, h, x0, x0 + 1.0 / 8.0, y0, y0 + 1.0 / 8.0)
    };
    for (name, scale) in [("floor", 1.0), ("meter", rho / PI)] {
        let r = &s.receivers[name];
        let nu = r.cells[0] as usize;
        for (k, (v, sigma)) in r.values.iter().zip(&r.sigma).enumerate() {
            let exact = scale * e(k % nu, k / nu);
            assert!(*v > 0.0, "{name} cell {k} read nothing");
            assert!(
                (v - exact).abs() <= 4.0 * sigma.max(1e-9 * exact),
                "{name} cell {k}: {v} vs {exact} (σ {sigma})"
            );
        }
    }
}

mod on_a_floor {
    use super::*;

    #[test]
    fn track() {
        receivers_lying_on_a_floor_read_its_illuminance_and_luminance(Estimator::Track, 8_000_000);
    }

    #[test]
    fn next_event() {
        receivers_lying_on_a_floor_read_its_illuminance_and_luminance(
            Estimator::NextEvent,
            8_000_000,
        );
    }
}

/// A spot light over a black plane: every cell against the exact cell average of
/// I(θ)·h/(h² + r²)^{3/2}, with the smooth profile between `falloff_deg` and `cone_deg`
/// (the cone reaches the receiver's edge, so cells see the core, the ramp and the dark).
fn spot_light_over_plane_follows_its_profile(estimator: Estimator, photons: u64) {
    let s = run_scene_with(&spot_over_black_floor(), photons, estimator);
    let exact = spot_cell_lx;
    let r = &s.receivers["r"];
    let peak = exact(8, 8);
    // Cells outside the cone read exactly nothing, with an unknown error. Next-event
    // receivers must be calibrated everywhere else; with the track estimator, cells the
    // cone's edge barely grazes (under 0.1 % of the peak) have too few hits to estimate
    // σ and are left out.
    let (mut z, mut checked) = (Vec::new(), 0);
    for k in 0..r.values.len() {
        let e = exact(k % 16, k / 16);
        if e == 0.0 {
            assert_eq!(r.values[k], 0.0, "cell {k} is outside the cone");
            assert!(r.sigma[k].is_nan(), "cell {k}: nothing scored, σ unknown");
        } else if r.estimator == "next_event" || e > 1e-3 * peak {
            checked += 1;
            z.push((r.values[k] - e) / r.sigma[k]);
        }
    }
    assert!(checked > 100, "{checked} cells checked");
    assert_calibrated(&z, &format!("spot over plane, {}", r.estimator));
}

/// A directional source at 36.87° from the vertical over a black plane: E⊥·cos θ
/// everywhere (the emitting disk covers the scene).
fn directional_light_gives_uniform_cosine_illuminance(estimator: Estimator, photons: u64) {
    let s = run_scene_with(
        r#"
        [materials.black]
        reflectance = 0.0
        [[objects]]
        shape = "rect"
        corner = [-3, -3, 0]
        u = [6, 0, 0]
        v = [0, 6, 0]
        material = "black"
        [[lights]]
        type = "directional"
        direction = [0, 0.6, -0.8]
        illuminance_lx = 1000
        [[receivers]]
        name = "r"
        corner = [-2, -2, 0.0001]
        u = [4, 0, 0]
        v = [0, 4, 0]
        cells = [16, 16]
        "#,
        photons,
        estimator,
    );
    assert_matches(&s.receivers["r"], |_, _| 800.0, "directional over plane");
}

mod spot_and_directional {
    use super::*;

    #[test]
    fn spot_track() {
        spot_light_over_plane_follows_its_profile(Estimator::Track, 4_000_000);
    }

    #[test]
    fn spot_next_event() {
        spot_light_over_plane_follows_its_profile(Estimator::NextEvent, 10_000);
    }

    #[test]
    fn directional_track() {
        directional_light_gives_uniform_cosine_illuminance(Estimator::Track, 4_000_000);
    }

    #[test]
    fn directional_next_event() {
        directional_light_gives_uniform_cosine_illuminance(Estimator::NextEvent, 10_000);
    }
}

//! Luminance meters' reflected direct light (`trace::reflected`): a meter looking at a
//! lit floor from a distance reads f(wo, wi)·|cos θ_i|·E averaged over its cells and
//! cone, against numerical integration of the BSDF, z-calibrated over seeds; behind a
//! pane and in a room, next-event and track estimates agree (no path missed or counted
//! twice).

use crate::common;

use common::{
    assert_calibrated, assert_estimators_agree, cell_average, gauss8, options, run_options, scene,
    z_scores,
};
use glam::DVec3;
use luxtally::accel::Backend;
use luxtally::scene::Material;
use luxtally::surface::Bsdf;
use std::f64::consts::PI;

const LIGHT: DVec3 = DVec3::new(0.8, 0.0, 2.0);
const INTENSITY_CD: f64 = 1000.0;
const HALF_ANGLE_DEG: f64 = 10.0;

/// An open floor lit by a point source, and a 4 × 4-cell meter 1 m above it looking
/// down and a little sideways, 10° half-angle: only light the floor reflects straight
/// from the source reaches it.
fn meter_over_floor(material: &str) -> String {
    format!(
        r#"
        [materials.floor]
        {material}
        [[objects]]
        shape = "rect"
        corner = [-20, -20, 0]
        u = [40, 0, 0]
        v = [0, 40, 0]
        material = "floor"
        [[lights]]
        type = "point"
        position = [0.8, 0, 2]
        intensity_cd = 1000
        [[receivers]]
        name = "meter"
        corner = [-0.25, -0.25, 1]
        u = [0.5, 0, 0]
        v = [0, 0.5, 0]
        cells = [4, 4]
        quantity = "luminance"
        view_direction = [0.3, 0, -1]
        half_angle_deg = {HALF_ANGLE_DEG}
        "#
    )
}

/// The meter's exact cell means: the mean over the cell (8 × 8 Gauss points) and the
/// cone (8 Gauss points in cos θ, 32 in φ) of f(wo, wi)·cos θ_i·I/d² at the floor point
/// each direction meets.
fn exact_cells(b: &Bsdf) -> impl Fn(usize, usize) -> f64 + '_ {
    let towards_meter = -DVec3::new(0.3, 0.0, -1.0).normalize();
    let cos_half = libm::cos(HALF_ANGLE_DEG.to_radians());
    let (t, s) = luxtally::sampling::basis(towards_meter);
    let cone_mean = move |x: f64, y: f64| -> f64 {
        let p = DVec3::new(x, y, 1.0);
        let mut sum = 0.0;
        for (u, weight) in gauss8() {
            let cos = 1.0 - u * (1.0 - cos_half);
            let sin = (1.0 - cos * cos).sqrt();
            for j in 0..32 {
                let phi = (j as f64 + 0.5) * 2.0 * PI / 32.0;
                let w =
                    t * (sin * libm::cos(phi)) + s * (sin * libm::sin(phi)) + towards_meter * cos;
                let floor = p - w * (p.z / w.z);
                let to_light = LIGHT - floor;
                let d2 = to_light.length_squared();
                let wi = to_light / d2.sqrt();
                sum += weight / 32.0 * b.f(w, wi, DVec3::Z) * wi.z * INTENSITY_CD / d2;
            }
        }
        sum
    };
    move |i, j| {
        let (x0, y0) = (-0.25 + i as f64 / 8.0, -0.25 + j as f64 / 8.0);
        cell_average(cone_mean, x0, x0 + 0.125, y0, y0 + 0.125)
    }
}

/// z-scores of the meter's cells over `seeds` seeds of `photons` photons each.
fn meter_z_over_seeds(
    material_toml: &str,
    material: &Material,
    photons: u64,
    seeds: u64,
) -> Vec<f64> {
    let s = scene(&meter_over_floor(material_toml));
    let b = Bsdf::new(material);
    let exact = exact_cells(&b);
    let mut z = Vec::new();
    for seed in 1..=seeds {
        let mut opts = options(&s, photons, 2, Backend::Embree);
        opts.seed = seed;
        let summary = run_options(&s, &opts);
        let r = &summary.receivers["meter"];
        assert_eq!(r.direct_estimator, "sampled");
        z.extend(z_scores(r, &exact));
    }
    z
}

#[test]
fn a_meter_over_a_lambertian_floor_reads_rho_e_over_pi_by_next_event() {
    let floor = Material::lambertian("floor", 0.6);
    let z = meter_z_over_seeds("reflectance = 0.6", &floor, 20_000, 12);
    assert_calibrated(&z, "meter over a Lambertian floor, 12 seeds");
}

#[test]
fn a_meter_over_a_glossy_floor_reads_its_bsdf_integral_by_next_event() {
    let floor = Material {
        reflectance: 0.1,
        glossy_reflectance: 0.8,
        roughness: 0.4,
        ..Material::lambertian("floor", 0.0)
    };
    let z = meter_z_over_seeds(
        "reflectance = 0.1\n        glossy_reflectance = 0.8\n        roughness = 0.4",
        &floor,
        20_000,
        12,
    );
    assert_calibrated(&z, "meter over a glossy floor, 12 seeds");
}

/// A meter inside a room behind double glazing, looking out through it at a lit floor,
/// and a second one looking at the room's lit wall: track and next-event agree.
#[test]
fn meters_behind_glazing_and_in_a_room_agree_with_track() {
    let s = scene(
        r#"
        [materials.grey]
        reflectance = 0.5
        [materials.pane]
        glazing = [0.88, 0.88]
        [[objects]]
        shape = "rect"
        corner = [-10, -10, 0]
        u = [20, 0, 0]
        v = [0, 20, 0]
        material = "grey"
        [[objects]]
        shape = "rect"
        corner = [-2, -2, 0.6]
        u = [4, 0, 0]
        v = [0, 4, 0]
        material = "pane"
        [[objects]]
        shape = "rect"
        corner = [-2, 1.5, 0]
        u = [4, 0, 0]
        v = [0, 0, 2]
        material = "grey"
        [[lights]]
        type = "point"
        position = [0.5, 0, 0.4]
        intensity_cd = 1000
        [[receivers]]
        name = "down"
        corner = [-0.3, -0.3, 1.2]
        u = [0.6, 0, 0]
        v = [0, 0.6, 0]
        cells = [8, 8]
        quantity = "luminance"
        view_direction = [0.2, 0.1, -1]
        half_angle_deg = 15
        [[receivers]]
        name = "wall"
        corner = [-0.4, 0.2, 0.1]
        u = [0.8, 0, 0]
        v = [0, 0, 0.3]
        cells = [8, 4]
        quantity = "luminance"
        view_direction = [0, 1, 0.1]
        half_angle_deg = 20
        "#,
    );
    assert_estimators_agree(&s, "down", 3_000_000, 300_000);
    assert_estimators_agree(&s, "wall", 3_000_000, 300_000);
}

//! Glossy surfaces (#17): the GGX BSDF against numerical integration over the sphere of
//! directions (reciprocity, energy bound, sampling consistency), and the engine with
//! glossy materials against independent references (furnace balance, the mirror limit,
//! estimator agreement, the luminance of a glossy floor).

use crate::common;

use common::{
    assert_calibrated, assert_estimators_agree, cell_average, gauss8, mirror_image_cell_lx,
    point_in_sphere, point_over_mirror, run_scene, run_scene_with, z_scores,
};
use glam::DVec3;
use luxtally::accel::Backend;
use luxtally::scene::{Estimator, Material};
use luxtally::surface::{Bsdf, Frame};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;
use std::f64::consts::PI;

fn material(glossy_r: f64, glossy_t: f64, roughness: f64) -> Material {
    Material {
        glossy_reflectance: glossy_r,
        glossy_transmittance: glossy_t,
        roughness,
        ..Material::lambertian("m", 0.0)
    }
}

fn direction(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(
        libm::sin(t) * libm::cos(p),
        libm::sin(t) * libm::sin(p),
        libm::cos(t),
    )
}

/// ∫ g(ω) dω over the whole sphere by jittered stratification: an n × 2n grid of equal
/// cells in (cos θ, φ), one uniform point per cell, repeated `REPLICAS` times with
/// independent jitter; (mean, its standard error from the replicas' spread). Unlike a
/// fixed rule it has an honest error bar at the BSDF's kinks (horizon, critical angle).
fn sphere_integral(n: usize, g: impl Fn(DVec3) -> f64) -> (f64, f64) {
    const REPLICAS: usize = 8;
    let mut rng = Pcg32::seed_from_u64(n as u64);
    let cells = (2 * n * n) as f64;
    let estimates: Vec<f64> = (0..REPLICAS)
        .map(|_| {
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..2 * n {
                    let mu = -1.0 + 2.0 * (i as f64 + rng.random::<f64>()) / n as f64;
                    let phi = PI * (j as f64 + rng.random::<f64>()) / n as f64;
                    let s = (1.0 - mu * mu).max(0.0).sqrt();
                    sum += g(DVec3::new(s * libm::cos(phi), s * libm::sin(phi), mu));
                }
            }
            4.0 * PI * sum / cells
        })
        .collect();
    let k = REPLICAS as f64;
    let mean = estimates.iter().sum::<f64>() / k;
    let var = estimates.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (k - 1.0);
    (mean, (var / k).sqrt())
}

const ROUGHNESS: [f64; 4] = [0.3, 0.5, 0.75, 1.0];
const INCIDENCE_DEG: [f64; 4] = [0.0, 30.0, 60.0, 80.0];

#[test]
fn glossy_reflection_is_reciprocal() {
    let mut rng = Pcg32::seed_from_u64(7);
    for roughness in [0.1, 0.3, 0.6, 1.0] {
        for lobe in [material(1.0, 0.0, roughness), material(0.0, 1.0, roughness)] {
            let b = Bsdf::new(&lobe);
            for _ in 0..200 {
                let wo = direction(rng.random_range(0.0..89.0), rng.random_range(0.0..360.0));
                let wi = direction(rng.random_range(0.0..89.0), rng.random_range(0.0..360.0));
                for n in [DVec3::Z, -DVec3::Z] {
                    let (wo, wi) = if n.z < 0.0 { (-wo, -wi) } else { (wo, wi) };
                    let (a, c) = (b.f(wo, wi, n), b.f(wi, wo, n));
                    assert!(a >= 0.0 && (a - c).abs() <= 1e-9 * a.max(1.0), "{a} vs {c}");
                }
            }
        }
    }
}

#[test]
fn rough_refraction_obeys_the_generalised_reciprocity() {
    // In the flux form (no 1/η² radiance factor) refraction is reciprocal up to η²:
    // f(wo outside, wi inside) = η²·f(wi, wo) for η = 1.5.
    let mut rng = Pcg32::seed_from_u64(8);
    let b = Bsdf::new(&material(0.0, 1.0, 0.5));
    let eta = 1.5;
    let mut checked = 0;
    for _ in 0..500 {
        let wo = direction(rng.random_range(0.0..89.0), rng.random_range(0.0..360.0));
        let wi = -direction(rng.random_range(0.0..89.0), rng.random_range(0.0..360.0));
        let (a, c) = (b.f(wo, wi, DVec3::Z), b.f(wi, wo, DVec3::Z));
        if a > 0.0 {
            checked += 1;
            assert!((a - c * eta * eta).abs() <= 1e-9 * a, "{a} vs {c}·η²");
        }
    }
    assert!(checked > 100);
}

/// Directional albedo ∫ f |cos θ_i| dω_i by quadrature, the same by the mean of sampled
/// weights, and ∫ pdf dω_i against the fraction of samples returned.
fn check_lobe(m: &Material, theta_deg: f64) -> f64 {
    let b = Bsdf::new(m);
    let n = DVec3::Z;
    let wo = direction(theta_deg, 20.0);
    let (albedo, q_err) = sphere_integral(300, |wi| b.f(wo, wi, n) * wi.z.abs());
    let (pdf_mass, p_err) = sphere_integral(300, |wi| b.pdf(wo, wi, n));
    let samples = 200_000;
    let mut rng = Pcg32::seed_from_u64(theta_deg.to_bits() ^ m.roughness.to_bits());
    let (mut sum, mut sum2, mut returned) = (0.0, 0.0, 0u64);
    for _ in 0..samples {
        let dir = -wo;
        if let Some(s) = b.sample(dir, n, &mut rng) {
            returned += 1;
            // Cross-check the sample against f and pdf where both are finite.
            let (f, p) = (b.f(wo, s.dir, n), b.pdf(wo, s.dir, n));
            let total = m.glossy_reflectance + m.glossy_transmittance;
            assert!(
                (s.weight * total - f * s.dir.z.abs() / p).abs() < 1e-6,
                "sample weight {} vs f·cos/pdf {}",
                s.weight * total,
                f * s.dir.z.abs() / p
            );
            let w = s.weight * total;
            sum += w;
            sum2 += w * w;
        }
    }
    let mean = sum / samples as f64;
    let sigma = ((sum2 / samples as f64 - mean * mean) / (samples - 1) as f64).sqrt();
    let fraction = returned as f64 / samples as f64;
    let f_sigma = (fraction * (1.0 - fraction) / samples as f64).sqrt();
    eprintln!(
        "roughness {} θ {theta_deg}: albedo {albedo:.5} (±{q_err:.1e}) sampled {mean:.5} ± {sigma:.1e}; pdf mass {pdf_mass:.5} vs returned {fraction:.5}",
        m.roughness
    );
    assert!(
        albedo <= 1.0 + 4.0 * q_err,
        "energy created: albedo {albedo} at roughness {} θ {theta_deg}",
        m.roughness
    );
    assert!(
        (albedo - mean).abs() <= 4.0 * libm::hypot(sigma, q_err),
        "albedo {albedo} vs sampled {mean} ± {sigma}"
    );
    assert!(
        (pdf_mass - fraction).abs() <= 4.0 * libm::hypot(f_sigma, p_err),
        "pdf mass {pdf_mass} vs returned fraction {fraction} ± {f_sigma}"
    );
    albedo
}

#[test]
fn glossy_reflector_conserves_energy_and_samples_its_pdf() {
    for roughness in ROUGHNESS {
        for theta in INCIDENCE_DEG {
            check_lobe(&material(1.0, 0.0, roughness), theta);
        }
    }
}

#[test]
fn rough_dielectric_conserves_energy_and_samples_its_pdf() {
    for roughness in ROUGHNESS {
        for theta in INCIDENCE_DEG {
            check_lobe(&material(0.0, 1.0, roughness), theta);
            // From inside the dielectric too (total internal reflection beyond 41.8°).
            let b = Bsdf::new(&material(0.0, 1.0, roughness));
            let wo = -direction(theta, 20.0);
            let (albedo, err) = sphere_integral(300, |wi| b.f(wo, wi, DVec3::Z) * wi.z.abs());
            assert!(albedo <= 1.0 + 4.0 * err, "inside: albedo {albedo} ± {err}");
        }
    }
}

#[test]
fn a_mix_is_the_weighted_sum_of_its_lobes() {
    let mix = Material {
        reflectance: 0.2,
        glossy_reflectance: 0.5,
        glossy_transmittance: 0.3,
        roughness: 0.4,
        ..Material::lambertian("mix", 0.0)
    };
    let b = Bsdf::new(&mix);
    let (r, t) = (
        Bsdf::new(&material(1.0, 0.0, 0.4)),
        Bsdf::new(&material(0.0, 1.0, 0.4)),
    );
    let wo = direction(35.0, 10.0);
    for wi in [
        direction(20.0, 190.0),
        direction(50.0, 100.0),
        -direction(25.0, 200.0),
    ] {
        let n = DVec3::Z;
        let diffuse = if wi.z > 0.0 { 0.2 / PI } else { 0.0 };
        let expect = diffuse + 0.5 * r.f(wo, wi, n) + 0.3 * t.f(wo, wi, n);
        assert!((b.f(wo, wi, n) - expect).abs() < 1e-12 * expect.max(1.0));
    }
}

#[test]
fn frame_round_trips() {
    let f = Frame::new(DVec3::new(0.1, -0.7, 0.2).normalize());
    let w = DVec3::new(0.3, 0.4, -0.5);
    assert!((f.to_world(f.to_local(w)) - w).length() < 1e-12);
}

/// Mean number of surface hits per photon from a sphere's centre: in a sphere a chord
/// meets the surface at the angle it left it, so the incidence angles form a Markov
/// chain driven by the BSDF alone: N̄ = Σ_k E[Π weights], estimated with its σ.
fn sphere_mean_hits(b: &Bsdf, chains: u64) -> (f64, f64) {
    let mut rng = Pcg32::seed_from_u64(99);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for _ in 0..chains {
        let (mut cos, mut weight, mut hits) = (1.0f64, 1.0, 0.0);
        while weight > 1e-12 {
            hits += weight;
            let wo = DVec3::new((1.0 - cos * cos).max(0.0).sqrt(), 0.0, cos);
            // Local frame, the sphere's inside on +z: the photon arrives along −wo.
            let Some(s) = b.sample(-wo, DVec3::Z, &mut rng) else {
                break;
            };
            if s.transmitted {
                break;
            }
            weight *= s.weight;
            cos = s.dir.z.abs();
        }
        sum += hits;
        sum2 += hits * hits;
    }
    let n = chains as f64;
    let mean = sum / n;
    (mean, ((sum2 / n - mean * mean) / (n - 1.0)).sqrt())
}

/// White furnace: a closed icosphere of glossy_reflectance = 1 (and a Lambertian mix
/// summing to 1) with a point source at its centre. GGX loses energy at high roughness,
/// so the balance is E = Φ·N̄/S, N̄ the mean hits per photon (equivalently
/// Φ/((1 − ρ_eff)S) with ρ_eff = 1 − 1/N̄), N̄ from the BSDF's own angular chain.
fn furnace(reflectance: f64, glossy: f64, roughness: f64, photons: u64) {
    let toml = point_in_sphere(
        "shell",
        &format!(
            "reflectance = {reflectance}\nglossy_reflectance = {glossy}\nroughness = {roughness}"
        ),
        5,
        [0.0, 0.0, 0.0],
    );
    let s = run_scene(&toml, photons);
    let m = Material {
        reflectance,
        glossy_reflectance: glossy,
        roughness,
        ..Material::lambertian("shell", 0.0)
    };
    let (hits, hits_sigma) = sphere_mean_hits(&Bsdf::new(&m), 400_000);
    let flux = 4.0 * PI * 100.0;
    let g = &s.global;
    let exact = flux * hits / g.area_m2;
    let sigma = libm::hypot(g.mean_sigma_lx, flux * hits_sigma / g.area_m2);
    eprintln!(
        "furnace ρ {reflectance} glossy {glossy} roughness {roughness}: mean {} vs {exact} (σ {sigma}), ρ_eff {}",
        g.mean_illuminance_lx,
        1.0 - 1.0 / hits
    );
    assert!(
        (g.mean_illuminance_lx - exact).abs() < 4.0 * sigma,
        "mean {} vs {exact} (σ {sigma})",
        g.mean_illuminance_lx
    );
    assert_eq!(s.photons_killed_by_bounce_cap, 0);
}

#[test]
fn furnace_glossy_rough() {
    furnace(0.0, 1.0, 1.0, 100_000);
}

#[test]
fn furnace_glossy_medium() {
    furnace(0.0, 1.0, 0.5, 40_000);
}

#[test]
fn furnace_glossy_with_lambertian_mix() {
    furnace(0.3, 0.7, 0.7, 60_000);
}

/// Roughness → 0: a glossy reflector of roughness 0.001 (α = 10⁻⁶, scored by crossing
/// like a mirror) adds the image of the source as the ideal mirror does.
fn nearly_smooth_glossy_is_a_mirror(estimator: Estimator, photons: u64) {
    let s = run_scene_with(
        &point_over_mirror("glossy_reflectance = 1.0\n    roughness = 0.001"),
        photons,
        estimator,
    );
    let z = z_scores(&s.receivers["r"], mirror_image_cell_lx);
    assert_calibrated(&z, "glossy mirror image");
}

#[test]
fn nearly_smooth_glossy_is_a_mirror_track() {
    nearly_smooth_glossy_is_a_mirror(Estimator::Track, 3_000_000);
}

#[test]
fn nearly_smooth_glossy_is_a_mirror_next_event() {
    nearly_smooth_glossy_is_a_mirror(Estimator::NextEvent, 3_000_000);
}

#[test]
fn track_and_next_event_agree_over_a_glossy_floor() {
    let scene = common::scene(
        r#"
        [materials.wall]
        reflectance = 0.5
        [materials.floor]
        reflectance = 0.2
        glossy_reflectance = 0.6
        roughness = 0.5
        [materials.frosted]
        glossy_transmittance = 0.9
        roughness = 0.4
        ior = 1.5
        [[objects]]
        shape = "box"
        min = [0, 0, 0]
        max = [2, 2, 2]
        material = "wall"
        [[objects]]
        shape = "rect"
        corner = [0, 0, 0.001]
        u = [2, 0, 0]
        v = [0, 2, 0]
        material = "floor"
        [[objects]]
        shape = "box"
        min = [1.2, 0.3, 0.9]
        max = [1.7, 0.8, 1.2]
        material = "frosted"
        [[lights]]
        type = "point"
        position = [0.7, 1.1, 1.7]
        intensity_cd = 100
        [[receivers]]
        name = "ceiling"
        corner = [0, 0, 1.99]
        u = [0, 2, 0]
        v = [2, 0, 0]
        cells = [12, 12]
        [[receivers]]
        name = "meter"
        corner = [0.2, 0.2, 1.0]
        u = [1.6, 0, 0]
        v = [0, 1.6, 0]
        cells = [8, 8]
        quantity = "luminance"
        view_direction = [0.3, 0, 1]
        half_angle_deg = 20
        "#,
    );
    assert_estimators_agree(&scene, "ceiling", 3_000_000, 600_000);
    assert_estimators_agree(&scene, "meter", 3_000_000, 600_000);
}

/// A luminance meter lying on a glossy floor lit by a point source reads the cone
/// average of f(ω, ω_light)·E(x) over its cells: the reference integrates the BSDF over
/// each cell (8 × 8 Gauss points) and the meter's cone (Gauss in cos θ, midpoint in φ).
fn glossy_floor_luminance(estimator: Estimator, photons: u64) {
    let (intensity, light) = (1000.0, DVec3::new(0.8, 0.0, 2.0));
    let floor = Material {
        reflectance: 0.1,
        glossy_reflectance: 0.8,
        roughness: 0.4,
        ..Material::lambertian("floor", 0.0)
    };
    let s = run_scene_with(
        r#"
        [materials.floor]
        reflectance = 0.1
        glossy_reflectance = 0.8
        roughness = 0.4
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
    let b = Bsdf::new(&floor);
    let cos_half = libm::cos(30f64.to_radians());
    let omega = 2.0 * PI * (1.0 - cos_half);
    let g = gauss8();
    let cone_mean = |x: f64, y: f64| -> f64 {
        let p = DVec3::new(x, y, 0.0);
        let to_light = light - p;
        let d2 = to_light.length_squared();
        let wi = to_light / d2.sqrt();
        let e = intensity * wi.z / d2;
        let mut sum = 0.0;
        for (s, w) in g {
            let cos = 1.0 - s * (1.0 - cos_half);
            let sin = (1.0 - cos * cos).sqrt();
            for j in 0..32 {
                let phi = (j as f64 + 0.5) * 2.0 * PI / 32.0;
                let wo = DVec3::new(sin * libm::cos(phi), sin * libm::sin(phi), cos);
                sum += w * (1.0 - cos_half) * (2.0 * PI / 32.0) * b.f(wo, wi, DVec3::Z);
            }
        }
        e * sum / omega
    };
    let z = z_scores(&s.receivers["meter"], |i, j| {
        let (x0, y0) = (-0.5 + i as f64 / 8.0, -0.5 + j as f64 / 8.0);
        cell_average(cone_mean, x0, x0 + 0.125, y0, y0 + 0.125)
    });
    assert_calibrated(&z, "glossy floor luminance");
}

#[test]
fn glossy_floor_luminance_track() {
    glossy_floor_luminance(Estimator::Track, 4_000_000);
}

#[test]
fn glossy_floor_luminance_next_event() {
    glossy_floor_luminance(Estimator::NextEvent, 4_000_000);
}

// ---- The eye pass ----

use luxtally::accel;
use luxtally::output::IndirectMap;
use luxtally::render::{self, Render};
use luxtally::scene::{Camera, Scene};

fn render_zero_map(scene: &Scene) -> Render {
    let caster = accel::build(Backend::Embree, &scene.geometry).expect("backend builds");
    let camera = scene.camera.as_ref().expect("test scene has a camera");
    let map = IndirectMap::zero(scene.geometry.triangle_count());
    render::render(scene, camera, &map, caster.as_ref(), 1, 2).expect("renders")
}

/// World ray through the centre of pixel (x, y) (the pinhole of docs/render.md).
fn pixel_ray(c: &Camera, x: usize, y: usize) -> (DVec3, DVec3) {
    let [w, h] = c.resolution.map(|v| v as f64);
    let forward = (c.look_at - c.position).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let t = libm::tan(0.5 * c.fov_deg.to_radians());
    let sx = (2.0 * (x as f64 + 0.5) / w - 1.0) * t * w / h;
    let sy = (1.0 - 2.0 * (y as f64 + 0.5) / h) * t;
    (c.position, (forward + right * sx + up * sy).normalize())
}

/// Where a ray meets the plane z = 0 (t > 0).
fn floor_point(o: DVec3, d: DVec3) -> Option<DVec3> {
    let t = -o.z / d.z;
    (t > 0.0).then(|| o + d * t)
}

#[test]
fn glossy_floor_shows_bsdf_times_illuminance() {
    // A lone glossy floor: the camera sees f(wo, ω_light)·E at every floor pixel, with
    // the highlight where the light's mirror direction meets the eye.
    let s = common::scene(
        r#"
        [materials.floor]
        reflectance = 0.1
        glossy_reflectance = 0.7
        roughness = 0.4
        [[objects]]
        shape = "rect"
        corner = [-5, -5, 0]
        u = [10, 0, 0]
        v = [0, 10, 0]
        material = "floor"
        [[lights]]
        type = "point"
        position = [0.5, 1.0, 2]
        intensity_cd = 150
        [camera]
        position = [0, -4, 3]
        look_at = [0, 0, 0]
        fov_deg = 50
        resolution = [48, 36]
        "#,
    );
    let r = render_zero_map(&s);
    let c = s.camera.as_ref().unwrap();
    let b = Bsdf::new(&s.materials[0]);
    let light = DVec3::new(0.5, 1.0, 2.0);
    let (mut checked, mut peak) = (0, 0.0f64);
    for y in 0..r.image.height {
        for x in 0..r.image.width {
            let (o, d) = pixel_ray(c, x, y);
            let got = r.image.luminance_cdm2[y * r.image.width + x];
            let Some(p) = floor_point(o, d).filter(|p| p.x.abs() < 5.0 && p.y.abs() < 5.0) else {
                assert_eq!(got, 0.0);
                continue;
            };
            let to = light - p;
            let r2 = to.length_squared();
            let wi = to / r2.sqrt();
            let want = b.f(-d, wi, DVec3::Z) * 150.0 * wi.z / r2;
            assert!(
                (got / want - 1.0).abs() < 1e-3,
                "pixel ({x}, {y}): {got} cd/m² against {want}"
            );
            peak = peak.max(got / (0.1 / PI * 150.0 * wi.z / r2));
            checked += 1;
        }
    }
    assert!(checked > 1000, "{checked} floor pixels");
    assert!(peak > 3.0, "a highlight shows: {peak}× the diffuse part");
}

#[test]
fn nearly_smooth_glossy_wall_shows_the_floor_like_a_mirror() {
    // tests/suite/physics/render.rs's mirror scene with the mirror made glossy of roughness 0.001: the
    // eye path continues through the sampled lobe with weight 0.8·G₂/G₁ ≈ 0.8.
    let s = common::scene(
        r#"
        [materials.floor]
        reflectance = 0.5
        [materials.mirror]
        glossy_reflectance = 0.8
        roughness = 0.001
        [[objects]]
        shape = "rect"
        corner = [-5, -5, 0]
        u = [7, 0, 0]
        v = [0, 10, 0]
        material = "floor"
        [[objects]]
        shape = "rect"
        corner = [2, -3, 0]
        u = [0, 6, 0]
        v = [0, 0, 3]
        material = "mirror"
        [[lights]]
        type = "point"
        position = [0, 0.4, 2]
        intensity_cd = 100
        [camera]
        position = [-2, 0, 1.5]
        look_at = [2, 0, 0.6]
        fov_deg = 40
        resolution = [40, 30]
        "#,
    );
    let r = render_zero_map(&s);
    let c = s.camera.as_ref().unwrap();
    let light = DVec3::new(0.0, 0.4, 2.0);
    let lambert = |p: DVec3| {
        let to = light - p;
        let r2 = to.length_squared();
        0.5 * 100.0 * (to.z / r2.sqrt()) / (PI * r2)
    };
    let mut in_mirror = 0;
    for y in 0..r.image.height {
        for x in 0..r.image.width {
            let (o, d) = pixel_ray(c, x, y);
            let got = r.image.luminance_cdm2[y * r.image.width + x];
            let t_mirror = (2.0 - o.x) / d.x;
            let m = o + d * t_mirror;
            let on_mirror = m.y.abs() < 3.0 && m.z > 0.0 && m.z < 3.0;
            let t_floor = -o.z / d.z;
            if !on_mirror || (t_floor > 0.0 && t_floor < t_mirror) {
                continue;
            }
            if (m.y.abs() - 3.0).abs() < 0.05 || m.z.abs() < 0.05 {
                continue;
            }
            let reflected = DVec3::new(-d.x, d.y, d.z);
            let Some(p) = floor_point(m, reflected).filter(|p| p.x > -5.0 && p.y.abs() < 5.0)
            else {
                continue;
            };
            let want = 0.8 * lambert(p);
            assert!(
                (got / want - 1.0).abs() < 1e-3,
                "pixel ({x}, {y}): {got} cd/m² against {want}"
            );
            in_mirror += 1;
        }
    }
    assert!(in_mirror > 200, "{in_mirror} mirror pixels");
}

#[test]
fn glossy_floor_under_an_area_source_counts_it_once() {
    // A Lambertian square source 2 m over a glossy floor: each floor pixel's luminance is
    // ∫ f(wo, ω)·L·cos θ dω over the source (Gauss quadrature here). The source is taken
    // by the shadow rays; the glossy continuation that meets it must not add it again
    // (that would add the whole reflected image a second time, ≥ +50 % at the highlight).
    let s = common::scene(
        r#"
        [materials.floor]
        glossy_reflectance = 0.8
        roughness = 0.5
        [[objects]]
        shape = "rect"
        corner = [-5, -5, 0]
        u = [10, 0, 0]
        v = [0, 10, 0]
        material = "floor"
        [[lights]]
        type = "area"
        corner = [-0.5, 0.5, 2]
        u = [1, 0, 0]
        v = [0, -1, 0]
        luminance_cdm2 = 1000
        [camera]
        position = [0, -3, 2]
        look_at = [0, 0.5, 0]
        fov_deg = 40
        resolution = [24, 18]
        samples = 4
        area_light_samples = 16
        "#,
    );
    let r = render_zero_map(&s);
    let c = s.camera.as_ref().unwrap();
    let b = Bsdf::new(&s.materials[0]);
    let g = gauss8();
    let (mut sum_rel, mut n) = (0.0, 0);
    for y in 0..r.image.height {
        for x in 0..r.image.width {
            let (o, d) = pixel_ray(c, x, y);
            let got = r.image.luminance_cdm2[y * r.image.width + x];
            let Some(p) = floor_point(o, d) else { continue };
            // The eye pass jitters 4 rays in the pixel; the pixel centre's value is
            // compared where the image is smooth on the pixel scale (the floor
            // near the source's reflection: rough enough here).
            let mut want = 0.0;
            for (a, wa) in g {
                for (bb, wb) in g {
                    for (i, j) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)] {
                        let q = DVec3::new(-0.5 + i + 0.5 * a, 0.5 - j - 0.5 * bb, 2.0);
                        let to = q - p;
                        let r2 = to.length_squared();
                        let wi = to / r2.sqrt();
                        // dω = cos θ_source dA / r²; the source faces −z.
                        want += wa * wb * 0.25 * 1000.0 * b.f(-d, wi, DVec3::Z) * wi.z * wi.z / r2;
                    }
                }
            }
            if want > 20.0 {
                sum_rel += got / want - 1.0;
                n += 1;
            }
        }
    }
    let mean_rel = sum_rel / n as f64;
    eprintln!(
        "area source over glossy floor: mean relative deviation {mean_rel:.4} over {n} pixels"
    );
    assert!(n > 50, "{n} pixels");
    assert!(mean_rel.abs() < 0.02, "mean relative deviation {mean_rel}");
}

// ---- Mesh files' materials ----

use luxtally::scene::mesh_io::{gltf_to_material, mtl_to_material};

#[test]
fn mtl_ks_ns_map_to_glossy_reflectance_and_roughness() {
    // No Ks: Lambertian as before.
    assert_eq!(
        mtl_to_material([0.5; 3], None, Some(100.0)),
        (0.5, 0.0, 1.0)
    );
    assert_eq!(
        mtl_to_material([0.5; 3], Some([0.0; 3]), None),
        (0.5, 0.0, 1.0)
    );
    // Ks 0.5, Ns 198: α = √(2/200) = 0.1, roughness √0.1; the diffuse part keeps 1 − k_s.
    let (rho, g, r) = mtl_to_material([0.8; 3], Some([0.5; 3]), Some(198.0));
    assert!((rho - 0.4).abs() < 1e-12 && (g - 0.5).abs() < 1e-12);
    assert!((r - 0.1f64.sqrt()).abs() < 1e-12);
    // Never more than 1, however bright the file's colours.
    let (rho, g, _) = mtl_to_material([1.0; 3], Some([1.0; 3]), Some(10.0));
    assert!(rho + g <= 1.0);
    // A huge exponent is a mirror in effect, never roughness 0.
    assert_eq!(
        mtl_to_material([0.2; 3], Some([0.3; 3]), Some(1e14)).2,
        1e-3
    );
}

#[test]
fn gltf_metallic_roughness_map_to_lobes() {
    let (rho, g, r) = gltf_to_material([0.5; 3], 0.0, 0.6);
    assert!((rho - 0.96 * 0.5).abs() < 1e-12 && (g - 0.04).abs() < 1e-12 && r == 0.6);
    let (rho, g, r) = gltf_to_material([0.9; 3], 1.0, 0.0);
    assert!(rho == 0.0 && (g - 0.9).abs() < 1e-12 && r == 1e-3);
    for m in [0.0, 0.3, 1.0] {
        let (rho, g, _) = gltf_to_material([1.0; 3], m, 0.5);
        assert!(rho + g <= 1.0 + 1e-12, "metallic {m}: {}", rho + g);
    }
}

#[test]
fn obj_with_ks_and_ns_loads_a_glossy_material() {
    let dir = std::env::temp_dir().join(format!("luxtally-glossy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("quad.mtl"),
        "newmtl satin\nKd 0.6 0.6 0.6\nKs 0.25 0.25 0.25\nNs 48\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("quad.obj"),
        "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl satin\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let s = luxtally::scene::load_str("[[objects]]\nfile = \"quad.obj\"\n", &dir, "test.toml")
        .expect("loads");
    let m = &s.materials[s.geometry.material.get(0) as usize];
    assert!((m.reflectance - 0.6 * 0.75).abs() < 1e-6, "{m:?}");
    assert!((m.glossy_reflectance - 0.25).abs() < 1e-6);
    assert!((m.roughness - (2.0f64 / 50.0).sqrt().sqrt()).abs() < 1e-6);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_glossy_keys_are_one_line_errors_naming_material_and_key() {
    let err = |toml: &str| {
        luxtally::scene::load_str(toml, std::path::Path::new("."), "t.toml")
            .expect_err("rejected")
            .to_string()
    };
    let e =
        err("[materials.satin]\nreflectance = 0.5\nglossy_reflectance = 0.6\nroughness = 0.3\n");
    assert!(
        e.contains("materials.satin") && e.contains("1.1 > 1") && !e.contains('\n'),
        "{e}"
    );
    let e = err("[materials.satin]\nglossy_reflectance = 0.6\n");
    assert!(
        e.contains("materials.satin.roughness") && e.contains("required"),
        "{e}"
    );
    for bad in ["0", "1.5", "-0.2"] {
        let e = err(&format!(
            "[materials.satin]\nglossy_transmittance = 0.5\nroughness = {bad}\n"
        ));
        assert!(
            e.contains("materials.satin.roughness") && e.contains("(0, 1]"),
            "{e}"
        );
    }
    let e = err("[materials.satin]\nglossy_reflectance = -0.1\nroughness = 0.5\n");
    assert!(e.contains("materials.satin.glossy_reflectance"), "{e}");
}

//! The eye pass against analytic truth: direct light at diffuse surfaces, the indirect
//! map in a closed box, mirrors, area sources, thread and backend independence; and the
//! bundled office's image stored as a test artifact.

use crate::common;

use common::{parallel_corner_factor, scene};
use glam::DVec3;
use luxtally::accel::{self, Backend, RayBatch};
use luxtally::output::{write_all, Finished, IndirectMap, Outputs};
use luxtally::render::{self, Render};
use luxtally::run::{run, RunOptions};
use luxtally::scene::{Camera, Scene};
use luxtally::stats::{map_stats, MapKind};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

fn render_with(scene: &Scene, map: &IndirectMap, backend: Backend, threads: usize) -> Render {
    let caster = accel::build(backend, &scene.geometry).expect("backend builds");
    let camera = scene.camera.as_ref().expect("test scene has a camera");
    render::render(scene, camera, map, caster.as_ref(), 1, threads).expect("renders")
}

/// World ray through the centre of pixel (x, y): the pinhole model of docs/render.md,
/// written out independently of the renderer.
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

/// Where a ray meets the plane z = 0 (t > 0), if it does.
fn floor_point(o: DVec3, d: DVec3) -> Option<DVec3> {
    let t = -o.z / d.z;
    (t > 0.0).then(|| o + d * t)
}

/// Luminance of a Lambertian floor point p (normal +z) lit by an isotropic point source:
/// L = ρ·I·cos θ / (π r²).
fn lambert_point_cdm2(rho: f64, intensity_cd: f64, light: DVec3, p: DVec3) -> f64 {
    let to = light - p;
    let r2 = to.length_squared();
    rho * intensity_cd * (to.z / r2.sqrt()) / (PI * r2)
}

const FLOOR: &str = r#"
[materials.floor]
reflectance = 0.6

[[objects]]
shape = "rect"
corner = [-5, -5, 0]
u = [10, 0, 0]
v = [0, 10, 0]
material = "floor"

[[lights]]
type = "point"
position = [0.5, -0.3, 2]
intensity_cd = 150

[camera]
position = [0, -4, 3]
look_at = [0, 0, 0]
fov_deg = 50
resolution = [48, 36]
"#;

#[test]
fn floor_under_point_source_shows_rho_i_cos_over_pi_r2() {
    let s = scene(FLOOR);
    // A lone plane: no photon comes back to it, so its indirect map is exactly zero.
    let options = RunOptions::with_photons(&s, 20_000);
    let result = run(&s, &options, &AtomicBool::new(false), &mut ()).unwrap();
    let map = IndirectMap::from_tallies(&s, &result.progress.tallies, result.setup.total_flux_lm);
    assert!(map.face_lx.iter().all(|f| f == &[0.0, 0.0]));
    let r = render_with(&s, &map, Backend::Embree, 2);
    let c = s.camera.as_ref().unwrap();
    let light = DVec3::new(0.5, -0.3, 2.0);
    let mut checked = 0;
    for y in 0..r.image.height {
        for x in 0..r.image.width {
            let (o, d) = pixel_ray(c, x, y);
            let got = r.image.luminance_cdm2[y * r.image.width + x];
            match floor_point(o, d).filter(|p| p.x.abs() < 5.0 && p.y.abs() < 5.0) {
                Some(p) => {
                    let want = lambert_point_cdm2(0.6, 150.0, light, p);
                    assert!(
                        (got / want - 1.0).abs() < 1e-3,
                        "pixel ({x}, {y}): {got} cd/m² against {want}"
                    );
                    checked += 1;
                }
                None => assert_eq!(got, 0.0, "pixel ({x}, {y}) sees nothing"),
            }
        }
    }
    assert!(checked > 1000, "{checked} floor pixels");
}

#[test]
fn images_do_not_depend_on_threads() {
    let mut s = scene(FLOOR);
    s.camera.as_mut().unwrap().samples = 5;
    let map = IndirectMap::zero(s.geometry.triangle_count());
    let one = render_with(&s, &map, Backend::Embree, 1);
    let two = render_with(&s, &map, Backend::Embree, 2);
    assert_eq!(one.image, two.image);
}

#[test]
fn mirror_shows_the_floor_at_its_reflectance() {
    let s = scene(
        r#"
[materials.floor]
reflectance = 0.5
[materials.mirror]
specular_reflectance = 0.8

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
    // Direct light only: light reaching the floor by the mirror is in the indirect map,
    // left out here so the expected value is exact.
    let map = IndirectMap::zero(s.geometry.triangle_count());
    let r = render_with(&s, &map, Backend::Embree, 2);
    let c = s.camera.as_ref().unwrap();
    let light = DVec3::new(0.0, 0.4, 2.0);
    let (mut in_mirror, mut direct) = (0, 0);
    for y in 0..r.image.height {
        for x in 0..r.image.width {
            let (o, d) = pixel_ray(c, x, y);
            let got = r.image.luminance_cdm2[y * r.image.width + x];
            let t_mirror = (2.0 - o.x) / d.x;
            let m = o + d * t_mirror;
            let on_mirror = m.y.abs() < 3.0 && m.z > 0.0 && m.z < 3.0;
            let t_floor = -o.z / d.z;
            let want = if on_mirror && !(t_floor > 0.0 && t_floor < t_mirror) {
                let reflected = DVec3::new(-d.x, d.y, d.z);
                match floor_point(m, reflected) {
                    Some(p) if p.x > -5.0 && p.y.abs() < 5.0 => {
                        in_mirror += 1;
                        0.8 * lambert_point_cdm2(0.5, 100.0, light, p)
                    }
                    _ => continue,
                }
            } else if t_floor > 0.0 {
                direct += 1;
                lambert_point_cdm2(0.5, 100.0, light, o + d * t_floor)
            } else {
                continue;
            };
            // Pixels whose centre ray grazes the mirror's edge are left out.
            if (m.y.abs() - 3.0).abs() < 0.05 || m.z.abs() < 0.05 {
                continue;
            }
            assert!(
                (got / want - 1.0).abs() < 1e-3,
                "pixel ({x}, {y}): {got} cd/m² against {want}"
            );
        }
    }
    assert!(
        in_mirror > 200 && direct > 50,
        "{in_mirror} mirror, {direct} floor pixels"
    );
}

#[test]
fn area_source_direct_light_matches_configuration_factor() {
    // A 1 × 0.8 m source 1.5 m above the floor, camera straight down at the point under
    // its centre: E = π·L·F with F from the exact parallel-rectangle factor.
    let s = scene(
        r#"
[materials.floor]
reflectance = 0.7
[[objects]]
shape = "rect"
corner = [-3, -3, 0]
u = [6, 0, 0]
v = [0, 6, 0]
material = "floor"
[[lights]]
type = "area"
corner = [-0.5, -0.4, 1.5]
u = [0, 0.8, 0]
v = [1, 0, 0]
luminance_cdm2 = 2000
[camera]
position = [0, 0, 1]
look_at = [0, 0, 0]
up = [0, 1, 0]
fov_deg = 1
resolution = [3, 3]
"#,
    );
    let map = IndirectMap::zero(s.geometry.triangle_count());
    let r = render_with(&s, &map, Backend::Embree, 1);
    let f = 4.0 * parallel_corner_factor(0.5, 0.4, 1.5);
    let want = 0.7 * PI * 2000.0 * f / PI;
    let got = r.image.luminance_cdm2[4];
    eprintln!("area source: {got} cd/m² against {want}");
    assert!((got / want - 1.0).abs() < 2e-3, "{got} against {want}");
}

const BOX: &str = r#"
[materials.wall]
reflectance = 0.5
[[objects]]
shape = "box"
min = [0, 0, 0]
max = [4, 3, 2.5]
material = "wall"
[[lights]]
type = "point"
position = [2, 1.5, 1.25]
intensity_cd = 300
[camera]
position = [0.5, 1.5, 1.25]
look_at = [4, 1.5, 1.25]
fov_deg = 60
resolution = [32, 24]
"#;

#[test]
fn closed_box_wall_shows_direct_plus_indirect_map() {
    let mut s = scene(BOX);
    let options = RunOptions {
        threads: 2,
        ..RunOptions::with_photons(&s, 400_000)
    };
    let result = run(&s, &options, &AtomicBool::new(false), &mut ()).unwrap();
    let map = IndirectMap::from_tallies(&s, &result.progress.tallies, result.setup.total_flux_lm);
    let stats = map_stats(
        &result.progress.tallies,
        MapKind::Indirect,
        &s.geometry,
        result.setup.total_flux_lm,
    );
    let light = DVec3::new(2.0, 1.5, 1.25);
    let caster = accel::build(Backend::Embree, &s.geometry).unwrap();
    for interpolate in [false, true] {
        s.camera.as_mut().unwrap().interpolate = interpolate;
        let r = render_with(&s, &map, Backend::Embree, 2);
        let c = s.camera.as_ref().unwrap();
        let mut worst = 0.0f64;
        for (x, y) in [(3, 3), (16, 12), (28, 20), (8, 18), (25, 5)] {
            let (o, d) = pixel_ray(c, x, y);
            // Which triangle and face the pixel sees, from the backend itself.
            let mut rays = RayBatch::default();
            let ol = (o - s.geometry.origin).as_vec3();
            rays.push(ol.into(), d.as_vec3().into(), 0.0, f32::INFINITY);
            let mut hits = Default::default();
            caster.intersect(&rays, &mut hits);
            let k = hits.tri[0] as usize;
            let n = s.geometry.normal(k).as_dvec3();
            let back = d.dot(n) > 0.0;
            let facing = if back { -n } else { n };
            let p = o + d * hits.t[0] as f64;
            let to = light - p;
            let e_direct = 300.0 * facing.dot(to.normalize()) / to.length_squared();
            let e_indirect = map.face_lx[k][back as usize];
            let want = 0.5 * (e_direct + e_indirect) / PI;
            let got = r.image.luminance_cdm2[y * c.resolution[0] as usize + x];
            // In luminance units, the map's RMS error σ (odd/even, method.md §3).
            let sigma = 0.5 * stats.sigma_lx / PI;
            let z = (got - want) / sigma;
            eprintln!(
                "interpolate {interpolate}: pixel ({x}, {y}) {got:.4} against {want:.4} cd/m² \
                 (E direct {e_direct:.2}, indirect {e_indirect:.2} lx), {z:.2} σ"
            );
            if interpolate {
                worst = worst.max(z.abs());
            } else {
                assert!((got / want - 1.0).abs() < 1e-4, "pixel ({x}, {y}) raw map");
            }
        }
        // Interpolation only mixes a wall's triangles, equal but for noise here.
        assert!(
            worst < 3.0,
            "interpolated luminance {worst:.1} σ from the map"
        );
    }
}

#[test]
fn saved_map_round_trips_and_refuses_another_scene() {
    let s = scene(BOX);
    let mut map = IndirectMap::zero(s.geometry.triangle_count());
    map.face_lx[3] = [1.5, 2.25];
    map.photons = 7;
    let dir = std::env::temp_dir().join(format!("luxtally-map-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(luxtally::output::MAP_FILE);
    map.save(&path, &s).unwrap();
    assert_eq!(IndirectMap::load(&path, &s).unwrap(), map);
    let other = scene(&BOX.replace("reflectance = 0.5", "reflectance = 0.4"));
    let message = IndirectMap::load(&path, &other).unwrap_err().to_string();
    assert!(
        !message.contains('\n') && message.contains("indirect_map.bin"),
        "{message}"
    );
    assert!(message.contains("another scene"), "{message}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Where test artifacts go: `<target dir>/test-artifacts/`.
fn artifacts_dir() -> PathBuf {
    let tmp = Path::new(env!("CARGO_TARGET_TMPDIR"));
    tmp.parent().unwrap_or(tmp).join("test-artifacts")
}

#[test]
fn office_image_is_stored_as_an_artifact() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/office.toml");
    let s = luxtally::scene::load(&path).unwrap();
    let options = RunOptions {
        threads: 2,
        ..RunOptions::with_photons(&s, 300_000)
    };
    let result = run(&s, &options, &AtomicBool::new(false), &mut ()).unwrap();
    let map = IndirectMap::from_tallies(&s, &result.progress.tallies, result.setup.total_flux_lm);
    let r = render_with(&s, &map, Backend::Embree, 2);
    let dir = artifacts_dir().join("office_render");
    std::fs::create_dir_all(&dir).unwrap();
    let finished = Finished {
        run: None,
        image: Some(&r.image),
    };
    write_all(&dir, finished, Outputs::ALL).unwrap();
    eprintln!(
        "office: {:.2} M eye rays/s, {:.2} s per megapixel; images in {}",
        r.eye_rays_per_s() / 1e6,
        r.s_per_megapixel(),
        dir.display()
    );
    for f in ["render.exr", "render.png", "render_false_colour.png"] {
        assert!(dir.join(f).metadata().unwrap().len() > 1000, "{f}");
    }
    // Every pixel sees a wall, the floor, the ceiling or the table: all lit.
    assert!(r
        .image
        .luminance_cdm2
        .iter()
        .all(|&l| l > 0.0 && l.is_finite()));
}

#[cfg(feature = "obvhs")]
#[test]
fn both_backends_give_the_same_image() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/office.toml");
    let mut s = luxtally::scene::load(&path).unwrap();
    let c = s.camera.as_mut().unwrap();
    c.resolution = [160, 120];
    let options = RunOptions {
        threads: 2,
        ..RunOptions::with_photons(&s, 100_000)
    };
    let result = run(&s, &options, &AtomicBool::new(false), &mut ()).unwrap();
    let map = IndirectMap::from_tallies(&s, &result.progress.tallies, result.setup.total_flux_lm);
    let a = render_with(&s, &map, Backend::Embree, 2).image;
    let b = render_with(&s, &map, Backend::Obvhs, 2).image;
    // Hit points agree to f32 rounding; a pixel whose ray grazes an edge may see a
    // different triangle of the same surface, so allow a handful of such pixels.
    let differing = a
        .luminance_cdm2
        .iter()
        .zip(&b.luminance_cdm2)
        .filter(|(x, y)| (*x - *y).abs() > 1e-4 * x.abs().max(1e-9))
        .count();
    eprintln!("{differing} of {} pixels differ", a.luminance_cdm2.len());
    assert!(
        differing * 1000 <= a.luminance_cdm2.len(),
        "{differing} pixels differ"
    );
}

/// Loads `text` as a scene file and returns its error, checked to be one line naming the
/// file and `key`.
fn camera_error(text: &str, key: &str) -> String {
    let path = std::env::temp_dir().join(format!(
        "luxtally-camera-{}-{}.toml",
        std::process::id(),
        key.replace('.', "_")
    ));
    std::fs::write(&path, text).unwrap();
    let result = luxtally::scene::load(&path);
    let _ = std::fs::remove_file(&path);
    let message = match result {
        Ok(_) => panic!("scene loaded but should not have:\n{text}"),
        Err(e) => e.to_string(),
    };
    assert!(!message.contains('\n'), "not one line: {message:?}");
    for part in [&path.display().to_string(), key] {
        assert!(message.contains(part), "`{part}` missing from: {message}");
    }
    message
}

#[test]
fn bad_camera_keys_are_one_line_errors_naming_the_key() {
    let good = "position = [0, 0, 1]\nlook_at = [1, 0, 1]\nfov_deg = 60\nresolution = [8, 6]\n";
    let with = |replace: &str, by: &str| format!("[camera]\n{}", good.replace(replace, by));
    let cases = [
        (
            with("look_at = [1, 0, 1]", "look_at = [0, 0, 1]"),
            "camera.look_at",
        ),
        (format!("[camera]\n{good}up = [1, 0, 0]\n"), "camera.up"),
        (format!("[camera]\n{good}up = [0, 0, 0]\n"), "camera.up"),
        (with("fov_deg = 60", "fov_deg = 180"), "camera.fov_deg"),
        (with("fov_deg = 60", "fov_deg = -5"), "camera.fov_deg"),
        (with("[8, 6]", "[0, 6]"), "camera.resolution"),
        (with("[8, 6]", "[8, 100000]"), "camera.resolution"),
        (with("[8, 6]", "[8]"), "camera.resolution"),
        (format!("[camera]\n{good}samples = 0\n"), "camera.samples"),
        (
            format!("[camera]\n{good}area_light_samples = 0\n"),
            "camera.area_light_samples",
        ),
        (
            format!("[camera]\n{good}max_depth = 1000\n"),
            "camera.max_depth",
        ),
        (
            format!("[camera]\n{good}interpolate = 1\n"),
            "camera.interpolate",
        ),
        (format!("[camera]\n{good}zoom = 2\n"), "zoom"),
        (with("fov_deg = 60\n", ""), "fov_deg"),
        (
            with("position = [0, 0, 1]", "position = [0, nan, 1]"),
            "camera.position",
        ),
    ];
    for (text, key) in &cases {
        let m = camera_error(text, key);
        eprintln!("{m}");
    }
}

fn luxtally(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("binary runs")
}

#[test]
fn render_command_writes_images_and_reuses_a_finished_run() {
    let dir = std::env::temp_dir().join(format!("luxtally-render-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let run_dir = dir.join("run");
    let run_dir_s = run_dir.to_str().unwrap();
    let out = luxtally(&[
        "run",
        "scenes/office.toml",
        "--photons",
        "50000",
        "--quiet",
        "--out",
        run_dir_s,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(run_dir.join("indirect_map.bin").exists());
    // --from: no photon pass, images next to the run's outputs.
    let out = luxtally(&["render", "scenes/office.toml", "--from", run_dir_s]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("eye rays/s") && text.contains("per megapixel"),
        "{text}"
    );
    for f in ["render.exr", "render.png", "render_false_colour.png"] {
        assert!(run_dir.join(f).exists(), "{f}");
    }
    // A map of another scene is refused, on one line naming the map.
    let other = dir.join("other.toml");
    let office = std::fs::read_to_string("scenes/office.toml").unwrap();
    std::fs::write(
        &other,
        office.replace("intensity_cd = 1000", "intensity_cd = 999"),
    )
    .unwrap();
    let out = luxtally(&["render", other.to_str().unwrap(), "--from", run_dir_s]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("indirect_map.bin") && err.contains("another scene"),
        "{err}"
    );
    // A scene without a camera.
    std::fs::write(&other, office.split("[camera]").next().unwrap()).unwrap();
    let out = luxtally(&[
        "render",
        other.to_str().unwrap(),
        "--quiet",
        "--photons",
        "1000",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("[camera]") && err.contains("other.toml"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// How the area-source sample count was chosen (docs/render.md): the relative noise of
/// the direct term over pixels that all see (nearly) the same floor point, for n × n
/// samples at heights h below a 1 × 0.8 m source. `cargo test --release --test suite
/// physics::render::area_source_noise -- --ignored --nocapture`.
#[test]
#[ignore]
fn area_source_noise_by_sample_count() {
    for h in [0.25, 0.5, 1.5] {
        for n in [4, 8, 16] {
            let s = scene(&format!(
                r#"
[materials.floor]
reflectance = 0.7
[[objects]]
shape = "rect"
corner = [-3, -3, 0]
u = [6, 0, 0]
v = [0, 6, 0]
material = "floor"
[[lights]]
type = "area"
corner = [-0.5, -0.4, {h}]
u = [0, 0.8, 0]
v = [1, 0, 0]
luminance_cdm2 = 2000
[camera]
position = [0, 0, {}]
look_at = [0, 0, 0]
up = [0, 1, 0]
fov_deg = 0.01
resolution = [64, 64]
area_light_samples = {n}
"#,
                h * 0.5
            ));
            let map = IndirectMap::zero(s.geometry.triangle_count());
            let l = render_with(&s, &map, Backend::Embree, 2)
                .image
                .luminance_cdm2;
            let mean = l.iter().sum::<f64>() / l.len() as f64;
            let sd = (l.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / l.len() as f64).sqrt();
            let exact = 0.7 * 2000.0 * 4.0 * parallel_corner_factor(0.5, 0.4, h);
            eprintln!(
                "h = {h} m, n = {n}: noise {:.4} %, bias {:+.4} %",
                100.0 * sd / mean,
                100.0 * (mean / exact - 1.0)
            );
        }
    }
}

/// A 3 × 3 image looking straight down from (0, 0, `eye_z`): the centre pixel's ray is
/// the −z axis.
fn looking_down(eye_z: f64) -> String {
    format!(
        "[camera]\nposition = [0, 0, {eye_z}]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov_deg = 1\nresolution = [3, 3]\n"
    )
}

#[test]
fn diffuse_transmitter_shows_light_from_its_other_side() {
    // A translucent pane (τ = 0.4, ρ = 0.1) with the source below it, seen from above:
    // L = τ·I·cos θ/(π r²) (light on the far face); its near face gets no direct light.
    let s = scene(&format!(
        r#"
[materials.pane]
reflectance = 0.1
transmittance = 0.4
[[objects]]
shape = "rect"
corner = [-1, -1, 1]
u = [2, 0, 0]
v = [0, 2, 0]
material = "pane"
[[lights]]
type = "point"
position = [0.3, 0, 0.2]
intensity_cd = 50
{}"#,
        looking_down(3.0)
    ));
    let map = IndirectMap::zero(s.geometry.triangle_count());
    let got = render_with(&s, &map, Backend::Embree, 1)
        .image
        .luminance_cdm2[4];
    let to = DVec3::new(0.3, 0.0, 0.2) - DVec3::new(0.0, 0.0, 1.0);
    let want = 0.4 * 50.0 * (-to.z / to.length()) / (PI * to.length_squared());
    assert!((got / want - 1.0).abs() < 1e-4, "{got} against {want}");
}

#[test]
fn glass_pane_passes_the_floor_at_normal_incidence_fresnel() {
    // Eye ray straight down through a glass interface (t_s = 0.9, n = 1.5): the floor
    // below shows through at t_s·(1 − F), F = ((n − 1)/(n + 1))² = 0.04; the reflected
    // part sees nothing. The source is under the glass (glass casts a direct shadow).
    let s = scene(&format!(
        r#"
[materials.glass]
specular_transmittance = 0.9
ior = 1.5
[materials.floor]
reflectance = 0.5
[[objects]]
shape = "rect"
corner = [-1, -1, 2]
u = [2, 0, 0]
v = [0, 2, 0]
material = "glass"
[[objects]]
shape = "rect"
corner = [-3, -3, 0]
u = [6, 0, 0]
v = [0, 6, 0]
material = "floor"
[[lights]]
type = "point"
position = [0.3, 0, 1]
intensity_cd = 80
{}"#,
        looking_down(3.0)
    ));
    let map = IndirectMap::zero(s.geometry.triangle_count());
    let got = render_with(&s, &map, Backend::Embree, 1)
        .image
        .luminance_cdm2[4];
    let fresnel = (0.5f64 / 2.5).powi(2);
    let floor = lambert_point_cdm2(0.5, 80.0, DVec3::new(0.3, 0.0, 1.0), DVec3::ZERO);
    let want = 0.9 * (1.0 - fresnel) * floor;
    assert!((got / want - 1.0).abs() < 1e-4, "{got} against {want}");
}

#[test]
fn area_source_is_seen_from_its_emitting_side_only() {
    // Looking up at a downward-emitting source shows its luminance; from above, its back
    // is invisible and the pixel sees nothing.
    let light = r#"
[[lights]]
type = "area"
corner = [-0.5, -0.5, 2]
u = [0, 1, 0]
v = [1, 0, 0]
luminance_cdm2 = 1234
"#;
    let below = scene(&format!(
        "{light}[camera]\nposition = [0, 0, 0]\nlook_at = [0, 0, 1]\nup = [0, 1, 0]\nfov_deg = 1\nresolution = [3, 3]\n"
    ));
    let above = scene(&format!("{light}{}", looking_down(3.0)));
    for (s, want) in [(below, 1234.0), (above, 0.0)] {
        let map = IndirectMap::zero(0);
        let got = render_with(&s, &map, Backend::Embree, 1)
            .image
            .luminance_cdm2[4];
        assert_eq!(got, want);
    }
}

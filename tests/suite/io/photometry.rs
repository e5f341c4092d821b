//! Photometric files: the flux of the interpolant, directions sampled from it, every
//! symmetry form of LM-63 and EULUMDAT expanding to the same intensity function, tilt,
//! units and factors, and one clear line (file and line number) for every malformed file.

use crate::common;

use common::gauss8;
use glam::DVec3;
use luxtally::photometry::{
    self, c_gamma_deg, Format, Opening, PhotometricType, Photometry, Symmetry,
};
use luxtally::sampling::uniform;
use rand_pcg::Pcg32;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/photometry")
        .join(name)
}

fn load(name: &str) -> Photometry {
    let path = if name == "examp1.ies" {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/photometry/examp1.ies")
    } else {
        data(name)
    };
    photometry::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// ∫ I dΩ over [c0, c1] × [g0, g1] (degrees) by 8 × 8 Gauss–Legendre in C and γ on
/// `intensity_cd`: independent of the library's cell integrals. Cells must lie within one
/// table cell for the bilinear interpolant to be smooth there.
fn quad_flux(p: &Photometry, c0: f64, c1: f64, g0: f64, g1: f64) -> f64 {
    let g = gauss8();
    let (dc, dg) = ((c1 - c0).to_radians(), (g1 - g0).to_radians());
    let mut sum = 0.0;
    for (sc, wc) in g {
        for (sg, wg) in g {
            let (c, gamma) = (c0 + sc * (c1 - c0), g0 + sg * (g1 - g0));
            sum += wc * wg * p.intensity_cd(c, gamma) * libm::sin(gamma.to_radians());
        }
    }
    sum * dc * dg
}

/// ∫ I dΩ over a grid of C and γ nodes, cell by cell.
fn quad_flux_grid(p: &Photometry, c_nodes: &[f64], g_nodes: &[f64]) -> f64 {
    let mut sum = 0.0;
    for c in c_nodes.windows(2) {
        for g in g_nodes.windows(2) {
            sum += quad_flux(p, c[0], c[1], g[0], g[1]);
        }
    }
    sum
}

fn steps(from: f64, to: f64, step: f64) -> Vec<f64> {
    let n = ((to - from) / step).round() as usize;
    (0..=n).map(|k| from + step * k as f64).collect()
}

fn rms(z: &[f64]) -> f64 {
    (z.iter().map(|x| x * x).sum::<f64>() / z.len() as f64).sqrt()
}

/// Draws `n` directions (through `sample_direction`, the vector the light code uses),
/// bins them on C × γ edges (each bin within one table cell) and compares each bin with its exact share of the flux:
/// binomial z-scores, RMS within [0.8, 1.25], none beyond 5σ, nothing where the
/// interpolant is 0.
fn assert_sampling_reproduces(
    p: &Photometry,
    n: usize,
    c_edges: &[f64],
    g_edges: &[f64],
    what: &str,
) {
    assert_draws_reproduce(p, n, (c_edges, g_edges), what, &mut |rng| {
        p.sample_direction(rng)
    });
}

/// [`assert_sampling_reproduces`] for directions drawn by `draw`.
fn assert_draws_reproduce(
    p: &Photometry,
    n: usize,
    (c_edges, g_edges): (&[f64], &[f64]),
    what: &str,
    draw: &mut dyn FnMut(&mut Pcg32) -> DVec3,
) {
    let (nc, ng) = (c_edges.len() - 1, g_edges.len() - 1);
    let mut counts = vec![0u64; nc * ng];
    let mut rng = Pcg32::new(0x5eed, 7);
    for _ in 0..n {
        let d = draw(&mut rng);
        assert!(
            (d.length() - 1.0).abs() < 1e-9,
            "{what}: not a unit vector: {d}"
        );
        let (c, g) = c_gamma_deg(d);
        let i = c_edges.partition_point(|&e| e <= c).clamp(1, nc) - 1;
        let j = g_edges.partition_point(|&e| e <= g).clamp(1, ng) - 1;
        counts[i * ng + j] += 1;
    }
    let flux = p.flux_lm();
    let mut z = Vec::new();
    for i in 0..nc {
        for j in 0..ng {
            let share = quad_flux(p, c_edges[i], c_edges[i + 1], g_edges[j], g_edges[j + 1]) / flux;
            let k = counts[i * ng + j] as f64;
            if share <= 0.0 {
                assert_eq!(
                    k, 0.0,
                    "{what}: bin C {} γ {}: photons where I = 0",
                    c_edges[i], g_edges[j]
                );
                continue;
            }
            let expected = n as f64 * share;
            z.push((k - expected) / (expected * (1.0 - share)).sqrt());
        }
    }
    let r = rms(&z);
    let worst = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    eprintln!(
        "{what}: {n} directions, {} bins, z RMS {r:.3}, worst {worst:.2}",
        z.len()
    );
    assert!((0.8..=1.25).contains(&r), "{what}: z RMS {r:.3}");
    assert!(worst < 5.0, "{what}: a bin is {worst:.1}σ off");
}

// ---------------------------------------------------------------------------------------
// examp1.ies

#[test]
fn examp1_flux_of_the_interpolant_is_5296_65_lm() {
    let p = load("examp1.ies");
    let flux = p.flux_lm();
    eprintln!("examp1.ies: {flux:.4} lm");
    assert!((flux - 5296.65).abs() <= 1e-4 * 5296.65, "{flux}");
    // The same integral by quadrature over the expanded table's cells.
    let q = quad_flux_grid(&p, &steps(0.0, 360.0, 22.5), &steps(0.0, 180.0, 2.5));
    assert!((q - flux).abs() <= 1e-9 * flux, "quadrature {q} vs {flux}");
    assert_eq!(p.format, Format::Ies(1995));
    assert_eq!(p.photometric_type, PhotometricType::C);
    assert_eq!(p.symmetry, Symmetry::Quadrant);
    assert_eq!(p.lamp_flux_lm, Some(5800.0));
    let lor = p.light_output_ratio().unwrap();
    assert!(
        (lor - flux / 5800.0).abs() < 1e-12 && (lor - 0.913).abs() < 5e-4,
        "{lor}"
    );
    match p.opening {
        Opening::Rectangle { length_m, width_m } => {
            assert!((length_m - 4.04 * 0.3048).abs() < 1e-12);
            assert!((width_m - 0.85 * 0.3048).abs() < 1e-12);
        }
        o => panic!("{o:?}"),
    }
    assert!((p.height_m - 0.292 * 0.3048).abs() < 1e-12);
    assert_eq!(
        p.keyword("MANUFAC"),
        Some("Ledalite Architectural Products  604-888-6811")
    );
    // Quadrant symmetry: C and −C, C and 180 − C see the same table.
    for (c, g) in [(10.0, 20.0), (33.3, 100.0), (80.0, 47.5)] {
        let i = p.intensity_cd(c, g);
        for c2 in [360.0 - c, 180.0 - c, 180.0 + c] {
            assert!((p.intensity_cd(c2, g) - i).abs() < 1e-9 * i.max(1.0));
        }
    }
    assert_eq!(p.intensity_cd(22.5, 2.5), 778.7);
    let peak = p.peak();
    assert_eq!((peak.intensity_cd, peak.gamma_deg), (1065.2, 25.0));
    assert!(peak.c_deg == 90.0 || peak.c_deg == 270.0, "{peak:?}");
}

#[test]
fn examp1_sampled_directions_reproduce_the_table() {
    let p = load("examp1.ies");
    assert_sampling_reproduces(
        &p,
        4_000_000,
        &steps(0.0, 360.0, 22.5),
        &steps(0.0, 180.0, 2.5),
        "examp1.ies",
    );
}

/// A QMC run's directions (`sample_direction_from`: the cell by inversion, the first
/// proposal from the point) have the same density: fed uniform random points, they
/// reproduce the table as `sample_direction` does, on a finer binning than the table's.
#[test]
fn examp1_directions_from_points_reproduce_the_table() {
    let p = load("examp1.ies");
    let (c, g) = (steps(0.0, 360.0, 11.25), steps(0.0, 180.0, 1.25));
    assert_draws_reproduce(
        &p,
        4_000_000,
        (&c, &g),
        "examp1.ies by inversion",
        &mut |rng| {
            let square = (uniform(rng), uniform(rng));
            p.sample_direction_from(square, rng)
        },
    );
}

// ---------------------------------------------------------------------------------------
// Synthetic distributions with known integrals

/// 2π ∫ L(γ) sin γ dγ for L the linear interpolation of I0 cos γ (0 beyond 90°) at every
/// `h_deg`, by Gauss–Legendre on each interval: the interpolant's exact flux.
fn cosine_interpolant_flux(i0: f64, h_deg: f64) -> f64 {
    let f = |g: f64| {
        if g <= 90.0 {
            i0 * libm::cos(g.to_radians())
        } else {
            0.0
        }
    };
    let mut sum = 0.0;
    for w in steps(0.0, 180.0, h_deg).windows(2) {
        let (a, b) = (w[0], w[1]);
        for (s, wt) in gauss8() {
            let g = a + s * (b - a);
            let l = f(a) + s * (f(b) - f(a));
            sum += wt * l * libm::sin(g.to_radians()) * (b - a).to_radians();
        }
    }
    2.0 * PI * sum
}

#[test]
fn cosine_distribution_has_flux_pi_i0_up_to_the_interpolation_error() {
    let p = load("cosine.ies");
    assert_eq!(p.symmetry, Symmetry::Rotational);
    assert_eq!(p.lamp_flux_lm, None, "lumens −1: absolute photometry");
    assert_eq!(p.light_output_ratio(), None);
    assert_eq!(p.opening, Opening::Point);
    let exact = cosine_interpolant_flux(1000.0, 5.0);
    assert!(
        (p.flux_lm() - exact).abs() <= 1e-8 * exact,
        "{} vs {exact}",
        p.flux_lm()
    );
    // Linear interpolation of the concave cos γ lies below it, by at most h²/8 · I0:
    // the flux is short of π I0 by at most π I0 h²/4.
    let h = 5f64.to_radians();
    let shortfall = PI * 1000.0 - p.flux_lm();
    eprintln!(
        "cosine: Φ = {:.4} lm, π I0 − Φ = {shortfall:.4} lm",
        p.flux_lm()
    );
    assert!(
        shortfall > 0.0 && shortfall <= PI * 1000.0 * h * h / 4.0,
        "{shortfall}"
    );
    // Rotationally symmetric: every C the same.
    for c in [0.0, 17.0, 123.4, 359.9] {
        assert!((p.intensity_cd(c, 32.5) - p.intensity_cd(0.0, 32.5)).abs() < 1e-12);
    }
    assert_eq!(p.intensity_cd(0.0, 120.0), 0.0);
    assert_sampling_reproduces(
        &p,
        1_000_000,
        &steps(0.0, 360.0, 30.0),
        &steps(0.0, 180.0, 5.0),
        "cosine.ies",
    );
}

#[test]
fn eulumdat_cosine_equals_the_ies_cosine() {
    let ies = load("cosine.ies");
    let ldt = load("cosine.ldt");
    assert_eq!(ldt.format, Format::Eulumdat);
    assert_eq!(ldt.symmetry, Symmetry::Rotational);
    assert_eq!(ldt.lamp_flux_lm, Some(1000.0));
    assert_eq!(ldt.stated_light_output_ratio, Some(1.0));
    assert!((ldt.flux_lm() - ies.flux_lm()).abs() < 1e-9 * ies.flux_lm());
    for (c, g) in [(0.0, 0.0), (200.0, 42.0), (77.0, 89.0), (5.0, 150.0)] {
        assert!((ldt.intensity_cd(c, g) - ies.intensity_cd(c, g)).abs() < 1e-6);
    }
}

#[test]
fn lobe_in_the_c90_plane_sends_every_direction_to_plus_y() {
    let p = load("lobe_c90.ies");
    assert_eq!(p.symmetry, Symmetry::None);
    assert_eq!(p.intensity_cd(90.0, 50.0), 500.0);
    assert_eq!(p.intensity_cd(270.0, 50.0), 0.0);
    assert_eq!(p.intensity_cd(0.0, 50.0), 0.0);
    let mut rng = Pcg32::new(3, 3);
    for _ in 0..100_000 {
        let d = p.sample_direction(&mut rng);
        // Planes C 80–100 at γ 30–70 only.
        assert!(
            d.y > 0.0 && d.x.abs() <= d.y * libm::tan(10f64.to_radians()) + 1e-12,
            "{d}"
        );
        let (c, g) = c_gamma_deg(d);
        assert!(
            (80.0..=100.0).contains(&c) && (30.0..=70.0).contains(&g),
            "C {c} γ {g}"
        );
    }
    let peak = p.peak();
    assert_eq!((peak.c_deg, peak.intensity_cd), (90.0, 500.0));
}

// ---------------------------------------------------------------------------------------
// Every symmetry form, LM-63 and EULUMDAT

/// LM-63-2002 text of a type C table: `f(C, γ)` at the given angles.
fn ies_text(horizontal: &[f64], vertical: &[f64], f: &dyn Fn(f64, f64) -> f64) -> String {
    let mut s = String::from("IESNA:LM-63-2002\n[TEST] symmetry form\nTILT=NONE\n");
    s += &format!(
        "1 -1 1 {} {} 1 2 0 0 0\n1 1 10\n",
        vertical.len(),
        horizontal.len()
    );
    let join = |v: Vec<f64>| {
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    s += &(join(vertical.to_vec()) + "\n");
    s += &(join(horizontal.to_vec()) + "\n");
    for &h in horizontal {
        s += &(join(vertical.iter().map(|&v| f(h, v)).collect()) + "\n");
    }
    s
}

/// EULUMDAT text of the same: Mc planes every 360/Mc, intensities for the planes Isym
/// stores (C270 … C90 for Isym 3), in cd/klm of a 2000 lm lamp set.
fn ldt_text(isym: u8, mc: usize, gamma: &[f64], f: &dyn Fn(f64, f64) -> f64) -> String {
    let dc = 360.0 / mc as f64;
    let (first, count) = match isym {
        0 => (0, mc),
        1 => (0, 1),
        2 => (0, mc / 2 + 1),
        3 => (3 * mc / 4, mc / 2 + 1),
        _ => (0, mc / 4 + 1),
    };
    let mut l: Vec<String> = vec![
        "luxtally test".into(),
        "1".into(),
        isym.to_string(),
        mc.to_string(),
        dc.to_string(),
        gamma.len().to_string(),
        "10".into(),
    ];
    l.extend(["report", "name", "number", "file.ldt", "date"].map(String::from));
    // Luminaire 600 × 600 × 80 mm, luminous area 500 × 300 mm.
    l.extend(["600", "600", "80", "500", "300", "0", "0", "0", "0"].map(String::from));
    l.extend(
        [
            "100", "80", "1", "0", "1", "2", "LED", "2000", "4000K", "1A", "20",
        ]
        .map(String::from),
    );
    l.extend(std::iter::repeat_n("0.5".to_string(), 10));
    l.extend((0..mc).map(|k| (dc * k as f64).to_string()));
    l.extend(gamma.iter().map(|g| g.to_string()));
    for k in 0..count {
        let c = (dc * ((first + k) % mc) as f64) % 360.0;
        l.extend(gamma.iter().map(|&g| (f(c, g) / 2.0).to_string()));
    }
    l.join("\r\n") + "\r\n"
}

fn parse_ies(text: &str, name: &str) -> Photometry {
    photometry::parse_ies(text, name, Path::new("."))
        .unwrap_or_else(|e| panic!("{name}: {e}\n{text}"))
}

fn parse_ldt(text: &str, name: &str) -> Photometry {
    photometry::parse_ldt(text, name).unwrap_or_else(|e| panic!("{name}: {e}\n{text}"))
}

/// `other` is `reference`'s intensity function: at random (C, γ) and on the nodes' edges,
/// and in flux.
fn assert_same_function(reference: &Photometry, other: &Photometry, what: &str) {
    let scale = reference.peak_cd();
    let mut rng = Pcg32::new(11, 13);
    let mut points: Vec<(f64, f64)> = (0..3000)
        .map(|_| (360.0 * uniform(&mut rng), 180.0 * uniform(&mut rng)))
        .collect();
    points.extend([
        (0.0, 0.0),
        (360.0, 90.0),
        (90.0, 180.0),
        (270.0, 45.0),
        (180.0, 10.0),
    ]);
    for (c, g) in points {
        let (a, b) = (reference.intensity_cd(c, g), other.intensity_cd(c, g));
        assert!(
            (a - b).abs() <= 1e-9 * scale,
            "{what}: C {c} γ {g}: {b} vs {a}"
        );
    }
    let (fa, fb) = (reference.flux_lm(), other.flux_lm());
    assert!((fa - fb).abs() <= 1e-12 * fa, "{what}: flux {fb} vs {fa}");
}

#[test]
fn every_symmetry_form_expands_to_the_same_intensity_function() {
    let gamma = steps(0.0, 180.0, 10.0);
    let full = steps(0.0, 360.0, 15.0);
    // (name, function, symmetric forms as (first, last) horizontal angles and their
    // Symmetry, EULUMDAT Isym values that can carry it)
    type F = fn(f64, f64) -> f64;
    type Family = (&'static str, F, Vec<(f64, f64, Symmetry)>, Vec<u8>);
    let families: [Family; 5] = [
        (
            "quadrant",
            |c, g| {
                100.0
                    + 60.0 * libm::cos((2.0 * c).to_radians()) * libm::sin((g / 2.0).to_radians())
                    + 30.0 * libm::cos((4.0 * c).to_radians())
            },
            vec![
                (0.0, 90.0, Symmetry::Quadrant),
                (0.0, 180.0, Symmetry::BilateralC0C180),
                (90.0, 270.0, Symmetry::BilateralC90C270),
            ],
            vec![4, 2, 3, 0],
        ),
        (
            "bilateral C0–C180",
            |c, g| {
                100.0
                    + 40.0 * libm::cos(c.to_radians()) * libm::sin(g.to_radians())
                    + 20.0 * libm::cos((2.0 * c).to_radians())
            },
            vec![(0.0, 180.0, Symmetry::BilateralC0C180)],
            vec![2, 0],
        ),
        (
            "bilateral C90–C270",
            |c, g| {
                100.0
                    + 40.0 * libm::sin(c.to_radians()) * libm::sin(g.to_radians())
                    + 20.0 * libm::cos((2.0 * c).to_radians())
            },
            vec![(90.0, 270.0, Symmetry::BilateralC90C270)],
            vec![3, 0],
        ),
        (
            "rotational",
            |_, g| 100.0 + 50.0 * libm::cos(g.to_radians()),
            vec![
                (0.0, 0.0, Symmetry::Rotational),
                (0.0, 90.0, Symmetry::Quadrant),
                (0.0, 180.0, Symmetry::BilateralC0C180),
                (90.0, 270.0, Symmetry::BilateralC90C270),
            ],
            vec![1, 4, 2, 3, 0],
        ),
        (
            "asymmetric",
            |c, g| {
                100.0
                    + 40.0 * libm::sin(c.to_radians()) * libm::sin(g.to_radians())
                    + 30.0 * libm::cos(c.to_radians()) * libm::cos(g.to_radians())
            },
            vec![],
            vec![0],
        ),
    ];
    for (name, f, forms, isyms) in families {
        let reference = parse_ies(&ies_text(&full, &gamma, &f), "full.ies");
        assert_eq!(reference.symmetry, Symmetry::None);
        for (first, last, symmetry) in forms {
            let h: Vec<f64> = if first == last {
                vec![first]
            } else {
                full.iter()
                    .copied()
                    .filter(|&c| c >= first && c <= last)
                    .collect()
            };
            let p = parse_ies(&ies_text(&h, &gamma, &f), "form.ies");
            assert_eq!(p.symmetry, symmetry, "{name} {first}–{last}");
            assert_same_function(&reference, &p, &format!("{name}, IES {first}–{last}"));
        }
        for isym in isyms {
            let p = parse_ldt(&ldt_text(isym, 24, &gamma, &f), "form.ldt");
            assert_same_function(&reference, &p, &format!("{name}, EULUMDAT Isym {isym}"));
            assert_eq!(p.lamp_flux_lm, Some(2000.0));
            assert_eq!(
                p.opening,
                Opening::Rectangle {
                    length_m: 0.5,
                    width_m: 0.3
                }
            );
        }
    }
}

#[test]
fn a_last_plane_short_of_360_wraps_to_c0() {
    let gamma = steps(0.0, 180.0, 10.0);
    let f = |c: f64, g: f64| 100.0 + 40.0 * libm::sin(c.to_radians()) * libm::sin(g.to_radians());
    let reference = parse_ies(&ies_text(&steps(0.0, 360.0, 15.0), &gamma, &f), "full.ies");
    let short = parse_ies(&ies_text(&steps(0.0, 345.0, 15.0), &gamma, &f), "short.ies");
    assert_same_function(&reference, &short, "0–345 against 0–360");
}

// ---------------------------------------------------------------------------------------
// Types A and B

#[test]
fn type_b_and_a_uniform_tables_fill_the_front_hemisphere() {
    for name in [
        "typeb_uniform.ies",
        "typeb_lateral.ies",
        "typea_uniform.ies",
    ] {
        let p = load(name);
        // A constant interpolant: I0 times the front hemisphere, 2π sr, exactly.
        assert!(
            (p.flux_lm() - 200.0 * PI).abs() < 1e-9,
            "{name}: {}",
            p.flux_lm()
        );
        assert_eq!(p.intensity_cd(123.0, 45.0), 100.0);
        assert_eq!(p.intensity_cd(10.0, 135.0), 0.0, "{name}: the back is dark");
        let n = 200_000;
        let mut rng = Pcg32::new(5, 5);
        let mut sum = 0.0;
        for _ in 0..n {
            let d = p.sample_direction(&mut rng);
            assert!(d.z <= 1e-12, "{name}: {d}");
            sum += -d.z;
        }
        // Uniform over the hemisphere: −z uniform on [0, 1], mean ½, variance 1/12.
        let z = (sum / n as f64 - 0.5) / (1.0 / 12.0 / n as f64).sqrt();
        assert!(z.abs() < 5.0, "{name}: mean −z off by {z:.1}σ");
    }
    assert_eq!(load("typeb_lateral.ies").symmetry, Symmetry::LateralH);
    assert_eq!(
        load("typeb_uniform.ies").photometric_type,
        PhotometricType::B
    );
    assert_eq!(
        load("typea_uniform.ies").photometric_type,
        PhotometricType::A
    );
}

#[test]
fn type_b_lobe_at_v_plus_30_points_to_plus_x_and_type_a_lobe_at_h_plus_30_to_minus_y() {
    // Type B: V = +30° (H = 0) is γ = 30° in the C0 plane; type A: H = +30° (V = 0) is
    // γ = 30° in the C270 plane (H positive towards −y).
    for (name, c_peak, axis) in [
        ("typeb_lobe.ies", 0.0, DVec3::X),
        ("typea_lobe.ies", 270.0, DVec3::NEG_Y),
    ] {
        let p = load(name);
        let peak = p.peak();
        assert!(
            (peak.c_deg - c_peak).abs() < 1e-9 && (peak.gamma_deg - 30.0).abs() < 1e-9,
            "{name}: {peak:?}"
        );
        assert!((p.intensity_cd(c_peak, 30.0) - 200.0).abs() < 1e-9);
        let mut rng = Pcg32::new(9, 9);
        for _ in 0..20_000 {
            let d = p.sample_direction(&mut rng);
            // Within the lobe's cells: 20–40° from the nadir towards `axis`, ±10° aside.
            assert!(d.dot(axis) > 0.3 && d.z < -0.7, "{name}: {d}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// Tilt, units, factors

#[test]
fn tilt_include_and_tilt_file_apply_the_factor_at_the_photometered_position() {
    let base = load("cosine.ies");
    for name in ["tilt_include.ies", "tilt_file.ies"] {
        let p = load(name);
        let t = p.tilt.as_ref().expect("a tilt table");
        assert_eq!(t.geometry, 1);
        assert_eq!(t.angles_deg, [0.0, 30.0, 60.0, 90.0]);
        assert_eq!(t.factors, [0.9, 0.85, 0.8, 0.7]);
        assert!((t.factor(45.0) - 0.825).abs() < 1e-12);
        assert_eq!(t.factor(120.0), 0.7);
        assert!(
            (p.flux_lm() - 0.9 * base.flux_lm()).abs() < 1e-9 * base.flux_lm(),
            "{name}"
        );
        assert!((p.intensity_cd(0.0, 30.0) - 0.9 * base.intensity_cd(0.0, 30.0)).abs() < 1e-9);
        assert!((p.lamp_output_factor - 0.9).abs() < 1e-15);
    }
}

#[test]
fn feet_and_metres_and_round_openings() {
    let ft = 0.3048;
    let feet = load("opening_feet.ies");
    assert_eq!(
        feet.opening,
        Opening::Rectangle {
            length_m: 4.0 * ft,
            width_m: 2.0 * ft
        }
    );
    assert!((feet.height_m - 0.5 * ft).abs() < 1e-15);
    let metres = load("opening_metres.ies");
    assert_eq!(
        metres.opening,
        Opening::Rectangle {
            length_m: 4.0,
            width_m: 2.0
        }
    );
    assert_eq!(metres.height_m, 0.5);
    assert_eq!(
        load("opening_round.ies").opening,
        Opening::Disc {
            diameter_m: 0.5 * ft
        }
    );
    assert_eq!(
        load("opening_round_1991.ies").opening,
        Opening::Disc {
            diameter_m: 0.33 * ft
        }
    );
    assert_eq!(load("opening_round_1991.ies").format, Format::Ies(1991));
    // The photometry does not depend on the units.
    assert_eq!(feet.flux_lm(), metres.flux_lm());
    // Points drawn on the openings stay on them and fill them.
    let mut rng = Pcg32::new(1, 2);
    let (mut max_x, mut max_y) = (0.0f64, 0.0f64);
    for _ in 0..10_000 {
        let q = metres.opening.sample_point_m(&mut rng);
        assert!(q.x.abs() <= 2.0 && q.y.abs() <= 1.0 && q.z == 0.0);
        max_x = max_x.max(q.x.abs());
        max_y = max_y.max(q.y.abs());
        let r = load("opening_round.ies").opening.sample_point_m(&mut rng);
        assert!(r.truncate().length() <= 0.25 * ft);
    }
    assert!(max_x > 1.99 && max_y > 0.99);
    assert!((metres.opening.area_m2() - 8.0).abs() < 1e-12);
}

#[test]
fn multiplier_ballast_and_ballast_lamp_factors_but_not_the_2019_generation_type() {
    let base = load("cosine.ies");
    let p1995 = load("factors_1995.ies");
    let p2019 = load("factors_2019.ies");
    assert_eq!(p2019.format, Format::Ies(2019));
    for (p, factor) in [(&p1995, 2.0 * 0.9 * 0.95), (&p2019, 2.0 * 0.9)] {
        for g in [0.0, 25.0, 60.0] {
            let want = factor * base.intensity_cd(0.0, g);
            assert!((p.intensity_cd(0.0, g) - want).abs() < 1e-9 * want.max(1.0));
        }
        assert!((p.flux_lm() - factor * base.flux_lm()).abs() < 1e-9 * base.flux_lm());
        assert_eq!(p.lamp_flux_lm, Some(1000.0));
    }
    // The light output ratio divides out what scales the lamps (ballast factors), not
    // the candela multiplier.
    let lor = p1995.light_output_ratio().unwrap();
    assert!((lor - p1995.flux_lm() / (1000.0 * 0.9 * 0.95)).abs() < 1e-12);
    assert!((lor - 2.0 * base.flux_lm() / 1000.0).abs() < 1e-9);
}

// ---------------------------------------------------------------------------------------
// Malformed files

/// The error of `text` read as `name`, checked to be one line naming `name` and a line.
fn error_of(text: &str, name: &str) -> String {
    let result = if name.ends_with(".ldt") {
        photometry::parse_ldt(text, name)
    } else {
        photometry::parse_ies(text, name, &data(""))
    };
    let message = match result {
        Ok(_) => panic!("{name} parsed but should not have:\n{text}"),
        Err(e) => e.to_string(),
    };
    eprintln!("{message}");
    assert!(!message.contains('\n'), "not one line: {message:?}");
    message
}

/// `text` with line `n` (1-based) replaced by `with` (None: removed).
fn edit_line(text: &str, n: usize, with: Option<&str>) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    match with {
        Some(w) => lines[n - 1] = w,
        None => {
            lines.remove(n - 1);
        }
    }
    lines.join("\n") + "\n"
}

#[test]
fn malformed_ies_files_name_the_file_and_line() {
    let examp1 = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/photometry/examp1.ies"),
    )
    .unwrap();
    // examp1.ies: line 15 TILT, 16 record 1, 17 record 2, 18–22 vertical angles, 23
    // horizontal angles, 24–26 the first plane's candela values, ..., 56 the last line.
    let n_lines = examp1.lines().count();
    let cases: Vec<(String, String)> = vec![
        // Truncated table.
        (edit_line(&examp1, n_lines, None), format!("line {}: the file ends before candela value", n_lines - 1)),
        // Wrong counts: one horizontal angle fewer leaves data over; one more runs out.
        (edit_line(&examp1, 16, Some("2 2900 1.0 73 4 1 1 0.85 4.04 .292")), "after the last value (73 vertical × 4 horizontal angles): the counts do not match the data".into()),
        (edit_line(&examp1, 16, Some("2 2900 1.0 73 6 1 1 0.85 4.04 .292")), format!("line {n_lines}: the file ends before candela value")),
        // Non-monotonic angles.
        (edit_line(&examp1, 18, Some("0 2.5 5 7.5 10 12.5 15 17.5 20 22.5 25 27.5 30 32.5 35 37.5 40 42.5 45 47.5 45")), "line 18: vertical angle 21 (45) does not increase".into()),
        (edit_line(&examp1, 23, Some("0 45 22.5 67.5 90")), "line 23: horizontal angle 3 (22.5) does not increase".into()),
        // Negative candela, NaN, not a number.
        (edit_line(&examp1, 24, Some("778.4 777.6 -774.9 769.9 763.2 754.1 741.0 726.1 711.6 692.2 672.3 651.0 628.4")), "line 24: candela value -774.9 at horizontal 0°, vertical 5° is negative".into()),
        (edit_line(&examp1, 24, Some("778.4 777.6 NaN 769.9 763.2 754.1 741.0 726.1 711.6 692.2 672.3 651.0 628.4")), "line 24: candela value at horizontal angle 0°: 3 of 73: `NaN` is not a finite number".into()),
        (edit_line(&examp1, 25, Some("600.0 553.8 472.5 369.4 267.7 18x6.3 120.3 62.4 21.7 4.1 0.0 0.0 0.0 0.0 0.0")), "line 25:".into()),
        // Unknown photometric type, units, symmetry range, vertical range.
        (edit_line(&examp1, 16, Some("2 2900 1.0 73 5 4 1 0.85 4.04 .292")), "line 16: unknown photometric type 4".into()),
        (edit_line(&examp1, 16, Some("2 2900 1.0 73 5 1 3 0.85 4.04 .292")), "line 16: unknown units type 3".into()),
        (edit_line(&examp1, 23, Some("0 22.5 45 67.5 100")), "line 23: horizontal angles 0–100°: type C stores".into()),
        (edit_line(&examp1, 22, Some("167.5 170 172.5 175 177.5 190")), "line 22: vertical angle 73 is 190°, outside 0..180°".into()),
        // Bad factors and header.
        (edit_line(&examp1, 16, Some("2 2900 0 73 5 1 1 0.85 4.04 .292")), "line 16: candela multiplier 0 must be positive".into()),
        (edit_line(&examp1, 17, Some("1.0 -1.0 63.7")), "line 17: ballast-lamp photometric factor -1 must be positive".into()),
        (edit_line(&examp1, 1, Some("IESNA:LM-63-2031")), "line 1: unknown LM-63 header".into()),
        (edit_line(&examp1, 15, Some("TILT=SOMETIMES")), "line 15: TILT file: ".into()),
        (edit_line(&examp1, 15, Some("TIL=NONE")), format!("line {n_lines}: no `TILT=` line")),
        // TILT=INCLUDE: bad geometry, truncated, decreasing angles, negative factors.
        (edit_line(&examp1, 15, Some("TILT=INCLUDE\n5\n2\n0 90\n1 1")), "line 16: the tilt's lamp-to-luminaire geometry: 5 is outside 1..=3".into()),
        (edit_line(&examp1, 15, Some("TILT=INCLUDE\n1\n3\n0 90 45\n1 1 1")), "line 18: tilt angle 3 (45) does not increase".into()),
        (edit_line(&examp1, 15, Some("TILT=INCLUDE\n1\n2\n0 90\n1 -0.5")), "line 19: tilt factor 2 is negative".into()),
        (examp1.lines().take(15).collect::<Vec<_>>().join("\n").replace("TILT=NONE", "TILT=INCLUDE\n1\n4\n0 30"), "line 18: the file ends before tilt angle 3 of 4".into()),
        // Every value 0.
        (examp1.lines().enumerate().map(|(k, l)| if k >= 23 { l.split_whitespace().map(|_| "0").collect::<Vec<_>>().join(" ") } else { l.to_string() }).collect::<Vec<_>>().join("\n"), "line 24: every candela value is 0".into()),
    ];
    for (text, want) in cases {
        let m = error_of(&text, "examp1.ies");
        assert!(m.starts_with("examp1.ies: line "), "{m}");
        assert!(m.contains(&want), "`{want}` missing from: {m}");
    }
}

#[test]
fn a_missing_tilt_file_names_its_path() {
    let text = std::fs::read_to_string(data("tilt_file.ies"))
        .unwrap()
        .replace("tilt_file.tlt", "no_such.tlt");
    let m = error_of(&text, "x.ies");
    assert!(m.contains("no_such.tlt"), "{m}");
    // A tilt file with a bad count names the tilt file and its line.
    let dir = std::env::temp_dir().join(format!("luxtally-tilt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bad.tlt"), "1\n3\n0 45 90\n1 1\n").unwrap();
    let e = photometry::parse_ies(&text.replace("no_such.tlt", "bad.tlt"), "x.ies", &dir)
        .expect_err("a bad tilt file is an error")
        .to_string();
    assert!(
        e.contains("bad.tlt: line 4: the file ends before tilt factor 3 of 3"),
        "{e}"
    );
}

#[test]
fn malformed_eulumdat_files_name_the_file_and_line() {
    let gamma = steps(0.0, 180.0, 10.0);
    let good = ldt_text(4, 24, &gamma, &|_, g| 100.0 + g);
    // Lines: 3 Isym, 4 Mc, 26 sets, 27–32 lamp set, 33–42 ratios, 43–66 C angles,
    // 67–85 γ angles, 86– intensities (7 planes × 19).
    assert!(photometry::parse_ldt(&good, "a.ldt").is_ok());
    let last = good.lines().count();
    let cases: Vec<(String, &str)> = vec![
        (
            edit_line(&good, 3, Some("5")),
            "line 3: symmetry indicator Isym: 5 is outside 0..=4",
        ),
        (
            edit_line(&good, 4, Some("22")),
            "line 4: Isym 4 needs Mc divisible by 4, not 22",
        ),
        (
            edit_line(&good, 45, Some("10")),
            "line 45: C angle 3 (10) does not increase",
        ),
        (
            edit_line(&good, 68, Some("-5")),
            "line 68: γ angle 2 (-5) does not increase",
        ),
        (
            edit_line(&good, 90, Some("-1")),
            "line 90: intensity -1 cd/klm at C0, γ 40° is negative",
        ),
        (
            edit_line(&good, 90, Some("nan")),
            "line 90: intensity of plane C0: 5 of 19: `nan` is not a finite number",
        ),
        (
            edit_line(&good, last, None),
            "the file ends before line 218 (intensity of plane C90: 19 of 19)",
        ),
        (
            good.clone() + "42\n",
            "line 219: `42` after the last intensity",
        ),
        (
            edit_line(&good, 29, Some("0")),
            "line 29: lamp set 1 flux 0 lm must be positive",
        ),
        (edit_line(&good, 43, Some("5")), "line 43: C angles 5–345°"),
    ];
    for (text, want) in cases {
        let m = error_of(&text, "a.ldt");
        assert!(m.starts_with("a.ldt: line "), "{m}");
        assert!(m.contains(want), "`{want}` missing from: {m}");
    }
}

/// Cuts examp1.ies (and an EULUMDAT file) after every line and every token, and puts bad
/// numbers in place of every token: never a panic, every error one line naming the file.
#[test]
fn truncated_and_mutated_files_never_panic() {
    let examp1 = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/photometry/examp1.ies"),
    )
    .unwrap();
    let ldt = ldt_text(2, 12, &steps(0.0, 180.0, 15.0), &|c, g| 50.0 + c / 10.0 + g);
    let check = |text: &str, name: &str| {
        let outcome = std::panic::catch_unwind(|| {
            if name.ends_with(".ldt") {
                photometry::parse_ldt(text, name).map(|_| ())
            } else {
                photometry::parse_ies(text, name, Path::new(".")).map(|_| ())
            }
        });
        match outcome {
            Err(_) => panic!("{name} panicked on:\n{text}"),
            Ok(Err(e)) => {
                let m = e.to_string();
                assert!(!m.contains('\n') && m.starts_with(name), "{m}");
            }
            Ok(Ok(())) => {}
        }
    };
    let mut parsed = 0;
    for (text, name) in [(examp1.as_str(), "examp1.ies"), (ldt.as_str(), "x.ldt")] {
        // Every prefix ending at a line or token boundary.
        let cuts: Vec<usize> = text
            .char_indices()
            .filter(|&(_, ch)| ch.is_whitespace())
            .map(|(k, _)| k)
            .collect();
        for &k in &cuts {
            check(&text[..k], name);
            parsed += 1;
        }
        // Every token replaced by a bad or extreme number.
        let tokens: Vec<(usize, usize)> = {
            let mut v = Vec::new();
            let mut start = None;
            for (k, ch) in text.char_indices() {
                match (ch.is_whitespace(), start) {
                    (false, None) => start = Some(k),
                    (true, Some(s)) => {
                        v.push((s, k));
                        start = None;
                    }
                    _ => {}
                }
            }
            v
        };
        for &(s, e) in &tokens {
            for bad in [
                "-1",
                "0",
                "nan",
                "inf",
                "1e308",
                "-1e308",
                "99999999999",
                "x",
                "2.5",
                "360",
            ] {
                check(&format!("{}{bad}{}", &text[..s], &text[e..]), name);
                parsed += 1;
            }
        }
    }
    eprintln!("{parsed} damaged files, no panic");
}

// ---------------------------------------------------------------------------------------
// The command and the diagram

#[test]
fn photometry_command_prints_the_facts_and_writes_the_polar_diagram() {
    let dir = std::env::temp_dir().join(format!("luxtally-photometry-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/photometry/examp1.ies");
    // Default output: FILE's stem + _polar.png in the current directory.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(["photometry", file.to_str().unwrap()])
        .current_dir(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    eprintln!("{stdout}");
    for needle in [
        "IES LM-63-1995",
        "photometric type C",
        "quadrant",
        "5296.6",
        "lamp lumens: 5800.0 lm",
        "light output ratio: 0.913",
        "peak intensity: 1065.2 cd",
        "rectangle 1.231 m",
        "examp1_polar.png",
    ] {
        assert!(
            stdout.contains(needle),
            "`{needle}` missing from:\n{stdout}"
        );
    }
    let png = std::fs::read(dir.join("examp1_polar.png")).unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(png));
    let info = decoder.read_info().unwrap().info().clone();
    assert_eq!((info.width, info.height), (480, 510));

    // A malformed file: exit 1, one line naming the file and line.
    let bad = dir.join("bad.ies");
    std::fs::write(
        &bad,
        std::fs::read_to_string(&file)
            .unwrap()
            .replace("2 2900 1.0 73 5 1 1", "2 2900 1.0 73 5 7 1"),
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_luxtally"))
        .args(["photometry", bad.to_str().unwrap(), "--out"])
        .arg(dir.join("bad.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("bad.ies: line 16: unknown photometric type 7"),
        "{stderr}"
    );
    assert!(!dir.join("bad.png").exists());
}

#[test]
fn polar_diagram_has_the_nadir_down_in_cd_per_klm() {
    let p = load("examp1.ies");
    let img = photometry::polar::polar_diagram(&p);
    let curves = photometry::polar::PolarCurves::of(&p, 0.5);
    // C0 at γ = 0: 778.4 cd of 5800 lamp lumens = 134.2 cd/klm.
    assert!((curves.c0[0] - 778.4 * 1000.0 / 5800.0).abs() < 1e-9);
    // Rings every 50 cd/klm up to 200: the nadir point sits 134.2/200 of the 200 px
    // radius below the centre (240, 265).
    assert_eq!(photometry::polar::ring_step(curves.max()), 50.0);
    let y = 265 + (200.0 * curves.c0[0] / 200.0).round() as usize;
    let red = (y - 2..=y + 2).any(|yy| {
        let k = 3 * (yy * img.width + 240);
        img.rgb[k] > 150 && img.rgb[k + 1] < 80
    });
    assert!(red, "no red curve below the centre at y ≈ {y}");
    let bytes = photometry::polar::polar_diagram_png(&p).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn lm63_1986_files_have_no_header_line_and_other_extensions_are_sniffed() {
    let cosine = std::fs::read_to_string(data("cosine.ies")).unwrap();
    // Without its header line the file is LM-63-1986: every line up to TILT is label.
    let old = parse_ies(&edit_line(&cosine, 1, None), "old.ies");
    assert_eq!(old.format, Format::Ies(1986));
    assert_eq!(old.keyword("LABEL"), Some("[TEST] luxtally synthetic"));
    assert_eq!(old.flux_lm(), load("cosine.ies").flux_lm());
    let dir = std::env::temp_dir().join(format!("luxtally-sniff-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("lamp.txt"), &cosine).unwrap();
    std::fs::write(
        dir.join("lamp.dat"),
        std::fs::read(data("cosine.ldt")).unwrap(),
    )
    .unwrap();
    assert_eq!(
        photometry::load(&dir.join("lamp.txt")).unwrap().format,
        Format::Ies(2002)
    );
    assert_eq!(
        photometry::load(&dir.join("lamp.dat")).unwrap().format,
        Format::Eulumdat
    );
    let missing = photometry::load(&dir.join("none.ies"))
        .err()
        .unwrap()
        .to_string();
    assert!(missing.contains("none.ies"), "{missing}");
}

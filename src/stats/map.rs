//! Scene-map statistics: the triangles' illuminance from their photon counts, the
//! odd/even error of the map (method.md §3, eqs. 4–5) and the scene's mean illuminance.

use super::*;

/// The scene map's illuminance and its odd/even error (method.md §3).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MapStats {
    /// Area-weighted mean illuminance <E> (arithmetic), lx.
    pub mean_lx: f64,
    /// RMS error of the combined map, σ = d/2 (eq. 5 with the /2 correction), lx.
    pub sigma_lx: f64,
    /// σ / <E>, with <E> averaged arithmetically and quadratically (eq. 4).
    pub rel_error: Averaged,
}

/// Which photon hits a map counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Every hit: the total illumination.
    Total,
    /// Hits after at least one scattering: the secondary illumination.
    Indirect,
}

/// Photon hits of one triangle in a map, from odd and from even photons (both faces).
#[inline]
fn parity_counts(slots: &[u64], kind: MapKind) -> (u64, u64) {
    let (mut odd, mut even) = (0, 0);
    for (slot, &c) in slots.iter().enumerate() {
        let slot = Slot::of(slot);
        if kind == MapKind::Indirect && !slot.indirect {
            continue;
        }
        if slot.odd_photon {
            odd += c;
        } else {
            even += c;
        }
    }
    (odd, even)
}

/// Illuminance of triangle `k` in a map: flux of both faces over the geometric area, from
/// photons of the given parities (`None`: all), lx.
pub fn triangle_illuminance_lx(
    t: &Tallies,
    kind: MapKind,
    k: usize,
    area_m2: f64,
    total_flux_lm: f64,
    parity: Option<bool>,
) -> f64 {
    let (n_odd, n_even) = t.odd_even_photons();
    let slots = t.triangle_slots(k);
    let (odd, even) = parity_counts(&slots, kind);
    let (count, photons) = match parity {
        None => (odd + even, n_odd + n_even),
        Some(true) => (odd, n_odd),
        Some(false) => (even, n_even),
    };
    if photons == 0 {
        return 0.0;
    }
    total_flux_lm * count as f64 / (photons as f64 * area_m2)
}

/// Illuminance of one face of triangle `k` in a map (`back_face`: the face behind the
/// triangle's normal), from all photons, lx. The two faces of
/// [`triangle_illuminance_lx`] kept apart: the eye sees one of them.
pub fn triangle_face_illuminance_lx(
    t: &Tallies,
    kind: MapKind,
    k: usize,
    area_m2: f64,
    total_flux_lm: f64,
    back_face: bool,
) -> f64 {
    if t.photons == 0 || area_m2 <= 0.0 {
        return 0.0;
    }
    let slots = t.triangle_slots(k);
    let count: u64 = slots
        .iter()
        .enumerate()
        .filter(|(slot, _)| {
            let slot = Slot::of(*slot);
            slot.back_face == back_face && (kind == MapKind::Total || slot.indirect)
        })
        .map(|(_, &c)| c)
        .sum();
    total_flux_lm * count as f64 / (t.photons as f64 * area_m2)
}

/// Relative error of every triangle's total illuminance in the scene map (σ/E; NaN
/// where no photon hit it: unknown).
///
/// A triangle's illuminance counts photons of equal flux, c of them over N photons.
/// The odd/even difference of one triangle, |E_odd − E_even|/2, is an estimate of its
/// σ with one degree of freedom (z-scores against it follow Student's t with 1 degree
/// of freedom, Cauchy's tails; it is 0 where as many odd as even photons hit); eq. 5
/// averages it over the scene. Per triangle we use the count itself: Var(c) = c for
/// histories hitting it at most once, times the scene's overdispersion
/// D = Σ(o − e)²/Σc (o, e: odd and even hits; E[(o − e)²] = Var(c)), which corrects
/// for photons hitting one triangle twice (1 in a scene of small triangles, up to 2–3 on
/// the few large faces of a bright room). As for receiver cells
/// ([`pooled_variance`]), a triangle that drew few hits would report a small value and
/// a small σ; the count it should have drawn is estimated by its neighbours (triangles
/// touching one of its corners' positions — `adjacent` from
/// [`crate::scene::adjacency::VertexFaces::by_position`], so that meshes whose triangles
/// keep their own vertices have neighbours too — those sharing an edge counted twice):
/// λ = median of their hits per m² × its area, and Var = D·max(λ, c − min(√c, λ)).
pub fn triangle_rel_errors(
    t: &Tallies,
    triangles: &[[u32; 3]],
    adjacent: &crate::scene::adjacency::VertexFaces,
    area_m2: impl Fn(usize) -> f64,
) -> Vec<f64> {
    let counts: Vec<(u64, u64)> = (0..triangles.len())
        .map(|k| parity_counts(&t.triangle_slots(k), MapKind::Total))
        .collect();
    let (mut d2, mut total) = (0.0f64, 0.0f64);
    for &(o, e) in &counts {
        d2 += (o as f64 - e as f64).powi(2);
        total += (o + e) as f64;
    }
    let dispersion = if total > 0.0 { d2 / total } else { 1.0 };
    let density: Vec<f64> = counts
        .iter()
        .enumerate()
        .map(|(k, &(o, e))| match area_m2(k) {
            a if a > 0.0 => (o + e) as f64 / a,
            _ => 0.0,
        })
        .collect();
    let mut nb: Vec<f64> = Vec::new();
    let mut rel = Vec::with_capacity(triangles.len());
    for (k, (&(o, e), tri)) in counts.iter().zip(triangles).enumerate() {
        let c = (o + e) as f64;
        if c == 0.0 {
            rel.push(f64::NAN);
            continue;
        }
        // The faces of its three vertices: a neighbour across an edge appears twice
        // (it shares two vertices), which weighs it double in the median, as it should.
        nb.clear();
        for &v in tri {
            for &j in adjacent.faces(v as usize) {
                if j as usize != k {
                    nb.push(density[j as usize]);
                }
            }
        }
        let lambda = match nb.len() {
            0 => 0.0,
            n => {
                let (below, &mut upper, _) = nb.select_nth_unstable_by(n / 2, f64::total_cmp);
                let median = if n % 2 == 1 {
                    upper
                } else {
                    0.5 * (below.iter().copied().fold(f64::MIN, f64::max) + upper)
                };
                median * area_m2(k)
            }
        };
        let var = dispersion * pooled_variance(c, c.sqrt(), lambda);
        rel.push(var.sqrt() / c);
    }
    rel
}

/// Mean illuminance and odd/even error of a scene map (eqs. 4–5, σ = d/2) over the
/// triangles of `g`. Runs after every epoch: triangles no photon reached add nothing
/// (exactly 0 to each sum) and are skipped before their area is computed.
pub fn map_stats(t: &Tallies, kind: MapKind, g: &Geometry, total_flux_lm: f64) -> MapStats {
    let total_area = g.total_area_m2();
    let (n_odd, n_even) = t.odd_even_photons();
    if total_area <= 0.0 || t.photons == 0 {
        return MapStats {
            rel_error: Averaged {
                arithmetic: REL_ERROR_UNKNOWN,
                quadratic: REL_ERROR_UNKNOWN,
            },
            ..MapStats::default()
        };
    }
    // One pass over the counts: flux per photon of all photons, of odd and of even ones,
    // in the score unit (a power of two: exact), where the squares below stay finite.
    let unit = t.score_unit;
    let total_flux_lm = total_flux_lm / unit;
    let per_photon = total_flux_lm / t.photons as f64;
    let per_odd = if n_odd > 0 {
        total_flux_lm / n_odd as f64
    } else {
        0.0
    };
    let per_even = if n_even > 0 {
        total_flux_lm / n_even as f64
    } else {
        0.0
    };
    let (mut sum_e, mut sum_e2, mut sum_d2) = (0.0, 0.0, 0.0);
    for k in 0..g.triangle_count() {
        let (odd, even) = parity_counts(&t.triangle_slots(k), kind);
        if odd == 0 && even == 0 {
            continue;
        }
        let a = g.area_m2(k);
        let e = per_photon * (odd + even) as f64 / a;
        sum_e += a * e;
        sum_e2 += a * e * e;
        let d = (per_odd * odd as f64 - per_even * even as f64) / a;
        sum_d2 += a * d * d;
    }
    let mean_lx = sum_e / total_area * unit;
    let quadratic_lx = (sum_e2 / total_area).sqrt() * unit;
    let sigma_lx = if n_odd > 0 && n_even > 0 {
        0.5 * (sum_d2 / total_area).sqrt() * unit
    } else {
        0.0
    };
    let unknown = n_odd == 0 || n_even == 0;
    MapStats {
        mean_lx,
        sigma_lx,
        rel_error: if unknown {
            Averaged {
                arithmetic: REL_ERROR_UNKNOWN,
                quadratic: REL_ERROR_UNKNOWN,
            }
        } else {
            Averaged {
                arithmetic: relative_error(mean_lx, sigma_lx),
                quadratic: relative_error(quadratic_lx, sigma_lx),
            }
        },
    }
}

/// Standard error (lx) of the scene's area-weighted mean illuminance Φ·Σk/(N·S), from
/// the per-history hit counts k (eq. 7 with the whole scene as one cell).
pub fn mean_illuminance_sigma_lx(t: &Tallies, total_area_m2: f64, total_flux_lm: f64) -> f64 {
    if total_area_m2 <= 0.0 {
        return 0.0;
    }
    let (_, sigma_hits) = cell_estimate(
        t.history_hits[0] as f64,
        t.history_hits[1] as f64,
        t.photons,
    );
    total_flux_lm * sigma_hits / total_area_m2
}

/// VOV of the scene's mean illuminance (from the per-history hit counts).
pub fn mean_illuminance_vov(t: &Tallies) -> f64 {
    variance_of_variance(t.history_hits.map(|m| m as f64), t.photons)
}

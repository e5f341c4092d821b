//! Statistics of the tallies: the equations of method.md, evaluated once per epoch.
//! They only read tallies; they never touch the photon path.

pub mod forecast;
pub mod stop;

use crate::scene::Geometry;
use crate::tally::{CellSums, Counts, Slot, Tallies};

/// Relative error reported for a value of 0 whose σ is known: 100 %, so no relative
/// target can be met by a quantity nothing has reached.
pub const REL_ERROR_UNKNOWN: f64 = 1.0;

/// Estimate and standard error of one cell from its history moments, N histories
/// (eqs. 6–7, with the unbiased N/(N−1) variance). Returns (value, sigma) in the score's
/// unit: value = Σx/N, sigma = sqrt(Var(x)/N); sigma is NaN (unknown) below 2 histories.
pub fn cell_estimate(sum: f64, sum_sq: f64, n: u64) -> (f64, f64) {
    if n == 0 {
        return (0.0, f64::NAN);
    }
    let nf = n as f64;
    let mean = sum / nf;
    if n == 1 {
        return (mean, f64::NAN);
    }
    let variance = ((sum_sq / nf - mean * mean) * nf / (nf - 1.0)).max(0.0);
    (mean, (variance / nf).sqrt())
}

/// A cell's value and σ: the photons' estimate (eqs. 6–7 over the histories) plus the
/// sampled direct light (the same equations over its replicates); the two are
/// independent, so their variances add. σ is NaN (unknown) when nothing has scored in
/// the cell, neither a photon nor a non-zero direct sample, so its error cannot be
/// estimated, whatever its true value (unless the scene emits no light at all).
pub fn cell_value(c: &CellSums, counts: Counts) -> (f64, f64) {
    let Counts {
        photons,
        direct_replicates: replicates,
        dark,
    } = counts;
    if c.hits == 0 {
        return (0.0, if dark { 0.0 } else { f64::NAN });
    }
    let (direct_sum, direct_sum_sq) = c.direct_sums();
    let (photon_value, photon_sigma) = cell_estimate(c.sum(), c.sum_sq(), photons);
    let (direct_value, direct_sigma) = if replicates == 0 {
        (0.0, 0.0)
    } else {
        cell_estimate(direct_sum, direct_sum_sq, replicates)
    };
    (
        photon_value + direct_value,
        photon_sigma.hypot(direct_sigma),
    )
}

/// VOV of a cell's value (photon part plus direct part): the parts are independent, so
/// the variance of its variance estimate is the sum of theirs,
/// VOV = (VOV_p·σ_p⁴ + VOV_d·σ_d⁴)/(σ_p² + σ_d²)²; 1 when nothing is known.
pub fn cell_vov(c: &CellSums, counts: Counts) -> f64 {
    let (photons, replicates) = (counts.photons, counts.direct_replicates);
    let part = |moments: [f64; 4], n: u64| {
        let (_, sigma) = cell_estimate(moments[0], moments[1], n);
        if moments[1] > 0.0 && sigma > 0.0 {
            (variance_of_variance(moments, n), sigma * sigma)
        } else {
            (0.0, 0.0)
        }
    };
    let (vov_p, var_p) = part(c.moments.map(|m| m.value()), photons);
    let (vov_d, var_d) = part(c.direct.map(|m| m.value()), replicates);
    let var = var_p + var_d;
    if var > 0.0 {
        (vov_p * var_p * var_p + vov_d * var_d * var_d) / (var * var)
    } else {
        1.0
    }
}

/// σ_rel of a value (eq. 8): NaN when σ is unknown, [`REL_ERROR_UNKNOWN`] for a zero
/// value.
pub fn relative_error(value: f64, sigma: f64) -> f64 {
    if sigma.is_nan() {
        f64::NAN
    } else if value > 0.0 {
        sigma / value
    } else {
        REL_ERROR_UNKNOWN
    }
}

/// Relative variance of the variance (MCNP's VOV) of a mean from the moments
/// [Σx, Σx², Σx³, Σx⁴] of N histories: Σ(x−x̄)⁴ / (Σ(x−x̄)²)² − 1/N. Below 0.1 the σ
/// of that mean can be trusted; 1 when nothing is known yet.
pub fn variance_of_variance(moments: [f64; 4], n: u64) -> f64 {
    if n < 2 {
        return 1.0;
    }
    let nf = n as f64;
    let [s1, s2, s3, s4] = moments;
    let m = s1 / nf;
    let c2 = s2 - s1 * m;
    if c2 <= 0.0 {
        return 1.0;
    }
    let c4 = s4 - 4.0 * m * s3 + 6.0 * m * m * s2 - 3.0 * nf * m.powi(4);
    (c4 / (c2 * c2) - 1.0 / nf).max(0.0)
}

/// Reading back numbers that serde_json wrote as null (it writes NaN and ±∞ so): NaN,
/// an unknown value, as the statistics write it.
pub mod null_as_nan {
    use serde::{Deserialize, Deserializer};

    pub fn f64<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }

    pub fn vec<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<Option<f64>>::deserialize(d)?
            .into_iter()
            .map(|x| x.unwrap_or(f64::NAN))
            .collect())
    }
}

/// Mean and mean relative error of a set of cells (eq. 9), by both averagings.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Averaged {
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub arithmetic: f64,
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub quadratic: f64,
}

/// Receiver (or block) summary per eq. 9: the arithmetic mean value and the RMS σ over
/// the mean by arithmetic and quadratic averaging of the values.
pub fn mean_error(values: &[f64], sigmas: &[f64]) -> (f64, Averaged) {
    if values.is_empty() {
        return (
            0.0,
            Averaged {
                arithmetic: f64::NAN,
                quadratic: f64::NAN,
            },
        );
    }
    let k = values.len() as f64;
    let mean = values.iter().sum::<f64>() / k;
    let quadratic_mean = (values.iter().map(|v| v * v).sum::<f64>() / k).sqrt();
    let rms_sigma = (sigmas.iter().map(|s| s * s).sum::<f64>() / k).sqrt();
    (
        mean,
        Averaged {
            arithmetic: relative_error(mean, rms_sigma),
            quadratic: relative_error(quadratic_mean, rms_sigma),
        },
    )
}

/// Values, errors and hits of one receiver.
#[derive(Clone, Debug, Default)]
pub struct ReceiverStats {
    pub values: Vec<f64>,
    /// NaN where the cell's error is unknown (nothing scored there).
    pub sigma: Vec<f64>,
    pub hits: Vec<u64>,
    pub mean: f64,
    /// Eq. 9 over all cells: NaN while some cell's error is unknown.
    pub rel_error: Averaged,
    /// Eq. 9 over the cells whose error is known.
    pub rel_error_known: Averaged,
    /// Cells whose error is unknown.
    pub unknown_cells: usize,
    /// RMS σ over the cells (eq. 9's numerator), in the receiver's unit; NaN while some
    /// cell's error is unknown.
    pub rms_sigma: f64,
}

/// Per-cell statistics of the cells `cells` ([`cell_value`]).
pub fn receiver_stats(cells: &[CellSums], counts: Counts) -> ReceiverStats {
    let mut s = ReceiverStats::default();
    for c in cells {
        let (value, sigma) = cell_value(c, counts);
        s.values.push(value);
        s.sigma.push(sigma);
        s.hits.push(c.hits);
    }
    (s.mean, s.rel_error) = mean_error(&s.values, &s.sigma);
    let (known_values, known_sigma): (Vec<f64>, Vec<f64>) = s
        .values
        .iter()
        .zip(&s.sigma)
        .filter(|(_, sigma)| !sigma.is_nan())
        .unzip();
    s.unknown_cells = cells.len() - known_values.len();
    s.rel_error_known = mean_error(&known_values, &known_sigma).1;
    s.rms_sigma = if cells.is_empty() {
        0.0
    } else {
        (s.sigma.iter().map(|x| x * x).sum::<f64>() / cells.len() as f64).sqrt()
    };
    s
}

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
    // One pass over the counts: flux per photon of all photons, of odd and of even ones.
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
    let mean_lx = sum_e / total_area;
    let quadratic_lx = (sum_e2 / total_area).sqrt();
    let sigma_lx = if n_odd > 0 && n_even > 0 {
        0.5 * (sum_d2 / total_area).sqrt()
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

/// Figure of merit 1/(σ_rel²·t) (method.md §5): constant while the run converges as
/// 1/sqrt(t); 0 before any error or time is known.
pub fn figure_of_merit(rel_error: f64, elapsed_s: f64) -> f64 {
    if rel_error > 0.0 && elapsed_s > 0.0 {
        1.0 / (rel_error * rel_error * elapsed_s)
    } else {
        0.0
    }
}

/// Reliability of the target's error, in the spirit of MCNP's tally checks.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Reliability {
    /// FOM of the target now.
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub fom: f64,
    /// FOM now against FOM at half the photons: within ±10 % once σ_rel ∝ 1/sqrt(t).
    pub fom_stable: bool,
    /// Largest variance of the variance among the target's scored cells (or of the
    /// scene mean for `global`).
    #[serde(deserialize_with = "null_as_nan::f64")]
    pub vov: f64,
    /// The error can be trusted: FOM stable and VOV < 0.1.
    pub reliable: bool,
}

/// Judges the history of (elapsed, photons, error) of a target and its VOV.
pub fn reliability(history: &[forecast::HistoryPoint], vov: f64) -> Reliability {
    let fom_at = |p: &forecast::HistoryPoint| figure_of_merit(p.rel_error, p.elapsed_s);
    let fom = history.last().map_or(0.0, fom_at);
    let fom_stable = match history.last() {
        Some(last) if history.len() >= 4 && fom > 0.0 => {
            let half = history
                .iter()
                .find(|p| p.photons * 2 >= last.photons)
                .unwrap_or(last);
            let fom_half = fom_at(half);
            fom_half > 0.0 && (fom / fom_half - 1.0).abs() < 0.1
        }
        _ => false,
    };
    Reliability {
        fom,
        fom_stable,
        vov,
        reliable: fom_stable && vov < 0.1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_estimate_matches_textbook_standard_error() {
        // Scores 0, 2, 4 over N = 3 histories: mean 2, unbiased variance 4, σ = sqrt(4/3).
        let (m, s) = cell_estimate(6.0, 20.0, 3);
        assert_eq!(m, 2.0);
        assert!((s - (4.0f64 / 3.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn single_hit_cells_follow_one_over_root_n() {
        // n hits of equal score among N histories: σ_rel → 1/sqrt(n) (eq. 11) for n ≪ N.
        let (n_hist, n_hits) = (1_000_000u64, 400u64);
        let (m, s) = cell_estimate(n_hits as f64, n_hits as f64, n_hist);
        let rel = relative_error(m, s);
        assert!((rel - 1.0 / (n_hits as f64).sqrt()).abs() < 1e-3 * rel);
    }

    #[test]
    fn mean_error_uses_both_averagings() {
        let (mean, rel) = mean_error(&[1.0, 3.0], &[0.1, 0.1]);
        assert_eq!(mean, 2.0);
        assert!((rel.arithmetic - 0.05).abs() < 1e-15);
        assert!((rel.quadratic - 0.1 / 5f64.sqrt()).abs() < 1e-15);
    }
}

//! The bounce cap: how many bounces a photon may make before the pass stops it, chosen
//! from the scene's highest albedo so the light it drops stays below 10⁻¹², and the bound
//! on that bias summary.json reports (docs/method.md, *Bounce cap*).

/// The bias the bounce cap is chosen to stay below: ρ_max^cap ≤ 1e-12.
pub const BOUNCE_CAP_BIAS: f64 = 1e-12;

/// The largest bounce cap, used for lossless materials (albedo 1), where roulette never
/// ends a path, and wherever ρ_max is so near 1 that the 1e-12 rule asks for more
/// (ρ_max > 1 − 1.3·10⁻⁵). 2²¹ keeps every history-hit moment exact: a history's hit
/// count k ≤ cap + 1, so Σk⁴ ≤ (cap + 1)³·Σk < 2⁶³·⁰⁰¹·2⁶⁴ < 2¹²⁸ (Σk ≤ the rays cast, a
/// u64), and k³ < 2⁶⁴.
pub const MAX_BOUNCE_CAP: u32 = 1 << 21;

/// The bounce cap: the number of bounces a photon survives with probability at most
/// [`BOUNCE_CAP_BIAS`] at the scene's highest albedo ρ_max, ⌈ln 10⁻¹² / ln ρ_max⌉
/// (ρ = 0.95 gives 539, ρ = 0.99995 gives 552,607); never below 64, never above
/// [`MAX_BOUNCE_CAP`] (the cap for ρ_max = 1).
pub fn bounce_cap(max_albedo: f64) -> u32 {
    if max_albedo < 1.0 {
        let n = (libm::log(BOUNCE_CAP_BIAS) / libm::log(max_albedo.max(1e-300))).ceil();
        n.clamp(64.0, MAX_BOUNCE_CAP as f64) as u32
    } else {
        MAX_BOUNCE_CAP
    }
}

/// The a-priori bound on the share of the light a cap of `cap` bounces drops at the
/// scene's highest albedo ρ_max < 1: ρ_max^cap (docs/method.md, *Bounce cap*); `None`
/// for lossless materials (ρ_max ≥ 1), where no a-priori bound exists.
pub fn bounce_cap_a_priori_bound(max_albedo: f64, cap: u32) -> Option<f64> {
    (max_albedo < 1.0).then(|| libm::exp(cap as f64 * libm::log(max_albedo.max(0.0))))
}

/// −ln 0.05: no photon of N stopped by the cap bounds the chance that one is by
/// −ln(0.05)/N ≈ 3/N at 95 % confidence (1 − 0.05^(1/N) ≤ −ln(0.05)/N).
const NONE_IN_N_95: f64 = 2.995_732_273_553_991;

/// `bounce_cap_bias_bound` of summary.json: the largest share of the light the cap can
/// have dropped, from the a-priori bound ρ_max^cap (`a_priori`, see
/// [`bounce_cap_a_priori_bound`]) and, when no photon of `photons` was stopped by the
/// cap (`killed` = 0), the 95 % bound −ln(0.05)/N on the share of the emitted flux it
/// stops; the smaller of the two. `None` (unknown) for lossless materials once a photon
/// was stopped, or before any photon.
pub fn bounce_cap_bias_bound(a_priori: Option<f64>, killed: u64, photons: u64) -> Option<f64> {
    let observed = (killed == 0 && photons > 0).then(|| NONE_IN_N_95 / photons as f64);
    match (a_priori, observed) {
        (Some(a), Some(o)) => Some(a.min(o)),
        (a, o) => a.or(o),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounce_cap_cannot_bias_a_bright_room() {
        assert_eq!(bounce_cap(0.95), 539);
        assert!(0.95f64.powi(bounce_cap(0.95) as i32) < 1e-12);
        assert_eq!(bounce_cap(0.0), 64);
        assert_eq!(bounce_cap(1.0), MAX_BOUNCE_CAP);
        assert_eq!(bounce_cap_a_priori_bound(1.0, MAX_BOUNCE_CAP), None);
        assert_eq!(bounce_cap_a_priori_bound(0.0, 64), Some(0.0));
    }

    #[test]
    fn bounce_cap_follows_the_albedo_past_the_old_ceiling() {
        // ρ = 0.99995: 1/(1 − ρ) = 20,000 bounces on average; the old ceiling of 100,000
        // dropped e⁻⁵ ≈ 0.67 % of the light. The cap is the least n with ρⁿ ≤ 1e-12.
        for rho in [0.99995f64, 0.9999, 0.999] {
            let cap = bounce_cap(rho);
            let bound = bounce_cap_a_priori_bound(rho, cap).unwrap();
            assert!(bound <= BOUNCE_CAP_BIAS * (1.0 + 1e-9), "ρ {rho}: {bound}");
            assert!(
                libm::pow(rho, cap as f64 - 1.0) > BOUNCE_CAP_BIAS,
                "ρ {rho}: not the least"
            );
            assert!((bound - libm::pow(rho, cap as f64)).abs() <= 1e-9 * bound);
        }
        assert_eq!(bounce_cap(0.99995), 552_607);
        assert!(bounce_cap(0.99995) > 100_000);
        // Past what the moments hold: the largest cap, its bound ρ^cap no longer tiny.
        let rho = 1.0 - 1e-7;
        assert_eq!(bounce_cap(rho), MAX_BOUNCE_CAP);
        let b = bounce_cap_a_priori_bound(rho, MAX_BOUNCE_CAP).unwrap();
        assert!((b - libm::exp(-0.2097152f64)).abs() < 1e-6, "{b}");
    }

    #[test]
    fn bias_bound_is_a_priori_or_from_no_photon_capped() {
        // Lossless: unknown once a photon was capped (or before any photon) …
        assert_eq!(bounce_cap_bias_bound(None, 1, 1000), None);
        assert_eq!(bounce_cap_bias_bound(None, 0, 0), None);
        // … else −ln(0.05)/N, which bounds 1 − 0.05^(1/N), the exact 95 % bound.
        let b = bounce_cap_bias_bound(None, 0, 1000).unwrap();
        assert!((b - 2.995_732_273_553_991e-3).abs() < 1e-15);
        assert!(1.0 - libm::pow(0.05f64, 1.0 / 1000.0) <= b);
        // A priori: kept whatever was capped; the smaller one when none was.
        assert_eq!(bounce_cap_bias_bound(Some(1e-12), 3, 1000), Some(1e-12));
        assert_eq!(bounce_cap_bias_bound(Some(0.5), 0, 1000), Some(b));
        assert_eq!(bounce_cap_bias_bound(Some(0.5), 2, 1000), Some(0.5));
    }
}

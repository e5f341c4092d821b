//! Time-to-accuracy forecast (method.md §5): error ∝ 1/sqrt(photons) (eq. 10), and
//! photons ∝ time at the recently measured rate.

/// One epoch's point of the convergence history.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HistoryPoint {
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub elapsed_s: f64,
    pub photons: u64,
    /// The target's error (relative, or absolute with `--absolute`).
    #[serde(deserialize_with = "super::null_as_nan::f64")]
    pub rel_error: f64,
    /// Forecast total time and photons to reach the target (absent without a target).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forecast_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forecast_photons: Option<u64>,
    /// The checks of the scene's requirements passing, failing and undecided after this
    /// epoch (absent without requirements, and for a shard).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checks: Option<super::verdict::CheckCounts>,
}

/// A forecast of when the target error is reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Forecast {
    pub total_s: f64,
    pub photons: u64,
}

/// How many of the latest points the fit uses: enough to damp the noise of the error
/// estimate itself, recent enough to follow changes of rate.
const FIT_POINTS: usize = 8;

/// Predicts the total time and photons at which the error reaches `target`, from the
/// history so far (points in increasing photon order). The constant c of
/// error = c/sqrt(N) is the median of error·sqrt(N) over the latest points (robust to a
/// noisy σ estimate); the rate is photons per second over the same points, so set-up
/// time and the first epoch's warm-up do not skew it.
pub fn forecast(history: &[HistoryPoint], target: f64) -> Option<Forecast> {
    let last = history.last()?;
    if !(target > 0.0) || last.photons == 0 {
        return None;
    }
    // Later half of the history, at most FIT_POINTS, at least the last point.
    let take = (history.len() / 2).clamp(1, FIT_POINTS);
    let recent = &history[history.len() - take..];
    let mut constants: Vec<f64> = recent
        .iter()
        .filter(|p| p.photons > 0 && p.rel_error.is_finite())
        .map(|p| p.rel_error * (p.photons as f64).sqrt())
        .collect();
    if constants.is_empty() {
        return None;
    }
    constants.sort_by(f64::total_cmp);
    let mid = constants.len() / 2;
    let c = if constants.len() % 2 == 1 {
        constants[mid]
    } else {
        0.5 * (constants[mid - 1] + constants[mid])
    };
    let photons_needed = (c / target).powi(2);
    if !photons_needed.is_finite() || photons_needed > u64::MAX as f64 / 2.0 {
        return None;
    }
    let rate = photon_rate(history)?;
    let total_s = last.elapsed_s + (photons_needed - last.photons as f64) / rate;
    Some(Forecast {
        total_s: total_s.max(0.0),
        photons: photons_needed.ceil() as u64,
    })
}

/// Photons per second over the latest points (the whole history when it is short).
fn photon_rate(history: &[HistoryPoint]) -> Option<f64> {
    let last = history.last()?;
    let first = if history.len() > FIT_POINTS {
        history[history.len() - 1 - FIT_POINTS]
    } else if history.len() >= 2 {
        history[0]
    } else {
        HistoryPoint {
            elapsed_s: 0.0,
            photons: 0,
            rel_error: 0.0,
            forecast_s: None,
            forecast_photons: None,
            checks: None,
        }
    };
    let dt = last.elapsed_s - first.elapsed_s;
    let dn = (last.photons - first.photons) as f64;
    (dt > 0.0 && dn > 0.0).then(|| dn / dt)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(t: f64, n: u64, err: f64) -> HistoryPoint {
        HistoryPoint {
            elapsed_s: t,
            photons: n,
            rel_error: err,
            forecast_s: None,
            forecast_photons: None,
            checks: None,
        }
    }

    #[test]
    fn exact_inverse_sqrt_history_is_extrapolated_exactly() {
        // 1e6 photons/s after 0.5 s of set-up; error = 2/sqrt(N).
        let history: Vec<_> = (1..=10u64)
            .map(|k| {
                let n = k * 100_000;
                point(0.5 + n as f64 / 1e6, n, 2.0 / (n as f64).sqrt())
            })
            .collect();
        let f = forecast(&history, 0.001).unwrap();
        assert_eq!(f.photons, 4_000_000);
        assert!((f.total_s - 4.5).abs() < 1e-9, "{}", f.total_s);
    }

    #[test]
    fn an_outlier_error_estimate_does_not_move_the_forecast() {
        let mut history: Vec<_> = (1..=10u64)
            .map(|k| point(k as f64, k * 1000, 1.0 / ((k * 1000) as f64).sqrt()))
            .collect();
        history[8].rel_error *= 3.0;
        let f = forecast(&history, 0.01).unwrap();
        assert_eq!(f.photons, 10_000);
    }
}

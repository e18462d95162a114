//! MSE against time: efficiency (1 / (MSE × time)) and the time an estimator needs to reach a
//! target MSE. (Not efficiency-aware MIS, `lt_core::path::efficiency`.)

use crate::fit::LineFit;

/// Efficiency = 1 / (MSE × seconds): doubles when either halves. Comparable only between runs
/// against the same reference on the same machine.
pub fn efficiency(mse: f64, seconds: f64) -> f64 {
    1.0 / (mse * seconds)
}

/// First time a measured (seconds, MSE) curve reaches `target`, by interpolating ln MSE against
/// ln time between the two bracketing measurements (exact for a power law). Points are sorted
/// by time first. None when the curve never gets down to `target`, or was already below it at
/// the first measurement (the crossing is not bracketed; see [`time_to_mse_extrapolated`]).
pub fn time_to_mse(curve: &[(f64, f64)], target: f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = curve
        .iter()
        .copied()
        .filter(|(t, m)| *t > 0.0 && *m > 0.0)
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let first = pts.first()?;
    if first.1 == target {
        return Some(first.0);
    }
    if first.1 < target {
        return None;
    }
    pts.windows(2).find(|w| w[1].1 <= target).map(|w| {
        let ((t0, m0), (t1, m1)) = (w[0], w[1]);
        let u = (target.ln() - m0.ln()) / (m1.ln() - m0.ln());
        (t0.ln() + u * (t1.ln() - t0.ln())).exp()
    })
}

/// Time to `target` from a log-log fit of MSE against time (see [`crate::fit_log_log`]), for
/// targets outside the measured range. Trust it only as far as the power law holds.
pub fn time_to_mse_extrapolated(fit: &LineFit, target: f64) -> f64 {
    ((target.ln() - fit.intercept) / fit.slope).exp()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::fit_log_log;

    #[test]
    fn power_law_interpolation_is_exact() {
        let mse = |t: f64| 0.5 * t.powf(-0.8);
        let curve: Vec<(f64, f64)> = [8.0, 1.0, 2.0, 4.0].iter().map(|&t| (t, mse(t))).collect();
        let t = time_to_mse(&curve, mse(3.0)).unwrap();
        assert!((t - 3.0).abs() < 1e-12, "{t}");
        assert_eq!(time_to_mse(&curve, mse(16.0)), None);
        assert_eq!(time_to_mse(&curve, mse(0.5)), None);
        let (ts, ms): (Vec<f64>, Vec<f64>) = curve.iter().copied().unzip();
        let fit = fit_log_log(&ts, &ms, 0.95).unwrap();
        assert!((time_to_mse_extrapolated(&fit, mse(16.0)) - 16.0).abs() < 1e-9);
        assert_eq!(efficiency(0.5, 4.0), 0.5);
    }

    #[test]
    fn first_crossing_of_a_noisy_curve() {
        // Dips below 1.0 between t = 2 and 3, bounces back, and crosses again later.
        let curve = [(1.0, 2.0), (2.0, 1.5), (3.0, 0.9), (4.0, 1.1), (5.0, 0.5)];
        let t = time_to_mse(&curve, 1.0).unwrap();
        assert!(t > 2.0 && t < 3.0, "{t}");
    }
}

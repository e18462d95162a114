//! Least-squares line fits with a confidence interval on the slope, mainly on log-log data
//! (MSE vs N, bias vs N, variance vs N, MSE vs time), where the slope is the convergence rate.
//!
//! The interval is the textbook one (t with n − 2 dof), which assumes independent residuals of
//! equal variance. In log space that holds for sample variances from a fixed number of runs per
//! point: ln s² has spread ≈ sqrt(2/(K−1)) whatever the level.

use crate::bias_variance::{t_quantile, Interval};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineFit {
    pub slope: f64,
    pub intercept: f64,
    pub slope_std_error: f64,
    /// Slope with its confidence interval at `confidence`.
    pub slope_ci: Interval,
    pub confidence: f64,
    pub points: usize,
    /// Residual standard deviation, sqrt(SSR / (n − 2)).
    pub residual_std: f64,
    pub r2: f64,
}

impl LineFit {
    pub fn predict(&self, x: f64) -> f64 {
        self.intercept + self.slope * x
    }

    /// For a fit from [`fit_log_log`]: y ≈ e^intercept · x^slope.
    pub fn power_law(&self, x: f64) -> f64 {
        (self.intercept + self.slope * x.ln()).exp()
    }
}

/// Ordinary least squares y = intercept + slope·x. Needs ≥ 3 points and distinct x.
pub fn fit_line(xs: &[f64], ys: &[f64], confidence: f64) -> Result<LineFit, String> {
    if xs.len() != ys.len() {
        return Err(format!(
            "fit_line: {} x values but {} y values",
            xs.len(),
            ys.len()
        ));
    }
    let n = xs.len();
    if n < 3 {
        return Err(format!(
            "fit_line: need at least 3 points for a slope interval, got {n}"
        ));
    }
    if let Some(v) = xs.iter().chain(ys).find(|v| !v.is_finite()) {
        return Err(format!("fit_line: non-finite value {v}"));
    }
    let nf = n as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / nf, ys.iter().sum::<f64>() / nf);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in xs.iter().zip(ys) {
        sxx += (x - mx) * (x - mx);
        sxy += (x - mx) * (y - my);
        syy += (y - my) * (y - my);
    }
    if sxx == 0.0 {
        return Err("fit_line: all x values are equal".into());
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let ssr: f64 = xs
        .iter()
        .zip(ys)
        .map(|(x, y)| (y - intercept - slope * x).powi(2))
        .sum();
    let residual_std = (ssr / (nf - 2.0)).sqrt();
    let se = residual_std / sxx.sqrt();
    let h = t_quantile(confidence, nf - 2.0) * se;
    Ok(LineFit {
        slope,
        intercept,
        slope_std_error: se,
        slope_ci: Interval {
            estimate: slope,
            lo: slope - h,
            hi: slope + h,
        },
        confidence,
        points: n,
        residual_std,
        r2: if syy > 0.0 { 1.0 - ssr / syy } else { 1.0 },
    })
}

/// Fit of ln y against ln x; all values must be positive.
pub fn fit_log_log(xs: &[f64], ys: &[f64], confidence: f64) -> Result<LineFit, String> {
    if let Some(v) = xs.iter().chain(ys).find(|v| !(**v > 0.0)) {
        return Err(format!("fit_log_log: values must be positive, got {v}"));
    }
    let lx: Vec<f64> = xs.iter().map(|x| x.ln()).collect();
    let ly: Vec<f64> = ys.iter().map(|y| y.ln()).collect();
    fit_line(&lx, &ly, confidence)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::binomial::binomial_test;
    use crate::running::RunningStat;
    use crate::test_rng::Rng;

    const META_ALPHA: f64 = 1e-3;

    #[test]
    fn exact_line_recovered() {
        let xs = [1.0, 2.0, 4.0, 8.0];
        let ys: Vec<f64> = xs.iter().map(|x: &f64| 3.0 * x.powf(-1.5)).collect();
        let f = fit_log_log(&xs, &ys, 0.95).unwrap();
        assert!(
            (f.slope + 1.5).abs() < 1e-12
                && (f.power_law(16.0) - 3.0 * 16f64.powf(-1.5)).abs() < 1e-12
        );
        assert!(f.slope_ci.half_width() < 1e-12);
        assert!(fit_log_log(&[1.0, 2.0, 0.0], &[1.0, 1.0, 1.0], 0.95).is_err());
        assert!(fit_line(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0], 0.95).is_err());
    }

    // Slope interval coverage on a noisy line: 95 % of intervals contain the true slope.
    #[test]
    fn slope_interval_coverage() {
        let mut rng = Rng::new(4);
        let (trials, conf) = (4000u64, 0.95);
        let xs: Vec<f64> = (0..6).map(|i| i as f64).collect();
        let hits = (0..trials)
            .filter(|_| {
                let ys: Vec<f64> = xs
                    .iter()
                    .map(|x| 1.0 - 0.7 * x + 0.3 * rng.normal())
                    .collect();
                fit_line(&xs, &ys, conf).unwrap().slope_ci.contains(-0.7)
            })
            .count() as u64;
        let t = binomial_test(hits, trials, conf);
        println!("slope CI coverage: {t}");
        assert!(!t.rejects(META_ALPHA), "{t}");
    }

    /// Sample variance over `k` runs of an estimator at each N, fitted on log-log.
    fn variance_slope(rng: &mut Rng, est: impl Fn(&mut Rng, usize) -> f64) -> LineFit {
        let k = 400;
        let ns: Vec<f64> = (2..=10).map(|e| (1u32 << e) as f64).collect();
        let vars: Vec<f64> = ns
            .iter()
            .map(|&n| {
                RunningStat::from_slice(&(0..k).map(|_| est(rng, n as usize)).collect::<Vec<_>>())
                    .sample_variance()
            })
            .collect();
        fit_log_log(&ns, &vars, 0.999).unwrap()
    }

    // Progressive estimators whose variance falls like N^-α exactly: plain Monte Carlo (α = 1)
    // and jittered (stratified) sampling of a linear integrand, variance 1/(12 N³) (α = 3).
    #[test]
    fn progressive_estimator_slopes() {
        let mut rng = Rng::new(99);
        let plain = variance_slope(&mut rng, |r, n| {
            (0..n).map(|_| 3.0 * r.uniform().powi(2)).sum::<f64>() / n as f64
        });
        let jitter = variance_slope(&mut rng, |r, n| {
            (0..n)
                .map(|i| (i as f64 + r.uniform()) / n as f64)
                .sum::<f64>()
                / n as f64
        });
        println!("plain MC variance slope {} (expect -1)", plain.slope_ci);
        println!("jittered variance slope {} (expect -3)", jitter.slope_ci);
        assert!(plain.slope_ci.contains(-1.0), "{}", plain.slope_ci);
        assert!(jitter.slope_ci.contains(-3.0), "{}", jitter.slope_ci);
        // Not vacuous: the intervals are narrow enough to tell neighbouring rates apart.
        assert!(plain.slope_ci.half_width() < 0.25 && jitter.slope_ci.half_width() < 0.25);
    }
}

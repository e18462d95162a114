//! The delete-one jackknife over K independent runs (Efron & Stein 1981; Efron & Tibshirani,
//! *An Introduction to the Bootstrap*, ch. 11): a standard error for any smooth statistic of the
//! runs, in particular for statistics whose inputs are correlated *within* a run — a slope fitted
//! to the same runs' errors at 1, 2, 4, … passes, where ordinary least squares would take the
//! points as independent and claim too narrow an interval.
//!
//! se² = (K−1)/K · Σ_i (θ_(i) − θ̄)², θ_(i) the statistic without run i; the interval is the
//! full-sample θ ± t_{K−1} · se.

use crate::bias_variance::{t_quantile, Interval};

/// The statistic on all runs, with its jackknife interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jackknifed {
    pub estimate: f64,
    pub std_error: f64,
    pub interval: Interval,
    pub runs: usize,
}

/// `statistic(kept)` on the run indices `kept`; fails (Err) where it is undefined, e.g. a log of a
/// non-positive value. Needs K ≥ 3 and the statistic defined on every delete-one subset.
pub fn jackknife(
    runs: usize,
    confidence: f64,
    statistic: impl Fn(&[usize]) -> Result<f64, String>,
) -> Result<Jackknifed, String> {
    if runs < 3 {
        return Err(format!("the jackknife needs at least 3 runs, got {runs}"));
    }
    let all: Vec<usize> = (0..runs).collect();
    let estimate = statistic(&all)?;
    let mut loo = Vec::with_capacity(runs);
    for i in 0..runs {
        let kept: Vec<usize> = all.iter().copied().filter(|&j| j != i).collect();
        loo.push(statistic(&kept).map_err(|e| format!("without run {i}: {e}"))?);
    }
    let k = runs as f64;
    let mean = loo.iter().sum::<f64>() / k;
    let var = (k - 1.0) / k * loo.iter().map(|t| (t - mean).powi(2)).sum::<f64>();
    let se = var.sqrt();
    let half = t_quantile(confidence, k - 1.0) * se;
    Ok(Jackknifed {
        estimate,
        std_error: se,
        interval: Interval {
            estimate,
            lo: estimate - half,
            hi: estimate + half,
        },
        runs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Rng;

    /// For the mean the jackknife standard error is exactly the textbook s/√K.
    #[test]
    fn jackknife_of_the_mean_is_the_standard_error() {
        let mut rng = Rng::new(3);
        let xs: Vec<f64> = (0..20).map(|_| rng.uniform()).collect();
        let j = jackknife(xs.len(), 0.95, |kept| {
            Ok(kept.iter().map(|&i| xs[i]).sum::<f64>() / kept.len() as f64)
        })
        .unwrap();
        let m = xs.iter().sum::<f64>() / 20.0;
        let s2 = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / 19.0;
        assert!((j.std_error - (s2 / 20.0).sqrt()).abs() < 1e-12 * j.std_error.max(1e-300));
        assert!((j.estimate - m).abs() < 1e-15);
    }

    /// X_r(N) = (mean of run r's first N standard normals)², the squared error of a running
    /// mean: E X = 1/N exactly, and a run's X at N and 2N share a prefix (the correlation OLS
    /// ignores). N·X_r(N) has the same law at every N, so the slope of ln(mean over runs of X)
    /// against ln N is −1 in expectation. The jackknife interval must cover −1 at its nominal
    /// 95 % (binomial 4σ over the repetitions); OLS's own interval, treating the points as
    /// independent, must fall short of it — which is why the studies use the jackknife.
    #[test]
    fn slope_interval_covers_under_within_run_correlation() {
        let mut rng = Rng::new(11);
        let (reps, k) = (1000, 16);
        let ns = [1usize, 2, 4, 8, 16, 32];
        let xs: Vec<f64> = ns.iter().map(|&n| (n as f64).ln()).collect();
        let (mut jack, mut ols) = (0, 0);
        for _ in 0..reps {
            let runs: Vec<Vec<f64>> = (0..k)
                .map(|_| {
                    let mut sum = 0.0;
                    let mut at = Vec::new();
                    for i in 1..=*ns.last().unwrap() {
                        sum += rng.normal();
                        if ns.contains(&i) {
                            at.push((sum / i as f64).powi(2));
                        }
                    }
                    at
                })
                .collect();
            let slope = |kept: &[usize]| {
                let ys: Vec<f64> = (0..ns.len())
                    .map(|j| {
                        (kept.iter().map(|&r| runs[r][j]).sum::<f64>() / kept.len() as f64).ln()
                    })
                    .collect();
                crate::fit::fit_line(&xs, &ys, 0.95)
            };
            if jackknife(k, 0.95, |kept| slope(kept).map(|f| f.slope))
                .unwrap()
                .interval
                .contains(-1.0)
            {
                jack += 1;
            }
            let all: Vec<usize> = (0..k).collect();
            if slope(&all).unwrap().slope_ci.contains(-1.0) {
                ols += 1;
            }
        }
        let (pj, po) = (jack as f64 / reps as f64, ols as f64 / reps as f64);
        let four_sigma = 4.0 * (0.95 * 0.05 / reps as f64).sqrt();
        eprintln!("coverage of the 95 % interval: jackknife {pj:.3}, OLS {po:.3}");
        assert!((pj - 0.95).abs() < four_sigma, "jackknife coverage {pj:.3}");
        assert!(
            po < 0.95 - four_sigma,
            "OLS coverage {po:.3} is not short of 95 %"
        );
    }
}

//! Bias / variance / MSE of an estimator from K independent runs (different seeds) against a
//! reference, each with a confidence interval.
//!
//! The intervals assume the run results are close to normal (true for Monte Carlo estimates with
//! many samples per run, by the central limit theorem): Student t for the mean and bias, χ² for
//! the variance. Estimates satisfy MSE = bias² + variance exactly, with bias² the unbiased
//! estimate (x̄ − r)² − s²/K, which can come out slightly negative when the bias is near zero.

use crate::image::Image;
use crate::running::RunningStat;
use statrs::distribution::{ChiSquared, ContinuousCDF, Normal, StudentsT};

/// A point estimate with a confidence interval [lo, hi].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub estimate: f64,
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    pub fn half_width(&self) -> f64 {
        (self.hi - self.lo) / 2.0
    }
}

impl std::fmt::Display for Interval {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.6e} [{:.6e}, {:.6e}]",
            self.estimate, self.lo, self.hi
        )
    }
}

/// Two-sided Student t quantile t_{dof, 1−(1−confidence)/2}.
pub fn t_quantile(confidence: f64, dof: f64) -> f64 {
    assert!(
        confidence > 0.0 && confidence < 1.0,
        "confidence must be in (0, 1), got {confidence}"
    );
    let p = 0.5 + confidence / 2.0;
    if dof > 1e4 {
        // statrs' inversion loses accuracy above ~1e4 dof and stalls for huge ones; the Cornish–Fisher
        // expansion around the normal quantile is exact to O(dof⁻³) there.
        let z = Normal::standard().inverse_cdf(p);
        let (z3, z5) = (z.powi(3), z.powi(5));
        return z + (z3 + z) / (4.0 * dof) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * dof * dof);
    }
    StudentsT::new(0.0, 1.0, dof)
        .expect("dof > 0")
        .inverse_cdf(p)
}

/// χ² interval for a variance estimate `s2` with `dof` degrees of freedom.
pub fn variance_interval(s2: f64, dof: f64, confidence: f64) -> Interval {
    let chi = ChiSquared::new(dof).expect("dof > 0");
    let a = (1.0 - confidence) / 2.0;
    Interval {
        estimate: s2,
        lo: dof * s2 / chi.inverse_cdf(1.0 - a),
        hi: dof * s2 / chi.inverse_cdf(a),
    }
}

/// t interval for a mean from its estimate, standard error and degrees of freedom.
pub fn mean_interval(mean: f64, std_error: f64, dof: f64, confidence: f64) -> Interval {
    let h = t_quantile(confidence, dof) * std_error;
    Interval {
        estimate: mean,
        lo: mean - h,
        hi: mean + h,
    }
}

/// The interval of b² for b in `bias` (same coverage: squaring maps the event b ∈ CI onto it).
fn squared(bias: Interval, estimate: f64) -> Interval {
    let (a, b) = (bias.lo * bias.lo, bias.hi * bias.hi);
    let lo = if bias.lo <= 0.0 && bias.hi >= 0.0 {
        0.0
    } else {
        a.min(b)
    };
    Interval {
        estimate,
        lo,
        hi: a.max(b),
    }
}

/// Scalar decomposition: one number per run (a pixel, a block, an integral).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasVariance {
    pub runs: u64,
    pub confidence: f64,
    pub reference: f64,
    /// Mean of the runs (t interval).
    pub mean: Interval,
    /// mean − reference (t interval).
    pub bias: Interval,
    /// bias² (unbiased estimate; interval = bias interval squared).
    pub bias2: Interval,
    /// Variance of one run (χ² interval).
    pub variance: Interval,
    /// Mean squared error of one run = bias² + variance. Its interval adds the bias² and variance
    /// intervals, each taken at confidence 1 − (1 − c)/2 so the sum covers at ≥ c (Bonferroni).
    pub mse: Interval,
}

impl BiasVariance {
    /// Needs at least two runs.
    pub fn from_runs(estimates: &[f64], reference: f64, confidence: f64) -> BiasVariance {
        Self::from_stat(&RunningStat::from_slice(estimates), reference, confidence)
    }

    pub fn from_stat(s: &RunningStat, reference: f64, confidence: f64) -> BiasVariance {
        let k = s.count();
        assert!(k >= 2, "bias/variance needs at least two runs, got {k}");
        let dof = (k - 1) as f64;
        let (m, s2, se) = (s.mean(), s.sample_variance(), s.std_error());
        let mean = mean_interval(m, se, dof, confidence);
        let shift = |i: Interval| Interval {
            estimate: i.estimate - reference,
            lo: i.lo - reference,
            hi: i.hi - reference,
        };
        let bias = shift(mean);
        let b2 = bias.estimate * bias.estimate - s2 / k as f64;
        let half = 1.0 - (1.0 - confidence) / 2.0;
        let (b2w, vw) = (
            squared(shift(mean_interval(m, se, dof, half)), b2),
            variance_interval(s2, dof, half),
        );
        BiasVariance {
            runs: k,
            confidence,
            reference,
            mean,
            bias,
            bias2: squared(bias, b2),
            variance: variance_interval(s2, dof, confidence),
            mse: Interval {
                estimate: b2 + s2,
                lo: b2w.lo + vw.lo,
                hi: b2w.hi + vw.hi,
            },
        }
    }
}

/// Image decomposition, averaged over pixels and channels: `mse` is the mean over runs of each
/// run's image MSE (t interval over the K per-run values); `variance` (mean per-pixel variance)
/// and `bias2` (mean per-pixel unbiased bias²) get delete-one jackknife t intervals, since their
/// per-pixel terms share the run means and are not independent across runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageBiasVariance {
    pub runs: usize,
    pub confidence: f64,
    pub bias2: Interval,
    pub variance: Interval,
    pub mse: Interval,
}

impl ImageBiasVariance {
    /// Needs at least three runs (the jackknife drops one and still needs a variance).
    pub fn from_runs(runs: &[Image], reference: &Image, confidence: f64) -> ImageBiasVariance {
        let k = runs.len();
        assert!(
            k >= 3,
            "image bias/variance needs at least three runs, got {k}"
        );
        assert!(
            runs.iter().all(|r| r.same_size(reference)),
            "image bias/variance: sizes differ"
        );
        let n = (reference.data.len() * 3) as f64;
        let kf = k as f64;
        // Full-sample sums and, per left-out run j, the delete-one sums.
        let (mut b2, mut var) = (0.0, 0.0);
        let (mut b2_loo, mut var_loo) = (vec![0.0; k], vec![0.0; k]);
        let mut mse_run = vec![0.0; k];
        let mut xs = vec![0.0; k];
        for (p, r) in reference.data.iter().enumerate() {
            for (c, &r_c) in r.iter().enumerate() {
                xs.iter_mut()
                    .zip(runs)
                    .for_each(|(x, run)| *x = run.data[p][c]);
                let s = RunningStat::from_slice(&xs);
                let (m, m2) = (s.mean(), s.sample_variance() * (kf - 1.0));
                b2 += (m - r_c).powi(2) - m2 / ((kf - 1.0) * kf);
                var += m2 / (kf - 1.0);
                for (j, &x) in xs.iter().enumerate() {
                    mse_run[j] += (x - r_c).powi(2);
                    // Removing one point: mean' = (K m − x)/(K−1), M2' = M2 − (x − m)² K/(K−1).
                    let m_j = (kf * m - x) / (kf - 1.0);
                    let m2_j = (m2 - (x - m).powi(2) * kf / (kf - 1.0)).max(0.0);
                    b2_loo[j] += (m_j - r_c).powi(2) - m2_j / ((kf - 2.0) * (kf - 1.0));
                    var_loo[j] += m2_j / (kf - 2.0);
                }
            }
        }
        let dof = kf - 1.0;
        let jack = |full: f64, loo: &[f64]| {
            let mean = loo.iter().sum::<f64>() / kf;
            let v = (kf - 1.0) / kf * loo.iter().map(|t| (t / n - mean / n).powi(2)).sum::<f64>();
            mean_interval(full / n, v.sqrt(), dof, confidence)
        };
        let mse = RunningStat::from_slice(&mse_run.iter().map(|m| m / n).collect::<Vec<_>>());
        ImageBiasVariance {
            runs: k,
            confidence,
            bias2: jack(b2, &b2_loo),
            variance: jack(var, &var_loo),
            mse: mean_interval(mse.mean(), mse.std_error(), dof, confidence),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::binomial::binomial_test;
    use crate::test_rng::Rng;

    const META_ALPHA: f64 = 1e-3;

    // f(x) = 3x² on [0, 1]: I = 1, Var f(U) = 9/5 − 1 = 4/5.
    const I: f64 = 1.0;
    const VAR_F: f64 = 0.8;
    fn f(x: f64) -> f64 {
        3.0 * x * x
    }
    fn sum_f(rng: &mut Rng, n: usize) -> f64 {
        (0..n).map(|_| f(rng.uniform())).sum()
    }

    // (1/N)Σf is unbiased; 1/(N+1)Σf has bias −I/(N+1) exactly. The measured bias intervals must
    // contain those values, exclude zero for the biased one while it is resolvable, and shrink.
    #[test]
    fn biased_pair_bias_matches_closed_form_and_vanishes() {
        let mut rng = Rng::new(2024);
        let (k, conf) = (4000, 0.999);
        let mut last_biased: Option<Interval> = None;
        for n in [4usize, 16, 64, 256] {
            let sums: Vec<f64> = (0..k).map(|_| sum_f(&mut rng, n)).collect();
            let plain: Vec<f64> = sums.iter().map(|s| s / n as f64).collect();
            let shrunk: Vec<f64> = sums.iter().map(|s| s / (n + 1) as f64).collect();
            let (u, b) = (
                BiasVariance::from_runs(&plain, I, conf),
                BiasVariance::from_runs(&shrunk, I, conf),
            );
            let expect = -I / (n + 1) as f64;
            println!(
                "N={n:4}: unbiased bias {}, biased bias {} (closed form {expect:.6e})",
                u.bias, b.bias
            );
            assert!(u.bias.contains(0.0), "N={n}: {}", u.bias);
            assert!(b.bias.contains(expect), "N={n}: {} vs {expect}", b.bias);
            // Variances: Var f/N and Var f·N/(N+1)².
            assert!(u.variance.contains(VAR_F / n as f64));
            assert!(b
                .variance
                .contains(VAR_F * n as f64 / ((n + 1) * (n + 1)) as f64));
            if n <= 64 {
                assert!(
                    !b.bias.contains(0.0),
                    "N={n}: bias not resolved: {}",
                    b.bias
                );
            }
            if let Some(prev) = last_biased {
                // Consistency: the whole interval of |bias| moved toward zero.
                assert!(b.bias.lo > prev.hi, "N={n}: {} not above {}", b.bias, prev);
            }
            last_biased = Some(b.bias);
        }
    }

    #[test]
    fn t_quantile_known_values_and_large_dof() {
        assert!((t_quantile(0.95, 4.0) - 2.776445105197793).abs() < 1e-9);
        assert!((t_quantile(0.99, 30.0) - 2.749995653567701).abs() < 1e-9);
        // Both sides of the switch to the expansion agree, and it approaches the normal value.
        assert!((t_quantile(0.95, 1e4) - t_quantile(0.95, 1e4 + 1e-6)).abs() < 1e-9);
        assert!((t_quantile(0.95, 1e12) - 1.959963984540054).abs() < 1e-10);
    }

    #[test]
    fn fixed_bias_is_detected() {
        let mut rng = Rng::new(77);
        let (n, k, bias) = (32, 500, 0.05);
        let runs: Vec<f64> = (0..k)
            .map(|_| sum_f(&mut rng, n) / n as f64 + bias)
            .collect();
        let bv = BiasVariance::from_runs(&runs, I, 0.999);
        println!(
            "fixed bias {bias}: {}, bias² {}, mse {}",
            bv.bias, bv.bias2, bv.mse
        );
        assert!(!bv.bias.contains(0.0) && bv.bias.contains(bias));
        assert!(bv.bias2.lo > 0.0 && bv.bias2.contains(bias * bias));
        assert!(bv.mse.contains(bias * bias + VAR_F / n as f64));
        // The decomposition is exact on the estimates.
        let direct = runs.iter().map(|x| (x - I).powi(2)).sum::<f64>() / k as f64;
        assert!((bv.mse.estimate - direct).abs() <= 1e-12 * direct);
    }

    // The coverage check: over many repeated experiments, a 95 % interval must contain the truth
    // about 95 % of the time. K = 5 runs per experiment, so using normal quantiles instead of t
    // (coverage ≈ 88 %) or a wrong χ² dof would be caught. Each count gets an exact binomial
    // test at false-alarm rate 1e-3.
    #[test]
    fn coverage_of_95_percent_intervals() {
        let mut rng = Rng::new(31337);
        let (experiments, k, n, conf) = (4000u64, 5, 64, 0.95);
        let (mut mean_hits, mut var_hits, mut mse_hits) = (0, 0, 0);
        let true_var = VAR_F / n as f64;
        for _ in 0..experiments {
            let runs: Vec<f64> = (0..k).map(|_| sum_f(&mut rng, n) / n as f64).collect();
            let bv = BiasVariance::from_runs(&runs, I, conf);
            mean_hits += bv.mean.contains(I) as u64;
            var_hits += bv.variance.contains(true_var) as u64;
            mse_hits += bv.mse.contains(true_var) as u64;
        }
        for (name, hits) in [("mean (t)", mean_hits), ("variance (chi2)", var_hits)] {
            let t = binomial_test(hits, experiments, conf);
            println!("coverage {name}: {t}");
            assert!(!t.rejects(META_ALPHA), "{name}: {t}");
        }
        // The MSE interval is Bonferroni-conservative: only too-low coverage is a failure.
        let t = binomial_test(mse_hits, experiments, conf);
        println!("coverage mse (Bonferroni, >= 95% expected): {t}");
        assert!(t.p_lower >= META_ALPHA, "{t}");
    }

    #[test]
    fn image_decomposition() {
        let mut rng = Rng::new(8);
        let (w, h, k, sigma, bias) = (16, 16, 40, 0.2, 0.1);
        let reference = Image::from_fn(w, h, |x, y| [x as f64, y as f64, 1.0]);
        let runs: Vec<Image> = (0..k)
            .map(|_| Image {
                width: w,
                height: h,
                data: reference
                    .data
                    .iter()
                    .map(|r| r.map(|v| v + bias + sigma * rng.normal()))
                    .collect(),
            })
            .collect();
        let d = ImageBiasVariance::from_runs(&runs, &reference, 0.999);
        println!(
            "image: bias2 {}, variance {}, mse {}",
            d.bias2, d.variance, d.mse
        );
        assert!(d.bias2.contains(bias * bias) && d.bias2.lo > 0.0);
        assert!(d.variance.contains(sigma * sigma));
        assert!(d.mse.contains(bias * bias + sigma * sigma));
        let sum = d.bias2.estimate + d.variance.estimate;
        assert!((d.mse.estimate - sum).abs() <= 1e-12 * sum);
    }
}

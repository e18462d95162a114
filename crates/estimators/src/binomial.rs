//! Exact binomial test, for checking rates (interval coverage, false alarms, detection power)
//! against the value theory predicts, instead of against a hand-picked band.

use statrs::distribution::{Beta, Binomial, ContinuousCDF, DiscreteCDF};
use std::fmt;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinomialTest {
    pub successes: u64,
    pub trials: u64,
    /// Success probability under the null hypothesis.
    pub p: f64,
    /// P(X ≤ successes): small when there are too few successes.
    pub p_lower: f64,
    /// P(X ≥ successes): small when there are too many.
    pub p_upper: f64,
    /// Two-sided p-value, 2·min(p_lower, p_upper) capped at 1.
    pub p_value: f64,
}

impl BinomialTest {
    /// True when the two-sided test rejects at level `alpha`.
    pub fn rejects(&self, alpha: f64) -> bool {
        self.p_value < alpha
    }

    pub fn rate(&self) -> f64 {
        self.successes as f64 / self.trials as f64
    }
}

/// Tests `successes` out of `trials` against success probability `p`.
pub fn binomial_test(successes: u64, trials: u64, p: f64) -> BinomialTest {
    assert!(
        successes <= trials && trials > 0,
        "binomial_test: {successes} of {trials}"
    );
    assert!((0.0..=1.0).contains(&p), "binomial_test: p = {p}");
    let d = Binomial::new(p, trials).expect("valid binomial");
    let p_lower = d.cdf(successes);
    let p_upper = if successes == 0 {
        1.0
    } else {
        d.sf(successes - 1)
    };
    BinomialTest {
        successes,
        trials,
        p,
        p_lower,
        p_upper,
        p_value: (2.0 * p_lower.min(p_upper)).min(1.0),
    }
}

/// Clopper–Pearson (exact, conservative) interval for a proportion.
pub fn clopper_pearson(successes: u64, trials: u64, confidence: f64) -> (f64, f64) {
    let a = (1.0 - confidence) / 2.0;
    let (k, n) = (successes as f64, trials as f64);
    let lo = if successes == 0 {
        0.0
    } else {
        Beta::new(k, n - k + 1.0).unwrap().inverse_cdf(a)
    };
    let hi = if successes == trials {
        1.0
    } else {
        Beta::new(k + 1.0, n - k).unwrap().inverse_cdf(1.0 - a)
    };
    (lo, hi)
}

impl fmt::Display for BinomialTest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (lo, hi) = clopper_pearson(self.successes, self.trials, 0.95);
        write!(
            f,
            "{}/{} = {:.4} (95% CI {:.4}..{:.4}) vs expected {:.4}: two-sided p = {:.3e}",
            self.successes,
            self.trials,
            self.rate(),
            lo,
            hi,
            self.p,
            self.p_value
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Against direct sums of the binomial pmf.
    #[test]
    fn tails_match_direct_sums() {
        let (n, p) = (20u64, 0.3f64);
        let pmf = |k: u64| {
            let c = (0..k).fold(1.0, |c, i| c * (n - i) as f64 / (i + 1) as f64);
            c * p.powi(k as i32) * (1.0 - p).powi((n - k) as i32)
        };
        for k in 0..=n {
            let t = binomial_test(k, n, p);
            let lower: f64 = (0..=k).map(pmf).sum();
            let upper: f64 = (k..=n).map(pmf).sum();
            assert!(
                (t.p_lower - lower).abs() < 1e-12 && (t.p_upper - upper).abs() < 1e-12,
                "k={k}"
            );
        }
        assert!(binomial_test(0, 100, 0.5).rejects(1e-20));
        assert!(!binomial_test(50, 100, 0.5).rejects(0.5));
    }

    #[test]
    fn clopper_pearson_contains_rate_and_inverts_tails() {
        let (lo, hi) = clopper_pearson(30, 100, 0.95);
        // At the bounds the one-sided tails are exactly 2.5 %.
        assert!((binomial_test(30, 100, lo).p_upper - 0.025).abs() < 1e-9);
        assert!((binomial_test(30, 100, hi).p_lower - 0.025).abs() < 1e-9);
    }
}

//! The lecture's own example of bias: for f on [0, 1] and N uniform samples, (1/N) Σ f(xᵢ) is
//! unbiased, while (1/(N+1)) Σ f(xᵢ) has expectation N μ/(N+1), so its bias is exactly
//! −μ/(N+1) and vanishes as N grows: biased but consistent. Here f(x) = 3x², μ = 1, σ² = 4/5,
//! so the variances are σ²/N and N σ²/(N+1)².

use lt_core::sampling::Sampler;
use lt_estimators::bias_variance::mean_interval;
use lt_estimators::{Interval, RunningStat};

pub const MU: f64 = 1.0;
pub const SIGMA2: f64 = 0.8;

fn f(x: f64) -> f64 {
    3.0 * x * x
}

pub struct LectureRow {
    pub n: u32,
    pub exact_bias: f64,
    /// Measured bias of (1/(N+1)) Σ f with its t interval over the repetitions.
    pub biased: Interval,
    /// Measured bias of (1/N) Σ f.
    pub unbiased: Interval,
    pub exact_variance_biased: f64,
    pub measured_variance_biased: f64,
}

/// `repetitions` independent estimates of each kind at every N (seeded, reproducible).
pub fn measure(ns: &[u32], repetitions: usize, confidence: f64) -> Vec<LectureRow> {
    ns.iter()
        .map(|&n| {
            let (mut b, mut u) = (RunningStat::new(), RunningStat::new());
            for rep in 0..repetitions {
                let mut s = Sampler::new(0x1ec7, rep as u64, n as u64);
                let sum: f64 = (0..n).map(|_| f(s.next_f32() as f64)).sum();
                u.add(sum / n as f64 - MU);
                b.add(sum / (n as f64 + 1.0) - MU);
            }
            let dof = repetitions as f64 - 1.0;
            let nf = n as f64;
            LectureRow {
                n,
                exact_bias: -MU / (nf + 1.0),
                biased: mean_interval(b.mean(), b.std_error(), dof, confidence),
                unbiased: mean_interval(u.mean(), u.std_error(), dof, confidence),
                exact_variance_biased: nf * SIGMA2 / ((nf + 1.0) * (nf + 1.0)),
                measured_variance_biased: b.sample_variance(),
            }
        })
        .collect()
}

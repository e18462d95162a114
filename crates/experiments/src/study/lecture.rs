//! The lecture's own example of bias: for f on [0, 1] and N uniform samples, (1/N) Σ f(xᵢ) is
//! unbiased, while (1/(N+1)) Σ f(xᵢ) has expectation N μ/(N+1), so its bias is exactly
//! −μ/(N+1) and vanishes as N grows: biased but consistent. Here f(x) = 3x², μ = 1, σ² = 4/5,
//! so the variances are σ²/N and N σ²/(N+1)².

use super::output::{num, StudyOutput};
use super::Scale;
use crate::plot::{Chart, Series, Style};
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

/// The example's table and chart in a study's output (the unbiased-vs-consistent study's last
/// section).
pub fn write(out: &mut StudyOutput, scale: &Scale) -> Result<(), String> {
    let ns = Scale::doublings(64);
    let lecture = measure(&ns, scale.lecture_repetitions, scale.confidence);
    let mut lrows = Vec::new();
    for r in &lecture {
        lrows.push(vec![
            r.n.to_string(),
            num(r.exact_bias),
            format!(
                "{} [{}, {}]",
                num(r.biased.estimate),
                num(r.biased.lo),
                num(r.biased.hi)
            ),
            if r.biased.contains(r.exact_bias) {
                "yes"
            } else {
                "no"
            }
            .into(),
            format!(
                "{} [{}, {}]",
                num(r.unbiased.estimate),
                num(r.unbiased.lo),
                num(r.unbiased.hi)
            ),
            num(r.exact_variance_biased),
            num(r.measured_variance_biased),
        ]);
    }
    out.para(&format!(
        "**The lecture's example.** f(x) = 3x² on [0, 1] (μ = 1, σ² = 0.8), {} repetitions per N: \
         (1/N) Σ f is unbiased; (1/(N+1)) Σ f has bias exactly −μ/(N+1), which vanishes as N \
         grows — biased yet consistent.",
        scale.lecture_repetitions
    ));
    out.table(
        "lecture",
        "(1/N) Σ f against (1/(N+1)) Σ f",
        "Exact and measured bias (t intervals over the repetitions), and the biased estimator's \
         variance N σ²/(N+1)² exact and measured.",
        &[
            "N",
            "exact bias of 1/(N+1)",
            "measured",
            "exact inside",
            "bias of 1/N",
            "variance exact",
            "variance measured",
        ],
        lrows,
        true,
    )?;
    let xs: Vec<f64> = lecture.iter().map(|r| r.n as f64).collect();
    out.chart(
        "lecture",
        &Chart {
            title: "The lecture's example: |bias| of (1/(N+1)) Σ f".into(),
            x_label: "N".into(),
            y_label: "|bias|".into(),
            log_x: true,
            log_y: true,
            series: vec![
                Series {
                    name: "exact μ/(N+1)".into(),
                    points: lecture
                        .iter()
                        .map(|r| (r.n as f64, -r.exact_bias))
                        .collect(),
                    y_interval: Vec::new(),
                    style: Style::Fitted,
                },
                Series {
                    name: "measured".into(),
                    points: xs
                        .iter()
                        .zip(&lecture)
                        .map(|(&x, r)| (x, -r.biased.estimate))
                        .collect(),
                    y_interval: lecture
                        .iter()
                        .map(|r| (-r.biased.hi, -r.biased.lo))
                        .collect(),
                    style: Style::Measured,
                },
            ],
        },
        "Measured bias (t intervals) against the exact −μ/(N+1).",
    )
}

//! Image errors against a reference, as the studies state them.
//!
//! - MSE = mean over pixels and channels of (I − R̂)², minus the reference's own mean variance
//!   (see `reference`): an unbiased estimate of the MSE against the true image.
//! - relMSE = mean over pixels and channels of (I − R̂)² / (R̂² + ε), ε = 0.01: errors in dark
//!   pixels count relative to 0.1 rather than blowing up (not corrected for reference noise).
//! - FLIP = mean of NVIDIA's FLIP error map between the tone-mapped images (`crate::flip`).

use super::reference::Reference;
use lt_estimators::Image;

pub const REL_EPSILON: f64 = 0.01;

pub fn mse(img: &Image, r: &Reference) -> f64 {
    raw_mse(img, &r.image) - r.mean_variance
}

pub fn raw_mse(img: &Image, reference: &Image) -> f64 {
    let mut s = 0.0;
    for (a, b) in img.data.iter().zip(&reference.data) {
        for c in 0..3 {
            s += (a[c] - b[c]).powi(2);
        }
    }
    s / (3 * img.data.len()).max(1) as f64
}

pub fn rel_mse(img: &Image, r: &Reference) -> f64 {
    let mut s = 0.0;
    for (a, b) in img.data.iter().zip(&r.image.data) {
        for c in 0..3 {
            s += (a[c] - b[c]).powi(2) / (b[c] * b[c] + REL_EPSILON);
        }
    }
    s / (3 * img.data.len()).max(1) as f64
}

/// The mean of one value per independent run, with its t interval (K − 1 dof).
pub fn mean_of_runs(values: &[f64], confidence: f64) -> lt_estimators::Interval {
    let s = lt_estimators::RunningStat::from_slice(values);
    let dof = (s.count() as f64 - 1.0).max(1.0);
    lt_estimators::bias_variance::mean_interval(s.mean(), s.std_error(), dof, confidence)
}

/// Mean over `kept` runs of a per-run value.
pub fn mean_over(kept: &[usize], values: &[f64]) -> f64 {
    kept.iter().map(|&i| values[i]).sum::<f64>() / kept.len().max(1) as f64
}

/// The slope of ln(mean over kept runs of y) against ln x, where `per_run[j][r]` is run r's value
/// at x[j]: the statistic the studies jackknife over runs.
pub fn log_log_slope(xs: &[f64], per_run: &[Vec<f64>], kept: &[usize]) -> Result<f64, String> {
    let mut lx = Vec::new();
    let mut ly = Vec::new();
    for (x, ys) in xs.iter().zip(per_run) {
        let m = mean_over(kept, ys);
        if !(m > 0.0) {
            return Err(format!("mean {m:.3e} at x = {x} is not positive"));
        }
        lx.push(x.ln());
        ly.push(m.ln());
    }
    lt_estimators::fit_line(&lx, &ly, 0.95).map(|f| f.slope)
}

/// bias² and variance of one run from the runs `kept` of `images` (one image per run, all at the
/// same N): per pixel and channel (m − R̂)² − s²/K and s², averaged over the image, bias² less
/// the reference's mean variance. The statistic the radius study jackknifes into slopes.
pub fn subset_bias_variance(images: &[Image], kept: &[usize], r: &Reference) -> (f64, f64) {
    let k = kept.len() as f64;
    let (mut b2, mut var) = (0.0, 0.0);
    for (p, rp) in r.image.data.iter().enumerate() {
        for (c, &rc) in rp.iter().enumerate() {
            let m = kept.iter().map(|&i| images[i].data[p][c]).sum::<f64>() / k;
            let s2 = kept
                .iter()
                .map(|&i| (images[i].data[p][c] - m).powi(2))
                .sum::<f64>()
                / (k - 1.0);
            b2 += (m - rc).powi(2) - s2 / k;
            var += s2;
        }
    }
    let n = (3 * r.image.data.len()).max(1) as f64;
    (b2 / n - r.mean_variance, var / n)
}

/// α as the studies print it: 2/3 by name, any other value as it reads.
pub fn alpha_text(a: f64) -> String {
    if (a - 2.0 / 3.0).abs() < 1e-12 {
        "2/3".into()
    } else {
        format!("{a}")
    }
}

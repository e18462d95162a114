//! Effective sample size of a correlated sequence of images, per pixel, from batch means
//! (Flegal & Jones 2010, "Batch means and spectral variance estimators in MCMC"; Geyer 1992 §3).
//!
//! A Markov chain's P passes x_1 … x_P are correlated, so their sample variance s² (the "naive"
//! σ²₀, what a per-pass error bar uses) understates the variance of their mean. Grouping the
//! passes into k batches of m consecutive ones, the batch means ȳ_j vary as the mean of m
//! correlated passes does, so σ²_BM = m · s²(ȳ) estimates the asymptotic variance
//! σ²_∞ = lim P · Var(x̄). Then ESS = P · σ²₀ / σ²_BM: independent passes give ESS/P ≈ 1, a
//! chain with integrated autocorrelation time τ gives ESS/P ≈ 1/τ.
//!
//! Passes arrive one at a time and their number is not known in advance, so batches of m passes
//! are kept (at most `MAX_BATCHES`, in f32: sums of a few passes' values) and neighbours merge
//! (m doubles) when the store is full. The summary regroups them into about √P batches of about
//! √P passes (Flegal & Jones' choice, consistent for σ²_∞ under mixing conditions).

use crate::running::RunningStat;

/// Completed batches kept before neighbours merge: memory is this many f32 per pixel.
pub const MAX_BATCHES: usize = 64;

/// Per-pixel running naive and batch-means variance of a sequence of pass values.
#[derive(Clone, Debug)]
pub struct BatchMeans {
    pixels: usize,
    passes: u64,
    /// Every pass's values, per pixel: the naive variance σ²₀.
    naive: Vec<RunningStat>,
    /// Passes per completed batch.
    batch_len: u64,
    /// Sums of the completed batches' passes, batch-major.
    batches: Vec<Vec<f32>>,
    open: Vec<f64>,
    open_len: u64,
}

/// ESS/P per pixel with how it was computed.
#[derive(Clone, Debug, PartialEq)]
pub struct Ess {
    pub passes: u64,
    /// Batches and passes per batch the estimate used (the passes of an unfinished batch are
    /// not in it).
    pub batches: usize,
    pub batch_len: u64,
    /// ESS / P per pixel; `None` where either variance is zero (unlit, or every pass equal).
    pub ratio: Vec<Option<f64>>,
    /// σ²₀ and σ²_BM per pixel (for pooled statistics).
    pub naive_var: Vec<f64>,
    pub batch_var: Vec<f64>,
}

impl BatchMeans {
    pub fn new(pixels: usize) -> Self {
        BatchMeans {
            pixels,
            passes: 0,
            naive: vec![RunningStat::new(); pixels],
            batch_len: 1,
            batches: Vec::new(),
            open: vec![0.0; pixels],
            open_len: 0,
        }
    }

    pub fn passes(&self) -> u64 {
        self.passes
    }

    /// One pass's value per pixel.
    pub fn add_pass(&mut self, values: &[f64]) {
        assert_eq!(values.len(), self.pixels, "one value per pixel");
        self.passes += 1;
        for (i, &x) in values.iter().enumerate() {
            self.naive[i].add(x);
            self.open[i] += x;
        }
        self.open_len += 1;
        if self.open_len < self.batch_len {
            return;
        }
        if self.batches.len() == MAX_BATCHES {
            // Full: neighbours merge and the open batch becomes the first half of a longer one.
            self.batches = merge_pairs(&self.batches, 2);
            self.batch_len *= 2;
            return;
        }
        self.batches
            .push(self.open.iter().map(|&v| v as f32).collect());
        self.open.iter_mut().for_each(|v| *v = 0.0);
        self.open_len = 0;
    }

    /// ESS/P per pixel from the completed batches regrouped to about √P of them; `None` before
    /// there are at least 4 passes in at least 2 batches of 2.
    pub fn ess(&self) -> Option<Ess> {
        let k = self.batches.len();
        let used = k as u64 * self.batch_len;
        // The largest power-of-two regrouping g that leaves at least √P batches (g divides the
        // stored count only when it is a power of two ≤ k; a ragged last group is dropped).
        let target = (used as f64).sqrt();
        let mut g = 1usize;
        while (k / (2 * g)) as f64 >= target && k / (2 * g) >= 2 {
            g *= 2;
        }
        let grouped = merge_pairs(&self.batches, g);
        let (kb, m) = (grouped.len(), self.batch_len * g as u64);
        if kb < 2 || m < 2 {
            return None;
        }
        let mut ratio = Vec::with_capacity(self.pixels);
        let mut naive_var = Vec::with_capacity(self.pixels);
        let mut batch_var = Vec::with_capacity(self.pixels);
        for i in 0..self.pixels {
            let s0 = self.naive[i].sample_variance();
            let means: Vec<f64> = grouped.iter().map(|b| b[i] as f64 / m as f64).collect();
            let mu = means.iter().sum::<f64>() / kb as f64;
            let s_bm = means.iter().map(|y| (y - mu).powi(2)).sum::<f64>() / (kb as f64 - 1.0);
            let bm = m as f64 * s_bm;
            naive_var.push(s0);
            batch_var.push(bm);
            ratio.push((s0 > 0.0 && bm > 0.0).then(|| s0 / bm));
        }
        Some(Ess {
            passes: self.passes,
            batches: kb,
            batch_len: m,
            ratio,
            naive_var,
            batch_var,
        })
    }
}

/// Sums of `g` consecutive batches (a ragged tail dropped).
fn merge_pairs(batches: &[Vec<f32>], g: usize) -> Vec<Vec<f32>> {
    batches
        .chunks_exact(g)
        .map(|group| {
            let mut sum = vec![0.0f64; group[0].len()];
            for b in group {
                for (s, &v) in sum.iter_mut().zip(b) {
                    *s += v as f64;
                }
            }
            sum.into_iter().map(|v| v as f32).collect()
        })
        .collect()
}

/// Median and 5 %/95 % quantiles of ESS/P over the pixels that have one (nearest rank).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EssSummary {
    pub median: f64,
    pub q05: f64,
    pub q95: f64,
    pub pixels: usize,
}

impl Ess {
    pub fn summary(&self) -> Option<EssSummary> {
        let mut v: Vec<f64> = self.ratio.iter().flatten().copied().collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let q = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
        Some(EssSummary {
            median: q(0.5),
            q05: q(0.05),
            q95: q(0.95),
            pixels: v.len(),
        })
    }
}

/// The coverage a nominal interval x̄ ± q·`half_se` really has when x̄'s error is the naive
/// (per-pass) standard error se₀ inflated to se₀/√(ESS/P), plus an independent error `other_se`
/// (a reference's, a normalisation's) — normal approximation:
/// 2Φ(q·half_se / √(se₀²·P/ESS + other²)) − 1.
pub fn naive_interval_coverage(
    q: f64,
    naive_se: f64,
    ess_ratio: f64,
    half_se: f64,
    other_se: f64,
) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    let sd = (naive_se.powi(2) / ess_ratio + other_se.powi(2)).sqrt();
    if !(sd > 0.0) {
        return 1.0;
    }
    2.0 * Normal::standard().cdf(q * half_se / sd) - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::jackknife::jackknife;
    use crate::test_rng::Rng;

    /// Exact E[σ²₀] and E[σ²_BM] for a stationary AR(1) of unit variance and lag-one correlation
    /// ρ, P = k·m passes in k batches of m: with c(d) the covariance of batch sums d apart,
    /// E[s²] of k equally-distributed correlated variables = (k·c(0) − Var(Σ)/k)/(k − 1).
    fn ar1_expected(rho: f64, k: usize, m: usize) -> (f64, f64) {
        let var_sum = |n: usize| -> f64 {
            n as f64
                + 2.0
                    * (1..n)
                        .map(|h| (n - h) as f64 * rho.powi(h as i32))
                        .sum::<f64>()
        };
        let geo = (0..m).map(|a| rho.powi(a as i32)).sum::<f64>();
        let c = |d: usize| -> f64 {
            if d == 0 {
                var_sum(m)
            } else {
                rho.powi(((d - 1) * m + 1) as i32) * geo * geo
            }
        };
        let total = k as f64 * c(0) + 2.0 * (1..k).map(|d| (k - d) as f64 * c(d)).sum::<f64>();
        let e_s_sums = (k as f64 * c(0) - total / k as f64) / (k as f64 - 1.0);
        let p = k * m;
        let e_naive = (p as f64 - var_sum(p) / p as f64) / (p as f64 - 1.0);
        (e_naive, e_s_sums / m as f64)
    }

    /// `pixels` independent AR(1) sequences of `passes` steps through `BatchMeans`.
    fn run_ar1(rho: f64, pixels: usize, passes: usize, seed: u64) -> Ess {
        let mut rng = Rng::new(seed);
        let mut x: Vec<f64> = (0..pixels).map(|_| rng.normal()).collect();
        let mut bm = BatchMeans::new(pixels);
        let innov = (1.0 - rho * rho).sqrt();
        for _ in 0..passes {
            bm.add_pass(&x);
            for v in &mut x {
                *v = rho * *v + innov * rng.normal();
            }
        }
        bm.ess().unwrap()
    }

    /// Σσ²_BM / Σσ²₀ over the pixels (P/ESS pooled), against its exact expectation for AR(1),
    /// with a jackknife interval over the independent pixels: iid passes (ESS/P = 1) and two
    /// correlated chains (ESS/P = (1−ρ)/(1+ρ) up to the finite-batch terms the exact formula
    /// keeps). 4096 passes regroup to 64 batches of 64.
    #[test]
    fn batch_means_ess_matches_ar1_exactly() {
        let (pixels, passes) = (400, 4096);
        // Three checks, Šidák over them at α = 1e-3 (two-sided t with pixels − 1 dof).
        let conf = (1.0 - 1e-3f64).powf(1.0 / 3.0);
        for (i, rho) in [0.0, 0.5, 0.9].into_iter().enumerate() {
            let ess = run_ar1(rho, pixels, passes, 17 + i as u64);
            assert_eq!((ess.batches, ess.batch_len), (64, 64));
            let (e0, ebm) = ar1_expected(rho, ess.batches, ess.batch_len as usize);
            let expected = ebm / e0;
            let pooled = |kept: &[usize]| -> Result<f64, String> {
                let bm: f64 = kept.iter().map(|&p| ess.batch_var[p]).sum();
                let n0: f64 = kept.iter().map(|&p| ess.naive_var[p]).sum();
                Ok(bm / n0)
            };
            let j = jackknife(pixels, conf, pooled).unwrap();
            println!(
                "ρ = {rho}: P/ESS pooled {:.4} ± {:.4}, expected {expected:.4} (asymptotic {:.4})",
                j.estimate,
                j.std_error,
                (1.0 + rho) / (1.0 - rho)
            );
            assert!(
                j.interval.lo <= expected && expected <= j.interval.hi,
                "ρ = {rho}: P/ESS {:.4} ∉ [{:.4}, {:.4}] around the exact {expected:.4}",
                j.estimate,
                j.interval.lo,
                j.interval.hi
            );
        }
    }

    #[test]
    fn few_passes_give_no_estimate_and_regrouping_follows_sqrt_p() {
        let mut bm = BatchMeans::new(1);
        for i in 0..3 {
            bm.add_pass(&[i as f64]);
        }
        assert!(bm.ess().is_none());
        for i in 3..64 {
            bm.add_pass(&[(i % 7) as f64]);
        }
        let e = bm.ess().unwrap();
        assert_eq!((e.batches, e.batch_len), (8, 8));
        let s = e.summary().unwrap();
        assert_eq!(s.pixels, 1);
    }
}

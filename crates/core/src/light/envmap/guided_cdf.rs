//! A discrete distribution sampled by CDF inversion with a guide table (the "cutpoint" or
//! guide-table method: Chen & Asau 1974; Devroye, *Non-Uniform Random Variate Generation*,
//! 1986, §III.2.4): the table holds, for each of n equal slices of [0, 1), the first bin whose
//! CDF exceeds the slice's start, and a draw walks up from there — O(1) expected steps with n
//! slices for n bins, where a binary search takes log₂ n.
//!
//! It inverts the same CDF, built with the same arithmetic, as `sampling::Distribution1D`, and
//! returns the same bin and remapped variate for every u, bit for bit (tested below): an
//! environment map sampled through it draws the same texels as before, so only its speed changed.

/// The CDF of non-negative weights (as `Distribution1D` builds it) with a guide table.
#[derive(Clone, Debug, Default)]
pub struct GuidedCdf {
    cdf: Vec<f32>,
    pmf: Vec<f32>,
    total: f32,
    /// `guide[k]` = the first bin i with cdf[i] > k / n (n = number of bins).
    guide: Vec<u32>,
}

impl GuidedCdf {
    /// Weights must be finite and non-negative; an all-zero list gives an empty distribution.
    pub fn new(weights: &[f32]) -> GuidedCdf {
        let total_f64: f64 = weights.iter().map(|&w| w as f64).sum();
        let total = total_f64 as f32;
        if total_f64 <= 0.0 {
            return GuidedCdf {
                cdf: vec![],
                pmf: vec![0.0; weights.len()],
                total: 0.0,
                guide: vec![],
            };
        }
        // `Distribution1D::new`'s sums and roundings, so the bins' edges are its bits.
        let mut acc = 0.0f64;
        let mut cdf = Vec::with_capacity(weights.len());
        for &w in weights {
            acc += w as f64;
            cdf.push((acc / total_f64) as f32);
        }
        *cdf.last_mut().unwrap() = 1.0;
        let pmf = weights
            .iter()
            .map(|&w| (w as f64 / total_f64) as f32)
            .collect();
        let n = cdf.len();
        let guide = (0..n)
            .map(|k| {
                let start = k as f32 / n as f32;
                cdf.partition_point(|&c| c <= start).min(n - 1) as u32
            })
            .collect();
        GuidedCdf {
            cdf,
            pmf,
            total,
            guide,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    pub fn total(&self) -> f32 {
        self.total
    }

    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// The first bin whose CDF exceeds u (the last bin for u ≥ 1): `Distribution1D`'s
    /// `partition_point(c ≤ u)`, found from the guide. The slice index k = ⌊u·n⌋ is rounded in
    /// f32 and may be one too high (u·n just below an integer rounds up), so the walk also steps
    /// down while the bin below still exceeds u; either walk ends at that first bin.
    #[inline]
    fn bin(&self, u: f32) -> usize {
        let n = self.cdf.len();
        let k = ((u * n as f32) as usize).min(n - 1);
        let mut i = self.guide[k] as usize;
        while i > 0 && self.cdf[i - 1] > u {
            i -= 1;
        }
        while i < n - 1 && self.cdf[i] <= u {
            i += 1;
        }
        i
    }

    /// Returns (bin, pmf, u remapped to [0, 1) within the bin), as `Distribution1D::sample`;
    /// for a non-empty distribution (`is_empty`).
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        debug_assert!(!self.is_empty(), "sampling an empty distribution");
        let i = self.bin(u);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let p = self.pmf[i];
        let remapped = if p > 0.0 {
            ((u - lo) / (self.cdf[i] - lo)).clamp(0.0, 1.0 - f32::EPSILON)
        } else {
            0.0
        };
        (i, p, remapped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Distribution1D, Sampler};

    /// For weights with zero runs (at the start, inside, at the end), one dominant bin and many
    /// equal ones, every u — random, on every CDF value, one ulp either side of it, 0 and the
    /// largest f32 below 1 — gives `Distribution1D::sample`'s answer bit for bit.
    #[test]
    fn samples_what_distribution1d_samples() {
        let mut s = Sampler::new(3, 0, 0);
        let lists: Vec<Vec<f32>> = vec![
            vec![1.0],
            vec![0.0, 0.0, 3.0, 0.0, 1.0, 0.0],
            vec![5.0; 37],
            (0..512)
                .map(|i| {
                    if i % 7 == 0 {
                        0.0
                    } else {
                        1.0 + (i % 13) as f32
                    }
                })
                .collect(),
            (0..300)
                .map(|i| if i == 150 { 1e6 } else { 1e-3 })
                .collect(),
            (0..257).map(|_| s.next_f32().powi(8)).collect(),
        ];
        for weights in &lists {
            let (ours, reference) = (GuidedCdf::new(weights), Distribution1D::new(weights));
            let mut us: Vec<f32> = (0..20_000).map(|_| s.next_f32()).collect();
            us.extend([0.0, 1.0 - f32::EPSILON / 2.0]);
            for &c in &ours.cdf {
                us.extend([
                    c,
                    f32::from_bits(c.to_bits() - 1),
                    f32::from_bits(c.to_bits() + 1),
                ]);
            }
            for u in us.into_iter().filter(|u| (0.0..1.0).contains(u)) {
                let (a, b) = (ours.sample(u), reference.sample(u));
                assert!(
                    a.0 == b.0 && a.1.to_bits() == b.1.to_bits() && a.2.to_bits() == b.2.to_bits(),
                    "{} bins, u = {u:e}: {a:?} vs Distribution1D {b:?}",
                    weights.len()
                );
            }
        }
    }
}

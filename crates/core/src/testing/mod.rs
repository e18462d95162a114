//! Statistical helpers for the sampling tests of materials and lights. Public (not `cfg(test)`) so
//! that the integration tests of every crate can use them.
//!
//! Every test here can fail: it has a fixed seed and a rejection threshold derived from the test
//! statistic (a p-value against a Šidák-corrected level, or a z-score against a normal quantile).

pub mod chi2;

use crate::math::{Frame, Vec3};

/// Per-test significance that keeps the family-wise false-rejection rate at `alpha` over `tests`
/// independent tests (Šidák correction).
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests.max(1) as f64)
}

/// z-score of `k` successes in `n` Bernoulli trials against success probability `p`.
/// Returns 0 when the outcome is certain and matches, ±∞ when it is certain and does not.
pub fn binomial_z(k: u64, n: u64, p: f64) -> f64 {
    let n_f = n as f64;
    let sd = (n_f * p * (1.0 - p)).sqrt();
    let diff = k as f64 - n_f * p;
    if sd == 0.0 {
        if diff == 0.0 {
            0.0
        } else {
            diff.signum() * f64::INFINITY
        }
    } else {
        diff / sd
    }
}

/// Running mean and standard error of i.i.d. values (Welford's update, in f64).
#[derive(Clone, Copy, Debug, Default)]
pub struct MeanEstimate {
    n: u64,
    mean: f64,
    m2: f64,
}

impl MeanEstimate {
    pub fn add(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }
    pub fn mean(&self) -> f64 {
        self.mean
    }
    pub fn count(&self) -> u64 {
        self.n
    }
    /// Standard error of the mean.
    pub fn std_error(&self) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        (self.m2 / (self.n - 1) as f64 / self.n as f64).sqrt()
    }
}

/// How much `f` may legitimately change when the unit direction `w` is perturbed by rounding:
/// the largest |f(w') − f(w)| over w' tilted by `delta` radians along two tangents, plus `delta`
/// relative to |f(w)|. A comparison of two computations of f at "the same" direction (one of
/// them through extra frame rotations) should agree to within this bound.
pub fn rounding_bound(f: impl Fn(Vec3) -> f64, w: Vec3, delta: f32) -> f64 {
    let f0 = f(w);
    let fr = Frame::from_z(w);
    let mut worst = 0.0f64;
    for t in [fr.x, -fr.x, fr.y, -fr.y] {
        let v = f((w + delta * t).normalize());
        worst = worst.max((v - f0).abs());
    }
    worst + delta as f64 * f0.abs()
}

/// Bound on the rounding error (radians) of a unit direction after the few f32 frame changes a
/// test puts it through: each `to_local` / `to_world` is three 3-term dot products (γ(3) ≈ 1.5ε
/// each) with a frame orthonormal to a few ulps, and a direction passes through at most four of
/// them, so ≲ 4·√3·(γ(3) + 4ε) ≈ 38ε; rounded up to 64ε.
pub const DIRECTION_ROUNDING: f32 = 64.0 * f32::EPSILON;

//! Phase functions: the angular distribution of light scattered at a point inside a medium.
//! Both directions point away from the scattering point; values and densities are per steradian.
//!
//! Sign convention (Mitsuba 3's `hg`, which evaluates HG at the cosine between its `wo` and the
//! interaction's `wi`, both pointing away, with 1 + g² **+** 2g·cos): here the cosine is taken
//! between the propagation direction −ω_o and ω_i, with 1 + g² − 2g·cos — the same function, so a
//! scene's `g` means what it means in Mitsuba: g > 0 scatters forward (ω_i ≈ −ω_o).
//!
//! Both phase functions are sampled exactly (their own density), so a sample's `value` equals its
//! `pdf` and the path throughput weight value/pdf is 1.

use crate::math::{Frame, Vec2, Vec3, PI};
use crate::sampling::{sample_uniform_sphere, UNIFORM_SPHERE_PDF};

/// A phase function (Mitsuba's `isotropic` and `hg`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhaseFunction {
    /// 1 / 4π in every direction.
    Isotropic,
    /// Henyey–Greenstein with mean cosine `g` ∈ (−1, 1) between the incident propagation
    /// direction −ω_o and ω_i (g > 0 scatters forward).
    HenyeyGreenstein { g: f32 },
}

/// A sampled direction ω_i with the phase function's value there and the solid-angle density of
/// the sample (equal, for the exactly sampled phase functions here).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseSample {
    pub wi: Vec3,
    pub value: f32,
    pub pdf: f32,
}

/// Below this |g| HG is sampled as isotropic: the inversion's 1/(2g) loses every digit as g → 0,
/// and at |g| = 1e-4 HG differs from 1/4π by at most 3|g| ≈ 3e-4 relative, while `pdf` (which
/// evaluates HG itself) keeps the pair consistent to that.
const HG_ISOTROPIC_BELOW: f32 = 1e-4;

impl PhaseFunction {
    /// A validated `hg`: g finite and strictly inside (−1, 1) (at ±1 HG is a delta).
    pub fn henyey_greenstein(g: f32) -> Result<PhaseFunction, String> {
        if g.is_finite() && g.abs() < 1.0 {
            Ok(PhaseFunction::HenyeyGreenstein { g })
        } else {
            Err(format!("hg: g = {g} must lie strictly between -1 and 1"))
        }
    }

    /// p(ω_o, ω_i), both unit and pointing away from the point.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            PhaseFunction::Isotropic => UNIFORM_SPHERE_PDF,
            PhaseFunction::HenyeyGreenstein { g } => henyey_greenstein(-wo.dot(wi), g),
        }
    }

    /// Solid-angle density of [`PhaseFunction::sample`] producing ω_i: the phase function itself.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.eval(wo, wi)
    }

    /// Samples ω_i ∝ p(ω_o, ·) by inverting the CDF of the cosine to the propagation direction −ω_o
    /// (uniform azimuth). `None` never happens for these two; it is in the signature for phase
    /// functions that may reject.
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<PhaseSample> {
        let wi = match *self {
            PhaseFunction::Isotropic => sample_uniform_sphere(u),
            PhaseFunction::HenyeyGreenstein { g } if g.abs() < HG_ISOTROPIC_BELOW => {
                sample_uniform_sphere(u)
            }
            PhaseFunction::HenyeyGreenstein { g } => {
                let cos = sample_hg_cos(u.x, g);
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
                Frame::from_z(-wo).to_world(local).normalize()
            }
        };
        let value = self.eval(wo, wi);
        Some(PhaseSample {
            wi,
            value,
            pdf: value,
        })
    }
}

/// HG's density in the cosine between propagation directions: (1 − g²) / (4π (1 + g² − 2g cos)^{3/2}).
fn henyey_greenstein(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    0.25 * std::f32::consts::FRAC_1_PI * (1.0 - g * g) / (denom * denom.max(0.0).sqrt())
}

/// The cosine μ with CDF u under HG (Henyey & Greenstein 1941; the inversion as in pbrt-v3 §15.2.3
/// with its sign fixed to our μ): P(μ' ≤ μ) = (1 − g²)/(2g) · ((1 + g² − 2gμ)^{−1/2} − (1 + g)^{−1}),
/// solved for μ = (1 + g² − ((1 − g²)/(1 − g + 2gu))²) / (2g). Computed in f64: for g near ±1 the
/// square nearly cancels 1 + g².
fn sample_hg_cos(u: f32, g: f32) -> f32 {
    let (u, g) = (u as f64, g as f64);
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hg_cosine_inversion_hits_both_ends_and_the_median() {
        for g in [-0.7f32, 0.3, 0.95] {
            assert_eq!(sample_hg_cos(0.0, g), -1.0);
            assert!((sample_hg_cos(1.0, g) - 1.0).abs() < 1e-6);
        }
        // The mean cosine is g: midpoint rule over u. μ(u) is monotone with total variation 2,
        // so the rule errs by at most 2/n; each f32 value adds ε/2 relative.
        for g in [-0.7f32, 0.3, 0.7] {
            let n = 100_000;
            let mean: f64 = (0..n)
                .map(|i| sample_hg_cos((i as f32 + 0.5) / n as f32, g) as f64)
                .sum::<f64>()
                / n as f64;
            let bound = 2.0 / n as f64 + f32::EPSILON as f64;
            assert!((mean - g as f64).abs() <= bound, "g {g}: mean {mean}");
        }
    }

    #[test]
    fn hg_refuses_g_outside_the_open_interval() {
        for g in [1.0, -1.0, 1.5, f32::NAN, f32::INFINITY] {
            assert!(PhaseFunction::henyey_greenstein(g).is_err(), "{g}");
        }
        assert!(PhaseFunction::henyey_greenstein(0.999).is_ok());
    }
}

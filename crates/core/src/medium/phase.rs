//! Phase functions: the angular distribution of light scattered at a point inside a medium.
//! Both directions point away from the scattering point; values and densities are per steradian.

use crate::math::Vec3;

/// A phase function (Mitsuba's `isotropic` and `hg`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhaseFunction {
    /// 1 / 4π in every direction.
    Isotropic,
    /// Henyey–Greenstein with mean cosine `g` ∈ (−1, 1) between the incident propagation
    /// direction −ω_o and ω_i (g > 0 scatters forward).
    HenyeyGreenstein { g: f32 },
}

impl PhaseFunction {
    /// p(ω_o, ω_i), both unit and pointing away from the point.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            PhaseFunction::Isotropic => 0.25 * std::f32::consts::FRAC_1_PI,
            PhaseFunction::HenyeyGreenstein { g } => henyey_greenstein(-wo.dot(wi), g),
        }
    }
}

/// HG's density in the cosine between propagation directions: (1 − g²) / (4π (1 + g² − 2g cos)^{3/2}).
fn henyey_greenstein(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    0.25 * std::f32::consts::FRAC_1_PI * (1.0 - g * g) / (denom * denom.max(0.0).sqrt())
}

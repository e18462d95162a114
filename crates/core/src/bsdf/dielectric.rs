//! Smooth dielectric (glass): Fresnel-weighted choice between specular reflection and refraction.
//! PLACEHOLDER until the bsdf helper lands.

use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3};

#[derive(Clone, Debug)]
pub struct Dielectric {
    /// Index of refraction inside relative to outside (the side the normal points to).
    pub ior: f32,
}

impl LocalBsdf for Dielectric {
    fn sample(&self, _wo: Vec3, _u_lobe: f32, _u: Vec2, _mode: TransportMode) -> Option<LocalSample> {
        None
    }
    fn eval(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> Color {
        Color::ZERO
    }
    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }
    fn is_delta(&self) -> bool {
        true
    }
}

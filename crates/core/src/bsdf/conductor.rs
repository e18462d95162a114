//! Smooth conductor (Mitsuba 3's `conductor`): a delta reflection with the Fresnel reflectance of
//! a complex IOR, times `specular_reflectance`. One-sided as in Mitsuba: light from below the
//! shading normal is absorbed (wrap it in `twosided` for both sides).

use super::conductor_ior::PERFECT_MIRROR;
use super::fresnel::{fresnel_conductor, ComplexIor};
use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3};

/// Mitsuba parameters: `material` (a name of `conductor_ior::named_conductor`, default "none" =
/// η 0, k 1, a perfect mirror) or `eta` and `k` (RGB); `specular_reflectance` (default 1).
#[derive(Clone, Debug)]
pub struct Conductor {
    pub ior: ComplexIor,
    pub specular_reflectance: Color,
}

impl Default for Conductor {
    /// Mitsuba's defaults: `material="none"`, `specular_reflectance` 1.
    fn default() -> Self {
        Conductor {
            ior: PERFECT_MIRROR,
            specular_reflectance: Color::ONE,
        }
    }
}

impl LocalBsdf for Conductor {
    fn sample(
        &self,
        wo: Vec3,
        _u_lobe: f32,
        _u: Vec2,
        _mode: TransportMode,
    ) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        Some(LocalSample {
            wi: Vec3::new(-wo.x, -wo.y, wo.z),
            weight: self.specular_reflectance * fresnel_conductor(wo.z, self.ior),
            pdf_w: 1.0,
            pdf_rev_w: 1.0,
            delta: true,
        })
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

/// The sampling tests' smooth conductor (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Conductor {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::test_registry::*;
        use super::Material;
        vec![(
            "conductor-Au",
            Material::Conductor(Conductor {
                ior: gold(),
                specular_reflectance: CONDUCTOR_TINT,
            }),
        )]
    }
}

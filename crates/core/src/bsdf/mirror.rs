//! Perfect specular reflection scaled by a constant reflectance.

use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3};

#[derive(Clone, Debug)]
pub struct Mirror {
    pub reflectance: Color,
}

impl LocalBsdf for Mirror {
    fn sample(
        &self,
        wo: Vec3,
        _u_lobe: f32,
        _u: Vec2,
        _mode: TransportMode,
    ) -> Option<LocalSample> {
        let wi = Vec3::new(-wo.x, -wo.y, wo.z);
        Some(LocalSample {
            wi,
            weight: self.reflectance,
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

/// The sampling tests' mirror (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Mirror {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::test_registry::*;
        use super::Material;
        vec![("mirror", Material::Mirror(Mirror { reflectance: COLOR }))]
    }
}

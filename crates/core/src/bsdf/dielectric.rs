//! Smooth dielectric (glass): specular reflection with probability F (exact unpolarised Fresnel)
//! and specular refraction with probability 1 − F. Both lobes are deltas.
//!
//! Refracted throughput takes `refraction::refracted_throughput_scale` (1/η² for radiance, 1 for
//! importance).

use super::fresnel::fresnel_dielectric;
use super::refraction::refracted_throughput_scale;
use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3};

#[derive(Clone, Debug)]
pub struct Dielectric {
    /// Index of refraction inside relative to outside (the side the normal points to).
    pub ior: f32,
}

impl Dielectric {
    /// Relative IOR η_t / η_i for a path arriving from `wo` (wo.z > 0: from outside).
    #[inline]
    pub fn eta_for(&self, wo: Vec3) -> f32 {
        if wo.z > 0.0 {
            self.ior
        } else {
            1.0 / self.ior
        }
    }
}

impl LocalBsdf for Dielectric {
    fn sample(&self, wo: Vec3, u_lobe: f32, _u: Vec2, mode: TransportMode) -> Option<LocalSample> {
        if wo.z == 0.0 {
            return None;
        }
        let eta = self.eta_for(wo);
        let (f, cos_t) = fresnel_dielectric(wo.z.abs(), eta);
        if u_lobe < f {
            // Lobe value F·δ / |cos θi| times |cos θi|, over its probability F: weight 1.
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(LocalSample {
                wi,
                weight: Color::ONE,
                pdf_w: f,
                pdf_rev_w: f,
                delta: true,
            });
        }
        let wi = Vec3::new(-wo.x / eta, -wo.y / eta, -cos_t.copysign(wo.z));
        let scale = refracted_throughput_scale(eta, mode);
        // Fresnel is symmetric (F(θt, 1/η) = F(θi, η)), so the reverse refraction has the same 1 − F.
        let t = 1.0 - f;
        Some(LocalSample {
            wi,
            weight: Color::splat(scale),
            pdf_w: t,
            pdf_rev_w: t,
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

/// The sampling tests' glasses, seen from both sides (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Dielectric {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::Material;
        let glass = |ior| Material::Dielectric(Dielectric { ior });
        vec![
            ("glass-1.5", glass(1.5)),
            ("glass-1/1.5", glass(1.0 / 1.5)),
            ("glass-2.4", glass(2.4)),
        ]
    }
}

//! Thin dielectric (Mitsuba 3's `thindielectric`): a pane of glass of negligible thickness. Light
//! bounces between its two faces; summing the geometric series of the internal reflections
//! (each face reflecting R = F(θ, η), transmitting T = 1 − R) gives
//!   R' = R + T² R / (1 − R²) = 2R / (1 + R),   T' = 1 − R'
//! (Mitsuba's `thindielectric`). Reflection is a mirror delta; transmission passes straight
//! through (wi = −wo), so the path leaves into the medium it came from and takes no η² factor in
//! either transport mode. The pane is the same seen from both sides.

use super::fresnel::fresnel_dielectric;
use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3};

/// Mitsuba parameters: `int_ior` ("bk7" = 1.5046) / `ext_ior` ("air" = 1.000277),
/// `specular_reflectance` and `specular_transmittance` (1).
#[derive(Clone, Debug)]
pub struct ThinDielectric {
    /// IOR of the pane relative to its surroundings (`int_ior / ext_ior`).
    pub ior: f32,
    pub specular_reflectance: Color,
    pub specular_transmittance: Color,
}

impl ThinDielectric {
    /// Mitsuba's defaults: bk7 in air, both factors 1.
    pub fn mitsuba_default() -> Self {
        ThinDielectric {
            ior: (1.5046f64 / 1.000277) as f32,
            specular_reflectance: Color::ONE,
            specular_transmittance: Color::ONE,
        }
    }

    /// R' of the pane at `cos_theta` (either side): 2R/(1 + R), the geometric series closed.
    pub fn reflectance(&self, cos_theta: f32) -> f32 {
        let r = fresnel_dielectric(cos_theta.abs().min(1.0), self.ior).0;
        2.0 * r / (1.0 + r)
    }
}

impl Default for ThinDielectric {
    fn default() -> Self {
        ThinDielectric::mitsuba_default()
    }
}

impl LocalBsdf for ThinDielectric {
    fn sample(&self, wo: Vec3, u_lobe: f32, _u: Vec2, _mode: TransportMode) -> Option<LocalSample> {
        if wo.z == 0.0 {
            return None;
        }
        // Both lobes keep |cos θ|, so the reverse step picks its lobe with the same probability.
        let r = self.reflectance(wo.z);
        let (wi, weight, p) = if u_lobe < r {
            (Vec3::new(-wo.x, -wo.y, wo.z), self.specular_reflectance, r)
        } else {
            (-wo, self.specular_transmittance, 1.0 - r)
        };
        Some(LocalSample {
            wi,
            weight,
            pdf_w: p,
            pdf_rev_w: p,
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

/// The sampling tests' panes (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for ThinDielectric {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::Material;
        let pane = |ior, specular_reflectance, specular_transmittance| {
            Material::ThinDielectric(ThinDielectric {
                ior,
                specular_reflectance,
                specular_transmittance,
            })
        };
        vec![
            ("thindielectric-1.5", pane(1.5, Color::ONE, Color::ONE)),
            (
                "thindielectric-1.33-tinted",
                pane(1.33, Color::new(0.9, 1.0, 0.7), Color::new(1.0, 0.6, 0.8)),
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R' of Mitsuba 3.9.1 (scalar_rgb) `thindielectric` with int_ior 1.5, ext_ior 1: the
    /// reflection lobe's probability (`bs.pdf`) from above and from below.
    #[test]
    fn reflectance_matches_mitsuba() {
        let pane = ThinDielectric {
            ior: 1.5,
            ..ThinDielectric::mitsuba_default()
        };
        for (cos, mitsuba) in [
            (1.0f32, 0.07692308723926544f64),
            (0.5, 0.1637675166130066),
            (0.1, 0.7274055480957031),
        ] {
            for side in [1.0, -1.0] {
                let wo = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, side * cos);
                let s = pane
                    .sample(wo, 0.0, Vec2::ZERO, TransportMode::Radiance)
                    .unwrap();
                assert!(
                    (s.pdf_w as f64 / mitsuba - 1.0).abs() < 1e-5 && s.wi.z == wo.z,
                    "cos θ {cos} side {side}: R' {} vs Mitsuba {mitsuba}",
                    s.pdf_w
                );
                let t = pane
                    .sample(wo, 0.9999, Vec2::ZERO, TransportMode::Importance)
                    .unwrap();
                assert!(t.wi == -wo && t.weight == Color::ONE && t.pdf_w == 1.0 - s.pdf_w);
            }
        }
    }
}

//! Rough conductor (Mitsuba 3's `roughconductor`): Beckmann or GGX microfacets, isotropic or not,
//! with the Fresnel reflectance of a complex IOR times `specular_reflectance` (Walter et al. 2007,
//! eq. 20): f = F(wo·h)·D(h)·G1(wo, h)·G1(wi, h) / (4 cos θo cos θi), h = (wo + wi)/‖wo + wi‖.
//! Sampled by `Microfacet::sample_normal` and reflected, so pdf(wi) = pdf_m(h) / (4 wi·h).
//! One-sided, as in Mitsuba.
//!
//! Single scattering only: light masked or shadowed by a facet is lost, so a white rough
//! conductor reflects less than 1, more so at grazing angles and large α (tested against Mitsuba).

use super::conductor_ior::PERFECT_MIRROR;
use super::fresnel::{fresnel_conductor, ComplexIor};
use super::microfacet::{reflect, reflection_jacobian, Microfacet, MicrofacetType};
use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3};

/// Mitsuba parameters: `distribution` ("beckmann" default, "ggx"), `alpha` (0.1) or `alpha_u` and
/// `alpha_v`, `sample_visible` (true), `material` ("none") or `eta`/`k`, `specular_reflectance` (1).
#[derive(Clone, Debug)]
pub struct RoughConductor {
    pub distribution: Microfacet,
    pub ior: ComplexIor,
    pub specular_reflectance: Color,
}

impl RoughConductor {
    /// Mitsuba's defaults: Beckmann, α = 0.1, visible normals, `material="none"`, reflectance 1.
    pub fn mitsuba_default() -> Self {
        RoughConductor {
            distribution: Microfacet::isotropic(MicrofacetType::Beckmann, 0.1),
            ior: PERFECT_MIRROR,
            specular_reflectance: Color::ONE,
        }
    }

    fn fresnel(&self, cos: f32) -> Color {
        self.specular_reflectance * fresnel_conductor(cos, self.ior)
    }
}

impl Default for RoughConductor {
    fn default() -> Self {
        RoughConductor::mitsuba_default()
    }
}

impl LocalBsdf for RoughConductor {
    fn sample(&self, wo: Vec3, _u_lobe: f32, u: Vec2, _mode: TransportMode) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let dist = &self.distribution;
        let m = dist.sample_normal(wo, u);
        let wi = reflect(wo, m);
        if wi.z <= 0.0 || wo.dot(m) <= 0.0 {
            return None;
        }
        let pdf_w = self.pdf(wo, wi);
        if !(pdf_w > 0.0) {
            return None;
        }
        // f·cos θi / pdf, with the common factors cancelled (Heitz 2018, eq. 19 for visible normals).
        let g_over_pdf = if dist.sample_visible {
            dist.g1(wi, m)
        } else {
            dist.g(wo, wi, m) * wo.dot(m) / (wo.z * m.z)
        };
        Some(LocalSample {
            wi,
            weight: self.fresnel(wo.dot(m)) * g_over_pdf,
            pdf_w,
            pdf_rev_w: self.pdf(wi, wo),
            delta: false,
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> Color {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Color::ZERO;
        }
        let h = (wo + wi).normalize();
        let dist = &self.distribution;
        // Grouped symmetrically in wo and wi so that f(wo, wi) == f(wi, wo) exactly (wo·h and
        // wi·h are equal but for rounding: Fresnel reads their mean).
        let g = dist.g1(wo, h) * dist.g1(wi, h);
        let cos_h = 0.5 * (wo.dot(h) + wi.dot(h));
        self.fresnel(cos_h) * (dist.d(h) * g / (4.0 * (wo.z * wi.z)))
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        if wo.dot(h) <= 0.0 || wi.dot(h) <= 0.0 {
            return 0.0;
        }
        self.distribution.pdf_normal(wo, h) * reflection_jacobian(wi, h)
    }

    fn is_delta(&self) -> bool {
        false
    }
}

/// The sampling tests' rough conductors (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for RoughConductor {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::microfacet::MicrofacetType::{Beckmann, Ggx};
        use super::test_registry::*;
        vec![
            (
                "roughconductor-beckmann-0.05",
                rough_gold(Beckmann, 0.05, 0.05, true),
            ),
            (
                "roughconductor-beckmann-0.3",
                rough_gold(Beckmann, 0.3, 0.3, true),
            ),
            (
                "roughconductor-beckmann-0.1x0.4",
                rough_gold(Beckmann, 0.1, 0.4, true),
            ),
            (
                "roughconductor-beckmann-0.3-all",
                rough_gold(Beckmann, 0.3, 0.3, false),
            ),
            ("roughconductor-ggx-0.05", rough_gold(Ggx, 0.05, 0.05, true)),
            ("roughconductor-ggx-0.3", rough_gold(Ggx, 0.3, 0.3, true)),
            (
                "roughconductor-ggx-0.4x0.1",
                rough_gold(Ggx, 0.4, 0.1, true),
            ),
            (
                "roughconductor-ggx-0.2x0.5-all",
                rough_gold(Ggx, 0.2, 0.5, false),
            ),
        ]
    }
}

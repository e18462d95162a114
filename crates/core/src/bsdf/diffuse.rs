//! Lambertian reflection: f = albedo / π, sampled by the cosine-weighted hemisphere. `Diffuse`
//! reflects alike on both sides (lt's own scenes); `FrontDiffuse` on the front only, as Mitsuba's
//! `diffuse` does unless `twosided` wraps it: a back face is black (the inside of an open
//! cylinder in Mitsuba's various_shapes test).

use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3, INV_PI};
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};

#[derive(Clone, Debug)]
pub struct Diffuse {
    pub albedo: Color,
}

impl LocalBsdf for Diffuse {
    fn sample(&self, wo: Vec3, _u_lobe: f32, u: Vec2, _mode: TransportMode) -> Option<LocalSample> {
        let mut wi = sample_cosine_hemisphere(u);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        let pdf_w = cosine_hemisphere_pdf(wi.z.abs());
        if pdf_w == 0.0 {
            return None;
        }
        Some(LocalSample {
            wi,
            weight: self.albedo,
            pdf_w,
            pdf_rev_w: cosine_hemisphere_pdf(wo.z.abs()),
            delta: false,
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> Color {
        if wo.z * wi.z > 0.0 {
            self.albedo * INV_PI
        } else {
            Color::ZERO
        }
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z * wi.z > 0.0 {
            cosine_hemisphere_pdf(wi.z.abs())
        } else {
            0.0
        }
    }

    fn is_delta(&self) -> bool {
        false
    }
}

/// Mitsuba's one-sided `diffuse`: `Diffuse` where wo and wi are both above the shading surface,
/// nothing below it.
#[derive(Clone, Debug)]
pub struct FrontDiffuse {
    pub albedo: Color,
}

impl LocalBsdf for FrontDiffuse {
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        Diffuse {
            albedo: self.albedo,
        }
        .sample(wo, u_lobe, u, mode)
    }

    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> Color {
        if wo.z > 0.0 && wi.z > 0.0 {
            self.albedo * INV_PI
        } else {
            Color::ZERO
        }
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z > 0.0 && wi.z > 0.0 {
            cosine_hemisphere_pdf(wi.z)
        } else {
            0.0
        }
    }

    fn is_delta(&self) -> bool {
        false
    }
}

/// The sampling tests' diffuse material (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Diffuse {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::test_registry::*;
        use super::Material;
        vec![("diffuse", Material::Diffuse(Diffuse { albedo: COLOR }))]
    }
}

/// The sampling tests' one-sided diffuse material (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for FrontDiffuse {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::test_registry::*;
        use super::Material;
        vec![(
            "diffuse-front",
            Material::FrontDiffuse(FrontDiffuse { albedo: COLOR }),
        )]
    }
}

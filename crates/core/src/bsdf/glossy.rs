//! Rough conductor: isotropic GGX (Trowbridge–Reitz) microfacets with Fresnel = 1 scaled by a
//! constant reflectance (Mitsuba 3's `roughconductor` with material="none").
//!
//! f = R·D(h)·G1(wo)·G1(wi) / (4|cos θo||cos θi|), with separable Smith shadowing (Walter et al.
//! 2007, as Mitsuba 3 uses). Directions are drawn from the distribution of visible normals
//! (Heitz 2018), so pdf(wi) = G1(wo)·D(h) / (4|cos θo|) and the sample weight is R·G1(wi).
//! Two-sided: a `wo` below the surface is mirrored to the upper hemisphere and back.

use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3, PI};

#[derive(Clone, Debug)]
pub struct Glossy {
    pub reflectance: Color,
    /// GGX α.
    pub roughness: f32,
}

/// Flips `v` into the upper hemisphere when `below`.
#[inline]
fn up(v: Vec3, below: bool) -> Vec3 {
    if below {
        Vec3::new(v.x, v.y, -v.z)
    } else {
        v
    }
}

impl Glossy {
    /// α, kept away from 0 where D degenerates into a delta (and divides by zero).
    #[inline]
    fn alpha(&self) -> f32 {
        self.roughness.max(1e-4)
    }

    /// GGX normal distribution for a unit `h` with h.z > 0, written as 1/(π α² t²) with
    /// t = (h.x² + h.y²)/α² + h.z² so that a small α suffers no cancellation.
    fn d(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha() * self.alpha();
        let t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
        1.0 / (PI * a2 * t * t)
    }

    /// Smith masking for the GGX distribution, 1/(1 + Λ(v)) = 2/(1 + √(1 + α² tan²θ)), for v.z > 0.
    fn g1(&self, v: Vec3) -> f32 {
        if v.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha() * self.alpha();
        let tan2 = (v.x * v.x + v.y * v.y) / (v.z * v.z);
        2.0 / (1.0 + (1.0 + a2 * tan2).sqrt())
    }

    /// pdf of the reflected direction for wo, wi in the upper hemisphere with half vector h.
    #[inline]
    fn pdf_up(&self, wo: Vec3, h: Vec3) -> f32 {
        self.g1(wo) * self.d(h) / (4.0 * wo.z)
    }

    /// A visible normal for `wo` (upper hemisphere), by Heitz 2018: stretch wo to the α = 1
    /// configuration, sample the projected hemisphere there, and unstretch the normal.
    fn sample_visible_normal(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let a = self.alpha();
        let v = Vec3::new(a * wo.x, a * wo.y, wo.z).normalize();
        let len2 = v.x * v.x + v.y * v.y;
        let t1 = if len2 > 0.0 {
            Vec3::new(-v.y, v.x, 0.0) / len2.sqrt()
        } else {
            Vec3::X
        };
        let t2 = v.cross(t1);
        // Uniform disk point, its second coordinate squeezed onto the visible half of the disk.
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let p1 = r * phi.cos();
        let s = 0.5 * (1.0 + v.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * (r * phi.sin());
        let n = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * v;
        Vec3::new(a * n.x, a * n.y, n.z.max(0.0)).normalize()
    }
}

impl LocalBsdf for Glossy {
    fn sample(&self, wo: Vec3, _u_lobe: f32, u: Vec2, _mode: TransportMode) -> Option<LocalSample> {
        if wo.z == 0.0 {
            return None;
        }
        let below = wo.z < 0.0;
        let wo_up = up(wo, below);
        let h = self.sample_visible_normal(wo_up, u);
        let wi_up = 2.0 * wo_up.dot(h) * h - wo_up;
        if wi_up.z <= 0.0 {
            return None; // reflected below the horizon: no contribution, counted as a failed sample
        }
        let pdf_w = self.pdf_up(wo_up, h);
        if !(pdf_w > 0.0) {
            return None;
        }
        let pdf_rev_w = self.pdf_up(wi_up, h);
        let weight = self.reflectance * self.g1(wi_up);
        Some(LocalSample {
            wi: up(wi_up, below),
            weight,
            pdf_w,
            pdf_rev_w,
            delta: false,
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> Color {
        if !(wo.z * wi.z > 0.0) {
            return Color::ZERO;
        }
        let below = wo.z < 0.0;
        let (o, i) = (up(wo, below), up(wi, below));
        let h = (o + i).normalize();
        // Products grouped symmetrically in o and i so that f(wo, wi) == f(wi, wo) exactly.
        let g = self.g1(o) * self.g1(i);
        self.reflectance * (self.d(h) * g / (4.0 * (o.z * i.z)))
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !(wo.z * wi.z > 0.0) {
            return 0.0;
        }
        let below = wo.z < 0.0;
        let (o, i) = (up(wo, below), up(wi, below));
        self.pdf_up(o, (o + i).normalize())
    }

    fn is_delta(&self) -> bool {
        false
    }
}

/// The sampling tests' glossy materials, near-specular to very rough (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Glossy {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::test_registry::*;
        vec![
            ("glossy-0.05", glossy(0.05)),
            ("glossy-0.2", glossy(0.2)),
            ("glossy-0.5", glossy(0.5)),
            ("glossy-1.0", glossy(1.0)),
        ]
    }
}

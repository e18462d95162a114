//! Smooth dielectric (glass): specular reflection with probability F (exact unpolarised Fresnel)
//! and specular refraction with probability 1 − F. Both lobes are deltas.
//!
//! Radiance mode divides refracted throughput by η² (η = η_wi-side / η_wo-side), because radiance
//! is compressed into the narrower cone on entering the denser medium; importance is not
//! (pbrt-v4's convention, Veach 1997 §5.2).

use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3};

#[derive(Clone, Debug)]
pub struct Dielectric {
    /// Index of refraction inside relative to outside (the side the normal points to).
    pub ior: f32,
}

/// Unpolarised Fresnel reflectance for light meeting the interface at `cos_i` (> 0) with relative
/// IOR `eta` = η_t / η_i. Returns (F, cos θt); F = 1 and cos θt = 0 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32) {
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    // Amplitude coefficients with both numerator and denominator divided by η_i.
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (r_perp * r_perp + r_par * r_par), cos_t)
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
        let scale = match mode {
            TransportMode::Radiance => 1.0 / (eta * eta),
            TransportMode::Importance => 1.0,
        };
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

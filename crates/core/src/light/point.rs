//! An isotropic point light: delta in position, uniform in direction.

use super::{LightLeSample, LightLiSample};
use crate::geometry::Ray;
use crate::math::{Color, Vec2, Vec3};
use crate::sampling::{sample_uniform_sphere, UNIFORM_SPHERE_PDF};
use crate::texture::TexPoint;

#[derive(Clone, Debug)]
pub struct PointLight {
    pub position: Vec3,
    pub intensity: Color,
}

impl PointLight {
    pub fn sample_li(&self, p: Vec3) -> Option<LightLiSample> {
        sample_li_at(self.position, p, |_| self.intensity)
    }

    pub fn sample_le(&self, u_dir: Vec2) -> LightLeSample {
        let d = sample_uniform_sphere(u_dir);
        LightLeSample {
            uv: TexPoint::default(),
            ray: Ray::new(self.position, d),
            p: self.position,
            p_err: Vec3::ZERO,
            n: d,
            radiance: self.intensity,
            pdf_pos: 1.0,
            pdf_dir: UNIFORM_SPHERE_PDF,
        }
    }
}

/// Next-event estimation from `p` towards a light at the point `position` (a delta in position:
/// point, spot, projector): radiance I(ω)/d² with `intensity(ω)` the intensity it sends along ω
/// (from the light towards `p`), chosen with the discrete density 1. `None` at the light itself.
pub(super) fn sample_li_at(
    position: Vec3,
    p: Vec3,
    intensity: impl FnOnce(Vec3) -> Color,
) -> Option<LightLiSample> {
    let to = position - p;
    let d2 = to.length_squared();
    if !(d2 > 0.0) {
        return None;
    }
    let distance = d2.sqrt();
    let wi = to / distance;
    Some(LightLiSample {
        uv: TexPoint::default(),
        p_err: Vec3::ZERO,
        wi,
        p: position,
        n: -wi,
        distance,
        radiance: intensity(-wi) / d2,
        pdf_w: 1.0,
        delta: true,
    })
}

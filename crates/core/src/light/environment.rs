//! Constant radiance from every direction at infinity.

use super::{LightLeSample, LightLiSample};
use crate::geometry::Ray;
use crate::math::{luminance, Color, Frame, Vec2, Vec3, PI};
use crate::sampling::{sample_concentric_disk, sample_uniform_sphere, UNIFORM_SPHERE_PDF};
use crate::texture::TexPoint;

#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    pub radiance: Color,
}

impl EnvironmentLight {
    pub fn sample_li(&self, u: Vec2) -> Option<LightLiSample> {
        let wi = sample_uniform_sphere(u);
        Some(LightLiSample {
            uv: TexPoint::default(),
            p_err: Vec3::ZERO,
            wi,
            p: wi,
            n: -wi,
            distance: f32::INFINITY,
            radiance: self.radiance,
            pdf_w: UNIFORM_SPHERE_PDF,
            delta: false,
        })
    }

    pub fn sample_le(&self, u_pos: Vec2, u_dir: Vec2, bounds: (Vec3, f32)) -> LightLeSample {
        distant_le(
            -sample_uniform_sphere(u_dir),
            u_pos,
            bounds,
            self.radiance,
            UNIFORM_SPHERE_PDF,
        )
    }
}

pub fn pdf_li() -> f32 {
    UNIFORM_SPHERE_PDF
}

pub fn pdf_le(bounds: (Vec3, f32)) -> (f32, f32) {
    (disk_pdf(bounds), UNIFORM_SPHERE_PDF)
}

pub fn power(l: &EnvironmentLight, bounds: (Vec3, f32)) -> f32 {
    4.0 * PI * PI * bounds.1 * bounds.1 * luminance(l.radiance)
}

/// Area pdf on the disk, perpendicular to the light's direction, that covers the scene's bounding
/// sphere: where rays from a light at infinity start.
pub fn disk_pdf(bounds: (Vec3, f32)) -> f32 {
    1.0 / (PI * bounds.1 * bounds.1)
}

/// The emitted ray of a light at infinity travelling in direction `d`: its origin is uniform on
/// the bounding disk upstream of the scene; `pdf_dir` is the light's own directional pdf.
pub fn distant_le(
    d: Vec3,
    u_pos: Vec2,
    bounds: (Vec3, f32),
    radiance: Color,
    pdf_dir: f32,
) -> LightLeSample {
    let ray = ray_from_bounding_disk(d, u_pos, bounds);
    LightLeSample {
        uv: TexPoint::default(),
        ray,
        p: ray.o,
        p_err: Vec3::ZERO,
        n: d,
        radiance,
        pdf_pos: disk_pdf(bounds),
        pdf_dir,
    }
}

/// A ray travelling in direction `d` that starts on the bounding disk upstream of the scene.
pub fn ray_from_bounding_disk(d: Vec3, u_pos: Vec2, bounds: (Vec3, f32)) -> Ray {
    let (c, r) = bounds;
    let f = Frame::from_z(d);
    let q = sample_concentric_disk(u_pos) * r;
    let o = c - d * r + f.x * q.x + f.y * q.y;
    Ray::new(o, d)
}

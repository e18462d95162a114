//! A projector (Mitsuba 3's `projector`): a point light that projects an irradiance image through
//! a pinhole — delta in position, with a density in direction, like `point`.
//!
//! Mitsuba 3.9's emission, checked against its Python package (`sample_direction` for textured
//! and constant irradiance at several fields of view and scales): the image lies on the local
//! plane z = 1 (`to_world` maps +z to the optical axis), spanning |x| ≤ tan(fov_x / 2) and
//! |y| ≤ tan(fov_y / 2), with uv = ½ − ½ (x / tan_x, y / tan_y) at the point (x, y, 1) (both axes
//! flipped, as a camera's film is); a direction through that point at angle θ from the axis
//! carries intensity I = π · scale · E(uv) / cos³ θ, so that a plane at distance 1 facing the
//! projector receives the irradiance π · scale · E (cos θ / r² with r = 1 / cos θ); nothing
//! outside the frustum.
//!
//! Sampling (our own): `sample_le` picks the point on the image plane uniformly, area density
//! 1 / (4 tan_x tan_y), so pdf_ω = 1 / (4 tan_x tan_y cos³ θ) (dA/dω = r² / cos θ = 1 / cos³ θ);
//! `sample_li` is the position's Dirac (discrete density 1).

use super::point::sample_li_at;
use super::{LightLeSample, LightLiSample};
use crate::geometry::Ray;
use crate::math::{luminance, Color, Vec2, Vec3, PI};
use crate::texture::TexPoint;
use crate::texture::Texture;
use glam::Mat3;

#[derive(Clone, Debug)]
pub struct ProjectorLight {
    pub position: Vec3,
    /// Rotation from the local frame (optical axis +z) to the world, and back.
    pub to_world: Mat3,
    to_local: Mat3,
    pub irradiance: Texture,
    pub scale: f32,
    /// Half extents of the image on the plane z = 1: tan(fov_x / 2), tan(fov_y / 2).
    pub tan_half: Vec2,
}

impl ProjectorLight {
    /// `to_world` must be a rotation and both half extents positive and finite (the loaders
    /// check).
    pub fn new(
        position: Vec3,
        to_world: Mat3,
        irradiance: Texture,
        scale: f32,
        tan_half: Vec2,
    ) -> ProjectorLight {
        ProjectorLight {
            position,
            to_world,
            to_local: to_world.transpose(),
            irradiance,
            scale,
            tan_half,
        }
    }

    /// The point of the image plane a local direction passes through (x/z, y/z), if in front.
    #[inline]
    fn plane_point(d: Vec3) -> Option<Vec2> {
        (d.z > 0.0).then(|| Vec2::new(d.x / d.z, d.y / d.z))
    }

    /// Intensity (W/sr) emitted in world direction `w` (leaving the light; need not be unit).
    pub fn intensity_towards(&self, w: Vec3) -> Color {
        let d = (self.to_local * w).normalize();
        let Some(q) = Self::plane_point(d) else {
            return Color::ZERO;
        };
        if !(q.x.abs() <= self.tan_half.x && q.y.abs() <= self.tan_half.y) {
            return Color::ZERO;
        }
        let uv = Vec2::splat(0.5) - 0.5 * q / self.tan_half;
        let cos3 = d.z * d.z * d.z;
        self.irradiance.eval(crate::texture::TexPoint::at(uv)) * (PI * self.scale / cos3)
    }

    pub fn sample_li(&self, p: Vec3) -> Option<LightLiSample> {
        sample_li_at(self.position, p, |w| self.intensity_towards(w))
    }

    pub fn sample_le(&self, u_dir: Vec2) -> LightLeSample {
        let q = (2.0 * u_dir - Vec2::ONE) * self.tan_half;
        let d = (self.to_world * Vec3::new(q.x, q.y, 1.0)).normalize();
        LightLeSample {
            uv: TexPoint::default(),
            ray: Ray::new(self.position, d),
            p: self.position,
            p_err: Vec3::ZERO,
            n: d,
            radiance: self.intensity_towards(d),
            pdf_pos: 1.0,
            pdf_dir: self.pdf_dir(d),
        }
    }

    /// Solid-angle density of `sample_le`'s direction `w`: 1 / (4 tan_x tan_y cos³ θ) in the
    /// frustum, zero outside.
    pub fn pdf_dir(&self, w: Vec3) -> f32 {
        let d = (self.to_local * w).normalize();
        match Self::plane_point(d) {
            Some(q) if q.x.abs() <= self.tan_half.x && q.y.abs() <= self.tan_half.y => {
                1.0 / (4.0 * self.tan_half.x * self.tan_half.y * d.z * d.z * d.z)
            }
            _ => 0.0,
        }
    }

    /// Emitted power (luminance, for light selection): ∫ I dω = π · scale · ∫ E dA over the
    /// image plane = π · scale · mean(E) · 4 tan_x tan_y.
    pub fn power(&self) -> f32 {
        let mean = match &self.irradiance {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => b.mean(),
            t => Color::splat(t.max_value()),
        };
        PI * self.scale * luminance(mean) * 4.0 * self.tan_half.x * self.tan_half.y
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::{Bitmap, FilterType, UvTransform, WrapMode};
    use std::sync::Arc;

    /// Mitsuba 3.9.1's `projector` (fov 60° along x, scale 2, identity to_world) with an 8 × 4
    /// nearest-filtered image whose texel (x, y) is (x + 1, y + 1, 1): intensity · d² from
    /// `sample_direction`, printed by its Python package, for directions through the image plane
    /// at (a tan 30°, b tan 30°, 1).
    #[test]
    fn intensity_is_mitsubas() {
        let (w, h) = (8, 4);
        let texels = (0..w * h)
            .map(|k| Color::new((k % w + 1) as f32, (k / w + 1) as f32, 1.0))
            .collect();
        let bitmap = Bitmap {
            width: w,
            height: h,
            texels,
            filter: FilterType::Nearest,
            wrap: WrapMode::Repeat,
            to_uv: UvTransform::IDENTITY,
        };
        let t = 30f32.to_radians().tan();
        let l = ProjectorLight::new(
            Vec3::ZERO,
            Mat3::IDENTITY,
            Texture::Bitmap(Arc::new(bitmap)),
            2.0,
            Vec2::new(t, t * h as f32 / w as f32),
        );
        for (a, b, mitsuba) in [
            (0.0f32, 0.0f32, Color::new(31.415928, 18.849556, 6.2831855)),
            (0.9, 0.0, Color::new(8.992603, 26.97781, 8.992603)),
            (-0.9, 0.0, Color::new(71.94083, 26.97781, 8.992603)),
            (0.0, 0.4, Color::new(33.962418, 6.792484, 6.792484)),
            (0.0, -0.4, Color::new(33.962418, 27.169935, 6.792484)),
            (0.0, 0.6, Color::ZERO),
            (0.45, 0.3, Color::new(21.672445, 7.2241483, 7.2241483)),
            (0.6, -0.35, Color::new(15.71682, 31.43364, 7.85841)),
            (-0.3, -0.2, Color::new(40.17591, 20.087955, 6.695985)),
            (1.1, 0.0, Color::ZERO),
        ] {
            let i = l.intensity_towards(Vec3::new(a * t, b * t, 1.0));
            assert!(
                (i - mitsuba).abs().max_element() <= 1e-5 * mitsuba.max_element().max(1.0),
                "({a}, {b}): {i} vs Mitsuba {mitsuba}"
            );
        }
    }
}

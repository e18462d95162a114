//! A spot light (Mitsuba 3's `spot`): a point light whose intensity is confined to a cone — delta
//! in position, with a density in direction, like `point`.
//!
//! Mitsuba 3.9's emission, checked against its Python package (`sample_direction` at angles across
//! the transition): in the light's local frame (`to_world` maps +z to the beam's axis), at angle
//! θ from the axis, I(θ) = intensity · texture(uv) · falloff(θ) with
//! falloff = 1 for θ ≤ `beam_width`, (cutoff − θ) / (cutoff − beam_width) between (linear in the
//! angle, not its cosine), and 0 from `cutoff_angle` on; the optional texture is looked up at
//! uv = ½ + ½ (x/z, y/z) / tan(cutoff) of the local direction (x, y, z), so the image spans the
//! square the cone's rim is inscribed in, its u along local +x and v along local +y.
//!
//! Sampling (our own; only variance depends on it): `sample_le` draws directions uniformly in the
//! cutoff cone, pdf_ω = 1 / (2π (1 − cos cutoff)), zero outside; `sample_li` is the position's
//! Dirac (discrete density 1), as for a point light.

use super::point::sample_li_at;
use super::{LightLeSample, LightLiSample};
use crate::geometry::Ray;
use crate::math::{luminance, Color, Vec2, Vec3, PI};
use crate::sampling::{sample_uniform_cone, uniform_cone_pdf};
use crate::texture::TexPoint;
use crate::texture::Texture;
use glam::Mat3;

#[derive(Clone, Debug)]
pub struct SpotLight {
    pub position: Vec3,
    /// Rotation from the light's local frame (beam along +z) to the world, and back.
    pub to_world: Mat3,
    to_local: Mat3,
    pub intensity: Color,
    pub texture: Option<Texture>,
    /// Angles from the axis, radians: full intensity up to `beam_width`, none from `cutoff`.
    pub cutoff: f32,
    pub beam_width: f32,
    cos_cutoff: f32,
    cos_beam: f32,
    /// 1 − cos cutoff, for the cone sampler (full precision for narrow cones).
    one_minus_cos_cutoff: f32,
    /// tan(cutoff): the texture's half extent on the plane z = 1.
    tan_cutoff: f32,
}

impl SpotLight {
    /// `to_world` must be a rotation (the loaders refuse anything else); angles in radians with
    /// 0 < cutoff < π/2 (the texture's plane needs the cone in front) and 0 ≤ beam ≤ cutoff.
    pub fn new(
        position: Vec3,
        to_world: Mat3,
        intensity: Color,
        texture: Option<Texture>,
        cutoff: f32,
        beam_width: f32,
    ) -> SpotLight {
        let (sin_half, _) = (0.5 * cutoff).sin_cos();
        SpotLight {
            position,
            to_world,
            to_local: to_world.transpose(),
            intensity,
            texture,
            cutoff,
            beam_width,
            cos_cutoff: cutoff.cos(),
            cos_beam: beam_width.cos(),
            // 1 − cos c = 2 sin²(c/2), without cancellation.
            one_minus_cos_cutoff: 2.0 * sin_half * sin_half,
            tan_cutoff: cutoff.tan(),
        }
    }

    /// Intensity (W/sr) emitted in world direction `w` (leaving the light; need not be unit).
    pub fn intensity_towards(&self, w: Vec3) -> Color {
        let d = (self.to_local * w).normalize();
        let cos_theta = d.z;
        if !(cos_theta > self.cos_cutoff) {
            return Color::ZERO;
        }
        let falloff = if cos_theta >= self.cos_beam {
            1.0
        } else {
            (self.cutoff - cos_theta.clamp(-1.0, 1.0).acos()) / (self.cutoff - self.beam_width)
        };
        let tex = match &self.texture {
            None => Color::ONE,
            Some(t) => {
                let s = 0.5 / (self.tan_cutoff * cos_theta);
                t.eval(crate::texture::TexPoint::at(Vec2::new(
                    0.5 + d.x * s,
                    0.5 + d.y * s,
                )))
            }
        };
        self.intensity * tex * falloff.max(0.0)
    }

    pub fn sample_li(&self, p: Vec3) -> Option<LightLiSample> {
        sample_li_at(self.position, p, |w| self.intensity_towards(w))
    }

    pub fn sample_le(&self, u_dir: Vec2) -> LightLeSample {
        let d = self.to_world * sample_uniform_cone(u_dir, self.one_minus_cos_cutoff);
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

    /// Solid-angle density of `sample_le`'s direction `w`: uniform in the cutoff cone.
    pub fn pdf_dir(&self, w: Vec3) -> f32 {
        let cos_theta = (self.to_local * w).normalize().z;
        if cos_theta >= self.cos_cutoff {
            uniform_cone_pdf(self.one_minus_cos_cutoff)
        } else {
            0.0
        }
    }

    /// Emitted power (luminance, for light selection): luminance(intensity · mean texture) times
    /// ∫ falloff dω = 2π [1 − (sin c − sin b) / (c − b)] (the linear ramp in θ integrated
    /// against sin θ dθ; 2π (1 − cos c) when b = c).
    pub fn power(&self) -> f32 {
        let (c, b) = (self.cutoff as f64, self.beam_width as f64);
        let solid = if c - b > 1e-6 {
            2.0 * std::f64::consts::PI * (1.0 - (c.sin() - b.sin()) / (c - b))
        } else {
            2.0 * PI as f64 * self.one_minus_cos_cutoff as f64
        };
        let tex = match &self.texture {
            None => Color::ONE,
            Some(Texture::Bitmap(b)) => b.mean(),
            Some(t) => Color::splat(t.max_value()),
        };
        luminance(self.intensity * tex) * solid as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba 3.9.1's `spot` (cutoff 20°, beam 15°, identity to_world) at angles across the
    /// transition, intensity · d² from `sample_direction` at distance 2 (printed by its Python
    /// package): 1 inside the beam, the linear ramp in θ, 0 from the cutoff on.
    #[test]
    fn falloff_is_mitsubas() {
        let l = SpotLight::new(
            Vec3::ZERO,
            Mat3::IDENTITY,
            Color::ONE,
            None,
            20f32.to_radians(),
            15f32.to_radians(),
        );
        for (deg, mitsuba) in [
            (0.0f32, 1.0f32),
            (14.9, 1.0),
            (15.1, 0.98),
            (16.0, 0.8),
            (17.5, 0.5),
            (19.0, 0.2),
            (19.9, 0.02),
            (20.1, 0.0),
            (25.0, 0.0),
        ] {
            let t = deg.to_radians();
            let i = l.intensity_towards(Vec3::new(t.sin(), 0.0, t.cos())).x;
            assert!(
                (i - mitsuba).abs() < 2e-5,
                "{deg}°: {i} vs Mitsuba {mitsuba}"
            );
        }
    }

    #[test]
    fn power_is_the_integral_of_the_falloff() {
        let l = SpotLight::new(
            Vec3::ZERO,
            Mat3::from_rotation_x(0.3),
            Color::ONE,
            None,
            0.6,
            0.2,
        );
        // Midpoint rule in θ over the cone.
        let n = 20_000;
        let mut sum = 0.0f64;
        for k in 0..n {
            let t = (k as f64 + 0.5) / n as f64 * 0.6;
            let f = if t <= 0.2 { 1.0 } else { (0.6 - t) / 0.4 };
            sum += f * t.sin() * 0.6 / n as f64;
        }
        let exact = 2.0 * std::f64::consts::PI * sum;
        assert!(
            (l.power() as f64 - exact).abs() < 1e-5 * exact,
            "{} vs {exact}",
            l.power()
        );
    }
}

//! Mitsuba 3's `mask`: a material that is only partly there. Where the opacity α (a texture,
//! Mitsuba's default 0.5) is below one, light passes straight through the surface with
//! probability 1 − α, untouched; otherwise it meets the nested material.
//!
//! f_mask = α · f_inner + (1 − α) · δ(ω_i + ω_o) / |cos θ_i|,
//!
//! so the pass-through is a delta lobe (Mitsuba's `Null` flag, which its integrators count as a
//! delta bounce): a shadow ray or a connection is blocked by a masked surface, and light behind
//! it is reached only by the pass-through sample — unbiased, as glass is. The pass-through is
//! symmetric (no η, no shading-normal correction: ω_i = −ω_o makes the adjoint factor one), so it
//! is the same in both transport modes.
//!
//! Lobe selection follows the convention of `Material::delta_lobe_probability`: `u_lobe` below
//! the delta probability picks a delta lobe — the pass-through first (1 − α), then the nested
//! material's own delta lobe (α · P_inner) — so a caller that splits delta from smooth lobes
//! (photon mapping's camera paths) sees every delta part.

use super::{BsdfEval, BsdfSample, Material, ShadingFrame, TransportMode};
use crate::math::{Vec2, Vec3};
use crate::texture::TexPoint;
use crate::texture::Texture;

#[derive(Clone, Debug)]
pub struct Mask {
    /// Opacity α: 1 opaque, 0 absent. A coloured texture counts by its luminance (Mitsuba reads
    /// it with `eval_1`); values outside [0, 1] are clamped, as Mitsuba clips them.
    pub opacity: Texture,
    pub inner: Material,
}

impl Mask {
    /// α at texture coordinates `uv`.
    #[inline]
    pub fn opacity_at(&self, uv: TexPoint) -> f32 {
        self.opacity.fraction(uv)
    }

    pub fn sample(
        &self,
        sf: &ShadingFrame,
        wo: Vec3,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        let alpha = self.opacity_at(sf.uv);
        let pass = 1.0 - alpha;
        if u_lobe < pass {
            // Value (1 − α)·δ, chosen with probability 1 − α: weight one.
            return Some(BsdfSample {
                wi: -wo,
                weight: crate::math::Color::ONE,
                pdf_w: pass,
                pdf_rev_w: pass,
                delta: true,
            });
        }
        // The rest of [0, 1) rescaled for the nested material (its own lobe choice).
        let u_inner = ((u_lobe - pass) / alpha).min(1.0 - f32::EPSILON / 2.0);
        let mut s = self.inner.sample(sf, wo, u_inner, u, mode)?;
        // f and pdf are both scaled by α: the weight f·cos/pdf is the nested one.
        s.pdf_w *= alpha;
        s.pdf_rev_w *= alpha;
        Some(s)
    }

    pub fn eval(&self, sf: &ShadingFrame, wo: Vec3, wi: Vec3, mode: TransportMode) -> BsdfEval {
        let alpha = self.opacity_at(sf.uv);
        if alpha == 0.0 {
            return BsdfEval::default();
        }
        let e = self.inner.eval(sf, wo, wi, mode);
        BsdfEval {
            f_cos: e.f_cos * alpha,
            pdf_w: e.pdf_w * alpha,
            pdf_rev_w: e.pdf_rev_w * alpha,
        }
    }

    pub fn pdf(&self, sf: &ShadingFrame, wo: Vec3, wi: Vec3) -> f32 {
        self.opacity_at(sf.uv) * self.inner.pdf(sf, wo, wi)
    }

    /// Probability that `sample` picks a delta lobe: the pass-through or the nested material's.
    pub fn delta_lobe_probability(&self, sf: &ShadingFrame, wo: Vec3) -> f32 {
        let alpha = self.opacity_at(sf.uv);
        (1.0 - alpha) + alpha * self.inner.delta_lobe_probability(sf, wo)
    }
}

/// The sampling tests' masks (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Mask {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::test_registry::*;
        let mask = |opacity, inner| {
            Material::Mask(Box::new(Mask {
                opacity: constant(opacity),
                inner,
            }))
        };
        vec![
            (
                "mask-0.4-diffuse",
                mask(0.4, Material::Diffuse(super::Diffuse { albedo: COLOR })),
            ),
            (
                "mask-0.7-twosided-plastic",
                mask(
                    0.7,
                    Material::TwoSided(super::TwoSided {
                        inner: Box::new(plastic(COLOR, false)),
                    }),
                ),
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Diffuse;
    use crate::math::Color;

    fn half_mask() -> (Mask, ShadingFrame) {
        let m = Mask {
            opacity: Texture::Constant(Color::splat(0.25)),
            inner: Material::Diffuse(Diffuse {
                albedo: Color::splat(0.8),
            }),
        };
        (m, ShadingFrame::new(Vec3::Z, Vec3::Z))
    }

    #[test]
    fn pass_through_is_chosen_with_probability_one_minus_opacity() {
        let (m, sf) = half_mask();
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let s = m
            .sample(&sf, wo, 0.7, Vec2::splat(0.5), TransportMode::Radiance)
            .unwrap();
        assert!(s.delta && s.wi == -wo && s.pdf_w == 0.75 && s.weight == Color::ONE);
        let s = m
            .sample(&sf, wo, 0.8, Vec2::splat(0.5), TransportMode::Importance)
            .unwrap();
        assert!(!s.delta && s.wi.z > 0.0);
        assert_eq!(m.delta_lobe_probability(&sf, wo), 0.75);
    }

    #[test]
    fn smooth_part_is_the_nested_material_times_opacity() {
        let (m, sf) = half_mask();
        let (wo, wi) = (
            Vec3::new(0.3, 0.1, 0.9).normalize(),
            Vec3::new(-0.2, 0.4, 0.7).normalize(),
        );
        let inner = m.inner.eval(&sf, wo, wi, TransportMode::Radiance);
        let e = m.eval(&sf, wo, wi, TransportMode::Radiance);
        assert_eq!(e.f_cos, inner.f_cos * 0.25);
        assert_eq!(e.pdf_w, inner.pdf_w * 0.25);
    }
}

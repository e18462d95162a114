//! Mitsuba 3's `blendbsdf`: a linear blend of two materials by a weight w (a texture, default
//! 0.5), f = (1 − w) · f₀ + w · f₁ — "weight 1 means only the second".
//!
//! Sampling picks a component with probability (1 − w, w) and the density of a smooth direction
//! is the blend's, (1 − w)·p₀ + w·p₁ (one-sample MIS over the two components, Veach 1997 §9.2.4),
//! so the weight f·cos/p and the pdfs MIS reads are those of the blended material, not of the
//! component that happened to be chosen. A delta direction of one component is weighted by that
//! component alone, with its probability scaled by the selection probability.
//!
//! `u_lobe` is laid out so that, as `Material::delta_lobe_probability` requires, every delta lobe
//! comes first: [component 0's deltas | component 1's deltas | 0's smooth | 1's smooth], each
//! part mapped back onto the component's own `u_lobe` range where it picks the same lobe.

use super::{BsdfEval, BsdfSample, Material, ShadingFrame, TransportMode};
use crate::math::{Vec2, Vec3};
use crate::texture::{TexPoint, Texture};

#[derive(Clone, Debug)]
pub struct Blend {
    /// w: how much of `second` (Mitsuba's `weight`, read by luminance, clamped to [0, 1]).
    pub weight: Texture,
    pub first: Material,
    pub second: Material,
}

impl Blend {
    #[inline]
    fn weight_at(&self, at: TexPoint) -> f32 {
        self.weight.fraction(at)
    }

    pub fn sample(
        &self,
        sf: &ShadingFrame,
        wo: Vec3,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        let w = self.weight_at(sf.uv);
        let sel = [1.0 - w, w];
        let parts = [&self.first, &self.second];
        let delta_p = [
            parts[0].delta_lobe_probability(sf, wo),
            parts[1].delta_lobe_probability(sf, wo),
        ];
        let d = [sel[0] * delta_p[0], sel[1] * delta_p[1]];
        let below_one = |x: f32| x.min(1.0 - f32::EPSILON / 2.0);
        // Which component, and the u_lobe it sees (inside the lobe range it would pick itself).
        let (i, u_i) = if u_lobe < d[0] {
            (0, u_lobe / sel[0])
        } else if u_lobe < d[0] + d[1] {
            (1, (u_lobe - d[0]) / sel[1])
        } else {
            let v = u_lobe - d[0] - d[1];
            let smooth0 = sel[0] * (1.0 - delta_p[0]);
            if v < smooth0 {
                (0, delta_p[0] + v / sel[0])
            } else {
                (1, delta_p[1] + (v - smooth0) / sel[1])
            }
        };
        if sel[i] == 0.0 {
            return None;
        }
        let s = parts[i].sample(sf, wo, below_one(u_i), u, mode)?;
        if s.delta {
            // Value sel·v, probability sel·P: the component's own weight.
            return Some(BsdfSample {
                pdf_w: s.pdf_w * sel[i],
                pdf_rev_w: s.pdf_rev_w * sel[i],
                ..s
            });
        }
        let e = self.eval(sf, wo, s.wi, mode);
        (e.pdf_w > 0.0).then(|| BsdfSample {
            wi: s.wi,
            weight: e.f_cos / e.pdf_w,
            pdf_w: e.pdf_w,
            pdf_rev_w: e.pdf_rev_w,
            delta: false,
        })
    }

    pub fn eval(&self, sf: &ShadingFrame, wo: Vec3, wi: Vec3, mode: TransportMode) -> BsdfEval {
        let w = self.weight_at(sf.uv);
        let e0 = self.first.eval(sf, wo, wi, mode);
        let e1 = self.second.eval(sf, wo, wi, mode);
        BsdfEval {
            f_cos: e0.f_cos * (1.0 - w) + e1.f_cos * w,
            pdf_w: (1.0 - w) * e0.pdf_w + w * e1.pdf_w,
            pdf_rev_w: (1.0 - w) * e0.pdf_rev_w + w * e1.pdf_rev_w,
        }
    }

    pub fn pdf(&self, sf: &ShadingFrame, wo: Vec3, wi: Vec3) -> f32 {
        let w = self.weight_at(sf.uv);
        (1.0 - w) * self.first.pdf(sf, wo, wi) + w * self.second.pdf(sf, wo, wi)
    }

    pub fn delta_lobe_probability(&self, sf: &ShadingFrame, wo: Vec3) -> f32 {
        let w = self.weight_at(sf.uv);
        (1.0 - w) * self.first.delta_lobe_probability(sf, wo)
            + w * self.second.delta_lobe_probability(sf, wo)
    }
}

/// The sampling tests' blends (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Blend {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::microfacet::MicrofacetType::Ggx;
        use super::test_registry::*;
        let blend = |weight, first, second| {
            Material::Blend(Box::new(Blend {
                weight: constant(weight),
                first,
                second,
            }))
        };
        vec![
            (
                "blend-0.3-diffuse-roughconductor",
                blend(
                    0.3,
                    Material::Diffuse(super::Diffuse { albedo: COLOR }),
                    rough_gold(Ggx, 0.2, 0.2, true),
                ),
            ),
            (
                "blend-0.6-plastic-glossy",
                blend(0.6, plastic(COLOR, false), glossy(0.3)),
            ),
        ]
    }
}

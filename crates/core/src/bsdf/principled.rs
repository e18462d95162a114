//! Mitsuba 3's `principled` BSDF (Burley 2012 and 2015, as Mitsuba evaluates them): a sum of
//! lobes weighted by brdf = (1 − metallic)(1 − spec_trans) and bsdf = (1 − metallic) spec_trans.
//! On the front (wo.z > 0):
//! - diffuse, retro-reflection and fake subsurface: brdf · base_color/π · `diffuse_shape`;
//! - sheen: sheen (1 − metallic) · F_S(θd) · lerp(1, tint, sheen_tint) (no 1/π, as Mitsuba);
//! - main specular reflection, anisotropic GGX: F_p D G / (4 |cos θo cos θi|) with
//!   F_p = (1 − metallic)(1 − spec_tint) F_dielectric + metallic · Schlick(base_color)
//!   + (1 − metallic) spec_tint · Schlick(tint · R0(η));
//! - clearcoat: 0.25 clearcoat · Schlick(0.04) D_GTR1 G_0.25 — without the 1/(4 cos θo cos θi)
//!   of a microfacet BRDF: Mitsuba's (its masking is the true G1, where Burley's smithG_GGX
//!   already holds the 1/(2 cos θ) factors);
//! - rough transmission: √base_color · bsdf · Walter et al. 2007's BTDF (eq. 21) through the
//!   same GGX, with `refraction::refracted_throughput_scale` for radiance (as `roughdielectric`).
//!
//! On the back (wo.z < 0) only the dielectric remains, weighted by bsdf: reflection with
//! F_p = bsdf · F_dielectric and transmission; with bsdf = 0 the back is black.
//! η is `eta`, or from `specular`: η = 2/(1 − √(0.08 specular)) − 1.
//!
//! Sampling, as Mitsuba: on the front, diffuse (cosine), clearcoat (GTR1 normals) and the main
//! specular lobe in proportion brdf : clearcoat/4 : 1 (times the sampling rates); the specular
//! lobe draws a visible GGX normal and reflects with probability 1 − bsdf (1 − F), else refracts.
//! On the back: reflect with F, refract with 1 − F. The pdf sums every lobe's density.

use super::fresnel::{fresnel_dielectric, fresnel_dielectric_signed};
use super::microfacet::{reflect, Microfacet};
use super::principled_common::{
    clearcoat_g1, diffuse_shape, diffuse_value, lobe_mixture_sample, normalised, schlick_fresnel,
    schlick_r0, sheen_value, specular_distribution, tint, Gtr1, PrincipledParam,
};
use super::refraction::refracted_throughput_scale;
use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3, INV_PI};
use crate::sampling::sample_cosine_hemisphere;

#[derive(Clone, Debug)]
pub struct Principled {
    pub base_color: Color,
    pub roughness: f32,
    pub anisotropic: f32,
    pub metallic: f32,
    pub spec_trans: f32,
    /// η = η_inside / η_outside (the shading normal points outside).
    pub eta: f32,
    pub spec_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    /// `diffuse_reflectance_sampling_rate`, `clearcoat_sampling_rate`,
    /// `main_specular_sampling_rate` (Mitsuba's defaults 1, 1, 1).
    pub sampling_rates: [f32; 3],
    /// The transmission lobe exists (spec_trans textured or > 0): the material refracts.
    pub has_spec_trans: bool,
}

impl Principled {
    /// Mitsuba's defaults: base_color 0.5, roughness 0.5, specular 0.5 (η = 1.5), all else 0.
    pub fn mitsuba_default() -> Principled {
        Principled {
            base_color: Color::splat(0.5),
            roughness: 0.5,
            anisotropic: 0.0,
            metallic: 0.0,
            spec_trans: 0.0,
            eta: Principled::eta_from_specular(0.5),
            spec_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            clearcoat: 0.0,
            clearcoat_gloss: 0.0,
            sampling_rates: [1.0; 3],
            has_spec_trans: false,
        }
    }

    /// Mitsuba's one-to-one map from `specular` to η: 2/(1 − √(0.08 specular)) − 1 (the
    /// inverse of specular = R0/0.08).
    pub fn eta_from_specular(specular: f32) -> f32 {
        2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
    }

    /// Sets one (textured) parameter; false when the principled BSDF has no such parameter.
    pub fn set(&mut self, param: PrincipledParam, value: Color) -> bool {
        use PrincipledParam::*;
        let x = value.x;
        match param {
            BaseColor => self.base_color = value,
            Roughness => self.roughness = x,
            Anisotropic => self.anisotropic = x,
            Metallic => self.metallic = x,
            SpecTrans => self.spec_trans = x,
            SpecTint => self.spec_tint = x,
            Sheen => self.sheen = x,
            SheenTint => self.sheen_tint = x,
            Flatness => self.flatness = x,
            Clearcoat => self.clearcoat = x,
            ClearcoatGloss => self.clearcoat_gloss = x,
            DiffTrans | Eta => return false,
        }
        true
    }

    fn distribution(&self) -> Microfacet {
        specular_distribution(self.roughness, self.anisotropic)
    }

    /// (brdf, bsdf): the weights of the opaque and the transmitting dielectric parts.
    fn weights(&self) -> (f32, f32) {
        let dielectric = 1.0 - self.metallic;
        (
            dielectric * (1.0 - self.spec_trans),
            dielectric * self.spec_trans,
        )
    }

    /// Probabilities of (diffuse, clearcoat, main specular) sampled from `wo`'s side; None when
    /// nothing is sampled (the back of a material that does not transmit).
    fn lobe_probabilities(&self, front: bool, brdf: f32, bsdf: f32) -> Option<[f32; 3]> {
        let [rate_d, rate_cc, rate_s] = self.sampling_rates;
        if front {
            normalised([brdf * rate_d, 0.25 * self.clearcoat * rate_cc, rate_s])
        } else {
            (bsdf > 0.0).then_some([0.0, 0.0, 1.0])
        }
    }

    /// The IOR of the side `w` points into (outside 1, inside η).
    #[inline]
    fn ior_on_side_of(&self, w: Vec3) -> f32 {
        if w.z > 0.0 {
            1.0
        } else {
            self.eta
        }
    }

    /// The microfacet normal (upper hemisphere) joining wo and wi by reflection (m ∝ wo + wi) or
    /// refraction (m ∝ η_o wo + η_i wi), if both see it from their own side (Mitsuba's
    /// `mac_mic_compatibility`).
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<Vec3> {
        let v = if wo.z * wi.z > 0.0 {
            wo + wi
        } else {
            self.ior_on_side_of(wo) * wo + self.ior_on_side_of(wi) * wi
        };
        let m = v.try_normalize()?;
        let m = if m.z < 0.0 { -m } else { m };
        (m.z > 0.0 && wo.dot(m) * wo.z > 0.0 && wi.dot(m) * wi.z > 0.0).then_some(m)
    }

    /// F_dielectric at m for the pair, the same bits for (wo, wi) and (wi, wo): reflection reads
    /// the mean of the two (equal) cosines, refraction the direction on the optically thinner
    /// side (F(θ, η) = F(θt, 1/η); Mitsuba reads wo's side, the same number).
    fn fresnel(&self, wo: Vec3, wi: Vec3, m: Vec3) -> f32 {
        if wo.z * wi.z > 0.0 {
            return fresnel_dielectric_signed(0.5 * (wo.dot(m) + wi.dot(m)), self.eta);
        }
        let outside = if wo.z > 0.0 { wo } else { wi };
        let inside = if wo.z > 0.0 { wi } else { wo };
        if self.eta >= 1.0 {
            fresnel_dielectric(outside.dot(m).abs(), self.eta).0
        } else {
            fresnel_dielectric(inside.dot(m).abs(), 1.0 / self.eta).0
        }
    }

    /// Mitsuba's `principled_fresnel` at the microfacet cosine `cos_h` (seen from wo's side).
    fn specular_fresnel(&self, f_dielectric: f32, cos_h: f32, front: bool, bsdf: f32) -> Color {
        if !front {
            // No tint, no metal from inside: the bare dielectric.
            return Color::splat(bsdf * f_dielectric);
        }
        let eta_it = if cos_h >= 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let dielectric = 1.0 - self.metallic;
        let mut f = Color::splat(dielectric * (1.0 - self.spec_tint) * f_dielectric);
        if self.metallic != 0.0 {
            f += self.metallic * schlick_fresnel(self.base_color, cos_h, self.eta);
        }
        if self.spec_tint != 0.0 {
            let r0 = tint(self.base_color) * schlick_r0(eta_it);
            f += dielectric * self.spec_tint * schlick_fresnel(r0, cos_h, self.eta);
        }
        f
    }

    /// Visible-normal observer: wo, or −wo from inside (Mitsuba's `mulsign(wi, cos θi)`).
    #[inline]
    fn observer(wo: Vec3) -> Vec3 {
        if wo.z < 0.0 {
            -wo
        } else {
            wo
        }
    }
}

impl Default for Principled {
    fn default() -> Self {
        Principled::mitsuba_default()
    }
}

impl LocalBsdf for Principled {
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<LocalSample> {
        if wo.z == 0.0 {
            return None;
        }
        let front = wo.z > 0.0;
        let (brdf, bsdf) = self.weights();
        let [p_d, p_cc, p_s] = self.lobe_probabilities(front, brdf, bsdf)?;
        // A microfacet lobe's direction counts only if it leaves on the side the lobe scatters
        // to and both directions see m from their side (as Mitsuba's sampler rejects it); the
        // pdf leaves such directions out of that lobe, so a sample there would be one no lobe
        // accounts for.
        let wi = if u_lobe < p_d {
            sample_cosine_hemisphere(u)
        } else if u_lobe < p_d + p_cc {
            let m = Gtr1::for_gloss(self.clearcoat_gloss).sample(u);
            let wi = reflect(wo, m);
            if !(wi.z > 0.0) || self.half_vector(wo, wi).is_none() {
                return None;
            }
            wi
        } else {
            let m = self.distribution().sample_normal(Self::observer(wo), u);
            let cos_om = wo.dot(m);
            if !(cos_om * wo.z > 0.0) {
                return None;
            }
            let eta = if front { self.eta } else { 1.0 / self.eta };
            let (f, cos_t) = fresnel_dielectric(cos_om.abs(), eta);
            let p_reflect = if front { 1.0 - bsdf * (1.0 - f) } else { f };
            // u_lobe rescaled to [0, 1) within the specular lobe chooses reflection or refraction.
            let u_spec = (u_lobe - (p_d + p_cc)) / p_s;
            let (wi, reflects) = if u_spec < p_reflect {
                (reflect(wo, m), true)
            } else {
                // Snell through m, on wo's side of it.
                let m_o = if cos_om > 0.0 { m } else { -m };
                (-wo / eta + (cos_om.abs() / eta - cos_t) * m_o, false)
            };
            if (wi.z * wo.z > 0.0) != reflects || self.half_vector(wo, wi).is_none() {
                return None;
            }
            wi
        };
        lobe_mixture_sample(self, wo, wi, mode)
    }

    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Color {
        if wo.z == 0.0 || wi.z == 0.0 {
            return Color::ZERO;
        }
        let front = wo.z > 0.0;
        let (brdf, bsdf) = self.weights();
        let dist = self.distribution();
        let cos_oi = (wo.z * wi.z).abs();
        if wo.z * wi.z < 0.0 {
            if !(bsdf > 0.0) {
                return Color::ZERO;
            }
            let Some(m) = self.half_vector(wo, wi) else {
                return Color::ZERO;
            };
            let f = self.fresnel(wo, wi, m);
            if !(f < 1.0) {
                return Color::ZERO;
            }
            // As `roughdielectric`, grouped symmetrically in wo and wi.
            let (eta_o, eta_i) = (self.ior_on_side_of(wo), self.ior_on_side_of(wi));
            let denom = eta_o * wo.dot(m) + eta_i * wi.dot(m);
            let dg = dist.d(m) * (dist.g1(wo, m) * dist.g1(wi, m));
            let symmetric =
                (1.0 - f) * dg * (wo.dot(m) * wi.dot(m)).abs() / (cos_oi * (denom * denom));
            let importance = symmetric * (eta_i * eta_i);
            let scale = refracted_throughput_scale(eta_i / eta_o, mode);
            return self.base_color.map(f32::sqrt) * (bsdf * importance * scale);
        }
        // Reflection: wo + wi never vanishes on one side, and m sees both from their side.
        let Some(m) = (wo + wi).try_normalize() else {
            return Color::ZERO;
        };
        let m = if m.z < 0.0 { -m } else { m };
        // The microfacet cosine from wo's side (negative from inside), the same for (wi, wo).
        let cos_h = 0.5 * (wo.dot(m) + wi.dot(m));
        let mut value = Color::ZERO;
        let f_dielectric = fresnel_dielectric_signed(cos_h, self.eta);
        if f_dielectric > 0.0 {
            let f = self.specular_fresnel(f_dielectric, cos_h, front, bsdf);
            let dg = dist.d(m) * (dist.g1(wo, m) * dist.g1(wi, m));
            value += f * (dg / (4.0 * cos_oi));
        }
        if !front {
            return value;
        }
        if self.clearcoat > 0.0 {
            let f = schlick_fresnel(Color::splat(0.04), cos_h, self.eta).x;
            let d = Gtr1::for_gloss(self.clearcoat_gloss).d(m);
            let g = clearcoat_g1(wo, m) * clearcoat_g1(wi, m);
            value += Color::splat(0.25 * self.clearcoat * f * d * g);
        }
        if brdf > 0.0 {
            let shape = diffuse_shape(wo.z, wi.z, cos_h, self.roughness, self.flatness);
            value += brdf * diffuse_value(self.base_color, shape);
        }
        // Mitsuba masks sheen by its own weight, not by brdf (its scalar variant skips it where
        // brdf = 0, i.e. at spec_trans = 1 exactly).
        let dielectric = 1.0 - self.metallic;
        if self.sheen > 0.0 && dielectric > 0.0 {
            value +=
                (self.sheen * dielectric) * sheen_value(self.base_color, self.sheen_tint, cos_h);
        }
        value
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z == 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let front = wo.z > 0.0;
        let (brdf, bsdf) = self.weights();
        let Some([p_d, p_cc, p_s]) = self.lobe_probabilities(front, brdf, bsdf) else {
            return 0.0;
        };
        let reflects = wo.z * wi.z > 0.0;
        let mut pdf = 0.0;
        if reflects && front {
            pdf += p_d * wi.z * INV_PI;
        }
        let Some(m) = self.half_vector(wo, wi) else {
            return pdf;
        };
        let f = self.fresnel(wo, wi, m);
        let pdf_m = self.distribution().pdf_normal(Self::observer(wo), m);
        if reflects {
            let p_reflect = if front { 1.0 - bsdf * (1.0 - f) } else { f };
            let jacobian = 1.0 / (4.0 * wi.dot(m).abs());
            pdf += p_s * p_reflect * pdf_m * jacobian;
            if front && p_cc > 0.0 {
                pdf += p_cc * Gtr1::for_gloss(self.clearcoat_gloss).pdf(m) * jacobian;
            }
        } else {
            let p_refract = if front { bsdf * (1.0 - f) } else { 1.0 - f };
            let (eta_o, eta_i) = (self.ior_on_side_of(wo), self.ior_on_side_of(wi));
            let denom = eta_o * wo.dot(m) + eta_i * wi.dot(m);
            // |dω_m/dω_i| = η_i² |wi·m| / (η_o wo·m + η_i wi·m)² (Walter et al. 2007, eq. 17).
            let jacobian = eta_i * eta_i * wi.dot(m).abs() / (denom * denom);
            pdf += p_s * p_refract * pdf_m * jacobian;
        }
        pdf
    }

    fn is_delta(&self) -> bool {
        false
    }
}

/// The sampling tests' principled materials (base colours ≤ 0.5) (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Principled {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::Material;
        let principled = |set: fn(&mut Principled)| {
            let mut p = Principled {
                base_color: Color::new(0.5, 0.35, 0.2),
                ..Principled::mitsuba_default()
            };
            set(&mut p);
            Material::Principled(p)
        };
        // Base colours stay ≤ 0.5: Mitsuba's principled adds its specular, sheen and clearcoat
        // lobes on top of a diffuse whose retro-reflection alone can exceed 1 (Burley 2012,
        // §5.3), so a bright one would break the furnace test by design, not by a bug.
        vec![
            ("principled-diffuse", principled(|_| {})),
            (
                "principled-metallic-anisotropic",
                principled(|p| {
                    p.metallic = 0.7;
                    p.anisotropic = 0.6;
                    p.roughness = 0.3;
                    p.spec_tint = 0.5;
                }),
            ),
            (
                "principled-clearcoat-sheen-flatness",
                principled(|p| {
                    p.clearcoat = 0.8;
                    p.clearcoat_gloss = 0.5;
                    p.sheen = 0.6;
                    p.sheen_tint = 0.5;
                    p.flatness = 0.4;
                    p.roughness = 0.6;
                }),
            ),
            (
                "principled-spec-trans-0.6",
                principled(|p| {
                    p.spec_trans = 0.6;
                    p.has_spec_trans = true;
                    p.roughness = 0.3;
                    p.clearcoat = 0.3;
                    p.sheen = 0.3;
                    p.eta = Principled::eta_from_specular(0.4);
                }),
            ),
            (
                "principled-glass-anisotropic",
                principled(|p| {
                    p.spec_trans = 1.0;
                    p.has_spec_trans = true;
                    p.roughness = 0.4;
                    p.anisotropic = 0.5;
                    p.eta = 1.33;
                }),
            ),
        ]
    }
}

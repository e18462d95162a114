//! What Mitsuba 3's `principled` and `principledthin` share (its `principledhelpers.h`): Burley's
//! Schlick weight, diffuse with retro-reflection and the "flatness" fake subsurface (Burley 2012,
//! "Physically Based Shading at Disney", §5.3; Burley 2015, "Extending the Disney BRDF to a BSDF
//! with Integrated Subsurface Scattering", §3), sheen, the roughness → (α_u, α_v) map with its
//! anisotropy aspect (Burley 2012, addendum B.2), and the clearcoat's GTR1 distribution with its
//! fixed-roughness (0.25) Smith masking. Everything in the shading frame (z = normal).

use super::microfacet::{Microfacet, MicrofacetType};
use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{luminance, Color, Vec2, Vec3, INV_PI, PI};

/// Which parameter of a principled material a texture drives (all but `BaseColor` are scalars,
/// read as Mitsuba's `eval_1` reads them: `Texture::eval_scalar`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrincipledParam {
    BaseColor,
    Roughness,
    Anisotropic,
    Metallic,
    SpecTrans,
    SpecTint,
    Sheen,
    SheenTint,
    Flatness,
    Clearcoat,
    ClearcoatGloss,
    /// `principledthin` only (range 0–2).
    DiffTrans,
    /// `principledthin` only (its `eta` may be a texture).
    Eta,
}

/// Schlick's weight (1 − cos θ)⁵, with 1 − cos θ clamped to [0, 1].
#[inline]
pub fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's Fresnel R0 + (1 − R0)(1 − cos)⁵ at the microfacet cosine `cos_i` (signed: < 0 seen
/// from inside), with `eta` = η_inside/η_outside; from the denser side the transmitted angle's
/// cosine enters (Mitsuba's `calc_schlick`).
pub fn schlick_fresnel(r0: Color, cos_i: f32, eta: f32) -> Color {
    let eta_it = if cos_i >= 0.0 { eta } else { 1.0 / eta };
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        let eta_ti = 1.0 / eta_it;
        let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * (eta_ti * eta_ti);
        schlick_weight(cos_t2.max(0.0).sqrt())
    };
    r0 + (Color::ONE - r0) * w
}

/// Normal-incidence reflectance ((η − 1)/(η + 1))².
#[inline]
pub fn schlick_r0(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// The base colour divided by its luminance (1 for black): the hue the tints lean towards.
#[inline]
pub fn tint(base_color: Color) -> Color {
    let lum = luminance(base_color);
    if lum > 0.0 {
        base_color / lum
    } else {
        Color::ONE
    }
}

/// The main specular GGX distribution: α = roughness², stretched by the aspect
/// √(1 − 0.9 anisotropic) (α_u = α/aspect along x, α_v = α·aspect), each at least 0.001.
pub fn specular_distribution(roughness: f32, anisotropic: f32) -> Microfacet {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    Microfacet::new(
        MicrofacetType::Ggx,
        (r2 / aspect).max(0.001),
        (r2 * aspect).max(0.001),
        true,
    )
}

/// Burley's diffuse shape per unit albedo/π: (1 − F_i/2)(1 − F_o/2) plus retro-reflection
/// R_R (F_o + F_i + F_o F_i (R_R − 1)), R_R = 2 roughness cos²θ_d, blended towards the
/// Hanrahan–Krueger-like fake subsurface 1.25 (F_ss (1/(cos θ_o + cos θ_i) − 0.5) + 0.5) by
/// `flatness`. Symmetric in the two directions, operation for operation.
pub fn diffuse_shape(cos_a: f32, cos_b: f32, cos_d: f32, roughness: f32, flatness: f32) -> f32 {
    let (fa, fb) = (schlick_weight(cos_a), schlick_weight(cos_b));
    let f_diff = (1.0 - 0.5 * fa) * (1.0 - 0.5 * fb);
    let rr = 2.0 * roughness * (cos_d * cos_d);
    let f_retro = rr * ((fa + fb) + (fa * fb) * (rr - 1.0));
    if flatness == 0.0 {
        return f_diff + f_retro;
    }
    let fss90 = 0.5 * rr;
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let fss = lerp(1.0, fss90, fa) * lerp(1.0, fss90, fb);
    let f_ss = 1.25 * (fss * (1.0 / (cos_a + cos_b) - 0.5) + 0.5);
    lerp(f_diff + f_retro, f_ss, flatness)
}

/// The diffuse lobe's value: base colour/π times `diffuse_shape`.
#[inline]
pub fn diffuse_value(base_color: Color, shape: f32) -> Color {
    base_color * (INV_PI * shape)
}

/// Sheen per unit weight: Schlick's weight of θ_d, tinted towards the base colour's hue.
#[inline]
pub fn sheen_value(base_color: Color, sheen_tint: f32, cos_d: f32) -> Color {
    let c = Color::ONE + (tint(base_color) - Color::ONE) * sheen_tint;
    c * schlick_weight(cos_d.abs())
}

/// Burley's GTR1 ("generalised Trowbridge–Reitz", γ = 1), the clearcoat's distribution
/// (Burley 2012, addendum B.1, eq. 4): D(m) = (α² − 1) / (π ln α² (1 + (α² − 1) cos²θm)),
/// normalised in D·cos θm.
#[derive(Clone, Copy, Debug)]
pub struct Gtr1 {
    pub alpha: f32,
}

impl Gtr1 {
    /// α from `clearcoat_gloss`: 0.1 at gloss 0 down to 0.001 at gloss 1.
    pub fn for_gloss(gloss: f32) -> Gtr1 {
        Gtr1 {
            alpha: 0.1 * (1.0 - gloss) + 0.001 * gloss,
        }
    }

    pub fn d(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let cos2 = m.z * m.z;
        let r = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * cos2));
        if r * m.z > 1e-20 {
            r
        } else {
            0.0
        }
    }

    /// Solid-angle density of `sample` at m: D(m) cos θm.
    pub fn pdf(&self, m: Vec3) -> f32 {
        if m.z < 0.0 {
            0.0
        } else {
            m.z * self.d(m)
        }
    }

    /// m by inverting the CDF of cos²θm: cos²θ = (1 − α^(2(1 − u_y))) / (1 − α²).
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let sin = (1.0 - cos2).max(0.0).sqrt();
        let cos = cos2.max(0.0).sqrt();
        let phi = 2.0 * PI * u.x;
        Vec3::new(phi.cos() * sin, phi.sin() * sin, cos)
    }
}

/// Smith's GGX masking of the clearcoat, at the fixed roughness 0.25 (Mitsuba's `smith_ggx1`):
/// 2 / (1 + √(1 + α² tan²θ)), zero when v sees the back of m.
pub fn clearcoat_g1(v: Vec3, m: Vec3) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let cos2 = v.z * v.z;
    let tan2 = (1.0 - cos2) / cos2;
    2.0 / (1.0 + (1.0 + 0.0625 * tan2).sqrt())
}

/// Sampling rates normalised to probabilities; None when they are all zero.
pub fn normalised<const N: usize>(p: [f32; N]) -> Option<[f32; N]> {
    let total: f32 = p.iter().sum();
    (total > 0.0).then(|| p.map(|x| x / total))
}

/// The sample in direction `wi` (already chosen by one of `bsdf`'s lobes) of a lobe mixture:
/// its density is the whole mixture's `pdf_w` (solid angle, every lobe that could have chosen
/// `wi`), so the weight is f |cos θi| / pdf_w, never one lobe's ratio. None where `wi` is
/// grazing or no lobe could have chosen it.
pub fn lobe_mixture_sample(
    bsdf: &impl LocalBsdf,
    wo: Vec3,
    wi: Vec3,
    mode: TransportMode,
) -> Option<LocalSample> {
    if wi.z == 0.0 {
        return None;
    }
    let pdf_w = bsdf.pdf(wo, wi);
    if !(pdf_w > 0.0) {
        return None;
    }
    let f = bsdf.eval(wo, wi, mode);
    Some(LocalSample {
        wi,
        weight: f * (wi.z.abs() / pdf_w),
        pdf_w,
        pdf_rev_w: bsdf.pdf(wi, wo),
        delta: false,
    })
}

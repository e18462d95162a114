//! Rough plastic (Mitsuba 3's `roughplastic`): `plastic` with a rough coating. Two lobes, front
//! side only, neither a delta:
//! - specular: the coating's microfacet reflection (Walter et al. 2007, eq. 20),
//!   F(wo·h) D(h) G1(wo, h) G1(wi, h) / (4 cos θo cos θi) · `specular_reflectance`;
//! - diffuse: T(cos θo) T(cos θi) · R / (π η² (1 − F_int · (nonlinear ? R : 1))), with T(μ) the
//!   rough interface's transmittance from outside at incidence cos θ = μ and F_int its diffuse
//!   reflectance from inside: Mitsuba's substitutes for 1 − F and F_dr of the smooth plastic.
//!
//! T and F_int are computed when the material is built, the way Mitsuba 3.9 does it (to match its
//! values, not a new model): T is tabulated at 64 cosines μ_j = max(10⁻⁶, j/63) as the mean over
//! visible normals m of the refracted direction's G1 times 1 − F(wo·m), and F_int is
//! 2·mean_j(μ_j R(μ_j)) over the same 64 cosines (a plain mean, not a quadrature in μ) with R the
//! mean over visible normals of G1(reflected)·F(·, 1/η). Each mean is an n×n Gauss–Legendre rule
//! over the visible-normal sampler's unit square (n = 32 for relative IOR > 1, else 128); T is
//! interpolated linearly between the tabulated cosines. Visible normals are always sampled here,
//! whatever `sample_visible` says. GGX normals are drawn through Mitsuba's map from the unit
//! square (a concentric disk; the quadrature depends on the map: our polar map moves T by 10 % at
//! grazing incidence), Beckmann's by our exact sampler (Mitsuba's three Newton steps would move T
//! by 2e-7). What is not matched: Mitsuba's Beckmann G1 is a rational fit (see `microfacet`), in
//! the specular lobe and inside T's integrand, where it moves T by ~5e-5; against Mitsuba 3.9.1
//! the diffuse lobe agrees to 2e-5 (GGX) and 6e-5 (Beckmann), the Beckmann specular lobe to 0.6 %.
//!
//! f is symmetric in (wo, wi), the same in both transport modes (see `plastic`). Lobe choice:
//! the specular lobe with probability P = (1 − T(cos θo)) w / ((1 − T) w + T (1 − w)), w as in
//! `plastic`; its microfacet normal from `Microfacet::sample_normal`, else a cosine-weighted
//! direction. Mitsuba's `roughplastic` is isotropic only.

use super::fresnel::fresnel_dielectric;
use super::microfacet::{reflect, reflection_jacobian, Microfacet, MicrofacetType};
use super::plastic::{
    channel_mean, internal_scattering, specular_lobe_probability, specular_sampling_weight,
    AIR_IOR, POLYPROPYLENE_IOR,
};
use super::quadrature::gauss_legendre;
use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3, INV_PI};
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// Cosines at which Mitsuba tabulates the rough interface's transmittance.
pub const TRANSMITTANCE_RES: usize = 64;

/// What the diffuse lobe needs of the rough coating: T(μ_j) and F_int.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughInterface {
    pub transmittance: [f32; TRANSMITTANCE_RES],
    pub internal_reflectance: f32,
}

impl RoughInterface {
    /// T(μ) by linear interpolation in the table (μ ∈ [0, 1]).
    #[inline]
    pub fn transmittance_at(&self, mu: f32) -> f32 {
        let x = mu * (TRANSMITTANCE_RES - 1) as f32;
        let i = (x as usize).min(TRANSMITTANCE_RES - 2);
        let t = x - i as f32;
        let (a, b) = (self.transmittance[i], self.transmittance[i + 1]);
        a + (b - a) * t
    }

    /// The interface of microfacets `kind`, `alpha` and relative IOR `eta` (η_inside/η_outside),
    /// computed once per distinct triple and kept for the process (a table costs up to ~1M
    /// visible-normal samples). Materials hold a shared reference: the 260-byte table inline made
    /// `Material` six times larger than its next-largest variant.
    pub fn get(kind: MicrofacetType, alpha: f32, eta: f32) -> &'static RoughInterface {
        type Key = (bool, u32, u32);
        static CACHE: OnceLock<Mutex<HashMap<Key, &'static RoughInterface>>> = OnceLock::new();
        let key = (kind == MicrofacetType::Ggx, alpha.to_bits(), eta.to_bits());
        let cache = CACHE.get_or_init(Default::default);
        if let Some(t) = cache.lock().unwrap().get(&key) {
            return t;
        }
        // Leaked on purpose: one table per distinct triple, alive as long as the cache is.
        let t: &'static RoughInterface =
            Box::leak(Box::new(RoughInterface::compute(kind, alpha, eta)));
        let mut map = cache.lock().unwrap();
        map.entry(key).or_insert(t);
        map[&key]
    }

    fn compute(kind: MicrofacetType, alpha: f32, eta: f32) -> RoughInterface {
        let dist = Microfacet::new(kind, alpha, alpha, true);
        let mu = |j: usize| (j as f32 / (TRANSMITTANCE_RES - 1) as f32).max(1e-6);
        let dir = |mu: f32| Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
        let mut transmittance = [0.0; TRANSMITTANCE_RES];
        for (j, t) in transmittance.iter_mut().enumerate() {
            *t = visible_normal_mean(&dist, dir(mu(j)), eta, |wi, m| {
                let (f, cos_t) = fresnel_dielectric(wi.dot(m).clamp(0.0, 1.0), eta);
                if f >= 1.0 {
                    return 0.0;
                }
                // Refraction through m: wt = m ((wi·m)/η − cos θt) − wi/η.
                let wt = m * (wi.dot(m) / eta - cos_t) - wi / eta;
                if wt.z * wi.z >= 0.0 {
                    return 0.0;
                }
                dist.g1(wt, m) as f64 * (1.0 - f) as f64
            }) as f32;
        }
        let inv_eta = 1.0 / eta;
        let sum: f64 = (0..TRANSMITTANCE_RES)
            .map(|j| {
                let wi = dir(mu(j));
                let r = visible_normal_mean(&dist, wi, inv_eta, |wi, m| {
                    let wr = reflect(wi, m);
                    if wr.z <= 0.0 || wi.z <= 0.0 {
                        return 0.0;
                    }
                    let f = fresnel_dielectric(wi.dot(m).clamp(0.0, 1.0), inv_eta).0;
                    dist.g1(wr, m) as f64 * f as f64
                });
                r * wi.z as f64
            })
            .sum();
        RoughInterface {
            transmittance,
            internal_reflectance: (2.0 * sum / TRANSMITTANCE_RES as f64) as f32,
        }
    }
}

/// The mean of `g(wi, m)` over visible normals m of `dist` seen from `wi`: an n×n Gauss–Legendre
/// rule on the sampler's unit square, n = 32 when `eta` > 1 else 128 (as Mitsuba 3.9).
fn visible_normal_mean(
    dist: &Microfacet,
    wi: Vec3,
    eta: f32,
    g: impl Fn(Vec3, Vec3) -> f64,
) -> f64 {
    let n = if eta > 1.0 { 32 } else { 128 };
    let (x, w) = gauss_legendre(n);
    let mut sum = 0.0;
    for (xa, wa) in x.iter().zip(&w) {
        for (xb, wb) in x.iter().zip(&w) {
            let u = Vec2::new((0.5 * xa + 0.5) as f32, (0.5 * xb + 0.5) as f32);
            let m = match dist.kind {
                MicrofacetType::Ggx => ggx_visible_normal_concentric(dist.alpha_u, wi, u),
                MicrofacetType::Beckmann => dist.sample_normal(wi, u),
            };
            sum += g(wi, m) * wa * wb * 0.25;
        }
    }
    sum
}

/// GGX visible normals (isotropic α, `wi` in the xz plane or not) parameterised as Mitsuba 3.9
/// does: the stretched view direction's α = 1 visible slopes from a concentric-disk point whose
/// y is squeezed onto the visible half (Heitz 2018, §4 with Shirley & Chiu's disk), rotated to
/// the view azimuth and unstretched. The same distribution as `Microfacet::sample_normal`, with
/// another map from the unit square: the tables are quadratures over that square, and this map
/// gives Mitsuba's values (T at grazing incidence differs by 10 % with the polar map).
fn ggx_visible_normal_concentric(alpha: f32, wi: Vec3, u: Vec2) -> Vec3 {
    let v = Vec3::new(alpha * wi.x, alpha * wi.y, wi.z).normalize();
    let sin = (1.0 - v.z * v.z).max(0.0).sqrt();
    let (cos_phi, sin_phi) = if sin > 0.0 {
        (v.x / sin, v.y / sin)
    } else {
        (1.0, 0.0)
    };
    let cos = v.z;
    let p = crate::sampling::sample_concentric_disk(u);
    let s = 0.5 * (1.0 + cos);
    let y = (1.0 - s) * (1.0 - p.x * p.x).max(0.0).sqrt() + s * p.y;
    let x = p.x;
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    let norm = 1.0 / (sin * y + cos * z);
    let (s1, s2) = ((cos * y - sin * z) * norm, x * norm);
    let sx = (cos_phi * s1 - sin_phi * s2) * alpha;
    let sy = (sin_phi * s1 + cos_phi * s2) * alpha;
    Vec3::new(-sx, -sy, 1.0).normalize()
}

/// Mitsuba parameters: `distribution` ("beckmann" default, "ggx"), `alpha` (0.1),
/// `sample_visible` (true), `int_ior`/`ext_ior` (polypropylene/air), `diffuse_reflectance` (0.5,
/// texturable), `specular_reflectance` (1, texturable), `nonlinear` (false).
#[derive(Clone, Debug)]
pub struct RoughPlastic {
    /// Isotropic (α_u = α_v).
    pub distribution: Microfacet,
    /// η = int_ior / ext_ior.
    pub eta: f32,
    pub diffuse_reflectance: Color,
    pub specular_reflectance: Color,
    pub nonlinear: bool,
    /// As `Plastic::specular_sampling_weight`.
    pub specular_sampling_weight: f32,
    pub interface: &'static RoughInterface,
}

impl RoughPlastic {
    pub fn new(
        distribution: Microfacet,
        eta: f32,
        diffuse: Color,
        specular: Color,
        nonlinear: bool,
    ) -> RoughPlastic {
        RoughPlastic {
            distribution,
            eta,
            diffuse_reflectance: diffuse,
            specular_reflectance: specular,
            nonlinear,
            specular_sampling_weight: specular_sampling_weight(
                channel_mean(diffuse),
                channel_mean(specular),
            ),
            interface: RoughInterface::get(distribution.kind, distribution.alpha_u, eta),
        }
    }

    /// Mitsuba's defaults: Beckmann, α = 0.1, visible normals, polypropylene in air.
    pub fn mitsuba_default() -> RoughPlastic {
        RoughPlastic::new(
            Microfacet::isotropic(MicrofacetType::Beckmann, 0.1),
            POLYPROPYLENE_IOR / AIR_IOR,
            Color::splat(0.5),
            Color::ONE,
            false,
        )
    }

    /// Probability of choosing the specular lobe from `wo` (wo.z > 0).
    #[inline]
    fn specular_probability(&self, wo: Vec3) -> f32 {
        let t = self.interface.transmittance_at(wo.z.min(1.0));
        specular_lobe_probability(self.specular_sampling_weight, 1.0 - t, t)
    }
}

impl LocalBsdf for RoughPlastic {
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.specular_probability(wo) {
            reflect(wo, self.distribution.sample_normal(wo, u))
        } else {
            sample_cosine_hemisphere(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf_w = self.pdf(wo, wi);
        if !(pdf_w > 0.0) {
            return None;
        }
        Some(LocalSample {
            wi,
            weight: self.eval(wo, wi, mode) * (wi.z / pdf_w),
            pdf_w,
            pdf_rev_w: self.pdf(wi, wo),
            delta: false,
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> Color {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Color::ZERO;
        }
        let dist = &self.distribution;
        let h = (wo + wi).normalize();
        // Grouped symmetrically so that f(wo, wi) == f(wi, wo) exactly (see `rough_conductor`).
        let g = dist.g1(wo, h) * dist.g1(wi, h);
        let cos_h = 0.5 * (wo.dot(h) + wi.dot(h));
        let f = fresnel_dielectric(cos_h.clamp(0.0, 1.0), self.eta).0;
        let specular = self.specular_reflectance * (f * dist.d(h) * g / (4.0 * (wo.z * wi.z)));
        let f_int = self.interface.internal_reflectance;
        let diffuse = internal_scattering(self.diffuse_reflectance, f_int, self.nonlinear);
        let t = self.interface.transmittance_at(wo.z.min(1.0))
            * self.interface.transmittance_at(wi.z.min(1.0));
        specular + diffuse * (t * INV_PI / (self.eta * self.eta))
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        let p_spec = self.specular_probability(wo);
        let h = (wo + wi).normalize();
        let specular = if wo.dot(h) > 0.0 && wi.dot(h) > 0.0 {
            self.distribution.pdf_normal(wo, h) * reflection_jacobian(wi, h)
        } else {
            0.0
        };
        p_spec * specular + (1.0 - p_spec) * cosine_hemisphere_pdf(wi.z)
    }

    fn is_delta(&self) -> bool {
        false
    }
}

/// The sampling tests' rough plastics (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for RoughPlastic {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::microfacet::MicrofacetType::{Beckmann, Ggx};
        use super::test_registry::*;
        vec![
            (
                "roughplastic-beckmann-0.05",
                rough_plastic(Beckmann, 0.05, true, false),
            ),
            (
                "roughplastic-beckmann-0.3-nonlinear",
                rough_plastic(Beckmann, 0.3, true, true),
            ),
            (
                "roughplastic-beckmann-0.3-all",
                rough_plastic(Beckmann, 0.3, false, false),
            ),
            (
                "roughplastic-ggx-0.1-nonlinear",
                rough_plastic(Ggx, 0.1, true, true),
            ),
            ("roughplastic-ggx-0.5", rough_plastic(Ggx, 0.5, true, false)),
            (
                "roughplastic-ggx-0.2-all",
                rough_plastic(Ggx, 0.2, false, false),
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::super::plastic::tests::{check_pins, check_pins_within};
    use super::*;

    #[test]
    fn matches_mitsuba_values() {
        let (a, b, c) = (
            (
                [0.309_426_37, 0.206_284_25, 0.928_279_1],
                [-0.577_350_26, 0.115_470_05, 0.808_290_36],
            ),
            (
                [0.929_981_1, -0.116_247_64, 0.348_742_9],
                [0.127_000_12, 0.762_000_74, 0.635_000_65],
            ),
            (
                [0.099_503_72, 0.0, 0.995_037_2],
                [-0.963_517_9, 0.214_115_1, 0.160_586_31],
            ),
        );
        let orange = Color::new(0.8, 0.4, 0.1);
        let ggx = RoughPlastic::new(
            Microfacet::isotropic(MicrofacetType::Ggx, 0.3),
            POLYPROPYLENE_IOR / AIR_IOR,
            orange,
            Color::ONE,
            false,
        );
        let near = [-0.310_684_9, -0.186_410_93, 0.932_054_6];
        check_pins(
            &ggx,
            &[
                (
                    a.0,
                    a.1,
                    [0.155_828_49, 0.085_585_6, 0.032_903_43],
                    0.271_613_72,
                ),
                (
                    b.0,
                    b.1,
                    [0.096_664_08, 0.049_222_87, 0.013_641_957],
                    0.153_173_12,
                ),
                (
                    c.0,
                    c.1,
                    [0.023_531_77, 0.012_358_081, 0.003_977_814],
                    0.049_924_27,
                ),
                (
                    a.0,
                    near,
                    [0.200_516_64, 0.118_674_755, 0.057_293_35],
                    0.365_700_78,
                ),
            ],
        );
        // Beckmann far from its lobe: the diffuse lobe alone pins the transmittance table and
        // the internal reflectance; bk7, nonlinear. Mitsuba's Beckmann G1 is a rational fit
        // (see `microfacet`), also inside the table's integrand, which moves T by ~5e-5
        // (measured: 5.4e-5 here; Mitsuba's own three-Newton-step sampler instead of ours moves
        // it by 2e-7), so these pins allow 1e-4.
        let beckmann = RoughPlastic::new(
            Microfacet::isotropic(MicrofacetType::Beckmann, 0.1),
            1.5046 / AIR_IOR,
            orange,
            Color::ONE,
            true,
        );
        check_pins_within(
            &beckmann,
            1e-4,
            &[
                (
                    a.0,
                    a.1,
                    [0.157_515_48, 0.055_556_05, 0.012_254_124],
                    0.236_735_14,
                ),
                (
                    b.0,
                    b.1,
                    [0.104_867_78, 0.036_470_864, 0.007_422_850_5],
                    0.138_133_17,
                ),
                (
                    c.0,
                    c.1,
                    [0.020_187_203, 0.007_020_695, 0.001_428_909_7],
                    0.046_573_557,
                ),
            ],
        );
    }
}

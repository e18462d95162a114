//! Smooth plastic (Mitsuba 3's `plastic`): a smooth dielectric coating (relative IOR η) over a
//! Lambertian base of reflectance R, with light reflected back and forth inside the coating.
//! Two lobes, both on the front side only (zero below the surface, as in Mitsuba):
//! - specular, a delta: F(cos θo) · `specular_reflectance` at the mirror direction;
//! - diffuse: f = (1 − F(cos θo))(1 − F(cos θi)) · R / (π η² (1 − F_dr,int · (nonlinear ? R : 1))),
//!   F_dr,int the diffuse Fresnel reflectance seen from inside (relative IOR 1/η): the geometric
//!   series of internal reflections (Weidlich & Wilkie 2007; Mitsuba 3's plastic). `nonlinear`
//!   lets the base's own albedo take part in that series (darker, more saturated colours).
//!
//! f is symmetric in (wo, wi), hence the same in both transport modes: the 1/η² is not a
//! refraction's radiance scaling (light enters and leaves; η² and 1/η² cancel) but the share of
//! the base's Lambertian radiance that fits in the exit cone.
//!
//! Lobe choice (Mitsuba's): with the sampling weight w = s̄ / (d̄ + s̄) of the mean specular and
//! diffuse reflectances (channel means; texture means when textured), the specular lobe is chosen
//! with probability P = F w / (F w + (1 − F)(1 − w)), F = F(cos θo), and the diffuse lobe is
//! sampled by the cosine-weighted hemisphere with probability 1 − P.

use super::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance_fit};
use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3, INV_PI};
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};

/// Mitsuba's named IORs the plastics default to: `int_ior` "polypropylene", `ext_ior` "air".
pub const POLYPROPYLENE_IOR: f32 = 1.49;
pub const AIR_IOR: f32 = 1.000277;

/// The mean of a reflectance as Mitsuba's RGB variants take it: the mean of its channels.
#[inline]
pub fn channel_mean(c: Color) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// Mitsuba's specular sampling weight s̄ / (d̄ + s̄).
pub fn specular_sampling_weight(diffuse_mean: f32, specular_mean: f32) -> f32 {
    specular_mean / (diffuse_mean + specular_mean)
}

/// The probability of choosing a plastic's specular lobe, sampling weight `w`, when its coating
/// reflects `reflected` and transmits `transmitted` of the light arriving from outside:
/// R w / (R w + T (1 − w)) (smooth: R = F, T = 1 − F; rough: the interface's 1 − T(μ), T(μ)).
#[inline]
pub fn specular_lobe_probability(w: f32, reflected: f32, transmitted: f32) -> f32 {
    let (s, d) = (reflected * w, transmitted * (1.0 - w));
    s / (s + d)
}

/// The base's reflectance `r` through the coating's internal reflections, the geometric series
/// R / (1 − F_int · (nonlinear ? R : 1)) with `f_int` the coating's diffuse reflectance from
/// inside (Weidlich & Wilkie 2007; Mitsuba 3's plastic and roughplastic).
#[inline]
pub fn internal_scattering(r: Color, f_int: f32, nonlinear: bool) -> Color {
    let internal = if nonlinear {
        r * f_int
    } else {
        Color::splat(f_int)
    };
    r / (Color::ONE - internal)
}

/// Mitsuba parameters: `int_ior` (polypropylene, 1.49), `ext_ior` (air, 1.000277),
/// `diffuse_reflectance` (0.5, texturable), `specular_reflectance` (1, texturable), `nonlinear`
/// (false).
#[derive(Clone, Debug)]
pub struct Plastic {
    /// η = int_ior / ext_ior.
    pub eta: f32,
    pub diffuse_reflectance: Color,
    pub specular_reflectance: Color,
    pub nonlinear: bool,
    /// w of the lobe choice: from the reflectances' means, fixed when the material is built (a
    /// textured reflectance enters by its texture's mean, not by its value at the point).
    pub specular_sampling_weight: f32,
    /// F_dr of the coating seen from inside (Mitsuba's fit at 1/η).
    pub fdr_int: f32,
}

impl Plastic {
    /// A plastic of relative IOR `eta` with the sampling weight of these (untextured) reflectances.
    pub fn new(eta: f32, diffuse: Color, specular: Color, nonlinear: bool) -> Plastic {
        Plastic {
            eta,
            diffuse_reflectance: diffuse,
            specular_reflectance: specular,
            nonlinear,
            specular_sampling_weight: specular_sampling_weight(
                channel_mean(diffuse),
                channel_mean(specular),
            ),
            fdr_int: fresnel_diffuse_reflectance_fit(1.0 / eta),
        }
    }

    /// Mitsuba's defaults.
    pub fn mitsuba_default() -> Plastic {
        Plastic::new(
            POLYPROPYLENE_IOR / AIR_IOR,
            Color::splat(0.5),
            Color::ONE,
            false,
        )
    }

    fn fresnel(&self, cos: f32) -> f32 {
        fresnel_dielectric(cos.min(1.0), self.eta).0
    }

    /// Probability of choosing the specular lobe when the outer Fresnel reflectance is `f`.
    #[inline]
    fn specular_probability(&self, f: f32) -> f32 {
        specular_lobe_probability(self.specular_sampling_weight, f, 1.0 - f)
    }

    /// The diffuse lobe with the two transmissions left out: R / (π η² (1 − F_dr,int·(R or 1))).
    #[inline]
    fn diffuse_base(&self) -> Color {
        internal_scattering(self.diffuse_reflectance, self.fdr_int, self.nonlinear)
            * (INV_PI / (self.eta * self.eta))
    }
}

impl Default for Plastic {
    fn default() -> Self {
        Plastic::mitsuba_default()
    }
}

impl LocalBsdf for Plastic {
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, _mode: TransportMode) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let f_o = self.fresnel(wo.z);
        let p_spec = self.specular_probability(f_o);
        if u_lobe < p_spec {
            // F·specular_reflectance over the lobe's probability; the mirror direction has the
            // same cos θ, so the reverse walk chooses this lobe with the same P.
            return Some(LocalSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: self.specular_reflectance * (f_o / p_spec),
                pdf_w: p_spec,
                pdf_rev_w: p_spec,
                delta: true,
            });
        }
        let wi = sample_cosine_hemisphere(u);
        if wi.z <= 0.0 {
            return None;
        }
        let f_i = self.fresnel(wi.z);
        let p_diff = 1.0 - p_spec;
        // f cos θi / ((1 − P) cos θi / π).
        let weight = self.diffuse_base() * ((1.0 - f_o) * (1.0 - f_i) / (p_diff * INV_PI));
        Some(LocalSample {
            wi,
            weight,
            pdf_w: p_diff * cosine_hemisphere_pdf(wi.z),
            pdf_rev_w: self.pdf(wi, wo),
            delta: false,
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> Color {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Color::ZERO;
        }
        let t = (1.0 - self.fresnel(wo.z)) * (1.0 - self.fresnel(wi.z));
        self.diffuse_base() * t
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        (1.0 - self.specular_probability(self.fresnel(wo.z))) * cosine_hemisphere_pdf(wi.z)
    }

    fn is_delta(&self) -> bool {
        false
    }

    fn has_delta_lobe(&self) -> bool {
        true
    }
}

/// The sampling tests' plastics (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Plastic {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::test_registry::*;
        use super::Material;
        vec![
            ("plastic", plastic(COLOR, false)),
            ("plastic-nonlinear", plastic(COLOR, true)),
            (
                "plastic-ior-2.4-dark",
                Material::Plastic(Plastic::new(
                    2.4,
                    Color::new(0.05, 0.1, 0.02),
                    Color::ONE,
                    false,
                )),
            ),
        ]
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// f·cos θi and pdf from Mitsuba 3.9.1 (`mi.load_dict`, `bsdf.eval`, `bsdf.pdf`, scalar_rgb),
    /// for (wo, wi) given as Mitsuba's (si.wi, wo).
    pub(crate) type Pin = ([f32; 3], [f32; 3], [f32; 3], f32);

    /// Both sides evaluate the same f32 formulas in different orders (Mitsuba with fused
    /// multiply-adds): over 400 random pairs away from grazing the spread was below 2e-5.
    pub(crate) const REL_TOL: f32 = 2e-5;

    pub(crate) fn check_pins(m: &dyn LocalBsdf, pins: &[Pin]) {
        check_pins_within(m, REL_TOL, pins)
    }

    pub(crate) fn check_pins_within(m: &dyn LocalBsdf, tol: f32, pins: &[Pin]) {
        for (wo, wi, f_cos, pdf) in pins {
            let (wo, wi) = (Vec3::from(*wo), Vec3::from(*wi));
            let f = m.eval(wo, wi, TransportMode::Radiance) * wi.z;
            let p = m.pdf(wo, wi);
            for c in 0..3 {
                let rel = (f[c] - f_cos[c]).abs() / f_cos[c];
                assert!(
                    rel <= tol,
                    "{wo} {wi}: f·cos[{c}] {} vs Mitsuba {}",
                    f[c],
                    f_cos[c]
                );
            }
            let rel = (p - pdf).abs() / pdf;
            assert!(rel <= tol, "{wo} {wi}: pdf {p} vs Mitsuba {pdf}");
        }
    }

    const A: ([f32; 3], [f32; 3]) = (
        [0.309_426_37, 0.206_284_25, 0.928_279_1],
        [-0.577_350_26, 0.115_470_05, 0.808_290_36],
    );
    const B: ([f32; 3], [f32; 3]) = (
        [0.929_981_1, -0.116_247_64, 0.348_742_9],
        [0.127_000_12, 0.762_000_74, 0.635_000_65],
    );
    const C: ([f32; 3], [f32; 3]) = (
        [0.099_503_72, 0.0, 0.995_037_2],
        [-0.963_517_9, 0.214_115_1, 0.160_586_31],
    );

    #[test]
    fn matches_mitsuba_values() {
        let d = Plastic::mitsuba_default();
        check_pins(
            &d,
            &[
                (A.0, A.1, [0.130_311_07; 3], 0.237_947_02),
                (B.0, B.1, [0.087_661_87; 3], 0.145_182_86),
                (C.0, C.1, [0.015_870_217; 3], 0.047_309_652),
            ],
        );
        // int_ior 1.9, diffuse (0.1, 0.27, 0.36), nonlinear: the sphere grid's shiny plastic.
        let nl = Plastic::new(1.9 / AIR_IOR, Color::new(0.1, 0.27, 0.36), Color::ONE, true);
        check_pins(
            &nl,
            &[
                (
                    A.0,
                    A.1,
                    [0.006_273_185, 0.019_707_147, 0.028_766_41],
                    0.178_666_34,
                ),
                (
                    B.0,
                    B.1,
                    [0.004_169_040_4, 0.013_097, 0.019_117_614],
                    0.093_227_61,
                ),
                (
                    C.0,
                    C.1,
                    [0.000_764_671_7, 0.002_402_208_5, 0.003_506_49],
                    0.035_556_25,
                ),
            ],
        );
    }
}

//! Microfacet distributions shared by every rough material: Beckmann and GGX (Trowbridge–Reitz),
//! isotropic or anisotropic (α_u along the shading frame's x, α_v along y), Smith masking in the
//! separable form G = G1(wo)·G1(wi) that Mitsuba 3 uses, and two ways to sample a microfacet
//! normal: visible normals (`sample_visible = true`, Mitsuba's default) or D(m)·cos θm.
//!
//! Everything is in the shading frame (z = macro normal); `m` is a unit microfacet normal.
//!
//! Differences from Mitsuba 3.9.1, on purpose:
//! - Beckmann's G1 is the exact Smith form from erf (Walter et al. 2007, eq. 27 with Λ of
//!   Heitz 2014, eq. 72), where Mitsuba uses a rational fit with < 0.35 % relative error; sampling
//!   and pdf must agree exactly for the χ² tests, and this way they do.
//! - Beckmann visible normals are sampled by inverting the visible-slope CDF to f64 precision
//!   (bracketed Newton), where Mitsuba stops after three Newton steps in f32.

use crate::math::{Vec2, Vec3, PI};
use statrs::function::erf::{erf, erf_inv};

/// Which normal distribution (Mitsuba's `distribution`: "beckmann" or "ggx").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MicrofacetType {
    Beckmann,
    Ggx,
}

/// Smallest roughness: Mitsuba clamps α to 1e-4, where D is still representable.
pub const MIN_ALPHA: f32 = 1e-4;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub kind: MicrofacetType,
    /// Roughness along the shading frame's x axis (Mitsuba's `alpha_u`, or `alpha` for both).
    pub alpha_u: f32,
    /// Roughness along y (`alpha_v`).
    pub alpha_v: f32,
    /// Sample the distribution of visible normals (Mitsuba's `sample_visible`, default true).
    pub sample_visible: bool,
}

impl Microfacet {
    /// A distribution with α clamped to `MIN_ALPHA` as Mitsuba does.
    pub fn new(kind: MicrofacetType, alpha_u: f32, alpha_v: f32, sample_visible: bool) -> Self {
        Microfacet {
            kind,
            alpha_u: alpha_u.max(MIN_ALPHA),
            alpha_v: alpha_v.max(MIN_ALPHA),
            sample_visible,
        }
    }

    /// Isotropic distribution with visible-normal sampling.
    pub fn isotropic(kind: MicrofacetType, alpha: f32) -> Self {
        Microfacet::new(kind, alpha, alpha, true)
    }

    /// The same distribution with both roughnesses scaled by `s`.
    pub fn scaled(&self, s: f32) -> Self {
        Microfacet::new(
            self.kind,
            self.alpha_u * s,
            self.alpha_v * s,
            self.sample_visible,
        )
    }

    /// α_u ≠ α_v: the lobe depends on the frame's tangent.
    pub fn is_anisotropic(&self) -> bool {
        self.alpha_u != self.alpha_v
    }

    /// The larger roughness (what a test places its bins by).
    #[inline]
    pub fn max_alpha(&self) -> f32 {
        self.alpha_u.max(self.alpha_v)
    }

    /// D(m), normalised so that ∫ D(m) cos θm dω = 1. Anisotropic forms of Walter et al. 2007,
    /// eq. 25 (Beckmann) and eq. 33 (GGX), with tan²θm cos²φ → m_x²/m_z² (Heitz 2014, §5.3 & 5.4):
    /// Beckmann exp(−(x̃² + ỹ²)/m_z²) / (π α_u α_v m_z⁴), GGX 1 / (π α_u α_v (x̃² + ỹ² + m_z²)²),
    /// x̃ = m_x/α_u, ỹ = m_y/α_v.
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (m.x / self.alpha_u, m.y / self.alpha_v);
        let cos2 = m.z * m.z;
        let a = PI * self.alpha_u * self.alpha_v;
        let d = match self.kind {
            MicrofacetType::Beckmann => (-(x * x + y * y) / cos2).exp() / (a * cos2 * cos2),
            MicrofacetType::Ggx => {
                let t = x * x + y * y + cos2;
                1.0 / (a * t * t)
            }
        };
        // As Mitsuba: values this small are zero, so that no denormal reaches f (whose rounding
        // there would break reciprocity, and carries no energy).
        if d.is_finite() && d * m.z > 1e-20 {
            d
        } else {
            0.0
        }
    }

    /// Smith's masking G1(v, m) = χ⁺(v·m / v_z) / (1 + Λ(v)) (Walter et al. 2007, eq. 23 & 27, 34;
    /// anisotropic through the projected roughness α_v² tan²θ = (α_u² v_x² + α_v² v_y²)/v_z²,
    /// Heitz 2014 eq. 80): GGX Λ = (√(1 + α² tan²θ) − 1)/2, Beckmann Λ = (erf(a) − 1)/2 +
    /// e^(−a²)/(2a√π) with a = 1/(α tan θ) (Heitz 2014, eq. 72). Zero when v sees the back of m.
    pub fn g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let xy = (self.alpha_u * v.x).powi(2) + (self.alpha_v * v.y).powi(2);
        if xy == 0.0 {
            return 1.0;
        }
        let alpha2_tan2 = xy as f64 / (v.z as f64 * v.z as f64);
        let lambda = match self.kind {
            MicrofacetType::Ggx => 0.5 * ((1.0 + alpha2_tan2).sqrt() - 1.0),
            MicrofacetType::Beckmann => {
                let a = 1.0 / alpha2_tan2.sqrt();
                0.5 * (erf(a) - 1.0) + (-a * a).exp() / (2.0 * a * std::f64::consts::PI.sqrt())
            }
        };
        (1.0 / (1.0 + lambda)) as f32
    }

    /// Separable masking–shadowing G(wo, wi, m) = G1(wo, m)·G1(wi, m) (Walter et al. 2007, eq. 23).
    pub fn g(&self, wo: Vec3, wi: Vec3, m: Vec3) -> f32 {
        self.g1(wo, m) * self.g1(wi, m)
    }

    /// Solid-angle density of `sample_normal(v, ·)` at m, for v in the upper hemisphere:
    /// visible normals D_v(m) = G1(v, m)·max(0, v·m)·D(m) / v_z (Heitz 2014, eq. 2 / Heitz 2018),
    /// otherwise D(m)·cos θm.
    pub fn pdf_normal(&self, v: Vec3, m: Vec3) -> f32 {
        if self.sample_visible {
            if v.z <= 0.0 {
                return 0.0;
            }
            self.d(m) * self.g1(v, m) * v.dot(m).max(0.0) / v.z
        } else {
            self.d(m) * m.z.max(0.0)
        }
    }

    /// A microfacet normal for an observer at `v` (v.z > 0), with density `pdf_normal(v, m)`.
    pub fn sample_normal(&self, v: Vec3, u: Vec2) -> Vec3 {
        if !self.sample_visible {
            return self.sample_all_normals(u);
        }
        match self.kind {
            MicrofacetType::Ggx => self.sample_visible_ggx(v, u),
            MicrofacetType::Beckmann => self.sample_visible_beckmann(v, u),
        }
    }

    /// m with density D(m) cos θm: the slope distribution P22 is the α = 1 one stretched by
    /// (α_u, α_v) (Heitz 2014, §5.3), so draw an isotropic α = 1 slope — radius by inverting its
    /// CDF (Beckmann tan²θ = −ln(1 − u), GGX tan²θ = u/(1 − u); Walter et al. 2007 eq. 28, 35),
    /// azimuth uniform — and stretch it. m = (−s_x, −s_y, 1)/‖·‖.
    fn sample_all_normals(&self, u: Vec2) -> Vec3 {
        let tan2 = match self.kind {
            MicrofacetType::Beckmann => -(1.0 - u.x as f64).ln(),
            MicrofacetType::Ggx => u.x as f64 / (1.0 - u.x as f64),
        };
        let phi = 2.0 * std::f64::consts::PI * u.y as f64;
        let t = tan2.sqrt();
        let (sx, sy) = (
            t * phi.cos() * self.alpha_u as f64,
            t * phi.sin() * self.alpha_v as f64,
        );
        normal_from_slopes(sx, sy)
    }

    /// GGX visible normals (Heitz 2018, "Sampling the GGX Distribution of Visible Normals"):
    /// stretch v to the α = 1 configuration, sample the projected hemisphere there, unstretch.
    fn sample_visible_ggx(&self, v: Vec3, u: Vec2) -> Vec3 {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let vh = Vec3::new(au * v.x, av * v.y, v.z).normalize();
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        // Uniform disk point, its second coordinate squeezed onto the visible half of the disk.
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let p1 = r * phi.cos();
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * (r * phi.sin());
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        Vec3::new(au * nh.x, av * nh.y, nh.z.max(0.0)).normalize()
    }

    /// Beckmann visible normals (Jakob 2014, "An Improved Visible Normal Sampling Routine for the
    /// Beckmann Distribution"; the stretch of Heitz & d'Eon 2014): stretch v to α = 1, draw the two
    /// slopes of a visible α = 1 facet, rotate them to v's azimuth, unstretch.
    fn sample_visible_beckmann(&self, v: Vec3, u: Vec2) -> Vec3 {
        let (au, av) = (self.alpha_u as f64, self.alpha_v as f64);
        let (x, y, z) = (au * v.x as f64, av * v.y as f64, v.z as f64);
        let len = (x * x + y * y + z * z).sqrt();
        let (x, y, z) = (x / len, y / len, z / len);
        let sin = (x * x + y * y).sqrt();
        let (cos_phi, sin_phi) = if sin > 0.0 {
            (x / sin, y / sin)
        } else {
            (1.0, 0.0)
        };
        let (s1, s2) = beckmann_visible_slopes(z, sin, u);
        let sx = (cos_phi * s1 - sin_phi * s2) * au;
        let sy = (sin_phi * s1 + cos_phi * s2) * av;
        normal_from_slopes(sx, sy)
    }
}

/// The unit normal of a facet with slopes (s_x, s_y): (−s_x, −s_y, 1)/‖·‖.
fn normal_from_slopes(sx: f64, sy: f64) -> Vec3 {
    let len = (sx * sx + sy * sy + 1.0).sqrt();
    Vec3::new((-sx / len) as f32, (-sy / len) as f32, (1.0 / len) as f32)
}

/// Slopes (x̃, ỹ) of a visible facet of the α = 1 Beckmann surface seen from polar angle θ in the
/// xz plane. A facet with slopes (x̃, ỹ) has normal ∝ (−x̃, −ỹ, 1) and projected area ∝
/// max(0, cos θ − x̃ sin θ), so the visible slopes have density ∝ (1 − x̃ tan θ)·e^(−x̃² − ỹ²) on
/// x̃ < cot θ: ỹ is an independent Gaussian of variance ½, and x̃ has the (doubled) CDF
/// C(x̃) = 1 + erf(x̃) + tan θ e^(−x̃²)/√π, inverted here by bracketed Newton in f64.
fn beckmann_visible_slopes(cos: f64, sin: f64, u: Vec2) -> (f64, f64) {
    const LIMIT: f64 = 8.0; // e^(−64): no mass beyond, in f64
    let inv_sqrt_pi = 1.0 / std::f64::consts::PI.sqrt();
    let tan = sin / cos;
    let cdf = |x: f64| 1.0 + erf(x) + tan * (-x * x).exp() * inv_sqrt_pi;
    let (mut lo, mut hi) = (
        -LIMIT,
        if sin > 0.0 {
            (cos / sin).min(LIMIT)
        } else {
            LIMIT
        },
    );
    let target = u.x as f64 * cdf(hi);
    let mut x = 0.0f64.clamp(lo, hi);
    for _ in 0..100 {
        let f = cdf(x) - target;
        if f > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        let df = 2.0 * inv_sqrt_pi * (-x * x).exp() * (1.0 - x * tan);
        let mut next = x - f / df;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        let done = (next - x).abs() <= 1e-12 * (1.0 + x.abs());
        x = next;
        if done || hi - lo <= 1e-14 {
            break;
        }
    }
    // ỹ = erf⁻¹(2u − 1), kept off ±1 where erf⁻¹ is infinite (mass 1e-12 moved).
    let w = (2.0 * u.y as f64 - 1.0).clamp(-1.0 + 1e-12, 1.0 - 1e-12);
    (x, erf_inv(w))
}

/// Mirror reflection of `v` about the unit normal `m`: 2(v·m)m − v.
#[inline]
pub fn reflect(v: Vec3, m: Vec3) -> Vec3 {
    2.0 * v.dot(m) * m - v
}

/// Jacobian |dω_m/dω_i| of the reflection half-vector map: 1 / (4 |wi·m|)
/// (Walter et al. 2007, eq. 14).
#[inline]
pub fn reflection_jacobian(wi: Vec3, m: Vec3) -> f32 {
    1.0 / (4.0 * wi.dot(m).abs())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    fn dists() -> Vec<Microfacet> {
        let mut v = Vec::new();
        for kind in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for (au, av) in [(0.1, 0.1), (0.5, 0.5), (0.2, 0.6)] {
                for vis in [true, false] {
                    v.push(Microfacet::new(kind, au, av, vis));
                }
            }
        }
        v
    }

    /// ∫ D(m) cos θm dω = 1 and ∫ D_v(m) dω = 1 (G1's normalisation, Heitz 2014 eq. 2), by
    /// sampling the one and dividing (importance sampling with the other distribution).
    #[test]
    fn distributions_are_normalised() {
        for d in dists() {
            let v = Vec3::new(0.6, 0.3, 0.5).normalize();
            let mut s = Sampler::new(3, 0, 0);
            let n = 200_000;
            let mut sum = 0.0f64;
            let mut sum2 = 0.0f64;
            // Sample uniformly over the hemisphere of m.
            for _ in 0..n {
                let u = s.next_2d();
                let z = u.x;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                let m = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                let x = (d.pdf_normal(v, m) * 2.0 * PI) as f64;
                sum += x;
                sum2 += x * x;
            }
            let mean = sum / n as f64;
            let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
            assert!(
                (mean - 1.0).abs() < 5.0 * se + 1e-3,
                "{d:?}: ∫pdf = {mean} ± {se}"
            );
        }
    }
}

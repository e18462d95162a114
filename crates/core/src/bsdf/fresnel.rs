//! Fresnel reflectance of smooth interfaces: dielectric (real relative IOR) and conductor
//! (complex IOR η + ik per RGB channel), and the diffuse Fresnel reflectance the plastics need.
//! Every material that reflects off or refracts through an interface reads these.

use crate::math::Color;

/// Unpolarised Fresnel reflectance for light meeting the interface at `cos_i` (> 0) with relative
/// IOR `eta` = η_t / η_i. Returns (F, cos θt); F = 1 and cos θt = 0 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32) {
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    // Amplitude coefficients with both numerator and denominator divided by η_i.
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (r_perp * r_perp + r_par * r_par), cos_t)
}

/// Dielectric Fresnel reflectance seen from either side: `cos_i` is signed against the normal
/// (> 0 on the outside) and `eta` = η_inside / η_outside. Index-matched interfaces reflect nothing.
pub fn fresnel_dielectric_signed(cos_i: f32, eta: f32) -> f32 {
    if eta == 1.0 {
        return 0.0;
    }
    let eta_rel = if cos_i >= 0.0 { eta } else { 1.0 / eta };
    fresnel_dielectric(cos_i.abs().min(1.0), eta_rel).0
}

/// Complex index of refraction η + ik of a conductor, per RGB channel (k ≥ 0 absorbs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ComplexIor {
    pub eta: Color,
    pub k: Color,
}

/// Unpolarised Fresnel reflectance of a conductor, one channel: the exact closed form for a
/// complex IOR n = η + ik relative to the outside (Born & Wolf §14.2; e.g. pbrt-v3 §8.2.1):
/// a² + b² = √((η² − k² − sin²θ)² + 4η²k²), a = √((a² + b² + η² − k² − sin²θ)/2),
/// R_s = (a² + b² − 2a cosθ + cos²θ) / (a² + b² + 2a cosθ + cos²θ),
/// R_p = R_s (cos²θ (a² + b²) − 2a cosθ sin²θ + sin⁴θ) / (cos²θ (a² + b²) + 2a cosθ sin²θ + sin⁴θ).
/// Computed in f64: the terms cancel at grazing angles and for k ≫ η.
fn fresnel_conductor_channel(cos_i: f64, eta: f64, k: f64) -> f64 {
    let cos2 = cos_i * cos_i;
    let sin2 = (1.0 - cos2).max(0.0);
    let t = eta * eta - k * k - sin2;
    let a2b2 = (t * t + 4.0 * eta * eta * k * k).sqrt();
    let a = (0.5 * (a2b2 + t)).max(0.0).sqrt();
    let rs = (a2b2 - 2.0 * a * cos_i + cos2) / (a2b2 + 2.0 * a * cos_i + cos2);
    let (p_num, p_cross) = (cos2 * a2b2 + sin2 * sin2, 2.0 * a * cos_i * sin2);
    let rp = rs * (p_num - p_cross) / (p_num + p_cross);
    let r = 0.5 * (rs + rp);
    if r.is_finite() {
        r
    } else {
        1.0 // cos θ = 0 and η = k = 0 … : grazing light is reflected entirely.
    }
}

/// Unpolarised Fresnel reflectance of a conductor at `cos_i` ∈ [0, 1], per RGB channel.
pub fn fresnel_conductor(cos_i: f32, ior: ComplexIor) -> Color {
    let c = cos_i.clamp(0.0, 1.0) as f64;
    let ch = |i: usize| fresnel_conductor_channel(c, ior.eta[i] as f64, ior.k[i] as f64) as f32;
    Color::new(ch(0), ch(1), ch(2))
}

/// The fits Mitsuba 3's plastics use for the diffuse Fresnel reflectance F_dr(η): Egan &
/// Hilgeman 1973 for η < 1, F_dr ≈ 0.0636/η + 0.6681 + 0.7099 η − 1.4399 η², and d'Eon & Irving
/// 2011 otherwise, F_dr ≈ 0.919317 − 3.4793/η + 6.75335/η² − 7.80989/η³ + 4.98554/η⁴ −
/// 1.36881/η⁵. They differ from the exact integral (`fresnel_diffuse_reflectance`) by 0.08 % at
/// η = 1/1.49; the plastics use them so that their values are Mitsuba's.
pub fn fresnel_diffuse_reflectance_fit(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + 0.6681 + eta * (0.7099 - 1.4399 * eta)
    } else {
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        c.iter().rev().fold(0.0, |acc, &k| acc * inv + k)
    }
}

/// Hemispherical (cosine-weighted) average of the dielectric reflectance, for light arriving
/// uniformly in projected solid angle from the side where the relative IOR is `eta`:
/// F_dr = ∫₀¹ F(μ, η) 2μ dμ. Integrated numerically (Gauss–Legendre in μ, the integrand's one kink —
/// the critical angle for η < 1 — on a panel edge), not by the fits Mitsuba 3 uses (Egan &
/// Hilgeman 1973 for η < 1, d'Eon & Irving 2011 otherwise), which differ by up to ~0.1–0.6 %.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let eta = eta as f64;
    let f = |mu: f64| {
        let sin2_t = (1.0 - mu * mu) / (eta * eta);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        let cos_t = (1.0 - sin2_t).sqrt();
        let rs = (mu - eta * cos_t) / (mu + eta * cos_t);
        let rp = (eta * mu - cos_t) / (eta * mu + cos_t);
        0.5 * (rs * rs + rp * rp)
    };
    // Total internal reflection below μ_c = √(1 − η²) when η < 1.
    let mu_c = if eta < 1.0 {
        (1.0 - eta * eta).sqrt()
    } else {
        0.0
    };
    let panel = |a: f64, b: f64| {
        let (nodes, weights) = super::quadrature::gauss_legendre(64);
        nodes
            .iter()
            .zip(&weights)
            .map(|(x, w)| {
                let mu = a + (b - a) * 0.5 * (x + 1.0);
                w * 0.5 * (b - a) * f(mu) * 2.0 * mu
            })
            .sum::<f64>()
    };
    (panel(0.0, mu_c) + panel(mu_c, 1.0)) as f32
}

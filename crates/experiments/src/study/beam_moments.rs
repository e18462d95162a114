//! Exact moments of one photon path's contribution to `pb2d`'s and `bb1d`'s estimate on a frozen
//! camera beam, at any radius r, for a point light in grey isotropic fog with single scattering
//! (the radius-shrinkage-media study's scene): no r² expansion, so the study's bias and variance
//! predictions at finite N are exact up to quadrature.
//!
//! **The field.** A point light of intensity I at l inside fog (σt, σs = albedo σt, phase
//! f_p = 1/4π) filling the slab |z| ≤ H (the cube's sides lie beyond every kernel the study
//! uses). The camera beam is the vertical line through (cₓ, c_y), entering at z = H and leaving
//! at z = −H; s is the distance along it from the entry, T_c(s) = e^{−σt s}. D is the line's
//! horizontal distance from l, A = H − l_z and B = H + l_z the light's distances to the faces.
//! With max_depth 2 a light path is one flight from l along a uniform direction ω (density 1/4π
//! per steradian).
//!
//! **pb2d** (`volume_density/beams.rs`). The flight scatters at x with density per unit volume
//! q(x) = σt e^{−σt d}/(4π d²) (d = |x − l|), storing a photon of power w = 4πI/σt (β = 4πI σs/σt
//! at the scattering, without σs: `photons.rs`), which the beam gathers when x lies in the
//! cylinder C_r of radius r about it: X = w σs f_p T_c(s)/(πr²), s the projection of x on the
//! beam. With q w = I e^{−σt d}/d²,
//!
//!   E[X]  = (σs f_p I/(πr²)) ∫_{C_r} T_c(s) e^{−σt d}/d² dV,
//!   E[X²] = w I (σs f_p/(πr²))² ∫_{C_r} T_c(s)² e^{−σt d}/d² dV      (dV: volume measure).
//!
//! In spherical coordinates about l (dV = d² dd dω, dω = sinθ dθ dφ, θ from +z) the 1/d² cancels
//! and s = A − d cosθ, so the radial integral is an exponential done in closed form:
//! ∫ e^{−σt d (1 − k cosθ)} dd, k = 1 (mean), 2 (second moment), times e^{−kσt A}. A direction's
//! horizontal projection from l (azimuth φ from the direction towards the beam) meets the disc of
//! radius r about the beam for b = d sinθ in [b₁(φ), b₂(φ)]; its θ range is split where
//! [b₁/sinθ, b₂/sinθ] meets the faces (tanθ = b/A, b/B), so each piece is smooth (Gauss–Legendre).
//! When D > r, φ runs over |sin φ| ≤ r/D and is substituted sin φ = (r/D) sin χ, which makes the
//! chord's square-root ends smooth; when D ≤ r (the light's projection inside the disc) φ runs
//! over the circle, split at ±π/2 where b₂ has its kink at D = r.
//!
//! **bb1d** (`volume_density/beam_beam.rs`, long beams). The path's one beam runs from l along ω
//! to the fog's face with power w = 4πI; the camera beam gathers it when the lines pass within r:
//! X = w T_c(s) T_b(t) σs f_p /(2r sinθ), s, t the closest points, θ the angle between the lines.
//! Only beams heading towards the camera line have t ≥ 0; with ψ their azimuth from the direction
//! towards it, the lines' distance is u = D |sin ψ| and the closest point lies ρ = D cos ψ from l
//! horizontally, at height Δz = ρ sinh v above it (t = ρ cosh v, sinθ = 1/cosh v,
//! dθ = dv/cosh v). The 1/sinθ cancels dω's sinθ in the mean, and
//!
//!   E[X]  = I σs f_p/(2r) ∫_{D|sinψ| ≤ r} dψ ∫ dv e^{−σt (A + ρ e^{−v})} / cosh v,
//!   E[X²] = w I (σs f_p/(2r))² ∫ dψ ∫ dv e^{−2σt (A + ρ e^{−v})},
//!
//! (σt(s + t) = σt(A − ρ sinh v + ρ cosh v)), v over the slab: ρ sinh v ∈ [−B, A]. ψ is
//! substituted ψ = ψ_max sin(πξ/2), clustering nodes where ρ → 0 (E[X²]'s v range grows as
//! ln 1/ρ there). The estimator skips beams with sinθ < 1e-4 (cosh v > 10⁴, only where
//! ρ < 4e-4): left out of the integral, a sliver of measure ~1e-8.
//!
//! As r → 0 both means tend to the beam's single scattering ∫ T_c σs L_i ds (the tests).

use std::f64::consts::PI;

/// A point light in a slab of grey isotropic fog (the module comment's field).
#[derive(Clone, Copy, Debug)]
pub struct PointInFog {
    pub light: [f64; 3],
    /// The slab's half-thickness H (the camera beams run from z = H to −H).
    pub half: f64,
    pub sigma_t: f64,
    pub albedo: f64,
    pub intensity: f64,
}

/// E[X] and E[X²] of one photon path's contribution X to a beam's estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moments {
    pub mean: f64,
    pub second: f64,
}

impl Moments {
    /// The variance of one pass's estimate, the mean of `paths` independent paths' X.
    pub fn pass_variance(&self, paths: u64) -> f64 {
        (self.second - self.mean * self.mean) / paths as f64
    }
}

const PHASE: f64 = 1.0 / (4.0 * PI);

/// ∫_{d1}^{d2} e^{−c d} dd, stable as c (d2 − d1) → 0 and for c < 0.
fn radial(c: f64, d1: f64, d2: f64) -> f64 {
    let x = c * (d2 - d1);
    let shape = if x.abs() < 1e-12 {
        1.0
    } else {
        -(-x).exp_m1() / x
    };
    (-c * d1).exp() * (d2 - d1) * shape
}

impl PointInFog {
    fn sigma_s(&self) -> f64 {
        self.sigma_t * self.albedo
    }

    /// (A, B): the light's distances to the top and bottom faces.
    fn slab(&self) -> (f64, f64) {
        (self.half - self.light[2], self.half + self.light[2])
    }

    /// D: the camera line's horizontal distance from the light.
    pub fn offset(&self, c: [f64; 2]) -> f64 {
        (c[0] - self.light[0]).hypot(c[1] - self.light[1])
    }

    /// [Θ₁, Θ₂], Θ_k = ∫ sinθ dθ ∫ e^{−σt d (1 − k cosθ)} dd over the directions whose
    /// projection meets the disc for b ∈ [b1, b2], d within the slab (`rule` on each smooth
    /// piece of θ).
    fn over_theta(&self, b1: f64, b2: f64, rule: &[(f64, f64)]) -> [f64; 2] {
        let (a, b) = self.slab();
        let up = |bb: f64| bb.atan2(a);
        let down = |bb: f64| PI - bb.atan2(b);
        let mut sums = [0.0; 2];
        // (θ from, θ to, whether d ends at b₂/sinθ rather than at a face)
        for (lo, hi, in_cylinder) in [
            (up(b1), up(b2), false),
            (up(b2), down(b2), true),
            (down(b2), down(b1), false),
        ] {
            if hi <= lo {
                continue;
            }
            for &(x, w) in rule {
                let theta = lo + (hi - lo) * x;
                let (st, ct) = theta.sin_cos();
                let d1 = if b1 > 0.0 { b1 / st } else { 0.0 };
                let d2 = if in_cylinder {
                    b2 / st
                } else if ct > 0.0 {
                    a / ct
                } else {
                    -b / ct
                };
                if d2 <= d1 {
                    continue;
                }
                for (k, s) in sums.iter_mut().enumerate() {
                    let c = self.sigma_t * (1.0 - (k + 1) as f64 * ct);
                    *s += w * (hi - lo) * st * radial(c, d1, d2);
                }
            }
        }
        sums
    }

    /// pb2d's one-path moments on the beam at `c` with radius `r` (module comment), `rule` the
    /// Gauss–Legendre nodes on [0, 1] of every one-dimensional piece.
    pub fn pb2d(&self, c: [f64; 2], r: f64, rule: &[(f64, f64)]) -> Moments {
        let dd = self.offset(c);
        let mut sums = [0.0; 2];
        let mut add = |b1: f64, b2: f64, w: f64| {
            let t = self.over_theta(b1, b2, rule);
            sums[0] += w * t[0];
            sums[1] += w * t[1];
        };
        if dd <= r {
            for (lo, hi) in [(-PI, -PI / 2.0), (-PI / 2.0, PI / 2.0), (PI / 2.0, PI)] {
                for &(x, w) in rule {
                    let phi = lo + (hi - lo) * x;
                    let (sp, cp) = phi.sin_cos();
                    let b2 = dd * cp + (r * r - (dd * sp).powi(2)).max(0.0).sqrt();
                    add(0.0, b2, w * (hi - lo));
                }
            }
        } else {
            for &(x, w) in rule {
                let chi = PI * (x - 0.5);
                let (sc, cc) = chi.sin_cos();
                let sin_phi = r / dd * sc;
                let cos_phi = (1.0 - sin_phi * sin_phi).sqrt();
                // dφ = (r/D) cosχ / cosφ dχ, dχ = π dx.
                let jac = PI * r / dd * cc / cos_phi;
                add(dd * cos_phi - r * cc, dd * cos_phi + r * cc, w * jac);
            }
        }
        let (a, _) = self.slab();
        let i = self.intensity;
        let per_photon = self.sigma_s() * PHASE / (PI * r * r);
        let w = 4.0 * PI * i / self.sigma_t;
        Moments {
            mean: per_photon * i * (-self.sigma_t * a).exp() * sums[0],
            second: w * i * per_photon * per_photon * (-2.0 * self.sigma_t * a).exp() * sums[1],
        }
    }

    /// bb1d's one-path moments on the beam at `c` with radius `r` (module comment).
    pub fn bb1d(&self, c: [f64; 2], r: f64, rule: &[(f64, f64)]) -> Moments {
        let dd = self.offset(c);
        let (a, b) = self.slab();
        let st = self.sigma_t;
        let psi_max = if dd > r { (r / dd).asin() } else { PI / 2.0 };
        let (mut m1, mut m2) = (0.0, 0.0);
        for &(x, wx) in rule {
            // ψ = ψ_max sin(πξ/2), ξ = 2x − 1.
            let arg = PI / 2.0 * (2.0 * x - 1.0);
            let psi = psi_max * arg.sin();
            let jac = psi_max * PI * arg.cos();
            let rho = dd * psi.cos();
            if !(rho > 0.0) {
                continue;
            }
            let (v0, v1) = ((-b / rho).asinh(), (a / rho).asinh());
            for &(y, wy) in rule {
                let v = v0 + (v1 - v0) * y;
                let e = st * (a + rho * (-v).exp());
                let w = wx * jac * wy * (v1 - v0);
                m1 += w * (-e).exp() / v.cosh();
                m2 += w * (-2.0 * e).exp();
            }
        }
        let i = self.intensity;
        let per_beam = self.sigma_s() * PHASE / (2.0 * r);
        let w = 4.0 * PI * i;
        Moments {
            mean: i * per_beam * m1,
            second: w * i * per_beam * per_beam * m2,
        }
    }
}

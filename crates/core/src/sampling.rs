//! Random streams and the warps every estimator shares. Each `sample_x` has its `x_pdf` beside it,
//! and the pair is tested together (the pdf integrates to one and matches the histogram).

use crate::keyed_pcg::{keyed_pcg, uniform_f32};
use crate::math::{Vec2, Vec3, PI};
use rand_pcg::Pcg32;

/// A PCG stream keyed by (seed, pixel or path index, pass), so any work split gives the same numbers.
/// Inside `primary_space::with_space` (Metropolis), `for_item` instead hands out a sampler that
/// reads the installed chain's stream for its domain (`stream` names it; `PCG` otherwise).
pub struct Sampler {
    rng: Pcg32,
    stream: u8,
}

/// `Sampler::stream` of an ordinary PCG sampler.
const PCG: u8 = u8::MAX;

/// Which family of work items a stream belongs to. Light path i and pixel i are different items:
/// without the domain word they would draw the same numbers, correlating the two ends of every
/// connection that pairs them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// Camera samples, one per pixel (and streams with no other use, such as tests).
    Camera = 0,
    /// Light subpaths (light tracing, BDPT, photons).
    Light = 1,
    /// Next-event and other samples drawn apart from a subpath.
    Aux = 2,
    /// Lens points of light-tracing connections drawn apart from their subpath (VCM's stored
    /// light paths), one stream per light path.
    Lens = 3,
}

/// Items are pixel or path indices, far below 2⁵⁶: the top byte is free for the domain.
const DOMAIN_SHIFT: u32 = 56;

impl Sampler {
    /// The stream for one item of a domain in one pass of one seeded run. Camera-domain streams
    /// are exactly `Sampler::new`'s.
    pub fn for_item(domain: Domain, seed: u64, item: u64, pass: u64) -> Sampler {
        debug_assert!(item < 1 << DOMAIN_SHIFT);
        let mut s = Sampler::new(seed, item ^ ((domain as u64) << DOMAIN_SHIFT), pass);
        if crate::primary_space::installed() {
            s.stream = 1 + domain as u8;
        }
        s
    }

    /// The stream for one work item (a pixel, or a light path) in one pass of one seeded run.
    /// Integrators use `for_item`, which keeps domains apart.
    pub fn new(seed: u64, item: u64, pass: u64) -> Sampler {
        Sampler {
            rng: keyed_pcg(seed, item, pass),
            stream: PCG,
        }
    }

    /// Uniform in [0, 1), never 1.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        if self.stream != PCG {
            return crate::primary_space::next_installed(self.stream as usize);
        }
        uniform_f32(&mut self.rng)
    }

    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

/// Multiple importance sampling: the power heuristic with β = 2, for one sample from each of two
/// techniques (Veach & Guibas 1995). Both pdfs must be in the same measure.
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    if a.is_infinite() {
        return 1.0;
    }
    if a + b == 0.0 {
        0.0
    } else {
        a / (a + b)
    }
}

/// Uniform point on the unit disk by Shirley's concentric map (keeps strata compact).
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, (PI / 4.0) * (o.y / o.x))
    } else {
        (o.y, PI / 2.0 - (PI / 4.0) * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction on the +z hemisphere (Malley's method).
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Solid-angle pdf of `sample_cosine_hemisphere`.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * crate::math::INV_PI
}

pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Solid-angle pdf of `sample_uniform_sphere`.
pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

/// Uniform direction in the cone around +z whose solid angle is `2π·one_minus_cos_max`.
/// Takes 1 − cos θmax rather than cos θmax so that tiny cones (the sun, 6.87e-5 sr, has
/// 1 − cos θmax ≈ 1.1e-5) keep full f32 precision.
pub fn sample_uniform_cone(u: Vec2, one_minus_cos_max: f32) -> Vec3 {
    let h = u.x * one_minus_cos_max; // 1 − cos θ
    let cos_theta = 1.0 - h;
    let sin_theta = (h * (2.0 - h)).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

/// Solid-angle pdf of `sample_uniform_cone` inside the cone.
#[inline]
pub fn uniform_cone_pdf(one_minus_cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos_max)
}

/// Uniform barycentrics (b1, b2) on a triangle (the square-root warp).
pub fn sample_uniform_triangle(u: Vec2) -> (f32, f32) {
    let su = u.x.sqrt();
    (1.0 - su, u.y * su)
}

/// A discrete distribution proportional to non-negative weights, sampled by its CDF.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    pmf: Vec<f32>,
    total: f32,
}

impl Distribution1D {
    /// Weights must be finite and non-negative; an all-zero list gives an empty distribution.
    pub fn new(weights: &[f32]) -> Distribution1D {
        let total_f64: f64 = weights.iter().map(|&w| w as f64).sum();
        let total = total_f64 as f32;
        if total_f64 <= 0.0 {
            return Distribution1D {
                cdf: vec![],
                pmf: vec![0.0; weights.len()],
                total: 0.0,
            };
        }
        let mut acc = 0.0f64;
        let mut cdf = Vec::with_capacity(weights.len());
        for &w in weights {
            acc += w as f64;
            cdf.push((acc / total_f64) as f32);
        }
        *cdf.last_mut().unwrap() = 1.0;
        let pmf = weights
            .iter()
            .map(|&w| (w as f64 / total_f64) as f32)
            .collect();
        Distribution1D { cdf, pmf, total }
    }

    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    pub fn total(&self) -> f32 {
        self.total
    }

    /// Returns (index, pmf, u remapped to [0,1) within the chosen bin).
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.cdf.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let p = self.pmf[i];
        let remapped = if p > 0.0 {
            ((u - lo) / (self.cdf[i] - lo)).clamp(0.0, 1.0 - f32::EPSILON)
        } else {
            0.0
        };
        (i, p, remapped)
    }

    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_deterministic_and_distinct() {
        let a: Vec<f32> = (0..4)
            .map({
                let mut s = Sampler::new(7, 3, 1);
                move |_| s.next_f32()
            })
            .collect();
        let b: Vec<f32> = (0..4)
            .map({
                let mut s = Sampler::new(7, 3, 1);
                move |_| s.next_f32()
            })
            .collect();
        let c: Vec<f32> = (0..4)
            .map({
                let mut s = Sampler::new(7, 3, 2);
                move |_| s.next_f32()
            })
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn domains_give_uncorrelated_streams_for_the_same_item() {
        // Pearson correlation of the first variate of camera item i and light item i over n items:
        // √n·r is standard normal when they are independent (identical streams give r = 1).
        let n = 20_000u64;
        let (mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            let x = Sampler::for_item(Domain::Camera, 5, i, 0).next_f32() as f64;
            let y = Sampler::for_item(Domain::Light, 5, i, 0).next_f32() as f64;
            sx += x;
            sy += y;
            sxx += x * x;
            syy += y * y;
            sxy += x * y;
        }
        let nf = n as f64;
        let cov = sxy / nf - sx * sy / (nf * nf);
        let r = cov / ((sxx / nf - (sx / nf).powi(2)) * (syy / nf - (sy / nf).powi(2))).sqrt();
        assert!((r * nf.sqrt()).abs() < 4.0, "r = {r}");
        // The camera domain keeps the streams every earlier image was rendered with.
        let a = Sampler::for_item(Domain::Camera, 5, 9, 2).next_f32();
        assert_eq!(a, Sampler::new(5, 9, 2).next_f32());
    }

    #[test]
    fn uniform_variates_have_the_right_mean() {
        let mut s = Sampler::new(1, 2, 3);
        let n = 100_000;
        let mean: f64 = (0..n).map(|_| s.next_f32() as f64).sum::<f64>() / n as f64;
        // Standard error of the mean of U(0,1) is sqrt(1/12/n).
        let se = (1.0 / 12.0 / n as f64).sqrt();
        assert!(((mean - 0.5) / se).abs() < 4.0, "mean {mean}");
    }

    #[test]
    fn distribution_pmf_matches_weights_and_sampling_frequencies() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert_eq!(d.pmf(1), 0.0);
        let mut s = Sampler::new(0, 0, 0);
        let n = 40_000;
        let mut counts = [0usize; 3];
        for _ in 0..n {
            let (i, p, r) = d.sample(s.next_f32());
            assert!(p > 0.0 && (0.0..1.0).contains(&r));
            counts[i] += 1;
        }
        assert_eq!(counts[1], 0);
        let p = 0.25f64;
        let se = (p * (1.0 - p) / n as f64).sqrt();
        assert!(((counts[0] as f64 / n as f64 - p) / se).abs() < 4.0);
    }

    #[test]
    fn cone_keeps_precision_for_the_sun() {
        let omega = 6.87e-5f32;
        let h = omega / (2.0 * PI);
        let d = sample_uniform_cone(Vec2::new(0.999, 0.3), h);
        assert!((d.length() - 1.0).abs() < 1e-6);
        assert!(1.0 - d.z <= h * 1.0001);
        assert!((uniform_cone_pdf(h) * omega - 1.0).abs() < 1e-5);
    }

    #[test]
    fn installed_space_feeds_samplers() {
        use crate::primary_space::{installed, with_space, PrimarySpace};
        let mut space = PrimarySpace::new(2, 3, 0.01);
        space.start_iteration(true);
        let (a, b) = with_space(&mut space, || {
            let mut cam = Sampler::for_item(Domain::Camera, 0, 0, 0);
            let mut light = Sampler::for_item(Domain::Light, 0, 0, 0);
            (cam.next_f32(), light.next_f32())
        });
        assert!(!installed());
        // Replaying the same iteration reads the same coordinates.
        let mut s = space.clone();
        s.rewind_draws();
        assert_eq!(s.next(1 + Domain::Camera as usize), a);
        assert_eq!(s.next(1 + Domain::Light as usize), b);
        // Outside, samplers are PCG streams as before.
        assert_eq!(
            Sampler::for_item(Domain::Camera, 5, 9, 2).next_f32(),
            Sampler::new(5, 9, 2).next_f32()
        );
    }
}

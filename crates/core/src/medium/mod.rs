//! Participating media: what a path sees between surfaces, and what a path vertex inside a volume
//! scatters by.
//!
//! **The contract** the path-space core (`path/`), the integrators and the volumetric density
//! estimators (photon points and beams, UPBP) read. Every quantity is RGB (`Color`), per unit
//! length of the scene's internal coordinates:
//!
//! - σt(x) (extinction), σs(x) = α(x) σt(x) (scattering), α the single-scattering albedo.
//! - T(a, b) = exp(−∫_a^b σt) per channel, computed deterministically
//!   ([`Medium::transmittance`]): exact for homogeneous media and for a trilinear grid. This is
//!   the T the from-scratch f(x̄) and the photon beams' estimates use.
//! - Free-flight sampling along a ray ([`Medium::sample_free_flight`]): returns either a
//!   scattering point at distance t < t_max or "passed" (no interaction before t_max), with the
//!   unbiased throughput weight of that outcome (σs T / p for a scattering, T / P for a pass,
//!   channel by channel: chromatic σt is sampled through one channel and weighed over all three,
//!   see the implementation for which scheme).
//! - [`Medium::free_flight_density`]: the density (per unit length at a scattering point, a
//!   probability for a pass) with which that sampler produces the outcome, as a function of the
//!   endpoints alone. Multiplied by the solid-angle density and the volume conversion 1/d² it is
//!   the `pdf_fwd`/`pdf_rev` of a medium vertex (`measure`), so MIS and the oracle weigh volume
//!   techniques with it.
//! - Unbiased transmittance estimates for shadow rays and connections
//!   ([`Medium::transmittance_estimate`]: ratio tracking; delta tracking as an option).
//!
//! Phase functions ([`phase`]) take both directions pointing away from the scattering point; a
//! forward-scattering HG (g > 0) favours ω_i = −ω_o. Their densities are solid angle, their values
//! per steradian and reciprocal (p(ω_o, ω_i) = p(ω_i, ω_o)), so transport mode does not enter.
//!
//! Two media: [`Homogeneous`] (closed forms, allocation-free: what photon beams read through
//! [`Medium::as_homogeneous`]) and [`GridMedium`] (Mitsuba's `heterogeneous` over a `gridvolume`
//! or `constvolume`; its scheme, a uniformly chosen channel tracked by delta tracking and weighed
//! by the mean density over channels with the exact deterministic T, is in `grid.rs`). Parameters
//! are checked by the constructors in [`params`].
//!
//! A scene without media holds none of this: `Scene::media` is empty and no walk asks.

pub mod grid;
pub mod majorant;
pub mod params;
pub mod phase;
pub mod volume;

pub use grid::{GridMedium, TransmittanceEstimator};
pub use phase::{PhaseFunction, PhaseSample};
pub use volume::{GridVolume, Volume, VolumeGrid, WrapMode};

use crate::math::{Color, Vec3};
use crate::sampling::Sampler;

/// Index of a medium in `Scene::media`.
pub type MediumId = u32;

/// A medium with σt and α constant in space (Mitsuba's `homogeneous`, after `scale`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    pub sigma_t: Color,
    pub albedo: Color,
    pub phase: PhaseFunction,
}

/// A participating medium.
#[derive(Clone, Debug, PartialEq)]
pub enum Medium {
    Homogeneous(Homogeneous),
    /// Mitsuba's `heterogeneous` (σt from a `gridvolume` or `constvolume`).
    /// Boxed: a scene's media are few, and the homogeneous variant stays small.
    Grid(Box<GridMedium>),
}

/// The outcome of free-flight sampling along a ray segment of length `t_max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FreeFlight {
    /// A real scattering at distance `t`; `weight` = σs(x) T(o, x) / p(t), per channel.
    Scattered { t: f32, weight: Color },
    /// No interaction before `t_max`; `weight` = T(o, o + t_max·d) / P(pass), per channel.
    Passed { weight: Color },
}

impl Medium {
    pub fn phase(&self) -> PhaseFunction {
        match self {
            Medium::Homogeneous(h) => h.phase,
            Medium::Grid(g) => g.phase,
        }
    }

    pub fn sigma_t(&self, p: Vec3) -> Color {
        match self {
            Medium::Homogeneous(h) => h.sigma_t,
            Medium::Grid(g) => g.sigma_t(p),
        }
    }

    pub fn sigma_s(&self, p: Vec3) -> Color {
        match self {
            Medium::Homogeneous(h) => h.sigma_s(),
            Medium::Grid(g) => g.sigma_s(p),
        }
    }

    /// T(a, b) = exp(−∫ σt) per channel, deterministic.
    pub fn transmittance(&self, a: Vec3, b: Vec3) -> Color {
        match self {
            Medium::Homogeneous(h) => h.transmittance(a.distance(b)),
            Medium::Grid(g) => g.transmittance(a, b),
        }
    }

    /// Density of [`Medium::sample_free_flight`]'s outcome on the segment a → b: per unit length
    /// of a scattering at b (`scattered_at_b`), or the probability of passing b. The channel is
    /// chosen uniformly, independent of the path, so the density is the mean over channels (the
    /// one-sample balance heuristic over the three channels' samplers): p(t) = ⅓ Σ_c σt,c T_c(t),
    /// P(pass) = ⅓ Σ_c T_c(t).
    pub fn free_flight_density(&self, a: Vec3, b: Vec3, scattered_at_b: bool) -> f32 {
        let tr = self.transmittance(a, b);
        let per_channel = if scattered_at_b {
            self.sigma_t(b) * tr
        } else {
            tr
        };
        mean(per_channel)
    }

    /// Samples where a ray from `o` along unit `d` first scatters before `t_max` (or passes).
    pub fn sample_free_flight(
        &self,
        o: Vec3,
        d: Vec3,
        t_max: f32,
        sampler: &mut Sampler,
    ) -> FreeFlight {
        match self {
            Medium::Homogeneous(_) => {
                let t = self.sample_flight_distance(sampler).expect("homogeneous");
                self.end_free_flight(o, d, t, t_max)
            }
            Medium::Grid(g) => g.sample_free_flight(o, d, t_max, sampler),
        }
    }

    /// A homogeneous medium's free-flight distance, drawn before the surface ahead is known (its
    /// draws do not depend on `t_max`); `end_free_flight` then compares it with the surface's
    /// distance. The two are `sample_free_flight` split in two, bit for bit, so a walk may look
    /// for a surface only up to the sampled distance (as Mitsuba's `volpath` does in homogeneous
    /// media). `None` (nothing drawn) for a grid, whose tracking steps stop at `t_max`.
    pub fn sample_flight_distance(&self, sampler: &mut Sampler) -> Option<f32> {
        match self {
            Medium::Homogeneous(h) => {
                let channel = ((sampler.next_f32() * 3.0) as usize).min(2);
                let sigma = h.sigma_t[channel];
                let u = sampler.next_f32();
                Some(if sigma > 0.0 {
                    -(1.0 - u).ln() / sigma
                } else {
                    f32::INFINITY
                })
            }
            Medium::Grid(_) => None,
        }
    }

    /// The outcome of a homogeneous free flight of sampled length `t` (`sample_flight_distance`)
    /// towards a surface at `t_max`: scattered at `t` before it, or passed to it.
    pub fn end_free_flight(&self, o: Vec3, d: Vec3, t: f32, t_max: f32) -> FreeFlight {
        if t < t_max {
            let x = o + d * t;
            let p = self.free_flight_density(o, x, true);
            FreeFlight::Scattered {
                t,
                weight: weigh(self.sigma_s(x) * self.transmittance(o, x), p),
            }
        } else {
            let x = o + d * t_max;
            let p = self.free_flight_density(o, x, false);
            FreeFlight::Passed {
                weight: weigh(self.transmittance(o, x), p),
            }
        }
    }

    /// An unbiased estimate of T(a, b) for shadow rays and connections (exact for homogeneous
    /// media; the grid's estimator otherwise, ratio tracking by default).
    pub fn transmittance_estimate(&self, a: Vec3, b: Vec3, sampler: &mut Sampler) -> Color {
        match self {
            Medium::Homogeneous(h) => h.transmittance(a.distance(b)),
            Medium::Grid(g) => g.transmittance_estimate(a, b, sampler),
        }
    }

    /// The homogeneous medium, for estimators that need σt, σs and T in closed form (photon
    /// beams).
    pub fn as_homogeneous(&self) -> Option<&Homogeneous> {
        match self {
            Medium::Homogeneous(h) => Some(h),
            Medium::Grid(_) => None,
        }
    }
}

impl Homogeneous {
    #[inline]
    pub fn sigma_s(&self) -> Color {
        self.sigma_t * self.albedo
    }

    /// T over a distance, per channel (1 in a channel with σt = 0 even over an infinite
    /// distance, where σt·d would be NaN).
    #[inline]
    pub fn transmittance(&self, distance: f32) -> Color {
        let depth = self.sigma_t * distance;
        exp_neg(Color::select(
            self.sigma_t.cmpeq(Color::ZERO),
            Color::ZERO,
            depth,
        ))
    }
}

/// `value / density`, or zero where the density underflowed (an outcome of probability zero in
/// f32, whose contribution is zero too).
#[inline]
fn weigh(value: Color, density: f32) -> Color {
    if density > 0.0 {
        value / density
    } else {
        Color::ZERO
    }
}

fn exp_neg(x: Color) -> Color {
    Color::new((-x.x).exp(), (-x.y).exp(), (-x.z).exp())
}

fn mean(c: Color) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

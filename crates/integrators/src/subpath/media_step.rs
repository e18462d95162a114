//! The two steps every walk through participating media takes, whatever it builds: `pt`'s and
//! `light`'s (`crate::media`) and the bidirectional subpath tracer (`media_walk`). Scattering at
//! a medium vertex samples the phase function and plays Russian roulette, as `walk::continue_path`
//! does at a surface; a `null` boundary is crossed without a vertex, switching to the medium on
//! its far side (Mitsuba's per-ray medium, `lt_core::scene::media`).

use super::walk::{russian_roulette, WalkRules};
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::medium::{MediumId, PhaseFunction, PhaseSample};
use lt_core::sampling::Sampler;
use lt_core::scene::SurfaceHit;
use lt_core::Scene;

/// More null crossings than this on one segment is a ray caught in a degenerate spot: it ends.
const MAX_NULL_CROSSINGS: u32 = 1024;

/// Continues a walk at a medium vertex, arrived at along −`wo`, by sampling `phase`: multiplies
/// the throughput by value / pdf (1 for the exactly sampled phase functions, kept general) and
/// plays Russian roulette (`depth` segments so far). `None` ends the walk.
#[inline]
pub fn scatter_in_medium(
    phase: PhaseFunction,
    wo: Vec3,
    rules: &WalkRules,
    beta: &mut Color,
    depth: u32,
    sampler: &mut Sampler,
) -> Option<PhaseSample> {
    let ps = phase.sample(wo, sampler.next_2d())?;
    *beta *= ps.value / ps.pdf;
    russian_roulette(beta, rules.rr_reference, depth, rules.rr_depth, sampler).then_some(ps)
}

/// The null crossings of the segment being walked: each one bumps the count, and too many end
/// the walk.
#[derive(Clone, Copy, Default)]
pub struct NullCrossings(u32);

impl NullCrossings {
    /// A segment begins (at a real vertex): no crossings yet.
    #[inline]
    pub fn reset(&mut self) {
        self.0 = 0;
    }

    /// Crosses the null boundary `hit` that `ray` reached: the ray goes on past it, straight, in
    /// the medium on its far side. False when the segment has crossed too many (the walk ends).
    #[inline]
    pub fn cross(
        &mut self,
        scene: &Scene,
        hit: &SurfaceHit,
        ray: &mut Ray,
        medium: &mut Option<MediumId>,
    ) -> bool {
        if !self.count() {
            return false;
        }
        *medium = scene.medium_after(hit.interface, hit.ng, ray.d, *medium);
        *ray = hit.spawn_ray(ray.d);
        true
    }

    /// Counts a null event the walk crossed itself (a pane passed); false when too many.
    #[inline]
    pub fn count(&mut self) -> bool {
        self.0 += 1;
        self.0 <= MAX_NULL_CROSSINGS
    }
}

//! Mitsuba's `null`: an index-matched boundary that only separates two media.
//!
//! It is a material, so that a scene file gives it where it gives every BSDF and a shape keeps one
//! material id; but it is not a scatterer, and the scene resolves it once into a shape property
//! (`Shape::null`), because what reads it is the ray query, not the shading code: a media-aware
//! walk and every transmittance query pass through a null shape without a vertex, changing the
//! medium by the side they leave it on (`Scene::medium_across`). Were it a path vertex, a
//! connection could never cross it (a delta vertex joins nothing) and next-event estimation into
//! a fog bank would be impossible.
//!
//! A walk that knows no media still sees a hit; it then scatters here as Mitsuba's `null` bounces:
//! a pass-through delta lobe ω_i = −ω_o of weight one in both transport modes (as `mask` with
//! opacity 0), so such a walk renders a null-bounded shape as invisible.

use super::{LocalBsdf, LocalSample, TransportMode};
use crate::math::{Color, Vec2, Vec3};

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Null;

impl LocalBsdf for Null {
    fn sample(
        &self,
        wo: Vec3,
        _u_lobe: f32,
        _u: Vec2,
        _mode: TransportMode,
    ) -> Option<LocalSample> {
        Some(LocalSample {
            wi: -wo,
            weight: Color::ONE,
            pdf_w: 1.0,
            pdf_rev_w: 1.0,
            delta: true,
        })
    }
    fn eval(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> Color {
        Color::ZERO
    }
    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }
    fn is_delta(&self) -> bool {
        true
    }
}

/// The sampling tests' null BSDFs: none (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Null {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        // Nothing to sample: it scatters nothing, and paths pass it before any BSDF is asked.
        vec![]
    }
}

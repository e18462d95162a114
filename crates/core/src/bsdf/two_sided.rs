//! Mitsuba 3's `twosided` around a one-sided material: the same BSDF on both sides. A direction
//! pair below the shading surface is mirrored through it (z → −z) to the front, evaluated or
//! sampled there, and mirrored back; the back is then the front seen in a mirror, as in Mitsuba
//! (which also flips the frame for the back face).

use super::{LocalBsdf, LocalSample, Material, TransportMode};
use crate::math::{Color, Vec2, Vec3};

#[derive(Clone, Debug)]
pub struct TwoSided {
    pub inner: Box<Material>,
}

/// `v` mirrored to the front when `back`.
#[inline]
fn front(v: Vec3, back: bool) -> Vec3 {
    if back {
        Vec3::new(v.x, v.y, -v.z)
    } else {
        v
    }
}

impl LocalBsdf for TwoSided {
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<LocalSample> {
        let back = wo.z < 0.0;
        let s = self
            .inner
            .local()
            .sample(front(wo, back), u_lobe, u, mode)?;
        Some(LocalSample {
            wi: front(s.wi, back),
            ..s
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Color {
        let back = wo.z < 0.0;
        self.inner
            .local()
            .eval(front(wo, back), front(wi, back), mode)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let back = wo.z < 0.0;
        self.inner.local().pdf(front(wo, back), front(wi, back))
    }

    fn is_delta(&self) -> bool {
        self.inner.local().is_delta()
    }
}

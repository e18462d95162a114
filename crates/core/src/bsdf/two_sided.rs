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

/// Any local BSDF seen from both sides: the front's lobes mirrored through the surface for a
/// `wo` below it. `TwoSided` is this around its inner material; a textured two-sided material
/// puts it around its resolved inner material on the stack.
pub(super) struct FrontFacing<'a>(pub &'a dyn LocalBsdf);

impl LocalBsdf for FrontFacing<'_> {
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<LocalSample> {
        let back = wo.z < 0.0;
        let s = self.0.sample(front(wo, back), u_lobe, u, mode)?;
        Some(LocalSample {
            wi: front(s.wi, back),
            ..s
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Color {
        let back = wo.z < 0.0;
        self.0.eval(front(wo, back), front(wi, back), mode)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let back = wo.z < 0.0;
        self.0.pdf(front(wo, back), front(wi, back))
    }

    fn is_delta(&self) -> bool {
        self.0.is_delta()
    }

    fn has_delta_lobe(&self) -> bool {
        self.0.has_delta_lobe()
    }
}

impl LocalBsdf for TwoSided {
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<LocalSample> {
        FrontFacing(self.inner.local()).sample(wo, u_lobe, u, mode)
    }

    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Color {
        FrontFacing(self.inner.local()).eval(wo, wi, mode)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        FrontFacing(self.inner.local()).pdf(wo, wi)
    }

    fn is_delta(&self) -> bool {
        self.inner.local().is_delta()
    }

    fn has_delta_lobe(&self) -> bool {
        self.inner.local().has_delta_lobe()
    }
}

/// The sampling tests' two-sided materials (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for TwoSided {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        use super::microfacet::MicrofacetType::Ggx;
        use super::test_registry::*;
        let two_sided = |inner| {
            Material::TwoSided(TwoSided {
                inner: Box::new(inner),
            })
        };
        vec![
            (
                "twosided-roughplastic-ggx-0.3",
                two_sided(rough_plastic(Ggx, 0.3, true, false)),
            ),
            (
                "twosided-roughconductor-ggx-0.3",
                two_sided(rough_gold(Ggx, 0.3, 0.3, true)),
            ),
        ]
    }
}

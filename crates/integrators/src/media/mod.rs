//! The walks of `pt`, `pt-bsdf` and `light` through participating media (issue 43, item 4), kept
//! apart from the surface walks: `pt.rs`, `pt_bsdf.rs` and `light.rs` branch here once per pass
//! on `Scene::has_media`, so a scene without media runs the old code, bit for bit and at its speed.
//!
//! The structure is Mitsuba 3's `volpath`: in the medium the ray is in (Mitsuba's per-ray medium,
//! `lt_core::scene::media`), free-flight sampling (`Medium::sample_free_flight`) either scatters
//! at a real collision — a medium vertex, which counts toward `max_depth` as a surface vertex
//! does — or passes to the next surface. A `null` surface is crossed without a bounce (it does not
//! count toward `max_depth`), the medium switching to the one on its far side. Shadow rays and
//! camera connections are worth an unbiased transmittance estimate through null boundaries and
//! media (`Scene::transmittance_estimate`), zero where an opaque surface blocks.
//!
//! MIS between next-event estimation and BSDF/phase sampling weighs the two by their solid-angle
//! direction densities at the vertex only (as `volpath` does): both techniques' estimates of the
//! transmittance along the shared last segment are unbiased, so any partition of unity over the
//! directions keeps the sum unbiased.

pub mod light;
pub mod pt;

use lt_core::light::LightLiSample;
use lt_core::math::Vec3;
use lt_core::scene::{ConnectionEnd, SurfaceHit};
use lt_core::Scene;

/// A shadow ray's or connection's end at a surface hit.
pub fn surface_end(hit: &SurfaceHit) -> ConnectionEnd {
    ConnectionEnd {
        p: hit.p,
        p_err: hit.p_err,
        ng: hit.ng,
        infinite: false,
    }
}

/// A point inside a medium (no surface: no normal, the scene's default error bound).
pub fn point_end(p: Vec3) -> ConnectionEnd {
    ConnectionEnd {
        p,
        p_err: Vec3::ZERO,
        ng: Vec3::ZERO,
        infinite: false,
    }
}

/// The light end of a next-event shadow ray: the sampled point (with its normal unless the light
/// is a delta), or the direction for a light at infinity.
pub fn light_end(ls: &LightLiSample) -> ConnectionEnd {
    if !ls.distance.is_finite() {
        return ConnectionEnd {
            p: ls.wi,
            p_err: Vec3::ZERO,
            ng: Vec3::ZERO,
            infinite: true,
        };
    }
    ConnectionEnd {
        p: ls.p,
        p_err: ls.p_err,
        ng: if ls.delta { Vec3::ZERO } else { ls.n },
        infinite: false,
    }
}

/// Whether the surface hit is a `null` boundary (crossed, never scattered at).
#[inline]
pub fn is_null(scene: &Scene, hit: &SurfaceHit) -> bool {
    scene.shapes[hit.shape as usize].null
}

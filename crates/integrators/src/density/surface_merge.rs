//! Surface vertex merging's kernel at one camera vertex, shared by the VCM engine and `upbp`:
//! which stored light vertices may merge at a camera surface vertex z (the side tests) and the
//! BSDF of z evaluated with the light vertex's incoming direction. The value of a merge is
//! β_z f(ω_z, ω_y) |cos| β_y / |n_y · ω_y| over the kernel's normalisation (M π r²), which each
//! caller applies with its own MIS weight.

use lt_core::bsdf::{BsdfEval, Material, ShadingFrame, TransportMode};
use lt_core::math::Vec3;
use lt_core::path::{PathVertex, VertexKind};
use lt_core::Scene;

/// A camera surface vertex z ready to merge: its shading frame and material, formed once per
/// vertex.
pub struct SurfaceGather<'a> {
    z: &'a PathVertex,
    sf: ShadingFrame,
    bsdf: &'a Material,
    /// n_g · ω_o at z: the side the camera looks from.
    wo_side: f32,
    transmits: bool,
}

impl<'a> SurfaceGather<'a> {
    /// The gather at `z`, or None when z is no surface vertex.
    pub fn at(scene: &'a Scene, z: &'a PathVertex) -> Option<SurfaceGather<'a>> {
        let VertexKind::Surface { material } = z.kind else {
            return None;
        };
        let bsdf = scene.material(material);
        Some(SurfaceGather {
            z,
            sf: z.shading_frame(),
            bsdf,
            wo_side: z.ng.dot(z.wo),
            transmits: bsdf.transmits(),
        })
    }

    /// z's BSDF (radiance mode) towards a light vertex's incoming direction `wi` (unit, towards
    /// y_{i−1}), `ng` its geometric normal and `cos_g` = |ng · wi|; None when the merge is
    /// refused or carries nothing.
    ///
    /// The light must arrive on the side the camera looks from (a thin wall lit from behind
    /// stays dark in front), not along the light vertex's own surface, and on the same side of
    /// its own surface (front or back, by the shapes' normals) as the camera looks at z: light
    /// stored on the sunlit outside of a wall is never merged at the inner surface meeting that
    /// wall at an edge (the leak the SmallVCM sun twin showed), while merges across an inner
    /// corner stay. Through a surface that transmits, the light may arrive on the side facing
    /// away from the camera; it must still arrive on the same side of its own surface as of z's.
    #[inline]
    pub fn eval(&self, wi: Vec3, ng: Vec3, cos_g: f32) -> Option<BsdfEval> {
        let z = self.z;
        let y_front = ng.dot(wi) > 0.0;
        let arrives_front = z.ng.dot(wi) > 0.0;
        let same_side = z.ng.dot(wi) * self.wo_side > 0.0;
        if !(same_side || self.transmits) || !(cos_g > 0.0) || y_front != arrives_front {
            return None;
        }
        let ev = self.bsdf.eval(&self.sf, z.wo, wi, TransportMode::Radiance);
        (ev.f_cos != lt_core::math::Color::ZERO).then_some(ev)
    }
}

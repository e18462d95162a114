//! Mitsuba 3's `normalmap` and `bumpmap`: a material seen through a shading normal that a texture
//! perturbs.
//!
//! The part that does not depend on directions — the perturbed normal n′ — is computed once where
//! the hit is made (`SurfaceHit::new` calls `Perturbed::normal`) and carried by every vertex as
//! its shading normal `ns`, so Veach's adjoint correction in `bsdf/mod.rs` (Veach 1997, §5.3) sees
//! it: that is what keeps light tracing, BDPT, photons and merging from rendering bump-mapped
//! surfaces "overly shiny" (pbrt-v4 #385/#526). The parts that depend on directions are applied
//! per query, as Mitsuba 3.9 does, relative to the unperturbed normal — here the geometric normal
//! `ng` (Mitsuba uses its interpolated shading normal: equal on analytic shapes and flat meshes,
//! within a facet's curvature on smooth meshes):
//! - `flip_invalid_normals`: when the camera-side direction lies below n′, n′ is mirrored about
//!   the unperturbed normal ((x, y, z) → (−x, −y, z) in its frame);
//! - `use_shadowing_function`: the BSDF is multiplied by the microfacet shadowing term of
//!   Estevez et al. 2019 ("A Microfacet-Based Shadowing Function to Solve the Bump Terminator
//!   Problem", Ray Tracing Gems ch. 12, eq. 2) of the light-side direction,
//!   G = 2 / (1 + √(1 + α² tan²θ)), α² = min(tan²θ_{n′} / 8, 1).
//!
//! Mitsuba decides both by its own query's directions (its `si.wi`, `wo`), which swap roles
//! between its path tracer and its particle tracer. Here they are fixed to the path's two sides —
//! the flip by the camera-side direction, the shadowing by the light-side one, in either transport
//! mode — so the BSDF is one function f(ω_camera, ω_light) and PT = LT = BDPT holds; in radiance
//! mode it is exactly Mitsuba's. Sampling always proposes with the frame the known direction
//! (`wo`) gives; where the camera-side direction's flip differs (importance mode only), the
//! weight is f / pdf of that proposal, and a delta inner lobe is dropped (its direction would need
//! the other frame).

use super::{BsdfEval, BsdfSample, Material, ShadingFrame, TransportMode};
use crate::math::{Frame, Vec2, Vec3};
use crate::texture::{TexPoint, Texture};

/// Where the perturbed normal comes from.
#[derive(Clone, Debug)]
pub enum NormalSource {
    /// Mitsuba's `normalmap`: RGB texels encode the normal in the shading frame (s, t, n) as
    /// (x + 1) / 2; (0.5, 0.5, 1) leaves the surface unchanged.
    NormalMap(Texture),
    /// Mitsuba's `bumpmap`: a height texture (its luminance) times `scale` displaces the surface
    /// along n; the normal is that of the displaced surface (Blinn 1978).
    BumpMap { height: Texture, scale: f32 },
}

#[derive(Clone, Debug)]
pub struct Perturbed {
    pub source: NormalSource,
    pub inner: Material,
    /// Mitsuba's `flip_invalid_normals` (default true).
    pub flip_invalid_normals: bool,
    /// Mitsuba's `use_shadowing_function` (default true).
    pub shadowing: bool,
}

impl Perturbed {
    /// The perturbed shading normal at a point with unperturbed shading normal `ns`, geometric
    /// normal `ng` (both unit, same side), surface tangents ∂p/∂u, ∂p/∂v and texture coordinates
    /// `uv`. The shading frame's first axis is ∂p/∂u made orthogonal to `ns`, as Mitsuba's.
    pub fn normal(&self, ng: Vec3, ns: Vec3, dpdu: Vec3, dpdv: Vec3, uv: TexPoint) -> Vec3 {
        let n = match &self.source {
            NormalSource::NormalMap(t) => {
                let c = t.eval(uv) * 2.0 - 1.0;
                let s = (dpdu - ns * ns.dot(dpdu)).try_normalize();
                let frame = match s {
                    Some(s) => Frame {
                        x: s,
                        y: ns.cross(s),
                        z: ns,
                    },
                    None => Frame::from_z(ns),
                };
                frame.to_world(c)
            }
            NormalSource::BumpMap { height, scale } => {
                let g = height.grad(uv.uv) * *scale;
                // Tangents of the displaced surface p + h n, with n's own variation neglected
                // (Mitsuba's choice): the in-plane parts of ∂p/∂u, ∂p/∂v plus ∂h along n.
                let du = dpdu + ns * (g.x - ns.dot(dpdu));
                let dv = dpdv + ns * (g.y - ns.dot(dpdv));
                du.cross(dv)
            }
        };
        match n.try_normalize() {
            Some(n) if n.dot(ng) < 0.0 => -n,
            Some(n) => n,
            None => ns,
        }
    }

    /// The shading frame a query uses: the perturbed normal, mirrored about `ng` when the
    /// camera-side direction `cam` lies below it (Mitsuba's `flip_invalid_normals`).
    #[inline]
    fn frame_for(&self, sf: &ShadingFrame, cam: Vec3) -> (ShadingFrame, bool) {
        let (n0, n) = (sf.ng, sf.ns());
        if self.flip_invalid_normals && n0.dot(cam) * n.dot(cam) <= 0.0 {
            let mirrored = (n0 * (2.0 * n0.dot(n)) - n).normalize();
            (
                ShadingFrame::oriented(sf.ng, mirrored, sf.tangent).with_uv(sf.uv),
                true,
            )
        } else {
            (*sf, false)
        }
    }

    /// Whether a query with camera-side direction `cam` flips the normal.
    #[inline]
    fn flips(&self, sf: &ShadingFrame, cam: Vec3) -> bool {
        self.flip_invalid_normals && sf.ng.dot(cam) * sf.ns().dot(cam) <= 0.0
    }

    /// The shadowing term of the light-side direction `light` (1 when switched off).
    #[inline]
    fn shadowing(&self, sf: &ShadingFrame, light: Vec3) -> f32 {
        if !self.shadowing {
            return 1.0;
        }
        let tan2 = |c: f32| (1.0 - c * c).max(0.0) / (c * c);
        let alpha2 = (0.125 * tan2(sf.ng.dot(sf.ns()))).min(1.0);
        let t = tan2(sf.ng.dot(light));
        if !t.is_finite() {
            return 0.0; // grazing the unperturbed surface
        }
        2.0 / (1.0 + (1.0 + alpha2 * t).sqrt())
    }

    pub(super) fn sample(
        &self,
        sf: &ShadingFrame,
        wo: Vec3,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        let (proposal, flipped_wo) = self.frame_for(sf, wo);
        let mut s = self.inner.sample(&proposal, wo, u_lobe, u, mode)?;
        let (cam, light) = sides(wo, s.wi, mode);
        let frame_wi_differs = self.flips(sf, s.wi) != flipped_wo;
        if frame_wi_differs {
            s.pdf_rev_w = self.inner.pdf(&self.frame_for(sf, s.wi).0, s.wi, wo);
        }
        if mode == TransportMode::Importance && frame_wi_differs {
            // f is defined with the camera side's (here wi's) frame, which the proposal was not.
            if s.delta {
                return None;
            }
            let f = self.inner.eval(&self.frame_for(sf, cam).0, wo, s.wi, mode);
            s.weight = f.f_cos / s.pdf_w;
        }
        s.weight *= self.shadowing(sf, light);
        (s.weight.is_finite() && s.weight.max_element() > 0.0).then_some(s)
    }

    pub(super) fn eval(
        &self,
        sf: &ShadingFrame,
        wo: Vec3,
        wi: Vec3,
        mode: TransportMode,
    ) -> BsdfEval {
        let (cam, light) = sides(wo, wi, mode);
        let (frame, flipped_cam) = self.frame_for(sf, cam);
        let mut e = self.inner.eval(&frame, wo, wi, mode);
        e.f_cos *= self.shadowing(sf, light);
        // The pdfs belong to the frames their conditioning directions give.
        if self.flips(sf, wo) != flipped_cam {
            e.pdf_w = self.inner.pdf(&self.frame_for(sf, wo).0, wo, wi);
        }
        if self.flips(sf, wi) != flipped_cam {
            e.pdf_rev_w = self.inner.pdf(&self.frame_for(sf, wi).0, wi, wo);
        }
        e
    }

    pub(super) fn pdf(&self, sf: &ShadingFrame, wo: Vec3, wi: Vec3) -> f32 {
        self.inner.pdf(&self.frame_for(sf, wo).0, wo, wi)
    }
}

/// (camera-side, light-side) directions of a query: radiance paths arrive from the camera
/// (`wo`), importance paths from the light.
#[inline]
fn sides(wo: Vec3, wi: Vec3, mode: TransportMode) -> (Vec3, Vec3) {
    match mode {
        TransportMode::Radiance => (wo, wi),
        TransportMode::Importance => (wi, wo),
    }
}

/// The sampling tests' normal-mapped materials: none (`test_registry`).
#[cfg(feature = "test-support")]
impl super::test_registry::Fixtures for Perturbed {
    fn fixtures() -> Vec<super::test_registry::Fixture> {
        // A normal or bump map needs a texture and a surface's uv; its frames are tested in
        // this file's tests and its images in the suite's normal-map scenes.
        vec![]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Diffuse;
    use crate::math::Color;

    fn flat_normal_map(rgb: Color) -> Perturbed {
        Perturbed {
            source: NormalSource::NormalMap(Texture::Constant(rgb)),
            inner: Material::Diffuse(Diffuse {
                albedo: Color::splat(0.8),
            }),
            flip_invalid_normals: true,
            shadowing: true,
        }
    }

    /// The identity normal map (0.5, 0.5, 1) changes nothing, and a tilted one tilts towards
    /// ∂p/∂u: (1, 0.5, 0.5) encodes the tangent s itself.
    #[test]
    fn normal_map_is_read_in_the_frame_of_dpdu() {
        let (ng, dpdu, dpdv) = (Vec3::Z, Vec3::new(2.0, 0.0, 0.3), Vec3::Y);
        let id = flat_normal_map(Color::new(0.5, 0.5, 1.0));
        assert!((id.normal(ng, ng, dpdu, dpdv, Default::default()) - ng).length() < 1e-6);
        let tilted = flat_normal_map(Color::new(0.5 + 0.5 * 0.6, 0.5, 0.5 + 0.5 * 0.8));
        let n = tilted.normal(ng, ng, dpdu, dpdv, Default::default());
        assert!((n - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-6, "{n}");
    }

    /// No shadowing at normal incidence or with the unperturbed normal; less towards grazing.
    #[test]
    fn shadowing_term_is_one_without_tilt_and_falls_towards_grazing() {
        let p = flat_normal_map(Color::new(0.5, 0.5, 1.0));
        let flat = ShadingFrame::new(Vec3::Z, Vec3::Z);
        let grazing = Vec3::new(0.99, 0.0, 0.141).normalize();
        assert_eq!(p.shadowing(&flat, grazing), 1.0);
        let tilted = ShadingFrame::new(Vec3::Z, Vec3::new(0.6, 0.0, 0.8));
        assert_eq!(p.shadowing(&tilted, Vec3::Z), 1.0);
        let g = p.shadowing(&tilted, grazing);
        assert!(g > 0.5 && g < 0.9, "{g}");
    }
}

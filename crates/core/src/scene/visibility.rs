//! Shadow rays between two points that both carry floating-point error bounds.
//!
//! Both ends are moved out of their error boxes towards each other (along the geometric normal
//! where there is one, as `offset_ray_origin` does for any spawned ray), and the ray stops a
//! further error box short of the moved target. Nothing here is a fixed epsilon: every margin is
//! a rounding bound, so the same code holds at millimetre scale, at 1e6 and far from the origin.

use super::{ray_stats, Scene, SurfaceHit};
use crate::geometry::packet::PACKET;
use crate::geometry::{offset_ray_origin, Ray};
use crate::math::{gamma, Vec3};

/// One end of a connection between two path vertices, as visibility needs it: a point with its
/// per-axis error bound and geometric normal, or (`infinite`) a unit direction towards a light at
/// infinity in `p`. The path module converts its vertices into these, so the scene knows no path.
#[derive(Clone, Copy, Debug)]
pub struct ConnectionEnd {
    pub p: Vec3,
    pub p_err: Vec3,
    pub ng: Vec3,
    pub infinite: bool,
}

/// A shadow query built but not yet traced: what `connection_visible` and `visible_light` trace,
/// split from the tracing so that a packet of queries can share the ray core's packet occlusion
/// query (`Scene::resolve_shadow_packet`, the lane-parallel `pt` and `light`).
#[derive(Clone, Copy, Debug)]
pub enum ShadowRay {
    /// Decided without tracing (true: visible).
    Known(bool),
    /// One ray towards a light at infinity: visible when nothing blocks it.
    Ray(Ray),
    /// A segment between finite ends: visible when nothing blocks the `whole` ray; if something
    /// does, the segment is traced again in two halves, from the moved a (`whole.o`) and from
    /// the moved b (`ob`), `len` being the distance between them.
    Segment { whole: Ray, ob: Vec3, len: f32 },
}

/// One end of a shadow ray: a point, its per-axis error bound and its geometric normal (zero when
/// it has none: a point light, a bare point).
#[derive(Clone, Copy, Debug)]
pub(super) struct End {
    pub(super) p: Vec3,
    pub(super) err: Vec3,
    ng: Vec3,
}

impl End {
    /// The point moved out of its error box to the side `w` points into. Without a normal it moves
    /// along `w` itself, which leaves the box just as surely.
    #[inline]
    pub(super) fn towards(&self, w: Vec3) -> Vec3 {
        let n = if self.ng == Vec3::ZERO {
            w.normalize_or_zero()
        } else {
            self.ng
        };
        offset_ray_origin(self.p, self.err, n, w)
    }
}

impl Scene {
    /// Error bound for a point that records none (a sampled light point, a caller's bare point):
    /// the rounding of a few operations on coordinates no larger than the scene's own. Translating
    /// the scene scales it with the coordinates, which is what keeps far-off scenes correct.
    fn default_error(&self, p: Vec3) -> Vec3 {
        let (lo, hi) = self.accel.bounds();
        (lo.abs().max(hi.abs()).max(p.abs())) * gamma(7)
    }

    pub(super) fn end(&self, p: Vec3, err: Vec3, ng: Vec3) -> End {
        let err = if err == Vec3::ZERO {
            self.default_error(p)
        } else {
            err
        };
        End { p, err, ng }
    }

    /// True when nothing blocks the segment between two finite ends. (Building and resolving are
    /// inlined here, and the public functions call this rather than resolving a built query, so
    /// the one-ray path carries no `ShadowRay`: measured, that cost scalar `pt` 0.6 % more
    /// instructions on the Cornell box.)
    fn segment_unoccluded(&self, a: End, b: End) -> bool {
        self.resolve_shadow(self.segment_shadow(a, b))
    }

    /// The shadow query of the segment between two finite ends: both ends moved out of their
    /// error boxes, the ray stopping short of b's (see `resolve_shadow` for the retry).
    #[inline(always)]
    fn segment_shadow(&self, a: End, b: End) -> ShadowRay {
        let ab = b.p - a.p;
        let (oa, ob) = (a.towards(ab), b.towards(-ab));
        let d = ob - oa;
        // Ends within each other's rounding (or non-finite input): nothing can be told to lie
        // between them.
        if !(d.dot(ab) > 0.0) {
            return ShadowRay::Known(d.is_finite());
        }
        let len = d.length();
        let dir = d / len;
        // Stop where the ray enters a box the size of b's error box around the moved target, less
        // the rounding of `len` itself.
        let t_max = (len - dir.abs().dot(b.err)) * (1.0 - gamma(2));
        if !(t_max > 0.0) {
            return ShadowRay::Known(true);
        }
        ShadowRay::Segment {
            whole: Ray {
                o: oa,
                d: dir,
                t_max,
            },
            ob,
            len,
        }
    }

    /// The answer to a shadow query, traced one ray at a time.
    #[inline(always)]
    fn resolve_shadow(&self, q: ShadowRay) -> bool {
        match q {
            ShadowRay::Known(visible) => visible,
            ShadowRay::Ray(ray) => {
                ray_stats::count_shadow();
                !self.accel.occluded(&ray)
            }
            ShadowRay::Segment { whole, ob, len } => {
                ray_stats::count_shadow();
                !self.accel.occluded(&whole) || self.halves_unoccluded(whole, ob, len)
            }
        }
    }

    /// A segment whose whole ray was blocked, traced again in two halves. What was hit may be a
    /// neighbour of b that b's rounding put b behind (b within its error box of an edge it shares
    /// with that surface): seen from b such a surface is rejected as the plane the ray leaves, but
    /// seen from a it is crossed, at a grazing angle possibly well before b's error box. So each
    /// half of the segment is traced from its own end, where that protection applies; the halves
    /// overlap by the rounding of `len`.
    fn halves_unoccluded(&self, whole: Ray, ob: Vec3, len: f32) -> bool {
        let half = 0.5 * len * (1.0 + gamma(2));
        ray_stats::count_shadow();
        if self.accel.occluded(&Ray {
            o: whole.o,
            d: whole.d,
            t_max: half,
        }) {
            return false;
        }
        ray_stats::count_shadow();
        !self.accel.occluded(&Ray {
            o: ob,
            d: -whole.d,
            t_max: half,
        })
    }

    /// True when nothing blocks the ray from a finite end in unit direction `dir` (unbounded).
    fn ray_unoccluded(&self, a: End, dir: Vec3) -> bool {
        self.resolve_shadow(Self::ray_shadow(a, dir))
    }

    /// The shadow query of the unbounded ray from a finite end in unit direction `dir`.
    #[inline(always)]
    fn ray_shadow(a: End, dir: Vec3) -> ShadowRay {
        if !(dir.length_squared() > 0.0) {
            return ShadowRay::Known(false);
        }
        ShadowRay::Ray(Ray::new(a.towards(dir), dir))
    }

    /// The answers to `PACKET` shadow queries (`Scene::connection_shadow`), each the one the
    /// scalar visibility functions give: the first rays
    /// through the ray core's packet occlusion query, a blocked segment's two halves per lane.
    pub fn resolve_shadow_packet(&self, q: &[ShadowRay; PACKET]) -> [bool; PACKET] {
        let rays: [Ray; PACKET] = std::array::from_fn(|i| match q[i] {
            ShadowRay::Ray(ray) | ShadowRay::Segment { whole: ray, .. } => ray,
            ShadowRay::Known(_) => Ray::new(Vec3::ZERO, Vec3::Z), // never traced
        });
        let traced: [bool; PACKET] = std::array::from_fn(|i| !matches!(q[i], ShadowRay::Known(_)));
        for _ in traced.iter().filter(|&&t| t) {
            ray_stats::count_shadow();
        }
        let blocked = self.accel.occluded_packet(&rays, &traced);
        std::array::from_fn(|i| match q[i] {
            ShadowRay::Known(visible) => visible,
            ShadowRay::Ray(_) => !blocked[i],
            ShadowRay::Segment { whole, ob, len } => {
                !blocked[i] || self.halves_unoccluded(whole, ob, len)
            }
        })
    }

    /// Visibility between two path vertices, either of which may sit at infinity (then `p` is
    /// the unit direction towards the light). Two vertices at infinity are never connected.
    pub fn connection_visible(
        &self,
        a: impl Into<ConnectionEnd>,
        b: impl Into<ConnectionEnd>,
    ) -> bool {
        // `connection_shadow` resolved, written out so the one-ray path builds no `ShadowRay`.
        let (a, b): (ConnectionEnd, ConnectionEnd) = (a.into(), b.into());
        match (a.infinite, b.infinite) {
            (true, true) => false,
            (true, false) => self.ray_unoccluded(self.end(b.p, b.p_err, b.ng), a.p),
            (false, true) => self.ray_unoccluded(self.end(a.p, a.p_err, a.ng), b.p),
            (false, false) => {
                self.segment_unoccluded(self.end(a.p, a.p_err, a.ng), self.end(b.p, b.p_err, b.ng))
            }
        }
    }

    /// `connection_visible` as a query to resolve (`resolve_shadow_packet`).
    pub fn connection_shadow(
        &self,
        a: impl Into<ConnectionEnd>,
        b: impl Into<ConnectionEnd>,
    ) -> ShadowRay {
        let (a, b): (ConnectionEnd, ConnectionEnd) = (a.into(), b.into());
        match (a.infinite, b.infinite) {
            (true, true) => ShadowRay::Known(false),
            (true, false) => Self::ray_shadow(self.end(b.p, b.p_err, b.ng), a.p),
            (false, true) => Self::ray_shadow(self.end(a.p, a.p_err, a.ng), b.p),
            (false, false) => {
                self.segment_shadow(self.end(a.p, a.p_err, a.ng), self.end(b.p, b.p_err, b.ng))
            }
        }
    }

    /// True when nothing blocks the segment from a surface point to a point `to` (a sampled light
    /// point; it is given the default error bound of a point computed in the scene's coordinates).
    #[inline]
    pub fn visible(&self, from: &SurfaceHit, to: Vec3) -> bool {
        self.segment_unoccluded(
            self.end(from.p, from.p_err, from.ng),
            self.end(to, Vec3::ZERO, Vec3::ZERO),
        )
    }

    /// True when nothing blocks the segment from a surface point to a point next-event estimation
    /// sampled on a light, whose own error bound and normal move that end off the light's
    /// surface. (With a bare point instead, a target on a curved emitter seen at a grazing angle
    /// from nearby — a sphere light from a point on its own surface — is spuriously occluded by
    /// the emitter itself.)
    #[inline]
    pub fn visible_light(&self, from: &SurfaceHit, ls: &crate::light::LightLiSample) -> bool {
        if !ls.distance.is_finite() {
            return self.unoccluded_towards(from, ls.wi);
        }
        let n = if ls.delta { Vec3::ZERO } else { ls.n };
        self.segment_unoccluded(
            self.end(from.p, from.p_err, from.ng),
            self.end(ls.p, ls.p_err, n),
        )
    }

    /// True when nothing blocks the ray leaving a surface point in direction `dir` (a distant light).
    #[inline]
    pub fn unoccluded_towards(&self, from: &SurfaceHit, dir: Vec3) -> bool {
        self.ray_unoccluded(self.end(from.p, from.p_err, from.ng), dir)
    }

    /// Visibility between two bare points (no normals; both get the default error bound).
    pub fn visible_between(&self, a: Vec3, b: Vec3) -> bool {
        self.segment_unoccluded(
            self.end(a, Vec3::ZERO, Vec3::ZERO),
            self.end(b, Vec3::ZERO, Vec3::ZERO),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Diffuse, Material};
    use crate::camera::{Camera, FovAxis};
    use crate::math::Color;
    use crate::sampling::Sampler;
    use crate::scene::{RenderSettings, SceneBuilder, ShapeGeometry, TriangleMesh};

    /// Parallelograms p0 + u·e1 + v·e2 (normal e1 × e2), each as the two-triangle mesh the loader
    /// makes of a quad.
    fn scene(quads: &[(Vec3, Vec3, Vec3)]) -> Scene {
        let cam =
            Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, 4, 4).unwrap();
        let mut b = SceneBuilder::new(cam, RenderSettings::default());
        let m = b.add_material(Material::Diffuse(Diffuse {
            albedo: Color::splat(0.5),
        }));
        for &(p0, e1, e2) in quads {
            let mesh = TriangleMesh {
                positions: vec![p0, p0 + e1, p0 + e1 + e2, p0 + e2],
                normals: None,
                uvs: None,
                indices: vec![[0, 1, 2], [0, 2, 3]],
                attributes: Vec::new(),
            };
            b.add_shape(ShapeGeometry::Mesh(mesh), m, None, false);
        }
        b.build()
    }

    /// The surface vertex where the ray from `from` towards `target` first hits, with the error
    /// bound the intersection code gives it (only the fields visibility reads matter here).
    fn try_vertex(s: &Scene, from: Vec3, target: Vec3) -> Option<ConnectionEnd> {
        let h = s.intersect(&Ray::new(from, (target - from).normalize()))?;
        Some(ConnectionEnd {
            p: h.p,
            p_err: h.p_err,
            ng: h.ng,
            infinite: false,
        })
    }

    fn vertex(s: &Scene, from: Vec3, target: Vec3) -> ConnectionEnd {
        try_vertex(s, from, target)
            .unwrap_or_else(|| panic!("{from} towards {target} hits nothing"))
    }

    fn at_infinity(dir: Vec3) -> ConnectionEnd {
        ConnectionEnd {
            p: dir,
            p_err: Vec3::ZERO,
            ng: Vec3::ZERO,
            infinite: true,
        }
    }

    #[test]
    fn facing_quads_see_each_other_and_a_third_quad_blocks() {
        let floor = (Vec3::ZERO, Vec3::Z, Vec3::X); // normal +y
        let ceiling = (Vec3::Y, Vec3::X, Vec3::Z); // normal −y
        let open = scene(&[floor, ceiling]);
        let blocker = (Vec3::new(0.25, 0.5, 0.25), Vec3::Z * 0.5, Vec3::X * 0.5);
        let blocked = scene(&[floor, ceiling, blocker]);
        let mut s = Sampler::new(3, 0, 0);
        let mid = Vec3::new(0.5, 0.3, 0.5);
        let mid_high = Vec3::new(0.5, 0.7, 0.5);
        for _ in 0..2000 {
            let (u, v) = (s.next_f32(), s.next_f32());
            let (x, z) = (0.3 + 0.4 * u, 0.3 + 0.4 * v);
            for sc in [&open, &blocked] {
                let a = vertex(sc, mid, Vec3::new(x, 0.0, z));
                let b = vertex(sc, mid_high, Vec3::new(1.0 - x, 1.0, 1.0 - z));
                let expect = std::ptr::eq(sc, &open);
                assert_eq!(sc.connection_visible(a, b), expect, "{a:?} {b:?}");
                assert_eq!(sc.connection_visible(b, a), expect);
                // Straight up from the floor: the ceiling always blocks, nothing below it.
                assert!(!sc.connection_visible(a, at_infinity(Vec3::Y)));
                assert!(!sc.connection_visible(at_infinity(Vec3::Y), a));
            }
        }
        // Without a ceiling the sky is visible from the floor.
        let floor_only = scene(&[floor]);
        let a = vertex(&floor_only, mid, Vec3::new(0.5, 0.0, 0.5));
        assert!(floor_only.connection_visible(a, at_infinity(Vec3::Y)));
    }

    /// A floor and a wall sharing an edge, and a second wall touching the floor only at a corner;
    /// points on them near the edge and corner are connected (all inside the convex region the
    /// surfaces bound, so every connection is visible). A fixed epsilon fails at one end of the
    /// scale range or the other; an error bound that ignores the translation fails far away.
    fn touching_surfaces_do_not_occlude(scale: f32, shift: Vec3) {
        // Tilted off the axes, so no plane is exact in floating point.
        let r = glam::Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.6);
        let p = |x: f32, y: f32, z: f32| r * Vec3::new(x, y, z) * scale + shift;
        let (ex, ey, ez) = (
            r * Vec3::X * scale,
            r * Vec3::Y * scale,
            r * Vec3::Z * scale,
        );
        let floor = (p(0.0, 0.0, 0.0), ez, ex); // y = 0, normal +y
        let wall = (p(0.0, 0.0, 0.0), ey, ez); // x = 0, normal +x
        let corner_wall = (p(0.0, 0.0, -1.0), ey, ez); // x = 0, z ∈ [−1, 0]
        let sc = scene(&[floor, wall, corner_wall]);
        // Query points in the scene's internal coordinates (exact: Sterbenz, see `Scene::origin`).
        let world = p;
        let p = |x: f32, y: f32, z: f32| world(x, y, z) - sc.origin;
        let mut s = Sampler::new(5, scale.to_bits() as u64, shift.x.to_bits() as u64);
        let inside = p(0.5, 0.5, 0.5);
        let mut tested = 0;
        for _ in 0..4000 {
            // Distances from the edge spread over six decades, down to the rounding level.
            let near = |s: &mut Sampler| 10f32.powf(-6.0 * s.next_f32());
            let (d1, d2, w) = (near(&mut s), near(&mut s), s.next_f32());
            // Targets closer to an open boundary than the coordinates' rounding may round onto it
            // and be missed; those pairs are skipped.
            let on_floor = try_vertex(&sc, inside, p(d1, 0.0, w));
            let on_wall = try_vertex(&sc, inside, p(0.0, d2, 1.0 - w));
            // Near the corner: the floor near (0, 0, 0) and the corner wall near (0, 0, −0).
            let near_corner = try_vertex(&sc, inside, p(d1, 0.0, d2));
            let on_corner_wall = try_vertex(&sc, p(0.5, 0.5, -0.5), p(0.0, d2, -d1));
            for pair in [(on_floor, on_wall), (near_corner, on_corner_wall)] {
                let (Some(a), Some(b)) = pair else { continue };
                // Only pairs the rays put on two different surfaces count.
                if a.ng.dot(b.ng).abs() > 0.5 {
                    continue;
                }
                tested += 1;
                assert!(
                    sc.connection_visible(a, b) && sc.connection_visible(b, a),
                    "scale {scale}, shift {shift}: {a:?} to {b:?} occluded"
                );
            }
        }
        // Far from the origin about a third of the targets round onto an open boundary.
        assert!(tested > 4000, "only {tested} pairs tested");
    }

    #[test]
    fn surfaces_touching_at_an_edge_or_corner_do_not_occlude_at_any_scale_or_place() {
        for scale in [1e-3, 1.0, 1e6] {
            touching_surfaces_do_not_occlude(scale, Vec3::ZERO);
        }
        touching_surfaces_do_not_occlude(1.0, Vec3::splat(1e4));
    }
}

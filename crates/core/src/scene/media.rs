//! Participating media as the scene sees them: which medium a ray is in, and what a segment
//! between two points passes through.
//!
//! **How the medium of a ray is tracked: Mitsuba's per-ray medium.** Each shape names the medium
//! inside it and the one outside (`MediumInterface`; the exterior is the side its geometric normal
//! faces, after `flip_normals`), the camera and each light the medium they sit in. A ray leaving a
//! surface is in the medium on the side it leaves into, a ray leaving a medium vertex in that
//! vertex's medium, and crossing a `null` boundary switches to the medium on the far side
//! (`MediumInterface::towards`). So the medium of every segment is a function of one end vertex
//! and the direction, never of the path's history: the light walk and the camera walk use the
//! same rule and agree by construction, a connection between any two subpath vertices knows its
//! medium from either end, the from-scratch oracle recomputes it, and a vertex carries it in two
//! bytes (`PathVertex::interface`). SmallUPBP's boundary stack with priorities instead carries the
//! history (which boundaries were entered), which must then travel with every vertex and be merged
//! at every connection; what it buys — overlapping media resolved by priority without saying what
//! is outside — is had here by declaring the exterior: a medium nested in another names the outer
//! medium as its exterior, and a medium inside glass is the dielectric's interior (its exterior the
//! air or fog around it), which is Mitsuba's convention and so its test scenes'.
//!
//! **A shape that declares no media** (interface 0) is no medium transition (Mitsuba's
//! `is_medium_transition`): a ray leaving it stays in the medium it arrived in
//! ([`Scene::medium_after`]), so an object placed inside fog without naming the fog reflects in
//! it (the suite's obj_inside_medium, emitter_inside_medium, and the hetero scenes' floor poking
//! into the cube). Only there does the rule read the arriving medium: a walk knows it, a vertex on
//! such a shape has the same medium on both sides.
//!
//! **A thin dielectric's pass-through is a null event** in a scene with media, as in Mitsuba's
//! `volpath` (its transmission lobe is `BSDFFlags::Null`: the direction is kept). This is one
//! path-space decision, read by every walk through media and by the oracle: a pane passed is no
//! vertex of the path and counts toward no `max_depth` ([`Scene::is_null_transmission`]; `pt`,
//! `light` and bdpt's subpaths cross it as they cross a null boundary, a pane that reflects is the
//! delta vertex it is), and a segment through it carries the pane's null transmission
//! (1 − R') · specular_transmittance in f and its pass probability 1 − R' in every walk density
//! (the walk samples the pass-through with that probability and weight `specular_transmittance`)
//! — [`PanesPassed`], which `connection_estimate`, `transmittance_estimate_past_panes`,
//! `edge_transmittance` and `free_flight_density` all take. Shadow rays and joins therefore pass
//! panes; the two techniques estimate the same and MIS pairs them from the last real vertex.
//! Surface scenes (no media) walk a pane as a delta vertex, as Mitsuba's `path` does.

use super::hit::BoundaryHit;
use super::SurfaceHit;
use super::{ConnectionEnd, Scene};
use crate::bsdf::Material;
use crate::geometry::{offset_ray_origin, segment_hits, PrimHit, Ray};
use crate::math::{gamma, Color, Vec3};
use crate::medium::MediumId;
use crate::sampling::Sampler;

/// Distinct (interior, exterior) pairs a scene's shapes may name, (none, none) included: a shape
/// keeps its pair's index in 16 bits (`Shape::interface`, copied into every hit and vertex).
pub const MAX_MEDIUM_INTERFACES: usize = u16::MAX as usize + 1;

/// The media on the two sides of a shape (Mitsuba's `interior` and `exterior`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct MediumInterface {
    pub interior: Option<MediumId>,
    pub exterior: Option<MediumId>,
}

impl MediumInterface {
    /// The medium on the side of a surface with geometric normal `ng` that `w` points into.
    #[inline]
    pub fn towards(&self, ng: Vec3, w: Vec3) -> Option<MediumId> {
        if ng.dot(w) > 0.0 {
            self.exterior
        } else {
            self.interior
        }
    }
}

/// One straight piece of a segment inside one medium (`None`: vacuum), from `a` to `b`.
#[derive(Clone, Copy, Debug)]
pub struct MediumPiece {
    pub medium: Option<MediumId>,
    pub a: Vec3,
    pub b: Vec3,
}

/// A connection's segment as one walk of it found it (`Scene::connection_estimate`).
#[derive(Clone, Copy, Debug)]
pub struct ConnectionFlight {
    /// An unbiased estimate of T(a, b).
    pub transmittance: Color,
    /// The free-flight density of a walk from a reaching b.
    pub a_to_b: f32,
    /// The free-flight density of a walk from b reaching a, through the media of the pieces
    /// walked from a: the right one only when `reversible` and b's medium towards a is
    /// `end_medium` (otherwise a walk from b crosses other media: `PathVertex::free_flight_to`).
    pub b_to_a: f32,
    /// Every boundary crossed, walked back, undoes itself (`PanesPassed::reversible`).
    pub reversible: bool,
    /// The medium of the last piece, at b.
    pub end_medium: Option<MediumId>,
}

/// What the thin dielectric panes a segment passes (as null events, module doc) do to it: the
/// product of their null transmissions (1 − R') · specular_transmittance, the factor of f, and of
/// their pass probabilities 1 − R', the factor of the density of every walk along the segment
/// (either way: R' depends on |cos θ| only).
#[derive(Clone, Copy, Debug)]
pub struct PanesPassed {
    pub transmission: Color,
    pub probability: f32,
    /// Whether every boundary crossed (null or pane) gives back the medium before it when crossed
    /// the other way. Per-ray media (Mitsuba's) are not reversible where two shapes naming media
    /// overlap: leaving one inside the other enters its exterior, so the segment walked backwards
    /// lies in other media and its free-flight density differs (`for_each_medium_piece`).
    pub reversible: bool,
}

impl PanesPassed {
    const NONE: PanesPassed = PanesPassed {
        transmission: Color::ONE,
        probability: 1.0,
        reversible: true,
    };
}

/// A surface a segment crosses (`Scene::boundary_crossings`).
#[derive(Clone, Copy, Debug)]
pub struct SegmentCrossing {
    pub p: Vec3,
    pub p_err: Vec3,
    pub shape: u32,
    /// The outward geometric normal.
    pub ng: Vec3,
    /// What passing it does, at a pane crossed with `panes`; else nothing.
    pub pane: PanesPassed,
}

/// Where the rays of a segment's crossings query start and stop (`Scene::boundary_crossings`).
struct SegmentWalk {
    /// The first ray's origin: `from` itself, or moved out of its error box when on a surface.
    start: Vec3,
    /// The direction from `from` towards `to`, not unit.
    dir0: Vec3,
    /// The point every ray aims at and its error box's depth along a unit direction (`to` moved
    /// out of its own box when on a surface); none towards a light at infinity.
    target: Option<(Vec3, Vec3)>,
}

impl SegmentWalk {
    fn new(scene: &Scene, from: ConnectionEnd, to: ConnectionEnd) -> SegmentWalk {
        let a = scene.end(from.p, from.p_err, from.ng);
        let b = (!to.infinite).then(|| scene.end(to.p, to.p_err, to.ng));
        let dir0 = match &b {
            Some(b) => b.p - a.p,
            None => to.p,
        };
        let on_surface = |e: &ConnectionEnd| e.ng != Vec3::ZERO;
        let start = if on_surface(&from) {
            a.towards(dir0)
        } else {
            a.p
        };
        let target = b.map(|b| {
            if on_surface(&to) {
                (b.towards(-dir0), b.err)
            } else {
                (b.p, Vec3::ZERO)
            }
        });
        SegmentWalk {
            start,
            dir0,
            target,
        }
    }

    /// The ray from `origin` to the target, stopping short of its error box (of a bare point, by
    /// the rounding of the length); None once `origin` is at or past it.
    fn ray_from(&self, origin: Vec3) -> Option<Ray> {
        let (d, t_max) = match self.target {
            Some((stop, err)) => {
                let d = stop - origin;
                if !(d.dot(self.dir0) > 0.0) {
                    return None;
                }
                let len = d.length();
                let dir = d / len;
                (dir, (len - dir.abs().dot(err)) * (1.0 - gamma(2)))
            }
            None => (self.dir0.normalize(), f32::INFINITY),
        };
        (t_max > 0.0).then_some(Ray {
            o: origin,
            d,
            t_max,
        })
    }
}

/// Where a segment towards a light at infinity is cut off: far enough that any positive σt
/// extinguishes it (T = 0, as over an infinite medium), representable in f32.
const FAR: f32 = 1e30;

/// More boundary crossings than this on one segment is a ray caught in a degenerate spot.
const MAX_CROSSINGS: usize = 1024;

/// A thread's buffers for the crossings of its segments, reused from one shadow ray to the next
/// (each was two or three allocations per shadow ray). Taken out while in use, so a nested use
/// would only allocate afresh.
#[derive(Default)]
struct Scratch {
    hits: Vec<PrimHit>,
    crossings: Vec<SegmentCrossing>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::default();
}

/// Which surfaces a segment walk passes: every one (the oracle, whose f excludes visibility:
/// an opaque surface is then a boundary like a null one, and V zeroes the edge anyway; a pane
/// passes as the null event it is), or null ones only (an opaque surface or a pane blocks), or
/// null ones and thin dielectric panes (the shadow rays and joins of the media walks, as
/// Mitsuba's `volpath` casts them: a pane passes as a null event, [`PanesPassed`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Crossing {
    Everything,
    NullOnly,
    NullAndPanes,
}

impl Scene {
    /// The medium on the side of a surface with interface `interface` and normal `ng` that `w`
    /// leaves into (0 is (none, none): no lookup needed without media).
    #[inline]
    pub fn medium_across(&self, interface: u16, ng: Vec3, w: Vec3) -> Option<MediumId> {
        self.interfaces[interface as usize].towards(ng, w)
    }

    /// The medium a ray is in after leaving (or crossing) a surface with interface `interface`
    /// along `w`, having arrived in `current`: the declared medium on that side, or `current`
    /// when the shape declares none (module doc).
    #[inline]
    pub fn medium_after(
        &self,
        interface: u16,
        ng: Vec3,
        w: Vec3,
        current: Option<MediumId>,
    ) -> Option<MediumId> {
        if interface == 0 {
            current
        } else {
            self.medium_across(interface, ng, w)
        }
    }

    /// The interface a surface vertex at a hit with interface `interface` carries when its walk
    /// arrived in `current`: the shape's own, or — for a shape that names no media, inside a
    /// medium m — the pair (m, m). The vertex then keeps the medium it sits in on both sides, so
    /// `PathVertex::medium_towards`, the joins and the oracle read the same medium as
    /// [`Scene::medium_after`] gives the walk, from either end of an edge.
    #[inline]
    pub fn interface_within(&self, interface: u16, current: Option<MediumId>) -> u16 {
        match current {
            Some(m) if interface == 0 => self.within_medium[m as usize],
            _ => interface,
        }
    }

    /// True when material `material` has a lobe Mitsuba's `volpath` counts as a null event (a
    /// plain `thindielectric`; a textured one is walked as any delta material): a sample there
    /// may not count toward `max_depth`, and the media walks' shadow rays pass it.
    #[inline]
    pub fn has_null_transmission(&self, material: u32) -> bool {
        matches!(self.material(material), Material::ThinDielectric(_))
    }

    /// What a thin dielectric pane at `hit` does to a segment passing it straight along `d`: its
    /// null transmission (Mitsuba's `eval_null_transmission`) (1 − R'(cos θ)) ·
    /// specular_transmittance and pass probability 1 − R'(cos θ), θ from the shading normal (the
    /// walk's lobe choice, `ThinDielectric::sample`); nothing passes any other material.
    pub fn pane_passed(&self, hit: &SurfaceHit, d: Vec3) -> PanesPassed {
        match self.material(hit.material) {
            Material::ThinDielectric(t) => {
                let cos = hit.shading_frame().ns().dot(d);
                let pass = 1.0 - t.reflectance(cos);
                PanesPassed {
                    transmission: t.specular_transmittance * pass,
                    probability: pass,
                    reversible: true,
                }
            }
            _ => PanesPassed {
                transmission: Color::ZERO,
                probability: 0.0,
                reversible: true,
            },
        }
    }

    /// True when a sample from `wo` to `wi` at a surface of material `material` with shading
    /// normal `ns` took that null lobe: a thin dielectric's transmission, the one lobe that
    /// leaves on the other side of the shading plane (its reflection mirrors about `ns`).
    #[inline]
    pub fn is_null_transmission(&self, material: u32, ns: Vec3, wo: Vec3, wi: Vec3) -> bool {
        self.has_null_transmission(material) && ns.dot(wo) * ns.dot(wi) < 0.0
    }

    /// The medium light `light` emits into from its point `at` along `w`: the one it was built
    /// with (a point or spot light's `medium`, an area light's exterior), except for an area light
    /// on a shape that names no media in a scene with media. That one emits into the medium around
    /// it, as a walk reaching it along −w finds it (`medium_after` keeps the arriving medium
    /// there): the first shape naming media along `w`, on the side facing back (vacuum when none;
    /// in a well-formed scene media are bounded by closed shapes). Per point and direction, not
    /// per light: an emitter may straddle a medium's boundary — the suite's emitter_inside_medium
    /// torus has 290 of its 1,160 vertices outside the fog sphere, and one medium for all of it
    /// (found once at build, as before) made light subpaths start in fog where camera walks reach
    /// the light in vacuum (bdpt mis-check: 5,165 of 19,201 paths failing).
    pub fn light_medium_towards(&self, light: u32, at: ConnectionEnd, w: Vec3) -> Option<MediumId> {
        let l = light as usize;
        match &self.lights[l] {
            crate::light::Light::Area(area)
                if self.has_media && self.shapes[area.shape as usize].interface == 0 =>
            {
                self.medium_around(Ray::new(offset_ray_origin(at.p, at.p_err, at.ng, w), w))
            }
            _ => self.light_media[l],
        }
    }

    /// The medium a ray starts in, judged by the first shape naming media that it reaches
    /// (vacuum when it reaches none).
    fn medium_around(&self, mut ray: Ray) -> Option<MediumId> {
        for _ in 0..MAX_CROSSINGS {
            let hit = self.intersect(&ray)?;
            let interface = self.shapes[hit.shape as usize].interface;
            if interface != 0 {
                return self.medium_across(interface, hit.ng, -ray.d);
            }
            ray = hit.spawn_ray(ray.d);
        }
        None
    }

    /// Cuts the segment a → b (either end may be at infinity, not both) into its pieces between
    /// boundaries, starting in `medium` at `a`, in order from `a`; `visit` sees each. Returns what
    /// the panes passed do to it (nothing unless `crossing` passes panes), or None (having visited
    /// the pieces before it) when a surface that `crossing` does not pass blocks.
    pub fn for_each_medium_piece(
        &self,
        a: ConnectionEnd,
        b: ConnectionEnd,
        medium: Option<MediumId>,
        crossing: Crossing,
        visit: impl FnMut(MediumPiece),
    ) -> Option<PanesPassed> {
        // Crossings are found from a finite end; from a light at infinity they are found from the
        // other end and walked backwards.
        let (from, to, reversed) = if a.infinite {
            (b, a, true)
        } else {
            (a, b, false)
        };
        let panes = crossing != Crossing::NullOnly;
        let mut crossings = SCRATCH.with(|s| std::mem::take(&mut s.borrow_mut().crossings));
        let walked = self.crossings_into(from, to, panes, false, &mut crossings);
        let through = walked
            .then(|| self.walk_pieces(&crossings, from, to, reversed, medium, crossing, visit));
        SCRATCH.with(|s| s.borrow_mut().crossings = crossings);
        through.flatten()
    }

    /// `for_each_medium_piece` over the segment's `crossings` (found from `from`).
    #[allow(clippy::too_many_arguments)]
    fn walk_pieces(
        &self,
        crossings: &[SegmentCrossing],
        from: ConnectionEnd,
        to: ConnectionEnd,
        reversed: bool,
        medium: Option<MediumId>,
        crossing: Crossing,
        mut visit: impl FnMut(MediumPiece),
    ) -> Option<PanesPassed> {
        let panes = crossing != Crossing::NullOnly;
        let dir = if to.infinite {
            to.p
        } else {
            (to.p - from.p).normalize()
        };
        let far = |p: Vec3, d: Vec3| p + d * FAR;
        let (start, end, d) = if reversed {
            (far(from.p, dir), from.p, -dir)
        } else if to.infinite {
            (from.p, far(from.p, dir), dir)
        } else {
            (from.p, to.p, dir)
        };
        let n = crossings.len();
        let (mut current, mut here, mut through) = (medium, start, PanesPassed::NONE);
        for k in 0..n {
            let c = &crossings[if reversed { n - 1 - k } else { k }];
            let (p, ng, pane) = (c.p, c.ng, c.pane);
            let s = &self.shapes[c.shape as usize];
            match crossing {
                _ if s.null => {}
                _ if panes && self.has_null_transmission(s.material) => {
                    through.transmission *= pane.transmission;
                    through.probability *= pane.probability;
                }
                Crossing::Everything => {}
                _ => return None,
            }
            visit(MediumPiece {
                medium: current,
                a: here,
                b: p,
            });
            let next = self.medium_after(s.interface, ng, d, current);
            through.reversible &= self.medium_after(s.interface, ng, -d, next) == current;
            current = next;
            here = p;
        }
        visit(MediumPiece {
            medium: current,
            a: here,
            b: end,
        });
        Some(through)
    }

    /// The surfaces strictly between `from` (finite) and `to`, in order from `from`, each with
    /// (with `panes`, at a thin dielectric) what passing the pane along the walk does, else
    /// nothing. `None` when the walk does not end (a degenerate spot).
    ///
    /// An end on a surface is left (and approached) from outside its error box, so that surface is
    /// not taken for a crossing. An end on no surface (no normal: a medium vertex, a point or spot
    /// light, a bare point) is left from and walked up to the point itself: that is how the walks
    /// trace from a scattering point (`Ray::new(x, w)`), so a boundary however close to it is
    /// crossed here as the walk crossed it. (With an error box there, a medium vertex 3.6e-6 inside
    /// a null face — within the box its bound accumulates along a walk — lost the face from the
    /// oracle's walk towards it: hg-spot's mis-check, results/media-mis-check.md.)
    ///
    /// One query of every hit on the segment (`Accel::all_hits`) where the ray core has it, else
    /// (`restart`, or obvhs's BVH and Embree) a closest-hit query restarted past each crossing
    /// (ARCHITECTURE.md, "Crossings in one query").
    pub fn boundary_crossings(
        &self,
        from: ConnectionEnd,
        to: ConnectionEnd,
        panes: bool,
        restart: bool,
    ) -> Option<Vec<SegmentCrossing>> {
        let mut found = Vec::new();
        self.crossings_into(from, to, panes, restart, &mut found)
            .then_some(found)
    }

    /// `boundary_crossings` into `found` (cleared first); false where that gives `None`. Its
    /// buffers are the thread's (`SCRATCH`), not allocated per shadow ray.
    fn crossings_into(
        &self,
        from: ConnectionEnd,
        to: ConnectionEnd,
        panes: bool,
        restart: bool,
        found: &mut Vec<SegmentCrossing>,
    ) -> bool {
        found.clear();
        let walk = SegmentWalk::new(self, from, to);
        let Some(ray) = walk.ray_from(walk.start) else {
            return true;
        };
        super::ray_stats::count_closest();
        if restart {
            return self.crossings_restarting(&walk, ray, panes, found);
        }
        let mut hits = SCRATCH.with(|s| std::mem::take(&mut s.borrow_mut().hits));
        let walked = self.crossings_from_hits(&walk, ray, panes, found, &mut hits);
        SCRATCH.with(|s| s.borrow_mut().hits = hits);
        walked
    }

    /// `crossings_into` from one every-hit query (into `hits`), where the ray core has it.
    fn crossings_from_hits(
        &self,
        walk: &SegmentWalk,
        ray: Ray,
        panes: bool,
        found: &mut Vec<SegmentCrossing>,
        hits: &mut Vec<PrimHit>,
    ) -> bool {
        if !self.accel.all_hits(&ray, hits) {
            return self.crossings_restarting(walk, ray, panes, found);
        }
        // The restart walk's next ray starts past the last crossing's error box
        // (`offset_ray_origin`) and finds what lies beyond that point. A hit of this ray near
        // it — the same crossing again (the neighbours at a shared edge or vertex) or another
        // surface within rounding — cannot be told apart by t, whose rounding is as large as
        // the offset (a few ulps of the coordinates). So from such a hit on, as from a curved
        // primitive's (whose test gives its nearest hit only), the restart walk goes on from the
        // last crossing: it is rare, and what happens there is then the restart walk's.
        let origin_scale = ray.o.abs().max_element();
        let (mut skip_to, mut next) = (0.0f32, walk.start);
        for &h in hits.iter() {
            let near = !found.is_empty() && h.t <= skip_to + gamma(16) * (origin_scale + h.t);
            if !near {
                let crossing = self.crossing_at(&ray, h, panes);
                next = offset_ray_origin(crossing.p, crossing.p_err, crossing.ng, ray.d);
                skip_to = (next - ray.o).dot(ray.d);
                found.push(crossing);
                if found.len() == MAX_CROSSINGS {
                    return false;
                }
            }
            if near || segment_hits::may_hit_again(self.accel.primitive(h.prim)) {
                let Some(ray) = walk.ray_from(next) else {
                    return true;
                };
                super::ray_stats::count_closest();
                return self.crossings_restarting(walk, ray, panes, found);
            }
        }
        true
    }

    /// `boundary_crossings` by a closest-hit query per crossing, each restarted past the last
    /// crossing's error box and re-aimed at the end; `ray` is the first query's, already counted.
    fn crossings_restarting(
        &self,
        walk: &SegmentWalk,
        mut ray: Ray,
        panes: bool,
        found: &mut Vec<SegmentCrossing>,
    ) -> bool {
        loop {
            let Some(prim_hit) = self.accel.intersect(&ray) else {
                return true;
            };
            let crossing = self.crossing_at(&ray, prim_hit, panes);
            let origin = offset_ray_origin(crossing.p, crossing.p_err, crossing.ng, ray.d);
            found.push(crossing);
            if found.len() == MAX_CROSSINGS {
                return false;
            }
            match walk.ray_from(origin) {
                Some(next) => ray = next,
                None => return true,
            }
            super::ray_stats::count_closest();
        }
    }

    /// The crossing where `ray` hits `h`: its point and normal only (`BoundaryHit`); a pane's
    /// pass needs its shading normal too.
    fn crossing_at(&self, ray: &Ray, h: PrimHit, panes: bool) -> SegmentCrossing {
        let hit = BoundaryHit::new(self, ray, h);
        let pane = if panes && self.has_null_transmission(hit.material) {
            // Seen along the walk's direction: |cos| is the same both ways.
            self.pane_passed(&SurfaceHit::new(self, ray, h), ray.d)
        } else {
            PanesPassed::NONE
        };
        SegmentCrossing {
            p: hit.p,
            p_err: hit.p_err,
            shape: hit.shape,
            ng: hit.ng,
            pane,
        }
    }

    /// T(a, b) through null boundaries, deterministic (each medium's exact `transmittance`), or
    /// `None` when an opaque surface blocks: what a shadow ray or connection is worth.
    pub fn transmittance(
        &self,
        a: ConnectionEnd,
        b: ConnectionEnd,
        medium: Option<MediumId>,
    ) -> Option<Color> {
        let mut t = Color::ONE;
        let open = self.for_each_medium_piece(a, b, medium, Crossing::NullOnly, |piece| {
            if let Some(m) = piece.medium {
                t *= self.media[m as usize].transmittance(piece.a, piece.b);
            }
        });
        open.map(|_| t)
    }

    /// An unbiased estimate of T(a, b) through null boundaries (`Medium::transmittance_estimate`
    /// per piece), or `None` when an opaque surface blocks: for integrators' shadow rays.
    pub fn transmittance_estimate(
        &self,
        a: ConnectionEnd,
        b: ConnectionEnd,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> Option<Color> {
        self.estimate_through(a, b, medium, Crossing::NullOnly, sampler)
    }

    /// `transmittance_estimate` past thin dielectric panes too, times what each lets through
    /// (`pane_transmission`): the shadow rays of `pt`'s and `light`'s media walks, which cross a
    /// pane as Mitsuba's `volpath` does — a null event, not a vertex (`is_null_transmission`).
    pub fn transmittance_estimate_past_panes(
        &self,
        a: ConnectionEnd,
        b: ConnectionEnd,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> Option<Color> {
        self.estimate_through(a, b, medium, Crossing::NullAndPanes, sampler)
    }

    fn estimate_through(
        &self,
        a: ConnectionEnd,
        b: ConnectionEnd,
        medium: Option<MediumId>,
        crossing: Crossing,
        sampler: &mut Sampler,
    ) -> Option<Color> {
        let mut t = Color::ONE;
        let through = self.for_each_medium_piece(a, b, medium, crossing, |piece| {
            if let Some(m) = piece.medium {
                t *= self.media[m as usize].transmittance_estimate(piece.a, piece.b, sampler);
            }
        })?;
        Some(t * through.transmission)
    }

    /// One walk of a connection's segment a → b through null boundaries, for what a join through
    /// media needs of it: an unbiased estimate of T(a, b) (the draws of `transmittance_estimate`,
    /// piece by piece) and the free-flight densities of the segment walked either way
    /// (`free_flight_density`: from a, scattering at b when `b_scatters`; from b, scattering at a
    /// when `a_scatters`), which are the same pieces taken in the other order. Panes pass as null
    /// events (module doc). `None` when an opaque surface blocks. One walk instead of three: a
    /// bdpt join reads all of it.
    pub fn connection_estimate(
        &self,
        a: ConnectionEnd,
        b: ConnectionEnd,
        medium: Option<MediumId>,
        (a_scatters, b_scatters): (bool, bool),
        sampler: &mut Sampler,
    ) -> Option<ConnectionFlight> {
        let (mut tr, mut a_to_b, mut b_to_a) = (Color::ONE, 1.0, 1.0);
        // A piece's walk density is known only once it is known whether it is the last.
        let mut last: Option<MediumPiece> = None;
        let mut first = true;
        let density = |piece: &MediumPiece, from_b: bool, scattered: bool| match piece.medium {
            Some(m) if from_b => {
                self.media[m as usize].free_flight_density(piece.b, piece.a, scattered)
            }
            Some(m) => self.media[m as usize].free_flight_density(piece.a, piece.b, scattered),
            None if scattered => 0.0,
            None => 1.0,
        };
        let panes = self.for_each_medium_piece(a, b, medium, Crossing::NullAndPanes, |piece| {
            if let Some(m) = piece.medium {
                tr *= self.media[m as usize].transmittance_estimate(piece.a, piece.b, sampler);
            }
            b_to_a *= density(&piece, true, first && a_scatters);
            first = false;
            if let Some(before) = last.replace(piece) {
                a_to_b *= density(&before, false, false);
            }
        })?;
        let piece = last.expect("every segment has a piece");
        a_to_b *= density(&piece, false, b_scatters);
        Some(ConnectionFlight {
            transmittance: tr * panes.transmission,
            a_to_b: a_to_b * panes.probability,
            b_to_a: b_to_a * panes.probability,
            reversible: panes.reversible,
            end_medium: piece.medium,
        })
    }

    /// The oracle's T of a path edge: every surface crossed is a boundary (visibility is not
    /// part of f(x̄)), so it is defined for every edge, and a pane passed is a null event (its
    /// null transmission, module doc); on a visible edge it is `transmittance` times the panes'.
    pub fn edge_transmittance(
        &self,
        a: ConnectionEnd,
        b: ConnectionEnd,
        medium: Option<MediumId>,
    ) -> Color {
        let mut t = Color::ONE;
        let walked = self.for_each_medium_piece(a, b, medium, Crossing::Everything, |piece| {
            if let Some(m) = piece.medium {
                t *= self.media[m as usize].transmittance(piece.a, piece.b);
            }
        });
        // A segment caught in a degenerate spot (no end to its crossings) carries nothing.
        walked.map_or(Color::ZERO, |panes| t * panes.transmission)
    }

    /// The density with which free-flight sampling from `a` towards `b`, restarted in each medium
    /// piece after a boundary, produces the outcome that ends at `b`: the product of the pieces'
    /// pass probabilities, times (when `scattered_at_b`) the last piece's density per unit length
    /// of scattering at `b` instead of its pass probability (`Medium::free_flight_density`), times
    /// the pass probability of every pane on the way (a null event, module doc). A vacuum piece
    /// is passed with probability 1 (and nothing scatters in it: density 0).
    pub fn free_flight_density(
        &self,
        a: ConnectionEnd,
        b: ConnectionEnd,
        medium: Option<MediumId>,
        scattered_at_b: bool,
    ) -> f32 {
        let mut pieces = Vec::new();
        let walked =
            self.for_each_medium_piece(a, b, medium, Crossing::Everything, |p| pieces.push(p));
        // A segment caught in a degenerate spot (no end to its crossings) has no density.
        let Some(panes) = walked else {
            return 0.0;
        };
        let last = pieces.len() - 1;
        let mut p = panes.probability;
        for (i, piece) in pieces.iter().enumerate() {
            let scattered = scattered_at_b && i == last;
            p *= match piece.medium {
                Some(m) => self.media[m as usize].free_flight_density(piece.a, piece.b, scattered),
                None if scattered => 0.0,
                None => 1.0,
            };
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Diffuse, Null};
    use crate::camera::{Camera, FovAxis};
    use crate::medium::{Homogeneous, Medium, PhaseFunction};
    use crate::scene::{RenderSettings, SceneBuilder, ShapeGeometry};

    /// A null sphere of fog (radius 1 at the origin) above an opaque floor at y = −1.001.
    fn fog_above_floor() -> Scene {
        let camera =
            Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, 2, 2).unwrap();
        let mut b = SceneBuilder::new(camera, RenderSettings::default());
        let fog =
            Homogeneous::new(Color::ONE, Color::splat(0.5), 1.0, PhaseFunction::Isotropic).unwrap();
        let fog = b.add_medium(Medium::Homogeneous(fog));
        let null = b.add_material(Material::Null(Null));
        let white = b.add_material(Material::Diffuse(Diffuse {
            albedo: Color::splat(0.5),
        }));
        b.add_shape(
            ShapeGeometry::Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
            },
            null,
            None,
            false,
        );
        b.set_last_shape_media(MediumInterface {
            interior: Some(fog),
            exterior: None,
        });
        let y = -1.001;
        let mesh = crate::scene::TriangleMesh {
            positions: vec![
                Vec3::new(-2.0, y, -2.0),
                Vec3::new(-2.0, y, 2.0),
                Vec3::new(2.0, y, 2.0),
                Vec3::new(2.0, y, -2.0),
            ],
            normals: None,
            uvs: None,
            indices: vec![[0, 1, 2], [0, 2, 3]],
            attributes: Vec::new(),
        };
        b.add_shape(ShapeGeometry::Mesh(mesh), white, None, false);
        b.try_build().unwrap()
    }

    fn media_along(
        s: &Scene,
        a: ConnectionEnd,
        b: ConnectionEnd,
        m: Option<MediumId>,
    ) -> Vec<Option<MediumId>> {
        let mut media = Vec::new();
        s.for_each_medium_piece(a, b, m, Crossing::Everything, |p| media.push(p.medium))
            .expect("the segment ends");
        media
    }

    /// A medium vertex a few rounding units inside a null boundary, with the error bound a walk
    /// of several medium vertices accumulates (larger than its distance to the boundary): the
    /// segment to the floor below crosses the boundary walked either way, as the walks (which
    /// trace from the scattering point itself) cross it. Boxing the medium vertex hid the
    /// boundary from the walk towards it (media [None] only): hg-spot's 3 failing mis-check paths.
    #[test]
    fn a_boundary_within_a_medium_vertexs_error_box_is_crossed_both_ways() {
        let s = fog_above_floor();
        for depth in [2e-6f32, 3.6e-6, 1e-5] {
            for x in [0.0f32, 0.05, -0.1] {
                let y = -(1.0 - x * x).sqrt() + depth;
                let vertex = ConnectionEnd {
                    p: Vec3::new(x, y, 0.0),
                    p_err: Vec3::splat(4e-6),
                    ng: Vec3::ZERO,
                    infinite: false,
                };
                let floor = ConnectionEnd {
                    p: Vec3::new(x, -1.001, 0.0),
                    p_err: Vec3::splat(1e-7),
                    ng: Vec3::Y,
                    infinite: false,
                };
                let at = format!("{depth} inside at x = {x}");
                assert_eq!(
                    media_along(&s, vertex, floor, Some(0)),
                    [Some(0), None],
                    "{at}"
                );
                assert_eq!(
                    media_along(&s, floor, vertex, None),
                    [None, Some(0)],
                    "{at}"
                );
                assert!(
                    s.free_flight_density(floor, vertex, None, true) > 0.0,
                    "{at}"
                );
            }
        }
    }
}

//! The subpath tracer through participating media (issue 43, item 4): `walk::random_walk` with
//! free flights, and the entries bidirectional estimators call, `camera_subpath_in` and
//! `light_subpath_in`, which pick it or the surface walk by `MEDIA` — once per pass, from
//! `Scene::has_media`, so a scene without media runs the surface walk's code alone. (They live
//! here, not in `walk`, so the imports run one way: this module reads `walk`, never the reverse.)
//!
//! Along each segment the walk samples a free flight in the ray's medium (Mitsuba's per-ray
//! medium: the medium a vertex leaves into, `PathVertex::medium_towards`, switched at every
//! `null` surface, which is crossed without a vertex). Where the flight scatters a **medium
//! vertex is born** (`PathVertex::medium`, volume measure: p_ω · p_ff / d²) and the walk goes on
//! by sampling its phase function; where it passes, the surface it reaches is a vertex of its
//! own (`PathVertex::surface_through_media`, p_ω |cos| / d² · P_pass). The free-flight density
//! of a segment is the product over its pieces between null boundaries of
//! `Medium::free_flight_density` — the pass probability of every piece but the last, and the
//! last's density per unit length of scattering when the segment ends in a medium — which is
//! `Scene::free_flight_density`, the oracle's, piece by piece as the walk passes them.
//!
//! The reverse density of the vertex before (`pdf_rev`, filled when the next direction is
//! sampled) carries the free flight of the same segment walked the other way: the pieces are the
//! same, but the one that may scatter is the first (at the vertex before, when it lies in a
//! medium) and the last is passed.
//!
//! Where shapes naming media overlap, per-ray media are not reversible (a boundary crossed
//! backwards need not give back the medium before it, `PanesPassed::reversible`): the segment
//! walked the other way lies in other media, and its reverse density is that walk's, walked anew
//! (`PathVertex::free_flight_to`, the oracle's) — only there, so nested media pay nothing.
//!
//! A thin dielectric pane passed is a null event (`lt_core::scene::media`'s one rule, as `pt` and
//! `light` walk it): no vertex, no count toward `max_vertices`; its pass probability 1 − R'
//! multiplies the segment's free-flight densities both ways, as `Scene::free_flight_density`
//! has it for the oracle and `Scene::connection_estimate` for joins, which pass panes.

use super::media_step::{scatter_in_medium, NullCrossings};
use super::walk::{self, camera_start, continue_subpath, light_start, reverse_density, Escape};
use super::walk::{Departure, Exit, Subpath, WalkLimits, WalkStart};
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec2, Vec3};
use lt_core::medium::{FreeFlight, Medium, MediumId};
use lt_core::path::PathVertex;
use lt_core::sampling::Sampler;
use lt_core::scene::SurfaceHit;
use lt_core::Scene;

/// `walk::camera_subpath`, through participating media when `MEDIA` (medium vertices where free
/// flights scatter, null surfaces crossed).
pub fn camera_subpath_in<const MEDIA: bool>(
    scene: &Scene,
    raster: Vec2,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    if let Some(start) = camera_start(scene, raster, sampler, limits, out) {
        dispatch::<MEDIA>(scene, start, sampler, limits, out);
    }
}

/// `walk::light_subpath`, through participating media when `MEDIA` (see `camera_subpath_in`).
pub fn light_subpath_in<const MEDIA: bool>(
    scene: &Scene,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    if let Some(start) = light_start(scene, sampler, limits, out) {
        dispatch::<MEDIA>(scene, start, sampler, limits, out);
    }
}

/// The surface walk, or the walk through media (`MEDIA`, a constant of the instantiation).
#[inline(always)]
fn dispatch<const MEDIA: bool>(
    scene: &Scene,
    start: WalkStart,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    if MEDIA {
        random_walk(scene, start, sampler, limits, out)
    } else {
        walk::random_walk(scene, start, sampler, limits, out)
    }
}

/// Where a segment towards nothing is cut off when it passes a medium (as `scene/media.rs` does
/// for a light at infinity): far enough that any positive σt extinguishes it.
const FAR: f32 = 1e30;

/// The free-flight densities of the segment being walked, over the pieces passed so far.
#[derive(Clone, Copy)]
struct Flight {
    /// Walk direction: pass probabilities so far (the last piece's scattering density once it
    /// scatters).
    forward: f32,
    /// The other direction: the same pieces, the first one's scattering density at the vertex
    /// the segment left when that vertex lies in a medium.
    reverse: f32,
    /// No piece walked yet: the next one touches the vertex the segment left.
    first: bool,
    /// The vertex the segment left is a medium vertex.
    from_medium: bool,
    /// Every boundary crossed so far, crossed backwards, gives back the medium before it.
    reversible: bool,
}

impl Flight {
    fn leaving(from_medium: bool) -> Flight {
        Flight {
            forward: 1.0,
            reverse: 1.0,
            first: true,
            from_medium,
            reversible: true,
        }
    }

    /// A boundary at `hit` was crossed along `d` from `before` into `after`.
    fn crossed(
        &mut self,
        scene: &Scene,
        hit: &SurfaceHit,
        d: Vec3,
        before: Option<MediumId>,
        after: Option<MediumId>,
    ) {
        self.reversible &= scene.medium_after(hit.interface, hit.ng, -d, after) == before;
    }

    /// The reverse density of the segment ending at `end` (arrived in `medium`) from `start`:
    /// the pieces walked, or — where a walk from `end` would cross other media — that walk's.
    fn reverse_to(
        &mut self,
        scene: &Scene,
        end: &PathVertex,
        start: &PathVertex,
        medium: Option<MediumId>,
    ) -> f32 {
        let w = end.dir_to(start);
        if !self.reversible || end.medium_towards(scene, w) != medium {
            self.reverse = end.free_flight_to(scene, start);
            self.reversible = true;
        }
        self.reverse
    }

    /// The piece a → b in medium `m` was walked; `scattered`: the flight stopped at b.
    fn piece(&mut self, m: &Medium, a: Vec3, b: Vec3, scattered: bool) {
        self.forward *= m.free_flight_density(a, b, scattered);
        self.reverse *= m.free_flight_density(b, a, self.first && self.from_medium);
        self.first = false;
    }
}

/// `walk::random_walk` through media: extends `out` (which holds at least its endpoint) along
/// `start.ray` until the walk ends or fills `max_vertices`.
fn random_walk(
    scene: &Scene,
    start: WalkStart,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    let rules = start.rules(limits.rr_depth);
    let WalkStart {
        mut ray,
        mut beta,
        mut pdf,
        mode,
    } = start;
    out.back_flight.clear();
    out.back_flight.resize(out.vertices.len(), 1.0);
    out.departure.clear();
    out.departure
        .resize(out.vertices.len(), Departure::default());
    out.exit = None;
    // How the walk left the last vertex along the segment being walked.
    let mut leave = Departure { beta, pdf_w: pdf };
    let endpoint = out.vertices.last().expect("the endpoint is pushed first");
    let mut medium = endpoint.medium_towards(scene, ray.d);
    let mut flight = Flight::leaving(false);
    let mut crossings = NullCrossings::default();
    loop {
        let hit = scene.intersect(&ray);
        if let Some(m) = medium {
            let mm = &scene.media[m as usize];
            let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
            match mm.sample_free_flight(ray.o, ray.d, t_max, sampler) {
                FreeFlight::Scattered { t, weight } => {
                    beta *= weight;
                    let x = ray.o + ray.d * t;
                    flight.piece(mm, ray.o, x, true);
                    let wo = -ray.d;
                    let n = out.vertices.len();
                    let prev = &out.vertices[n - 1];
                    let v = PathVertex::medium(m, x, wo, beta, pdf, flight.forward, prev);
                    let reverse = flight.reverse_to(scene, &v, prev, medium);
                    out.vertices.push(v);
                    out.back_flight.push(reverse);
                    out.departure.push(leave);
                    if beta == Color::ZERO || n + 1 >= limits.max_vertices {
                        return;
                    }
                    let phase = mm.phase();
                    let Some(ps) =
                        scatter_in_medium(phase, wo, &rules, &mut beta, n as u32, sampler)
                    else {
                        return;
                    };
                    // The reverse density of the vertex before: the phase function from ps.wi
                    // back to wo, then the segment's free flight walked backwards.
                    let (before, v) = out.vertices.split_at_mut(n);
                    let pdf_rev_w = phase.pdf(ps.wi, wo);
                    before[n - 1].pdf_rev =
                        reverse_density(&before[n - 1], &v[0], pdf_rev_w) * flight.reverse;
                    pdf = ps.pdf;
                    ray = Ray::new(x, ps.wi);
                    leave = Departure { beta, pdf_w: pdf };
                    flight = Flight::leaving(true);
                    crossings.reset();
                    continue;
                }
                FreeFlight::Passed { weight } => {
                    beta *= weight;
                    if beta == Color::ZERO {
                        return;
                    }
                    let end = hit.as_ref().map_or(ray.o + ray.d * FAR, |h| h.p);
                    flight.piece(mm, ray.o, end, false);
                }
            }
        } else {
            // A vacuum piece is passed with probability 1.
            flight.first = false;
        }
        let Some(hit) = hit else {
            out.exit = Some(Exit { dir: ray.d, leave });
            if mode == lt_core::bsdf::TransportMode::Radiance && !scene.infinite_lights.is_empty() {
                // The light at infinity is reached through every piece passed: its density is
                // the direction's times the pass probability (as `surface_through_media`).
                out.escape = Some(Escape {
                    dir: ray.d,
                    beta,
                    pdf_w: pdf * flight.forward,
                    back_flight: flight.reverse,
                });
            }
            return;
        };
        if scene.shapes[hit.shape as usize].null {
            let (before, d) = (medium, ray.d);
            if !crossings.cross(scene, &hit, &mut ray, &mut medium) {
                return;
            }
            flight.crossed(scene, &hit, d, before, medium);
            continue;
        }
        let wo = -ray.d;
        let n = out.vertices.len();
        let prev = &out.vertices[n - 1];
        let rev_before = prev.pdf_rev;
        let mut v = PathVertex::surface_through_media(&hit, wo, beta, pdf, flight.forward, prev);
        // A shape that names no media keeps the medium the walk is in, on both sides.
        v.interface = scene.interface_within(hit.interface, medium);
        let interface = v.interface;
        let reverse = flight.reverse_to(scene, &v, prev, medium);
        out.vertices.push(v);
        out.back_flight.push(reverse);
        out.departure.push(leave);
        // A pane may be passed at the last vertex: passing it is a null event, no vertex
        // (`Scene::is_null_transmission`); only a reflection makes it one.
        let pane = scene.has_null_transmission(hit.material);
        if n + 1 >= limits.max_vertices && !pane {
            return;
        }
        let Some(bs) =
            continue_subpath(scene, &hit, &rules, &mut beta, out, flight.reverse, sampler)
        else {
            return;
        };
        let before = medium;
        medium = scene.medium_across(interface, hit.ng, bs.wi);
        ray = hit.spawn_ray(bs.wi);
        if pane && scene.is_null_transmission(hit.material, hit.shading_frame().ns(), wo, bs.wi) {
            flight.crossed(scene, &hit, bs.wi, before, medium);
            // As a null boundary, but chosen with the lobe's probability 1 − R' (either way):
            // the segment goes on from the last real vertex, its densities times that.
            out.vertices.pop();
            out.back_flight.pop();
            out.departure.pop();
            out.vertices[n - 1].pdf_rev = rev_before;
            flight.forward *= bs.pdf_w;
            flight.reverse *= bs.pdf_rev_w;
            if !crossings.count() {
                return;
            }
            continue;
        }
        if n + 1 >= limits.max_vertices {
            return;
        }
        crossings.reset();
        pdf = bs.pdf_w;
        leave = Departure { beta, pdf_w: pdf };
        flight = Flight::leaving(false);
    }
}

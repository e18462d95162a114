//! The subpath tracer through participating media (issue 43, item 4): `walk::random_walk` with
//! free flights. Bidirectional estimators pick it once per pass (`camera_subpath_in::<true>`,
//! `light_subpath_in::<true>`) for a scene with media; a scene without media never enters it.
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

use super::walk::{continue_path, reverse_density, russian_roulette, Escape, Subpath};
use super::walk::{WalkLimits, WalkPoint, WalkRules, WalkStart};
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::medium::{FreeFlight, Medium};
use lt_core::path::PathVertex;
use lt_core::sampling::Sampler;
use lt_core::Scene;

/// More null crossings than this on one segment is a ray caught in a degenerate spot: it ends.
const MAX_NULL_CROSSINGS: u32 = 1024;

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
}

impl Flight {
    fn leaving(from_medium: bool) -> Flight {
        Flight {
            forward: 1.0,
            reverse: 1.0,
            first: true,
            from_medium,
        }
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
pub(super) fn random_walk(
    scene: &Scene,
    start: WalkStart,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    let WalkStart {
        mut ray,
        mut beta,
        mut pdf,
        mode,
    } = start;
    let rules = WalkRules {
        mode,
        rr_reference: beta,
        rr_depth: limits.rr_depth,
    };
    let endpoint = out.vertices.last().expect("the endpoint is pushed first");
    let mut medium = endpoint.medium_towards(scene, ray.d);
    let mut flight = Flight::leaving(false);
    let mut crossings = 0;
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
                    out.vertices.push(v);
                    if beta == Color::ZERO || n + 1 >= limits.max_vertices {
                        return;
                    }
                    let phase = mm.phase();
                    let Some(ps) = phase.sample(wo, sampler.next_2d()) else {
                        return;
                    };
                    beta *= ps.value / ps.pdf;
                    if !russian_roulette(
                        &mut beta,
                        rules.rr_reference,
                        n as u32,
                        rules.rr_depth,
                        sampler,
                    ) {
                        return;
                    }
                    // The reverse density of the vertex before: the phase function from ps.wi
                    // back to wo, then the segment's free flight walked backwards.
                    let (before, v) = out.vertices.split_at_mut(n);
                    let pdf_rev_w = phase.pdf(ps.wi, wo);
                    before[n - 1].pdf_rev =
                        reverse_density(&before[n - 1], &v[0], pdf_rev_w) * flight.reverse;
                    pdf = ps.pdf;
                    ray = Ray::new(x, ps.wi);
                    flight = Flight::leaving(true);
                    crossings = 0;
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
            if mode == lt_core::bsdf::TransportMode::Radiance && !scene.infinite_lights.is_empty() {
                // The light at infinity is reached through every piece passed: its density is
                // the direction's times the pass probability (as `surface_through_media`).
                out.escape = Some(Escape {
                    dir: ray.d,
                    beta,
                    pdf_w: pdf * flight.forward,
                });
            }
            return;
        };
        if scene.shapes[hit.shape as usize].null {
            crossings += 1;
            if crossings > MAX_NULL_CROSSINGS {
                return;
            }
            medium = scene.medium_after(hit.interface, hit.ng, ray.d, medium);
            ray = hit.spawn_ray(ray.d);
            continue;
        }
        crossings = 0;
        let wo = -ray.d;
        let n = out.vertices.len();
        let prev = &out.vertices[n - 1];
        let mut v = PathVertex::surface_through_media(&hit, wo, beta, pdf, flight.forward, prev);
        // A shape that names no media keeps the medium the walk is in, on both sides.
        v.interface = scene.interface_within(hit.interface, medium);
        let interface = v.interface;
        out.vertices.push(v);
        if n + 1 >= limits.max_vertices {
            return;
        }
        let sf = hit.shading_frame();
        let at = WalkPoint {
            hit: &hit,
            sf: &sf,
            wo,
        };
        let Some(bs) = continue_path(scene, &at, &rules, &mut beta, n as u32, sampler) else {
            return;
        };
        let (before, v) = out.vertices.split_at_mut(n);
        let (before, v) = (&mut before[n - 1], &mut v[0]);
        v.delta = bs.delta;
        before.pdf_rev = reverse_density(before, v, bs.pdf_rev_w) * flight.reverse;
        medium = scene.medium_across(interface, hit.ng, bs.wi);
        pdf = bs.pdf_w;
        ray = hit.spawn_ray(bs.wi);
        flight = Flight::leaving(false);
    }
}

//! `pt` and `pt-bsdf` through participating media: Mitsuba 3's `volpath` on lt's walk (see the
//! module above). A medium vertex is born where free-flight sampling in the ray's medium scatters;
//! there next-event estimation samples a light, evaluates the phase function towards it and
//! estimates the transmittance to it through null boundaries, and the walk continues by sampling
//! the phase function. At surfaces the walk is `pt`'s, with the shadow ray's transmittance and
//! the medium tracked across every surface the walk leaves.
//!
//! `pt-bsdf` runs the same walk with `Techniques::Bsdf` (no next-event estimation, every emitter
//! hit at full weight), so `pt` against `pt-bsdf` checks next-event estimation, transmittance
//! estimates and MIS in media against plain free-flight and phase sampling.

use super::{is_null, light_end, point_end, surface_end};
use crate::pt::{Pt, Techniques};
use crate::subpath::media_step::{scatter_in_medium, NullCrossings};
use crate::subpath::walk::{continue_path, escaped_radiance, WalkPoint, WalkRules};
use lt_core::bsdf::TransportMode;
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::medium::{FreeFlight, MediumId, PhaseFunction};
use lt_core::sampling::Sampler;
use lt_core::scene::ConnectionEnd;
use lt_core::{Scene, Vec2};

/// The last real vertex, as MIS and the light pdf of an emitter hit read it.
#[derive(Clone, Copy)]
struct Previous {
    /// Solid-angle density of the direction sampled there (BSDF or phase function).
    pdf_w: f32,
    /// A delta lobe or the camera: emitters hit next get full weight.
    delta: bool,
    p: Vec3,
}

/// What scatters light at a vertex towards a sampled light direction: its value (with the cosine
/// at a surface) and its solid-angle density of sampling that direction.
struct Scatter {
    f: Color,
    pdf_w: f32,
}

/// What a camera walk does in a medium besides `pt`'s free-flight sampling: the volumetric
/// density estimators (`volume_density`) end the walk at its first medium vertex with a kernel
/// estimate there (photon points) or along the flight that would have found it (beams). `pt`'s
/// own walk is [`Volpath`], whose defaults do nothing; the walk is monomorphised per kind, so
/// `pt` runs the code it ran before.
pub trait MediumEvents {
    /// Whether `along_flight` reads the surface ahead (`t_max`): then every free flight waits
    /// for the full closest-hit query. `Volpath` does not, and in a homogeneous medium looks for
    /// a surface only up to the sampled flight distance (`radiance_with`).
    const READS_FLIGHT_END: bool = true;

    /// At the start of a free flight in medium `m` along `ray` up to `t_max`, whose scattering
    /// vertex would be the walk's `depth`-th: an estimate to add (times β) of every path whose
    /// first medium vertex from the camera lies on this flight.
    #[inline]
    fn along_flight(&self, _ray: &Ray, _t_max: f32, _m: MediumId, _depth: u32) -> Option<Color> {
        None
    }

    /// At a sampled scattering `x` (the walk's `depth`-th vertex, β holding σs there): `Some`
    /// ends the walk with that estimate (times β) of the in-scattered radiance; `None` goes on
    /// as `pt`.
    #[inline]
    fn at_scatter(&self, _x: Vec3, _wo: Vec3, _m: MediumId, _depth: u32) -> Option<Color> {
        None
    }
}

/// `pt`'s own walk: free flights sampled, medium vertices lit by next-event estimation and
/// continued by phase sampling.
pub struct Volpath;

impl MediumEvents for Volpath {
    const READS_FLIGHT_END: bool = false;
}

/// The bound of the closest-hit query of a free flight of sampled length `t`: above `t` by far
/// more than the rounding of the primitive tests' `t < t_max` (a few ulps), so every surface
/// nearer than `t` is found and one not found lies beyond `t` — the walk then takes the same
/// branch as with the unbounded query.
const FLIGHT_BOUND: f32 = 1.0 + 1.0 / 1_048_576.0;

/// The radiance estimate of one camera sample at `raster` through media.
pub fn radiance(pt: &Pt, scene: &Scene, raster: Vec2, sampler: &mut Sampler) -> Color {
    radiance_with(pt, scene, raster, sampler, &Volpath)
}

/// `radiance` with the medium events `events` (see [`MediumEvents`]).
pub fn radiance_with<E: MediumEvents>(
    pt: &Pt,
    scene: &Scene,
    raster: Vec2,
    sampler: &mut Sampler,
    events: &E,
) -> Color {
    let params = pt.params;
    let nee = params.techniques != Techniques::Bsdf;
    let rules = WalkRules::camera(params.rr_depth);
    let mut ray = scene.camera.sample_ray(raster, sampler);
    let mut medium = scene.camera_medium;
    let mut beta = Color::ONE;
    let mut l = Color::ZERO;
    let mut prev = Previous {
        pdf_w: 0.0,
        delta: true,
        p: ray.o,
    };
    let mut depth = 1;
    let mut crossings = NullCrossings::default();
    loop {
        // In a homogeneous medium the flight's length is drawn first and the surface looked for
        // only up to it: a short flight's query is cut off early, and the SurfaceHit of a
        // surface beyond a scattering is never built. The same draws and the same comparison as
        // `sample_free_flight` (`Medium::sample_flight_distance`): the same path, bit for bit.
        let flight = match medium {
            Some(m) if !E::READS_FLIGHT_END => {
                scene.media[m as usize].sample_flight_distance(sampler)
            }
            _ => None,
        };
        let hit = match flight {
            Some(t) => scene.intersect(&Ray {
                t_max: ray.t_max.min(t * FLIGHT_BOUND),
                ..ray
            }),
            None => scene.intersect(&ray),
        };
        if let Some(m) = medium {
            let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
            let mm = &scene.media[m as usize];
            if let Some(along) = events.along_flight(&ray, t_max, m, depth) {
                l += beta * along;
            }
            let outcome = match flight {
                Some(t) => mm.end_free_flight(ray.o, ray.d, t, t_max),
                None => mm.sample_free_flight(ray.o, ray.d, t_max, sampler),
            };
            match outcome {
                FreeFlight::Scattered { t, weight } => {
                    beta *= weight;
                    if beta == Color::ZERO || depth == params.max_depth {
                        break;
                    }
                    let x = ray.o + ray.d * t;
                    let wo = -ray.d;
                    if let Some(estimate) = events.at_scatter(x, wo, m, depth) {
                        l += beta * estimate;
                        break;
                    }
                    let phase = mm.phase();
                    if nee {
                        l += beta * nee_in_medium(pt, scene, x, wo, phase, m, sampler);
                    }
                    let Some(ps) = scatter_in_medium(phase, wo, &rules, &mut beta, depth, sampler)
                    else {
                        break;
                    };
                    prev = Previous {
                        pdf_w: ps.pdf,
                        delta: false,
                        p: x,
                    };
                    ray = Ray::new(x, ps.wi);
                    depth += 1;
                    crossings.reset();
                    continue;
                }
                FreeFlight::Passed { weight } => {
                    beta *= weight;
                    if beta == Color::ZERO {
                        break;
                    }
                }
            }
        }
        let Some(hit) = hit else {
            l += beta
                * escaped_radiance(scene, ray.d, |i| {
                    let light_pdf = scene.light_sampler.pmf(i as usize)
                        * scene.lights[i as usize].pdf_li(prev.p, ray.d, ray.d, -ray.d);
                    pt.hit_weights(prev.delta, prev.pdf_w, light_pdf).0
                });
            break;
        };
        if is_null(scene, &hit) {
            if !crossings.cross(scene, &hit, &mut ray, &mut medium) {
                break;
            }
            continue;
        }
        crossings.reset();
        let wo = -ray.d;
        if let Some(li) = hit.light {
            let light = &scene.lights[li as usize];
            let le = light.emitted(hit.ng, wo, hit.uv);
            if le != Color::ZERO {
                let light_pdf = scene.light_sampler.pmf(li as usize)
                    * light.pdf_li(prev.p, ray.d, hit.p, hit.ng);
                l += beta * le * pt.hit_weights(prev.delta, prev.pdf_w, light_pdf).0;
            }
        }
        // A pane (thin dielectric) may still be passed at the last depth: its pass-through is
        // Mitsuba's null event, no bounce (`Scene::is_null_transmission`).
        let pane = scene.has_null_transmission(hit.material);
        if depth == params.max_depth && !pane {
            break;
        }
        let sf = hit.shading_frame();
        let at = WalkPoint {
            hit: &hit,
            sf: &sf,
            wo,
        };
        if nee && !scene.material_is_delta(hit.material) {
            l += beta * nee_at_surface(pt, scene, &at, medium, sampler);
        }
        let Some(bs) = continue_path(scene, &at, &rules, &mut beta, depth, sampler) else {
            break;
        };
        let crossed = pane && scene.is_null_transmission(hit.material, sf.ns(), wo, bs.wi);
        if depth == params.max_depth && !crossed {
            break;
        }
        medium = scene.medium_after(hit.interface, hit.ng, bs.wi, medium);
        ray = hit.spawn_ray(bs.wi);
        if crossed {
            // As a null boundary: no vertex, so MIS still weighs from the last real one, whose
            // shadow rays pass the pane too (`Scene::transmittance_estimate_past_panes`).
            continue;
        }
        prev = Previous {
            pdf_w: bs.pdf_w,
            delta: bs.delta,
            p: hit.p,
        };
        depth += 1;
    }
    l
}

/// Next-event estimation from a surface vertex: `pt`'s, times the transmittance to the light;
/// `medium` is the one the walk arrived in (kept by a shape that declares none).
fn nee_at_surface(
    pt: &Pt,
    scene: &Scene,
    at: &WalkPoint,
    medium: Option<MediumId>,
    sampler: &mut Sampler,
) -> Color {
    let hit = at.hit;
    let material = scene.material(hit.material);
    next_event(
        pt,
        scene,
        hit.p,
        surface_end(hit),
        sampler,
        |wi| {
            let ev = material.eval(at.sf, at.wo, wi, TransportMode::Radiance);
            Scatter {
                f: ev.f_cos,
                pdf_w: ev.pdf_w,
            }
        },
        |wi| scene.medium_after(hit.interface, hit.ng, wi, medium),
    )
}

/// Next-event estimation from a medium vertex at `x` in medium `m`: the phase function towards
/// the light (no cosine) and the transmittance to it.
fn nee_in_medium(
    pt: &Pt,
    scene: &Scene,
    x: Vec3,
    wo: Vec3,
    phase: PhaseFunction,
    m: MediumId,
    sampler: &mut Sampler,
) -> Color {
    next_event(
        pt,
        scene,
        x,
        point_end(x),
        sampler,
        |wi| {
            let value = phase.eval(wo, wi);
            Scatter {
                f: Color::splat(value),
                pdf_w: phase.pdf(wo, wi),
            }
        },
        |_| Some(m),
    )
}

/// One light chosen by power and sampled towards `p`; `scatter(wi)` is the vertex's value and
/// density towards it, `medium_towards(wi)` the medium the shadow ray starts in. Weighted against
/// the vertex's own sampling by `pt`'s heuristic over the two solid-angle densities.
fn next_event(
    pt: &Pt,
    scene: &Scene,
    p: Vec3,
    from: ConnectionEnd,
    sampler: &mut Sampler,
    scatter: impl Fn(Vec3) -> Scatter,
    medium_towards: impl Fn(Vec3) -> Option<MediumId>,
) -> Color {
    let Some((li, pmf, _)) = scene.light_sampler.sample(sampler.next_f32()) else {
        return Color::ZERO;
    };
    let u = sampler.next_2d();
    let Some(ls) = scene.lights[li].sample_li(p, u) else {
        return Color::ZERO;
    };
    if ls.radiance == Color::ZERO || ls.pdf_w == 0.0 {
        return Color::ZERO;
    }
    let s = scatter(ls.wi);
    if s.f == Color::ZERO {
        return Color::ZERO;
    }
    let tr = scene
        .transmittance_estimate_past_panes(from, light_end(&ls), medium_towards(ls.wi), sampler)
        .unwrap_or(Color::ZERO);
    if tr == Color::ZERO {
        return Color::ZERO;
    }
    let light_pdf = pmf * ls.pdf_w;
    let w = if ls.delta || pt.params.techniques == Techniques::Light {
        1.0
    } else {
        pt.weight(light_pdf, s.pdf_w)
    };
    s.f * ls.radiance * tr * (w / light_pdf)
}

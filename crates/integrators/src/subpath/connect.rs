//! Connections shared by the bidirectional estimators and owned by none of them: a light-subpath
//! vertex joined to the lens (t = 1, light tracing), and the BSDF of a subpath vertex evaluated
//! towards another vertex. Visibility is always `Scene::connection_visible`, which offsets both
//! ends by their error bounds.

use crate::film::splat::Splats;
use crate::record::{Completed, Recorder, Work};
use lt_core::bsdf::{BsdfEval, TransportMode};
use lt_core::math::{Color, Vec2, Vec3};
use lt_core::medium::MediumId;
use lt_core::path::camis::Mixture;
use lt_core::path::scatter::connectable;
use lt_core::path::{PathVertex, VertexKind};
use lt_core::sampling::Sampler;
use lt_core::scene::ConnectionFlight;
use lt_core::Scene;

/// The free-flight densities of a connection's edge walked either way (`Scene::free_flight_density`),
/// found by the join's own walk of it (`Scene::connection_estimate`); 1 without media, unread.
#[derive(Clone, Copy, Debug)]
pub struct EdgeFlights {
    /// A walk from the light end reaching the camera end.
    pub from_light: f32,
    /// A walk from the camera end reaching the light end.
    pub from_camera: f32,
}

impl Default for EdgeFlights {
    fn default() -> EdgeFlights {
        EdgeFlights {
            from_light: 1.0,
            from_camera: 1.0,
        }
    }
}

/// Every free-flight density a strategy's MIS weight patches (`strategy_weight::with_chain_in`):
/// the connecting edge both ways, and the segment arriving at each end walked backwards — which
/// the walk that made that end found as it walked it (`Subpath::back_flight`), so no join walks
/// a subpath's segment again.
#[derive(Clone, Copy, Debug, Default)]
pub struct JoinFlights {
    pub edge: EdgeFlights,
    /// x_{s−1} → x_{s−2}: the light end's arriving segment from its far end (s ≥ 2).
    pub light_back: f32,
    /// x_s → x_{s+1}: the camera end's arriving segment from its far end (t ≥ 2); for s = 0
    /// the segment x0 → x1 of the walk that reached the emitter.
    pub camera_back: f32,
}

/// A light-subpath vertex seen by the camera.
#[derive(Clone, Copy, Debug)]
pub struct CameraConnection {
    pub raster: Vec2,
    /// Unit direction from the lens point to the vertex.
    pub dir: Vec3,
    /// β · f_cos · We · cos θ_camera / d²: the splat before the 1/M of M light subpaths.
    pub value: Color,
    /// The vertex's BSDF towards the camera (importance mode); `None` at x0 on a light.
    pub eval: Option<BsdfEval>,
    /// The camera vertex the connection sampled (the eye, or a point of a thin lens).
    pub camera: PathVertex,
    /// Through media: the edge's free-flight densities.
    pub flights: EdgeFlights,
}

/// The BSDF of surface vertex `v` between its stored incoming direction `v.wo` and the direction
/// `wi`, in `mode`; at a medium vertex its phase function (`in_medium`). `None` for endpoints.
#[inline]
pub fn eval_towards(
    scene: &Scene,
    v: &PathVertex,
    wi: Vec3,
    mode: TransportMode,
) -> Option<BsdfEval> {
    let material = match v.kind {
        VertexKind::Surface { material } => material,
        VertexKind::Medium { medium } => return Some(in_medium(scene, medium, v.wo, wi)),
        _ => return None,
    };
    let sf = v.shading_frame();
    Some(scene.material(material).eval(&sf, v.wo, wi, mode))
}

/// A medium vertex's scattering towards `wi` as a connection uses it: the phase function alone
/// (no cosine; σs is already in the vertex's β, from the free flight's weight σs T / p), its
/// solid-angle density that of sampling it, and the reverse density the same (reciprocal).
/// Transport mode does not enter (`lt_core::medium`).
fn in_medium(scene: &Scene, medium: MediumId, wo: Vec3, wi: Vec3) -> BsdfEval {
    let phase = scene.media[medium as usize].phase();
    let value = phase.eval(wo, wi);
    BsdfEval {
        f_cos: Color::splat(value),
        pdf_w: phase.pdf(wo, wi),
        pdf_rev_w: phase.pdf(wi, wo),
    }
}

/// The edge a → b between two subpath vertices through media, walked once: an unbiased estimate
/// of its transmittance through null boundaries and every medium on the way (ratio tracking in
/// grids, exact in homogeneous media) and its free-flight densities either way (`a_to_b`,
/// `b_to_a`), which the join's MIS weight reads (no density depends on the estimate). `None`
/// when an opaque surface blocks. Without media a join asks `Scene::connection_visible` alone.
#[inline]
pub fn edge_estimate(
    scene: &Scene,
    a: &PathVertex,
    b: &PathVertex,
    sampler: &mut Sampler,
) -> Option<ConnectionFlight> {
    let medium = a.medium_towards(scene, a.dir_to(b));
    let scatters = (a.in_medium(), b.in_medium());
    let mut f = scene.connection_estimate(a.into(), b.into(), medium, scatters, sampler)?;
    // Where media shapes overlap, a walk from b crosses other media than the pieces walked from
    // a (`PanesPassed::reversible`): its density is that walk's.
    if !b.is_infinite() && (!f.reversible || f.end_medium != b.medium_towards(scene, b.dir_to(a))) {
        f.b_to_a = b.free_flight_to(scene, a);
    }
    Some(f)
}

/// Joins light-subpath vertex `y` (x0 on a light, or a non-delta surface) to a point of the lens
/// (the pinhole's eye; a thin lens's aperture point, two numbers from `sampler`). `None` when it
/// is off the film, faces away, contributes nothing, or the segment to that lens point is
/// blocked — a partly blocked aperture darkens splats as it darkens camera rays (pbrt-v4 #458).
/// A point light (delta position) cannot be seen and returns `None`; so does a directional light
/// (delta direction: `escaped` is zero towards any camera ray, and `scatter::connectable` already
/// refuses its x0), and so does every vertex for an orthographic camera (a delta in direction).
pub fn connect_to_camera(
    scene: &Scene,
    y: &PathVertex,
    sampler: &mut Sampler,
) -> Option<CameraConnection> {
    connect_to_camera_in::<false>(scene, y, sampler)
}

/// `connect_to_camera`, through media when `MEDIA`: a medium vertex joins too (its phase
/// function towards the lens), and the value carries the edge's transmittance estimate (drawn
/// from `sampler` after the lens point).
pub fn connect_to_camera_in<const MEDIA: bool>(
    scene: &Scene,
    y: &PathVertex,
    sampler: &mut Sampler,
) -> Option<CameraConnection> {
    let cam = &scene.camera;
    let (lens, value, eval) = match y.kind {
        VertexKind::Light { light, infinite } => {
            // x0 from `Light::sample_le`: its pdf_fwd is pmf · pdf_pos (pmf · pdf_dir at infinity),
            // and the radiance towards the camera replaces the one along the sampled ray.
            let l = &scene.lights[light as usize];
            if infinite {
                // The camera looks along y.p, towards the light; there is no cosine at x0.
                let lens = cam.connect_direction(y.p, sampler)?;
                (lens, l.escaped(y.p) / y.pdf_fwd, None)
            } else if !y.on_surface() {
                return None;
            } else {
                let lens = cam.connect(y.p, sampler)?;
                let dir = lens.dir;
                let le = l.emitted(y.ng, -dir, y.uv) * y.ng.dot(dir).abs();
                (lens, le / y.pdf_fwd, None)
            }
        }
        VertexKind::Surface { .. } | VertexKind::Medium { .. } => {
            let lens = cam.connect(y.p, sampler)?;
            let ev = eval_towards(scene, y, -lens.dir, TransportMode::Importance)?;
            (lens, y.beta * ev.f_cos, Some(ev))
        }
        VertexKind::Camera => return None,
    };
    if value == Color::ZERO {
        return None;
    }
    let camera = PathVertex::camera_at(cam, lens.origin, Color::ONE);
    let (value, flights) = if MEDIA {
        let f = edge_estimate(scene, y, &camera, sampler)?;
        let flights = EdgeFlights {
            from_light: f.a_to_b,
            from_camera: f.b_to_a,
        };
        (value * f.transmittance, flights)
    } else {
        if !scene.connection_visible(y, &camera) {
            return None;
        }
        (value, EdgeFlights::default())
    };
    if value == Color::ZERO {
        return None;
    }
    Some(CameraConnection {
        raster: lens.raster,
        dir: lens.dir,
        value: value * (lens.importance * lens.cos_lens / lens.distance_squared),
        eval,
        camera,
        flights,
    })
}

/// Light tracing (t = 1) for one light subpath `y`: each connectable vertex y_{s−1}, s ≤ `max_k`,
/// joined to the lens (its point drawn from `lens`) and splatted as value · w · `scale`, with
/// (w, mixture) = `weight(s, &connection)` the caller's MIS weight (and, from full-path
/// weights, the effective densities it came from) and `scale` = 1 / light paths per pass.
/// bdpt, lvc-bdpt and vcm/bpm share this loop and differ only in how they weight.
#[allow(clippy::too_many_arguments)]
pub fn splat_light_subpath<R: Recorder>(
    scene: &Scene,
    y: &[PathVertex],
    max_k: usize,
    scale: f32,
    lens: &mut Sampler,
    splats: &mut Splats,
    rec: &mut R,
    weight: impl FnMut(usize, &CameraConnection) -> (f64, Option<Mixture>),
) {
    splat_light_subpath_in::<false, R>(scene, y, max_k, scale, lens, splats, rec, weight)
}

/// `splat_light_subpath`, through media when `MEDIA` (`connect_to_camera_in`).
#[allow(clippy::too_many_arguments)]
pub fn splat_light_subpath_in<const MEDIA: bool, R: Recorder>(
    scene: &Scene,
    y: &[PathVertex],
    max_k: usize,
    scale: f32,
    lens: &mut Sampler,
    splats: &mut Splats,
    rec: &mut R,
    mut weight: impl FnMut(usize, &CameraConnection) -> (f64, Option<Mixture>),
) {
    for s in 1..=y.len().min(max_k) {
        'attempt: {
            let yv = &y[s - 1];
            if !connectable(scene, yv) {
                break 'attempt;
            }
            let Some(c) = connect_to_camera_in::<MEDIA>(scene, yv, lens) else {
                break 'attempt;
            };
            let (w, mixture) = weight(s, &c);
            if R::ACTIVE {
                if let Some(m) = mixture {
                    rec.mixture(m);
                }
                rec.completed(Completed {
                    s,
                    light: &y[..s],
                    camera: std::slice::from_ref(&c.camera),
                    weight: w,
                    value: c.value * scale,
                    raster: c.raster,
                    alternatives: &[],
                });
            }
            if w > 0.0 {
                splats.add_filtered(scene.camera.film(), c.raster, c.value * (w as f32 * scale));
            }
        }
        rec.lap(Work::Connection { s: s as u16, t: 1 });
    }
}

/// Density of x0 when next-event estimation from x1 chooses it: pmf · pdf_li in x0's measure
/// (area; solid angle at infinity; the pmf alone for a delta light, point or directional).
/// Mirrors `Path::densities`.
pub fn nee_density(scene: &Scene, x0: &PathVertex, x1: &PathVertex) -> f64 {
    let VertexKind::Light { light, .. } = x0.kind else {
        return 0.0;
    };
    let l = &scene.lights[light as usize];
    let pmf = scene.light_sampler.pmf(light as usize) as f64;
    if l.is_delta() {
        return pmf;
    }
    let pdf_w = l.pdf_li(x1.p, x1.dir_to(x0), x0.p, x0.ng);
    pmf * x1.convert_density(pdf_w, x0) as f64
}

/// (pmf · positional density of x0, density of x1 from x0's emitted direction) — the light
/// walk's l_0 and l_1 for an x0 that the light walk did not make. Mirrors `Path::densities`.
pub fn emission_densities(scene: &Scene, x0: &PathVertex, x1: Option<&PathVertex>) -> (f64, f64) {
    let VertexKind::Light { light, .. } = x0.kind else {
        return (0.0, 0.0);
    };
    let l = &scene.lights[light as usize];
    let pmf = scene.light_sampler.pmf(light as usize) as f64;
    let Some(x1) = x1 else {
        // x1 is the pinhole, which no light walk hits: l_1 = l_k = 0.
        let dir = if x0.is_infinite() { -x0.p } else { -x0.ng };
        let (pos, d) = l.pdf_le(x0.ng, dir, scene.bounding_sphere);
        return (pmf * if x0.is_infinite() { d } else { pos } as f64, 0.0);
    };
    let (pos, dir) = l.pdf_le(x0.ng, x0.dir_to(x1), scene.bounding_sphere);
    let (first, second) = if x0.is_infinite() {
        (dir, pos)
    } else {
        (pos, dir)
    };
    (pmf * first as f64, x0.convert_density(second, x1) as f64)
}

/// A shadow-ray join of light vertex `y` and camera vertex `z` (both connectable surfaces): the
/// two end evaluations and the unweighted contribution β_y f_y f_z β_z / d² (G's cosines are in
/// the `f_cos`s). `None` when coincident, zero or occluded.
pub struct Joined {
    pub light_end: BsdfEval,
    pub camera_end: BsdfEval,
    pub value: Color,
    /// Through media: the edge's free-flight densities.
    pub flights: EdgeFlights,
}

pub fn join(scene: &Scene, y: &PathVertex, z: &PathVertex) -> Option<Joined> {
    join_in::<false>(scene, y, z, None)
}

/// `join`, through media when `MEDIA`: either end may be a medium vertex (its phase function),
/// and the value carries the edge's transmittance estimate, drawn from `sampler` (`Some` exactly
/// when `MEDIA`).
#[inline]
pub fn join_in<const MEDIA: bool>(
    scene: &Scene,
    y: &PathVertex,
    z: &PathVertex,
    sampler: Option<&mut Sampler>,
) -> Option<Joined> {
    let d = y.p - z.p;
    let d2 = d.length_squared();
    if !(d2 > 0.0) {
        return None;
    }
    let dir = d / d2.sqrt();
    let light_end = eval_towards(scene, y, -dir, TransportMode::Importance)?;
    let camera_end = eval_towards(scene, z, dir, TransportMode::Radiance)?;
    let value = y.beta * light_end.f_cos * camera_end.f_cos * z.beta / d2;
    if !MEDIA {
        return (value != Color::ZERO && scene.connection_visible(y, z)).then_some(Joined {
            light_end,
            camera_end,
            value,
            flights: EdgeFlights::default(),
        });
    }
    if value == Color::ZERO {
        return None;
    }
    let sampler = sampler.expect("a join through media draws its transmittance estimate");
    let f = edge_estimate(scene, y, z, sampler)?;
    (f.transmittance != Color::ZERO).then_some(Joined {
        light_end,
        camera_end,
        value: value * f.transmittance,
        flights: EdgeFlights {
            from_light: f.a_to_b,
            from_camera: f.b_to_a,
        },
    })
}

/// Next-event estimation from camera vertex `z`: one light chosen by power and sampled towards
/// it (three numbers from `sampler`, in this order, whatever happens after the choice).
pub struct NextEvent {
    /// x0 as `PathVertex::light_sampled` makes it (pdf_fwd = next-event's density).
    pub x0: PathVertex,
    /// z's BSDF towards x0 (radiance mode).
    pub camera_end: BsdfEval,
    /// β_z f_cos Le / (pmf pdf_w): the unweighted contribution.
    pub value: Color,
    /// Through media: the shadow ray's free-flight densities.
    pub flights: EdgeFlights,
}

pub fn next_event(scene: &Scene, z: &PathVertex, sampler: &mut Sampler) -> Option<NextEvent> {
    next_event_in::<false>(scene, z, sampler)
}

/// `next_event`, through media when `MEDIA`: from a medium vertex too (its phase function), the
/// value times the shadow ray's transmittance estimate (drawn from `sampler` after the three
/// numbers of the light sample).
pub fn next_event_in<const MEDIA: bool>(
    scene: &Scene,
    z: &PathVertex,
    sampler: &mut Sampler,
) -> Option<NextEvent> {
    let (li, pmf, _) = scene.light_sampler.sample(sampler.next_f32())?;
    let u = sampler.next_2d();
    let ls = scene.lights[li].sample_li(z.p, u)?;
    if ls.radiance == Color::ZERO || ls.pdf_w == 0.0 {
        return None;
    }
    let camera_end = eval_towards(scene, z, ls.wi, TransportMode::Radiance)?;
    if camera_end.f_cos == Color::ZERO {
        return None;
    }
    let x0 = PathVertex::light_sampled(scene, li as u32, &ls, pmf, z);
    // Without media the shadow ray runs from x0, as it always has (same bits); through media
    // from z, whose side of a surface names the medium the ray starts in.
    let value = z.beta * camera_end.f_cos * ls.radiance / (pmf * ls.pdf_w);
    let (value, flights) = if MEDIA {
        let f = edge_estimate(scene, z, &x0, sampler)?;
        if f.transmittance == Color::ZERO {
            return None;
        }
        let flights = EdgeFlights {
            from_light: f.b_to_a,
            from_camera: f.a_to_b,
        };
        (value * f.transmittance, flights)
    } else {
        if !scene.connection_visible(&x0, z) {
            return None;
        }
        (value, EdgeFlights::default())
    };
    Some(NextEvent {
        x0,
        camera_end,
        value,
        flights,
    })
}

//! Walk code shared by every integrator and owned by none: Russian roulette, radiance escaping to
//! lights at infinity, one BSDF continuation (in either transport mode), and the subpath tracer
//! that bidirectional estimators build their camera and light subpaths with.
//!
//! The subpath tracer is where a bidirectional vertex is born: it creates each vertex through
//! `PathVertex`'s constructors (which fill `pdf_fwd`, area measure) and fills the previous
//! vertex's `pdf_rev` when it samples the next direction — `convert_density` of the reverse BSDF
//! density (pbrt-v4's `RandomWalk`; Veach 1997, §10.2). Russian roulette reweights β but is never
//! part of a density.

use lt_core::bsdf::{BsdfSample, ShadingFrame, TransportMode};
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::path::PathVertex;
use lt_core::sampling::Sampler;
use lt_core::scene::SurfaceHit;
use lt_core::{Scene, Vec2};

/// Russian roulette: continue with probability min(max βᵢ / max refᵢ, 0.95) and reweight.
/// Returns false to stop. `depth` counts segments so far; roulette starts once it reaches
/// `rr_depth`. `reference` is the walk's β at its start: 1 for camera walks, Le/pdf for light
/// walks, whose β carries the light's power — comparing that with 1 would end almost every light
/// walk from a small bright emitter (and keep every one from a large dim one), which is unbiased
/// but makes the survivors' weights explode.
#[inline]
pub fn russian_roulette(
    beta: &mut Color,
    reference: Color,
    depth: u32,
    rr_depth: u32,
    sampler: &mut Sampler,
) -> bool {
    if depth < rr_depth {
        return true;
    }
    let q = (beta.max_element() / reference.max_element()).min(0.95);
    if sampler.next_f32() >= q {
        return false;
    }
    *beta /= q;
    true
}

/// Radiance from every light at infinity along a ray leaving the scene, each weighted by `weight`.
#[inline]
pub fn escaped_radiance(scene: &Scene, dir: Vec3, mut weight: impl FnMut(u32) -> f32) -> Color {
    let mut l = Color::ZERO;
    for &i in &scene.infinite_lights {
        let le = scene.lights[i as usize].escaped(dir);
        if le != Color::ZERO {
            l += le * weight(i);
        }
    }
    l
}

/// The surface point a walk has reached: the hit, its shading frame, and `wo`, the direction back
/// along the walk.
#[derive(Clone, Copy)]
pub struct WalkPoint<'a> {
    pub hit: &'a SurfaceHit,
    pub sf: &'a ShadingFrame,
    pub wo: Vec3,
}

/// What stays fixed along one walk: its transport mode and its Russian roulette — the β it
/// started with (the reference) and the depth from which roulette plays.
#[derive(Clone, Copy, Debug)]
pub struct WalkRules {
    pub mode: TransportMode,
    pub rr_reference: Color,
    pub rr_depth: u32,
}

impl WalkRules {
    /// A camera walk: radiance mode, β starting at 1.
    pub fn camera(rr_depth: u32) -> WalkRules {
        WalkRules {
            mode: TransportMode::Radiance,
            rr_reference: Color::ONE,
            rr_depth,
        }
    }
}

/// Continues a walk at `at` by sampling its BSDF in `rules.mode`: multiplies the throughput by
/// the sample weight and plays Russian roulette (`depth` segments so far). `None` ends the walk.
#[inline]
pub fn continue_path(
    scene: &Scene,
    at: &WalkPoint,
    rules: &WalkRules,
    beta: &mut Color,
    depth: u32,
    sampler: &mut Sampler,
) -> Option<BsdfSample> {
    let u_lobe = sampler.next_f32();
    let u = sampler.next_2d();
    let bs = scene
        .material(at.hit.material)
        .sample(at.sf, at.wo, u_lobe, u, rules.mode)?;
    *beta *= bs.weight;
    (*beta != Color::ZERO
        && russian_roulette(beta, rules.rr_reference, depth, rules.rr_depth, sampler))
    .then_some(bs)
}

/// How long subpaths may grow.
#[derive(Clone, Copy, Debug)]
pub struct WalkLimits {
    /// Most vertices in the subpath, its endpoint included.
    pub max_vertices: usize,
    pub rr_depth: u32,
}

impl WalkLimits {
    /// The camera subpaths of a bidirectional estimator of paths of at most `max_depth`
    /// segments: t ≤ k + 1 vertices (strategy s = 0).
    pub fn camera(max_depth: u32, rr_depth: u32) -> WalkLimits {
        WalkLimits {
            max_vertices: max_depth as usize + 1,
            rr_depth,
        }
    }

    /// Its light subpaths: s ≤ k vertices (strategy t = 1).
    pub fn light(max_depth: u32, rr_depth: u32) -> WalkLimits {
        WalkLimits {
            max_vertices: max_depth as usize,
            rr_depth,
        }
    }
}

/// A camera walk that left the scene: the radiance of lights at infinity along `dir` completes
/// it (technique s = 0 with x0 at infinity).
#[derive(Clone, Copy, Debug)]
pub struct Escape {
    pub dir: Vec3,
    /// Throughput up to the escape.
    pub beta: Color,
    /// Solid-angle density with which the last vertex chose `dir` (through media, times the
    /// probability of passing every medium on the way out).
    pub pdf_w: f32,
}

/// One subpath: the camera or light endpoint first, then surfaces in walk order.
#[derive(Clone, Debug, Default)]
pub struct Subpath {
    pub vertices: Vec<PathVertex>,
    /// For camera subpaths: the walk left the scene after its last vertex.
    pub escape: Option<Escape>,
}

impl Subpath {
    pub fn with_capacity(n: usize) -> Subpath {
        Subpath {
            vertices: Vec::with_capacity(n),
            escape: None,
        }
    }

    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }
}

/// Traces a camera subpath through `raster`: z0 = the lens point (the pinhole's eye, or a thin
/// lens's aperture sample: two numbers from `sampler`), then the surfaces the walk meets
/// (radiance mode). The primary ray's density is the film-wide `Camera::pdf_dir`, so β starts at
/// 1 (see `lt_core::path` on image normalisation).
pub fn camera_subpath(
    scene: &Scene,
    raster: Vec2,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    camera_subpath_in::<false>(scene, raster, sampler, limits, out)
}

/// `camera_subpath`, through participating media when `MEDIA` (`media_walk`: medium vertices
/// where free flights scatter, null surfaces crossed). The estimator picks `MEDIA` once per pass
/// from `Scene::has_media`, so a scene without media runs the surface walk's code alone.
pub fn camera_subpath_in<const MEDIA: bool>(
    scene: &Scene,
    raster: Vec2,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    out.vertices.clear();
    out.escape = None;
    let ray = scene.camera.sample_ray(raster, sampler);
    out.vertices
        .push(PathVertex::camera_at(&scene.camera, ray.o, Color::ONE));
    if limits.max_vertices < 2 {
        return;
    }
    let pdf = scene.camera.pdf_dir(ray.o, ray.d);
    let start = WalkStart {
        ray,
        beta: Color::ONE,
        pdf,
        mode: TransportMode::Radiance,
    };
    walk::<MEDIA>(scene, start, sampler, limits, out);
}

/// The surface walk, or the walk through media (`MEDIA`, a constant of the instantiation).
#[inline(always)]
fn walk<const MEDIA: bool>(
    scene: &Scene,
    start: WalkStart,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    if MEDIA {
        super::media_walk::random_walk(scene, start, sampler, limits, out)
    } else {
        random_walk(scene, start, sampler, limits, out)
    }
}

/// Traces a light subpath: y0 on a light chosen by power (`Light::sample_le`), then the surfaces
/// the emitted ray meets (importance mode). β of y0 is Le / pdf_fwd; the emitted direction's
/// cosine and density enter β at y1.
pub fn light_subpath(scene: &Scene, sampler: &mut Sampler, limits: WalkLimits, out: &mut Subpath) {
    light_subpath_in::<false>(scene, sampler, limits, out)
}

/// `light_subpath`, through participating media when `MEDIA` (see `camera_subpath_in`).
pub fn light_subpath_in<const MEDIA: bool>(
    scene: &Scene,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    out.vertices.clear();
    out.escape = None;
    let Some((li, pmf, _)) = scene.light_sampler.sample(sampler.next_f32()) else {
        return;
    };
    let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
    let light = &scene.lights[li];
    let Some(le) = light.sample_le(u_pos, u_dir, scene.bounding_sphere) else {
        return;
    };
    if le.radiance == Color::ZERO || le.pdf_pos == 0.0 || le.pdf_dir == 0.0 {
        return;
    }
    let y0 = PathVertex::light_emitted(scene, li as u32, &le, pmf);
    out.vertices.push(y0);
    if limits.max_vertices < 2 {
        return;
    }
    // β at y1: Le |cos θ0| / (pmf pdf_pos pdf_dir); a light at infinity has no cosine at y0 and
    // its perpendicular-disk density belongs to y1.
    let cos0 = if light.is_infinite() || light.delta_position() {
        1.0
    } else {
        le.n.dot(le.ray.d).abs()
    };
    let beta = le.radiance * (cos0 / (pmf * le.pdf_pos * le.pdf_dir));
    let pdf = if light.is_infinite() {
        le.pdf_pos
    } else {
        le.pdf_dir
    };
    let start = WalkStart {
        ray: le.ray,
        beta,
        pdf,
        mode: TransportMode::Importance,
    };
    walk::<MEDIA>(scene, start, sampler, limits, out);
}

/// The first ray of a subpath's walk, leaving its endpoint: the throughput it carries, the
/// density with which the endpoint chose it (see `PathVertex::surface`) and the transport mode.
pub(super) struct WalkStart {
    pub ray: Ray,
    pub beta: Color,
    pub pdf: f32,
    pub mode: TransportMode,
}

/// Extends `out` (which holds at least its endpoint) along `start.ray` until the walk ends or
/// fills `max_vertices`.
fn random_walk(
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
    loop {
        let Some(hit) = scene.intersect(&ray) else {
            if mode == TransportMode::Radiance && !scene.infinite_lights.is_empty() {
                out.escape = Some(Escape {
                    dir: ray.d,
                    beta,
                    pdf_w: pdf,
                });
            }
            return;
        };
        let wo = -ray.d;
        // The new vertex is built in place and read by reference: a vertex is 136 bytes, and a
        // copy of the one before plus a move into the vector were two `memcpy` calls per bounce.
        let n = out.vertices.len();
        let prev = out.vertices.last().expect("the endpoint is pushed first");
        out.vertices
            .push(PathVertex::surface(&hit, wo, beta, pdf, prev));
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
        // The reverse density of the vertex before: how a walk from the other end, arriving along
        // bs.wi, would have chosen it.
        let (before, v) = out.vertices.split_at_mut(n);
        let (before, v) = (&mut before[n - 1], &mut v[0]);
        v.delta = bs.delta;
        before.pdf_rev = reverse_density(before, v, bs.pdf_rev_w);
        pdf = bs.pdf_w;
        ray = hit.spawn_ray(bs.wi);
    }
}

/// The density of generating `target` from `from` with a solid-angle density `pdf_w` at `from`,
/// in `target`'s measure; zero where a walk cannot land: a delta light, in position (a point) or
/// in direction (a directional light), see `PathVertex::is_delta_light`.
#[inline]
pub fn reverse_density(target: &PathVertex, from: &PathVertex, pdf_w: f32) -> f32 {
    if target.is_delta_light() {
        return 0.0;
    }
    from.convert_density(pdf_w, target)
}

/// A light vertex without a surface (a point light): no walk can arrive at it. A directional
/// light cannot be arrived at either; `PathVertex::is_delta_light` tests for both.
#[inline]
pub fn is_point_light(v: &PathVertex) -> bool {
    matches!(
        v.kind,
        lt_core::path::VertexKind::Light {
            infinite: false,
            ..
        }
    ) && !v.on_surface()
}

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
use lt_core::light::LightLeSample;
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
    /// Through media: the free-flight density of the way out walked from infinity back to the
    /// last vertex (`Subpath::back_flight`); 1 without media.
    pub back_flight: f32,
}

/// One subpath: the camera or light endpoint first, then surfaces in walk order.
#[derive(Clone, Debug, Default)]
pub struct Subpath {
    pub vertices: Vec<PathVertex>,
    /// For camera subpaths: the walk left the scene after its last vertex.
    pub escape: Option<Escape>,
    /// Through media, one per vertex (empty otherwise): the free-flight density of the segment
    /// that reached the vertex walked backwards, from it to the vertex before
    /// (`Scene::free_flight_density`; 1 at the endpoint). The walk finds it as it walks the
    /// segment; a join patching the reverse density of the vertex before reads it here instead of
    /// walking the segment again. (Beside the vertices, not in them: a vertex is kept at 128 bytes.)
    pub back_flight: Vec<f32>,
    /// Through media, one per vertex (empty otherwise): how the walk left the vertex before
    /// along the segment that reached this one (throughput and direction density at the
    /// segment's start; default at the endpoint). Volumetric estimators that integrate along a
    /// segment (camera beams, `upbp`) read it: the segment's start throughput is not recoverable
    /// from the vertex's β once a free flight's weight is stochastic (grids).
    pub departure: Vec<Departure>,
    /// Through media: the segment the walk took after its last vertex when it reached no vertex
    /// (it left the scene), whatever the lights; `None` otherwise. Set by the media walk only.
    pub exit: Option<Exit>,
}

/// How a walk left a vertex along one segment (`Subpath::departure`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Departure {
    /// Throughput leaving the vertex (after its scattering and Russian roulette).
    pub beta: Color,
    /// Solid-angle density of the direction (the camera's `pdf_dir` for the primary ray).
    pub pdf_w: f32,
}

/// The walk's last segment, which reached no vertex (`Subpath::exit`).
#[derive(Clone, Copy, Debug)]
pub struct Exit {
    /// Unit direction from the last vertex.
    pub dir: Vec3,
    pub leave: Departure,
}

impl Subpath {
    pub fn with_capacity(n: usize) -> Subpath {
        Subpath {
            vertices: Vec::with_capacity(n),
            escape: None,
            back_flight: Vec::new(),
            departure: Vec::new(),
            exit: None,
        }
    }

    /// `departure` of vertex `i` (default when the walk kept none: a surface walk).
    #[inline]
    pub fn departure(&self, i: usize) -> Departure {
        self.departure.get(i).copied().unwrap_or_default()
    }

    /// `back_flight` of vertex `i` (1 when the walk kept none: a surface walk).
    #[inline]
    pub fn back_flight(&self, i: usize) -> f32 {
        self.back_flight.get(i).copied().unwrap_or(1.0)
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
/// 1 (see `lt_core::path` on image normalisation). The walk through media is
/// `media_walk::camera_subpath_in`.
pub fn camera_subpath(
    scene: &Scene,
    raster: Vec2,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) {
    if let Some(start) = camera_start(scene, raster, sampler, limits, out) {
        random_walk(scene, start, sampler, limits, out);
    }
}

/// Begins a camera subpath in `out`: z0 pushed, and the primary ray its walk follows (`None` when
/// the limits allow z0 alone).
pub(super) fn camera_start(
    scene: &Scene,
    raster: Vec2,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) -> Option<WalkStart> {
    out.vertices.clear();
    out.escape = None;
    let ray = scene.camera.sample_ray(raster, sampler);
    out.vertices
        .push(PathVertex::camera_at(&scene.camera, ray.o, Color::ONE));
    if limits.max_vertices < 2 {
        return None;
    }
    let pdf = scene.camera.pdf_dir(ray.o, ray.d);
    Some(WalkStart {
        ray,
        beta: Color::ONE,
        pdf,
        mode: TransportMode::Radiance,
    })
}

/// Traces a light subpath: y0 on a light chosen by power (`Light::sample_le`), then the surfaces
/// the emitted ray meets (importance mode). β of y0 is Le / pdf_fwd; the emitted direction's
/// cosine and density enter β at y1. The walk through media is `media_walk::light_subpath_in`.
pub fn light_subpath(scene: &Scene, sampler: &mut Sampler, limits: WalkLimits, out: &mut Subpath) {
    if let Some(start) = light_start(scene, sampler, limits, out) {
        random_walk(scene, start, sampler, limits, out);
    }
}

/// A light chosen by power and an emitted ray sampled from it (`Light::sample_le`): what every
/// light walk starts from, surface or media, subpath or `light`'s splatting walk.
pub struct Emission {
    pub light: usize,
    pub pmf: f32,
    pub le: LightLeSample,
}

impl Emission {
    /// Three numbers from `sampler` (light choice, position, direction); `None` when nothing is
    /// emitted.
    pub fn sample(scene: &Scene, sampler: &mut Sampler) -> Option<Emission> {
        let (light, pmf, _) = scene.light_sampler.sample(sampler.next_f32())?;
        let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
        let le = scene.lights[light].sample_le(u_pos, u_dir, scene.bounding_sphere)?;
        if le.radiance == Color::ZERO || le.pdf_pos == 0.0 || le.pdf_dir == 0.0 {
            return None;
        }
        Some(Emission { light, pmf, le })
    }

    /// The walk along the emitted ray (importance mode): β at y1 is Le |cos θ0| / (pmf pdf_pos
    /// pdf_dir); a light at infinity has no cosine at y0 and its perpendicular-disk density
    /// belongs to y1.
    pub fn walk_start(&self, scene: &Scene) -> WalkStart {
        let (light, le) = (&scene.lights[self.light], &self.le);
        let cos0 = if light.is_infinite() || light.delta_position() {
            1.0
        } else {
            le.n.dot(le.ray.d).abs()
        };
        let beta = le.radiance * (cos0 / (self.pmf * le.pdf_pos * le.pdf_dir));
        let pdf = if light.is_infinite() {
            le.pdf_pos
        } else {
            le.pdf_dir
        };
        WalkStart {
            ray: le.ray,
            beta,
            pdf,
            mode: TransportMode::Importance,
        }
    }

    /// The emitter's point as a connection's end (on the bounding disk for a light at infinity).
    pub fn at(&self) -> lt_core::scene::ConnectionEnd {
        lt_core::scene::ConnectionEnd {
            p: self.le.p,
            p_err: self.le.p_err,
            ng: self.le.n,
            infinite: false,
        }
    }

    /// The medium the emitted ray starts in (`Scene::light_medium_towards`).
    pub fn medium(&self, scene: &Scene) -> Option<lt_core::medium::MediumId> {
        scene.light_medium_towards(self.light as u32, self.at(), self.le.ray.d)
    }
}

/// Begins a light subpath in `out`: y0 pushed, and the emitted ray its walk follows (`None` when
/// nothing is emitted or the limits allow y0 alone).
pub(super) fn light_start(
    scene: &Scene,
    sampler: &mut Sampler,
    limits: WalkLimits,
    out: &mut Subpath,
) -> Option<WalkStart> {
    out.vertices.clear();
    out.escape = None;
    let e = Emission::sample(scene, sampler)?;
    let y0 = PathVertex::light_emitted(scene, e.light as u32, &e.le, e.pmf);
    out.vertices.push(y0);
    if limits.max_vertices < 2 {
        return None;
    }
    Some(e.walk_start(scene))
}

/// The first ray of a subpath's walk, leaving its endpoint: the throughput it carries, the
/// density with which the endpoint chose it (see `PathVertex::surface`) and the transport mode.
pub struct WalkStart {
    pub ray: Ray,
    pub beta: Color,
    pub pdf: f32,
    pub mode: TransportMode,
}

impl WalkStart {
    /// The rules of a walk from here: its mode, roulette against the β it starts with.
    pub fn rules(&self, rr_depth: u32) -> WalkRules {
        WalkRules {
            mode: self.mode,
            rr_reference: self.beta,
            rr_depth,
        }
    }
}

/// Extends `out` (which holds at least its endpoint) along `start.ray` until the walk ends or
/// fills `max_vertices`.
pub(super) fn random_walk(
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
    loop {
        let Some(hit) = scene.intersect(&ray) else {
            if mode == TransportMode::Radiance && !scene.infinite_lights.is_empty() {
                out.escape = Some(Escape {
                    dir: ray.d,
                    beta,
                    pdf_w: pdf,
                    back_flight: 1.0,
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
        let Some(bs) = continue_subpath(scene, &hit, &rules, &mut beta, out, 1.0, sampler) else {
            return;
        };
        pdf = bs.pdf_w;
        ray = hit.spawn_ray(bs.wi);
    }
}

/// Continues a subpath at its last vertex, a surface at `hit` (`continue_path`), and fills what
/// the sample decides of the vertices: the last one's `delta`, and the `pdf_rev` of the one before
/// — how a walk from the other end, arriving along the sampled direction, would have chosen it,
/// times `ff_reverse`, the free flight of the segment between them walked backwards (1 without
/// media, an exact no-op).
#[inline(always)]
pub(super) fn continue_subpath(
    scene: &Scene,
    hit: &SurfaceHit,
    rules: &WalkRules,
    beta: &mut Color,
    out: &mut Subpath,
    ff_reverse: f32,
    sampler: &mut Sampler,
) -> Option<BsdfSample> {
    let n = out.vertices.len() - 1;
    let sf = hit.shading_frame();
    let at = WalkPoint {
        hit,
        sf: &sf,
        wo: out.vertices[n].wo,
    };
    let bs = continue_path(scene, &at, rules, beta, n as u32, sampler)?;
    let (before, v) = out.vertices.split_at_mut(n);
    let (before, v) = (&mut before[n - 1], &mut v[0]);
    v.delta = bs.delta;
    before.pdf_rev = reverse_density(before, v, bs.pdf_rev_w) * ff_reverse;
    Some(bs)
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

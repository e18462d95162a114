//! The bidirectional camera loop, written once for every estimator that joins a camera subpath
//! to light vertices (`bdpt`, `lvc-bdpt`, and the VCM engine behind `vcm`, `bpm` and `eamis`).
//! Per camera sample it walks the camera subpath z_0 z_1 … through a filtered position of the
//! pixel and, at every vertex z_{t−1} (t ≥ 2), runs
//!
//! - s = 0: the walk reached an emitter at z_{t−1} (after the walk: a light at infinity it
//!   escaped to);
//! - s = 1: next-event estimation from z_{t−1};
//! - s ≥ 2: shadow rays to the light vertices the estimator chooses (`Joins`);
//! - the estimator's own techniques at the vertex (VCM's merges, upbp's medium points) and along
//!   the segment that reached it (upbp's camera beams; after the last vertex, along the segment
//!   that left the scene: `after_walk`),
//!
//! each completed path reported to the recorder and each technique's time lapped. What differs
//! between estimators is a [`CameraPolicy`]: which light vertices a camera vertex joins, the MIS
//! weight of s = 0, of s = 1 and of each connection, and techniques of their own. The loop is
//! generic over the policy and the recorder, so each estimator gets its own monomorphised copy
//! and the hot loop calls no trait object. Light tracing (t = 1) is per light subpath, not per
//! camera sample: `connect::splat_light_subpath`.
//!
//! The random numbers are drawn from the pixel's camera stream in this order: film position,
//! camera walk, then per vertex next-event estimation's three numbers (and, through media, its
//! shadow ray's transmittance estimate) and whatever the policy's `connect` draws (lvc-bdpt's
//! cache picks). Through media (`CameraPolicy::MEDIA`) the joins s, t ≥ 2 draw their
//! transmittance estimates from the pixel's own `Domain::Aux` stream. Contributions are summed in technique order, so an
//! estimator's image does not depend on which code path formed it.

use crate::film::pixel::{pixel_sample, weighted};
use crate::film::splat::Pass;
use crate::record::{Completed, Recorder, Work};
use crate::subpath::connect::{join_in, next_event_in, JoinFlights, Joined, NextEvent};
use crate::subpath::media_walk::camera_subpath_in;
use crate::subpath::walk::{Subpath, WalkLimits};
use lt_core::bsdf::BsdfEval;
use lt_core::math::{Color, Vec2};
use lt_core::path::camis::Mixture;
use lt_core::path::scatter::connectable;
use lt_core::path::PathVertex;
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;

/// The MIS weight a policy gives one path, with the effective densities of every technique when
/// it was computed from the full path (`lt_core::path::camis`; reported to the recorder first).
pub type Weight = (f64, Option<Mixture>);

/// What a bidirectional estimator does at the camera vertices the loop visits. `z` is always the
/// camera prefix z_0 … z_{t−1}, camera first, its last vertex the one being visited.
pub trait CameraPolicy {
    /// The estimator walks participating media (`media_walk::camera_subpath_in`, next-event estimation
    /// and joins with transmittance estimates). A constant of the policy's type, chosen once per
    /// pass from `Scene::has_media`, so the loop without media is the surface loop alone.
    const MEDIA: bool = false;

    /// The camera walk `z` is done, before any technique runs: per-sample state (the VCM
    /// engine's MIS records of the walk, whether the pixel at `raster` merges).
    #[inline]
    fn walked(&mut self, _scene: &Scene, _z: &[PathVertex], _raster: Vec2) {}

    /// s = 0: the weight of the path `path` = z_0 … z_m, x0 — a camera walk and the light
    /// endpoint it reached (its `pdf_fwd` the walk's density of x0). Through media `flights`
    /// holds the walk's free flight of x0 → z_m (`camera_back`).
    fn emitter_weight(
        &self,
        scene: &Scene,
        path: &[PathVertex],
        flights: JoinFlights,
        raster: Vec2,
    ) -> Weight;

    /// Whether the techniques with s ≥ 1 run (`bpm` has merges only).
    #[inline]
    fn connects(&self) -> bool {
        true
    }

    /// s = 1: the weight of next-event estimation's light sample x0 joined to z_{t−1}, whose
    /// BSDF towards it is `camera_end` (`light_end` = (x0, camera_end)); through media `flights` holds the shadow ray's free
    /// flights and the walk's of z_{t−1} → z_{t−2}.
    fn next_event_weight(
        &self,
        scene: &Scene,
        z: &[PathVertex],
        light_end: (&PathVertex, BsdfEval),
        flights: JoinFlights,
        raster: Vec2,
    ) -> Weight;

    /// s ≥ 2: joins z_{t−1} (`joins.camera()`) to each light vertex it connects to, through
    /// `Joins::join` (one light subpath: `Joins::join_subpath`). `sampler` is the pixel's camera
    /// stream, for estimators that draw the light vertices.
    fn connect<R: Recorder>(
        &mut self,
        scene: &Scene,
        joins: &mut Joins<'_, R>,
        sampler: &mut Sampler,
    );

    /// The estimator's own techniques at z_{t−1}, after its connections (VCM's merges), each
    /// adding its weighted contribution to `l`.
    #[inline]
    fn at_vertex<R: Recorder>(
        &mut self,
        _scene: &Scene,
        _z: &[PathVertex],
        _sample: &mut SampleCtx<'_, R>,
        _l: &mut Color,
    ) {
    }

    /// The estimator's own techniques along the segment z_{t−2} → z_{t−1}, before any at
    /// z_{t−1} (volumetric estimators' camera beams: `upbp`).
    #[inline]
    fn along_segment<R: Recorder>(
        &mut self,
        _scene: &Scene,
        _z: &[PathVertex],
        _sample: &mut SampleCtx<'_, R>,
        _l: &mut Color,
    ) {
    }

    /// The camera walk as a subpath (after `walked`): what segment techniques read besides the
    /// vertices (through media, `Subpath::departure` and `Subpath::exit`; `upbp`).
    #[inline]
    fn camera_walk(&mut self, _scene: &Scene, _camera: &Subpath) {}

    /// After every vertex's techniques: the estimator's own techniques along the walk's last
    /// segment when it reached no vertex (`Subpath::exit`; `upbp`'s camera beams).
    #[inline]
    fn after_walk<R: Recorder>(
        &mut self,
        _scene: &Scene,
        _z: &[PathVertex],
        _sample: &mut SampleCtx<'_, R>,
        _l: &mut Color,
    ) {
    }
}

/// What every technique of one camera sample shares: its film position and the recorder.
pub struct SampleCtx<'a, R> {
    pub raster: Vec2,
    pub rec: &'a mut R,
}

/// Per-thread buffers of the loop.
pub struct CameraScratch {
    camera: Subpath,
    /// A camera walk and the light endpoint it reached (s = 0), as one path.
    reached: Vec<PathVertex>,
}

impl CameraScratch {
    /// Buffers for paths of at most `max_depth` segments.
    pub fn new(max_depth: u32) -> CameraScratch {
        let d = max_depth as usize;
        CameraScratch {
            camera: Subpath::with_capacity(d + 1),
            reached: Vec::with_capacity(d + 2),
        }
    }
}

/// One connection (s ≥ 2, t ≥ 2) as the loop formed it, for the policy to weigh.
#[derive(Clone, Copy)]
pub struct Connection<'a> {
    /// y_0 … y_{s−1}.
    pub light: &'a [PathVertex],
    /// z_0 … z_{t−1}, camera first.
    pub camera: &'a [PathVertex],
    pub joined: &'a Joined,
    /// Where on the film the path lands.
    pub raster: Vec2,
    /// Through media: every free flight the weight patches (the edge's from `joined`).
    pub flights: JoinFlights,
}

/// The connections of camera vertex z_{t−1}: joins, records and sums them.
pub struct Joins<'a, R> {
    z: &'a [PathVertex],
    /// Through media: the camera walk's free flight of z_{t−1} → z_{t−2} (`Subpath::back_flight`).
    z_back: f32,
    max_k: usize,
    raster: Vec2,
    rec: &'a mut R,
    l: &'a mut Color,
    /// Through media: the stream the joins' transmittance estimates draw from (the pixel's
    /// auxiliary stream, so the camera stream's order is the surface loop's).
    transmittance: Option<&'a mut Sampler>,
}

impl<R: Recorder> Joins<'_, R> {
    /// z_0 … z_{t−1}.
    pub fn camera(&self) -> &[PathVertex] {
        self.z
    }

    /// t: the camera vertices of every path joined here.
    pub fn t(&self) -> usize {
        self.z.len()
    }

    /// Longest path in segments.
    pub fn max_k(&self) -> usize {
        self.max_k
    }

    /// Strategy (s, t), s = |y|: a shadow ray from z_{t−1} to y_{s−1} (`y` = y_0 … y_{s−1}),
    /// its value scaled by `scale` and weighed by `weight`; reported, added, and its time lapped
    /// whether or not it joined.
    #[inline]
    pub fn join(
        &mut self,
        scene: &Scene,
        y: &[PathVertex],
        scale: f32,
        weight: impl FnOnce(Connection) -> Weight,
    ) {
        self.join_in::<false>(scene, (y, 1.0), scale, weight)
    }

    /// `join`, through media when `MEDIA` (the policy's `CameraPolicy::MEDIA`): the value
    /// carries the edge's transmittance estimate; `y_back` is the light walk's free flight of
    /// y_{s−1} → y_{s−2} (`Subpath::back_flight`).
    #[inline]
    pub fn join_in<const MEDIA: bool>(
        &mut self,
        scene: &Scene,
        (y, y_back): (&[PathVertex], f32),
        scale: f32,
        weight: impl FnOnce(Connection) -> Weight,
    ) {
        let (s, t) = (y.len(), self.z.len());
        'attempt: {
            let yv = &y[s - 1];
            if !connectable(scene, yv) {
                break 'attempt;
            }
            let tr = if MEDIA {
                self.transmittance.as_deref_mut()
            } else {
                None
            };
            let Some(joined) = join_in::<MEDIA>(scene, yv, &self.z[t - 1], tr) else {
                break 'attempt;
            };
            let value = joined.value * scale;
            let flights = JoinFlights {
                edge: joined.flights,
                light_back: y_back,
                camera_back: self.z_back,
            };
            let (w, mixture) = weight(Connection {
                light: y,
                camera: self.z,
                joined: &joined,
                raster: self.raster,
                flights,
            });
            if R::ACTIVE {
                if let Some(m) = mixture {
                    self.rec.mixture(m);
                }
                self.rec.completed(Completed {
                    s,
                    light: y,
                    camera: self.z,
                    weight: w,
                    value,
                    raster: self.raster,
                    alternatives: &[],
                });
            }
            *self.l += value * w as f32;
        }
        self.rec.lap(Work::Connection {
            s: s as u16,
            t: t as u16,
        });
    }

    /// Every strategy (s, t), 2 ≤ s ≤ min(|y|, k_max + 1 − t), joining z_{t−1} to the vertices
    /// of one light subpath `y` (bdpt's pairing), weighed by `weight`.
    #[inline]
    pub fn join_subpath(
        &mut self,
        scene: &Scene,
        y: &[PathVertex],
        mut weight: impl FnMut(Connection) -> Weight,
    ) {
        for s in 2..=y.len().min(self.max_k + 1 - self.z.len()) {
            self.join_in::<false>(scene, (&y[..s], 1.0), 1.0, &mut weight);
        }
    }

    /// `join_subpath`, through media when `MEDIA`: `y` with its walk's `back_flight`s.
    #[inline]
    pub fn join_subpath_in<const MEDIA: bool>(
        &mut self,
        scene: &Scene,
        y: &Subpath,
        mut weight: impl FnMut(Connection) -> Weight,
    ) {
        for s in 2..=y.len().min(self.max_k + 1 - self.z.len()) {
            let prefix = (&y.vertices[..s], y.back_flight(s - 1));
            self.join_in::<MEDIA>(scene, prefix, 1.0, &mut weight);
        }
    }
}

/// Segment limits of the camera walk: longest path (segments) and Russian roulette's start.
#[derive(Clone, Copy, Debug)]
pub struct Depths {
    pub max_depth: u32,
    pub rr_depth: u32,
}

/// The camera sample of `pixel` in `pass`: its walk and every technique with t ≥ 2 under
/// `policy`; returns the pixel's estimate (weighted by the film filter).
pub fn camera_sample<P: CameraPolicy, R: Recorder>(
    scene: &Scene,
    (pass, pixel): (Pass, u64),
    depths: Depths,
    policy: &mut P,
    scratch: &mut CameraScratch,
    rec: &mut R,
) -> Color {
    let mut cs = Sampler::for_item(Domain::Camera, pass.seed, pixel, pass.pass as u64);
    let Some(film) = pixel_sample(scene, pixel, &mut cs) else {
        return Color::ZERO;
    };
    let raster = film.raster;
    let limits = WalkLimits::camera(depths.max_depth, depths.rr_depth);
    if P::MEDIA {
        camera_subpath_in::<true>(scene, raster, &mut cs, limits, &mut scratch.camera);
    } else {
        camera_subpath_in::<false>(scene, raster, &mut cs, limits, &mut scratch.camera);
    }
    let mut transmittance =
        P::MEDIA.then(|| Sampler::for_item(Domain::Aux, pass.seed, pixel, pass.pass as u64));
    let camera = &scratch.camera;
    let z = &camera.vertices;
    policy.walked(scene, z, raster);
    policy.camera_walk(scene, camera);
    rec.begin_sample(pixel, film.weight);
    rec.lap(Work::CameraWalk);
    let reached = &mut scratch.reached;
    let max_k = depths.max_depth as usize;
    let mut ctx = SampleCtx { raster, rec };
    let mut l = Color::ZERO;
    for t in 2..=z.len() {
        policy.along_segment(scene, &z[..t], &mut ctx, &mut l);
        let zv = &z[t - 1];
        // s = 0: the walk hit an emitter at z_{t−1}.
        if t - 1 <= max_k {
            if let (Some(x0), Some(li)) = (zv.as_light_endpoint(), zv.emitter()) {
                let le = scene.lights[li as usize].emitted(x0.ng, x0.wo, x0.uv);
                if le != Color::ZERO {
                    let value = zv.beta * le;
                    let back = camera.back_flight(t - 1);
                    let walk = (&z[..t - 1], x0, back, value);
                    l += emitter_reached(scene, policy, walk, reached, &mut ctx);
                }
                ctx.rec.lap(Work::Connection { s: 0, t: t as u16 });
            }
        }
        if !connectable(scene, zv) {
            continue;
        }
        if policy.connects() {
            // s = 1: next-event estimation from z_{t−1}.
            if t <= max_k {
                let back = camera.back_flight(t - 1);
                l += next_event_weighted(scene, policy, (&z[..t], back), &mut cs, &mut ctx);
                ctx.rec.lap(Work::Connection { s: 1, t: t as u16 });
            }
            let mut joins = Joins {
                z: &z[..t],
                z_back: camera.back_flight(t - 1),
                max_k,
                raster,
                rec: &mut *ctx.rec,
                l: &mut l,
                transmittance: transmittance.as_mut(),
            };
            policy.connect(scene, &mut joins, &mut cs);
        }
        policy.at_vertex(scene, &z[..t], &mut ctx, &mut l);
    }
    policy.after_walk(scene, z, &mut ctx, &mut l);
    // s = 0 at infinity: the walk left the scene after its last vertex.
    if let Some(esc) = camera.escape {
        if z.len() <= max_k {
            for &li in &scene.infinite_lights {
                let le = scene.lights[li as usize].escaped(esc.dir);
                if le == Color::ZERO {
                    continue;
                }
                let x0 = PathVertex::light_escaped(li, esc.dir, esc.beta, esc.pdf_w);
                let value = esc.beta * le;
                let walk = (&z[..], x0, esc.back_flight, value);
                l += emitter_reached(scene, policy, walk, reached, &mut ctx);
            }
            ctx.rec.lap(Work::Connection {
                s: 0,
                t: z.len() as u16 + 1,
            });
        }
    }
    weighted(l, film.weight)
}

/// Strategy s = 0: the camera walk `camera` reached light endpoint `x0` (through media with the
/// free flight `back` of x0 → the walk's last vertex) with unweighted contribution `value`; the
/// path is assembled in `path` (weighed and reported as one).
fn emitter_reached<P: CameraPolicy, R: Recorder>(
    scene: &Scene,
    policy: &P,
    (camera, x0, back, value): (&[PathVertex], PathVertex, f32, Color),
    path: &mut Vec<PathVertex>,
    ctx: &mut SampleCtx<'_, R>,
) -> Color {
    path.clear();
    path.extend_from_slice(camera);
    path.push(x0);
    let flights = JoinFlights {
        camera_back: back,
        ..JoinFlights::default()
    };
    let (w, mixture) = policy.emitter_weight(scene, path, flights, ctx.raster);
    if R::ACTIVE {
        if let Some(m) = mixture {
            ctx.rec.mixture(m);
        }
        let n = path.len();
        ctx.rec.completed(Completed {
            s: 0,
            light: &path[n - 1..],
            camera: &path[..n - 1],
            weight: w,
            value,
            raster: ctx.raster,
            alternatives: &[],
        });
    }
    value * w as f32
}

/// Strategy s = 1 at z_{t−1} (`z` = z_0 … z_{t−1}, through media with the walk's free flight
/// `back` of z_{t−1} → z_{t−2}): one light chosen by power and sampled towards it
/// (`connect::next_event`'s three numbers from `sampler`).
fn next_event_weighted<P: CameraPolicy, R: Recorder>(
    scene: &Scene,
    policy: &P,
    (z, back): (&[PathVertex], f32),
    sampler: &mut Sampler,
    ctx: &mut SampleCtx<'_, R>,
) -> Color {
    let Some(NextEvent {
        x0,
        camera_end,
        value,
        flights,
    }) = (if P::MEDIA {
        next_event_in::<true>(scene, &z[z.len() - 1], sampler)
    } else {
        next_event_in::<false>(scene, &z[z.len() - 1], sampler)
    })
    else {
        return Color::ZERO;
    };
    let flights = JoinFlights {
        edge: flights,
        light_back: 1.0,
        camera_back: back,
    };
    let (w, mixture) = policy.next_event_weight(scene, z, (&x0, camera_end), flights, ctx.raster);
    if R::ACTIVE {
        if let Some(m) = mixture {
            ctx.rec.mixture(m);
        }
        ctx.rec.completed(Completed {
            s: 1,
            light: std::slice::from_ref(&x0),
            camera: z,
            weight: w,
            value,
            raster: ctx.raster,
            alternatives: &[],
        });
    }
    value * w as f32
}

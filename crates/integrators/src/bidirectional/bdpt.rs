//! `bdpt` — bidirectional path tracing (Veach & Guibas 1994; Veach 1997, ch. 10): per pixel
//! sample, one camera subpath and one light subpath, joined by every strategy (s, t) — s light
//! vertices and t camera vertices, k = s + t − 1 ≤ `max_depth` segments — and combined by MIS.
//!
//! - s = 0: the camera walk hits an emitter (or escapes to a light at infinity);
//! - s = 1: a fresh light sample towards the camera vertex (next-event estimation, as in `pt`);
//! - t = 1: the light vertex is joined to the pinhole and splatted (light tracing; `light`);
//! - s, t ≥ 2: a shadow ray between the two subpath ends.
//!
//! Weights come from the subpaths' stored densities (`pdf_fwd`, `pdf_rev`, filled by
//! `walk::random_walk`) with the ≤ 4 entries the connection changes patched, never a `Path`.
//! By default (`weights = recursive`) they run the O(1) per-vertex recursion of
//! `lt_core::path::SubpathMis` (Georgiev et al. 2012), each subpath's records formed once per
//! walk (`subpath::recursive_weight`); `weights = chain` builds the O(k) `lt_core::path::Chain`
//! of every strategy — the same arithmetic the from-scratch oracle runs, and the oracle the
//! recursion is held to per path (tests/bdpt_weights.rs). The two give each path the same
//! weight up to f64 rounding. `mis = none` (uniform weights) always takes the chain.
//! With `light_paths` = M ≠ N, camera sample j pairs with light subpath j mod M, every light
//! subpath is splatted once, and light tracing's weight carries n_k/n_s = M/N.
//!
//! Through participating media (a scene with `has_media`, chosen once per pass: `pass::<true>`)
//! both subpaths are walked by `subpath::media_walk` (medium vertices where free flights scatter,
//! null boundaries crossed), every join of (s, t) carries the edge's transmittance estimate, and
//! the weights read the walks' volume-measure densities with the join's patched densities taking
//! their free flights (`strategy_weight::with_chain_in::<true>`, `recursive_weight`'s
//! `with_flight`); never the estimate.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `mis` | power/balance/none | power | heuristic over the strategies (none: uniform weights) |
//! | `light_paths` | u64 | the pixel count | light subpaths per pass |
//! | `weights` | recursive/chain | recursive | O(1) per-vertex recursion or the O(k) chain per strategy (`mis = none`: the chain) |

use crate::film::splat::{splat_pass_with, Pass, Splats, Worker};
use crate::params::ParamReader;
use crate::record::tally::{tallied_pass, ItemTally, PassClock, PassTally, Tally};
use crate::record::{NoRecord, Recorder, Work};
use crate::subpath::camera_loop::{
    camera_sample, CameraPolicy, CameraScratch, Depths, Joins, Weight,
};
use crate::subpath::connect::{nee_density, splat_light_subpath_in, JoinFlights};
use crate::subpath::media_walk::light_subpath_in;
use crate::subpath::recursive_weight::{self as recursive, camera_records, light_records};
pub use crate::subpath::strategy_weight::{mis_weight, mis_weight_in, with_chain, with_chain_in};
pub use crate::subpath::strategy_weight::{EndEvals, Split};
use crate::subpath::walk::{Subpath, WalkLimits};
use crate::Integrator;
use lt_core::bsdf::BsdfEval;
use lt_core::math::{Color, Vec2};
use lt_core::path::{CameraMis, Heuristic, LightMis, PathVertex, SubpathMis, TechniqueSet};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use lt_estimators::Image;

#[derive(Clone, Copy, Debug)]
pub struct BdptParams {
    pub max_depth: u32,
    pub rr_depth: u32,
    pub mis: Heuristic,
    /// `None`: one light subpath per pixel.
    pub light_paths: Option<u64>,
    pub weights: BdptWeights,
}

/// How bdpt computes a strategy's MIS weight (the same number up to f64 rounding).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BdptWeights {
    /// O(1) per strategy from per-vertex records (`subpath::recursive_weight`); power and
    /// balance heuristics (uniform weights take the chain).
    Recursive,
    /// O(k) per strategy: the path's density chain (`subpath::strategy_weight`), the oracle.
    Chain,
}

impl BdptWeights {
    pub fn parse(v: &str) -> Result<BdptWeights, String> {
        match v {
            "recursive" => Ok(BdptWeights::Recursive),
            "chain" => Ok(BdptWeights::Chain),
            _ => Err(format!("'{v}' is not recursive or chain")),
        }
    }
}

impl BdptParams {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<BdptParams, String> {
        Ok(BdptParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
            mis: r
                .get_with("mis", Heuristic::parse)?
                .unwrap_or(Heuristic::Power),
            light_paths: r.light_paths()?,
            weights: r
                .get_with("weights", BdptWeights::parse)?
                .unwrap_or(BdptWeights::Recursive),
        })
    }
}

pub struct Bdpt {
    pub params: BdptParams,
}

/// Per-thread buffers of one sample.
pub struct Scratch {
    camera: CameraScratch,
    light: Subpath,
    /// The recursion's records of the light and the camera subpath (`recursive_weight`).
    light_mis: Vec<LightMis>,
    camera_mis: Vec<CameraMis>,
}

/// What one camera sample pairs: the pixel it samples (none for items past the pixel count), the
/// light subpath it connects to, and whether this sample splats that light subpath's t = 1
/// strategies (each light subpath is splatted by exactly one sample).
#[derive(Clone, Copy, Debug)]
struct Pairing {
    pixel: Option<u64>,
    light_index: u64,
    splat_light: bool,
}

/// bdpt's policy in the camera loop: every camera vertex joins every vertex of the one light
/// subpath `y` it is paired with; weights from the stored densities (`strategy_weight`).
/// `MEDIA`: the scene has participating media (chosen once per pass: `Bdpt::item_in`).
struct Policy<'a, const MEDIA: bool> {
    /// With its walk's free flights (`Subpath::back_flight`, through media).
    y: &'a Subpath,
    /// Next-event estimation's density of y_0 from y_1.
    light_nee: f64,
    h: Heuristic,
    /// M/N.
    ratio: f64,
    /// With recursive weights: the recursion and the records of `y` and of the camera walk
    /// (formed in `walked`); `None` weighs by the chain.
    recursion: Option<Records<'a>>,
}

/// What recursive weights read: the pass's recursion and both subpaths' records.
struct Records<'a> {
    mis: SubpathMis,
    light: &'a [LightMis],
    camera: &'a mut Vec<CameraMis>,
}

impl<const MEDIA: bool> CameraPolicy for Policy<'_, MEDIA> {
    const MEDIA: bool = MEDIA;

    fn walked(&mut self, scene: &Scene, z: &[PathVertex], _: Vec2) {
        if let Some(r) = &mut self.recursion {
            camera_records(scene, &r.mis, z, r.camera);
        }
    }

    fn emitter_weight(
        &self,
        scene: &Scene,
        path: &[PathVertex],
        flights: JoinFlights,
        _: Vec2,
    ) -> Weight {
        if let Some(r) = &self.recursion {
            let w = recursive::emitter_weight::<MEDIA>(
                scene,
                &r.mis,
                path,
                r.camera,
                flights.camera_back,
            );
            return (w, None);
        }
        let (split, mut evals) = Split::reached(path);
        evals.flights = Some(flights);
        let w = mis_weight_in::<MEDIA>(scene, split, evals, self.h, self.ratio);
        (w, None)
    }

    fn next_event_weight(
        &self,
        scene: &Scene,
        z: &[PathVertex],
        (x0, camera_end): (&PathVertex, BsdfEval),
        flights: JoinFlights,
        _: Vec2,
    ) -> Weight {
        if let Some(r) = &self.recursion {
            let w = recursive::next_event_weight::<MEDIA>(
                scene,
                &r.mis,
                (z, r.camera),
                (x0, camera_end),
                flights,
            );
            return (w, None);
        }
        let (split, mut evals) = Split::next_event(z, x0, camera_end);
        evals.flights = Some(flights);
        let w = mis_weight_in::<MEDIA>(scene, split, evals, self.h, self.ratio);
        (w, None)
    }

    fn connect<R: Recorder>(&mut self, scene: &Scene, joins: &mut Joins<'_, R>, _: &mut Sampler) {
        if let Some(r) = &self.recursion {
            let (mis, ly, zr) = (&r.mis, r.light, &r.camera[..]);
            joins.join_subpath_in::<MEDIA>(scene, self.y, |c| {
                (recursive::connection_weight::<MEDIA>(mis, c, ly, zr), None)
            });
            return;
        }
        joins.join_subpath_in::<MEDIA>(scene, self.y, |c| {
            let (split, evals) = Split::connection(c, self.light_nee);
            let w = mis_weight_in::<MEDIA>(scene, split, evals, self.h, self.ratio);
            (w, None)
        });
    }
}

impl Bdpt {
    fn light_paths(&self, scene: &Scene) -> u64 {
        self.params
            .light_paths
            .unwrap_or(scene.camera.pixel_count() as u64)
    }

    fn ratio(&self, scene: &Scene) -> f64 {
        self.light_paths(scene) as f64 / scene.camera.pixel_count() as f64
    }

    /// The per-vertex recursion when the weights take it (`weights = recursive` with the power or
    /// balance heuristic: Veach's counts, light tracing's M/N), else `None` (the chain).
    fn recursion(&self, scene: &Scene) -> Option<SubpathMis> {
        let h = self.params.mis;
        let exact = matches!(h, Heuristic::Power | Heuristic::Balance);
        (self.params.weights == BdptWeights::Recursive && exact)
            .then(|| SubpathMis::new(h, TechniqueSet::new(true, 0.0), self.ratio(scene)))
    }

    /// One camera sample as `pair` says; returns the pixel's own estimate (strategies t ≥ 2).
    fn sample<const MEDIA: bool, R: Recorder>(
        &self,
        scene: &Scene,
        pass: Pass,
        pair: Pairing,
        worker: &mut Worker<'_, Scratch, R>,
    ) -> Color {
        let Pass { seed, pass } = pass;
        let Pairing {
            pixel,
            light_index,
            splat_light,
        } = pair;
        let Worker {
            splats,
            scratch,
            rec,
        } = worker;
        let ratio = self.ratio(scene);
        let h = self.params.mis;
        let max_k = self.params.max_depth as usize;
        let mut ls = Sampler::for_item(Domain::Light, seed, light_index, pass as u64);
        light_subpath_in::<MEDIA>(
            scene,
            &mut ls,
            WalkLimits::light(self.params.max_depth, self.params.rr_depth),
            &mut scratch.light,
        );
        let light = &scratch.light;
        let y = &light.vertices;
        let light_nee = if y.len() >= 2 {
            nee_density(scene, &y[0], &y[1])
        } else {
            0.0
        };
        let mis = self.recursion(scene);
        if let Some(mis) = &mis {
            light_records(scene, mis, y, light_nee, &mut scratch.light_mis);
        }
        let ly = &scratch.light_mis[..];
        rec.lap(Work::LightWalk);

        // t = 1: every connectable light vertex joined to the pinhole.
        if splat_light {
            let scale = 1.0 / self.light_paths(scene) as f32;
            // A thin lens draws its lens points from the light path's own lens stream (as vcm
            // does, so vcm without merging takes bdpt's paths).
            let mut lens = Sampler::for_item(Domain::Lens, seed, light_index, pass as u64);
            let rec = &mut **rec;
            splat_light_subpath_in::<MEDIA, R>(
                scene,
                y,
                max_k,
                scale,
                &mut lens,
                splats,
                rec,
                |s, c| {
                    if let Some(mis) = &mis {
                        let back = light.back_flight(s - 1);
                        let w = recursive::light_tracing_weight::<MEDIA>(
                            scene,
                            mis,
                            (&y[..s], ly),
                            c,
                            back,
                        );
                        return (w, None);
                    }
                    let camera_only = [c.camera];
                    let split = Split {
                        light: &y[..s],
                        camera: &camera_only,
                        light_nee,
                    };
                    let flights = JoinFlights {
                        edge: c.flights,
                        light_back: light.back_flight(s - 1),
                        camera_back: 1.0,
                    };
                    let evals = EndEvals {
                        light_end: c.eval,
                        camera_end: None,
                        flights: Some(flights),
                    };
                    (mis_weight_in::<MEDIA>(scene, split, evals, h, ratio), None)
                },
            );
        }
        let Some(pixel) = pixel else {
            return Color::ZERO;
        };
        let mut policy = Policy::<MEDIA> {
            y: light,
            light_nee,
            h,
            ratio,
            recursion: mis.map(|mis| Records {
                mis,
                light: ly,
                camera: &mut scratch.camera_mis,
            }),
        };
        let depths = Depths {
            max_depth: self.params.max_depth,
            rr_depth: self.params.rr_depth,
        };
        camera_sample(
            scene,
            (Pass { seed, pass }, pixel),
            depths,
            &mut policy,
            &mut scratch.camera,
            &mut **rec,
        )
    }

    /// One pass with every path reported to `rec` (for `lt mis-check`), pixel by pixel on one
    /// thread; the image is discarded.
    pub fn record_pass<R: Recorder>(&self, scene: &Scene, seed: u64, pass: u32, rec: &mut R) {
        let n = scene.camera.pixel_count() as u64;
        let m = self.light_paths(scene);
        let mut scratch = self.scratch();
        let mut splats = Splats::new(scene.camera.width, scene.camera.height);
        let mut worker = Worker {
            splats: &mut splats,
            scratch: &mut scratch,
            rec,
        };
        for i in 0..n.max(m) {
            self.item(scene, Pass { seed, pass }, i, &mut worker);
        }
    }

    pub fn scratch(&self) -> Scratch {
        Scratch {
            camera: CameraScratch::new(self.params.max_depth),
            light: Subpath::with_capacity(self.params.max_depth as usize),
            light_mis: Vec::with_capacity(self.params.max_depth as usize + 1),
            camera_mis: Vec::with_capacity(self.params.max_depth as usize + 2),
        }
    }

    /// Work item i of a pass (0 … max(N, M)−1): pixel i (when i < N) with light subpath i mod M, splatting that
    /// light subpath when i < M; items N … M−1 (M > N) splat their light subpath only. Through
    /// media when the scene has them (callers outside the pass loop: the pyramid, tests).
    pub fn item<R: Recorder>(
        &self,
        scene: &Scene,
        pass: Pass,
        i: u64,
        worker: &mut Worker<'_, Scratch, R>,
    ) {
        if scene.has_media {
            self.item_in::<true, R>(scene, pass, i, worker)
        } else {
            self.item_in::<false, R>(scene, pass, i, worker)
        }
    }

    /// `item` with the walks and joins through media or not (`MEDIA`), as a pass picks once.
    pub fn item_in<const MEDIA: bool, R: Recorder>(
        &self,
        scene: &Scene,
        pass: Pass,
        i: u64,
        worker: &mut Worker<'_, Scratch, R>,
    ) {
        let n = scene.camera.pixel_count() as u64;
        let m = self.light_paths(scene);
        let pair = Pairing {
            pixel: (i < n).then_some(i),
            light_index: i % m,
            splat_light: i < m,
        };
        worker.rec.begin_item(i);
        let l = self.sample::<MEDIA, R>(scene, pass, pair, worker);
        if let Some(p) = pair.pixel {
            worker.splats.add_to_pixel(p as u32, l);
        }
    }
}

/// Work items per splat chunk (fixed, so the image does not depend on the thread count).
const CHUNK: u64 = 256;

impl Bdpt {
    /// `render_pass` with every technique's contributions and time tallied (`crate::record::tally`):
    /// the same image, bit for bit.
    pub fn tally_pass(
        &self,
        scene: &Scene,
        seed: u64,
        pass: u32,
        every: u64,
    ) -> (Image, u64, PassTally) {
        let clock = PassClock::start();
        let items = (scene.camera.pixel_count() as u64).max(self.light_paths(scene));
        let (img, invalid, tally): (Image, u64, ItemTally) = tallied_pass(
            scene,
            pass,
            every,
            (items, CHUNK),
            || self.scratch(),
            |i, splats, scratch, rec: &mut Tally| {
                let mut worker = Worker {
                    splats,
                    scratch,
                    rec,
                };
                self.item(scene, Pass { seed, pass }, i, &mut worker)
            },
        );
        (img, invalid, tally.finish(clock, &[]))
    }
}

impl Integrator for Bdpt {
    fn name(&self) -> &'static str {
        "bdpt"
    }

    fn render_pass(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
        // Media or not, chosen once per pass: each is its own monomorphised loop.
        if scene.has_media {
            self.pass::<true>(scene, seed, pass)
        } else {
            self.pass::<false>(scene, seed, pass)
        }
    }
}

impl Bdpt {
    fn pass<const MEDIA: bool>(&self, scene: &Scene, seed: u64, pass: u32) -> (Image, u64) {
        let cam = &scene.camera;
        let n = cam.pixel_count() as u64;
        let items = n.max(self.light_paths(scene));
        let (w, h) = (cam.width as usize, cam.height as usize);
        splat_pass_with(
            w,
            h,
            items,
            CHUNK,
            || self.scratch(),
            |i, splats, scratch| {
                let mut worker = Worker {
                    splats,
                    scratch,
                    rec: &mut NoRecord,
                };
                self.item_in::<MEDIA, NoRecord>(scene, Pass { seed, pass }, i, &mut worker)
            },
        )
    }
}

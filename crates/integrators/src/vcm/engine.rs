//! Vertex connection and merging (Georgiev, Křivánek, Davidovič & Slusallek 2012), shared by
//! `vcm` and `bpm` and owned by neither: one pass traces M light subpaths, indexes their
//! non-delta vertices, then per pixel traces a camera subpath that at every vertex
//!
//! - **connects** as `bdpt` does — s = 0 (the walk hits a light), s = 1 (next-event
//!   estimation), s ≥ 2 (shadow rays to light subpath j mod M), t = 1 (light subpath j splatted
//!   to the camera) — with the same random numbers in the same order, and
//! - **merges** with every stored light vertex within the pass's radius rᵢ (disk kernel), the
//!   light vertex's incoming direction evaluated in the camera vertex's BSDF.
//!
//! All techniques share one MIS (`lt_core::path::SubpathMis`): merging at x_i counts
//! η = M π rᵢ² times a connection (Georgiev et al. 2012's η_VCM). The per-vertex
//! records (their dVCM/dVC/dVM) are formed once per subpath from the walks' stored densities, so
//! a weight is O(1). Radii shrink as rᵢ = r₀ · i^((α−1)/2), i = 1, 2, … (Knaus & Zwicker's
//! rate, as in SmallVCM, α = 0.75); r₀ is pixel-footprint relative by default (at the mean
//! primary-hit distance: one radius for the whole pass, which η needs) or scene relative.

use crate::density::radius::InitialRadius;
pub use crate::film::splat::pixel_of;
use crate::film::splat::{splat_pass_with, Pass, Splats, Worker};
use crate::params::ParamReader;
use crate::record::tally::{pool_cpu_seconds, tallied_pass, PassClock, PassTally, Tally};
use crate::record::{Merged, NoRecord, Recorder, Work};
use crate::subpath::camera_loop::{
    camera_sample, CameraPolicy, CameraScratch, Connection, Depths, Joins, SampleCtx, Weight,
};
use crate::subpath::connect::{emission_densities, nee_density, splat_light_subpath, Joined};
use crate::subpath::strategy_weight::{with_chain, EndEvals, Split};
use crate::subpath::walk::{light_subpath, reverse_density, Subpath, WalkLimits};
use crate::{ProgressLog, ProgressiveRun};
use lt_core::bsdf::{BsdfEval, TransportMode};
use lt_core::math::{Color, Vec2, Vec3, PI};
use lt_core::path::camis::Weighed;
use lt_core::path::scatter::{connectable, connectable_inside};
use lt_core::path::subpath_mis::{ConnectionDensities, NextEventDensities, VertexTechniques};
use lt_core::path::{
    camis, CameraMis, Chain, Correlation, Heuristic, LightMis, PathVertex, SubpathMis, Technique,
    TechniqueSet, VertexKind,
};
use lt_core::sampling::{Domain, Sampler};
use lt_core::spatial::PointGrid;
use lt_core::Scene;
use lt_estimators::Image;
use rayon::prelude::*;
use std::sync::Arc;

/// The techniques and schedule of a VCM-family estimator.
#[derive(Clone, Copy, Debug)]
pub struct VcmParams {
    pub max_depth: u32,
    pub rr_depth: u32,
    pub mis: Heuristic,
    /// `None`: one light subpath per pixel.
    pub light_paths: Option<u64>,
    pub radius: InitialRadius,
    pub alpha: f64,
    /// Connections s ≥ 1 (bdpt's techniques); s = 0 always runs.
    pub connections: bool,
    pub merging: bool,
    /// Correlation-aware MIS for merging (`lt_core::path::camis`): every weight from the full
    /// path's densities instead of the per-vertex recursion. Off by default.
    pub correlation_aware: bool,
    /// Vertex connections s ≥ 2, t ≥ 2 (with `connections`); off keeps next-event estimation
    /// and light tracing. Off needs full-path weights (`SubpathMis` counts every connection).
    pub vertex_connections: bool,
}

/// SmallVCM's radius reduction.
pub const DEFAULT_ALPHA: f64 = 0.75;

/// Which techniques a VCM-family estimator runs besides light tracing (t = 1) and the camera
/// walk reaching a light (s = 0), which always run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Techniques {
    /// Connections s ≥ 1, t ≥ 2 (bdpt's techniques).
    pub connections: bool,
    /// Merging at camera vertices (photon mapping's technique).
    pub merging: bool,
}

impl Techniques {
    /// `vcm`: connections and merging under one MIS.
    pub const VCM: Techniques = Techniques {
        connections: true,
        merging: true,
    };
    /// `bpm`: merging without connections (Georgiev et al. 2012's bidirectional photon mapping).
    pub const BPM: Techniques = Techniques {
        connections: false,
        merging: true,
    };
    /// `vcm merging=false`: bdpt's techniques under VCM's bookkeeping.
    pub const CONNECTIONS: Techniques = Techniques {
        connections: true,
        merging: false,
    };
}

impl VcmParams {
    /// Reads the keys common to `vcm` and `bpm`.
    pub fn read(
        scene: &Scene,
        r: &ParamReader,
        who: &str,
        techniques: Techniques,
    ) -> Result<VcmParams, String> {
        let base = VcmParams::read_base(scene, r, who, Heuristic::Power)?;
        Ok(VcmParams {
            light_paths: r.light_paths()?,
            connections: techniques.connections,
            merging: techniques.merging,
            correlation_aware: r.get::<bool>("correlation_aware")?.unwrap_or(false),
            // bpm has no connections to turn off.
            vertex_connections: if techniques.connections {
                r.get::<bool>("vertex_connections")?.unwrap_or(true)
            } else {
                true
            },
            ..base
        })
    }

    /// The keys every VCM-family estimator reads — `max_depth`, `rr_depth`, `mis` (default
    /// `mis`), the initial radius and `alpha` — with one light subpath per pixel, every technique
    /// and recursive weights; refuses an orthographic camera.
    pub fn read_base(
        scene: &Scene,
        r: &ParamReader,
        who: &str,
        mis: Heuristic,
    ) -> Result<VcmParams, String> {
        if scene.camera.is_delta_direction() {
            // Its MIS records count light tracing as a technique; with a camera that no
            // connection reaches, that share would be lost.
            return Err(format!(
                "{who} cannot render through an orthographic camera (a delta in direction: no \
                 light-tracing connection reaches it); use pt or bdpt"
            ));
        }
        let alpha = r.get::<f64>("alpha")?.unwrap_or(DEFAULT_ALPHA);
        if !(alpha > 0.0 && alpha <= 1.0) {
            return Err(format!("{who}: alpha must be in (0, 1], got {alpha}"));
        }
        Ok(VcmParams {
            max_depth: r.max_depth(scene)?,
            rr_depth: r.rr_depth(scene)?,
            mis: r.get_with("mis", Heuristic::parse)?.unwrap_or(mis),
            light_paths: None,
            radius: InitialRadius::read(r, who)?,
            alpha,
            connections: true,
            merging: true,
            correlation_aware: false,
            vertex_connections: true,
        })
    }

    /// Whether weights come from the full path's densities (`camis::weigh`) rather than the
    /// per-vertex recursion: the recursion counts every connection and one η for every pixel.
    pub fn full_path_weights(&self) -> bool {
        self.correlation_aware || (self.connections && !self.vertex_connections)
    }

    pub fn light_path_count(&self, scene: &Scene) -> u64 {
        self.light_paths
            .unwrap_or(scene.camera.pixel_count() as u64)
    }

    /// r_i / r_0 of pass `pass` (0-based; iteration i = pass + 1).
    pub fn radius_scale(&self, pass: u32) -> f64 {
        ((pass + 1) as f64).powf((self.alpha - 1.0) / 2.0)
    }
}

/// r₀ in scene units: footprint-relative radii use the footprint at the mean distance of primary
/// hits over a fixed grid of pixel centres (deterministic, and one radius for the whole pass).
pub fn initial_radius(scene: &Scene, radius: InitialRadius) -> f32 {
    match radius {
        InitialRadius::Pixels(k) => {
            let cam = &scene.camera;
            let step = (cam.width.max(cam.height) / 64).max(1);
            let (mut sum, mut n) = (0.0f64, 0u64);
            for y in (0..cam.height).step_by(step as usize) {
                for x in (0..cam.width).step_by(step as usize) {
                    let ray = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                    if let Some(hit) = scene.intersect(&ray) {
                        sum += ((hit.p - ray.o).dot(cam.forward())) as f64;
                        n += 1;
                    }
                }
            }
            let distance = if n > 0 {
                (sum / n as f64) as f32
            } else {
                scene.bounding_sphere.1
            };
            k * cam.pixel_footprint(distance)
        }
        InitialRadius::Scene(f) => f * 2.0 * scene.bounding_sphere.1,
        InitialRadius::Absolute(r) => r,
    }
}

/// The light subpaths of one pass with their MIS records and the merge index. Paths are kept in
/// the fixed chunks they were traced in (no copy into one array), and a run reuses the buffers
/// from pass to pass (`Engine::trace_light_paths_into`).
#[derive(Default)]
pub struct LightPaths {
    chunks: Vec<LightChunk>,
    /// Mergeable vertices, compact (what a merge reads, contiguous).
    merge_vertex: Vec<MergeVertex>,
    merge_positions: Vec<Vec3>,
    grid: Option<PointGrid>,
}

/// Light subpaths c·LIGHT_CHUNK … of one pass.
#[derive(Default)]
struct LightChunk {
    vertices: Vec<PathVertex>,
    mis: Vec<LightMis>,
    /// Path j of the chunk is `vertices[starts[j]..starts[j + 1]]`.
    starts: Vec<u32>,
}

impl LightPaths {
    pub fn path(&self, j: usize) -> (&[PathVertex], &[LightMis]) {
        let c = &self.chunks[j / LIGHT_CHUNK as usize];
        let l = j % LIGHT_CHUNK as usize;
        let (a, b) = (c.starts[l] as usize, c.starts[l + 1] as usize);
        (&c.vertices[a..b], &c.mis[a..b])
    }

    /// Stored light vertices (for the record and memory figures).
    pub fn merge_candidates(&self) -> usize {
        self.merge_vertex.len()
    }
}

/// What a merge reads of a stored light vertex y_j, in one place.
#[derive(Clone, Copy, Debug)]
struct MergeVertex {
    /// Unit direction towards y_{j−1}: the light's incoming direction ω_y.
    wi: Vec3,
    /// |n_g · ω_y| of y_j's own surface.
    cos_g: f32,
    /// y_j's geometric normal.
    ng: Vec3,
    beta: Color,
    /// Segments from the light (j).
    segments: u32,
    /// Where the vertex is kept: chunk and index in it (for the record).
    chunk: u32,
    index: u32,
    /// Turns a solid-angle density at y_j towards y_{j−1} into y_{j−1}'s measure
    /// (`walk::reverse_density` of y_{j−1} from y_j, factored: |cos at y_{j−1}| / d², 1 at
    /// infinity, 0 on a point light).
    to_prev: f32,
    mis: LightMis,
}

/// Whether a connection technique can join `a` and `b` (both non-delta).
#[inline]
fn joinable(scene: &Scene, a: &PathVertex, b: &PathVertex) -> bool {
    connectable(scene, a) && connectable(scene, b)
}

/// Light subpaths traced per parallel chunk (fixed: the order of the flat arrays, hence every
/// sum, does not depend on the thread count).
const LIGHT_CHUNK: u64 = 1024;

/// Work items per splat chunk, as in `bdpt` (same order of floating-point sums).
const CHUNK: u64 = 256;

/// One pass of the estimator.
pub struct PassSetup {
    pub mis: SubpathMis,
    pub radius: f32,
    /// η = M π r² (0 without merging).
    pub eta: f64,
    /// 1 / (M π r²): the density-estimation normalisation of one merge.
    merge_norm: f32,
    light_paths: u64,
    /// With full-path weights: the techniques and sample counts they read.
    camis: Option<FullPathSetup>,
}

/// Which pixels merge (row-major, one flag per pixel): merging's count η is that of the pixel the
/// path lands in, 0 where the flag is off (efficiency-aware MIS's per-pixel choice).
pub type MergeMask = Arc<[bool]>;

/// What full-path weights (`camis::weigh`) read besides a path's densities.
#[derive(Clone, Debug)]
struct FullPathSetup {
    set: TechniqueSet,
    heuristic: Heuristic,
    /// M, light subpaths per pass (N_VM).
    light_paths: f64,
    /// M/N.
    ratio: f64,
    /// Merging at x_i counted η ρ_i (correlation-aware) instead of η.
    correlation: bool,
    merge_mask: Option<MergeMask>,
    width: u32,
    height: u32,
}

impl FullPathSetup {
    /// Whether merging runs for paths landing at `raster`.
    fn merges_at(&self, raster: Vec2) -> bool {
        match &self.merge_mask {
            None => true,
            Some(mask) => mask[pixel_of(raster, self.width, self.height)],
        }
    }

    /// The weight of `technique` on `chain`, whose primary hit lies `distance` from the camera
    /// and which lands at `raster`.
    fn weigh(&self, chain: &Chain, technique: Technique, distance: f32, raster: Vec2) -> Weighed {
        // ρ always, for `Mixture::merges_correlated`; in the weights only when correlation-aware.
        let corr = Correlation::new(self.light_paths, distance as f64);
        let mut set = self.set;
        if !self.merges_at(raster) {
            set.merging_eta = 0.0;
        }
        camis::weigh_full(
            chain,
            set,
            Some(&corr),
            self.correlation,
            technique,
            self.heuristic,
        )
    }

    /// The weight of connection technique (s, t) formed by `split` (`strategy_weight`).
    fn connection(
        &self,
        scene: &Scene,
        split: Split,
        evals: EndEvals,
        distance: f32,
        raster: Vec2,
    ) -> Weighed {
        with_chain(scene, split, evals, self.ratio, |chain, s| {
            self.weigh(chain, Technique::Connect(s), distance, raster)
        })
    }
}

pub struct Engine<'a> {
    pub params: VcmParams,
    pub scene: &'a Scene,
    /// Per-pixel merging (`MergeMask`); every pixel merges without one.
    pub merge_mask: Option<MergeMask>,
}

/// Per-thread buffers of one camera sample.
pub struct Scratch {
    walk: CameraScratch,
    records: Vec<CameraMis>,
}

impl<'a> Engine<'a> {
    pub fn new(params: &VcmParams, scene: &'a Scene) -> Engine<'a> {
        Engine {
            params: *params,
            scene,
            merge_mask: None,
        }
    }

    pub fn setup(&self, r0: f32, pass: u32) -> PassSetup {
        let p = self.params;
        let m = p.light_path_count(self.scene);
        let n = self.scene.camera.pixel_count() as f64;
        let radius = (r0 as f64 * p.radius_scale(pass)) as f32;
        let eta = if p.merging {
            m as f64 * PI as f64 * (radius as f64).powi(2)
        } else {
            0.0
        };
        let set = TechniqueSet {
            vertex_connections: p.connections && p.vertex_connections,
            ..TechniqueSet::new(p.connections, eta)
        };
        let cam = &self.scene.camera;
        PassSetup {
            mis: SubpathMis::new(p.mis, set, m as f64 / n),
            radius,
            eta,
            merge_norm: (1.0 / eta) as f32,
            light_paths: m,
            camis: (p.full_path_weights() || self.merge_mask.is_some()).then(|| FullPathSetup {
                set,
                heuristic: p.mis,
                light_paths: m as f64,
                ratio: m as f64 / n,
                correlation: p.correlation_aware,
                merge_mask: self.merge_mask.clone(),
                width: cam.width,
                height: cam.height,
            }),
        }
    }

    /// Traces the pass's light subpaths and forms their MIS records (and the merge index).
    pub fn trace_light_paths(&self, setup: &PassSetup, seed: u64, pass: u32) -> LightPaths {
        let mut out = LightPaths::default();
        self.trace_light_paths_into(setup, seed, pass, &mut out);
        out
    }

    /// `trace_light_paths` into `out`, reusing its buffers.
    pub fn trace_light_paths_into(
        &self,
        setup: &PassSetup,
        seed: u64,
        pass: u32,
        out: &mut LightPaths,
    ) {
        let scene = self.scene;
        let m = setup.light_paths;
        let n_chunks = m.div_ceil(LIGHT_CHUNK) as usize;
        out.chunks.resize_with(n_chunks, LightChunk::default);
        out.chunks
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, chunk)| {
                let c = c as u64;
                let mut sub = Subpath::with_capacity(self.params.max_depth as usize);
                chunk.vertices.clear();
                chunk.mis.clear();
                chunk.starts.clear();
                chunk.starts.push(0);
                for j in c * LIGHT_CHUNK..((c + 1) * LIGHT_CHUNK).min(m) {
                    let mut ls = Sampler::for_item(Domain::Light, seed, j, pass as u64);
                    light_subpath(
                        scene,
                        &mut ls,
                        WalkLimits::light(self.params.max_depth, self.params.rr_depth),
                        &mut sub,
                    );
                    light_records(scene, &setup.mis, &sub.vertices, &mut chunk.mis);
                    chunk.vertices.extend_from_slice(&sub.vertices);
                    chunk.starts.push(chunk.vertices.len() as u32);
                }
            });
        out.merge_vertex.clear();
        out.merge_positions.clear();
        out.grid = None;
        if !self.params.merging {
            return;
        }
        for (c, chunk) in out.chunks.iter().enumerate() {
            for w in chunk.starts.windows(2) {
                for (d, idx) in (w[0] + 1..w[1]).enumerate() {
                    let mis = chunk.mis[idx as usize];
                    if !mis.mergeable {
                        continue;
                    }
                    let (y, before) = (
                        &chunk.vertices[idx as usize],
                        &chunk.vertices[idx as usize - 1],
                    );
                    out.merge_vertex.push(MergeVertex {
                        wi: y.wo,
                        cos_g: y.ng.dot(y.wo).abs(),
                        ng: y.ng,
                        beta: y.beta,
                        segments: d as u32 + 1,
                        chunk: c as u32,
                        index: idx,
                        to_prev: reverse_density(before, y, 1.0),
                        mis,
                    });
                    out.merge_positions.push(y.p);
                }
            }
        }
        out.grid = Some(PointGrid::build(&out.merge_positions, 2.0 * setup.radius));
    }

    pub fn scratch(&self) -> Scratch {
        Scratch {
            walk: CameraScratch::new(self.params.max_depth),
            records: Vec::with_capacity(self.params.max_depth as usize + 1),
        }
    }

    /// One pass's image: pixel estimates plus light-tracing splats. Returns (image, invalid).
    pub fn render_pass(
        &self,
        setup: &PassSetup,
        lights: &LightPaths,
        seed: u64,
        pass: u32,
    ) -> (Image, u64) {
        let cam = &self.scene.camera;
        let n = cam.pixel_count() as u64;
        let items = n.max(setup.light_paths);
        splat_pass_with(
            cam.width as usize,
            cam.height as usize,
            items,
            CHUNK,
            || self.scratch(),
            |i, splats, scratch| {
                let inputs = PassInputs {
                    setup,
                    lights,
                    pass: Pass { seed, pass },
                };
                self.item_into(&inputs, i, (splats, scratch, &mut NoRecord))
            },
        )
    }

    /// Work item i: pixel i (i < N) with light subpath i mod M, splatting light subpath i (i < M),
    /// exactly as `bdpt` pairs them.
    pub fn item<R: Recorder>(
        &self,
        inputs: &PassInputs,
        i: u64,
        worker: &mut Worker<'_, Scratch, R>,
    ) {
        let PassInputs {
            setup,
            lights,
            pass: Pass { seed, pass },
        } = *inputs;
        let n = self.scene.camera.pixel_count() as u64;
        let m = setup.light_paths;
        let light = lights.path((i % m) as usize);
        worker.rec.begin_item(i);
        if i < m && self.params.connections {
            // A thin lens draws its lens points from the light path's own lens stream.
            let mut lens = Sampler::for_item(Domain::Lens, seed, i, pass as u64);
            self.splat_light_path(setup, light, &mut lens, worker.splats, worker.rec);
        }
        if i < n {
            let l = self.camera_sample(inputs, light, i, worker);
            worker.splats.add_to_pixel(i as u32, l);
        }
    }

    /// `item` with its worker assembled from (splats, scratch, recorder).
    pub fn item_into<R: Recorder>(
        &self,
        inputs: &PassInputs,
        i: u64,
        (splats, scratch, rec): (&mut Splats, &mut Scratch, &mut R),
    ) {
        let mut worker = Worker {
            splats,
            scratch,
            rec,
        };
        self.item(inputs, i, &mut worker)
    }

    /// t = 1: every connectable vertex of one light subpath joined to the pinhole.
    fn splat_light_path<R: Recorder>(
        &self,
        setup: &PassSetup,
        (y, ly): (&[PathVertex], &[LightMis]),
        lens: &mut Sampler,
        splats: &mut Splats,
        rec: &mut R,
    ) {
        let scene = self.scene;
        let cam = &scene.camera;
        let scale = 1.0 / setup.light_paths as f32;
        let max_k = self.params.max_depth as usize;
        // One value per light subpath, read by every correlation-aware t = 1 weight.
        let nee = if setup.camis.is_some() {
            light_nee(scene, y)
        } else {
            0.0
        };
        splat_light_subpath(scene, y, max_k, scale, lens, splats, rec, |s, c| {
            let camera = c.camera;
            let yv = &y[s - 1];
            if let Some(camis) = &setup.camis {
                let split = Split {
                    light: &y[..s],
                    camera: std::slice::from_ref(&camera),
                    light_nee: nee,
                };
                let evals = EndEvals {
                    light_end: c.eval,
                    camera_end: None,
                };
                let distance = (camera.p - yv.p).length();
                let wd = camis.connection(scene, split, evals, distance, c.raster);
                return (wd.weight, Some(wd.mixture));
            }
            let c_y = reverse_density(yv, &camera, cam.pdf_dir(camera.p, camera.dir_to(yv))) as f64;
            let w = if s == 1 {
                setup.mis.light_tracing_origin(&ly[0], c_y)
            } else {
                let ev = c.eval.expect("a surface connected to the camera");
                let c_prev = reverse_density(&y[s - 2], yv, ev.pdf_rev_w) as f64;
                setup.mis.light_tracing(&ly[s - 1], c_y, c_prev)
            };
            (w, None)
        });
    }

    /// The camera sample of `pixel`: every technique with t ≥ 2 (merges included), through the
    /// camera loop under the VCM policy.
    fn camera_sample<R: Recorder>(
        &self,
        inputs: &PassInputs,
        light: (&[PathVertex], &[LightMis]),
        pixel: u64,
        worker: &mut Worker<'_, Scratch, R>,
    ) -> Color {
        let PassInputs {
            setup,
            lights,
            pass,
        } = *inputs;
        let Scratch { walk, records } = &mut *worker.scratch;
        let mut policy = VcmCamera {
            engine: self,
            setup,
            lights,
            light,
            records,
            primary: 0.0,
            light_nee: 0.0,
            merges_here: true,
        };
        let depths = Depths {
            max_depth: self.params.max_depth,
            rr_depth: self.params.rr_depth,
        };
        camera_sample(
            self.scene,
            (pass, pixel),
            depths,
            &mut policy,
            walk,
            &mut *worker.rec,
        )
    }
}

/// The VCM engine's policy in the camera loop, for one camera sample: its connections are
/// bdpt's (light subpath j mod M), every weight comes from the per-vertex recursion
/// (`SubpathMis`) or, when on, from the full path (`FullPathSetup`), and every non-delta camera
/// vertex merges with the stored light vertices within the pass's radius.
struct VcmCamera<'a, 'e> {
    engine: &'a Engine<'e>,
    setup: &'a PassSetup,
    lights: &'a LightPaths,
    /// The light subpath this sample connects to, and its MIS records.
    light: (&'a [PathVertex], &'a [LightMis]),
    /// The camera walk's MIS records, one per vertex (`walked`).
    records: &'a mut Vec<CameraMis>,
    /// |z_1 − z_0|: the primary hit's distance (the footprint of correlation-aware MIS).
    primary: f32,
    /// With full-path weights: next-event estimation's density of y_0 of `light`, read by each
    /// of its connections.
    light_nee: f64,
    /// Whether the sample's pixel merges (efficiency-aware MIS's mask).
    merges_here: bool,
}

impl CameraPolicy for VcmCamera<'_, '_> {
    fn walked(&mut self, scene: &Scene, z: &[PathVertex], raster: Vec2) {
        let setup = self.setup;
        camera_records(scene, &setup.mis, z, self.records);
        self.merges_here = setup.camis.as_ref().is_none_or(|c| c.merges_at(raster));
        self.primary = if z.len() >= 2 {
            (z[1].p - z[0].p).length()
        } else {
            0.0
        };
        self.light_nee = if setup.camis.is_some() {
            light_nee(scene, self.light.0)
        } else {
            0.0
        };
    }

    /// The camera walk (camera first, ending at x1) reached light endpoint x0 with density c0
    /// (its `pdf_fwd`).
    fn emitter_weight(&self, scene: &Scene, path: &[PathVertex], raster: Vec2) -> Weight {
        let (camera, x0) = path.split_at(path.len() - 1);
        let (x0, c0) = (&x0[0], x0[0].pdf_fwd);
        let x1 = camera.last().expect("the pinhole");
        if let Some(camis) = &self.setup.camis {
            let primary = if camera.len() == 1 {
                (x0.p - x1.p).length()
            } else {
                self.primary
            };
            let (split, evals) = Split::reached(path);
            let wd = camis.connection(scene, split, evals, primary, raster);
            return (wd.weight, Some(wd.mixture));
        }
        let mis = &self.setup.mis;
        if camera.len() == 1 {
            let (l0, _) = emission_densities(scene, x0, None);
            return (
                mis.emitter_seen(c0 as f64, l0, joinable(scene, x0, x1)),
                None,
            );
        }
        // VC(1) is next-event estimation from x1 (`Chain::valid`); x1 is inside this path.
        let vc1 = connectable_inside(scene, x1);
        let (l0, l1) = emission_densities(scene, x0, Some(x1));
        let nee = nee_density(scene, x0, x1);
        let records = &self.records[camera.len() - 1];
        (mis.emitter_hit(records, c0 as f64, l0, l1, nee, vc1), None)
    }

    fn connects(&self) -> bool {
        self.engine.params.connections
    }

    fn next_event_weight(
        &self,
        scene: &Scene,
        z: &[PathVertex],
        x0: &PathVertex,
        ev_z: BsdfEval,
        raster: Vec2,
    ) -> Weight {
        let t = z.len();
        let zv = &z[t - 1];
        if let Some(camis) = &self.setup.camis {
            let (split, evals) = Split::next_event(z, x0, ev_z);
            let wd = camis.connection(scene, split, evals, self.primary, raster);
            return (wd.weight, Some(wd.mixture));
        }
        let (l0, l1) = emission_densities(scene, x0, Some(zv));
        let d = NextEventDensities {
            nee: x0.pdf_fwd as f64,
            c0: reverse_density(x0, zv, ev_z.pdf_w) as f64,
            l0,
            l1,
            l_z_prev: if t >= 3 {
                reverse_density(&z[t - 2], zv, ev_z.pdf_rev_w) as f64
            } else {
                0.0
            },
        };
        let zr = &self.records;
        (self.setup.mis.next_event((&zr[t - 1], &zr[t - 2]), d), None)
    }

    /// bdpt's connections to light subpath j mod M; with vertex connections off, none.
    fn connect<R: Recorder>(&mut self, scene: &Scene, joins: &mut Joins<'_, R>, _: &mut Sampler) {
        if self.engine.params.vertex_connections {
            joins.join_subpath(scene, self.light.0, |c| self.connection_weight(scene, c));
        }
    }

    fn at_vertex<R: Recorder>(
        &mut self,
        scene: &Scene,
        z: &[PathVertex],
        sample: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let params = &self.engine.params;
        let t = z.len();
        if params.merging && t <= params.max_depth as usize && self.merges_here {
            *l += self.merge(scene, z, sample);
            sample.rec.lap(Work::Merge { t: t as u16 });
        }
    }
}

impl VcmCamera<'_, '_> {
    /// The weight of strategy (s, t), s ≥ 2, t ≥ 2: a shadow ray from z_{t−1} to y_{s−1}.
    fn connection_weight(&self, scene: &Scene, c: Connection) -> Weight {
        let (y, z) = (c.light, c.camera);
        let (s, t) = (y.len(), z.len());
        let (yv, zv) = (&y[s - 1], &z[t - 1]);
        if let Some(camis) = &self.setup.camis {
            let (split, evals) = Split::connection(c, self.light_nee);
            let wd = camis.connection(scene, split, evals, self.primary, c.raster);
            return (wd.weight, Some(wd.mixture));
        }
        let Joined {
            light_end: ev_y,
            camera_end: ev_z,
            ..
        } = *c.joined;
        let d = ConnectionDensities {
            c_y: reverse_density(yv, zv, ev_z.pdf_w) as f64,
            c_y_prev: reverse_density(&y[s - 2], yv, ev_y.pdf_rev_w) as f64,
            l_z: yv.convert_density(ev_y.pdf_w, zv) as f64,
            l_z_prev: if t >= 3 {
                reverse_density(&z[t - 2], zv, ev_z.pdf_rev_w) as f64
            } else {
                0.0
            },
        };
        let (ly, zr) = (self.light.1, &self.records);
        let w = self
            .setup
            .mis
            .connection(&ly[s - 1], (&zr[t - 1], &zr[t - 2]), d);
        (w, None)
    }

    /// Merges at z_{t−1} (`z` = z_0 … z_{t−1}) with every stored light vertex within the pass's
    /// radius (disk kernel).
    fn merge<R: Recorder>(
        &self,
        scene: &Scene,
        z: &[PathVertex],
        sample: &mut SampleCtx<'_, R>,
    ) -> Color {
        let (setup, lights, zr) = (self.setup, self.lights, &self.records);
        let t = z.len();
        let zv = &z[t - 1];
        let Some(grid) = &lights.grid else {
            return Color::ZERO;
        };
        let VertexKind::Surface { material } = zv.kind else {
            return Color::ZERO;
        };
        let max_k = self.engine.params.max_depth;
        let camera_segments = (t - 1) as u32;
        let sf = zv.shading_frame();
        let bsdf = scene.material(material);
        let wo_side = zv.ng.dot(zv.wo);
        let transmits = bsdf.transmits();
        let mut sum = Color::ZERO;
        grid.for_each_within(&lights.merge_positions, zv.p, setup.radius, |e, _| {
            let y = &lights.merge_vertex[e as usize];
            if y.segments + camera_segments > max_k {
                return;
            }
            // The light arrived on the side the camera looks from (a thin wall lit from behind
            // stays dark in front), not along the light vertex's own surface, and on the same
            // side of its own surface (front or back, by the shapes' normals) as the camera
            // looks at z: light stored on the sunlit outside of a wall is never merged at the
            // inner surface meeting that wall at an edge (the leak the SmallVCM sun twin showed),
            // while merges across an inner corner stay.
            // Through a surface that transmits, the light may arrive on the side facing away
            // from the camera; it must still arrive on the same side of its own surface as of z's.
            let y_front = y.ng.dot(y.wi) > 0.0;
            let arrives_front = zv.ng.dot(y.wi) > 0.0;
            let same_side = zv.ng.dot(y.wi) * wo_side > 0.0;
            if !(same_side || transmits) || !(y.cos_g > 0.0) || y_front != arrives_front {
                return;
            }
            let ev = bsdf.eval(&sf, zv.wo, y.wi, TransportMode::Radiance);
            if ev.f_cos == Color::ZERO {
                return;
            }
            let value = zv.beta * ev.f_cos * y.beta / y.cos_g;
            let c_y_prev = (ev.pdf_w * y.to_prev) as f64;
            let l_z_prev = if t >= 3 {
                reverse_density(&z[t - 2], zv, ev.pdf_rev_w) as f64
            } else {
                0.0
            };
            let (vi, first) = (y.index as usize, (y.index - y.segments) as usize);
            let ys = &lights.chunks[y.chunk as usize].vertices[first..=vi];
            let (w, mixture) = match &setup.camis {
                Some(camis) => {
                    let merge = MergeDensities { c_y_prev, l_z_prev };
                    let wd =
                        merge_weight(scene, camis, (ys, z), merge, (self.primary, sample.raster));
                    (wd.weight, Some(wd.mixture))
                }
                None => (
                    setup
                        .mis
                        .merge(&y.mis, &zr[t - 1], &zr[t - 2], c_y_prev, l_z_prev),
                    None,
                ),
            };
            if R::ACTIVE {
                if let Some(m) = mixture {
                    sample.rec.mixture(m);
                }
                sample.rec.merged(Merged {
                    i: y.segments as usize,
                    light: ys,
                    camera: z,
                    weight: w,
                    value: value * setup.merge_norm,
                    raster: sample.raster,
                    radius: setup.radius,
                });
            }
            sum += value * w as f32;
        });
        sum * setup.merge_norm
    }
}

/// One pass's inputs to its work items: the setup (MIS, radius), the pass's light subpaths, and
/// the seed and pass that key every random stream.
#[derive(Clone, Copy)]
pub struct PassInputs<'a> {
    pub setup: &'a PassSetup,
    pub lights: &'a LightPaths,
    pub pass: Pass,
}

/// Next-event estimation's density of y_0 from y_1 (0 for a one-vertex subpath): the density of
/// technique 1 on a path y_0 y_1 … joined further up.
fn light_nee(scene: &Scene, y: &[PathVertex]) -> f64 {
    if y.len() >= 2 {
        nee_density(scene, &y[0], &y[1])
    } else {
        0.0
    }
}

/// The two densities a merge adds, as `SubpathMis::merge` takes them.
#[derive(Clone, Copy)]
struct MergeDensities {
    /// c_{i−1}: z's BSDF towards y_{i−1}, given the light's incoming direction, in area at y_{i−1}.
    c_y_prev: f64,
    /// l_{i+1}: z's BSDF (importance) towards z_{t−2} given ω_y, in area at z_{t−2} (0 if t = 2).
    l_z_prev: f64,
}

/// Longest merged path (segments, + 1) whose densities `merge_weight` keeps on the stack.
const MERGE_STACK: usize = 24;

/// The full-path weight of merging light vertex y_i (`y` = y_0 … y_i) at z_{t−1} (`z` =
/// z_0 … z_{t−1}): the full path's densities from the walks' stored ones, as
/// `Densities::merged` defines them from scratch — the light side l_0 … l_i, c_0 … c_{i−2} from
/// the light walk, c_i … c_k and l_{i+2} … from the camera walk, c_{i−1} and l_{i+1} the merge's.
fn merge_weight(
    scene: &Scene,
    camis: &FullPathSetup,
    (y, z): (&[PathVertex], &[PathVertex]),
    m: MergeDensities,
    (primary, raster): (f32, Vec2),
) -> Weighed {
    let i = y.len() - 1;
    let t = z.len();
    let k = i + t - 1;
    // On the stack up to k = MERGE_STACK − 1 (every merge of a pass builds one).
    let (mut la, mut ca, mut na) = (
        [0.0f64; MERGE_STACK],
        [0.0f64; MERGE_STACK],
        [false; MERGE_STACK],
    );
    let (mut lv, mut cv, mut nv) = (Vec::new(), Vec::new(), Vec::new());
    let (light, camera, conn): (&mut [f64], &mut [f64], &mut [bool]) = if k < MERGE_STACK {
        (&mut la[..=k], &mut ca[..=k], &mut na[..=k])
    } else {
        lv.resize(k + 1, 0.0);
        cv.resize(k + 1, 0.0);
        nv.resize(k + 1, false);
        (&mut lv, &mut cv, &mut nv)
    };
    for j in 0..=k {
        if j <= i {
            light[j] = y[j].pdf_fwd as f64;
        }
        if j + 2 <= i {
            camera[j] = y[j].pdf_rev as f64;
        }
        if j >= i {
            camera[j] = z[k - j].pdf_fwd as f64;
        }
        if j >= i + 2 {
            light[j] = z[k - j].pdf_rev as f64;
        }
        // Inner vertices as their walk left them; x_i, the merge, by evaluation on both sides.
        conn[j] = if j == i {
            connectable(scene, &z[t - 1]) && connectable(scene, &y[i])
        } else if j < i {
            connectable_inside(scene, &y[j])
        } else {
            connectable_inside(scene, &z[k - j])
        };
    }
    camera[i - 1] = m.c_y_prev;
    if i + 1 < k {
        light[i + 1] = m.l_z_prev;
    }
    camera[k] = 1.0;
    light[k] = 0.0;
    let chain = Chain {
        light,
        camera,
        nee: light_nee(scene, y),
        connectable: conn,
        light_tracing_ratio: camis.ratio,
    };
    camis.weigh(&chain, Technique::Merge(i), primary, raster)
}

/// The MIS records of a light subpath y_0 … (see `SubpathMis`), appended to `out`.
fn light_records(scene: &Scene, mis: &SubpathMis, y: &[PathVertex], out: &mut Vec<LightMis>) {
    let Some(y0) = y.first() else {
        return;
    };
    let base = out.len();
    out.push(mis.light_origin(y0.pdf_fwd as f64));
    let nee_over_l0 = if y.len() >= 2 {
        nee_density(scene, &y[0], &y[1]) / y0.pdf_fwd as f64
    } else {
        0.0
    };
    for j in 1..y.len() {
        let c_pp = if j >= 2 { y[j - 2].pdf_rev as f64 } else { 0.0 };
        let prev = out[base + j - 1];
        let surface = matches!(y[j].kind, VertexKind::Surface { .. });
        let vertex = VertexTechniques {
            // VC(1) is next-event estimation: the light samples x0 itself (`Chain::valid`).
            // VC(j) joins y_j, the end, to y_{j−1}, inside the path.
            vc_valid: if j == 1 {
                connectable(scene, &y[1])
            } else {
                connectable_inside(scene, &y[j - 1]) && connectable(scene, &y[j])
            },
            mergeable: surface && connectable(scene, &y[j]) && mis.merging(),
            through_delta: y[j].delta,
        };
        let r = mis.light_vertex(j, y[j].pdf_fwd as f64, (&prev, c_pp), nee_over_l0, vertex);
        out.push(r);
    }
}

/// The MIS records of a camera subpath z_0 (pinhole) … into `out`.
fn camera_records(scene: &Scene, mis: &SubpathMis, z: &[PathVertex], out: &mut Vec<CameraMis>) {
    out.clear();
    out.push(mis.camera_origin());
    for m in 1..z.len() {
        let surface = matches!(z[m].kind, VertexKind::Surface { .. });
        let vertex = VertexTechniques {
            // VC(i+1) joins z_m, the end, to z_{m−1}, inside the path.
            vc_valid: connectable(scene, &z[m]) && connectable_inside(scene, &z[m - 1]),
            mergeable: surface && connectable(scene, &z[m]) && mis.merging(),
            through_delta: z[m].delta,
        };
        let r = mis.camera_vertex(
            m,
            z[m].pdf_fwd as f64,
            (&out[m - 1], z[m - 1].pdf_rev as f64),
            vertex,
        );
        out.push(r);
    }
}

/// A run's log entries of one pass.
pub fn log_pass(log: &mut ProgressLog, setup: &PassSetup, r0: f32) {
    log.photon_paths.push(setup.light_paths);
    log.radius_scale.push(setup.radius as f64 / r0 as f64);
    log.mean_radius.push(setup.radius as f64);
    if log.facts.is_empty() {
        log.facts
            .push(("initial_radius".into(), format!("{r0:.6e}")));
    }
}

/// One run of the VCM family (`vcm`, `bpm`): the mean of its iterations' images.
pub struct Run<'a> {
    engine: Engine<'a>,
    seed: u64,
    r0: f32,
    sum: Image,
    passes: u32,
    log: ProgressLog,
    /// The last pass's light subpaths: buffers reused by the next.
    lights: LightPaths,
}

impl<'a> Run<'a> {
    pub fn new(params: &VcmParams, scene: &'a Scene, seed: u64) -> Run<'a> {
        let cam = &scene.camera;
        Run {
            engine: Engine::new(params, scene),
            seed,
            r0: initial_radius(scene, params.radius),
            sum: Image::new(cam.width as usize, cam.height as usize),
            passes: 0,
            log: ProgressLog::default(),
            lights: LightPaths::default(),
        }
    }
}

impl Run<'_> {
    /// Adds one pass's image to the run and logs it.
    fn add_pass(&mut self, img: &Image, setup: &PassSetup) {
        for (a, b) in self.sum.data.iter_mut().zip(&img.data) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
        self.passes += 1;
        log_pass(&mut self.log, setup, self.r0);
    }

    /// Merging only where `mask` is on (efficiency-aware MIS's per-pixel choice); every weight
    /// then comes from the full path's densities.
    pub fn with_merge_mask(mut self, mask: MergeMask) -> Self {
        self.engine.merge_mask = Some(mask);
        self
    }

    /// `pass` run on one thread, item after item, every path reported to `rec` (efficiency-aware
    /// MIS's pilot): one chunk, so what `rec` sums does not depend on the thread count.
    pub fn recorded_pass<R: Recorder + Send>(&mut self, pass: u32, rec: &mut R) -> u64 {
        let setup = self.engine.setup(self.r0, pass);
        self.engine
            .trace_light_paths_into(&setup, self.seed, pass, &mut self.lights);
        let engine = &self.engine;
        let lights = &self.lights;
        let seed = self.seed;
        let cam = &engine.scene.camera;
        let items = (cam.pixel_count() as u64).max(setup.light_paths);
        let rec = std::sync::Mutex::new(rec);
        let (img, invalid) = splat_pass_with(
            cam.width as usize,
            cam.height as usize,
            items,
            items,
            || engine.scratch(),
            |i, splats, scratch| {
                let mut rec = rec.lock().unwrap_or_else(|e| e.into_inner());
                let inputs = PassInputs {
                    setup: &setup,
                    lights,
                    pass: Pass { seed, pass },
                };
                engine.item_into(&inputs, i, (splats, scratch, &mut **rec))
            },
        );
        self.add_pass(&img, &setup);
        invalid
    }

    /// Light vertices stored for merging in the last pass (the light walk's cost, counted).
    pub fn stored_light_vertices(&self) -> usize {
        self.lights.merge_candidates()
    }

    /// Passes done and their summed images (the estimate is the sum over the passes).
    pub fn sum(&self) -> (&Image, u32) {
        (&self.sum, self.passes)
    }

    /// `pass` with every technique's contributions and time tallied (`crate::record::tally`): the same
    /// state and estimate, bit for bit. The light subpaths, their MIS records and the merge grid
    /// are one phase (`Work::LightWalk`).
    pub fn tally_pass(&mut self, pass: u32, every: u64) -> (u64, PassTally) {
        let clock = PassClock::start();
        let cpu0 = pool_cpu_seconds();
        let setup = self.engine.setup(self.r0, pass);
        self.engine
            .trace_light_paths_into(&setup, self.seed, pass, &mut self.lights);
        let walk = pool_cpu_seconds() - cpu0;
        let engine = &self.engine;
        let lights = &self.lights;
        let seed = self.seed;
        let scene = engine.scene;
        let items = (scene.camera.pixel_count() as u64).max(setup.light_paths);
        let (img, invalid, tally) = tallied_pass(
            scene,
            pass,
            every,
            (items, CHUNK),
            || engine.scratch(),
            |i, splats, scratch, rec: &mut Tally| {
                let inputs = PassInputs {
                    setup: &setup,
                    lights,
                    pass: Pass { seed, pass },
                };
                engine.item_into(&inputs, i, (splats, scratch, rec))
            },
        );
        self.add_pass(&img, &setup);
        (invalid, tally.finish(clock, &[(Work::LightWalk, walk)]))
    }
}

impl ProgressiveRun for Run<'_> {
    fn pass(&mut self, pass: u32) -> u64 {
        let setup = self.engine.setup(self.r0, pass);
        self.engine
            .trace_light_paths_into(&setup, self.seed, pass, &mut self.lights);
        let (img, invalid) = self
            .engine
            .render_pass(&setup, &self.lights, self.seed, pass);
        self.add_pass(&img, &setup);
        invalid
    }

    fn estimate(&self) -> Image {
        let mut img = self.sum.clone();
        let k = 1.0 / self.passes.max(1) as f64;
        img.data
            .iter_mut()
            .for_each(|p| p.iter_mut().for_each(|c| *c *= k));
        img
    }

    fn log(&self) -> ProgressLog {
        self.log.clone()
    }
}

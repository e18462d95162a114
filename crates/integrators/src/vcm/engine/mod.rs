//! The VCM engine: vertex connection and merging (Georgiev, Křivánek, Davidovič & Slusallek
//! 2012), shared by `vcm`, `bpm` and `eamis` and owned by none: one pass traces M light
//! subpaths, indexes their non-delta vertices, then per pixel runs the bidirectional camera loop
//! (`crate::subpath::camera_loop`) under the engine's policy (`camera`), whose camera subpath at
//! every vertex
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
//!
//! The engine's parts: `params` (the keys and techniques of the family, r₀), `light_paths` (a
//! pass's light subpaths, their MIS records and the merge grid), `camera` (its policy in the
//! bidirectional camera loop, merges included), `full_path` (weights from the full path's
//! densities: correlation-aware MIS and efficiency-aware MIS's per-pixel merging) and `run` (a
//! run of passes, the `ProgressiveRun` of `vcm` and `bpm`).

mod camera;
mod full_path;
mod light_paths;
mod params;
mod run;

pub use light_paths::LightPaths;
pub use params::{initial_radius, Techniques, VcmParams, DEFAULT_ALPHA};
pub use run::{log_pass, Run};

pub use crate::film::splat::pixel_of;
use crate::film::splat::{splat_pass_with, Pass, Splats, Worker};
use crate::record::{NoRecord, Recorder};
use crate::subpath::camera_loop::CameraScratch;
use crate::subpath::connect::{nee_density, splat_light_subpath};
use crate::subpath::strategy_weight::{EndEvals, Split};
use crate::subpath::walk::reverse_density;
use full_path::FullPathSetup;
use lt_core::math::PI;
use lt_core::path::{CameraMis, LightMis, PathVertex, SubpathMis, TechniqueSet};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use lt_estimators::Image;
use std::sync::Arc;

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
                    flights: None,
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

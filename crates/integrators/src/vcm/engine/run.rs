//! One run of the VCM family: passes in order, each with its own radius, their images summed.

use super::params::initial_radius;
use super::{Engine, LightPaths, MergeMask, PassInputs, PassSetup, VcmParams, CHUNK};
use crate::film::splat::{splat_pass_with, Pass};
use crate::record::tally::{pool_cpu_seconds, tallied_pass, PassClock, PassTally, Tally};
use crate::record::{Recorder, Work};
use crate::{ProgressLog, ProgressiveRun};
use lt_core::Scene;
use lt_estimators::Image;

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

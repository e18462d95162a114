//! The pass loop: runs an integrator's passes on a thread pool of the requested size, accumulates
//! them (per-pixel mean and variance), and stops at a pass count or a time budget.

use crate::Integrator;
use lt_core::Scene;
use lt_estimators::running::RunningImage;
use lt_estimators::Image;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Passes (samples per pixel for pixel-based integrators). With a time budget, the upper bound.
    pub passes: u32,
    pub time_limit: Option<Duration>,
    pub seed: u64,
    /// Worker threads; 0 means one per core.
    pub threads: usize,
}

/// What the caller is told after each pass.
pub struct PassReport<'a> {
    pub passes_done: u32,
    /// The image of the pass just finished (for statistics that need every pass, e.g. block means).
    pub pass_image: &'a Image,
    pub elapsed: Duration,
    pub accumulated: &'a RunningImage,
}

pub struct RenderResult {
    pub image: RunningImage,
    pub passes: u32,
    pub elapsed: Duration,
    /// Samples an integrator produced as NaN, infinite or negative (dropped). Zero when correct.
    pub invalid_samples: u64,
}

/// Renders until `opts.passes` passes are done, the time budget is spent, or `on_pass` breaks.
pub fn render(
    scene: &Scene,
    integrator: &dyn Integrator,
    opts: &RenderOptions,
    mut on_pass: impl FnMut(&PassReport) -> ControlFlow<()>,
) -> Result<RenderResult, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads)
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))?;
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut acc = RunningImage::new(w, h);
    let mut invalid = 0;
    let start = Instant::now();
    let mut pass = 0;
    while pass < opts.passes {
        let (img, bad) = pool.install(|| integrator.render_pass(scene, opts.seed, pass));
        acc.add(&img);
        invalid += bad;
        pass += 1;
        let elapsed = start.elapsed();
        if on_pass(&PassReport {
            passes_done: pass,
            pass_image: &img,
            elapsed,
            accumulated: &acc,
        })
        .is_break()
        {
            break;
        }
        if opts.time_limit.is_some_and(|t| elapsed >= t) {
            break;
        }
    }
    Ok(RenderResult {
        image: acc,
        passes: pass,
        elapsed: start.elapsed(),
        invalid_samples: invalid,
    })
}

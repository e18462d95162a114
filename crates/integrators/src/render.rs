//! The pass loop: runs an estimator's passes on a thread pool of the requested size and stops at
//! a pass count or a time budget. An unbiased estimator's passes are accumulated (per-pixel mean
//! and variance over passes); a consistent one's run keeps its own state and is asked for its
//! estimate. `render_runs` repeats a render over independent seeds: the only honest error bars of
//! a consistent estimator, and a cross-check of the per-pass ones of an unbiased estimator.

use crate::record::cpu_clock::pool_cpu_time;
use crate::{Estimator, Integrator, Kind, ProgressLog, Progressive, ProgressiveRun};
use lt_core::Scene;
use lt_estimators::running::RunningImage;
use lt_estimators::Image;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Passes (samples per pixel for pixel-based integrators). With a time budget, the upper bound.
    pub passes: u32,
    /// Per run, with `render_runs`.
    pub time_limit: Option<Duration>,
    /// The seed of the run (of run 0 with `render_runs`; run k uses `seed + k`).
    pub seed: u64,
    /// Worker threads; 0 means one per core.
    pub threads: usize,
}

/// A borrowed estimator of either kind (what `render` runs).
#[derive(Clone, Copy)]
pub enum EstimatorRef<'a> {
    Unbiased(&'a dyn Integrator),
    Consistent(&'a dyn Progressive),
}

impl<'a> From<&'a Estimator> for EstimatorRef<'a> {
    fn from(e: &'a Estimator) -> EstimatorRef<'a> {
        match e {
            Estimator::Unbiased(i) => EstimatorRef::Unbiased(i.as_ref()),
            Estimator::Consistent(p) => EstimatorRef::Consistent(p.as_ref()),
        }
    }
}

impl EstimatorRef<'_> {
    pub fn kind(&self) -> Kind {
        match self {
            EstimatorRef::Unbiased(_) => Kind::Unbiased,
            EstimatorRef::Consistent(_) => Kind::Consistent,
        }
    }
}

/// Where a run stands after a pass.
pub enum PassState<'a> {
    Unbiased {
        /// The image of the pass just finished (for statistics that need every pass).
        pass_image: &'a Image,
        accumulated: &'a RunningImage,
    },
    Consistent {
        run: &'a dyn ProgressiveRun,
    },
}

/// What the caller is told after each pass.
pub struct PassReport<'a> {
    pub passes_done: u32,
    pub elapsed: Duration,
    /// CPU time of the render's threads so far (`cpu_clock::pool_cpu_time`).
    pub cpu: Duration,
    pub state: PassState<'a>,
}

impl PassReport<'_> {
    /// The run's estimate so far.
    pub fn estimate(&self) -> Image {
        match &self.state {
            PassState::Unbiased { accumulated, .. } => accumulated.mean(),
            PassState::Consistent { run } => run.estimate(),
        }
    }

    /// The pass's own image: only an unbiased estimator has one.
    pub fn pass_image(&self) -> Option<&Image> {
        match &self.state {
            PassState::Unbiased { pass_image, .. } => Some(pass_image),
            PassState::Consistent { .. } => None,
        }
    }

    /// Per-pixel standard error from the spread of passes: only meaningful, and only given, for
    /// an unbiased estimator.
    pub fn std_error(&self) -> Option<Image> {
        match &self.state {
            PassState::Unbiased { accumulated, .. } => Some(accumulated.std_error()),
            PassState::Consistent { .. } => None,
        }
    }
}

pub struct RenderResult {
    pub kind: Kind,
    /// The image the run estimates.
    pub estimate: Image,
    /// Unbiased estimators: mean and variance over the passes. `None` for consistent ones, whose
    /// passes are not independent.
    pub per_pass: Option<RunningImage>,
    pub passes: u32,
    pub elapsed: Duration,
    /// CPU time of the render's threads.
    pub cpu: Duration,
    /// Samples an integrator produced as NaN, infinite or negative (dropped). Zero when correct.
    pub invalid_samples: u64,
    /// Consistent estimators: their schedule.
    pub log: Option<ProgressLog>,
}

/// Renders until `opts.passes` passes are done, the time budget is spent, or `on_pass` breaks.
pub fn render<'a>(
    scene: &Scene,
    estimator: impl Into<EstimatorRef<'a>>,
    opts: &RenderOptions,
    on_pass: impl FnMut(&PassReport) -> ControlFlow<()>,
) -> Result<RenderResult, String> {
    let pool = pool(opts.threads)?;
    Ok(render_in(
        &pool,
        scene,
        estimator.into(),
        opts,
        opts.seed,
        on_pass,
    ))
}

fn pool(threads: usize) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))
}

fn render_in(
    pool: &rayon::ThreadPool,
    scene: &Scene,
    estimator: EstimatorRef,
    opts: &RenderOptions,
    seed: u64,
    mut on_pass: impl FnMut(&PassReport) -> ControlFlow<()>,
) -> RenderResult {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let start = Instant::now();
    let cpu_start = pool_cpu_time(pool);
    let cpu_since_start = || pool_cpu_time(pool).saturating_sub(cpu_start);
    let mut invalid = 0;
    let mut pass = 0;
    // After each pass: false when the caller or the time budget says stop.
    let mut go_on = |pass: u32, state: PassState| {
        let elapsed = start.elapsed();
        let report = PassReport {
            passes_done: pass,
            elapsed,
            cpu: cpu_since_start(),
            state,
        };
        on_pass(&report).is_continue() && opts.time_limit.is_none_or(|t| elapsed < t)
    };
    match estimator {
        EstimatorRef::Unbiased(integrator) => {
            let mut acc = RunningImage::new(w, h);
            while pass < opts.passes {
                let (img, bad) = pool.install(|| integrator.render_pass(scene, seed, pass));
                acc.add(&img);
                invalid += bad;
                pass += 1;
                let state = PassState::Unbiased {
                    pass_image: &img,
                    accumulated: &acc,
                };
                if !go_on(pass, state) {
                    break;
                }
            }
            RenderResult {
                kind: Kind::Unbiased,
                estimate: acc.mean(),
                per_pass: Some(acc),
                passes: pass,
                elapsed: start.elapsed(),
                cpu: cpu_since_start(),
                invalid_samples: invalid,
                log: None,
            }
        }
        EstimatorRef::Consistent(progressive) => {
            let mut run = pool.install(|| progressive.start(scene, seed));
            run.plan(opts.passes);
            while pass < opts.passes {
                invalid += pool.install(|| run.pass(pass));
                pass += 1;
                if !go_on(pass, PassState::Consistent { run: run.as_ref() }) {
                    break;
                }
            }
            RenderResult {
                kind: Kind::Consistent,
                estimate: pool.install(|| run.estimate()),
                per_pass: None,
                passes: pass,
                elapsed: start.elapsed(),
                cpu: cpu_since_start(),
                invalid_samples: invalid,
                log: Some(run.log()),
            }
        }
    }
}

/// Passes `passes.start .. passes.end` of an unbiased estimator under one seed: what one shard of
/// a sharded render computes. Pass p is `render_pass(scene, seed, p)` whatever the range, so the
/// ranges of a split cover exactly the passes of the whole render, and passes are accumulated in
/// order, so the range 0..N is bit for bit the accumulator `render` keeps (at any thread count).
pub struct PassRange {
    pub accumulated: RunningImage,
    /// The passes done (`passes.start ..` the last one finished).
    pub passes: std::ops::Range<u32>,
    pub elapsed: Duration,
    pub invalid_samples: u64,
}

/// Renders passes `passes` of `integrator` with `seed` on `threads` workers (0 = one per core).
/// `on_pass(done, accumulated)` is told after each pass (`done` passes of the range finished);
/// when it breaks, the range stops short (the result says where).
pub fn render_pass_range(
    scene: &Scene,
    integrator: &dyn Integrator,
    seed: u64,
    passes: std::ops::Range<u32>,
    threads: usize,
    mut on_pass: impl FnMut(u32, &RunningImage) -> ControlFlow<()>,
) -> Result<PassRange, String> {
    if passes.is_empty() {
        return Err(format!(
            "the pass range {}..{} is empty",
            passes.start, passes.end
        ));
    }
    let pool = pool(threads)?;
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let start = Instant::now();
    let mut acc = RunningImage::new(w, h);
    let mut invalid = 0;
    let mut pass = passes.start;
    while pass < passes.end {
        let (img, bad) = pool.install(|| integrator.render_pass(scene, seed, pass));
        acc.add(&img);
        invalid += bad;
        pass += 1;
        if on_pass(pass - passes.start, &acc).is_break() {
            break;
        }
    }
    Ok(PassRange {
        accumulated: acc,
        passes: passes.start..pass,
        elapsed: start.elapsed(),
        invalid_samples: invalid,
    })
}

/// One run of `render_runs`.
pub struct RunSummary {
    pub seed: u64,
    pub passes: u32,
    pub elapsed: Duration,
    pub cpu: Duration,
    pub invalid_samples: u64,
    pub log: Option<ProgressLog>,
}

pub struct RunsResult {
    pub kind: Kind,
    /// Mean and variance over the runs' estimates: `std_error()` is the standard error across
    /// runs, valid for both kinds.
    pub across_runs: RunningImage,
    /// Unbiased estimators: every pass of every run pooled (its standard error must agree with the
    /// one across runs). `None` for consistent estimators.
    pub per_pass: Option<RunningImage>,
    pub runs: Vec<RunSummary>,
    pub elapsed: Duration,
    /// CPU time of the finished runs' threads, summed.
    pub cpu: Duration,
    pub invalid_samples: u64,
}

/// `runs` independent renders, run k seeded by `opts.seed + k`, each under `opts` (a time budget
/// is per run). `on_pass(k, report)` is told of every pass of run k, `on_run` of every finished
/// run. When `on_pass` breaks, the run in progress is dropped unless it is the first (a shorter
/// run would mix an estimate of different bias into the spread).
pub fn render_runs<'a>(
    scene: &Scene,
    estimator: impl Into<EstimatorRef<'a>>,
    opts: &RenderOptions,
    runs: u32,
    mut on_pass: impl FnMut(u32, &PassReport) -> ControlFlow<()>,
    mut on_run: impl FnMut(&RunsResult),
) -> Result<RunsResult, String> {
    if runs == 0 {
        return Err("--runs must be at least 1".into());
    }
    let estimator = estimator.into();
    let pool = pool(opts.threads)?;
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let start = Instant::now();
    let mut out = RunsResult {
        kind: estimator.kind(),
        across_runs: RunningImage::new(w, h),
        per_pass: (estimator.kind() == Kind::Unbiased).then(|| RunningImage::new(w, h)),
        runs: Vec::new(),
        elapsed: Duration::ZERO,
        cpu: Duration::ZERO,
        invalid_samples: 0,
    };
    for k in 0..runs {
        let seed = opts.seed.wrapping_add(k as u64);
        let mut stopped = false;
        let r = render_in(&pool, scene, estimator, opts, seed, |report| {
            let flow = on_pass(k, report);
            stopped |= flow.is_break();
            flow
        });
        if stopped && k > 0 {
            break;
        }
        out.across_runs.add(&r.estimate);
        if let (Some(all), Some(run)) = (&mut out.per_pass, &r.per_pass) {
            all.merge(run);
        }
        out.invalid_samples += r.invalid_samples;
        out.runs.push(RunSummary {
            seed,
            passes: r.passes,
            elapsed: r.elapsed,
            cpu: r.cpu,
            invalid_samples: r.invalid_samples,
            log: r.log,
        });
        out.cpu += r.cpu;
        out.elapsed = start.elapsed();
        on_run(&out);
        if stopped {
            break;
        }
    }
    Ok(out)
}

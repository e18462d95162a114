//! `lt render`: one scene, one integrator, written as linear EXR plus an sRGB PNG preview, a
//! standard-error EXR and a JSON record of how the image was made.

use crate::cluster::partial::{normalize_params, parse_pass_range, PartialJob, Span};
use crate::image_io::{mean_of, sibling, write_outputs};
use crate::verify::strategies::{make_bdpt, write_pyramid, PyramidIntegrator, PyramidMeta};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lt_estimators::Image;
use lt_integrators::{
    make_integrator, render_runs, EstimatorRef, ProgressLog, RenderOptions, RunsResult,
};
use lt_scene_io::load_scene;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML, see docs/scene-format.md).
    pub scene: PathBuf,
    /// Integrator name (`lt list` shows them).
    #[arg(long, short, default_value = "pt")]
    pub integrator: String,
    /// Samples per pixel (passes); defaults to the scene's `[render] spp`. With --time, an upper bound.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Time budget in seconds: stop after the pass that crosses it.
    #[arg(long)]
    pub time: Option<f64>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Independent runs, run k seeded by seed + k: the image is their mean and OUT.stderr.exr the
    /// standard error across them — the only error bar a consistent estimator (pm, ppm, sppm) has.
    /// --spp and --time apply to each run.
    #[arg(long, default_value_t = 1)]
    pub runs: u32,
    /// Worker threads (0 = one per core). The image does not depend on it.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    #[command(flatten)]
    pub integrator_args: crate::integrator_args::IntegratorArgs,
    /// Output EXR; `.png`, `.json` and (where there is an honest one) `.stderr.exr` beside it.
    #[arg(long, short, required_unless_present = "partial")]
    pub output: Option<PathBuf>,
    /// Render only passes A..B (A to B-1, counted from 0) of the seed: with --partial, one shard
    /// of a render split by passes (unbiased integrators).
    #[arg(long, value_name = "A..B")]
    pub passes: Option<String>,
    /// Write the exact accumulation (count, per-pixel mean and M2 in f64, scene hash, parameters)
    /// to OUT instead of images, for `lt merge`; with --runs K, of K runs (seeds seed…seed+K-1).
    #[arg(long, value_name = "OUT", conflicts_with_all = ["time", "strategies", "output"])]
    pub partial: Option<PathBuf>,
    /// Seconds between checkpoints of the partial image (an interrupted run keeps what it finished).
    #[arg(long, default_value_t = 30.0)]
    pub checkpoint: f64,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// bdpt only: also write Veach's path pyramid into DIR — per strategy (s, t) of every length
    /// k ≤ --strategy-length its weighted and unweighted images with standard errors, a tiled
    /// pyramid.png, README.md and strategies.json. The main image is unchanged.
    #[arg(long, value_name = "DIR")]
    pub strategies: Option<PathBuf>,
    /// Longest path length k (segments) in the pyramid written by --strategies.
    #[arg(long, value_name = "L", default_value_t = crate::verify::strategies::DEFAULT_LENGTH)]
    pub strategy_length: usize,
}

fn log_json(log: &ProgressLog) -> serde_json::Value {
    serde_json::json!({
        "photon_paths_per_pass": log.photon_paths,
        "radius_scale_per_pass": log.radius_scale,
        "mean_radius_per_pass": log.mean_radius,
        "facts": log.facts.iter().map(|(k, v)| (k.clone(), serde_json::Value::String(v.clone()))).collect::<serde_json::Map<_, _>>(),
        "images": log.images.iter().map(|(name, _)| format!(".{name}.exr")).collect::<Vec<_>>(),
    })
}

pub fn run(args: &RenderArgs) -> Result<(), String> {
    match &args.partial {
        Some(part) => run_partial(args, part),
        None => render(args),
    }
}

/// `lt render … -o OUT.exr`: the mean of the passes (or runs), its standard error, side images,
/// the JSON record, and with `--strategies` bdpt's per-strategy pyramid.
fn render(args: &RenderArgs) -> Result<(), String> {
    let output = check_render_args(args)?;
    let scene = load_scene(&args.scene).map_err(|e| e.to_string())?;
    let params = args.integrator_args.to_params()?;
    let pyramid = match &args.strategies {
        None => None,
        Some(dir) => Some(pyramid(args, &scene, &params, dir)?),
    };
    let plain = match pyramid {
        None => Some(make_integrator(&args.integrator, &scene, &params)?),
        Some(_) => None,
    };
    let estimator: EstimatorRef = match (&pyramid, &plain) {
        (Some((_, p, _)), _) => EstimatorRef::Unbiased(p),
        (None, Some(i)) => i.into(),
        (None, None) => unreachable!("one of the two is built"),
    };
    let kind = estimator.kind();
    let write_all = |mean: &Image, se: Option<&Image>| -> Result<(), String> {
        write_outputs(output, mean, se)?;
        if let Some((dir, integ, meta)) = &pyramid {
            integ.with_pyramid(|p| write_pyramid(dir, p, meta))?;
        }
        Ok(())
    };
    let opts = render_options(args, &scene)?;
    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        // A second Ctrl-C still kills the process the usual way once this handler has run.
        let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    }
    let result = render_with_checkpoints(args, &scene, estimator, &opts, &write_all, &interrupted)?;
    let errors = StdErrors::of(&result);
    let (se, se_source) = errors.chosen();
    write_all(&result.across_runs.mean(), se)?;
    // The first run's side images (one run's choice; `--runs K` repeats it with other seeds).
    for (name, img) in result.runs[0].log.iter().flat_map(|l| &l.images) {
        crate::image_io::write_exr(&sibling(output, &format!(".{name}.exr")), img)?;
    }
    let runs_done = result.runs.len();
    let secs = result.elapsed.as_secs_f64();
    let total_passes: u64 = result.runs.iter().map(|r| r.passes as u64).sum();
    let first = &result.runs[0];
    let (across, per_pass) = (&errors.across, &errors.per_pass);
    let record = serde_json::json!({
        "scene": args.scene.display().to_string(),
        "integrator": args.integrator,
        "kind": kind.name(),
        "spp": first.passes,
        "runs": runs_done,
        "run_seeds": result.runs.iter().map(|r| r.seed).collect::<Vec<_>>(),
        "run_passes": result.runs.iter().map(|r| r.passes).collect::<Vec<_>>(),
        "run_seconds": result.runs.iter().map(|r| r.elapsed.as_secs_f64()).collect::<Vec<_>>(),
        "run_cpu_seconds": result.runs.iter().map(|r| r.cpu.as_secs_f64()).collect::<Vec<_>>(),
        "seed": args.seed,
        "threads": args.threads,
        "ray_core": scene.ray_core(),
        "max_depth": args.integrator_args.max_depth.unwrap_or(scene.settings.max_depth),
        "params": params.pairs().iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>(),
        "seconds": secs,
        "cpu_seconds": result.cpu.as_secs_f64(),
        "spp_per_second": total_passes as f64 / secs,
        "std_error_source": se_source,
        "mean_std_error": se.map(mean_of),
        "mean_std_error_across_runs": across.as_ref().map(mean_of),
        "mean_std_error_per_pass": per_pass.as_ref().map(mean_of),
        "progress": first.log.as_ref().map(log_json),
        "invalid_samples": result.invalid_samples,
        "interrupted": interrupted.load(Ordering::SeqCst),
        "strategies": pyramid.as_ref().map(|(dir, _, _)| dir.display().to_string()),
        "strategy_length": pyramid.as_ref().map(|_| args.strategy_length),
    });
    crate::image_io::write_atomic(
        &sibling(output, ".json"),
        serde_json::to_string_pretty(&record).unwrap().as_bytes(),
    )?;
    if !args.quiet {
        print_summary(args, &result, output);
    }
    Ok(())
}

/// The flags a full render refuses or needs, checked before the scene is read; the output path.
fn check_render_args(args: &RenderArgs) -> Result<&Path, String> {
    if let Some(p) = &args.passes {
        return Err(format!(
            "--passes {p} renders a part for `lt merge`: give --partial OUT.ltp"
        ));
    }
    let output = args
        .output
        .as_deref()
        .ok_or("give -o OUT.exr (or --partial OUT)")?;
    if let Some(dir) = &args.strategies {
        if args.integrator != "bdpt" {
            return Err(format!(
                "--strategies {} needs -i bdpt: the per-strategy path pyramid splits bdpt's \
                 (s, t) strategies, which '{}' does not have",
                dir.display(),
                args.integrator
            ));
        }
        if args.strategy_length == 0 {
            return Err("--strategy-length must be at least 1".into());
        }
        if args.runs != 1 {
            return Err("--strategies takes one run: drop --runs".into());
        }
    }
    if args.runs == 0 {
        return Err("--runs must be at least 1".into());
    }
    Ok(output)
}

/// `--strategies DIR`: bdpt wrapped to keep every (s, t) strategy's image, with what the
/// pyramid's files record.
fn pyramid(
    args: &RenderArgs,
    scene: &lt_core::Scene,
    params: &lt_integrators::IntegratorParams,
    dir: &Path,
) -> Result<(PathBuf, PyramidIntegrator, PyramidMeta), String> {
    let bdpt = make_bdpt(scene, params)?;
    let meta = PyramidMeta {
        scene: args.scene.display().to_string(),
        seed: args.seed,
        max_depth: bdpt.params.max_depth,
    };
    let integ = PyramidIntegrator::new(scene, bdpt, args.strategy_length);
    Ok((dir.to_path_buf(), integ, meta))
}

/// The pass budget (`--spp`, the scene's, or as many as `--time` allows), seed and threads.
fn render_options(args: &RenderArgs, scene: &lt_core::Scene) -> Result<RenderOptions, String> {
    if args.time.is_some_and(|t| !(t > 0.0 && t.is_finite())) {
        return Err("--time must be a positive number of seconds".into());
    }
    let passes = match (args.spp, args.time) {
        (Some(n), _) => n,
        (None, Some(_)) => u32::MAX,
        (None, None) => scene.settings.spp,
    };
    if passes == 0 {
        return Err("--spp must be at least 1".into());
    }
    Ok(RenderOptions {
        passes,
        time_limit: args.time.map(Duration::from_secs_f64),
        seed: args.seed,
        threads: args.threads,
    })
}

/// The runs with a progress bar, writing the images every `--checkpoint` seconds (one run) or
/// after every run (several), and stopping at Ctrl-C.
fn render_with_checkpoints(
    args: &RenderArgs,
    scene: &lt_core::Scene,
    estimator: EstimatorRef,
    opts: &RenderOptions,
    write_all: &dyn Fn(&Image, Option<&Image>) -> Result<(), String>,
    interrupted: &AtomicBool,
) -> Result<RunsResult, String> {
    let passes = opts.passes;
    let bar = progress_bar(args, passes);
    let pixels = scene.camera.pixel_count() as f64;
    let mut last_checkpoint = Instant::now();
    // Both callbacks may record a failed checkpoint.
    let checkpoint_error = std::cell::RefCell::new(None);
    let many = args.runs > 1;
    let result = render_runs(
        scene,
        estimator,
        opts,
        args.runs,
        |k, r| {
            bar.set_position(if args.time.is_some() {
                r.elapsed.as_millis() as u64
            } else {
                r.passes_done as u64
            });
            let rate = r.passes_done as f64 * pixels / r.elapsed.as_secs_f64().max(1e-9);
            let run = if many {
                format!("run {}/{}, ", k + 1, args.runs)
            } else {
                String::new()
            };
            bar.set_message(format!(
                "{run}{} spp, {:.2} Msamples/s",
                r.passes_done,
                rate / 1e6
            ));
            // With several runs a checkpoint is a finished run (written by the run callback).
            if !many && last_checkpoint.elapsed().as_secs_f64() >= args.checkpoint {
                last_checkpoint = Instant::now();
                if let Err(e) = write_all(&r.estimate(), r.std_error().as_ref()) {
                    *checkpoint_error.borrow_mut() = Some(e);
                    return ControlFlow::Break(());
                }
            }
            if interrupted.load(Ordering::SeqCst) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
        |done| {
            if many && checkpoint_error.borrow().is_none() {
                let se = (done.runs.len() >= 2).then(|| done.across_runs.std_error());
                if let Err(e) = write_all(&done.across_runs.mean(), se.as_ref()) {
                    *checkpoint_error.borrow_mut() = Some(e);
                }
            }
        },
    )?;
    bar.finish_and_clear();
    if let Some(e) = checkpoint_error.into_inner() {
        return Err(e);
    }
    Ok(result)
}

/// The standard errors a render has: across independent runs (two or more), and from the spread
/// of passes (an unbiased estimator's).
struct StdErrors {
    across: Option<Image>,
    per_pass: Option<Image>,
}

impl StdErrors {
    fn of(result: &RunsResult) -> StdErrors {
        StdErrors {
            across: (result.runs.len() >= 2).then(|| result.across_runs.std_error()),
            per_pass: result.per_pass.as_ref().map(|p| p.std_error()),
        }
    }

    /// Where the written standard error comes from: independent runs when there are two or
    /// more, else the spread of passes for an unbiased estimator, else nowhere.
    fn chosen(&self) -> (Option<&Image>, &'static str) {
        match (&self.across, &self.per_pass) {
            (Some(a), _) => (Some(a), "independent runs"),
            (None, Some(p)) => (Some(p), "spread of passes"),
            (None, None) => (
                None,
                "none written: the passes of a consistent estimator are not independent; use --runs K",
            ),
        }
    }
}

/// What a finished render prints: passes, runs, time, and its integrators' warnings.
fn print_summary(args: &RenderArgs, result: &RunsResult, output: &Path) {
    let runs_done = result.runs.len();
    let secs = result.elapsed.as_secs_f64();
    let total_passes: u64 = result.runs.iter().map(|r| r.passes as u64).sum();
    let first = &result.runs[0];
    let many = args.runs > 1;
    let runs = if many {
        format!(" × {runs_done} runs")
    } else {
        String::new()
    };
    eprintln!(
        "{}: {} spp{runs} in {:.2} s ({:.2} spp/s) -> {}",
        args.integrator,
        first.passes,
        secs,
        total_passes as f64 / secs,
        output.display()
    );
    let mut warnings: Vec<&str> = result
        .runs
        .iter()
        .filter_map(|r| r.log.as_ref())
        .flat_map(|l| l.facts.iter())
        .filter(|(k, _)| k == "warning")
        .map(|(_, v)| v.as_str())
        .collect();
    warnings.dedup();
    for w in warnings {
        eprintln!("warning: {w}");
    }
    if result.invalid_samples > 0 {
        eprintln!(
            "warning: {} invalid (NaN/Inf/negative) samples were dropped",
            result.invalid_samples
        );
    }
}

/// Counts passes against the pass budget, or milliseconds against the time budget when there is
/// one (the pass count then goes in the message), so the ETA is meaningful in both modes.
fn progress_bar(args: &RenderArgs, passes: u32) -> ProgressBar {
    if args.quiet {
        return ProgressBar::hidden();
    }
    let (len, unit) = match args.time {
        Some(t) => ((t * 1000.0) as u64, "ms"),
        None => (passes as u64, "passes"),
    };
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "[{{elapsed_precise}}] {{bar:30}} {{pos}}/{{len}} {unit}  {{msg}}  ETA {{eta}}"
        ))
        .unwrap(),
    );
    bar
}

/// `lt render … --partial OUT [--passes A..B]`: one part, written to OUT.
fn run_partial(args: &RenderArgs, out: &Path) -> Result<(), String> {
    if args.runs == 0 {
        return Err("--runs must be at least 1".into());
    }
    if args.time.is_some() {
        return Err(
            "--partial takes a fixed number of passes (--passes A..B or --spp N), not \
                    --time: a part must be reproducible to be merged"
                .into(),
        );
    }
    if args.output.is_some() || args.strategies.is_some() {
        return Err(
            "--partial writes the part only: drop -o/--strategies (lt merge writes the \
                    images)"
                .into(),
        );
    }
    let params = normalize_params(args.integrator_args.to_params()?.pairs());
    let mut job = PartialJob {
        scene: args.scene.clone(),
        resolution: None,
        integrator: args.integrator.clone(),
        params,
        span: Span::Runs {
            first_seed: args.seed,
            runs: 1,
            passes: 1,
        },
    };
    let scene = job.load_scene()?;
    let kind = lt_integrators::registry::find(&args.integrator)?.kind;
    let passes = args.spp.unwrap_or(scene.settings.spp);
    if passes == 0 {
        return Err("--spp must be at least 1".into());
    }
    job.span = match (&args.passes, args.runs) {
        (Some(_), _) if args.spp.is_some() => {
            return Err("give --passes A..B or --spp N, not both".into())
        }
        (Some(_), k) if k > 1 => {
            return Err(
                "--passes splits one run into ranges; with --runs K a part holds whole runs \
                 (split the seeds with --seed S --runs K)"
                    .into(),
            )
        }
        (Some(r), _) => {
            let (start, end) = parse_pass_range(r)?;
            Span::Passes {
                seed: args.seed,
                start,
                end,
            }
        }
        (None, 1) if kind == lt_integrators::Kind::Unbiased => Span::Passes {
            seed: args.seed,
            start: 0,
            end: passes,
        },
        (None, k) => Span::Runs {
            first_seed: args.seed,
            runs: k,
            passes,
        },
    };
    let part = job.render(&scene, args.threads, |_, _| {})?;
    part.write(out)?;
    if !args.quiet {
        eprintln!(
            "{}: {} in {:.2} s -> {}",
            args.integrator,
            part.header.span.describe(),
            part.header.seconds,
            out.display()
        );
    }
    Ok(())
}

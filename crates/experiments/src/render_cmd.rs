//! `lt render`: one scene, one integrator, written as linear EXR plus an sRGB PNG preview, a
//! standard-error EXR and a JSON record of how the image was made.

use crate::image_io::{write_exr, write_png_preview};
use crate::strategies::{make_bdpt, write_pyramid, PyramidIntegrator, PyramidMeta};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lt_core::scene::load_scene;
use lt_integrators::{make_integrator, render, Integrator, RenderOptions};
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
    /// Worker threads (0 = one per core). The image does not depend on it.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    #[command(flatten)]
    pub integrator_args: crate::integrator_args::IntegratorArgs,
    /// Output EXR; `.png`, `.stderr.exr` and `.json` are written beside it.
    #[arg(long, short)]
    pub output: PathBuf,
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
    #[arg(long, value_name = "L", default_value_t = crate::strategies::DEFAULT_LENGTH)]
    pub strategy_length: usize,
}

/// Paths of everything written beside the main EXR.
pub fn sibling(out: &Path, suffix: &str) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    out.with_file_name(format!("{stem}{suffix}"))
}

fn write_outputs(out: &Path, acc: &lt_estimators::running::RunningImage) -> Result<(), String> {
    let mean = acc.mean();
    write_exr(out, &mean)?;
    write_png_preview(&sibling(out, ".png"), &mean)?;
    write_exr(&sibling(out, ".stderr.exr"), &acc.std_error())
}

pub fn run(args: &RenderArgs) -> Result<(), String> {
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
    }
    let scene = load_scene(&args.scene).map_err(|e| e.to_string())?;
    let params = args.integrator_args.to_params()?;
    let pyramid = match &args.strategies {
        None => None,
        Some(dir) => {
            let bdpt = make_bdpt(&scene, &params)?;
            let meta = PyramidMeta {
                scene: args.scene.display().to_string(),
                seed: args.seed,
                max_depth: bdpt.params.max_depth,
            };
            let integ = PyramidIntegrator::new(&scene, bdpt, args.strategy_length);
            Some((dir.clone(), integ, meta))
        }
    };
    let plain = match pyramid {
        None => Some(make_integrator(&args.integrator, &scene, &params)?),
        Some(_) => None,
    };
    let integrator: &dyn Integrator = match (&pyramid, &plain) {
        (Some((_, p, _)), _) => p,
        (None, Some(i)) => i.as_ref(),
        (None, None) => unreachable!("one of the two is built"),
    };
    let write_all = |acc: &lt_estimators::running::RunningImage| -> Result<(), String> {
        write_outputs(&args.output, acc)?;
        if let Some((dir, integ, meta)) = &pyramid {
            integ.with_pyramid(|p| write_pyramid(dir, p, meta))?;
        }
        Ok(())
    };
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
    let opts = RenderOptions {
        passes,
        time_limit: args.time.map(Duration::from_secs_f64),
        seed: args.seed,
        threads: args.threads,
    };

    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        // A second Ctrl-C still kills the process the usual way once this handler has run.
        let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    }
    let bar = progress_bar(args, passes);
    let pixels = scene.camera.pixel_count() as f64;
    let mut last_checkpoint = Instant::now();
    let mut checkpoint_error = None;
    let result = render(&scene, integrator, &opts, |r| {
        bar.set_position(if args.time.is_some() {
            r.elapsed.as_millis() as u64
        } else {
            r.passes_done as u64
        });
        let rate = r.passes_done as f64 * pixels / r.elapsed.as_secs_f64().max(1e-9);
        bar.set_message(format!(
            "{} spp, {:.2} Msamples/s",
            r.passes_done,
            rate / 1e6
        ));
        if last_checkpoint.elapsed().as_secs_f64() >= args.checkpoint {
            last_checkpoint = Instant::now();
            if let Err(e) = write_all(r.accumulated) {
                checkpoint_error = Some(e);
                return ControlFlow::Break(());
            }
        }
        if interrupted.load(Ordering::SeqCst) {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })?;
    bar.finish_and_clear();
    if let Some(e) = checkpoint_error {
        return Err(e);
    }
    write_all(&result.image)?;
    let secs = result.elapsed.as_secs_f64();
    let record = serde_json::json!({
        "scene": args.scene.display().to_string(),
        "integrator": args.integrator,
        "spp": result.passes,
        "seed": args.seed,
        "threads": args.threads,
        "max_depth": args.integrator_args.max_depth.unwrap_or(scene.settings.max_depth),
        "params": params.pairs().iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>(),
        "seconds": secs,
        "spp_per_second": result.passes as f64 / secs,
        "invalid_samples": result.invalid_samples,
        "interrupted": interrupted.load(Ordering::SeqCst),
        "strategies": pyramid.as_ref().map(|(dir, _, _)| dir.display().to_string()),
        "strategy_length": pyramid.as_ref().map(|_| args.strategy_length),
    });
    crate::image_io::write_atomic(
        &sibling(&args.output, ".json"),
        serde_json::to_string_pretty(&record).unwrap().as_bytes(),
    )?;
    if !args.quiet {
        eprintln!(
            "{}: {} spp in {:.2} s ({:.2} spp/s) -> {}",
            args.integrator,
            result.passes,
            secs,
            result.passes as f64 / secs,
            args.output.display()
        );
        if result.invalid_samples > 0 {
            eprintln!(
                "warning: {} invalid (NaN/Inf/negative) samples were dropped",
                result.invalid_samples
            );
        }
    }
    Ok(())
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

//! `lt reference SCENE`: a long render with the scene's best unbiased integrator (or the one
//! named), kept in the content-addressed cache under `results/references/` with its record
//! (integrator, passes, seeds, seconds, mean standard error, code version, scene content hash)
//! and reused for as long as the scene and the rendering code are unchanged.

use crate::cache::RenderCache;
use crate::runs::{Executor, RunSpec};
use crate::study::reference::{integrator_for, CONSISTENT_REFERENCE_RUNS, REFERENCE_SEED};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    pub scene: PathBuf,
    /// Integrator (default: the scene's reference integrator; `bdpt` for most scenes).
    #[arg(long, short)]
    pub integrator: Option<String>,
    /// Passes (per run, for a consistent reference). Default: 16 × the scene's `[render] spp`.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Seconds to spend instead: the pass count that fits is measured by a 2-pass probe, so the
    /// reference stays reproducible from its record.
    #[arg(long, conflicts_with = "spp")]
    pub time: Option<f64>,
    /// Film width override (the aspect ratio is kept).
    #[arg(long)]
    pub width: Option<u32>,
    #[arg(long, default_value = "results")]
    pub results: PathBuf,
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
}

pub fn run(args: &ReferenceArgs) -> Result<(), String> {
    let scene = lt_scene_io::load_scene(&args.scene).map_err(|e| e.to_string())?;
    let stem = crate::study::output::stem(&args.scene);
    let (default, why) = integrator_for(&stem);
    let integrator = args
        .integrator
        .clone()
        .unwrap_or_else(|| default.to_string());
    let info = lt_integrators::registry::find(&integrator)?;
    let consistent = info.kind == lt_integrators::Kind::Consistent;
    let runs = if consistent {
        CONSISTENT_REFERENCE_RUNS
    } else {
        1
    };
    let resolution = args.width.map(|w| {
        let (cw, ch) = (scene.camera.width, scene.camera.height);
        (
            w,
            ((w as f64) * ch as f64 / cw as f64).round().max(1.0) as u32,
        )
    });
    let build = |passes: u32| {
        let s = RunSpec::new(&args.scene, &integrator, REFERENCE_SEED, passes)
            .resolution(resolution)
            .runs(runs);
        if consistent && args.integrator.is_none() {
            s.param("radius_px", 1)
        } else {
            s
        }
    };
    let exec = Executor {
        cache: RenderCache::new(args.results.join("references")),
        threads: args.threads,
    };
    let passes = match (args.spp, args.time) {
        (Some(0), _) => return Err("--spp must be at least 1".into()),
        (Some(n), _) => n,
        (None, Some(t)) if !(t > 0.0 && t.is_finite()) => {
            return Err("--time must be a positive number of seconds".into())
        }
        (None, Some(t)) => {
            // The probe goes to a throw-away cache: only its timing is wanted.
            let probe_dir = std::env::temp_dir().join(format!("lt-probe-{}", std::process::id()));
            let probe = Executor {
                cache: RenderCache::new(&probe_dir),
                threads: args.threads,
            };
            let e = probe.run(&build(2).runs(1))?;
            let _ = std::fs::remove_dir_all(&probe_dir);
            let per_pass = e.record.seconds.last().copied().unwrap_or(1.0) / 2.0;
            ((t / per_pass / runs as f64).floor() as u32).max(2)
        }
        (None, None) => scene.settings.spp.saturating_mul(16).max(2),
    };
    let spec = build(passes);
    let started = Instant::now();
    let found = exec.lookup(&spec)?.is_some();
    let entry = exec.run(&spec)?;
    let r = &entry.record;
    eprintln!(
        "{} reference of {}: {} × {} passes of {integrator} ({}), {:.1} s, mean standard error {:.3e} ({}); {}",
        if found { "found the" } else { "rendered the" },
        args.scene.display(),
        spec.runs,
        spec.passes,
        if args.integrator.is_none() { why } else { "as asked" },
        r.seconds.last().copied().unwrap_or(0.0),
        r.mean_std_error.unwrap_or(f64::NAN),
        r.std_error_source,
        if found {
            format!("looked up in {:.2} s", started.elapsed().as_secs_f64())
        } else {
            "kept for reuse".into()
        }
    );
    println!(
        "{}",
        entry
            .dir
            .join(format!("snapshot-{}.exr", spec.passes))
            .display()
    );
    Ok(())
}

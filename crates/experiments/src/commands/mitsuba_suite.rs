//! `lt mitsuba-suite DIR`: Mitsuba 3's render-test suite run and judged
//! (`crate::verify::mitsuba_suite`), the scoreboard written.

use crate::image_io::write_atomic;
use crate::verify::mitsuba_suite::{run_suite_pairs, table, Budget, DEFAULT_OUT};
use std::path::PathBuf;
use std::time::Duration;

#[derive(clap::Args, Debug)]
pub struct SuiteArgs {
    /// A copy of mitsuba-data (the folder holding tests/scenes), e.g. ../shared/mitsuba-render-tests.
    pub dir: PathBuf,
    /// Independent passes per estimator (their spread gives the standard errors).
    #[arg(long, default_value_t = 32)]
    pub passes: u32,
    /// Samples per pixel in each pass. 2048 spp in all: at 256, NEE through Mitsuba's
    /// near-specular rough glass (Beckmann α = 0.02) is so heavy-tailed that 32 passes' spread
    /// underestimates its error (roughdielectric failed, 99.22 %, mean ×0.985; it passes at 2048).
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Time budget per scene in seconds, shared by its estimators; an estimator stops at its share
    /// with the passes it finished (at least 2 are needed).
    #[arg(long, default_value_t = 60.0)]
    pub time_per_scene: f64,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Only the scenes whose name (`folder/file` without `.xml`) contains one of these strings
    /// (repeatable). A partial run prints its table but writes it only where `--out` says, so the
    /// committed scoreboard is never overwritten by a part of it.
    #[arg(long)]
    pub only: Vec<String>,
    /// Only these estimators (repeatable; default: every one the scene's file name implies), so
    /// one estimator can be judged on the suite without paying for the others. A run with it is
    /// partial, as with `--only`.
    #[arg(long)]
    pub estimator: Vec<String>,
    /// Where the table is written (atomically); default results/mitsuba-render-tests.md for a
    /// full run, nowhere for a partial one.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A folder to write, per judged render, its mean (`<scene>_<estimator>_mean.exr`) and its
    /// signed z map (`…_z.exr`: (mean − reference) / σ per value, σ as the rule forms it), to see
    /// where a failing image fails.
    #[arg(long)]
    pub diagnostics: Option<PathBuf>,
}

/// The command: runs the suite, prints the table and writes it to `args.out` atomically.
pub fn run(args: &SuiteArgs) -> Result<(), String> {
    if args.passes < 2 {
        return Err("--passes must be at least 2 (standard errors come from their spread)".into());
    }
    if !(args.time_per_scene > 0.0) {
        return Err(format!(
            "--time-per-scene must be positive, got {}",
            args.time_per_scene
        ));
    }
    let budget = Budget {
        passes: args.passes,
        spp_per_pass: args.spp.max(1),
        time_per_estimator: Duration::from_secs_f64(args.time_per_scene / 2.0),
        threads: args.threads,
        seed: 0,
        diagnostics: args.diagnostics.clone(),
    };
    if let Some(dir) = &args.diagnostics {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let scene_chosen =
        |name: &str| args.only.is_empty() || args.only.iter().any(|o| name.contains(o.as_str()));
    let estimator_chosen =
        |e: &str| args.estimator.is_empty() || args.estimator.iter().any(|x| x == e);
    let rows = run_suite_pairs(&args.dir, &budget, |name, e| {
        scene_chosen(name) && estimator_chosen(e)
    })?;
    if rows.is_empty() {
        return Err(format!(
            "no scene of {} matches --only {} with --estimator {}",
            args.dir.display(),
            args.only.join(", "),
            args.estimator.join(", ")
        ));
    }
    let mut command = format!(
        "lt mitsuba-suite {} --passes {} --spp {} --time-per-scene {}",
        args.dir.display(),
        args.passes,
        args.spp,
        args.time_per_scene
    );
    for o in &args.only {
        command += &format!(" --only {o}");
    }
    for e in &args.estimator {
        command += &format!(" --estimator {e}");
    }
    let md = table::markdown(&rows, &budget, &command);
    print!("{md}");
    let full = args.only.is_empty() && args.estimator.is_empty();
    let out = match (&args.out, full) {
        (Some(out), _) => out.clone(),
        (None, true) => PathBuf::from(DEFAULT_OUT),
        (None, false) => return Ok(()),
    };
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
    }
    write_atomic(&out, md.as_bytes())
}

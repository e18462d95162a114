//! `lt study NAME`: runs a study (or all of them, then the report) into RESULTS/<study>/.

use crate::report;
use crate::study::{registry, run_named, Ctx, StudySetup};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args, Debug, Clone)]
pub struct StudyArgs {
    /// convergence, unbiased-vs-consistent, radius-shrinkage, equal-time, per-length, or all.
    pub name: String,
    /// Publication scale (larger images, more runs and passes) instead of the quick one.
    #[arg(long)]
    pub full: bool,
    /// Where the study folders (and index.html) are written.
    #[arg(long, default_value = "results")]
    pub results: PathBuf,
    /// The cache of finished renders (default: RESULTS/cache; references in RESULTS/references).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// The shipped scenes.
    #[arg(long, default_value = "scenes")]
    pub scenes: PathBuf,
    /// Worker threads (0 = one per core). No image depends on it; timings do.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Test hook: fail after this many new renders, as an interruption would.
    #[arg(long, hide = true)]
    pub stop_after: Option<u64>,
    /// Test hook: the tiny scale the tests run.
    #[arg(long, hide = true)]
    pub test_scale: bool,
}

impl StudyArgs {
    pub fn setup(&self) -> StudySetup {
        let scale = if self.test_scale {
            "test"
        } else if self.full {
            "full"
        } else {
            "quick"
        };
        StudySetup {
            scale: scale.into(),
            results: self.results.clone(),
            cache: self.cache.clone(),
            scenes: self.scenes.clone(),
            threads: self.threads,
            quiet: self.quiet,
            stop_after: self.stop_after,
        }
    }
}

pub fn run(args: &StudyArgs) -> Result<(), String> {
    registry::resolve(&args.name)?;
    let started = Instant::now();
    let ctx = Ctx::new(&args.setup())?;
    run_named(&args.name, &ctx)?;
    let (built, reused) = ctx.counts();
    ctx.finish();
    if args.name == "all" {
        let index = report::write_report(&args.results)?;
        eprintln!(
            "all studies done in {:.0} s ({built} renders made, {reused} found in the cache). \
             The report: {}",
            started.elapsed().as_secs_f64(),
            index.display()
        );
    } else if !args.quiet {
        eprintln!(
            "{} done in {:.0} s ({built} renders made, {reused} found in the cache); \
             `lt report` gathers it into {}",
            args.name,
            started.elapsed().as_secs_f64(),
            args.results.join("index.html").display()
        );
    }
    Ok(())
}

//! `lt study NAME`: runs a study (or all of them, then the report) into RESULTS/<study>/.

use crate::report;
use crate::study::{registry, run_named, StudyContext, StudySetup};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args, Debug, Clone)]
pub struct StudyArgs {
    /// convergence, unbiased-vs-consistent, radius-shrinkage, equal-time, per-length, or all.
    pub name: String,
    /// Publication scale (larger images, more runs and passes) instead of the quick one: the
    /// same as --scale full.
    #[arg(long)]
    pub full: bool,
    /// The scale: quick (a first run, minutes), committed (what the committed report shows for
    /// convergence and the galleries), bitterli (the studies on scenes/bitterli/; give
    /// -D integrator=path), full, test.
    #[arg(long, default_value = "quick")]
    pub scale: String,
    /// Where the study folders (and index.html) are written. Default: results/quick for the
    /// quick scale, so a first run never overwrites the committed report; results otherwise.
    #[arg(long)]
    pub results: Option<PathBuf>,
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
    /// equal-time only: make the full-size galleries of this scene (repeatable), at the pass
    /// counts the study's table records; the table and summary are left as they are.
    #[arg(long)]
    pub scene: Vec<String>,
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
            self.scale.as_str()
        };
        StudySetup {
            scale: scale.into(),
            results: self.results_dir(scale),
            cache: self.cache.clone(),
            scenes: self.scenes.clone(),
            threads: self.threads,
            quiet: self.quiet,
            stop_after: self.stop_after,
        }
    }
}

impl StudyArgs {
    /// --results, or its default for `scale`.
    pub fn results_dir(&self, scale: &str) -> PathBuf {
        match &self.results {
            Some(r) => r.clone(),
            None if scale == "quick" => PathBuf::from("results/quick"),
            None => PathBuf::from("results"),
        }
    }
}

pub fn run(args: &StudyArgs) -> Result<(), String> {
    registry::resolve(&args.name)?;
    if !args.scene.is_empty() && args.name != crate::study::equal_time::NAME {
        return Err(format!(
            "--scene applies to `lt study equal-time` only, not to `{}`",
            args.name
        ));
    }
    let started = Instant::now();
    let setup = args.setup();
    let results = setup.results.clone();
    let ctx = StudyContext::new(&setup)?;
    if args.scene.is_empty() {
        run_named(&args.name, &ctx)?;
    } else {
        crate::study::equal_time::regenerate(&ctx, &args.scene)?;
    }
    let (built, reused) = ctx.counts();
    ctx.finish();
    if args.name == "all" {
        let index = report::write_report(&results)?;
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
            results.join("index.html").display()
        );
    }
    Ok(())
}

//! `lt study NAME`: the bias, variance and consistency studies. Each study is a list of cached
//! renders (`RunSpec`s, see `crate::runs`) and an analysis of their entries that writes CSV,
//! charts (SVG and PNG), a Markdown summary and a manifest under `results/<study>/`, which
//! `lt report` gathers into `results/index.html`.
//!
//! Because every render goes through the cache, a study that was interrupted resumes where it
//! stopped, and a study whose renders ran elsewhere (`lt plan study`, a cluster) is finished by
//! running it again: every render is then found.

pub mod context;
pub mod convergence;
pub mod equal_time;
pub mod lecture;
pub mod metrics;
pub mod output;
pub mod per_length;
pub mod radius_shrinkage;
pub mod reference;
pub mod scale;
pub mod unbiased_consistent;

use crate::runs::RunSpec;
use clap::Args;
pub use context::Ctx;
pub use scale::Scale;
use std::path::PathBuf;
use std::time::Instant;

/// The studies in the order `all` runs them (and the report shows them).
pub const STUDIES: [&str; 5] = [
    "convergence",
    "unbiased-vs-consistent",
    "radius-shrinkage",
    "equal-time",
    "per-length",
];

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
    pub fn scale(&self) -> Result<Scale, String> {
        let name = if self.test_scale {
            "test"
        } else if self.full {
            "full"
        } else {
            "quick"
        };
        Scale::named(name, &self.scenes)
    }
}

fn check_name(name: &str) -> Result<(), String> {
    if name == "all" || STUDIES.contains(&name) {
        Ok(())
    } else {
        Err(format!(
            "unknown study '{name}': the studies are {} and all",
            STUDIES.join(", ")
        ))
    }
}

/// Which cache a planned render belongs in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A study run: the runs cache (default RESULTS/cache).
    Runs,
    /// A reference: RESULTS/references.
    References,
}

/// Every render study `name` needs at `scale` (references included) and the cache each belongs
/// in, for `lt plan study`. The equal-time study's pass counts come from the convergence study's
/// measured timings, so its equal-time renders are planned only with a context whose cache holds
/// those (`ctx` = None plans the rest of it).
pub fn plan(name: &str, scale: &Scale, ctx: Option<&Ctx>) -> Result<Vec<(RunSpec, Role)>, String> {
    check_name(name)?;
    let names: Vec<&str> = if name == "all" {
        STUDIES.to_vec()
    } else {
        vec![name]
    };
    let mut specs = Vec::new();
    for n in names {
        specs.extend(match n {
            "convergence" => convergence::specs(scale),
            "unbiased-vs-consistent" => unbiased_consistent::specs(scale),
            "radius-shrinkage" => radius_shrinkage::specs(scale),
            "equal-time" => match ctx {
                Some(c) => equal_time::specs(c)?,
                None => equal_time::fixed_specs(scale),
            },
            "per-length" => per_length::specs(scale),
            _ => unreachable!("checked above"),
        });
    }
    let mut seen = std::collections::HashSet::new();
    specs.retain(|s| seen.insert(serde_json::to_string(s).unwrap_or_default()));
    Ok(specs
        .into_iter()
        .map(|s| {
            // A reference is exactly what `reference::spec` makes for its scene and depth.
            let depth = s
                .params
                .iter()
                .find(|(k, _)| k == "max_depth")
                .and_then(|(_, v)| v.parse().ok());
            let is_reference = reference::spec(scale, &s.scene, depth).is_ok_and(|r| r == s);
            let role = if is_reference {
                Role::References
            } else {
                Role::Runs
            };
            (s, role)
        })
        .collect())
}

/// Runs study `name` (or all of them, then the report) with the context's cache.
pub fn run_named(name: &str, ctx: &Ctx) -> Result<(), String> {
    check_name(name)?;
    let names: Vec<&str> = if name == "all" {
        STUDIES.to_vec()
    } else {
        vec![name]
    };
    for n in names {
        let t = Instant::now();
        ctx.say(&format!("study {n} ({} scale)", ctx.scale.name));
        match n {
            "convergence" => convergence::run(ctx)?,
            "unbiased-vs-consistent" => unbiased_consistent::run(ctx)?,
            "radius-shrinkage" => radius_shrinkage::run(ctx)?,
            "equal-time" => equal_time::run(ctx)?,
            "per-length" => per_length::run(ctx)?,
            _ => unreachable!("checked above"),
        }
        ctx.say(&format!(
            "study {n}: done in {:.1} s -> {}",
            t.elapsed().as_secs_f64(),
            ctx.study_dir(n).display()
        ));
    }
    Ok(())
}

pub fn run(args: &StudyArgs) -> Result<(), String> {
    check_name(&args.name)?;
    let started = Instant::now();
    let ctx = Ctx::new(args)?;
    run_named(&args.name, &ctx)?;
    let (built, reused) = ctx.counts();
    ctx.finish();
    if args.name == "all" {
        let index = crate::report::write_report(&args.results)?;
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

//! `lt plan render|study … -o PLAN/`: a folder of numbered, independent shards. Each shard is one
//! command (`lt run-shard PLAN/ INDEX`) whose output lives in the experiments' cache under the
//! hash of its inputs, so running a shard twice does the work once, and any scheduler (a Slurm
//! job array, GNU parallel, a shell loop) can run the shards in any order, on any host that sees
//! the same filesystem.
//!
//! A plan folder holds `plan.json` (the shards and what collecting makes of them),
//! `commands.txt` (one shard command a line), `README.md`, and, once shards run, `state/` (one
//! JSON file a shard: running, done or failed, where and when) and `logs/` (one log a shard).

use super::partial::{normalize_params, parse_resolution, PartialJob, Span};
use super::study_link;
use crate::cache::{key_of, RenderCache, CODE_VERSION};
use crate::runs::RunSpec;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub const PLAN_FILE: &str = "plan.json";
pub const PLAN_FORMAT: &str = "lt-plan";
pub const PLAN_VERSION: u32 = 1;

/// What one shard does.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ShardWork {
    /// A partial render (a range of passes, or a set of runs) into `partial.ltp`.
    Partial(PartialJob),
    /// One of a study's cached renders (`runs::Executor::run`).
    Run(RunSpec),
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Shard {
    pub index: usize,
    /// The cache key of its output (computed when planned; a shard refuses to run if its scene
    /// changed since, as its key would).
    pub key: String,
    /// The cache it writes into.
    pub cache: PathBuf,
    pub label: String,
    pub work: ShardWork,
}

/// What `lt collect` makes of the finished shards.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Target {
    /// Merge the parts into one render (what `lt render` writes) at `output`.
    Render {
        output: PathBuf,
        scene: PathBuf,
        integrator: String,
        /// The whole render the parts must cover.
        span: Span,
    },
    /// Run the study again: every render is then found in the cache.
    Study {
        name: String,
        scale: String,
        results: PathBuf,
        scenes: PathBuf,
        /// The study's cache of runs (references live in RESULTS/references).
        cache: PathBuf,
    },
}

/// A study render split into pass ranges: its shards' parts become its cache entry when collected.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Assembly {
    pub spec: RunSpec,
    /// The render's own cache key (`RunSpec::key_material`).
    pub key: String,
    pub cache: PathBuf,
    /// The shards holding its pass ranges, in pass order.
    pub shards: Vec<usize>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Plan {
    pub format: String,
    pub version: u32,
    /// The rendering code the shards' keys were made with.
    pub code_version: String,
    /// The `lt` binary the shard commands run (absolute: on a cluster, on the shared filesystem).
    pub lt: PathBuf,
    /// Worker threads per shard (0 = every core the shard is given).
    pub threads: usize,
    pub target: Target,
    pub shards: Vec<Shard>,
    /// Study renders split into pass ranges (`lt plan study --split-passes`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub assemble: Vec<Assembly>,
}

impl Plan {
    /// A plan of this build's code, run by the lt binary the setup names.
    fn of(
        target: Target,
        shards: Vec<Shard>,
        assemble: Vec<Assembly>,
        setup: &PlanSetup,
    ) -> Result<Plan, String> {
        Ok(Plan {
            format: PLAN_FORMAT.into(),
            version: PLAN_VERSION,
            code_version: CODE_VERSION.into(),
            lt: lt_binary(&setup.lt)?,
            threads: setup.threads,
            target,
            shards,
            assemble,
        })
    }

    pub fn read(dir: &Path) -> Result<Plan, String> {
        let path = dir.join(PLAN_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            format!(
                "cannot read {}: {e} (is {} a plan made by `lt plan`?)",
                path.display(),
                dir.display()
            )
        })?;
        let plan: Plan = serde_json::from_str(&text)
            .map_err(|e| format!("{}: not a plan: {e}", path.display()))?;
        if plan.format != PLAN_FORMAT || plan.version != PLAN_VERSION {
            return Err(format!(
                "{}: format {} version {}, this lt reads {PLAN_FORMAT} version {PLAN_VERSION}",
                path.display(),
                plan.format,
                plan.version
            ));
        }
        Ok(plan)
    }

    /// The plan's shards are keyed by its code version; another lt would look for other keys.
    pub fn check_code(&self, dir: &Path) -> Result<(), String> {
        if self.code_version != CODE_VERSION {
            return Err(format!(
                "{} was planned with rendering code {} but this lt is {}: its shards would be \
                 cached under other keys. Run the plan's own binary ({}) or plan again",
                dir.display(),
                self.code_version,
                CODE_VERSION,
                self.lt.display()
            ));
        }
        Ok(())
    }

    /// The shell command that runs shard `index`.
    pub fn command(&self, dir: &Path, index: usize) -> String {
        format!(
            "{} run-shard {} {index}",
            shell_quote(&self.lt.display().to_string()),
            shell_quote(&dir.display().to_string())
        )
    }

    /// The finished entry of shard `i`, if there is one.
    pub fn finished(&self, i: usize) -> Option<PathBuf> {
        let s = &self.shards[i];
        RenderCache::new(&s.cache).lookup(&crate::cache::Key(s.key.clone()))
    }

    /// Indices of the shards not yet finished.
    pub fn unfinished(&self) -> Vec<usize> {
        (0..self.shards.len())
            .filter(|&i| self.finished(i).is_none())
            .collect()
    }
}

/// Quotes a word for a POSIX shell when it needs it.
pub fn shell_quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "/._-+=:,@%".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// An absolute form of `p` (relative to the working directory), without requiring it to exist.
pub fn absolute(p: &Path) -> Result<PathBuf, String> {
    if let Ok(c) = p.canonicalize() {
        return Ok(c);
    }
    std::path::absolute(p).map_err(|e| format!("cannot make {} absolute: {e}", p.display()))
}

/// GNU parallel's job log, in the plan folder (`lt submit --parallel` writes it).
pub const JOBLOG: &str = "parallel.joblog";

pub fn state_dir(plan_dir: &Path) -> PathBuf {
    plan_dir.join("state")
}

pub fn logs_dir(plan_dir: &Path) -> PathBuf {
    plan_dir.join("logs")
}

pub fn log_path(plan_dir: &Path, i: usize) -> PathBuf {
    logs_dir(plan_dir).join(format!("shard-{i}.log"))
}

pub fn state_path(plan_dir: &Path, i: usize) -> PathBuf {
    state_dir(plan_dir).join(format!("shard-{i}.json"))
}

/// Where a plan is written and how its shards run: what `lt plan`'s common flags give.
#[derive(Clone, Debug)]
pub struct PlanSetup {
    /// The plan folder to write.
    pub output: PathBuf,
    /// The cache the shards write into (default results/cache; for a study RESULTS/cache).
    pub cache: Option<PathBuf>,
    /// The lt binary the shard commands run (default: this one).
    pub lt: Option<PathBuf>,
    /// Worker threads per shard (0 = one per core the shard may use).
    pub threads: usize,
    /// Replace an existing, different plan in the folder.
    pub force: bool,
}

/// One render to split: pass ranges of one seed, or groups of independent runs.
#[derive(Clone, Debug)]
pub struct RenderSplit {
    pub scene: PathBuf,
    pub integrator: String,
    /// Passes of the whole render (or of each run); default the scene's.
    pub spp: Option<u32>,
    pub seed: u64,
    /// Independent runs (seeds seed, seed + 1, …).
    pub runs: u32,
    /// Film size WxH instead of the scene's.
    pub resolution: Option<String>,
    /// Number of shards, or passes (runs) per shard.
    pub shards: Option<u32>,
    pub passes_per_shard: Option<u32>,
    pub runs_per_shard: Option<u32>,
    /// Where `lt collect` writes the render (default PLAN/render.exr).
    pub image: Option<PathBuf>,
    pub integrator_args: crate::integrator_args::IntegratorArgs,
}

/// A study to split into its cached renders.
#[derive(Clone, Debug)]
pub struct StudySplit {
    /// The study (`lt study`'s names).
    pub name: String,
    pub scale: String,
    /// Where `lt collect` writes the study's outputs.
    pub results: PathBuf,
    pub scenes: PathBuf,
    /// Split single-run unbiased renders longer than M passes into ranges of at most M.
    pub split_passes: Option<u32>,
}

/// Splits `0..n` into `k` contiguous pieces as even as possible.
pub fn split_even(n: u32, k: u32) -> Vec<(u32, u32)> {
    (0..k)
        .map(|i| {
            let a = (n as u64 * i as u64 / k as u64) as u32;
            let b = (n as u64 * (i as u64 + 1) / k as u64) as u32;
            (a, b)
        })
        .filter(|(a, b)| b > a)
        .collect()
}

/// Splits `0..n` into pieces of `m` (the last shorter).
pub fn split_by(n: u32, m: u32) -> Vec<(u32, u32)> {
    (0..n.div_ceil(m))
        .map(|i| (i * m, ((i + 1) * m).min(n)))
        .collect()
}

/// Pass ranges covering 0..passes, cut at every snapshot and at most `m` long.
pub fn cuts(passes: u32, snapshots: &[u32], m: u32) -> Vec<(u32, u32)> {
    let mut b: Vec<u32> = snapshots
        .iter()
        .copied()
        .filter(|&p| p > 0 && p < passes)
        .collect();
    b.push(0);
    b.push(passes);
    b.sort_unstable();
    b.dedup();
    let mut out = Vec::new();
    for w in b.windows(2) {
        let len = w[1] - w[0];
        for (x, y) in split_even(len, len.div_ceil(m.max(1))) {
            out.push((w[0] + x, w[0] + y));
        }
    }
    out
}

fn pieces(
    n: u32,
    shards: Option<u32>,
    per: Option<u32>,
    default_per: Option<u32>,
    what: &str,
) -> Result<Vec<(u32, u32)>, String> {
    match (shards, per.or(default_per)) {
        (Some(_), Some(_)) if per.is_some() => {
            Err(format!("give --shards or --{what}-per-shard, not both"))
        }
        (Some(0), _) => Err("--shards must be at least 1".into()),
        (Some(k), _) if k > n => Err(format!(
            "--shards {k} is more shards than there are {what} ({n})"
        )),
        (Some(k), _) => Ok(split_even(n, k)),
        (None, Some(0)) => Err(format!("--{what}-per-shard must be at least 1")),
        (None, Some(m)) => Ok(split_by(n, m)),
        (None, None) => Err(format!(
            "say how to split the {n} {what}: --shards N or --{what}-per-shard M"
        )),
    }
}

/// The shards of a render plan.
pub fn render_shards(args: &RenderSplit, cache: &Path) -> Result<(Vec<Shard>, Span), String> {
    let scene_path = absolute(&args.scene)?;
    let resolution = args
        .resolution
        .as_deref()
        .map(parse_resolution)
        .transpose()?;
    let params = normalize_params(args.integrator_args.to_params()?.pairs());
    let base = PartialJob {
        scene: scene_path.clone(),
        resolution,
        integrator: args.integrator.clone(),
        params,
        span: Span::Runs {
            first_seed: args.seed,
            runs: 1,
            passes: 1,
        },
    };
    let scene = base.load_scene()?;
    // Builds the estimator once: bad parameters are refused now, not on every node.
    lt_integrators::make_integrator(&args.integrator, &scene, &{
        let mut p = lt_integrators::IntegratorParams::new();
        base.params.iter().for_each(|(k, v)| p.set(k, v));
        p
    })?;
    let kind = lt_integrators::registry::find(&args.integrator)?.kind;
    let passes = args.spp.unwrap_or(scene.settings.spp);
    if passes == 0 {
        return Err("--spp must be at least 1".into());
    }
    if args.runs == 0 {
        return Err("--runs must be at least 1".into());
    }
    if args.seed.checked_add(args.runs as u64).is_none() {
        return Err("--seed + --runs overflows: use a smaller --seed".into());
    }
    let (spans, total) = if args.runs > 1 {
        if args.passes_per_shard.is_some() {
            return Err(
                "--passes-per-shard splits one run's passes; with --runs the shards are groups \
                 of runs (--runs-per-shard or --shards)"
                    .into(),
            );
        }
        let p = pieces(args.runs, args.shards, args.runs_per_shard, Some(1), "runs")?;
        let spans: Vec<Span> = p
            .into_iter()
            .map(|(a, b)| Span::Runs {
                first_seed: args.seed + a as u64,
                runs: b - a,
                passes,
            })
            .collect();
        let total = Span::Runs {
            first_seed: args.seed,
            runs: args.runs,
            passes,
        };
        (spans, total)
    } else if kind == lt_integrators::Kind::Consistent {
        if args.shards.unwrap_or(1) > 1 || args.passes_per_shard.is_some() {
            return Err(format!(
                "'{}' is a consistent estimator: its passes share state, so one run cannot be \
                 split; shard independent runs instead (--runs K, each shard a group of seeds)",
                args.integrator
            ));
        }
        let s = Span::Runs {
            first_seed: args.seed,
            runs: 1,
            passes,
        };
        (vec![s.clone()], s)
    } else {
        if args.runs_per_shard.is_some() {
            return Err("--runs-per-shard needs --runs K (K ≥ 2)".into());
        }
        let p = pieces(passes, args.shards, args.passes_per_shard, None, "passes")?;
        let spans = p
            .into_iter()
            .map(|(a, b)| Span::Passes {
                seed: args.seed,
                start: a,
                end: b,
            })
            .collect();
        let total = Span::Passes {
            seed: args.seed,
            start: 0,
            end: passes,
        };
        (spans, total)
    };
    let stem = args
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut shards = Vec::new();
    for (index, span) in spans.into_iter().enumerate() {
        let job = PartialJob {
            span,
            ..base.clone()
        };
        let key = key_of(&job.key_material(&scene)?).0;
        shards.push(Shard {
            index,
            key,
            cache: cache.to_path_buf(),
            label: format!("{stem} {} {}", job.integrator, job.span.describe()),
            work: ShardWork::Partial(job),
        });
    }
    Ok((shards, total))
}

fn write_plan(dir: &Path, plan: &Plan, force: bool) -> Result<(), String> {
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("cannot create the plan folder {}: {e}", dir.display()))?;
    if let Ok(old) = Plan::read(dir) {
        if old == *plan {
            return Ok(());
        }
        if !force {
            return Err(format!(
                "{} already holds a different plan ({} shards); use another folder, or --force \
                 to replace it (its state, logs and joblog are removed; finished shards stay in \
                 the cache)",
                dir.display(),
                old.shards.len()
            ));
        }
        for sub in ["state", "logs", "slurm"] {
            let _ = std::fs::remove_dir_all(dir.join(sub));
        }
        let _ = std::fs::remove_file(dir.join(JOBLOG));
    }
    for d in [state_dir(dir), logs_dir(dir)] {
        std::fs::create_dir_all(&d).map_err(|e| format!("cannot create {}: {e}", d.display()))?;
    }
    let text = serde_json::to_string_pretty(plan).map_err(|e| e.to_string())?;
    crate::image_io::write_atomic(&dir.join(PLAN_FILE), text.as_bytes())?;
    let commands: String = (0..plan.shards.len())
        .map(|i| plan.command(dir, i) + "\n")
        .collect();
    crate::image_io::write_atomic(&dir.join("commands.txt"), commands.as_bytes())?;
    let collect = format!(
        "{} collect {}",
        shell_quote(&plan.lt.display().to_string()),
        shell_quote(&dir.display().to_string())
    );
    let readme = format!(
        "# lt plan: {} shards\n\n\
         Made by `lt plan` (rendering code {}). Each line of `commands.txt` runs one shard; \
         a finished shard is in the cache and running it again does nothing.\n\n\
         - Slurm: `lt submit {d} --slurm [--partition P] [--max-running N]`\n\
         - GNU parallel: `lt submit {d} --parallel [--jobs J] [--sshloginfile FILE]`\n\
         - here: `lt submit {d} --local`\n\
         - by hand: run the lines of commands.txt anywhere that sees this folder, then `{collect}`\n\n\
         `state/shard-I.json` says where and when shard I ran and how it ended; `logs/shard-I.log` \
         is its output.\n",
        plan.shards.len(),
        plan.code_version,
        d = shell_quote(&dir.display().to_string()),
    );
    crate::image_io::write_atomic(&dir.join("README.md"), readme.as_bytes())
}

fn lt_binary(given: &Option<PathBuf>) -> Result<PathBuf, String> {
    match given {
        Some(p) => {
            let p = absolute(p)?;
            if !p.is_file() {
                return Err(format!("--lt {}: no such file", p.display()));
            }
            Ok(p)
        }
        None => std::env::current_exe()
            .map_err(|e| format!("cannot find this lt binary: {e}; give --lt PATH")),
    }
}

/// `lt plan render`: the shards of one render, written as a plan.
pub fn plan_render(a: &RenderSplit, c: &PlanSetup) -> Result<(), String> {
    let dir = absolute(&c.output)?;
    let cache = absolute(c.cache.as_deref().unwrap_or(Path::new("results/cache")))?;
    let (shards, span) = render_shards(a, &cache)?;
    let output = match &a.image {
        Some(p) => absolute(p)?,
        None => dir.join("render.exr"),
    };
    let target = Target::Render {
        output,
        scene: absolute(&a.scene)?,
        integrator: a.integrator.clone(),
        span,
    };
    let plan = Plan::of(target, shards, Vec::new(), c)?;
    publish(&dir, &plan, c.force)
}

/// `lt plan study`: a study's renders, one shard each (long ones split), written as a plan.
pub fn plan_study(a: &StudySplit, c: &PlanSetup) -> Result<(), String> {
    let dir = absolute(&c.output)?;
    let results = absolute(&a.results)?;
    let cache = absolute(&c.cache.clone().unwrap_or_else(|| results.join("cache")))?;
    let scenes = absolute(&a.scenes)?;
    if a.split_passes == Some(0) {
        return Err("--split-passes must be at least 1".into());
    }
    let mut shards = Vec::new();
    let mut assemble = Vec::new();
    for (spec, role) in study_link::plan(&a.name, &a.scale, &results, &scenes, &cache)? {
        let mut spec = spec;
        let cache = study_link::cache_for(role, &cache, &results);
        spec.scene = absolute(&spec.scene)?;
        let scene = spec.load_scene()?;
        let key = key_of(&spec.key_material(&scene)?).0;
        let kind = lt_integrators::registry::find(&spec.integrator)?.kind;
        let split = a.split_passes.filter(|&m| {
            spec.runs == 1 && kind == lt_integrators::Kind::Unbiased && spec.passes > m
        });
        let Some(m) = split else {
            shards.push(Shard {
                index: shards.len(),
                key,
                cache: cache.clone(),
                label: spec.label(),
                work: ShardWork::Run(spec),
            });
            continue;
        };
        let mut parts = Vec::new();
        for (start, end) in cuts(spec.passes, &spec.snapshots, m) {
            let job = PartialJob {
                scene: spec.scene.clone(),
                resolution: spec.resolution,
                integrator: spec.integrator.clone(),
                params: normalize_params(&spec.params),
                span: Span::Passes {
                    seed: spec.seed,
                    start,
                    end,
                },
            };
            parts.push(shards.len());
            shards.push(Shard {
                index: shards.len(),
                key: key_of(&job.key_material(&scene)?).0,
                cache: cache.clone(),
                label: format!("{}: passes {start}..{end}", spec.label()),
                work: ShardWork::Partial(job),
            });
        }
        assemble.push(Assembly {
            spec,
            key,
            cache: cache.clone(),
            shards: parts,
        });
    }
    let target = Target::Study {
        name: a.name.clone(),
        scale: a.scale.clone(),
        results,
        scenes,
        cache,
    };
    let plan = Plan::of(target, shards, assemble, c)?;
    publish(&dir, &plan, c.force)
}

/// Writes the plan and says how to run it.
fn publish(dir: &Path, plan: &Plan, force: bool) -> Result<(), String> {
    if plan.shards.is_empty() {
        return Err("the plan has no shards".into());
    }
    write_plan(dir, plan, force)?;
    let done = plan.shards.len() - plan.unfinished().len();
    eprintln!(
        "plan {}: {} shards ({done} already in the cache); run them with `lt submit {} \
         --slurm|--parallel|--local`, or the lines of {}",
        dir.display(),
        plan.shards.len(),
        shell_quote(&dir.display().to_string()),
        dir.join("commands.txt").display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_cover_exactly() {
        for n in [1u32, 7, 64, 1000] {
            for k in 1..=n.min(9) {
                let s = split_even(n, k);
                assert_eq!(s.len(), k as usize);
                assert_eq!(s[0].0, 0);
                assert_eq!(s.last().unwrap().1, n);
                assert!(s.windows(2).all(|w| w[0].1 == w[1].0));
            }
            let c = cuts(n, &[1, n / 2, n + 5], 3);
            assert_eq!((c[0].0, c.last().unwrap().1), (0, n));
            assert!(c.windows(2).all(|w| w[0].1 == w[1].0));
            assert!(c.iter().all(|(a, b)| b - a <= 3));
            assert!(n < 2 || c.iter().any(|&(_, b)| b == n / 2));
            let s = split_by(n, 3);
            assert_eq!(s.last().unwrap().1, n);
            assert!(s.windows(2).all(|w| w[0].1 == w[1].0));
        }
    }

    #[test]
    fn quoting() {
        assert_eq!(shell_quote("/a/b-c.d"), "/a/b-c.d");
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
    }
}

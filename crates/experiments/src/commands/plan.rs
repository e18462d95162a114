//! `lt plan render|study`: a render or a study split into independent shards, written as a plan
//! folder (`crate::cluster::plan`; docs/cluster.md).

use crate::cluster::plan::{plan_render, plan_study, PlanSetup, RenderSplit, StudySplit};
use clap::{Args, Subcommand};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct PlanArgs {
    #[command(subcommand)]
    pub what: PlanWhat,
}

#[derive(Subcommand, Debug)]
#[allow(clippy::large_enum_variant)] // parsed once
pub enum PlanWhat {
    /// Split one render into shards: pass ranges of one seed (unbiased integrators) or groups of
    /// independent runs (--runs K; the only split of pm, ppm, sppm, bpm, vcm).
    Render(PlanRenderArgs),
    /// Split a study into its cached renders, one shard each.
    Study(PlanStudyArgs),
}

#[derive(Args, Debug, Clone)]
pub struct PlanCommon {
    /// The plan folder to write.
    #[arg(long, short)]
    pub output: PathBuf,
    /// The cache the shards write into (default results/cache; for a study plan RESULTS/cache,
    /// the one `lt study` reads, with its references in RESULTS/references).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// The lt binary the shard commands run (default: this one). On a cluster it must be on a
    /// filesystem every node mounts at the same path.
    #[arg(long)]
    pub lt: Option<PathBuf>,
    /// Worker threads per shard (0 = one per core the shard may use).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Replace an existing, different plan in the folder (its state, logs and joblog go too).
    #[arg(long)]
    pub force: bool,
}

#[derive(Args, Debug)]
pub struct PlanRenderArgs {
    /// Scene file.
    pub scene: PathBuf,
    #[arg(long, short, default_value = "pt")]
    pub integrator: String,
    /// Passes (samples per pixel) of the whole render, or of each run with --runs; default the
    /// scene's.
    #[arg(long)]
    pub spp: Option<u32>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Independent runs (seeds seed, seed+1, …): the render is their mean with the standard
    /// error across them, as `lt render --runs K`; shards are groups of runs.
    #[arg(long, default_value_t = 1)]
    pub runs: u32,
    /// Film size WxH instead of the scene's (the camera keeps its field of view).
    #[arg(long)]
    pub resolution: Option<String>,
    /// Number of shards (passes or runs split as evenly as possible).
    #[arg(long)]
    pub shards: Option<u32>,
    /// Passes per shard (the last may be shorter); instead of --shards.
    #[arg(long)]
    pub passes_per_shard: Option<u32>,
    /// Runs per shard with --runs (default 1); instead of --shards.
    #[arg(long)]
    pub runs_per_shard: Option<u32>,
    /// Where `lt collect` writes the render (default PLAN/render.exr), with .png, .stderr.exr
    /// and .json beside it.
    #[arg(long)]
    pub image: Option<PathBuf>,
    #[command(flatten)]
    pub integrator_args: crate::integrator_args::IntegratorArgs,
    #[command(flatten)]
    pub common: PlanCommon,
}

#[derive(Args, Debug)]
pub struct PlanStudyArgs {
    /// The study (`lt study`'s names).
    pub name: String,
    /// quick, full or test.
    #[arg(long, default_value = "quick")]
    pub scale: String,
    /// Where `lt collect` writes the study's outputs.
    #[arg(long, default_value = "results")]
    pub results: PathBuf,
    /// The shipped scenes.
    #[arg(long, default_value = "scenes")]
    pub scenes: PathBuf,
    /// Split every single-run render of an unbiased integrator longer than M passes (a long
    /// reference) into pass ranges of at most M, cut at its snapshots too; collecting merges
    /// them into the render's cache entry, where the study finds it.
    #[arg(long, value_name = "M")]
    pub split_passes: Option<u32>,
    #[command(flatten)]
    pub common: PlanCommon,
}

impl PlanCommon {
    fn setup(&self) -> PlanSetup {
        PlanSetup {
            output: self.output.clone(),
            cache: self.cache.clone(),
            lt: self.lt.clone(),
            threads: self.threads,
            force: self.force,
        }
    }
}

impl PlanRenderArgs {
    fn split(&self) -> RenderSplit {
        RenderSplit {
            scene: self.scene.clone(),
            integrator: self.integrator.clone(),
            spp: self.spp,
            seed: self.seed,
            runs: self.runs,
            resolution: self.resolution.clone(),
            shards: self.shards,
            passes_per_shard: self.passes_per_shard,
            runs_per_shard: self.runs_per_shard,
            image: self.image.clone(),
            integrator_args: self.integrator_args.clone(),
        }
    }
}

impl PlanStudyArgs {
    fn split(&self) -> StudySplit {
        StudySplit {
            name: self.name.clone(),
            scale: self.scale.clone(),
            results: self.results.clone(),
            scenes: self.scenes.clone(),
            split_passes: self.split_passes,
        }
    }
}

pub fn run(args: &PlanArgs) -> Result<(), String> {
    match &args.what {
        PlanWhat::Render(a) => plan_render(&a.split(), &a.common.setup()),
        PlanWhat::Study(a) => plan_study(&a.split(), &a.common.setup()),
    }
}

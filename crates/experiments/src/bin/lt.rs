//! `lt` — the testbed's command line: render scenes, compare images, run the studies, plan and
//! merge work for a cluster, convert scenes.

use clap::{Parser, Subcommand};
use lt_experiments as x;
use std::process::ExitCode;

/// mimalloc keeps freed pages for reuse: the progressive integrators allocate their per-pass
/// buffers afresh every pass, and the system allocator returned them to the kernel each time
/// (sppm on cornell-box spent 6 % of its CPU in page faults; results/bench.md). The allocator
/// changes no arithmetic, so images keep their bits.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(name = "lt", version, about = "Bidirectional light-transport testbed")]
struct Cli {
    #[command(subcommand)]
    command: Command,
    #[command(flatten)]
    load: x::load_args::LoadArgs,
    /// How rays find primitives: auto (flat for scenes of at most 64 primitives and no triangles,
    /// else wide up to 100,000 primitives on a CPU with AVX2, else bvh), bvh, flat (every primitive tested, vectorised), flat-scalar (the same, one at
    /// a time: the reference, bit for bit the same hits), wide (an 8-wide BVH with triangles
    /// tested 8 at a time: the same hits as flat-scalar) or embree (Intel's Embree 3, where the
    /// build found it). See results/bench.md.
    #[arg(long, global = true, default_value = "auto", value_parser = parse_ray_core)]
    ray_core: lt_core::geometry::RayCore,
}

fn parse_ray_core(s: &str) -> Result<lt_core::geometry::RayCore, String> {
    lt_core::geometry::RayCore::parse(s)
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to EXR (+ PNG preview, standard-error EXR, JSON record).
    Render(x::commands::render::RenderArgs),
    /// Compare two EXR images: metrics, per-block z-scores, and OpenImageIO's view when installed.
    Compare(x::commands::compare::CompareArgs),
    /// Measure BVH and integrator throughput (results/bench.md).
    Bench(x::commands::bench::BenchArgs),
    /// Check an integrator's MIS weights (pt, bdpt, lvc-bdpt, vcm, bpm, upbp; eamis's counts through vcm)
    /// against the from-scratch path-space oracle.
    MisCheck(x::commands::mis_check::MisCheckArgs),
    /// Render (or reuse from the cache) a long reference image of a scene.
    Reference(x::commands::reference::ReferenceArgs),
    /// Run a study (convergence, unbiased-vs-consistent, radius-shrinkage, equal-time,
    /// per-length, or all) into results/<study>/.
    Study(x::commands::study::StudyArgs),
    /// Write results/index.html from the studies' outputs.
    Report(x::commands::report::ReportArgs),
    /// Write one of our scenes as Mitsuba 3 XML.
    Convert(x::commands::convert::ConvertArgs),
    /// Merge partial renders (--partial) or independent runs exactly into one image.
    Merge(x::commands::merge::MergeArgs),
    /// Split a render or a study into independent shards for a cluster.
    Plan(x::commands::plan::PlanArgs),
    /// Run one shard of a plan.
    RunShard(x::commands::run_shard::RunShardArgs),
    /// Hand a plan to Slurm, GNU parallel or the local pool.
    Submit(x::commands::submit::SubmitArgs),
    /// Merge a plan's finished shards into its render or study outputs.
    Collect(x::commands::collect::CollectArgs),
    /// Render Mitsuba 3's render-test suite (mitsuba-data's tests/scenes) and judge each scene
    /// against its reference: results/mitsuba-render-tests.md.
    MitsubaSuite(x::commands::mitsuba_suite::SuiteArgs),
    /// List the integrators.
    List,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    lt_core::geometry::set_ray_core(cli.ray_core);
    lt_scene_io::set_default_load_options(cli.load.options());
    let result = match &cli.command {
        Command::Render(a) => x::commands::render::run(a),
        Command::Compare(a) => x::commands::compare::run(a).map(|report| print!("{report}")),
        Command::Bench(a) => x::commands::bench::run(a).map(|table| print!("{table}")),
        Command::MisCheck(a) => x::commands::mis_check::run(a).map(|table| print!("{table}")),
        Command::Reference(a) => x::commands::reference::run(a),
        Command::Study(a) => x::commands::study::run(a),
        Command::Report(a) => x::commands::report::run(a),
        Command::Convert(a) => x::commands::convert::run(a),
        Command::Merge(a) => x::commands::merge::run(a),
        Command::Plan(a) => x::commands::plan::run(a),
        Command::RunShard(a) => x::commands::run_shard::run(a),
        Command::Submit(a) => x::commands::submit::run(a),
        Command::Collect(a) => x::commands::collect::run(a),
        Command::MitsubaSuite(a) => x::commands::mitsuba_suite::run(a),
        Command::List => x::commands::list::run(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

//! `lt` — the testbed's command line: render scenes, compare images, list integrators.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "lt", version, about = "Bidirectional light-transport testbed")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to EXR (+ PNG preview, standard-error EXR, JSON record).
    Render(lt_experiments::render_cmd::RenderArgs),
    /// Compare two EXR images: metrics, per-block z-scores, and OpenImageIO's view when installed.
    Compare(lt_experiments::compare::CompareArgs),
    /// Measure BVH and integrator throughput (results/bench.md).
    Bench(lt_experiments::bench_cmd::BenchArgs),
    /// Check an integrator's MIS weights (pt, bdpt) against the from-scratch path-space oracle.
    MisCheck(lt_experiments::mis_check::MisCheckArgs),
    /// List the integrators.
    List,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Render(a) => lt_experiments::render_cmd::run(a),
        Command::Compare(a) => lt_experiments::compare::run(a).map(|report| print!("{report}")),
        Command::Bench(a) => lt_experiments::bench_cmd::run(a).map(|table| print!("{table}")),
        Command::MisCheck(a) => lt_experiments::mis_check::run(a).map(|table| print!("{table}")),
        Command::List => {
            for i in lt_integrators::INTEGRATORS {
                println!("{:10} {}", i.name, i.about);
            }
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

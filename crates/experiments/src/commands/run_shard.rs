//! `lt run-shard PLAN/ INDEX`: one shard of a plan into the cache, with its state file
//! (`crate::cluster::shard`).

use crate::cluster::plan::{absolute, Plan};
use crate::cluster::shard::run_one;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct RunShardArgs {
    /// The plan folder (`lt plan … -o PLAN`).
    pub plan: PathBuf,
    /// The shard's index (0-based, as in commands.txt).
    pub index: usize,
    /// Worker threads (default: the plan's; under Slurm, the CPUs the task was given).
    #[arg(long)]
    pub threads: Option<usize>,
}

pub fn run(args: &RunShardArgs) -> Result<(), String> {
    let dir = absolute(&args.plan)?;
    let plan = Plan::read(&dir)?;
    plan.check_code(&dir)?;
    run_one(&dir, &plan, args.index, args.threads)
}

//! `lt submit PLAN/ --slurm|--parallel|--local`: a plan's unfinished shards handed to a scheduler
//! (`crate::cluster::submit`).

use crate::cluster::submit::{submit, Engine, ParallelOptions, SlurmOptions, Submission};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct SubmitArgs {
    /// The plan folder.
    pub plan: PathBuf,
    /// Submit an sbatch job array of the unfinished shards and a collect job after it.
    #[arg(long)]
    pub slurm: bool,
    /// Run the shards with GNU parallel (--joblog, --resume-failed), then collect.
    #[arg(long)]
    pub parallel: bool,
    /// Run the unfinished shards here, one after the other, then collect.
    #[arg(long)]
    pub local: bool,
    /// Slurm: the partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Slurm: at most N shards at once (--array=…%N).
    #[arg(long)]
    pub max_running: Option<u32>,
    /// Slurm: CPUs per shard (shards then use that many threads unless the plan says).
    #[arg(long)]
    pub cpus_per_task: Option<u32>,
    /// Slurm: memory per shard (sbatch --mem, e.g. 2G).
    #[arg(long)]
    pub mem: Option<String>,
    /// Slurm: time limit per shard (sbatch --time, e.g. 1:00:00).
    #[arg(long)]
    pub time_limit: Option<String>,
    /// Slurm: any further sbatch option for the shards' job (repeatable), e.g. --sbatch-arg=--qos=low.
    #[arg(long = "sbatch-arg", value_name = "OPTION", allow_hyphen_values = true)]
    pub sbatch_args: Vec<String>,
    /// GNU parallel: jobs at once (default: cores / threads per shard, or 1 when shards use every core).
    #[arg(long)]
    pub jobs: Option<String>,
    /// GNU parallel: run on the hosts of this file (--sshloginfile); they must share the plan's filesystem.
    #[arg(long)]
    pub sshloginfile: Option<PathBuf>,
    /// Write the scripts and print the commands instead of running them.
    #[arg(long)]
    pub print: bool,
    /// GNU parallel and local: do not collect after the shards.
    #[arg(long)]
    pub no_collect: bool,
}

impl SubmitArgs {
    /// The one scheduler the flags name, with its options.
    fn engine(&self) -> Result<Engine, String> {
        match (self.slurm, self.parallel, self.local) {
            (true, false, false) => Ok(Engine::Slurm(SlurmOptions {
                partition: self.partition.clone(),
                max_running: self.max_running,
                cpus_per_task: self.cpus_per_task,
                mem: self.mem.clone(),
                time_limit: self.time_limit.clone(),
                sbatch_args: self.sbatch_args.clone(),
            })),
            (false, true, false) => Ok(Engine::Parallel(ParallelOptions {
                jobs: self.jobs.clone(),
                sshloginfile: self.sshloginfile.clone(),
            })),
            (false, false, true) => Ok(Engine::Local),
            _ => Err("say where the shards run: one of --slurm, --parallel, --local".into()),
        }
    }
}

pub fn run(args: &SubmitArgs) -> Result<(), String> {
    submit(&Submission {
        plan: args.plan.clone(),
        engine: args.engine()?,
        print: args.print,
        no_collect: args.no_collect,
    })
}

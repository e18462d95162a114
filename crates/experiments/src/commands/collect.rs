//! `lt collect PLAN/`: a plan's finished shards merged into its render, or its study rerun from
//! the cache (`crate::cluster::collect`).

use crate::cluster::collect::{collect, CollectOptions};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct CollectArgs {
    /// The plan folder.
    pub plan: PathBuf,
    /// Merge the finished shards even if some are missing (the record lists what is missing).
    #[arg(long)]
    pub allow_incomplete: bool,
    /// Write the render here instead of where the plan says (render plans).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Worker threads for what a study renders itself (0 = one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
}

impl CollectArgs {
    fn options(&self) -> CollectOptions {
        CollectOptions {
            plan: self.plan.clone(),
            allow_incomplete: self.allow_incomplete,
            output: self.output.clone(),
            threads: self.threads,
        }
    }
}

pub fn run(args: &CollectArgs) -> Result<(), String> {
    collect(&args.options())
}

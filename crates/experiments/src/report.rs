//! `lt report`: results/index.html from the studies' manifests (not yet).

use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// The results folder holding one sub-folder per study.
    #[arg(long, default_value = "results")]
    pub results: PathBuf,
}

pub fn run(_args: &ReportArgs) -> Result<(), String> {
    Err("lt report is not written yet".into())
}

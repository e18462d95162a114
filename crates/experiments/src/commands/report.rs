//! `lt report`: RESULTS/index.html from the studies' outputs (`crate::report`).

use crate::report::write_report;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// The results folder holding one sub-folder per study.
    #[arg(long, default_value = "results")]
    pub results: PathBuf,
}

pub fn run(args: &ReportArgs) -> Result<(), String> {
    let path = write_report(&args.results)?;
    println!("{}", path.display());
    Ok(())
}

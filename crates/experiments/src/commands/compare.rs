//! `lt compare A.exr B.exr`: metrics, per-block z-scores and OpenImageIO's view (`crate::compare`).

use crate::compare::{report, Comparison};
use std::path::PathBuf;

#[derive(clap::Args, Clone, Debug)]
pub struct CompareArgs {
    /// Image to assess (EXR).
    pub a: PathBuf,
    /// Reference image (EXR); relative MSE divides by it.
    pub b: PathBuf,
    /// Block side in pixels for the per-region z-scores.
    #[arg(long, default_value_t = 16)]
    pub blocks: usize,
    /// Per-pixel standard-error image of A (e.g. A.stderr.exr from `lt render`).
    #[arg(long)]
    pub a_stderr: Option<PathBuf>,
    /// Per-pixel standard-error image of B; without it B is taken as exact.
    #[arg(long)]
    pub b_stderr: Option<PathBuf>,
}

impl CompareArgs {
    fn comparison(&self) -> Comparison {
        Comparison {
            a: self.a.clone(),
            b: self.b.clone(),
            blocks: self.blocks,
            a_stderr: self.a_stderr.clone(),
            b_stderr: self.b_stderr.clone(),
        }
    }
}

pub fn run(args: &CompareArgs) -> Result<String, String> {
    report(&args.comparison())
}

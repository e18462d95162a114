//! `lt reference SCENE`: a long render with the scene's best unbiased integrator, kept in the
//! content-addressed cache under results/references/ (not yet).

use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    pub scene: PathBuf,
}

pub fn run(_args: &ReferenceArgs) -> Result<(), String> {
    Err("lt reference is not written yet".into())
}

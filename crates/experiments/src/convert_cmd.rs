//! `lt convert SCENE.toml -o SCENE.xml`: our scenes as Mitsuba 3 XML (issue 16; not yet).

use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ConvertArgs {
    pub scene: PathBuf,
    #[arg(long, short)]
    pub output: PathBuf,
}

pub fn run(_args: &ConvertArgs) -> Result<(), String> {
    Err("lt convert is not written yet".into())
}

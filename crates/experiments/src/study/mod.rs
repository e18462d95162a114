//! `lt study NAME`: the bias, variance and consistency studies (not yet).

use clap::Args;

#[derive(Args, Debug)]
pub struct StudyArgs {
    pub name: String,
}

pub fn run(_args: &StudyArgs) -> Result<(), String> {
    Err("lt study is not written yet".into())
}

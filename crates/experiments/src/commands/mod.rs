//! One file per `lt` subcommand: its arguments (clap) and a thin `run` that hands them to the
//! module doing the work.

pub mod mis_check;
pub mod report;
pub mod study;

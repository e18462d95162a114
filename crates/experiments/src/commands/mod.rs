//! One file per `lt` subcommand: its arguments (clap) and a `run` that checks them and hands
//! them to the module doing the work. The cluster's commands (`merge`, `plan`, `run-shard`,
//! `submit`, `collect`) take their arguments from `crate::cluster`.

pub mod bench;
pub mod compare;
pub mod convert;
pub mod list;
pub mod mis_check;
pub mod mitsuba_suite;
pub mod reference;
pub mod render;
pub mod report;
pub mod study;

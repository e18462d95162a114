//! One file per `lt` subcommand: its arguments (clap) and a `run` that checks them and hands
//! them to the module doing the work (the cluster's five — `merge`, `plan`, `run_shard`, `submit`,
//! `collect` — to `crate::cluster`).

pub mod bench;
pub mod collect;
pub mod compare;
pub mod convert;
pub mod list;
pub mod merge;
pub mod mis_check;
pub mod mitsuba_suite;
pub mod plan;
pub mod reference;
pub mod render;
pub mod report;
pub mod run_shard;
pub mod study;
pub mod submit;

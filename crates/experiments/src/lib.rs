//! The binaries users run (`lt`, benches, experiments) and the I/O they share.

pub mod bench;
pub mod bench_cmd;
pub mod cache;
pub mod cluster;
pub mod commands;
pub mod compare;
pub mod convert_cmd;
pub mod flip;
pub mod gallery;
pub mod image_io;
pub mod integrator_args;
pub mod load_args;
pub mod manifest;
pub mod mitsuba_suite;
pub mod plot;
pub mod reference_cmd;
pub mod render_cmd;
pub mod report;
pub mod runs;
pub mod strategies;
pub mod study;
pub mod verify;

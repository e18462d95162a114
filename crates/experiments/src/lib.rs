//! The binaries users run (`lt`, benches, experiments) and the I/O they share.

pub mod bench;
pub mod cache;
pub mod cluster;
pub mod commands;
pub mod compare;
pub mod flip;
pub mod gallery;
pub mod image_io;
pub mod integrator_args;
pub mod load_args;
pub mod manifest;
pub mod plot;
pub mod report;
pub mod runs;
pub mod scene_load;
pub mod study;
pub mod verify;

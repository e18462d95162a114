//! The workspace's checks that can share one process, one module per file (see Cargo.toml for
//! why they are one binary and which stay apart). Run one file's checks with, for example,
//! `cargo test --release --test checks agreement::`. The crates' own integration tests live here
//! too, under `integrators::` and `scene_io::` (tests/integrators/, tests/scene_io/): a binary per
//! crate would cost a compile and link each for a few seconds of tests.

// The statistics here walk blocks × channels of several parallel arrays at once (run means,
// references, weights); index loops say that plainest.
#![allow(clippy::needless_range_loop)]

mod agreement;
mod bdpt_weights;
mod consistency;
mod crossings;
mod directional;
mod furnace;
mod light_lanes;
mod light_paths;
mod material_grid;
mod media;
mod media_figures;
mod mis_check;
mod mis_check_upbp;
mod mis_check_vcm;
mod mitsuba_suite;
mod mlt;
mod partial_merge;
mod photon_estimates;
mod points_beams;
mod pt_agreement;
mod pt_lanes;
mod robustness;
mod runs;
mod side_images;
mod studies;
mod techniques_study;
mod translation;
mod vcm_consistency;
mod vcm_is_bdpt;
mod vcm_leak;
mod xml_cornell;
mod xml_errors;
mod xml_file_rules;
mod xml_roundtrip;

/// lt-integrators' integration tests (photon tracing, subpath walks, work tallies).
mod integrators {
    mod photons;
    mod subpaths;
    mod tally;
}

/// lt-scene-io's integration tests (TOML and XML scene files, the shipped scenes, media in XML).
mod scene_io {
    mod scene_files;
    mod shipped_scenes;
    mod smallvcm_twins;
    mod xml_media;
}

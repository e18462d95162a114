//! lt-scene-io's integration tests as one binary: each test binary costs a thin-LTO link of the
//! crate and its dependencies (tens of seconds on 2 cores in CI), and in one binary the files'
//! tests also run side by side. One file's tests:
//! `cargo test --release -p lt-scene-io --test scene_io_tests <file>::`.

mod scene_files;
mod shipped_scenes;
mod smallvcm_twins;
mod xml_media;

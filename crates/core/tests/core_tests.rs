//! lt-core's integration tests as one binary: each test binary costs a compile and a link of the
//! crate and its dependencies (seconds to tens of seconds on 2 cores in CI), and in one binary the files'
//! tests also run side by side. One file's tests:
//! `cargo test --release -p lt-core --test core_tests <file>::`.

mod bsdf_sampling;
mod light_sampling;
mod media;
mod path_space;
mod phase_sampling;

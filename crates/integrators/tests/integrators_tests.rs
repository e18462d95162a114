//! lt-integrators' integration tests as one binary: each test binary costs a thin-LTO link of the
//! crate and its dependencies (tens of seconds on 2 cores in CI), and in one binary the files'
//! tests also run side by side. One file's tests:
//! `cargo test --release -p lt-integrators --test integrators_tests <file>::`.

mod photons;
mod subpaths;
mod tally;

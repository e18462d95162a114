//! lt-experiments's integration tests as one binary: each test binary costs a compile and a link of the
//! crate and its dependencies (seconds to tens of seconds on 2 cores in CI), and in one binary the files'
//! tests also run side by side. One file's tests:
//! `cargo test --release -p lt-experiments --test experiments_tests <file>::`.
//!
//! `cluster_*` run plans through the `lt` binary on the local pool, GNU parallel and a private
//! Slurm cluster, and `report_browser` loads `lt report`'s page in headless Chromium: they wait on
//! outside programs with timeouts, and share this process only with the other light tests here,
//! not with the renders of the workspace's `checks`.

mod cli;
mod cluster_common;
mod cluster_local;
mod cluster_parallel;
mod cluster_slurm;
mod docs;
mod oiio_agreement;
mod report_browser;
mod strategies;
